//! Appearance in the export: ImageTexture and PixelTexture images embedded in the .glb (PNG
//! and JPEG as found, BMP converted), TextureTransform as KHR_texture_transform, texture
//! coordinates given or generated, PBRAppearance parameters, transparency as blending. A
//! missing or malformed image is a warning naming it (lenient) or an error at its line
//! (strict); an oversized one is refused by name.

use std::path::{Path, PathBuf};

use regatta_gltf::{export, Options};
use regatta_schema::{check_path, Checked, Limits};
use regatta_tests::root;
use serde_json::Value;

fn check(world: &Path, strict: bool, limits: Limits) -> Checked {
    check_path(
        world,
        &regatta_schema::Options {
            strict,
            limits,
            ..regatta_schema::Options::default()
        },
    )
    .expect("world readable")
}

fn export_json(checked: &Checked) -> (Value, Vec<u8>) {
    let compiled = regatta_runtime::compile(&checked.scene);
    let document = export(&compiled, &Options { quality: 16 }, &[]).unwrap();
    let glb = document.to_glb();
    gltf::Gltf::from_slice(&glb).expect("the gltf crate reads the export");
    (document.json, document.bin)
}

#[test]
fn the_geometry_world_embeds_its_images_with_coordinates_and_transforms() {
    let world = root().join("tests/data/gltf/worlds/geometry.wbt");
    let checked = check(&world, true, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let (json, bin) = export_json(&checked);
    let images = json["images"].as_array().expect("images");
    // checker.png (named three times, once embedded), bands.bmp converted, the PixelTexture,
    // and the PBR sphere's roughness map made glTF's metallic-roughness image.
    assert_eq!(images.len(), 4, "{images:?}");
    for image in images {
        assert_eq!(image["mimeType"], "image/png");
        let view = &json["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(&bin[start..start + 4], b"\x89PNG");
    }
    let used: Vec<&str> = json["extensionsUsed"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert!(used.contains(&"KHR_texture_transform"), "{used:?}");
    let materials = json["materials"].as_array().unwrap();
    let textured: Vec<usize> = (0..materials.len())
        .filter(|&m| materials[m]["pbrMetallicRoughness"]["baseColorTexture"].is_object())
        .collect();
    assert_eq!(textured.len(), 5);
    // Every mesh of a textured material has texture coordinates.
    for mesh in json["meshes"].as_array().unwrap() {
        let primitive = &mesh["primitives"][0];
        if textured.contains(&(primitive["material"].as_u64().unwrap() as usize)) {
            assert!(primitive["attributes"]["TEXCOORD_0"].is_u64(), "{mesh}");
        }
    }
    assert!(materials
        .iter()
        .any(|m| m["pbrMetallicRoughness"]["metallicRoughnessTexture"].is_object()));
    // The transparent textured face blends; the PBR sphere keeps its roughness.
    assert!(materials
        .iter()
        .any(|m| m["alphaMode"] == "BLEND"
            && m["pbrMetallicRoughness"]["baseColorTexture"].is_object()));
    assert!(materials.iter().any(|m| {
        (m["pbrMetallicRoughness"]["roughnessFactor"]
            .as_f64()
            .unwrap()
            - 0.4)
            .abs()
            < 1e-6
    }));
}

fn project(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "regatta-gltf-textures-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn textured_box(url: &str) -> String {
    format!("Shape {{ appearance Appearance {{ texture ImageTexture {{ url \"{url}\" }} }} geometry Box {{ }} }}\n")
}

#[test]
fn a_jpeg_is_embedded_as_found() {
    let dir = project("jpeg");
    let image = image::RgbImage::from_fn(8, 8, |x, y| {
        image::Rgb([(x * 30) as u8, (y * 30) as u8, 90])
    });
    image.save(dir.join("photo.jpg")).unwrap();
    let jpeg = std::fs::read(dir.join("photo.jpg")).unwrap();
    let world = dir.join("world.wbt");
    std::fs::write(
        &world,
        format!("#VRML_SIM R2023b utf8\n{}", textured_box("photo.jpg")),
    )
    .unwrap();
    let checked = check(&world, true, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let (json, bin) = export_json(&checked);
    let image = &json["images"][0];
    assert_eq!(image["mimeType"], "image/jpeg");
    let view = &json["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap() as usize;
    assert_eq!(&bin[start..start + jpeg.len()], &jpeg[..]);
}

#[test]
fn missing_malformed_and_oversized_images_are_named() {
    let dir = project("bad");
    std::fs::write(dir.join("broken.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    std::fs::write(dir.join("huge.png"), vec![0u8; 4096]).unwrap();
    let world = dir.join("world.wbt");
    let body = [
        textured_box("missing.png"),
        textured_box("broken.png"),
        textured_box("huge.png"),
    ]
    .concat();
    std::fs::write(&world, format!("#VRML_SIM R2023b utf8\n{body}")).unwrap();
    let mut limits = Limits::default();
    limits.set("file-size=1k").unwrap();
    let checked = check(&world, false, limits.clone());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let text = checked.render(false);
    assert!(
        text.contains("missing.png") && text.contains("huge.png"),
        "{text}"
    );
    let compiled = regatta_runtime::compile(&checked.scene);
    assert!(
        compiled.warnings.iter().any(|w| w.contains("broken.png")),
        "{:?}",
        compiled.warnings
    );
    // Every box is still exported, untextured.
    assert_eq!(compiled.graph.primitives.len(), 3);
    let (json, _) = export_json(&checked);
    assert!(json.get("images").is_none());
    // Strict: the missing image is an error at its line.
    let checked = check(&world, true, limits);
    let missing = checked
        .diagnostics
        .iter()
        .find(|d| d.diagnostic.message.contains("missing.png"))
        .expect("named");
    assert!(missing.diagnostic.is_error());
    let (line, _) = regatta_parser::diagnostic::line_col(
        &checked.sources[missing.file.0 as usize].text,
        missing.diagnostic.span.start as usize,
    );
    assert_eq!(line, 2);
}

#[test]
fn a_texture_outside_the_project_is_a_warning_in_lenient_mode_and_is_never_read() {
    // A project written on someone's laptop: its floor's image lies outside the project, and
    // another is an absolute path.
    let dir = project("outside");
    let image = image::RgbImage::from_fn(4, 4, |x, _| image::Rgb([(x * 60) as u8, 0, 0]));
    image.save(dir.join("line.png")).unwrap();
    let worlds = dir.join("project").join("worlds");
    std::fs::create_dir_all(&worlds).unwrap();
    let world = worlds.join("w.wbt");
    let absolute = dir.join("line.png");
    let body = [
        textured_box("../../line.png"),
        textured_box(absolute.to_str().unwrap()),
    ]
    .concat();
    std::fs::write(&world, format!("#VRML_SIM R2023b utf8\n{body}")).unwrap();
    let checked = check(&world, false, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let warnings: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| !d.diagnostic.is_error())
        .map(|d| d.diagnostic.message.clone())
        .collect();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("'../../line.png' leads outside the world's project")),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|w| w.contains("is an absolute path")),
        "{warnings:?}"
    );
    // Nothing was read: the boxes are exported untextured.
    assert!(checked.scene.assets.is_empty());
    let (json, _) = export_json(&checked);
    assert!(json.get("images").is_none());
    // Strict: still errors, at their lines.
    let checked = check(&world, true, Limits::default());
    assert_eq!(
        checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .count(),
        2,
        "{}",
        checked.render(false)
    );
}
