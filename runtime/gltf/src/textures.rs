//! Images in the .glb: each render-graph texture embedded once (a buffer view with its MIME
//! type), a sampler per wrap mode, and a material's maps as texture infos, with VRML97's
//! TextureTransform as `KHR_texture_transform`.
//!
//! VRML97 texture space has t up from the image's bottom; glTF's v runs down from its top,
//! so meshes carry (s, 1 − t) and the transform is conjugated by that flip: VRML's
//! t' = S·R·(t + translation + center) − center becomes glTF's offset, rotation and scale
//! exactly when the rotation is 0 or the scale uniform (otherwise the scale is applied after
//! the rotation instead of before, which glTF cannot say).

use glam::{DMat2, DVec2};
use regatta_runtime::compile::graph::{Material, TextureTransform};
use serde_json::{json, Map, Value};

use super::Builder;

const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

impl Builder<'_> {
    /// Adds a material's maps to its glTF material `out`.
    pub(super) fn maps(&mut self, material: &Material, out: &mut Value) {
        let maps = &material.maps;
        if let Some((roughness, metalness)) = maps.pbr {
            out["pbrMetallicRoughness"]["roughnessFactor"] =
                json!(roughness.clamp(0.0, 1.0) as f32);
            out["pbrMetallicRoughness"]["metallicFactor"] = json!(metalness.clamp(0.0, 1.0) as f32);
        }
        if let Some(texture) = maps.base_color {
            out["pbrMetallicRoughness"]["baseColorTexture"] =
                self.texture_info(texture, maps.transform);
        }
        if let Some(texture) = maps.metallic_roughness {
            out["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
                self.texture_info(texture, maps.transform);
        }
        if let Some(texture) = maps.normal {
            out["normalTexture"] = self.texture_info(texture, maps.transform);
        }
        if let Some(texture) = maps.occlusion {
            out["occlusionTexture"] = self.texture_info(texture, maps.transform);
        }
        if let Some(texture) = maps.emissive {
            out["emissiveTexture"] = self.texture_info(texture, maps.transform);
            if out.get("emissiveFactor").is_none() {
                out["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
            }
        }
    }

    fn texture_info(&mut self, texture: usize, transform: Option<TextureTransform>) -> Value {
        let index = self.texture(texture);
        let mut info = json!({ "index": index, "texCoord": 0 });
        if let Some(t) = transform {
            let (offset, rotation, scale) = khr_transform(&t);
            self.extensions_used.insert(TEXTURE_TRANSFORM);
            let mut extension = Map::new();
            extension.insert("offset".into(), json!([offset.x as f32, offset.y as f32]));
            if rotation != 0.0 {
                extension.insert("rotation".into(), json!(rotation as f32));
            }
            extension.insert("scale".into(), json!([scale.x as f32, scale.y as f32]));
            info["extensions"] = json!({ TEXTURE_TRANSFORM: extension });
        }
        info
    }

    /// The glTF texture of a graph texture, its image embedded the first time.
    fn texture(&mut self, texture: usize) -> usize {
        if let Some(&index) = self.written.by_texture.get(&texture) {
            return index;
        }
        let source = &self.graph.textures[texture];
        let view = self.view(&source.bytes, None);
        self.written.images.push(json!({
            "bufferView": view,
            "mimeType": source.mime,
            "name": source.name,
        }));
        let image = self.written.images.len() - 1;
        let wrap = (source.repeat_s, source.repeat_t);
        let sampler = match self.written.by_wrap.get(&wrap) {
            Some(&s) => s,
            None => {
                let mode = |repeat: bool| if repeat { 10497 } else { 33071 };
                self.written.samplers.push(json!({
                    "magFilter": 9729,
                    "minFilter": 9987,
                    "wrapS": mode(wrap.0),
                    "wrapT": mode(wrap.1),
                }));
                let s = self.written.samplers.len() - 1;
                self.written.by_wrap.insert(wrap, s);
                s
            }
        };
        self.written
            .textures
            .push(json!({ "source": image, "sampler": sampler }));
        let index = self.written.textures.len() - 1;
        self.written.by_texture.insert(texture, index);
        index
    }
}

/// VRML97's TextureTransform in glTF's flipped texture space: (offset, rotation, scale).
pub(crate) fn khr_transform(t: &TextureTransform) -> (DVec2, f64, DVec2) {
    let scale = DVec2::from_array(t.scale);
    let (center, translation) = (
        DVec2::from_array(t.center),
        DVec2::from_array(t.translation),
    );
    // VRML: st' = S·R(θ)·(st + translation + center) − center. With st = F(uv) = (u, 1 − v):
    // uv' = F(st') = S·R(−θ)·uv + D·(S·R(θ)·((0, 1) + translation + center) − center) + (0, 1).
    let rotate = DMat2::from_angle(t.rotation);
    let inner = scale * (rotate * (DVec2::Y + translation + center)) - center;
    let offset = DVec2::new(inner.x, -inner.y) + DVec2::Y;
    // KHR_texture_transform's rotation r turns uv by R(−r): r = θ.
    (offset, t.rotation, scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// VRML's mapping of (s, t), then flipped, against KHR's of the flipped (u, v).
    fn agree(t: TextureTransform) {
        for (s, tt) in [(0.0, 0.0), (1.0, 0.0), (0.3, 0.8), (1.0, 1.0)] {
            let st = DVec2::new(s, tt);
            let rotate = DMat2::from_angle(t.rotation);
            let vrml = DVec2::from_array(t.scale)
                * (rotate * (st + DVec2::from_array(t.translation) + DVec2::from_array(t.center)))
                - DVec2::from_array(t.center);
            let want = DVec2::new(vrml.x, 1.0 - vrml.y);
            let (offset, r, scale) = khr_transform(&t);
            let uv = DVec2::new(s, 1.0 - tt);
            let got = DMat2::from_angle(-r) * (scale * uv) + offset;
            assert!(
                got.distance(want) < 1e-12,
                "{t:?} at {st}: {got} against {want}"
            );
        }
    }

    #[test]
    fn texture_transforms_match_in_the_flipped_space() {
        agree(TextureTransform {
            center: [0.0; 2],
            rotation: 0.0,
            scale: [4.0, 2.0],
            translation: [0.1, 0.3],
        });
        agree(TextureTransform {
            center: [0.5, 0.5],
            rotation: 0.7,
            scale: [3.0, 3.0],
            translation: [0.2, -0.1],
        });
    }
}
