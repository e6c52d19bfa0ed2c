//! `regatta bench webots`: what Webots worlds cost beyond regatta's own: typing a world whose
//! PROTOs are JavaScript templates (the engine's start, then each instance) against the same
//! world with arithmetic-only templates, and one frame of the e-puck's 52×39 camera.

use std::time::Instant;

use anyhow::{bail, Context};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// PROTO instances in the generated worlds.
    #[arg(long, default_value_t = 200)]
    instances: usize,
    /// Timed repetitions; the best is reported.
    #[arg(long, default_value_t = 5)]
    runs: usize,
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

    // One frame of the e-puck's camera in its test world.
    let text = include_str!("../../tests/data/webots/e-puck_camera.wbt");
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes(
            "e-puck_camera.wbt".into(),
            text.as_bytes().to_vec(),
        ),
        &regatta_schema::Options::default(),
    );
    if checked.has_errors() {
        bail!("{}", checked.render(false));
    }
    let compiled = regatta_runtime::compile(&checked.scene);
    let rig = &compiled.rig.robots[0];
    let camera_rig = rig.cameras.first().context("the e-puck has no camera")?;
    let caster = regatta_runtime::render::raycast::RayCaster::new(&compiled.graph, &compiled.plan);
    let poses = regatta_runtime::render::Poses {
        poses: vec![rig.start],
        floor_y: vec![rig.floor_y],
    };
    let camera = regatta_runtime::camera::Camera::new(camera_rig);
    let mut image = regatta_runtime::camera::CameraImage::default();
    let mut noise = regatta_runtime::sim::noise::Stream::new(0, 0, 5, 0);
    let frames = 50 * args.runs;
    let mut best = f64::INFINITY;
    for _ in 0..args.runs {
        let started = Instant::now();
        for _ in 0..frames / args.runs {
            let view = caster.prepare(&compiled.plan, &poses, Some(0));
            camera.update(
                &caster,
                &view,
                rig.start,
                rig.floor_y,
                &mut noise,
                &mut image,
            );
        }
        best = best.min(started.elapsed().as_secs_f64() / (frames / args.runs) as f64);
    }
    println!(
        "e-puck camera ({}×{}, ray cast, 1 light with shadows): {:.3} ms per frame, {:.2} M rays/s",
        camera_rig.width,
        camera_rig.height,
        best * 1e3,
        (camera_rig.width * camera_rig.height) as f64 / best / 1e6
    );
    Ok(Outcome::Clean)
}
