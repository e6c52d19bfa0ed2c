//! Texture coordinates on a shape's surface: VRML97's mappings (a Box's faces, the wrap of the
//! round shapes, their caps' inscribed circle, a face set's given or default coordinates).
//! The tessellation writes them at its vertices and [`at_point`] gives them anywhere on the
//! surface, so that a sensor's ray reads the texel a renderer draws where the ray lands.

use glam::DVec3;

use crate::compile::graph::{Mesh, Shape};

/// The directions a Box face's s and t run along (VRML97 6.4): each face shows the whole
/// image, upright seen from outside (the top's seen from the front, the bottom's from
/// behind).
pub(crate) fn box_face_axes(normal: DVec3) -> (DVec3, DVec3) {
    match (normal.x, normal.y, normal.z) {
        (x, _, _) if x > 0.0 => (DVec3::NEG_Z, DVec3::Y),
        (x, _, _) if x < 0.0 => (DVec3::Z, DVec3::Y),
        (_, y, _) if y > 0.0 => (DVec3::X, DVec3::NEG_Z),
        (_, y, _) if y < 0.0 => (DVec3::X, DVec3::Z),
        (_, _, z) if z > 0.0 => (DVec3::X, DVec3::Y),
        _ => (DVec3::NEG_X, DVec3::Y),
    }
}

/// A mesh's texture coordinates per triangle corner: given, or VRML97 6.23's default for a
/// face set: s along the longest side of the bounding box, t along the second longest, both
/// in units of the longest, from its minimum. Points out of range count for nothing.
pub(crate) fn mesh_tex_coords(mesh: &Mesh) -> impl Fn(usize, usize) -> [f64; 2] + '_ {
    let point = |i: u32| mesh.positions.get(i as usize).copied();
    let (lo, hi) = mesh
        .triangles
        .iter()
        .flatten()
        .filter_map(|&i| point(i))
        .fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        );
    let size = (hi - lo).max(DVec3::ZERO);
    let mut axes = [0usize, 1, 2];
    // Longest first; ties keep x before y before z, as VRML97 asks.
    axes.sort_by(|&a, &b| size[b].total_cmp(&size[a]));
    let (s_axis, t_axis) = (axes[0], axes[1]);
    let scale = if size[s_axis] > 0.0 {
        1.0 / size[s_axis]
    } else {
        0.0
    };
    move |triangle: usize, corner: usize| {
        if let Some(given) = mesh.tex_coords.as_ref().and_then(|g| g.get(triangle)) {
            return given[corner];
        }
        let p = mesh.triangles[triangle][corner];
        let p = point(p).unwrap_or(lo);
        [
            (p[s_axis] - lo[s_axis]) * scale,
            (p[t_axis] - lo[t_axis]) * scale,
        ]
    }
}

/// The texture s of a point at `angle` (radians from +x towards +z) around the y axis: 0 at
/// the back (−z), growing counter-clockwise seen from above (the tessellation's
/// `0.75 − k/segments`).
fn around_s(x: f64, z: f64) -> f64 {
    let turn = libm::atan2(z, x).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
    0.75 - turn
}

/// A cap's coordinates: the image's inscribed circle, upright seen from outside (`up` is +1
/// for a top cap, −1 for a bottom one).
fn cap(point: DVec3, radius: f64, up: f64) -> [f64; 2] {
    [
        (point.x / radius + 1.0) / 2.0,
        (1.0 - up * point.z / radius) / 2.0,
    ]
}

/// The texture coordinates (s, t) of `point`, a point on `shape`'s surface in its local frame;
/// `triangle` is the mesh triangle it lies on (meshes only). `None` for a mesh without that
/// triangle.
pub fn at_point(
    shape: &Shape,
    meshes: &[Mesh],
    point: DVec3,
    triangle: Option<u32>,
) -> Option<[f64; 2]> {
    match *shape {
        Shape::Box { half } => {
            // The face the point lies on: the axis along which it is farthest out, relatively.
            let relative = point / half.max(DVec3::splat(f64::MIN_POSITIVE));
            let axis = relative.abs().max_position();
            let mut normal = DVec3::ZERO;
            normal[axis] = relative[axis].signum();
            let (s_dir, t_dir) = box_face_axes(normal);
            let along = |d: DVec3| (point.dot(d) / half.dot(d.abs()) + 1.0) / 2.0;
            Some([along(s_dir), along(t_dir)])
        }
        Shape::Sphere { radius } => {
            let n = point / radius;
            let polar = libm::acos(n.y.clamp(-1.0, 1.0));
            Some([around_s(n.x, n.z), 1.0 - polar / std::f64::consts::PI])
        }
        Shape::Cylinder { radius, height, .. } | Shape::Cone { radius, height, .. } => {
            let half = height / 2.0;
            let radial = libm::hypot(point.x, point.z);
            let is_cone = matches!(shape, Shape::Cone { .. });
            // A cone's side narrows to its apex; a point is on a cap when it is nearer the
            // cap's plane than the side.
            let side_radius = if is_cone {
                radius * (half - point.y) / height
            } else {
                radius
            };
            let to_side = (radial - side_radius).abs();
            let to_top = (point.y - half).abs();
            let to_bottom = (point.y + half).abs();
            if !is_cone && to_top < to_side && to_top <= to_bottom {
                Some(cap(point, radius, 1.0))
            } else if to_bottom < to_side {
                Some(cap(point, radius, -1.0))
            } else {
                Some([around_s(point.x, point.z), (point.y + half) / height])
            }
        }
        Shape::Mesh(index) => {
            let mesh = meshes.get(index)?;
            let triangle = triangle? as usize;
            let corners = mesh.triangles.get(triangle)?;
            let mut p = [DVec3::ZERO; 3];
            for (slot, &i) in p.iter_mut().zip(corners) {
                *slot = *mesh.positions.get(i as usize)?;
            }
            let weights = barycentric(point, p)?;
            let uv = mesh_tex_coords(mesh);
            let mut out = [0.0; 2];
            for (corner, weight) in weights.into_iter().enumerate() {
                let [s, t] = uv(triangle, corner);
                out[0] += weight * s;
                out[1] += weight * t;
            }
            Some(out)
        }
    }
}

/// The barycentric weights of `point` (on the triangle's plane) in triangle `p`; `None` for a
/// triangle without area.
fn barycentric(point: DVec3, p: [DVec3; 3]) -> Option<[f64; 3]> {
    let (e1, e2, d) = (p[1] - p[0], p[2] - p[0], point - p[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let denominator = d11 * d22 - d12 * d12;
    if !(denominator.is_finite() && denominator > 0.0) {
        return None;
    }
    let v = (d22 * d1 - d12 * d2) / denominator;
    let w = (d11 * d2 - d12 * d1) / denominator;
    Some([1.0 - v - w, v, w])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tessellate::{tessellate, Detail};

    /// Every vertex the tessellation writes carries the coordinates `at_point` gives there
    /// (seams aside: s is taken modulo 1, and a pole's or a cap centre's s is free).
    #[test]
    fn the_coordinates_at_every_tessellated_vertex_are_the_tessellations() {
        let shapes = [
            Shape::Box {
                half: DVec3::new(0.3, 0.1, 0.2),
            },
            Shape::Sphere { radius: 0.5 },
            Shape::Cylinder {
                radius: 0.4,
                height: 1.0,
                side: true,
                bottom: true,
                top: true,
            },
            Shape::Cone {
                radius: 0.4,
                height: 1.0,
                side: true,
                bottom: true,
            },
        ];
        for shape in shapes {
            let set = tessellate(&shape, &[], &Detail::export(16));
            for ((&position, &normal), &uv) in set.positions.iter().zip(&set.normals).zip(&set.uvs)
            {
                // Step a hair towards the middle of the vertex's own face, off its edges.
                let in_plane = position - normal * position.dot(normal);
                let inside = position - in_plane * 1e-7;
                let got = at_point(&shape, &[], inside, None).unwrap();
                let pole = matches!(shape, Shape::Sphere { .. }) && normal.y.abs() > 1.0 - 1e-9;
                let apex = matches!(shape, Shape::Cone { .. }) && uv[1] == 1.0;
                let centre = uv == [0.5, 0.5];
                let on_rim = matches!(shape, Shape::Cylinder { .. } | Shape::Cone { .. })
                    && normal.y == 0.0
                    && (uv[1] == 0.0 || uv[1] == 1.0);
                if !(pole || apex || centre) {
                    let ds = (got[0] - uv[0]).rem_euclid(1.0);
                    assert!(
                        ds.min(1.0 - ds) < 1e-6,
                        "{shape:?} at {position}: s {} against {}",
                        got[0],
                        uv[0]
                    );
                }
                if !on_rim || !matches!(shape, Shape::Cone { .. }) {
                    assert!(
                        (got[1] - uv[1]).abs() < 1e-6 || centre,
                        "{shape:?} at {position}: t {} against {}",
                        got[1],
                        uv[1]
                    );
                }
            }
        }
    }

    #[test]
    fn a_mesh_point_interpolates_its_triangles_coordinates() {
        let mesh = Mesh {
            positions: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, -1.0),
            ],
            triangles: vec![[0, 1, 2]],
            triangle_colors: None,
            corner_colors: None,
            solid: true,
            crease_angle: 0.0,
            tex_coords: Some(vec![[[0.0, 0.0], [4.0, 0.0], [0.0, 2.0]]]),
        };
        let got = at_point(
            &Shape::Mesh(0),
            std::slice::from_ref(&mesh),
            DVec3::new(1.0, 0.0, -0.25),
            Some(0),
        )
        .unwrap();
        assert!(
            (got[0] - 2.0).abs() < 1e-12 && (got[1] - 0.5).abs() < 1e-12,
            "{got:?}"
        );
        assert_eq!(
            at_point(&Shape::Mesh(0), &[mesh], DVec3::ZERO, Some(3)),
            None
        );
    }
}
