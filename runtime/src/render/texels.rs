//! The colour of a textured surface at a point: the render graph's images decoded the first
//! time a sensor reads one (a world whose sensors read no texture decodes none), VRML97's
//! TextureTransform, repeat or clamp, and the nearest texel.
//!
//! The renderers draw materials' colours; what reads texels is what a ray meets (the ground
//! sensors of a line follower).

use std::sync::OnceLock;

use glam::DVec3;

#[cfg(doc)]
use crate::compile::graph::RenderGraph;
use crate::compile::graph::{Material, Texture, TextureTransform};

/// The decoded images of a render graph, each decoded at most once.
pub struct Texels<'g> {
    textures: &'g [Texture],
    images: Vec<OnceLock<Option<Image>>>,
}

/// An image as 8-bit RGB rows, the first row at the top (t = 1).
struct Image {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

impl<'g> Texels<'g> {
    /// Over a render graph's [`RenderGraph::textures`].
    pub fn new(textures: &'g [Texture]) -> Texels<'g> {
        Texels {
            textures,
            images: textures.iter().map(|_| OnceLock::new()).collect(),
        }
    }

    /// The diffuse colour of `material` at texture coordinates `uv`: the base colour map's
    /// texel, times a PBRAppearance's base colour (VRML97's Appearance: the texel replaces
    /// the material's colour). `None` when the material maps no image, or its image cannot
    /// be decoded (compiling warned of it already).
    pub fn diffuse(&self, material: &Material, uv: [f64; 2]) -> Option<[f64; 3]> {
        let index = material.maps.base_color?;
        let texture = self.textures.get(index)?;
        let image = self
            .images
            .get(index)?
            .get_or_init(|| decode(&texture.bytes));
        let image = image.as_ref()?;
        let [s, t] = transformed(uv, material.maps.transform);
        let s = wrap(s, texture.repeat_s);
        let t = wrap(t, texture.repeat_t);
        let column = ((s * image.width as f64) as usize).min(image.width - 1);
        let row = (((1.0 - t) * image.height as f64) as usize).min(image.height - 1);
        let texel = image.rgb[row * image.width + column].map(|c| f64::from(c) / 255.0);
        let tint = if material.maps.pbr.is_some() {
            material.diffuse
        } else {
            [1.0; 3]
        };
        Some([texel[0] * tint[0], texel[1] * tint[1], texel[2] * tint[2]])
    }
}

fn decode(bytes: &[u8]) -> Option<Image> {
    let image = image::load_from_memory(bytes).ok()?.to_rgb8();
    let (width, height) = (image.width() as usize, image.height() as usize);
    if width == 0 || height == 0 {
        return None;
    }
    let rgb = image.pixels().map(|p| p.0).collect();
    Some(Image { width, height, rgb })
}

/// VRML97 6.50: Tc' = −C × S × R × C × T × Tc (translated, then turned and scaled about the
/// centre).
fn transformed(uv: [f64; 2], transform: Option<TextureTransform>) -> [f64; 2] {
    let Some(transform) = transform else {
        return uv;
    };
    let centre = DVec3::new(transform.center[0], transform.center[1], 0.0);
    let p = DVec3::new(
        uv[0] + transform.translation[0],
        uv[1] + transform.translation[1],
        0.0,
    ) + centre;
    let (sin, cos) = (libm::sin(transform.rotation), libm::cos(transform.rotation));
    let turned = DVec3::new(cos * p.x - sin * p.y, sin * p.x + cos * p.y, 0.0);
    let scaled = DVec3::new(
        turned.x * transform.scale[0],
        turned.y * transform.scale[1],
        0.0,
    );
    let out = scaled - centre;
    [out.x, out.y]
}

/// A coordinate into 0…1: its fraction when the image repeats, else clamped. Not finite: 0.
fn wrap(x: f64, repeat: bool) -> f64 {
    if !x.is_finite() {
        0.0
    } else if repeat {
        x.rem_euclid(1.0)
    } else {
        x.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::graph::Maps;

    /// A 2×2 PNG: top row red, white; bottom row black, blue.
    fn checker() -> Vec<u8> {
        let mut image = image::RgbImage::new(2, 2);
        image.put_pixel(0, 0, image::Rgb([255, 0, 0]));
        image.put_pixel(1, 0, image::Rgb([255, 255, 255]));
        image.put_pixel(0, 1, image::Rgb([0, 0, 0]));
        image.put_pixel(1, 1, image::Rgb([0, 0, 255]));
        let mut bytes = Vec::new();
        image
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .unwrap();
        bytes
    }

    fn textures(repeat: bool) -> Vec<Texture> {
        vec![Texture {
            name: "checker.png".to_owned(),
            mime: "image/png",
            bytes: checker().into(),
            repeat_s: repeat,
            repeat_t: repeat,
        }]
    }

    fn material(pbr: bool, transform: Option<TextureTransform>) -> Material {
        Material {
            diffuse: [0.5, 1.0, 1.0],
            maps: Maps {
                base_color: Some(0),
                transform,
                pbr: pbr.then_some((0.5, 0.0)),
                ..Maps::NONE
            },
            ..Material::WHITE
        }
    }

    #[test]
    fn the_image_lies_with_its_first_row_at_the_top() {
        let textures = textures(true);
        let texels = Texels::new(&textures);
        let plain = material(false, None);
        assert_eq!(texels.diffuse(&plain, [0.25, 0.75]), Some([1.0, 0.0, 0.0]));
        assert_eq!(texels.diffuse(&plain, [0.75, 0.75]), Some([1.0; 3]));
        assert_eq!(texels.diffuse(&plain, [0.25, 0.25]), Some([0.0; 3]));
        assert_eq!(texels.diffuse(&plain, [0.75, 0.25]), Some([0.0, 0.0, 1.0]));
        // Repeating: 1.25 is 0.25.
        assert_eq!(texels.diffuse(&plain, [1.25, -0.25]), Some([1.0, 0.0, 0.0]));
        // A PBRAppearance's base colour tints the texel.
        let tinted = material(true, None);
        assert_eq!(texels.diffuse(&tinted, [0.75, 0.75]), Some([0.5, 1.0, 1.0]));
        // No map, no texel.
        assert_eq!(texels.diffuse(&Material::WHITE, [0.5, 0.5]), None);
    }

    #[test]
    fn clamping_and_the_texture_transform_move_the_texel() {
        let textures = textures(false);
        let texels = Texels::new(&textures);
        let plain = material(false, None);
        assert_eq!(texels.diffuse(&plain, [1.25, -0.25]), Some([0.0, 0.0, 1.0]));
        let scaled = material(
            false,
            Some(TextureTransform {
                center: [0.0, 0.0],
                rotation: 0.0,
                scale: [2.0, 2.0],
                translation: [0.0, 0.0],
            }),
        );
        // Scaled by 2 about the origin: (0.3, 0.2) reads (0.6, 0.4), the bottom right.
        assert_eq!(texels.diffuse(&scaled, [0.3, 0.2]), Some([0.0, 0.0, 1.0]));
        assert_eq!(texels.diffuse(&plain, [0.3, 0.2]), Some([0.0; 3]));
    }
}
