//! Differential drive, integrated exactly over a step: with constant wheel speeds the robot
//! moves along a circular arc (a segment when the speeds are equal), so the step length
//! changes nothing but how often the controller is asked.
//!
//! The chord of an arc of heading change Δ is `v·dt·sinc(Δ/2)` along the mean heading; the
//! sinc is evaluated by its series near 0, so small turns lose no precision.

use crate::compile::rig::Pose2;

/// `sin(x)/x`, accurate near 0.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        let x2 = x * x;
        1.0 - x2 / 6.0 * (1.0 - x2 / 20.0)
    } else {
        libm::sin(x) / x
    }
}

/// Wraps a heading to (−π, π].
pub fn normalize_heading(heading: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    // `%` returns a heading already within one turn unchanged: only larger ones pay for it.
    let mut h = if heading.abs() < two_pi {
        heading
    } else {
        heading % two_pi
    };
    if h <= -std::f64::consts::PI {
        h += two_pi;
    } else if h > std::f64::consts::PI {
        h -= two_pi;
    }
    h
}

/// Moves `pose` for `dt` seconds with wheel ground speeds `left` and `right` (m/s) on an axle
/// of length `axle` (m). Heading is counter-clockwise seen from above; forward is (cos θ, −sin θ)
/// in (x, z).
pub fn advance(pose: Pose2, left: f64, right: f64, axle: f64, dt: f64) -> Pose2 {
    let v = 0.5 * (left + right);
    let delta = (right - left) / axle * dt;
    let chord = v * dt * sinc(0.5 * delta);
    let middle = pose.heading + 0.5 * delta;
    // One range reduction for both (bit for bit `sin` and `cos`: see the noise's test).
    let (sin, cos) = libm::sincos(middle);
    Pose2 {
        x: pose.x + chord * cos,
        z: pose.z - chord * sin,
        heading: normalize_heading(pose.heading + delta),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_and_turning_on_the_spot() {
        let start = Pose2 {
            x: 0.0,
            z: 0.0,
            heading: 0.0,
        };
        let moved = advance(start, 0.1, 0.1, 0.053, 1.0);
        assert!((moved.x - 0.1).abs() < 1e-15 && moved.z.abs() < 1e-15);
        let spun = advance(start, -0.01, 0.01, 0.053, 1.0);
        assert!(spun.x.abs() < 1e-15 && spun.z.abs() < 1e-15);
        assert!((spun.heading - 0.02 / 0.053).abs() < 1e-15);
    }

    #[test]
    fn left_wheel_slower_turns_left_counter_clockwise() {
        let pose = advance(
            Pose2 {
                x: 0.0,
                z: 0.0,
                heading: 0.0,
            },
            0.05,
            0.1,
            0.053,
            0.5,
        );
        assert!(pose.heading > 0.0, "counter-clockwise");
        assert!(pose.z < 0.0, "towards −z, the robot's left");
    }
}
