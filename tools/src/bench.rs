//! `regatta bench`: benchmarks that report figures (speed is measured here, never in tests).
//!
//! `bench parse` generates a mesh-heavy world (one IndexedFaceSet with millions of points),
//! writes it to a temporary file and parses it in a child process, so that the peak resident
//! memory it reports belongs to reading and parsing alone.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(clap::Subcommand)]
enum What {
    /// Retina update time against error, for paper and exact optics at several densities,
    /// against a converged reference. Prints a table; writes CSV and a PNG plot.
    Retina(crate::bench_retina::Args),
    /// The crowd level of detail on generated swarms: time per retina against error
    /// (6-bit outputs and photocurrents) for each crowd distance, against every robot drawn;
    /// `--behaviour N` compares buoy visits too. Prints a table; writes CSV and a chart.
    Crowd(crate::bench_crowd::Args),
    /// Simulation steps per second: the regatta world, IR only, 10 robots, parallel worlds,
    /// and the peak memory of a one-robot run.
    Step(crate::bench_step::Args),
    /// Accuracy against cost of the physics step: the world at a ladder of basicTimeSteps,
    /// control and sensor periods fixed; pose divergence, sensor error and buoy visits
    /// against the finest step, the observed order; a table, CSV and a chart.
    Accuracy(crate::bench_accuracy::Args),
    /// Webots worlds: JavaScript templates against arithmetic ones, and the e-puck's camera.
    Webots(crate::bench_webots::Args),
    /// A world's project controllers (Webots controllers, processes of their own) beside the
    /// built-in braitenberg: steps per second and peak memory.
    Controllers(crate::bench_controllers::Args),
    /// glTF export time on a generated world of about a million triangles.
    Gltf {
        /// Points in the generated IndexedFaceSet (709² gives 1,002,528 triangles).
        #[arg(long, default_value_t = 709 * 709)]
        points: usize,
        /// Timed exports; the best is reported.
        #[arg(long, default_value_t = 5)]
        runs: usize,
    },
    /// Parser throughput (MB/s) and peak memory (× file size) on a generated mesh world.
    Parse {
        /// Points in the generated IndexedFaceSet.
        #[arg(long, default_value_t = 2_000_000)]
        points: usize,
        /// Timed parses; the best is reported.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Parse this file instead of a generated one (used by the child process).
        #[arg(long, hide = true)]
        child: Option<PathBuf>,
    },
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    match args.what {
        What::Retina(args) => crate::bench_retina::run(args),
        What::Crowd(args) => crate::bench_crowd::run(args),
        What::Step(args) => crate::bench_step::run(args),
        What::Webots(args) => crate::bench_webots::run(args),
        What::Controllers(args) => crate::bench_controllers::run(args),
        What::Accuracy(args) => crate::bench_accuracy::run(args),
        What::Gltf { points, runs } => gltf(points, runs),
        What::Parse {
            points,
            runs,
            child: Some(path),
        } => {
            let _ = points;
            parse_child(&path, runs)
        }
        What::Parse {
            points,
            runs,
            child: None,
        } => parse_parent(points, runs),
    }
}

fn parse_parent(points: usize, runs: usize) -> anyhow::Result<Outcome> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let dir = std::env::temp_dir().join(format!("regatta-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join("mesh.wbt");
    let world = regatta_parser::testgen::mesh_world(points);
    std::fs::write(&path, &world).with_context(|| format!("cannot write {}", path.display()))?;
    let size = world.len();
    drop(world);
    let exe = std::env::current_exe().context("cannot find the regatta executable")?;
    let output = std::process::Command::new(exe)
        .args(["bench", "parse", "--runs", &runs.to_string(), "--child"])
        .arg(&path)
        .output()
        .context("cannot run the measuring child process")?;
    std::fs::remove_dir_all(&dir).ok();
    if !output.status.success() {
        bail!(
            "the measuring process failed: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let report = String::from_utf8_lossy(&output.stdout);
    println!("mesh world: {points} points, {:.1} MB", size as f64 / 1e6);
    print!("{report}");
    Ok(Outcome::Clean)
}

fn parse_child(path: &std::path::Path, runs: usize) -> anyhow::Result<Outcome> {
    let size = std::fs::metadata(path)?.len() as f64;
    let mut best = f64::INFINITY;
    let mut diagnostics = 0;
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        let source = regatta_parser::SourceText::read(path)?;
        let parsed = regatta_parser::parse(&source.text);
        let seconds = start.elapsed().as_secs_f64();
        diagnostics = parsed.diagnostics.len();
        best = best.min(seconds);
        drop(parsed);
        drop(source);
    }
    let peak = crate::memory::peak_resident_bytes().unwrap_or(0) as f64;
    println!(
        "read + parse: best of {runs}: {:.3} s, {:.0} MB/s",
        best,
        size / best / 1e6
    );
    println!(
        "peak resident memory: {:.1} MB = {:.2} × the file size",
        peak / 1e6,
        peak / size
    );
    println!("diagnostics: {diagnostics}");
    Ok(Outcome::Clean)
}

fn gltf(points: usize, runs: usize) -> anyhow::Result<Outcome> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let world = regatta_parser::testgen::mesh_world(points);
    let started = Instant::now();
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("mesh.wbt".into(), world.into_bytes()),
        &regatta_schema::Options::default(),
    );
    if checked.has_errors() {
        bail!("the generated world does not check");
    }
    let compiled = regatta_runtime::compile(&checked.scene);
    let load = started.elapsed();
    let options = regatta_gltf::Options::default();
    let mut best_export = f64::INFINITY;
    let mut best_glb = f64::INFINITY;
    let mut document = None;
    for _ in 0..runs {
        let started = Instant::now();
        let exported = regatta_gltf::export(&compiled, &options, &[])?;
        let exported_at = started.elapsed().as_secs_f64();
        let glb = exported.to_glb();
        let total = started.elapsed().as_secs_f64();
        best_export = best_export.min(exported_at);
        best_glb = best_glb.min(total);
        document = Some((exported.triangle_count, exported.node_count, glb.len()));
    }
    let (triangles, nodes, bytes) = document.expect("runs ≥ 1");
    println!("glTF export of a generated mesh world ({points} points), best of {runs}:");
    println!("  triangles            {triangles}");
    println!("  nodes                {nodes}");
    println!("  export               {:.3} s", best_export);
    println!(
        "  export + GLB bytes   {:.3} s ({:.1} MB)",
        best_glb,
        bytes as f64 / 1e6
    );
    println!(
        "  (parse, check and compile before it: {:.3} s)",
        load.as_secs_f64()
    );
    Ok(Outcome::Clean)
}
