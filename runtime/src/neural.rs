//! The `neural` controller: a network kept in the world file (a `NeuralNetwork` node in a
//! robot's `network` field), read into a [`Topology`] and its weights, checked against its
//! inputs and outputs, and run once per step.
//!
//! Value ranges (also in the catalogue's doc of `NeuralNetwork`):
//! - IR and ambient inputs are the readings divided by 1024 (0 … 0.999). A power of two keeps
//!   every product with a small integer weight exact, which is why a network with K-Team's
//!   weights gives the `braitenberg` controller's commands bit for bit.
//! - A retina sector is its pixels' digital values, each centred and scaled to
//!   `(d − (2^b − 1)/2) / 2^(b−1)` (−1 … 1), pooled by mean, max or min.
//! - The bias input is 1. When the inputs list it, every later layer reads it too, first.
//! - Outputs: tanh (−1 … 1), sigmoid mapped by `2y − 1`, or linear; a wheel command is
//!   `round(outputScale · output)` clamped to the real robot's −127 … 127 pulses per 10 ms.
//! - CTRNN (Beer 1995): `τ_i dy_i/dt = −y_i + Σ_j w_ij σ(y_j) + Σ_k g_ik I_k`, forward Euler
//!   steps of the world's time step from y = 0, motor outputs `2σ(y) − 1`.

use std::sync::Arc;

use regatta_parser::Diagnostic;
use regatta_schema::{FileDiagnostic, NodeId, Scene};

use crate::khepera::{Controller, Khepera, KheperaError, Senses};
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
    /// Every retina sector.
    Retina,
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
    fn apply(self, x: f64) -> f64 {
        match self {
            Activation::Tanh => libm::tanh(x),
            Activation::Sigmoid => sigmoid(x),
            Activation::Linear => x,
        }
    }
}

fn sigmoid(x: f64) -> f64 {
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
    /// The controller's step (s): the CTRNN's Euler step.
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
                Input::Retina => self.retina_sectors,
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
    fn layer_shapes(&self) -> Vec<(usize, usize, usize)> {
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
            vision: self.inputs.contains(&Input::Retina),
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
        "time constant {tau} s is shorter than the time step {time_step} s: the Euler steps would be unstable"
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

fn parse_input(name: &str) -> Option<Input> {
    let indexed = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|n| n.parse::<usize>().ok())
            .filter(|&n| n < 8)
    };
    match name {
        "bias" => Some(Input::Bias),
        "retina" => Some(Input::Retina),
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
/// carries a Panoramic turret; `time_step` is the world's (s).
pub fn network_from_scene(
    scene: &Scene,
    node: NodeId,
    panoramic: bool,
    time_step: f64,
) -> Result<NetworkSpec, NetworkError> {
    let mut inputs = Vec::new();
    for name in scene.strings(node, "inputs") {
        match name.as_str() {
            "ir" => inputs.extend((0..8).map(Input::Ir)),
            "ambient" => inputs.extend((0..8).map(Input::Ambient)),
            other => inputs.push(
                parse_input(other).ok_or_else(|| NetworkError::UnknownInput(other.to_owned()))?,
            ),
        }
    }
    let topology = Topology {
        inputs,
        retina_filter: crate::compile::rig::filter_kind(scene.string(node, "retinaFilter"))
            .unwrap_or(FilterKind::Raw),
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
    if topology.inputs.contains(&Input::Retina) && !panoramic {
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

/// Every robot's network checked, as diagnostics at the field they are about (what
/// `regatta check` adds to the schema's): sizes against inputs and outputs, retina inputs
/// without a turret, and controller "neural" without a network.
pub fn check_networks(scene: &Scene) -> Vec<FileDiagnostic> {
    let time_step = crate::compile::world_settings(scene).time_step;
    let mut diagnostics = Vec::new();
    for robot in scene.find("DifferentialWheels") {
        let panoramic = scene
            .child(robot, "turret")
            .is_some_and(|t| scene.type_name(t) == "PanoramicTurret");
        let result = match scene.child(robot, "network") {
            Some(network) => network_from_scene(scene, network, panoramic, time_step)
                .map(|_| ())
                .map_err(|e| (network, e)),
            None if scene.string(robot, "controller") == "neural" => {
                Err((robot, NetworkError::NoNetwork))
            }
            None => Ok(()),
        };
        if let Err((node, error)) = result {
            let field = match error {
                NetworkError::NoNetwork => "controller",
                _ => error.field(),
            };
            let at = scene.value_span(node, field);
            let label = match &error {
                NetworkError::WeightCount { expected, .. } => {
                    format!("{expected} weights expected")
                }
                _ => format!("in '{field}'"),
            };
            diagnostics.push(FileDiagnostic {
                file: at.file,
                diagnostic: Diagnostic::error(at.span, error.to_string())
                    .with_label(label)
                    .with_code("network"),
            });
        }
    }
    diagnostics
}

/// The network running on a robot.
pub struct Neural {
    topology: Arc<Topology>,
    weights: Arc<[f64]>,
    /// Each layer's current values (Elman contexts, CTRNN states y).
    state: Vec<Vec<f64>>,
    /// The input vector and a layer's input, reused.
    input: Vec<f64>,
    scratch: Vec<f64>,
    next: Vec<f64>,
    retina: Vec<u16>,
    filter_enabled: bool,
}

impl Neural {
    /// The network of `topology` with `weights` (one candidate of an evolution, or a world's).
    pub fn new(topology: Arc<Topology>, weights: Arc<[f64]>) -> Result<Neural, NetworkError> {
        let expected = topology.parameter_count();
        if weights.len() != expected {
            return Err(NetworkError::WeightCount {
                expected,
                found: weights.len(),
            });
        }
        let state = topology.layers().iter().map(|&n| vec![0.0; n]).collect();
        Ok(Neural {
            topology,
            weights,
            state,
            input: Vec::new(),
            scratch: Vec::new(),
            next: Vec::new(),
            retina: Vec::new(),
            filter_enabled: false,
        })
    }

    /// A world's network.
    pub fn from_spec(spec: &NetworkSpec) -> Result<Neural, NetworkError> {
        Neural::new(spec.topology.clone(), spec.weights.clone().into())
    }

    /// Fills the input vector from the robot.
    fn read_inputs(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        let topology = &*self.topology;
        let senses = topology.senses();
        let proximity = if senses.proximity {
            robot.proximity()?
        } else {
            [0; 8]
        };
        let ambient = if senses.ambient {
            robot.ambient()?
        } else {
            [0; 8]
        };
        let mut bits = 0;
        if senses.vision {
            let turret = robot.panoramic().ok_or(KheperaError::NoDevice(
                "Panoramic turret (the network reads the retina)",
            ))?;
            if !self.filter_enabled {
                turret.enable_filter(topology.retina_filter)?;
                self.filter_enabled = true;
            }
            turret.read_into(topology.retina_filter, &mut self.retina)?;
            bits = turret.bits()?;
        }
        self.input.clear();
        for &input in &topology.inputs {
            match input {
                Input::Bias => self.input.push(1.0),
                Input::Ir(i) => self.input.push(proximity[i] as f64 / 1024.0),
                Input::Ambient(i) => self.input.push(ambient[i] as f64 / 1024.0),
                Input::Retina => pool_sectors(
                    &self.retina,
                    bits,
                    topology.retina_sectors,
                    topology.retina_pooling,
                    &mut self.input,
                ),
            }
        }
        Ok(())
    }

    /// The two outputs, mapped to −1 … 1 where the activation is bounded.
    fn outputs(&mut self) -> (f64, f64) {
        let topology = &*self.topology;
        let shapes = topology.layer_shapes();
        let bias = topology.has_bias();
        let mut offset = 0;
        if topology.recurrence == Recurrence::Ctrnn {
            let (neurons, outside, _) = shapes[0];
            let state = &mut self.state[0];
            // Firing rates of the current states: every neuron reads them all.
            self.scratch.clear();
            self.scratch.extend(state.iter().map(|&y| sigmoid(y)));
            self.next.clear();
            for i in 0..neurons {
                let row = &self.weights[offset + i * (outside + neurons)..];
                let mut drive = 0.0;
                for (w, x) in row[..outside].iter().zip(&self.input) {
                    drive += w * x;
                }
                for (w, r) in row[outside..outside + neurons].iter().zip(&self.scratch) {
                    drive += w * r;
                }
                let tau = topology.time_constants[i];
                self.next
                    .push(state[i] + topology.time_step / tau * (drive - state[i]));
            }
            state.copy_from_slice(&self.next);
            let rate = |y: f64| 2.0 * sigmoid(y) - 1.0;
            return (rate(state[neurons - 2]), rate(state[neurons - 1]));
        }
        let last = shapes.len() - 1;
        for (index, &(neurons, outside, recurrent)) in shapes.iter().enumerate() {
            // The layer's input: the network's inputs, or the bias and the previous layer.
            if index > 0 {
                self.scratch.clear();
                if bias {
                    self.scratch.push(1.0);
                }
                self.scratch.extend_from_slice(&self.state[index - 1]);
                std::mem::swap(&mut self.scratch, &mut self.input);
            }
            let activation = if index == last {
                topology.output_activation
            } else {
                topology.activation
            };
            self.next.clear();
            let context = &self.state[index];
            for i in 0..neurons {
                let row = &self.weights[offset + i * (outside + recurrent)..];
                let mut sum = 0.0;
                for (w, x) in row[..outside].iter().zip(&self.input) {
                    sum += w * x;
                }
                for (w, c) in row[outside..outside + recurrent].iter().zip(context) {
                    sum += w * c;
                }
                self.next.push(activation.apply(sum));
            }
            offset += neurons * (outside + recurrent);
            if index > 0 {
                // Give the network's inputs back their buffer.
                std::mem::swap(&mut self.scratch, &mut self.input);
            }
            self.state[index].copy_from_slice(&self.next);
        }
        let out = &self.state[last];
        let map = |y: f64| match topology.output_activation {
            Activation::Sigmoid => 2.0 * y - 1.0,
            _ => y,
        };
        (map(out[0]), map(out[1]))
    }
}

/// Appends `sectors` pooled values of a digital retina output (`bits` bits), left to right.
/// Every sector holds at least one pixel, so a region of interest shorter than the sector
/// count repeats pixels rather than leaving inputs undefined.
pub fn pool_sectors(
    digital: &[u16],
    bits: u32,
    sectors: usize,
    pooling: Pooling,
    out: &mut Vec<f64>,
) {
    if digital.is_empty() {
        out.extend(std::iter::repeat_n(0.0, sectors));
        return;
    }
    let zero = ((1u64 << bits) - 1) as f64 / 2.0;
    let scale = 1.0 / (1u64 << (bits.max(1) - 1)) as f64;
    let n = digital.len();
    for s in 0..sectors {
        let start = (s * n / sectors).min(n - 1);
        let end = ((s + 1) * n / sectors).max(start + 1);
        let pixels = &digital[start..end];
        let value = |d: u16| (d as f64 - zero) * scale;
        out.push(match pooling {
            Pooling::Mean => {
                let mut sum = 0.0;
                for &d in pixels {
                    sum += value(d);
                }
                sum / pixels.len() as f64
            }
            Pooling::Max => value(pixels.iter().copied().max().unwrap_or(0)),
            Pooling::Min => value(pixels.iter().copied().min().unwrap_or(0)),
        });
    }
}

impl Controller for Neural {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        self.read_inputs(robot)?;
        let (left, right) = self.outputs();
        let scale = self.topology.output_scale;
        robot.set_speed(
            crate::controllers::to_command(scale * left),
            crate::controllers::to_command(scale * right),
        )
    }

    fn senses(&self) -> Senses {
        self.topology.senses()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topology(hidden: Vec<usize>, recurrence: Recurrence) -> Topology {
        Topology {
            inputs: vec![Input::Bias, Input::Ir(0), Input::Ir(1), Input::Retina],
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

    #[test]
    fn sectors_pool_left_to_right_and_are_never_empty() {
        let mut out = Vec::new();
        // 6 bits: 31.5 is zero, 32 is 1/64.
        pool_sectors(&[32, 63, 0, 31], 6, 2, Pooling::Max, &mut out);
        assert_eq!(out, vec![31.5 / 32.0, -0.5 / 32.0]);
        out.clear();
        pool_sectors(&[32, 63, 0, 31], 6, 2, Pooling::Mean, &mut out);
        assert_eq!(out, vec![16.0 / 32.0, -16.0 / 32.0]);
        out.clear();
        pool_sectors(&[40], 6, 3, Pooling::Min, &mut out);
        assert_eq!(out, vec![8.5 / 32.0; 3]);
    }

    #[test]
    fn a_ctrnn_relaxes_to_its_fixed_point() {
        // One motor neuron pair, no interneurons, only a bias input of weight 2 and no
        // recurrent weights: y → 2 with time constant τ, so after many steps the output is
        // 2σ(2) − 1.
        let mut t = topology(vec![], Recurrence::Ctrnn);
        t.inputs = vec![Input::Bias];
        t.time_constants = vec![0.1, 0.1];
        let weights: Vec<f64> = vec![2.0, 0.0, 0.0, 2.0, 0.0, 0.0];
        let mut network = Neural::new(Arc::new(t), weights.into()).unwrap();
        network.input = vec![1.0];
        let mut outputs = (0.0, 0.0);
        for _ in 0..2000 {
            network.input = vec![1.0];
            outputs = network.outputs();
        }
        let expected = 2.0 * sigmoid(2.0) - 1.0;
        assert!((outputs.0 - expected).abs() < 1e-12, "{outputs:?}");
        assert_eq!(outputs.0, outputs.1);
    }

    #[test]
    fn elman_context_carries_the_previous_step() {
        // No hidden layer: each output reads the bias (weight 0) and its own previous value
        // (weight 1) with a linear activation, so an output starting at 0 stays 0, and one
        // given a bias weight of 1 counts steps.
        let mut t = topology(vec![], Recurrence::Elman);
        t.inputs = vec![Input::Bias];
        t.output_activation = Activation::Linear;
        let weights = vec![1.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut network = Neural::new(Arc::new(t), weights.into()).unwrap();
        for step in 1..=5 {
            network.input = vec![1.0];
            let (left, right) = network.outputs();
            assert_eq!((left, right), (step as f64, 0.0));
        }
    }
}
