//! The `braitenberg` controller: Mondada's obstacle avoider, the feed-forward network of the
//! Khepera BIOS: `speed = bias + irGain · Σ proximity[i]·w[i] / 400` per wheel, K-Team's
//! weights. The `regatta` controller adds light seeking to the same network. A robot whose
//! sensors are not the Khepera's eight (the Thymio's seven) gets weights from its sensors'
//! headings ([`Weights::for_robot`]). Facing a corner the network deadlocks (its two sides
//! cancel); the stall escape ([`super::escape`]) turns the robot away, as the `regatta`
//! controller's does.

use super::escape::StallEscape;
use super::parameters::Parameters;
use crate::compile::rig::RobotRig;
use crate::khepera::{to_command, Controller, Khepera, KheperaError, Senses};

/// K-Team's weights, sensors 0…7 (khepera.md).
pub const LEFT_WEIGHTS: [f64; 8] = [4.0, 4.0, 6.0, -18.0, -15.0, -5.0, 5.0, 3.0];
pub const RIGHT_WEIGHTS: [f64; 8] = [-5.0, -15.0, -18.0, 6.0, 4.0, 4.0, 3.0, 5.0];

/// Where K-Team's sensors 0…7 look (degrees, left of forward positive; khepera.md): the
/// headings that K-Team's weights were tuned for.
const KTEAM_HEADINGS: [f64; 8] = [90.0, 45.0, 10.0, -10.0, -45.0, -90.0, -170.0, 170.0];

/// The network's weights per proximity slot, (left wheel, right wheel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    pub left: [f64; 8],
    pub right: [f64; 8],
}

impl Weights {
    /// K-Team's weights, for the Khepera and the robots whose sensors fill its slots.
    pub const KTEAM: Weights = Weights {
        left: LEFT_WEIGHTS,
        right: RIGHT_WEIGHTS,
    };

    /// The weights for a robot's sensors: K-Team's where it has eight (the Khepera, and the
    /// stand-ins that list theirs in the Khepera's order); otherwise each sensor takes the
    /// weights of the K-Team sensor whose heading is nearest its own, so that a robot with
    /// other sensors (the Thymio's five in front and two behind) turns away from what it
    /// sees as a Khepera would. Slots with no sensor weigh nothing.
    pub fn for_robot(robot: Option<&RobotRig>) -> Weights {
        let Some(robot) = robot else {
            return Weights::KTEAM;
        };
        if robot.distance_sensors.len() >= 8 {
            return Weights::KTEAM;
        }
        let mut weights = Weights {
            left: [0.0; 8],
            right: [0.0; 8],
        };
        for (slot, sensor) in robot.distance_sensors.iter().enumerate() {
            let heading = libm::atan2(-sensor.direction.z, sensor.direction.x).to_degrees();
            let nearest = nearest_heading(heading);
            weights.left[slot] = LEFT_WEIGHTS[nearest];
            weights.right[slot] = RIGHT_WEIGHTS[nearest];
        }
        weights
    }
}

/// The K-Team sensor whose heading is nearest `heading` (degrees); ties go to the lower index.
fn nearest_heading(heading: f64) -> usize {
    let gap = |k: usize| {
        let d = (heading - KTEAM_HEADINGS[k]).rem_euclid(360.0);
        d.min(360.0 - d)
    };
    (1..8).fold(0, |best, k| if gap(k) < gap(best) { k } else { best })
}

/// The IR network's wheel commands (pulses per 10 ms, unrounded), with K-Team's weights.
#[inline]
pub fn braitenberg_speeds(proximity: &[u16; 8], parameters: &Parameters) -> (f64, f64) {
    weighted_speeds(proximity, &Weights::KTEAM, parameters)
}

/// The IR network's wheel commands with the given weights.
#[inline]
pub fn weighted_speeds(
    proximity: &[u16; 8],
    weights: &Weights,
    parameters: &Parameters,
) -> (f64, f64) {
    let mut left = 0.0;
    let mut right = 0.0;
    for i in 0..8 {
        left += proximity[i] as f64 * weights.left[i];
        right += proximity[i] as f64 * weights.right[i];
    }
    (
        parameters.bias + parameters.ir_gain * left / 400.0,
        parameters.bias + parameters.ir_gain * right / 400.0,
    )
}

/// Mondada's Braitenberg obstacle avoider.
pub struct Braitenberg {
    pub parameters: Parameters,
    /// The weights unless they are K-Team's, which a swarm's robots share from one static
    /// copy rather than each reading two cache lines of its own every step.
    other_weights: Option<Box<Weights>>,
    escape: StallEscape,
}

impl Braitenberg {
    /// The controller with its weights, to be called every `period` seconds.
    pub fn new(parameters: Parameters, weights: Weights, period: f64) -> Braitenberg {
        Braitenberg {
            parameters,
            other_weights: (weights != Weights::KTEAM).then(|| Box::new(weights)),
            escape: StallEscape::new(period),
        }
    }

    /// The network's weights.
    pub fn weights(&self) -> &Weights {
        self.other_weights.as_deref().unwrap_or(&Weights::KTEAM)
    }
}

impl Controller for Braitenberg {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        let proximity = robot.proximity()?;
        let (left, right) = weighted_speeds(&proximity, self.weights(), &self.parameters);
        let command = (to_command(left), to_command(right));
        let (left, right) = self
            .escape
            .command(&proximity, command, self.parameters.bias);
        robot.set_speed(left, right)
    }

    fn senses(&self) -> Senses {
        Senses {
            proximity: true,
            ..Senses::NONE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_controller_keeps_the_weights_it_was_given() {
        let mut other = Weights::KTEAM;
        other.right[7] = 2.5;
        for weights in [Weights::KTEAM, other] {
            let controller = Braitenberg::new(Parameters::default(), weights, 0.032);
            assert_eq!(*controller.weights(), weights);
        }
    }

    #[test]
    fn an_obstacle_on_the_left_turns_the_robot_right() {
        let mut proximity = [0u16; 8];
        proximity[1] = 800;
        let (left, right) = braitenberg_speeds(&proximity, &Parameters::default());
        assert!(left > right, "left {left} right {right}");
    }

    #[test]
    fn the_khepera_headings_map_to_their_own_slots() {
        for (k, heading) in KTEAM_HEADINGS.iter().enumerate() {
            assert_eq!(nearest_heading(*heading), k);
        }
        // The Thymio's: ±40° and ±20° in front, straight ahead, straight behind.
        assert_eq!(nearest_heading(40.0), 1);
        assert_eq!(nearest_heading(-20.0), 3);
        assert_eq!(nearest_heading(0.0), 2);
        assert_eq!(nearest_heading(180.0), 6);
        assert_eq!(nearest_heading(-180.0), 6);
    }
}
