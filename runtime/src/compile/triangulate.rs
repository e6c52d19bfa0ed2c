//! Triangulation of IndexedFaceSet and ElevationGrid into [`Mesh`]es.
//!
//! Faces are projected onto the plane of their Newell normal and ear-clipped, so concave and
//! mildly non-planar faces triangulate correctly; a face that will not clip (self-crossing)
//! falls back to a fan, so no input is lost. Invalid indices are skipped.

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
    };
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

/// Ear-clips one polygon (vertex indices into `points`) into `out`.
pub fn triangulate_polygon(points: &[DVec3], polygon: &[u32], ccw: bool, out: &mut Vec<[u32; 3]>) {
    let push = |out: &mut Vec<[u32; 3]>, a: u32, b: u32, c: u32| {
        out.push(if ccw { [a, b, c] } else { [a, c, b] });
    };
    if polygon.len() == 3 {
        push(out, polygon[0], polygon[1], polygon[2]);
        return;
    }
    // Newell normal, then a 2-D basis in its plane.
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
    let flat: Vec<DVec2> = polygon
        .iter()
        .map(|&i| {
            let p = points[i as usize];
            DVec2::new(p.dot(u), p.dot(v))
        })
        .collect();
    let mut remaining: Vec<usize> = (0..polygon.len()).collect();
    let cross = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let mut guard = 0;
    while remaining.len() > 3 && guard < polygon.len() * polygon.len() {
        guard += 1;
        let n = remaining.len();
        let mut clipped = false;
        for k in 0..n {
            let (ia, ib, ic) = (
                remaining[(k + n - 1) % n],
                remaining[k],
                remaining[(k + 1) % n],
            );
            let (a, b, c) = (flat[ia], flat[ib], flat[ic]);
            if cross(a, b, c) <= 0.0 {
                continue; // reflex or flat corner
            }
            let contains_other = remaining.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let p = flat[j];
                cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
            });
            if contains_other {
                continue;
            }
            push(out, polygon[ia], polygon[ib], polygon[ic]);
            remaining.remove(k);
            clipped = true;
            break;
        }
        if !clipped {
            break;
        }
    }
    if remaining.len() >= 3 {
        // What is left (3 vertices, or a self-crossing rest) becomes a fan.
        for k in 1..remaining.len() - 1 {
            push(
                out,
                polygon[remaining[0]],
                polygon[remaining[k]],
                polygon[remaining[k + 1]],
            );
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
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(points: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
        triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (
                    points[t[0] as usize],
                    points[t[1] as usize],
                    points[t[2] as usize],
                );
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
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
}
