//! `regatta gltf` end to end: `--report` on the geometry test world, and exports seen in a
//! browser: each world is exported with `regatta gltf`, loaded in
//! headless Chromium by three.js' GLTFLoader (`tests/browser/gltf.js`) and rendered from the
//! world's Viewpoint. The loader reports no error; a textured floor shows its image (not one
//! flat colour); and the browser's silhouette of each of regatta's worlds overlaps regatta's
//! own CPU render of the same view (`regatta render --viewpoint --silhouette`) by at least
//! 90 % (intersection over union).

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;

use common::{ok, regatta, root, temp_dir};

const SIZE: &str = "320x240";

/// Whether Chromium, Node and three.js are here; in CI (REGATTA_REQUIRE_BROWSER=1) they must be.
fn browser_available() -> bool {
    let found = |program: &str| {
        std::process::Command::new(program)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "chromium".to_owned());
    let three = root().join("target/npm/node_modules/three/build");
    let missing = if !found(&chromium) {
        "chromium (apt-get install chromium)"
    } else if !found("node") {
        "node"
    } else if !three.is_dir() {
        "three.js (npm install --prefix target/npm three, as .ci/run does)"
    } else {
        return true;
    };
    assert!(
        std::env::var("REGATTA_REQUIRE_BROWSER").as_deref() != Ok("1"),
        "REGATTA_REQUIRE_BROWSER=1 but {missing} is not installed"
    );
    eprintln!("SKIPPED: the glTF browser test needs {missing}");
    false
}

fn export(world: &Path, out: &Path) {
    ok(&regatta()
        .arg("gltf")
        .arg(world)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap());
}

/// Pixels brighter than half: the silhouette.
fn mask(path: &Path) -> Vec<bool> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_luma8()
        .pixels()
        .map(|p| p.0[0] > 127)
        .collect()
}

fn overlap(a: &[bool], b: &[bool]) -> f64 {
    assert_eq!(a.len(), b.len());
    let both = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let either = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    }
}

#[test]
fn exports_load_in_three_js_and_look_like_regatta_s_own_render() {
    if !browser_available() {
        return;
    }
    let dir = temp_dir("gltf-browser");
    let worlds: Vec<PathBuf> = [
        "regatta.wbt",
        "single_buoy.wbt",
        "k213.wbt",
        "avoidance.wbt",
        "regatta_five.wbt",
        "thymio.wbt",
        "epuck2.wbt",
    ]
    .iter()
    .map(|w| root().join("worlds").join(w))
    .collect();
    let geometry = root().join("tests/data/gltf/worlds/geometry.wbt");
    let mut exports = Vec::new();
    for world in worlds.iter().chain([&geometry]) {
        let name = world.file_stem().unwrap().to_str().unwrap();
        let glb = dir.join(format!("{name}.glb"));
        export(world, &glb);
        exports.push(glb);
    }
    let output = std::process::Command::new("node")
        .env("NODE_PATH", root().join("target/npm/node_modules"))
        .arg(root().join("tools/tests/browser/gltf.js"))
        .arg(&dir)
        .arg(SIZE)
        .args(&exports)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "the browser script failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let results = report["results"].as_array().unwrap();
    assert_eq!(results.len(), exports.len());
    for result in results {
        let errors = result["errors"].as_array().unwrap();
        assert!(errors.is_empty(), "{}: {errors:?}", result["file"]);
    }
    // Each of regatta's worlds against the CPU rasteriser's silhouette of the same view.
    for (world, result) in worlds.iter().zip(results) {
        let name = world.file_stem().unwrap().to_str().unwrap();
        let out = dir.join(format!("cpu-{name}"));
        ok(&regatta()
            .args([
                "render",
                "--viewpoint",
                "--silhouette",
                "--size",
                SIZE,
                "--out",
            ])
            .arg(&out)
            .arg(world)
            .output()
            .unwrap());
        let cpu = mask(&out.join("viewpoint.png"));
        let browser = mask(Path::new(result["mask"].as_str().unwrap()));
        let iou = overlap(&cpu, &browser);
        eprintln!("{name}: silhouette overlap {:.3}", iou);
        assert!(iou >= 0.9, "{name}: silhouette overlap {iou:.3} < 0.9");
    }
    // The geometry world's textured floor is a checkerboard, not one flat colour: the
    // bottom middle of the picture (all floor) holds both of its colours.
    let shaded = image::open(results.last().unwrap()["shaded"].as_str().unwrap())
        .unwrap()
        .to_rgb8();
    let (w, h) = shaded.dimensions();
    let mut reddish = 0;
    let mut light = 0;
    for y in h * 3 / 4..h - 4 {
        for x in w / 3..w * 2 / 3 {
            let [r, g, b] = shaded.get_pixel(x, y).0;
            if r as i32 > g as i32 + 40 && r as i32 > b as i32 + 40 {
                reddish += 1;
            } else if r > 150 && g > 150 && b > 150 {
                light += 1;
            }
        }
    }
    assert!(
        reddish > 50 && light > 50,
        "the textured floor is not a checkerboard: {reddish} red and {light} light pixels"
    );
}

#[test]
fn the_report_lists_every_shape_with_what_became_of_it() {
    let dir = temp_dir("gltf-report");
    let output = regatta()
        .args(["gltf", "--report", "--lenient"])
        .arg(root().join("tests/data/gltf/worlds/geometry.wbt"))
        .arg("-o")
        .arg(dir.join("geometry.glb"))
        .output()
        .unwrap();
    let report = ok(&output);
    for geometry in [
        "Plane",
        "Capsule",
        "Extrusion",
        "ElevationGrid",
        "IndexedLineSet",
        "PointSet",
        "Mesh",
        "CadShape",
        "Box",
        "Sphere",
        "Cylinder",
        "IndexedFaceSet",
    ] {
        assert!(
            report
                .lines()
                .any(|l| l.starts_with("exported ") && l.contains(&format!(" {geometry}: "))),
            "{geometry} not reported exported:\n{report}"
        );
    }
    assert!(report.contains("geometry.wbt:"), "{report}");
    assert!(report.contains(" 0 skipped;"), "{report}");
    // A mesh whose file is missing is reported skipped, naming the file.
    let world = dir.join("missing.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nShape { geometry Mesh { url \"gone.obj\" } }\n",
    )
    .unwrap();
    let output = regatta()
        .args(["gltf", "--report", "--lenient"])
        .arg(&world)
        .arg("-o")
        .arg(dir.join("missing.glb"))
        .output()
        .unwrap();
    let report = ok(&output);
    assert!(
        report.contains("skipped ") && report.contains("gone.obj"),
        "{report}"
    );
    assert!(
        report.contains("1 shapes: 0 exported, 1 skipped"),
        "{report}"
    );
}

/// Issue 40: with `--proto-path` at a Webots installation, a world made of its PROTOs exports
/// whole (`../shared/webots` stands where an installation would: the API tests' `SolidProto`).
#[test]
fn protos_from_a_webots_installation_export_whole() {
    let webots = common::root().join("../shared/webots");
    if !webots.join("tests/api/protos/SolidProto.proto").is_file() {
        eprintln!("skipped: ../shared/webots is not there");
        return;
    }
    let out = common::temp_dir("gltf-proto-path").join("solid.glb");
    let output = common::regatta()
        .arg("--proto-path")
        .arg(&webots)
        .args(["gltf", "--lenient", "--report"])
        .arg(webots.join("tests/api/worlds/supervisor_get_from_def.wbt"))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let report = format!("{stdout}{stderr}");
    assert!(
        report.contains("1 shapes: 1 exported, 0 skipped"),
        "the box inside the installation's SolidProto is exported:\n{report}"
    );
    assert!(out.is_file());
}
