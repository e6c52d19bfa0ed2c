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
            let robots = [
                "Khepera1 {",
                "Khepera2 {",
                "E-puck {",
                "E-puck_enu {",
                "Thymio2 {",
            ];
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
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-falls-{}", std::process::id()));
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

/// `regatta render` draws the 2-D cameras: the e-puck's 52×39 and the Khepera gripper world's
/// 64×64, enlarged four times, and their pixels as JSON.
#[test]
fn render_draws_the_epuck_and_gripper_cameras() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-cameras-{}", std::process::id()));
    let epuck =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/webots/e-puck_camera.wbt");
    let gripper =
        corpus().join("webots/projects/robots/k-team/khepera1/worlds/khepera_gripper.wbt");
    for (world, png, size) in [
        (&epuck, "e-puck-camera-camera.png", (52, 39)),
        (&gripper, "khepera-camera-camera.png", (64, 64)),
    ] {
        let output = regatta()
            .arg("render")
            .arg(world)
            .arg("--lenient")
            .arg("--out")
            .arg(&dir)
            .output()
            .expect("regatta runs");
        let (stdout, stderr) = text(&output);
        assert!(output.status.success(), "{stderr}");
        assert!(stdout.contains(png), "{stdout}");
        let picture = image::open(dir.join(png)).expect("a PNG").to_rgb8();
        assert_eq!(picture.dimensions(), (4 * size.0, 4 * size.1));
        let output = regatta()
            .arg("render")
            .arg(world)
            .args(["--lenient", "--format", "json"])
            .output()
            .expect("regatta runs");
        let (stdout, _) = text(&output);
        let line = stdout
            .lines()
            .find(|l| l.contains("\"device\":\"Camera\""))
            .expect("the camera's JSON");
        let value: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(value["width"], size.0);
        assert_eq!(
            value["rgb"].as_array().unwrap().len(),
            (3 * size.0 * size.1) as usize
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `batch` (and `evolve`, which loads worlds the same way) map Webots controller names as
/// `run` does, refuse what `run` refuses, and fall back in lenient mode as `run` does.
#[test]
fn batch_maps_webots_controllers_as_run_does() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-batch-webots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let world = |name: &str, controller: &str| {
        let path = dir.join(name);
        std::fs::write(
            &path,
            format!(
                "#VRML_SIM R2023b utf8\nRectangleArena {{ floorSize 1 1 }}\nE-puck {{ controller \"{controller}\" }}\n"
            ),
        )
        .unwrap();
        path
    };
    let batch = |path: &Path, extra: &[&str]| {
        regatta()
            .arg("batch")
            .arg(path)
            .args(["--seeds", "1", "--duration", "2", "--fitness", "avoidance"])
            .args(extra)
            .output()
            .expect("regatta runs")
    };
    let mapped = world("mapped.wbt", "e-puck_avoid_obstacles");
    let output = batch(&mapped, &[]);
    let (stdout, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("Webots controller \"e-puck_avoid_obstacles\""),
        "{stderr}"
    );
    let row: serde_json::Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
    assert_eq!(row["robots"][0]["controller"], "braitenberg", "{row}");
    // The same run as `run --json` gives, controller for controller.
    let single = regatta()
        .arg("run")
        .arg(&mapped)
        .args([
            "--seed",
            "1",
            "--duration",
            "2",
            "--json",
            "--fitness",
            "avoidance",
        ])
        .output()
        .unwrap();
    let (single_stdout, single_stderr) = text(&single);
    assert!(single.status.success(), "{single_stderr}");
    let single: serde_json::Value = serde_json::from_str(&single_stdout).unwrap();
    assert_eq!(row["fitness"], single["fitness"]);
    let unknown = world("unknown.wbt", "khepera_gripper");
    let output = batch(&unknown, &[]);
    assert!(!output.status.success());
    assert!(text(&output).1.contains("\"khepera_gripper\""));
    let output = batch(&unknown, &["--lenient"]);
    let (_, stderr) = text(&output);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("lenient mode runs \"braitenberg\" instead"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An `"<extern>"` e-puck (webots_ros2's world) is driven by `regatta serve`: a client over
/// TCP runs braitenberg through the Khepera protocol, and the served run records the same
/// poses, wheels and sensors as the same controller run in-process.
#[test]
fn an_extern_epuck_is_driven_by_serve() {
    use std::io::BufRead;
    use std::process::Stdio;
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-extern-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let world = corpus().join(
        "webots-ext/cyberbotics+webots_ros2/_versions/R2023b/webots_ros2_epuck/worlds/epuck_world.wbt",
    );
    let served_log = dir.join("served.mcap");
    let mut server = regatta()
        .arg("serve")
        .arg(&world)
        .args(["--lenient", "--tcp", "127.0.0.1:0", "--steps", "150"])
        .args(["--channels", "regatta", "--log"])
        .arg(&served_log)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(server.stdout.take().unwrap()).lines();
    let banner = lines.next().unwrap().unwrap();
    assert!(banner.contains("serving robot 'e-puck'"), "{banner}");
    let address = banner
        .split("tcp ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap()
        .to_owned();
    let drive = regatta()
        .args(["drive", "--tcp", &address, "--controller", "braitenberg"])
        .args(["--steps", "150", "--period", "0"])
        .output()
        .unwrap();
    assert!(drive.status.success(), "{:?}", text(&drive));
    assert!(server.wait().unwrap().success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    assert!(
        rest.iter().any(|l| l.starts_with("served 150 steps")),
        "{rest:?}"
    );
    let run_log = dir.join("run.mcap");
    let run = regatta()
        .arg("run")
        .arg(&world)
        .args([
            "--lenient",
            "--controller",
            "e-puck=braitenberg",
            "--steps",
            "150",
        ])
        .args(["--channels", "regatta", "--log"])
        .arg(&run_log)
        .output()
        .unwrap();
    assert!(run.status.success(), "{:?}", text(&run));
    for (log, csv) in [(&served_log, "served"), (&run_log, "run")] {
        let export = regatta()
            .args(["log", "export"])
            .arg(log)
            .arg("--csv")
            .arg(dir.join(csv))
            .output()
            .unwrap();
        assert!(export.status.success(), "{:?}", text(&export));
    }
    for channel in ["pose.csv", "wheels.csv", "proximity.csv"] {
        let served = std::fs::read_to_string(dir.join("served").join(channel)).unwrap();
        let run = std::fs::read_to_string(dir.join("run").join(channel)).unwrap();
        assert_eq!(served.lines().count(), 151, "{channel}");
        assert_eq!(
            served, run,
            "{channel} differs between served and in-process runs"
        );
    }
    // It moved.
    let poses = std::fs::read_to_string(dir.join("served/pose.csv")).unwrap();
    let last = poses.lines().last().unwrap();
    assert_ne!(
        poses.lines().nth(1).unwrap().split(',').nth(2),
        last.split(',').nth(2)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--proto-path` (and `REGATTA_PROTO_PATH`) finds `webots://` PROTOs in a folder under the
/// same file rules as the world's own urls: a link out of the folder is refused and named.
#[test]
fn proto_path_lookups_obey_the_file_rules() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-proto-path-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let webots = dir.join("webots");
    let protos = webots.join("projects/objects/misc/protos");
    std::fs::create_dir_all(&protos).unwrap();
    std::fs::create_dir_all(dir.join("world")).unwrap();
    std::fs::write(
        protos.join("Crate.proto"),
        "#VRML_SIM R2023b utf8\n# template language: javascript\nPROTO Crate [ field SFFloat side 0.1 ] {\n  Shape { geometry Box { size %<= fields.side.value >% %<= fields.side.value >% %<= fields.side.value * 2 >% } }\n}\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("secret.proto"),
        "#VRML_SIM R2023b utf8\nPROTO Secret [] { Group {} }\n",
    )
    .unwrap();
    let world = dir.join("world/w.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nEXTERNPROTO \"webots://projects/objects/misc/protos/Crate.proto\"\nEXTERNPROTO \"webots://projects/objects/misc/protos/Secret.proto\"\nCrate { side 0.2 }\nSecret { }\n",
    )
    .unwrap();
    // `..` out of the folder, to a file that exists: refused without a look.
    let climbing = dir.join("world/climbing.wbt");
    std::fs::write(
        &climbing,
        "#VRML_SIM R2023b utf8\nEXTERNPROTO \"webots://projects/../../secret.proto\"\nsecret { }\n",
    )
    .unwrap();
    let output = regatta()
        .arg("check")
        .arg(&climbing)
        .arg("--lenient")
        .arg("--proto-path")
        .arg(&webots)
        .output()
        .expect("regatta runs");
    let (_, stderr) = text(&output);
    assert!(!output.status.success(), "{stderr}");
    assert!(stderr.contains("leads outside that folder"), "{stderr}");
    assert!(stderr.contains("climbing.wbt:2:"), "{stderr}");
    let check = |env: bool| {
        let mut command = regatta();
        command.arg("check").arg(&world).arg("--lenient");
        if env {
            command.env("REGATTA_PROTO_PATH", &webots);
        } else {
            command.arg("--proto-path").arg(&webots);
        }
        command.output().expect("regatta runs")
    };
    let output = check(false);
    let (_, stderr) = text(&output);
    assert!(!stderr.contains("Crate"), "{stderr}");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(dir.join("secret.proto"), webots.join("Secret.proto")).unwrap();
        for env in [false, true] {
            let output = check(env);
            let (_, stderr) = text(&output);
            assert!(!output.status.success(), "{stderr}");
            assert!(
                stderr.contains("is a symbolic link to a place outside that folder"),
                "{stderr}"
            );
            assert!(!stderr.contains("Crate"), "{stderr}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
