//! `regatta bench retina`: run time against error for the retina's optics.
//!
//! For a set of poses spread over the world (deterministic), every configuration renders the
//! first robot's Panoramic turret; its analog[] and digital[] are compared with a converged
//! reference: the column renderer at 64 evaluations per window piece when the scene is
//! upright (itself checked against 32×32 rays per photodiode), else 48×48 rays.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::{Optics, PanoramicRig, Pose2, TurretRig};
use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
use regatta_runtime::render::Poses;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world (its first robot with a Panoramic turret is measured).
    #[arg(default_value = "worlds/regatta.wbt")]
    world: PathBuf,
    /// Poses to average over.
    #[arg(long, default_value_t = 24)]
    poses: usize,
    /// Directory for retina.csv and the chart (retina.png or retina.svg).
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
    /// File format of the chart.
    #[arg(long, value_enum, default_value_t)]
    format: crate::plot::FigureFormat,
    /// Minimum time spent timing each configuration (ms).
    #[arg(long, default_value_t = 300)]
    millis: u64,
    /// `wgpu`: time per update for populations of 1, 10, 100 and 1000 robots, each in its own
    /// copy of the world, all rendered in one batch (paper optics), and their agreement with
    /// the CPU's paper optics.
    #[arg(long, value_enum, default_value_t)]
    renderer: crate::vision::RendererKind,
    /// Population sizes for `--renderer wgpu`.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 10, 100, 1000])]
    robots: Vec<usize>,
}

struct Row {
    name: String,
    optics: &'static str,
    renderer: &'static str,
    samples: usize,
    micros: f64,
    analog_mean: f64,
    analog_max: f64,
    lsb_mean: f64,
    lsb_max: u32,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let loaded = crate::world::load(&args.world, &Default::default(), false)?;
    let compiled = &loaded.compiled;
    let Some((robot, base)) =
        compiled
            .rig
            .robots
            .iter()
            .enumerate()
            .find_map(|(i, r)| match &r.turret {
                Some(TurretRig::Panoramic(p)) => Some((i, p.clone())),
                _ => None,
            })
    else {
        bail!(
            "{} has no robot with a Panoramic turret",
            args.world.display()
        );
    };
    if args.renderer == crate::vision::RendererKind::Wgpu {
        // Fails here, before any CPU work, in a build without the backend.
        drop(crate::vision::backend(
            args.renderer,
            compiled,
            &args.world,
        )?);
        let poses = spread_poses(
            compiled,
            robot,
            args.robots.iter().copied().max().unwrap_or(1),
        );
        let paper = PanoramicRig {
            optics: Optics::Paper,
            ..base.clone()
        };
        let mut paper_world = compiled.clone();
        if let Some(TurretRig::Panoramic(p)) = &mut paper_world.rig.robots[robot].turret {
            *p = paper.clone();
        }
        let agreement_poses = &poses[..poses.len().min(args.poses.max(1))];
        let cpu = outputs(&paper_world, robot, &paper, false, agreement_poses);
        return crate::vision::bench_population(
            &paper_world,
            robot,
            &poses,
            &cpu,
            &args.robots,
            args.millis,
            &args.out,
        );
    }
    let poses = spread_poses(compiled, robot, args.poses.max(1));
    let upright = compiled.plan.renderer == RendererChoice::Columns;
    // The reference.
    let reference_rig = PanoramicRig {
        optics: Optics::Exact,
        samples: if upright { 64 } else { 48 },
        stride: 1,
        ..base.clone()
    };
    let reference = outputs(compiled, robot, &reference_rig, !upright, &poses);
    let mut report = String::new();
    if upright {
        let rays = outputs(
            compiled,
            robot,
            &PanoramicRig {
                samples: 32,
                ..reference_rig.clone()
            },
            true,
            &poses,
        );
        let (mean, max, _, _) = errors(&rays, &reference);
        let _ = writeln!(report, "reference: columns, 64 evaluations per window piece; 32×32 rays per photodiode differ from it by {:.2e} mean, {:.2e} max (relative analog)", mean, max);
    } else {
        let _ = writeln!(
            report,
            "reference: 48×48 rays per photodiode (the scene is not all upright)"
        );
    }
    // (optics, samples, stride, rays)
    let mut configurations: Vec<(Optics, usize, usize, bool)> = Vec::new();
    if upright {
        for (samples, stride) in [
            (1, 16),
            (1, 12),
            (1, 8),
            (1, 6),
            (1, 4),
            (1, 3),
            (1, 2),
            (1, 1),
            (2, 1),
            (4, 1),
            (8, 1),
        ] {
            configurations.push((Optics::Exact, samples, stride, false));
        }
    }
    for samples in [1, 2, 4, 8] {
        configurations.push((Optics::Exact, samples, 1, true));
    }
    for samples in [1, 2, 4] {
        configurations.push((Optics::Paper, samples, 1, !upright));
    }
    let mut rows = Vec::new();
    for (optics, samples, stride, rays) in configurations {
        let rig = PanoramicRig {
            optics,
            samples,
            stride,
            ..base.clone()
        };
        let results = outputs(compiled, robot, &rig, rays, &poses);
        let (analog_mean, analog_max, lsb_mean, lsb_max) = errors(&results, &reference);
        let micros = time_per_update(compiled, robot, &rig, rays, &poses, args.millis);
        let optics_name = if optics == Optics::Exact {
            "exact"
        } else {
            "paper"
        };
        let renderer = if rays { "rays" } else { "columns" };
        let name = if optics == Optics::Exact && !rays {
            format!("{optics_name} {renderer} s={samples} stride={stride}")
        } else {
            format!("{optics_name} {renderer} s={samples}")
        };
        let default = optics == base.optics
            && samples == base.samples
            && (stride == base.stride || optics == Optics::Paper)
            && rays != upright;
        let name = if default { format!("{name} *") } else { name };
        rows.push(Row {
            name,
            optics: optics_name,
            renderer,
            samples,
            micros,
            analog_mean,
            analog_max,
            lsb_mean,
            lsb_max,
        });
    }
    let filters: Vec<&str> = base.filters.iter().map(|k| k.name()).collect();
    println!(
        "retina bench: {} , robot '{}', {} poses, filters [{}], {} bits, single thread",
        args.world.display(),
        compiled.rig.robots[robot].name,
        poses.len(),
        filters.join(", "),
        base.bits
    );
    print!("{report}");
    println!("(* marks the world's own setting)");
    println!(
        "{:<34} {:>12} {:>14} {:>14} {:>10} {:>10}",
        "configuration", "µs/update", "analog mean", "analog max", "LSB mean", "LSB max"
    );
    let mut csv = String::from("configuration,optics,renderer,samples,micros_per_update,analog_rel_error_mean,analog_rel_error_max,digital_lsb_error_mean,digital_lsb_error_max\n");
    for row in &rows {
        println!(
            "{:<34} {:>12.2} {:>14.2e} {:>14.2e} {:>10.3} {:>10}",
            row.name, row.micros, row.analog_mean, row.analog_max, row.lsb_mean, row.lsb_max
        );
        let _ = writeln!(
            csv,
            "{},{},{},{},{:.4},{:.6e},{:.6e},{:.6},{}",
            row.name,
            row.optics,
            row.renderer,
            row.samples,
            row.micros,
            row.analog_mean,
            row.analog_max,
            row.lsb_mean,
            row.lsb_max
        );
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join("retina.csv");
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    println!("{}", csv_path.display());
    let world = args.world.file_name().map_or_else(
        || args.world.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    crate::plot::save(&chart(&rows, &world), &args.out, "retina", args.format)?;
    Ok(Outcome::Clean)
}

/// Poses spread over the plan's region, away from walls and static cylinders.
pub(crate) fn spread_poses(
    compiled: &regatta_runtime::Compiled,
    robot: usize,
    count: usize,
) -> Vec<Pose2> {
    let region = compiled.plan.region;
    let margin = compiled.rig.robots[robot].body_radius + 0.05;
    let (x0, x1, z0, z1) = (
        region.min.x + margin,
        region.max.x - margin,
        region.min.z + margin,
        region.max.z - margin,
    );
    let mut state = 0x2545F4914F6CDD1Du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut poses = vec![compiled.rig.robots[robot].start];
    let mut tries = 0;
    while poses.len() < count && tries < count * 100 {
        tries += 1;
        let pose = Pose2 {
            x: x0 + (x1 - x0) * uniform(),
            z: z0 + (z1 - z0) * uniform(),
            heading: (uniform() * 2.0 - 1.0) * std::f64::consts::PI,
        };
        let clear = compiled.graph.static_primitives.iter().all(|&p| {
            let b = compiled.graph.primitives[p].bounds;
            b.max.y < 0.001
                || pose.x < b.min.x - margin
                || pose.x > b.max.x + margin
                || pose.z < b.min.z - margin
                || pose.z > b.max.z + margin
        });
        if clear {
            poses.push(pose);
        }
    }
    poses
}

fn outputs(
    compiled: &regatta_runtime::Compiled,
    robot: usize,
    rig: &PanoramicRig,
    rays: bool,
    poses: &[Pose2],
) -> Vec<RetinaOutput> {
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, rays);
    let mut retina = Panoramic::new(rig);
    let floor = compiled.rig.robots[robot].floor_y;
    poses
        .iter()
        .map(|&pose| {
            let view = renderer.view(
                &compiled.plan,
                &crate::vision::posed(compiled, robot, pose),
                robot,
            );
            let mut out = RetinaOutput::default();
            retina.update(&renderer, &view, pose, floor, &mut out);
            out
        })
        .collect()
}

/// Mean and max relative analog error, mean and max digital error in LSB.
fn errors(results: &[RetinaOutput], reference: &[RetinaOutput]) -> (f64, f64, f64, u32) {
    let (mut sum, mut max, mut count) = (0.0, 0.0f64, 0usize);
    let (mut lsb_sum, mut lsb_max, mut lsb_count) = (0.0, 0u32, 0usize);
    for (result, reference) in results.iter().zip(reference) {
        for (a, r) in result.analog.iter().zip(&reference.analog) {
            let error = (a - r).abs() / r.abs().max(1e-3);
            sum += error;
            max = max.max(error);
            count += 1;
        }
        for ((_, d), (_, e)) in result.digital.iter().zip(&reference.digital) {
            for (x, y) in d.iter().zip(e) {
                let error = (*x as i32 - *y as i32).unsigned_abs();
                lsb_sum += error as f64;
                lsb_max = lsb_max.max(error);
                lsb_count += 1;
            }
        }
    }
    (
        sum / count.max(1) as f64,
        max,
        lsb_sum / lsb_count.max(1) as f64,
        lsb_max,
    )
}

/// Wall time per update (render frame + retina), single thread, best of several rounds.
fn time_per_update(
    compiled: &regatta_runtime::Compiled,
    robot: usize,
    rig: &PanoramicRig,
    rays: bool,
    poses: &[Pose2],
    millis: u64,
) -> f64 {
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, rays);
    let mut retina = Panoramic::new(rig);
    let floor = compiled.rig.robots[robot].floor_y;
    let mut out = RetinaOutput::default();
    let all_poses: Vec<Poses> = poses
        .iter()
        .map(|&p| crate::vision::posed(compiled, robot, p))
        .collect();
    let budget = std::time::Duration::from_millis(millis);
    let started = Instant::now();
    let mut best = f64::INFINITY;
    while started.elapsed() < budget || best.is_infinite() {
        let round = Instant::now();
        for (pose, poses) in poses.iter().zip(&all_poses) {
            let view = renderer.view(&compiled.plan, poses, robot);
            retina.update(&renderer, &view, *pose, floor, &mut out);
        }
        best = best.min(round.elapsed().as_secs_f64() / poses.len() as f64);
        std::hint::black_box(&out);
    }
    best * 1e6
}

/// Error (mean LSB) against time per update (µs), both on log axes: one series per optics
/// and renderer, larger dots for more samples. An error of 0 is drawn at the axis' floor
/// (10⁻³ LSB), as a log axis has no zero.
fn chart(rows: &[Row], world: &str) -> regatta_figures::Chart {
    use regatta_figures::{Axis, Chart, Corner, Series};
    let floor = 1e-3;
    let mut chart = Chart::new(
        format!("retina update on {world}: time against error"),
        Axis::log("time per update (µs)"),
        Axis::log("mean digital error (LSB; 0 drawn at 0.001)"),
    )
    .legend(Corner::UpperRight);
    for (name, optics, renderer) in [
        ("exact optics, columns", "exact", "columns"),
        ("exact optics, rays", "exact", "rays"),
        ("paper optics", "paper", ""),
    ] {
        let picked: Vec<&Row> = rows
            .iter()
            .filter(|r| r.optics == optics && (renderer.is_empty() || r.renderer == renderer))
            .collect();
        if picked.is_empty() {
            continue;
        }
        chart = chart.with(
            Series::markers(
                name,
                picked
                    .iter()
                    .map(|r| (r.micros, r.lsb_mean.max(floor)))
                    .collect(),
            )
            .marker_sizes(
                picked
                    .iter()
                    .map(|r| 6 + 2 * r.samples.trailing_zeros())
                    .collect(),
            ),
        );
    }
    let top = rows.iter().map(|r| r.lsb_mean).fold(10.0f64, f64::max);
    chart.y = chart.y.clone().range(floor, 10f64.powf(top.log10().ceil()));
    chart
}
