//! `regatta run`: step a world and print a summary of the run.

use std::path::PathBuf;
use std::time::Instant;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context;
use regatta_runtime::sim::Simulation;

use crate::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file.
    world: PathBuf,
    /// Simulated time to run (s).
    #[arg(long, conflicts_with = "steps")]
    duration: Option<f64>,
    /// Steps to run.
    #[arg(long)]
    steps: Option<u64>,
    /// Seed of every random stream (overrides WorldInfo.randomSeed).
    #[arg(long)]
    seed: Option<u64>,
    /// Read a foreign file leniently.
    #[arg(long)]
    lenient: bool,
    /// Record every sensor and actuator to this MCAP file.
    #[arg(long, value_name = "FILE.mcap")]
    log: Option<PathBuf>,
    /// The log's channels, comma-separated: `all`, `regatta` (the reproducible record),
    /// `foxglove` (scene, tf, world_pose, images, events), or single channels.
    #[arg(long, value_name = "LIST", default_value = "all", requires = "log")]
    channels: regatta_runtime::log::Channels,
    /// What renders vision devices.
    #[arg(long, value_enum, default_value_t)]
    renderer: crate::vision::RendererKind,
    /// Threads that sense and control the robots (default: every core). The log is the
    /// same for any number.
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    controllers: crate::webots::ControllerOverride,
    /// Print the run as one JSON object (docs/run.schema.json) instead of text.
    #[arg(long)]
    json: bool,
    /// The fitness the JSON's top-level `fitness` reports (NAME[:key=value,...]).
    #[arg(long, default_value = "regatta", value_parser = parse_fitness)]
    fitness: regatta_evolve::Fitness,
}

pub(crate) fn parse_fitness(text: &str) -> Result<regatta_evolve::Fitness, String> {
    regatta_evolve::Fitness::parse(text).map_err(|e| e.to_string())
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    match args.threads {
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(threads) => rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("cannot start the thread pool")?
            .install(|| run_here(args, color)),
        None => run_here(args, color),
    }
}

fn run_here(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let mut loaded = crate::world::load(&args.world, args.lenient, color)?;
    crate::webots::refuse_unbuilt_robots(&loaded)?;
    crate::webots::resolve_controllers(
        &mut loaded.compiled,
        &args.controllers,
        args.lenient,
        None,
    )?;
    let compiled = &loaded.compiled;
    let mut simulation = Simulation::new(compiled, args.seed)
        .with_context(|| format!("cannot run {}", args.world.display()))?;
    let backend = crate::vision::backend(args.renderer, compiled, &args.world)?;
    let vision = backend.as_ref().map(|b| b.describe());
    if let Some(backend) = backend {
        simulation.set_vision_backend(backend);
    }
    let steps = match (args.steps, args.duration) {
        (Some(steps), _) => steps,
        (None, Some(duration)) => crate::world::steps_for(duration, simulation.time_step)?,
        (None, None) => crate::world::steps_for(60.0, simulation.time_step)?,
    };
    let mut recorder = args
        .log
        .as_deref()
        .map(|path| {
            crate::world::create_recorder(
                path,
                &args.world,
                &loaded,
                &mut simulation,
                args.lenient,
                steps,
                args.channels,
            )
        })
        .transpose()?;
    // Ctrl-C ends the run between steps; the log is then closed properly and marked.
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let interrupted = interrupted.clone();
        let _ = ctrlc::set_handler(move || interrupted.store(true, Ordering::SeqCst));
    }
    let mut observer = args.json.then(|| {
        regatta_evolve::experiment::sense_for_fitness(&mut simulation);
        regatta_evolve::Observer::new(&simulation, &args.fitness)
    });
    let progress = progress_bar(steps);
    let started = Instant::now();
    for step in 0..steps {
        if interrupted.load(Ordering::SeqCst) {
            break;
        }
        simulation.step();
        if let Some(error) = &simulation.vision_error {
            anyhow::bail!("step {}: {error}", simulation.steps);
        }
        if let Some(recorder) = &mut recorder {
            recorder
                .record(&simulation)
                .with_context(|| format!("while logging step {}", simulation.steps))?;
        }
        if let Some(observer) = &mut observer {
            observer.after_step(&simulation);
        }
        if step % 1024 == 0 {
            if let Some(bar) = &progress {
                if started.elapsed().as_secs_f64() > 1.0 {
                    bar.set_position(step);
                }
            }
        }
    }
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    let was_interrupted = interrupted.load(Ordering::SeqCst);
    if let Some(recorder) = recorder {
        recorder
            .finish(&simulation, was_interrupted)
            .context("cannot close the log")?;
    }
    let wall = started.elapsed().as_secs_f64();
    if was_interrupted {
        eprintln!(
            "interrupted after {} steps{}",
            simulation.steps,
            if args.log.is_some() {
                "; the log is complete and marked interrupted"
            } else {
                ""
            }
        );
    }
    if let Some(observer) = &observer {
        let summary = observer.summary(&simulation, &args.world.display().to_string(), Some(wall));
        println!("{}", serde_json::to_string_pretty(&summary)?);
        return Ok(Outcome::Clean);
    }
    println!("world {}: seed {}", args.world.display(), simulation.seed);
    if let Some(vision) = vision {
        println!("vision rendered by {vision}");
    }
    println!(
        "simulated {:.3} s in {} steps of {} ms",
        simulation.time,
        simulation.steps,
        simulation.time_step * 1000.0
    );
    println!(
        "wall time {:.3} s: {:.0} steps/s, {:.0}× real time",
        wall,
        simulation.steps as f64 / wall.max(1e-9),
        simulation.time / wall.max(1e-9)
    );
    for robot in &simulation.robots {
        let contacts = &robot.contacts;
        print!(
            "{}: at x {:.3} z {:.3} heading {:.1}°; contacts {} (longest {:.2} s, {} steps)",
            robot.name,
            robot.pose.x,
            robot.pose.z,
            robot.pose.heading.to_degrees(),
            contacts.events,
            contacts.longest,
            contacts.steps
        );
        if !compiled.landmarks.is_empty() {
            let sequence: Vec<String> = robot
                .visits
                .sequence
                .iter()
                .map(|&k| (k + 1).to_string())
                .collect();
            print!("; buoy visits {}: {}", sequence.len(), sequence.join(" "));
        }
        if let Some(fall) = &robot.fell {
            print!(
                "; fell off the floor at t {:.3} s, x {:.3} z {:.3}",
                fall.time, fall.pose.x, fall.pose.z
            );
        }
        if robot.controller_errors > 0 {
            print!(
                "; controller errors {} (last: {})",
                robot.controller_errors,
                robot.last_controller_error.as_deref().unwrap_or("")
            );
        }
        println!();
    }
    Ok(Outcome::Clean)
}

/// A progress bar on standard error when it is a terminal (hidden otherwise); it shows up only
/// once a run has lasted a second.
fn progress_bar(steps: u64) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(steps);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps, {per_sec}, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(bar)
}
