//! `regatta gltf --report` against an independent count: for every world of
//! `../shared/corpus` and of `worlds/`, the shapes the world holds (counted from the typed
//! scene: every Shape and CadShape reached from the roots through node-valued fields, once per
//! USE, leaving out collision geometry and the unchosen choices of a Switch) are each in the
//! report, exported or skipped, and a shape is skipped only for a file (a mesh that could not
//! be read or decoded). It prints the per-world table (shapes in the world, exported,
//! triangles, textures) with `--nocapture`.

use std::path::Path;

use regatta_gltf::{export, report, Options};
use regatta_schema::{NodeId, Scene};
use regatta_tests::{corpus, files_with, root};

/// The shapes below `node`, counted as the file places them.
fn shapes_in(scene: &Scene, node: NodeId, depth: usize) -> usize {
    if depth > 256 {
        return 0;
    }
    match scene.type_name(node) {
        "Shape" | "CadShape" => 1,
        "Switch" => usize::try_from(scene.int(node, "whichChoice"))
            .ok()
            .and_then(|i| scene.children(node, "choice").get(i))
            .map_or(0, |&c| shapes_in(scene, c, depth + 1)),
        _ => {
            let spec = scene.spec(node);
            spec.fields
                .iter()
                .filter(|f| f.name != "boundingObject")
                .flat_map(|f| scene.children(node, &f.name))
                .map(|&c| shapes_in(scene, c, depth + 1))
                .sum()
        }
    }
}

/// The options `tests/interop/gltf.sh` exports a world with: lenient, a Webots project's
/// folder allowed.
fn check(world: &Path) -> Option<regatta_schema::Checked> {
    let mut options = regatta_schema::Options {
        strict: false,
        ..regatta_schema::Options::default()
    };
    let folder = world.parent()?;
    if folder.file_name().is_some_and(|n| n == "worlds") {
        options.access.allow(folder.parent()?).ok()?;
    }
    let checked = regatta_schema::check_path(world, &options).ok()?;
    (!checked.has_errors()).then_some(checked)
}

#[test]
fn every_shape_of_every_world_is_in_the_report() {
    let mut worlds = files_with(&corpus(), &["wbt", "wrl"]);
    worlds.extend(files_with(&root().join("worlds"), &["wbt"]));
    assert!(worlds.len() > 40, "{} worlds", worlds.len());
    let mut table = vec![format!(
        "{:<80} {:>6} {:>8} {:>9} {:>8}",
        "world", "shapes", "exported", "triangles", "textures"
    )];
    let (mut exported_worlds, mut all_shapes, mut all_exported) = (0, 0, 0);
    let mut problems = Vec::new();
    for world in &worlds {
        let Some(checked) = check(world) else {
            continue;
        };
        let scene = &checked.scene;
        let compiled = regatta_runtime::compile(scene);
        let rows = report(&compiled, 16);
        let count: usize = scene.roots.iter().map(|&r| shapes_in(scene, r, 0)).sum();
        let name = world
            .strip_prefix(root().join(".."))
            .unwrap_or(world)
            .display()
            .to_string();
        if rows.len() != count {
            problems.push(format!(
                "{name}: {count} shapes, {} in the report",
                rows.len()
            ));
        }
        for row in &rows {
            if let Err(reason) = &row.status {
                if !reason.contains('\'') {
                    problems.push(format!("{name}: {} skipped: {reason}", row.geometry));
                }
            }
        }
        let document = export(&compiled, &Options { quality: 16 }, &[]).expect("export");
        let exported = rows.iter().filter(|r| r.status.is_ok()).count();
        let triangles: usize = rows.iter().filter_map(|r| r.status.as_ref().ok()).sum();
        let textures = document.json["images"].as_array().map_or(0, Vec::len);
        table.push(format!(
            "{name:<80} {count:>6} {exported:>8} {triangles:>9} {textures:>8}"
        ));
        exported_worlds += 1;
        all_shapes += count;
        all_exported += exported;
    }
    table.push(format!(
        "{exported_worlds} worlds: {all_shapes} shapes, {all_exported} exported"
    ));
    println!("{}", table.join("\n"));
    assert!(
        exported_worlds >= 40,
        "only {exported_worlds} worlds exported"
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
