//! Webots worlds, end to end through the `regatta` binary: the corpus's Khepera and e-puck
//! worlds run with every robot built and moving, at least 15 of Webots' 19 `.wbt` files run
//! and the rest are refused for the reasons listed, controllers are mapped or overridden,
//! and a robot driving off its floor is reported.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus")
}

fn run(world: &Path, extra: &[&str]) -> Output {
    let duration = if extra.contains(&"--duration") {
        &[][..]
    } else {
        &["--duration", "10"][..]
    };
    regatta()
        .arg("run")
        .arg(world)
        .arg("--lenient")
        .args(duration)
        .args(project_access(world))
        .args(extra)
        .output()
        .expect("regatta runs")
}

/// What a user gives a Webots project's world: its PROTOs live in `protos/` beside `worlds/`
/// (`--allow-path ..`), and a world without robots is run on purpose (`--allow-empty`).
fn project_access(world: &Path) -> Vec<String> {
    let mut flags = vec!["--allow-empty".to_owned()];
    let folder = world.parent().expect("a world is in a folder");
    if folder.file_name().is_some_and(|n| n == "worlds") {
        flags.push("--allow-path".to_owned());
        flags.push(folder.parent().expect("a project").display().to_string());
    }
    flags
}

fn text(output: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// (x, z) of each robot line of a run summary.
fn positions(stdout: &str) -> Vec<(f64, f64)> {
    stdout
        .lines()
        .filter_map(|line| {
            let rest = line.split_once(": at x ")?.1;
            let mut words = rest.split_whitespace();
            let x: f64 = words.next()?.parse().ok()?;
            words.next(); // "z"
            let z: f64 = words.next()?.trim_end_matches(';').parse().ok()?;
            Some((x, z))
        })
        .collect()
}

fn webots_worlds(folder: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![corpus().join(folder)];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("corpus folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "wbt") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

#[test]
fn khepera_and_epuck_worlds_run_with_every_robot_moving() {
    let mut checked = 0;
    for folder in ["webots", "webots-ext"] {
        for world in webots_worlds(folder) {
            let source = std::fs::read_to_string(&world).expect("readable");
            let robots = ["Khepera1 {", "Khepera2 {", "E-puck {", "E-puck_enu {"];
            if !robots.iter().any(|r| source.contains(r)) {
                continue;
            }
            checked += 1;
            // Two minutes: long enough for the gripper world's robot, which starts with the
            // stick dead ahead, to break the Braitenberg network's symmetric standstill.
            let output = run(&world, &["--duration", "120"]);
            let (stdout, stderr) = text(&output);
            assert!(
                output.status.success(),
                "{}: {stdout}{stderr}",
                world.display()
            );
            let moved = positions(&stdout);
            assert!(!moved.is_empty(), "{}: no robot: {stdout}", world.display());
            // Every robot left its start: compare with a run of no time.
            let start = regatta()
                .arg("run")
                .arg(&world)
                .args(["--lenient", "--steps", "0"])
                .args(project_access(&world))
                .output()
                .expect("regatta runs");
            let start = positions(&text(&start).0);
            for (a, b) in moved.iter().zip(&start) {
                let distance = ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();
                assert!(distance > 0.05, "{}: a robot did not move", world.display());
            }
            // Every warning says why: unknown nodes name their PROTO's url or reason, and
            // controllers say what runs instead.
            assert!(!stderr.contains("unknown node type\n   │\n\n"), "{stderr}");
        }
    }
    // The Khepera I, II and the e-puck at eight versions and the maze.
    assert!(checked >= 14, "only {checked} Khepera/e-puck worlds found");
}

#[test]
fn fifteen_of_webots_nineteen_worlds_run_and_the_rest_are_refused_for_their_reason() {
    let worlds = webots_worlds("webots");
    assert_eq!(worlds.len(), 19);
    let mut refused = Vec::new();
    for world in &worlds {
        let output = run(world, &[]);
        if !output.status.success() {
            let (_, stderr) = text(&output);
            let name = world.strip_prefix(corpus()).unwrap().display().to_string();
            refused.push((name, stderr));
        }
    }
    let names: Vec<&str> = refused.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "webots/projects/robots/blue_robotics/blueboat/worlds/ocean.wbt",
            "webots/projects/robots/clearpath/heron/worlds/ocean.wbt",
            "webots/tests/parser/worlds/empty_value.wbt",
            "webots/tests/parser/worlds/node_without_brackets.wbt",
        ]
    );
    assert!(refused[0]
        .1
        .contains("'BlueBoat' (its PROTO: ../protos/BlueBoat.proto)"));
    assert!(refused[1].1.contains("'Heron'"));
    assert!(refused[2]
        .1
        .contains("Expected floating point value, found 'direction'."));
    assert!(refused[3]
        .1
        .contains("Expected '{', found 'RectangleArena'."));
    assert!(worlds.len() - refused.len() >= 15);
}

#[test]
fn check_says_which_stand_ins_were_used() {
    let world = corpus().join("webots/projects/robots/k-team/khepera1/worlds/khepera.wbt");
    let output = regatta()
        .args(["check", "--lenient"])
        .arg(&world)
        .output()
        .expect("regatta runs");
    let (_, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains(
        "note: 'Khepera1' is regatta's built-in stand-in for webots://projects/robots/k-team/khepera1/protos/Khepera1.proto"
    ));
    assert!(stderr.contains("note: 'RectangleArena' is regatta's built-in stand-in"));
}

#[test]
fn controllers_are_mapped_refused_or_overridden() {
    let world = corpus().join("webots/projects/robots/k-team/khepera1/worlds/khepera_gripper.wbt");
    // Strict mode refuses a controller regatta does not have, naming it.
    let output = regatta()
        .arg("run")
        .arg(&world)
        .args(["--duration", "1"])
        .output()
        .expect("regatta runs");
    assert!(!output.status.success());
    // (strict typing stops at the world's unknown nodes first; lenient reads it)
    let output = regatta()
        .arg("run")
        .arg(&world)
        .args([
            "--lenient",
            "--duration",
            "1",
            "--controller",
            "nothing-like-this",
        ])
        .output()
        .expect("regatta runs");
    let (_, stderr) = text(&output);
    assert!(!output.status.success());
    assert!(
        stderr.contains("no controller \"nothing-like-this\""),
        "{stderr}"
    );
    // An override for one robot, with arguments; the idle controller keeps it in place.
    let output = run(&world, &["--controller", "khepera=none"]);
    let (stdout, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    let start = positions(&stdout)[0];
    assert!((start.0 - -0.0746).abs() < 1e-3, "{stdout}");
    let output = run(&world, &["--controller", "nobody=none"]);
    assert!(!output.status.success());
    assert!(text(&output).1.contains("no robot named 'nobody'"));
    // An <extern> robot: strict mode points at serve; lenient mode says what runs instead.
    let epuck = corpus().join(
        "webots-ext/cyberbotics+webots_ros2/_versions/R2022a/webots_ros2_epuck/worlds/epuck_world.wbt",
    );
    let output = run(&epuck, &[]);
    let (_, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("regatta serve WORLD --robot epuck"),
        "{stderr}"
    );
    assert!(
        stderr.contains("lenient mode runs \"braitenberg\" instead"),
        "{stderr}"
    );
}

#[test]
fn a_robot_driving_off_its_floor_is_reported_in_the_summary_and_the_log() {
    let dir = std::env::temp_dir().join(format!("regatta-falls-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let world = dir.join("off_the_edge.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nFloor { size 0.5 0.5 }\nKhepera1 { controller \"braitenberg\" }\n",
    )
    .unwrap();
    let log = dir.join("run.mcap");
    let output = regatta()
        .arg("run")
        .arg(&world)
        .args(["--duration", "10", "--log"])
        .arg(&log)
        .output()
        .expect("regatta runs");
    let (stdout, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    assert!(stdout.contains("fell off the floor at t "), "{stdout}");
    let bytes = std::fs::read(&log).unwrap();
    let needle = b"fell.Khepera";
    assert!(bytes.windows(needle.len()).any(|w| w == needle));
    std::fs::remove_dir_all(&dir).unwrap();
}
