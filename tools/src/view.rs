//! `regatta view`: step a world and show it live in the browser, or replay a log there with
//! a timeline. The page and its server are `regatta-view`'s; this module runs the steps: the
//! controls a client sent are applied between steps, real time (× a factor) is kept by
//! sleeping, and as fast as possible nothing ever waits on a client.

use std::io::Write;
use std::net::IpAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;
use regatta_runtime::sim::Simulation;
use regatta_view::{Control, Viewer};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input), or a log (`.mcap`) to replay.
    world: PathBuf,
    /// The port to serve on (0, the default, picks a free one; the URL, with the run's
    /// token, is printed first).
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// The address to listen on: 127.0.0.1 (this machine only) unless another is given.
    /// Beyond the loopback (`--bind 0.0.0.0`) the page, its data and its controls (pause,
    /// step, reset, speed) answer only requests carrying the run's token, a random one
    /// printed in the URL (others get 403): whoever has the URL can watch and drive the run.
    #[arg(long, value_name = "ADDR")]
    bind: Option<IpAddr>,
    /// Speed: `1` is real time, `N` N× real time, `fast` as fast as possible.
    #[arg(long, default_value = "1", value_parser = parse_speed)]
    speed: Speed,
    /// Start paused (play, or step, from the page).
    #[arg(long)]
    paused: bool,
    /// Simulated time to run (s); without it or --steps, the run goes on until stopped.
    #[arg(long, conflicts_with = "steps", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Steps to run.
    #[arg(long)]
    steps: Option<u64>,
    /// End when the run does, instead of keeping its last state on view until Ctrl-C.
    #[arg(long)]
    exit: bool,
    /// Seed of every random stream (overrides WorldInfo.randomSeed); a reset may give another.
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    options: crate::world::WorldOptions,
    /// Record every sensor and actuator to this MCAP file (the same bytes as `run --log`;
    /// resets are then refused, as a log holds one run).
    #[arg(long, value_name = "FILE.mcap")]
    log: Option<PathBuf>,
    /// The log's channels (as `run --channels`).
    #[arg(long, value_name = "LIST", default_value = "all", requires = "log")]
    channels: regatta_runtime::log::Channels,
    /// Threads that sense and control the robots (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    controllers: crate::webots::ControllerOverride,
}

/// Real time × factor; `None` as fast as possible.
#[derive(Clone, Copy, Debug)]
pub struct Speed(Option<f64>);

fn parse_speed(text: &str) -> Result<Speed, String> {
    match text {
        "fast" | "max" => Ok(Speed(None)),
        "realtime" | "real-time" => Ok(Speed(Some(1.0))),
        _ => match text.trim_start_matches(['x', '×']).parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(Speed(Some(x))),
            _ => Err("a positive factor of real time (1, 10, 0.5) or `fast`".to_owned()),
        },
    }
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    if args.threads == Some(0) {
        anyhow::bail!("--threads must be at least 1");
    }
    let bind = args.bind.unwrap_or(IpAddr::from([127, 0, 0, 1]));
    if !bind.is_loopback() {
        eprintln!(
            "note: --bind {bind}: other machines may reach the viewer; it answers only requests with the token in its URL, so whoever has that URL can watch this run and pause, step or reset it (the connection is plain HTTP: use it on networks you trust, or `ssh -L`)"
        );
        if bind.is_unspecified() {
            eprintln!(
                "note: listening on every address: open the URL with this machine's name or address in place of {bind}"
            );
        }
    }
    if args.world.extension().is_some_and(|e| e == "mcap") {
        return crate::view_replay::replay(&args.world, &args.options, bind, args.port);
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the thread pool")?
        .install(|| live(args, bind, color))
}

/// What the loop keeps of the page's controls.
struct Pace {
    paused: bool,
    speed: Option<f64>,
    /// Steps still to go of a `step` control (then pause).
    stepping: Option<u64>,
    /// Wall time and simulated time that real time counts from.
    anchor: (Instant, f64),
}

impl Pace {
    fn restart(&mut self, time: f64) {
        self.anchor = (Instant::now(), time);
    }

    /// Sleeps until the wall clock has caught up with simulated time (real time × speed);
    /// more than a quarter second behind, real time starts again from here instead of
    /// racing to catch up.
    fn keep(&mut self, time: f64) {
        let Some(speed) = self.speed.filter(|_| self.stepping.is_none()) else {
            return;
        };
        let due = Duration::from_secs_f64(((time - self.anchor.1) / speed).max(0.0));
        let elapsed = self.anchor.0.elapsed();
        if let Some(ahead) = due.checked_sub(elapsed) {
            std::thread::sleep(ahead);
        } else if elapsed - due > Duration::from_millis(250) {
            self.restart(time);
        }
    }
}

fn live(args: Args, bind: IpAddr, color: bool) -> anyhow::Result<Outcome> {
    let mut loaded = crate::world::load(&args.world, &args.options, color)?;
    // A project's own controllers run as in `run`, started again at each reset.
    let programs = crate::webots::plan_programs(
        &mut loaded,
        &args.world,
        &args.controllers,
        args.options.lenient,
    )?;
    crate::webots::prepare_run(&mut loaded, &args.controllers, args.options.lenient)?;
    let compiled = &loaded.compiled;
    let name = crate::world::world_name(&args.world);
    let renderer = crate::vision::RendererKind::default();
    let start = |seed: Option<u64>| -> anyhow::Result<Simulation<'_>> {
        let mut simulation =
            Simulation::new(compiled, seed).with_context(|| format!("cannot run {name}"))?;
        if let Some(backend) = crate::vision::backend(renderer, compiled, &args.world)? {
            simulation.set_vision_backend(backend);
        }
        Ok(simulation)
    };
    let mut simulation = start(args.seed)?;
    let mut running = crate::webots::start_programs(
        &mut simulation,
        programs.clone(),
        &args.world,
        &args.controllers,
        args.log.is_some(),
    )?;
    let limit = crate::world::step_limit(args.steps, args.duration, simulation.time_step)?;
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
                limit.unwrap_or(0),
                args.channels,
            )
        })
        .transpose()?;
    let mut viewer = Viewer::serve(compiled, bind, args.port)
        .with_context(|| format!("cannot serve the viewer on {bind}:{}", args.port))?;
    let stop = crate::signals::Stop::install();
    let mut pace = Pace {
        paused: args.paused,
        speed: args.speed.0,
        stepping: None,
        anchor: (Instant::now(), 0.0),
    };
    let mut finished = limit == Some(0);
    let seed = simulation.seed;
    viewer.update_status(|s| {
        s.paused = pace.paused;
        s.speed = pace.speed;
        s.seed = seed;
        s.finished = finished;
    });
    viewer.publish(&simulation);
    // The first line is the URL alone, for a person to open and a script to read; by then
    // the page finds the run's status and first state.
    println!("{}", viewer.url());
    let _ = std::io::stdout().flush();
    eprintln!("viewing {name} (Ctrl-C ends it)");
    // Wall time while stepping only (not paused or ended), for the steps/s figure.
    let mut stepping = Duration::ZERO;
    let mut running_since: Option<Instant> = None;
    let mut failure = None;
    while !stop.requested() {
        let idle = pace.paused || finished;
        if idle {
            if let Some(since) = running_since.take() {
                stepping += since.elapsed();
            }
        } else if running_since.is_none() {
            running_since = Some(Instant::now());
        }
        if idle && finished && args.exit {
            break;
        }
        let control = if idle {
            viewer.wait_control(Duration::from_millis(100))
        } else {
            viewer.control()
        };
        if let Some(control) = control {
            let logging = recorder.is_some();
            match apply(control, &mut pace, finished, logging, &simulation) {
                Applied::Note(note) => viewer.update_status(|s| s.note = note),
                Applied::Reset(seed) => {
                    if let Some(old) = running.take() {
                        old.finish(&simulation);
                    }
                    simulation = start(seed.or(args.seed))?;
                    running = crate::webots::start_programs(
                        &mut simulation,
                        programs.clone(),
                        &args.world,
                        &args.controllers,
                        false,
                    )?;
                    finished = limit == Some(0);
                    pace.restart(0.0);
                    viewer.restart(&simulation);
                }
                Applied::Done => {}
            }
            let seed = simulation.seed;
            viewer.update_status(|s| {
                s.paused = pace.paused;
                s.speed = pace.speed;
                s.seed = seed;
                s.finished = finished;
            });
            continue;
        }
        if idle {
            continue;
        }
        match running.as_mut() {
            Some(controllers) => {
                simulation.sense();
                if let Err(error) = controllers.exchange(&mut simulation) {
                    failure = Some(error.to_string());
                }
                simulation.act();
            }
            None => simulation.step(),
        }
        if let Some(error) = &simulation.vision_error {
            anyhow::bail!("step {}: {error}", simulation.steps);
        }
        if let Some(recorder) = recorder.as_mut() {
            recorder
                .record(&simulation)
                .with_context(|| format!("while logging step {}", simulation.steps))?;
            if let Some(controllers) = running.as_mut() {
                crate::run::record_programs(recorder, controllers.take_records())
                    .with_context(|| format!("while logging step {}", simulation.steps))?;
            }
        }
        viewer.after_step(&simulation);
        if let Some(robot) = simulation
            .robots
            .iter()
            .find(|r| r.updated.controller_error)
        {
            failure = Some(format!(
                "robot '{}': controller failed at step {}: {}",
                robot.name,
                simulation.steps,
                robot.last_controller_error.as_deref().unwrap_or("")
            ));
        }
        if let Some(left) = pace.stepping.as_mut() {
            *left = left.saturating_sub(1);
            if *left == 0 {
                pace.stepping = None;
                pace.paused = true;
                viewer.update_status(|s| s.paused = true);
                viewer.publish(&simulation);
            }
        }
        if failure.is_some() && running.is_some() {
            // A failed controller is done; the others end with it, as in `run`.
            if let Some(old) = running.take() {
                old.finish(&simulation);
            }
        }
        if failure.is_some() || limit.is_some_and(|l| simulation.steps >= l) {
            finished = true;
            viewer.publish(&simulation);
            viewer.update_status(|s| s.finished = true);
            continue;
        }
        pace.keep(simulation.time);
    }
    if let Some(since) = running_since {
        stepping += since.elapsed();
    }
    let wall = stepping.as_secs_f64();
    if let Some(controllers) = running.take() {
        let last = controllers.finish(&simulation);
        if let Some(recorder) = recorder.as_mut() {
            crate::run::record_programs(recorder, last).context("cannot write the log")?;
        }
    }
    let log_line = match (recorder, args.log.as_deref()) {
        (Some(recorder), Some(path)) => {
            let stats = recorder
                .finish(&simulation, stop.requested())
                .context("cannot close the log")?;
            Some(crate::world::log_line(path, stats.messages))
        }
        _ => None,
    };
    drop(viewer);
    println!(
        "simulated {:.3} s in {} steps; {:.0} steps/s over {:.3} s of wall time stepping",
        simulation.time,
        simulation.steps,
        simulation.steps as f64 / wall.max(1e-9),
        wall
    );
    if let Some(line) = log_line {
        println!("{line}");
    }
    if let Some(failure) = failure {
        eprintln!("error: {failure}");
        return Ok(Outcome::Errors);
    }
    Ok(stop.outcome().unwrap_or(Outcome::Clean))
}

enum Applied {
    Done,
    Note(String),
    Reset(Option<u64>),
}

fn apply(
    control: Control,
    pace: &mut Pace,
    finished: bool,
    logging: bool,
    simulation: &Simulation,
) -> Applied {
    match control {
        Control::Play | Control::Step(_) if finished => {
            return Applied::Note("the run has ended; reset to run it again".to_owned())
        }
        Control::Play => {
            pace.paused = false;
            pace.stepping = None;
            pace.restart(simulation.time);
        }
        Control::Pause => {
            pace.paused = true;
            pace.stepping = None;
        }
        Control::Step(n) => {
            pace.paused = false;
            // Steps asked while others are still pending add up: two clicks are two steps,
            // however busy the loop was when they arrived.
            pace.stepping = Some(pace.stepping.unwrap_or(0).saturating_add(n));
        }
        Control::Speed(speed) => {
            pace.speed = speed;
            pace.restart(simulation.time);
        }
        Control::Reset(_) if logging => {
            return Applied::Note("reset is off while logging: a log holds one run".to_owned())
        }
        Control::Reset(seed) => return Applied::Reset(seed),
    }
    Applied::Done
}
