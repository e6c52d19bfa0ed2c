//! The Khepera API: one interface for the simulated robot and the real one.
//!
//! Units are the real robot's (`../shared/reference/khepera.md`): wheel speeds in encoder
//! pulses per 10 ms, positions in pulses, proximity and ambient light 0…1023 (ambient larger
//! when darker), retina values as the converter gives them. Every call is fallible, because on
//! a real robot every call crosses a serial line.

use crate::retina::FilterKind;

/// A wheel speed (pulses per 10 ms) as the robot takes it: rounded half away from zero,
/// clamped to −127 … 127.
#[inline]
pub fn to_command(speed: f64) -> i32 {
    libm::round(speed).clamp(-127.0, 127.0) as i32
}

/// Why a Khepera call failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KheperaError {
    #[error("the robot has no {0}")]
    NoDevice(&'static str),
    #[error("filter {0} is not enabled; enable it before reading it")]
    FilterNotEnabled(&'static str),
    #[error("{what} {value} is out of range ({range})")]
    OutOfRange {
        what: &'static str,
        value: i64,
        range: &'static str,
    },
    #[error("link to the robot failed: {0}")]
    Link(String),
    #[error("the robot answered {got:?} to {command:?}")]
    Protocol { command: String, got: String },
    #[error("the {0} is not refreshed for this controller: declare it in Controller::senses")]
    NotSensed(&'static str),
}

/// The sensors a controller reads. A simulation refreshes only these (and whatever a log
/// records), so a scene pays for no sensor nobody reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Senses {
    pub proximity: bool,
    pub ambient: bool,
    /// The turret's vision device (Panoramic or K213).
    pub vision: bool,
    /// The 2-D colour cameras.
    pub camera: bool,
}

impl Senses {
    /// Every sensor: what a controller reads unless it says otherwise.
    pub const ALL: Senses = Senses {
        proximity: true,
        ambient: true,
        vision: true,
        camera: true,
    };
    /// No sensor.
    pub const NONE: Senses = Senses {
        proximity: false,
        ambient: false,
        vision: false,
        camera: false,
    };
    /// What a robot driven over the Khepera serial protocol can read: everything but the 2-D
    /// cameras, which the protocol has no message for.
    pub const PROTOCOL: Senses = Senses {
        camera: false,
        ..Senses::ALL
    };

    /// The sensors either set holds.
    pub fn union(self, other: Senses) -> Senses {
        Senses {
            proximity: self.proximity | other.proximity,
            ambient: self.ambient | other.ambient,
            vision: self.vision | other.vision,
            camera: self.camera | other.camera,
        }
    }
}

/// What an LED does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LedAction {
    Off,
    On,
    Toggle,
}

/// The robot itself: motors, encoders, the 8 IR sensors, the 2 LEDs, and its turret.
pub trait Khepera {
    /// Sets both wheel speeds (pulses per 10 ms; the real robot accepts −127…127).
    fn set_speed(&mut self, left: i32, right: i32) -> Result<(), KheperaError>;
    /// Reads the wheel speeds (pulses per 10 ms).
    fn speed(&mut self) -> Result<(i32, i32), KheperaError>;
    /// Reads the position counters (pulses).
    fn position(&mut self) -> Result<(i32, i32), KheperaError>;
    /// Sets the position counters (`0, 0` resets them).
    fn set_position(&mut self, left: i32, right: i32) -> Result<(), KheperaError>;
    /// Proximity sensors 0…7, 0…1023, larger when closer.
    fn proximity(&mut self) -> Result<[u16; 8], KheperaError>;
    /// Ambient light sensors 0…7, 0…1023, larger when darker.
    fn ambient(&mut self) -> Result<[u16; 8], KheperaError>;
    /// LED 0 or 1.
    fn set_led(&mut self, led: u8, action: LedAction) -> Result<(), KheperaError>;
    /// The Panoramic turret, if mounted.
    fn panoramic(&mut self) -> Option<&mut dyn PanoramicTurret>;
    /// The K213 linear camera, if mounted.
    fn linear_camera(&mut self) -> Option<&mut dyn LinearCameraTurret>;
    /// The robot's 2-D colour cameras (the e-puck's), in the order it carries them; none
    /// unless the backend has them.
    fn cameras(&mut self) -> Vec<&mut dyn Camera> {
        Vec::new()
    }
}

/// A 2-D colour camera.
pub trait Camera {
    /// Its name in the world.
    fn name(&self) -> &str;
    /// Width and height in pixels.
    fn size(&self) -> (usize, usize);
    /// The last image: row-major RGB, 3 bytes a pixel, the top row first.
    fn image(&mut self) -> Result<Vec<u8>, KheperaError>;
}

/// The Panoramic turret (EDI retina).
pub trait PanoramicTurret {
    fn enable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError>;
    fn disable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError>;
    /// One filter's converted output over the region of interest; an error if not enabled.
    fn read(&mut self, filter: FilterKind) -> Result<Vec<u16>, KheperaError>;
    /// [`PanoramicTurret::read`] into `out`, which a robot may fill without allocating.
    fn read_into(&mut self, filter: FilterKind, out: &mut Vec<u16>) -> Result<(), KheperaError> {
        *out = self.read(filter)?;
        Ok(())
    }
    /// Sets the space constant λ (pixels) of the lowpass, highpass and odd networks; the API's
    /// spatial cutoff is 1/λ.
    fn set_lambda(&mut self, lambda: f64) -> Result<(), KheperaError>;
    /// Sets the converter's resolution (1…16 bits).
    fn set_bits(&mut self, bits: u32) -> Result<(), KheperaError>;
    /// Sets the region of interest (first and last pixel, 0…149).
    fn set_region_of_interest(&mut self, first: usize, last: usize) -> Result<(), KheperaError>;
    /// The region of interest.
    fn region_of_interest(&mut self) -> Result<(usize, usize), KheperaError>;
    /// The converter's resolution.
    fn bits(&mut self) -> Result<u32, KheperaError>;
    /// The space constant λ.
    fn lambda(&mut self) -> Result<f64, KheperaError>;
}

/// The K213 linear vision turret.
pub trait LinearCameraTurret {
    /// The 64 grey levels, pixel 0 at the left.
    fn pixels(&mut self) -> Result<Vec<u16>, KheperaError>;
    /// The light-level sensor (0…255).
    fn light_level(&mut self) -> Result<u16, KheperaError>;
}

/// A controller: called once per control period (the robot's `controlPeriod`, a whole
/// number of physics steps) with the robot to read and drive; its commands hold until the
/// next call. Whatever it times, it times in seconds, given the period when it is built.
pub trait Controller: Send {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError>;

    /// The sensors [`Controller::step`] reads; a simulated robot refreshes no other (reading
    /// one is then [`KheperaError::NotSensed`]). Every sensor unless a controller narrows it.
    fn senses(&self) -> Senses {
        Senses::ALL
    }
}
