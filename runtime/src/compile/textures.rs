//! Appearances' images read into the render graph's [`Texture`]s and a material's [`Maps`]:
//! an ImageTexture's file as the check read it (PNG and JPEG kept as found, BMP converted to
//! PNG), a PixelTexture's pixels encoded as PNG, a TextureTransform, and a PBRAppearance's
//! base colour, roughness and metalness (combined into one image), normal, occlusion and
//! emissive maps. Only exporters read them. An image that does not decode is a warning
//! naming it, never a panic.

use std::collections::HashMap;
use std::io::Cursor;

use regatta_schema::{NodeId, Scene, Value};

use super::graph::{Maps, Texture, TextureTransform};

/// Texture nodes already read (`None`: read, unusable), so each image is embedded once.
#[derive(Default)]
pub(crate) struct TextureCache {
    read: HashMap<NodeId, Option<usize>>,
}

/// The maps of an appearance (Appearance or PBRAppearance).
pub(crate) fn maps_of(
    scene: &Scene,
    appearance: NodeId,
    cache: &mut TextureCache,
    textures: &mut Vec<Texture>,
    warnings: &mut Vec<String>,
) -> Maps {
    let pbr = scene.type_name(appearance) == "PBRAppearance";
    let metallic_roughness = pbr
        .then(|| metallic_roughness(scene, appearance))
        .flatten()
        .and_then(|made| match made {
            Ok(texture) => {
                textures.push(texture);
                Some(textures.len() - 1)
            }
            Err(reason) => {
                warnings.push(reason);
                None
            }
        });
    let mut texture = |field: &str| {
        let node = scene.child(appearance, field)?;
        if let Some(&done) = cache.read.get(&node) {
            return done;
        }
        let read = match texture_of(scene, node) {
            // The same file (read once by the check) with the same wrap is one texture.
            Ok(texture) => match textures.iter().position(|t| {
                std::sync::Arc::ptr_eq(&t.bytes, &texture.bytes)
                    && (t.repeat_s, t.repeat_t) == (texture.repeat_s, texture.repeat_t)
            }) {
                Some(same) => Some(same),
                None => {
                    textures.push(texture);
                    Some(textures.len() - 1)
                }
            },
            Err(reason) => {
                warnings.push(reason);
                None
            }
        };
        cache.read.insert(node, read);
        read
    };
    let transform = |scene: &Scene| {
        let node = scene.child(appearance, "textureTransform")?;
        Some(TextureTransform {
            center: scene.vec2(node, "center"),
            rotation: scene.float(node, "rotation"),
            scale: scene.vec2(node, "scale"),
            translation: scene.vec2(node, "translation"),
        })
    };
    if pbr {
        Maps {
            base_color: texture("baseColorMap"),
            metallic_roughness,
            normal: texture("normalMap"),
            occlusion: texture("occlusionMap"),
            emissive: texture("emissiveColorMap"),
            transform: transform(scene),
            pbr: Some((
                scene.float(appearance, "roughness"),
                scene.float(appearance, "metalness"),
            )),
        }
    } else {
        Maps {
            base_color: texture("texture"),
            transform: transform(scene),
            ..Maps::NONE
        }
    }
}

/// A PBRAppearance's roughness and metalness maps as one image, roughness in green and
/// metalness in blue (glTF's metallicRoughnessTexture), at the first map's size; a missing
/// map is 1 (its factor alone). `None` when it has neither.
fn metallic_roughness(scene: &Scene, pbr: NodeId) -> Option<Result<Texture, String>> {
    let roughness = scene.child(pbr, "roughnessMap");
    let metalness = scene.child(pbr, "metalnessMap");
    if roughness.is_none() && metalness.is_none() {
        return None;
    }
    let decode = |node: Option<NodeId>| -> Result<Option<(image::GrayImage, bool, bool)>, String> {
        let Some(node) = node else { return Ok(None) };
        let texture = texture_of(scene, node)?;
        let gray = image::load_from_memory(&texture.bytes)
            .map_err(|e| format!("texture '{}' is not a valid image ({e})", texture.name))?
            .to_luma8();
        Ok(Some((gray, texture.repeat_s, texture.repeat_t)))
    };
    let made = (|| {
        let (roughness, metalness) = (decode(roughness)?, decode(metalness)?);
        let first = roughness.as_ref().or(metalness.as_ref()).ok_or("no map")?;
        let (w, h) = first.0.dimensions();
        let (repeat_s, repeat_t) = (first.1, first.2);
        let sized = |map: &Option<(image::GrayImage, bool, bool)>| {
            map.as_ref().map(|(gray, _, _)| {
                if gray.dimensions() == (w, h) {
                    gray.clone()
                } else {
                    image::imageops::resize(gray, w, h, image::imageops::FilterType::Triangle)
                }
            })
        };
        let (g, b) = (sized(&roughness), sized(&metalness));
        let combined = image::RgbImage::from_fn(w, h, |x, y| {
            let at =
                |m: &Option<image::GrayImage>| m.as_ref().map_or(255, |m| m.get_pixel(x, y).0[0]);
            image::Rgb([255, at(&g), at(&b)])
        });
        let mut png = Vec::new();
        combined
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| format!("roughness and metalness maps could not be combined ({e})"))?;
        Ok(Texture {
            name: "roughness and metalness".to_owned(),
            mime: "image/png",
            bytes: png.into(),
            repeat_s,
            repeat_t,
        })
    })();
    Some(made)
}

/// Whether an appearance maps an image (its material is then its own, not its Material's).
pub(crate) fn has_texture(scene: &Scene, appearance: NodeId) -> bool {
    let fields: &[&str] = match scene.type_name(appearance) {
        "PBRAppearance" => &[
            "baseColorMap",
            "normalMap",
            "occlusionMap",
            "emissiveColorMap",
        ],
        _ => &["texture"],
    };
    fields.iter().any(|f| scene.child(appearance, f).is_some())
}

fn texture_of(scene: &Scene, node: NodeId) -> Result<Texture, String> {
    let (name, mime, bytes) = match scene.type_name(node) {
        "ImageTexture" => {
            let asset =
                scene
                    .asset(node)
                    .ok_or_else(|| match scene.strings(node, "url").first() {
                        Some(url) => {
                            format!("texture '{url}' could not be read (the check said why)")
                        }
                        None => "an ImageTexture names no file".to_owned(),
                    })?;
            let (mime, bytes) = encoded(&asset.url, &asset.bytes)?;
            (asset.url.clone(), mime, bytes)
        }
        "PixelTexture" => match scene.field(node, "image") {
            Value::Image(image) => ("PixelTexture".to_owned(), "image/png", pixels(image)?),
            _ => return Err("a PixelTexture holds no image".to_owned()),
        },
        other => return Err(format!("a {other} texture is not exported")),
    };
    Ok(Texture {
        name,
        mime,
        bytes,
        repeat_s: scene.bool(node, "repeatS"),
        repeat_t: scene.bool(node, "repeatT"),
    })
}

/// A file's image as glTF takes it: PNG and JPEG as found (their header checked), BMP
/// converted to PNG.
fn encoded(
    url: &str,
    bytes: &std::sync::Arc<[u8]>,
) -> Result<(&'static str, std::sync::Arc<[u8]>), String> {
    let reader = image::ImageReader::new(Cursor::new(&bytes[..]))
        .with_guessed_format()
        .map_err(|_| format!("texture '{url}' cannot be read"))?;
    let format = reader.format();
    let invalid = |e: image::ImageError| format!("texture '{url}' is not a valid image ({e})");
    match format {
        Some(image::ImageFormat::Png) | Some(image::ImageFormat::Jpeg) => {
            reader.into_dimensions().map_err(invalid)?;
            let mime = if format == Some(image::ImageFormat::Png) {
                "image/png"
            } else {
                "image/jpeg"
            };
            Ok((mime, bytes.clone()))
        }
        Some(_) => {
            let decoded = reader.decode().map_err(invalid)?;
            let mut png = Vec::new();
            decoded
                .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(invalid)?;
            Ok(("image/png", png.into()))
        }
        None => Err(format!(
            "texture '{url}' is not an image regatta reads (PNG, JPEG, BMP)"
        )),
    }
}

/// A PixelTexture's pixels (VRML97 5.5: rows from the bottom, one integer per pixel, 1 to 4
/// components) as a PNG (rows from the top).
fn pixels(image: &regatta_schema::value::Image) -> Result<std::sync::Arc<[u8]>, String> {
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 || image.pixels.len() < (w as usize) * (h as usize) {
        return Err("a PixelTexture's image is empty".to_owned());
    }
    let mut rgba = image::RgbaImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let p = image.pixels[(y * w + x) as usize];
            let [a, b, c, d] = p.to_be_bytes();
            let rgba_pixel = match image.components {
                1 => [d, d, d, 255],
                2 => [c, c, c, d],
                3 => [b, c, d, 255],
                _ => [a, b, c, d],
            };
            rgba.put_pixel(x, h - 1 - y, image::Rgba(rgba_pixel));
        }
    }
    let mut png = Vec::new();
    rgba.write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| format!("a PixelTexture could not be encoded ({e})"))?;
    Ok(png.into())
}
