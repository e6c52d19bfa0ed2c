//! Profiling aid: updates the first robot's retina in worlds/regatta.wbt in a loop.
//! `cargo run --release -p regatta-runtime --example retina_loop [UPDATES]`
use regatta_runtime::compile::rig::TurretRig;
use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
use regatta_runtime::render::Poses;

fn main() {
    let updates: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200_000);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/regatta.wbt");
    let checked = regatta_schema::check_file(&path, true).expect("readable");
    let compiled = regatta_runtime::compile(&checked.scene);
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, false);
    let robot = &compiled.rig.robots[0];
    let Some(TurretRig::Panoramic(rig)) = &robot.turret else {
        panic!("no turret")
    };
    let mut retina = Panoramic::new(rig);
    let mut out = RetinaOutput::default();
    let mut poses = Poses {
        poses: vec![robot.start],
        floor_y: vec![robot.floor_y],
    };
    let start = std::time::Instant::now();
    for i in 0..updates {
        poses.poses[0].heading = robot.start.heading + (i % 360) as f64 * 0.0174;
        let view = renderer.view(&compiled.plan, &poses, 0);
        retina.update(&renderer, &view, poses.poses[0], robot.floor_y, &mut out);
    }
    println!(
        "{:.2} µs per update",
        start.elapsed().as_secs_f64() * 1e6 / updates as f64
    );
}
