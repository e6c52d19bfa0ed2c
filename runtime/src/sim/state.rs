//! What a simulation keeps of each robot from step to step (its pose, commands, readings and
//! their due times, noise streams, devices, contacts, visits and falls), the step's working
//! buffers, and the wall-time profile of its phases.

use glam::DVec2;

use super::noise::Stream;
use crate::compile::rig::{Pose2, RobotRig};
use crate::khepera::{Controller, Senses};
use crate::optics::{LinearCamera, LinearCameraOutput, Panoramic, RetinaOutput};
use crate::render::Poses;
use crate::vision::VisionRequest;

/// Which sensor readings a step refreshed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Updated {
    pub proximity: bool,
    pub ambient: bool,
    pub vision: bool,
    /// Which 2-D cameras took an image (bit i: camera i).
    pub cameras: u64,
    /// A contact began or ended.
    pub contact: bool,
    /// The controller returned an error.
    pub controller_error: bool,
}

/// Contact bookkeeping of one robot.
#[derive(Clone, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Contacts {
    // First what every step's end reads ([`RobotState`] lays it beside the robot's other
    // bookkeeping of the step).
    /// The obstacles touched at the end of the last step, ascending.
    pub(super) touching: Vec<u32>,
    pub(super) current: f64,
    /// Times a contact began.
    pub events: u64,
    /// Steps that ended in contact.
    pub steps: u64,
    /// Longest unbroken contact (s).
    pub longest: f64,
    /// Contact events per obstacle, for the obstacles ever touched, by obstacle (static
    /// obstacles are numbered first, then robots): kept sparse, so that a swarm's table grows
    /// with its contacts, not with the square of its size.
    pub per_obstacle: Vec<(u32, u64)>,
}

impl Contacts {
    /// Whether the robot ended the last step touching something.
    pub fn is_touching(&self) -> bool {
        !self.touching.is_empty()
    }

    /// Contact events with one obstacle (static obstacles first, then robots).
    pub fn events_with(&self, obstacle: usize) -> u64 {
        self.per_obstacle
            .binary_search_by_key(&(obstacle as u32), |&(k, _)| k)
            .map_or(0, |i| self.per_obstacle[i].1)
    }

    #[inline]
    pub(super) fn count_event(&mut self, obstacle: u32) {
        match self
            .per_obstacle
            .binary_search_by_key(&obstacle, |&(k, _)| k)
        {
            Ok(i) => self.per_obstacle[i].1 += 1,
            Err(i) => self.per_obstacle.insert(i, (obstacle, 1)),
        }
    }

    /// The obstacles it ended the last step touching, ascending (indices into
    /// `Simulation::obstacle_names`).
    pub fn touching(&self) -> &[u32] {
        &self.touching
    }
}

/// Visits to the world's landmarks (buoys).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Visits {
    /// Landmark indices in the order they were entered.
    pub sequence: Vec<usize>,
    /// When each entry of `sequence` happened (simulated s, the end of the step).
    pub times: Vec<f64>,
}

impl Visits {
    /// The radius of the disc a robot's centre enters to visit a landmark of `radius`: the
    /// landmark's radius plus two body diameters.
    #[inline]
    pub fn disc_radius(radius: f64, body_radius: f64) -> f64 {
        radius + 4.0 * body_radius
    }
}

/// The Panoramic turret of a simulated robot.
pub struct PanoramicState {
    pub model: Panoramic,
    pub output: RetinaOutput,
    pub(super) due: f64,
    /// Whether the turret is refreshed (someone reads it).
    pub(super) sensed: bool,
}

/// The K213 of a simulated robot.
pub struct LinearCameraState {
    pub model: LinearCamera,
    pub output: LinearCameraOutput,
    pub(super) due: f64,
    /// Whether the camera is refreshed (someone reads it).
    pub(super) sensed: bool,
}

/// A 2-D camera of a simulated robot.
pub struct CameraState {
    pub model: crate::camera::Camera,
    pub image: crate::camera::CameraImage,
    pub(super) noise: Stream,
    pub(super) due: f64,
    /// Whether the camera is refreshed (someone reads it).
    pub(super) sensed: bool,
}

/// A robot's readings before the Khepera's rounding and clamping to 0…1023, for every
/// distance and light sensor it carries (not only the first eight): what a Webots controller
/// reads through its sensors' lookup tables. Kept only for robots that ask
/// ([`RobotState::keep_raw_readings`]), so that no other robot pays for them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawReadings {
    /// One per distance sensor, in the rig's order.
    pub distance: Vec<f64>,
    /// One per light sensor, in the rig's order.
    pub light: Vec<f64>,
}

/// The numbers of a robot's rig that every step reads (control period, wheels, body, floor
/// height), side by side in one cache line: a crowd's step sweeps its robots a dozen times,
/// and these lie over several lines of a 650-byte rig. Named as the rig names them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(super) struct Body {
    pub body_radius: f64,
    pub body_height: f64,
    pub floor_y: f64,
    pub axle_length: f64,
    pub max_speed: f64,
    pub encoder_resolution: f64,
    pub wheel_speed_noise: f64,
    pub control_steps: u64,
}

/// Each robot's [`Body`], each distinct one kept once: most robots of a world share one, so
/// a sweep reads one line for them all, not a line a robot.
#[derive(Debug, Default)]
pub(super) struct Bodies {
    table: Vec<Body>,
    /// Each robot's body, an index into `table` (unread while there is one).
    of: Vec<u32>,
}

impl Bodies {
    pub fn of(rigs: &[RobotRig]) -> Bodies {
        let mut bodies = Bodies::default();
        for body in rigs.iter().map(Body::of) {
            let index = match bodies.table.iter().position(|b| *b == body) {
                Some(index) => index,
                None => {
                    bodies.table.push(body);
                    bodies.table.len() - 1
                }
            };
            bodies.of.push(index as u32);
        }
        bodies
    }

    /// Robot `robot`'s body.
    #[inline]
    pub fn get(&self, robot: usize) -> &Body {
        if self.table.len() == 1 {
            &self.table[0]
        } else {
            &self.table[self.of[robot] as usize]
        }
    }

    /// How many robots.
    pub fn len(&self) -> usize {
        self.of.len()
    }
}

impl Body {
    pub fn of(rig: &RobotRig) -> Body {
        Body {
            body_radius: rig.body_radius,
            body_height: rig.body_height,
            floor_y: rig.floor_y,
            axle_length: rig.axle_length,
            max_speed: rig.max_speed,
            encoder_resolution: rig.encoder_resolution,
            wheel_speed_noise: rig.wheel_speed_noise,
            control_steps: rig.control_steps,
        }
    }
}

/// One simulated robot.
///
/// Laid out by the sweeps of a step that read each field (`repr(C)` keeps this order, and
/// each robot starts a cache line): a crowd's step sweeps its robots several times, and at
/// 10,000 robots the lines each sweep pulls in, not the arithmetic, were most of its cost.
/// Line 0 is read by every sweep; then what IR sensing reads (lines 1–2), the devices (3),
/// what the controller's wheels and motion read (4–5), what the end of the step reads (6–7),
/// and last what a step of IR and motion does not read.
#[repr(C, align(64))]
pub struct RobotState {
    // Line 0: every sweep.
    pub pose: Pose2,
    /// Which readings the last step refreshed (what a log records, at each sensor's rate).
    pub updated: Updated,
    /// The sensors refreshed in the last step: those the controller reads, or all.
    pub senses: Senses,
    /// A batched backend is to render this robot's vision device in this step.
    pub(super) vision_requested: bool,
    /// Whether every IR sensor reads nothing without noise (the table's far rows have none):
    /// what lets a reading of nothing leave its stream behind.
    pub(super) ir_quiet: bool,
    /// Whether every IR sensor is due at `ir_next` (`ir_due` not kept meanwhile).
    pub(super) ir_together: bool,
    /// Whether it carries a vision device or a 2-D camera (set where they are made): a robot
    /// without leaves their line unread.
    pub(super) has_devices: bool,
    pub(super) controller: Option<Box<dyn Controller>>,
    // Lines 1–2: the IR sensors, and their readings that the controller reads.
    /// Readings before rounding, when kept ([`RawReadings`]): boxed, as few robots keep them.
    pub raw: Option<Box<RawReadings>>,
    /// How far from the centre any IR sensor reaches ([`super::sensors::ir_reach`]).
    pub(super) ir_reach: f64,
    /// Readings of nothing whose draws every IR stream still owes: a robot alone reads its
    /// sensors' far values without touching its streams, and they catch up (the same draws,
    /// skipped) before a reading needs one ([`RobotState::ir_streams_caught_up`]).
    pub(super) ir_skipped: u64,
    /// The IR sensors' period when they all share one (read here, not from the rig, in the
    /// step loop).
    pub(super) ir_period: Option<f64>,
    /// When every IR sensor is next due, while they are due together (`ir_together`): a
    /// Khepera's eight always are, and then their list is left alone.
    pub(super) ir_next: f64,
    pub proximity: [u16; 8],
    /// Each IR sensor's next due time, once they are not due together.
    pub(super) ir_due: Vec<f64>,
    /// Each IR sensor's noise stream: read only through
    /// [`RobotState::ir_streams_caught_up`], which pays what `ir_skipped` owes.
    pub(super) ir_streams: Vec<Stream>,
    /// Each IR sensor's reading with nothing in range
    /// ([`super::sensors::nothing_in_range`]), shared by robots with the same sensors.
    pub(super) ir_nothing: std::sync::Arc<[super::sensors::NothingInRange]>,
    // Line 3: the devices, read only where `has_devices` says there are some.
    /// Boxed: the robots without one (an IR-only swarm's) keep 550 bytes less each.
    pub panoramic: Option<Box<PanoramicState>>,
    pub linear_camera: Option<Box<LinearCameraState>>,
    pub cameras: Vec<CameraState>,
    // Filling line 3: read now and then.
    pub name: String,
    // Lines 4–5: the wheels, and the travel that motion adds to.
    pub(super) wheel_stream: Stream,
    /// Wheel speed commands (pulses per 10 ms).
    pub command: (i32, i32),
    /// Each wheel's speed factor (1 + relative noise), drawn with each control command and
    /// held for its period: the noise's statistics do not depend on the physics step.
    pub(super) wheel_noise: (f64, f64),
    /// Wheel rim speeds (m/s) that replace `command` when set: a robot driven in SI units
    /// (a Webots controller's motors) rather than in the Khepera's pulses.
    pub wheel_velocity: Option<(f64, f64)>,
    /// Wheel travel since the start (m), from which the encoders count.
    pub travel: (f64, f64),
    /// Controller calls that returned an error, and the last message (filling line 5).
    pub controller_errors: u64,
    // Lines 6–7: the end of the step: contacts, falls and visits.
    /// Obstacles touched in this step's sub-steps (numbered as [`Contacts::per_obstacle`]).
    pub(super) touched: Vec<u32>,
    /// The landmarks whose visit disc holds the robot now, ascending.
    pub(super) visiting: Vec<u32>,
    /// Where and when the robot left every floor (it stays there, fallen off the world):
    /// boxed, as few robots fall.
    pub fell: Option<Box<Fall>>,
    // Filling line 6.
    pub leds: [bool; 2],
    pub contacts: Contacts,
    pub(super) counter_offset: (i64, i64),
    pub visits: Visits,
    // Below: what a step of IR and motion does not read.
    pub ambient: [u16; 8],
    pub(super) ambient_due: Vec<f64>,
    pub(super) ambient_streams: Vec<Stream>,
    pub last_controller_error: Option<String>,
}

/// A robot leaving its floor: simulated time (s) and position (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fall {
    pub time: f64,
    pub pose: Pose2,
}

impl RobotState {
    /// The IR sensors' noise streams, each moved past the draws it still owes.
    #[inline]
    pub(super) fn ir_streams_caught_up(&mut self) -> &mut [Stream] {
        if self.ir_skipped > 0 {
            for stream in &mut self.ir_streams {
                stream.skip_gaussians(self.ir_skipped);
            }
            self.ir_skipped = 0;
        }
        &mut self.ir_streams
    }

    /// Keeps this robot's [`RawReadings`] from the next step on (all its distance and light
    /// sensors, before rounding), `NaN` until first read.
    pub fn keep_raw_readings(&mut self, rig: &RobotRig) {
        self.raw = Some(Box::new(RawReadings {
            distance: vec![f64::NAN; rig.distance_sensors.len()],
            light: vec![f64::NAN; rig.light_sensors.len()],
        }));
    }

    /// Whether its vision device is read and due at `t` (without moving its due time).
    #[inline]
    pub(super) fn vision_due(&self, t: f64) -> bool {
        let next = match (&self.panoramic, &self.linear_camera) {
            (Some(turret), _) => (turret.due, turret.model.rig.period),
            (None, Some(camera)) => (camera.due, camera.model.rig.period),
            (None, None) => return false,
        };
        self.senses.vision && (next.1 <= 0.0 || t + 1e-12 >= next.0)
    }

    /// The encoder counters (pulses), as the robot reports them.
    #[inline]
    pub fn counters(&self, rig: &RobotRig) -> (i32, i32) {
        let pulses = |travel: f64, offset: i64| {
            ((libm::floor(travel * rig.encoder_resolution) as i64) - offset) as i32
        };
        (
            pulses(self.travel.0, self.counter_offset.0),
            pulses(self.travel.1, self.counter_offset.1),
        )
    }
}

/// Wall time spent in each phase of the steps run while profiling.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Sensors: IR, ambient light, vision.
    pub sense: std::time::Duration,
    /// Controllers, and the wheel speeds their commands give (robot by robot).
    pub control: std::time::Duration,
    /// Wheels moved along their arcs, with the first collision pass against static
    /// obstacles (robot by robot as each moves).
    pub kinematics: std::time::Duration,
    /// Bodies pushed apart (the rest of the passes), contacts and visits counted.
    pub collisions: std::time::Duration,
}

/// Times a phase when profiling.
pub(super) struct PhaseClock(Option<std::time::Instant>);

impl PhaseClock {
    #[inline]
    pub(super) fn start(on: bool) -> PhaseClock {
        PhaseClock(on.then(std::time::Instant::now))
    }

    /// Adds the time since the last lap to `slot` and starts the next lap.
    #[inline]
    pub(super) fn lap(&mut self, slot: Option<&mut std::time::Duration>) {
        if let (Some(started), Some(slot)) = (self.0, slot) {
            let now = std::time::Instant::now();
            *slot += now - started;
            self.0 = Some(now);
        }
    }
}

/// Working lists of one robot's sensing: the static obstacles and the robots near enough for
/// its IR sensors. Kept by whoever senses robots one after another (a thread), not by each
/// robot, so that a robot's state keeps no lists it only needs while it is sensed.
#[derive(Debug, Default)]
pub(super) struct NearbyLists {
    pub(super) obstacles: Vec<u32>,
    pub(super) robots: Vec<u32>,
}

thread_local! {
    /// Each thread's lists, kept from step to step: a warm step allocates none.
    static THREAD_LISTS: std::cell::Cell<NearbyLists> = std::cell::Cell::new(NearbyLists::default());
}

/// A thread's [`NearbyLists`], lent to one run of robots sensed side by side and given back
/// when the run ends.
pub(super) struct ThreadLists(NearbyLists);

impl ThreadLists {
    pub(super) fn lend() -> ThreadLists {
        ThreadLists(THREAD_LISTS.with(std::cell::Cell::take))
    }
}

impl std::ops::Deref for ThreadLists {
    type Target = NearbyLists;

    fn deref(&self) -> &NearbyLists {
        &self.0
    }
}

impl std::ops::DerefMut for ThreadLists {
    fn deref_mut(&mut self) -> &mut NearbyLists {
        &mut self.0
    }
}

impl Drop for ThreadLists {
    fn drop(&mut self) {
        let lists = std::mem::take(&mut self.0);
        THREAD_LISTS.with(|kept| kept.set(lists));
    }
}

/// A step's working buffers.
#[derive(Default)]
pub(super) struct StepScratch {
    pub(super) poses: Poses,
    /// Where each robot stands and its floor; its sine and cosine only where a renderer reads
    /// them (not a number otherwise: a robot's own sensors turn it, `SenseShared::turned`).
    pub(super) placements: Vec<crate::compile::rig::Placement>,
    /// The plan's lights in the world, kept from step to step when none is on a robot.
    pub(super) lights: Vec<crate::render::WorldLight>,
    pub(super) lights_move: bool,
    pub(super) requests: Vec<VisionRequest>,
    pub(super) speeds: Vec<(f64, f64)>,
    /// Collision candidates of one robot.
    pub(super) candidates: Vec<u32>,
    /// How far each robot was pushed since the robots' grid was filed (an upper bound).
    pub(super) drift: Vec<f64>,
    /// Each robot's centre after a collision pass against the static obstacles.
    pub(super) centres: Vec<DVec2>,
    /// What one robot's IR sensors may see, when robots are sensed one after another.
    pub(super) nearby: NearbyLists,
    /// One robot's landmarks inside at the last step.
    pub(super) was_inside: Vec<u32>,
    /// Where each robot was before the sub-step, and which go back there.
    pub(super) before: Vec<DVec2>,
    pub(super) marked: Vec<bool>,
    /// The world placed once for every viewer of the step (column renderer).
    pub(super) frame: Option<crate::render::column::ColumnFrame>,
}
#[cfg(test)]
mod tests {
    use super::RobotState;
    use std::mem::offset_of;

    /// The size of the field `field` reads.
    fn size_of_field<T, F: Fn(&RobotState) -> &T>(_field: F) -> usize {
        std::mem::size_of::<T>()
    }

    /// The line of the robot's state a field starts on, and the line it ends on.
    macro_rules! lines {
        ($field:ident) => {{
            let start = offset_of!(RobotState, $field);
            let size = size_of_field(|robot: &RobotState| &robot.$field);
            (start / 64, (start + size - 1) / 64)
        }};
    }

    #[test]
    fn each_sweep_finds_its_fields_in_the_lines_it_reads() {
        assert_eq!(std::mem::align_of::<RobotState>(), 64);
        let within = |lines: &[(usize, usize)], first: usize, last: usize| {
            for line in lines {
                assert!(line.0 >= first && line.1 <= last, "{line:?}");
            }
        };
        // Every sweep: line 0.
        within(
            &[
                lines!(pose),
                lines!(updated),
                lines!(senses),
                lines!(ir_together),
                lines!(has_devices),
                lines!(controller),
            ],
            0,
            0,
        );
        // IR sensing: lines 1 and 2.
        within(
            &[
                lines!(raw),
                lines!(ir_reach),
                lines!(ir_skipped),
                lines!(ir_period),
                lines!(ir_next),
                lines!(ir_due),
                lines!(proximity),
                lines!(ir_streams),
                lines!(ir_nothing),
            ],
            1,
            2,
        );
        // The controller's readings beside its IR sensors' due time.
        assert_eq!(lines!(proximity), lines!(ir_next));
        within(
            &[lines!(panoramic), lines!(linear_camera), lines!(cameras)],
            3,
            3,
        );
        // The wheels: lines 4 and 5, with the travel that motion adds to.
        within(
            &[
                lines!(wheel_stream),
                lines!(command),
                lines!(wheel_noise),
                lines!(wheel_velocity),
                lines!(travel),
            ],
            4,
            5,
        );
        assert_eq!(lines!(travel), lines!(wheel_noise));
        // The end of the step: lines 6 and 7, with what contacts read first.
        within(&[lines!(touched), lines!(visiting), lines!(fell)], 6, 7);
        let contacts = offset_of!(RobotState, contacts);
        let touching = contacts + offset_of!(super::Contacts, touching);
        let current = contacts + offset_of!(super::Contacts, current);
        assert_eq!((touching / 64, (touching + 23) / 64), (7, 7));
        assert_eq!((current / 64, (current + 7) / 64), (7, 7));
    }
}
