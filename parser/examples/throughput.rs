//! `throughput POINTS` or `throughput FILE`: parse time and rate (peak memory: run it under
//! `/usr/bin/time -v`).
fn main() {
    let arg = std::env::args().nth(1).unwrap_or_else(|| "1000000".into());
    let world = match arg.parse::<usize>() {
        Ok(points) => regatta_parser::testgen::mesh_world(points),
        Err(_) => std::fs::read_to_string(&arg).expect("readable file"),
    };
    let t = std::time::Instant::now();
    let parse = regatta_parser::parse(&world);
    let dt = t.elapsed().as_secs_f64();
    println!(
        "{} bytes, {:.1} MB/s, {} diags",
        world.len(),
        world.len() as f64 / dt / 1e6,
        parse.diagnostics.len()
    );
}
