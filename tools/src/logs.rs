//! Commands over sensor logs: `regatta replay --verify`, `regatta log export`, `regatta plot`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_runtime::log::{read, CdrReader, LogContents, Recorder, RunInfo};
use regatta_runtime::sim::Simulation;

use crate::Outcome;

/// Reads a log file, warning when it was cut short.
fn load(path: &Path) -> anyhow::Result<LogContents> {
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
fn compile_embedded(
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
    regatta_runtime::check::check_scene(&mut checked);
    if checked.has_errors() {
        eprint!("{}", checked.render(false));
        bail!("the world embedded in the log no longer checks with this regatta");
    }
    Ok(regatta_runtime::compile(&checked.scene))
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
    /// Compute a fitness from the log's channels: the value `run --json` gives for the run
    /// (the mean over robots first, then each robot's).
    Fitness {
        /// The log.
        log: PathBuf,
        /// NAME[:key=value,...]: avoidance, regatta, phototaxis.
        #[arg(long, value_parser = crate::run::parse_fitness)]
        fitness: regatta_evolve::Fitness,
        #[command(flatten)]
        world: crate::world::LogWorldOptions,
    },
}

pub fn log(args: LogArgs) -> anyhow::Result<Outcome> {
    match args.what {
        LogCommand::Export { log, csv } => export(&log, &csv),
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
        let (robot, kind) = split_topic(topic);
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

#[derive(clap::Args)]
pub struct PlotArgs {
    /// The log.
    log: PathBuf,
    /// Directory for the pictures.
    #[arg(long, default_value = "out/plots")]
    out: PathBuf,
    #[command(flatten)]
    world: crate::world::LogWorldOptions,
}

/// `regatta plot`: a top view of the arena with every robot's trajectory, and for each robot
/// with a retina a kymograph (time downwards, 150 photodiodes across, digital values as grey).
pub fn plot(args: PlotArgs) -> anyhow::Result<Outcome> {
    use image::{Rgb, RgbImage};
    let contents = load(&args.log)?;
    let compiled = compile_embedded(&contents.run, &args.world.into())?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    // Trajectories and retina rows per robot, in file order.
    let mut paths: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut retinas: Vec<(String, Vec<Vec<f64>>)> = Vec::new();
    for (topic, _, data) in &contents.messages {
        let (robot, kind) = split_topic(topic);
        let mut r = CdrReader::new(data);
        match kind {
            "pose" => {
                if let Ok((_, pose)) = regatta_runtime::log::decode_pose(data) {
                    let point = (pose.x, pose.z);
                    match paths.iter_mut().find(|(name, _)| name == robot) {
                        Some((_, path)) => path.push(point),
                        None => paths.push((robot.to_owned(), vec![point])),
                    }
                }
            }
            "retina" => {
                let row = (|| -> Result<Vec<f64>, regatta_runtime::log::ShortMessage> {
                    r.f64()?;
                    r.bool()?;
                    r.u16()?;
                    r.u16()?;
                    let analog = r.f32s()?;
                    let filters = r.strings()?;
                    r.f32s()?;
                    let digital = r.u16s(None)?;
                    // The first filter's digital values, scaled to 0…1; analog when none.
                    if filters.is_empty() || digital.is_empty() {
                        let peak = analog
                            .iter()
                            .fold(0.0f32, |m, v| m.max(*v))
                            .max(f32::MIN_POSITIVE);
                        return Ok(analog.iter().map(|&a| (a / peak) as f64).collect());
                    }
                    let width = digital.len() / filters.len();
                    let top = digital.iter().copied().max().unwrap_or(1).max(1) as f64;
                    let top = if top <= 63.0 { 63.0 } else { top };
                    Ok(digital[..width].iter().map(|&d| d as f64 / top).collect())
                })();
                if let Ok(row) = row {
                    match retinas.iter_mut().find(|(name, _)| name == robot) {
                        Some((_, rows)) => rows.push(row),
                        None => retinas.push((robot.to_owned(), vec![row])),
                    }
                }
            }
            _ => {}
        }
    }
    // Top view: x to the right, z downwards, 800 px across the static geometry and the paths.
    let mut bounds = compiled.graph.static_bounds();
    for (_, path) in &paths {
        for &(x, z) in path {
            bounds = bounds.union(regatta_runtime::geometry::Aabb {
                min: glam_point(x, z),
                max: glam_point(x, z),
            });
        }
    }
    if bounds.is_empty() {
        bail!("the log has neither geometry nor poses to plot");
    }
    let (span_x, span_z) = (
        (bounds.max.x - bounds.min.x).max(1e-6),
        (bounds.max.z - bounds.min.z).max(1e-6),
    );
    let scale = 760.0 / span_x.max(span_z);
    let (width, height) = ((span_x * scale) as u32 + 40, (span_z * scale) as u32 + 40);
    let mut top = RgbImage::from_pixel(width, height, Rgb([250, 250, 250]));
    let to_pixel = |x: f64, z: f64| {
        (
            (20.0 + (x - bounds.min.x) * scale) as i64,
            (20.0 + (z - bounds.min.z) * scale) as i64,
        )
    };
    let dot = |image: &mut RgbImage, (px, py): (i64, i64), color: Rgb<u8>| {
        if px >= 0 && py >= 0 && (px as u32) < image.width() && (py as u32) < image.height() {
            image.put_pixel(px as u32, py as u32, color);
        }
    };
    // Static geometry standing on the floor, as footprints.
    for &index in &compiled.graph.static_primitives {
        let primitive = &compiled.graph.primitives[index];
        let b = primitive.bounds;
        if b.max.y <= 0.001 {
            continue; // floors
        }
        let (x0, z0) = to_pixel(b.min.x, b.min.z);
        let (x1, z1) = to_pixel(b.max.x, b.max.z);
        for py in z0..=z1 {
            for px in x0..=x1 {
                dot(&mut top, (px, py), Rgb([150, 150, 150]));
            }
        }
    }
    for landmark in &compiled.landmarks {
        let (cx, cz) = to_pixel(landmark.center.x, landmark.center.y);
        let r = (landmark.radius * scale).max(2.0) as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy <= r * r {
                    dot(&mut top, (cx + dx, cz + dy), Rgb([230, 180, 20]));
                }
            }
        }
    }
    let colors = [
        Rgb([30, 80, 200]),
        Rgb([200, 40, 40]),
        Rgb([30, 150, 60]),
        Rgb([140, 60, 180]),
        Rgb([20, 150, 160]),
    ];
    for (k, (_, path)) in paths.iter().enumerate() {
        for pair in path.windows(2) {
            let (a, b) = (
                to_pixel(pair[0].0, pair[0].1),
                to_pixel(pair[1].0, pair[1].1),
            );
            let steps = (a.0 - b.0).abs().max((a.1 - b.1).abs()).max(1);
            for s in 0..=steps {
                let p = (a.0 + (b.0 - a.0) * s / steps, a.1 + (b.1 - a.1) * s / steps);
                dot(&mut top, p, colors[k % colors.len()]);
            }
        }
    }
    let path = args.out.join("top.png");
    top.save(&path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("{}", path.display());
    // Kymographs: at most 3000 rows, each pixel 4 px wide.
    for (robot, rows) in &retinas {
        let every = rows.len().div_ceil(3000).max(1);
        let kept: Vec<&Vec<f64>> = rows.iter().step_by(every).collect();
        let width = kept.iter().map(|r| r.len()).max().unwrap_or(0) as u32 * 4;
        let mut image = image::GrayImage::new(width.max(1), kept.len().max(1) as u32);
        for (y, row) in kept.iter().enumerate() {
            for (i, &v) in row.iter().enumerate() {
                let grey = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                for dx in 0..4 {
                    image.put_pixel(i as u32 * 4 + dx, y as u32, image::Luma([grey]));
                }
            }
        }
        let path = args.out.join(format!("{robot}-kymograph.png"));
        image
            .save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        println!("{}", path.display());
    }
    Ok(Outcome::Clean)
}

fn glam_point(x: f64, z: f64) -> glam::DVec3 {
    glam::DVec3::new(x, 0.0, z)
}
