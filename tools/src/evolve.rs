//! `regatta evolve`: evolve the weights of a world's `NeuralNetwork` (CMA-ES or a genetic
//! algorithm, in `regatta-evolve`), with checkpoints, resume, Ctrl-C after the current
//! generation, and the outputs: the best world, the fitness per generation as CSV and PNG,
//! and the best candidate's log.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::{bail, Context};
use regatta_evolve::evolve::{text_hash, Aggregate, Evolution, GenerationStats, Method, Settings};
use regatta_evolve::world::Override;
use regatta_evolve::{Experiment, Fitness};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world whose NeuralNetwork is evolved (and the world best.wbt is written from).
    world: PathBuf,
    /// More worlds every candidate is evaluated in (repeatable); their networks must take
    /// as many weights. A world with no network takes the first world's robot: its
    /// controller, network and turret (the arenas as they are, one controller).
    #[arg(long = "world", value_name = "WORLD")]
    more_worlds: Vec<PathBuf>,
    /// NAME[:key=value,...]: avoidance, regatta, phototaxis.
    #[arg(long, value_parser = check_fitness)]
    fitness: String,
    /// Candidates per generation (0: CMA-ES's default 4 + 3 ln n; 40 for the GA).
    #[arg(long, default_value_t = 0)]
    population: usize,
    /// Generations to run (a resumed run may be given more).
    #[arg(long, default_value_t = 50)]
    generations: u64,
    /// Seeds per candidate and world.
    #[arg(long, default_value_t = 2)]
    trials: usize,
    /// Simulated time per run (s).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    duration: f64,
    /// How a candidate's runs make its fitness.
    #[arg(long, value_enum, default_value_t = AggregateArg::Mean)]
    aggregate: AggregateArg,
    /// The optimiser.
    #[arg(long, value_enum, default_value_t = MethodArg::Cmaes)]
    method: MethodArg,
    /// Seed of the evolution (candidates and trial seeds).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Initial step size (CMA-ES) or mutation deviation (GA); default 0.5 and 0.2.
    #[arg(long, allow_negative_numbers = true)]
    sigma: Option<f64>,
    /// Threads (0: one per core). Results do not depend on it.
    #[arg(short = 'j', long = "jobs", default_value_t = 0)]
    jobs: usize,
    /// Save a checkpoint into DIR after every generation.
    #[arg(long, value_name = "DIR")]
    checkpoint: Option<PathBuf>,
    /// Start from the first world's written weights (CMA-ES's mean, the genetic algorithm's
    /// centre) instead of random ones: evolve on from a network evolved before (a network
    /// grown by new inputs whose weights are written 0 keeps its behaviour at the start).
    #[arg(long)]
    from_weights: bool,
    /// Continue the evolution saved in DIR (same command and seed), bit for bit.
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// Where the outputs go.
    #[arg(long, default_value = "out/evolve")]
    out: PathBuf,
    /// File format of the fitness chart.
    #[arg(long, value_enum, default_value_t)]
    format: crate::plot::FigureFormat,
    /// Set a field in every world: NODE.FIELD=VALUE (repeatable).
    #[arg(long = "set", value_name = "NODE.FIELD=VALUE", value_parser = crate::batch::parse_override)]
    overrides: Vec<Override>,
    #[command(flatten)]
    vary: crate::vary::VaryOptions,
    #[command(flatten)]
    reading: crate::world::WorldOptions,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum AggregateArg {
    Mean,
    Min,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    Cmaes,
    Ga,
}

fn check_fitness(text: &str) -> Result<String, String> {
    regatta_evolve::Fitness::parse(text)
        .map_err(|e| e.to_string())
        .map(|_| text.to_owned())
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let fitness = Fitness::parse(&args.fitness)?;
    let reading = args.reading.options()?;
    let load = |path: &Path, overrides: &[Override]| {
        Experiment::load_with(path, &reading, overrides, regatta_evolve::Driven::Nobody)
    };
    let mut paths = vec![args.world.clone()];
    paths.extend(args.more_worlds.iter().cloned());
    let mut experiments: Vec<Experiment> = paths
        .iter()
        .map(|path| {
            load(path, &args.overrides).with_context(|| format!("cannot load {}", path.display()))
        })
        .collect::<anyhow::Result<_>>()?;
    // A world whose robots have no network takes the first world's robot (controller,
    // network, turret): the same controller sails every arena.
    for index in 1..experiments.len() {
        if experiments[index].network.is_some() || experiments[0].network.is_none() {
            continue;
        }
        let mut overrides = regatta_evolve::world::network_overrides(&experiments[0].text)
            .with_context(|| format!("cannot take the network of {}", experiments[0].name))?;
        overrides.extend(args.overrides.iter().cloned());
        let path = &paths[index];
        experiments[index] =
            load(path, &overrides).with_context(|| format!("cannot load {}", path.display()))?;
        eprintln!(
            "{}: its robots take {}'s network and turret",
            path.display(),
            experiments[0].name
        );
    }
    // Every world's trials draw the same variations, each from its trial's seed.
    let variations = args.vary.all()?;
    let experiments: Vec<Experiment> = experiments
        .into_iter()
        .map(|experiment| {
            let name = experiment.name.clone();
            experiment
                .with_variations(variations.clone())
                .with_context(|| format!("cannot vary {name}"))
        })
        .collect::<anyhow::Result<_>>()?;
    let dimension = experiments[0].parameter_count().with_context(|| {
        format!(
            "{} has no robot with controller \"neural\" and a NeuralNetwork to evolve",
            args.world.display()
        )
    })?;
    for experiment in &experiments[1..] {
        match experiment.parameter_count() {
            Some(n) if n == dimension => {}
            Some(n) => bail!(
                "{}'s network takes {n} weights, {}'s {dimension}: every world must share the network's shape",
                experiment.name,
                experiments[0].name
            ),
            None => bail!("{} has no neural robot to evaluate candidates on", experiment.name),
        }
    }
    if !(args.duration > 0.0 && args.duration.is_finite()) {
        bail!("--duration must be a positive number of seconds");
    }
    if args.trials == 0 {
        bail!("--trials must be at least 1");
    }
    let method = match args.method {
        MethodArg::Cmaes => Method::Cmaes,
        MethodArg::Ga => Method::Ga,
    };
    let population = match (method, args.population) {
        (Method::Ga, 0) => 40,
        (_, p) => p,
    };
    let settings = Settings {
        method,
        fitness: args.fitness.clone(),
        population,
        generations: args.generations,
        trials: args.trials,
        steps: experiments[0].steps_for(args.duration),
        aggregate: match args.aggregate {
            AggregateArg::Mean => Aggregate::Mean,
            AggregateArg::Min => Aggregate::Min,
        },
        seed: args.seed,
        sigma: args.sigma.unwrap_or(match method {
            Method::Cmaes => 0.5,
            Method::Ga => 0.2,
        }),
        worlds: experiments
            .iter()
            .map(|e| (e.name.clone(), text_hash(&e.text)))
            .collect(),
        from_weights: args.from_weights,
    };
    let mut evolution = match &args.resume {
        Some(dir) => {
            let mut evolution = Evolution::load(dir)?;
            evolution.resumes(&settings)?;
            eprintln!(
                "resuming {} after generation {}",
                dir.display(),
                evolution.generation()
            );
            evolution
        }
        None if args.from_weights => {
            let written = experiments[0]
                .network
                .as_ref()
                .map(|n| n.weights.clone())
                .unwrap_or_default();
            if written.len() != dimension {
                bail!(
                    "--from-weights: {} holds {} weights, its network takes {dimension}",
                    experiments[0].name,
                    written.len()
                );
            }
            Evolution::starting_at(settings, written)
        }
        None => Evolution::new(settings, dimension),
    };
    let checkpoint_dir = args.checkpoint.clone().or_else(|| args.resume.clone());
    // SIGINT or SIGTERM ends the evolution after the generation in progress, with a
    // checkpoint to resume from; the exit code says which signal it was.
    let stop = crate::signals::Stop::install();
    let pool = regatta_evolve::thread_pool(args.jobs);
    let runs_per_generation =
        (evolution.population() * experiments.len() * evolution.settings.trials) as u64;
    let remaining = evolution
        .settings
        .generations
        .saturating_sub(evolution.generation());
    let bar = crate::batch::progress_bar(remaining * runs_per_generation, "runs");
    let done = AtomicU64::new(0);
    let tick = || {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(bar) = &bar {
            bar.set_position(n);
        }
    };
    eprintln!(
        "evolving {dimension} weights: {} candidates × {} world(s) × {} trial(s) of {} steps per generation, {} threads",
        evolution.population(),
        experiments.len(),
        evolution.settings.trials,
        evolution.settings.steps,
        pool.current_num_threads()
    );
    let started = Instant::now();
    while !evolution.finished() {
        let stats = evolution.step(&experiments, &fitness, &pool, &tick)?;
        let line = format!(
            "generation {}: best {:.4} mean {:.4} worst {:.4} (best so far {:.4}), sigma {:.4}",
            stats.generation, stats.best, stats.mean, stats.worst, stats.best_ever, stats.sigma
        );
        match &bar {
            Some(bar) => bar.println(line),
            None => println!("{line}"),
        }
        if let Some(dir) = &checkpoint_dir {
            evolution.save(dir)?;
        }
        if stop.requested() {
            break;
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let wall = started.elapsed().as_secs_f64();
    if !evolution.finished() {
        let dir = checkpoint_dir.unwrap_or_else(|| args.out.join("checkpoint"));
        evolution.save(&dir)?;
        eprintln!(
            "interrupted after generation {}: checkpoint in {}; continue with --resume {}",
            evolution.generation(),
            dir.display(),
            dir.display()
        );
    }
    write_outputs(
        &reading,
        &evolution,
        &experiments[0],
        &variations,
        &fitness,
        &args.out,
        args.format,
    )?;
    eprintln!(
        "{} runs in {wall:.1} s ({:.1} evaluations/s)",
        done.load(Ordering::Relaxed),
        done.load(Ordering::Relaxed) as f64 / wall.max(1e-9)
    );
    Ok(stop.outcome().unwrap_or(Outcome::Clean))
}

/// best.wbt, fitness.csv, fitness.png (or .svg) and best.mcap in `out`.
fn write_outputs(
    reading: &regatta_schema::Options,
    evolution: &Evolution,
    experiment: &Experiment,
    variations: &[regatta_evolve::variations::Variation],
    fitness: &Fitness,
    out: &Path,
    format: crate::plot::FigureFormat,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let csv_path = out.join("fitness.csv");
    let mut csv = String::from("generation,evaluations,best,mean,worst,best_ever,sigma\n");
    for s in &evolution.history {
        csv.push_str(&format!(
            "{},{},{:?},{:?},{:?},{:?},{:?}\n",
            s.generation, s.evaluations, s.best, s.mean, s.worst, s.best_ever, s.sigma
        ));
    }
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    println!("{}", csv_path.display());
    if !evolution.history.is_empty() {
        let chart = fitness_chart(&evolution.history, &evolution.settings.fitness);
        crate::plot::save(&chart, out, "fitness", format)?;
    }
    let Some(best) = &evolution.best else {
        return Ok(());
    };
    let text = regatta_evolve::world::with_weights(&experiment.text, &best.weights)
        .with_context(|| format!("cannot write the weights into {}", experiment.name))?;
    let world_path = out.join("best.wbt");
    std::fs::write(&world_path, &text)
        .with_context(|| format!("cannot write {}", world_path.display()))?;
    println!("{}", world_path.display());
    // The best candidate's run, logged: the world just written, under its generation's
    // first trial seed, with what that trial's variations drew (what `regatta run best.wbt
    // --seed S --vary … --log` records too).
    let best_world = Experiment::from_text_with(
        &world_path.display().to_string(),
        &text,
        Path::new(&experiment.name).parent().map(Path::to_owned),
        reading,
        &[],
        regatta_evolve::Driven::Nobody,
    )?
    .with_variations(variations.to_vec())?;
    let best_world = best_world.for_seed(best.seed)?.unwrap_or(best_world);
    let mut simulation = best_world.simulation(best.seed, None)?;
    let log_path = out.join("best.mcap");
    let file = std::fs::File::create(&log_path)
        .with_context(|| format!("cannot create {}", log_path.display()))?;
    let run = regatta_runtime::log::RunInfo {
        world_name: world_path.display().to_string(),
        world_text: best_world.text.clone(),
        seed: best.seed,
        lenient: experiment.lenient,
        steps_requested: evolution.settings.steps,
        channels: regatta_runtime::log::Channels::ALL,
        controllers: Vec::new(),
        variations: (!best_world.drawn.is_empty())
            .then(|| serde_json::to_string(&best_world.drawn))
            .transpose()?,
    };
    let mut recorder =
        regatta_runtime::log::Recorder::new(std::io::BufWriter::new(file), &mut simulation, &run)?;
    let mut observer = regatta_evolve::Observer::new(&simulation, fitness);
    for _ in 0..evolution.settings.steps {
        simulation.step();
        recorder.record(&simulation)?;
        observer.after_step(&simulation);
    }
    recorder.finish(&simulation, false)?;
    let summary = observer.summary(&simulation, &run.world_name, None);
    println!(
        "{} (seed {}: {} {:.4})",
        log_path.display(),
        best.seed,
        summary.fitness.name,
        summary.fitness.value
    );
    Ok(())
}

/// The fitness per generation: the population's spread (worst to best) as a band, best and
/// mean as lines.
fn fitness_chart(history: &[GenerationStats], fitness: &str) -> regatta_figures::Chart {
    use regatta_figures::{Axis, Chart, Corner, Series};
    let finite =
        |h: &&GenerationStats| h.best.is_finite() && h.mean.is_finite() && h.worst.is_finite();
    let kept: Vec<&GenerationStats> = history.iter().filter(finite).collect();
    let line = |value: fn(&GenerationStats) -> f64| -> Vec<(f64, f64)> {
        kept.iter()
            .map(|h| (h.generation as f64, value(h)))
            .collect()
    };
    Chart::new(
        format!("regatta evolve: {fitness}"),
        Axis::linear("generation"),
        Axis::linear(format!("fitness ({fitness})")),
    )
    .with(
        Series::band(
            "worst to best",
            kept.iter()
                .map(|h| (h.generation as f64, h.worst, h.best))
                .collect(),
        )
        .color(regatta_figures::style::color(0)),
    )
    .with(Series::line("best", line(|h| h.best)).color(regatta_figures::style::color(0)))
    .with(Series::line("mean", line(|h| h.mean)).color(regatta_figures::style::color(1)))
    .legend(Corner::LowerRight)
}
