//! `--renderer cpu|wgpu`: which backend renders vision devices. The CPU renderer is the
//! default and needs nothing; the wgpu backend exists only in builds with the `wgpu` feature,
//! and is started only when the scene has a vision device.

use std::path::Path;

use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::Pose2;
use regatta_runtime::render::Poses;
use regatta_runtime::vision::VisionBackend;
use regatta_runtime::Compiled;

/// The backend a command renders vision devices with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RendererKind {
    /// The CPU renderer (analytic columns or ray casting, as the plan chose).
    #[default]
    Cpu,
    /// The GPU, through wgpu: paper-mode flat views, many robots per submission.
    Wgpu,
}

/// The wgpu backend for `compiled`, or `None` when the CPU renders (the CPU was chosen, or
/// there is nothing to render: no GPU is then started).
pub fn backend<'c>(
    kind: RendererKind,
    compiled: &'c Compiled,
    world: &Path,
) -> anyhow::Result<Option<Box<dyn VisionBackend + 'c>>> {
    if kind == RendererKind::Cpu {
        return Ok(None);
    }
    if compiled.plan.renderer == RendererChoice::None {
        eprintln!(
            "note: {} has no vision device; the GPU is not started",
            world.display()
        );
        return Ok(None);
    }
    open(compiled, world)
}

#[cfg(feature = "wgpu")]
fn open<'c>(
    compiled: &'c Compiled,
    world: &Path,
) -> anyhow::Result<Option<Box<dyn VisionBackend + 'c>>> {
    let gpu = regatta_gpu::GpuVision::new(&[compiled])
        .map_err(|e| anyhow::anyhow!("cannot render {} with wgpu: {e}", world.display()))?;
    for turret in gpu.exact_turrets(0) {
        eprintln!(
            "note: {turret} asks for exact optics; the wgpu backend renders paper optics (two 75×7 flat views)"
        );
    }
    Ok(Some(Box::new(gpu)))
}

#[cfg(not(feature = "wgpu"))]
fn open<'c>(
    _compiled: &'c Compiled,
    world: &Path,
) -> anyhow::Result<Option<Box<dyn VisionBackend + 'c>>> {
    anyhow::bail!(
        "cannot render {} with wgpu: this regatta was built without the wgpu backend; rebuild it with `cargo build --release -p regatta --features wgpu`, or use `--renderer cpu`",
        world.display()
    )
}

/// `regatta bench retina --renderer wgpu`: one batch per population size, timed; each robot in
/// its own copy of the world at its own pose. Digital outputs are compared with the CPU's paper
/// optics (`cpu`, for the first poses).
#[cfg(feature = "wgpu")]
pub fn bench_population(
    compiled: &Compiled,
    robot: usize,
    poses: &[regatta_runtime::compile::rig::Pose2],
    cpu: &[regatta_runtime::optics::RetinaOutput],
    sizes: &[usize],
    millis: u64,
    out: &Path,
) -> anyhow::Result<crate::outcome::Outcome> {
    use std::fmt::Write as _;
    use std::time::Instant;

    use anyhow::Context;
    use regatta_runtime::compile::rig::TurretRig;
    use regatta_runtime::optics::{Panoramic, RetinaOutput};
    use regatta_runtime::vision::{VisionRequest, WorldInstance};

    let mut gpu = regatta_gpu::GpuVision::new(&[compiled])?;
    let device = format!(
        "{}{}",
        gpu.adapter(),
        if gpu.is_software() { " (software)" } else { "" }
    );
    let Some(TurretRig::Panoramic(rig)) = &compiled.rig.robots[robot].turret else {
        anyhow::bail!("robot {robot} has no Panoramic turret");
    };
    let worlds: Vec<_> = poses
        .iter()
        .map(|&pose| crate::vision::posed(compiled, robot, pose))
        .collect();
    let mut luminance = Vec::new();
    // Agreement with the CPU, from one batch of the compared poses.
    let compared = cpu.len().min(worlds.len());
    let instances: Vec<_> = worlds[..compared]
        .iter()
        .map(|poses| WorldInstance { scene: 0, poses })
        .collect();
    let requests: Vec<_> = (0..compared)
        .map(|instance| VisionRequest { instance, robot })
        .collect();
    gpu.render(&instances, &requests, &mut luminance)?;
    let mut retina = Panoramic::new(rig);
    let (mut lsb_max, mut lsb_sum, mut count) = (0u16, 0.0, 0usize);
    for (luminance, reference) in luminance.iter().zip(cpu) {
        let mut output = RetinaOutput::default();
        retina.accept(luminance, &mut output);
        for ((_, a), (_, b)) in output.digital.iter().zip(&reference.digital) {
            for (x, y) in a.iter().zip(b) {
                let d = x.abs_diff(*y);
                lsb_max = lsb_max.max(d);
                lsb_sum += d as f64;
                count += 1;
            }
        }
    }
    let mut report = format!(
        "wgpu retina updates on {device}: paper optics, samples {}, each robot in its own copy of the world, one batch per step\nagreement with the CPU's paper optics over {compared} poses: digital max {lsb_max} LSB, mean {:.4} LSB\n\n| robots | ms per batch | µs per retina update | updates/s |\n|---:|---:|---:|---:|\n",
        rig.samples,
        lsb_sum / count.max(1) as f64
    );
    let mut csv = String::from("robots,ms_per_batch,micros_per_update,updates_per_second,device\n");
    for &size in sizes {
        let size = size.max(1);
        let instances: Vec<_> = (0..size)
            .map(|i| WorldInstance {
                scene: 0,
                poses: &worlds[i % worlds.len()],
            })
            .collect();
        let requests: Vec<_> = (0..size)
            .map(|instance| VisionRequest { instance, robot })
            .collect();
        // Warm: the first batch of a size grows the buffers.
        gpu.render(&instances, &requests, &mut luminance)?;
        let started = Instant::now();
        let mut batches = 0u32;
        while batches < 3 || started.elapsed().as_millis() < millis as u128 {
            gpu.render(&instances, &requests, &mut luminance)?;
            batches += 1;
        }
        let per_batch = started.elapsed().as_secs_f64() / batches as f64;
        let per_update = per_batch / size as f64;
        let _ = writeln!(
            report,
            "| {size} | {:.3} | {:.2} | {:.0} |",
            per_batch * 1e3,
            per_update * 1e6,
            1.0 / per_update
        );
        let _ = writeln!(
            csv,
            "{size},{:.6},{:.4},{:.1},{device}",
            per_batch * 1e3,
            per_update * 1e6,
            1.0 / per_update
        );
    }
    print!("{report}");
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let path = out.join("retina-wgpu.csv");
    std::fs::write(&path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    println!("\nwrote {}", path.display());
    Ok(crate::outcome::Outcome::Clean)
}

#[cfg(not(feature = "wgpu"))]
pub fn bench_population(
    _compiled: &Compiled,
    _robot: usize,
    _poses: &[regatta_runtime::compile::rig::Pose2],
    _cpu: &[regatta_runtime::optics::RetinaOutput],
    _sizes: &[usize],
    _millis: u64,
    _out: &Path,
) -> anyhow::Result<crate::outcome::Outcome> {
    unreachable!("bench retina asks for the backend first")
}

/// The robots at their start poses, with `robot` moved to `pose`.
pub(crate) fn posed(compiled: &regatta_runtime::Compiled, robot: usize, pose: Pose2) -> Poses {
    let mut poses = Poses {
        poses: compiled.rig.robots.iter().map(|r| r.start).collect(),
        floor_y: compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
    };
    poses.poses[robot] = pose;
    poses
}
