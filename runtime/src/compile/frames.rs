//! A node's own frame from its `translation` and `rotation` (no scale): what rooms that place
//! a robot's parts themselves (the drive's wheels, Webots' devices, a supervisor's nodes)
//! read, so that every one of them reads it the same way.

use glam::DVec3;
use regatta_schema::{NodeId, Scene};

use crate::geometry::Frame;

/// `node`'s frame in its parent: its `translation` and `rotation`.
pub fn local_frame(scene: &Scene, node: NodeId) -> Frame {
    Frame::vrml(
        DVec3::from_array(scene.vec3(node, "translation")),
        scene.rotation(node, "rotation"),
        DVec3::ONE,
        [0.0, 0.0, 1.0, 0.0],
        DVec3::ZERO,
    )
}
