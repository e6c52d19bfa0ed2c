//! The world's geometry for the page: the runtime's one tessellation as the glTF export takes
//! it (`regatta_gltf::tessellate`, the same triangles at the same quality), flattened into triangle lists with
//! one colour each, static parts in world coordinates and each robot's parts in its own
//! frame (the page places them at every pose).

use std::fmt::Write;

use glam::Vec3;
use regatta_runtime::compile::graph::{Material, Owner};
use regatta_runtime::Compiled;

use crate::sample::num;

/// Segments around a circle: the glTF export's default.
const QUALITY: u32 = 32;

/// The palette robots are told apart by (Okabe–Ito, as the figures use): their heading
/// markers and trails.
pub const ROBOT_COLOURS: [[u8; 3]; 7] = [
    [230, 159, 0],
    [86, 180, 233],
    [0, 158, 115],
    [213, 94, 0],
    [204, 121, 167],
    [0, 114, 178],
    [240, 228, 66],
];

/// Triangles of one owner: nine coordinates and, per triangle, an RGB diffuse colour and an
/// emissive flag's colour.
#[derive(Default)]
struct Soup {
    positions: Vec<f32>,
    colours: Vec<u8>,
    emissive: Vec<u8>,
}

impl Soup {
    fn add(&mut self, compiled: &Compiled, index: usize) {
        let graph = &compiled.graph;
        let primitive = &graph.primitives[index];
        let material = &graph.materials[primitive.material];
        let mut triangles =
            regatta_gltf::tessellate::triangles(&primitive.shape, &graph.meshes, QUALITY);
        triangles.bake(&primitive.frame);
        let (diffuse, emissive) = colours(material);
        for (face, corners) in triangles.indices.chunks_exact(3).enumerate() {
            for &corner in corners {
                let p = triangles
                    .positions
                    .get(corner as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO);
                self.positions.extend_from_slice(&p.to_array());
            }
            // Per-vertex colours (a Color node) are averaged over the face.
            let colour = match &triangles.colors {
                Some(colors) => {
                    let sum = corners
                        .iter()
                        .filter_map(|&c| colors.get(c as usize))
                        .fold(Vec3::ZERO, |a, &b| a + b);
                    rgb([sum.x / 3.0, sum.y / 3.0, sum.z / 3.0].map(f64::from))
                }
                None => diffuse,
            };
            let _ = face;
            self.colours.extend_from_slice(&colour);
            self.emissive.extend_from_slice(&emissive);
        }
    }

    fn write_json(&self, out: &mut String) {
        out.push_str("{\"positions\":[");
        for (i, v) in self.positions.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            let _ = write!(out, "{}", (f64::from(*v) * 1e5).round() / 1e5);
        }
        out.push_str("],\"colours\":");
        write_bytes(&self.colours, out);
        out.push_str(",\"emissive\":");
        write_bytes(&self.emissive, out);
        out.push('}');
    }
}

fn write_bytes(bytes: &[u8], out: &mut String) {
    out.push('[');
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        let _ = write!(out, "{b}");
    }
    out.push(']');
}

fn rgb(c: [f64; 3]) -> [u8; 3] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// A material's diffuse and emissive colours as the page draws them; an unlit material
/// (no Material node) shows its colour as it is, as glTF's KHR_materials_unlit does.
fn colours(material: &Material) -> ([u8; 3], [u8; 3]) {
    if material.unlit {
        ([0; 3], rgb(material.diffuse))
    } else {
        (rgb(material.diffuse), rgb(material.emissive))
    }
}

/// The scene as the page reads it (`/scene.json`).
pub fn scene_json(compiled: &Compiled) -> String {
    let graph = &compiled.graph;
    let rig = &compiled.rig;
    let mut fixed = Soup::default();
    let mut robots: Vec<Soup> = rig.robots.iter().map(|_| Soup::default()).collect();
    for (index, primitive) in graph.primitives.iter().enumerate() {
        match primitive.owner {
            Owner::Static => fixed.add(compiled, index),
            Owner::Robot(robot) => {
                if let Some(soup) = robots.get_mut(robot) {
                    soup.add(compiled, index);
                }
            }
        }
    }
    let bounds = graph.static_bounds();
    let mut out = String::with_capacity(1 << 16);
    let _ = write!(
        out,
        "{{\"title\":{},\"timeStep\":{},\"sky\":{:?},\"bounds\":[{},{},{},{},{},{}],\"static\":",
        serde_json::Value::String(compiled.settings.title.clone()),
        compiled.settings.time_step,
        rgb(graph.background.sky),
        finite(bounds.min.x),
        finite(bounds.min.y),
        finite(bounds.min.z),
        finite(bounds.max.x),
        finite(bounds.max.y),
        finite(bounds.max.z),
    );
    fixed.write_json(&mut out);
    out.push_str(",\"robots\":[");
    for (index, (robot, soup)) in rig.robots.iter().zip(&robots).enumerate() {
        if index > 0 {
            out.push(',');
        }
        let _ = write!(
            out,
            "{{\"name\":{},\"floorY\":{},\"bodyRadius\":{},\"bodyHeight\":{},\"colour\":{:?},\"retina\":{},\"mesh\":",
            serde_json::Value::String(robot.name.clone()),
            num(robot.floor_y),
            num(robot.body_radius),
            num(robot.body_height),
            ROBOT_COLOURS[index % ROBOT_COLOURS.len()],
            matches!(robot.turret, Some(regatta_runtime::compile::rig::TurretRig::Panoramic(_))),
        );
        soup.write_json(&mut out);
        out.push('}');
    }
    out.push_str("],\"buoys\":[");
    for (index, landmark) in compiled.landmarks.iter().enumerate() {
        if index > 0 {
            out.push(',');
        }
        // The lamp: the landmark's brightest emissive part, and its top.
        let lamp = landmark
            .primitives
            .clone()
            .filter_map(|p| graph.primitives.get(p))
            .map(|p| (p, &graph.materials[p.material]))
            .max_by(|a, b| luminance(a.1.emissive).total_cmp(&luminance(b.1.emissive)));
        let (colour, top) = match lamp {
            Some((p, m)) => (colours(m).1, p.frame.translation.y),
            None => ([0; 3], 0.0),
        };
        let _ = write!(
            out,
            "{{\"name\":{},\"x\":{},\"z\":{},\"radius\":{},\"lamp\":{:?},\"lampY\":{},\"disc\":{}}}",
            serde_json::Value::String(landmark.name.clone()),
            num(landmark.center.x),
            num(landmark.center.y),
            num(landmark.radius),
            colour,
            num(top),
            num(regatta_runtime::sim::Visits::disc_radius(
                landmark.radius,
                rig.robots.first().map_or(0.0, |r| r.body_radius)
            )),
        );
    }
    out.push_str("]}");
    out
}

fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn finite(v: f64) -> String {
    if v.is_finite() {
        num(v)
    } else {
        "0".to_owned()
    }
}
