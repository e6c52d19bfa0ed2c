//! Loading a world for the commands that run it: check (printing diagnostics), then compile;
//! and what those commands share once it is loaded (robot lookup, step counts, log recorders).
//! [`WorldOptions`] are the flags of every command that reads a world: `--lenient`,
//! `--allow-path DIR` and `--limit KEY=N`; `-` reads the world from standard input.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_parser::SourceText;
use regatta_runtime::log::{Recorder, RunInfo};
use regatta_runtime::{compile, compile_for_run, Compiled};
use regatta_schema::{check, check_path, Checked, FileAccess, FileDiagnostic, Limits, Options};

/// How a world is read: the flags shared by every command that reads one.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct WorldOptions {
    /// Read a foreign file leniently: unknown nodes and fields are skipped with a warning.
    #[arg(long)]
    pub lenient: bool,
    /// Let the world read files under DIR too (repeatable). A world reads only files under
    /// its project (its folder, or the folder above a `worlds` folder); one read from
    /// standard input reads none unless this names a folder.
    #[arg(long = "allow-path", value_name = "DIR")]
    pub allow_paths: Vec<PathBuf>,
    /// Raise a limit (repeatable): nesting (64), include-depth (16), proto-depth (32),
    /// nodes (1000000), file-size (256M).
    #[arg(long = "limit", value_name = "KEY=N", value_parser = parse_limit)]
    pub limits: Vec<String>,
    /// Compile for a run, which exports nothing ([`regatta_runtime::compile_for_run`]):
    /// set by `run`, not a flag.
    #[arg(skip)]
    pub for_run: bool,
}

/// Checks `--limit KEY=N` when the command line is read (a bad one is a usage error).
fn parse_limit(assignment: &str) -> Result<String, String> {
    Limits::default().set(assignment)?;
    Ok(assignment.to_owned())
}

/// What the world embedded in a log may read (its mode comes from the log).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct LogWorldOptions {
    /// Let the log's world read files under DIR (repeatable); otherwise it reads files only
    /// under its recorded folder, and only when that folder is inside the current directory.
    #[arg(long = "allow-path", value_name = "DIR")]
    pub allow_paths: Vec<PathBuf>,
    /// Raise a limit (repeatable): nesting, include-depth, proto-depth, nodes, file-size.
    #[arg(long = "limit", value_name = "KEY=N", value_parser = parse_limit)]
    pub limits: Vec<String>,
}

impl From<LogWorldOptions> for WorldOptions {
    fn from(options: LogWorldOptions) -> WorldOptions {
        WorldOptions {
            lenient: false,
            allow_paths: options.allow_paths,
            limits: options.limits,
            for_run: false,
        }
    }
}

impl WorldOptions {
    /// The folders a world at `world` may read files under: its project and `--allow-path`'s
    /// folders (none for standard input, unless `--allow-path` names some), canonical and
    /// without repeats, as `FileAccess` keeps them.
    pub fn readable_roots(&self, world: &Path) -> Vec<PathBuf> {
        let mut access = FileAccess::none();
        let folder = (world != Path::new("-"))
            .then(|| world.canonicalize().ok())
            .flatten()
            .and_then(|path| path.parent().map(Path::to_owned));
        if let Some(folder) = folder {
            let _ = access.allow(&regatta_schema::access::project_root(&folder));
        }
        for dir in &self.allow_paths {
            let _ = access.allow(dir);
        }
        access.roots().to_vec()
    }

    /// The checking options these flags ask for.
    pub fn options(&self) -> anyhow::Result<Options> {
        let mut access = FileAccess::none();
        for dir in &self.allow_paths {
            access
                .allow(dir)
                .with_context(|| format!("--allow-path {}", dir.display()))?;
        }
        let mut limits = Limits::default();
        for assignment in &self.limits {
            limits
                .set(assignment)
                .map_err(|message| anyhow::anyhow!("--limit {assignment}: {message}"))?;
        }
        Ok(Options {
            strict: !self.lenient,
            access,
            limits,
            base_dir: None,
            proto_path: proto_path(),
        })
    }
}

/// Whether `path` means standard input.
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// How messages and logs name a world given as `path`.
pub fn world_name(path: &Path) -> String {
    if is_stdin(path) {
        "<stdin>".to_owned()
    } else {
        path.display().to_string()
    }
}

/// Reads and checks the world at `path` (`-`: standard input), printing nothing.
pub fn check_world(path: &Path, world: &WorldOptions) -> anyhow::Result<Checked> {
    let options = world.options()?;
    if is_stdin(path) {
        let bytes =
            regatta_parser::source::read_bytes(std::io::stdin().lock(), options.limits.file_size)
                .map_err(|error| anyhow::anyhow!("standard input is not a world: {error}"))?;
        return Ok(check(
            SourceText::from_bytes("<stdin>".to_owned(), bytes),
            &options,
        ));
    }
    Ok(check_path(path, &options)?)
}

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
    /// What a log needs of the typed scene, kept when the scene is released.
    changed: Option<Vec<(String, String, Vec<String>)>>,
    /// The values variations drew for this run (`--vary`), which its log records.
    pub drawn: Vec<regatta_evolve::variations::Drawn>,
}

impl Loaded {
    /// Frees the typed scene's nodes once nothing will read them again: a run reads the
    /// compiled form only, and in a crowd the scene is a fifth of the process's memory. What
    /// a log records of it (the controllers the command line changed) is kept. Call it after
    /// the controllers are resolved.
    pub fn release_scene(&mut self) {
        self.changed = Some(changed_controllers(self));
        self.checked.scene.nodes = Vec::new();
    }
}

/// Checks `path` (printing errors, and warnings too in lenient mode, to stderr) and compiles
/// it; fails on errors.
pub fn load(path: &Path, world: &WorldOptions, color: bool) -> anyhow::Result<Loaded> {
    finish_load(check_world(path, world)?, path, world, color)
}

/// [`load`] with the world's text given (a variation of the file at `path`): it reads files
/// as the file at `path` would.
pub fn load_text(
    path: &Path,
    text: &str,
    world: &WorldOptions,
    color: bool,
) -> anyhow::Result<Loaded> {
    let mut options = world.options()?;
    if !is_stdin(path) {
        let canonical = path
            .canonicalize()
            .with_context(|| format!("cannot read {}", path.display()))?;
        if let Some(folder) = canonical.parent() {
            options
                .access
                .allow(&regatta_schema::access::project_root(folder))?;
            options.base_dir = Some(folder.to_owned());
        }
    }
    let source = SourceText::from_bytes(world_name(path), text.as_bytes().to_vec());
    finish_load(check(source, &options), path, world, color)
}

fn finish_load(
    mut checked: Checked,
    path: &Path,
    world: &WorldOptions,
    color: bool,
) -> anyhow::Result<Loaded> {
    print_substitutions(&checked);
    regatta_runtime::check::check_scene_with(&mut checked, &regatta_webots::programs_of(path));
    eprint!(
        "{}",
        checked.render_where(|d| d.diagnostic.is_error() || world.lenient, color)
    );
    if checked.has_errors() {
        let errors = checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .count();
        let errors = if errors == 1 {
            "1 error".to_owned()
        } else {
            format!("{errors} errors")
        };
        bail!(
            "{} has {errors}; `regatta check` lists them",
            world_name(path)
        );
    }
    let compiled = if world.for_run {
        compile_for_run(&checked.scene)
    } else {
        compile(&checked.scene)
    };
    for warning in &compiled.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(Loaded {
        checked,
        compiled,
        changed: None,
        drawn: Vec::new(),
    })
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
        let hint = regatta_schema::catalogue::did_you_mean(name, names.iter().copied())
            .map(|close| format!("; did you mean '{close}'?"))
            .unwrap_or_default();
        anyhow::anyhow!(
            "{} has no robot named '{name}' (it has: {}){hint}",
            world_name(world),
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

/// The steps `--steps` or `--duration` ask for (`--steps` first); `None`: no end asked for.
pub fn step_limit(
    steps: Option<u64>,
    duration: Option<f64>,
    time_step: f64,
) -> anyhow::Result<Option<u64>> {
    match (steps, duration) {
        (Some(steps), _) => Ok(Some(steps)),
        (None, Some(duration)) => steps_for(duration, time_step).map(Some),
        (None, None) => Ok(None),
    }
}

/// Creates the log file at `path`. A missing folder is created and said (a typo in a folder
/// name should not scatter logs unnoticed); a part of the path that is a file, or a path
/// that is a folder, is named as the problem.
pub fn create_log_file(path: &Path) -> anyhow::Result<std::fs::File> {
    if path.is_dir() {
        bail!(
            "cannot write the log to {}: it is a folder; give a file name such as {}",
            path.display(),
            path.join("run.mcap").display()
        );
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        // The nearest part of the path that exists must be a folder.
        if let Some(existing) = parent
            .ancestors()
            .find(|a| !a.as_os_str().is_empty() && a.exists())
        {
            if !existing.is_dir() {
                bail!(
                    "cannot write the log to {}: {} is a file, not a folder",
                    path.display(),
                    existing.display()
                );
            }
        }
        if !parent.exists() {
            std::fs::create_dir_all(parent).with_context(|| {
                format!("cannot create the folder {} for the log", parent.display())
            })?;
            eprintln!("note: created the folder {} for the log", parent.display());
        }
    }
    std::fs::File::create(path).with_context(|| format!("cannot create the log {}", path.display()))
}

/// "log: PATH (size, messages)", the line a command prints about a log it wrote.
pub fn log_line(path: &Path, messages: u64) -> String {
    let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
    let size = if bytes >= 1_000_000 {
        format!("{:.1} MB", bytes as f64 / 1e6)
    } else {
        format!("{:.1} kB", bytes as f64 / 1e3)
    };
    format!("log: {} ({size}, {messages} messages)", path.display())
}

/// What is left of a log whose writing failed: the messages of its complete chunks, up to
/// which simulated time, or that nothing of it can be read.
pub fn salvaged_log_line(path: &Path) -> String {
    let contents = std::fs::read(path)
        .ok()
        .and_then(|bytes| regatta_runtime::log::read(&bytes).ok());
    match contents {
        Some(contents) if !contents.messages.is_empty() => {
            let last = contents.messages.iter().map(|m| m.1).max().unwrap_or(0);
            format!(
                "log: {} is cut short: {} messages up to t = {:.3} s are readable (`regatta log info` reads it)",
                path.display(),
                contents.messages.len(),
                last as f64 * 1e-9
            )
        }
        _ => format!("log: nothing of {} is readable", path.display()),
    }
}

/// A log recorder writing to `path` (see [`create_log_file`]), with the run's world text and
/// seed.
pub fn create_recorder(
    path: &Path,
    world: &Path,
    loaded: &Loaded,
    simulation: &mut regatta_runtime::sim::Simulation,
    lenient: bool,
    steps_requested: u64,
    channels: regatta_runtime::log::Channels,
) -> anyhow::Result<Recorder<std::io::BufWriter<std::fs::File>>> {
    let file = create_log_file(path)?;
    let run = RunInfo {
        world_name: world_name(world),
        world_text: loaded.checked.sources[0].text.to_string(),
        seed: simulation.seed,
        lenient,
        steps_requested,
        channels,
        controllers: changed_controllers(loaded),
        variations: (!loaded.drawn.is_empty())
            .then(|| serde_json::to_string(&loaded.drawn))
            .transpose()?,
    };
    Recorder::new(std::io::BufWriter::new(file), simulation, &run).map_err(|error| {
        remove_unstarted_log(path);
        error.into()
    })
}

/// Removes what a log that could not start wrote: it holds no message. Only a plain file is
/// removed (a device such as /dev/full, a pipe or a link stays as it was).
fn remove_unstarted_log(path: &Path) {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
        std::fs::remove_file(path).ok();
    }
}

/// Rays traced per update above which `check` warns (about 10 ms per update at 20 ns a ray).
const COSTLY_RAYS: f64 = 500_000.0;

/// Warns about vision devices whose settings make a step slow, with the estimated cost per
/// step: the rays (or column evaluations) of one update, times the updates per step, at
/// about 20 ns per ray through a small scene's BVH. Only a world that checks is estimated.
pub fn warn_about_cost(checked: &mut Checked) {
    use regatta_runtime::compile::plan::RendererChoice;
    if checked.has_errors() {
        return;
    }
    // Compiling is what costs here (a large mesh is triangulated): a world without a vision
    // device has nothing to warn about and is not compiled for it.
    let has_vision = checked.scene.walk().into_iter().any(|id| {
        matches!(
            checked.scene.type_name(id),
            "PanoramicTurret" | "LinearCamera"
        )
    });
    if !has_vision {
        return;
    }
    let compiled = compile(&checked.scene);
    let rays = compiled.plan.renderer == RendererChoice::Rays;
    let time_step = compiled.settings.time_step;
    let mut warnings = Vec::new();
    for id in checked.scene.walk() {
        let scene = &checked.scene;
        let name = scene.type_name(id);
        let (per_update, what) = match name {
            "PanoramicTurret" => {
                let samples = scene.int(id, "samples").max(1) as f64;
                let stride = scene.int(id, "stride").max(1) as f64;
                match (scene.string(id, "optics"), rays) {
                    ("paper", _) => (1050.0 * samples * samples, "flat-view rays"),
                    (_, true) => (150.0 * samples * samples, "rays"),
                    (_, false) => (150.0 * samples / stride, "column evaluations"),
                }
            }
            "LinearCamera" => {
                let samples = scene.int(id, "samples").max(1) as f64;
                let pixels = scene.int(id, "pixels").max(1) as f64;
                if rays {
                    (pixels * samples * samples, "rays")
                } else {
                    (pixels * samples, "column evaluations")
                }
            }
            _ => continue,
        };
        if per_update <= COSTLY_RAYS {
            continue;
        }
        let period = scene.float(id, "samplingPeriod");
        let updates_per_step = if period <= time_step {
            1.0
        } else {
            time_step / period
        };
        let seconds = per_update * updates_per_step * 20e-9;
        let node = scene.node(id);
        let samples_index = scene.spec(id).field_index("samples");
        let at = samples_index
            .and_then(|i| node.value_span_at(i))
            .unwrap_or(node.origin);
        warnings.push(FileDiagnostic {
            file: at.file,
            diagnostic: regatta_parser::Diagnostic::warning(
                at.span,
                format!(
                    "this {name} costs about {:.0} ms per step ({per_update:.0} {what} per update)",
                    seconds * 1000.0
                ),
            )
            .with_label("these settings make every step slow")
            .with_note("fewer samples, or exact optics with the column renderer, cost less; `regatta bench retina` measures time against error")
            .with_code("costly-device"),
        });
    }
    checked.diagnostics.extend(warnings);
    checked.sort_diagnostics();
}

/// Robots whose controller (or its arguments) is not what their world gives, for the log.
fn changed_controllers(loaded: &Loaded) -> Vec<(String, String, Vec<String>)> {
    if let Some(changed) = &loaded.changed {
        return changed.clone();
    }
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
