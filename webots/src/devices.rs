//! A robot's devices as a Webots controller sees them: names, kinds, Webots' parameters, and
//! where in regatta's simulation each reads or acts.
//!
//! A generic Webots `Robot` lists its device nodes in the order of the tree, as Webots does
//! (`wb_robot_get_device_by_index`): distance and light sensors and cameras read what the
//! runtime senses for them (by name), the motors and position sensors of its wheel hinges
//! drive and measure the wheels of the drive the compiler inferred, and the GPS and LEDs are
//! this room's own. A `DifferentialWheels` robot (regatta's stand-ins for the E-puck, the
//! Kheperas, the Thymio) has no motor nodes: its drive appears as Webots' two wheel motors with
//! their position sensors (`left wheel motor`, `right wheel motor`, `left wheel sensor`,
//! `right wheel sensor`, the names of Webots' own models), then its sensors.

use glam::DVec3;
use regatta_runtime::compile::frames::local_frame;
use regatta_runtime::compile::rig::RobotRig;
use regatta_runtime::geometry::Frame;
use regatta_schema::{NodeId, Scene};

use crate::protocol::kind;

/// Where a device reads or acts in the simulation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Source {
    /// A wheel's motor: on the left side or the right, and the sign that makes a positive
    /// velocity roll forward.
    Wheel {
        left: bool,
        sign: f64,
    },
    /// A wheel's position sensor (its angle from the distance the side rolled).
    WheelAngle {
        left: bool,
        sign: f64,
    },
    /// A motor regatta does not simulate (an arm's, a gripper's): commands are accepted.
    Inert,
    /// A reading that never changes (the angle of a rigid hinge).
    Fixed(f64),
    /// Index into the rig's distance sensors (a stand-in's, read in the floor-level world).
    Distance(usize),
    /// A generic robot's distance sensor, cast in 3-D ([`crate::rays`]).
    Ray(crate::rays::RaySensor),
    /// Index into the rig's light sensors.
    Light(usize),
    /// Index into the rig's cameras.
    Camera(usize),
    /// The device's position in the robot's frame (regatta's: x forward, y up).
    Gps(DVec3),
    /// An inertial unit or a compass: its rotation relative to the robot node, in the file's
    /// axes.
    InertialUnit(glam::DMat3),
    Compass(glam::DMat3),
    /// An accelerometer: its rotation relative to the robot node (file axes) and its position
    /// in the robot's frame (regatta's), whose motion it reads.
    Accelerometer(glam::DMat3, DVec3),
    /// A gyro: its rotation relative to the robot node (file axes).
    Gyro(glam::DMat3),
    /// An emitter or a receiver, at its position in the robot's frame.
    Emitter(DVec3),
    Receiver(DVec3),
    Led,
}

/// One device.
#[derive(Clone, Debug, PartialEq)]
pub struct Device {
    pub kind: u8,
    pub name: String,
    pub model: String,
    /// Kind-specific parameters, in the order the C library reads them:
    /// - rotational motor: max velocity (rad/s), min and max position (rad; 0 and 0: none),
    ///   max torque, the tag of its position sensor (0: none);
    /// - position sensor: the tag of its motor (0: none);
    /// - distance sensor: type (0 generic, 1 infra-red, 2 sonar, 3 laser), min and max value,
    ///   aperture (rad);
    /// - camera: width, height, field of view (rad), near (m);
    /// - LED: gradual (0 or 1), number of colours;
    /// - emitter and receiver: medium (0 radio, 1 serial, 2 infra-red), channel, range (m;
    ///   −1 unlimited), buffer size (bytes; −1 unlimited), max range, aperture (rad).
    pub params: Vec<f64>,
    /// Lookup table rows (input, value, relative noise), as Webots returns them.
    pub table: Vec<[f64; 3]>,
    /// Webots' `resolution` of the readings (≤ 0: infinite).
    pub resolution: f64,
    pub source: Source,
}

/// Every device of a robot, in tag order; `scene` is the typed world the rig was compiled
/// from (its device nodes beyond what the runtime senses are read there).
pub fn devices(scene: &Scene, rig: &RobotRig) -> Vec<Device> {
    let mut devices = Vec::new();
    if scene.type_name(rig.node) != "Robot" {
        drive_devices(rig, &mut devices);
        sensor_devices(rig, &mut devices);
        let model = scene
            .node(rig.node)
            .proto_names()
            .first()
            .map(String::as_str);
        stand_in_leds(model.unwrap_or(""), &mut devices);
        stand_in_accelerometer(model.unwrap_or(""), &mut devices);
    }
    let mut walk = Walk {
        scene,
        rig,
        devices: &mut devices,
        generic: scene.type_name(rig.node) == "Robot",
    };
    for &child in scene.children(rig.node, "children") {
        walk.node(child, &Frame::IDENTITY, None, 0);
    }
    devices
}

/// The devices of a stand-in's drive (tags 1–4).
fn drive_devices(rig: &RobotRig, devices: &mut Vec<Device>) {
    // To the µrad/s, as a PROTO writes it: 0.12874 m/s on 20.5 mm wheels is the e-puck's
    // 6.28 rad/s, not 6.279999…, which a controller's own `MAX_SPEED 6.28` would exceed.
    let max_velocity = if rig.wheel_radius > 0.0 {
        libm::round(rig.max_speed / rig.wheel_radius * 1e6) / 1e6
    } else {
        0.0
    };
    for (index, (name, left)) in [("left wheel motor", true), ("right wheel motor", false)]
        .into_iter()
        .enumerate()
    {
        devices.push(Device {
            kind: kind::ROTATIONAL_MOTOR,
            name: name.to_owned(),
            model: String::new(),
            params: vec![max_velocity, 0.0, 0.0, 10.0, (index + 3) as f64],
            table: Vec::new(),
            resolution: -1.0,
            source: Source::Wheel { left, sign: 1.0 },
        });
    }
    for (index, (name, left)) in [("left wheel sensor", true), ("right wheel sensor", false)]
        .into_iter()
        .enumerate()
    {
        devices.push(Device {
            kind: kind::POSITION_SENSOR,
            name: name.to_owned(),
            model: String::new(),
            params: vec![(index + 1) as f64],
            table: Vec::new(),
            resolution: -1.0,
            source: Source::WheelAngle { left, sign: 1.0 },
        });
    }
}

/// The e-puck's accelerometer (`accelerometer`, at the body's centre, axes along the robot's,
/// ±4 g with 0.5 % noise as Webots' model gives it): Webots' own e-puck controller reads it.
fn stand_in_accelerometer(model: &str, devices: &mut Vec<Device>) {
    if !matches!(model, "E-puck" | "E-puck_enu") {
        return;
    }
    devices.push(Device {
        kind: kind::ACCELEROMETER,
        name: "accelerometer".to_owned(),
        model: String::new(),
        params: Vec::new(),
        table: vec![[-39.24, -39.24, 0.005], [39.24, 39.24, 0.005]],
        resolution: -1.0,
        source: Source::Accelerometer(glam::DMat3::IDENTITY, DVec3::ZERO),
    });
}

/// The LEDs of Webots' models that regatta's stand-ins leave out of their bodies (they are
/// devices only: a controller sets and reads them): the e-puck's ring `led0`–`led7`, its body
/// `led8` and front `led9`; the Khepera I's and II's `led0` and `led1`.
fn stand_in_leds(model: &str, devices: &mut Vec<Device>) {
    let count = match model {
        "E-puck" | "E-puck_enu" => 10,
        "Khepera1" | "Khepera2" => 2,
        _ => 0,
    };
    for index in 0..count {
        devices.push(Device {
            kind: kind::LED,
            name: format!("led{index}"),
            model: String::new(),
            params: vec![0.0, 1.0],
            table: Vec::new(),
            resolution: -1.0,
            source: Source::Led,
        });
    }
}

/// A stand-in's sensors, as the rig has them.
fn sensor_devices(rig: &RobotRig, devices: &mut Vec<Device>) {
    for index in 0..rig.distance_sensors.len() {
        devices.push(distance_device(rig, index, -1.0, None));
    }
    for (index, sensor) in rig.light_sensors.iter().enumerate() {
        devices.push(Device {
            kind: kind::LIGHT_SENSOR,
            name: sensor.name.clone(),
            model: String::new(),
            params: Vec::new(),
            table: sensor.lookup.to_vec(),
            resolution: -1.0,
            source: Source::Light(index),
        });
    }
    for index in 0..rig.cameras.len() {
        devices.push(camera_device(rig, index));
    }
}

fn distance_device(
    rig: &RobotRig,
    index: usize,
    resolution: f64,
    kind_name: Option<&str>,
) -> Device {
    let sensor = &rig.distance_sensors[index];
    let (low, high) = value_range(&sensor.lookup);
    let type_code = match kind_name {
        Some("infra-red") => 1.0,
        Some("sonar") => 2.0,
        Some("laser") => 3.0,
        Some(_) => 0.0,
        None if sensor.rays > 1 => 1.0,
        None => 0.0,
    };
    Device {
        kind: kind::DISTANCE_SENSOR,
        name: sensor.name.clone(),
        model: String::new(),
        params: vec![type_code, low, high, sensor.aperture],
        table: sensor.lookup.to_vec(),
        resolution,
        source: Source::Distance(index),
    }
}

fn camera_device(rig: &RobotRig, index: usize) -> Device {
    let camera = &rig.cameras[index];
    Device {
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
        resolution: -1.0,
        source: Source::Camera(index),
    }
}

/// The walk of a robot's tree for its device nodes.
struct Walk<'a> {
    scene: &'a Scene,
    rig: &'a RobotRig,
    devices: &'a mut Vec<Device>,
    /// A generic Robot lists every device here; a stand-in only those its rig lacks.
    generic: bool,
}

impl Walk<'_> {
    fn node(&mut self, node: NodeId, frame: &Frame, hinge: Option<NodeId>, depth: usize) {
        if depth > 64 {
            return;
        }
        let scene = self.scene;
        match scene.type_name(node) {
            "Transform" | "Solid" => {
                let frame = frame.then(&local_frame(scene, node));
                for &child in scene.children(node, "children") {
                    self.node(child, &frame, None, depth + 1);
                }
            }
            "Group" => {
                for &child in scene.children(node, "children") {
                    self.node(child, frame, None, depth + 1);
                }
            }
            "HingeJoint" => {
                let first = self.devices.len();
                for &device in scene.children(node, "device") {
                    self.node(device, frame, Some(node), depth + 1);
                }
                self.pair(first);
                if let Some(end) = scene.child(node, "endPoint") {
                    self.node(end, frame, None, depth + 1);
                }
            }
            "RotationalMotor" if self.generic => self.motor(node, hinge),
            "PositionSensor" if self.generic => self.position_sensor(node),
            // A stand-in's own sensors are in its rig; one the compiler left out (looking
            // down, as the e-puck's ground sensors) is cast in 3-D as a generic robot's.
            "DistanceSensor"
                if self.generic
                    || !self
                        .rig
                        .distance_sensors
                        .iter()
                        .any(|s| s.name == scene.string(node, "name")) =>
            {
                let name = scene.string(node, "name");
                let at = frame.then(&local_frame(scene, node));
                let placed = self.rig.body_to_robot.then(&at);
                // The compiler gave the rig Webots' defaults; a sensor it left out (one
                // looking down) has its own table.
                let rig = self.rig.distance_sensors.iter().find(|s| s.name == name);
                let table = rig.map_or_else(|| lookup_table(scene, node), |s| s.lookup.to_vec());
                let rays = rig.map_or(1, |s| s.rays) as u32;
                let medium = match scene.string(node, "type") {
                    "infra-red" => 1,
                    "sonar" => 2,
                    "laser" => 3,
                    _ => 0,
                };
                let own_up = if scene.up_axis == regatta_schema::UpAxis::Z {
                    DVec3::Z
                } else {
                    DVec3::Y
                };
                let (low, high) = value_range(&table);
                self.devices.push(Device {
                    kind: kind::DISTANCE_SENSOR,
                    name: name.to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params: vec![f64::from(medium), low, high, scene.float(node, "aperture")],
                    table,
                    resolution: scene.float(node, "resolution"),
                    source: Source::Ray(crate::rays::RaySensor {
                        position: placed.translation,
                        direction: placed.linear * DVec3::X,
                        up: placed.linear * own_up,
                        medium,
                        rays,
                        aperture: scene.float(node, "aperture"),
                    }),
                });
            }
            "LightSensor" if self.generic => {
                let name = scene.string(node, "name");
                let index = self.rig.light_sensors.iter().position(|s| s.name == name);
                self.devices.push(Device {
                    kind: kind::LIGHT_SENSOR,
                    name: name.to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params: Vec::new(),
                    table: lookup_table(scene, node),
                    resolution: scene.float(node, "resolution"),
                    source: index.map_or(Source::Fixed(f64::NAN), Source::Light),
                });
            }
            "Camera" if self.generic => {
                let name = scene.string(node, "name");
                if let Some(index) = self.rig.cameras.iter().position(|c| c.name == name) {
                    self.devices.push(camera_device(self.rig, index));
                }
            }
            "GPS" => {
                let at = frame.then(&local_frame(scene, node));
                let offset = self.rig.body_to_robot.then(&at).translation;
                self.devices.push(Device {
                    kind: kind::GPS,
                    name: scene.string(node, "name").to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params: Vec::new(),
                    table: Vec::new(),
                    resolution: scene.float(node, "resolution"),
                    source: Source::Gps(offset),
                });
            }
            // Devices a controller may name whose readings regatta does not simulate yet:
            // listed (so tags and indices are Webots'), read as NaN.
            "Emitter" | "Receiver" => {
                let at = frame.then(&local_frame(scene, node));
                let offset = self.rig.body_to_robot.then(&at).translation;
                let medium = match scene.string(node, "type") {
                    "serial" => 1.0,
                    "infra-red" => 2.0,
                    _ => 0.0,
                };
                let emitter = scene.type_name(node) == "Emitter";
                let (range, max_range) = if emitter {
                    (scene.float(node, "range"), scene.float(node, "maxRange"))
                } else {
                    (-1.0, -1.0)
                };
                self.devices.push(Device {
                    kind: if emitter {
                        kind::EMITTER
                    } else {
                        kind::RECEIVER
                    },
                    name: scene.string(node, "name").to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params: vec![
                        medium,
                        f64::from(scene.int(node, "channel")),
                        range,
                        f64::from(scene.int(node, "bufferSize")),
                        max_range,
                        scene.float(node, "aperture"),
                    ],
                    table: Vec::new(),
                    resolution: -1.0,
                    source: if emitter {
                        Source::Emitter(offset)
                    } else {
                        Source::Receiver(offset)
                    },
                });
            }
            "Accelerometer" | "Gyro" | "Compass" | "InertialUnit" | "TouchSensor" => {
                let at = frame.then(&local_frame(scene, node));
                let relative = at.linear;
                let (kind, table, source) = match scene.type_name(node) {
                    "Accelerometer" => (
                        kind::ACCELEROMETER,
                        lookup_table(scene, node),
                        Source::Accelerometer(
                            relative,
                            self.rig.body_to_robot.then(&at).translation,
                        ),
                    ),
                    "Gyro" => (
                        kind::GYRO,
                        lookup_table(scene, node),
                        Source::Gyro(relative),
                    ),
                    "Compass" => (
                        kind::COMPASS,
                        lookup_table(scene, node),
                        Source::Compass(relative),
                    ),
                    "InertialUnit" => (
                        kind::INERTIAL_UNIT,
                        Vec::new(),
                        Source::InertialUnit(relative),
                    ),
                    _ => (
                        kind::TOUCH_SENSOR,
                        lookup_table(scene, node),
                        Source::Fixed(f64::NAN),
                    ),
                };
                let params = match scene.type_name(node) {
                    "InertialUnit" => vec![scene.float(node, "noise")],
                    _ => Vec::new(),
                };
                self.devices.push(Device {
                    kind,
                    name: scene.string(node, "name").to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params,
                    table,
                    resolution: scene.float(node, "resolution"),
                    source,
                });
            }
            "LED" => {
                let colors = match scene.field(node, "color") {
                    regatta_schema::Value::Vec3s(c) => c.len(),
                    _ => 1,
                };
                self.devices.push(Device {
                    kind: kind::LED,
                    name: scene.string(node, "name").to_owned(),
                    model: scene.string(node, "model").to_owned(),
                    params: vec![
                        f64::from(u8::from(scene.bool(node, "gradual"))),
                        colors as f64,
                    ],
                    table: Vec::new(),
                    resolution: -1.0,
                    source: Source::Led,
                });
            }
            _ => {}
        }
    }

    fn motor(&mut self, node: NodeId, hinge: Option<NodeId>) {
        let scene = self.scene;
        let name = scene.string(node, "name");
        let wheel = self
            .rig
            .drive
            .as_ref()
            .and_then(|d| d.wheels.iter().find(|w| hinge.is_some() && w.motor == name));
        self.devices.push(Device {
            kind: kind::ROTATIONAL_MOTOR,
            name: name.to_owned(),
            model: scene.string(node, "model").to_owned(),
            params: vec![
                scene.float(node, "maxVelocity"),
                scene.float(node, "minPosition"),
                scene.float(node, "maxPosition"),
                scene.float(node, "maxTorque"),
                0.0,
            ],
            table: Vec::new(),
            resolution: -1.0,
            source: match wheel {
                Some(w) => Source::Wheel {
                    left: w.left,
                    sign: w.sign,
                },
                None => Source::Inert,
            },
        });
    }

    fn position_sensor(&mut self, node: NodeId) {
        let scene = self.scene;
        let name = scene.string(node, "name");
        let wheel = self.rig.drive.as_ref().and_then(|d| {
            d.wheels
                .iter()
                .find(|w| !w.sensor.is_empty() && w.sensor == name)
        });
        self.devices.push(Device {
            kind: kind::POSITION_SENSOR,
            name: name.to_owned(),
            model: scene.string(node, "model").to_owned(),
            params: vec![0.0],
            table: Vec::new(),
            resolution: scene.float(node, "resolution"),
            source: match wheel {
                Some(w) => Source::WheelAngle {
                    left: w.left,
                    sign: w.sign,
                },
                None => Source::Fixed(0.0),
            },
        });
    }

    /// A hinge's motor and position sensor name each other.
    fn pair(&mut self, first: usize) {
        let slice = &self.devices[first..];
        let motor = slice.iter().position(|d| d.kind == kind::ROTATIONAL_MOTOR);
        let sensor = slice.iter().position(|d| d.kind == kind::POSITION_SENSOR);
        if let (Some(m), Some(s)) = (motor, sensor) {
            self.devices[first + m].params[4] = (first + s + 1) as f64;
            self.devices[first + s].params[0] = (first + m + 1) as f64;
        }
    }
}

fn lookup_table(scene: &Scene, node: NodeId) -> Vec<[f64; 3]> {
    match scene.field(node, "lookupTable") {
        regatta_schema::Value::Vec3s(rows) => rows.clone(),
        _ => Vec::new(),
    }
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

/// The world's north in its file's axes: +x for NUE (and y-up worlds), +y for ENU (and
/// z-up worlds), +z for EUN.
pub fn north_of(scene: &regatta_schema::Scene) -> glam::DVec3 {
    let written = scene
        .roots
        .iter()
        .find(|&&n| scene.type_name(n) == "WorldInfo")
        .map(|&n| scene.string(n, "coordinateSystem").to_owned())
        .unwrap_or_default();
    north_for(&written, scene.up_axis == regatta_schema::UpAxis::Z)
}

/// North for a `coordinateSystem` value (empty: by the world's up axis).
pub fn north_for(system: &str, z_up: bool) -> glam::DVec3 {
    match system {
        "NUE" => glam::DVec3::X,
        "EUN" => glam::DVec3::Z,
        "ENU" => glam::DVec3::Y,
        _ if z_up => glam::DVec3::Y,
        _ => glam::DVec3::X,
    }
}

/// `WorldInfo.gravity` (m/s²; Webots' 9.81 when the world has no WorldInfo).
pub fn gravity_of(scene: &regatta_schema::Scene) -> f64 {
    scene
        .roots
        .iter()
        .find(|&&n| scene.type_name(n) == "WorldInfo")
        .map_or(9.81, |&n| scene.float(n, "gravity"))
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
        assert_eq!(with_resolution(0.0987654, -1.0), 0.0987654);
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
