//! `regatta bench controllers WORLD [WORLD…]`: worlds whose robots run their project's
//! controllers (Webots controllers in C or Python, each a process of its own) beside the first
//! world with the built-in `braitenberg`, in one sitting, runs alternated so that the
//! machine's drift hits all alike (the same world with its controller in C and in Python
//! compares the languages). Each run is `regatta run` in a child process; its steps per second come from its own
//! summary, the peak memory from the operating system's accounting of the largest process
//! (the simulator or a controller).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{bail, Context};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The worlds, each in a Webots project whose controllers/ its robots name.
    #[arg(required = true)]
    worlds: Vec<PathBuf>,
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

/// What one run printed of its speed, and its peak memory (KiB, the largest of the
/// simulator and its controllers).
struct Run {
    steps_per_second: f64,
    peak_kib: i64,
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
    let first = &args.worlds[0];
    // One warm-up each (the first compiles the controllers into the cache).
    for world in &args.worlds {
        one(&me, &programs, world)?;
    }
    one(&me, &builtin, first)?;
    let mut speeds = vec![Vec::new(); args.worlds.len() + 1];
    let mut peaks = vec![0; args.worlds.len() + 1];
    for _ in 0..args.runs {
        for (i, world) in args.worlds.iter().enumerate() {
            let run = one(&me, &programs, world)?;
            speeds[i].push(run.steps_per_second);
            peaks[i] = peaks[i].max(run.peak_kib);
        }
        let run = one(&me, &builtin, first)?;
        speeds[args.worlds.len()].push(run.steps_per_second);
        peaks[args.worlds.len()] = peaks[args.worlds.len()].max(run.peak_kib);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let medians: Vec<f64> = speeds.iter_mut().map(median).collect();
    let b = medians[args.worlds.len()];
    println!(
        "{} simulated s a run, {} runs each, median steps/s; peak memory of a run's largest process",
        args.duration, args.runs
    );
    let labels: Vec<String> = args
        .worlds
        .iter()
        .map(|w| format!("{} (its controllers)", w.display()))
        .chain([format!("{} (built-in {})", first.display(), args.builtin)])
        .collect();
    let width = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    for (i, label) in labels.iter().enumerate() {
        println!(
            "  {label:<width$} {:>10.0} steps/s  {:>6.3}× the built-in  {:>6.1} MB",
            medians[i],
            medians[i] / b,
            peaks[i] as f64 / 1024.0
        );
    }
    Ok(Outcome::Clean)
}

fn one(me: &Path, args: &[String], world: &Path) -> anyhow::Result<Run> {
    use std::io::Read;
    let mut child = Command::new(me)
        .args(args)
        .arg(world)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .context("cannot start regatta run")?;
    let mut stdout = String::new();
    let mut stderr = String::new();
    if let Some(mut out) = child.stdout.take() {
        out.read_to_string(&mut stdout)?;
    }
    if let Some(mut err) = child.stderr.take() {
        err.read_to_string(&mut stderr)?;
    }
    let (status, peak_kib) = wait_with_peak(child.id() as i32)?;
    if status != 0 {
        bail!("regatta run {} failed:\n{stderr}", world.display());
    }
    let steps_per_second = stdout
        .lines()
        .find_map(|line| {
            let rest = line.strip_prefix("wall time ")?;
            let (_, speed) = rest.split_once(": ")?;
            speed.split_whitespace().next()?.parse::<f64>().ok()
        })
        .context("the run printed no speed")?;
    Ok(Run {
        steps_per_second,
        peak_kib,
    })
}

/// Waits for a child, returning its exit status and the peak resident set (KiB) of it and the
/// descendants it waited for, from the operating system's accounting (wait4).
fn wait_with_peak(pid: i32) -> anyhow::Result<(i32, i64)> {
    let mut status = 0;
    // SAFETY: wait4 fills the status and usage it is given; the child is ours and not yet
    // waited for (std's handle is dropped without waiting).
    let (done, usage) = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        let done = libc::wait4(pid, &mut status, 0, &mut usage);
        (done, usage)
    };
    if done != pid {
        bail!(
            "cannot wait for regatta run: {}",
            std::io::Error::last_os_error()
        );
    }
    let code = if libc::WIFEXITED(status) {
        libc::WEXITSTATUS(status)
    } else {
        -1
    };
    Ok((code, usage.ru_maxrss))
}
