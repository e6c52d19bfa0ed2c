//! Commands over sensor logs: `regatta replay --verify`, `regatta log export`, `regatta log info`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_runtime::log::{read, CdrReader, LogContents, Recorder, RunInfo};
use regatta_runtime::sim::Simulation;

use crate::outcome::Outcome;

/// Reads a log file, warning when it was cut short.
pub(crate) fn load(path: &Path) -> anyhow::Result<LogContents> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let contents =
        read(&bytes).with_context(|| format!("{} is not a regatta log", path.display()))?;
    if let Some(reason) = &contents.truncated {
        eprintln!(
            "warning: {} ends early ({reason}); using the {} messages of its complete chunks",
            path.display(),
            contents.messages.len()
        );
    }
    Ok(contents)
}

/// Checks and compiles the world embedded in a log. A log is input like any other: its world
/// reads files (Inline, EXTERNPROTO) only under the recorded world's folder when that folder
/// is inside the current directory (a user replaying their own runs), or under folders given
/// with `--allow-path`; never elsewhere.
pub(crate) fn compile_embedded(
    run: &RunInfo,
    world: &crate::world::WorldOptions,
) -> anyhow::Result<regatta_runtime::Compiled> {
    let source = regatta_parser::SourceText::from_bytes(
        run.world_name.clone(),
        run.world_text.clone().into_bytes(),
    );
    let mut options = world.options()?;
    options.strict = !run.lenient;
    let recorded_folder = Path::new(&run.world_name)
        .parent()
        .filter(|_| !run.world_name.starts_with('<'))
        .map(|p| {
            if p.as_os_str().is_empty() {
                Path::new(".")
            } else {
                p
            }
        })
        .and_then(|p| p.canonicalize().ok());
    let here = std::env::current_dir().and_then(|d| d.canonicalize()).ok();
    if let (Some(folder), Some(here)) = (&recorded_folder, &here) {
        if folder.starts_with(here) {
            options.access.allow(folder)?;
        }
    }
    options.base_dir = recorded_folder;
    let mut checked = regatta_schema::check(source, &options);
    // The project's own controller programs (a Webots project's `controllers/NAME`) are
    // known names, as `run` knows them.
    let programs = regatta_webots::programs_of(Path::new(&run.world_name));
    regatta_runtime::check::check_scene_with(&mut checked, &programs);
    if checked.has_errors() {
        eprint!("{}", checked.render(false));
        bail!("the world embedded in the log no longer checks with this regatta");
    }
    let mut compiled = regatta_runtime::compile(&checked.scene);
    // A robot that ran its project's program: the log holds what it did; nothing here runs
    // the program again.
    for rig in &mut compiled.rig.robots {
        if programs(&rig.controller) {
            rig.program = Some(std::mem::replace(&mut rig.controller, "none".to_owned()));
            rig.controller_args.clear();
        }
    }
    // The controllers the run had: Webots names mapped as `run` maps them, then what the log
    // says the run changed.
    crate::webots::resolve_controllers(
        &mut compiled,
        &crate::webots::ControllerOverride::default(),
        true,
        None,
    )?;
    for (robot, controller, args) in &run.controllers {
        if let Some(rig) = compiled.rig.robots.iter_mut().find(|r| &r.name == robot) {
            rig.controller = controller.clone();
            rig.controller_args = args.clone();
        }
    }
    Ok(compiled)
}

#[derive(clap::Args)]
pub struct ReplayArgs {
    /// Re-run the log's world and seed and compare every message.
    #[arg(long, required = true)]
    verify: bool,
    /// The log.
    log: PathBuf,
    #[command(flatten)]
    world: crate::world::LogWorldOptions,
}

pub fn replay(args: ReplayArgs) -> anyhow::Result<Outcome> {
    let _ = args.verify;
    let contents = load(&args.log)?;
    let steps: u64 = contents
        .end
        .as_ref()
        .and_then(|end| end.get("steps"))
        .and_then(|s| s.parse().ok())
        .unwrap_or(contents.run.steps_requested);
    let compiled = compile_embedded(&contents.run, &args.world.into())?;
    if let Some(rig) = compiled.rig.robots.iter().find(|r| r.program.is_some()) {
        bail!(
            "robot '{}' ran its project's controller program \"{}\": `replay --verify` re-runs built-in controllers only (run the world again with `regatta run --log` and compare the logs)",
            rig.name,
            rig.program.as_deref().unwrap_or_default()
        );
    }
    let mut simulation = Simulation::new(&compiled, Some(contents.run.seed))?;
    let mut buffer = std::io::Cursor::new(Vec::new());
    let mut recorder = Recorder::new(&mut buffer, &mut simulation, &contents.run)?;
    for _ in 0..steps {
        simulation.step();
        recorder.record(&simulation)?;
    }
    let interrupted = contents
        .end
        .as_ref()
        .and_then(|e| e.get("interrupted"))
        .is_some_and(|v| v == "true");
    recorder.finish(&simulation, interrupted)?;
    let again = read(buffer.get_ref())?;
    for (index, (recorded, replayed)) in contents.messages.iter().zip(&again.messages).enumerate() {
        if recorded != replayed {
            println!(
                "DIFFERS at message {index}: {} at t = {:.3} s (replayed {} at t = {:.3} s)",
                recorded.0,
                recorded.1 as f64 / 1e9,
                replayed.0,
                replayed.1 as f64 / 1e9
            );
            return Ok(Outcome::Errors);
        }
    }
    if contents.truncated.is_none() && contents.messages.len() != again.messages.len() {
        println!(
            "DIFFERS: the log has {} messages, the replay {}",
            contents.messages.len(),
            again.messages.len()
        );
        return Ok(Outcome::Errors);
    }
    println!(
        "OK: {} messages over {} steps replay identically",
        contents.messages.len().min(again.messages.len()),
        steps
    );
    Ok(Outcome::Clean)
}

#[derive(clap::Args)]
pub struct LogArgs {
    #[command(subcommand)]
    what: LogCommand,
}

#[derive(clap::Subcommand)]
enum LogCommand {
    /// Write one CSV per channel kind (pose.csv: step,t_ns,t,robot,x,z,heading; …) and
    /// units.csv, the unit of every column.
    Export {
        /// The log.
        log: PathBuf,
        /// Directory for the CSV files.
        #[arg(long, value_name = "DIR")]
        csv: PathBuf,
    },
    /// What a log holds: world, seed, version, duration, and each channel with its schema and
    /// message count.
    Info {
        /// The log.
        log: PathBuf,
    },
    /// Compute a fitness from the log's channels: the value `run --json` gives for the run
    /// (the mean over robots first, then each robot's).
    Fitness {
        /// The log.
        log: PathBuf,
        /// NAME[:key=value,...]: avoidance, regatta, phototaxis.
        #[arg(long, value_parser = regatta_evolve::Fitness::parse)]
        fitness: regatta_evolve::Fitness,
        #[command(flatten)]
        world: crate::world::LogWorldOptions,
    },
}

pub fn log(args: LogArgs) -> anyhow::Result<Outcome> {
    match args.what {
        LogCommand::Export { log, csv } => export(&log, &csv),
        LogCommand::Info { log } => info(&log),
        LogCommand::Fitness {
            log,
            fitness,
            world,
        } => log_fitness(&log, &fitness, &world.into()),
    }
}

/// `regatta log fitness`: a fitness computed from a log's channels, the same value a live
/// run computes (both read the same per-step records).
fn log_fitness(
    log: &Path,
    fitness: &regatta_evolve::Fitness,
    world: &crate::world::WorldOptions,
) -> anyhow::Result<Outcome> {
    let contents = load(log)?;
    let compiled = compile_embedded(&contents.run, world)?;
    let (time_step, robots) = regatta_evolve::record::records_from_log(&contents)
        .with_context(|| format!("cannot read {}", log.display()))?;
    let mut values = Vec::new();
    let mut lines = Vec::new();
    for robot in &robots {
        let mut meters = regatta_evolve::fitness::Meters::new(fitness, &compiled.landmarks);
        robot.for_each(time_step, |record| meters.add(record));
        let terms = meters.terms();
        let value = terms.value(fitness);
        values.push(value);
        let detail = match fitness {
            regatta_evolve::Fitness::Avoidance { .. } => format!(
                "V {:?}, Δv {:?}, i {:?}",
                terms.avoidance.speed, terms.avoidance.turning, terms.avoidance.proximity
            ),
            regatta_evolve::Fitness::Regatta { .. } => format!(
                "cyclic visits {}, other visits {}, contact {:?} s",
                terms.regatta.cyclic_visits, terms.regatta.other_visits, terms.regatta.contact_s
            ),
            regatta_evolve::Fitness::Phototaxis { .. } => match terms.phototaxis.buoy {
                Some(buoy) => format!("brightest buoy {buoy}"),
                None => "no buoy".to_owned(),
            },
        };
        lines.push(format!("{}: {value:?} ({detail})", robot.name));
    }
    if values.is_empty() {
        bail!(
            "{} has no robot poses to compute a fitness from",
            log.display()
        );
    }
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    println!("{} {:?}", fitness.name(), mean);
    for line in lines {
        println!("{line}");
    }
    Ok(Outcome::Clean)
}

/// The robot and the channel kind of a topic `/{robot}/{kind}`.
pub(crate) fn split_topic(topic: &str) -> (&str, &str) {
    let trimmed = topic.trim_start_matches('/');
    trimmed.rsplit_once('/').unwrap_or(("", trimmed))
}

/// The robot's own name and the channel kind of a topic: the name from the channel's
/// metadata (topics carry the name sanitised), else from the topic itself (older logs).
pub(crate) fn robot_of<'a>(contents: &'a LogContents, topic: &'a str) -> (&'a str, &'a str) {
    let (token, kind) = split_topic(topic);
    let name = contents
        .topics
        .iter()
        .find(|t| t.topic == topic)
        .and_then(|t| t.robot.as_deref())
        .unwrap_or(token);
    (name, kind)
}

/// A decoded message: the CSV header after `step,t_ns,t,robot`, and the row.
type CsvRow = (Vec<String>, Vec<String>);

/// The unit and meaning of each column of each file (`units.csv`, beside the data).
const UNITS: &[(&str, &str, &str, &str)] = &[
    (
        "*",
        "step",
        "1",
        "steps completed at t (t_ns / the basic time step)",
    ),
    ("*", "t_ns", "ns", "simulated time, exact"),
    ("*", "t", "s", "simulated time, t_ns / 1e9 written exactly"),
    ("*", "robot", "", "the robot's name"),
    ("pose", "x", "m", "position of the robot's centre"),
    ("pose", "z", "m", "position of the robot's centre"),
    (
        "pose",
        "heading",
        "rad",
        "counter-clockwise from +x, seen from above",
    ),
    (
        "wheels",
        "command_*",
        "pulses/10 ms",
        "speed commanded to each wheel",
    ),
    (
        "wheels",
        "encoder_*",
        "pulses",
        "wheel encoder counts (1/12 mm)",
    ),
    (
        "proximity",
        "p0…p7",
        "0…1023",
        "IR proximity readings, K-Team's sensor order",
    ),
    (
        "ambient",
        "a0…a7",
        "0…1023",
        "ambient light readings (larger is darker)",
    ),
    ("retina", "dark", "", "whether every photodiode read 0"),
    (
        "retina",
        "analog0…",
        "photocurrent (0…150)",
        "each photodiode's analog value",
    ),
    (
        "retina",
        "FILTER0…",
        "photocurrent",
        "each enabled filter's output",
    ),
    (
        "retina",
        "FILTER_digitalN",
        "LSB",
        "the converter's output over the region of interest",
    ),
    ("k213", "pixel0…", "0…255", "grey levels"),
    ("k213", "light_level", "0…255", "the light-level sensor"),
    (
        "contacts",
        "touching",
        "",
        "whether the robot touches something",
    ),
    ("contacts", "contacts", "1", "contacts begun so far"),
    (
        "contacts",
        "with",
        "",
        "what the robot touches, names separated by ;",
    ),
    ("visits", "buoy", "1", "the buoy's index, in file order"),
    ("visits", "name", "", "the buoy's name"),
    ("visits", "visits", "1", "visits so far"),
    ("controller", "error", "", "why a controller call failed"),
];

/// One CSV row (after `step,t_ns,t,robot`) and its header, from a message of `kind`.
fn decode(kind: &str, data: &[u8]) -> Result<Option<CsvRow>, regatta_runtime::log::ShortMessage> {
    let mut r = CdrReader::new(data);
    r.f64()?;
    let numbered =
        |prefix: &str, n: usize| (0..n).map(|i| format!("{prefix}{i}")).collect::<Vec<_>>();
    Ok(Some(match kind {
        "pose" => (
            vec!["x".into(), "z".into(), "heading".into()],
            vec![
                r.f64()?.to_string(),
                r.f64()?.to_string(),
                r.f64()?.to_string(),
            ],
        ),
        "wheels" => (
            [
                "command_left",
                "command_right",
                "encoder_left",
                "encoder_right",
            ]
            .map(String::from)
            .to_vec(),
            vec![
                r.i32()?.to_string(),
                r.i32()?.to_string(),
                r.i32()?.to_string(),
                r.i32()?.to_string(),
            ],
        ),
        "proximity" | "ambient" => (
            numbered(if kind == "proximity" { "p" } else { "a" }, 8),
            r.u16s(Some(8))?.iter().map(u16::to_string).collect(),
        ),
        "retina" => {
            let dark = r.bool()?;
            let (first, last) = (r.u16()?, r.u16()?);
            let analog = r.f32s()?;
            let filters = r.strings()?;
            let filtered = r.f32s()?;
            let digital = r.u16s(None)?;
            let roi = (last as usize).saturating_sub(first as usize) + 1;
            let mut header = vec!["dark".to_owned()];
            let mut row = vec![dark.to_string()];
            header.extend(numbered("analog", analog.len()));
            row.extend(analog.iter().map(f32::to_string));
            for (k, name) in filters.iter().enumerate() {
                header.extend((0..analog.len()).map(|i| format!("{name}{i}")));
                row.extend(
                    filtered
                        .iter()
                        .skip(k * analog.len())
                        .take(analog.len())
                        .map(f32::to_string),
                );
                header.extend(
                    (first as usize..first as usize + roi).map(|i| format!("{name}_digital{i}")),
                );
                row.extend(digital.iter().skip(k * roi).take(roi).map(u16::to_string));
            }
            (header, row)
        }
        "k213" => {
            let pixels = r.u16s(None)?;
            let light = r.u16()?;
            let mut header = numbered("pixel", pixels.len());
            header.push("light_level".into());
            let mut row: Vec<String> = pixels.iter().map(u16::to_string).collect();
            row.push(light.to_string());
            (header, row)
        }
        "contacts" => {
            let (touching, contacts) = (r.bool()?, r.u64()?);
            // Logs written before contacts said with what have no such field.
            let with = r.strings().unwrap_or_default();
            (
                vec!["touching".into(), "contacts".into(), "with".into()],
                vec![touching.to_string(), contacts.to_string(), with.join(";")],
            )
        }
        "visits" => (
            vec!["buoy".into(), "name".into(), "visits".into()],
            vec![r.u32()?.to_string(), r.string()?, r.u32()?.to_string()],
        ),
        "controller" => (vec!["error".into()], vec![r.string()?]),
        _ => return Ok(None),
    }))
}

/// `t_ns` as seconds, written exactly (no binary-fraction noise: 32.000000000, not
/// 32.00000000000001).
fn seconds(t_ns: u64) -> String {
    format!("{}.{:09}", t_ns / 1_000_000_000, t_ns % 1_000_000_000)
}

/// One open CSV file: its header (after the time columns) and its writer.
struct CsvFile {
    header: Vec<String>,
    writer: csv::Writer<std::io::BufWriter<std::fs::File>>,
}

fn export(log: &Path, dir: &Path) -> anyhow::Result<Outcome> {
    let contents = load(log)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let time_step_ns = contents
        .time_step
        .map(|t| (t * 1e9).round() as u64)
        .filter(|&t| t > 0);
    if time_step_ns.is_none() {
        eprintln!("warning: the log does not give its time step: the step column is left empty");
    }
    // One file per channel kind; a robot whose messages of a kind have other columns (a
    // differently configured retina) gets a file of its own.
    let mut files: std::collections::BTreeMap<String, CsvFile> = Default::default();
    let mut order: Vec<String> = Vec::new();
    for (topic, t_ns, data) in &contents.messages {
        let (robot, kind) = robot_of(&contents, topic);
        let Some((header, row)) =
            decode(kind, data).with_context(|| format!("a {topic} message is damaged"))?
        else {
            continue;
        };
        let mut name = kind.to_owned();
        if files.get(&name).is_some_and(|f| f.header != header) {
            name = format!("{kind}-{robot}");
        }
        if !files.contains_key(&name) {
            let path = dir.join(format!("{name}.csv"));
            let file = std::fs::File::create(&path)
                .with_context(|| format!("cannot create {}", path.display()))?;
            let mut writer = csv::Writer::from_writer(std::io::BufWriter::new(file));
            let mut full = vec!["step", "t_ns", "t", "robot"];
            full.extend(header.iter().map(String::as_str));
            writer.write_record(&full)?;
            files.insert(name.clone(), CsvFile { header, writer });
            order.push(name.clone());
        }
        let file = files
            .get_mut(&name)
            .context("the CSV file was just opened")?;
        let step = time_step_ns
            .map(|dt| ((t_ns + dt / 2) / dt).to_string())
            .unwrap_or_default();
        let mut record = vec![step, t_ns.to_string(), seconds(*t_ns), robot.to_owned()];
        record.extend(row);
        file.writer.write_record(&record)?;
    }
    for name in &order {
        if let Some(mut file) = files.remove(name) {
            let path = dir.join(format!("{name}.csv"));
            file.writer
                .flush()
                .with_context(|| format!("cannot write {}", path.display()))?;
            println!("{}", path.display());
        }
    }
    let path = dir.join("units.csv");
    let file = std::fs::File::create(&path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    let mut units = csv::Writer::from_writer(file);
    units.write_record(["file", "column", "unit", "meaning"])?;
    for (file, column, unit, meaning) in UNITS {
        units.write_record([file, column, unit, meaning])?;
    }
    units
        .flush()
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("{}", path.display());
    Ok(Outcome::Clean)
}

/// `regatta log info`: the run, then one line per channel (like `mcap info`).
fn info(path: &Path) -> anyhow::Result<Outcome> {
    let contents = load(path)?;
    let size = std::fs::metadata(path)
        .with_context(|| format!("cannot read {}", path.display()))?
        .len();
    let run = &contents.run;
    let meta = |key: &str| {
        contents
            .metadata
            .get(key)
            .map(String::as_str)
            .unwrap_or("?")
    };
    let first = contents.messages.first().map_or(0, |m| m.1);
    let last = contents.messages.last().map_or(0, |m| m.1);
    let simulated = contents
        .end
        .as_ref()
        .and_then(|e| e.get("time"))
        .and_then(|t| t.parse::<f64>().ok())
        .unwrap_or(last as f64 / 1e9);
    println!("log:          {}", path.display());
    println!(
        "size:         {} bytes{}",
        size,
        if simulated > 0.0 {
            format!(
                " ({:.0} bytes per simulated minute)",
                size as f64 * 60.0 / simulated
            )
        } else {
            String::new()
        }
    );
    println!(
        "world:        {} (sha256 {})",
        run.world_name,
        meta("world_sha256")
    );
    println!("seed:         {}", run.seed);
    // The values `--vary` drew (the embedded world holds them; this names them).
    if let Some(drawn) = &run.variations {
        let drawn: Vec<serde_json::Value> = serde_json::from_str(drawn).unwrap_or_default();
        for d in drawn {
            println!(
                "varied:       {}[{}].{} = {}",
                d["node"].as_str().unwrap_or("?"),
                d["index"],
                d["field"].as_str().unwrap_or("?"),
                d["value"].as_str().unwrap_or("?")
            );
        }
    }
    println!("regatta:      {}", meta("regatta_version"));
    println!(
        "time step:    {} s{}",
        meta("time_step"),
        if run.lenient { "; read leniently" } else { "" }
    );
    let state = match (&contents.end, &contents.truncated) {
        (_, Some(reason)) => format!("truncated ({reason})"),
        (Some(end), None) if end.get("interrupted").is_some_and(|v| v == "true") => {
            "interrupted".to_owned()
        }
        _ => "complete".to_owned(),
    };
    let steps = contents
        .end
        .as_ref()
        .and_then(|e| e.get("steps"))
        .map_or("?".to_owned(), String::clone);
    println!(
        "steps:        {steps} of {} requested; {state}",
        run.steps_requested
    );
    println!(
        "duration:     {:.3} s simulated (messages from {:.3} s to {:.3} s)",
        simulated,
        first as f64 / 1e9,
        last as f64 / 1e9
    );
    println!("messages:     {}", contents.messages.len());
    println!("channels:     {}", run.channels);
    let mut counts: std::collections::BTreeMap<&str, (usize, u64, u64)> = Default::default();
    for (topic, time, _) in &contents.messages {
        let entry = counts.entry(topic).or_insert((0, *time, *time));
        entry.0 += 1;
        entry.1 = entry.1.min(*time);
        entry.2 = entry.2.max(*time);
    }
    let width = contents
        .topics
        .iter()
        .map(|t| t.topic.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    println!(
        "{:<width$}  {:<34}  {:>9}  {:>9}  {:>9}",
        "topic", "schema", "messages", "first (s)", "last (s)"
    );
    for topic in &contents.topics {
        let (n, from, to) = counts
            .get(topic.topic.as_str())
            .copied()
            .unwrap_or((0, 0, 0));
        let times = |ns: u64| {
            if n == 0 {
                "-".to_owned()
            } else {
                format!("{:.3}", ns as f64 / 1e9)
            }
        };
        println!(
            "{:<width$}  {:<34}  {:>9}  {:>9}  {:>9}",
            topic.topic,
            topic.schema,
            n,
            times(from),
            times(to)
        );
    }
    Ok(Outcome::Clean)
}
