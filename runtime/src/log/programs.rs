//! What controller programs (Webots controllers, run by `regatta-webots`) add to a log: each
//! line a program prints, and its robot's LEDs whenever they change, on `/{robot}/output` and
//! `/{robot}/leds`. Both belong to the `controller` channel of `--channels`. Their channels are
//! added when a robot's first message comes, so that a run without programs writes the same
//! bytes as before.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use super::error::LogError;

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

/// The channels of one kind (an index into [`PROGRAM_SCHEMAS`]), per robot, made on first use.
#[derive(Default)]
pub(super) struct Lazy {
    schema: Option<u16>,
    channels: Vec<Option<u16>>,
}

impl Lazy {
    /// Robot `robot`'s channel of kind `kind` (0 output, 1 LEDs), added to `writer` on first
    /// use as `/{token}/output` or `/{token}/leds`.
    pub(super) fn channel<W: Write + Seek>(
        &mut self,
        writer: &mut mcap::Writer<W>,
        budget: &mut super::budget::ChannelBudget,
        kind: usize,
        robot: usize,
        token: &str,
        robot_name: &str,
    ) -> Result<u16, LogError> {
        if self.channels.len() <= robot {
            self.channels.resize(robot + 1, None);
        }
        if let Some(channel) = self.channels[robot] {
            return Ok(channel);
        }
        let (name, text) = PROGRAM_SCHEMAS[kind];
        let schema = match self.schema {
            Some(schema) => schema,
            None => {
                let schema = writer
                    .add_schema(name, "ros2msg", text.as_bytes())
                    .map_err(LogError::Write)?;
                self.schema = Some(schema);
                schema
            }
        };
        let topic = format!("/{token}/{}", if kind == 0 { "output" } else { "leds" });
        let owner = BTreeMap::from([("robot".to_owned(), robot_name.to_owned())]);
        let channel = budget.add_channel(writer, schema, &topic, &owner)?;
        self.channels[robot] = Some(channel);
        Ok(channel)
    }
}
