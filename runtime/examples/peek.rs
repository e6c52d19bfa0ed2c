//! Prints the first robot's odd-filter digital output and proximity at a given time.
//! `cargo run --release -p regatta-runtime --example peek -- WORLD SECONDS`
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let checked =
        regatta_schema::check_file(std::path::Path::new(&args[1]), true).expect("readable");
    let compiled = regatta_runtime::compile(&checked.scene);
    let seconds: f64 = args[2].parse().expect("seconds");
    let mut sim = regatta_runtime::sim::Simulation::new(&compiled, None).expect("runs");
    while sim.time < seconds {
        sim.step();
    }
    let robot = &sim.robots[0];
    println!(
        "pose {:?} command {:?} proximity {:?}",
        robot.pose, robot.command, robot.proximity
    );
    if let Some(p) = &robot.panoramic {
        for (kind, digital) in &p.output.digital {
            println!("{kind:?}: {digital:?}");
        }
        let analog: Vec<String> = p.output.analog.iter().map(|a| format!("{a:.1}")).collect();
        println!("analog: {}", analog.join(" "));
    }
}
