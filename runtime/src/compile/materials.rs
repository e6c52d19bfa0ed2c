//! A Shape's appearance read into the render graph's materials, each shared where it can
//! be: a VRML Material by every Appearance that uses it, and in a run
//! ([`super::compile_for_run`]) any two equal materials.

use regatta_schema::NodeId;

use super::graph::Material;
use super::shapes::material_of;
use super::{textures, Compiler};

impl Compiler<'_> {
    pub(super) fn material(&mut self, appearance: Option<NodeId>) -> usize {
        // A VRML Appearance shares its Material, unless it maps an image; a PBRAppearance is
        // its own material.
        let key = appearance.and_then(|a| match self.scene.type_name(a) {
            "PBRAppearance" => Some(a),
            _ if textures::has_texture(self.scene, a) => Some(a),
            _ => self.scene.child(a, "material"),
        });
        if let Some(&index) = self.materials.get(&key) {
            return index;
        }
        let mut material: Material = material_of(self.scene, appearance);
        if let Some(appearance) = appearance {
            let mut maps = textures::maps_of(
                self.scene,
                appearance,
                &mut self.texture_cache,
                &mut self.graph.textures,
                &mut self.warnings,
            );
            // A texture without a Material is lit as a white one is (VRML97 6.4).
            if maps.base_color.is_some() && material.unlit {
                material = Material::WHITE;
            }
            std::mem::swap(&mut material.maps, &mut maps);
        }
        // A run shares equal materials: a swarm's robots have a few between them.
        let equal = (!self.robot_groups)
            .then(|| self.graph.materials.iter().position(|m| *m == material))
            .flatten();
        if let Some(index) = equal {
            self.materials.insert(key, index);
            return index;
        }
        self.graph.materials.push(material);
        let index = self.graph.materials.len() - 1;
        self.materials.insert(key, index);
        index
    }
}
