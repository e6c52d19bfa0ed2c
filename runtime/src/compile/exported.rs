//! What the compiler reads for exporters beyond what regatta simulates: the shapes inside
//! Webots nodes it does not simulate (joints, solid devices, Servo, Supervisor) and inside
//! devices, Webots' CadShape, and the shapes it leaves out with the reason (the export's
//! report).

use regatta_schema::NodeId;

use super::graph::{self, Material, Owner};
use super::{shapes, turned, Compiler};
use crate::geometry::Frame;

impl Compiler<'_> {
    /// A Webots node regatta does not simulate (a joint, a solid device, a Servo), or a
    /// device's children: the shapes it holds, at its transform (a joint's endPoint Solid
    /// places itself).
    pub(super) fn open_node(&mut self, node: NodeId, frame: &Frame, owner: Owner, depth: usize) {
        let scene = self.scene;
        let axes = scene.node(node).axes;
        let spec = scene.spec(node);
        let local = if spec.field_index("translation").is_some() {
            super::frames::local_frame(scene, node)
        } else {
            Frame::IDENTITY
        };
        let frame = turned(&frame.then(&local), scene.turn(axes.own, axes.body));
        let outer = self.enter_group(node, &frame, owner, None);
        for field in ["children", "endPoint"] {
            if spec.field_index(field).is_some() {
                for &child in scene.children(node, field) {
                    self.walk(child, &frame, owner, depth + 1);
                }
            }
        }
        self.group = outer;
    }

    /// A shape left out of the graph, with why (the export's report lists it; a file that
    /// could not be decoded is also a warning).
    pub(super) fn skip(&mut self, node: NodeId, geometry: &str, reason: String) {
        if reason.starts_with('\'') {
            self.warnings.push(reason.clone());
        }
        self.graph.skipped.push(graph::Skipped {
            node,
            geometry: geometry.to_owned(),
            reason,
        });
    }

    /// Webots' CadShape: a mesh file with its own colours.
    pub(super) fn cad_shape(&mut self, node: NodeId, frame: &Frame, owner: Owner) {
        let scene = self.scene;
        match shapes::cad_shape(scene, node, &mut self.graph.meshes) {
            Ok(shape) => {
                // The file's colours replace the diffuse colour, as a Color node does: a
                // white VRML97 Material otherwise at its defaults.
                self.graph.materials.push(Material::WHITE);
                let material = self.graph.materials.len() - 1;
                self.place(node, shape, material, frame, owner);
            }
            Err(reason) => self.skip(node, "CadShape", reason),
        }
    }
}
