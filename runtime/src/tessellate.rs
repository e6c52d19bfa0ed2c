//! The one tessellation of the render graph's shapes: Box, Cylinder, Cone and Sphere as
//! triangles at the detail a user asks for ([`Detail`]), and meshes given their normals. The
//! CPU rasteriser (`render::raster`), the glTF export (`regatta-gltf`) and the live viewer
//! (`regatta-view`, through the export) all read it; the wgpu backend ray-casts the analytic
//! shapes exactly and packs only meshes, so it needs none.
//!
//! Output is in the shape's local frame, double precision, with a unit normal, VRML97's
//! texture coordinates and (for meshes with a Color node) a colour at every vertex. Every
//! triangle is wound counter-clockwise seen from the side its normals face (glTF's front).
//! Flat faces keep their face normal (as the ray caster's exact intersections give it);
//! curved surfaces carry the smooth normal at each vertex.
//!
//! Round shapes go around from +x towards +z (angle a: x = cos a, z = sin a), in
//! [`Detail::segments`] steps; a multiple of 4 puts a vertex on every extreme point. The
//! texture's s is VRML97's (0 at the back, −z, counter-clockwise seen from above) written as
//! `0.75 − k/segments`, continuous around the seam: it runs below 0 on purpose, a repeating
//! sampler wraps it, and the seam needs no vertex of its own.

use glam::DVec3;

use crate::compile::graph::{Mesh, Shape};
use crate::texcoord::{box_face_axes, mesh_tex_coords};

/// How finely shapes are cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detail {
    /// Segments around a full circle (cylinders, cones, spheres; a sphere has half as many
    /// rings): a multiple of 4, at least 8 ([`segments`] rounds a quality setting).
    pub segments: usize,
    /// A refinement step for flat faces (a Box's): `None` draws each face as two triangles.
    pub cells: Option<Cells>,
    /// How meshes get their normals.
    pub mesh_normals: MeshNormals,
}

/// Flat faces cut into a grid, so that lights whose attenuation varies across a face (point
/// and spot lights) are sampled often enough for per-vertex (Gouraud) lighting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cells {
    /// A face longer than this (m) along a side is cut along it ...
    pub size: f64,
    /// ... into at most this many cells (a 100 m floor does not cost 160,000 triangles).
    pub max: usize,
}

/// A mesh's vertex normals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshNormals {
    /// Each triangle flat, with corners of its own (the ray caster's geometric normal, and
    /// the triangle's colour); triangles with a non-finite corner or no area are left out.
    Flat,
    /// VRML97's creaseAngle rule, corners shared where position, normal, colour and texture
    /// coordinates agree.
    Crease,
}

impl Detail {
    /// The CPU rasteriser's: 32 segments (the polygon's radial error is 1 − cos(π/32) ≈ 0.5 %
    /// of the radius, under a pixel for objects narrower than ~200 pixels), faces cut every
    /// 0.25 m into at most 16 cells a side, flat mesh triangles.
    pub const RASTER: Detail = Detail {
        segments: 32,
        cells: Some(Cells {
            size: 0.25,
            max: 16,
        }),
        mesh_normals: MeshNormals::Flat,
    };

    /// An exporter's: [`segments`]`(quality)`, whole faces, creaseAngle normals.
    pub fn export(quality: u32) -> Detail {
        Detail {
            segments: segments(quality),
            cells: None,
            mesh_normals: MeshNormals::Crease,
        }
    }
}

/// Segments around a full circle for a quality setting: a multiple of 4 (so that the
/// tessellation reaches a round shape's extreme points on every axis), at least 8.
pub fn segments(quality: u32) -> usize {
    (quality.clamp(8, 4096) as usize).div_ceil(4) * 4
}

/// Triangles over shared vertices; the per-vertex arrays are parallel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tessellation {
    pub positions: Vec<DVec3>,
    /// Unit normals.
    pub normals: Vec<DVec3>,
    /// VRML97 texture coordinates (s, t).
    pub uvs: Vec<[f64; 2]>,
    /// Colours that replace the material's diffuse colour (a mesh's Color node).
    pub colors: Option<Vec<[f64; 3]>>,
    pub triangles: Vec<[u32; 3]>,
}

impl Tessellation {
    fn vertex(&mut self, position: DVec3, normal: DVec3, uv: [f64; 2]) -> u32 {
        self.positions.push(position);
        self.normals.push(normal);
        self.uvs.push(uv);
        (self.positions.len() - 1) as u32
    }

    /// A parallelogram `origin + s·u + t·v` (s, t in 0…1), facing `normal` (u × v), cut into
    /// cells when `cells` asks; texture coordinates from `uv` of each position.
    fn quad(
        &mut self,
        [origin, u, v, normal]: [DVec3; 4],
        cells: Option<Cells>,
        uv: impl Fn(DVec3) -> [f64; 2],
    ) {
        let count = |length: f64| {
            let Some(cells) = cells else { return 1 };
            let n = (length / cells.size).ceil();
            if n.is_finite() && n >= 1.0 {
                (n as usize).min(cells.max)
            } else {
                1
            }
        };
        let (nu, nv) = (count(u.length()), count(v.length()));
        let first = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let p = origin + u * (i as f64 / nu as f64) + v * (j as f64 / nv as f64);
                self.vertex(p, normal, uv(p));
            }
        }
        let stride = nu as u32 + 1;
        for j in 0..nv as u32 {
            for i in 0..nu as u32 {
                let a = first + j * stride + i;
                let (b, c, d) = (a + 1, a + stride, a + stride + 1);
                self.triangles.push([a, b, d]);
                self.triangles.push([a, d, c]);
            }
        }
    }

    /// A disc of `radius` at height `y`, facing `up` (±1 along y).
    fn disc(&mut self, radius: f64, y: f64, up: f64, n: usize) {
        let normal = DVec3::Y * up;
        // VRML97: a cap shows the image's inscribed circle, upright seen from outside.
        let centre = self.vertex(DVec3::new(0.0, y, 0.0), normal, [0.5, 0.5]);
        let first = self.positions.len() as u32;
        for k in 0..n {
            let (s, c) = angle(k, n);
            let uv = [(c + 1.0) / 2.0, (1.0 - up * s) / 2.0];
            self.vertex(DVec3::new(c * radius, y, s * radius), normal, uv);
        }
        for k in 0..n as u32 {
            let next = (k + 1) % n as u32;
            // Going around from +x towards +z faces −y.
            self.triangles.push(if up < 0.0 {
                [centre, first + k, first + next]
            } else {
                [centre, first + next, first + k]
            });
        }
    }
}

/// (sin, cos) of step `k` of `n` around a full circle.
fn angle(k: usize, n: usize) -> (f64, f64) {
    let a = std::f64::consts::TAU * k as f64 / n as f64;
    (libm::sin(a), libm::cos(a))
}

/// The texture s of step `k` of `n` around the y axis (see the module's notes).
fn around_s(k: usize, n: usize) -> f64 {
    0.75 - k as f64 / n as f64
}

/// Whether every number that shapes the geometry is finite and positive: anything else gives
/// no triangles (a zero-size or degenerate shape is a clean skip, never a panic or a NaN).
fn usable(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite() && *v > 0.0)
}

/// Why an analytic shape gives no triangles at any detail, if it gives none: a size that is
/// not finite and positive, or a Cylinder or Cone with none of its parts. (A mesh gives none
/// when it has no triangles, or, drawn flat, none with an area.)
pub fn no_surface(shape: &Shape) -> Option<&'static str> {
    let (sizes, parts): (&[f64], bool) = match shape {
        Shape::Box { half } => (&[half.x, half.y, half.z], true),
        Shape::Sphere { radius } => (std::slice::from_ref(radius), true),
        Shape::Cylinder {
            radius,
            height,
            side,
            bottom,
            top,
        } => (&[*radius, *height], *side || *bottom || *top),
        Shape::Cone {
            radius,
            height,
            side,
            bottom,
        } => (&[*radius, *height], *side || *bottom),
        Shape::Mesh(_) => return None,
    };
    if !usable(sizes) {
        Some("a size that is not finite and positive")
    } else if !parts {
        Some("none of its parts (side, bottom, top) drawn")
    } else {
        None
    }
}

/// The shape's triangles in its local frame at `detail` (none for a degenerate shape or a
/// mesh index out of range).
pub fn tessellate(shape: &Shape, meshes: &[Mesh], detail: &Detail) -> Tessellation {
    let n = detail.segments.max(3);
    let mut set = Tessellation::default();
    match *shape {
        Shape::Box { half: h } => {
            if !usable(&[h.x, h.y, h.z]) {
                return set;
            }
            let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
            // Each face: a corner, two edges, its outward normal.
            let faces = [
                [
                    h * DVec3::new(1.0, -1.0, -1.0),
                    y * 2.0 * h.y,
                    z * 2.0 * h.z,
                    x,
                ],
                [-h, z * 2.0 * h.z, y * 2.0 * h.y, -x],
                [
                    h * DVec3::new(-1.0, 1.0, -1.0),
                    z * 2.0 * h.z,
                    x * 2.0 * h.x,
                    y,
                ],
                [-h, x * 2.0 * h.x, z * 2.0 * h.z, -y],
                [
                    h * DVec3::new(-1.0, -1.0, 1.0),
                    x * 2.0 * h.x,
                    y * 2.0 * h.y,
                    z,
                ],
                [-h, y * 2.0 * h.y, x * 2.0 * h.x, -z],
            ];
            for face in faces {
                let (s_dir, t_dir) = box_face_axes(face[3]);
                let uv = |p: DVec3| {
                    let along = |d: DVec3| (p.dot(d) / h.dot(d.abs()) + 1.0) / 2.0;
                    [along(s_dir), along(t_dir)]
                };
                set.quad(face, detail.cells, uv);
            }
        }
        Shape::Sphere { radius } => {
            if !usable(&[radius]) {
                return set;
            }
            let rings = n / 2;
            for ring in 0..=rings {
                let polar = std::f64::consts::PI * ring as f64 / rings as f64;
                let (sp, cp) = (libm::sin(polar), libm::cos(polar));
                let t = 1.0 - ring as f64 / rings as f64;
                for k in 0..=n {
                    let (s, c) = angle(k, n);
                    let normal = DVec3::new(sp * c, cp, sp * s);
                    set.vertex(normal * radius, normal, [around_s(k, n), t]);
                }
            }
            let stride = n as u32 + 1;
            for ring in 0..rings as u32 {
                for k in 0..n as u32 {
                    let a = ring * stride + k;
                    let (b, c, d) = (a + 1, a + stride, a + stride + 1);
                    // At the poles one of the two has no area.
                    if ring != 0 {
                        set.triangles.push([a, b, d]);
                    }
                    if ring + 1 != rings as u32 {
                        set.triangles.push([a, d, c]);
                    }
                }
            }
        }
        Shape::Cylinder {
            radius: r,
            height,
            side,
            bottom,
            top,
        } => {
            if !usable(&[r, height]) {
                return set;
            }
            let y = height / 2.0;
            if side {
                let first = set.positions.len() as u32;
                for k in 0..=n {
                    let (s, c) = angle(k, n);
                    let normal = DVec3::new(c, 0.0, s);
                    let u = around_s(k, n);
                    set.vertex(DVec3::new(c * r, -y, s * r), normal, [u, 0.0]);
                    set.vertex(DVec3::new(c * r, y, s * r), normal, [u, 1.0]);
                }
                for k in 0..n as u32 {
                    let a = first + 2 * k;
                    set.triangles.push([a, a + 1, a + 3]);
                    set.triangles.push([a, a + 3, a + 2]);
                }
            }
            if bottom {
                set.disc(r, -y, -1.0, n);
            }
            if top {
                set.disc(r, y, 1.0, n);
            }
        }
        Shape::Cone {
            radius: r,
            height,
            side,
            bottom,
        } => {
            if !usable(&[r, height]) {
                return set;
            }
            let y = height / 2.0;
            if side {
                // The side's normal leans up by atan(r/h); the apex gets one vertex per
                // segment, with the normal of the segment's middle.
                let normal = |s: f64, c: f64| DVec3::new(c * height, r, s * height).normalize();
                for k in 0..n {
                    let (s0, c0) = angle(k, n);
                    let (s1, c1) = angle(k + 1, n);
                    let mid = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
                    let (sm, cm) = (libm::sin(mid), libm::cos(mid));
                    let (u0, u1) = (around_s(k, n), around_s(k + 1, n));
                    let a = set.vertex(DVec3::new(c0 * r, -y, s0 * r), normal(s0, c0), [u0, 0.0]);
                    let b = set.vertex(DVec3::new(c1 * r, -y, s1 * r), normal(s1, c1), [u1, 0.0]);
                    let apex = set.vertex(
                        DVec3::new(0.0, y, 0.0),
                        normal(sm, cm),
                        [(u0 + u1) / 2.0, 1.0],
                    );
                    set.triangles.push([a, apex, b]);
                }
            }
            if bottom {
                set.disc(r, -y, -1.0, n);
            }
        }
        Shape::Mesh(index) => {
            if let Some(mesh) = meshes.get(index) {
                return match detail.mesh_normals {
                    MeshNormals::Flat => flat_mesh(mesh),
                    MeshNormals::Crease => crease_mesh(mesh),
                };
            }
        }
    }
    set
}

/// Unshared corners: each triangle flat, with its own colour.
fn flat_mesh(mesh: &Mesh) -> Tessellation {
    let colors = mesh
        .triangle_colors
        .as_ref()
        .filter(|c| c.len() == mesh.triangles.len());
    let mut set = Tessellation {
        colors: colors.map(|_| Vec::new()),
        ..Tessellation::default()
    };
    let uv_of = mesh_tex_coords(mesh);
    for (t, triangle) in mesh.triangles.iter().enumerate() {
        let Some([a, b, c]) = corners(mesh, triangle) else {
            continue;
        };
        let normal = (b - a).cross(c - a);
        let length = normal.length();
        if !(length.is_finite() && length > 0.0) {
            continue;
        }
        let normal = normal / length;
        let first = set.positions.len() as u32;
        for (corner, p) in [a, b, c].into_iter().enumerate() {
            set.vertex(p, normal, uv_of(t, corner));
        }
        if let (Some(out), Some(colors)) = (&mut set.colors, colors) {
            out.extend([colors[t]; 3]);
        }
        set.triangles.push([first, first + 1, first + 2]);
    }
    set
}

fn corners(mesh: &Mesh, triangle: &[u32; 3]) -> Option<[DVec3; 3]> {
    let mut out = [DVec3::ZERO; 3];
    for (slot, &i) in out.iter_mut().zip(triangle) {
        let p = *mesh.positions.get(i as usize)?;
        if !p.is_finite() {
            return None;
        }
        *slot = p;
    }
    Some(out)
}

fn unit_or_up(v: DVec3) -> DVec3 {
    v.try_normalize().unwrap_or(DVec3::Y)
}

/// Vertex normals by VRML97's creaseAngle rule: at each corner, the area-weighted average of
/// the normals of the triangles around that point whose angle to this triangle's normal is at
/// most creaseAngle. Corners that end up with the same position, normal, colour and texture
/// coordinates share a vertex.
fn crease_mesh(mesh: &Mesh) -> Tessellation {
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
    let mut out = Tessellation {
        colors: (mesh.corner_colors.is_some() || mesh.triangle_colors.is_some()).then(Vec::new),
        ..Tessellation::default()
    };
    let uv_of = mesh_tex_coords(mesh);
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
            let normal = unit_or_up(if sum == DVec3::ZERO { own } else { sum });
            let color = color_of(index, corner);
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
                found = out.vertex(positions[point as usize], normal, uv);
                if let (Some(colors), Some(c)) = (&mut out.colors, color) {
                    colors.push(c);
                }
                next.push(head[point as usize]);
                head[point as usize] = found;
            }
            corners[corner] = found;
        }
        out.triangles.push(corners);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_shapes() -> Vec<Shape> {
        vec![
            Shape::Sphere { radius: 0.5 },
            Shape::Cylinder {
                radius: 0.5,
                height: 1.0,
                side: true,
                bottom: true,
                top: true,
            },
            Shape::Cone {
                radius: 0.5,
                height: 1.0,
                side: true,
                bottom: true,
            },
            Shape::Box {
                half: DVec3::new(0.5, 0.5, 0.5),
            },
        ]
    }

    #[test]
    fn round_shapes_reach_their_extremes_and_face_outwards() {
        for shape in round_shapes() {
            for detail in [Detail::export(8), Detail::export(13), Detail::RASTER] {
                let t = tessellate(&shape, &[], &detail);
                let (lo, hi) = t.positions.iter().fold(
                    (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
                    |(lo, hi), &p| (lo.min(p), hi.max(p)),
                );
                assert_eq!(
                    (lo, hi),
                    (DVec3::splat(-0.5), DVec3::splat(0.5)),
                    "{shape:?}"
                );
                assert_eq!(t.normals.len(), t.positions.len());
                assert_eq!(t.uvs.len(), t.positions.len());
                for tri in &t.triangles {
                    let [a, b, c] = tri.map(|i| t.positions[i as usize]);
                    let facing = (b - a).cross(c - a);
                    assert!(facing.length() > 1e-9, "{shape:?}: a triangle without area");
                    // Counter-clockwise seen from outside, and from where the normals face.
                    assert!(facing.dot((a + b + c) / 3.0) > 0.0, "{shape:?} {detail:?}");
                    for i in tri {
                        assert!(facing.dot(t.normals[*i as usize]) > 0.0, "{shape:?}");
                        assert!((t.normals[*i as usize].length() - 1.0).abs() < 1e-12);
                    }
                }
            }
        }
    }

    #[test]
    fn large_faces_are_cut_into_cells_only_when_asked() {
        let shape = Shape::Box {
            half: DVec3::new(0.5, 0.05, 100.0),
        };
        let whole = tessellate(&shape, &[], &Detail::export(32));
        assert_eq!(whole.triangles.len(), 12);
        let cut = tessellate(&shape, &[], &Detail::RASTER);
        // ±x: 1 × 16 cells, ±y: 4 × 16, ±z: 4 × 1.
        assert_eq!(cut.triangles.len(), 2 * 2 * (16 + 64 + 4));
    }

    #[test]
    fn box_faces_show_the_whole_image_upright() {
        let t = tessellate(
            &Shape::Box {
                half: DVec3::new(1.0, 2.0, 3.0),
            },
            &[],
            &Detail::RASTER,
        );
        for (i, p) in t.positions.iter().enumerate() {
            let [s, v] = t.uvs[i];
            assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&v));
            // The front face (+z): s along x, t along y.
            if t.normals[i] == DVec3::Z {
                assert_eq!([s, v], [(p.x + 1.0) / 2.0, (p.y + 2.0) / 4.0]);
            }
        }
    }

    #[test]
    fn the_texture_wraps_from_the_back_counter_clockwise_seen_from_above() {
        let t = tessellate(&round_shapes()[1], &[], &Detail::export(8));
        let s_at = |direction: DVec3| {
            let i = (0..t.positions.len())
                .find(|&i| (t.normals[i] - direction).length() < 1e-12)
                .unwrap();
            t.uvs[i][0].rem_euclid(1.0)
        };
        assert_eq!(s_at(DVec3::NEG_X), 0.25);
        assert_eq!(s_at(DVec3::Z), 0.5);
        assert_eq!(s_at(DVec3::X), 0.75);
        assert_eq!(s_at(DVec3::NEG_Z), 0.0);
    }

    #[test]
    fn degenerate_shapes_give_no_triangles() {
        for shape in [
            Shape::Box {
                half: DVec3::new(0.0, 1.0, 1.0),
            },
            Shape::Sphere { radius: f64::NAN },
            Shape::Cylinder {
                radius: -1.0,
                height: 1.0,
                side: true,
                bottom: true,
                top: true,
            },
            Shape::Cone {
                radius: 1.0,
                height: f64::INFINITY,
                side: true,
                bottom: true,
            },
            Shape::Mesh(7),
        ] {
            for detail in [Detail::RASTER, Detail::export(32)] {
                assert!(
                    tessellate(&shape, &[], &detail).triangles.is_empty(),
                    "{shape:?}"
                );
            }
            assert!(
                no_surface(&shape).is_some() || matches!(shape, Shape::Mesh(_)),
                "{shape:?}"
            );
        }
    }

    #[test]
    fn a_cylinder_or_cone_without_parts_has_no_surface() {
        let empty = [
            Shape::Cylinder {
                radius: 1.0,
                height: 1.0,
                side: false,
                bottom: false,
                top: false,
            },
            Shape::Cone {
                radius: 1.0,
                height: 1.0,
                side: false,
                bottom: false,
            },
        ];
        for shape in empty {
            assert!(no_surface(&shape).is_some());
            assert!(tessellate(&shape, &[], &Detail::RASTER)
                .triangles
                .is_empty());
        }
        for shape in round_shapes() {
            assert_eq!(no_surface(&shape), None);
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
        let crease = Detail::export(32);
        let count = |m: Mesh, d: &Detail| tessellate(&Shape::Mesh(0), &[m], d).positions.len();
        assert_eq!(count(mesh(0.0), &crease), 6);
        assert_eq!(count(mesh(0.5), &crease), 4);
        // The rasteriser's flat triangles never share corners.
        assert_eq!(count(mesh(0.5), &Detail::RASTER), 6);
    }
}
