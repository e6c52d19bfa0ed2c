//! `regatta batch`: one world, many seeds, independent runs in parallel; one row per run
//! (JSON lines or CSV), the same bytes for any `-j`.

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::{bail, Context};
use regatta_evolve::world::Override;
use regatta_evolve::{Experiment, Fitness};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    /// Seeds: a range `1..1000` (both ends included) or a list `1,5,9`.
    #[arg(long, default_value = "1..10", value_parser = parse_seeds)]
    seeds: Seeds,
    /// Simulated time per run (s).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    duration: f64,
    /// Set a field of every node of a type or DEF name: NODE.FIELD=VALUE (repeatable), e.g.
    /// `Khepera.controllerArgs=irGain=2`; a VALUE that is not a number, list, node or quoted
    /// string is quoted.
    #[arg(long = "set", value_name = "NODE.FIELD=VALUE", value_parser = parse_override)]
    overrides: Vec<Override>,
    /// Run the robots with the network of WORLD's first robot that has one (its controller,
    /// network with weights, and turret): an evolved controller in another arena.
    #[arg(long, value_name = "WORLD")]
    network_from: Option<PathBuf>,
    /// The fitness of each row: NAME[:key=value,...] (avoidance, regatta, phototaxis).
    #[arg(long, default_value = "regatta", value_parser = regatta_evolve::Fitness::parse)]
    fitness: Fitness,
    /// Threads (0: one per core). The output does not depend on it.
    #[arg(short = 'j', long = "jobs", default_value_t = 0)]
    jobs: usize,
    /// One JSON object per line (the default), as `run --json` prints but without wall time.
    #[arg(long, conflicts_with = "csv")]
    json: bool,
    /// One CSV row per run, with a header.
    #[arg(long)]
    csv: bool,
    /// Run no program of the world's project (see `run --builtin-only`): robots whose
    /// controller is the project's own are refused, or with --lenient run a built-in one.
    #[arg(long)]
    builtin_only: bool,
    #[command(flatten)]
    vary: crate::vary::VaryOptions,
    #[command(flatten)]
    reading: crate::world::WorldOptions,
}

/// The seeds of a batch.
#[derive(Clone, Debug)]
pub struct Seeds(pub Vec<u64>);

pub(crate) fn parse_seeds(text: &str) -> Result<Seeds, String> {
    let number = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| format!("\"{s}\" is not a seed (a non-negative integer)"))
    };
    let seeds: Vec<u64> = if let Some((a, b)) = text.split_once("..") {
        let (a, b) = (number(a)?, number(b.trim_start_matches('='))?);
        if b < a {
            return Err(format!("the range {text} is empty"));
        }
        if b - a >= 100_000_000 {
            return Err(format!("the range {text} has more than 100000000 seeds"));
        }
        (a..=b).collect()
    } else {
        text.split(',').map(number).collect::<Result<_, _>>()?
    };
    Ok(Seeds(seeds))
}

pub(crate) fn parse_override(text: &str) -> Result<Override, String> {
    Override::parse(text).map_err(|e| e.to_string())
}

/// A progress bar on standard error when it is a terminal.
pub(crate) fn progress_bar(total: u64, unit: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {unit}, {{per_sec}}, eta {{eta}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(bar)
}

/// The overrides that move `world`'s neural robot into another world.
pub(crate) fn network_from(world: &std::path::Path) -> anyhow::Result<Vec<Override>> {
    let source = regatta_parser::SourceText::read(world)
        .with_context(|| format!("cannot read {}", world.display()))?;
    regatta_evolve::world::network_overrides(&source.text)
        .with_context(|| format!("cannot take a network from {}", world.display()))
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let mut overrides = match &args.network_from {
        Some(world) => network_from(world)?,
        None => Vec::new(),
    };
    overrides.extend(args.overrides.iter().cloned());
    // A batch runs the robots' project controllers as `run` does (each trial its own
    // processes), unless --builtin-only.
    let experiment = if args.builtin_only {
        Experiment::load_with(
            &args.world,
            &args.reading.options()?,
            &overrides,
            regatta_evolve::Driven::Nobody,
        )
    } else {
        Experiment::load_with_programs(&args.world, &args.reading.options()?, &overrides)
    }
    .with_context(|| format!("cannot load {}", args.world.display()))?
    .with_variations(args.vary.all()?)
    .with_context(|| format!("cannot vary {}", args.world.display()))?;
    eprint!("{}", experiment.warnings);
    if !(args.duration >= 0.0 && args.duration.is_finite()) {
        bail!("--duration must be a non-negative number of seconds");
    }
    let steps = experiment.steps_for(args.duration);
    let pool = regatta_evolve::thread_pool(args.jobs);
    let bar = progress_bar(args.seeds.0.len() as u64, "runs");
    let done = AtomicU64::new(0);
    let tick = || {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(bar) = &bar {
            bar.set_position(n);
        }
    };
    let started = Instant::now();
    let rows = regatta_evolve::evaluate(
        &experiment,
        None,
        &args.seeds.0,
        &args.fitness,
        steps,
        &pool,
        &tick,
    )?;
    let wall = started.elapsed().as_secs_f64();
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    if args.csv {
        if let Some(first) = rows.first() {
            writeln!(out, "{}", first.csv_header())?;
        }
        for row in &rows {
            writeln!(out, "{}", row.csv_row())?;
        }
    } else {
        let _ = args.json;
        for row in &rows {
            writeln!(out, "{}", serde_json::to_string(row)?)?;
        }
    }
    out.flush()?;
    eprintln!(
        "{} runs of {} steps in {wall:.3} s: {:.1} evaluations/s on {} threads",
        rows.len(),
        steps,
        rows.len() as f64 / wall.max(1e-9),
        pool.current_num_threads()
    );
    Ok(Outcome::Clean)
}
