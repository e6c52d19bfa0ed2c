//! What the commands that simulate a world do with Webots' conventions: the robots a world
//! has but regatta could not build (refused), the controllers it names (Webots' names mapped
//! to built-ins, the rest refused, lenient mode falling back to the robot's default), and the
//! `--controller` override.

use anyhow::bail;
use regatta_runtime::webots_controllers::{resolve, Resolution, LENIENT_DEFAULT};
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
    let unbuilt = &loaded.checked.unbuilt_robots;
    if unbuilt.is_empty() {
        return Ok(());
    }
    let lines: Vec<String> = unbuilt
        .iter()
        .map(|robot| {
            let source = &loaded.checked.sources[robot.file.0 as usize];
            let (line, column) = line_column(&source.text, robot.span.start as usize);
            let from = match &robot.url {
                Some(url) => format!(" (its PROTO: {url})"),
                None => String::new(),
            };
            format!(
                "  {}:{line}:{column}: '{}'{from}",
                source.name, robot.type_name
            )
        })
        .collect();
    bail!(
        "the world has {} robot(s) regatta could not build, so it is not simulated:\n{}\nregatta has stand-ins for Khepera1, Khepera2 and E-puck (and its own Khepera); --proto-path DIR can point at a folder with the others' PROTOs",
        unbuilt.len(),
        lines.join("\n")
    )
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
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
            if !matches!(resolve(&robot.controller), Resolution::Builtin(..)) {
                robot.controller = "none".to_owned();
            }
            continue;
        }
        let name = robot.controller.clone();
        match resolve(&name) {
            Resolution::Builtin(builtin, why) => {
                if builtin != name {
                    eprintln!(
                        "note: robot '{}': Webots controller \"{name}\" ({why}) runs as regatta's \"{builtin}\"",
                        robot.name
                    );
                    robot.controller = builtin.to_owned();
                }
            }
            Resolution::External(how) => {
                let message = format!(
                    "robot '{}' has controller \"{name}\": {how}; `regatta serve WORLD --robot {}` drives it over the Khepera serial protocol, or --controller chooses a built-in one",
                    robot.name, robot.name
                );
                if !lenient {
                    bail!("{message}");
                }
                eprintln!("warning: {message}; lenient mode runs \"{LENIENT_DEFAULT}\" instead");
                robot.controller = LENIENT_DEFAULT.to_owned();
                robot.controller_args.clear();
            }
            Resolution::Unknown => {
                let message = format!(
                    "robot '{}' has controller \"{name}\", which regatta does not have (built in: none, braitenberg, regatta, neural, and the Webots names in the README)",
                    robot.name
                );
                if !lenient {
                    bail!("{message}; --controller chooses one");
                }
                eprintln!("warning: {message}; lenient mode runs \"{LENIENT_DEFAULT}\" instead (--controller chooses another)");
                robot.controller = LENIENT_DEFAULT.to_owned();
                robot.controller_args.clear();
            }
        }
    }
    Ok(())
}
