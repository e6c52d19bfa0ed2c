//! A robot's devices as a Webots controller sees them: names, kinds, Webots' parameters, and
//! where in regatta's simulation each reads or acts.
//!
//! The devices come from the compiled robot (`RobotRig`): its distance and light sensors and
//! cameras under their own names, and its differential drive as Webots' two wheel motors with
//! their position sensors (`left wheel motor`, `right wheel motor`, `left wheel sensor`,
//! `right wheel sensor`: the names every Webots wheeled robot of the standard library uses).
//! Tags are indices into the table plus one, in this order, so that
//! `wb_robot_get_device_by_index` is stable.

use regatta_runtime::compile::rig::RobotRig;

use crate::protocol::kind;

/// A wheel of the differential drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

/// Where a device reads or acts in the simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Motor(Side),
    Encoder(Side),
    /// Index into the rig's distance sensors.
    Distance(usize),
    /// Index into the rig's light sensors.
    Light(usize),
    /// Index into the rig's cameras.
    Camera(usize),
}

/// One device.
#[derive(Clone, Debug, PartialEq)]
pub struct Device {
    pub kind: u8,
    pub name: String,
    pub model: String,
    /// Kind-specific parameters, in the order the C library reads them:
    /// - rotational motor: max velocity (rad/s), min and max position (rad; 0 and 0: none),
    ///   max torque, the tag of its position sensor;
    /// - position sensor: the tag of its motor;
    /// - distance sensor: type (0 generic, 1 infra-red, 2 sonar, 3 laser), min and max value,
    ///   aperture (rad);
    /// - camera: width, height, field of view (rad), near (m).
    pub params: Vec<f64>,
    /// Lookup table rows (input, value, relative noise), as Webots returns them.
    pub table: Vec<[f64; 3]>,
    pub source: Source,
}

/// Every device of a robot, in tag order.
pub fn devices(rig: &RobotRig) -> Vec<Device> {
    let mut devices = Vec::new();
    // The drive: motors first, then their sensors (tags 1–4).
    let max_velocity = if rig.wheel_radius > 0.0 {
        rig.max_speed / rig.wheel_radius
    } else {
        0.0
    };
    for (index, side) in [Side::Left, Side::Right].into_iter().enumerate() {
        let name = match side {
            Side::Left => "left wheel motor",
            Side::Right => "right wheel motor",
        };
        devices.push(Device {
            kind: kind::ROTATIONAL_MOTOR,
            name: name.to_owned(),
            model: String::new(),
            params: vec![max_velocity, 0.0, 0.0, 10.0, (index + 3) as f64],
            table: Vec::new(),
            source: Source::Motor(side),
        });
    }
    for (index, side) in [Side::Left, Side::Right].into_iter().enumerate() {
        let name = match side {
            Side::Left => "left wheel sensor",
            Side::Right => "right wheel sensor",
        };
        devices.push(Device {
            kind: kind::POSITION_SENSOR,
            name: name.to_owned(),
            model: String::new(),
            params: vec![(index + 1) as f64],
            table: Vec::new(),
            source: Source::Encoder(side),
        });
    }
    for (index, sensor) in rig.distance_sensors.iter().enumerate() {
        let (low, high) = value_range(&sensor.lookup);
        let infra_red = if sensor.rays > 1 { 1.0 } else { 0.0 };
        devices.push(Device {
            kind: kind::DISTANCE_SENSOR,
            name: sensor.name.clone(),
            model: String::new(),
            params: vec![infra_red, low, high, sensor.aperture],
            table: sensor.lookup.to_vec(),
            source: Source::Distance(index),
        });
    }
    for (index, sensor) in rig.light_sensors.iter().enumerate() {
        devices.push(Device {
            kind: kind::LIGHT_SENSOR,
            name: sensor.name.clone(),
            model: String::new(),
            params: Vec::new(),
            table: sensor.lookup.to_vec(),
            source: Source::Light(index),
        });
    }
    for (index, camera) in rig.cameras.iter().enumerate() {
        devices.push(Device {
            kind: kind::CAMERA,
            name: camera.name.clone(),
            model: String::new(),
            params: vec![
                camera.width as f64,
                camera.height as f64,
                camera.field_of_view,
                camera.near,
            ],
            table: Vec::new(),
            source: Source::Camera(index),
        });
    }
    devices
}

/// The smallest and largest value a lookup table gives.
fn value_range(table: &[[f64; 3]]) -> (f64, f64) {
    let values = table.iter().map(|row| row[1]);
    let low = values.clone().fold(f64::INFINITY, f64::min);
    let high = values.fold(f64::NEG_INFINITY, f64::max);
    if low.is_finite() {
        (low, high)
    } else {
        (0.0, 0.0)
    }
}

/// A reading with Webots' `resolution`: rounded to a multiple of it (0 or less: as is).
pub fn with_resolution(value: f64, resolution: f64) -> f64 {
    if resolution > 0.0 {
        libm::round(value / resolution) * resolution
    } else {
        value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_rounds_to_its_multiples() {
        assert_eq!(with_resolution(0.0987654, 0.0), 0.0987654);
        assert_eq!(with_resolution(123.4, 15.0), 120.0);
        assert_eq!(with_resolution(127.6, 15.0), 135.0);
    }

    #[test]
    fn a_table_gives_its_value_range() {
        assert_eq!(
            value_range(&[[0.0, 4095.0, 0.0], [0.07, 67.0, 0.0]]),
            (67.0, 4095.0)
        );
        assert_eq!(value_range(&[]), (0.0, 0.0));
    }
}
