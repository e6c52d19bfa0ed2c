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
use image::{Rgb, RgbImage};
use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::{Optics, PanoramicRig, Pose2, TurretRig};
use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
use regatta_runtime::render::Poses;

use crate::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world (its first robot with a Panoramic turret is measured).
    #[arg(default_value = "worlds/regatta.wbt")]
    world: PathBuf,
    /// Poses to average over.
    #[arg(long, default_value_t = 24)]
    poses: usize,
    /// Directory for retina.csv and retina.png.
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
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
    let png_path = args.out.join("retina.png");
    plot(&rows)
        .save(&png_path)
        .with_context(|| format!("cannot write {}", png_path.display()))?;
    println!("wrote {} and {}", csv_path.display(), png_path.display());
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
            let view = renderer.view(&compiled.plan, &posed(compiled, robot, pose), robot);
            let mut out = RetinaOutput::default();
            retina.update(&renderer, &view, pose, floor, &mut out);
            out
        })
        .collect()
}

pub(crate) fn posed(compiled: &regatta_runtime::Compiled, robot: usize, pose: Pose2) -> Poses {
    let mut poses = Poses {
        poses: compiled.rig.robots.iter().map(|r| r.start).collect(),
        floor_y: compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
    };
    poses.poses[robot] = pose;
    poses
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
    let all_poses: Vec<Poses> = poses.iter().map(|&p| posed(compiled, robot, p)).collect();
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

/// Error (mean LSB, log scale) against time per update (µs, log scale): exact columns in
/// blue, exact rays in green, paper in red; larger dots for more samples. Grid lines at
/// decades.
fn plot(rows: &[Row]) -> RgbImage {
    let (width, height, pad) = (640u32, 440u32, 48u32);
    let mut image = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    let (t_min, t_max) = (0.1f64, 1e6f64);
    let (e_min, e_max) = (1e-3f64, 10.0f64);
    let x_of = |t: f64| {
        pad as f64
            + (t.clamp(t_min, t_max) / t_min).log10() / (t_max / t_min).log10()
                * (width - 2 * pad) as f64
    };
    let y_of = |e: f64| {
        (height - pad) as f64
            - (e.clamp(e_min, e_max) / e_min).log10() / (e_max / e_min).log10()
                * (height - 2 * pad) as f64
    };
    let mut decade = t_min;
    while decade <= t_max * 1.01 {
        let x = x_of(decade) as u32;
        for y in pad..=height - pad {
            image.put_pixel(x, y, Rgb([220, 220, 220]));
        }
        decade *= 10.0;
    }
    let mut decade = e_min;
    while decade <= e_max * 1.01 {
        let y = y_of(decade) as u32;
        for x in pad..=width - pad {
            image.put_pixel(x, y, Rgb([220, 220, 220]));
        }
        decade *= 10.0;
    }
    for x in pad..=width - pad {
        image.put_pixel(x, height - pad, Rgb([0, 0, 0]));
    }
    for y in pad..=height - pad {
        image.put_pixel(pad, y, Rgb([0, 0, 0]));
    }
    // Labels: decades on both axes, axis titles, legend.
    let ink = Rgb([40, 40, 40]);
    let mut decade = t_min;
    while decade <= t_max * 1.01 {
        let label = if decade >= 1e6 {
            "1M".to_owned()
        } else if decade >= 1e3 {
            format!("{}k", (decade / 1e3).round())
        } else {
            format!("{decade}")
        };
        let x = x_of(decade) as u32;
        crate::font::draw_text(
            &mut image,
            x.saturating_sub(crate::font::text_width(&label, 2) / 2),
            height - pad + 6,
            &label,
            2,
            ink,
        );
        decade *= 10.0;
    }
    let mut decade = e_min;
    while decade <= e_max * 1.01 {
        let label = format!("{decade}");
        let y = y_of(decade) as u32;
        crate::font::draw_text(&mut image, 2, y.saturating_sub(5), &label, 2, ink);
        decade *= 10.0;
    }
    let title = "time per update (us), log";
    crate::font::draw_text(
        &mut image,
        (width - crate::font::text_width(title, 2)) / 2,
        height - 14,
        title,
        2,
        ink,
    );
    crate::font::draw_text(&mut image, pad, 8, "mean digital error (LSB), log", 2, ink);
    let legend = [
        ("exact, columns", Rgb([40, 80, 210])),
        ("exact, rays", Rgb([40, 160, 60])),
        ("paper", Rgb([210, 40, 40])),
    ];
    for (k, (name, color)) in legend.iter().enumerate() {
        let y = pad + 8 + 16 * k as u32;
        for dy in 0..8 {
            for dx in 0..8 {
                image.put_pixel(width - pad - 140 + dx, y + dy, *color);
            }
        }
        crate::font::draw_text(&mut image, width - pad - 126, y, name, 2, ink);
    }
    for row in rows {
        let color = match (row.optics, row.renderer) {
            ("paper", _) => Rgb([210, 40, 40]),
            (_, "rays") => Rgb([40, 160, 60]),
            _ => Rgb([40, 80, 210]),
        };
        let (cx, cy) = (
            x_of(row.micros) as i64,
            y_of(row.lsb_mean.max(e_min)) as i64,
        );
        let r = 2 + row.samples.trailing_zeros() as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy <= r * r {
                    let (x, y) = (cx + dx, cy + dy);
                    if x >= 0 && y >= 0 && (x as u32) < width && (y as u32) < height {
                        image.put_pixel(x as u32, y as u32, color);
                    }
                }
            }
        }
    }
    image
}
