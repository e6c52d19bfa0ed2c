//! The `neural` controller: runs a robot's network ([`crate::compile::network`]: a
//! `NeuralNetwork` node read into a topology and weights) once per step.
//!
//! Value ranges (also in the catalogue's doc of `NeuralNetwork`):
//! - IR and ambient inputs are the readings divided by 1024 (0 … 0.999). A power of two keeps
//!   every product with a small integer weight exact, which is why a network with K-Team's
//!   weights gives the `braitenberg` controller's commands bit for bit.
//! - A retina sector is its pixels' digital values, each centred and scaled to
//!   `(d − (2^b − 1)/2) / 2^(b−1)` (−1 … 1), pooled by mean, max or min. Each retina input
//!   names the turret output it reads (`retina` the `retinaFilter`, `retina:odd` the odd
//!   filter…); the outputs read are enabled on the first call.
//! - The bias input is 1. When the inputs list it, every later layer reads it too, first.
//! - Outputs: tanh (−1 … 1), sigmoid mapped by `2y − 1`, or linear; a wheel command is
//!   `round(outputScale · output)` clamped to the real robot's −127 … 127 pulses per 10 ms.
//! - CTRNN (Beer 1995): `τ_i dy_i/dt = −y_i + Σ_j w_ij σ(y_j) + Σ_k g_ik I_k`, forward Euler
//!   steps of the robot's control period (it runs once per controller call) from y = 0, motor
//!   outputs `2σ(y) − 1`.

use std::sync::Arc;

use crate::compile::network::{
    sigmoid, Activation, Input, NetworkError, NetworkSpec, Pooling, Recurrence, Topology,
};
use crate::khepera::{to_command, Controller, Khepera, KheperaError, Senses};
use crate::retina::FilterKind;

/// The turret outputs a network's inputs read, each once, in order of first mention.
fn retina_outputs(topology: &Topology) -> Vec<(FilterKind, Vec<u16>)> {
    let mut outputs: Vec<(FilterKind, Vec<u16>)> = Vec::new();
    for input in &topology.inputs {
        if let Input::Retina(filter) = *input {
            if outputs.iter().all(|(f, _)| *f != filter) {
                outputs.push((filter, Vec::new()));
            }
        }
    }
    outputs
}

/// The network running on a robot.
pub struct Neural {
    topology: Arc<Topology>,
    /// The topology's layer shapes, computed once rather than on every call.
    shapes: Vec<(usize, usize, usize)>,
    weights: Arc<[f64]>,
    /// Each layer's current values (Elman contexts, CTRNN states y).
    state: Vec<Vec<f64>>,
    /// The input vector and a layer's input, reused.
    input: Vec<f64>,
    scratch: Vec<f64>,
    next: Vec<f64>,
    /// The turret outputs the inputs read, in their first-mention order, each with its last
    /// reading.
    retina: Vec<(FilterKind, Vec<u16>)>,
    filters_enabled: bool,
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
        let retina = retina_outputs(&topology);
        Ok(Neural {
            shapes: topology.layer_shapes(),
            topology,
            weights,
            state,
            input: Vec::new(),
            scratch: Vec::new(),
            next: Vec::new(),
            retina,
            filters_enabled: false,
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
            if !self.filters_enabled {
                for (filter, _) in &self.retina {
                    turret.enable_filter(*filter)?;
                }
                self.filters_enabled = true;
            }
            for (filter, reading) in &mut self.retina {
                turret.read_into(*filter, reading)?;
            }
            bits = turret.bits()?;
        }
        self.input.clear();
        for &input in &topology.inputs {
            match input {
                Input::Bias => self.input.push(1.0),
                Input::Ir(i) => self.input.push(proximity[i] as f64 / 1024.0),
                Input::Ambient(i) => self.input.push(ambient[i] as f64 / 1024.0),
                Input::Retina(filter) => pool_sectors(
                    self.retina
                        .iter()
                        .find(|(f, _)| *f == filter)
                        .map_or(&[][..], |(_, reading)| reading.as_slice()),
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
        let shapes = &self.shapes;
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
        robot.set_speed(to_command(scale * left), to_command(scale * right))
    }

    fn senses(&self) -> Senses {
        self.topology.senses()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::network::tests::topology;
    use crate::compile::network::{Activation, Input, Pooling, Recurrence};

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
