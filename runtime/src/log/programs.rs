//! What controller programs (Webots controllers, run by `regatta-webots`) add to a log: each
//! line a program prints, and its robot's LEDs whenever they change, on `/{robot}/output` and
//! `/{robot}/leds`. Both belong to the `controller` channel of `--channels`. Their channels are
//! added when a robot's first message comes, so that a run without programs writes the same
//! bytes as before.

use std::io::{Seek, Write};

use super::{Channel, LogError, Recorder};

/// The `ros2msg` schemas of these channels.
pub const PROGRAM_SCHEMAS: &[(&str, &str)] = &[
    (
        "regatta/msg/ControllerOutput",
        "# A line a robot's controller program printed (standard output and error, in order)\nfloat64 t\nstring line\n",
    ),
    (
        "regatta/msg/Leds",
        "# A robot's LEDs after one changed: names and values (0 off; a colour 0xRRGGBB or an intensity index)\nfloat64 t\nstring[] names\nint32[] values\n",
    ),
];

/// The channels of one kind, per robot, made on first use.
#[derive(Default)]
pub(super) struct Lazy {
    schema: Option<u16>,
    channels: Vec<Option<u16>>,
}

impl<W: Write + Seek> Recorder<W> {
    /// Records a line that robot `robot`'s controller printed at simulated time `t`.
    pub fn record_output(&mut self, robot: usize, t: f64, line: &str) -> Result<(), LogError> {
        let Some(channel) = self.program_channel(robot, 0)? else {
            return Ok(());
        };
        self.cdr.start();
        self.cdr.f64(t);
        self.cdr.string(line);
        self.write(Some(channel), super::ns(t))
    }

    /// Records robot `robot`'s LEDs (name and value each) after a change at time `t`.
    pub fn record_leds(
        &mut self,
        robot: usize,
        t: f64,
        leds: &[(String, i32)],
    ) -> Result<(), LogError> {
        let Some(channel) = self.program_channel(robot, 1)? else {
            return Ok(());
        };
        self.cdr.start();
        self.cdr.f64(t);
        self.cdr.u32(leds.len() as u32);
        for (name, _) in leds {
            self.cdr.string(name);
        }
        self.cdr.u32(leds.len() as u32);
        for (_, value) in leds {
            self.cdr.i32(*value);
        }
        self.write(Some(channel), super::ns(t))
    }

    /// The channel of kind `kind` (0 output, 1 LEDs) for `robot`, added on first use; `None`
    /// when the log does not hold the `controller` channel or there is no such robot.
    fn program_channel(&mut self, robot: usize, kind: usize) -> Result<Option<u16>, LogError> {
        if !self.wanted.contains(Channel::Controller) || robot >= self.tokens.len() {
            return Ok(None);
        }
        let lazy = &mut self.programs[kind];
        if lazy.channels.len() < self.tokens.len() {
            lazy.channels.resize(self.tokens.len(), None);
        }
        if let Some(channel) = lazy.channels[robot] {
            return Ok(Some(channel));
        }
        let (name, text) = PROGRAM_SCHEMAS[kind];
        let schema = match lazy.schema {
            Some(schema) => schema,
            None => {
                let schema = self
                    .writer
                    .add_schema(name, "ros2msg", text.as_bytes())
                    .map_err(LogError::Write)?;
                lazy.schema = Some(schema);
                schema
            }
        };
        let topic = format!(
            "/{}/{}",
            self.tokens[robot],
            if kind == 0 { "output" } else { "leds" }
        );
        let owner = std::collections::BTreeMap::from([(
            "robot".to_owned(),
            self.robot_names[robot].clone(),
        )]);
        let channel = self
            .writer
            .add_channel(schema, &topic, "cdr", &owner)
            .map_err(LogError::Write)?;
        self.programs[kind].channels[robot] = Some(channel);
        Ok(Some(channel))
    }
}
