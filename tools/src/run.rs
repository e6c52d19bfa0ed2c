//! `regatta run`: step a world and print a summary of the run.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
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
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let loaded = crate::world::load(&args.world, args.lenient, color)?;
    let compiled = &loaded.compiled;
    let mut simulation = Simulation::new(compiled, args.seed)
        .with_context(|| format!("cannot run {}", args.world.display()))?;
    let steps = match (args.steps, args.duration) {
        (Some(steps), _) => steps,
        (None, Some(duration)) => {
            if !(duration >= 0.0 && duration.is_finite()) {
                bail!("--duration must be a non-negative number of seconds, found {duration}");
            }
            libm_ceil(duration / simulation.time_step)
        }
        (None, None) => libm_ceil(60.0 / simulation.time_step),
    };
    let started = Instant::now();
    simulation.run(steps);
    let wall = started.elapsed().as_secs_f64();
    println!("world {}: seed {}", args.world.display(), simulation.seed);
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

fn libm_ceil(x: f64) -> u64 {
    x.ceil().max(0.0) as u64
}
