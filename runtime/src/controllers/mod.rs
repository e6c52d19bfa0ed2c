//! The built-in controllers, chosen by a world's `controller` field and tuned by
//! `controllerArgs` (`"key=value"` strings).
//!
//! [`CONTROLLERS`] is the registry: each entry names a controller, documents it, lists its
//! parameters with their kinds and defaults ([`parameters`]), and builds it. `regatta check`
//! validates a world's controllers against it (`check_scene`, in `check.rs`: unknown names and
//! keys, ill-typed values, with "did you mean"), and a run builds them from it ([`build`],
//! [`build_for`]), so both agree by construction. Adding a controller is one entry here and
//! its own file. Webots' controller names map to these in `webots.rs`.
//!
//! - `none` ([`idle`]): does nothing.
//! - `braitenberg` ([`braitenberg`]): Mondada's obstacle avoider, the feed-forward network of
//!   the Khepera BIOS.
//! - `regatta` ([`regatta`]): the paper's controller: the Braitenberg network plus light
//!   seeking, with its stall escape and its habituation to a light kept abeam.
//! - `neural` ([`neural`]): the robot's `NeuralNetwork` node
//!   ([`crate::compile::network`]); it takes no `controllerArgs`: its parameters are the
//!   network's fields.

pub mod braitenberg;
pub mod check;
pub mod escape;
pub mod idle;
pub mod neural;
pub mod parameters;
pub mod regatta;
pub mod webots;

use regatta_schema::catalogue::did_you_mean as did_you_mean_in;

use crate::compile::network::NetworkError;
use crate::compile::rig::RobotRig;
use crate::khepera::Controller;
use braitenberg::Braitenberg;
use idle::Idle;
use neural::Neural;
use parameters::{
    Arguments, ParameterKind, ParameterSpec, Parameters, BRAITENBERG_PARAMETERS, REGATTA_PARAMETERS,
};
use regatta::Regatta;

/// Why a controller could not be built from a world's fields.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControllerError {
    #[error("unknown controller \"{name}\"; built in: {}{}", known_names(), did_you_mean_note(*.hint))]
    Unknown {
        name: String,
        /// The built-in name closest to it, if one is close.
        hint: Option<&'static str>,
    },
    #[error(transparent)]
    Network(#[from] NetworkError),
    #[error("controller argument \"{0}\" is not key=value")]
    Malformed(String),
    #[error("controller {controller} has no parameter \"{key}\"; it takes {}{}", parameter_names(controller), did_you_mean_note(*.hint))]
    UnknownKey {
        controller: &'static str,
        key: String,
        /// The parameter closest to it, if one is close.
        hint: Option<&'static str>,
    },
    #[error("controller argument {key}={value} is not {expected}")]
    NotANumber {
        key: String,
        value: String,
        /// "a finite number", "a whole number"…
        expected: &'static str,
    },
}

/// A built-in controller: what a world names and what it may pass.
pub struct ControllerSpec {
    pub name: &'static str,
    /// Other names that mean the same controller.
    pub aliases: &'static [&'static str],
    pub doc: &'static str,
    pub parameters: &'static [ParameterSpec],
    /// Builds the controller from arguments already checked against `parameters`, and the
    /// robot it drives when there is one (a controller may need more of the world than its
    /// arguments: `neural` takes its network from there).
    pub build: Builder,
}

/// How a registry entry makes its controller: from checked arguments, for a run the robot it
/// drives, and the control period (s) at which it will be called: every time a controller
/// keeps (timers, integration) is in seconds and turned into calls with it.
pub type Builder =
    fn(&Arguments, Option<&RobotRig>, f64) -> Result<Box<dyn Controller>, ControllerError>;

/// Every built-in controller.
pub static CONTROLLERS: &[ControllerSpec] = &[
    ControllerSpec {
        name: "none",
        aliases: &["", "<none>"],
        doc: "Does nothing: the robot stands still (its sensors still read).",
        parameters: &[],
        build: |_, _, _| Ok(Box::new(Idle)),
    },
    ControllerSpec {
        name: "braitenberg",
        aliases: &[],
        doc: "Mondada's obstacle avoider: the Khepera BIOS's feed-forward IR network, with a stall escape from corners.",
        parameters: BRAITENBERG_PARAMETERS,
        build: |args, robot, period| {
            Ok(Box::new(Braitenberg::new(
                Parameters::from_arguments(args),
                braitenberg::Weights::for_robot(robot),
                period,
            )))
        },
    },
    ControllerSpec {
        name: "regatta",
        aliases: &[],
        doc: "The paper's controller: the Braitenberg network plus light seeking with the Panoramic turret's odd filter.",
        parameters: REGATTA_PARAMETERS,
        build: |args, _, period| {
            Ok(Box::new(Regatta::new(
                Parameters::from_arguments(args),
                period,
            )))
        },
    },
    ControllerSpec {
        name: "neural",
        aliases: &[],
        doc: "The robot's NeuralNetwork node (feed-forward, Elman or CTRNN); its parameters are the network's fields.",
        parameters: &[],
        build: |_, rig, _| match rig.and_then(|rig| rig.network.as_ref()) {
            Some(Ok(spec)) => Ok(Box::new(Neural::from_spec(spec)?)),
            Some(Err(error)) => Err(error.clone().into()),
            None => Err(NetworkError::NoNetwork.into()),
        },
    },
];

/// The registry entry called `name` (or one of its aliases).
pub fn find(name: &str) -> Option<&'static ControllerSpec> {
    CONTROLLERS
        .iter()
        .find(|c| c.name == name || c.aliases.contains(&name))
}

/// The names a world may give, for messages.
pub(super) fn known_names() -> String {
    CONTROLLERS
        .iter()
        .map(|c| c.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The parameters of the controller called `name`, for messages.
fn parameter_names(name: &str) -> String {
    match find(name) {
        Some(spec) if !spec.parameters.is_empty() => spec
            .parameters
            .iter()
            .map(|p| p.key)
            .collect::<Vec<_>>()
            .join(", "),
        _ => "no parameters".to_owned(),
    }
}

/// "; did you mean …?", or nothing.
fn did_you_mean_note(close: Option<&str>) -> String {
    close
        .map(|close| format!("; did you mean \"{close}\"?"))
        .unwrap_or_default()
}

/// The controller called `name`, or why not.
pub fn spec_of(name: &str) -> Result<&'static ControllerSpec, ControllerError> {
    find(name).ok_or_else(|| ControllerError::Unknown {
        name: name.to_owned(),
        hint: did_you_mean_in(name, CONTROLLERS.iter().map(|c| c.name)),
    })
}

/// The `key=value` items of `controllerArgs` strings (each string may hold several,
/// separated by spaces, commas or semicolons).
pub(super) fn items(args: &[String]) -> impl Iterator<Item = &str> {
    args.iter()
        .flat_map(|a| a.split([' ', ',', ';']))
        .filter(|a| !a.is_empty())
}

/// Checks one `key=value` item against a controller's parameters.
pub(super) fn argument(
    spec: &ControllerSpec,
    item: &str,
) -> Result<(&'static str, f64), ControllerError> {
    let (key, value) = item
        .split_once('=')
        .ok_or_else(|| ControllerError::Malformed(item.to_owned()))?;
    let key = key.trim();
    let Some(parameter) = spec.parameters.iter().find(|p| p.key == key) else {
        return Err(ControllerError::UnknownKey {
            controller: spec.name,
            key: key.to_owned(),
            hint: did_you_mean_in(key, spec.parameters.iter().map(|p| p.key)),
        });
    };
    let number = value
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .filter(|v| parameter.kind != ParameterKind::Integer || v.fract() == 0.0)
        .filter(|v| parameter.kind != ParameterKind::Seconds || *v >= 0.0)
        .ok_or_else(|| ControllerError::NotANumber {
            key: key.to_owned(),
            value: value.to_owned(),
            expected: parameter.kind.noun(),
        })?;
    Ok((parameter.key, number))
}

/// Checks `controllerArgs` against the controller called `name`.
pub fn arguments(name: &str, args: &[String]) -> Result<Arguments, ControllerError> {
    let spec = spec_of(name)?;
    let mut values = Vec::new();
    for item in items(args) {
        values.push(argument(spec, item)?);
    }
    Ok(Arguments { values })
}

/// Builds a built-in controller from its name and arguments, to be called every `period`
/// seconds (`neural` needs its robot: see [`build_for`]).
pub fn build(
    name: &str,
    args: &[String],
    period: f64,
) -> Result<Box<dyn Controller>, ControllerError> {
    let spec = spec_of(name)?;
    (spec.build)(&arguments(name, args)?, None, period)
}

/// Builds a robot's controller as its world sets it.
pub fn build_for(rig: &RobotRig) -> Result<Box<dyn Controller>, ControllerError> {
    let spec = spec_of(&rig.controller)?;
    (spec.build)(
        &arguments(&rig.controller, &rig.controller_args)?,
        Some(rig),
        rig.control_period,
    )
}

impl Parameters {
    /// Reads `key=value` strings for the controller called `controller`.
    pub fn parse(controller: &str, args: &[String]) -> Result<Parameters, ControllerError> {
        Ok(Parameters::from_arguments(&arguments(controller, args)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_parse_and_reject_nonsense() {
        let p = Parameters::parse(
            "regatta",
            &["irGain=2".to_owned(), "bias=12 lightGain=0.5".to_owned()],
        )
        .unwrap();
        assert_eq!((p.ir_gain, p.bias, p.light_gain), (2.0, 12.0, 0.5));
        assert!(matches!(
            Parameters::parse("regatta", &["gain=2".to_owned()]),
            Err(ControllerError::UnknownKey { .. })
        ));
        assert!(matches!(
            Parameters::parse("regatta", &["irGain".to_owned()]),
            Err(ControllerError::Malformed(_))
        ));
        assert!(matches!(
            Parameters::parse("regatta", &["irGain=NaN".to_owned()]),
            Err(ControllerError::NotANumber { .. })
        ));
        assert!(matches!(
            build("wander", &[], 0.032),
            Err(ControllerError::Unknown { .. })
        ));
        assert!(matches!(
            Parameters::parse("braitenberg", &["lightGain=1".to_owned()]),
            Err(ControllerError::UnknownKey { .. })
        ));
    }

    #[test]
    fn habituation_is_a_time_in_seconds() {
        let p = Parameters::parse("regatta", &["habituation=0".to_owned()]).unwrap();
        assert_eq!(p.habituation, 0.0);
        assert_eq!(Parameters::default().habituation, 2.4);
        assert!(matches!(
            Parameters::parse("regatta", &["habituation=-3".to_owned()]),
            Err(ControllerError::NotANumber { .. })
        ));
        let p = Parameters::parse("regatta", &["habituation=2.5".to_owned()]).unwrap();
        assert_eq!(p.habituation, 2.5);
    }
}
