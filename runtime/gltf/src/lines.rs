//! Lines and points (IndexedLineSet, PointSet) as glTF primitives of mode LINES (1) and
//! POINTS (0): positions and COLOR_0, no normals (glTF leaves them unlit), the shape's
//! emissive or diffuse colour as the material's base colour.

use glam::Vec3;
use serde_json::{json, Map};

use super::{clamp01, f32s, Builder};

impl Builder<'_> {
    pub(super) fn lines(&mut self) {
        let graph = self.graph;
        for set in &graph.lines {
            let (parent, parent_world) = self.parent_of(set.group);
            let world = self.world(set.owner, &set.frame);
            let Some(local) = parent_world.inverse().map(|inv| inv.then(&world)) else {
                continue;
            };
            // Lines carry no transform of their own: their points are baked into the parent.
            let positions: Vec<Vec3> = set
                .positions
                .iter()
                .map(|&p| local.apply(p).as_vec3())
                .collect();
            let (lo, hi) = positions.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            let flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
            let mut attributes = Map::new();
            let position = self.accessor(
                &flat,
                "VEC3",
                Some(34962),
                Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
            );
            attributes.insert("POSITION".into(), json!(position));
            if let Some(colors) = &set.colors {
                let flat: Vec<f32> = colors
                    .iter()
                    .flat_map(|c| clamp01(*c).map(|x| x as f32))
                    .collect();
                let color = self.accessor(&flat, "VEC3", Some(34962), None);
                attributes.insert("COLOR_0".into(), json!(color));
            }
            // VRML97 draws lines in the emissive colour (they are unlit).
            let source = &graph.materials[set.material];
            let base = if set.colors.is_some() {
                [1.0; 3]
            } else if source.unlit || source.emissive != [0.0; 3] {
                clamp01(source.emissive)
            } else {
                clamp01(source.diffuse)
            };
            self.materials.push(json!({
                "name": format!("lines {}", self.materials.len()),
                "pbrMetallicRoughness": {
                    "baseColorFactor": f32s([base[0], base[1], base[2], 1.0]),
                    "metallicFactor": 0.0,
                },
                "extensions": { super::UNLIT: {} },
            }));
            self.extensions_used.insert(super::UNLIT);
            let material = self.materials.len() - 1;
            let name = if set.lines {
                "IndexedLineSet"
            } else {
                "PointSet"
            };
            self.meshes.push(json!({
                "name": name,
                "primitives": [{
                    "attributes": attributes,
                    "material": material,
                    "mode": if set.lines { 1 } else { 0 },
                }],
            }));
            let mesh = self.meshes.len() - 1;
            let node = self.add_node(parent, name, None, parent_world);
            self.nodes[node].insert("mesh".into(), json!(mesh));
        }
    }
}
