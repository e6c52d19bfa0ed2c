//! Prints a world's first robot trajectory as CSV (t,x,z,heading), for quick looks while
//! tuning. `cargo run --release -p regatta-runtime --example trajectory -- WORLD SECONDS`
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = std::path::Path::new(&args[1]);
    let seconds: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(600.0);
    let checked = regatta_schema::check_file(path, true).expect("readable");
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let compiled = regatta_runtime::compile(&checked.scene);
    let mut sim = regatta_runtime::sim::Simulation::new(&compiled, None).expect("runs");
    println!("t,x,z,heading,left,right");
    while sim.time < seconds {
        sim.step();
        let r = &sim.robots[0];
        println!(
            "{:.3},{:.5},{:.5},{:.4},{},{}",
            sim.time, r.pose.x, r.pose.z, r.pose.heading, r.command.0, r.command.1
        );
    }
}
