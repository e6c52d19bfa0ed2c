//! The floor-level world robots touch and their IR sensors see: the horizontal cross-sections
//! of everything standing in the slab between the floor and the robots' bodies.
//!
//! Upright boxes and cylinders keep their exact rectangles and circles; any other primitive
//! is represented by its bounding rectangle (a documented approximation). Floors — primitives
//! whose top is at or below the floor the robots stand on — are not obstacles.

use glam::DVec2;

pub use crate::geometry::Footprint;

use crate::compile::graph::{Owner, RenderGraph, Shape};
use crate::compile::rig::SensorRig;

/// Something a robot can touch or sense.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    pub shape: Footprint,
    /// Vertical extent (m).
    pub y0: f64,
    pub y1: f64,
    pub ir_reflectance: f64,
    /// The primitive it comes from.
    pub primitive: usize,
}

/// The static obstacles of a world.
#[derive(Clone, Debug, Default)]
pub struct Slab {
    pub obstacles: Vec<Obstacle>,
    /// Per robot: its body's IR reflectance (from its largest attached cylinder).
    pub robot_reflectance: Vec<f64>,
    /// Per robot: its body's height and radius (its rig's), side by side: every proximity
    /// sensor tests the robots near it against them, and a crowd's rigs are large and cold.
    pub robot_bodies: Vec<RobotBody>,
}

/// A robot's body as proximity sensors see it: an upright cylinder on its floor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RobotBody {
    pub height: f64,
    pub radius: f64,
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
            // Upright boxes and cylinders keep their exact cross-section.
            let exact = if primitive.upright {
                primitive.shape.footprint(&primitive.frame).map(|(f, _)| f)
            } else {
                None
            };
            let shape = exact.unwrap_or_else(|| {
                let center = DVec2::new(
                    (bounds.min.x + bounds.max.x) * 0.5,
                    (bounds.min.z + bounds.max.z) * 0.5,
                );
                Footprint::Rect {
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
        // Each robot's largest cylinder (the first of equal radii), in one pass over the
        // primitives: a swarm has many robots and many primitives.
        let mut largest = vec![(0.0, 1.0); rig.robots.len()];
        for p in &graph.primitives {
            let (Owner::Robot(robot), Shape::Cylinder { radius, .. }) = (p.owner, &p.shape) else {
                continue;
            };
            if let Some(best) = largest.get_mut(robot) {
                if *radius > best.0 {
                    *best = (*radius, graph.materials[p.material].ir_reflectance);
                }
            }
        }
        let robot_reflectance = largest.into_iter().map(|(_, r)| r).collect();
        Slab {
            obstacles,
            robot_reflectance,
            robot_bodies: rig
                .robots
                .iter()
                .map(|r| RobotBody {
                    height: r.body_height,
                    radius: r.body_radius,
                })
                .collect(),
        }
    }
}
