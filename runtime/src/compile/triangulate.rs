//! Triangulation of IndexedFaceSet and ElevationGrid into [`Mesh`]es.
//!
//! Faces are projected onto the plane of their Newell normal and cut by the `earcut` crate
//! (Mapbox's ear-cutting algorithm), so concave and mildly non-planar faces triangulate
//! correctly and small self-crossings are cured. Invalid indices are skipped.

use glam::{DVec2, DVec3};
use regatta_schema::{NodeId, Scene, Value};

use super::graph::Mesh;

pub fn indexed_face_set(scene: &Scene, node: NodeId) -> Mesh {
    let points: Vec<DVec3> = match scene.child(node, "coord").map(|c| scene.field(c, "point")) {
        Some(Value::Vec3s(points)) => points.iter().map(|p| DVec3::from_array(*p)).collect(),
        _ => Vec::new(),
    };
    let colors: Vec<[f64; 3]> = match scene.child(node, "color").map(|c| scene.field(c, "color")) {
        Some(Value::Vec3s(colors)) => colors.clone(),
        _ => Vec::new(),
    };
    let index = match scene.field(node, "coordIndex") {
        Value::Ints(index) => index.as_slice(),
        _ => &[],
    };
    let color_index = match scene.field(node, "colorIndex") {
        Value::Ints(index) => index.as_slice(),
        _ => &[],
    };
    let per_vertex = scene.bool(node, "colorPerVertex");
    let ccw = scene.bool(node, "ccw");
    let mut mesh = Mesh {
        positions: points.clone(),
        triangles: Vec::new(),
        triangle_colors: (!colors.is_empty()).then(Vec::new),
        corner_colors: (!colors.is_empty() && per_vertex).then(Vec::new),
        solid: scene.bool(node, "solid"),
        crease_angle: scene.float(node, "creaseAngle"),
        tex_coords: None,
    };
    let tex_points: Vec<[f64; 2]> = match scene
        .child(node, "texCoord")
        .map(|c| scene.field(c, "point"))
    {
        Some(Value::Vec2s(points)) => points.clone(),
        _ => Vec::new(),
    };
    let tex_index = match scene.field(node, "texCoordIndex") {
        Value::Ints(index) if !index.is_empty() => index.as_slice(),
        _ => &[],
    };
    if !tex_points.is_empty() {
        mesh.tex_coords = Some(Vec::new());
    }
    let mut face: Vec<u32> = Vec::new();
    let mut face_number = 0usize;
    let mut corner = 0usize;
    let mut face_start_corner = 0usize;
    let flush = |face: &mut Vec<u32>, face_number: usize, start_corner: usize, mesh: &mut Mesh| {
        let valid: Vec<u32> = face
            .iter()
            .copied()
            .filter(|&i| (i as usize) < points.len())
            .collect();
        if valid.len() >= 3 {
            let before = mesh.triangles.len();
            triangulate_polygon(&points, &valid, ccw, &mut mesh.triangles);
            if let Some(triangle_colors) = &mut mesh.triangle_colors {
                let color = face_color(
                    &colors,
                    color_index,
                    per_vertex,
                    face_number,
                    start_corner,
                    face.len(),
                    &valid,
                );
                triangle_colors.extend(std::iter::repeat_n(color, mesh.triangles.len() - before));
            }
            if let Some(tex_coords) = &mut mesh.tex_coords {
                // Given texture coordinates: by texCoordIndex corner for corner, else by
                // coordIndex (VRML97 6.23).
                let corners = &face[..];
                let coord_of = |point: u32| {
                    let slot = corners.iter().position(|&p| p == point).unwrap_or(0);
                    let index = if tex_index.is_empty() {
                        point as usize
                    } else {
                        tex_index
                            .get(start_corner + slot)
                            .map_or(usize::MAX, |&c| c.max(0) as usize)
                    };
                    tex_points.get(index).copied().unwrap_or([0.0; 2])
                };
                for triangle in &mesh.triangles[before..] {
                    tex_coords.push(triangle.map(coord_of));
                }
            }
            if let Some(corner_colors) = &mut mesh.corner_colors {
                let corners = &face[..];
                let color_of = |point: u32| {
                    let slot = corners.iter().position(|&p| p == point).unwrap_or(0);
                    let index = if color_index.is_empty() {
                        point as usize
                    } else {
                        color_index
                            .get(start_corner + slot)
                            .map_or(usize::MAX, |&c| c.max(0) as usize)
                    };
                    colors.get(index).copied().unwrap_or([1.0; 3])
                };
                for triangle in &mesh.triangles[before..] {
                    corner_colors.push(triangle.map(color_of));
                }
            }
        }
        face.clear();
    };
    for &i in index {
        if i < 0 {
            flush(&mut face, face_number, face_start_corner, &mut mesh);
            face_number += 1;
            corner += 1;
            face_start_corner = corner;
        } else {
            face.push(i as u32);
            corner += 1;
        }
    }
    flush(&mut face, face_number, face_start_corner, &mut mesh);
    mesh
}

/// One colour per face: the face's colour, or the mean of its vertices' colours.
fn face_color(
    colors: &[[f64; 3]],
    color_index: &[i32],
    per_vertex: bool,
    face: usize,
    start_corner: usize,
    corners: usize,
    vertices: &[u32],
) -> [f64; 3] {
    let pick = |i: usize| colors.get(i).copied().unwrap_or([1.0; 3]);
    if !per_vertex {
        let i = color_index.get(face).map_or(face, |&c| c.max(0) as usize);
        return pick(i);
    }
    let mut sum = [0.0; 3];
    let ids: Vec<usize> = if color_index.is_empty() {
        vertices.iter().map(|&v| v as usize).collect()
    } else {
        (start_corner..start_corner + corners)
            .filter_map(|c| color_index.get(c).filter(|&&x| x >= 0).map(|&x| x as usize))
            .collect()
    };
    for &i in &ids {
        let c = pick(i);
        for k in 0..3 {
            sum[k] += c[k];
        }
    }
    let n = ids.len().max(1) as f64;
    sum.map(|s| s / n)
}

/// Triangulates one polygon (vertex indices into `points`) into `out`: projected onto the
/// plane of its Newell normal, then cut by `earcut` (Mapbox's algorithm, which also cures
/// small self-intersections). Each triangle is turned to the polygon's own winding, so `ccw`
/// decides the facing as it does for triangles given directly.
pub fn triangulate_polygon(points: &[DVec3], polygon: &[u32], ccw: bool, out: &mut Vec<[u32; 3]>) {
    let push = |out: &mut Vec<[u32; 3]>, a: u32, b: u32, c: u32| {
        out.push(if ccw { [a, b, c] } else { [a, c, b] });
    };
    if polygon.len() == 3 {
        push(out, polygon[0], polygon[1], polygon[2]);
        return;
    }
    // Newell normal, then a 2-D basis in its plane in which the polygon winds positively.
    let mut normal = DVec3::ZERO;
    for i in 0..polygon.len() {
        let a = points[polygon[i] as usize];
        let b = points[polygon[(i + 1) % polygon.len()] as usize];
        normal += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    if normal.length_squared() == 0.0 {
        return; // degenerate: all collinear, nothing visible
    }
    let normal = normal.normalize();
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let flat: Vec<[f64; 2]> = polygon
        .iter()
        .map(|&i| {
            let p = points[i as usize];
            [p.dot(u), p.dot(v)]
        })
        .collect();
    let mut corners: Vec<u32> = Vec::new();
    earcut::Earcut::new().earcut(flat.iter().copied(), &[] as &[u32], &mut corners);
    for t in corners.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|k| k as usize);
        let area = DVec2::from(flat[b]) - DVec2::from(flat[a]);
        let area = area.perp_dot(DVec2::from(flat[c]) - DVec2::from(flat[a]));
        if area >= 0.0 {
            push(out, polygon[a], polygon[b], polygon[c]);
        } else {
            push(out, polygon[a], polygon[c], polygon[b]);
        }
    }
}

pub fn elevation_grid(scene: &Scene, node: NodeId) -> Mesh {
    let nx = scene.int(node, "xDimension").max(0) as usize;
    let nz = scene.int(node, "zDimension").max(0) as usize;
    let (sx, sz) = (scene.float(node, "xSpacing"), scene.float(node, "zSpacing"));
    let heights = match scene.field(node, "height") {
        Value::Floats(h) => h.as_slice(),
        _ => &[],
    };
    let mut mesh = Mesh {
        solid: scene.bool(node, "solid"),
        crease_angle: scene.float(node, "creaseAngle"),
        ..Mesh::default()
    };
    if nx < 2 || nz < 2 || heights.len() < nx * nz {
        return mesh;
    }
    for j in 0..nz {
        for i in 0..nx {
            mesh.positions.push(DVec3::new(
                i as f64 * sx,
                heights[j * nx + i],
                j as f64 * sz,
            ));
        }
    }
    let ccw = scene.bool(node, "ccw");
    for j in 0..nz - 1 {
        for i in 0..nx - 1 {
            let a = (j * nx + i) as u32;
            let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
            // Counter-clockwise seen from +y.
            let (t1, t2) = ([a, c, b], [b, c, d]);
            if ccw {
                mesh.triangles.push(t1);
                mesh.triangles.push(t2);
            } else {
                mesh.triangles.push([t1[0], t1[2], t1[1]]);
                mesh.triangles.push([t2[0], t2[2], t2[1]]);
            }
        }
    }
    mesh.tex_coords_per_point(&grid_tex_coords(scene, node, nx, nz));
    mesh
}

/// An elevation grid's texture coordinates, one per point: its TextureCoordinate's, else
/// (VRML97 6.15) 0 to 1 from the first point to the last along each axis.
pub fn grid_tex_coords(scene: &Scene, node: NodeId, nx: usize, nz: usize) -> Vec<[f64; 2]> {
    if let Some(Value::Vec2s(points)) = scene
        .child(node, "texCoord")
        .map(|c| scene.field(c, "point"))
    {
        if points.len() >= nx * nz {
            return points[..nx * nz].to_vec();
        }
    }
    let mut out = Vec::with_capacity(nx * nz);
    for j in 0..nz {
        for i in 0..nx {
            out.push([
                i as f64 / (nx - 1).max(1) as f64,
                j as f64 / (nz - 1).max(1) as f64,
            ]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each triangle's (b − a) × (c − a).
    fn crosses<'a>(
        points: &'a [DVec3],
        triangles: &'a [[u32; 3]],
    ) -> impl Iterator<Item = DVec3> + 'a {
        triangles.iter().map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            (b - a).cross(c - a)
        })
    }

    fn area(points: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
        crosses(points, triangles).map(|c| c.length() / 2.0).sum()
    }

    #[test]
    fn concave_l_shape_triangulates_to_its_area() {
        // An L: 2×2 square minus its top-right 1×1 quarter: area 3.
        let pts: Vec<DVec3> = [[0., 0.], [2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.]]
            .iter()
            .map(|p| DVec3::new(p[0], 0.0, p[1]))
            .collect();
        let mut out = Vec::new();
        triangulate_polygon(&pts, &[0, 1, 2, 3, 4, 5], true, &mut out);
        assert_eq!(out.len(), 4);
        assert!((area(&pts, &out) - 3.0).abs() < 1e-12);
    }

    /// Each triangle's turn about +y (twice its signed area seen along y).
    fn windings(points: &[DVec3], triangles: &[[u32; 3]]) -> Vec<f64> {
        crosses(points, triangles).map(|c| c.y).collect()
    }

    #[test]
    fn triangles_keep_the_faces_winding_and_ccw_flips_it() {
        // A concave "comb" in the y = 0 plane, wound clockwise seen from +y, then reversed.
        let outline = [
            [0., 0.],
            [0., 3.],
            [1., 3.],
            [1., 1.],
            [2., 1.],
            [2., 3.],
            [3., 3.],
            [3., 0.],
        ];
        let pts: Vec<DVec3> = outline
            .iter()
            .map(|p| DVec3::new(p[0], 0.0, p[1]))
            .collect();
        let order: Vec<u32> = (0..8).collect();
        let reversed: Vec<u32> = (0..8).rev().collect();
        for (polygon, sign) in [(&order, 1.0), (&reversed, -1.0)] {
            let mut out = Vec::new();
            triangulate_polygon(&pts, polygon, true, &mut out);
            assert_eq!(out.len(), 6);
            assert!((area(&pts, &out) - 7.0).abs() < 1e-12);
            // Seen from +y, x × z points down: a polygon listed clockwise from above has a
            // Newell normal along +y, and so do its triangles.
            let turn: Vec<f64> = windings(&pts, &out);
            assert!(turn.iter().all(|w| w * sign > 0.0), "{turn:?}");
            let mut flipped = Vec::new();
            triangulate_polygon(&pts, polygon, false, &mut flipped);
            let turn: Vec<f64> = windings(&pts, &flipped);
            assert!(turn.iter().all(|w| w * sign < 0.0), "{turn:?}");
        }
    }

    #[test]
    fn degenerate_faces_give_nothing_and_never_panic() {
        let pts: Vec<DVec3> = (0..5).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        let mut out = Vec::new();
        triangulate_polygon(&pts, &[0, 1, 2, 3, 4], true, &mut out);
        assert!(out.is_empty());
        // A bow tie crosses itself: whatever comes out lies on its points.
        let tie: Vec<DVec3> = [[0., 0.], [2., 2.], [2., 0.], [0., 2.]]
            .iter()
            .map(|p| DVec3::new(p[0], 0.0, p[1]))
            .collect();
        triangulate_polygon(&tie, &[0, 1, 2, 3], true, &mut out);
        assert!(out.iter().flatten().all(|&i| i < 4));
    }
}
