//! `regatta bench crowd`: run time against error for the crowd level of detail.
//!
//! On the generated swarms of `bench step --robots` (10 robots/m², N/10 buoys), every sampled
//! robot's retina is rendered from the same shared frame with every robot drawn (the
//! reference, `crowdDistance 0`) and with each crowd distance; the 6-bit outputs (odd filter)
//! and the photocurrents are compared. Frames: the start, and the crowd after the IR-only
//! Braitenberg avoider has scattered it for a few seconds (robots anywhere, headings any).
//! `--behaviour` also runs whole swarms with the regatta controller under both settings and
//! compares buoy visits per robot per minute over several seeds.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use regatta_runtime::compile::rig::{Pose2, TurretRig};
use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput, ViewOf};
use regatta_runtime::render::Poses;
use regatta_runtime::sim::Simulation;
use regatta_runtime::Compiled;

use crate::bench_swarm::{compile_text, swarm_world, SwarmSpec};
use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// Swarm sizes.
    #[arg(long, value_delimiter = ',', default_values_t = [10usize, 100, 1000])]
    robots: Vec<usize>,
    /// Crowd distances to measure (m).
    #[arg(long, value_delimiter = ',', default_values_t = [0.25f64, 0.5, 1.0])]
    distances: Vec<f64>,
    /// Far distances (m): each crowd distance is measured without one and with each of these
    /// (`crowdFarDistance`: buoys farther are left out, not drawn as impostors).
    #[arg(long, value_delimiter = ',')]
    far_distances: Vec<f64>,
    /// Keep distances (m): each crowd and far distance is also measured with impostors kept
    /// (`crowdKeepDistance`), each retina's kept ones worked out with the eye up to this far
    /// away (a seeded offset and turn) and then drawn where the eye is.
    #[arg(long, value_delimiter = ',')]
    keep_distances: Vec<f64>,
    /// Robots whose retina is compared per frame (spread evenly over the swarm).
    #[arg(long, default_value_t = 40)]
    viewers: usize,
    /// Frames compared: the start, then one every `--spacing` seconds of the IR-only swarm.
    #[arg(long, default_value_t = 3)]
    frames: usize,
    /// Seconds between frames.
    #[arg(long, default_value_t = 4.0)]
    spacing: f64,
    /// Times each retina is rendered; the fastest counts (the machine is shared).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Seed of the placements.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also compare behaviour: buoy visits per robot per minute of swarms of this size with
    /// the regatta controller, exact against each crowd distance, over `--seeds` seeds.
    #[arg(long, value_name = "ROBOTS")]
    behaviour: Option<usize>,
    /// The behaviour comparison's reference: this crowd distance (m), no far distance,
    /// instead of exact (which a thousand robots cannot run for a minute in reasonable time).
    #[arg(long, value_name = "METRES")]
    behaviour_reference: Option<f64>,
    /// Seeds (placements and noise) of the behaviour comparison.
    #[arg(long, default_value_t = 5)]
    seeds: u64,
    /// Simulated seconds per behaviour run.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Directory for crowd.csv and the chart (crowd.png or crowd.svg).
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
    /// File format of the chart.
    #[arg(long, value_enum, default_value_t)]
    format: crate::plot::FigureFormat,
}

/// A crowd level of detail: the crowd distance, the far distance (`None`: impostors however
/// far) and the keep distance (`None`: impostors worked out on every update).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Lod {
    crowd: f64,
    far: Option<f64>,
    keep: Option<f64>,
}

/// A level of detail: `None`, the reference (every robot and buoy drawn exactly).
type Setting = Option<Lod>;

/// The settings measured: the reference, then each crowd distance without a far distance
/// and with each far distance, each also with each keep distance.
fn settings(args: &Args) -> Vec<Setting> {
    let mut out = vec![None];
    for &crowd in &args.distances {
        let fars = std::iter::once(None).chain(args.far_distances.iter().map(|&f| Some(f)));
        for far in fars {
            let keeps = std::iter::once(None).chain(args.keep_distances.iter().map(|&k| Some(k)));
            out.extend(keeps.map(|keep| Some(Lod { crowd, far, keep })));
        }
    }
    out
}

/// How a setting reads in the table.
fn label(setting: Setting) -> String {
    match setting {
        None => "exact".to_owned(),
        Some(Lod { crowd, far, keep }) => {
            format!("{crowd} m")
                + &far.map_or(String::new(), |f| format!(", far {f} m"))
                + &keep.map_or(String::new(), |k| format!(", keep {k} m"))
        }
    }
}

/// One swarm size at one setting.
struct Row {
    robots: usize,
    distance: Setting,
    micros_per_retina: f64,
    outputs: usize,
    lsb_mean: f64,
    beyond_one_lsb: f64,
    lsb_max: u32,
    analog_mean: f64,
    analog_max: f64,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    if args.robots.is_empty() || args.robots.contains(&0) {
        bail!("--robots: give sizes of at least 1");
    }
    if let Some(bad) = args
        .distances
        .iter()
        .find(|d| !(d.is_finite() && **d > 0.0))
    {
        bail!("--distances: {bad} is not a distance above 0 m");
    }
    if let Some(bad) = args
        .far_distances
        .iter()
        .chain(&args.keep_distances)
        .chain(&args.behaviour_reference)
        .find(|d| !(d.is_finite() && **d > 0.0))
    {
        bail!("--far-distances, --keep-distances, --behaviour-reference: {bad} is not a distance above 0 m");
    }
    if args.viewers == 0 || args.frames == 0 {
        bail!("--viewers and --frames must be at least 1");
    }
    if !(args.spacing.is_finite() && args.spacing > 0.0) {
        bail!("--spacing must be a time above 0 s");
    }
    println!(
        "crowd bench: generated swarms (10 robots/m², N/10 buoys, seed {}), {} frames {} s apart, up to {} retinas per frame, odd filter, 6 bits, single thread, fastest of {} renders",
        args.seed, args.frames, args.spacing, args.viewers, args.repeats.max(1)
    );
    println!(
        "{:>6} {:>30} {:>12} {:>16} {:>10} {:>10} {:>8} {:>12} {:>12}",
        "robots",
        "distance",
        "µs/retina",
        "vision ms/step",
        "LSB mean",
        ">1 LSB %",
        "LSB max",
        "analog mean",
        "analog max"
    );
    let mut rows = Vec::new();
    for &robots in &args.robots {
        for row in measure(robots, &args)? {
            println!(
                "{:>6} {:>30} {:>12.2} {:>16.3} {:>10.4} {:>10.3} {:>8} {:>12.2e} {:>12.2e}",
                row.robots,
                label(row.distance),
                row.micros_per_retina,
                row.micros_per_retina * robots as f64 / 1000.0,
                row.lsb_mean,
                100.0 * row.beyond_one_lsb,
                row.lsb_max,
                row.analog_mean,
                row.analog_max
            );
            rows.push(row);
        }
    }
    let mut csv = String::from("robots,crowd_distance_m,far_distance_m,keep_distance_m,micros_per_retina,outputs_compared,digital_lsb_error_mean,share_beyond_1_lsb,digital_lsb_error_max,analog_rel_error_mean,analog_rel_error_max\n");
    for row in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{:.3},{},{:.6},{:.6},{},{:.6e},{:.6e}",
            row.robots,
            row.distance
                .map_or("exact".to_owned(), |lod| lod.crowd.to_string()),
            row.distance
                .and_then(|lod| lod.far)
                .map_or(String::new(), |f| f.to_string()),
            row.distance
                .and_then(|lod| lod.keep)
                .map_or(String::new(), |k| k.to_string()),
            row.micros_per_retina,
            row.outputs,
            row.lsb_mean,
            row.beyond_one_lsb,
            row.lsb_max,
            row.analog_mean,
            row.analog_max
        );
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join("crowd.csv");
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    println!("{}", csv_path.display());
    crate::plot::save(&chart(&rows), &args.out, "crowd", args.format)?;
    if let Some(robots) = args.behaviour {
        behaviour(robots, &args)?;
    }
    Ok(Outcome::Clean)
}

/// The swarm's frames: the start, then the IR-only swarm every `spacing` seconds.
fn frames(robots: usize, args: &Args) -> anyhow::Result<Vec<Poses>> {
    let spec = SwarmSpec {
        robots,
        buoys: None,
        ir_only: true,
        seed: args.seed,
        crowd_distance: None,
        far_distance: None,
        keep_distance: None,
    };
    let compiled = compile_text("swarm-ir.wbt", swarm_world(&spec))?;
    let mut simulation = Simulation::new(&compiled, Some(args.seed))?;
    let floor_y: Vec<f64> = compiled.rig.robots.iter().map(|r| r.floor_y).collect();
    let poses_now = |simulation: &Simulation| Poses {
        poses: simulation.robots.iter().map(|r| r.pose).collect(),
        floor_y: floor_y.clone(),
    };
    let mut out = vec![poses_now(&simulation)];
    let steps = (args.spacing / simulation.time_step).ceil() as u64;
    while out.len() < args.frames {
        simulation.run(steps);
        out.push(poses_now(&simulation));
    }
    Ok(out)
}

fn measure(robots: usize, args: &Args) -> anyhow::Result<Vec<Row>> {
    let spec = SwarmSpec {
        robots,
        buoys: None,
        ir_only: false,
        seed: args.seed,
        crowd_distance: None,
        far_distance: None,
        keep_distance: None,
    };
    let compiled = compile_text("swarm.wbt", swarm_world(&spec))?;
    let frames = frames(robots, args)?;
    let viewers: Vec<usize> = {
        let count = args.viewers.min(robots);
        let mut picked: Vec<usize> = (0..count).map(|i| i * robots / count).collect();
        picked.dedup();
        picked
    };
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, false);
    let settings = settings(args);
    let mut offsets = Unit(args.seed ^ 0x4b45_4550);
    // outputs[setting][frame × viewer]
    let mut outputs: Vec<Vec<RetinaOutput>> = vec![Vec::new(); settings.len()];
    let mut seconds = vec![0.0f64; settings.len()];
    for poses in &frames {
        let mut shared = None;
        renderer.prepare_shared(&compiled.plan, poses, &[], false, &mut shared);
        let frame = shared.context("exact optics on a swarm render by columns")?;
        for &viewer in &viewers {
            let Some(TurretRig::Panoramic(turret)) = &compiled.rig.robots[viewer].turret else {
                bail!("robot {viewer} of the swarm has no Panoramic turret");
            };
            let pose: Pose2 = poses.poses[viewer];
            let floor = compiled.rig.robots[viewer].floor_y;
            for (slot, setting) in settings.iter().enumerate() {
                let mut rig = turret.clone();
                rig.crowd_distance = setting.map_or(f64::INFINITY, |lod| lod.crowd);
                rig.far_distance = setting.and_then(|lod| lod.far).unwrap_or(f64::INFINITY);
                let keep = setting.and_then(|lod| lod.keep);
                rig.keep_distance = keep.unwrap_or(0.0);
                let mut retina = Panoramic::new(&rig);
                let mut out = RetinaOutput::default();
                let view = ViewOf::Columns(&frame, Some(viewer));
                if let Some(keep) = keep {
                    // The kept impostors worked out where the eye was up to `keep` ago.
                    let then = moved_within(pose, keep, &mut offsets);
                    retina.update_of(&renderer, view, then, floor, &mut out);
                }
                let mut fastest = f64::INFINITY;
                for _ in 0..args.repeats.max(1) {
                    let started = Instant::now();
                    retina.update_of(&renderer, view, pose, floor, &mut out);
                    fastest = fastest.min(started.elapsed().as_secs_f64());
                }
                seconds[slot] += fastest;
                outputs[slot].push(out);
            }
        }
    }
    let retinas = (frames.len() * viewers.len()) as f64;
    Ok(settings
        .iter()
        .enumerate()
        .map(|(slot, &distance)| {
            let errors = compare(&outputs[slot], &outputs[0]);
            Row {
                robots,
                distance,
                micros_per_retina: seconds[slot] / retinas * 1e6,
                outputs: errors.outputs,
                lsb_mean: errors.lsb_mean,
                beyond_one_lsb: errors.beyond_one,
                lsb_max: errors.lsb_max,
                analog_mean: errors.analog_mean,
                analog_max: errors.analog_max,
            }
        })
        .collect())
}

/// A uniform stream in [0, 1) (SplitMix64), for the kept impostors' offsets.
struct Unit(u64);

impl Unit {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Where an eye now at `pose` was when its impostors were worked out: up to `keep` away in
/// any direction (uniform over the disc, just inside it), turned by up to a radian either way.
fn moved_within(pose: Pose2, keep: f64, unit: &mut Unit) -> Pose2 {
    let radius = 0.999 * keep * unit.next().sqrt();
    let angle = std::f64::consts::TAU * unit.next();
    Pose2 {
        x: pose.x + radius * libm::cos(angle),
        z: pose.z + radius * libm::sin(angle),
        heading: pose.heading + 2.0 * unit.next() - 1.0,
    }
}

struct Errors {
    outputs: usize,
    lsb_mean: f64,
    beyond_one: f64,
    lsb_max: u32,
    analog_mean: f64,
    analog_max: f64,
}

/// Digital error in LSB over every enabled output, and the photocurrents' relative error.
fn compare(results: &[RetinaOutput], reference: &[RetinaOutput]) -> Errors {
    let (mut lsb_sum, mut beyond, mut lsb_max, mut outputs) = (0u64, 0usize, 0u32, 0usize);
    let (mut analog_sum, mut analog_max, mut analog_count) = (0.0, 0.0f64, 0usize);
    for (result, reference) in results.iter().zip(reference) {
        for ((_, d), (_, e)) in result.digital.iter().zip(&reference.digital) {
            for (x, y) in d.iter().zip(e) {
                let error = (*x as i32 - *y as i32).unsigned_abs();
                lsb_sum += error as u64;
                beyond += (error > 1) as usize;
                lsb_max = lsb_max.max(error);
                outputs += 1;
            }
        }
        for (a, r) in result.luminance.iter().zip(&reference.luminance) {
            let error = (a - r).abs() / r.abs().max(1e-3);
            analog_sum += error;
            analog_max = analog_max.max(error);
            analog_count += 1;
        }
    }
    Errors {
        outputs,
        lsb_mean: lsb_sum as f64 / outputs.max(1) as f64,
        beyond_one: beyond as f64 / outputs.max(1) as f64,
        lsb_max,
        analog_mean: analog_sum / analog_count.max(1) as f64,
        analog_max,
    }
}

/// Buoy visits per robot per minute, the reference (exact, or `--behaviour-reference`)
/// against each setting, over seeds.
fn behaviour(robots: usize, args: &Args) -> anyhow::Result<()> {
    println!(
        "behaviour: {robots} robots, regatta controller, {} s, seeds 1…{}",
        args.seconds, args.seeds
    );
    let reference: Setting = args.behaviour_reference.map(|crowd| Lod {
        crowd,
        far: None,
        keep: None,
    });
    let mut compared = vec![reference];
    compared.extend(
        settings(args)
            .into_iter()
            .skip(1)
            .filter(|&s| s != reference),
    );
    println!(
        "{:>18} {:>28} {:>12}",
        "distance", "visits/robot/min per seed", "mean"
    );
    let mut reference_mean = None;
    for setting in compared {
        let mut rates = Vec::new();
        for seed in 1..=args.seeds {
            let spec = SwarmSpec {
                robots,
                buoys: None,
                ir_only: false,
                seed,
                crowd_distance: setting.map(|lod| lod.crowd),
                far_distance: setting.and_then(|lod| lod.far),
                keep_distance: setting.and_then(|lod| lod.keep),
            };
            let compiled: Compiled = compile_text("swarm.wbt", swarm_world(&spec))?;
            let mut simulation = Simulation::new(&compiled, Some(seed))?;
            let steps = (args.seconds / simulation.time_step).round() as u64;
            simulation.run(steps);
            let visits: u64 = simulation
                .robots
                .iter()
                .map(|r| r.visits.sequence.len() as u64)
                .sum();
            rates.push(visits as f64 / robots as f64 / (simulation.time / 60.0));
        }
        let mean = rates.iter().sum::<f64>() / rates.len().max(1) as f64;
        let relative = reference_mean.map_or(String::new(), |e: f64| {
            format!(
                " ({:+.1} % of {})",
                100.0 * (mean - e) / e.max(1e-12),
                label(reference)
            )
        });
        if reference_mean.is_none() {
            reference_mean = Some(mean);
        }
        println!(
            "{:>18} {:>28} {:>12.3}{relative}",
            label(setting),
            rates
                .iter()
                .map(|r| format!("{r:.2}"))
                .collect::<Vec<_>>()
                .join(" "),
            mean
        );
    }
    Ok(())
}

/// Time per retina against mean error, one series per swarm size, log axes.
fn chart(rows: &[Row]) -> regatta_figures::Chart {
    use regatta_figures::{Axis, Chart, Corner, Series};
    let floor = 1e-4;
    let mut chart = Chart::new(
        "crowd level of detail: time per retina against error",
        Axis::log("time per retina update (µs)"),
        Axis::log("mean digital error (LSB; exact drawn at 0.0001)"),
    )
    .legend(Corner::UpperRight);
    // One series per swarm size, far distance and keep distance (the reference in each).
    let bits = |v: Option<f64>| v.map(f64::to_bits);
    let key = |r: &Row| {
        r.distance
            .map(|lod| (bits(lod.far), bits(lod.keep)))
            .unwrap_or((None, None))
    };
    // (robots, the far and keep distances' bits, the setting naming the series)
    type SeriesKey = (Option<u64>, Option<u64>);
    let mut series: Vec<(usize, SeriesKey, Lod)> = Vec::new();
    for row in rows {
        let Some(lod) = row.distance else { continue };
        if !series.iter().any(|s| s.0 == row.robots && s.1 == key(row)) {
            series.push((row.robots, key(row), lod));
        }
    }
    for (robots, wanted, lod) in series {
        let mut points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.robots == robots && (r.distance.is_none() || key(r) == wanted))
            .map(|r| (r.micros_per_retina, r.lsb_mean.max(floor)))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let name = format!("{robots} robots")
            + &lod.far.map_or(String::new(), |f| format!(", far {f} m"))
            + &lod.keep.map_or(String::new(), |k| format!(", keep {k} m"));
        chart = chart.with(Series::line_markers(name, points));
    }
    chart
}
