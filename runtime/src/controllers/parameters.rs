//! What a world may pass a built-in controller in `controllerArgs`: parameter specs with their
//! kinds and defaults (the `braitenberg` and `regatta` controllers'), checked arguments, and
//! the [`Parameters`] those two controllers run with. Reading `key=value` strings against
//! the registry is the registry's (`arguments`, `Parameters::parse`, in `controllers/mod.rs`).

/// The kind of a parameter's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParameterKind {
    /// A finite number.
    Number,
    /// A whole number.
    Integer,
    /// A time in seconds, not negative. Every time a controller takes is in seconds, never
    /// in steps: a count of steps would change meaning with the control period.
    Seconds,
}

impl ParameterKind {
    pub(crate) fn noun(self) -> &'static str {
        match self {
            ParameterKind::Number => "a finite number",
            ParameterKind::Integer => "a whole number",
            ParameterKind::Seconds => "a time in seconds, not negative",
        }
    }
}

/// One `controllerArgs` key of a controller.
#[derive(Clone, Copy, Debug)]
pub struct ParameterSpec {
    pub key: &'static str,
    pub kind: ParameterKind,
    pub default: f64,
    pub doc: &'static str,
}

/// Checked `controllerArgs`: each known key with its value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Arguments {
    pub(super) values: Vec<(&'static str, f64)>,
}

impl Arguments {
    /// The value of `key`, or `default` when the world did not give it.
    pub fn get(&self, key: &str, default: f64) -> f64 {
        self.values
            .iter()
            .rev()
            .find(|(k, _)| *k == key)
            .map_or(default, |(_, v)| *v)
    }
}

pub(crate) const BRAITENBERG_PARAMETERS: &[ParameterSpec] = &[
    ParameterSpec {
        key: "irGain",
        kind: ParameterKind::Number,
        default: 1.0,
        doc: "Multiplies the IR network (the paper doubled it in simulation).",
    },
    ParameterSpec {
        key: "bias",
        kind: ParameterKind::Number,
        default: 10.0,
        doc: "The bias neurons' forward speed (pulses per 10 ms).",
    },
];

pub(crate) const REGATTA_PARAMETERS: &[ParameterSpec] = &[
    BRAITENBERG_PARAMETERS[0],
    BRAITENBERG_PARAMETERS[1],
    ParameterSpec {
        key: "lightGain",
        kind: ParameterKind::Number,
        default: 0.1,
        doc: "Steering per pixel of light offset (pulses per 10 ms per pixel).",
    },
    ParameterSpec {
        key: "minContrast",
        kind: ParameterKind::Number,
        default: 1.5,
        doc: "Least odd-filter lobe, in LSB, that counts as a light edge.",
    },
    ParameterSpec {
        key: "habituation",
        kind: ParameterKind::Seconds,
        // About 160° of a tight orbit: in the paper's arena the next light almost always
        // takes over sooner; later, the next mark has turned past the bow and the rounding
        // would change sense. (75 control cycles of 32 ms, the value it had in steps.)
        default: 2.4,
        doc: "Seconds with the followed light abeam before the robot loses interest in it (0: never).",
    },
];

/// Parameters of the built-in controllers, with their defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameters {
    /// Multiplies the IR network (the paper doubled it in simulation).
    pub ir_gain: f64,
    /// The bias neurons' forward speed (pulses per 10 ms).
    pub bias: f64,
    /// Steering per pixel of light offset (pulses per 10 ms per pixel).
    pub light_gain: f64,
    /// Least odd-filter lobe, in LSB, that counts as a light edge.
    pub min_contrast: f64,
    /// Seconds with the followed light abeam before the robot loses interest in it
    /// (0: never).
    pub habituation: f64,
}

impl Default for Parameters {
    fn default() -> Parameters {
        Parameters::from_arguments(&Arguments::default())
    }
}

impl Parameters {
    /// The parameters of checked arguments, defaults filled in from the registry.
    pub fn from_arguments(args: &Arguments) -> Parameters {
        let value = |key: &str| {
            let default = REGATTA_PARAMETERS
                .iter()
                .find(|p| p.key == key)
                .map_or(0.0, |p| p.default);
            args.get(key, default)
        };
        Parameters {
            ir_gain: value("irGain"),
            bias: value("bias"),
            light_gain: value("lightGain"),
            min_contrast: value("minContrast"),
            habituation: value("habituation"),
        }
    }
}
