//! The `braitenberg` controller: Mondada's obstacle avoider, the feed-forward network of the
//! Khepera BIOS: `speed = bias + irGain · Σ proximity[i]·w[i] / 400` per wheel, K-Team's
//! weights. The `regatta` controller adds light seeking to the same network.

use super::parameters::Parameters;
use crate::khepera::{to_command, Controller, Khepera, KheperaError, Senses};

/// K-Team's weights, sensors 0…7 (khepera.md).
pub const LEFT_WEIGHTS: [f64; 8] = [4.0, 4.0, 6.0, -18.0, -15.0, -5.0, 5.0, 3.0];
pub const RIGHT_WEIGHTS: [f64; 8] = [-5.0, -15.0, -18.0, 6.0, 4.0, 4.0, 3.0, 5.0];

/// The IR network's wheel commands (pulses per 10 ms, unrounded).
#[inline]
pub fn braitenberg_speeds(proximity: &[u16; 8], parameters: &Parameters) -> (f64, f64) {
    let mut left = 0.0;
    let mut right = 0.0;
    for i in 0..8 {
        left += proximity[i] as f64 * LEFT_WEIGHTS[i];
        right += proximity[i] as f64 * RIGHT_WEIGHTS[i];
    }
    (
        parameters.bias + parameters.ir_gain * left / 400.0,
        parameters.bias + parameters.ir_gain * right / 400.0,
    )
}

/// Mondada's Braitenberg obstacle avoider.
pub struct Braitenberg {
    pub parameters: Parameters,
}

impl Controller for Braitenberg {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        let proximity = robot.proximity()?;
        let (left, right) = braitenberg_speeds(&proximity, &self.parameters);
        robot.set_speed(to_command(left), to_command(right))
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
    fn an_obstacle_on_the_left_turns_the_robot_right() {
        let mut proximity = [0u16; 8];
        proximity[1] = 800;
        let (left, right) = braitenberg_speeds(&proximity, &Parameters::default());
        assert!(left > right, "left {left} right {right}");
    }
}
