//! The sensor rig: every robot with its parameters and its devices, their mount poses in the
//! robot's frame (+x forward, +y up, −z left).

use std::sync::Arc;

use glam::DVec3;

use super::network::{NetworkError, NetworkSpec};
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
        self.frame_turned(floor_y, libm::sincos(self.heading))
    }

    /// [`Pose2::frame`] from the heading's sine and cosine, worked out by the caller.
    pub fn frame_turned(&self, floor_y: f64, (s, c): (f64, f64)) -> crate::geometry::Frame {
        crate::geometry::Frame {
            linear: glam::DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c)),
            translation: DVec3::new(self.x, floor_y, self.z),
        }
    }

    /// The pose with its sine and cosine computed once, for many transforms (by one
    /// `sincos`: one argument reduction, `sin`'s and `cos`'s bits).
    pub fn placement(&self, floor_y: f64) -> Placement {
        let (sin, cos) = libm::sincos(self.heading);
        Placement {
            x: self.x,
            z: self.z,
            floor_y,
            sin,
            cos,
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
    /// Rows (distance m, value, relative noise), distances increasing (shared by the
    /// sensors whose tables are the same, as a swarm's are).
    pub lookup: Arc<[[f64; 3]]>,
    pub rays: usize,
    pub aperture: f64,
    pub range: f64,
    pub period: f64,
    /// (offset angle, cos, sin) of each ray, spread evenly over the aperture (shared like
    /// `lookup`).
    pub ray_turns: Arc<[(f64, f64, f64)]>,
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

/// How a point or spot light's attenuation 1 / (a₀ + a₁d + a₂d²) is bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attenuation {
    /// VRML97 4.14.5: never above 1 (the divisor is at least 1), for rendering and regatta's
    /// own ambient light model.
    Vrml97,
    /// Webots' LightSensor irradiance: the divisor as it is, so that a sensor near a bulb
    /// reads more than the bulb's intensity (Webots advises 0 0 4π for a real source).
    Unbounded,
}

/// An ambient light sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSensorRig {
    pub name: String,
    pub position: DVec3,
    pub direction: DVec3,
    /// Rows (irradiance, value, relative noise), shared like [`DistanceSensorRig::lookup`].
    pub lookup: Arc<[[f64; 3]]>,
    pub occlusion: bool,
    pub period: f64,
    /// How lights' attenuation is bounded: Webots' formula (unbounded) in files of Webots
    /// R2022a and later, VRML97's elsewhere (regatta's worlds, whose ambient model uses it).
    pub attenuation: Attenuation,
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
    /// Exact optics: other robots farther than this (m) are not drawn (infinite: all are).
    pub crowd_distance: f64,
    /// Exact optics with a crowd distance: small static objects wholly farther than this (m)
    /// are left out (infinite: none are).
    pub far_distance: f64,
    /// Exact optics with a crowd distance: impostors are worked out again once the eye has
    /// moved this far (m) since they last were (0: on every update).
    pub keep_distance: f64,
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

/// A 2-D colour camera (Webots' `Camera` of more than one row: the e-puck's 52×39): a planar
/// projection rendered by the ray caster.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraRig {
    pub name: String,
    /// The camera in the robot's frame: it looks along its +x, +y is up in the image and +z
    /// to the right (the robot frame's convention).
    pub frame: crate::geometry::Frame,
    pub width: usize,
    pub height: usize,
    /// Horizontal field of view (rad); pixels are square.
    pub field_of_view: f64,
    /// Nothing nearer than this along a pixel's ray is seen (m).
    pub near: f64,
    /// Nothing farther is seen (m); 0 is no limit.
    pub far: f64,
    /// Gaussian noise of each colour channel, as a fraction of full scale.
    pub noise: f64,
    pub period: f64,
    /// Which renderer draws it.
    pub renderer: CameraRenderer,
}

/// How a 2-D camera is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraRenderer {
    /// The CPU rasteriser (`render/raster`): the default since per-pixel ray casting made a
    /// 640×480 camera cost ~250 ms a frame. Lighting per vertex, shadows by ray.
    #[default]
    Raster,
    /// Per-pixel ray casting: the reference the rasteriser is measured against
    /// (`rendering "rays"`).
    Rays,
}

impl CameraRenderer {
    pub fn name(self) -> &'static str {
        match self {
            CameraRenderer::Raster => "rasterised",
            CameraRenderer::Rays => "ray cast",
        }
    }
}

impl CameraRig {
    /// Tangent of half the vertical field of view.
    pub fn tan_half_vertical(&self) -> f64 {
        libm::tan(self.field_of_view / 2.0) * self.height as f64 / self.width as f64
    }

    /// The direction of pixel (column, row)'s centre in the camera's frame (row 0 at the top,
    /// column 0 at the left), not normalised.
    pub fn pixel_direction(&self, column: usize, row: usize) -> DVec3 {
        let tan_h = libm::tan(self.field_of_view / 2.0);
        self.direction_with(column, row, tan_h, self.tan_half_vertical())
    }

    /// [`CameraRig::pixel_direction`] of every pixel, row by row, the top row first (the
    /// tangents computed once).
    pub fn pixel_directions(&self) -> impl Iterator<Item = DVec3> + '_ {
        let tan_h = libm::tan(self.field_of_view / 2.0);
        let tan_v = self.tan_half_vertical();
        (0..self.height).flat_map(move |row| {
            (0..self.width).map(move |column| self.direction_with(column, row, tan_h, tan_v))
        })
    }

    fn direction_with(&self, column: usize, row: usize, tan_h: f64, tan_v: f64) -> DVec3 {
        let right = (2.0 * (column as f64 + 0.5) / self.width as f64 - 1.0) * tan_h;
        let up = (1.0 - 2.0 * (row as f64 + 0.5) / self.height as f64) * tan_v;
        DVec3::new(1.0, up, right)
    }

    /// The steepest tan-elevation (in the robot's frame) any pixel's ray can have: the band
    /// of heights the camera can see at a distance.
    pub fn tan_half_band(&self) -> f64 {
        let mut steepest: f64 = 0.0;
        for (column, row) in [
            (0, 0),
            (self.width - 1, 0),
            (0, self.height - 1),
            (self.width - 1, self.height - 1),
        ] {
            // The extreme rays pass through the image's corners, not the corner pixels' centres.
            let mut d = self.pixel_direction(column, row);
            d.y *= self.height as f64 / (self.height as f64 - 1.0).max(1.0);
            d.z *= self.width as f64 / (self.width as f64 - 1.0).max(1.0);
            let d = self.frame.linear * d;
            let horizontal = (d.x * d.x + d.z * d.z).sqrt();
            steepest = steepest.max(if horizontal > 0.0 {
                d.y.abs() / horizontal
            } else {
                f64::INFINITY
            });
        }
        steepest
    }
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
    /// Physics steps between controller calls (at least 1), and the period they make (s):
    /// the `controlPeriod` field, or the Khepera's cycle rounded up to whole steps.
    pub control_steps: u64,
    pub control_period: f64,
    pub body_radius: f64,
    pub body_height: f64,
    pub controller: String,
    pub controller_args: Vec<String>,
    /// The program of the world's project that drives it instead of a built-in controller
    /// (a Webots controller, as `NAME (C)`), which summaries name; `controller` is then `none`.
    pub program: Option<String>,
    /// Horizontal extents (x0, z0, x1, z1) of the floors the robot starts on; leaving all of
    /// them is falling off the world. Empty: no floor under it, nothing is checked.
    pub floors: Vec<[f64; 4]>,
    /// A generic Webots robot's drive, inferred from its wheel hinges (`None` for a
    /// DifferentialWheels robot, whose fields give it, and for a robot without one).
    pub drive: Option<super::drive::Drive>,
    /// The rotation from the robot node's own (body) frame to regatta's robot frame (x
    /// forward, y up): where a room of its own places the robot's parts.
    pub body_to_robot: crate::geometry::Frame,
    /// The `network` field's NeuralNetwork, read and checked (`None`: the field is NULL).
    pub network: Option<Result<NetworkSpec, NetworkError>>,
    /// Shared by the robots whose sensors are equal (a swarm's robots of one PROTO); change
    /// them through `Arc::make_mut`.
    pub distance_sensors: Arc<Vec<DistanceSensorRig>>,
    pub light_sensors: Arc<Vec<LightSensorRig>>,
    pub turret: Option<TurretRig>,
    /// 2-D cameras, in the order the robot carries them.
    pub cameras: Vec<CameraRig>,
}

/// The Khepera's control cycle (s): what `controlPeriod 0` asks for, rounded up to a whole
/// number of physics steps. At the default `basicTimeStep 32` it is one step, as before
/// controllers had a period of their own.
pub const DEFAULT_CONTROL_PERIOD: f64 = 0.032;

/// Physics steps per control period for a `controlPeriod` field of `period_ms` (0: the
/// default cycle) at a step of `time_step` seconds; `Err` with the ratio when the period is
/// not a whole, positive number of steps.
pub fn control_steps(period_ms: f64, time_step: f64) -> Result<u64, f64> {
    if !(time_step > 0.0 && time_step.is_finite() && period_ms.is_finite()) {
        return Err(f64::NAN);
    }
    if period_ms <= 0.0 {
        // Rounded up, with a tolerance for steps written in decimal (0.1 ms).
        let steps = libm::ceil(DEFAULT_CONTROL_PERIOD / time_step - 1e-6).max(1.0);
        return Ok(steps.min(u32::MAX as f64) as u64);
    }
    let ratio = period_ms / 1000.0 / time_step;
    let steps = libm::round(ratio);
    if steps < 1.0 || (ratio - steps).abs() > 1e-6 * steps || steps > u32::MAX as f64 {
        return Err(ratio);
    }
    Ok(steps as u64)
}

/// Every robot of the world, in the order they appear in the file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensorRig {
    pub robots: Vec<RobotRig>,
}

impl SensorRig {
    /// Whether any robot carries a vision device (and so anything must be rendered).
    pub fn has_vision(&self) -> bool {
        self.robots
            .iter()
            .any(|r| r.turret.is_some() || !r.cameras.is_empty())
    }

    /// Whether any robot carries a 2-D camera (which the ray caster renders).
    pub fn has_cameras(&self) -> bool {
        self.robots.iter().any(|r| !r.cameras.is_empty())
    }

    pub fn robot(&self, name: &str) -> Option<usize> {
        self.robots.iter().position(|r| r.name == name)
    }
}

/// The distinct sets of distance and light sensors read so far: a robot whose set equals
/// one of them shares it (a swarm's 1000 Kheperas keep one copy, 1.9 MB less).
#[derive(Default)]
pub(crate) struct SharedSensors {
    distance: Vec<Arc<Vec<DistanceSensorRig>>>,
    light: Vec<Arc<Vec<LightSensorRig>>>,
}

impl SharedSensors {
    /// Points `robot`'s sensors at an equal set read before, or keeps them as a new one.
    pub(crate) fn share(&mut self, robot: &mut RobotRig) {
        fn share<T: PartialEq>(kept: &mut Vec<Arc<Vec<T>>>, sensors: &mut Arc<Vec<T>>) {
            match kept.iter().find(|k| **k == *sensors) {
                Some(equal) => *sensors = equal.clone(),
                None => kept.push(sensors.clone()),
            }
        }
        share(&mut self.distance, &mut robot.distance_sensors);
        share(&mut self.light, &mut robot.light_sensors);
    }
}

/// Filters named in a world's `filters` field.
pub(crate) fn filter_set(names: &[String]) -> FilterSet {
    let mut set = FilterSet::default();
    for kind in names.iter().filter_map(|name| FilterKind::from_name(name)) {
        set.insert(kind);
    }
    set
}
