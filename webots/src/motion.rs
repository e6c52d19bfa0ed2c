//! What inertial devices read from a robot's exact planar motion (and an inertial unit's
//! angles of an orientation): an accelerometer's specific
//! force (the acceleration of its point, with gravity's reaction) and a gyro's turn rate, by
//! finite differences of the poses of the last steps, so that they agree with the motion the
//! simulation made rather than with the commands.

use glam::DVec3;
use regatta_runtime::compile::rig::Pose2;
use regatta_runtime::sim::noise::Stream;
use regatta_runtime::sim::sensors::lookup;

/// The specific force (m/s², regatta's y-up world axes) at `offset` (the robot's frame) of a
/// robot whose last poses are `trail` (oldest first): the point's acceleration by second
/// differences, plus `gravity` upwards. With fewer than three poses the robot is taken as
/// having been at rest.
pub fn specific_force(
    trail: &[Pose2],
    offset: DVec3,
    floor_y: f64,
    dt: f64,
    gravity: f64,
) -> DVec3 {
    let up = DVec3::new(0.0, gravity, 0.0);
    let [a, b, c] = match trail {
        [.., a, b, c] => [a, b, c],
        _ => return up,
    };
    let point = |pose: &Pose2| pose.to_world(offset, floor_y);
    let acceleration = (point(c) - 2.0 * point(b) + point(a)) / (dt * dt);
    acceleration + up
}

/// The turn rate (rad/s, counter-clockwise seen from above) over the last step.
pub fn turn_rate(trail: &[Pose2], dt: f64) -> f64 {
    match trail {
        [.., a, b] => {
            let turned = libm::remainder(b.heading - a.heading, std::f64::consts::TAU);
            turned / dt
        }
        _ => 0.0,
    }
}

/// A vector of regatta's y-up world in a z-up file's axes (`(x, y, z)` → `(x, −z, y)`).
pub fn to_file_axes(v: DVec3, z_up: bool) -> DVec3 {
    if z_up {
        DVec3::new(v.x, -v.z, v.y)
    } else {
        v
    }
}

/// One axis of a reading through its device's lookup table (interpolated, clamped to its
/// ends, with the table's relative noise drawn from `stream`); without a table, as is.
pub fn through_table(value: f64, table: &[[f64; 3]], stream: &mut Stream) -> f64 {
    if table.len() < 2 {
        return value;
    }
    let (mean, noise) = lookup(table, value);
    if noise == 0.0 {
        stream.skip_gaussian();
        return mean;
    }
    mean * (1.0 + noise * stream.gaussian())
}

/// Webots' roll, pitch and yaw of a rotation: about x, y and z in a z-up (ENU) world
/// (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`), about x, z and y in a y-up (NUE) one
/// (`R = Ry(yaw)·Rz(pitch)·Rx(roll)`).
pub fn roll_pitch_yaw(m: glam::DMat3, z_up: bool) -> [f64; 3] {
    let at = |row: usize, column: usize| m.col(column)[row];
    if z_up {
        [
            libm::atan2(at(2, 1), at(2, 2)),
            -libm::asin(at(2, 0).clamp(-1.0, 1.0)),
            libm::atan2(at(1, 0), at(0, 0)),
        ]
    } else {
        [
            libm::atan2(-at(1, 2), at(1, 1)),
            libm::asin(at(1, 0).clamp(-1.0, 1.0)),
            libm::atan2(-at(2, 0), at(0, 0)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, z: f64, heading: f64) -> Pose2 {
        Pose2 { x, z, heading }
    }

    #[test]
    fn a_robot_at_rest_feels_gravity_alone() {
        let trail = [pose(1.0, 2.0, 0.3); 3];
        let f = specific_force(&trail, DVec3::new(0.03, 0.01, 0.0), 0.0, 0.032, 9.81);
        assert!((f - DVec3::new(0.0, 9.81, 0.0)).length() < 1e-12);
        assert_eq!(
            specific_force(&trail[..1], DVec3::ZERO, 0.0, 0.032, 9.81).y,
            9.81
        );
    }

    #[test]
    fn turning_on_the_spot_gives_the_turn_rate_and_a_centripetal_pull() {
        // 2 rad/s about the centre; a point 0.05 m ahead feels ω²r towards the centre.
        let dt = 0.001;
        let trail: Vec<Pose2> = (0..3)
            .map(|i| pose(0.0, 0.0, 2.0 * dt * i as f64))
            .collect();
        assert!((turn_rate(&trail, dt) - 2.0).abs() < 1e-9);
        let f = specific_force(&trail, DVec3::new(0.05, 0.0, 0.0), 0.0, dt, 0.0);
        assert!((f.length() - 4.0 * 0.05).abs() < 1e-3, "{f}");
        let heading = 2.0 * dt;
        let outward = DVec3::new(libm::cos(heading), 0.0, -libm::sin(heading));
        assert!(f.dot(outward) < 0.0, "towards the centre: {f}");
    }

    #[test]
    fn a_turn_across_pi_is_not_a_full_turn() {
        let trail = [pose(0.0, 0.0, 3.1), pose(0.0, 0.0, -3.1)];
        let rate = turn_rate(&trail, 0.1);
        assert!(
            (rate - (std::f64::consts::TAU - 6.2) / 0.1).abs() < 1e-9,
            "{rate}"
        );
    }

    #[test]
    fn tables_interpolate_and_clamp() {
        let table = [[-10.0, -100.0, 0.0], [10.0, 100.0, 0.0]];
        let mut stream = Stream::new(1, 0, 0, 0);
        assert_eq!(through_table(5.0, &table, &mut stream), 50.0);
        assert_eq!(through_table(50.0, &table, &mut stream), 100.0);
        assert_eq!(through_table(3.0, &[], &mut stream), 3.0);
    }
}
