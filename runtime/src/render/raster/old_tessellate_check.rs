//! TEMPORARY (deleted before merge): the rasteriser's former tessellation, compared with
//! `crate::tessellate` at `Detail::RASTER`.
//!
//! The render graph's shapes as triangles, in their local frames, once per world: the
//! geometric half of the rasteriser, kept apart from its pipeline.
//!
//! Flat faces keep their face normal (as the ray caster's exact intersections give it); curved
//! surfaces carry the smooth normal at each vertex, so that per-vertex lighting interpolates
//! across them. Large flat faces are cut into a grid, so that point and spot lights, whose
//! attenuation varies across a face, are sampled often enough for Gouraud interpolation.

use glam::DVec3;

use crate::compile::graph::{Mesh, Shape};

/// Segments around a cylinder, cone or sphere: the polygon's radial error is
/// 1 − cos(π/32) ≈ 0.5 % of the radius, under a pixel for objects narrower than ~200 pixels.
const SEGMENTS: usize = 32;

/// A flat face longer than this (m) is cut, so that lights are sampled at least this often.
const CELL: f64 = 0.25;

/// At most this many cells per side of a face: a 100 m floor does not cost 160,000 triangles.
const MAX_CELLS: usize = 16;

/// One vertex: position, unit normal, and a colour that replaces the material's diffuse
/// colour (a mesh's Color node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub position: DVec3,
    pub normal: DVec3,
    pub color: Option<[f64; 3]>,
}

/// Triangles over shared vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSet {
    pub vertices: Vec<Vertex>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleSet {
    fn vertex(&mut self, position: DVec3, normal: DVec3, color: Option<[f64; 3]>) -> u32 {
        self.vertices.push(Vertex {
            position,
            normal,
            color,
        });
        (self.vertices.len() - 1) as u32
    }

    /// A parallelogram `origin + s·u + t·v` (s, t in 0…1), cut into a grid, facing `normal`.
    fn quad(&mut self, origin: DVec3, u: DVec3, v: DVec3, normal: DVec3) {
        let cells = |length: f64| {
            let n = (length / CELL).ceil();
            if n.is_finite() && n >= 1.0 {
                (n as usize).min(MAX_CELLS)
            } else {
                1
            }
        };
        let (nu, nv) = (cells(u.length()), cells(v.length()));
        let first = self.vertices.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let p = origin + u * (i as f64 / nu as f64) + v * (j as f64 / nv as f64);
                self.vertex(p, normal, None);
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

    /// A disc of `radius` at height `y`, facing `normal` (±y).
    fn disc(&mut self, radius: f64, y: f64, normal: DVec3) {
        let centre = self.vertex(DVec3::new(0.0, y, 0.0), normal, None);
        let first = self.vertices.len() as u32;
        for k in 0..SEGMENTS {
            let (s, c) = angle(k);
            self.vertex(DVec3::new(c * radius, y, s * radius), normal, None);
        }
        for k in 0..SEGMENTS as u32 {
            let next = (k + 1) % SEGMENTS as u32;
            self.triangles.push([centre, first + k, first + next]);
        }
    }
}

fn angle(k: usize) -> (f64, f64) {
    let a = std::f64::consts::TAU * k as f64 / SEGMENTS as f64;
    (libm::sin(a), libm::cos(a))
}

/// Whether every number that shapes the geometry is finite and positive: anything else draws
/// nothing (a zero-size or degenerate shape is a clean skip, never a panic or a NaN pixel).
fn usable(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite() && *v > 0.0)
}

/// The shape's triangles in its local frame (empty for degenerate shapes).
fn tessellate(shape: &Shape, meshes: &[Mesh]) -> TriangleSet {
    let mut set = TriangleSet::default();
    match shape {
        Shape::Box { half } => {
            if !usable(&[half.x, half.y, half.z]) {
                return set;
            }
            let h = *half;
            let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
            // Each face: a corner and two edges, then its outward normal.
            set.quad(
                h * DVec3::new(1.0, -1.0, -1.0),
                y * 2.0 * h.y,
                z * 2.0 * h.z,
                x,
            );
            set.quad(-h, z * 2.0 * h.z, y * 2.0 * h.y, -x);
            set.quad(
                h * DVec3::new(-1.0, 1.0, -1.0),
                z * 2.0 * h.z,
                x * 2.0 * h.x,
                y,
            );
            set.quad(-h, x * 2.0 * h.x, z * 2.0 * h.z, -y);
            set.quad(
                h * DVec3::new(-1.0, -1.0, 1.0),
                x * 2.0 * h.x,
                y * 2.0 * h.y,
                z,
            );
            set.quad(-h, y * 2.0 * h.y, x * 2.0 * h.x, -z);
        }
        Shape::Sphere { radius } => {
            if !usable(&[*radius]) {
                return set;
            }
            let rings = SEGMENTS / 2;
            for ring in 0..=rings {
                let polar = std::f64::consts::PI * ring as f64 / rings as f64;
                let (sp, cp) = (libm::sin(polar), libm::cos(polar));
                for k in 0..=SEGMENTS {
                    let (s, c) = angle(k);
                    let n = DVec3::new(sp * c, cp, sp * s);
                    set.vertex(n * *radius, n, None);
                }
            }
            let stride = SEGMENTS as u32 + 1;
            for ring in 0..rings as u32 {
                for k in 0..SEGMENTS as u32 {
                    let a = ring * stride + k;
                    let (b, c, d) = (a + 1, a + stride, a + stride + 1);
                    set.triangles.push([a, b, d]);
                    set.triangles.push([a, d, c]);
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
            if !usable(&[*radius, *height]) {
                return set;
            }
            let (r, y) = (*radius, height / 2.0);
            if *side {
                let first = set.vertices.len() as u32;
                for k in 0..=SEGMENTS {
                    let (s, c) = angle(k);
                    let n = DVec3::new(c, 0.0, s);
                    set.vertex(DVec3::new(c * r, -y, s * r), n, None);
                    set.vertex(DVec3::new(c * r, y, s * r), n, None);
                }
                for k in 0..SEGMENTS as u32 {
                    let a = first + 2 * k;
                    set.triangles.push([a, a + 1, a + 3]);
                    set.triangles.push([a, a + 3, a + 2]);
                }
            }
            if *bottom {
                set.disc(r, -y, -DVec3::Y);
            }
            if *top {
                set.disc(r, y, DVec3::Y);
            }
        }
        Shape::Cone {
            radius,
            height,
            side,
            bottom,
        } => {
            if !usable(&[*radius, *height]) {
                return set;
            }
            let (r, y) = (*radius, height / 2.0);
            if *side {
                // The side's normal leans up by atan(r/h); the apex gets one vertex per segment,
                // with the normal of the segment's middle.
                let normal = |s: f64, c: f64| DVec3::new(c * height, r, s * height).normalize();
                for k in 0..SEGMENTS {
                    let (s0, c0) = angle(k);
                    let (s1, c1) = angle(k + 1);
                    let mid = std::f64::consts::TAU * (k as f64 + 0.5) / SEGMENTS as f64;
                    let (sm, cm) = (libm::sin(mid), libm::cos(mid));
                    let a = set.vertex(DVec3::new(c0 * r, -y, s0 * r), normal(s0, c0), None);
                    let b = set.vertex(DVec3::new(c1 * r, -y, s1 * r), normal(s1, c1), None);
                    let apex = set.vertex(DVec3::new(0.0, y, 0.0), normal(sm, cm), None);
                    set.triangles.push([a, apex, b]);
                }
            }
            if *bottom {
                set.disc(r, -y, -DVec3::Y);
            }
        }
        Shape::Mesh(index) => {
            let Some(mesh) = meshes.get(*index) else {
                return set;
            };
            // Unshared vertices: each triangle is flat (the ray caster's geometric normal) and
            // may have its own colour.
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
                let color = mesh
                    .triangle_colors
                    .as_ref()
                    .and_then(|colors| colors.get(t).copied());
                let first = set.vertex(a, normal, color);
                set.vertex(b, normal, color);
                set.vertex(c, normal, color);
                set.triangles.push([first, first + 1, first + 2]);
            }
        }
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


#[test]
fn the_shared_tessellation_gives_the_rasterisers_triangles() {
    use crate::tessellate::{tessellate as shared, Detail};
    let mut shapes = Vec::new();
    for h in [0.01, 0.1, 0.25, 0.3, 1.0, 3.7, 50.0] {
        shapes.push(Shape::Box { half: DVec3::new(h, 0.5 * h, 2.0 * h) });
        shapes.push(Shape::Sphere { radius: h });
        for (side, bottom, top) in [(true, true, true), (true, false, true), (false, true, false), (true, false, false)] {
            shapes.push(Shape::Cylinder { radius: h, height: 2.0 * h, side, bottom, top });
            shapes.push(Shape::Cone { radius: h, height: 1.5 * h, side, bottom });
        }
    }
    let mesh = Mesh {
        positions: vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1.0, 0.1, -1.0),
            DVec3::new(1.0, 0.1, -1.0),
            DVec3::new(f64::NAN, 0.1, -1.0),
        ],
        triangles: vec![[0, 1, 2], [1, 3, 2], [3, 4, 2], [0, 5, 1]],
        triangle_colors: Some(vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.0; 3], [1.0; 3]]),
        solid: true,
        ..Mesh::default()
    };
    let meshes = vec![mesh.clone(), Mesh { triangle_colors: None, ..mesh }];
    shapes.push(Shape::Mesh(0));
    shapes.push(Shape::Mesh(1));
    let (mut reversed, mut dropped) = (0, 0);
    for shape in &shapes {
        let old = tessellate(shape, &meshes);
        let new = shared(shape, &meshes, &Detail::RASTER);
        assert_eq!(old.vertices.len(), new.positions.len(), "{shape:?}");
        for (i, v) in old.vertices.iter().enumerate() {
            assert_eq!(v.position.to_array().map(f64::to_bits), new.positions[i].to_array().map(f64::to_bits), "{shape:?}");
            assert_eq!(v.normal.to_array().map(f64::to_bits), new.normals[i].to_array().map(f64::to_bits), "{shape:?}");
            assert_eq!(v.color, new.colors.as_ref().map(|c| c[i]), "{shape:?}");
        }
        let mut next = 0;
        for t in &old.triangles {
            if new.triangles.get(next) == Some(t) {
                next += 1;
            } else if new.triangles.get(next) == Some(&[t[0], t[2], t[1]]) {
                reversed += 1;
                next += 1;
            } else {
                let [a, b, c] = t.map(|i| old.vertices[i as usize].position);
                assert!((b - a).cross(c - a).length() < 1e-12, "{shape:?} {t:?}");
                dropped += 1;
            }
        }
        assert_eq!(next, new.triangles.len(), "{shape:?}");
    }
    eprintln!("{reversed} triangles reversed, {dropped} without area dropped");
}
