//! Webots' own sample projects (../shared/webots/SAMPLES.tsv) run unchanged by `regatta run
//! --lenient` for 60 simulated seconds, each with its own controllers (C or Python), and show
//! the behaviour SAMPLES.tsv documents where regatta can show it; README's table of samples
//! says why the others cannot. Skipped when ../shared/webots is not there.

mod common;

use std::path::PathBuf;

use common::{regatta, root};

fn shared() -> Option<PathBuf> {
    let dir = root().join("../shared/webots");
    if dir.join("SAMPLES.tsv").is_file() {
        Some(dir)
    } else {
        eprintln!("skipped: ../shared/webots is not there");
        None
    }
}

/// A sample's 60-second run: its summary and its standard error.
struct Sample {
    summary: serde_json::Value,
    stderr: String,
}

fn sample(world: &str) -> Option<Sample> {
    let world = shared()?.join(world);
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-samples-cache-{}", std::process::id()));
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache)
        .env_remove("REGATTA_PYTHON")
        .arg("run")
        .arg("--lenient")
        .arg(&world)
        .args(["--duration", "60", "--json"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{}: {stderr}", world.display());
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert!(
        (summary["simulated_s"].as_f64().unwrap() - 60.0).abs() < 0.05,
        "{summary}"
    );
    Some(Sample { summary, stderr })
}

impl Sample {
    fn robot(&self, name: &str) -> &serde_json::Value {
        self.summary["robots"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["name"] == name)
            .unwrap_or_else(|| panic!("no robot {name} in {}", self.summary))
    }

    fn distance(&self, robot: &str) -> f64 {
        self.robot(robot)["distance_m"].as_f64().unwrap()
    }

    /// Runs its project's own controller, in `language`, for `robot`, and no API call failed.
    fn runs_its_own(&self, robot: &str, language: &str) {
        assert!(
            self.stderr.lines().any(|l| l.starts_with(&format!(
                "note: robot '{robot}' runs its project's controller"
            )) && l.contains(&format!("({language})"))),
            "{robot} runs its own {language} controller: {}",
            self.stderr
        );
        assert!(!self.stderr.contains("] Error: "), "{}", self.stderr);
        assert!(!self.stderr.contains("Traceback"), "{}", self.stderr);
    }

    fn lines_of(&self, robot: &str, text: &str) -> usize {
        let prefix = format!("[{robot}] {text}");
        self.stderr
            .lines()
            .filter(|l| l.starts_with(&prefix))
            .count()
    }
}

#[test]
fn led_sample_changes_its_leds_while_it_avoids_obstacles() {
    let Some(s) = sample("projects/samples/devices/worlds/led.wbt") else {
        return;
    };
    s.runs_its_own("MyBot", "Python");
    // LED 0 changes every 4 to 7 of its 64 ms steps: 937 steps, between 134 and 234 changes
    // (each printed as a colour or as turned off).
    let changes =
        s.lines_of("MyBot", "LED 0 uses color ") + s.lines_of("MyBot", "LED 0 is turned off");
    assert!((134..=235).contains(&changes), "{changes} changes of LED 0");
    assert!(s.distance("MyBot") > 1.0, "{}", s.summary);
}

#[test]
fn distance_sensor_sample_avoids_obstacles() {
    let Some(s) = sample("projects/samples/devices/worlds/distance_sensor.wbt") else {
        return;
    };
    s.runs_its_own("MyBot", "C");
    assert!(s.distance("MyBot") > 1.0, "{}", s.summary);
}

#[test]
fn gps_sample_moves_with_its_python_supervisor_beside_it() {
    let Some(s) = sample("projects/samples/devices/worlds/gps.wbt") else {
        return;
    };
    s.runs_its_own("MyBot", "Python");
    s.runs_its_own("gps_supervisor", "Python");
    assert_eq!(
        s.lines_of("MyBot", "Press 'G' to read the GPS device's position"),
        1
    );
    assert!(s.distance("MyBot") > 1.0, "{}", s.summary);
}

#[test]
fn emitter_receiver_sample_runs_both_robots_python_controller() {
    let Some(s) = sample("projects/samples/devices/worlds/emitter_receiver.wbt") else {
        return;
    };
    s.runs_its_own("MyBot emitter", "Python");
    s.runs_its_own("MyBot receiver", "Python");
    assert!(s.distance("MyBot receiver") > 1.0, "{}", s.summary);
    // The emitter's body is its bounding object (a 45 mm cylinder), not the 0.4 m translucent
    // sphere it shows around its emitter: it drives too, and comes within range.
    assert!(s.distance("MyBot emitter") > 1.0, "{}", s.summary);
    assert!(
        s.lines_of("MyBot receiver", "Communicating: received \"Hello!\"") >= 1,
        "{}",
        s.stderr
    );
}

#[test]
fn light_sensor_sample_drives_to_the_light_and_stops_there() {
    let Some(s) = sample("projects/samples/devices/worlds/light_sensor.wbt") else {
        return;
    };
    s.runs_its_own("MyBot", "C");
    // Webots' irradiance (the lamp's attenuation 0 0 5, unbounded) saturates both sensors'
    // tables near the lamp at (0, -0.1): the wheels stop there, nearer than the start (0.61 m).
    let pose = &s.robot("MyBot")["final_pose"];
    let (x, y) = (pose["x"].as_f64().unwrap(), -pose["z"].as_f64().unwrap());
    let distance = x.hypot(y + 0.1);
    assert!(distance < 0.35, "{distance} m from the lamp: {}", s.summary);
    assert_eq!(s.robot("MyBot")["contacts"]["events"], 0, "{}", s.summary);
}

#[test]
fn position_sensor_sample_runs_its_pid_loop() {
    let Some(s) = sample("projects/samples/devices/worlds/position_sensor.wbt") else {
        return;
    };
    s.runs_its_own("MyBot", "Python");
    // The pole is rigid (no 3-D physics): its angle stays 0, so the PID commands nothing,
    // every step; the controller prints its "fallen" line only when the run ends.
    let loops = s.lines_of("MyBot", "Position: +0.0000 -> control force: +0.0000");
    assert!(loops >= 3700, "{loops} loops of 3750 steps");
    assert_eq!(s.lines_of("MyBot", "Pole has fallen."), 1);
}

#[test]
fn python_example_slaves_avoid_obstacles_and_import_the_drivers_module() {
    let Some(s) = sample("projects/languages/python/worlds/example.wbt") else {
        return;
    };
    s.runs_its_own("Driver", "Python");
    // runtime.ini's PYTHONPATH=../driver/ lets each slave import the driver's `common`.
    for robot in ["robot1", "robot2", "robot3"] {
        s.runs_its_own(robot, "Python");
        assert_eq!(
            s.lines_of(
                robot,
                "This module is common to both driver and slave controllers (called from slave)."
            ),
            1,
            "{}",
            s.stderr
        );
        assert!(s.distance(robot) > 1.0, "{robot}: {}", s.summary);
    }
    assert_eq!(
        s.lines_of(
            "Driver",
            "This module is common to both driver and slave controllers (called from driver)."
        ),
        1
    );
}

#[test]
fn khepera_k213_sample_waits_64_seconds_before_it_moves() {
    let Some(s) = sample("projects/robots/k-team/khepera1/worlds/khepera_k213.wbt") else {
        return;
    };
    assert!(
        s.stderr.contains("runs its project's controller"),
        "{}",
        s.stderr
    );
    assert_eq!(s.distance("khepera"), 0.0, "{}", s.summary);
}

#[test]
fn khepera_sample_runs_braitenberg_without_touching_the_boxes() {
    let Some(s) = sample("projects/robots/k-team/khepera1/worlds/khepera.wbt") else {
        return;
    };
    assert!(s.distance("khepera") > 0.1, "{}", s.summary);
    assert_eq!(s.robot("khepera")["contacts"]["events"], 0, "{}", s.summary);
}

#[test]
fn the_python_twins_of_the_c_samples_drive_as_the_c_ones_do() {
    // distance_sensor and light_sensor have a C and a Python controller; regatta runs the C
    // one. Their Python controllers, alone in a copy of the project, behave as the C ones.
    let Some(webots) = shared() else {
        return;
    };
    let devices = webots.join("projects/samples/devices");
    let dir = common::temp_dir("python-twins");
    std::fs::create_dir_all(dir.join("worlds")).unwrap();
    for name in ["distance_sensor", "light_sensor"] {
        let world = format!("worlds/{name}.wbt");
        std::fs::copy(devices.join(&world), dir.join(&world)).unwrap();
        let folder = dir.join("controllers").join(name);
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::copy(
            devices.join(format!("controllers/{name}/{name}.py")),
            folder.join(format!("{name}.py")),
        )
        .unwrap();
        let c = sample(&format!("projects/samples/devices/{world}")).unwrap();
        let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("regatta-samples-cache-{}", std::process::id()));
        let output = regatta()
            .env("REGATTA_CACHE_DIR", cache)
            .env_remove("REGATTA_PYTHON")
            .args(["run", "--lenient"])
            .arg(dir.join(&world))
            .args(["--duration", "60", "--json"])
            .output()
            .unwrap();
        let python = Sample {
            summary: serde_json::from_slice(&output.stdout).unwrap(),
            stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        };
        python.runs_its_own("MyBot", "Python");
        if name == "distance_sensor" {
            // The Python twin turns on the spot (0.5, -0.5 rad/s) for its first 64 ms step
            // where the C one stands still: from there an avoider's path is its own. Both
            // avoid obstacles over more than a metre.
            assert!(c.distance("MyBot") > 1.0, "{}", c.summary);
            assert!(python.distance("MyBot") > 1.0, "{}", python.summary);
            continue;
        }
        // Both drive to the lamp and stop at the same place.
        let (a, b) = (c.robot("MyBot"), python.robot("MyBot"));
        for key in ["x", "z"] {
            let (a, b) = (
                a["final_pose"][key].as_f64().unwrap(),
                b["final_pose"][key].as_f64().unwrap(),
            );
            assert!((a - b).abs() < 0.02, "{name}: C ends at {a}, Python at {b}");
        }
    }
}

#[test]
fn e_puck_line_sample_runs_its_line_follower_on_a_floor_without_its_image() {
    let Some(s) = sample("projects/robots/gctronic/e-puck/worlds/e-puck_line.wbt") else {
        return;
    };
    s.runs_its_own("e-puck", "C");
    // Its floor image is a `webots://` url, which regatta never fetches (and ../shared does
    // not hold it): a warning at its line, and the floor reads plain. With no line to follow
    // the controller drives its obstacle-avoiding and line-seeking modules.
    assert!(
        s.stderr.contains("textures/floor.png") && s.stderr.contains("never fetches"),
        "{}",
        s.stderr
    );
    assert!(s.distance("e-puck") > 0.3, "{}", s.summary);
}

#[test]
fn e_puck_sample_avoids_the_boxes_and_reads_gravity_and_odometry() {
    let Some(s) = sample("projects/robots/gctronic/e-puck/worlds/e-puck.wbt") else {
        return;
    };
    s.runs_its_own("e-puck", "C");
    assert_eq!(s.robot("e-puck")["contacts"]["events"], 0, "{}", s.summary);
    // Its accelerometer reads gravity (noise aside), and its odometry grows to what it drove.
    let values = |prefix: &str| -> Vec<Vec<f64>> {
        s.stderr
            .lines()
            .filter_map(|l| l.strip_prefix(&format!("[e-puck] {prefix}")))
            .map(|rest| {
                rest.split_whitespace()
                    .filter_map(|w| w.trim_end_matches('.').parse().ok())
                    .collect()
            })
            .collect()
    };
    let gravity = values("accelerometer values = ");
    assert!(gravity.len() > 50, "{}", s.stderr);
    let mean = gravity.iter().map(|v| v[2]).sum::<f64>() / gravity.len() as f64;
    assert!((mean - 9.81).abs() < 0.1, "mean z {mean}");
    let left = values("estimated distance covered by left wheel: ");
    let last = left.last().unwrap()[0];
    assert!(last > 1.0 && last < s.distance("e-puck") * 1.5, "{last} m");
}
