//! Stall escape: the Braitenberg network's deadlock, and the turn that breaks it. Facing a
//! corner, K-Team's weights cancel (both wheels get the same command, and a small turn either
//! way is turned back), so the network has a stable fixed point there that a robot's sensor
//! and wheel noise does not leave: the robot sits. A robot whose commands both stay within
//! ±`STALL_SPEED` while a front sensor reads more than `STALL_PROXIMITY`, for `STALL_TIME`
//! seconds, turns on the spot away from the side that reads more for `ESCAPE_TIME` seconds.
//! Noise can make the deadlock a jitter instead (the Thymio's commands flicker between
//! (−2, 4) and (1, −1) in a corner): commands whose means over `STALL_SMOOTHING` seconds
//! neither advance nor turn the robot count as stalled too.
//! The `braitenberg` and `regatta` controllers share it. Times are in seconds and become
//! controller calls through the control period, so the escape is the same at any physics step.

use crate::khepera::to_command;

/// Commands this close to zero count as stopped.
pub const STALL_SPEED: i32 = 1;
/// A front IR reading above this counts as facing an obstacle.
pub const STALL_PROXIMITY: u16 = 300;
/// Time stalled before turning away (s): 32 cycles of 32 ms, about a second.
pub const STALL_TIME: f64 = 1.024;
/// Time constant (s) of the commands' running means: long enough to average out a jitter of
/// a few calls, short beside [`STALL_TIME`].
pub const STALL_SMOOTHING: f64 = 0.25;
/// Time turning on the spot (s): 24 cycles of 32 ms, roughly a right angle at the bias speed.
pub const ESCAPE_TIME: f64 = 0.768;

/// The number of controller calls, `period` seconds apart, that last `seconds` (at least one).
pub fn calls(seconds: f64, period: f64) -> u32 {
    let calls = libm::round(seconds / period);
    if calls.is_finite() {
        calls.clamp(1.0, u32::MAX as f64) as u32
    } else {
        1
    }
}

/// Turns a stalled robot away from what it faces.
#[derive(Clone, Debug, PartialEq)]
pub struct StallEscape {
    /// [`STALL_TIME`] and [`ESCAPE_TIME`] in calls of the controller.
    stall_calls: u32,
    escape_calls: u32,
    stalled: u32,
    /// The running means' weight of one call (from [`STALL_SMOOTHING`] and the period), and
    /// the means of the commands' forward part `(l + r) / 2` and turning part `(l − r) / 2`.
    smoothing: f64,
    forward_mean: f64,
    turn_mean: f64,
    /// Steps left to turn, and the direction (+1 turns right).
    escaping: u32,
    direction: i32,
}

impl StallEscape {
    /// The escape of a controller called every `period` seconds.
    pub fn new(period: f64) -> StallEscape {
        StallEscape {
            stall_calls: calls(STALL_TIME, period),
            escape_calls: calls(ESCAPE_TIME, period),
            stalled: 0,
            smoothing: 1.0 - libm::exp(-period / STALL_SMOOTHING),
            forward_mean: 0.0,
            turn_mean: 0.0,
            escaping: 0,
            direction: 0,
        }
    }

    /// The commands to send instead of `(left, right)`, if the robot must turn away.
    pub fn check(
        &mut self,
        proximity: &[u16; 8],
        (left, right): (i32, i32),
        bias: f64,
    ) -> Option<(i32, i32)> {
        let turn = to_command(bias).max(1);
        if self.escaping > 0 {
            self.escaping -= 1;
            self.average(0, 2 * self.direction * turn);
            return Some((self.direction * turn, -self.direction * turn));
        }
        let front = proximity[1..5].iter().copied().max().unwrap_or(0);
        self.average(left + right, left - right);
        let still = left.abs() <= STALL_SPEED && right.abs() <= STALL_SPEED;
        let going_nowhere = self.forward_mean.abs() <= STALL_SPEED as f64
            && self.turn_mean.abs() <= STALL_SPEED as f64;
        if (still || going_nowhere) && front > STALL_PROXIMITY {
            self.stalled += 1;
        } else {
            self.stalled = 0;
        }
        if self.stalled < self.stall_calls {
            return None;
        }
        self.stalled = 0;
        self.escaping = self.escape_calls - 1;
        // Away from the side that reads more (left sensors 0…2, right 3…5); right on a tie.
        let left_side: u32 = proximity[0..3].iter().map(|&v| v as u32).sum();
        let right_side: u32 = proximity[3..6].iter().map(|&v| v as u32).sum();
        self.direction = if right_side > left_side { -1 } else { 1 };
        self.average(0, 2 * self.direction * turn);
        Some((self.direction * turn, -self.direction * turn))
    }

    /// The commands to send: `command`, or the escape's turn while the robot must turn away.
    pub fn command(&mut self, proximity: &[u16; 8], command: (i32, i32), bias: f64) -> (i32, i32) {
        self.check(proximity, command, bias).unwrap_or(command)
    }

    /// Folds a call's commands, as their sum and difference, into the running means.
    fn average(&mut self, sum: i32, difference: i32) {
        self.forward_mean += self.smoothing * (sum as f64 / 2.0 - self.forward_mean);
        self.turn_mean += self.smoothing * (difference as f64 / 2.0 - self.turn_mean);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERIOD: f64 = 0.032;

    /// Calls until the escape takes over, feeding `commands` in turn (None: never, in `limit`).
    fn calls_to_escape(front: u16, commands: &[(i32, i32)], limit: usize) -> Option<usize> {
        let mut escape = StallEscape::new(PERIOD);
        let mut proximity = [0u16; 8];
        proximity[2] = front;
        proximity[3] = front;
        (0..limit).find(|&call| {
            let command = commands[call % commands.len()];
            escape.check(&proximity, command, 10.0).is_some()
        })
    }

    #[test]
    fn a_robot_standing_still_before_a_wall_turns_after_the_stall_time() {
        let calls = calls_to_escape(800, &[(0, -1)], 1000).unwrap();
        assert_eq!(calls + 1, self::calls(STALL_TIME, PERIOD) as usize);
    }

    #[test]
    fn a_jittering_robot_before_a_wall_turns_too() {
        // The Thymio's commands in a corner, noise flickering around a standstill.
        let jitter = [(-2, 4), (1, -1), (0, -4), (2, -3), (-1, 2), (3, -2)];
        let calls = calls_to_escape(800, &jitter, 1000).unwrap();
        assert!(
            calls < 2 * self::calls(STALL_TIME, PERIOD) as usize,
            "{calls}"
        );
    }

    #[test]
    fn turning_away_or_driving_on_is_not_a_stall() {
        assert_eq!(calls_to_escape(800, &[(-4, 4)], 1000), None);
        assert_eq!(calls_to_escape(800, &[(3, 3)], 1000), None);
        // Nothing ahead: standing still is the controller's choice.
        assert_eq!(calls_to_escape(100, &[(0, 0)], 1000), None);
    }

    #[test]
    fn the_turn_lasts_the_escape_time_away_from_the_nearer_side() {
        let mut escape = StallEscape::new(PERIOD);
        let mut proximity = [0u16; 8];
        proximity[1] = 900; // the left front sensor reads more: turn right
        proximity[4] = 400;
        let mut turns = Vec::new();
        for _ in 0..200 {
            if let Some(command) = escape.check(&proximity, (0, 0), 10.0) {
                turns.push(command);
            } else if !turns.is_empty() {
                break;
            }
        }
        assert_eq!(turns.len(), calls(ESCAPE_TIME, PERIOD) as usize);
        assert!(turns.iter().all(|&command| command == (10, -10)));
    }
}
