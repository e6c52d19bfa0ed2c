//! A generic Webots `Robot`'s drive, inferred from its wheels as Webots' tutorials and most
//! projects build them: `HingeJoint`s whose `RotationalMotor` turns a solid holding a wheel
//! (a `Cylinder` or `Sphere`) about a common horizontal axis. Two such wheels make a
//! differential drive; four, two on each side, a skid-steer drive simulated as a differential
//! one whose each side rolls at the mean of its wheels' speeds (the documented approximation:
//! no side slip). Caster wheels and any other hinge are contact only, or parts drawn in place.
//!
//! Wheel `i` turning at ω about its axis `aᵢ` rolls forward at `sᵢ·ω·R`, where the robot's
//! forward direction is `a × up` for the first wheel's axis `a` and `sᵢ = sign(aᵢ·a)`; its side
//! is left when its position along `a` is above the wheels' mean.

use glam::{DMat3, DVec3};
use regatta_schema::{NodeId, Scene};

use super::frames::local_frame;
use crate::geometry::Frame;

/// A driven wheel.
#[derive(Clone, Debug, PartialEq)]
pub struct Wheel {
    /// The motor's and position sensor's device names (empty when there is none).
    pub motor: String,
    pub sensor: String,
    /// The motor's `maxVelocity` (rad/s).
    pub max_velocity: f64,
    /// +1 or −1: the sign that turns a positive motor velocity into forward rolling.
    pub sign: f64,
    pub left: bool,
    pub radius: f64,
}

/// What was inferred of a generic robot's drive.
#[derive(Clone, Debug, PartialEq)]
pub struct Drive {
    pub wheels: Vec<Wheel>,
    pub wheel_radius: f64,
    pub axle_length: f64,
    /// The slowest wheel's top rim speed (m/s).
    pub max_speed: f64,
    /// The robot's forward direction, in its body's frame.
    pub forward: DVec3,
    /// What `explain` says of it.
    pub summary: String,
}

/// A wheel candidate: hinge axis and wheel centre in the robot's body frame.
struct Candidate {
    axis: DVec3,
    centre: DVec3,
    wheel: Wheel,
}

/// The drive of the generic robot `robot`, whose body has `up` as its up direction; `None`
/// when it has no pair of driven wheels about one axis.
pub fn infer(scene: &Scene, robot: NodeId, up: DVec3) -> Option<Drive> {
    let mut candidates = Vec::new();
    for &child in scene.children(robot, "children") {
        collect(scene, child, &Frame::IDENTITY, &mut candidates, 0);
    }
    // Horizontal axes only.
    candidates.retain(|c| c.axis.dot(up).abs() < 0.1 && c.wheel.radius > 0.0);
    let first = candidates.first()?;
    let axis = (first.axis - up * first.axis.dot(up)).normalize_or_zero();
    if axis == DVec3::ZERO {
        return None;
    }
    // Wheels about the same axis (parallel or opposed).
    candidates.retain(|c| c.axis.normalize_or_zero().dot(axis).abs() > 0.99);
    if candidates.len() < 2 {
        return None;
    }
    let lateral: Vec<f64> = candidates.iter().map(|c| c.centre.dot(axis)).collect();
    let middle = lateral.iter().sum::<f64>() / lateral.len() as f64;
    let mut wheels = Vec::new();
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for (candidate, &side) in candidates.iter().zip(&lateral) {
        let mut wheel = candidate.wheel.clone();
        wheel.sign = if candidate.axis.dot(axis) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        wheel.left = side > middle;
        if wheel.left {
            left.push(side);
        } else {
            right.push(side);
        }
        wheels.push(wheel);
    }
    if left.is_empty() || right.is_empty() {
        return None;
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let axle_length = mean(&left) - mean(&right);
    let wheel_radius = wheels.iter().map(|w| w.radius).sum::<f64>() / wheels.len() as f64;
    let max_speed = wheels
        .iter()
        .map(|w| w.max_velocity * w.radius)
        .fold(f64::INFINITY, f64::min);
    let forward = axis.cross(up).normalize_or_zero();
    let kind = if wheels.len() == 2 {
        "differential drive"
    } else {
        "skid-steer drive (each side at the mean of its wheels: no side slip)"
    };
    let summary = format!(
        "{kind} inferred from {} wheel hinges: wheel radius {wheel_radius:.4} m, axle {axle_length:.4} m, top speed {max_speed:.3} m/s; left {}; right {}",
        wheels.len(),
        names(wheels.iter().filter(|w| w.left)),
        names(wheels.iter().filter(|w| !w.left)),
    );
    Some(Drive {
        wheels,
        wheel_radius,
        axle_length,
        max_speed,
        forward,
        summary,
    })
}

fn names<'a>(wheels: impl Iterator<Item = &'a Wheel>) -> String {
    let names: Vec<String> = wheels
        .map(|w| {
            if w.motor.is_empty() {
                "(unnamed motor)".to_owned()
            } else {
                format!("\"{}\"", w.motor)
            }
        })
        .collect();
    names.join(", ")
}

/// The rotation from regatta's robot frame (x forward, y up) to a body frame whose robot
/// looks along `forward` with `up` up.
pub fn body_rotation(forward: DVec3, up: DVec3) -> Frame {
    let x = forward.normalize_or(DVec3::X);
    let y = up.normalize_or(DVec3::Y);
    Frame {
        linear: DMat3::from_cols(x, y, x.cross(y)),
        translation: DVec3::ZERO,
    }
}

/// The hinges with a motor under `node` (through groups and solids, not into other joints).
fn collect(scene: &Scene, node: NodeId, frame: &Frame, out: &mut Vec<Candidate>, depth: usize) {
    if depth > 64 {
        return;
    }
    match scene.type_name(node) {
        "Transform" | "Solid" => {
            let local = local_frame(scene, node);
            let frame = frame.then(&local);
            for &child in scene.children(node, "children") {
                collect(scene, child, &frame, out, depth + 1);
            }
        }
        "Group" => {
            for &child in scene.children(node, "children") {
                collect(scene, child, frame, out, depth + 1);
            }
        }
        "HingeJoint" => {
            if let Some(candidate) = hinge(scene, node, frame) {
                out.push(candidate);
            }
        }
        _ => {}
    }
}

fn hinge(scene: &Scene, node: NodeId, frame: &Frame) -> Option<Candidate> {
    let mut motor = None;
    let mut sensor = String::new();
    for &device in scene.children(node, "device") {
        match scene.type_name(device) {
            "RotationalMotor" => {
                motor = Some((
                    scene.string(device, "name").to_owned(),
                    scene.float(device, "maxVelocity"),
                ))
            }
            "PositionSensor" => sensor = scene.string(device, "name").to_owned(),
            _ => {}
        }
    }
    let (motor, max_velocity) = motor?;
    let axis = match scene.child(node, "jointParameters") {
        Some(parameters) => DVec3::from_array(scene.vec3(parameters, "axis")),
        None => DVec3::X,
    };
    let end = scene.child(node, "endPoint")?;
    let end_frame = frame.then(&local_frame(scene, end));
    let radius = wheel_radius(scene, end, 0)?;
    Some(Candidate {
        axis: frame.apply_vector(axis),
        centre: end_frame.translation,
        wheel: Wheel {
            motor,
            sensor,
            max_velocity,
            sign: 1.0,
            left: false,
            radius,
        },
    })
}

/// The radius of the first cylinder or sphere among a solid's shapes (or its bounding object).
fn wheel_radius(scene: &Scene, node: NodeId, depth: usize) -> Option<f64> {
    if depth > 16 {
        return None;
    }
    match scene.type_name(node) {
        "Cylinder" | "Sphere" => Some(scene.float(node, "radius")),
        "Shape" => scene
            .child(node, "geometry")
            .and_then(|g| wheel_radius(scene, g, depth + 1)),
        "Transform" | "Group" | "Solid" => {
            let mut found = scene
                .children(node, "children")
                .iter()
                .find_map(|&c| wheel_radius(scene, c, depth + 1));
            if found.is_none() && scene.type_name(node) == "Solid" {
                found = scene
                    .child(node, "boundingObject")
                    .and_then(|b| wheel_radius(scene, b, depth + 1));
            }
            found
        }
        _ => None,
    }
}
