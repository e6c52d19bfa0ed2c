//! Loading a world for the commands that run it: check (printing diagnostics), then compile;
//! and what those commands share once it is loaded (robot lookup, step counts, log recorders).

use std::path::Path;

use anyhow::{bail, Context};
use regatta_runtime::log::{Recorder, RunInfo};
use regatta_runtime::{compile, Compiled};
use regatta_schema::{check_file_with_proto_path, Checked};

static PROTO_PATH: std::sync::OnceLock<Vec<std::path::PathBuf>> = std::sync::OnceLock::new();

/// Sets the folders where `webots://` PROTOs are looked for (`--proto-path`, then
/// `REGATTA_PROTO_PATH`), once, before any world is read.
pub fn set_proto_path(dirs: Vec<std::path::PathBuf>) {
    let _ = PROTO_PATH.set(dirs);
}

/// The folders where `webots://` PROTOs are looked for.
pub fn proto_path() -> Vec<std::path::PathBuf> {
    PROTO_PATH.get().cloned().unwrap_or_default()
}

/// Prints which Webots PROTOs regatta's stand-ins replaced (`note:` lines on stderr).
pub fn print_substitutions(checked: &Checked) {
    for substitution in &checked.substitutions {
        eprintln!(
            "note: '{}' is regatta's built-in stand-in for {}",
            substitution.name, substitution.url
        );
    }
}

/// A checked and compiled world.
pub struct Loaded {
    pub checked: Checked,
    pub compiled: Compiled,
}

/// Adds what the runtime checks beyond the schema (each robot's network against its inputs
/// and outputs), keeping the diagnostics in file and position order.
pub fn check_runtime(checked: &mut Checked) {
    let extra = regatta_runtime::neural::check_networks(&checked.scene);
    if extra.is_empty() {
        return;
    }
    checked.diagnostics.extend(extra);
    checked
        .diagnostics
        .sort_by_key(|d| (d.file.0, d.diagnostic.span.start));
}

/// Checks `path` (printing warnings and errors to stderr) and compiles it; fails on errors.
pub fn load(path: &Path, lenient: bool, color: bool) -> anyhow::Result<Loaded> {
    let mut checked = check_file_with_proto_path(path, !lenient, proto_path())?;
    print_substitutions(&checked);
    check_runtime(&mut checked);
    let shown: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| d.diagnostic.is_error() || lenient)
        .collect();
    for diagnostic in &shown {
        let source = &checked.sources[diagnostic.file.0 as usize];
        eprint!(
            "{}",
            diagnostic
                .diagnostic
                .render(&source.name, &source.text, color)
        );
    }
    if checked.has_errors() {
        let errors = checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .count();
        bail!(
            "{} has {errors} error(s); `regatta check` lists them",
            path.display()
        );
    }
    let compiled = compile(&checked.scene);
    for warning in &compiled.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(Loaded { checked, compiled })
}

/// The index of the robot called `name`; the error lists the robots the world has.
pub fn robot_named(compiled: &Compiled, world: &Path, name: &str) -> anyhow::Result<usize> {
    compiled.rig.robot(name).ok_or_else(|| {
        let names: Vec<&str> = compiled
            .rig
            .robots
            .iter()
            .map(|r| r.name.as_str())
            .collect();
        anyhow::anyhow!(
            "{} has no robot named '{name}' (it has: {})",
            world.display(),
            names.join(", ")
        )
    })
}

/// Steps covering `duration` seconds of simulated time (a partial step counts as one).
pub fn steps_for(duration: f64, time_step: f64) -> anyhow::Result<u64> {
    if !(duration >= 0.0 && duration.is_finite()) {
        bail!("--duration must be a non-negative number of seconds, found {duration}");
    }
    Ok((duration / time_step).ceil().max(0.0) as u64)
}

/// A log recorder writing to `path` (its folder created), with the run's world text and seed.
pub fn create_recorder(
    path: &Path,
    world: &Path,
    loaded: &Loaded,
    simulation: &mut regatta_runtime::sim::Simulation,
    lenient: bool,
    steps_requested: u64,
    channels: regatta_runtime::log::Channels,
) -> anyhow::Result<Recorder<std::io::BufWriter<std::fs::File>>> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
    }
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let run = RunInfo {
        world_name: world.display().to_string(),
        world_text: loaded.checked.sources[0].text.to_string(),
        seed: simulation.seed,
        lenient,
        steps_requested,
        channels,
        controllers: changed_controllers(loaded),
    };
    Ok(Recorder::new(
        std::io::BufWriter::new(file),
        simulation,
        &run,
    )?)
}

/// Robots whose controller (or its arguments) is not what their world gives, for the log.
fn changed_controllers(loaded: &Loaded) -> Vec<(String, String, Vec<String>)> {
    let scene = &loaded.checked.scene;
    loaded
        .compiled
        .rig
        .robots
        .iter()
        .filter(|robot| {
            scene.string(robot.node, "controller") != robot.controller
                || scene.strings(robot.node, "controllerArgs") != robot.controller_args
        })
        .map(|robot| {
            (
                robot.name.clone(),
                robot.controller.clone(),
                robot.controller_args.clone(),
            )
        })
        .collect()
}
