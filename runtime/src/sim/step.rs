//! The simulation and its step loop: fixed steps of `WorldInfo.basicTimeStep`. In each step, sensors that are
//! due update (each at its own period), controllers whose period is due read them and set
//! wheel speeds (each robot at its own `controlPeriod`, a whole number of steps: the step
//! sets how finely motion is integrated, never how often a robot decides), then kinematics
//! and collisions run. All randomness comes from the run's seed, one stream per
//! robot and per sensor; robots are visited in file order; nothing depends on wall time.
//! A step is two halves: [`Simulation::sense`] (sensors, side by side where robots are many)
//! and [`Simulation::act`] (controllers, then motion and collisions, falls and visits).

use std::sync::Arc;

use glam::DVec2;

use super::broad_phase::BroadPhase;
use super::contacts::Motion;
use super::drive::Drive;
use super::noise::{kind, Stream};
use super::robot::SimulatedKhepera;
use super::sense::SenseShared;
use super::sensors;
use super::state::{
    Bodies, CameraState, Contacts, LinearCameraState, PanoramicState, PhaseClock, PhaseTimes,
    RobotState, StepScratch, ThreadLists, Updated, Visits,
};
use super::visits::{finish_step, FloorSets};
use super::world2d::Slab;
use crate::compile::rig::{DistanceSensorRig, TurretRig};
use crate::compile::Compiled;
use crate::controllers;
use crate::khepera::{Controller, Senses};
use crate::optics::{LinearCamera, LinearCameraOutput, Panoramic, Renderer, RetinaOutput};
use crate::render::Poses;
use crate::vision::{VisionBackend, VisionError, VisionRequest, WorldInstance};

/// Each IR sensor's (mean, spread) with nothing in range, shared by robots with the same
/// sensors.
type Nothing = Arc<[sensors::NothingInRange]>;

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

/// A running world.
pub struct Simulation<'c> {
    pub compiled: &'c Compiled,
    renderer: Option<Renderer<'c>>,
    /// The ray caster of the 2-D cameras that ask for it (the reference).
    camera_caster: Option<crate::render::raycast::RayCaster<'c>>,
    /// The rasteriser of the other 2-D cameras (the default).
    camera_raster: Option<crate::render::raster::Rasterizer<'c>>,
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
    /// What every step reads of each robot's rig, in a line a robot ([`Body`]).
    bodies: Bodies,
    /// The floors each robot started on (leaving all of them is a fall).
    floors: FloorSets,
    /// Whether every vision device looks with the crowd level of detail (a Panoramic turret
    /// with a crowd distance): the step's shared frame then places no part that only
    /// exact looks draw.
    crowd_looks_only: bool,
    /// Simulated time (s) and steps done.
    pub time: f64,
    pub steps: u64,
    pub time_step: f64,
    pub seed: u64,
    /// The seed the noise streams were made from (`seed` as it was at the start): streams made
    /// on first use (ambient sensors) come from it.
    streams_seed: u64,
    /// Sensors refreshed whether or not a controller reads them (what a log records).
    pub always_sensed: Senses,
    /// Buffers a step fills and the next reuses: stepping allocates nothing once warm.
    scratch: StepScratch,
    /// Wall time spent in each phase, when profiling (`regatta bench step`); never read by
    /// the simulation itself, so it changes no result.
    profile: Option<PhaseTimes>,
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
        // The last robot's sensors and their readings of nothing: the next robot with the same
        // sensors (a swarm's, shared by the rig) reads the same values from one place, which
        // stays in cache across a crowd instead of costing each robot a miss.
        let mut last_nothing: Option<(&Arc<Vec<DistanceSensorRig>>, Nothing)> = None;
        // Every robot's IR due times and noise streams, allocated one robot after the other
        // before anything else of theirs: the sensing sweep then reads ascending addresses that
        // the hardware's prefetcher follows (interleaved with each robot's other allocations,
        // a crowd's streams cost a cache miss a robot).
        let mut ir_state = compiled
            .rig
            .robots
            .iter()
            .enumerate()
            .map(|(index, rig)| {
                let count = rig.distance_sensors.len();
                let due = vec![0.0; count];
                let streams: Vec<Stream> = (0..count)
                    .map(|s| Stream::new(seed, index, kind::PROXIMITY, s))
                    .collect();
                (due, streams)
            })
            .collect::<Vec<_>>()
            .into_iter();
        for (index, rig) in compiled.rig.robots.iter().enumerate() {
            let (ir_due, ir_streams) = ir_state.next().unwrap_or_default();
            let controller =
                controllers::build_for(rig).map_err(|source| SimError::Controller {
                    robot: rig.name.clone(),
                    source,
                })?;
            let ir_nothing: Nothing = match &last_nothing {
                Some((sensors, nothing)) if Arc::ptr_eq(sensors, &rig.distance_sensors) => {
                    nothing.clone()
                }
                _ => {
                    let nothing: Nothing = rig
                        .distance_sensors
                        .iter()
                        .map(sensors::nothing_in_range)
                        .collect();
                    last_nothing = Some((&rig.distance_sensors, nothing.clone()));
                    nothing
                }
            };
            let ir_quiet = ir_nothing.iter().all(|n| n.spread == 0.0);
            let ir_period = rig.distance_sensors.first().map(|s| s.period).filter(|&p| {
                rig.distance_sensors
                    .iter()
                    .all(|s| s.period.to_bits() == p.to_bits())
            });
            robots.push(RobotState {
                name: rig.name.clone(),
                updated: Updated::default(),
                pose: rig.start,
                command: (0, 0),
                travel: (0.0, 0.0),
                counter_offset: (0, 0),
                leds: [false; 2],
                wheel_velocity: None,
                raw: None,
                senses: Senses::ALL,
                proximity: [0; 8],
                ambient: [0; 8],
                ir_together: ir_period.is_some()
                    && ir_due
                        .iter()
                        .all(|d: &f64| d.to_bits() == ir_due[0].to_bits()),
                ir_next: ir_due.first().copied().unwrap_or(0.0),
                has_devices: false,
                ir_due,
                // Made when first read (most robots' controllers never do): the same due
                // times and streams as if made here, since none is drawn before that.
                ambient_due: Vec::new(),
                ir_nothing,
                ir_quiet,
                ir_reach: sensors::ir_reach(&rig.distance_sensors),
                ir_period,
                ir_streams,
                ir_skipped: 0,
                ambient_streams: Vec::new(),
                wheel_stream: Stream::new(seed, index, kind::WHEELS, 0),
                wheel_noise: (1.0, 1.0),
                panoramic: match &rig.turret {
                    Some(TurretRig::Panoramic(p)) => Some(Box::new(PanoramicState {
                        model: Panoramic::new_like(
                            p,
                            last_panoramic
                                .and_then(|r| robots[r].panoramic.as_ref())
                                .map(|state| &state.model),
                        ),
                        output: RetinaOutput::default(),
                        due: 0.0,
                        sensed: true,
                    })),
                    _ => None,
                },
                linear_camera: match &rig.turret {
                    // Boxed: the robots without one (a swarm's) keep 288 bytes less each.
                    Some(TurretRig::Linear(c)) => Some(Box::new(LinearCameraState {
                        model: LinearCamera::new(c),
                        output: LinearCameraOutput::default(),
                        due: 0.0,
                        sensed: true,
                    })),
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
                    sequence: Vec::with_capacity(16),
                    times: Vec::with_capacity(16),
                },
                visiting: Vec::with_capacity(4),
                touched: Vec::with_capacity(8),
                vision_requested: false,
                fell: None,
            });
            let robot = &mut robots[index];
            robot.has_devices = robot.panoramic.is_some()
                || robot.linear_camera.is_some()
                || !robot.cameras.is_empty();
            if robot.panoramic.is_some() {
                last_panoramic = Some(index);
            }
        }
        let uses = |renderer: crate::compile::rig::CameraRenderer| {
            compiled
                .rig
                .robots
                .iter()
                .flat_map(|r| &r.cameras)
                .any(|c| c.renderer == renderer)
        };
        let camera_caster = uses(crate::compile::rig::CameraRenderer::Rays)
            .then(|| crate::render::raycast::RayCaster::new(&compiled.graph, &compiled.plan));
        let camera_raster = uses(crate::compile::rig::CameraRenderer::Raster)
            .then(|| crate::render::raster::Rasterizer::new(&compiled.graph, &compiled.plan));
        let mut simulation = Simulation {
            compiled,
            renderer,
            camera_caster,
            camera_raster,
            vision: None,
            vision_error: None,
            vision_buffers: Vec::new(),
            slab,
            broad,
            robots,
            bodies: Bodies::of(&compiled.rig.robots),
            floors: FloorSets::of(&compiled.rig.robots),
            crowd_looks_only: compiled.rig.robots.iter().all(|r| match &r.turret {
                None => true,
                Some(TurretRig::Panoramic(turret)) => turret.crowd_distance.is_finite(),
                Some(TurretRig::Linear(_)) => false,
            }),
            time: 0.0,
            steps: 0,
            time_step,
            seed,
            streams_seed: seed,
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
        // Robots that start inside a visit disc visit it at time 0.
        finish_step(
            &mut simulation.robots,
            (compiled, &simulation.bodies, &simulation.floors),
            &simulation.broad,
            (None, simulation.time),
            &mut simulation.scratch,
        );
        Ok(simulation)
    }

    /// Whether the retinas keep their filters' outputs over every pixel (`RetinaOutput`'s
    /// `filtered`, which logs record) or only their converted outputs, which controllers
    /// read: a run that records nothing keeps 1.2 kB less per retina. Kept unless told.
    pub fn keep_filter_outputs(&mut self, keep: bool) {
        for turret in self.robots.iter_mut().filter_map(|r| r.panoramic.as_mut()) {
            turret.output.filtered_unkept = !keep;
            if !keep {
                turret.output.filtered = Vec::new();
            }
        }
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

    /// Advances the world by one step: [`Simulation::sense`] then [`Simulation::act`]. Where
    /// nothing comes between them (no batched vision backend, no profile of the phases),
    /// each robot is sensed and driven in one sweep: its controller reads only its own
    /// readings, so the results are the same, and each robot's lines are read once for both.
    pub fn step(&mut self) {
        if self.vision.is_some() || self.profile.is_some() {
            self.sense();
            self.act();
            return;
        }
        self.mark_senses();
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut speeds = std::mem::take(&mut scratch.speeds);
        speeds.clear();
        speeds.resize(self.robots.len(), (0.0, 0.0));
        let most_sub_steps = self.update_sensors_with(self.time, &mut scratch, Some(&mut speeds));
        self.scratch = scratch;
        self.move_and_finish(&mut PhaseClock::start(false), speeds, most_sub_steps);
    }

    /// The first half of a step: clears the update flags and refreshes the sensors that are
    /// due. A robot driven from outside (over the serial protocol) is read and commanded
    /// between this and [`Simulation::act`], exactly where a built-in controller runs.
    pub fn sense(&mut self) {
        self.mark_senses();
        let mut clock = PhaseClock::start(self.profile.is_some());
        let mut scratch = std::mem::take(&mut self.scratch);
        self.update_sensors_with(self.time, &mut scratch, None);
        self.scratch = scratch;
        clock.lap(self.profile.as_mut().map(|p| &mut p.sense));
    }

    /// Clears each robot's update flags and marks what it senses in this step; gathers where
    /// every robot is, in the same sweep (each robot's first line read once, not once per
    /// list).
    fn mark_senses(&mut self) {
        let StepScratch {
            poses, placements, ..
        } = &mut self.scratch;
        if poses.floor_y.len() != self.bodies.len() {
            // Robots never change floors' heights: filed once.
            let bodies = &self.bodies;
            poses.floor_y.clear();
            poses
                .floor_y
                .extend((0..bodies.len()).map(|i| bodies.get(i).floor_y));
        }
        poses.poses.clear();
        placements.clear();
        // Other robots are read by where they stand (IR sensors, the grid); a renderer reads
        // how they are turned too. Without one, a robot's own sensors turn it where they need
        // it (`SenseShared::turned`): one `sincos` less for a robot nothing is near.
        let turned = self.renderer.is_some();
        for (robot, &floor_y) in self.robots.iter_mut().zip(&poses.floor_y) {
            poses.poses.push(robot.pose);
            placements.push(if turned {
                robot.pose.placement(floor_y)
            } else {
                crate::compile::rig::Placement {
                    x: robot.pose.x,
                    z: robot.pose.z,
                    floor_y,
                    sin: f64::NAN,
                    cos: f64::NAN,
                }
            });
            robot.updated = Updated::default();
            // A robot driven from outside may read anything its protocol reads. Which of its
            // devices are read is marked as it senses (where their line is read anyway).
            let reads = robot
                .controller
                .as_ref()
                .map_or(Senses::PROTOCOL, |c| c.senses());
            robot.senses = reads.union(self.always_sensed);
        }
    }

    /// The second half of a step: runs the built-in controllers, moves the robots and
    /// advances time.
    pub fn act(&mut self) {
        let mut clock = PhaseClock::start(self.profile.is_some());
        // Each controller drives its own robot only, and its wheel speeds follow from its own
        // commands and noise: side by side, the same results; robot by robot, one sweep.
        let drive = Drive {
            rigs: &self.compiled.rig.robots,
            bodies: &self.bodies,
            steps: self.steps,
            dt: self.time_step,
        };
        let mut speeds = std::mem::take(&mut self.scratch.speeds);
        speeds.clear();
        speeds.resize(self.robots.len(), (0.0, 0.0));
        let most_sub_steps = if parallel(self.robots.len() as u64 * CONTROL_NS) {
            use rayon::prelude::*;
            self.robots
                .par_iter_mut()
                .zip(speeds.par_iter_mut())
                .enumerate()
                .map(|(index, (robot, speeds))| drive.drive(index, robot, speeds))
                .max()
                .unwrap_or(0)
        } else {
            let mut most = 0;
            for (index, (robot, speeds)) in self.robots.iter_mut().zip(&mut speeds).enumerate() {
                most = most.max(drive.drive(index, robot, speeds));
            }
            most
        };
        clock.lap(self.profile.as_mut().map(|p| &mut p.control));
        self.move_and_finish(&mut clock, speeds, most_sub_steps);
    }

    /// Moves the robots at `speeds` (m/s, each robot's wheels) in `most_sub_steps` sub-steps,
    /// advances time, and counts contacts, falls and visits.
    fn move_and_finish(
        &mut self,
        clock: &mut PhaseClock,
        speeds: Vec<(f64, f64)>,
        most_sub_steps: usize,
    ) {
        Motion {
            rigs: &self.bodies,
            slab: &self.slab,
            broad: &mut self.broad,
            robots: &mut self.robots,
            scratch: &mut self.scratch,
            profile: &mut self.profile,
            time_step: self.time_step,
        }
        .move_robots(clock, &speeds, most_sub_steps);
        self.scratch.speeds = speeds;
        self.steps += 1;
        self.time = self.steps as f64 * self.time_step;
        finish_step(
            &mut self.robots,
            (self.compiled, &self.bodies, &self.floors),
            &self.broad,
            (Some(self.time_step), self.time),
            &mut self.scratch,
        );
        clock.lap(self.profile.as_mut().map(|p| &mut p.collisions));
    }

    /// Whether robot `robot`'s controller runs in the step about to be taken (its control
    /// period's grid): where something driving it from outside reads and commands it.
    pub fn control_due(&self, robot: usize) -> bool {
        self.steps
            .is_multiple_of(self.compiled.rig.robots[robot].control_steps)
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

    /// Refreshes every robot's due sensors at `t`; with `control`, drives each robot right
    /// after it senses, its wheel speeds into `control`, and returns the most sub-steps any
    /// needs (0 without).
    fn update_sensors_with(
        &mut self,
        t: f64,
        scratch: &mut StepScratch,
        control: Option<&mut [(f64, f64)]>,
    ) -> usize {
        let compiled = self.compiled;
        let StepScratch {
            poses,
            placements,
            lights,
            lights_move,
            requests,
            ..
        } = scratch;
        // Placed in `sense`'s first sweep.
        let (poses, placements) = (&*poses, &*placements);
        // Ambient sensors read the plan's lights, placed once per step where they move.
        if *lights_move
            && self
                .robots
                .iter()
                .zip(&compiled.rig.robots)
                .any(|(r, rig)| r.senses.ambient && !rig.light_sensors.is_empty())
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
            Some(renderer) if self.robots.iter().any(|r| r.vision_due(t)) => renderer
                .prepare_shared(
                    &compiled.plan,
                    poses,
                    placements,
                    self.crowd_looks_only,
                    frame,
                ),
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
            camera_raster: self.camera_raster.as_ref(),
            batched: self.vision.is_some(),
            t,
            streams_seed: self.streams_seed,
        };
        // Each robot reads only what is shared and writes only itself: side by side when
        // there is enough work, and the same results either way.
        let renders = renderer.is_some();
        let work: u64 = self
            .robots
            .iter()
            .zip(&compiled.rig.robots)
            .map(|(r, rig)| {
                if renders && r.vision_due(t) {
                    vision_ns(rig)
                } else {
                    SENSORS_NS
                }
            })
            .sum();
        let drive = Drive {
            rigs: &compiled.rig.robots,
            bodies: &self.bodies,
            steps: self.steps,
            dt: self.time_step,
        };
        let robots = self.robots.len();
        let work = work + control.as_ref().map_or(0, |_| robots as u64 * CONTROL_NS);
        // Robots are handed out in runs of about TASK_NS of work: one a task when each
        // renders, dozens when they only cast IR rays.
        let run = (TASK_NS / (work / robots.max(1) as u64).max(1)).max(1) as usize;
        let most_sub_steps = match (parallel(work), control) {
            (true, None) => {
                use rayon::prelude::*;
                self.robots
                    .par_iter_mut()
                    .enumerate()
                    .with_min_len(run)
                    .with_max_len(run)
                    .for_each_init(ThreadLists::lend, |lists, (index, robot)| {
                        shared.sense(index, robot, lists)
                    });
                0
            }
            (true, Some(speeds)) => {
                use rayon::prelude::*;
                self.robots
                    .par_iter_mut()
                    .zip(speeds.par_iter_mut())
                    .enumerate()
                    .with_min_len(run)
                    .with_max_len(run)
                    .map_init(ThreadLists::lend, |lists, (index, (robot, speeds))| {
                        shared.sense(index, robot, lists);
                        drive.drive(index, robot, speeds)
                    })
                    .max()
                    .unwrap_or(0)
            }
            (false, None) => {
                for (index, robot) in self.robots.iter_mut().enumerate() {
                    shared.sense(index, robot, &mut scratch.nearby);
                }
                0
            }
            (false, Some(speeds)) => {
                let mut most = 0;
                for (index, (robot, speeds)) in self.robots.iter_mut().zip(speeds).enumerate() {
                    shared.sense(index, robot, &mut scratch.nearby);
                    most = most.max(drive.drive(index, robot, speeds));
                }
                most
            }
        };
        requests.clear();
        if !shared.batched {
            return most_sub_steps;
        }
        requests.extend(
            self.robots
                .iter()
                .enumerate()
                .filter(|(_, r)| r.vision_requested)
                .map(|(robot, _)| VisionRequest { instance: 0, robot }),
        );
        if requests.is_empty() || self.vision_error.is_some() {
            return most_sub_steps;
        }
        let Some(backend) = &mut self.vision else {
            return most_sub_steps;
        };
        let instances = [WorldInstance { scene: 0, poses }];
        if let Err(error) = backend.render(&instances, requests, &mut self.vision_buffers) {
            self.vision_error = Some(error);
            return most_sub_steps;
        }
        for (request, luminance) in requests.iter().zip(&self.vision_buffers) {
            let robot = &mut self.robots[request.robot];
            robot.updated.vision = true;
            if let Some(turret) = &mut robot.panoramic {
                turret.model.accept_unkept(luminance, &mut turret.output);
            } else if let Some(camera) = &mut robot.linear_camera {
                camera.model.accept(luminance, &mut camera.output);
            }
        }
        most_sub_steps
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
}

/// Estimated work of sensing a robot whose vision device is due (ns; a retina's update is
/// tens of microseconds), and of one that only reads IR and ambient light (under a
/// microsecond). Estimates, not clock readings: which phases run side by side never depends
/// on the machine's load, and results are the same either way.
const VISION_NS: u64 = 50_000;
/// A Panoramic retina with the crowd level of detail: 2.6 to 14 µs to render at 10 to 1000
/// robots (`regatta bench crowd`, 0.5 m), and its filters and converter.
const CROWD_VISION_NS: u64 = 10_000;
const SENSORS_NS: u64 = 700;
/// Estimated work of one built-in controller's call (ns).
const CONTROL_NS: u64 = 300;
/// Work of a phase below which handing robots to other threads costs more than it saves:
/// 100 IR-only robots (70 µs) ran 30 % slower on two threads than on one.
const PARALLEL_NS: u64 = 200_000;
/// Work of one parallel task (ns).
const TASK_NS: u64 = 20_000;

/// The estimated work of `rig`'s vision device (ns).
fn vision_ns(rig: &crate::compile::rig::RobotRig) -> u64 {
    match &rig.turret {
        Some(crate::compile::rig::TurretRig::Panoramic(turret))
            if turret.crowd_distance.is_finite() =>
        {
            CROWD_VISION_NS
        }
        _ => VISION_NS,
    }
}

/// Whether a phase of `work` ns runs side by side: with more than one thread, and enough
/// work that sharing it out pays.
fn parallel(work: u64) -> bool {
    work >= PARALLEL_NS && rayon::current_num_threads() > 1
}
