//! `regatta bench controllers WORLD`: a world whose robots run their project's controllers
//! (Webots controllers, each a process of its own) beside the same world with the built-in
//! `braitenberg`, in one sitting, runs alternated so that the machine's drift hits both
//! alike. Each run is `regatta run` in a child process; its steps per second come from its own
//! summary, the peak memory from the operating system's accounting of the largest process
//! (the simulator or a controller).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{bail, Context};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world, in a Webots project whose controllers/ its robots name.
    world: PathBuf,
    /// Simulated time of each run (s).
    #[arg(long, default_value_t = 600.0)]
    duration: f64,
    /// Runs of each; the median is reported.
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// The built-in controller to compare with.
    #[arg(long, default_value = "braitenberg")]
    builtin: String,
}

/// What one run printed of its speed.
struct Run {
    steps_per_second: f64,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if !(args.duration > 0.0 && args.duration.is_finite()) {
        bail!("--duration must be a positive number of seconds");
    }
    let me = std::env::current_exe().context("cannot find regatta's own executable")?;
    let duration = args.duration.to_string();
    let programs: Vec<String> = vec!["run".into(), "--duration".into(), duration.clone()];
    let builtin: Vec<String> = vec![
        "run".into(),
        "--duration".into(),
        duration,
        "--builtin-only".into(),
        "--controller".into(),
        args.builtin.clone(),
    ];
    // One warm-up each (the first compiles the controllers into the cache).
    one(&me, &programs, &args.world)?;
    one(&me, &builtin, &args.world)?;
    let (mut with_programs, mut with_builtin) = (Vec::new(), Vec::new());
    for _ in 0..args.runs {
        with_programs.push(one(&me, &programs, &args.world)?.steps_per_second);
        with_builtin.push(one(&me, &builtin, &args.world)?.steps_per_second);
    }
    let peak = largest_child_peak_kib();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (p, b) = (median(&mut with_programs), median(&mut with_builtin));
    println!(
        "world {}: {} simulated s a run, {} runs each, median",
        args.world.display(),
        args.duration,
        args.runs
    );
    println!("  project's controllers    {p:>12.0} steps/s");
    println!("  built-in {:<15} {b:>12.0} steps/s", args.builtin);
    println!("  ratio                    {:>12.3}", p / b);
    if let Some(kib) = peak {
        println!(
            "  peak memory of the largest process (simulator or controller): {:.1} MB",
            kib as f64 / 1024.0
        );
    }
    Ok(Outcome::Clean)
}

fn one(me: &Path, args: &[String], world: &Path) -> anyhow::Result<Run> {
    let output = Command::new(me)
        .args(args)
        .arg(world)
        .stdin(Stdio::null())
        .output()
        .context("cannot start regatta run")?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        bail!(
            "regatta run {} failed:\n{}",
            world.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let steps_per_second = stdout
        .lines()
        .find_map(|line| {
            let rest = line.strip_prefix("wall time ")?;
            let (_, speed) = rest.split_once(": ")?;
            speed.split_whitespace().next()?.parse::<f64>().ok()
        })
        .context("the run printed no speed")?;
    Ok(Run { steps_per_second })
}

/// The largest peak resident set of any child process so far (KiB), from getrusage.
fn largest_child_peak_kib() -> Option<i64> {
    // SAFETY: getrusage fills the struct it is given and reads nothing else.
    unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        (libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) == 0).then_some(usage.ru_maxrss)
    }
}
