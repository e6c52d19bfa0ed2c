//! glTF 2.0 export of a compiled world: this crate owns the conversion from the render graph
//! and sensor rig to a glTF document (JSON plus one binary buffer), and the animation of
//! recorded robot poses. It reads the compiled form only; it never looks at the syntax tree.
//!
//! Conventions (glTF's own): metres, y up, right-handed, cameras and lights looking along −z.
//! The render graph is already y-up (z-up Webots worlds are turned −90° about x by the schema),
//! so no further axis change is made. Conversions that are not one-to-one are listed on
//! [`export`] and in ARCHITECTURE.md.

mod lines;
pub mod report;
pub mod tessellate;
mod textures;

use std::collections::{BTreeSet, HashMap};

use glam::{DMat3, DQuat, DVec3, Vec3};
use regatta_runtime::compile::graph::{LightKind, Material, Owner, RenderGraph, Shape};
use regatta_runtime::compile::rig::{Optics, Pose2, RobotRig, TurretRig};
use regatta_runtime::geometry::Frame;
use regatta_runtime::Compiled;
use serde_json::{json, Map, Value};

pub use report::{report, Row};
pub use tessellate::{segments, Triangles};

/// Export settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Segments around a full circle for cylinders, cones and spheres (rounded up to a
    /// multiple of 4, at least 8).
    pub quality: u32,
}

impl Default for Options {
    fn default() -> Options {
        Options { quality: 32 }
    }
}

/// One robot's recorded poses, for the animation: times in seconds, strictly increasing.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// Index of the robot in the sensor rig.
    pub robot: usize,
    pub times: Vec<f64>,
    pub poses: Vec<Pose2>,
}

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("the export needs {0} bytes of binary data; glTF buffers stop at 4 GiB")]
    TooLarge(usize),
    #[error("track for robot {robot}: {reason}")]
    BadTrack { robot: usize, reason: String },
}

/// An exported document: the glTF JSON and its binary buffer.
#[derive(Clone, Debug)]
pub struct Document {
    pub json: Value,
    pub bin: Vec<u8>,
    /// How many glTF nodes were written.
    pub node_count: usize,
    /// How many triangles the meshes hold (shared meshes once).
    pub triangle_count: usize,
}

impl Document {
    /// Binary glTF (.glb): the JSON and the buffer in one file.
    pub fn to_glb(&self) -> Vec<u8> {
        let json = serde_json::to_vec(&self.json).expect("a JSON value always serialises");
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0, // computed by the writer
            },
            json: json.into(),
            bin: (!self.bin.is_empty()).then(|| self.bin.as_slice().into()),
        };
        glb.to_vec().expect("writing to memory cannot fail")
    }

    /// Text glTF (.gltf) whose buffer lives in a separate file named `bin_uri`.
    pub fn to_gltf(&self, bin_uri: &str) -> String {
        let mut json = self.json.clone();
        if let Some(buffer) = json["buffers"].get_mut(0) {
            buffer["uri"] = Value::String(bin_uri.to_owned());
        }
        serde_json::to_string_pretty(&json).expect("a JSON value always serialises")
    }
}

/// Exports a compiled world, with an animation when `tracks` is not empty.
///
/// - Nodes: one per render-graph group (named by DEF, PROTO instance or type), per primitive,
///   per line or point set (glTF modes LINES and POINTS, unlit), per light, for the Viewpoint, and per robot sensor (a child of its robot, with its
///   parameters in `extras`). Robots are scene roots so that their animation is in world
///   coordinates.
/// - Transforms that glTF's translation–rotation–scale cannot carry (a shear from
///   scaleOrientation) are applied to the vertices instead; the geometry is the same.
/// - Material: diffuseColor → baseColorFactor; transparency → alpha (BLEND); shininess →
///   roughness = (2/(128·shininess+2))^¼ (Blinn–Phong exponent to GGX), metallic 0;
///   emissiveColor → emissiveFactor (KHR_materials_emissive_strength above 1); no Material →
///   KHR_materials_unlit; `solid FALSE` and open cylinders → doubleSided. Colour nodes →
///   COLOR_0, with baseColor white as VRML replaces the diffuse colour.
/// - Lights (KHR_lights_punctual): intensity and colour as given; VRML's attenuation
///   1/max(a0 + a1·d + a2·d², 1) becomes glTF's inverse square matched at 1 m,
///   I = intensity / max(a0 + a1 + a2, 1), exact for pure quadratic attenuation; radius →
///   range; beamWidth/cutOffAngle → inner/outer cone angles. The originals go in `extras`.
pub fn export(
    compiled: &Compiled,
    options: &Options,
    tracks: &[Track],
) -> Result<Document, ExportError> {
    let mut builder = Builder::new(compiled, options);
    builder.groups();
    builder.primitives();
    builder.lines();
    builder.lights();
    builder.viewpoint();
    builder.sensors();
    builder.animation(tracks)?;
    builder.finish()
}

/// A node's translation, rotation and scale.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Trs {
    translation: DVec3,
    rotation: DQuat,
    scale: DVec3,
}

/// Splits a frame into glTF's T·R·S, if it has no shear.
fn trs(frame: &Frame) -> Option<Trs> {
    let l = frame.linear;
    let mut scale = DVec3::new(l.x_axis.length(), l.y_axis.length(), l.z_axis.length());
    if !(scale.min_element() > 1e-12 && scale.is_finite() && frame.translation.is_finite()) {
        return None;
    }
    let mut x = l.x_axis / scale.x;
    if l.determinant() < 0.0 {
        scale.x = -scale.x;
        x = -x;
    }
    let rotation = DMat3::from_cols(x, l.y_axis / scale.y, l.z_axis / scale.z);
    let error = rotation.transpose() * rotation - DMat3::IDENTITY;
    let worst = [error.x_axis, error.y_axis, error.z_axis]
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max);
    (worst < 1e-9).then(|| Trs {
        translation: frame.translation,
        rotation: DQuat::from_mat3(&rotation).normalize(),
        scale,
    })
}

/// A rigid frame at `origin` whose `from` axis is turned onto `to`.
fn aimed(origin: DVec3, from: DVec3, to: DVec3) -> Frame {
    let to = to.try_normalize().unwrap_or(from);
    Frame {
        linear: DMat3::from_quat(DQuat::from_rotation_arc(from, to)),
        translation: origin,
    }
}

fn f32s<const N: usize>(v: [f64; N]) -> Value {
    json!(v.map(|x| x as f32).to_vec())
}

fn clamp01(v: [f64; 3]) -> [f64; 3] {
    v.map(|x| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    })
}

const LIGHTS: &str = "KHR_lights_punctual";
const UNLIT: &str = "KHR_materials_unlit";
const EMISSIVE_STRENGTH: &str = "KHR_materials_emissive_strength";

struct Builder<'a> {
    compiled: &'a Compiled,
    graph: &'a RenderGraph,
    quality: u32,
    bin: Vec<u8>,
    buffer_views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    lights: Vec<Value>,
    cameras: Vec<Value>,
    nodes: Vec<Map<String, Value>>,
    children: Vec<Vec<usize>>,
    roots: Vec<usize>,
    /// The world frame each node's children are placed in.
    effective: Vec<Frame>,
    group_nodes: Vec<usize>,
    robot_nodes: Vec<Option<usize>>,
    material_cache: HashMap<(usize, bool, bool), usize>,
    mesh_cache: HashMap<(String, usize, usize), usize>,
    extensions_used: BTreeSet<&'static str>,
    animations: Vec<Value>,
    triangle_count: usize,
    /// Images, samplers and textures written so far.
    written: Written,
    /// glTF materials that map an image: their meshes carry TEXCOORD_0.
    textured: std::collections::HashSet<usize>,
}

impl<'a> Builder<'a> {
    fn new(compiled: &'a Compiled, options: &Options) -> Builder<'a> {
        Builder {
            compiled,
            graph: &compiled.graph,
            quality: options.quality,
            bin: Vec::new(),
            buffer_views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            cameras: Vec::new(),
            nodes: Vec::new(),
            children: Vec::new(),
            roots: Vec::new(),
            effective: Vec::new(),
            group_nodes: Vec::new(),
            robot_nodes: vec![None; compiled.rig.robots.len()],
            material_cache: HashMap::new(),
            mesh_cache: HashMap::new(),
            extensions_used: BTreeSet::new(),
            animations: Vec::new(),
            triangle_count: 0,
            written: Default::default(),
            textured: Default::default(),
        }
    }

    /// The world frame of a robot as compiled (its start pose).
    fn robot_world(&self, robot: usize) -> Frame {
        match self.robot_nodes.get(robot).copied().flatten() {
            Some(node) => self.effective[node],
            None => {
                let rig = &self.compiled.rig.robots[robot];
                rig.start.frame(rig.floor_y)
            }
        }
    }

    fn world(&self, owner: Owner, frame: &Frame) -> Frame {
        match owner {
            Owner::Static => *frame,
            Owner::Robot(robot) => self.robot_world(robot).then(frame),
        }
    }

    /// The node (and its world frame) a thing in `group` hangs from; `None` is the scene root.
    fn parent_of(&self, group: Option<usize>) -> (Option<usize>, Frame) {
        match group {
            Some(group) => {
                let node = self.group_nodes[group];
                (Some(node), self.effective[node])
            }
            None => (None, Frame::IDENTITY),
        }
    }

    /// The rigid anchor of a thing: its robot's node, else the scene root.
    fn anchor_of(&self, owner: Owner) -> (Option<usize>, Frame) {
        match owner {
            Owner::Robot(robot) => match self.robot_nodes[robot] {
                Some(node) => (Some(node), self.effective[node]),
                None => (None, Frame::IDENTITY),
            },
            Owner::Static => (None, Frame::IDENTITY),
        }
    }

    /// Adds a node under `parent` whose children are placed in `effective`.
    fn add_node(
        &mut self,
        parent: Option<usize>,
        name: &str,
        transform: Option<Trs>,
        effective: Frame,
    ) -> usize {
        let mut node = Map::new();
        node.insert("name".into(), json!(name));
        if let Some(t) = transform {
            if t.translation != DVec3::ZERO {
                node.insert("translation".into(), f32s(t.translation.to_array()));
            }
            if t.rotation != DQuat::IDENTITY {
                node.insert("rotation".into(), f32s(t.rotation.to_array()));
            }
            if t.scale != DVec3::ONE {
                node.insert("scale".into(), f32s(t.scale.to_array()));
            }
        }
        self.nodes.push(node);
        self.children.push(Vec::new());
        self.effective.push(effective);
        let index = self.nodes.len() - 1;
        match parent {
            Some(parent) => self.children[parent].push(index),
            None => self.roots.push(index),
        }
        index
    }

    /// Places a rigid thing (light, sensor) at world frame `world`: under `preferred` when the
    /// relative transform is a TRS, else under its anchor.
    fn add_rigid(
        &mut self,
        preferred: (Option<usize>, Frame),
        anchor: (Option<usize>, Frame),
        name: &str,
        world: Frame,
    ) -> usize {
        for (parent, parent_world) in [preferred, anchor] {
            if let Some(local) = parent_world.inverse().map(|inv| inv.then(&world)) {
                if let Some(t) = trs(&local) {
                    return self.add_node(parent, name, Some(t), world);
                }
            }
        }
        let fallback = trs(&world).unwrap_or(Trs {
            translation: world.translation,
            rotation: DQuat::IDENTITY,
            scale: DVec3::ONE,
        });
        self.add_node(None, name, Some(fallback), world)
    }

    fn groups(&mut self) {
        let graph = self.graph;
        for group in &graph.groups {
            let (parent, parent_world) = if group.robot.is_some() {
                (None, Frame::IDENTITY)
            } else {
                self.parent_of(group.parent)
            };
            let world = self.world(group.owner, &group.frame);
            let local = parent_world.inverse().map(|inv| inv.then(&world));
            let node = match local.as_ref().and_then(trs) {
                Some(t) => self.add_node(parent, &group.name, Some(t), world),
                None => {
                    // A shear (or a zero scale): keep the offset, let the children carry the rest.
                    let translation = local.map_or(DVec3::ZERO, |l| l.translation);
                    let effective = parent_world.then(&Frame {
                        linear: DMat3::IDENTITY,
                        translation,
                    });
                    let t = Trs {
                        translation,
                        rotation: DQuat::IDENTITY,
                        scale: DVec3::ONE,
                    };
                    self.add_node(parent, &group.name, Some(t), effective)
                }
            };
            self.group_nodes.push(node);
            if let Some(robot) = group.robot {
                self.robot_nodes[robot] = Some(node);
                let rig = &self.compiled.rig.robots[robot];
                self.nodes[node].insert("extras".into(), robot_extras(rig));
            }
        }
    }

    fn primitives(&mut self) {
        let graph = self.graph;
        for primitive in &graph.primitives {
            let (parent, parent_world) = self.parent_of(primitive.group);
            let world = self.world(primitive.owner, &primitive.frame);
            let Some(local) = parent_world.inverse().map(|inv| inv.then(&world)) else {
                continue;
            };
            // Nothing to draw (a Cylinder with no side, top or bottom): no empty mesh, which
            // glTF forbids; the report says why.
            if tessellate::no_triangles(&primitive.shape, graph).is_some() {
                continue;
            }
            let material = &graph.materials[primitive.material];
            let (colored, double_sided) = match &primitive.shape {
                Shape::Mesh(index) => {
                    let mesh = &graph.meshes[*index];
                    (mesh.triangle_colors.is_some(), !mesh.solid)
                }
                Shape::Cylinder { top, bottom, .. } => (false, !top || !bottom),
                Shape::Cone { bottom, .. } => (false, !bottom),
                _ => (false, false),
            };
            let material_index = self.material(primitive.material, material, colored, double_sided);
            let (transform, mesh) = match trs(&local) {
                Some(t) => (Some(t), self.shared_mesh(&primitive.shape, material_index)),
                None => {
                    let mut triangles =
                        tessellate::triangles(&primitive.shape, &graph.meshes, self.quality);
                    triangles.bake(&local);
                    (
                        None,
                        self.mesh(&triangles, material_index, primitive.shape.name()),
                    )
                }
            };
            let node = self.add_node(parent, primitive.shape.name(), transform, world);
            self.nodes[node].insert("mesh".into(), json!(mesh));
        }
    }

    fn shared_mesh(&mut self, shape: &Shape, material: usize) -> usize {
        // Analytic shapes are keyed by their parameters, meshes by their index.
        let cache_key = match shape {
            Shape::Mesh(index) => (String::new(), *index, material),
            other => (format!("{other:?}"), usize::MAX, material),
        };
        if let Some(&mesh) = self.mesh_cache.get(&cache_key) {
            return mesh;
        }
        let triangles = tessellate::triangles(shape, &self.graph.meshes, self.quality);
        let mesh = self.mesh(&triangles, material, shape.name());
        self.mesh_cache.insert(cache_key, mesh);
        mesh
    }

    fn mesh(&mut self, triangles: &Triangles, material: usize, name: &str) -> usize {
        self.triangle_count += triangles.indices.len() / 3;
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let (lo, hi) = triangles.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let mut attributes = Map::new();
        let position = self.accessor(
            &flat(&triangles.positions),
            "VEC3",
            Some(34962),
            Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
        );
        attributes.insert("POSITION".into(), json!(position));
        let normal = self.accessor(&flat(&triangles.normals), "VEC3", Some(34962), None);
        attributes.insert("NORMAL".into(), json!(normal));
        if let Some(colors) = &triangles.colors {
            let color = self.accessor(&flat(colors), "VEC3", Some(34962), None);
            attributes.insert("COLOR_0".into(), json!(color));
        }
        if self.textured.contains(&material) && triangles.uvs.len() == triangles.positions.len() {
            // glTF's v runs down the image, VRML's t up it.
            let uvs: Vec<f32> = triangles
                .uvs
                .iter()
                .flat_map(|uv| [uv.x, 1.0 - uv.y])
                .collect();
            let uv = self.accessor(&uvs, "VEC2", Some(34962), None);
            attributes.insert("TEXCOORD_0".into(), json!(uv));
        }
        let indices = self.index_accessor(&triangles.indices);
        self.meshes.push(json!({
            "name": name,
            "primitives": [{
                "attributes": attributes,
                "indices": indices,
                "material": material,
                "mode": 4,
            }],
        }));
        self.meshes.len() - 1
    }

    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
        });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bin.extend_from_slice(bytes);
        self.buffer_views.push(view);
        self.buffer_views.len() - 1
    }

    /// A float accessor of `kind` ("SCALAR", "VEC3", "VEC4").
    fn accessor(
        &mut self,
        data: &[f32],
        kind: &str,
        target: Option<u32>,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let width = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut accessor = json!({
            "bufferView": view,
            "componentType": 5126,
            "count": data.len() / width,
            "type": kind,
        });
        if let Some((min, max)) = bounds {
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn index_accessor(&mut self, indices: &[u32]) -> usize {
        let max = indices.iter().copied().max().unwrap_or(0);
        let (component, bytes): (u32, Vec<u8>) = if max < u16::MAX as u32 {
            (
                5123,
                indices
                    .iter()
                    .flat_map(|&i| (i as u16).to_le_bytes())
                    .collect(),
            )
        } else {
            (5125, indices.iter().flat_map(|i| i.to_le_bytes()).collect())
        };
        let view = self.view(&bytes, Some(34963));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": component,
            "count": indices.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    fn material(
        &mut self,
        index: usize,
        material: &Material,
        colored: bool,
        double_sided: bool,
    ) -> usize {
        let key = (index, colored, double_sided);
        if let Some(&m) = self.material_cache.get(&key) {
            return m;
        }
        // VRML replaces the diffuse colour by a Color node's or an image's (glTF multiplies);
        // Webots' PBRAppearance multiplies its map by its base colour, as glTF does.
        let replaced = material.maps.base_color.is_some() && material.maps.pbr.is_none();
        let base = if colored || replaced {
            [1.0; 3]
        } else {
            clamp01(material.diffuse)
        };
        let alpha = (1.0 - material.transparency).clamp(0.0, 1.0);
        let mut out = json!({
            "name": format!("material {index}"),
            "pbrMetallicRoughness": {
                "baseColorFactor": f32s([base[0], base[1], base[2], alpha]),
                "metallicFactor": 0.0,
                "roughnessFactor": roughness(material.shininess) as f32,
            },
            "extras": {
                "ambientIntensity": material.ambient_intensity,
                "specularColor": material.specular,
                "shininess": material.shininess,
                "transparency": material.transparency,
                "irReflectance": material.ir_reflectance,
            },
        });
        if alpha < 1.0 {
            out["alphaMode"] = json!("BLEND");
        }
        if double_sided {
            out["doubleSided"] = json!(true);
        }
        let mut extensions = Map::new();
        if material.unlit {
            self.extensions_used.insert(UNLIT);
            extensions.insert(UNLIT.into(), json!({}));
        } else {
            let emissive = material
                .emissive
                .map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
            let strongest = emissive.iter().copied().fold(0.0, f64::max);
            if strongest > 1.0 {
                self.extensions_used.insert(EMISSIVE_STRENGTH);
                out["emissiveFactor"] = f32s(emissive.map(|x| x / strongest));
                extensions.insert(
                    EMISSIVE_STRENGTH.into(),
                    json!({ "emissiveStrength": strongest as f32 }),
                );
            } else if strongest > 0.0 {
                out["emissiveFactor"] = f32s(emissive);
            }
        }
        if !extensions.is_empty() {
            out["extensions"] = Value::Object(extensions);
        }
        self.maps(material, &mut out);
        self.materials.push(out);
        let m = self.materials.len() - 1;
        if material.maps.textured() {
            self.textured.insert(m);
        }
        self.material_cache.insert(key, m);
        m
    }

    fn lights(&mut self) {
        let graph = self.graph;
        for light in &graph.lights {
            let attenuated = |attenuation: DVec3| {
                light.intensity / (attenuation.x + attenuation.y + attenuation.z).max(1.0)
            };
            let (frame, description, name) = match &light.kind {
                LightKind::Directional { direction } => (
                    aimed(DVec3::ZERO, DVec3::NEG_Z, *direction),
                    json!({ "type": "directional", "intensity": light.intensity as f32 }),
                    "DirectionalLight",
                ),
                LightKind::Point {
                    location,
                    radius,
                    attenuation,
                } => (
                    aimed(*location, DVec3::NEG_Z, DVec3::NEG_Z),
                    json!({
                        "type": "point",
                        "intensity": attenuated(*attenuation) as f32,
                        "range": radius.max(1e-6) as f32,
                    }),
                    "PointLight",
                ),
                LightKind::Spot {
                    location,
                    direction,
                    radius,
                    attenuation,
                    beam_width,
                    cut_off,
                } => {
                    let outer = cut_off.clamp(1e-4, std::f64::consts::FRAC_PI_2);
                    let inner = beam_width.clamp(0.0, outer * 0.999);
                    (
                        aimed(*location, DVec3::NEG_Z, *direction),
                        json!({
                            "type": "spot",
                            "intensity": attenuated(*attenuation) as f32,
                            "range": radius.max(1e-6) as f32,
                            "spot": {
                                "innerConeAngle": inner as f32,
                                "outerConeAngle": outer as f32,
                            },
                        }),
                        "SpotLight",
                    )
                }
            };
            let mut description = description;
            description["name"] = json!(name);
            description["color"] = f32s(clamp01(light.color));
            if !light.on {
                description["intensity"] = json!(0.0);
            }
            let attenuation = match &light.kind {
                LightKind::Point { attenuation, .. } | LightKind::Spot { attenuation, .. } => {
                    Some(attenuation.to_array())
                }
                LightKind::Directional { .. } => None,
            };
            description["extras"] = json!({
                "on": light.on,
                "intensity": light.intensity,
                "ambientIntensity": light.ambient_intensity,
                "attenuation": attenuation,
                "castShadows": light.shadows,
            });
            self.lights.push(description);
            self.extensions_used.insert(LIGHTS);
            let world = self.world(light.owner, &frame);
            let preferred = self.parent_of(light.group);
            let anchor = self.anchor_of(light.owner);
            let node = self.add_rigid(preferred, anchor, name, world);
            self.nodes[node].insert(
                "extensions".into(),
                json!({ LIGHTS: { "light": self.lights.len() - 1 } }),
            );
        }
    }

    fn viewpoint(&mut self) {
        let Some(viewpoint) = &self.graph.viewpoint else {
            return;
        };
        let fov = viewpoint
            .field_of_view
            .clamp(1e-3, std::f64::consts::PI - 1e-3);
        self.cameras.push(json!({
            "name": viewpoint.name,
            "type": "perspective",
            "perspective": { "yfov": fov as f32, "znear": 0.001 },
        }));
        // The viewpoint's frame may carry a scale from its Transform: keep only its rotation.
        let rotation = DQuat::from_mat3(&orthonormalized(viewpoint.frame.linear));
        let world = Frame {
            linear: DMat3::from_quat(rotation),
            translation: viewpoint.frame.translation,
        };
        let node = self.add_rigid(
            (None, Frame::IDENTITY),
            (None, Frame::IDENTITY),
            &viewpoint.name,
            world,
        );
        self.nodes[node].insert("camera".into(), json!(self.cameras.len() - 1));
    }

    fn sensors(&mut self) {
        let rig = &self.compiled.rig;
        for (robot, robot_rig) in rig.robots.iter().enumerate() {
            let anchor = self.anchor_of(Owner::Robot(robot));
            let robot_world = self.robot_world(robot);
            let add = |builder: &mut Builder, name: &str, frame: Frame, extras: Value| {
                let node = builder.add_rigid(anchor, anchor, name, robot_world.then(&frame));
                builder.nodes[node].insert("extras".into(), extras);
            };
            for sensor in robot_rig.distance_sensors.iter() {
                add(
                    self,
                    &sensor.name,
                    aimed(sensor.position, DVec3::X, sensor.direction),
                    json!({
                        "type": "DistanceSensor",
                        "lookupTable": &*sensor.lookup,
                        "numberOfRays": sensor.rays,
                        "aperture": sensor.aperture,
                        "range": sensor.range,
                        "samplingPeriod": sensor.period,
                    }),
                );
            }
            for sensor in robot_rig.light_sensors.iter() {
                add(
                    self,
                    &sensor.name,
                    aimed(sensor.position, DVec3::X, sensor.direction),
                    json!({
                        "type": "LightSensor",
                        "lookupTable": &*sensor.lookup,
                        "occlusion": sensor.occlusion,
                        "samplingPeriod": sensor.period,
                    }),
                );
            }
            match &robot_rig.turret {
                Some(TurretRig::Panoramic(turret)) => add(
                    self,
                    &turret.name,
                    aimed(DVec3::Y * turret.height, DVec3::X, DVec3::X),
                    json!({
                        "type": "PanoramicTurret",
                        "photodiodes": 150,
                        "fieldOfView": 240f64.to_radians(),
                        "optics": match turret.optics { Optics::Paper => "paper", Optics::Exact => "exact" },
                        "samples": turret.samples,
                        "stride": turret.stride,
                        "filters": turret.filters.iter().map(|k| k.name()).collect::<Vec<_>>(),
                        "lambda": turret.lambda,
                        "bandpassLambdas": [turret.bandpass.0, turret.bandpass.1],
                        "bits": turret.bits,
                        "iBda": turret.i_bda,
                        "regionOfInterest": [turret.roi.0, turret.roi.1],
                        "samplingPeriod": turret.period,
                    }),
                ),
                Some(TurretRig::Linear(camera)) => add(
                    self,
                    &camera.name,
                    aimed(DVec3::Y * camera.height, DVec3::X, DVec3::X),
                    json!({
                        "type": "LinearCamera",
                        "pixels": camera.pixels,
                        "fieldOfView": camera.field_of_view,
                        "verticalFieldOfView": camera.vertical_field_of_view,
                        "samples": camera.samples,
                        "bits": camera.bits,
                        "samplingPeriod": camera.period,
                    }),
                ),
                None => {}
            }
        }
    }

    fn animation(&mut self, tracks: &[Track]) -> Result<(), ExportError> {
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for track in tracks {
            let bad = |reason: &str| ExportError::BadTrack {
                robot: track.robot,
                reason: reason.to_owned(),
            };
            let Some(node) = self.robot_nodes.get(track.robot).copied().flatten() else {
                return Err(bad("no such robot in the world"));
            };
            if track.times.len() != track.poses.len() {
                return Err(bad("times and poses differ in number"));
            }
            if track.times.is_empty() {
                continue;
            }
            let times: Vec<f32> = track.times.iter().map(|&t| t as f32).collect();
            if times
                .windows(2)
                .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
                || !times.iter().all(|t| t.is_finite())
            {
                return Err(bad("times are not strictly increasing"));
            }
            let floor_y = self.compiled.rig.robots[track.robot].floor_y;
            let mut translations = Vec::with_capacity(times.len() * 3);
            let mut rotations = Vec::with_capacity(times.len() * 4);
            for pose in &track.poses {
                translations.extend([pose.x as f32, floor_y as f32, pose.z as f32]);
                // A turn about +y by the heading, its half angle through libm (as every pose).
                let (s, c) = (libm::sin(pose.heading / 2.0), libm::cos(pose.heading / 2.0));
                let q = DQuat::from_xyzw(0.0, s, 0.0, c).as_quat().normalize();
                rotations.extend(q.to_array());
            }
            let bounds = (vec![times[0]], vec![times[times.len() - 1]]);
            let input = self.accessor(&times, "SCALAR", None, Some(bounds));
            let translation = self.accessor(&translations, "VEC3", None, None);
            let rotation = self.accessor(&rotations, "VEC4", None, None);
            for (output, path) in [(translation, "translation"), (rotation, "rotation")] {
                samplers
                    .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
                channels.push(json!({
                    "sampler": samplers.len() - 1,
                    "target": { "node": node, "path": path },
                }));
            }
        }
        if !channels.is_empty() {
            self.animations.push(json!({
                "name": "run",
                "samplers": samplers,
                "channels": channels,
            }));
        }
        Ok(())
    }

    fn finish(mut self) -> Result<Document, ExportError> {
        if self.bin.len() > u32::MAX as usize - 64 {
            return Err(ExportError::TooLarge(self.bin.len()));
        }
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let node_count = self.nodes.len();
        let nodes: Vec<Value> = self
            .nodes
            .into_iter()
            .zip(self.children)
            .map(|(mut node, children)| {
                if !children.is_empty() {
                    node.insert("children".into(), json!(children));
                }
                Value::Object(node)
            })
            .collect();
        let settings = &self.compiled.settings;
        let mut scene = json!({
            "name": if settings.title.is_empty() { "world" } else { settings.title.as_str() },
            "extras": { "units": "metres", "up": "+y", "basicTimeStep": settings.time_step },
        });
        // glTF forbids empty arrays: an empty world is a scene without nodes.
        if !self.roots.is_empty() {
            scene["nodes"] = json!(self.roots);
        }
        let mut root = json!({
            "asset": {
                "version": "2.0",
                "generator": concat!("regatta ", env!("CARGO_PKG_VERSION")),
            },
            "scene": 0,
            "scenes": [scene],
        });
        let mut put = |key: &str, items: Vec<Value>| {
            if !items.is_empty() {
                root[key] = Value::Array(items);
            }
        };
        put("nodes", nodes);
        put("meshes", self.meshes);
        put("materials", self.materials);
        put("accessors", self.accessors);
        put("bufferViews", self.buffer_views);
        put("cameras", self.cameras);
        put("images", self.written.images);
        put("samplers", self.written.samplers);
        put("textures", self.written.textures);
        put("animations", self.animations);
        if !self.bin.is_empty() {
            root["buffers"] = json!([{ "byteLength": self.bin.len() }]);
        }
        if !self.lights.is_empty() {
            root["extensions"] = json!({ LIGHTS: { "lights": self.lights } });
        }
        if !self.extensions_used.is_empty() {
            root["extensionsUsed"] = json!(self.extensions_used);
        }
        Ok(Document {
            json: root,
            bin: self.bin,
            node_count,
            triangle_count: self.triangle_count,
        })
    }
}

/// What the builder keeps of the textures it wrote.
#[derive(Default)]
pub(crate) struct Written {
    pub(crate) images: Vec<Value>,
    pub(crate) samplers: Vec<Value>,
    pub(crate) textures: Vec<Value>,
    /// Graph texture → glTF texture.
    pub(crate) by_texture: HashMap<usize, usize>,
    /// (repeatS, repeatT) → sampler.
    pub(crate) by_wrap: HashMap<(bool, bool), usize>,
}

/// Blinn–Phong shininess (VRML's 0…1, exponent 128·s) to glTF perceptual roughness.
fn roughness(shininess: f64) -> f64 {
    let exponent = 128.0 * shininess.clamp(0.0, 1.0);
    (2.0 / (exponent + 2.0)).sqrt().sqrt()
}

/// The rotation nearest to `m` (columns normalised and made orthogonal).
fn orthonormalized(m: DMat3) -> DMat3 {
    let z = m.z_axis.try_normalize().unwrap_or(DVec3::Z);
    let x = m.y_axis.cross(z).try_normalize().unwrap_or(DVec3::X);
    DMat3::from_cols(x, z.cross(x), z)
}

fn robot_extras(robot: &RobotRig) -> Value {
    json!({
        "type": "DifferentialWheels",
        "controller": robot.controller,
        "controllerArgs": robot.controller_args,
        "wheelRadius": robot.wheel_radius,
        "axleLength": robot.axle_length,
        "encoderResolution": robot.encoder_resolution,
        "maxSpeed": robot.max_speed,
        "bodyRadius": robot.body_radius,
        "bodyHeight": robot.body_height,
    })
}
