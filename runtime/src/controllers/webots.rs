//! Webots controller names, as worlds written for Webots give them, and what regatta runs for
//! each: the ones whose documented behaviour a built-in controller has map to it; robots
//! driven from outside Webots (`<extern>`, and the Khepera serial-protocol bridges `pipe` and
//! `tcpip`) are driven by `regatta serve`; the rest are refused with their name.

/// What regatta does with a controller name a world gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolution {
    /// A built-in controller, and why it stands for the name (empty when it is the same).
    Builtin(&'static str, &'static str),
    /// The robot is driven from outside the simulator (`regatta serve`, or the Python module).
    External(&'static str),
    /// No built-in controller does what this one does.
    Unknown,
}

/// The controller a DifferentialWheels robot runs when lenient mode replaces one regatta
/// does not have: the Khepera's and e-puck's default in Webots is obstacle avoidance.
pub const LENIENT_DEFAULT: &str = "braitenberg";

/// (Webots name, regatta controller, documented behaviour): the table in the README.
pub const MAPPED: &[(&str, &str, &str)] = &[
    (
        "braitenberg",
        "braitenberg",
        "Braitenberg obstacle avoidance (Webots' default for the Khepera I and II)",
    ),
    (
        "e-puck_avoid_obstacles",
        "braitenberg",
        "the e-puck's default: obstacle avoidance with its proximity sensors",
    ),
    (
        "e-puck_avoid_collisions",
        "braitenberg",
        "obstacle avoidance with the proximity sensors",
    ),
    (
        "obstacle_avoidance",
        "braitenberg",
        "obstacle avoidance with the proximity sensors",
    ),
    (
        "avoid_obstacles",
        "braitenberg",
        "obstacle avoidance with the proximity sensors",
    ),
    (
        "void",
        "none",
        "Webots' empty controller: the robot stands still",
    ),
    ("<none>", "none", "no controller: the robot stands still"),
    (
        "<generic>",
        "none",
        "Webots' default for a Robot (a generic robot window): the robot stands still",
    ),
];

/// (Webots name, how the robot is driven from outside).
pub const EXTERNAL: &[(&str, &str)] = &[
    ("<extern>", "an extern controller connects to the simulator"),
    (
        "pipe",
        "a program sends Khepera serial-protocol commands through a pipe",
    ),
    (
        "tcpip",
        "a program sends Khepera serial-protocol commands over TCP/IP",
    ),
];

/// Resolves a controller name: regatta's own names first, then Webots' names.
pub fn resolve(name: &str) -> Resolution {
    if name.is_empty() {
        return Resolution::Builtin("none", "");
    }
    // regatta's own names (and their aliases): the registry's.
    if let Some(own) = super::find(name) {
        return Resolution::Builtin(own.name, "");
    }
    if let Some((_, builtin, why)) = MAPPED.iter().find(|(n, _, _)| *n == name) {
        return Resolution::Builtin(builtin, why);
    }
    if let Some((_, how)) = EXTERNAL.iter().find(|(n, _)| *n == name) {
        return Resolution::External(how);
    }
    Resolution::Unknown
}

/// What resolving a robot's controller did, to tell the user.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Resolved {
    /// The name is regatta's own.
    Same,
    /// A Webots name runs as a built-in (a note).
    Mapped(String),
    /// Lenient mode replaced a controller regatta does not have (a warning).
    Replaced(String),
}

/// Resolves a robot's controller name to a built-in one, in place: what `run`, `serve`,
/// `batch` and `evolve` all do. `Err` is strict mode's refusal, with the reason.
pub fn resolve_robot(
    robot: &mut crate::compile::rig::RobotRig,
    lenient: bool,
) -> Result<Resolved, String> {
    let name = robot.controller.clone();
    match resolve(&name) {
        Resolution::Builtin(builtin, why) => {
            if builtin == name {
                return Ok(Resolved::Same);
            }
            robot.controller = builtin.to_owned();
            Ok(Resolved::Mapped(format!(
                "robot '{}': Webots controller \"{name}\" ({why}) runs as regatta's \"{builtin}\"",
                robot.name
            )))
        }
        Resolution::External(how) => {
            let message = format!(
                "robot '{}' has controller \"{name}\": {how}; {}`regatta serve WORLD --robot {}` drives it over the Khepera serial protocol, Python's `regatta.World(WORLD, control=[\"{}\"])` by actions, or --controller chooses a built-in one",
                robot.name,
                if name == "<extern>" {
                    "`regatta run --extern` waits for a Webots controller started by hand, "
                } else {
                    ""
                },
                robot.name,
                robot.name
            );
            if !lenient {
                return Err(message);
            }
            robot.controller = LENIENT_DEFAULT.to_owned();
            robot.controller_args.clear();
            Ok(Resolved::Replaced(format!(
                "{message}; lenient mode runs \"{LENIENT_DEFAULT}\" instead"
            )))
        }
        Resolution::Unknown => {
            let message = format!(
                "robot '{}' has controller \"{name}\", which regatta does not have (built in: none, braitenberg, regatta, neural, and the Webots names in the README)",
                robot.name
            );
            if !lenient {
                return Err(format!("{message}; --controller chooses one"));
            }
            robot.controller = LENIENT_DEFAULT.to_owned();
            robot.controller_args.clear();
            Ok(Resolved::Replaced(format!(
                "{message}; lenient mode runs \"{LENIENT_DEFAULT}\" instead (--controller chooses another)"
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn webots_names() {
        assert_eq!(resolve("regatta"), Resolution::Builtin("regatta", ""));
        assert!(matches!(
            resolve("e-puck_avoid_obstacles"),
            Resolution::Builtin("braitenberg", _)
        ));
        assert!(matches!(resolve("<extern>"), Resolution::External(_)));
        assert!(matches!(resolve("pipe"), Resolution::External(_)));
        assert_eq!(resolve("khepera_gripper"), Resolution::Unknown);
        // Every mapped name resolves to a controller regatta builds.
        for (_, builtin, _) in MAPPED {
            assert!(crate::controllers::build(builtin, &[], 0.032).is_ok());
        }
    }
}
