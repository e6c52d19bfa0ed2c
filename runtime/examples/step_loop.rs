//! Profiling aid: steps a world in a loop. `step_loop WORLD STEPS`
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let checked =
        regatta_schema::check_file(std::path::Path::new(&args[1]), true).expect("readable");
    let compiled = regatta_runtime::compile(&checked.scene);
    let steps: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200_000);
    let mut sim = regatta_runtime::sim::Simulation::new(&compiled, None).expect("runs");
    let start = std::time::Instant::now();
    sim.run(steps);
    println!(
        "{:.2} µs per step",
        start.elapsed().as_secs_f64() * 1e6 / steps as f64
    );
}
