//! What an export holds, shape by shape: each Shape the compiler met, exported (with its
//! triangles, or its segments and points) or skipped with the reason, so that a user sees
//! what became of every part of a world (`regatta gltf --report`).

use regatta_runtime::compile::graph::{RenderGraph, Shape};
use regatta_runtime::Compiled;
use regatta_schema::NodeId;

use crate::tessellate;

/// One shape of the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The Shape (or CadShape) node.
    pub node: NodeId,
    /// The geometry's type ("Box", "Mesh", "IndexedLineSet"…; "" when it has none).
    pub geometry: String,
    /// `Ok(triangles)` (0 for lines and points), or why it was left out.
    pub status: Result<usize, String>,
}

/// Every shape in graph order (primitives, then lines and points), then the skipped ones.
pub fn report(compiled: &Compiled, quality: u32) -> Vec<Row> {
    let graph: &RenderGraph = &compiled.graph;
    let mut rows = Vec::new();
    for primitive in &graph.primitives {
        if let Some(reason) = tessellate::no_triangles(&primitive.shape, graph) {
            rows.push(Row {
                node: primitive.node,
                geometry: primitive.shape.name().to_owned(),
                status: Err(format!("no surface: {reason}")),
            });
            continue;
        }
        let triangles = match &primitive.shape {
            Shape::Mesh(index) => graph.meshes[*index].triangles.len(),
            shape => {
                tessellate::triangles(shape, &graph.meshes, quality)
                    .indices
                    .len()
                    / 3
            }
        };
        rows.push(Row {
            node: primitive.node,
            geometry: primitive.shape.name().to_owned(),
            status: Ok(triangles),
        });
    }
    for set in &graph.lines {
        rows.push(Row {
            node: set.node,
            geometry: if set.lines {
                "IndexedLineSet"
            } else {
                "PointSet"
            }
            .to_owned(),
            status: Ok(0),
        });
    }
    for skipped in &graph.skipped {
        rows.push(Row {
            node: skipped.node,
            geometry: skipped.geometry.clone(),
            status: Err(skipped.reason.clone()),
        });
    }
    rows
}
