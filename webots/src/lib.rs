//! Webots controllers against regatta: a world's robots run the controllers of its project,
//! unchanged, as Webots runs them.
//!
//! This room stands on the runtime's public API only. It owns:
//! - the C API's headers (`include/webots/`) and the controller library (`c/`), written from
//!   Webots' published reference, embedded in the binary ([`compile::HEADERS`],
//!   [`compile::LIBRARY`]);
//! - the controller protocol ([`protocol`]): the frames a controller process and regatta
//!   exchange over a Unix socket;
//! - finding a controller in its project and compiling it into a cache ([`compile`]);
//! - a robot's devices as Webots names them ([`devices`]), and what its inertial devices
//!   read from its motion ([`motion`]);
//! - emitters and receivers: packets between robots ([`radio`]);
//! - a generic robot's distance sensors, cast in 3-D ([`rays`]), and the red spots its
//!   lasers draw on camera images ([`laser`]);
//! - a supervisor's view of the world ([`supervisor`]);
//! - the processes in lock-step with a simulation ([`session`]), and what they print
//!   ([`output`]).
//!
//! Running a world's controllers runs its project's code: [`plan`] finds which robots would,
//! and the command line says so before it starts them.

pub mod compile;
pub mod devices;
mod error;
pub mod laser;
mod link;
pub mod motion;
pub mod output;
pub mod protocol;
pub mod python;
pub mod radio;
pub mod rays;
pub mod session;
pub mod supervisor;

use std::path::{Path, PathBuf};

use regatta_runtime::compile::Compiled;

pub use compile::{is_program, project_of, Program};
pub use error::WebotsError;

/// `is_program` for the world at `world` (`-`, standard input, has no project).
pub fn programs_of(world: &Path) -> impl Fn(&str) -> bool {
    let project = (world != Path::new("-")).then(|| project_of(world));
    move |name: &str| project.as_deref().is_some_and(|p| is_program(p, name))
}
pub use output::ProgramLine;
pub use session::{Controllers, LedState, Options, Records, Start};

/// A robot whose controller is its project's own program.
#[derive(Clone, Debug)]
pub struct Planned {
    pub robot: usize,
    pub program: Program,
    /// The robot's `controllerArgs`, passed to the program as its arguments.
    pub args: Vec<String>,
    /// Its devices, in tag order (read from the scene, which a run then releases).
    pub devices: Vec<devices::Device>,
    /// Whether the world's file is z-up (a GPS answers in the file's axes).
    pub z_up: bool,
    /// Whether the robot is a supervisor (its `supervisor` field).
    pub supervisor: bool,
    /// Its `customData`.
    pub custom_data: String,
    /// Its rotation as written, in the file's axes (what orientation devices start from).
    pub start_rotation: glam::DMat3,
    /// The world's north in the file's axes (from `WorldInfo.coordinateSystem`).
    pub north: glam::DVec3,
    /// `WorldInfo.gravity` (m/s²), which accelerometers read.
    pub gravity: f64,
}

impl Planned {
    /// What [`Controllers::start`] needs to run it, from its compiled `executable` (none for
    /// an `<extern>` controller).
    pub fn start(&self, executable: Option<PathBuf>) -> Start {
        Start {
            robot: self.robot,
            controller: match &self.program {
                Program::Extern { .. } => "<extern>".to_owned(),
                program => program
                    .folder()
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            },
            executable,
            folder: self.program.folder().to_path_buf(),
            args: self.args.clone(),
            env: Vec::new(),
            devices: self.devices.clone(),
            z_up: self.z_up,
            supervisor: self.supervisor,
            custom_data: self.custom_data.clone(),
            start_rotation: self.start_rotation,
            north: self.north,
            gravity: self.gravity,
        }
    }
}

impl Planned {
    /// What [`Controllers::start`] needs to run it as `launch` says ([`runnable`]).
    pub fn start_with(&self, launch: &python::Launch) -> Start {
        let mut start = self.start(Some(launch.executable.clone()));
        let mut args = launch.args.clone();
        args.append(&mut start.args);
        start.args = args;
        start.env = launch.env.clone();
        start
    }
}

/// Makes a project's controller runnable: a C controller compiled (or found compiled), a
/// Python one given its interpreter and the `controller` package (built once). Returns how
/// to start it and whether something was built now.
pub fn runnable(program: &Program, cache: &Path) -> Result<(python::Launch, bool), WebotsError> {
    match program {
        Program::C { .. } => {
            let (executable, built) = compile::compile(program, cache)?;
            Ok((
                python::Launch {
                    executable,
                    ..python::Launch::default()
                },
                built,
            ))
        }
        Program::Python { .. } => python::launch(program, cache),
        // The user starts it: nothing to make (`Planned::start(None)`).
        Program::Extern { .. } => Err(WebotsError::Unsupported {
            controller: program.name().to_owned(),
            language: program.language(),
        }),
    }
}

/// The robots of `compiled` whose controller name is a program of `project`
/// (`controllers/NAME/`), in robot order. Names regatta has built in are left to the
/// built-ins; robots in `skip` (driven otherwise) are left alone.
pub fn plan(
    compiled: &Compiled,
    scene: &regatta_schema::Scene,
    project: &Path,
    skip: &[usize],
) -> Result<Vec<Planned>, WebotsError> {
    let north = devices::north_of(scene);
    let mut planned = Vec::new();
    for (robot, rig) in compiled.rig.robots.iter().enumerate() {
        if skip.contains(&robot) {
            continue;
        }
        let program = if rig.controller == "<extern>" {
            Some(Program::Extern {
                folder: project.to_path_buf(),
            })
        } else {
            compile::find(project, &rig.controller)?
        };
        if let Some(program) = program {
            planned.push(Planned {
                robot,
                program,
                args: rig.controller_args.clone(),
                devices: devices::devices(scene, rig),
                z_up: scene.up_axis == regatta_schema::UpAxis::Z,
                supervisor: scene.spec(rig.node).field_index("supervisor").is_some()
                    && scene.bool(rig.node, "supervisor"),
                custom_data: if scene.spec(rig.node).field_index("customData").is_some() {
                    scene.string(rig.node, "customData").to_owned()
                } else {
                    String::new()
                },
                start_rotation: regatta_runtime::geometry::Frame::vrml(
                    glam::DVec3::ZERO,
                    scene.rotation(rig.node, "rotation"),
                    glam::DVec3::ONE,
                    [0.0, 0.0, 1.0, 0.0],
                    glam::DVec3::ZERO,
                )
                .linear,
                north,
                gravity: devices::gravity_of(scene),
            });
        }
    }
    Ok(planned)
}

/// Readies the compiled world for the planned robots: their built-in controller is `none`,
/// and their distance and light sensors and cameras refresh every step, so that each
/// controller's own sampling periods decide what it reads.
pub fn prepare(compiled: &mut Compiled, planned: &[Planned]) {
    for item in planned {
        let rig = &mut compiled.rig.robots[item.robot];
        rig.program = Some(format!(
            "{} ({})",
            if let Program::Extern { .. } = item.program {
                "<extern>".to_owned()
            } else {
                rig.controller.clone()
            },
            item.program.language()
        ));
        rig.controller = "none".to_owned();
        rig.controller_args.clear();
        for sensor in std::sync::Arc::make_mut(&mut rig.distance_sensors).iter_mut() {
            sensor.period = 0.0;
        }
        for sensor in std::sync::Arc::make_mut(&mut rig.light_sensors).iter_mut() {
            sensor.period = 0.0;
        }
        for camera in &mut rig.cameras {
            camera.period = 0.0;
        }
    }
}
