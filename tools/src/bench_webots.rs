//! `regatta bench webots`: what Webots worlds cost beyond regatta's own: typing a world whose
//! PROTOs are JavaScript templates (the engine's start, then each instance) against the same
//! world with arithmetic-only templates, and 2-D cameras: frames/s of the e-puck's 52×39 camera
//! and steps/s of a 640×480 camera world whose every sensor is read (as `--log` reads them),
//! each rasterised and ray cast (the reference).

use std::time::Instant;

use anyhow::{bail, Context};

use regatta_runtime::compile::rig::CameraRenderer;
use regatta_runtime::render::raster::Rasterizer;
use regatta_runtime::render::raycast::RayCaster;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// PROTO instances in the generated worlds.
    #[arg(long, default_value_t = 200)]
    instances: usize,
    /// Timed repetitions; the best is reported.
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// The 640×480 camera world whose steps are timed (default: the e-puck camera test world
    /// with its camera at 640×480; webots_ros2's epuck_world.wbt is the issue's).
    #[arg(long, value_name = "WORLD")]
    camera_world: Option<std::path::PathBuf>,
    /// Steps timed in the camera world, rasterised (ray casting runs a tenth as many).
    #[arg(long, default_value_t = 500)]
    steps: usize,
}

/// Every camera of the world drawn by `renderer`.
fn with_renderer(
    compiled: &regatta_runtime::compile::Compiled,
    renderer: CameraRenderer,
) -> regatta_runtime::compile::Compiled {
    let mut compiled = compiled.clone();
    for robot in &mut compiled.rig.robots {
        for camera in &mut robot.cameras {
            camera.renderer = renderer;
        }
    }
    compiled
}

fn compile_text(name: &str, text: &str) -> anyhow::Result<regatta_runtime::compile::Compiled> {
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes(name.into(), text.as_bytes().to_vec()),
        &regatta_schema::Options::default(),
    );
    if checked.has_errors() {
        bail!("{}", checked.render(false));
    }
    Ok(regatta_runtime::compile(&checked.scene))
}

/// Frames per second of robot 0's first camera, best of `runs`.
fn camera_frames(
    compiled: &regatta_runtime::compile::Compiled,
    renderer: CameraRenderer,
    frames: usize,
    runs: usize,
) -> anyhow::Result<f64> {
    let rig = &compiled.rig.robots[0];
    let camera_rig = rig.cameras.first().context("the e-puck has no camera")?;
    let plan = &compiled.plan;
    let poses = regatta_runtime::render::Poses {
        poses: vec![rig.start],
        floor_y: vec![rig.floor_y],
    };
    let mut camera = regatta_runtime::camera::Camera::new(camera_rig);
    let mut image = regatta_runtime::camera::CameraImage::default();
    let mut noise = regatta_runtime::sim::noise::Stream::new(0, 0, 5, 0);
    let mut best = f64::INFINITY;
    match renderer {
        CameraRenderer::Rays => {
            let caster = RayCaster::new(&compiled.graph, plan);
            for _ in 0..runs {
                let started = Instant::now();
                for _ in 0..frames {
                    let view = caster.prepare(plan, &poses, Some(0));
                    camera.update(
                        &caster,
                        &view,
                        rig.start,
                        rig.floor_y,
                        &mut noise,
                        &mut image,
                    );
                }
                best = best.min(started.elapsed().as_secs_f64() / frames as f64);
            }
        }
        CameraRenderer::Raster => {
            let raster = Rasterizer::new(&compiled.graph, plan);
            for _ in 0..runs {
                let started = Instant::now();
                for _ in 0..frames {
                    camera.update_raster(&raster, plan, &poses, 0, &mut noise, &mut image);
                }
                best = best.min(started.elapsed().as_secs_f64() / frames as f64);
            }
        }
    }
    Ok(1.0 / best)
}

/// Steps per second of a world whose every sensor is read, on one thread, best of `runs`.
fn camera_steps(
    compiled: &regatta_runtime::compile::Compiled,
    steps: usize,
    runs: usize,
) -> anyhow::Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        let mut simulation = regatta_runtime::sim::Simulation::new(compiled, Some(1))?;
        simulation.sense_everything();
        // The first step builds what later steps reuse.
        simulation.step();
        let started = Instant::now();
        for _ in 0..steps {
            simulation.step();
        }
        best = best.min(started.elapsed().as_secs_f64() / steps as f64);
    }
    Ok(1.0 / best)
}

/// A PROTO whose template is JavaScript (a loop and a conditional), and one whose only
/// templates are arithmetic over fields, both placing the same four walls.
const JAVASCRIPT: &str = "PROTO Walls [ field SFFloat side 1 field SFFloat height 0.1 ] {\n  Group { children [\n    %< for (let i = 0; i < 4; ++i) { const a = i * Math.PI / 2; >%\n    Transform {\n      translation %<= Math.cos(a) * fields.side.value / 2 >% %<= fields.height.value / 2 >% %<= Math.sin(a) * fields.side.value / 2 >%\n      rotation 0 1 0 %<= -a >%\n      children [ Shape { geometry Box { size 0.01 %<= fields.height.value >% %<= fields.side.value >% } } ]\n    }\n    %< } >%\n  ] }\n}\n";

const ARITHMETIC: &str = "PROTO Walls [ field SFFloat side 1 field SFFloat height 0.1 ] {\n  Group { children [\n    Transform { translation %<= fields.side.value / 2 >% %<= fields.height.value / 2 >% 0 children [ Shape { geometry Box { size 0.01 %<= fields.height.value >% %<= fields.side.value >% } } ] }\n    Transform { translation 0 %<= fields.height.value / 2 >% %<= fields.side.value / 2 >% rotation 0 1 0 -1.5707963267948966 children [ Shape { geometry Box { size 0.01 %<= fields.height.value >% %<= fields.side.value >% } } ] }\n    Transform { translation %<= -fields.side.value / 2 >% %<= fields.height.value / 2 >% 0 rotation 0 1 0 -3.141592653589793 children [ Shape { geometry Box { size 0.01 %<= fields.height.value >% %<= fields.side.value >% } } ] }\n    Transform { translation 0 %<= fields.height.value / 2 >% %<= -fields.side.value / 2 >% rotation 0 1 0 -4.71238898038469 children [ Shape { geometry Box { size 0.01 %<= fields.height.value >% %<= fields.side.value >% } } ] }\n  ] }\n}\n";

fn world(proto: &str, instances: usize) -> String {
    let mut text =
        format!("#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" }}\n{proto}");
    for i in 0..instances {
        // Distinct fields: no instance reuses another's expansion.
        text.push_str(&format!("Walls {{ side {} }}\n", 1.0 + i as f64 * 1e-3));
    }
    text
}

/// Best time (s) to type `text`, and its node count.
fn check(text: &str, runs: usize) -> anyhow::Result<(f64, usize)> {
    let mut best = f64::INFINITY;
    let mut nodes = 0;
    for _ in 0..runs {
        let started = Instant::now();
        let checked = regatta_schema::check(
            regatta_parser::SourceText::from_bytes("bench.wbt".into(), text.as_bytes().to_vec()),
            &regatta_schema::Options::default(),
        );
        best = best.min(started.elapsed().as_secs_f64());
        if checked.has_errors() {
            bail!(
                "the generated world does not check:\n{}",
                checked.render(false)
            );
        }
        nodes = checked.scene.nodes.len();
    }
    Ok((best, nodes))
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    if args.runs == 0 || args.instances == 0 {
        bail!("--runs and --instances must be at least 1");
    }
    let (arithmetic, nodes_a) = check(&world(ARITHMETIC, args.instances), args.runs)?;
    let (javascript, nodes_j) = check(&world(JAVASCRIPT, args.instances), args.runs)?;
    let (one, _) = check(&world(JAVASCRIPT, 1), args.runs)?;
    if nodes_a != nodes_j {
        bail!("the two worlds differ ({nodes_a} and {nodes_j} nodes)");
    }
    let n = args.instances as f64;
    println!(
        "typing {} PROTO instances ({nodes_a} nodes), best of {}:",
        args.instances, args.runs
    );
    println!(
        "  arithmetic templates (no engine)   {:8.2} ms   {:7.1} µs per instance",
        arithmetic * 1e3,
        arithmetic / n * 1e6
    );
    println!(
        "  JavaScript templates               {:8.2} ms   {:7.1} µs per instance",
        javascript * 1e3,
        javascript / n * 1e6
    );
    println!(
        "  one JavaScript instance (engine started for it) {:.2} ms",
        one * 1e3
    );

    // The e-puck's camera in its test world, rasterised and ray cast.
    let text = include_str!("../../tests/data/webots/e-puck_camera.wbt");
    let compiled = compile_text("e-puck_camera.wbt", text)?;
    let camera = &compiled.rig.robots[0]
        .cameras
        .first()
        .context("the e-puck has no camera")?;
    let (width, height) = (camera.width, camera.height);
    let raster = camera_frames(&compiled, CameraRenderer::Raster, 2000, args.runs)?;
    let rays = camera_frames(&compiled, CameraRenderer::Rays, 50, args.runs)?;
    println!(
        "e-puck camera ({width}×{height}), frames/s, best of {}:",
        args.runs
    );
    println!("  rasterised   {raster:10.0}   (target ≥ 20,000)");
    println!(
        "  ray cast     {rays:10.0}   ({:.1}× slower)",
        raster / rays
    );

    // A 640×480 camera world with every sensor read (what `--log` asks), one thread.
    let (name, compiled) = match &args.camera_world {
        Some(path) => {
            let checked = regatta_schema::check_file(path, false)
                .with_context(|| format!("cannot read {}", path.display()))?;
            if checked.has_errors() {
                bail!("{}", checked.render(false));
            }
            let mut compiled = regatta_runtime::compile(&checked.scene);
            // Cameras cost the same whatever drives the robot; "<extern>" has no stand-in.
            for robot in &mut compiled.rig.robots {
                robot.controller = "none".to_owned();
            }
            (path.display().to_string(), compiled)
        }
        None => (
            "e-puck_camera.wbt at 640×480".to_owned(),
            compile_text(
                "e-puck_camera.wbt",
                &text.replace(
                    "controller \"none\"",
                    "controller \"none\"\n  camera_width 640\n  camera_height 480",
                ),
            )?,
        ),
    };
    let step = compiled.settings.time_step;
    let raster = camera_steps(
        &with_renderer(&compiled, CameraRenderer::Raster),
        args.steps,
        args.runs,
    )?;
    let rays = camera_steps(
        &with_renderer(&compiled, CameraRenderer::Rays),
        (args.steps / 100).max(2),
        1,
    )?;
    println!(
        "{name}: steps/s of {} ms with every sensor read, one thread:",
        step * 1e3
    );
    println!(
        "  rasterised   {raster:10.1}   ({:.1}× real time; target ≥ 500)",
        raster * step
    );
    println!(
        "  ray cast     {rays:10.1}   ({:.2}× real time)",
        rays * step
    );
    Ok(Outcome::Clean)
}
