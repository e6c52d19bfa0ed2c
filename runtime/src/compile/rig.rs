//! The sensor rig: every robot with its parameters and its devices, their mount poses in the
//! robot's frame (+x forward, +y up, −z left).

use glam::DVec3;

use crate::retina::{FilterKind, FilterSet};

/// A robot's position on the floor: x and z in metres, heading in radians counter-clockwise
/// seen from above (0 faces +x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose2 {
    pub x: f64,
    pub z: f64,
    pub heading: f64,
}

impl Pose2 {
    /// The robot's forward direction in the world.
    pub fn forward(&self) -> DVec3 {
        DVec3::new(libm::cos(self.heading), 0.0, -libm::sin(self.heading))
    }

    /// Robot-frame point to world (the robot frame's origin is on the floor at `y`).
    pub fn to_world(&self, local: DVec3, floor_y: f64) -> DVec3 {
        let (s, c) = (libm::sin(self.heading), libm::cos(self.heading));
        DVec3::new(
            self.x + c * local.x + s * local.z,
            floor_y + local.y,
            self.z - s * local.x + c * local.z,
        )
    }

    /// The robot's frame in the world: upright on the floor at height `floor_y`, turned by its
    /// heading about +y.
    pub fn frame(&self, floor_y: f64) -> crate::geometry::Frame {
        let (s, c) = (libm::sin(self.heading), libm::cos(self.heading));
        crate::geometry::Frame {
            linear: glam::DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c)),
            translation: DVec3::new(self.x, floor_y, self.z),
        }
    }

    /// The pose with its sine and cosine computed once, for many transforms.
    pub fn placement(&self, floor_y: f64) -> Placement {
        Placement {
            x: self.x,
            z: self.z,
            floor_y,
            sin: libm::sin(self.heading),
            cos: libm::cos(self.heading),
        }
    }

    /// Robot-frame direction to world.
    pub fn direction_to_world(&self, local: DVec3) -> DVec3 {
        let (s, c) = (libm::sin(self.heading), libm::cos(self.heading));
        DVec3::new(
            c * local.x + s * local.z,
            local.y,
            -s * local.x + c * local.z,
        )
    }
}

/// A pose ready to transform robot-frame points and directions to the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub x: f64,
    pub z: f64,
    pub floor_y: f64,
    pub sin: f64,
    pub cos: f64,
}

impl Placement {
    pub fn to_world(&self, local: DVec3) -> DVec3 {
        DVec3::new(
            self.x + self.cos * local.x + self.sin * local.z,
            self.floor_y + local.y,
            self.z - self.sin * local.x + self.cos * local.z,
        )
    }

    pub fn direction_to_world(&self, local: DVec3) -> DVec3 {
        DVec3::new(
            self.cos * local.x + self.sin * local.z,
            local.y,
            -self.sin * local.x + self.cos * local.z,
        )
    }
}

/// An infra-red proximity sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceSensorRig {
    pub name: String,
    pub position: DVec3,
    pub direction: DVec3,
    /// Rows (distance m, value, relative noise), distances increasing.
    pub lookup: Vec<[f64; 3]>,
    pub rays: usize,
    pub aperture: f64,
    pub range: f64,
    pub period: f64,
    /// (offset angle, cos, sin) of each ray, spread evenly over the aperture.
    pub ray_turns: Vec<(f64, f64, f64)>,
}

impl DistanceSensorRig {
    /// The rays' turns for `rays` rays over `aperture` (extreme rays at ±aperture/2).
    pub fn turns(rays: usize, aperture: f64) -> Vec<(f64, f64, f64)> {
        let rays = rays.max(1);
        (0..rays)
            .map(|i| {
                let offset = if rays == 1 {
                    0.0
                } else {
                    -0.5 * aperture + aperture * i as f64 / (rays - 1) as f64
                };
                (offset, libm::cos(offset), libm::sin(offset))
            })
            .collect()
    }
}

/// An ambient light sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSensorRig {
    pub name: String,
    pub position: DVec3,
    pub direction: DVec3,
    pub lookup: Vec<[f64; 3]>,
    pub occlusion: bool,
    pub period: f64,
}

/// How the retina's optics are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Optics {
    /// Two 75×7 flat views warped to the cylinder (1999).
    Paper,
    /// Each photodiode's window integrated.
    Exact,
}

/// The Panoramic turret's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PanoramicRig {
    pub name: String,
    pub height: f64,
    pub optics: Optics,
    pub samples: usize,
    /// Exact optics: pixels between evaluated columns in edge-free runs (1 = every pixel).
    pub stride: usize,
    pub filters: FilterSet,
    pub lambda: f64,
    pub bandpass: (f64, f64),
    pub bits: u32,
    /// `None`: calibrated so that one lit photodiode barely saturates.
    pub i_bda: Option<f64>,
    pub roi: (usize, usize),
    pub quantize_views: bool,
    pub period: f64,
}

/// The K213 linear camera's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearCameraRig {
    pub name: String,
    pub height: f64,
    pub pixels: usize,
    pub field_of_view: f64,
    pub vertical_field_of_view: f64,
    pub samples: usize,
    pub bits: u32,
    pub period: f64,
}

/// The turret on top of a robot.
#[derive(Clone, Debug, PartialEq)]
pub enum TurretRig {
    Panoramic(PanoramicRig),
    Linear(LinearCameraRig),
}

/// One robot.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotRig {
    pub name: String,
    pub node: regatta_schema::NodeId,
    pub start: Pose2,
    /// Height of the floor the robot stands on.
    pub floor_y: f64,
    pub wheel_radius: f64,
    pub axle_length: f64,
    pub encoder_resolution: f64,
    pub max_speed: f64,
    pub wheel_speed_noise: f64,
    pub body_radius: f64,
    pub body_height: f64,
    pub controller: String,
    pub controller_args: Vec<String>,
    /// Horizontal extents (x0, z0, x1, z1) of the floors the robot starts on; leaving all of
    /// them is falling off the world. Empty: no floor under it, nothing is checked.
    pub floors: Vec<[f64; 4]>,
    /// The `network` field's NeuralNetwork, read and checked (`None`: the field is NULL).
    pub network: Option<Result<crate::neural::NetworkSpec, crate::neural::NetworkError>>,
    pub distance_sensors: Vec<DistanceSensorRig>,
    pub light_sensors: Vec<LightSensorRig>,
    pub turret: Option<TurretRig>,
}

/// Every robot of the world, in the order they appear in the file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensorRig {
    pub robots: Vec<RobotRig>,
}

impl SensorRig {
    /// Whether any robot carries a vision device (and so anything must be rendered).
    pub fn has_vision(&self) -> bool {
        self.robots.iter().any(|r| r.turret.is_some())
    }

    pub fn robot(&self, name: &str) -> Option<usize> {
        self.robots.iter().position(|r| r.name == name)
    }
}

/// The filter a world names.
pub(crate) fn filter_kind(name: &str) -> Option<FilterKind> {
    Some(match name {
        "raw" => FilterKind::Raw,
        "lowpass" => FilterKind::Lowpass,
        "highpass" => FilterKind::Highpass,
        "bandpass" => FilterKind::Bandpass,
        "odd" => FilterKind::Odd,
        _ => return None,
    })
}

/// Filters named in a world's `filters` field.
pub(crate) fn filter_set(names: &[String]) -> FilterSet {
    let mut set = FilterSet::default();
    for kind in names.iter().filter_map(|name| filter_kind(name)) {
        set.insert(kind);
    }
    set
}
