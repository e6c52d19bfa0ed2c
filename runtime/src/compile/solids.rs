//! Geometry regatta tessellates once at compile time: Webots' Plane and Capsule, VRML97's
//! Extrusion and the Webots field convention of ElevationGrid, each into a [`Mesh`] in the
//! shape's local frame (y up; the compiler turns FLU geometry as it turns cylinders).

use glam::{DQuat, DVec2, DVec3};
use regatta_schema::{NodeId, Scene, Value};

use super::graph::Mesh;
use super::triangulate::triangulate_polygon;

/// Webots' Plane: a size.x × size.y rectangle in the x-z plane, facing +y.
pub fn plane(scene: &Scene, node: NodeId) -> Mesh {
    let [sx, sz] = scene.vec2(node, "size");
    let (hx, hz) = (sx / 2.0, sz / 2.0);
    Mesh {
        positions: vec![
            DVec3::new(-hx, 0.0, -hz),
            DVec3::new(-hx, 0.0, hz),
            DVec3::new(hx, 0.0, hz),
            DVec3::new(hx, 0.0, -hz),
        ],
        // Counter-clockwise seen from +y.
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        solid: true,
        // The image upright seen from above with −z up, as on a Box's top.
        tex_coords: Some(vec![
            [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0]],
            [[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]],
        ]),
        ..Mesh::default()
    }
}

/// Webots' Capsule: a cylinder of `height` along y with a hemisphere of `radius` on each end.
pub fn capsule(scene: &Scene, node: NodeId) -> Mesh {
    let radius = scene.float(node, "radius");
    let half = scene.float(node, "height") / 2.0;
    // Segments around: the subdivision, at least 8, rounded up to a multiple of 4 so that the
    // extreme points are vertices (as `tessellate.rs` cuts cylinders).
    let around = (scene.int(node, "subdivision").max(8) as usize).div_ceil(4) * 4;
    let rings = around / 4;
    let mut mesh = Mesh {
        solid: true,
        crease_angle: std::f64::consts::PI,
        ..Mesh::default()
    };
    let ring = |mesh: &mut Mesh, y: f64, r: f64| -> u32 {
        let first = mesh.positions.len() as u32;
        for k in 0..around {
            let a = std::f64::consts::TAU * k as f64 / around as f64;
            mesh.positions
                .push(DVec3::new(r * libm::cos(a), y, -r * libm::sin(a)));
        }
        first
    };
    // Joins ring `a` (below) to ring `b` (above), facing out.
    let band = |mesh: &mut Mesh, a: u32, b: u32| {
        let n = around as u32;
        for k in 0..n {
            let k1 = (k + 1) % n;
            mesh.triangles.push([a + k, a + k1, b + k1]);
            mesh.triangles.push([a + k, b + k1, b + k]);
        }
    };
    let pole = |mesh: &mut Mesh, ring: u32, y: f64, up: bool| {
        let apex = mesh.positions.len() as u32;
        mesh.positions.push(DVec3::new(0.0, y, 0.0));
        let n = around as u32;
        for k in 0..n {
            let k1 = (k + 1) % n;
            mesh.triangles.push(if up {
                [ring + k, ring + k1, apex]
            } else {
                [ring + k1, ring + k, apex]
            });
        }
    };
    let side = scene.bool(node, "side");
    let (bottom, top) = (scene.bool(node, "bottom"), scene.bool(node, "top"));
    if side {
        let (a, b) = (
            ring(&mut mesh, -half, radius),
            ring(&mut mesh, half, radius),
        );
        band(&mut mesh, a, b);
    }
    for (present, sign) in [(top, 1.0), (bottom, -1.0)] {
        if !present {
            continue;
        }
        // Rings from the equator to the pole.
        let mut previous = ring(&mut mesh, sign * half, radius);
        for i in 1..rings {
            let phi = std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
            let next = ring(
                &mut mesh,
                sign * (half + radius * libm::sin(phi)),
                radius * libm::cos(phi),
            );
            if sign > 0.0 {
                band(&mut mesh, previous, next);
            } else {
                band(&mut mesh, next, previous);
            }
            previous = next;
        }
        pole(&mut mesh, previous, sign * (half + radius), sign > 0.0);
    }
    mesh
}

/// Webots' ElevationGrid (R2022a on: xDimension × yDimension heights in the x-y plane, z up),
/// built in the local frame the compiler then turns to FLU (+90° about x takes local −z to
/// +y), so that point (i, j) lands at (i·xSpacing, j·ySpacing, height) as Webots puts it.
pub fn webots_elevation_grid(scene: &Scene, node: NodeId) -> Mesh {
    let nx = scene.int(node, "xDimension").max(0) as usize;
    let ny = scene.int(node, "yDimension").max(0) as usize;
    let (sx, sy) = (scene.float(node, "xSpacing"), scene.float(node, "ySpacing"));
    let heights = match scene.field(node, "height") {
        Value::Floats(h) => h.as_slice(),
        _ => &[],
    };
    let mut mesh = Mesh {
        solid: scene.bool(node, "solid"),
        crease_angle: scene.float(node, "creaseAngle"),
        ..Mesh::default()
    };
    if nx < 2 || ny < 2 || heights.len() < nx * ny {
        return mesh;
    }
    for j in 0..ny {
        for i in 0..nx {
            mesh.positions.push(DVec3::new(
                i as f64 * sx,
                heights[j * nx + i],
                -(j as f64) * sy,
            ));
        }
    }
    let ccw = scene.bool(node, "ccw");
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = (j * nx + i) as u32;
            let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
            // Rows run towards −z here: counter-clockwise seen from +y.
            let (t1, t2) = ([a, b, c], [b, d, c]);
            for t in [t1, t2] {
                mesh.triangles
                    .push(if ccw { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    mesh.tex_coords_per_point(&super::triangulate::grid_tex_coords(scene, node, nx, ny));
    mesh
}

/// VRML97's Extrusion (6.18): the cross-section, scaled and oriented per spine point, placed
/// in each spine point's cross-section plane (SCP), joined ring to ring, with caps.
pub fn extrusion(scene: &Scene, node: NodeId) -> Mesh {
    let section: Vec<DVec2> = match scene.field(node, "crossSection") {
        Value::Vec2s(v) => v.iter().map(|p| DVec2::from_array(*p)).collect(),
        _ => Vec::new(),
    };
    let spine: Vec<DVec3> = match scene.field(node, "spine") {
        Value::Vec3s(v) => v.iter().map(|p| DVec3::from_array(*p)).collect(),
        _ => Vec::new(),
    };
    let scales: Vec<DVec2> = match scene.field(node, "scale") {
        Value::Vec2s(v) => v.iter().map(|p| DVec2::from_array(*p)).collect(),
        _ => Vec::new(),
    };
    let orientations: &[[f64; 4]] = match scene.field(node, "orientation") {
        Value::Rotations(v) => v,
        _ => &[],
    };
    let mut mesh = Mesh {
        solid: scene.bool(node, "solid"),
        crease_angle: scene.float(node, "creaseAngle"),
        ..Mesh::default()
    };
    if section.len() < 2 || spine.len() < 2 {
        return mesh;
    }
    let frames = spine_frames(&spine);
    let closed_section = section.first() == section.last();
    let n = if closed_section {
        section.len() - 1
    } else {
        section.len()
    };
    for (i, (&point, &(x, y, z))) in spine.iter().zip(&frames).enumerate() {
        let scale = scales
            .get(i)
            .or(scales.last())
            .copied()
            .unwrap_or(DVec2::ONE);
        let turn = orientations
            .get(i)
            .or(orientations.last())
            .map(|r| {
                let axis = DVec3::new(r[0], r[1], r[2]).normalize_or(DVec3::Z);
                DQuat::from_axis_angle(axis, r[3])
            })
            .unwrap_or(DQuat::IDENTITY);
        for p in &section[..n] {
            let local = turn * DVec3::new(p.x * scale.x, 0.0, p.y * scale.y);
            mesh.positions
                .push(point + x * local.x + y * local.y + z * local.z);
        }
    }
    let ccw = scene.bool(node, "ccw");
    let rows = spine.len() as u32;
    let n32 = n as u32;
    let segments = if closed_section { n32 } else { n32 - 1 };
    for r in 0..rows - 1 {
        for k in 0..segments {
            let k1 = (k + 1) % n32;
            let (a, b) = (r * n32 + k, r * n32 + k1);
            let (c, d) = (a + n32, b + n32);
            // VRML97's default section runs counter-clockwise seen from +y: with ccw TRUE
            // its sides then face out.
            for t in [[a, b, c], [b, d, c]] {
                mesh.triangles
                    .push(if ccw { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    if closed_section && n >= 3 {
        let ring: Vec<u32> = (0..n32).collect();
        let last: Vec<u32> = (0..n32).map(|k| (rows - 1) * n32 + k).collect();
        let positions = mesh.positions.clone();
        // The begin cap faces back along the spine, the end cap forward.
        let forward = spine[1] - spine[0];
        for (present, polygon, outward) in [
            (scene.bool(node, "beginCap"), ring, -forward),
            (
                scene.bool(node, "endCap"),
                last,
                spine[spine.len() - 1] - spine[spine.len() - 2],
            ),
        ] {
            if !present {
                continue;
            }
            let before = mesh.triangles.len();
            triangulate_polygon(&positions, &polygon, true, &mut mesh.triangles);
            for t in &mut mesh.triangles[before..] {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                if (b - a).cross(c - a).dot(outward) < 0.0 {
                    t.swap(1, 2);
                }
            }
        }
    }
    mesh
}

/// Each spine point's SCP axes (x, y, z) as VRML97 defines them: y along the spine, z normal
/// to the spine's plane there (kept from the previous point where the spine is straight).
fn spine_frames(spine: &[DVec3]) -> Vec<(DVec3, DVec3, DVec3)> {
    let n = spine.len();
    let closed = n > 2 && spine[0].distance(spine[n - 1]) < 1e-12;
    let mut ys = Vec::with_capacity(n);
    let mut zs: Vec<Option<DVec3>> = Vec::with_capacity(n);
    for i in 0..n {
        let (prev, next) = match i {
            0 if closed => (spine[n - 2], spine[1]),
            0 => (spine[0], spine[1]),
            _ if i == n - 1 && closed => (spine[n - 2], spine[1]),
            _ if i == n - 1 => (spine[n - 2], spine[n - 1]),
            _ => (spine[i - 1], spine[i + 1]),
        };
        ys.push((next - prev).normalize_or_zero());
        let z = if (i == 0 || i == n - 1) && !closed {
            None
        } else {
            let here = spine[i];
            let z = (next - here).cross(prev - here);
            (z.length() > 1e-12).then(|| z.normalize())
        };
        zs.push(z);
    }
    // Ends and straight stretches take the nearest defined z; none at all: the rotation of
    // +y onto the spine's direction carries +z.
    let first = zs.iter().flatten().next().copied();
    let mut last = first;
    let mut frames = Vec::with_capacity(n);
    for i in 0..n {
        let y = if ys[i] == DVec3::ZERO {
            DVec3::Y
        } else {
            ys[i]
        };
        let mut z = match zs[i] {
            Some(z) => {
                if let Some(previous) = last {
                    if z.dot(previous) < 0.0 {
                        -z
                    } else {
                        z
                    }
                } else {
                    z
                }
            }
            None => last.unwrap_or_else(|| DQuat::from_rotation_arc(DVec3::Y, y) * DVec3::Z),
        };
        // Keep z normal to y.
        z = (z - y * z.dot(y)).normalize_or(DQuat::from_rotation_arc(DVec3::Y, y) * DVec3::Z);
        last = Some(z);
        frames.push((y.cross(z), y, z));
    }
    frames
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(text: &str) -> (Scene, NodeId) {
        let source = regatta_parser::SourceText::from_bytes("t.wbt".to_owned(), text.into());
        let checked = regatta_schema::check(source, &regatta_schema::Options::default());
        assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
        let scene = checked.scene;
        let node = scene.walk().into_iter().find(|&n| {
            matches!(
                scene.type_name(n),
                "Plane" | "Capsule" | "Extrusion" | "ElevationGrid"
            )
        });
        (scene.clone(), node.expect("a geometry node"))
    }

    fn area_normal(mesh: &Mesh) -> DVec3 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                (b - a).cross(c - a) / 2.0
            })
            .sum()
    }

    fn volume(mesh: &Mesh) -> f64 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn a_plane_faces_up_with_its_area() {
        let (scene, node) = scene("#VRML_SIM R2021a utf8\nShape { geometry Plane { size 2 3 } }");
        let mesh = plane(&scene, node);
        let n = area_normal(&mesh);
        assert!(
            (n.y - 6.0).abs() < 1e-12 && n.x.abs() < 1e-12 && n.z.abs() < 1e-12,
            "{n}"
        );
    }

    #[test]
    fn a_capsule_is_closed_outward_with_about_its_volume() {
        let (scene, node) = scene(
            "#VRML_SIM R2021a utf8\nShape { geometry Capsule { radius 0.5 height 2 subdivision 48 } }",
        );
        let mesh = capsule(&scene, node);
        let exact = std::f64::consts::PI * 0.25 * 2.0 + 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        let v = volume(&mesh);
        assert!(v > 0.97 * exact && v <= exact, "{v} against {exact}");
        assert!(area_normal(&mesh).length() < 1e-9);
    }

    #[test]
    fn the_default_extrusion_is_a_closed_unit_box_facing_out() {
        let (scene, node) = scene("#VRML V2.0 utf8\nShape { geometry Extrusion { } }");
        let mesh = extrusion(&scene, node);
        // The default section is 2 × 2, the spine 1 long: a volume of 4.
        assert_eq!(mesh.triangles.len(), 12);
        assert!((volume(&mesh) - 4.0).abs() < 1e-9, "{}", volume(&mesh));
    }

    #[test]
    fn a_webots_grid_faces_up_and_spans_its_spacing() {
        let (scene, node) = scene(
            "#VRML_SIM R2021a utf8\nShape { geometry ElevationGrid { xDimension 3 yDimension 2 xSpacing 1 ySpacing 2 height [0 0 0 0 0 0] } }",
        );
        let mesh = webots_elevation_grid(&scene, node);
        let n = area_normal(&mesh);
        assert!((n.y - 4.0).abs() < 1e-12, "{n}");
    }
}
