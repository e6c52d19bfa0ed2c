//! Sensor logs: every sensor and actuator of every robot, at each sensor's own rate, in MCAP.
//!
//! Format decisions:
//! - One channel per robot and sensor: `/{robot}/pose`, `/wheels`, `/proximity`, `/ambient`,
//!   `/retina`, `/k213`, `/contacts` (when contact begins or ends, with what is touched),
//!   `/visits` (each entry into a buoy's visit disc), `/controller` (regatta's own schemas:
//!   the reproducible record), and beside them Foxglove's well-known schemas (`foxglove`:
//!   scene, transforms, poses, images, events) so that Foxglove and ROS 2 tools show a log
//!   as it is. `{robot}` is the robot's name made a valid ROS 2 token (`channels`);
//!   `--channels` picks the channels a log holds, and the log's metadata says which.
//! - Chunks close every [`CHUNK_SECONDS`] of simulated time or at [`CHUNK_BYTES`]
//!   (uncompressed), whichever comes first, and go to the file as they close: a crash or a full
//!   disk loses at most that much of a run, and the reader keeps every complete chunk. zstd
//!   level 1.
//! - Messages are CDR-encoded with a `ros2msg` schema per channel (the ROS 2 convention that
//!   Foxglove and the MCAP tools decode without code generation). Binary was chosen over JSON
//!   for speed and size: JSON made a ten-minute regatta log 43 MB and logging 10× slower.
//!   Retina analog and filtered values are float32, poses and times float64.
//! - A metadata record `regatta` holds the world file's text and SHA-256, the seed, regatta's
//!   version and every setting needed to run it again; a closing record `regatta.end` holds the
//!   steps done and whether the run was interrupted.
//! - Log time is simulated time in nanoseconds. Nothing in a log depends on wall time, so the
//!   same world, seed and version give byte-identical files.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use sha2::{Digest, Sha256};

use crate::khepera::Senses;
use crate::sim::Simulation;

mod budget;
mod cdr;
mod channels;
mod error;
mod foxglove;
mod programs;

use budget::ChannelBudget;
pub use budget::MOST_CHANNELS;
pub use cdr::{Cdr, CdrReader, ShortMessage};
pub use channels::{is_ros2_topic, robot_tokens, sanitize, Channel, Channels, UnknownChannel};
pub use error::LogError;
pub use foxglove::SCHEMAS as FOXGLOVE_SCHEMAS;
pub use programs::PROGRAM_SCHEMAS;

/// What a run needs to be repeated, stored in the log.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    /// The world file's name as given.
    pub world_name: String,
    /// The world file's text.
    pub world_text: String,
    pub seed: u64,
    pub lenient: bool,
    pub steps_requested: u64,
    /// The channels recorded.
    pub channels: Channels,
    /// Robots whose controller is not the one their world gives (a `--controller` override,
    /// a Webots name mapped to a built-in, lenient mode's fallback): (robot, controller,
    /// controllerArgs). Written only when there is one, so other logs do not change.
    pub controllers: Vec<(String, String, Vec<String>)>,
    /// The values `--vary` drew for the run, as JSON, when it drew any (the world text
    /// already holds them: this says which they were). Written only when there are some.
    pub variations: Option<String>,
}

impl RunInfo {
    /// The metadata record's entries.
    pub fn to_metadata(&self, time_step: f64) -> BTreeMap<String, String> {
        let mut hash = Sha256::new();
        hash.update(self.world_text.as_bytes());
        let digest: String = hash.finalize().iter().map(|b| format!("{b:02x}")).collect();
        let mut metadata = BTreeMap::from([
            ("world_name".to_owned(), self.world_name.clone()),
            ("world".to_owned(), self.world_text.clone()),
            ("world_sha256".to_owned(), digest),
            ("seed".to_owned(), self.seed.to_string()),
            ("lenient".to_owned(), self.lenient.to_string()),
            (
                "steps_requested".to_owned(),
                self.steps_requested.to_string(),
            ),
            ("time_step".to_owned(), format!("{time_step}")),
            ("channels".to_owned(), self.channels.to_string()),
            (
                "regatta_version".to_owned(),
                env!("CARGO_PKG_VERSION").to_owned(),
            ),
        ]);
        if !self.controllers.is_empty() {
            let lines: Vec<String> = self
                .controllers
                .iter()
                .map(|(robot, controller, args)| {
                    format!("{robot}\t{controller}\t{}", args.join("\u{1f}"))
                })
                .collect();
            metadata.insert("controllers".to_owned(), lines.join("\n"));
        }
        if let Some(variations) = &self.variations {
            metadata.insert("variations".to_owned(), variations.clone());
        }
        metadata
    }

    /// Reads the metadata back.
    pub fn from_metadata(metadata: &BTreeMap<String, String>) -> Result<RunInfo, LogError> {
        let get = |key: &'static str| metadata.get(key).ok_or(LogError::MissingField(key));
        Ok(RunInfo {
            world_name: get("world_name")?.clone(),
            world_text: get("world")?.clone(),
            seed: get("seed")?
                .parse()
                .map_err(|_| LogError::MissingField("seed"))?,
            lenient: get("lenient")? == "true",
            steps_requested: get("steps_requested")?
                .parse()
                .map_err(|_| LogError::MissingField("steps_requested"))?,
            // Logs from before `--channels` hold regatta's own channels.
            channels: match metadata.get("channels") {
                Some(names) => names
                    .parse()
                    .map_err(|_| LogError::MissingField("channels"))?,
                None => Channels::REGATTA,
            },
            controllers: metadata
                .get("controllers")
                .map(|text| {
                    text.lines()
                        .filter_map(|line| {
                            let mut parts = line.splitn(3, '\t');
                            let robot = parts.next()?.to_owned();
                            let controller = parts.next()?.to_owned();
                            let args = parts
                                .next()
                                .unwrap_or("")
                                .split('\u{1f}')
                                .filter(|a| !a.is_empty())
                                .map(str::to_owned)
                                .collect();
                            Some((robot, controller, args))
                        })
                        .collect()
                })
                .unwrap_or_default(),
            variations: metadata.get("variations").cloned(),
        })
    }
}

/// The channels of one robot (`None`: not recorded).
struct RobotChannels {
    pose: Option<u16>,
    wheels: Option<u16>,
    proximity: Option<u16>,
    ambient: Option<u16>,
    retina: Option<u16>,
    k213: Option<u16>,
    contacts: Option<u16>,
    visits: Option<u16>,
    controller: Option<u16>,
}

/// Writes a run's messages, step by step.
pub struct Recorder<W: Write + Seek> {
    writer: mcap::Writer<W>,
    /// The channels added so far, against what one file can number.
    budget: ChannelBudget,
    robots: Vec<RobotChannels>,
    foxglove: Option<foxglove::Foxglove>,
    /// What robots can touch, named once ([`Simulation::obstacle_names`]).
    obstacle_names: Vec<String>,
    /// Per robot: visits already written.
    visits_written: Vec<usize>,
    sequence: u32,
    cdr: Cdr,
    /// Simulated time at which the open chunk is closed and written out.
    chunk_closes_at: f64,
    /// The channels the log holds, the robots' topic tokens and names (for the channels of
    /// controller programs, made on first use).
    wanted: Channels,
    tokens: Vec<String>,
    robot_names: Vec<String>,
    programs: [programs::Lazy; 2],
}

/// Simulated seconds as a log time (ns).
fn ns(seconds: f64) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

/// Simulated seconds a chunk covers at most: a crash or a full disk loses at most this much
/// of a run (or [`CHUNK_BYTES`] of messages, whichever is less). Chunks close at simulated
/// times, never at clock times, so that the same run writes the same bytes.
pub const CHUNK_SECONDS: f64 = 10.0;

/// Uncompressed bytes a chunk holds at most (about 40 simulated seconds of one robot with
/// every channel). Closing a chunk waits for its compression, which otherwise runs beside
/// the simulation: closing every 2 s cost a third of a logging run's speed, every 10 s about
/// a tenth of `bench step`'s in-memory logging and nothing measurable writing a file.
pub const CHUNK_BYTES: u64 = 4 << 20;

/// The `ros2msg` schemas, one per message type.
pub const SCHEMAS: &[(&str, &str)] = &[
    ("regatta/msg/Pose", "# Ground-truth pose: time (s), x and z (m), heading (rad, counter-clockwise from +x)\nfloat64 t\nfloat64 x\nfloat64 z\nfloat64 heading\n"),
    ("regatta/msg/Wheels", "# Wheel commands (pulses per 10 ms) and encoders (pulses)\nfloat64 t\nint32 command_left\nint32 command_right\nint32 encoder_left\nint32 encoder_right\n"),
    ("regatta/msg/Readings8", "# Eight sensor readings, 0..1023\nfloat64 t\nuint16[8] values\n"),
    ("regatta/msg/Retina", "# EDI retina: analog[150]; per enabled filter (in `filters` order) 150 filtered values and the digital values over the region of interest\nfloat64 t\nbool dark\nuint16 roi_first\nuint16 roi_last\nfloat32[] analog\nstring[] filters\nfloat32[] filtered\nuint16[] digital\n"),
    ("regatta/msg/LinearCamera", "# K213: grey levels, pixel 0 at the left, and the light level\nfloat64 t\nuint16[] pixels\nuint16 light_level\n"),
    ("regatta/msg/Contact", "# A contact began (touching) or ended; contacts begun so far; what is touched now\nfloat64 t\nbool touching\nuint64 contacts\nstring[] with\n"),
    ("regatta/msg/Visit", "# The robot entered a buoy's visit disc (its radius plus two body diameters): buoy number (from 1, in file order), its name, visits so far\nfloat64 t\nuint32 buoy\nstring name\nuint32 visits\n"),
    ("regatta/msg/ControllerEvent", "# A controller call failed\nfloat64 t\nstring error\n"),
];

/// A `/{robot}/pose` message: its time (s) and the pose.
pub fn decode_pose(data: &[u8]) -> Result<(f64, crate::compile::rig::Pose2), ShortMessage> {
    let mut r = CdrReader::new(data);
    Ok((
        r.f64()?,
        crate::compile::rig::Pose2 {
            x: r.f64()?,
            z: r.f64()?,
            heading: r.f64()?,
        },
    ))
}

impl<W: Write + Seek> Recorder<W> {
    /// Starts a log for `simulation`, writing the header, metadata, schemas and the channels
    /// `run.channels` names. From now on the simulation refreshes every sensor those channels
    /// record, read or not (see [`Simulation::always_sensed`]).
    pub fn new(
        sink: W,
        simulation: &mut Simulation,
        run: &RunInfo,
    ) -> Result<Recorder<W>, LogError> {
        let wanted = run.channels;
        simulation.always_sensed = Senses {
            proximity: wanted.contains(Channel::Proximity),
            ambient: wanted.contains(Channel::Ambient),
            vision: wanted.contains(Channel::Retina)
                || wanted.contains(Channel::K213)
                || wanted.contains(Channel::Images),
            camera: wanted.contains(Channel::Images),
        };
        let simulation = &*simulation;
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(CHUNK_BYTES))
            .compression_level(1)
            .library(format!("regatta {}", env!("CARGO_PKG_VERSION")))
            .profile("");
        let mut writer = options.create(sink).map_err(LogError::Write)?;
        writer
            .write_metadata(&mcap::records::Metadata {
                name: "regatta".to_owned(),
                metadata: run.to_metadata(simulation.time_step),
            })
            .map_err(LogError::Write)?;
        let mut schema = BTreeMap::new();
        let kinds = [
            (Channel::Pose, "regatta/msg/Pose"),
            (Channel::Wheels, "regatta/msg/Wheels"),
            (Channel::Proximity, "regatta/msg/Readings8"),
            (Channel::Ambient, "regatta/msg/Readings8"),
            (Channel::Retina, "regatta/msg/Retina"),
            (Channel::K213, "regatta/msg/LinearCamera"),
            (Channel::Contacts, "regatta/msg/Contact"),
            (Channel::Visits, "regatta/msg/Visit"),
            (Channel::Controller, "regatta/msg/ControllerEvent"),
        ];
        for (name, text) in SCHEMAS {
            if kinds.iter().any(|(c, s)| s == name && wanted.contains(*c)) {
                schema.insert(
                    *name,
                    writer
                        .add_schema(name, "ros2msg", text.as_bytes())
                        .map_err(LogError::Write)?,
                );
            }
        }
        let tokens = robot_tokens(simulation.robots.iter().map(|r| r.name.as_str()));
        let mut budget = ChannelBudget {
            added: 0,
            robots: simulation.robots.len(),
        };
        let mut robots = Vec::new();
        for (robot, token) in simulation.robots.iter().zip(&tokens) {
            let owner = BTreeMap::from([("robot".to_owned(), robot.name.clone())]);
            let mut channel = |kind: Channel, present: bool| -> Result<Option<u16>, LogError> {
                if !present || !wanted.contains(kind) {
                    return Ok(None);
                }
                let schema_name = kinds
                    .iter()
                    .find(|(c, _)| *c == kind)
                    .map(|(_, s)| *s)
                    .expect("every regatta channel has a schema");
                budget
                    .add_channel(
                        &mut writer,
                        schema[schema_name],
                        &format!("/{token}/{}", kind.name()),
                        &owner,
                    )
                    .map(Some)
            };
            robots.push(RobotChannels {
                pose: channel(Channel::Pose, true)?,
                wheels: channel(Channel::Wheels, true)?,
                proximity: channel(Channel::Proximity, true)?,
                ambient: channel(Channel::Ambient, true)?,
                retina: channel(Channel::Retina, robot.panoramic.is_some())?,
                k213: channel(Channel::K213, robot.linear_camera.is_some())?,
                contacts: channel(Channel::Contacts, true)?,
                visits: channel(Channel::Visits, true)?,
                controller: channel(Channel::Controller, true)?,
            });
        }
        let mut cdr = Cdr {
            buf: Vec::with_capacity(4096),
        };
        let mut sequence = 0;
        let foxglove = if wanted.any_foxglove() {
            Some(foxglove::Foxglove::new(
                (&mut writer, &mut budget),
                &mut cdr,
                &mut sequence,
                simulation,
                wanted,
                &tokens,
                &run.world_name,
            )?)
        } else {
            None
        };
        Ok(Recorder {
            writer,
            budget,
            robots,
            foxglove,
            obstacle_names: simulation.obstacle_names(),
            visits_written: vec![0; simulation.robots.len()],
            sequence,
            cdr,
            chunk_closes_at: simulation.time + CHUNK_SECONDS,
            wanted,
            robot_names: simulation.robots.iter().map(|r| r.name.clone()).collect(),
            tokens,
            programs: Default::default(),
        })
    }

    /// Writes the message encoded in `self.cdr` (nothing when the channel is not recorded).
    fn write(&mut self, channel: Option<u16>, time_ns: u64) -> Result<(), LogError> {
        let Some(channel) = channel else {
            return Ok(());
        };
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: time_ns,
            publish_time: time_ns,
        };
        self.writer
            .write_to_known_channel(&header, &self.cdr.buf)
            .map_err(LogError::Write)
    }

    /// Records what the last step produced: the pose and wheels every step, sensors when they
    /// updated, contacts and controller errors when they happened.
    pub fn record(&mut self, simulation: &Simulation) -> Result<(), LogError> {
        // Sensors were read at the start of the step, the pose is the end of it.
        let t = simulation.time;
        let read_at = t - simulation.time_step;
        for (index, robot) in simulation.robots.iter().enumerate() {
            let rig = &simulation.compiled.rig.robots[index];
            let channels = &self.robots[index];
            let (pose, wheels, proximity, ambient, retina, k213, contacts, visits, controller) = (
                channels.pose,
                channels.wheels,
                channels.proximity,
                channels.ambient,
                channels.retina,
                channels.k213,
                channels.contacts,
                channels.visits,
                channels.controller,
            );
            let updated = robot.updated;
            if updated.proximity && proximity.is_some() {
                self.cdr.start();
                self.cdr.f64(read_at);
                robot.proximity.iter().for_each(|&v| self.cdr.u16(v));
                self.write(proximity, ns(read_at))?;
            }
            if updated.ambient && ambient.is_some() {
                self.cdr.start();
                self.cdr.f64(read_at);
                robot.ambient.iter().for_each(|&v| self.cdr.u16(v));
                self.write(ambient, ns(read_at))?;
            }
            if updated.vision {
                if let (Some(channel), Some(turret)) = (retina, &robot.panoramic) {
                    let channel = Some(channel);
                    let out = &turret.output;
                    let roi = turret.model.rig.roi;
                    let cdr = &mut self.cdr;
                    cdr.start();
                    cdr.f64(read_at);
                    cdr.bool(out.dark);
                    cdr.u16(roi.0 as u16);
                    cdr.u16(roi.1 as u16);
                    cdr.f32s(out.analog.iter().copied());
                    cdr.u32(out.filtered.len() as u32);
                    for (kind, _) in &out.filtered {
                        cdr.string(kind.name());
                    }
                    let total: usize = out.filtered.iter().map(|(_, v)| v.len()).sum();
                    cdr.u32(total as u32);
                    for (_, values) in &out.filtered {
                        for &x in values {
                            cdr.buf.extend_from_slice(&(x as f32).to_le_bytes());
                        }
                    }
                    let total: usize = out.digital.iter().map(|(_, v)| v.len()).sum();
                    cdr.u32(total as u32);
                    for (_, values) in &out.digital {
                        for &x in values {
                            cdr.buf.extend_from_slice(&x.to_le_bytes());
                        }
                    }
                    self.write(channel, ns(read_at))?;
                }
                if let (Some(channel), Some(camera)) = (k213, &robot.linear_camera) {
                    let channel = Some(channel);
                    self.cdr.start();
                    self.cdr.f64(read_at);
                    self.cdr.u16s(&camera.output.digital);
                    self.cdr.u16(camera.output.light_level);
                    self.write(channel, ns(read_at))?;
                }
            }
            if updated.controller_error && controller.is_some() {
                self.cdr.start();
                self.cdr.f64(read_at);
                self.cdr
                    .string(robot.last_controller_error.as_deref().unwrap_or(""));
                self.write(controller, ns(read_at))?;
            }
            let (left, right) = robot.counters(rig);
            if wheels.is_some() {
                self.cdr.start();
                self.cdr.f64(t);
                self.cdr.i32(robot.command.0);
                self.cdr.i32(robot.command.1);
                self.cdr.i32(left);
                self.cdr.i32(right);
                self.write(wheels, ns(t))?;
            }
            if pose.is_some() {
                self.cdr.start();
                self.cdr.f64(t);
                self.cdr.f64(robot.pose.x);
                self.cdr.f64(robot.pose.z);
                self.cdr.f64(robot.pose.heading);
                self.write(pose, ns(t))?;
            }
            if updated.contact && contacts.is_some() {
                self.cdr.start();
                self.cdr.f64(t);
                self.cdr.bool(robot.contacts.is_touching());
                self.cdr.u64(robot.contacts.events);
                let touching = robot.contacts.touching();
                self.cdr.u32(touching.len() as u32);
                for &obstacle in touching {
                    self.cdr.string(&self.obstacle_names[obstacle as usize]);
                }
                self.write(contacts, ns(t))?;
            }
            let landmarks = &simulation.compiled.landmarks;
            while self.visits_written[index] < robot.visits.sequence.len() {
                let n = self.visits_written[index];
                let buoy = robot.visits.sequence[n];
                self.cdr.start();
                self.cdr.f64(robot.visits.times[n]);
                self.cdr.u32(buoy as u32 + 1);
                self.cdr.string(&landmarks[buoy].name);
                self.cdr.u32(n as u32 + 1);
                self.write(visits, ns(robot.visits.times[n]))?;
                self.visits_written[index] += 1;
            }
        }
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.record(
                &mut self.writer,
                &mut self.cdr,
                &mut self.sequence,
                simulation,
            )?;
        }
        if t >= self.chunk_closes_at {
            // Closes the chunk and hands its bytes to the sink, so that they are on disk (or
            // the disk's refusal is known) before the run goes on.
            self.writer.flush().map_err(LogError::Write)?;
            while self.chunk_closes_at <= t {
                self.chunk_closes_at += CHUNK_SECONDS;
            }
        }
        Ok(())
    }

    /// Records a line that robot `robot`'s controller program printed at simulated time `t`
    /// (`/{robot}/output`, with the `controller` channel).
    pub fn record_output(&mut self, robot: usize, t: f64, line: &str) -> Result<(), LogError> {
        let Some(channel) = self.program_channel(robot, 0)? else {
            return Ok(());
        };
        self.cdr.start();
        self.cdr.f64(t);
        self.cdr.string(line);
        self.write(Some(channel), ns(t))
    }

    /// Records robot `robot`'s LEDs (name and value each) after its controller program
    /// changed one at time `t` (`/{robot}/leds`, with the `controller` channel).
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
        self.write(Some(channel), ns(t))
    }

    /// A program's channel of kind `kind` for `robot`; `None` when the log does not hold
    /// the `controller` channel or there is no such robot.
    fn program_channel(&mut self, robot: usize, kind: usize) -> Result<Option<u16>, LogError> {
        if !self.wanted.contains(Channel::Controller) || robot >= self.tokens.len() {
            return Ok(None);
        }
        self.programs[kind]
            .channel(
                &mut self.writer,
                &mut self.budget,
                kind,
                robot,
                &self.tokens[robot],
                &self.robot_names[robot],
            )
            .map(Some)
    }

    /// Closes the log with its end record.
    pub fn finish(
        mut self,
        simulation: &Simulation,
        interrupted: bool,
    ) -> Result<LogStats, LogError> {
        let end = BTreeMap::from([
            ("steps".to_owned(), simulation.steps.to_string()),
            ("time".to_owned(), format!("{}", simulation.time)),
            ("interrupted".to_owned(), interrupted.to_string()),
        ]);
        let mut end = end;
        // Robots that fell off the world: only then is the key written.
        for robot in &simulation.robots {
            if let Some(fall) = &robot.fell {
                end.insert(
                    format!("fell.{}", robot.name),
                    format!("t={} x={} z={}", fall.time, fall.pose.x, fall.pose.z),
                );
            }
        }
        self.writer
            .write_metadata(&mcap::records::Metadata {
                name: "regatta.end".to_owned(),
                metadata: end,
            })
            .map_err(LogError::Write)?;
        let summary = self.writer.finish().map_err(LogError::Write)?;
        Ok(LogStats {
            messages: summary.stats.map_or(0, |stats| stats.message_count),
        })
    }
}

/// What a finished log holds, for the line a command prints about it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogStats {
    /// Messages written, on every channel.
    pub messages: u64,
}

/// A channel of a log.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicInfo {
    pub topic: String,
    /// Its schema's name (`regatta/msg/Pose`, `foxglove_msgs/msg/FrameTransform`, …).
    pub schema: String,
    pub message_encoding: String,
    /// The robot it belongs to (its own name, before sanitising), if any.
    pub robot: Option<String>,
}

/// A log read back.
pub struct LogContents {
    pub run: RunInfo,
    /// Every channel, in the order they were added.
    pub topics: Vec<TopicInfo>,
    /// The `regatta` metadata record as written (world hash, version, time step, …).
    pub metadata: BTreeMap<String, String>,
    /// The run's basic time step (s), when the log says it.
    pub time_step: Option<f64>,
    /// The end record's entries, if the run finished writing it.
    pub end: Option<BTreeMap<String, String>>,
    /// (topic, log time ns, CDR bytes), in file order.
    pub messages: Vec<(String, u64, Vec<u8>)>,
    /// Set when the file ends before its end (a killed or truncated recording): the messages
    /// of every complete chunk are still there.
    pub truncated: Option<String>,
}

/// Largest uncompressed chunk a log may claim: regatta writes chunks of at most about 1 MB, and a
/// damaged or hostile header must not make the reader allocate what it says.
const MAX_CHUNK: u64 = 256 << 20;

/// The longest prefix of `bytes` whose records are framed soundly (lengths within the file,
/// chunks of sane sizes), and why it ends early, if it does. MCAP frames every record as an
/// opcode byte and a little-endian u64 length; a chunk (opcode 6) gives its uncompressed size
/// at bytes 16..24 of its body.
fn sound_prefix(bytes: &[u8]) -> (&[u8], Option<String>) {
    const MAGIC: usize = 8;
    let mut at = MAGIC.min(bytes.len());
    while at < bytes.len() {
        let Some(header) = bytes.get(at..at + 9) else {
            return (&bytes[..at], None);
        };
        let length = u64::from_le_bytes(header[1..9].try_into().unwrap_or_default());
        let body_start = at + 9;
        let end = match usize::try_from(length)
            .ok()
            .and_then(|l| body_start.checked_add(l))
        {
            Some(end) if end <= bytes.len() => end,
            // Cut short: the reader says so itself.
            _ => return (&bytes[..at], None),
        };
        if header[0] == 0x06 {
            let claimed = bytes
                .get(body_start + 16..body_start + 24)
                .map(|b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
                .unwrap_or(u64::MAX);
            if claimed > MAX_CHUNK {
                return (
                    &bytes[..at],
                    Some(format!(
                        "a chunk at byte {at} claims {claimed} bytes uncompressed: the log is damaged there"
                    )),
                );
            }
        }
        if header[0] == 0x02 {
            // The footer: the file ends here.
            return (&bytes[..end], None);
        }
        at = end;
    }
    (bytes, None)
}

/// The reader's bounds: every length at most [`MAX_CHUNK`] (a damaged length must not make it
/// allocate what it says), every chunk's CRC checked before its records are read.
fn reader_options() -> mcap::sans_io::LinearReaderOptions {
    mcap::sans_io::LinearReaderOptions::default()
        .with_skip_end_magic(true)
        .with_record_length_limit(MAX_CHUNK as usize)
        .with_prevalidate_chunk_crcs(true)
}

/// Calls `visit` on every record of `bytes`, chunks flattened; returns why reading stopped
/// early, if it did.
fn each_record(
    bytes: &[u8],
    mut visit: impl FnMut(mcap::records::Record<'_>) -> Result<(), LogError>,
) -> Result<Option<String>, LogError> {
    let mut reader = mcap::sans_io::LinearReader::new_with_options(reader_options());
    let mut at = 0;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(mcap::sans_io::LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(bytes.len() - at);
                reader.insert(n).copy_from_slice(&bytes[at..at + n]);
                reader.notify_read(n);
                at += n;
            }
            Ok(mcap::sans_io::LinearReadEvent::Record { data, opcode }) => {
                match mcap::parse_record(opcode, data) {
                    Ok(record) => visit(record)?,
                    Err(error) => return Ok(Some(error.to_string())),
                }
            }
            Err(error) => return Ok(Some(error.to_string())),
        }
    }
    Ok(None)
}

/// Reads a log; a file cut short or damaged yields what its complete chunks hold, and says so.
pub fn read(bytes: &[u8]) -> Result<LogContents, LogError> {
    let (bytes, damaged) = sound_prefix(bytes);
    let mut run = None;
    let mut time_step = None;
    let mut end = None;
    let mut schemas = BTreeMap::new();
    let mut topics = Vec::new();
    let mut raw_metadata = BTreeMap::new();
    let stopped = each_record(bytes, |record| {
        match record {
            mcap::records::Record::Schema { header, .. } => {
                schemas.insert(header.id, header.name);
            }
            mcap::records::Record::Channel(channel)
                if !topics.iter().any(|t: &TopicInfo| t.topic == channel.topic) =>
            {
                topics.push(TopicInfo {
                    schema: schemas.get(&channel.schema_id).cloned().unwrap_or_default(),
                    robot: channel.metadata.get("robot").cloned(),
                    topic: channel.topic,
                    message_encoding: channel.message_encoding,
                });
            }
            mcap::records::Record::Metadata(metadata) if metadata.name == "regatta" => {
                time_step = metadata
                    .metadata
                    .get("time_step")
                    .and_then(|t| t.parse::<f64>().ok())
                    .filter(|t| *t > 0.0 && t.is_finite());
                run = Some(RunInfo::from_metadata(&metadata.metadata)?);
                raw_metadata = metadata.metadata;
            }
            mcap::records::Record::Metadata(metadata) if metadata.name == "regatta.end" => {
                end = Some(metadata.metadata)
            }
            _ => {}
        }
        Ok(())
    })?;
    let mut truncated = damaged.or(stopped);
    let run = run.ok_or(LogError::NoMetadata)?;
    let mut messages = Vec::new();
    let stream = mcap::io::MessageReader::new_with_options(bytes, reader_options());
    for message in stream {
        match message {
            Ok(message) => messages.push((
                message.channel.topic.clone(),
                message.log_time,
                message.data.into_owned(),
            )),
            Err(error) => {
                truncated.get_or_insert(error.to_string());
                break;
            }
        }
    }
    if end.is_none() && truncated.is_none() {
        truncated = Some("the log has no end record".to_owned());
    }
    Ok(LogContents {
        run,
        topics,
        metadata: raw_metadata,
        time_step,
        end,
        messages,
        truncated,
    })
}
