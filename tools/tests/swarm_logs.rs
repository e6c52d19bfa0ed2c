//! Logging a large swarm: MCAP numbers a file's channels with 16 bits, so a run whose robots
//! have more channels than that is refused with the way out (`--channels`), and leaves no
//! half-written file; with fewer channels the same swarm logs.

mod common;

use common::{regatta, temp_dir};

/// A square of `n` Kheperas 10 cm apart, IR only.
fn swarm(n: usize) -> String {
    let side = (n as f64).sqrt().ceil() as usize;
    let arena = side as f64 * 0.1 + 1.0;
    let mut text = format!(
        "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" basicTimeStep 32 }}\nArena {{ size {arena} {arena} }}\n"
    );
    for i in 0..n {
        let (x, z) = ((i % side) as f64 * 0.1, (i / side) as f64 * 0.1);
        let half = side as f64 * 0.05;
        text.push_str(&format!(
            "Khepera {{ translation {:.2} 0 {:.2} name \"k{i}\" controller \"braitenberg\" }}\n",
            x - half,
            z - half
        ));
    }
    text
}

#[test]
fn a_swarm_past_mcaps_channel_limit_is_refused_with_the_way_out_and_no_file() {
    let dir = temp_dir("swarm-logs");
    let world = dir.join("swarm.wbt");
    // Eight or more channels a robot with every channel: past 65,534.
    std::fs::write(&world, swarm(8_500)).unwrap();
    let log = dir.join("all.mcap");
    let refused = regatta()
        .args(["run", "--steps", "1", "--log"])
        .arg(&log)
        .arg(&world)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("8500 robots")
            && stderr.contains("65,534")
            && stderr.contains("--channels"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!log.exists(), "a half-written log was left behind");
    // The way out it names works.
    let few = dir.join("few.mcap");
    let logged = regatta()
        .args(["run", "--steps", "2", "--channels", "pose,visits", "--log"])
        .arg(&few)
        .arg(&world)
        .output()
        .unwrap();
    assert_eq!(
        logged.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&logged.stderr)
    );
    assert!(std::fs::metadata(&few).unwrap().len() > 100_000);
    std::fs::remove_dir_all(dir).ok();
}
