//! `regatta run`: step a world and print a summary of the run.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use regatta_runtime::sim::Simulation;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    /// Simulated time to run (s).
    #[arg(long, conflicts_with = "steps", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Steps to run.
    #[arg(long)]
    steps: Option<u64>,
    /// Seed of every random stream (overrides WorldInfo.randomSeed).
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    options: crate::world::WorldOptions,
    #[command(flatten)]
    vary: crate::vary::VaryOptions,
    /// Run a world that has no robot (otherwise a mistake: nothing would move).
    #[arg(long)]
    allow_empty: bool,
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
    #[arg(long, default_value = "regatta", value_parser = regatta_evolve::Fitness::parse)]
    fitness: regatta_evolve::Fitness,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    if args.threads == Some(0) {
        anyhow::bail!("--threads must be at least 1");
    }
    // The step loop runs on one of the pool's threads, whatever the count: parallel phases
    // started from outside a pool wake its workers through a slower path, twice a step,
    // which made the default slower than `--threads 1` for small worlds.
    rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the thread pool")?
        .install(|| run_here(args, color))
}

fn run_here(mut args: Args, color: bool) -> anyhow::Result<Outcome> {
    // A run exports nothing: its robots' grouping nodes are never made.
    args.options.for_run = true;
    let variations = args.vary.all()?;
    let mut loaded = if variations.is_empty() {
        crate::world::load(&args.world, &args.options, color)?
    } else {
        crate::vary::load_varied(&args.world, &args.options, args.seed, variations, color)?
    };
    let programs = crate::webots::plan_programs(
        &mut loaded,
        &args.world,
        &args.controllers,
        args.options.lenient,
    )?;
    crate::webots::prepare_run(&mut loaded, &args.controllers, args.options.lenient)?;
    let compiled = &loaded.compiled;
    let name = crate::world::world_name(&args.world);
    let mut simulation =
        Simulation::new(compiled, args.seed).with_context(|| format!("cannot run {name}"))?;
    let mut programs = crate::webots::start_programs(
        &mut simulation,
        programs,
        &args.world,
        &args.controllers,
        args.log.is_some(),
    )?;
    // Only a log reads the retinas' filter outputs over every pixel.
    simulation.keep_filter_outputs(args.log.is_some());
    let backend = crate::vision::backend(args.renderer, compiled, &args.world)?;
    let vision = backend.as_ref().map(|b| b.describe());
    if let Some(backend) = backend {
        simulation.set_vision_backend(backend);
    }
    // Without --steps or --duration a run lasts a simulated minute.
    let steps = crate::world::step_limit(
        args.steps,
        Some(args.duration.unwrap_or(60.0)),
        simulation.time_step,
    )?
    .unwrap_or(0);
    let mut recorder = args
        .log
        .as_deref()
        .map(|path| {
            crate::world::create_recorder(
                path,
                &args.world,
                &loaded,
                &mut simulation,
                args.options.lenient,
                steps,
                args.channels,
            )
        })
        .transpose()?;
    // SIGINT and SIGTERM end the run between steps; the log is then closed properly and
    // marked interrupted, and the exit code says which signal it was.
    let stop = crate::signals::Stop::install();
    let mut observer = args.json.then(|| {
        regatta_evolve::experiment::sense_for_fitness(&mut simulation);
        regatta_evolve::Observer::new(&simulation, &args.fitness)
    });
    // The set-up's freed memory (the world's syntax and typed scene) lies between blocks a
    // run keeps; glibc holds on to it unless asked. Returned, a 1000-robot run's resident
    // set is about 0.5 MB smaller while it steps.
    #[cfg(target_env = "gnu")]
    // SAFETY: malloc_trim only releases free heap pages; it touches no live allocation.
    unsafe {
        libc::malloc_trim(0);
    }
    let progress = progress_bar(steps);
    let started = Instant::now();
    let mut failure = None;
    for step in 0..steps {
        if stop.requested() {
            break;
        }
        match &mut programs {
            // Nothing between sensing and acting: each robot sensed and driven in one sweep.
            None => simulation.step(),
            Some(programs) => {
                simulation.sense();
                // A project's controller that fails ends the run; the log keeps the steps
                // before.
                if let Err(error) = programs.exchange(&mut simulation) {
                    failure = Some(error.to_string());
                    break;
                }
                // A supervisor's wb_supervisor_simulation_quit ends the run after this step.
                if let Some(status) = programs.quit_requested() {
                    eprintln!("a supervisor ended the run (status {status})");
                    simulation.act();
                    break;
                }
                simulation.act();
            }
        }
        if let Some(error) = &simulation.vision_error {
            anyhow::bail!("step {}: {error}", simulation.steps);
        }
        let logged = recorder.as_mut().map_or(Ok(()), |r| {
            r.record(&simulation)?;
            match &mut programs {
                Some(programs) => record_programs(r, programs.take_records()),
                None => Ok(()),
            }
        });
        if let Err(error) = logged {
            let error = anyhow::Error::new(error)
                .context(format!("while logging step {}", simulation.steps));
            // The file is closed as it stands; the chunks written so far are readable.
            drop(recorder.take());
            if let Some(path) = args.log.as_deref() {
                eprintln!("{}", crate::world::salvaged_log_line(path));
            }
            return Err(error);
        }
        if let Some(observer) = &mut observer {
            observer.after_step(&simulation);
        }
        // A controller that fails is a broken run: said once, and the run ends there (the
        // log keeps the step with the failure).
        if let Some((index, robot)) = simulation
            .robots
            .iter()
            .enumerate()
            .find(|(_, r)| r.updated.controller_error)
        {
            failure = Some(format!(
                "robot '{}': controller \"{}\" failed at t = {:.3} s (step {}): {}",
                robot.name,
                compiled.rig.robots[index].controller,
                simulation.time - simulation.time_step,
                simulation.steps,
                robot.last_controller_error.as_deref().unwrap_or("")
            ));
            break;
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
    // The controllers end as in Webots: their last wb_robot_step returns -1.
    if let Some(programs) = programs.take() {
        let last = programs.finish(&simulation);
        if let Some(recorder) = &mut recorder {
            record_programs(recorder, last).context("cannot write the log")?;
        }
    }
    let was_interrupted = stop.requested();
    let log_line = match (recorder, args.log.as_deref()) {
        (Some(recorder), Some(path)) => {
            let stats = recorder
                .finish(&simulation, was_interrupted)
                .context("cannot close the log")?;
            Some(crate::world::log_line(path, stats.messages))
        }
        _ => None,
    };
    let wall = started.elapsed().as_secs_f64();
    if was_interrupted {
        eprintln!(
            "interrupted by {} after {} steps{}",
            stop.name(),
            simulation.steps,
            if args.log.is_some() {
                "; the log is complete and marked interrupted"
            } else {
                ""
            }
        );
    }
    if let Some(observer) = &observer {
        let mut summary = observer.summary(&simulation, &name, Some(wall));
        summary.variations = loaded.drawn.clone();
        println!("{}", serde_json::to_string_pretty(&summary)?);
        // Standard output is the JSON object alone.
        if let Some(line) = &log_line {
            eprintln!("{line}");
        }
        return Ok(finish(failure, &simulation, &name, &args, &stop));
    }
    println!("world {name}: seed {}", simulation.seed);
    for drawn in &loaded.drawn {
        println!("varied {} = {}", drawn.key(), drawn.value);
    }
    if let Some(vision) = vision {
        println!("vision rendered by {vision}");
    }
    println!(
        "simulated {:.3} s in {} steps of {} ms",
        simulation.time,
        simulation.steps,
        simulation.time_step * 1000.0
    );
    // Short runs take well under a millisecond: three significant digits, not three decimals.
    let wall_shown = if wall >= 1.0 {
        format!("{wall:.3} s")
    } else {
        format!("{:.3} ms", wall * 1e3)
    };
    println!(
        "wall time {wall_shown}: {:.0} steps/s, {:.0}× real time",
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
        println!();
    }
    if let Some(line) = &log_line {
        println!("{line}");
    }
    Ok(finish(failure, &simulation, &name, &args, &stop))
}

/// How a run ends once its summary is printed: a controller's failure (said once), a world
/// without robots (an error unless `--allow-empty`), a signal, or clean.
fn finish(
    failure: Option<String>,
    simulation: &Simulation,
    name: &str,
    args: &Args,
    stop: &crate::signals::Stop,
) -> Outcome {
    if let Some(failure) = failure {
        eprintln!("error: {failure}");
        if args.log.is_some() {
            eprintln!("the log is complete up to the failed step");
        }
        return Outcome::Errors;
    }
    if simulation.robots.is_empty() {
        eprintln!(
            "warning: {name} has no robot: the run only advanced time ({} steps); nothing moved and no sensor was read",
            simulation.steps
        );
        if !args.allow_empty {
            eprintln!("error: nothing to run; `--allow-empty` runs a world without robots");
            return Outcome::Errors;
        }
    }
    stop.outcome().unwrap_or(Outcome::Clean)
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

/// Writes what controller programs printed and their LEDs' changes into the log.
pub fn record_programs<W: std::io::Write + std::io::Seek>(
    recorder: &mut regatta_runtime::log::Recorder<W>,
    records: regatta_webots::Records,
) -> Result<(), regatta_runtime::log::LogError> {
    for line in &records.lines {
        recorder.record_output(line.robot, line.time, &line.line)?;
    }
    for state in &records.leds {
        recorder.record_leds(state.robot, state.time, &state.leds)?;
    }
    Ok(())
}
