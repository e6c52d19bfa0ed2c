//! What regatta knows of Webots beyond its node types: which `webots://` PROTOs have a
//! built-in stand-in, how Webots' axis conventions changed across versions, and which Webots
//! nodes are read but not simulated (with the reason a warning gives).
//!
//! Axis conventions (Webots' "from R2021b to R2022a" guide): a world's *up* axis follows
//! `WorldInfo.coordinateSystem` when it is written, else its header: y-up before R2020b, z-up
//! (ENU, the field's default) from R2020b. Its *objects* (robots, devices, the axes of
//! Cylinder, Cone, Capsule, Plane, ElevationGrid, Camera and Viewpoint) are FLU (x forward,
//! z up) in z-up worlds from R2022a and in the y-up convention otherwise (Webots' robots then
//! face −z). regatta's built-in PROTOs are written y-up with +x forward and are turned to the
//! world's conventions where they are placed.

/// Who wrote a node, which decides the axes its coordinates are in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Authoring {
    /// A world file, or a PROTO or Inline file it reads: the world's object convention.
    #[default]
    World,
    /// One of regatta's own PROTOs (Arena, Buoy, Khepera): y-up, +x forward; turned only in
    /// FLU worlds.
    Regatta,
    /// A stand-in for a Webots object (arena, floor, box, background): y-up; turned to FLU in
    /// FLU worlds.
    Webots,
    /// A stand-in for a Webots robot: y-up, +x forward; turned to FLU in FLU worlds and to
    /// Webots' legacy robot frame (forward −z) in the others.
    WebotsRobot,
    /// A stand-in for a PROTO that is FLU whatever the world (webots_ros2's `E-puck_enu`).
    WebotsFlu,
}

/// The axes a node's own transform and its children are written in. A PROTO instance's root
/// takes its own transform from the instance (IS fields), its children from the PROTO.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Axes {
    pub own: Authoring,
    pub body: Authoring,
}

/// The convention of a world's objects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Objects {
    /// y-up objects: VRML97, regatta's worlds, Webots before R2022a.
    #[default]
    Legacy,
    /// Webots from R2022a in a z-up world: x forward, y left, z up; Cylinder along z; cameras
    /// and viewpoints look along +x.
    Flu,
    /// Webots from R2022a in a world that declares itself y-up (`coordinateSystem "NUE"` or
    /// `"EUN"`) and its PROTOs (`EXTERNPROTO`), as Webots' own API tests do: geometry, cameras,
    /// viewpoints and Webots' PROTOs (regatta's stand-ins) are FLU as in any R2022a file, and
    /// the file turns them where it wants them; but the world's up is y, so a generic `Robot`
    /// stands with its y up and +x forward, and regatta's own PROTOs (written y-up) need no
    /// turn.
    FluYUp,
}

impl Objects {
    /// Whether geometry axes (Cylinder, Cone, Capsule, Plane, ElevationGrid), cameras and
    /// viewpoints are FLU.
    pub fn flu_geometry(self) -> bool {
        matches!(self, Objects::Flu | Objects::FluYUp)
    }
}

/// The rotation (axis, angle) that maps coordinates written by `to` into those of `from`:
/// a node written by `to` placed among nodes written by `from` is turned by it. `None` when
/// they agree.
pub fn turn(from: Authoring, to: Authoring, objects: Objects) -> Option<[f64; 4]> {
    // Each authoring's turn from world coordinates, as a rotation about one axis.
    fn from_world(a: Authoring, objects: Objects) -> Option<[f64; 4]> {
        use std::f64::consts::FRAC_PI_2;
        match (a, objects) {
            (Authoring::World, _)
            | (Authoring::Regatta | Authoring::Webots, Objects::Legacy)
            | (Authoring::Regatta, Objects::FluYUp) => None,
            (Authoring::WebotsRobot, Objects::Legacy) => Some([0.0, 1.0, 0.0, FRAC_PI_2]),
            (Authoring::Regatta | Authoring::Webots | Authoring::WebotsRobot, Objects::Flu)
            | (Authoring::Webots | Authoring::WebotsRobot, Objects::FluYUp)
            | (Authoring::WebotsFlu, _) => Some([1.0, 0.0, 0.0, FRAC_PI_2]),
        }
    }
    if from == to {
        return None;
    }
    let back = from_world(from, objects).map(|[x, y, z, a]| [x, y, z, -a]);
    let forth = from_world(to, objects);
    match (back, forth) {
        (None, None) => None,
        (Some(r), None) | (None, Some(r)) => Some(r),
        // Two different built-in kinds: through world coordinates.
        (Some(b), Some(f)) => Some(compose(b, f)),
    }
}

/// The product a·b of two axis-angle rotations (b applied first).
fn compose(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let q = |r: [f64; 4]| {
        let (s, c) = (libm::sin(r[3] / 2.0), libm::cos(r[3] / 2.0));
        [c, r[0] * s, r[1] * s, r[2] * s]
    };
    let (p, r) = (q(a), q(b));
    let w = p[0] * r[0] - p[1] * r[1] - p[2] * r[2] - p[3] * r[3];
    let x = p[0] * r[1] + p[1] * r[0] + p[2] * r[3] - p[3] * r[2];
    let y = p[0] * r[2] - p[1] * r[3] + p[2] * r[0] + p[3] * r[1];
    let z = p[0] * r[3] + p[1] * r[2] - p[2] * r[1] + p[3] * r[0];
    let s = (x * x + y * y + z * z).sqrt();
    if s < 1e-12 {
        return [0.0, 1.0, 0.0, 0.0];
    }
    [x / s, y / s, z / s, 2.0 * libm::atan2(s, w)]
}

/// The path inside a Webots installation that a PROTO url names: `webots://projects/…` and
/// `https://raw.githubusercontent.com/cyberbotics/webots/<version>/projects/…` give
/// `projects/…`. `None` for anything else.
pub fn webots_path(url: &str) -> Option<&str> {
    if let Some(rest) = url.strip_prefix("webots://") {
        return Some(rest.trim_start_matches('/'));
    }
    let rest = url
        .strip_prefix("https://raw.githubusercontent.com/cyberbotics/webots/")
        .or_else(|| url.strip_prefix("http://raw.githubusercontent.com/cyberbotics/webots/"))?;
    // Skip the version (a tag, branch or commit).
    rest.split_once('/').map(|(_, path)| path)
}

/// Webots nodes and PROTOs that regatta reads but does not simulate, with the reason.
pub fn unsimulated(name: &str) -> Option<&'static str> {
    Some(match name {
        "Hinge2Joint" | "SliderJoint" | "BallJoint" | "JointParameters" | "LinearMotor"
        | "Brake" | "Servo" => {
            "joints and motors other than a differential drive are not simulated (regatta's robots are kinematic); the parts they carry stay where the file puts them"
        }
        "Speaker" | "Microphone" | "Display" | "Pen" | "Connector" | "VacuumGripper"
        | "Altimeter" | "Lidar" | "RangeFinder" | "Radar" | "Radio" | "Charger" | "Track"
        | "Propeller" | "Muscle" | "Skin" => {
            "this Webots device is not simulated; a controller cannot read it"
        }
        "Fluid" | "ImmersionProperties" | "Damping" | "Fog" => {
            "this Webots node is not simulated by regatta"
        }
        "Pi-puck" => "the Pi-puck extension board carries no device regatta simulates",
        "Supervisor" => "a supervisor's controller is not run (regatta has no supervisor API)",
        _ => return None,
    })
}
