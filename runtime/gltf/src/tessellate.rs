//! The render graph's shapes as glTF stores them: the runtime's one tessellation
//! ([`regatta_runtime::tessellate`], at an exporter's [`Detail`]) in single precision, with
//! a frame the node cannot carry baked in.

use glam::{DVec2, DVec3, Vec2, Vec3};
use regatta_runtime::compile::graph::{Mesh, RenderGraph, Shape};
use regatta_runtime::geometry::Frame;
use regatta_runtime::tessellate::{tessellate, Detail, Tessellation};

pub use regatta_runtime::tessellate::segments;

/// One glTF mesh primitive's vertex data, in single precision as glTF stores it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangles {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub colors: Option<Vec<Vec3>>,
    /// VRML97 texture coordinates (s, t), one per vertex.
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl From<Tessellation> for Triangles {
    fn from(t: Tessellation) -> Triangles {
        let cast = |v: &[DVec3]| v.iter().map(|p| p.as_vec3()).collect();
        Triangles {
            positions: cast(&t.positions),
            normals: cast(&t.normals),
            colors: t
                .colors
                .map(|c| c.iter().map(|&c| DVec3::from_array(c).as_vec3()).collect()),
            uvs: t
                .uvs
                .iter()
                .map(|&uv| DVec2::from_array(uv).as_vec2())
                .collect(),
            indices: t.triangles.into_iter().flatten().collect(),
        }
    }
}

impl Triangles {
    /// Applies a frame the node cannot carry (a shear) to the vertices themselves.
    pub fn bake(&mut self, frame: &Frame) {
        let normal_matrix = frame.linear.inverse().transpose();
        for p in &mut self.positions {
            *p = frame.apply(p.as_dvec3()).as_vec3();
        }
        for n in &mut self.normals {
            *n = unit_or_up(normal_matrix * n.as_dvec3()).as_vec3();
        }
        if frame.linear.determinant() < 0.0 {
            for triangle in self.indices.chunks_exact_mut(3) {
                triangle.swap(1, 2);
            }
        }
    }
}

fn unit_or_up(v: DVec3) -> DVec3 {
    v.try_normalize().unwrap_or(DVec3::Y)
}

/// A shape's triangles at a quality setting ([`Detail::export`]): the analytic shapes cut
/// into [`segments`]`(quality)` around, meshes with creaseAngle normals.
pub fn triangles(shape: &Shape, meshes: &[Mesh], quality: u32) -> Triangles {
    tessellate(shape, meshes, &Detail::export(quality)).into()
}

/// Why a shape gives no triangles, if it gives none: the export leaves it out (glTF has no
/// empty meshes) and the report says why.
pub fn no_triangles(shape: &Shape, graph: &RenderGraph) -> Option<&'static str> {
    match *shape {
        Shape::Mesh(index) => graph
            .meshes
            .get(index)
            .is_none_or(|mesh| mesh.triangles.is_empty())
            .then_some("a mesh without triangles"),
        ref shape => regatta_runtime::tessellate::no_surface(shape),
    }
}
