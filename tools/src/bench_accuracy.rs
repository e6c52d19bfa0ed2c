//! `regatta bench accuracy`: what the physics step costs and what it changes.
//!
//! The world runs at a ladder of `basicTimeStep`s with everything else fixed: each robot's
//! control period is the one it has at the world's own step, and the sensors keep their
//! sampling periods. A rung whose step does not divide the control period and every sensor
//! period (those above 0) would move when the robot decides or senses, so it is left out and
//! said why (`--sensor-period` sets every IR and ambient sensor's period, to keep more rungs).
//! Each rung is compared with the finest, seed by seed: pose divergence after 1, 10 and 60 s
//! (or the run's end), the IR readings' error at the control ticks of the first second, and
//! the buoy visits (with the share in cyclic order) over the run; and timed. The observed
//! order of convergence is the slope of log divergence against log step.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use regatta_evolve::world::Override;
use regatta_evolve::{Experiment, Fitness, Observer};
use regatta_runtime::sim::Simulation;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world.
    #[arg(default_value = "worlds/regatta.wbt")]
    world: PathBuf,
    /// Physics steps to try (ms), coarsest first; the finest that fits is the reference.
    #[arg(long, value_delimiter = ',', default_values_t = [128.0, 64.0, 32.0, 16.0, 8.0, 4.0, 2.0, 1.0])]
    steps: Vec<f64>,
    /// Seeds 1..=N.
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// Simulated seconds per run.
    #[arg(long, default_value_t = 60.0)]
    duration: f64,
    /// Sets every IR and ambient sensor's sampling period (ms) before the ladder is chosen.
    #[arg(long)]
    sensor_period: Option<f64>,
    /// Directory for accuracy.csv and the chart.
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
    /// File format of the chart.
    #[arg(long, value_enum, default_value_t)]
    format: crate::plot::FigureFormat,
}

/// Times (s) at which poses are compared.
const CHECKPOINTS: [f64; 3] = [1.0, 10.0, 60.0];

/// One run's record: poses at the checkpoints, IR readings at the control ticks of the first
/// second, visits.
struct Trace {
    poses: Vec<[(f64, f64); 3]>,
    ir: Vec<[u16; 8]>,
    visits: usize,
    cyclic: usize,
    wall: f64,
}

struct Rung {
    step_ms: f64,
    wall: f64,
    /// Mean over seeds and robots of the pose divergence (m) at each checkpoint.
    divergence: [f64; 3],
    ir_error: f64,
    visits: f64,
    cyclic_share: f64,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    if args.seeds == 0 || args.duration.is_nan() || args.duration <= 0.0 {
        bail!("--seeds must be at least 1 and --duration positive");
    }
    let own = load(&args, None)?;
    let own_step = own.compiled.settings.time_step;
    let periods: Vec<f64> = own
        .compiled
        .rig
        .robots
        .iter()
        .map(|r| r.control_period)
        .collect();
    if periods.is_empty() {
        bail!("{} has no robot", args.world.display());
    }
    println!(
        "{}: control periods {} ms (at the world's own step, {} ms); {} s per run, seeds 1..={}",
        args.world.display(),
        periods
            .iter()
            .map(|p| format!("{}", p * 1000.0))
            .collect::<Vec<_>>()
            .join(", "),
        own_step * 1000.0,
        args.duration,
        args.seeds
    );
    let mut ladder = Vec::new();
    for &step_ms in &args.steps {
        let experiment = load(&args, Some(step_ms))?;
        match misfit(&experiment, &periods, step_ms) {
            Some(why) => println!("  {step_ms} ms left out: {why}"),
            None => ladder.push((step_ms, experiment)),
        }
    }
    ladder.sort_by(|a, b| b.0.total_cmp(&a.0));
    let Some((finest, _)) = ladder.last() else {
        bail!("no step of the ladder fits the world's control and sensor periods");
    };
    let finest = *finest;
    // Poses are compared at times every rung reaches in whole steps: each checkpoint rounded
    // down to a multiple of the coarsest step (1 s is 31.25 steps of 32 ms).
    let coarsest = ladder[0].0 / 1000.0;
    let checkpoints: Vec<f64> = CHECKPOINTS
        .iter()
        .map(|&t| ((t.min(args.duration) / coarsest + 1e-9).floor().max(1.0)) * coarsest)
        .collect();
    let mut traces = Vec::new();
    for (step_ms, experiment) in &ladder {
        let mut per_seed = Vec::new();
        for seed in 1..=args.seeds {
            per_seed.push(trace(
                experiment,
                &periods,
                seed,
                args.duration,
                &checkpoints,
            )?);
        }
        traces.push((*step_ms, per_seed));
    }
    let reference = &traces.last().expect("a rung").1;
    let rungs: Vec<Rung> = traces
        .iter()
        .map(|(step_ms, runs)| compare(*step_ms, runs, reference))
        .collect();
    let mut table = String::new();
    writeln!(
        table,
        "{:>8} {:>9} {:>12} {:>12} {:>12} {:>10} {:>8} {:>7}",
        "step ms",
        "run s",
        "pose 1 s m",
        "pose 10 s m",
        "pose 60 s m",
        "IR error",
        "visits",
        "cyclic"
    )?;
    for r in &rungs {
        writeln!(
            table,
            "{:>8} {:>9.3} {:>12.3e} {:>12.3e} {:>12.3e} {:>10.3} {:>8.1} {:>6.0}%",
            r.step_ms,
            r.wall,
            r.divergence[0],
            r.divergence[1],
            r.divergence[2],
            r.ir_error,
            r.visits,
            100.0 * r.cyclic_share
        )?;
    }
    print!("{table}");
    println!(
        "(poses compared at {} s: whole steps of every rung)",
        checkpoints
            .iter()
            .map(|t| format!("{t:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("(errors against the {finest} ms run, seed by seed; IR error in readings, 0…1023)");
    for (k, t) in CHECKPOINTS.iter().enumerate() {
        match order(&rungs, k) {
            Some(p) => println!("observed order of convergence, pose at {t} s: {p:.2}"),
            None => println!(
                "observed order of convergence, pose at {t} s: none measurable (every coarser rung within round-off of the finest)"
            ),
        }
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join("accuracy.csv");
    let mut csv = String::from(
        "step_ms,run_s,pose_1s_m,pose_10s_m,pose_60s_m,ir_error,visits,cyclic_share\n",
    );
    for r in &rungs {
        writeln!(
            csv,
            "{},{},{},{},{},{},{},{}",
            r.step_ms,
            r.wall,
            r.divergence[0],
            r.divergence[1],
            r.divergence[2],
            r.ir_error,
            r.visits,
            r.cyclic_share
        )?;
    }
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    println!("{}", csv_path.display());
    let name = crate::world::world_name(&args.world);
    crate::plot::save(&chart(&rungs, &name), &args.out, "accuracy", args.format)?;
    Ok(Outcome::Clean)
}

/// The world at `step_ms` (its own step when `None`), sensor periods set as asked.
fn load(args: &Args, step_ms: Option<f64>) -> anyhow::Result<Experiment> {
    let overrides: Vec<Override> = step_ms
        .map(|ms| Override::parse(&format!("WorldInfo.basicTimeStep={ms}")))
        .transpose()?
        .into_iter()
        .collect();
    let mut experiment = Experiment::load(&args.world, false, &overrides)
        .with_context(|| format!("cannot load {}", args.world.display()))?;
    if let Some(ms) = args.sensor_period {
        for robot in &mut experiment.compiled.rig.robots {
            for s in std::sync::Arc::make_mut(&mut robot.distance_sensors).iter_mut() {
                s.period = ms / 1000.0;
            }
            for s in std::sync::Arc::make_mut(&mut robot.light_sensors).iter_mut() {
                s.period = ms / 1000.0;
            }
        }
    }
    Ok(experiment)
}

/// Why `step_ms` cannot run the world with everything else fixed, if it cannot; fixes each
/// robot's control period to `periods` when it can.
fn misfit(experiment: &Experiment, periods: &[f64], step_ms: f64) -> Option<String> {
    let step = step_ms / 1000.0;
    let divides = |period: f64| {
        let ratio = period / step;
        (ratio - ratio.round()).abs() <= 1e-6 * ratio.max(1.0) && ratio.round() >= 1.0
    };
    for (robot, &period) in experiment.compiled.rig.robots.iter().zip(periods) {
        if !divides(period) {
            return Some(format!(
                "does not divide robot '{}''s control period, {} ms",
                robot.name,
                period * 1000.0
            ));
        }
        let sensors = robot
            .distance_sensors
            .iter()
            .map(|s| s.period)
            .chain(robot.light_sensors.iter().map(|s| s.period));
        for p in sensors.filter(|&p| p > 0.0) {
            if !divides(p) {
                return Some(format!(
                    "does not divide a sampling period of robot '{}', {} ms (--sensor-period sets them)",
                    robot.name,
                    p * 1000.0
                ));
            }
        }
    }
    None
}

/// One run of `experiment` under `seed`, each robot's control period fixed to `periods`.
fn trace(
    experiment: &Experiment,
    periods: &[f64],
    seed: u64,
    duration: f64,
    checkpoints: &[f64],
) -> anyhow::Result<Trace> {
    let mut compiled = experiment.compiled.clone();
    let step = compiled.settings.time_step;
    for (robot, &period) in compiled.rig.robots.iter_mut().zip(periods) {
        robot.control_steps = ((period / step).round() as u64).max(1);
        robot.control_period = robot.control_steps as f64 * step;
    }
    let started = Instant::now();
    let mut simulation = Simulation::new(&compiled, Some(seed))?;
    regatta_evolve::experiment::sense_for_fitness(&mut simulation);
    let fitness = Fitness::parse("regatta")?;
    let mut observer = Observer::new(&simulation, &fitness);
    let steps = (duration / step).round().max(1.0) as u64;
    let at: Vec<u64> = checkpoints
        .iter()
        .map(|&t| ((t / step).round() as u64).clamp(1, steps))
        .collect();
    let control = compiled.rig.robots[0].control_steps;
    let first_second = (1.0 / step).round() as u64;
    let mut poses = vec![[(0.0, 0.0); 3]; compiled.rig.robots.len()];
    let mut ir = Vec::new();
    for s in 0..steps {
        simulation.sense();
        if s % control == 0 && s < first_second {
            ir.push(simulation.robots[0].proximity);
        }
        simulation.act();
        observer.after_step(&simulation);
        for (k, &when) in at.iter().enumerate() {
            if simulation.steps == when {
                for (pose, robot) in poses.iter_mut().zip(&simulation.robots) {
                    pose[k] = (robot.pose.x, robot.pose.z);
                }
            }
        }
    }
    let wall = started.elapsed().as_secs_f64();
    let summary = observer.summary(&simulation, &experiment.name, None);
    let (visits, cyclic) = summary.robots.iter().fold((0, 0), |(v, c), r| {
        (
            v + r.visits.len(),
            c + r.visits.iter().filter(|v| v.cyclic).count(),
        )
    });
    Ok(Trace {
        poses,
        ir,
        visits,
        cyclic,
        wall,
    })
}

fn compare(step_ms: f64, runs: &[Trace], reference: &[Trace]) -> Rung {
    let mut divergence = [0.0; 3];
    let (mut ir_sum, mut ir_count) = (0.0, 0usize);
    let mut pose_count = 0usize;
    for (run, base) in runs.iter().zip(reference) {
        for (a, b) in run.poses.iter().zip(&base.poses) {
            for k in 0..3 {
                divergence[k] += ((a[k].0 - b[k].0).powi(2) + (a[k].1 - b[k].1).powi(2)).sqrt();
            }
            pose_count += 1;
        }
        for (a, b) in run.ir.iter().zip(&base.ir) {
            for (x, y) in a.iter().zip(b) {
                ir_sum += (*x as f64 - *y as f64).abs();
                ir_count += 1;
            }
        }
    }
    for d in &mut divergence {
        *d /= pose_count.max(1) as f64;
    }
    let visits: usize = runs.iter().map(|r| r.visits).sum();
    let cyclic: usize = runs.iter().map(|r| r.cyclic).sum();
    Rung {
        step_ms,
        wall: runs.iter().map(|r| r.wall).sum(),
        divergence,
        ir_error: ir_sum / ir_count.max(1) as f64,
        visits: visits as f64 / runs.len().max(1) as f64,
        cyclic_share: if visits == 0 {
            0.0
        } else {
            cyclic as f64 / visits as f64
        },
    }
}

/// Divergences below this (m) are round-off: they measure no order.
const ROUND_OFF: f64 = 1e-9;

/// The least-squares slope of log divergence at checkpoint `k` against log step, over the
/// rungs coarser than the finest whose divergence is above round-off.
fn order(rungs: &[Rung], k: usize) -> Option<f64> {
    let points: Vec<(f64, f64)> = rungs[..rungs.len().saturating_sub(1)]
        .iter()
        .filter(|r| r.divergence[k] > ROUND_OFF)
        .map(|r| (r.step_ms.ln(), r.divergence[k].ln()))
        .collect();
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(x, y), p| (x + p.0 / n, y + p.1 / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + (p.0 - mx) * (p.1 - my), b + (p.0 - mx).powi(2))
    });
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Pose divergence against run time, log–log, one series per checkpoint, the finest rung
/// left out (its error is zero by construction); a divergence below 10⁻¹² m is drawn there.
fn chart(rungs: &[Rung], world: &str) -> regatta_figures::Chart {
    use regatta_figures::{Axis, Chart, Corner, Series};
    let floor = 1e-12;
    let mut chart = Chart::new(
        format!("{world}: run time against pose error, by physics step"),
        Axis::log("run time, all seeds (s)"),
        Axis::log("pose divergence from the finest step (m; < 1e-12 drawn at 1e-12)"),
    )
    .legend(Corner::UpperRight);
    let coarse = &rungs[..rungs.len().saturating_sub(1)];
    for (k, t) in CHECKPOINTS.iter().enumerate() {
        chart = chart.with(Series::line_markers(
            format!("after {t} s"),
            coarse
                .iter()
                .map(|r| (r.wall.max(1e-6), r.divergence[k].max(floor)))
                .collect(),
        ));
    }
    chart
}
