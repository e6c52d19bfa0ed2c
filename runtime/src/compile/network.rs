//! A robot's neural network as its world holds it: a `NeuralNetwork` node (in a robot's
//! `network` field) read into a [`Topology`] (what evolution keeps fixed) and its weights, and
//! checked against its inputs and outputs. The rig carries it (a robot's `network`); the
//! `neural` controller (`controllers/neural.rs`) runs it, with the value ranges its
//! documentation gives.

use std::sync::Arc;

use regatta_schema::{NodeId, Scene};

use crate::khepera::Senses;
use crate::retina::FilterKind;

/// One named entry of a network's input list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The constant 1.
    Bias,
    /// One IR proximity reading.
    Ir(usize),
    /// One ambient light reading.
    Ambient(usize),
    /// Every retina sector of one Panoramic turret output: `"retina"` reads `retinaFilter`,
    /// `"retina:odd"` (and the other outputs' names) that output, so that a network may read
    /// several and evolution weigh them.
    Retina(FilterKind),
}

impl Input {
    /// Whether this input reads the retina.
    pub fn is_retina(&self) -> bool {
        matches!(self, Input::Retina(_))
    }
}

/// How a layer's neurons are connected to their past.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recurrence {
    None,
    Elman,
    Ctrnn,
}

/// A neuron's output function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activation {
    Tanh,
    Sigmoid,
    Linear,
}

impl Activation {
    #[inline]
    pub(crate) fn apply(self, x: f64) -> f64 {
        match self {
            Activation::Tanh => libm::tanh(x),
            Activation::Sigmoid => sigmoid(x),
            Activation::Linear => x,
        }
    }
}

#[inline]
pub(crate) fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + libm::exp(-x))
}

/// How a retina sector's pixels become one input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pooling {
    Mean,
    Max,
    Min,
}

/// Everything about a network but its weights: what evolution keeps fixed.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    pub inputs: Vec<Input>,
    pub retina_filter: FilterKind,
    pub retina_sectors: usize,
    pub retina_pooling: Pooling,
    pub hidden: Vec<usize>,
    pub recurrence: Recurrence,
    pub activation: Activation,
    pub output_activation: Activation,
    pub output_scale: f64,
    /// CTRNN: one per neuron (interneurons, then the two motor neurons).
    pub time_constants: Vec<f64>,
    /// The robot's control period (s): the CTRNN's Euler step, one per controller call.
    pub time_step: f64,
}

/// The two wheels.
pub const OUTPUTS: usize = 2;
/// A CTRNN neuron's time constant when none is given (s).
pub const DEFAULT_TIME_CONSTANT: f64 = 0.1;

impl Topology {
    /// Whether the inputs list the bias (then every later layer reads it too).
    pub fn has_bias(&self) -> bool {
        self.inputs.contains(&Input::Bias)
    }

    /// The length of the input vector.
    pub fn input_count(&self) -> usize {
        self.inputs
            .iter()
            .map(|i| match i {
                Input::Retina(_) => self.retina_sectors,
                _ => 1,
            })
            .sum()
    }

    /// Neurons of each non-input layer, input side first: the hidden layers and the outputs;
    /// for a CTRNN one layer of every neuron.
    pub fn layers(&self) -> Vec<usize> {
        match self.recurrence {
            Recurrence::Ctrnn => vec![self.hidden.iter().sum::<usize>() + OUTPUTS],
            _ => self
                .hidden
                .iter()
                .copied()
                .chain(std::iter::once(OUTPUTS))
                .collect(),
        }
    }

    /// (neurons, inputs per neuron from outside the layer, recurrent inputs per neuron) of
    /// each layer.
    pub(crate) fn layer_shapes(&self) -> Vec<(usize, usize, usize)> {
        let layers = self.layers();
        let bias = usize::from(self.has_bias());
        let mut previous = self.input_count();
        let last = layers.len() - 1;
        layers
            .iter()
            .enumerate()
            .map(|(index, &neurons)| {
                let outside = if index == 0 {
                    previous
                } else {
                    previous + bias
                };
                let recurrent = match self.recurrence {
                    Recurrence::None => 0,
                    Recurrence::Ctrnn => neurons,
                    // Elman: every hidden layer keeps a context; the outputs only when
                    // there is no hidden layer (Floreano and Mondada's recurrent motors).
                    Recurrence::Elman if index < last || last == 0 => neurons,
                    Recurrence::Elman => 0,
                };
                previous = neurons;
                (neurons, outside, recurrent)
            })
            .collect()
    }

    /// How many weights the network takes.
    pub fn parameter_count(&self) -> usize {
        self.layer_shapes()
            .iter()
            .map(|&(n, outside, recurrent)| n * (outside + recurrent))
            .sum()
    }

    /// The sensors the network reads.
    pub fn senses(&self) -> Senses {
        Senses {
            proximity: self.inputs.iter().any(|i| matches!(i, Input::Ir(_))),
            ambient: self.inputs.iter().any(|i| matches!(i, Input::Ambient(_))),
            vision: self.inputs.iter().any(Input::is_retina),
            camera: false,
        }
    }
}

/// A network with its weights, as a world holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct NetworkSpec {
    pub topology: Arc<Topology>,
    pub weights: Vec<f64>,
    /// The `NeuralNetwork` node.
    pub node: NodeId,
}

/// Why a `NeuralNetwork` cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NetworkError {
    #[error("the network takes {expected} weights, found {found}")]
    WeightCount { expected: usize, found: usize },
    #[error("the network has no inputs")]
    NoInputs,
    #[error("a CTRNN takes one entry in 'hidden' (its interneurons), found {0}")]
    CtrnnLayers(usize),
    #[error("the CTRNN has {neurons} neurons but {found} time constants")]
    TimeConstantCount { neurons: usize, found: usize },
    #[error(
        "time constant {tau} s is shorter than the control period {time_step} s: the Euler steps would be unstable"
    )]
    TimeConstantTooShort { tau: f64, time_step: f64 },
    #[error("retina inputs need a PanoramicTurret on the robot")]
    NoRetina,
    #[error("controller \"neural\" needs a NeuralNetwork in the robot's 'network' field")]
    NoNetwork,
    #[error("unknown input \"{0}\"")]
    UnknownInput(String),
}

impl NetworkError {
    /// The `NeuralNetwork` field a message about this error points at.
    pub fn field(&self) -> &'static str {
        match self {
            NetworkError::WeightCount { .. } => "weights",
            NetworkError::NoInputs | NetworkError::UnknownInput(_) | NetworkError::NoRetina => {
                "inputs"
            }
            NetworkError::CtrnnLayers(_) => "hidden",
            NetworkError::TimeConstantCount { .. } | NetworkError::TimeConstantTooShort { .. } => {
                "timeConstants"
            }
            NetworkError::NoNetwork => "network",
        }
    }
}

fn parse_input(name: &str, retina_filter: FilterKind) -> Option<Input> {
    let indexed = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|n| n.parse::<usize>().ok())
            .filter(|&n| n < 8)
    };
    match name {
        "bias" => Some(Input::Bias),
        "retina" => Some(Input::Retina(retina_filter)),
        _ if name.starts_with("retina:") => {
            FilterKind::from_name(&name["retina:".len()..]).map(Input::Retina)
        }
        _ => indexed("ir")
            .map(Input::Ir)
            .or_else(|| indexed("ambient").map(Input::Ambient)),
    }
}

fn activation(name: &str) -> Activation {
    match name {
        "sigmoid" => Activation::Sigmoid,
        "linear" => Activation::Linear,
        _ => Activation::Tanh,
    }
}

/// Reads a `NeuralNetwork` node (typed by the schema, so its strings are among the allowed
/// values) and checks it against its inputs and outputs. `panoramic` says whether the robot
/// carries a Panoramic turret; `time_step` is the robot's control period (s), the step of a
/// CTRNN's integration.
pub fn network_from_scene(
    scene: &Scene,
    node: NodeId,
    panoramic: bool,
    time_step: f64,
) -> Result<NetworkSpec, NetworkError> {
    let retina_filter =
        FilterKind::from_name(scene.string(node, "retinaFilter")).unwrap_or(FilterKind::Raw);
    let mut inputs = Vec::new();
    for name in scene.strings(node, "inputs") {
        match name.as_str() {
            "ir" => inputs.extend((0..8).map(Input::Ir)),
            "ambient" => inputs.extend((0..8).map(Input::Ambient)),
            other => inputs.push(
                parse_input(other, retina_filter)
                    .ok_or_else(|| NetworkError::UnknownInput(other.to_owned()))?,
            ),
        }
    }
    let topology = Topology {
        inputs,
        retina_filter,
        retina_sectors: scene.int(node, "retinaSectors").max(1) as usize,
        retina_pooling: match scene.string(node, "retinaPooling") {
            "mean" => Pooling::Mean,
            "min" => Pooling::Min,
            _ => Pooling::Max,
        },
        hidden: match scene.field(node, "hidden") {
            regatta_schema::Value::Ints(sizes) => {
                sizes.iter().map(|&n| n.max(1) as usize).collect()
            }
            _ => Vec::new(),
        },
        recurrence: match scene.string(node, "recurrence") {
            "elman" => Recurrence::Elman,
            "ctrnn" => Recurrence::Ctrnn,
            _ => Recurrence::None,
        },
        activation: activation(scene.string(node, "activation")),
        output_activation: activation(scene.string(node, "outputActivation")),
        output_scale: scene.float(node, "outputScale"),
        time_constants: match scene.field(node, "timeConstants") {
            regatta_schema::Value::Floats(taus) => taus.clone(),
            _ => Vec::new(),
        },
        time_step,
    };
    let weights = match scene.field(node, "weights") {
        regatta_schema::Value::Floats(w) => w.clone(),
        _ => Vec::new(),
    };
    let topology = checked(topology, panoramic)?;
    let expected = topology.parameter_count();
    if weights.len() != expected {
        return Err(NetworkError::WeightCount {
            expected,
            found: weights.len(),
        });
    }
    Ok(NetworkSpec {
        topology: Arc::new(topology),
        weights,
        node,
    })
}

/// Checks what does not depend on the weights; fills the CTRNN's default time constants.
fn checked(mut topology: Topology, panoramic: bool) -> Result<Topology, NetworkError> {
    if topology.inputs.is_empty() {
        return Err(NetworkError::NoInputs);
    }
    if topology.inputs.iter().any(Input::is_retina) && !panoramic {
        return Err(NetworkError::NoRetina);
    }
    if topology.recurrence == Recurrence::Ctrnn {
        if topology.hidden.len() > 1 {
            return Err(NetworkError::CtrnnLayers(topology.hidden.len()));
        }
        let neurons = topology.layers()[0];
        if topology.time_constants.is_empty() {
            topology.time_constants = vec![DEFAULT_TIME_CONSTANT; neurons];
        }
        if topology.time_constants.len() != neurons {
            return Err(NetworkError::TimeConstantCount {
                neurons,
                found: topology.time_constants.len(),
            });
        }
        if let Some(&tau) = topology
            .time_constants
            .iter()
            .find(|&&tau| tau < topology.time_step)
        {
            return Err(NetworkError::TimeConstantTooShort {
                tau,
                time_step: topology.time_step,
            });
        }
    }
    Ok(topology)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small network's topology for tests (also the neural controller's).
    pub(crate) fn topology(hidden: Vec<usize>, recurrence: Recurrence) -> Topology {
        Topology {
            inputs: vec![
                Input::Bias,
                Input::Ir(0),
                Input::Ir(1),
                Input::Retina(FilterKind::Raw),
            ],
            retina_filter: FilterKind::Raw,
            retina_sectors: 4,
            retina_pooling: Pooling::Max,
            hidden,
            recurrence,
            activation: Activation::Tanh,
            output_activation: Activation::Tanh,
            output_scale: 20.0,
            time_constants: Vec::new(),
            time_step: 0.032,
        }
    }

    #[test]
    fn parameter_counts_follow_the_layout() {
        // 7 inputs (bias, 2 IR, 4 sectors) straight to 2 outputs.
        assert_eq!(topology(vec![], Recurrence::None).parameter_count(), 14);
        // 7 → 3 (bias + 3 into the outputs).
        assert_eq!(
            topology(vec![3], Recurrence::None).parameter_count(),
            3 * 7 + 2 * 4
        );
        // Elman: the hidden layer also reads its 3 previous values.
        assert_eq!(
            topology(vec![3], Recurrence::Elman).parameter_count(),
            3 * (7 + 3) + 2 * 4
        );
        // Elman without hidden layers: the outputs read each other (Floreano and Mondada).
        assert_eq!(
            topology(vec![], Recurrence::Elman).parameter_count(),
            2 * (7 + 2)
        );
        // CTRNN of 3 interneurons and 2 motor neurons, fully connected.
        assert_eq!(
            topology(vec![3], Recurrence::Ctrnn).parameter_count(),
            5 * (7 + 5)
        );
    }
}
