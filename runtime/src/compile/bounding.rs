//! The extent of a Webots `boundingObject`: the geometry a solid collides with, which may be
//! smaller than what it shows. Primitives (Box, Cylinder, Cone, Sphere, Capsule), a Shape's
//! geometry, and Transform, Pose and Group nodes placing them; anything else (a mesh) adds
//! nothing.

use glam::DVec3;
use regatta_schema::{NodeId, Scene};

use super::frames::local_frame;
use crate::geometry::{Aabb, Frame};

/// Nesting followed at most (a world's own nesting limit is checked when it is read).
const DEPTH: usize = 64;

/// The bounds of `node` (a bounding object) in the frame `frame` maps its coordinates to;
/// [`Aabb::EMPTY`] when it holds nothing this reads.
pub(super) fn bounds(scene: &Scene, node: NodeId, frame: &Frame) -> Aabb {
    walk(scene, node, frame, 0)
}

fn walk(scene: &Scene, node: NodeId, frame: &Frame, depth: usize) -> Aabb {
    if depth > DEPTH {
        return Aabb::EMPTY;
    }
    let half = match scene.type_name(node) {
        "Box" => DVec3::from_array(scene.vec3(node, "size")) * 0.5,
        "Cylinder" => {
            let r = scene.float(node, "radius");
            DVec3::new(r, scene.float(node, "height") / 2.0, r)
        }
        "Cone" => {
            let r = scene.float(node, "bottomRadius");
            DVec3::new(r, scene.float(node, "height") / 2.0, r)
        }
        "Sphere" => DVec3::splat(scene.float(node, "radius")),
        "Capsule" => {
            let r = scene.float(node, "radius");
            DVec3::new(r, scene.float(node, "height") / 2.0 + r, r)
        }
        "Shape" => {
            return scene
                .child(node, "geometry")
                .map_or(Aabb::EMPTY, |g| walk(scene, g, frame, depth + 1));
        }
        "Transform" | "Pose" | "Group" => {
            let inner = if scene.type_name(node) == "Group" {
                *frame
            } else {
                frame.then(&local_frame(scene, node))
            };
            return scene
                .children(node, "children")
                .iter()
                .fold(Aabb::EMPTY, |b, &c| {
                    b.union(walk(scene, c, &inner, depth + 1))
                });
        }
        _ => return Aabb::EMPTY,
    };
    if !half.is_finite() || half.min_element() < 0.0 {
        return Aabb::EMPTY;
    }
    Aabb {
        min: -half,
        max: half,
    }
    .transformed(frame)
}
