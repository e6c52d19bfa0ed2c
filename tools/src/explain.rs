//! `regatta explain`: what a world compiles to — the render graph's size, the sensor rig, and
//! the plan with everything it skips and why.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::PathBuf;

use regatta_runtime::compile::graph::Owner;
use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::{Optics, TurretRig};

use crate::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    #[command(flatten)]
    options: crate::world::WorldOptions,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let loaded = crate::world::load(&args.world, &args.options, color)?;
    print!(
        "{}",
        explain(&crate::world::world_name(&args.world), &loaded)
    );
    Ok(Outcome::Clean)
}

fn mm(metres: f64) -> String {
    format!("{:.2} mm", metres * 1000.0)
}

pub fn explain(name: &str, loaded: &crate::world::Loaded) -> String {
    let compiled = &loaded.compiled;
    let (graph, rig, plan, settings) = (
        &compiled.graph,
        &compiled.rig,
        &compiled.plan,
        &compiled.settings,
    );
    let mut out = String::new();
    let _ = writeln!(
        out,
        "world {name}: \"{}\", time step {} ms, seed {}, {} ({} scene nodes)",
        settings.title,
        settings.time_step * 1000.0,
        settings.seed,
        match loaded.checked.scene.up_axis {
            regatta_schema::UpAxis::Y => "y-up",
            regatta_schema::UpAxis::Z => "z-up, turned to y-up",
        },
        loaded.checked.scene.nodes.len()
    );
    let mut shapes: BTreeMap<&str, usize> = BTreeMap::new();
    for p in &graph.primitives {
        *shapes.entry(p.shape.name()).or_default() += 1;
    }
    let attached = graph
        .primitives
        .iter()
        .filter(|p| p.owner != Owner::Static)
        .count();
    let _ = writeln!(out, "\nrender graph");
    let _ = writeln!(
        out,
        "  {} primitives ({} static, {} attached to robots): {}",
        graph.primitives.len(),
        graph.primitives.len() - attached,
        attached,
        shapes
            .iter()
            .map(|(k, v)| format!("{v} {k}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        out,
        "  {} meshes, {} triangles; {} materials; {} lights",
        graph.meshes.len(),
        graph.triangle_count(),
        graph.materials.len(),
        graph.lights.len()
    );
    let bounds = graph.static_bounds();
    if !bounds.is_empty() {
        let _ = writeln!(
            out,
            "  static bounds x {:.3}…{:.3}, y {:.3}…{:.3}, z {:.3}…{:.3} m, indexed by a BVH",
            bounds.min.x, bounds.max.x, bounds.min.y, bounds.max.y, bounds.min.z, bounds.max.z
        );
    }
    let sky = graph.background.sky;
    let _ = writeln!(out, "  background sky {} {} {}", sky[0], sky[1], sky[2]);
    let _ = writeln!(out, "\nsensor rig: {} robot(s)", rig.robots.len());
    for robot in &rig.robots {
        let _ = writeln!(
            out,
            "  {} at x {:.3} z {:.3}, heading {:.1}°: wheels r {} axle {}, body r {}, controller \"{}\"{}",
            robot.name,
            robot.start.x,
            robot.start.z,
            robot.start.heading.to_degrees(),
            mm(robot.wheel_radius),
            mm(robot.axle_length),
            mm(robot.body_radius),
            robot.controller,
            if robot.controller_args.is_empty() { String::new() } else { format!(" {:?}", robot.controller_args) }
        );
        if let Some(ir) = robot.distance_sensors.first() {
            let _ = writeln!(
                out,
                "    {} IR proximity sensors: {} rays over {:.0}°, range {}, every {} ms",
                robot.distance_sensors.len(),
                ir.rays,
                ir.aperture.to_degrees(),
                mm(ir.range),
                ir.period * 1000.0
            );
        }
        if !robot.light_sensors.is_empty() {
            let _ = writeln!(
                out,
                "    {} ambient light sensors",
                robot.light_sensors.len()
            );
        }
        match &robot.turret {
            Some(TurretRig::Panoramic(p)) => {
                let filters: Vec<&str> = p.filters.iter().map(|k| k.name()).collect();
                let _ = writeln!(
                    out,
                    "    PanoramicTurret \"{}\" at {}: {} optics, samples {}, stride {}, filters [{}], λ {}, bandpass λ {}/{}, {} bits, I_bda {}, region of interest {}…{}",
                    p.name,
                    mm(p.height),
                    if p.optics == Optics::Paper { "paper" } else { "exact" },
                    p.samples,
                    p.stride,
                    filters.join(", "),
                    p.lambda,
                    p.bandpass.0,
                    p.bandpass.1,
                    p.bits,
                    p.i_bda.map_or("calibrated".to_owned(), |v| v.to_string()),
                    p.roi.0,
                    p.roi.1
                );
            }
            Some(TurretRig::Linear(c)) => {
                let _ = writeln!(
                    out,
                    "    LinearCamera \"{}\" at {}: {} pixels over {:.1}°, {} bits",
                    c.name,
                    mm(c.height),
                    c.pixels,
                    c.field_of_view.to_degrees(),
                    c.bits
                );
            }
            None => {}
        }
    }
    let _ = writeln!(out, "\nplan");
    let renderer = match plan.renderer {
        RendererChoice::None => "none: no robot carries a vision device",
        RendererChoice::Columns => "analytic columns: every visible primitive is upright",
        RendererChoice::Rays => "ray casting: some visible primitive is not upright",
    };
    let _ = writeln!(out, "  renderer: {renderer}");
    if plan.renderer != RendererChoice::None {
        let own: usize = plan.own_visible.iter().map(Vec::len).sum();
        let _ = writeln!(
            out,
            "  visible: {} primitives (+{own} seen by their own robot's turret)",
            plan.visible.len()
        );
        let r = plan.region;
        let _ = writeln!(
            out,
            "  robots assumed within x {:.3}…{:.3}, z {:.3}…{:.3} m",
            r.min.x, r.max.x, r.min.z, r.max.z
        );
    }
    let _ = writeln!(
        out,
        "  lights used: {} of {}",
        plan.lights.len(),
        graph.lights.len()
    );
    if plan.skipped.is_empty() {
        let _ = writeln!(out, "  skipped: nothing");
    } else {
        let _ = writeln!(out, "  skipped:");
        for skipped in &plan.skipped {
            let _ = writeln!(out, "    - {}: {}", skipped.what, skipped.why);
        }
    }
    for robot in &rig.robots {
        if let Some(TurretRig::Panoramic(p)) = &robot.turret {
            let off: Vec<&str> = regatta_runtime::retina::FilterKind::ALL
                .iter()
                .filter(|k| !p.filters.contains(**k))
                .map(|k| k.name())
                .collect();
            if !off.is_empty() {
                let _ = writeln!(
                    out,
                    "    - filters {} of {}: not enabled",
                    off.join(", "),
                    robot.name
                );
            }
        }
    }
    out
}
