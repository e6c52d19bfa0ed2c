//! `regatta explain`: what a world compiles to — the render graph's size, the sensor rig, and
//! the plan with everything it skips and why.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::PathBuf;

use regatta_runtime::compile::graph::Owner;
use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::{Optics, TurretRig};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    #[command(flatten)]
    options: crate::world::WorldOptions,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let loaded = crate::world::load(&args.world, &args.options, color)?;
    let text = explain(&crate::world::world_name(&args.world), &loaded);
    // The world line first, then what the world may read.
    let (first, rest) = text.split_once('\n').unwrap_or((&text, ""));
    println!("{first}");
    let roots = args.options.readable_roots(&args.world);
    if roots.is_empty() {
        println!("reads no file (standard input; --allow-path DIR lets it)");
    } else {
        let shown: Vec<String> = roots.iter().map(|r| r.display().to_string()).collect();
        println!("reads files under {}", shown.join(", "));
    }
    print!("{rest}");
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
    if !loaded.checked.substitutions.is_empty() {
        let _ = writeln!(out, "\nWebots PROTOs replaced by regatta's stand-ins");
        for s in &loaded.checked.substitutions {
            let _ = writeln!(
                out,
                "  {} ← {}: built-in stand-in worlds/protos/webots/{}.proto",
                s.name, s.url, s.name
            );
        }
    }
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
    // Robots alike but for their name and place are described once, as a group: a swarm's
    // rig stays readable.
    let mut groups: Vec<(String, String, Vec<usize>)> = Vec::new();
    let mut by_description: std::collections::HashMap<String, usize> = Default::default();
    for (index, robot) in rig.robots.iter().enumerate() {
        let kind = robot_kind(&loaded.checked.scene, robot);
        let description = robot_description(robot);
        let key = format!("{kind}\n{description}");
        match by_description.get(&key) {
            Some(&group) => groups[group].2.push(index),
            None => {
                by_description.insert(key, groups.len());
                groups.push((kind, description, vec![index]));
            }
        }
    }
    for (kind, description, members) in &groups {
        let (first, rest) = description.split_once('\n').unwrap_or((description, ""));
        if let [only] = members[..] {
            let robot = &rig.robots[only];
            let _ = writeln!(
                out,
                "  {} at x {:.3} z {:.3}, heading {:.1}°: {first}",
                robot.name,
                robot.start.x,
                robot.start.z,
                robot.start.heading.to_degrees(),
            );
        } else {
            let robots: Vec<_> = members.iter().map(|&i| &rig.robots[i]).collect();
            let span = |value: &dyn Fn(&&regatta_runtime::compile::rig::RobotRig) -> f64| {
                robots
                    .iter()
                    .map(value)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                        (lo.min(v), hi.max(v))
                    })
            };
            let (x0, x1) = span(&|r| r.start.x);
            let (z0, z1) = span(&|r| r.start.z);
            let names = if robots.len() > 4 {
                format!(
                    "{}, {}, … {}",
                    robots[0].name,
                    robots[1].name,
                    robots[robots.len() - 1].name
                )
            } else {
                robots
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(
                out,
                "  {} × {kind} ({names}) within x {x0:.3}…{x1:.3} z {z0:.3}…{z1:.3}: {first}",
                robots.len(),
            );
        }
        out.push_str(rest);
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
            "  visible: {} primitives (+{own} seen by their own robot's devices)",
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
        // Many things skipped for one reason (a swarm's switched-off lamps) make one line.
        let mut reasons: Vec<(&str, Vec<&str>)> = Vec::new();
        for skipped in &plan.skipped {
            match reasons.iter_mut().find(|(why, _)| *why == skipped.why) {
                Some((_, whats)) => whats.push(&skipped.what),
                None => reasons.push((&skipped.why, vec![&skipped.what])),
            }
        }
        for (why, whats) in reasons {
            if whats.len() > 3 {
                let _ = writeln!(
                    out,
                    "    - {} things ({}, {}, … {}): {why}",
                    whats.len(),
                    whats[0],
                    whats[1],
                    whats[whats.len() - 1]
                );
            } else {
                for what in whats {
                    let _ = writeln!(out, "    - {what}: {why}");
                }
            }
        }
    }
    // Filters left off, robots with the same ones together.
    let mut off_groups: Vec<(String, Vec<&str>)> = Vec::new();
    for robot in &rig.robots {
        if let Some(TurretRig::Panoramic(p)) = &robot.turret {
            let off: Vec<&str> = regatta_runtime::retina::FilterKind::ALL
                .iter()
                .filter(|k| !p.filters.contains(**k))
                .map(|k| k.name())
                .collect();
            if off.is_empty() {
                continue;
            }
            let off = off.join(", ");
            match off_groups.iter_mut().find(|(o, _)| *o == off) {
                Some((_, names)) => names.push(&robot.name),
                None => off_groups.push((off, vec![&robot.name])),
            }
        }
    }
    for (off, names) in off_groups {
        let whose = match names[..] {
            [one] => one.to_owned(),
            [first, .., last] => format!("{} robots ({first} … {last})", names.len()),
            [] => continue,
        };
        let _ = writeln!(out, "    - filters {off} of {whose}: not enabled");
    }
    out
}

/// What a robot is, for grouping: its PROTO (or node type) and what its turret is.
fn robot_kind(
    scene: &regatta_schema::Scene,
    robot: &regatta_runtime::compile::rig::RobotRig,
) -> String {
    let node = scene.node(robot.node);
    let name = node
        .proto_names()
        .last()
        .cloned()
        .unwrap_or_else(|| scene.spec(robot.node).name.to_string());
    match &robot.turret {
        Some(TurretRig::Panoramic(_)) => format!("{name} with PanoramicTurret"),
        Some(TurretRig::Linear(_)) => format!("{name} with LinearCamera"),
        None => name,
    }
}

/// Everything about a robot but its name and place: the rest of its first line, then its
/// devices' lines.
fn robot_description(robot: &regatta_runtime::compile::rig::RobotRig) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "wheels r {} axle {}, body r {}, controller \"{}\"{}",
        mm(robot.wheel_radius),
        mm(robot.axle_length),
        mm(robot.body_radius),
        robot.controller,
        if robot.controller_args.is_empty() {
            String::new()
        } else {
            format!(" {:?}", robot.controller_args)
        }
    );
    if let Some(drive) = &robot.drive {
        let _ = writeln!(out, "    {}", drive.summary);
    }
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
                match (p.optics, p.crowd_distance.is_finite()) {
                    (Optics::Paper, _) => "paper".to_owned(),
                    (Optics::Exact, false) => "exact".to_owned(),
                    (Optics::Exact, true) => format!(
                        "exact (crowd level of detail: other robots drawn within {0}; buoys and other \
                         small round static objects beyond {0} drawn as impostors{1}; parts wholly \
                         outside the band and other robots' parts tucked under their body left out)",
                        mm(p.crowd_distance),
                        if p.far_distance.is_finite() {
                            format!(", left out beyond {}", mm(p.far_distance))
                        } else {
                            String::new()
                        } + &if p.keep_distance > 0.0 {
                            format!(
                                ", kept from update to update while the retina moves less than {}",
                                mm(p.keep_distance)
                            )
                        } else {
                            String::new()
                        }
                    ),
                },
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
    for c in &robot.cameras {
        let _ = writeln!(
            out,
            "    Camera \"{}\": {}×{} pixels over {:.1}°, planar, {}{}, {}",
            c.name,
            c.width,
            c.height,
            c.field_of_view.to_degrees(),
            match c.renderer {
                regatta_runtime::compile::rig::CameraRenderer::Raster => {
                    "rasterised (the default for 2-D cameras: per-vertex lighting, shadows by ray; ray casting is the reference, docs/camera-raster.md)"
                }
                regatta_runtime::compile::rig::CameraRenderer::Rays => {
                    "ray cast (the reference: the world asks for it with rendering \"rays\")"
                }
            },
            if c.noise > 0.0 {
                format!(", noise {}", c.noise)
            } else {
                String::new()
            },
            if c.period > 0.0 {
                format!("every {} ms when read", c.period * 1000.0)
            } else {
                "every step when read".to_owned()
            }
        );
    }
    out
}
