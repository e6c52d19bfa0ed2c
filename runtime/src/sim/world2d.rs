//! The floor-level world robots touch and their IR sensors see: the horizontal cross-sections
//! of everything standing in the slab between the floor and the robots' bodies.
//!
//! Upright boxes and cylinders keep their exact rectangles and circles; any other primitive
//! is represented by its bounding rectangle (a documented approximation). Floors — primitives
//! whose top is at or below the floor the robots stand on — are not obstacles.

use glam::{DVec2, DVec3};

use crate::compile::graph::{Owner, RenderGraph, Shape};
use crate::compile::rig::SensorRig;

/// A horizontal cross-section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape2 {
    Circle {
        center: DVec2,
        radius: f64,
    },
    Rect {
        center: DVec2,
        u: DVec2,
        v: DVec2,
        half_u: f64,
        half_v: f64,
    },
}

/// Something a robot can touch or sense.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    pub shape: Shape2,
    /// Vertical extent (m).
    pub y0: f64,
    pub y1: f64,
    pub ir_reflectance: f64,
    /// The primitive it comes from.
    pub primitive: usize,
}

impl Shape2 {
    /// Distance along a unit ray to the boundary, if hit at `t ≥ 0` (from inside: 0).
    pub fn ray(&self, origin: DVec2, direction: DVec2) -> Option<f64> {
        match *self {
            Shape2::Circle { center, radius } => {
                let oc = origin - center;
                let b = oc.dot(direction);
                let c = oc.length_squared() - radius * radius;
                if c <= 0.0 {
                    return Some(0.0);
                }
                let disc = b * b - c;
                if disc < 0.0 || b > 0.0 {
                    return None;
                }
                Some(-b - disc.sqrt())
            }
            Shape2::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let oc = origin - center;
                let (pu, pv) = (oc.dot(u), oc.dot(v));
                let (du, dv) = (direction.dot(u), direction.dot(v));
                let mut t_in = f64::NEG_INFINITY;
                let mut t_out = f64::INFINITY;
                for (p, d, h) in [(pu, du, half_u), (pv, dv, half_v)] {
                    if d.abs() < 1e-300 {
                        if p.abs() > h {
                            return None;
                        }
                        continue;
                    }
                    let (a, b) = ((-h - p) / d, (h - p) / d);
                    t_in = t_in.max(a.min(b));
                    t_out = t_out.min(a.max(b));
                }
                (t_in <= t_out && t_out >= 0.0).then_some(t_in.max(0.0))
            }
        }
    }

    /// How far a circle of radius `r` at `c` reaches into the shape, and the unit direction to
    /// push it out; `None` when they do not touch.
    pub fn penetration(&self, c: DVec2, r: f64) -> Option<(f64, DVec2)> {
        match *self {
            Shape2::Circle { center, radius } => {
                let offset = c - center;
                let distance = offset.length();
                let depth = r + radius - distance;
                if depth <= 0.0 {
                    return None;
                }
                let normal = if distance > 1e-12 {
                    offset / distance
                } else {
                    DVec2::X
                };
                Some((depth, normal))
            }
            Shape2::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let offset = c - center;
                let (pu, pv) = (offset.dot(u), offset.dot(v));
                let (qu, qv) = (pu.clamp(-half_u, half_u), pv.clamp(-half_v, half_v));
                if pu.abs() <= half_u && pv.abs() <= half_v {
                    // Centre inside: out through the nearest face.
                    let (exit_u, exit_v) = (half_u - pu.abs(), half_v - pv.abs());
                    return Some(if exit_u < exit_v {
                        (exit_u + r, u * pu.signum())
                    } else {
                        (exit_v + r, v * pv.signum())
                    });
                }
                let closest = center + u * qu + v * qv;
                let away = c - closest;
                let distance = away.length();
                let depth = r - distance;
                (depth > 0.0).then(|| (depth, away / distance.max(1e-300)))
            }
        }
    }
}

/// The static obstacles of a world.
#[derive(Clone, Debug, Default)]
pub struct Slab {
    pub obstacles: Vec<Obstacle>,
    /// Per robot: its body's IR reflectance (from its largest attached cylinder).
    pub robot_reflectance: Vec<f64>,
}

impl Slab {
    pub fn new(graph: &RenderGraph, rig: &SensorRig) -> Slab {
        let floor = rig
            .robots
            .iter()
            .map(|r| r.floor_y)
            .fold(f64::INFINITY, f64::min);
        let floor = if floor.is_finite() { floor } else { 0.0 };
        let top = rig
            .robots
            .iter()
            .map(|r| {
                let sensors = r
                    .distance_sensors
                    .iter()
                    .chain(std::iter::empty())
                    .map(|s| s.position.y)
                    .fold(0.0f64, f64::max);
                r.floor_y + r.body_height.max(sensors)
            })
            .fold(floor, f64::max);
        let mut obstacles = Vec::new();
        for &index in &graph.static_primitives {
            let primitive = &graph.primitives[index];
            let bounds = primitive.bounds;
            // Floors and anything entirely above the slab are not obstacles.
            if bounds.max.y <= floor + 1e-6 || bounds.min.y >= top {
                continue;
            }
            let shape = footprint(primitive, &graph.meshes).unwrap_or_else(|| {
                let center = DVec2::new(
                    (bounds.min.x + bounds.max.x) * 0.5,
                    (bounds.min.z + bounds.max.z) * 0.5,
                );
                Shape2::Rect {
                    center,
                    u: DVec2::X,
                    v: DVec2::Y,
                    half_u: (bounds.max.x - bounds.min.x) * 0.5,
                    half_v: (bounds.max.z - bounds.min.z) * 0.5,
                }
            });
            obstacles.push(Obstacle {
                shape,
                y0: bounds.min.y,
                y1: bounds.max.y,
                ir_reflectance: graph.materials[primitive.material].ir_reflectance,
                primitive: index,
            });
        }
        let robot_reflectance = (0..rig.robots.len())
            .map(|robot| {
                graph
                    .primitives
                    .iter()
                    .filter(|p| p.owner == Owner::Robot(robot))
                    .filter_map(|p| match p.shape {
                        Shape::Cylinder { radius, .. } => {
                            Some((radius, graph.materials[p.material].ir_reflectance))
                        }
                        _ => None,
                    })
                    .fold((0.0, 1.0), |best, (radius, reflectance)| {
                        if radius > best.0 {
                            (radius, reflectance)
                        } else {
                            best
                        }
                    })
                    .1
            })
            .collect();
        Slab {
            obstacles,
            robot_reflectance,
        }
    }
}

/// The exact cross-section of an upright box or cylinder, in (x, z).
fn footprint(
    primitive: &crate::compile::graph::Primitive,
    _meshes: &[crate::compile::graph::Mesh],
) -> Option<Shape2> {
    if !primitive.upright {
        return None;
    }
    let frame = &primitive.frame;
    let center = DVec2::new(frame.translation.x, frame.translation.z);
    let x = frame.apply_vector(DVec3::X);
    let z = frame.apply_vector(DVec3::Z);
    match primitive.shape {
        Shape::Box { half } => {
            let (u, v) = (DVec2::new(x.x, x.z), DVec2::new(z.x, z.z));
            Some(Shape2::Rect {
                center,
                u: u.normalize(),
                v: v.normalize(),
                half_u: half.x * u.length(),
                half_v: half.z * v.length(),
            })
        }
        Shape::Cylinder { radius, .. } => Some(Shape2::Circle {
            center,
            radius: radius * DVec2::new(x.x, x.z).length(),
        }),
        _ => None,
    }
}
