//! What the commands that simulate a world do with Webots' conventions: the robots a world
//! has but regatta could not build (refused), the controllers it names (Webots' names mapped
//! to built-ins, the rest refused, lenient mode falling back to the robot's default), and the
//! `--controller` override.

use anyhow::bail;
use regatta_runtime::controllers::webots::{resolve, resolve_robot, Resolution, Resolved};
use regatta_runtime::Compiled;

use crate::world::Loaded;

/// `--controller` and `--controller-args`, shared by `run` and `serve`.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ControllerOverride {
    /// Controller for every robot (NAME) or for one (ROBOT=NAME), instead of the world's;
    /// repeatable. Webots names with a documented behaviour map to built-ins (README).
    #[arg(long = "controller", value_name = "[ROBOT=]NAME")]
    pub controllers: Vec<String>,
    /// controllerArgs ("key=value …") for the robots --controller sets (every robot when
    /// --controller is not given); repeatable.
    #[arg(long = "controller-args", value_name = "ARGS")]
    pub args: Vec<String>,
    /// Run no program of the world's project: a robot whose controller is the project's own
    /// (controllers/NAME/) is refused, or with --lenient runs a built-in one. For worlds from
    /// people you do not trust: running a project's controllers runs its code.
    #[arg(long)]
    pub builtin_only: bool,
    /// Wait for the controllers of `<extern>` robots, started by hand with the
    /// REGATTA_CONTROLLER_URL the run prints (as Webots' extern controllers); without it such
    /// a robot is refused, or with --lenient runs a built-in controller.
    #[arg(long = "extern")]
    pub extern_controllers: bool,
    /// How long a project's controller may take to start or to ask for its next step before
    /// the run ends with an error (wall-clock seconds).
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0)]
    pub controller_timeout: f64,
}

/// The robots whose controller is a program of the world's project (Webots' `controllers/NAME/`
/// beside `worlds/`), readied to be run by it: their built-in controller becomes `none`. Says
/// that the project's code will run. Robots that `--controller` sets are left to it; with
/// `--builtin-only`, or a world read from standard input, there are none.
pub fn plan_programs(
    loaded: &mut Loaded,
    world: &std::path::Path,
    overrides: &ControllerOverride,
    _lenient: bool,
) -> anyhow::Result<Programs> {
    if overrides.builtin_only || world == std::path::Path::new("-") {
        return Ok(Programs::default());
    }
    if !(overrides.controller_timeout > 0.0 && overrides.controller_timeout.is_finite()) {
        bail!(
            "--controller-timeout must be a positive number of seconds, not {}",
            overrides.controller_timeout
        );
    }
    let names: Vec<String> = loaded
        .compiled
        .rig
        .robots
        .iter()
        .map(|r| r.name.clone())
        .collect();
    let mut overridden = Vec::new();
    for spec in &overrides.controllers {
        let (targets, controller): (Vec<usize>, &str) = match spec.split_once('=') {
            Some((robot, controller)) => (
                names.iter().position(|n| n == robot).into_iter().collect(),
                controller,
            ),
            None => ((0..names.len()).collect(), spec.as_str()),
        };
        // `--controller ROBOT=<extern>`: the robot waits for a program started by hand (a
        // Gymnasium environment's agent), as if its world said so.
        if controller == "<extern>" {
            if !overrides.extern_controllers {
                bail!("--controller {spec}: an <extern> controller needs --extern (the run then waits for it)");
            }
            for &robot in &targets {
                loaded.compiled.rig.robots[robot].controller = "<extern>".to_owned();
            }
            continue;
        }
        overridden.extend(targets);
    }
    let project = regatta_webots::project_of(world);
    let mut planned = regatta_webots::plan(
        &loaded.compiled,
        &loaded.checked.scene,
        &project,
        &overridden,
    )?;
    // Without --controller, --controller-args are the programs' arguments (one each), as a
    // world's controllerArgs are.
    if overrides.controllers.is_empty() && !overrides.args.is_empty() {
        for item in &mut planned {
            item.args = overrides.args.clone();
        }
    }
    // An <extern> robot is left to the controller resolution (refused, or a built-in)
    // unless asked for.
    planned.retain(|item| match &item.program {
        regatta_webots::Program::Extern { .. } => overrides.extern_controllers,
        _ => true,
    });
    regatta_webots::prepare(&mut loaded.compiled, &planned);
    // A supervisor reads the typed scene, which the run would otherwise release.
    let scene = planned
        .iter()
        .any(|p| p.supervisor)
        .then(|| loaded.checked.scene.clone());
    for item in planned
        .iter()
        .filter(|p| !matches!(p.program, regatta_webots::Program::Extern { .. }))
    {
        eprintln!(
            "note: robot '{}' runs its project's controller {} ({}): this runs the project's code (--builtin-only runs none)",
            names[item.robot],
            item.program.folder().display(),
            item.program.language(),
        );
    }
    Ok(Programs { planned, scene })
}

/// The robots that run their project's programs, and the scene a supervisor among them reads.
#[derive(Clone, Default)]
pub struct Programs {
    planned: Vec<regatta_webots::Planned>,
    scene: Option<regatta_schema::Scene>,
}

/// Compiles (or finds compiled) and starts the planned controllers, each connected to its
/// robot; `None` when there are none.
pub fn start_programs<'c>(
    simulation: &mut regatta_runtime::sim::Simulation<'c>,
    programs: Programs,
    world: &std::path::Path,
    overrides: &ControllerOverride,
    record: bool,
) -> anyhow::Result<Option<regatta_webots::Controllers<'c>>> {
    let Programs { planned, scene } = programs;
    if planned.is_empty() {
        return Ok(None);
    }
    let cache = regatta_webots::compile::cache_dir();
    let mut starts = Vec::new();
    for item in planned {
        let robot = simulation.compiled.rig.robots[item.robot].name.clone();
        if let regatta_webots::Program::Extern { .. } = item.program {
            starts.push(item.start(None));
            continue;
        }
        let started = std::time::Instant::now();
        let (launch, built) = regatta_webots::runnable(&item.program, &cache)
            .map_err(|e| anyhow::anyhow!("robot '{robot}': {e}"))?;
        let start = item.start_with(&launch);
        if built {
            eprintln!(
                "note: {} \"{}\" in {:.2} s",
                match item.program {
                    regatta_webots::Program::Python { .. } =>
                        "built the Python controller library for",
                    _ => "compiled controller",
                },
                start.controller,
                started.elapsed().as_secs_f64()
            );
        }
        starts.push(start);
    }
    let options = regatta_webots::Options {
        timeout: std::time::Duration::from_secs_f64(overrides.controller_timeout),
        echo: true,
        record,
    };
    let project = regatta_webots::project_of(world);
    let controllers =
        regatta_webots::Controllers::start(simulation, starts, scene, world, &project, &options)?;
    Ok(Some(controllers))
}

/// Fails when the world has robots regatta could not build (their PROTO has no stand-in and
/// was not found), naming each.
pub fn refuse_unbuilt_robots(loaded: &Loaded) -> anyhow::Result<()> {
    match loaded.checked.unbuilt_refusal() {
        Some(refusal) => bail!("{refusal}"),
        None => Ok(()),
    }
}

/// Readies a loaded world for a run that drives every robot itself (`run`, `view`): refuses
/// unbuilt robots, resolves every controller, and frees the typed scene, which a run never
/// reads again.
pub fn prepare_run(
    loaded: &mut Loaded,
    overrides: &ControllerOverride,
    lenient: bool,
) -> anyhow::Result<()> {
    refuse_unbuilt_robots(loaded)?;
    resolve_controllers(&mut loaded.compiled, overrides, lenient, None)?;
    loaded.release_scene();
    Ok(())
}

/// Applies `--controller` overrides and resolves every robot's controller name to a built-in
/// one (robot `served`, driven over the protocol, needs none). Prints a note for each name
/// it maps; an unknown or external controller is an error, or in lenient mode a warning and
/// the robot's default controller.
pub fn resolve_controllers(
    compiled: &mut Compiled,
    overrides: &ControllerOverride,
    lenient: bool,
    served: Option<usize>,
) -> anyhow::Result<()> {
    let names: Vec<String> = compiled.rig.robots.iter().map(|r| r.name.clone()).collect();
    let mut overridden = vec![false; names.len()];
    for spec in &overrides.controllers {
        let (robot, controller) = match spec.split_once('=') {
            Some((robot, controller)) => (Some(robot), controller),
            None => (None, spec.as_str()),
        };
        if matches!(resolve(controller), Resolution::Unknown) {
            bail!(
                "--controller {spec}: no controller \"{controller}\"; built in: none, braitenberg, regatta, neural, and the Webots names in the README"
            );
        }
        let targets: Vec<usize> = match robot {
            Some(robot) => match names.iter().position(|n| n == robot) {
                Some(index) => vec![index],
                None => bail!(
                    "--controller {spec}: the world has no robot named '{robot}' (it has: {})",
                    names.join(", ")
                ),
            },
            None => (0..names.len()).collect(),
        };
        for index in targets {
            // An <extern> robot planned to wait for its program is its program's.
            if controller == "<extern>" && compiled.rig.robots[index].program.is_some() {
                continue;
            }
            compiled.rig.robots[index].controller = controller.to_owned();
            overridden[index] = true;
        }
    }
    if !overrides.args.is_empty() {
        let any = overridden.iter().any(|&o| o);
        for (index, robot) in compiled.rig.robots.iter_mut().enumerate() {
            // A robot driven by its project's program got them as its arguments.
            if (overridden[index] || !any) && robot.program.is_none() {
                robot.controller_args = overrides.args.clone();
            }
        }
    }
    for (index, robot) in compiled.rig.robots.iter_mut().enumerate() {
        if Some(index) == served {
            // Driven over the protocol: its own controller never runs, but must be buildable.
            robot.controller = match resolve(&robot.controller) {
                Resolution::Builtin(builtin, _) => builtin,
                _ => "none",
            }
            .to_owned();
            continue;
        }
        match resolve_robot(robot, lenient) {
            Ok(Resolved::Same) => {}
            Ok(Resolved::Mapped(note)) => eprintln!("note: {note}"),
            Ok(Resolved::Replaced(warning)) => eprintln!("warning: {warning}"),
            Err(refusal) => bail!("{refusal}"),
        }
    }
    Ok(())
}
