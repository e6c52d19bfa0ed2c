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
            compiled.rig.robots[index].controller = controller.to_owned();
            overridden[index] = true;
        }
    }
    if !overrides.args.is_empty() {
        let any = overridden.iter().any(|&o| o);
        for (index, robot) in compiled.rig.robots.iter_mut().enumerate() {
            if overridden[index] || !any {
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
