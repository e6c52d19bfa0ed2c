//! Controller processes in lock-step with a simulation: started with a socket to talk over,
//! answered with their robot's readings when the time they asked of `wb_robot_step` has
//! passed, and their commands applied to the robot before it moves.
//!
//! Between [`Simulation::sense`] and [`Simulation::act`] of every step, [`Controllers::exchange`]
//! first sends a reply to every controller whose step is due, then reads each one's next
//! request, in robot order: the controllers compute side by side, and each sees only its own
//! robot, so a run is the same whatever the machine's load. Nothing is timed by the wall
//! clock except the timeout that ends a run whose controller stopped answering.

use std::os::unix::net::UnixListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use regatta_runtime::khepera::{Controller, Khepera, KheperaError, Senses};
use regatta_runtime::sim::Simulation;

use crate::devices::{with_resolution, Device, Source};
use crate::error::WebotsError;
use crate::link::{absolute, describe_exit, socket_folder, Link};
use crate::output::{Output, ProgramLine};
use crate::protocol::{self, kind, op, status, Command as StepCommand, Writer};
use crate::radio::{Delivered, Listener, Packet, Radio};
use crate::supervisor::{Supervisor, MODE_REAL_TIME};

/// How controllers are run.
#[derive(Clone, Debug)]
pub struct Options {
    /// How long a controller may take to connect, or to ask for its next step (wall time).
    pub timeout: Duration,
    /// Where controllers' output goes: each line prefixed by the robot's name.
    pub echo: bool,
    /// Whether controllers' output lines and LEDs are kept for a log ([`Controllers::take_records`]).
    pub record: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            timeout: Duration::from_secs(10),
            echo: true,
            record: false,
        }
    }
}

/// A robot to be driven by a controller program.
pub struct Start {
    /// The robot's index in the world.
    pub robot: usize,
    /// The controller's name, as the world gives it.
    pub controller: String,
    /// The executable, and the folder it runs in; no executable for an `<extern>` controller,
    /// which the user starts.
    pub executable: Option<PathBuf>,
    pub folder: PathBuf,
    pub args: Vec<String>,
    /// Environment variables added to the controller's (a Python controller's `PYTHONPATH`).
    pub env: Vec<(std::ffi::OsString, std::ffi::OsString)>,
    /// Its devices, in tag order ([`crate::devices::devices`]).
    pub devices: Vec<Device>,
    /// Whether the world's file is z-up (positions answer in the file's axes).
    pub z_up: bool,
    /// Whether the robot is a supervisor, and its custom data.
    pub supervisor: bool,
    pub custom_data: String,
    /// Its rotation as written and the world's north, in the file's axes.
    pub start_rotation: glam::DMat3,
    pub north: glam::DVec3,
    /// Gravity (m/s²), which accelerometers read.
    pub gravity: f64,
}

/// The sensors a controller enabled, as the runtime's controller interface declares them.
struct Listening(Arc<AtomicU8>);

const PROXIMITY: u8 = 1;
const AMBIENT: u8 = 2;
const CAMERA: u8 = 4;

impl Controller for Listening {
    fn step(&mut self, _: &mut dyn Khepera) -> Result<(), KheperaError> {
        Ok(())
    }

    fn senses(&self) -> Senses {
        let bits = self.0.load(Ordering::Relaxed);
        Senses {
            proximity: bits & PROXIMITY != 0,
            ambient: bits & AMBIENT != 0,
            vision: false,
            camera: bits & CAMERA != 0,
        }
    }
}

/// A device's sampling: its period in steps (0: disabled) and the step of its next reading.
#[derive(Clone, Copy, Debug, Default)]
struct Sampling {
    period: u64,
    due: u64,
}

/// A motor: target position (+∞: velocity control) and velocity (rad/s).
#[derive(Clone, Copy, Debug)]
struct Motor {
    target: f64,
    velocity: f64,
}

/// One controller process and its robot.
struct Driven {
    robot: usize,
    /// The process and its connection.
    link: Link,
    devices: Vec<Device>,
    sampling: Vec<Sampling>,
    /// One per device (used by the motors).
    motors: Vec<Motor>,
    leds: Vec<i32>,
    /// One per device (used by emitters and receivers).
    radios: Vec<Radio>,
    /// One per device (used by the distance sensors cast in 3-D): their noise.
    streams: Vec<regatta_runtime::sim::noise::Stream>,
    z_up: bool,
    supervisor: bool,
    custom_data: String,
    start_rotation: glam::DMat3,
    start_heading: f64,
    north: glam::DVec3,
    gravity: f64,
    /// The robot's poses at the last three steps, newest last (what accelerometers and gyros
    /// differentiate).
    trail: Vec<regatta_runtime::compile::rig::Pose2>,
    /// The step at which the controller's `wb_robot_step` returns.
    wake: u64,
    senses: Arc<AtomicU8>,
    /// Its standard output and error (kept even when neither echoed nor recorded).
    output: Option<Output>,
    /// Whether its output is echoed (else an error quotes it).
    echo: bool,
    /// Whether a command changed an LED since its state was last recorded.
    leds_changed: bool,
    /// The controller is done (it called `wb_robot_cleanup`, or exited with status 0): its
    /// robot stands still from then on.
    finished: bool,
}

/// Every controller process of a run.
pub struct Controllers<'c> {
    driven: Vec<Driven>,
    sockets: PathBuf,
    time_step_ms: f64,
    timeout: Duration,
    writer: Writer,
    commands: Vec<StepCommand>,
    /// Emitters' packets not yet arrived.
    in_flight: Vec<Packet>,
    /// The supervisor's view, when a robot is one.
    supervisor: Option<Supervisor>,
    /// Wall clock and simulated time when real-time mode began.
    real_time: Option<(Instant, f64)>,
    /// The ray caster of generic robots' distance sensors, when one has any.
    rays: Option<crate::rays::Rays<'c>>,
    /// This step's laser spots (enabled laser sensors' hits), which cameras see.
    spots: Vec<crate::laser::Spot>,
    /// Whether output and LEDs are kept, and what was kept since the last `take_records`.
    record: bool,
    records: Records,
}

/// What controllers printed and how their robots' LEDs changed, for a log.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Records {
    pub lines: Vec<ProgramLine>,
    pub leds: Vec<LedState>,
}

/// A robot's LEDs after a step in which its controller changed one.
#[derive(Clone, Debug, PartialEq)]
pub struct LedState {
    pub robot: usize,
    pub time: f64,
    /// Each LED's name and value (0 off).
    pub leds: Vec<(String, i32)>,
}

/// Webots' steps for `ms` milliseconds at a basic time step of `step_ms`: whole steps,
/// rounded up (a duration is meant to be a multiple of the basic step).
fn steps_for(ms: f64, step_ms: f64) -> u64 {
    if ms <= 0.0 {
        return 0;
    }
    libm::ceil(ms / step_ms - 1e-9).max(1.0) as u64
}

impl<'c> Controllers<'c> {
    /// Starts every controller, sends each its robot, and waits for each one's first step
    /// request (what it commands at time 0).
    pub fn start(
        simulation: &mut Simulation<'c>,
        starts: Vec<Start>,
        scene: Option<regatta_schema::Scene>,
        world: &Path,
        project: &Path,
        options: &Options,
    ) -> Result<Controllers<'c>, WebotsError> {
        let sockets = socket_folder()?;
        let time_step_ms = simulation.time_step * 1000.0;
        let mut controllers = Controllers {
            driven: Vec::new(),
            sockets,
            time_step_ms,
            timeout: options.timeout,
            writer: Writer::new(),
            commands: Vec::new(),
            in_flight: Vec::new(),
            supervisor: None,
            real_time: None,
            rays: None,
            spots: Vec::new(),
            record: options.record,
            records: Records::default(),
        };
        let compiled = simulation.compiled;
        if starts
            .iter()
            .any(|s| s.devices.iter().any(|d| matches!(d.source, Source::Ray(_))))
        {
            controllers.rays = Some(crate::rays::Rays::new(compiled));
        }
        if starts.iter().any(|s| s.supervisor) {
            if let Some(scene) = scene {
                controllers.supervisor = Some(Supervisor::new(scene, simulation));
            }
        }
        for start in starts {
            let driven = controllers.launch(simulation, start, world, project, options)?;
            controllers.driven.push(driven);
        }
        // Each controller's first request: its commands at time 0.
        for index in 0..controllers.driven.len() {
            controllers.receive(index, simulation)?;
        }
        Ok(controllers)
    }

    fn launch(
        &mut self,
        simulation: &mut Simulation,
        start: Start,
        world: &Path,
        project: &Path,
        options: &Options,
    ) -> Result<Driven, WebotsError> {
        let rig = &simulation.compiled.rig.robots[start.robot];
        let robot_name = rig.name.clone();
        let devices = start.devices;
        let path = self.sockets.join(format!("{}.sock", start.robot));
        let listener =
            UnixListener::bind(&path).map_err(|source| WebotsError::io(&path, source))?;
        listener
            .set_nonblocking(true)
            .map_err(|source| WebotsError::io(&path, source))?;
        // Kept even when neither echoed nor recorded: an error quotes its last lines.
        let file = self.sockets.join(format!("{}.out", start.robot));
        let (output, stdout, stderr) =
            Output::create(&file, start.robot, &robot_name, options.echo)?;
        let mut output = Some(output);
        let mut child = match &start.executable {
            Some(executable) => Some(
                Command::new(executable)
                    .args(&start.args)
                    .envs(start.env.iter().map(|(k, v)| (k, v)))
                    .current_dir(&start.folder)
                    .env("REGATTA_CONTROLLER_URL", &path)
                    .env("WEBOTS_ROBOT_NAME", &robot_name)
                    .stdin(Stdio::null())
                    .stdout(stdout)
                    .stderr(stderr)
                    .spawn()
                    .map_err(|source| WebotsError::Spawn {
                        robot: robot_name.clone(),
                        controller: start.controller.clone(),
                        source: Arc::new(source),
                    })?,
            ),
            None => {
                // Webots' extern controllers: the user starts the program, which finds the
                // robot through the environment.
                output = None;
                eprintln!(
                    "note: robot '{robot_name}' waits for its <extern> controller: start it with REGATTA_CONTROLLER_URL={} (or WEBOTS_CONTROLLER_URL)",
                    path.display()
                );
                None
            }
        };
        let failure = |child: &mut Child, what: String| WebotsError::Controller {
            robot: robot_name.clone(),
            controller: start.controller.clone(),
            time: 0.0,
            what: match child.try_wait() {
                Ok(Some(status)) => format!("{what}: it {}", describe_exit(status)),
                _ => what,
            },
        };
        let started = Instant::now();
        let stream = loop {
            match listener.accept() {
                Ok((stream, _)) => break stream,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    // An extern controller is waited for as Webots waits, without limit.
                    let Some(child) = child.as_mut() else {
                        std::thread::sleep(Duration::from_millis(5));
                        continue;
                    };
                    if let Ok(Some(status)) = child.try_wait() {
                        // What it printed says why (shown when echoing, else quoted).
                        let words = output
                            .as_mut()
                            .map(|o| o.last_words(0.0))
                            .unwrap_or_default();
                        return Err(WebotsError::Controller {
                            robot: robot_name.clone(),
                            controller: start.controller.clone(),
                            time: 0.0,
                            what: format!(
                                "it {} before connecting (did it call wb_robot_init, or create its Robot in Python?){words}",
                                describe_exit(status),
                            ),
                        });
                    }
                    if started.elapsed() > options.timeout {
                        let _ = child.kill();
                        return Err(failure(
                            child,
                            format!(
                                "it did not connect within {} s",
                                options.timeout.as_secs_f64()
                            ),
                        ));
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(source) => return Err(WebotsError::io(&path, source)),
            }
        };
        let _ = std::fs::remove_file(&path);
        stream
            .set_nonblocking(false)
            .map_err(|source| WebotsError::io(&path, source))?;
        // An extern controller may be paused in a debugger: it is waited for.
        stream
            .set_read_timeout(child.is_some().then_some(options.timeout))
            .map_err(|source| WebotsError::io(&path, source))?;
        let senses = Arc::new(AtomicU8::new(0));
        simulation.set_controller(start.robot, Box::new(Listening(senses.clone())));
        let rig = &simulation.compiled.rig.robots[start.robot];
        simulation.robots[start.robot].keep_raw_readings(rig);
        // Webots' motors start in position control at 0, at their largest velocity.
        let motors = devices
            .iter()
            .map(|d| Motor {
                target: 0.0,
                velocity: d.params.first().copied().unwrap_or(0.0),
            })
            .collect();
        let mut driven = Driven {
            robot: start.robot,
            link: Link {
                robot_name,
                controller: start.controller,
                child,
                stream,
                frame: Vec::new(),
            },
            sampling: vec![Sampling::default(); devices.len()],
            leds: vec![0; devices.len()],
            streams: (0..devices.len())
                .map(|d| {
                    regatta_runtime::sim::noise::Stream::new(
                        simulation.seed,
                        start.robot,
                        crate::rays::STREAM_KIND,
                        d,
                    )
                })
                .collect(),
            radios: devices
                .iter()
                .map(|d| Radio {
                    channel: d.params.get(1).copied().unwrap_or(0.0) as i32,
                    range: d.params.get(2).copied().unwrap_or(-1.0),
                    pending: Vec::new(),
                })
                .collect(),
            devices,
            motors,
            z_up: start.z_up,
            supervisor: start.supervisor,
            custom_data: start.custom_data,
            start_rotation: start.start_rotation,
            start_heading: simulation.robots[start.robot].pose.heading,
            north: start.north,
            gravity: start.gravity,
            trail: Vec::new(),
            wake: 0,
            senses,
            output,
            echo: options.echo,
            leds_changed: false,
            finished: false,
        };
        self.hello(&mut driven, simulation, world, project)?;
        Ok(driven)
    }

    fn hello(
        &mut self,
        driven: &mut Driven,
        simulation: &Simulation,
        world: &Path,
        project: &Path,
    ) -> Result<(), WebotsError> {
        let rig = &simulation.compiled.rig.robots[driven.robot];
        let w = &mut self.writer;
        w.clear();
        w.u32(protocol::MAGIC);
        w.u32(protocol::VERSION);
        w.f64(self.time_step_ms);
        w.str(&rig.name);
        w.str("");
        w.str(&driven.custom_data);
        w.str(&absolute(project).to_string_lossy());
        w.str(&absolute(world).to_string_lossy());
        w.u8(1);
        w.u8(u8::from(driven.supervisor && self.supervisor.is_some()));
        w.u16(driven.devices.len() as u16);
        for device in &driven.devices {
            w.u8(device.kind);
            w.str(&device.name);
            w.str(&device.model);
            w.u16(device.params.len() as u16);
            for &p in &device.params {
                w.f64(p);
            }
            w.u16(device.table.len() as u16);
            for row in &device.table {
                for &x in row {
                    w.f64(x);
                }
            }
        }
        let frame = w.finish().to_vec();
        driven.link.send(&frame, 0.0)
    }

    /// The step's exchange, between [`Simulation::sense`] and [`Simulation::act`]: replies to
    /// the controllers whose step is due, reads their next requests, applies their commands,
    /// and sets every driven robot's wheel speeds for the step.
    pub fn exchange(&mut self, simulation: &mut Simulation) -> Result<(), WebotsError> {
        let step = simulation.steps;
        if !self.in_flight.is_empty() {
            self.deliver(simulation);
        }
        self.find_spots(simulation);
        for driven in &mut self.driven {
            if driven.trail.len() == 3 {
                driven.trail.remove(0);
            }
            driven.trail.push(simulation.robots[driven.robot].pose);
        }
        let mut due = Vec::new();
        for index in 0..self.driven.len() {
            if !self.driven[index].finished && self.driven[index].wake <= step {
                self.reply(index, simulation, status::RUNNING)?;
                due.push(index);
            }
        }
        for index in due {
            self.receive(index, simulation)?;
            // `wb_robot_step(0)` returns at once, without time passing.
            while !self.driven[index].finished && self.driven[index].wake <= step {
                self.reply(index, simulation, status::RUNNING)?;
                self.receive(index, simulation)?;
            }
        }
        for driven in &self.driven {
            drive(driven, simulation);
        }
        self.pace(simulation.time);
        Ok(())
    }

    /// The spots of the enabled laser sensors, when some camera is enabled to see them.
    fn find_spots(&mut self, simulation: &Simulation) {
        self.spots.clear();
        let Some(rays) = &self.rays else { return };
        let enabled = |driven: &Driven, wanted: fn(&Source) -> bool| {
            driven
                .devices
                .iter()
                .zip(&driven.sampling)
                .any(|(device, sampling)| sampling.period > 0 && wanted(&device.source))
        };
        let is_laser = |source: &Source| matches!(source, Source::Ray(s) if s.medium == 3);
        let is_camera = |source: &Source| matches!(source, Source::Camera(_));
        if !self.driven.iter().any(|d| enabled(d, is_camera)) {
            return;
        }
        for driven in self.driven.iter().filter(|d| enabled(d, is_laser)) {
            let prepared = rays.prepare(simulation, driven.robot);
            for (device, sampling) in driven.devices.iter().zip(&driven.sampling) {
                if let (Source::Ray(sensor), true) = (&device.source, sampling.period > 0) {
                    if sensor.medium != 3 {
                        continue;
                    }
                    let far = device.table.last().map_or(0.0, |row| row[0]);
                    self.spots.extend(crate::laser::spot_of(
                        rays,
                        &prepared,
                        simulation,
                        driven.robot,
                        sensor,
                        far,
                    ));
                }
            }
        }
    }

    /// In real-time mode (a supervisor's `wb_supervisor_simulation_set_mode`), the run waits
    /// for the wall clock; the results are the same in every mode.
    fn pace(&mut self, time: f64) {
        let real_time = self
            .supervisor
            .as_ref()
            .is_some_and(|s| s.mode == MODE_REAL_TIME);
        match (real_time, self.real_time) {
            (true, None) => self.real_time = Some((Instant::now(), time)),
            (true, Some((since, start))) => {
                let ahead = (time - start) - since.elapsed().as_secs_f64();
                if ahead > 0.0 {
                    std::thread::sleep(Duration::from_secs_f64(ahead));
                }
            }
            (false, _) => self.real_time = None,
        }
    }

    /// The status a supervisor asked the run to end with (`wb_supervisor_simulation_quit`).
    pub fn quit_requested(&self) -> Option<i32> {
        self.supervisor.as_ref().and_then(|s| s.quit)
    }

    /// Packets sent before this step arrive at the receivers enabled now.
    fn deliver(&mut self, simulation: &Simulation) {
        let mut listeners = Vec::new();
        for driven in &mut self.driven {
            let robot = &simulation.robots[driven.robot];
            let rig = &simulation.compiled.rig.robots[driven.robot];
            let to_robot = robot.pose.frame(rig.floor_y).linear.transpose();
            for ((device, sampling), radio) in driven
                .devices
                .iter()
                .zip(&driven.sampling)
                .zip(&mut driven.radios)
            {
                if let (Source::Receiver(offset), true) = (device.source, sampling.period > 0) {
                    listeners.push(Listener {
                        medium: device.params[0] as u8,
                        at: robot.pose.to_world(offset, rig.floor_y),
                        to_robot,
                        radio,
                    });
                }
            }
        }
        crate::radio::deliver(&mut self.in_flight, simulation.steps, &mut listeners);
    }

    fn reply(
        &mut self,
        index: usize,
        simulation: &Simulation,
        state: u8,
    ) -> Result<(), WebotsError> {
        let step = simulation.steps;
        let driven = &mut self.driven[index];
        let w = &mut self.writer;
        w.clear();
        w.f64(simulation.time);
        w.u8(state);
        let robot = &simulation.robots[driven.robot];
        let rig = &simulation.compiled.rig.robots[driven.robot];
        let mut readings: Vec<(usize, Reading)> = Vec::new();
        // The robot's orientation and the world's north, for the devices that read them.
        let rotation = orientation(driven, robot.pose.heading, self.supervisor.as_ref());
        let north = self
            .supervisor
            .as_ref()
            .and_then(|s| s.north())
            .unwrap_or(driven.north);
        let mut prepared = None;
        for (d, sampling) in driven.sampling.iter_mut().enumerate() {
            if sampling.period == 0 || step < sampling.due {
                continue;
            }
            while sampling.due <= step {
                sampling.due += sampling.period;
            }
            let device = &driven.devices[d];
            let one = |v: f64| Reading::Values(vec![with_resolution(v, device.resolution)]);
            let reading = match device.source {
                Source::WheelAngle { left, sign } => {
                    let travel = if left { robot.travel.0 } else { robot.travel.1 };
                    let angle = if rig.wheel_radius > 0.0 {
                        sign * travel / rig.wheel_radius
                    } else {
                        0.0
                    };
                    one(angle)
                }
                Source::Fixed(v) => one(v),
                Source::Ray(sensor) => match &self.rays {
                    Some(rays) => {
                        let prepared =
                            prepared.get_or_insert_with(|| rays.prepare(simulation, driven.robot));
                        one(rays.measure(
                            prepared,
                            simulation,
                            driven.robot,
                            &sensor,
                            &device.table,
                            &mut driven.streams[d],
                        ))
                    }
                    None => one(f64::NAN),
                },
                Source::Distance(i) => one(robot
                    .raw
                    .as_ref()
                    .and_then(|r| r.distance.get(i).copied())
                    .unwrap_or(f64::NAN)),
                Source::Light(i) => one(robot
                    .raw
                    .as_ref()
                    .and_then(|r| r.light.get(i).copied())
                    .unwrap_or(f64::NAN)),
                Source::Camera(i) => match robot.cameras.get(i) {
                    Some(camera) => {
                        let mut image = bgra(&camera.image.rgb);
                        if let (Some(rays), false) = (&self.rays, self.spots.is_empty()) {
                            let prepared = prepared
                                .get_or_insert_with(|| rays.prepare(simulation, driven.robot));
                            crate::laser::paint(
                                &mut image,
                                &rig.cameras[i],
                                rays,
                                prepared,
                                simulation,
                                driven.robot,
                                &self.spots,
                            );
                        }
                        Reading::Bytes(image)
                    }
                    None => continue,
                },
                Source::Gps(offset) => {
                    let p = robot.pose.to_world(offset, rig.floor_y);
                    // regatta is y-up; a z-up file's (x, y, z) is regatta's (x, −z, y).
                    let p = if driven.z_up {
                        [p.x, -p.z, p.y]
                    } else {
                        [p.x, p.y, p.z]
                    };
                    Reading::Values(p.map(|v| with_resolution(v, device.resolution)).to_vec())
                }
                Source::Receiver(_) => {
                    Reading::Packets(std::mem::take(&mut driven.radios[d].pending))
                }
                Source::InertialUnit(relative) => {
                    let m = rotation * relative;
                    let angles = crate::motion::roll_pitch_yaw(m, driven.z_up);
                    Reading::Values(
                        angles
                            .map(|v| with_resolution(v, device.resolution))
                            .to_vec(),
                    )
                }
                Source::Accelerometer(relative, offset) => {
                    let force = crate::motion::specific_force(
                        &driven.trail,
                        offset,
                        rig.floor_y,
                        simulation.time_step,
                        driven.gravity,
                    );
                    let force = crate::motion::to_file_axes(force, driven.z_up);
                    let values = ((rotation * relative).transpose() * force).to_array();
                    let stream = &mut driven.streams[d];
                    Reading::Values(
                        values
                            .map(|v| {
                                let v = crate::motion::through_table(v, &device.table, stream);
                                with_resolution(v, device.resolution)
                            })
                            .to_vec(),
                    )
                }
                Source::Gyro(relative) => {
                    let up = if driven.z_up {
                        glam::DVec3::Z
                    } else {
                        glam::DVec3::Y
                    };
                    let turning = crate::motion::turn_rate(&driven.trail, simulation.time_step);
                    let values = ((rotation * relative).transpose() * (up * turning)).to_array();
                    let stream = &mut driven.streams[d];
                    Reading::Values(
                        values
                            .map(|v| {
                                let v = crate::motion::through_table(v, &device.table, stream);
                                with_resolution(v, device.resolution)
                            })
                            .to_vec(),
                    )
                }
                Source::Compass(relative) => {
                    let v = (rotation * relative).transpose() * north;
                    Reading::Values(
                        v.to_array()
                            .map(|x| with_resolution(x, device.resolution))
                            .to_vec(),
                    )
                }
                Source::Wheel { .. } | Source::Inert | Source::Led | Source::Emitter(_) => continue,
            };
            readings.push((d, reading));
        }
        // A supervisor's change of this robot's custom data travels as a reading of tag 0.
        let custom = self.supervisor.as_mut().and_then(|s| {
            std::mem::take(&mut s.custom_data_changed[driven.robot])
                .then(|| s.custom_data[driven.robot].clone())
        });
        w.u16((readings.len() + usize::from(custom.is_some())) as u16);
        if let Some(custom) = custom {
            w.u16(0);
            w.u8(protocol::reading::CUSTOM_DATA);
            w.str(&custom);
            driven.custom_data = custom;
        }
        for (d, reading) in &readings {
            w.u16(*d as u16 + 1);
            match reading {
                Reading::Values(values) => {
                    w.u8(protocol::reading::VALUES);
                    w.u16(values.len() as u16);
                    for &v in values {
                        w.f64(v);
                    }
                }
                Reading::Bytes(bytes) => {
                    w.u8(protocol::reading::BYTES);
                    w.bytes(bytes);
                }
                Reading::Packets(packets) => {
                    w.u8(protocol::reading::PACKETS);
                    w.u16(packets.len().min(u16::MAX as usize) as u16);
                    for packet in packets.iter().take(u16::MAX as usize) {
                        w.f64(packet.strength);
                        for &x in &packet.direction {
                            w.f64(x);
                        }
                        w.bytes(&packet.data);
                    }
                }
            }
        }
        let frame = w.finish().to_vec();
        let sent = driven.link.send(&frame, simulation.time);
        sent.map_err(|e| with_last_words(driven, e))
    }

    /// Reads a controller's next step request and applies it.
    fn receive(&mut self, index: usize, simulation: &mut Simulation) -> Result<(), WebotsError> {
        let step = simulation.steps;
        let time = simulation.time;
        let time_step_ms = self.time_step_ms;
        let driven = &mut self.driven[index];
        loop {
            let received = driven.link.receive(time, self.timeout);
            if !received.map_err(|e| with_last_words(driven, e))? {
                driven.finished = true;
                if let Some(output) = &mut driven.output {
                    output.finish(time, &mut self.records.lines);
                }
                return Ok(());
            }
            if driven.link.frame.first() != Some(&protocol::frame::REQUEST) {
                break;
            }
            // A supervisor's request, answered at once.
            let Some(supervisor) = self.supervisor.as_mut().filter(|_| driven.supervisor) else {
                return Err(driven
                    .link
                    .protocol_error(time, protocol::FrameError::Short(0)));
            };
            supervisor
                .answer(
                    &driven.link.frame[1..],
                    driven.robot,
                    simulation,
                    &mut self.writer,
                )
                .map_err(|e| driven.link.protocol_error(time, e))?;
            let answer = self.writer.finish().to_vec();
            driven.link.send(&answer, time)?;
        }
        // What it printed before asking for this step.
        if let Some(output) = &mut driven.output {
            output.drain(time, &mut self.records.lines);
        }
        let duration = protocol::read_step(&driven.link.frame, &mut self.commands)
            .map_err(|e| driven.link.protocol_error(time, e))?;
        if duration < 0 {
            // wb_robot_cleanup: the controller is done.
            driven.finished = true;
            return Ok(());
        }
        for command in &self.commands {
            if command.op == op::CUSTOM_DATA {
                let text =
                    String::from_utf8_lossy(&driven.link.frame[command.data.0..command.data.1])
                        .into_owned();
                if let Some(supervisor) = &mut self.supervisor {
                    supervisor.custom_data[driven.robot] = text.clone();
                }
                driven.custom_data = text;
                continue;
            }
            let d = command.tag as usize;
            let Some(device) = d.checked_sub(1).and_then(|d| driven.devices.get(d)) else {
                return Err(driven
                    .link
                    .protocol_error(time, protocol::FrameError::NoDevice(command.tag)));
            };
            match (command.op, device.source) {
                (op::ENABLE, _) => {
                    let sampling = &mut driven.sampling[d - 1];
                    if command.value > 0.0 && command.value.is_finite() {
                        sampling.period = steps_for(command.value, time_step_ms);
                        sampling.due = step + sampling.period;
                    } else {
                        sampling.period = 0;
                    }
                }
                (op::MOTOR_POSITION, Source::Wheel { .. } | Source::Inert) => {
                    driven.motors[d - 1].target = command.value;
                }
                (op::MOTOR_VELOCITY, Source::Wheel { .. } | Source::Inert) => {
                    driven.motors[d - 1].velocity = command.value;
                }
                (op::LED_SET, _) => {
                    let value = command.value as i32;
                    driven.leds_changed |= driven.leds[d - 1] != value;
                    driven.leds[d - 1] = value;
                }
                (op::EMITTER_SEND, Source::Emitter(offset)) => {
                    let robot = &simulation.robots[driven.robot];
                    let rig = &simulation.compiled.rig.robots[driven.robot];
                    let radio = &driven.radios[d - 1];
                    self.in_flight.push(Packet {
                        sent: step,
                        medium: device.params[0] as u8,
                        channel: radio.channel,
                        range: radio.range,
                        from: robot.pose.to_world(offset, rig.floor_y),
                        data: driven.link.frame[command.data.0..command.data.1].to_vec(),
                    });
                }
                (op::EMITTER_CHANNEL, Source::Emitter(_))
                | (op::RECEIVER_CHANNEL, Source::Receiver(_)) => {
                    driven.radios[d - 1].channel = command.value as i32;
                }
                (op::EMITTER_RANGE, Source::Emitter(_)) => {
                    driven.radios[d - 1].range = command.value;
                }
                (op, _) => {
                    return Err(driven.link.protocol_error(
                        time,
                        protocol::FrameError::UnknownOp {
                            op,
                            tag: command.tag,
                        },
                    ))
                }
            }
        }
        let mut bits = 0;
        for (device, sampling) in driven.devices.iter().zip(&driven.sampling) {
            if sampling.period > 0 {
                bits |= match (device.kind, device.source) {
                    (_, Source::Distance(_)) => PROXIMITY,
                    (kind::LIGHT_SENSOR, _) => AMBIENT,
                    (kind::CAMERA, _) => CAMERA,
                    _ => 0,
                };
            }
        }
        driven.senses.store(bits, Ordering::Relaxed);
        driven.wake = step + steps_for(duration as f64, time_step_ms);
        if std::mem::take(&mut driven.leds_changed) && self.record {
            let leds = driven
                .devices
                .iter()
                .zip(&driven.leds)
                .filter(|(device, _)| matches!(device.source, Source::Led))
                .map(|(device, &value)| (device.name.clone(), value))
                .collect();
            self.records.leds.push(LedState {
                robot: driven.robot,
                time,
                leds,
            });
        }
        if !self.record {
            self.records.lines.clear();
        }
        Ok(())
    }

    /// What controllers printed and their LEDs' changes since the last call, in the order
    /// they happened (robot by robot within a step).
    pub fn take_records(&mut self) -> Records {
        std::mem::take(&mut self.records)
    }

    /// Whether every controller is done (each called `wb_robot_cleanup` or exited with
    /// status 0).
    pub fn all_finished(&self) -> bool {
        self.driven.iter().all(|d| d.finished)
    }

    /// Ends every controller as Webots does: `wb_robot_step` returns −1, and a controller
    /// still running a second later is killed. Returns what they printed last.
    pub fn finish(mut self, simulation: &Simulation) -> Records {
        self.quit(Some(simulation));
        if !self.record {
            self.records.lines.clear();
        }
        std::mem::take(&mut self.records)
    }

    fn quit(&mut self, simulation: Option<&Simulation>) {
        for index in 0..self.driven.len() {
            if let (Some(simulation), false) = (simulation, self.driven[index].finished) {
                let _ = self.reply(index, simulation, status::QUIT);
            }
        }
        let deadline = Instant::now() + Duration::from_secs(1);
        for driven in &mut self.driven {
            while let Some(child) = driven.link.child.as_mut() {
                match child.try_wait() {
                    Ok(Some(_)) | Err(_) => break,
                    Ok(None) if Instant::now() < deadline => {
                        std::thread::sleep(Duration::from_millis(2))
                    }
                    Ok(None) => {
                        let _ = child.kill();
                        let _ = child.wait();
                        break;
                    }
                }
            }
            if let Some(output) = &mut driven.output {
                output.finish(simulation.map_or(0.0, |s| s.time), &mut self.records.lines);
            }
        }
        self.driven.clear();
        let _ = std::fs::remove_dir_all(&self.sockets);
    }
}

impl Drop for Controllers<'_> {
    fn drop(&mut self) {
        if !self.driven.is_empty() {
            for driven in &mut self.driven {
                if let Some(child) = driven.link.child.as_mut() {
                    let _ = child.kill();
                }
            }
            self.quit(None);
        }
    }
}

/// A failed controller's error, with what it printed last when its output is not shown (a
/// batch's Python traceback).
fn with_last_words(driven: &mut Driven, error: WebotsError) -> WebotsError {
    match error {
        WebotsError::Controller {
            robot,
            controller,
            time,
            mut what,
        } if !driven.echo
            && (what.starts_with("it exited") || what.starts_with("it was killed")) =>
        {
            if let Some(output) = &mut driven.output {
                what.push_str(&output.last_words(time));
            }
            WebotsError::Controller {
                robot,
                controller,
                time,
                what,
            }
        }
        other => other,
    }
}

/// A robot's orientation now, in the file's axes: as a supervisor last set it, or as written,
/// turned about the vertical by as much as the robot has turned since.
fn orientation(driven: &Driven, heading: f64, supervisor: Option<&Supervisor>) -> glam::DMat3 {
    let up = if driven.z_up {
        glam::DVec3::Z
    } else {
        glam::DVec3::Y
    };
    let (rotation, since) = supervisor
        .and_then(|s| s.orientation(driven.robot))
        .unwrap_or((driven.start_rotation, driven.start_heading));
    glam::DMat3::from_quat(glam::DQuat::from_axis_angle(up, heading - since)) * rotation
}

enum Reading {
    Values(Vec<f64>),
    Bytes(Vec<u8>),
    Packets(Vec<Delivered>),
}

/// RGB rows to Webots' BGRA.
fn bgra(rgb: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rgb.len() / 3 * 4);
    for pixel in rgb.chunks_exact(3) {
        out.extend_from_slice(&[pixel[2], pixel[1], pixel[0], 255]);
    }
    out
}

/// The wheel speeds a robot's motors give for this step: velocity control, or Webots'
/// default position control (P = 10, the speed bounded by the motor's velocity). A side with
/// several driven wheels (skid steer) rolls at their mean.
fn drive(driven: &Driven, simulation: &mut Simulation) {
    let rig = &simulation.compiled.rig.robots[driven.robot];
    let radius = rig.wheel_radius;
    let robot = &mut simulation.robots[driven.robot];
    if driven.finished || radius <= 0.0 {
        robot.wheel_velocity = Some((0.0, 0.0));
        return;
    }
    let mut sums = [(0.0, 0usize); 2];
    for (device, motor) in driven.devices.iter().zip(&driven.motors) {
        let Source::Wheel { left, sign } = device.source else {
            continue;
        };
        let travel = if left { robot.travel.0 } else { robot.travel.1 };
        let limit = motor.velocity.abs();
        let velocity = if motor.target.is_infinite() {
            motor.velocity
        } else {
            (10.0 * (motor.target - sign * travel / radius)).clamp(-limit, limit)
        };
        let side = &mut sums[usize::from(!left)];
        side.0 += sign * velocity;
        side.1 += 1;
    }
    let mean = |(sum, n): (f64, usize)| if n == 0 { 0.0 } else { sum / n as f64 };
    let (left, right) = (mean(sums[0]) * radius, mean(sums[1]) * radius);
    robot.wheel_velocity = Some((left, right));
    // What the log and the fitness meters read: the speeds in the Khepera's pulses per 10 ms
    // (the motion itself uses the exact speeds above).
    let pulses = |v: f64| regatta_runtime::khepera::to_command(v * rig.encoder_resolution / 100.0);
    robot.command = (pulses(left), pulses(right));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_become_whole_steps() {
        assert_eq!(steps_for(32.0, 32.0), 1);
        assert_eq!(steps_for(64.0, 32.0), 2);
        assert_eq!(steps_for(40.0, 32.0), 2);
        assert_eq!(steps_for(0.0, 32.0), 0);
        assert_eq!(steps_for(8.0, 8.0), 1);
        assert_eq!(steps_for(1.0, 32.0), 1);
    }

    #[test]
    fn images_are_bgra() {
        assert_eq!(bgra(&[1, 2, 3, 4, 5, 6]), vec![3, 2, 1, 255, 6, 5, 4, 255]);
    }
}
