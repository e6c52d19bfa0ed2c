//! The runtime loop: fixed steps of `WorldInfo.basicTimeStep`. In each step, sensors that are
//! due update (each at its own period), controllers read them and set wheel speeds, then
//! kinematics and collisions run. All randomness comes from the run's seed, one stream per
//! robot and per sensor; robots are visited in file order; nothing depends on wall time.

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
use crate::optics::{LinearCamera, LinearCameraOutput, Panoramic, Renderer, RetinaOutput};
use crate::render::Poses;
use crate::retina::FilterKind;
use crate::vision::{VisionBackend, VisionError, VisionRequest, WorldInstance};
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
    /// Contact events per obstacle (static obstacles, then robots).
    pub per_obstacle: Vec<u64>,
    touching: Vec<bool>,
}

impl Contacts {
    /// Whether the robot ended the last step touching something.
    pub fn is_touching(&self) -> bool {
        self.touching.iter().any(|&t| t)
    }

    /// What it ended the last step touching, per obstacle (in
    /// [`Simulation::obstacle_names`] order).
    pub fn touching(&self) -> &[bool] {
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
    inside: Vec<bool>,
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
    ambient_streams: Vec<Stream>,
    wheel_stream: Stream,
    pub panoramic: Option<PanoramicState>,
    pub linear_camera: Option<LinearCameraState>,
    controller: Option<Box<dyn Controller>>,
    /// Controller calls that returned an error, and the last message.
    pub controller_errors: u64,
    pub last_controller_error: Option<String>,
    pub contacts: Contacts,
    pub visits: Visits,
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
    /// A batched backend that renders every due vision device of a step in one call,
    /// replacing the CPU renderer.
    vision: Option<Box<dyn VisionBackend + 'c>>,
    /// The first error the vision backend returned; vision readings stop refreshing after it.
    pub vision_error: Option<VisionError>,
    vision_buffers: Vec<Vec<f64>>,
    pub slab: Slab,
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
    /// One robot's obstacles its IR sensors could see.
    nearby: Vec<u32>,
    speeds: Vec<(f64, f64)>,
    touched: Vec<Vec<bool>>,
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
        let landmarks = compiled.landmarks.len();
        let obstacles = slab.obstacles.len() + compiled.rig.robots.len();
        let mut robots = Vec::with_capacity(compiled.rig.robots.len());
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
                ir_streams: (0..rig.distance_sensors.len())
                    .map(|s| Stream::new(seed, index, kind::PROXIMITY, s))
                    .collect(),
                ambient_streams: (0..rig.light_sensors.len())
                    .map(|s| Stream::new(seed, index, kind::AMBIENT, s))
                    .collect(),
                wheel_stream: Stream::new(seed, index, kind::WHEELS, 0),
                panoramic: match &rig.turret {
                    Some(TurretRig::Panoramic(p)) => Some(PanoramicState {
                        model: Panoramic::new(p),
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
                controller: Some(controller),
                controller_errors: 0,
                last_controller_error: None,
                contacts: Contacts {
                    per_obstacle: vec![0; obstacles],
                    touching: vec![false; obstacles],
                    ..Contacts::default()
                },
                visits: Visits {
                    sequence: Vec::new(),
                    times: Vec::new(),
                    inside: vec![false; landmarks],
                },
                fell: None,
            });
        }
        let mut simulation = Simulation {
            compiled,
            renderer,
            vision: None,
            vision_error: None,
            vision_buffers: Vec::new(),
            slab,
            robots,
            time: 0.0,
            steps: 0,
            time_step,
            seed,
            always_sensed: Senses::NONE,
            scratch: StepScratch::default(),
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
            // A robot driven from outside may read anything.
            let reads = robot
                .controller
                .as_ref()
                .map_or(Senses::ALL, |c| c.senses());
            robot.senses = reads.union(self.always_sensed);
            let vision = robot.senses.vision;
            if let Some(turret) = &mut robot.panoramic {
                turret.sensed = vision;
            }
            if let Some(camera) = &mut robot.linear_camera {
                camera.sensed = vision;
            }
        }
        self.update_sensors(t);
    }

    /// The second half of a step: runs the built-in controllers, moves the robots and
    /// advances time.
    pub fn act(&mut self) {
        let rigs = &self.compiled.rig.robots;
        for (index, robot) in self.robots.iter_mut().enumerate() {
            let Some(mut controller) = robot.controller.take() else {
                continue;
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
        }
        self.move_robots();
        self.steps += 1;
        self.time = self.steps as f64 * self.time_step;
        self.track_falls();
        self.track_visits();
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
            nearby,
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
        let lights = &*lights;
        requests.clear();
        for (index, robot) in self.robots.iter_mut().enumerate() {
            let rig = &compiled.rig.robots[index];
            let mut nearby_found = false;
            let senses = robot.senses;
            let proximity_sensors = if senses.proximity { 8 } else { 0 };
            for (s, sensor) in rig
                .distance_sensors
                .iter()
                .enumerate()
                .take(proximity_sensors)
            {
                if due(&mut robot.ir_due[s], t, sensor.period) {
                    if !nearby_found {
                        sensors::nearby_obstacles(
                            &self.slab,
                            &placements[index],
                            &rig.distance_sensors,
                            nearby,
                        );
                        nearby_found = true;
                    }
                    robot.updated.proximity = true;
                    robot.proximity[s] = sensors::proximity(
                        &self.slab,
                        nearby,
                        placements,
                        index,
                        &compiled.rig.robots,
                        sensor,
                        &mut robot.ir_streams[s],
                    );
                }
            }
            let ambient_sensors = if senses.ambient { 8 } else { 0 };
            for (s, sensor) in rig.light_sensors.iter().enumerate().take(ambient_sensors) {
                if due(&mut robot.ambient_due[s], t, sensor.period) {
                    robot.updated.ambient = true;
                    robot.ambient[s] = sensors::ambient(
                        lights,
                        &self.slab,
                        placements,
                        index,
                        sensor,
                        &mut robot.ambient_streams[s],
                    );
                }
            }
            if !senses.vision {
                continue;
            }
            if self.vision.is_some() {
                let due_now = match (&mut robot.panoramic, &mut robot.linear_camera) {
                    (Some(turret), _) => due(&mut turret.due, t, turret.model.rig.period),
                    (None, Some(camera)) => due(&mut camera.due, t, camera.model.rig.period),
                    (None, None) => false,
                };
                if due_now {
                    requests.push(VisionRequest {
                        instance: 0,
                        robot: index,
                    });
                }
                continue;
            }
            if let Some(renderer) = &self.renderer {
                if let Some(turret) = &mut robot.panoramic {
                    if due(&mut turret.due, t, turret.model.rig.period) {
                        robot.updated.vision = true;
                        let view = renderer.view(&compiled.plan, poses, index);
                        turret.model.update(
                            renderer,
                            &view,
                            robot.pose,
                            rig.floor_y,
                            &mut turret.output,
                        );
                    }
                }
                if let Some(camera) = &mut robot.linear_camera {
                    if due(&mut camera.due, t, camera.model.rig.period) {
                        robot.updated.vision = true;
                        let view = renderer.view(&compiled.plan, poses, index);
                        camera.model.update(
                            renderer,
                            &view,
                            robot.pose,
                            rig.floor_y,
                            &mut camera.output,
                        );
                    }
                }
            }
        }
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

    fn move_robots(&mut self) {
        let dt = self.time_step;
        let rigs = &self.compiled.rig.robots;
        let mut speeds = std::mem::take(&mut self.scratch.speeds);
        let mut touched = std::mem::take(&mut self.scratch.touched);
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
        touched.resize_with(self.robots.len(), Vec::new);
        for row in &mut touched {
            row.clear();
            row.resize(self.slab.obstacles.len() + rigs.len(), false);
        }
        for _ in 0..sub_steps {
            for ((robot, rig), &(left, right)) in self.robots.iter_mut().zip(rigs).zip(&speeds) {
                robot.pose = kinematics::advance(robot.pose, left, right, rig.axle_length, h);
                robot.travel.0 += left * h;
                robot.travel.1 += right * h;
            }
            self.resolve_collisions(&mut touched);
        }
        for (robot, touched) in self.robots.iter_mut().zip(&touched) {
            let contacts = &mut robot.contacts;
            let any = touched.iter().any(|&t| t);
            for (k, &now) in touched.iter().enumerate() {
                if now && !contacts.touching[k] {
                    contacts.per_obstacle[k] += 1;
                }
            }
            let was = contacts.touching.iter().any(|&t| t);
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
        self.scratch.touched = touched;
    }

    /// Pushes bodies out of obstacles and out of each other.
    fn resolve_collisions(&mut self, touched: &mut [Vec<bool>]) {
        let rigs = &self.compiled.rig.robots;
        let statics = self.slab.obstacles.len();
        for _ in 0..3 {
            // A pass that pushes nothing leaves the next one nothing new to find.
            let mut pushed = false;
            for (index, robot) in self.robots.iter_mut().enumerate() {
                let rig = &rigs[index];
                let (floor, top) = (rig.floor_y, rig.floor_y + rig.body_height);
                for (k, obstacle) in self.slab.obstacles.iter().enumerate() {
                    if obstacle.y1 <= floor + 1e-6 || obstacle.y0 >= top {
                        continue;
                    }
                    let center = DVec2::new(robot.pose.x, robot.pose.z);
                    if let Some((depth, normal)) =
                        obstacle.shape.penetration(center, rig.body_radius)
                    {
                        let moved = center + normal * depth;
                        robot.pose.x = moved.x;
                        robot.pose.z = moved.y;
                        touched[index][k] = true;
                        pushed = true;
                    } else if obstacle
                        .shape
                        .penetration(center, rig.body_radius + 1e-6)
                        .is_some()
                    {
                        touched[index][k] = true;
                    }
                }
            }
            for a in 0..self.robots.len() {
                for b in a + 1..self.robots.len() {
                    let (ra, rb) = (rigs[a].body_radius, rigs[b].body_radius);
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
                        touched[a][statics + b] = true;
                        touched[b][statics + a] = true;
                        pushed = true;
                    }
                }
            }
            if !pushed {
                break;
            }
        }
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
        for (robot, rig) in self.robots.iter_mut().zip(&compiled.rig.robots) {
            for (k, landmark) in compiled.landmarks.iter().enumerate() {
                let distance = DVec2::new(
                    robot.pose.x - landmark.center.x,
                    robot.pose.z - landmark.center.y,
                )
                .length();
                let inside = distance <= Visits::disc_radius(landmark.radius, rig.body_radius);
                if inside && !robot.visits.inside[k] {
                    robot.visits.sequence.push(k);
                    robot.visits.times.push(self.time);
                }
                robot.visits.inside[k] = inside;
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
