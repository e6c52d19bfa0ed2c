//! Turning render-graph shapes into indexed triangle lists with normals (and colours): the
//! analytic shapes tessellated at a chosen quality, IndexedFaceSet and ElevationGrid meshes
//! given creaseAngle normals.

use glam::{DVec2, DVec3, Vec2, Vec3};
use regatta_runtime::compile::graph::{Mesh, Shape};
use regatta_runtime::geometry::Frame;

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

impl Triangles {
    fn vertex(&mut self, position: DVec3, normal: DVec3, uv: [f64; 2]) -> u32 {
        self.positions.push(position.as_vec3());
        self.normals.push(unit_or_up(normal).as_vec3());
        self.uvs.push(DVec2::from_array(uv).as_vec2());
        (self.positions.len() - 1) as u32
    }

    /// Adds a triangle, wound counter-clockwise seen from the side its normals face.
    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        let [pa, pb, pc] = [a, b, c].map(|i| self.positions[i as usize].as_dvec3());
        let facing = (pb - pa).cross(pc - pa);
        let normal = self.normals[a as usize] + self.normals[b as usize] + self.normals[c as usize];
        if facing.dot(normal.as_dvec3()) < 0.0 {
            self.indices.extend([a, c, b]);
        } else {
            self.indices.extend([a, b, c]);
        }
    }

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

/// Segments around a full circle for a quality setting: a multiple of 4 (so that the
/// tessellation reaches a round shape's extreme points on every axis), at least 8.
pub fn segments(quality: u32) -> usize {
    (quality.clamp(8, 4096) as usize).div_ceil(4) * 4
}

/// Point on the unit circle in the xz-plane at step `k` of `n` (k = 0 on +z).
fn around(k: usize, n: usize) -> (f64, f64) {
    let angle = std::f64::consts::TAU * (k % n) as f64 / n as f64;
    (libm::sin(angle), libm::cos(angle))
}

/// The texture s of step `k` of `n` around the y axis: VRML97 starts at the back (−z) and
/// goes counter-clockwise seen from above; step 0 is on +z, half way. Past 1 on purpose: a
/// repeating sampler wraps it, and the seam needs no vertex of its own.
fn around_s(k: usize, n: usize) -> f64 {
    0.5 + k as f64 / n as f64
}

/// The directions a Box face's s and t run along (VRML97 6.4).
fn box_face_axes(axis: usize, sign: f64) -> (DVec3, DVec3) {
    match (axis, sign > 0.0) {
        (0, true) => (DVec3::NEG_Z, DVec3::Y),
        (0, false) => (DVec3::Z, DVec3::Y),
        (1, true) => (DVec3::X, DVec3::NEG_Z),
        (1, false) => (DVec3::X, DVec3::Z),
        (_, true) => (DVec3::X, DVec3::Y),
        (_, false) => (DVec3::NEG_X, DVec3::Y),
    }
}

/// Tessellates an analytic shape, or gives a mesh creaseAngle normals.
pub fn triangles(shape: &Shape, meshes: &[Mesh], quality: u32) -> Triangles {
    let n = segments(quality);
    let mut out = Triangles::default();
    match *shape {
        Shape::Box { half } => {
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut normal = DVec3::ZERO;
                    normal[axis] = sign;
                    let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
                    let corner = |su: f64, sv: f64| {
                        let mut p = DVec3::ZERO;
                        p[axis] = sign * half[axis];
                        p[ua] = su * half[ua];
                        p[va] = sv * half[va];
                        p
                    };
                    // VRML97 6.4: each face shows the whole image, upright seen from
                    // outside (the top's seen from the front, the bottom's from behind).
                    let (s_dir, t_dir) = box_face_axes(axis, sign);
                    let uv = |p: DVec3| {
                        let along = |d: DVec3| (p.dot(d) / half.dot(d.abs()) + 1.0) / 2.0;
                        [along(s_dir), along(t_dir)]
                    };
                    let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                        .map(|(su, sv)| out.vertex(corner(su, sv), normal, uv(corner(su, sv))));
                    out.triangle(quad[0], quad[1], quad[2]);
                    out.triangle(quad[0], quad[2], quad[3]);
                }
            }
        }
        Shape::Cylinder {
            radius,
            height,
            side,
            bottom,
            top,
        } => {
            let half = height / 2.0;
            if side {
                let ring: Vec<(u32, u32)> = (0..=n)
                    .map(|k| {
                        let (s, c) = around(k, n);
                        let normal = DVec3::new(s, 0.0, c);
                        let u = around_s(k, n);
                        let low =
                            out.vertex(DVec3::new(radius * s, -half, radius * c), normal, [u, 0.0]);
                        let high =
                            out.vertex(DVec3::new(radius * s, half, radius * c), normal, [u, 1.0]);
                        (low, high)
                    })
                    .collect();
                for k in 0..n {
                    let ((a, b), (c, d)) = (ring[k], ring[k + 1]);
                    out.triangle(a, c, d);
                    out.triangle(a, d, b);
                }
            }
            for (present, y, up) in [(bottom, -half, -1.0), (top, half, 1.0)] {
                if present {
                    disk(&mut out, radius, y, up, n);
                }
            }
        }
        Shape::Cone {
            radius,
            height,
            side,
            bottom,
        } => {
            let half = height / 2.0;
            if side {
                for k in 0..n {
                    let (s0, c0) = around(k, n);
                    let (s1, c1) = around(k + 1, n);
                    let (sm, cm) = around(2 * k + 1, 2 * n);
                    let slope = |s: f64, c: f64| DVec3::new(s * height, radius, c * height);
                    let (u0, u1) = (around_s(k, n), around_s(k + 1, n));
                    let a = out.vertex(
                        DVec3::new(radius * s0, -half, radius * c0),
                        slope(s0, c0),
                        [u0, 0.0],
                    );
                    let b = out.vertex(
                        DVec3::new(radius * s1, -half, radius * c1),
                        slope(s1, c1),
                        [u1, 0.0],
                    );
                    let apex = out.vertex(
                        DVec3::new(0.0, half, 0.0),
                        slope(sm, cm),
                        [(u0 + u1) / 2.0, 1.0],
                    );
                    out.triangle(a, b, apex);
                }
            }
            if bottom {
                disk(&mut out, radius, -half, -1.0, n);
            }
        }
        Shape::Sphere { radius } => {
            let rings = n / 2;
            let grid: Vec<Vec<u32>> = (0..=rings)
                .map(|i| {
                    let polar = std::f64::consts::PI * i as f64 / rings as f64;
                    let (sp, cp) = (libm::sin(polar), libm::cos(polar));
                    (0..=n)
                        .map(|k| {
                            let (s, c) = around(k, n);
                            let unit = DVec3::new(sp * s, cp, sp * c);
                            let t = 1.0 - i as f64 / rings as f64;
                            out.vertex(unit * radius, unit, [around_s(k, n), t])
                        })
                        .collect()
                })
                .collect();
            for i in 0..rings {
                for k in 0..n {
                    let (a, b) = (grid[i][k], grid[i][k + 1]);
                    let (c, d) = (grid[i + 1][k], grid[i + 1][k + 1]);
                    if i != 0 {
                        out.triangle(a, c, b);
                    }
                    if i != rings - 1 {
                        out.triangle(b, c, d);
                    }
                }
            }
        }
        Shape::Mesh(index) => return mesh_triangles(&meshes[index]),
    }
    out
}

/// A flat disk of `radius` at height `y`, facing `up` (±1).
fn disk(out: &mut Triangles, radius: f64, y: f64, up: f64, n: usize) {
    let normal = DVec3::Y * up;
    // VRML97: a cap shows the image's inscribed circle, upright seen from outside.
    let uv = |s: f64, c: f64| [(s + 1.0) / 2.0, (1.0 - up * c) / 2.0];
    let center = out.vertex(DVec3::new(0.0, y, 0.0), normal, [0.5, 0.5]);
    let rim: Vec<u32> = (0..=n)
        .map(|k| {
            let (s, c) = around(k, n);
            out.vertex(DVec3::new(radius * s, y, radius * c), normal, uv(s, c))
        })
        .collect();
    for k in 0..n {
        out.triangle(center, rim[k], rim[k + 1]);
    }
}

/// Vertex normals by VRML97's creaseAngle rule: at each corner, the area-weighted average of
/// the normals of the triangles around that point whose angle to this triangle's normal is at
/// most creaseAngle. Corners that end up with the same position, normal and colour share a
/// vertex.
pub fn mesh_triangles(mesh: &Mesh) -> Triangles {
    let positions = &mesh.positions;
    let face_normals: Vec<DVec3> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    let unit: Vec<DVec3> = face_normals
        .iter()
        .map(|n| n.try_normalize().unwrap_or(DVec3::ZERO))
        .collect();
    // Triangles around each point, as compressed rows.
    let mut start = vec![0u32; positions.len() + 1];
    for t in &mesh.triangles {
        for &i in t {
            start[i as usize + 1] += 1;
        }
    }
    for i in 0..positions.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around_point = vec![0u32; mesh.triangles.len() * 3];
    for (index, t) in mesh.triangles.iter().enumerate() {
        for &i in t {
            around_point[fill[i as usize] as usize] = index as u32;
            fill[i as usize] += 1;
        }
    }
    let cos_crease = if mesh.crease_angle >= std::f64::consts::PI {
        -2.0
    } else {
        libm::cos(mesh.crease_angle.max(0.0)) - 1e-9
    };
    let color_of = |triangle: usize, corner: usize| -> Option<[f64; 3]> {
        if let Some(corners) = &mesh.corner_colors {
            return Some(corners[triangle][corner]);
        }
        mesh.triangle_colors.as_ref().map(|c| c[triangle])
    };
    let mut out = Triangles {
        colors: (mesh.corner_colors.is_some() || mesh.triangle_colors.is_some()).then(Vec::new),
        ..Triangles::default()
    };
    let generated = generated_tex_coords(mesh);
    let uv_of = |triangle: usize, corner: usize| -> Vec2 {
        let st = match &mesh.tex_coords {
            Some(given) => given[triangle][corner],
            None => generated(mesh.triangles[triangle][corner]),
        };
        DVec2::from_array(st).as_vec2()
    };
    // Output vertices made at each point, chained: head per point, next per vertex.
    let mut head = vec![u32::MAX; positions.len()];
    let mut next: Vec<u32> = Vec::new();
    for (index, t) in mesh.triangles.iter().enumerate() {
        let mut corners = [0u32; 3];
        for (corner, &point) in t.iter().enumerate() {
            let own = unit[index];
            let range = start[point as usize] as usize..start[point as usize + 1] as usize;
            let mut sum = DVec3::ZERO;
            for &other in &around_point[range] {
                if other as usize == index || own.dot(unit[other as usize]) >= cos_crease {
                    sum += face_normals[other as usize];
                }
            }
            let normal = unit_or_up(if sum == DVec3::ZERO { own } else { sum }).as_vec3();
            let color = color_of(index, corner).map(|c| DVec3::from_array(c).as_vec3());
            let uv = uv_of(index, corner);
            let mut found = head[point as usize];
            while found != u32::MAX {
                let same_color = match (&out.colors, color) {
                    (Some(colors), Some(c)) => colors[found as usize] == c,
                    _ => true,
                };
                if out.normals[found as usize] == normal
                    && same_color
                    && out.uvs[found as usize] == uv
                {
                    break;
                }
                found = next[found as usize];
            }
            if found == u32::MAX {
                found = out.positions.len() as u32;
                out.positions.push(positions[point as usize].as_vec3());
                out.normals.push(normal);
                out.uvs.push(uv);
                if let (Some(colors), Some(c)) = (&mut out.colors, color) {
                    colors.push(c);
                }
                next.push(head[point as usize]);
                head[point as usize] = found;
            }
            corners[corner] = found;
        }
        out.indices.extend(corners);
    }
    out
}

/// VRML97 6.23's default texture coordinates of a face set: s along the longest side of the
/// bounding box, t along the second longest, both in units of the longest, from its minimum.
fn generated_tex_coords(mesh: &Mesh) -> impl Fn(u32) -> [f64; 2] + '_ {
    let (lo, hi) = mesh.used_positions().fold(
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
    move |i: u32| {
        let p = mesh.positions[i as usize];
        [
            (p[s_axis] - lo[s_axis]) * scale,
            (p[t_axis] - lo[t_axis]) * scale,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounds(t: &Triangles) -> (Vec3, Vec3) {
        t.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    fn outward(t: &Triangles) -> bool {
        t.indices.chunks_exact(3).all(|tri| {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| t.positions[i as usize]);
            let facing = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            facing.length() < 1e-12 || facing.dot(centroid) > 0.0
        })
    }

    #[test]
    fn round_shapes_reach_their_extremes_and_face_outwards() {
        for shape in [
            Shape::Sphere { radius: 0.5 },
            Shape::Cylinder {
                radius: 0.5,
                height: 1.0,
                side: true,
                bottom: true,
                top: true,
            },
            Shape::Box {
                half: DVec3::new(0.5, 0.5, 0.5),
            },
        ] {
            for quality in [8, 13, 32] {
                let t = triangles(&shape, &[], quality);
                let (lo, hi) = bounds(&t);
                assert_eq!((lo, hi), (Vec3::splat(-0.5), Vec3::splat(0.5)), "{shape:?}");
                assert!(outward(&t), "{shape:?} q{quality}");
            }
        }
    }

    #[test]
    fn crease_angle_decides_whether_a_shallow_fold_is_smoothed() {
        // Two triangles folded by about 8° along their shared edge.
        let mesh = |crease: f64| Mesh {
            positions: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, -1.0),
                DVec3::new(1.0, 0.1, -1.0),
            ],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
            crease_angle: crease,
            solid: true,
            ..Mesh::default()
        };
        assert_eq!(mesh_triangles(&mesh(0.0)).positions.len(), 6);
        assert_eq!(mesh_triangles(&mesh(0.5)).positions.len(), 4);
    }
}
