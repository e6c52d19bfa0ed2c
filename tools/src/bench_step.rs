//! `regatta bench step`: simulation speed, single thread unless said otherwise.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use rayon::prelude::*;
use regatta_runtime::compile::plan::Plan;
use regatta_runtime::sim::Simulation;
use regatta_runtime::Compiled;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world.
    #[arg(default_value = "worlds/regatta.wbt")]
    world: PathBuf,
    /// Minimum time spent timing each configuration (ms).
    #[arg(long, default_value_t = 1000)]
    millis: u64,
    /// Measure the peak memory of running the world (used by the child process).
    #[arg(long, hide = true)]
    memory_child: bool,
    /// What renders vision devices (`wgpu`: the world as written, stepped with the GPU
    /// rendering its vision devices; the other configurations are CPU-only).
    #[arg(long, value_enum, default_value_t)]
    renderer: crate::vision::RendererKind,
    /// Generated swarms of these sizes instead of the world (10 robots/m², regatta
    /// controller, Panoramic turrets, N/10 light buoys): cost per step against N.
    #[arg(long, value_delimiter = ',')]
    robots: Vec<usize>,
    /// Swarms: no turrets (IR proximity and ambient light only; the braitenberg controller).
    #[arg(long)]
    ir_only: bool,
    /// Swarms: buoys in each world instead of N/10 (the arena grows to hold them).
    #[arg(long)]
    buoys: Option<usize>,
    /// Threads that sense and control (swarms: 1 unless given; the world's configurations:
    /// every core for the parallel worlds unless given).
    #[arg(long)]
    threads: Option<usize>,
    /// Swarms: simulate this many seconds per size and time them, instead of `--millis`.
    #[arg(long, allow_negative_numbers = true)]
    seconds: Option<f64>,
    /// Swarms: the turrets' crowd level of detail (`crowdDistance`, m): other robots farther
    /// than this are not drawn (its error: `regatta bench crowd`). 0 draws every robot (exact).
    #[arg(long, value_name = "METRES", default_value_t = 0.5)]
    crowd_distance: f64,
    /// Swarms, with a crowd distance: the turrets' `crowdFarDistance` (m): buoys farther than
    /// this are left out rather than drawn as impostors (its error: `regatta bench crowd
    /// --far-distances`). 0: impostors however far.
    #[arg(long, value_name = "METRES", default_value_t = 5.0)]
    far_distance: f64,
    /// Swarms, with a crowd distance: the turrets' `crowdKeepDistance` (m): impostors are
    /// worked out again only once a retina has moved this far (its error: `regatta bench
    /// crowd --keep-distances`). 0: on every update.
    #[arg(long, value_name = "METRES", default_value_t = 0.0)]
    keep_distance: f64,
    /// Swarms: seed of the placements.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Swarms: directory for swarm.csv and swarm.png (swarm-ir.* with `--ir-only`).
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
    /// Swarms: only write each generated world to this directory (swarm-N.wbt), to run or
    /// inspect it.
    #[arg(long, value_name = "DIR")]
    write_worlds: Option<PathBuf>,
}

/// Steps per second of a world over about `millis` ms; `everything` refreshes the sensors no
/// controller reads too.
fn steps_per_second(compiled: &Compiled, millis: u64, everything: bool) -> anyhow::Result<f64> {
    let mut simulation = Simulation::new(compiled, None)?;
    if everything {
        simulation.sense_everything();
    }
    simulation.run(100); // warm up
    let started = Instant::now();
    let budget = std::time::Duration::from_millis(millis);
    let mut steps = 0u64;
    while started.elapsed() < budget {
        simulation.run(500);
        steps += 500;
    }
    Ok(steps as f64 / started.elapsed().as_secs_f64())
}

fn text_of(path: &std::path::Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

fn load(path: &std::path::Path) -> anyhow::Result<Compiled> {
    Ok(crate::world::load(path, &Default::default(), false)?.compiled)
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let threads = match args.threads {
        Some(0) => bail!("--threads must be at least 1"),
        Some(threads) => threads,
        None if args.robots.is_empty() => return world_configurations(args),
        None => 1,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the thread pool")?;
    pool.install(|| match args.robots.is_empty() {
        true => world_configurations(args),
        false => swarms(args, threads),
    })
}

/// `--robots`: generated swarms of each size.
fn swarms(args: Args, threads: usize) -> anyhow::Result<Outcome> {
    use crate::bench_swarm::{measure, Budget, SwarmSpec};
    if args.robots.contains(&0) {
        bail!("--robots: every size must be at least 1");
    }
    for (flag, value) in [
        ("--far-distance", args.far_distance),
        ("--keep-distance", args.keep_distance),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            bail!("{flag}: {value} is not a distance of 0 m or more");
        }
    }
    let spec = |robots: usize| SwarmSpec {
        robots,
        buoys: args.buoys,
        ir_only: args.ir_only,
        seed: args.seed,
        crowd_distance: (args.crowd_distance > 0.0).then_some(args.crowd_distance),
        far_distance: (args.far_distance > 0.0).then_some(args.far_distance),
        keep_distance: (args.keep_distance > 0.0).then_some(args.keep_distance),
    };
    if let Some(directory) = &args.write_worlds {
        std::fs::create_dir_all(directory)
            .with_context(|| format!("cannot create {}", directory.display()))?;
        for &robots in &args.robots {
            let path = directory.join(format!(
                "swarm-{robots}{}.wbt",
                if args.ir_only { "-ir" } else { "" }
            ));
            std::fs::write(&path, crate::bench_swarm::swarm_world(&spec(robots)))
                .with_context(|| format!("cannot write {}", path.display()))?;
            println!("wrote {}", path.display());
        }
        return Ok(Outcome::Clean);
    }
    if args.memory_child {
        // Peak memory of building and stepping one swarm (a fresh process per size).
        let row = measure(
            &spec(args.robots[0]),
            args.seconds.map_or(
                Budget::Wall(std::time::Duration::from_millis(args.millis)),
                Budget::Simulated,
            ),
        )?;
        let peak = crate::memory::peak_resident_bytes().unwrap_or(0);
        println!("{peak} {}", row.steps);
        return Ok(Outcome::Clean);
    }
    let budget = args.seconds.map_or(
        Budget::Wall(std::time::Duration::from_millis(args.millis)),
        Budget::Simulated,
    );
    let mut rows = Vec::new();
    let exe = std::env::current_exe()?;
    for &robots in &args.robots {
        let mut row = measure(&spec(robots), budget)?;
        // The child runs a short version: memory peaks once every buffer has grown.
        let mut child = std::process::Command::new(&exe);
        child.args([
            "bench",
            "step",
            "--memory-child",
            "--millis",
            "200",
            "--threads",
            &threads.to_string(),
            "--seed",
            &args.seed.to_string(),
            "--robots",
            &robots.to_string(),
        ]);
        if args.ir_only {
            child.arg("--ir-only");
        }
        if let Some(buoys) = args.buoys {
            child.args(["--buoys", &buoys.to_string()]);
        }
        let output = child.output()?;
        row.peak_bytes = String::from_utf8_lossy(&output.stdout)
            .split_whitespace()
            .next()
            .and_then(|s| s.parse().ok());
        eprintln!(
            "{robots} robots: {:.1} steps/s ({} steps in {:.2} s)",
            row.steps_per_second(),
            row.steps,
            row.seconds
        );
        rows.push(row);
    }
    crate::bench_swarm::print_table(
        &rows,
        threads,
        args.ir_only,
        (
            (args.crowd_distance > 0.0).then_some(args.crowd_distance),
            (args.far_distance > 0.0).then_some(args.far_distance),
            (args.keep_distance > 0.0).then_some(args.keep_distance),
        ),
    );
    if let Some((slope, from, to)) = crate::bench_swarm::fitted_exponent(&rows) {
        println!("fitted exponent {from}→{to}: cost per step ∝ N^{slope:.2}");
    }
    let (csv, png) = crate::bench_swarm::write_outputs(&args.out, &rows, threads, args.ir_only)?;
    println!("wrote {} and {}", csv.display(), png.display());
    Ok(Outcome::Clean)
}

/// The world as written, and its variants.
fn world_configurations(args: Args) -> anyhow::Result<Outcome> {
    if args.memory_child {
        let compiled = load(&args.world)?;
        let mut simulation = Simulation::new(&compiled, None)?;
        simulation.run(20_000);
        let peak = crate::memory::peak_resident_bytes().unwrap_or(0);
        println!("{peak}");
        return Ok(Outcome::Clean);
    }
    let compiled = load(&args.world)?;
    if compiled.rig.robots.is_empty() {
        bail!("{} has no robot to step", args.world.display());
    }
    let time_step = compiled.settings.time_step;
    let report = |name: &str, rate: f64| {
        println!(
            "{name:<44} {rate:>12.0} steps/s {:>10.0}× real time",
            rate * time_step
        );
    };
    println!(
        "step bench: {}, {} ms steps",
        args.world.display(),
        time_step * 1000.0
    );
    if let Some(backend) = crate::vision::backend(args.renderer, &compiled, &args.world)? {
        let describe = backend.describe();
        let mut simulation = Simulation::new(&compiled, None)?;
        simulation.set_vision_backend(backend);
        simulation.run(10);
        let started = Instant::now();
        let mut steps = 0u64;
        while steps < 20 || started.elapsed() < std::time::Duration::from_millis(args.millis) {
            simulation.run(10);
            steps += 10;
        }
        if let Some(error) = &simulation.vision_error {
            bail!("{error}");
        }
        report(
            "as written, vision on wgpu (paper optics)",
            steps as f64 / started.elapsed().as_secs_f64(),
        );
        println!("(vision rendered by {describe}; the configurations below use the CPU)");
    }
    let full = steps_per_second(&compiled, args.millis, false)?;
    report("as written (IR and vision every step)", full);
    report(
        "as written, every sensor (ambient too)",
        steps_per_second(&compiled, args.millis, true)?,
    );
    // The same with every message logged (into memory: the cost of recording, not of a disk).
    {
        let mut simulation = Simulation::new(&compiled, None)?;
        let run = regatta_runtime::log::RunInfo {
            world_name: args.world.display().to_string(),
            world_text: text_of(&args.world)?,
            seed: simulation.seed,
            lenient: false,
            steps_requested: 0,
            channels: regatta_runtime::log::Channels::ALL,
            controllers: Vec::new(),
            variations: None,
        };
        let mut sink = std::io::Cursor::new(Vec::new());
        let mut recorder = regatta_runtime::log::Recorder::new(&mut sink, &mut simulation, &run)?;
        let started = Instant::now();
        let budget = std::time::Duration::from_millis(args.millis);
        let mut steps = 0u64;
        while started.elapsed() < budget {
            for _ in 0..500 {
                simulation.step();
                recorder.record(&simulation)?;
            }
            steps += 500;
        }
        let rate = steps as f64 / started.elapsed().as_secs_f64();
        recorder.finish(&simulation, false)?;
        report("as written, logging every message", rate);
        let per_minute = sink.get_ref().len() as f64 / simulation.time * 60.0;
        println!(
            "{:<44} {:>12.1} MB per simulated minute ({:.1} MB for 10 minutes)",
            "log size",
            per_minute / 1e6,
            per_minute * 10.0 / 1e6
        );
    }
    // IR only: the same world with the turrets taken off.
    let mut ir_only = compiled.clone();
    for robot in &mut ir_only.rig.robots {
        robot.turret = None;
    }
    ir_only.plan = Plan::new(&ir_only.graph, &ir_only.rig);
    report(
        "IR only (turret taken off)",
        steps_per_second(&ir_only, args.millis, false)?,
    );
    // Ten robots: the world's robot repeated on a grid inside the world's region.
    let text = std::fs::read_to_string(&args.world)
        .with_context(|| format!("cannot read {}", args.world.display()))?;
    let mut crowd = text.clone();
    for i in 0..9 {
        let (x, z) = (
            -0.35 + 0.35 * (i % 3) as f64,
            -0.42 + 0.16 * (i / 3) as f64 + if i >= 3 { 0.34 } else { 0.0 },
        );
        crowd.push_str(&format!(
            "Khepera {{ translation {x:.3} 0 {z:.3} rotation 0 1 0 {:.2} name \"k{i}\" controller \"regatta\" turret PanoramicTurret {{ lambda 5 }} }}\n",
            i as f64 * 0.7
        ));
    }
    let directory = std::env::temp_dir().join(format!("regatta-bench-{}", std::process::id()));
    std::fs::create_dir_all(&directory)?;
    let crowd_path = directory.join("ten.wbt");
    std::fs::write(&crowd_path, crowd)?;
    let ten = load(&crowd_path);
    std::fs::remove_dir_all(&directory).ok();
    let ten = ten?;
    let rate = steps_per_second(&ten, args.millis, false)?;
    report(&format!("{} robots", ten.rig.robots.len()), rate);
    // Independent worlds in parallel (an evolutionary run's population).
    let threads = rayon::current_num_threads();
    let worlds = 2 * threads;
    let started = Instant::now();
    let steps: u64 = (0..worlds)
        .into_par_iter()
        .map(|seed| {
            let mut simulation =
                Simulation::new(&compiled, Some(seed as u64)).expect("the world runs");
            let budget = std::time::Duration::from_millis(args.millis);
            let begun = Instant::now();
            let mut steps = 0;
            while begun.elapsed() < budget {
                simulation.run(500);
                steps += 500;
            }
            steps
        })
        .sum();
    report(
        &format!("{worlds} worlds in parallel on {threads} threads (total)"),
        steps as f64 / started.elapsed().as_secs_f64(),
    );
    // Peak memory of a one-robot run, in a fresh process.
    let exe = std::env::current_exe()?;
    let output = std::process::Command::new(exe)
        .args(["bench", "step", "--memory-child"])
        .arg(&args.world)
        .output()?;
    let peak: f64 = String::from_utf8_lossy(&output.stdout)
        .trim()
        .parse()
        .unwrap_or(0.0);
    println!(
        "{:<44} {:>12.1} MB (VmHWM, 20000 steps)",
        "peak memory of a one-robot run",
        peak / 1e6
    );
    Ok(Outcome::Clean)
}
