//! The controller protocol: the frames regatta and a controller process exchange over a Unix
//! socket, one request and one reply per controller step. Its other end is written twice, in
//! C (`c/regatta_controller.c`, which the Python module of the next room reuses) and here; the
//! constants below are the contract both keep.
//!
//! Every frame is a little-endian `u32` payload length, then the payload. Three frames exist:
//! - **hello** (regatta → controller, once): the robot (name, model, custom data, paths,
//!   basic time step, synchronisation, supervisor) and its devices, each with its kind, name,
//!   model, parameters and lookup table;
//! - **step** (controller → regatta): the duration asked of `wb_robot_step` (ms) and the
//!   commands queued since the last step, each `(op, device tag, value)`;
//! - **request** (a supervisor → regatta, between steps): one question or change, answered
//!   at once by an **answer** frame ([`request`]);
//! - **reply** (regatta → controller): the simulated time, whether the run goes on, and the
//!   readings due since the last reply, each `(tag, values)` or `(tag, bytes)`.
//!
//! Sensor values travel only when due, so a step costs what the controller enabled.

/// First word of a hello: "RGWB" and the protocol's version.
pub const MAGIC: u32 = u32::from_le_bytes(*b"RGWB");
pub const VERSION: u32 = 1;

/// Device kinds (the C library maps each to its `WB_NODE_*`).
pub mod kind {
    pub const ROTATIONAL_MOTOR: u8 = 1;
    pub const POSITION_SENSOR: u8 = 2;
    pub const DISTANCE_SENSOR: u8 = 3;
    pub const LIGHT_SENSOR: u8 = 4;
    pub const LED: u8 = 5;
    pub const CAMERA: u8 = 6;
    pub const GPS: u8 = 7;
    pub const COMPASS: u8 = 8;
    pub const INERTIAL_UNIT: u8 = 9;
    pub const ACCELEROMETER: u8 = 10;
    pub const GYRO: u8 = 11;
    pub const TOUCH_SENSOR: u8 = 12;
    pub const EMITTER: u8 = 13;
    pub const RECEIVER: u8 = 14;
}

/// The first byte of a controller's frame.
pub mod frame {
    pub const STEP: u8 = 0;
    pub const REQUEST: u8 = 1;
}

/// A supervisor's requests (the byte after [`frame::REQUEST`]).
pub mod request {
    /// → the requester's own node.
    pub const SELF: u8 = 1;
    /// DEF name → node (0: none).
    pub const FROM_DEF: u8 = 2;
    /// node, DEF name inside its PROTO → node.
    pub const FROM_PROTO_DEF: u8 = 3;
    /// node → type name, base type name, DEF name, whether it is a PROTO instance.
    pub const NODE_INFO: u8 = 4;
    /// node, field name → field (0: none) and its `WbFieldType`.
    pub const FIELD: u8 = 5;
    /// field → its value: a count of numbers, the numbers, a string.
    pub const FIELD_GET: u8 = 6;
    /// field, a count of numbers, the numbers, a string.
    pub const FIELD_SET: u8 = 7;
    /// node → position (3), orientation (9, row-major), velocity (6), in the file's axes.
    pub const NODE_STATE: u8 = 8;
    pub const SET_VELOCITY: u8 = 9;
    pub const RESET_PHYSICS: u8 = 10;
    pub const SIMULATION_RESET_PHYSICS: u8 = 11;
    pub const SIMULATION_RESET: u8 = 12;
    pub const SIMULATION_MODE: u8 = 13;
    pub const SIMULATION_QUIT: u8 = 14;
}

/// Commands of a step frame.
pub mod op {
    /// Enable a sensor with a sampling period (ms; 0 disables).
    pub const ENABLE: u8 = 1;
    /// A motor's target position (rad; +∞: velocity control).
    pub const MOTOR_POSITION: u8 = 2;
    /// A motor's velocity (rad/s), already clamped to its maximum by the library.
    pub const MOTOR_VELOCITY: u8 = 3;
    /// An LED's value.
    pub const LED_SET: u8 = 4;
    /// An emitter's packet: the value is its size, its bytes follow the command.
    pub const EMITTER_SEND: u8 = 5;
    /// An emitter's channel.
    pub const EMITTER_CHANNEL: u8 = 6;
    /// An emitter's range (m; −1: unlimited).
    pub const EMITTER_RANGE: u8 = 7;
    /// A receiver's channel.
    pub const RECEIVER_CHANNEL: u8 = 8;
    /// The robot's custom data (tag 0): the value is its size, its bytes follow.
    pub const CUSTOM_DATA: u8 = 9;
}

/// Run states of a reply.
pub mod status {
    pub const RUNNING: u8 = 0;
    /// The run ends: `wb_robot_step` returns −1 and the controller has a second to clean up.
    pub const QUIT: u8 = 1;
}

/// A reading's encoding in a reply.
pub mod reading {
    pub const VALUES: u8 = 0;
    pub const BYTES: u8 = 1;
    /// A receiver's packets: a count, then each one's signal strength, the emitter's
    /// direction (3 values) and its bytes.
    pub const PACKETS: u8 = 2;
    /// The robot's custom data as a supervisor wrote it (tag 0), a string.
    pub const CUSTOM_DATA: u8 = 3;
}

/// A frame being written.
#[derive(Default)]
pub struct Writer {
    bytes: Vec<u8>,
}

impl Writer {
    /// Starts a frame (its length is filled in by [`Writer::finish`]).
    pub fn new() -> Writer {
        Writer { bytes: vec![0; 4] }
    }

    /// Empties the frame for reuse, keeping its buffer.
    pub fn clear(&mut self) {
        self.bytes.clear();
        self.bytes.extend_from_slice(&[0; 4]);
    }

    pub fn u8(&mut self, value: u8) {
        self.bytes.push(value);
    }

    pub fn u16(&mut self, value: u16) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    pub fn u32(&mut self, value: u32) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    pub fn f64(&mut self, value: f64) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// A string: `u32` length, then its UTF-8 bytes (no NUL).
    pub fn str(&mut self, value: &str) {
        self.bytes(value.as_bytes());
    }

    /// Bytes: `u32` length, then the bytes.
    pub fn bytes(&mut self, value: &[u8]) {
        self.u32(value.len() as u32);
        self.bytes.extend_from_slice(value);
    }

    /// Writes the payload's length in front and returns the whole frame.
    pub fn finish(&mut self) -> &[u8] {
        let length = (self.bytes.len() - 4) as u32;
        self.bytes[..4].copy_from_slice(&length.to_le_bytes());
        &self.bytes
    }
}

/// Why a frame could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    #[error("the frame ends early (byte {0})")]
    Short(usize),
    #[error("unknown command {op} for device {tag}")]
    UnknownOp { op: u8, tag: u16 },
    #[error("no device has tag {0}")]
    NoDevice(u16),
}

/// A frame's payload being read.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader { bytes, at: 0 }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], FrameError> {
        let end = self.at.checked_add(n).ok_or(FrameError::Short(self.at))?;
        let slice = self
            .bytes
            .get(self.at..end)
            .ok_or(FrameError::Short(self.at))?;
        self.at = end;
        Ok(slice)
    }

    pub fn u8(&mut self) -> Result<u8, FrameError> {
        Ok(self.take(1)?[0])
    }

    pub fn u16(&mut self) -> Result<u16, FrameError> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub fn i32(&mut self) -> Result<i32, FrameError> {
        let b = self.take(4)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Where the reader stands in the payload.
    pub fn position(&self) -> usize {
        self.at
    }

    /// Skips `n` bytes, returning where they start.
    pub fn skip(&mut self, n: usize) -> Result<usize, FrameError> {
        let start = self.at;
        self.take(n)?;
        Ok(start)
    }

    pub fn u32(&mut self) -> Result<u32, FrameError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A string: `u32` length, then UTF-8 bytes (replaced where they are not).
    pub fn str(&mut self) -> Result<String, FrameError> {
        let n = self.u32()? as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }

    pub fn f64(&mut self) -> Result<f64, FrameError> {
        let b = self.take(8)?;
        let mut word = [0; 8];
        word.copy_from_slice(b);
        Ok(f64::from_le_bytes(word))
    }
}

/// One command of a step frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command {
    pub op: u8,
    /// The device's tag (its index in the hello, plus one).
    pub tag: u16,
    pub value: f64,
    /// Where the bytes that follow the command lie in the payload (an emitter's packet).
    pub data: (usize, usize),
}

/// A step frame: the duration asked (ms) and the commands.
pub fn read_step(payload: &[u8], commands: &mut Vec<Command>) -> Result<i32, FrameError> {
    let mut reader = Reader::new(payload);
    if reader.u8()? != frame::STEP {
        return Err(FrameError::Short(0));
    }
    let duration = reader.i32()?;
    let count = reader.u16()?;
    commands.clear();
    for _ in 0..count {
        let op = reader.u8()?;
        let tag = reader.u16()?;
        let value = reader.f64()?;
        let data = if op == op::EMITTER_SEND || op == op::CUSTOM_DATA {
            if !(value >= 0.0 && value <= u32::MAX as f64) {
                return Err(FrameError::Short(reader.position()));
            }
            let start = reader.skip(value as usize)?;
            (start, start + value as usize)
        } else {
            (0, 0)
        };
        commands.push(Command {
            op,
            tag,
            value,
            data,
        });
    }
    Ok(duration)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_frame_reads_back() {
        let mut payload = vec![frame::STEP];
        payload.extend_from_slice(&32i32.to_le_bytes());
        payload.extend_from_slice(&2u16.to_le_bytes());
        for (op, tag, value) in [(op::ENABLE, 3u16, 64.0f64), (op::MOTOR_VELOCITY, 1, -2.5)] {
            payload.push(op);
            payload.extend_from_slice(&tag.to_le_bytes());
            payload.extend_from_slice(&value.to_le_bytes());
        }
        let mut commands = Vec::new();
        assert_eq!(read_step(&payload, &mut commands), Ok(32));
        assert_eq!(
            commands,
            vec![
                Command {
                    op: op::ENABLE,
                    tag: 3,
                    value: 64.0,
                    data: (0, 0),
                },
                Command {
                    op: op::MOTOR_VELOCITY,
                    tag: 1,
                    value: -2.5,
                    data: (0, 0),
                }
            ]
        );
        // Cut anywhere, it is an error, never a panic.
        for end in 0..payload.len() {
            assert!(read_step(&payload[..end], &mut commands).is_err());
        }
    }

    #[test]
    fn a_frame_carries_its_length() {
        let mut writer = Writer::new();
        writer.u16(7);
        writer.str("ps0");
        let frame = writer.finish().to_vec();
        assert_eq!(
            u32::from_le_bytes([frame[0], frame[1], frame[2], frame[3]]),
            9
        );
        writer.clear();
        assert_eq!(writer.finish(), &[0, 0, 0, 0]);
    }
}
