//! Helpers shared by the integration tests: where the corpus and test data are, and the
//! expect-file harness (`REGATTA_BLESS=1` rewrites expectations, as rust-analyzer's
//! `UPDATE_EXPECT` does).

use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_owned()
}

/// `../shared/corpus`, beside the checkout.
pub fn corpus() -> PathBuf {
    root().join("../shared/corpus")
}

/// Every file below `dir` whose extension is one of `extensions`, sorted.
pub fn files_with(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.contains(&e))
            {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Compares `actual` with the file `expected`; with `REGATTA_BLESS=1`, writes it instead.
/// Returns a description of the mismatch, if any.
pub fn expect_file(expected: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("REGATTA_BLESS").is_some() {
        std::fs::write(expected, actual)
            .map_err(|e| format!("cannot write {}: {e}", expected.display()))?;
        return Ok(());
    }
    let wanted = std::fs::read_to_string(expected).map_err(|e| {
        format!(
            "{}: {e} (run with REGATTA_BLESS=1 to create it)",
            expected.display()
        )
    })?;
    if wanted == actual {
        return Ok(());
    }
    let first_difference = wanted
        .lines()
        .zip(actual.lines())
        .position(|(a, b)| a != b)
        .unwrap_or_else(|| wanted.lines().count().min(actual.lines().count()));
    Err(format!(
        "{} differs at line {}:\n  expected: {:?}\n  actual:   {:?}\n(run with REGATTA_BLESS=1 to accept)",
        expected.display(),
        first_difference + 1,
        wanted.lines().nth(first_difference).unwrap_or("<end>"),
        actual.lines().nth(first_difference).unwrap_or("<end>")
    ))
}

/// Checks and compiles a world given as text (strict mode); panics with the diagnostics if it
/// does not check.
pub fn compile_text(text: &str) -> regatta_runtime::Compiled {
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("test.wbt".to_owned(), text.as_bytes().to_vec()),
        &regatta_schema::Options::default(),
    );
    assert!(!checked.has_errors(), "{}", checked.render(false));
    regatta_runtime::compile(&checked.scene)
}

/// Compiles a project world from `worlds/`.
pub fn compile_world(name: &str) -> regatta_runtime::Compiled {
    let checked = regatta_schema::check_file(&root().join("worlds").join(name), true)
        .expect("world readable");
    assert!(!checked.has_errors(), "{}", checked.render(false));
    regatta_runtime::compile(&checked.scene)
}

/// A black world with one emissive vertical stripe `width_deg` wide at azimuth `azimuth_deg`
/// (counter-clockwise from the robot's forward +x), 0.5 m away, seen by a Khepera carrying
/// `turret` (a turret node, e.g. `PanoramicTurret { optics "exact" }`).
pub fn stripe_world(azimuth_deg: f64, width_deg: f64, turret: &str) -> String {
    let a = azimuth_deg.to_radians();
    let (x, z) = (0.5 * a.cos(), -0.5 * a.sin());
    let width = 2.0 * 0.5 * (width_deg.to_radians() / 2.0).tan();
    format!(
        "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
Transform {{ translation {x} 0.05 {z} rotation 0 1 0 {a}
  children [ Shape {{ appearance Appearance {{ material Material {{ diffuseColor 0 0 0 emissiveColor 1 1 1 }} }}
    geometry Box {{ size 0.001 1 {width} }} }} ] }}
Khepera {{ controller \"none\" turret {turret} }}
"
    )
}

/// Renders robot 0's Panoramic turret at its start pose.
pub fn panoramic_at_start(
    compiled: &regatta_runtime::Compiled,
    force_rays: bool,
) -> regatta_runtime::optics::RetinaOutput {
    use regatta_runtime::compile::rig::TurretRig;
    use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, force_rays);
    let poses = start_poses(compiled);
    let view = renderer.view(&compiled.plan, &poses, 0);
    let robot = &compiled.rig.robots[0];
    let Some(TurretRig::Panoramic(rig)) = &robot.turret else {
        panic!("robot 0 has no Panoramic turret")
    };
    let mut retina = Panoramic::new(rig);
    let mut out = RetinaOutput::default();
    retina.update(&renderer, &view, robot.start, robot.floor_y, &mut out);
    out
}

/// Every robot at its start pose.
pub fn start_poses(compiled: &regatta_runtime::Compiled) -> regatta_runtime::render::Poses {
    regatta_runtime::render::Poses {
        poses: compiled.rig.robots.iter().map(|r| r.start).collect(),
        floor_y: compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
    }
}
