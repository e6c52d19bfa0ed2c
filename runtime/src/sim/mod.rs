//! The runtime loop: fixed steps of `WorldInfo.basicTimeStep`. In each step, sensors that are
//! due update (each at its own period), controllers read them and set wheel speeds, then
//! kinematics and collisions run. All randomness comes from the run's seed, one stream per
//! robot and per sensor; robots are visited in file order; nothing depends on wall time.

mod broad_phase;
pub mod kinematics;
pub mod noise;
pub mod sensors;
pub mod world2d;

use glam::DVec2;

use crate::compile::rig::{Pose2, RobotRig, TurretRig};
use crate::compile::Compiled;
use crate::controllers;
use crate::khepera::{
    Controller, Khepera, KheperaError, LedAction, LinearCameraTurret, PanoramicTurret, Senses,
};
use crate::optics::{LinearCamera, LinearCameraOutput, Panoramic, Renderer, RetinaOutput, ViewOf};
use crate::render::Poses;
use crate::retina::FilterKind;
use crate::vision::{VisionBackend, VisionError, VisionRequest, WorldInstance};
use broad_phase::BroadPhase;
use noise::{kind, Stream};
use world2d::{Footprint, Slab};

/// Why a simulation could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error("robot '{robot}': {source}")]
    Controller {
        robot: String,
        #[source]
        source: controllers::ControllerError,
    },
    #[error("the world's time step must be positive, found {0} s")]
    TimeStep(f64),
}

/// Most collision sub-steps in one step. A world whose robots could need more (a long time
/// step at a high top speed) is refused when it is checked ([`crate::check`]), so the bound
/// never cuts a step short and nothing tunnels at any accepted time step.
pub const MAX_SUB_STEPS: usize = 4096;

/// Largest penetration left after a step's collision handling (m).
pub const PENETRATION_TOLERANCE: f64 = 1e-9;

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
pub struct Contacts {
    /// Times a contact began.
    pub events: u64,
    /// Steps that ended in contact.
    pub steps: u64,
    /// Longest unbroken contact (s).
    pub longest: f64,
    current: f64,
    /// Contact events per obstacle, for the obstacles ever touched, by obstacle (static
    /// obstacles are numbered first, then robots): kept sparse, so that a swarm's table grows
    /// with its contacts, not with the square of its size.
    pub per_obstacle: Vec<(u32, u64)>,
    /// The obstacles touched at the end of the last step, ascending.
    touching: Vec<u32>,
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

    fn count_event(&mut self, obstacle: u32) {
        match self
            .per_obstacle
            .binary_search_by_key(&obstacle, |&(k, _)| k)
        {
            Ok(i) => self.per_obstacle[i].1 += 1,
            Err(i) => self.per_obstacle.insert(i, (obstacle, 1)),
        }
    }

    /// The obstacles it ended the last step touching, ascending (indices into
    /// [`Simulation::obstacle_names`]).
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
    /// The landmarks whose visit disc holds the robot now, ascending.
    inside: Vec<u32>,
}

impl Visits {
    /// The radius of the disc a robot's centre enters to visit a landmark of `radius`: the
    /// landmark's radius plus two body diameters.
    pub fn disc_radius(radius: f64, body_radius: f64) -> f64 {
        radius + 4.0 * body_radius
    }
}

/// The Panoramic turret of a simulated robot.
pub struct PanoramicState {
    pub model: Panoramic,
    pub output: RetinaOutput,
    due: f64,
    /// Whether the turret is refreshed (someone reads it).
    sensed: bool,
}

/// The K213 of a simulated robot.
pub struct LinearCameraState {
    pub model: LinearCamera,
    pub output: LinearCameraOutput,
    due: f64,
    /// Whether the camera is refreshed (someone reads it).
    sensed: bool,
}

/// A 2-D camera of a simulated robot.
pub struct CameraState {
    pub model: crate::camera::Camera,
    pub image: crate::camera::CameraImage,
    noise: Stream,
    due: f64,
    /// Whether the camera is refreshed (someone reads it).
    sensed: bool,
}

/// One simulated robot.
pub struct RobotState {
    pub name: String,
    /// Which readings the last step refreshed (what a log records, at each sensor's rate).
    pub updated: Updated,
    pub pose: Pose2,
    /// Wheel speed commands (pulses per 10 ms).
    pub command: (i32, i32),
    /// Wheel travel since the start (m), from which the encoders count.
    pub travel: (f64, f64),
    counter_offset: (i64, i64),
    pub leds: [bool; 2],
    /// The sensors refreshed in the last step: those the controller reads, or all.
    pub senses: Senses,
    pub proximity: [u16; 8],
    pub ambient: [u16; 8],
    ir_due: Vec<f64>,
    ambient_due: Vec<f64>,
    ir_streams: Vec<Stream>,
    /// Each IR sensor's (mean, spread) with nothing in range ([`sensors::nothing_in_range`]).
    ir_nothing: Vec<(f64, f64)>,
    /// How far from the centre any IR sensor reaches ([`sensors::ir_reach`]).
    ir_reach: f64,
    /// The IR sensors' period when they all share one (read here, not from the rig, in the
    /// step loop).
    ir_period: Option<f64>,
    ambient_streams: Vec<Stream>,
    wheel_stream: Stream,
    pub panoramic: Option<PanoramicState>,
    pub linear_camera: Option<LinearCameraState>,
    pub cameras: Vec<CameraState>,
    controller: Option<Box<dyn Controller>>,
    /// Controller calls that returned an error, and the last message.
    pub controller_errors: u64,
    pub last_controller_error: Option<String>,
    pub contacts: Contacts,
    pub visits: Visits,
    /// Working lists, kept from step to step (the robot's own, so that robots can be sensed
    /// side by side): static obstacles and robots near enough for the IR sensors, obstacles
    /// touched in this step.
    nearby: Vec<u32>,
    nearby_robots: Vec<u32>,
    touched: Vec<u32>,
    /// A batched backend is to render this robot's vision device in this step.
    vision_requested: bool,
    /// Where and when the robot left every floor (it stays there, fallen off the world).
    pub fell: Option<Fall>,
}

/// A robot leaving its floor: simulated time (s) and position (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fall {
    pub time: f64,
    pub pose: Pose2,
}

impl RobotState {
    /// Whether its vision device is read and due at `t` (without moving its due time).
    fn vision_due(&self, t: f64) -> bool {
        let next = match (&self.panoramic, &self.linear_camera) {
            (Some(turret), _) => (turret.due, turret.model.rig.period),
            (None, Some(camera)) => (camera.due, camera.model.rig.period),
            (None, None) => return false,
        };
        self.senses.vision && (next.1 <= 0.0 || t + 1e-12 >= next.0)
    }

    /// The encoder counters (pulses), as the robot reports them.
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

/// A running world.
pub struct Simulation<'c> {
    pub compiled: &'c Compiled,
    renderer: Option<Renderer<'c>>,
    /// The ray caster 2-D cameras render with, when a robot has one.
    camera_caster: Option<crate::render::raycast::RayCaster<'c>>,
    /// A batched backend that renders every due vision device of a step in one call,
    /// replacing the CPU renderer.
    vision: Option<Box<dyn VisionBackend + 'c>>,
    /// The first error the vision backend returned; vision readings stop refreshing after it.
    pub vision_error: Option<VisionError>,
    vision_buffers: Vec<Vec<f64>>,
    pub slab: Slab,
    /// Grids over the floor: what pairs bodies without testing every pair.
    broad: BroadPhase,
    pub robots: Vec<RobotState>,
    /// Simulated time (s) and steps done.
    pub time: f64,
    pub steps: u64,
    pub time_step: f64,
    pub seed: u64,
    /// Sensors refreshed whether or not a controller reads them (what a log records).
    pub always_sensed: Senses,
    /// Buffers a step fills and the next reuses: stepping allocates nothing once warm.
    scratch: StepScratch,
    /// Wall time spent in each phase, when profiling (`regatta bench step`); never read by
    /// the simulation itself, so it changes no result.
    profile: Option<PhaseTimes>,
}

/// Wall time spent in each phase of the steps run while profiling.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Sensors: IR, ambient light, vision.
    pub sense: std::time::Duration,
    /// Controllers.
    pub control: std::time::Duration,
    /// Wheels moved along their arcs.
    pub kinematics: std::time::Duration,
    /// Bodies pushed apart, contacts and visits counted.
    pub collisions: std::time::Duration,
}

/// Times a phase when profiling.
struct PhaseClock(Option<std::time::Instant>);

impl PhaseClock {
    fn start(on: bool) -> PhaseClock {
        PhaseClock(on.then(std::time::Instant::now))
    }

    /// Adds the time since the last lap to `slot` and starts the next lap.
    fn lap(&mut self, slot: Option<&mut std::time::Duration>) {
        if let (Some(started), Some(slot)) = (self.0, slot) {
            let now = std::time::Instant::now();
            *slot += now - started;
            self.0 = Some(now);
        }
    }
}

/// A step's working buffers.
#[derive(Default)]
struct StepScratch {
    poses: Poses,
    placements: Vec<crate::compile::rig::Placement>,
    /// The plan's lights in the world, kept from step to step when none is on a robot.
    lights: Vec<crate::render::WorldLight>,
    lights_move: bool,
    requests: Vec<VisionRequest>,
    speeds: Vec<(f64, f64)>,
    /// Collision candidates of one robot.
    candidates: Vec<u32>,
    /// How far each robot was pushed since the robots' grid was filed (an upper bound).
    drift: Vec<f64>,
    /// One robot's landmarks inside at the last step.
    was_inside: Vec<u32>,
    /// Where each robot was before the sub-step, and which go back there.
    before: Vec<DVec2>,
    marked: Vec<bool>,
    /// The world placed once for every viewer of the step (column renderer).
    frame: Option<crate::render::column::ColumnFrame>,
}

impl<'c> Simulation<'c> {
    /// Starts a world with its built-in controllers; `seed` overrides the world's.
    pub fn new(compiled: &'c Compiled, seed: Option<u64>) -> Result<Simulation<'c>, SimError> {
        let time_step = compiled.settings.time_step;
        if !(time_step > 0.0 && time_step.is_finite()) {
            return Err(SimError::TimeStep(time_step));
        }
        let seed = seed.unwrap_or(compiled.settings.seed);
        let slab = Slab::new(&compiled.graph, &compiled.rig);
        let renderer = (compiled.plan.renderer != crate::compile::plan::RendererChoice::None)
            .then(|| Renderer::new(&compiled.graph, &compiled.plan, false));
        let broad = BroadPhase::new(compiled, &slab);
        let mut robots: Vec<RobotState> = Vec::with_capacity(compiled.rig.robots.len());
        // The last turret built: the next with the same settings shares its filters.
        let mut last_panoramic: Option<usize> = None;
        for (index, rig) in compiled.rig.robots.iter().enumerate() {
            let controller =
                controllers::build_for(rig).map_err(|source| SimError::Controller {
                    robot: rig.name.clone(),
                    source,
                })?;
            robots.push(RobotState {
                name: rig.name.clone(),
                updated: Updated::default(),
                pose: rig.start,
                command: (0, 0),
                travel: (0.0, 0.0),
                counter_offset: (0, 0),
                leds: [false; 2],
                senses: Senses::ALL,
                proximity: [0; 8],
                ambient: [0; 8],
                ir_due: vec![0.0; rig.distance_sensors.len()],
                ambient_due: vec![0.0; rig.light_sensors.len()],
                ir_nothing: rig
                    .distance_sensors
                    .iter()
                    .map(sensors::nothing_in_range)
                    .collect(),
                ir_reach: sensors::ir_reach(&rig.distance_sensors),
                ir_period: rig.distance_sensors.first().map(|s| s.period).filter(|&p| {
                    rig.distance_sensors
                        .iter()
                        .all(|s| s.period.to_bits() == p.to_bits())
                }),
                ir_streams: (0..rig.distance_sensors.len())
                    .map(|s| Stream::new(seed, index, kind::PROXIMITY, s))
                    .collect(),
                ambient_streams: (0..rig.light_sensors.len())
                    .map(|s| Stream::new(seed, index, kind::AMBIENT, s))
                    .collect(),
                wheel_stream: Stream::new(seed, index, kind::WHEELS, 0),
                panoramic: match &rig.turret {
                    Some(TurretRig::Panoramic(p)) => Some(PanoramicState {
                        model: Panoramic::new_like(
                            p,
                            last_panoramic
                                .and_then(|r| robots[r].panoramic.as_ref())
                                .map(|state| &state.model),
                        ),
                        output: RetinaOutput::default(),
                        due: 0.0,
                        sensed: true,
                    }),
                    _ => None,
                },
                linear_camera: match &rig.turret {
                    Some(TurretRig::Linear(c)) => Some(LinearCameraState {
                        model: LinearCamera::new(c),
                        output: LinearCameraOutput::default(),
                        due: 0.0,
                        sensed: true,
                    }),
                    _ => None,
                },
                cameras: rig
                    .cameras
                    .iter()
                    .enumerate()
                    .map(|(c, camera)| CameraState {
                        model: crate::camera::Camera::new(camera),
                        image: crate::camera::CameraImage::default(),
                        noise: Stream::new(seed, index, kind::CAMERA, c),
                        due: 0.0,
                        sensed: true,
                    })
                    .collect(),
                controller: Some(controller),
                controller_errors: 0,
                last_controller_error: None,
                // Room for a few contacts and visits at once: a step allocates only when a
                // record outgrows it (amortised doubling), never as routine.
                contacts: Contacts {
                    per_obstacle: Vec::with_capacity(8),
                    touching: Vec::with_capacity(8),
                    ..Contacts::default()
                },
                visits: Visits {
                    sequence: Vec::with_capacity(64),
                    times: Vec::with_capacity(64),
                    inside: Vec::with_capacity(4),
                },
                nearby: Vec::with_capacity(16),
                nearby_robots: Vec::with_capacity(32),
                touched: Vec::with_capacity(8),
                vision_requested: false,
                fell: None,
            });
            if robots[index].panoramic.is_some() {
                last_panoramic = Some(index);
            }
        }
        let camera_caster = compiled
            .rig
            .has_cameras()
            .then(|| crate::render::raycast::RayCaster::new(&compiled.graph, &compiled.plan));
        let mut simulation = Simulation {
            compiled,
            renderer,
            camera_caster,
            vision: None,
            vision_error: None,
            vision_buffers: Vec::new(),
            slab,
            broad,
            robots,
            time: 0.0,
            steps: 0,
            time_step,
            seed,
            always_sensed: Senses::NONE,
            scratch: StepScratch::default(),
            profile: None,
        };
        let plan = &compiled.plan;
        simulation.scratch.lights_move = plan
            .lights
            .iter()
            .any(|&l| compiled.graph.lights[l].owner != crate::compile::graph::Owner::Static);
        simulation.scratch.lights =
            crate::render::world_lights(&compiled.graph, plan, &simulation.poses());
        simulation.track_visits();
        Ok(simulation)
    }

    /// Renders vision devices with `backend` (built for this world as scene 0) instead of
    /// the CPU renderer.
    pub fn set_vision_backend(&mut self, backend: Box<dyn VisionBackend + 'c>) {
        self.vision = Some(backend);
    }

    /// Refreshes every sensor from now on, whether or not a controller reads it: what a log
    /// records. Other robots' readings and noise streams do not change.
    pub fn sense_everything(&mut self) {
        self.always_sensed = Senses::ALL;
    }

    /// Starts (or stops) adding up the wall time of each phase of the steps that follow.
    pub fn set_profiling(&mut self, on: bool) {
        self.profile = on.then(PhaseTimes::default);
    }

    /// The wall time of each phase since profiling started.
    pub fn phase_times(&self) -> Option<PhaseTimes> {
        self.profile
    }

    /// Replaces a robot's controller (a library user's own).
    pub fn set_controller(&mut self, robot: usize, controller: Box<dyn Controller>) {
        self.robots[robot].controller = Some(controller);
    }

    fn poses(&self) -> Poses {
        Poses {
            poses: self.robots.iter().map(|r| r.pose).collect(),
            floor_y: self.compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
        }
    }

    /// Advances the world by one step: [`Simulation::sense`] then [`Simulation::act`].
    pub fn step(&mut self) {
        self.sense();
        self.act();
    }

    /// The first half of a step: clears the update flags and refreshes the sensors that are
    /// due. A robot driven from outside (over the serial protocol) is read and commanded
    /// between this and [`Simulation::act`], exactly where a built-in controller runs.
    pub fn sense(&mut self) {
        let t = self.time;
        for robot in &mut self.robots {
            robot.updated = Updated::default();
            // A robot driven from outside may read anything its protocol reads.
            let reads = robot
                .controller
                .as_ref()
                .map_or(Senses::PROTOCOL, |c| c.senses());
            robot.senses = reads.union(self.always_sensed);
            let vision = robot.senses.vision;
            if let Some(turret) = &mut robot.panoramic {
                turret.sensed = vision;
            }
            if let Some(camera) = &mut robot.linear_camera {
                camera.sensed = vision;
            }
            for camera in &mut robot.cameras {
                camera.sensed = robot.senses.camera;
            }
        }
        let mut clock = PhaseClock::start(self.profile.is_some());
        self.update_sensors(t);
        clock.lap(self.profile.as_mut().map(|p| &mut p.sense));
    }

    /// The second half of a step: runs the built-in controllers, moves the robots and
    /// advances time.
    pub fn act(&mut self) {
        let mut clock = PhaseClock::start(self.profile.is_some());
        let rigs = &self.compiled.rig.robots;
        let control = |index: usize, robot: &mut RobotState| {
            let Some(mut controller) = robot.controller.take() else {
                return;
            };
            let mut io = SimulatedKhepera {
                robot,
                rig: &rigs[index],
            };
            if let Err(error) = controller.step(&mut io) {
                robot.updated.controller_error = true;
                robot.controller_errors += 1;
                robot.last_controller_error = Some(error.to_string());
            }
            robot.controller = Some(controller);
        };
        // Each controller drives its own robot only: side by side, the same results.
        if parallel(&self.robots) {
            use rayon::prelude::*;
            self.robots
                .par_iter_mut()
                .enumerate()
                .for_each(|(index, robot)| control(index, robot));
        } else {
            for (index, robot) in self.robots.iter_mut().enumerate() {
                control(index, robot);
            }
        }
        clock.lap(self.profile.as_mut().map(|p| &mut p.control));
        self.move_robots(&mut clock);
        self.steps += 1;
        self.time = self.steps as f64 * self.time_step;
        self.track_falls();
        self.track_visits();
        clock.lap(self.profile.as_mut().map(|p| &mut p.collisions));
    }

    /// A robot whose centre has left every floor it started on has fallen off the world: the
    /// event is kept, and the robot stays where it fell.
    fn track_falls(&mut self) {
        for (robot, rig) in self.robots.iter_mut().zip(&self.compiled.rig.robots) {
            if let Some(fall) = robot.fell {
                robot.pose = fall.pose;
                continue;
            }
            if rig.floors.is_empty() {
                continue;
            }
            let (x, z) = (robot.pose.x, robot.pose.z);
            let on_floor = rig
                .floors
                .iter()
                .any(|f| (f[0]..=f[2]).contains(&x) && (f[1]..=f[3]).contains(&z));
            if !on_floor {
                robot.fell = Some(Fall {
                    time: self.time,
                    pose: robot.pose,
                });
            }
        }
    }

    /// Takes a robot's built-in controller away, so that something outside drives it.
    pub fn detach_controller(&mut self, robot: usize) -> Option<Box<dyn Controller>> {
        self.robots[robot].controller.take()
    }

    /// One robot's Khepera API, for driving it from outside between [`Simulation::sense`] and
    /// [`Simulation::act`].
    pub fn khepera(&mut self, robot: usize) -> SimulatedKhepera<'_> {
        SimulatedKhepera {
            robot: &mut self.robots[robot],
            rig: &self.compiled.rig.robots[robot],
        }
    }

    /// Runs `steps` steps.
    pub fn run(&mut self, steps: u64) {
        for _ in 0..steps {
            self.step();
        }
    }

    fn update_sensors(&mut self, t: f64) {
        let mut scratch = std::mem::take(&mut self.scratch);
        self.update_sensors_with(t, &mut scratch);
        self.scratch = scratch;
    }

    fn update_sensors_with(&mut self, t: f64, scratch: &mut StepScratch) {
        let compiled = self.compiled;
        let StepScratch {
            poses,
            placements,
            lights,
            lights_move,
            requests,
            ..
        } = scratch;
        poses.poses.clear();
        poses.poses.extend(self.robots.iter().map(|r| r.pose));
        poses.floor_y.clear();
        poses
            .floor_y
            .extend(compiled.rig.robots.iter().map(|r| r.floor_y));
        let poses = &*poses;
        placements.clear();
        placements.extend(
            poses
                .poses
                .iter()
                .zip(&poses.floor_y)
                .map(|(p, &y)| p.placement(y)),
        );
        let placements = &*placements;
        // Ambient sensors read the plan's lights, placed once per step where they move.
        if *lights_move
            && self
                .robots
                .iter()
                .any(|r| r.senses.ambient && !r.ambient_due.is_empty())
        {
            *lights = crate::render::world_lights(&compiled.graph, &compiled.plan, poses);
        }
        // Where every robot is, once per step, for every robot's IR sensors.
        if self.robots.len() > 1 && self.robots.iter().any(|r| r.senses.proximity) {
            self.broad.file_robots(placements.len(), |i| {
                DVec2::new(placements[i].x, placements[i].z)
            });
        }
        let renderer = self.renderer.as_ref().filter(|_| self.vision.is_none());
        // The world placed once, for every robot's vision device, when one is due.
        let frame = &mut scratch.frame;
        match renderer {
            Some(renderer) if self.robots.iter().any(|r| r.vision_due(t)) => {
                renderer.prepare_shared(&compiled.plan, poses, frame)
            }
            _ => {}
        }
        let shared = SenseShared {
            compiled,
            slab: &self.slab,
            broad: &self.broad,
            placements,
            lights,
            poses,
            renderer,
            frame: frame.as_ref(),
            camera_caster: self.camera_caster.as_ref(),
            batched: self.vision.is_some(),
            t,
        };
        // Each robot reads only what is shared and writes only itself: side by side when
        // there is enough work, and the same results either way.
        if parallel(&self.robots) {
            use rayon::prelude::*;
            self.robots
                .par_iter_mut()
                .enumerate()
                .with_max_len(1)
                .for_each(|(index, robot)| shared.sense(index, robot));
        } else {
            for (index, robot) in self.robots.iter_mut().enumerate() {
                shared.sense(index, robot);
            }
        }
        requests.clear();
        if !shared.batched {
            return;
        }
        requests.extend(
            self.robots
                .iter()
                .enumerate()
                .filter(|(_, r)| r.vision_requested)
                .map(|(robot, _)| VisionRequest { instance: 0, robot }),
        );
        if requests.is_empty() || self.vision_error.is_some() {
            return;
        }
        let Some(backend) = &mut self.vision else {
            return;
        };
        let instances = [WorldInstance { scene: 0, poses }];
        if let Err(error) = backend.render(&instances, requests, &mut self.vision_buffers) {
            self.vision_error = Some(error);
            return;
        }
        for (request, luminance) in requests.iter().zip(&self.vision_buffers) {
            let robot = &mut self.robots[request.robot];
            robot.updated.vision = true;
            if let Some(turret) = &mut robot.panoramic {
                turret.model.accept(luminance, &mut turret.output);
            } else if let Some(camera) = &mut robot.linear_camera {
                camera.model.accept(luminance, &mut camera.output);
            }
        }
    }

    fn move_robots(&mut self, clock: &mut PhaseClock) {
        let dt = self.time_step;
        let rigs = &self.compiled.rig.robots;
        let mut speeds = std::mem::take(&mut self.scratch.speeds);
        // Wheel speeds (m/s) of every robot for this step.
        speeds.clear();
        speeds.extend(self.robots.iter_mut().zip(rigs).map(|(robot, rig)| {
            let to_metres = 100.0 / rig.encoder_resolution;
            let clamp =
                |command: i32| (command as f64 * to_metres).clamp(-rig.max_speed, rig.max_speed);
            let (mut left, mut right) = (clamp(robot.command.0), clamp(robot.command.1));
            if rig.wheel_speed_noise > 0.0 {
                left *= 1.0 + rig.wheel_speed_noise * robot.wheel_stream.gaussian();
                right *= 1.0 + rig.wheel_speed_noise * robot.wheel_stream.gaussian();
            }
            (left, right)
        }));
        // Sub-steps short enough that no body crosses half its radius in one: no tunnelling.
        let sub_steps = speeds
            .iter()
            .zip(rigs)
            .map(|(&(l, r), rig)| {
                libm::ceil(l.abs().max(r.abs()) * dt / (0.5 * rig.body_radius)) as usize
            })
            .max()
            .unwrap_or(1)
            .clamp(1, MAX_SUB_STEPS);
        let h = dt / sub_steps as f64;
        for robot in &mut self.robots {
            robot.touched.clear();
        }
        for _ in 0..sub_steps {
            self.scratch.before.clear();
            self.scratch
                .before
                .extend(self.robots.iter().map(|r| DVec2::new(r.pose.x, r.pose.z)));
            for ((robot, rig), &(left, right)) in self.robots.iter_mut().zip(rigs).zip(&speeds) {
                robot.pose = kinematics::advance(robot.pose, left, right, rig.axle_length, h);
                robot.travel.0 += left * h;
                robot.travel.1 += right * h;
            }
            clock.lap(self.profile.as_mut().map(|p| &mut p.kinematics));
            if self.resolve_collisions() {
                self.settle();
            }
            clock.lap(self.profile.as_mut().map(|p| &mut p.collisions));
        }
        for robot in &mut self.robots {
            robot.touched.sort_unstable();
            robot.touched.dedup();
            let RobotState {
                contacts, touched, ..
            } = robot;
            let any = !touched.is_empty();
            for &k in touched.iter() {
                if contacts.touching.binary_search(&k).is_err() {
                    contacts.count_event(k);
                }
            }
            let was = !contacts.touching.is_empty();
            if any && !was {
                contacts.events += 1;
            }
            robot.updated.contact |= any != was;
            if any {
                contacts.steps += 1;
                contacts.current += dt;
                contacts.longest = contacts.longest.max(contacts.current);
            } else {
                contacts.current = 0.0;
            }
            contacts.touching.clone_from(touched);
        }
        self.scratch.speeds = speeds;
    }

    /// Pushes bodies out of obstacles and out of each other: up to 3 passes, each robot
    /// against each static obstacle in order, then each pair of robots in order, every push
    /// seen by the tests after it. The grids only leave out pairs that cannot touch, so the
    /// pushes are those of testing every pair.
    fn resolve_collisions(&mut self) -> bool {
        let rigs = &self.compiled.rig.robots;
        let statics = self.slab.obstacles.len();
        let mut candidates = std::mem::take(&mut self.scratch.candidates);
        let mut drift = std::mem::take(&mut self.scratch.drift);
        let max_radius = self.broad.max_radius;
        let mut unsettled = false;
        for pass in 0..PASSES {
            // A pass that pushes nothing leaves the next one nothing new to find.
            let mut pushed = false;
            for (index, robot) in self.robots.iter_mut().enumerate() {
                let rig = &rigs[index];
                let (floor, top) = (rig.floor_y, rig.floor_y + rig.body_height);
                let reach = rig.body_radius + 1e-6;
                // Candidates from where the robot is; asked again if pushes carry it further
                // than SLACK from there.
                let mut anchor = DVec2::new(robot.pose.x, robot.pose.z);
                let (lo, hi) = broad_phase::square(anchor, reach + SLACK);
                self.broad.statics.query(lo, hi, &mut candidates);
                let mut next = 0;
                while let Some(&k) = candidates.get(next) {
                    next += 1;
                    let center = DVec2::new(robot.pose.x, robot.pose.z);
                    if center.distance(anchor) > SLACK {
                        anchor = center;
                        let (lo, hi) = broad_phase::square(anchor, reach + SLACK);
                        self.broad.statics.query(lo, hi, &mut candidates);
                        next = candidates.partition_point(|&c| c < k);
                        continue;
                    }
                    let obstacle = &self.slab.obstacles[k as usize];
                    if obstacle.y1 <= floor + 1e-6 || obstacle.y0 >= top {
                        continue;
                    }
                    if let Some((depth, normal)) =
                        obstacle.shape.penetration(center, rig.body_radius)
                    {
                        let moved = center + normal * depth;
                        robot.pose.x = moved.x;
                        robot.pose.z = moved.y;
                        robot.touched.push(k);
                        pushed = true;
                    } else if obstacle
                        .shape
                        .penetration(center, rig.body_radius + 1e-6)
                        .is_some()
                    {
                        robot.touched.push(k);
                    }
                }
            }
            let count = self.robots.len();
            if count > 1 {
                let robots = &self.robots;
                self.broad
                    .file_robots(count, |i| DVec2::new(robots[i].pose.x, robots[i].pose.z));
                drift.clear();
                drift.resize(count, 0.0);
            }
            // The largest drift of any robot since the grid was filed.
            let mut max_drift = 0.0f64;
            for a in 0..count.saturating_sub(1) {
                let ra = rigs[a].body_radius;
                // Candidates b > a whose filed centre is near enough that they might touch a,
                // allowing for SLACK of motion of a, or of anyone, before they are asked again.
                let (mut anchor, mut drift_then) = (
                    DVec2::new(self.robots[a].pose.x, self.robots[a].pose.z),
                    max_drift,
                );
                let query = |anchor: DVec2, drift_then: f64, out: &mut Vec<u32>| {
                    let (lo, hi) =
                        broad_phase::square(anchor, ra + max_radius + drift_then + SLACK);
                    self.broad.robots.query(lo, hi, out);
                };
                query(anchor, drift_then, &mut candidates);
                let mut next = candidates.partition_point(|&c| c as usize <= a);
                let mut moved = 0.0;
                while let Some(&b) = candidates.get(next) {
                    next += 1;
                    let b = b as usize;
                    if moved + (max_drift - drift_then) > SLACK {
                        anchor = DVec2::new(self.robots[a].pose.x, self.robots[a].pose.z);
                        drift_then = max_drift;
                        moved = 0.0;
                        query(anchor, drift_then, &mut candidates);
                        next = candidates.partition_point(|&c| (c as usize) < b);
                        continue;
                    }
                    let rb = rigs[b].body_radius;
                    let ca = DVec2::new(self.robots[a].pose.x, self.robots[a].pose.z);
                    let cb = DVec2::new(self.robots[b].pose.x, self.robots[b].pose.z);
                    if let Some((depth, normal)) = (Footprint::Circle {
                        center: cb,
                        radius: rb,
                    })
                    .penetration(ca, ra)
                    {
                        let half = normal * (0.5 * depth);
                        self.robots[a].pose.x += half.x;
                        self.robots[a].pose.z += half.y;
                        self.robots[b].pose.x -= half.x;
                        self.robots[b].pose.z -= half.y;
                        self.robots[a].touched.push((statics + b) as u32);
                        self.robots[b].touched.push((statics + a) as u32);
                        pushed = true;
                        // Bounds on how far each has gone since the grid was filed.
                        let step = half.length() * (1.0 + 1e-9);
                        drift[a] += step;
                        drift[b] += step;
                        moved += step;
                        max_drift = max_drift.max(drift[a]).max(drift[b]);
                    }
                }
                let _ = anchor;
            }
            if !pushed {
                break;
            }
            // The last pass still pushed: what it left may overlap (a pressing crowd).
            unsettled = pass + 1 == PASSES;
        }
        self.scratch.candidates = candidates;
        self.scratch.drift = drift;
        unsettled
    }

    /// After the passes of a crowd: every robot still overlapping something beyond the
    /// tolerance goes back to where it was before this sub-step (where nothing overlapped),
    /// until nothing does. Blocked robots stay put; the others keep their motion.
    fn settle(&mut self) {
        let rigs = &self.compiled.rig.robots;
        let mut candidates = std::mem::take(&mut self.scratch.candidates);
        let mut marked = std::mem::take(&mut self.scratch.marked);
        let max_radius = self.broad.max_radius;
        for _ in 0..=self.robots.len() {
            marked.clear();
            marked.resize(self.robots.len(), false);
            let mut any = false;
            for (index, robot) in self.robots.iter().enumerate() {
                let rig = &rigs[index];
                let (floor, top) = (rig.floor_y, rig.floor_y + rig.body_height);
                let center = DVec2::new(robot.pose.x, robot.pose.z);
                let (lo, hi) = broad_phase::square(center, rig.body_radius);
                self.broad.statics.query(lo, hi, &mut candidates);
                let in_wall = candidates.iter().any(|&k| {
                    let obstacle = &self.slab.obstacles[k as usize];
                    !(obstacle.y1 <= floor + 1e-6 || obstacle.y0 >= top)
                        && obstacle
                            .shape
                            .penetration(center, rig.body_radius)
                            .is_some_and(|(depth, _)| depth > PENETRATION_TOLERANCE)
                });
                if in_wall {
                    marked[index] = true;
                    any = true;
                }
            }
            let robots = &self.robots;
            self.broad.file_robots(robots.len(), |i| {
                DVec2::new(robots[i].pose.x, robots[i].pose.z)
            });
            for a in 0..robots.len() {
                let ca = DVec2::new(robots[a].pose.x, robots[a].pose.z);
                let ra = rigs[a].body_radius;
                let (lo, hi) = broad_phase::square(ca, ra + max_radius);
                self.broad.robots.query(lo, hi, &mut candidates);
                for &b in candidates.iter().filter(|&&b| b as usize > a) {
                    let b = b as usize;
                    let cb = DVec2::new(robots[b].pose.x, robots[b].pose.z);
                    if ca.distance(cb) < ra + rigs[b].body_radius - PENETRATION_TOLERANCE {
                        marked[a] = true;
                        marked[b] = true;
                        any = true;
                    }
                }
            }
            if !any {
                break;
            }
            for ((robot, &back), before) in self
                .robots
                .iter_mut()
                .zip(&marked)
                .zip(&self.scratch.before)
            {
                if back {
                    robot.pose.x = before.x;
                    robot.pose.z = before.y;
                }
            }
        }
        self.scratch.candidates = candidates;
        self.scratch.marked = marked;
    }

    /// A name for everything a robot can touch, in [`Contacts::per_obstacle`] order: a buoy's
    /// landmark name, else the outermost named group the obstacle stands in (a DEF or PROTO
    /// name such as `Arena`), then the robots by name.
    pub fn obstacle_names(&self) -> Vec<String> {
        let graph = &self.compiled.graph;
        let statics = self.slab.obstacles.iter().map(|obstacle| {
            if let Some(landmark) = self
                .compiled
                .landmarks
                .iter()
                .find(|l| l.primitives.contains(&obstacle.primitive))
            {
                return landmark.name.clone();
            }
            let mut group = graph.primitives[obstacle.primitive].group;
            let mut name = None;
            while let Some(g) = group {
                name = Some(&graph.groups[g].name);
                group = graph.groups[g].parent;
            }
            name.cloned().unwrap_or_else(|| "an obstacle".to_owned())
        });
        statics
            .chain(self.robots.iter().map(|r| r.name.clone()))
            .collect()
    }

    /// Counts entries into each landmark's visit disc (its radius plus two body diameters).
    fn track_visits(&mut self) {
        let compiled = self.compiled;
        let mut candidates = std::mem::take(&mut self.scratch.candidates);
        let mut was = std::mem::take(&mut self.scratch.was_inside);
        let time = self.time;
        for (robot, rig) in self.robots.iter_mut().zip(&compiled.rig.robots) {
            let center = DVec2::new(robot.pose.x, robot.pose.z);
            if compiled.landmarks.len() <= FEW_LANDMARKS {
                // A few: each tested, as the grid would hand them (ascending).
                candidates.clear();
                candidates.extend(0..compiled.landmarks.len() as u32);
            } else {
                self.broad.landmarks.query(center, center, &mut candidates);
            }
            let visits = &mut robot.visits;
            was.clear();
            was.extend_from_slice(&visits.inside);
            visits.inside.clear();
            for &k in &candidates {
                let landmark = &compiled.landmarks[k as usize];
                let distance = DVec2::new(
                    robot.pose.x - landmark.center.x,
                    robot.pose.z - landmark.center.y,
                )
                .length();
                if distance <= Visits::disc_radius(landmark.radius, rig.body_radius) {
                    if was.binary_search(&k).is_err() {
                        visits.sequence.push(k as usize);
                        visits.times.push(time);
                    }
                    visits.inside.push(k);
                }
            }
        }
        self.scratch.was_inside = was;
        self.scratch.candidates = candidates;
    }
}

/// Whether robots are sensed and controlled side by side: with more than one thread and
/// enough robots to share (a few robots cost less than handing them out).
fn parallel(robots: &[RobotState]) -> bool {
    robots.len() >= 8 && rayon::current_num_threads() > 1
}

/// Below this many landmarks, each is tested rather than looked up in the grid.
const FEW_LANDMARKS: usize = 8;

/// Collision passes in one sub-step, at most.
const PASSES: usize = 3;

/// How far a robot may move before its collision candidates are asked again (m).
const SLACK: f64 = 0.005;

/// What every robot's sensing reads in a step, shared and never written while robots sense:
/// so robots can be sensed side by side, each writing only its own state.
struct SenseShared<'s, 'c> {
    compiled: &'c Compiled,
    slab: &'s Slab,
    broad: &'s BroadPhase,
    placements: &'s [crate::compile::rig::Placement],
    lights: &'s [crate::render::WorldLight],
    poses: &'s Poses,
    /// The CPU renderer, unless a batched backend renders vision.
    renderer: Option<&'s Renderer<'c>>,
    /// The step's frame, when the renderer shares one between viewers.
    frame: Option<&'s crate::render::column::ColumnFrame>,
    /// The ray caster of the 2-D cameras, when a robot has one.
    camera_caster: Option<&'s crate::render::raycast::RayCaster<'c>>,
    batched: bool,
    t: f64,
}

impl SenseShared<'_, '_> {
    /// Refreshes one robot's due sensors.
    fn sense(&self, index: usize, robot: &mut RobotState) {
        let (compiled, t) = (self.compiled, self.t);
        let rig = &compiled.rig.robots[index];
        let senses = robot.senses;
        robot.vision_requested = false;
        let proximity_sensors = if senses.proximity { 8 } else { 0 };
        let mut nearby_found = false;
        // Sensors that share a period and a due time are due alike: one division for all.
        let mut last_due: Option<(u64, f64, bool, f64)> = None;
        for (s, sensor) in rig
            .distance_sensors
            .iter()
            .enumerate()
            .take(proximity_sensors)
        {
            let period = robot.ir_period.unwrap_or(sensor.period);
            let before = robot.ir_due[s];
            let is_due = match last_due {
                Some((bits, last_period, was_due, after))
                    if bits == before.to_bits() && last_period.to_bits() == period.to_bits() =>
                {
                    robot.ir_due[s] = after;
                    was_due
                }
                _ => {
                    let is_due = due(&mut robot.ir_due[s], t, period);
                    last_due = Some((before.to_bits(), period, is_due, robot.ir_due[s]));
                    is_due
                }
            };
            if !is_due {
                continue;
            }
            if !nearby_found {
                let placement = &self.placements[index];
                sensors::nearby_obstacles(
                    self.slab,
                    &self.broad.statics,
                    placement,
                    robot.ir_reach,
                    &mut robot.nearby,
                );
                robot.nearby_robots.clear();
                if self.placements.len() > 1 {
                    let reach = robot.ir_reach + self.broad.max_radius;
                    let (lo, hi) = broad_phase::square(DVec2::new(placement.x, placement.z), reach);
                    self.broad.robots.query(lo, hi, &mut robot.nearby_robots);
                    // The grid's square holds its corners too: only robots whose bodies come
                    // within reach are worth a sensor's test (in a crowd, most sensors then
                    // have none and trace nothing).
                    let center = DVec2::new(placement.x, placement.z);
                    let sensor_reach = robot.ir_reach;
                    let rigs = &compiled.rig.robots;
                    robot.nearby_robots.retain(|&other| {
                        let place = &self.placements[other as usize];
                        other as usize != index
                            && DVec2::new(place.x, place.z).distance(center)
                                <= sensor_reach + rigs[other as usize].body_radius
                    });
                }
                nearby_found = true;
            }
            robot.updated.proximity = true;
            if robot.nearby.is_empty() && robot.nearby_robots.is_empty() {
                robot.proximity[s] =
                    sensors::proximity_of_nothing(robot.ir_nothing[s], &mut robot.ir_streams[s]);
                continue;
            }
            robot.proximity[s] = sensors::proximity(
                self.slab,
                &robot.nearby,
                &robot.nearby_robots,
                self.placements,
                index,
                &compiled.rig.robots,
                sensor,
                &mut robot.ir_streams[s],
            );
        }
        let ambient_sensors = if senses.ambient { 8 } else { 0 };
        for (s, sensor) in rig.light_sensors.iter().enumerate().take(ambient_sensors) {
            if due(&mut robot.ambient_due[s], t, sensor.period) {
                robot.updated.ambient = true;
                robot.ambient[s] = sensors::ambient(
                    self.lights,
                    self.slab,
                    &self.broad.statics,
                    self.placements,
                    index,
                    sensor,
                    &mut robot.ambient_streams[s],
                );
            }
        }
        // 2-D cameras always render on the CPU, with the ray caster.
        if let (true, Some(caster)) = (senses.camera, self.camera_caster) {
            let mut view = None;
            for (c, camera) in robot.cameras.iter_mut().enumerate() {
                if due(&mut camera.due, t, camera.model.rig.period) {
                    robot.updated.cameras |= 1 << c.min(63);
                    let view = view.get_or_insert_with(|| {
                        caster.prepare(&compiled.plan, self.poses, Some(index))
                    });
                    camera.model.update(
                        caster,
                        view,
                        robot.pose,
                        rig.floor_y,
                        &mut camera.noise,
                        &mut camera.image,
                    );
                }
            }
        }
        if !senses.vision {
            return;
        }
        if self.batched {
            robot.vision_requested = match (&mut robot.panoramic, &mut robot.linear_camera) {
                (Some(turret), _) => due(&mut turret.due, t, turret.model.rig.period),
                (None, Some(camera)) => due(&mut camera.due, t, camera.model.rig.period),
                (None, None) => false,
            };
            return;
        }
        let Some(renderer) = self.renderer else {
            return;
        };
        // The shared frame, or a viewer's own (the ray caster's).
        let own;
        let view = match self.frame {
            Some(frame) => ViewOf::Columns(frame, Some(index)),
            None => {
                own = renderer.view(&compiled.plan, self.poses, index);
                own.of()
            }
        };
        if let Some(turret) = &mut robot.panoramic {
            if due(&mut turret.due, t, turret.model.rig.period) {
                robot.updated.vision = true;
                turret
                    .model
                    .update_of(renderer, view, robot.pose, rig.floor_y, &mut turret.output);
            }
        }
        if let Some(camera) = &mut robot.linear_camera {
            if due(&mut camera.due, t, camera.model.rig.period) {
                robot.updated.vision = true;
                camera
                    .model
                    .update_of(renderer, view, robot.pose, rig.floor_y, &mut camera.output);
            }
        }
    }
}

/// Whether a sensor with `period` is due at `t`; moves its next due time on a regular grid.
fn due(next: &mut f64, t: f64, period: f64) -> bool {
    if period <= 0.0 {
        return true;
    }
    if t + 1e-12 < *next {
        return false;
    }
    *next = (libm::floor(t / period + 1e-9) + 1.0) * period;
    true
}

/// The simulated robot behind the Khepera API.
pub struct SimulatedKhepera<'a> {
    robot: &'a mut RobotState,
    rig: &'a RobotRig,
}

impl Khepera for SimulatedKhepera<'_> {
    fn set_speed(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        for value in [left, right] {
            if !(-127..=127).contains(&value) {
                return Err(KheperaError::OutOfRange {
                    what: "wheel speed",
                    value: value as i64,
                    range: "-127…127",
                });
            }
        }
        self.robot.command = (left, right);
        Ok(())
    }

    fn speed(&mut self) -> Result<(i32, i32), KheperaError> {
        Ok(self.robot.command)
    }

    fn position(&mut self) -> Result<(i32, i32), KheperaError> {
        Ok(self.robot.counters(self.rig))
    }

    fn set_position(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        let raw = |travel: f64| libm::floor(travel * self.rig.encoder_resolution) as i64;
        self.robot.counter_offset = (
            raw(self.robot.travel.0) - left as i64,
            raw(self.robot.travel.1) - right as i64,
        );
        Ok(())
    }

    fn proximity(&mut self) -> Result<[u16; 8], KheperaError> {
        if !self.robot.senses.proximity {
            return Err(KheperaError::NotSensed("proximity sensors"));
        }
        Ok(self.robot.proximity)
    }

    fn ambient(&mut self) -> Result<[u16; 8], KheperaError> {
        if !self.robot.senses.ambient {
            return Err(KheperaError::NotSensed("ambient light sensors"));
        }
        Ok(self.robot.ambient)
    }

    fn set_led(&mut self, led: u8, action: LedAction) -> Result<(), KheperaError> {
        let slot = self
            .robot
            .leds
            .get_mut(led as usize)
            .ok_or(KheperaError::OutOfRange {
                what: "LED",
                value: led as i64,
                range: "0…1",
            })?;
        *slot = match action {
            LedAction::Off => false,
            LedAction::On => true,
            LedAction::Toggle => !*slot,
        };
        Ok(())
    }

    fn panoramic(&mut self) -> Option<&mut dyn PanoramicTurret> {
        self.robot
            .panoramic
            .as_mut()
            .map(|p| p as &mut dyn PanoramicTurret)
    }

    fn linear_camera(&mut self) -> Option<&mut dyn LinearCameraTurret> {
        self.robot
            .linear_camera
            .as_mut()
            .map(|c| c as &mut dyn LinearCameraTurret)
    }

    fn cameras(&mut self) -> Vec<&mut dyn crate::khepera::Camera> {
        self.robot
            .cameras
            .iter_mut()
            .map(|c| c as &mut dyn crate::khepera::Camera)
            .collect()
    }
}

impl crate::khepera::Camera for CameraState {
    fn name(&self) -> &str {
        &self.model.rig.name
    }

    fn size(&self) -> (usize, usize) {
        (self.model.rig.width, self.model.rig.height)
    }

    fn image(&mut self) -> Result<Vec<u8>, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("camera"));
        }
        Ok(self.image.rgb.clone())
    }
}

impl PanoramicState {
    fn reconfigure(&mut self, change: impl FnOnce(&mut crate::compile::rig::PanoramicRig)) {
        let mut rig = self.model.rig.clone();
        change(&mut rig);
        self.model.reconfigure(rig);
        // Filters depend on analog[] alone: recompute them now rather than at the next update.
        if !self.output.luminance.is_empty() {
            self.model.process(&mut self.output);
        }
    }
}

impl PanoramicTurret for PanoramicState {
    fn enable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        if !self.model.rig.filters.contains(filter) {
            self.reconfigure(|rig| rig.filters.insert(filter));
        }
        Ok(())
    }

    fn disable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        if self.model.rig.filters.contains(filter) {
            self.reconfigure(|rig| rig.filters.remove(filter));
        }
        Ok(())
    }

    fn read(&mut self, filter: FilterKind) -> Result<Vec<u16>, KheperaError> {
        let mut out = Vec::new();
        self.read_into(filter, &mut out)?;
        Ok(out)
    }

    fn read_into(&mut self, filter: FilterKind, out: &mut Vec<u16>) -> Result<(), KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("Panoramic turret"));
        }
        if !self.model.rig.filters.contains(filter) {
            return Err(KheperaError::FilterNotEnabled(filter.name()));
        }
        out.clear();
        if let Some((_, digital)) = self.output.digital.iter().find(|(k, _)| *k == filter) {
            out.extend_from_slice(digital);
        }
        Ok(())
    }

    fn set_lambda(&mut self, lambda: f64) -> Result<(), KheperaError> {
        if !(lambda > 0.0 && lambda.is_finite()) {
            return Err(KheperaError::OutOfRange {
                what: "λ (×1000)",
                value: (lambda * 1000.0) as i64,
                range: "> 0",
            });
        }
        self.reconfigure(|rig| rig.lambda = lambda);
        Ok(())
    }

    fn set_bits(&mut self, bits: u32) -> Result<(), KheperaError> {
        if !(1..=16).contains(&bits) {
            return Err(KheperaError::OutOfRange {
                what: "bits",
                value: bits as i64,
                range: "1…16",
            });
        }
        self.reconfigure(|rig| rig.bits = bits);
        Ok(())
    }

    fn set_region_of_interest(&mut self, first: usize, last: usize) -> Result<(), KheperaError> {
        if first > last || last >= crate::retina::PIXELS {
            return Err(KheperaError::OutOfRange {
                what: "region of interest end",
                value: last as i64,
                range: "first ≤ last ≤ 149",
            });
        }
        self.reconfigure(|rig| rig.roi = (first, last));
        Ok(())
    }

    fn region_of_interest(&mut self) -> Result<(usize, usize), KheperaError> {
        Ok(self.model.rig.roi)
    }

    fn bits(&mut self) -> Result<u32, KheperaError> {
        Ok(self.model.rig.bits)
    }

    fn lambda(&mut self) -> Result<f64, KheperaError> {
        Ok(self.model.rig.lambda)
    }
}

impl LinearCameraTurret for LinearCameraState {
    fn pixels(&mut self) -> Result<Vec<u16>, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("K213 camera"));
        }
        Ok(self.output.digital.clone())
    }

    fn light_level(&mut self) -> Result<u16, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("K213 camera"));
        }
        Ok(self.output.light_level)
    }
}
