//! Webots controllers written in Python, run by `regatta run` and `batch`: the e-puck's
//! avoider in Python drives the path of its C twin, with the same log on any thread count; a
//! supervisor resets and moves a robot between episodes and talks to another over an emitter;
//! an exception ends the run with the traceback and the robot's name; a missing interpreter is
//! one clear error; a batch reproduces single runs; and Webots' own Python samples
//! (../shared/webots/SAMPLES.tsv) run unchanged with their documented behaviour.
//!
//! The controllers run with `python3` from the PATH (or `$REGATTA_PYTHON`): the standard
//! library only, so CI's bare Python 3 runs them.

mod common;

use std::path::{Path, PathBuf};

use common::{regatta, root, run_waiting_for_extern, temp_dir};

fn cache() -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-python-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(world: &Path, args: &[&str]) -> std::process::Output {
    regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env_remove("REGATTA_PYTHON")
        .arg("run")
        .arg(world)
        .args(args)
        .output()
        .unwrap()
}

fn json(output: &std::process::Output) -> serde_json::Value {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    serde_json::from_slice(&output.stdout).unwrap_or_else(|e| panic!("{e}: {stderr}"))
}

/// The robot `name` of a `run --json` summary.
fn robot<'a>(summary: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    summary["robots"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["name"] == name)
        .unwrap_or_else(|| panic!("no robot {name} in {summary}"))
}

const AVOID: &str = "webots/tests/projects/avoid/worlds/epuck_avoid.wbt";
const AVOID_PY: &str = "webots/tests/projects/avoid/worlds/epuck_avoid_py.wbt";
const SUPERVISED: &str = "webots/tests/projects/python/worlds/supervised.wbt";

#[test]
fn a_python_controller_drives_the_path_of_its_c_twin_and_logs_the_same_on_any_thread_count() {
    let dir = temp_dir("python-threads");
    let mut logs = Vec::new();
    let mut poses = Vec::new();
    for threads in ["1", "2"] {
        let log = dir.join(format!("run{threads}.mcap"));
        let output = run(
            &root().join(AVOID_PY),
            &["--duration", "30", "--threads", threads, "--json"],
        );
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(
            stderr.contains("runs its project's controller") && stderr.contains("(Python)"),
            "the run says it runs the project's code: {stderr}"
        );
        assert!(stderr.contains("[e-puck] t = 20.000 s: ps0 "), "{stderr}");
        poses.push(robot(&json(&output), "e-puck")["final_pose"].clone());
        let output = run(
            &root().join(AVOID_PY),
            &[
                "--duration",
                "30",
                "--threads",
                threads,
                "--log",
                log.to_str().unwrap(),
            ],
        );
        assert!(output.status.success());
        logs.push(std::fs::read(&log).unwrap());
    }
    assert!(logs[0] == logs[1], "the logs of 1 and 2 threads differ");
    assert_eq!(poses[0], poses[1]);
    // The C controller computes the same numbers in the same order: the same path, bit for bit.
    let c = json(&run(&root().join(AVOID), &["--duration", "30", "--json"]));
    let c = &robot(&c, "e-puck")["final_pose"];
    assert_eq!(&poses[0], c, "Python and C drive different paths");
    let moved = (c["x"].as_f64().unwrap() + 0.1).abs() + (c["z"].as_f64().unwrap() + 0.1).abs();
    assert!(moved > 0.1, "the e-puck moved: {c}");
}

/// The numbers after `prefix` on the controller's line that starts with it.
fn numbers_after(stderr: &str, prefix: &str) -> Vec<Vec<f64>> {
    stderr
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .map(|rest| {
            rest.split_whitespace()
                .filter_map(|w| w.parse::<f64>().ok())
                .collect()
        })
        .collect()
}

#[test]
fn a_python_supervisor_resets_and_moves_a_robot_and_packets_reach_a_python_receiver() {
    // Three Python processes in lock-step: the same log on any thread count.
    let dir = temp_dir("python-supervised");
    let mut logs = Vec::new();
    for threads in ["1", "2"] {
        let log = dir.join(format!("run{threads}.mcap"));
        let output = run(
            &root().join(SUPERVISED),
            &[
                "--duration",
                "10",
                "--threads",
                threads,
                "--log",
                log.to_str().unwrap(),
            ],
        );
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        logs.push(std::fs::read(&log).unwrap());
    }
    assert!(logs[0] == logs[1], "the logs of 1 and 2 threads differ");
    let output = run(&root().join(SUPERVISED), &["--duration", "10"]);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    let start = &numbers_after(&stderr, "[trainer] start ")[0];
    assert_eq!(&start[..2], &[-0.2, 0.1], "{stderr}");
    assert!(stderr.contains("type E-puck"), "{stderr}");
    // Every episode starts where the first did (the reset puts the robot back), and the
    // episodes without a move end at the same place: the same simulation each time.
    let starts = numbers_after(&stderr, "[trainer] episode ");
    assert_eq!(
        starts.len(),
        8,
        "four episodes, each a start and an end: {stderr}"
    );
    let begins: Vec<&Vec<f64>> = starts.iter().step_by(2).collect();
    let ends: Vec<&Vec<f64>> = starts.iter().skip(1).step_by(2).collect();
    for begin in &begins {
        assert_eq!(begin[1..3], begins[0][1..3], "{stderr}");
        let near = (begin[1] - start[0]).abs() + (begin[2] - start[1]).abs();
        assert!(
            near < 0.01,
            "an episode starts at the robot's place: {stderr}"
        );
    }
    assert_eq!(ends[0][1..3], ends[1][1..3], "{stderr}");
    assert_eq!(ends[0][1..3], ends[3][1..3], "{stderr}");
    assert!(
        (ends[0][1] - begins[0][1]).abs() > 0.05,
        "the e-puck moves in an episode: {stderr}"
    );
    // setSFVec3f moved it in the third episode.
    let moved = &numbers_after(&stderr, "[trainer] moved to ")[0];
    assert!(
        (moved[0] - 0.2).abs() < 0.01 && (moved[1] + 0.2).abs() < 0.01,
        "{stderr}"
    );
    assert_ne!(ends[2][1..3], ends[0][1..3], "{stderr}");
    // The e-puck's camera through getImage (BGRA bytes), getImageArray ([x][y][rgb]) and
    // imageGetGray, which agree on the centre pixel.
    let camera = stderr
        .lines()
        .find_map(|l| {
            l.strip_prefix("[e-puck] camera 52x39: 8112 bytes, array 52x39x3, centre grey ")
        })
        .unwrap_or_else(|| panic!("{stderr}"));
    let numbers: Vec<u32> = camera
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|w| w.parse().ok())
        .collect();
    assert_eq!(numbers.len(), 4, "{camera}");
    assert!(numbers[0] > 0, "the camera sees the lit floor: {camera}");
    assert_eq!(
        numbers[0],
        (numbers[1] + numbers[2] + numbers[3]) / 3,
        "{camera}"
    );
    // The listener read the packets as text and as floats, two a step.
    assert!(stderr.contains("[listener] text t=0.032"), "{stderr}");
    assert!(stderr.contains("[listener] floats 0.032 0.064"), "{stderr}");
    assert!(
        stderr.contains("[listener] 312 packets in 5.024 s"),
        "{stderr}"
    );
}

/// A project with a world of one e-puck and a Python controller `name`.
fn project(name: &str, source: &str) -> PathBuf {
    let dir = temp_dir("python-project");
    std::fs::create_dir_all(dir.join("worlds")).unwrap();
    std::fs::create_dir_all(dir.join("controllers").join(name)).unwrap();
    let world = std::fs::read_to_string(root().join(AVOID)).unwrap();
    std::fs::write(
        dir.join("worlds").join("w.wbt"),
        world.replace(
            "controller \"epuck_avoid\"",
            &format!("controller \"{name}\""),
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("controllers")
            .join(name)
            .join(format!("{name}.py")),
        source,
    )
    .unwrap();
    dir.join("worlds").join("w.wbt")
}

#[test]
fn a_python_exception_ends_the_run_with_its_traceback_and_the_robots_name() {
    let world = project(
        "boom",
        "from controller import Robot\nrobot = Robot()\nn = 0\nwhile robot.step(32) != -1:\n    n += 1\n    if n == 10:\n        raise ValueError('bad value at step %d' % n)\n",
    );
    let log = world.with_file_name("run.mcap");
    let output = run(&world, &["--duration", "5", "--log", log.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(
        stderr.contains("[e-puck] Traceback (most recent call last):"),
        "{stderr}"
    );
    assert!(
        stderr.contains("[e-puck] ValueError: bad value at step 10"),
        "{stderr}"
    );
    assert!(
        stderr.contains("error: robot 'e-puck': controller \"boom\" failed at t = 0.320 s: it exited with status 1"),
        "{stderr}"
    );
    assert!(
        stderr.contains("the log is complete up to the failed step"),
        "{stderr}"
    );
    // The log is finished: it reads back.
    let info = regatta().args(["log", "info"]).arg(&log).output().unwrap();
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
}

#[test]
fn a_missing_python_is_one_clear_error_naming_the_robot_and_controller() {
    let world = project("calm", "from controller import Robot\nRobot()\n");
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env("REGATTA_PYTHON", "/nonexistent/python3")
        .arg("run")
        .arg(&world)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("robot 'e-puck': controller \"calm\" is written in Python: no Python interpreter \"/nonexistent/python3\""),
        "{stderr}"
    );
}

#[test]
fn a_python_script_that_never_creates_its_robot_is_named() {
    let world = project("idle", "print('no robot here')\n");
    let output = run(&world, &["--duration", "1"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(stderr.contains("[e-puck] no robot here"), "{stderr}");
    assert!(
        stderr.contains("robot 'e-puck': controller \"idle\" failed at t = 0.000 s: it exited with status 0 before connecting (did it call wb_robot_init, or create its Robot in Python?)"),
        "{stderr}"
    );
}

#[test]
fn a_controller_that_imports_a_module_that_is_not_there_is_named() {
    let world = project("needs", "import no_such_module_here\n");
    let output = run(&world, &["--duration", "1"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("[e-puck] ModuleNotFoundError: No module named 'no_such_module_here'"),
        "{stderr}"
    );
    assert!(
        stderr.contains("robot 'e-puck': controller \"needs\" failed"),
        "{stderr}"
    );
}

#[test]
fn a_batch_of_a_python_controllers_world_reproduces_its_single_runs() {
    let world = root().join(AVOID_PY);
    let batch = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .args(["batch", world.to_str().unwrap()])
        .args(["--seeds", "1..4", "-j", "2", "--duration", "10", "--json"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&batch.stderr);
    assert!(batch.status.success(), "{stderr}");
    let rows: Vec<serde_json::Value> = String::from_utf8_lossy(&batch.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 4);
    for row in rows {
        let seed = row["seed"].as_u64().unwrap().to_string();
        let single = run(&world, &["--seed", &seed, "--duration", "10", "--json"]);
        let mut single = json(&single);
        let single = single.as_object_mut().unwrap();
        single.retain(|key, _| row.get(key).is_some());
        for (key, value) in single.iter() {
            assert_eq!(&row[key], value, "seed {seed}: {key} differs");
        }
        assert!(
            row["robots"][0]["distance_m"].as_f64().unwrap() > 0.1,
            "{row}"
        );
    }
}

#[test]
fn a_batchs_python_exception_is_quoted_in_its_error() {
    // A batch does not show its controllers' output: the error quotes the traceback's end.
    let world = project(
        "boom",
        "from controller import Robot\nrobot = Robot()\nwhile robot.step(32) != -1:\n    if robot.getTime() > 0.3:\n        raise ValueError('bad value')\n",
    );
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env_remove("REGATTA_PYTHON")
        .args(["batch", world.to_str().unwrap()])
        .args(["--seeds", "1..2", "--duration", "2", "--json"])
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(text.contains("robot 'e-puck': controller \"boom\" failed at t = 0.320 s: it exited with status 1; its last words:"), "{text}");
    assert!(text.contains("ValueError: bad value"), "{text}");
    assert!(
        text.contains("Traceback (most recent call last):"),
        "{text}"
    );
}

#[test]
fn an_extern_python_controller_started_by_hand_drives_its_robot() {
    // What people who wrap Webots by hand do: their own Python process drives the robot,
    // with the `controller` package of `regatta webots-sdk`.
    let dir = temp_dir("python-extern");
    std::fs::create_dir_all(dir.join("worlds")).unwrap();
    let world = dir.join("worlds").join("w.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nEXTERNPROTO \"webots://projects/robots/gctronic/e-puck/protos/E-puck.proto\"\nWorldInfo {\n  basicTimeStep 32\n}\nE-puck {\n  controller \"<extern>\"\n}\n",
    )
    .unwrap();
    let sdk = dir.join("sdk");
    let output = regatta().arg("webots-sdk").arg(&sdk).output().unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(String::from_utf8_lossy(&output.stdout).contains("PYTHONPATH="));
    std::fs::write(
        dir.join("drive.py"),
        "from controller import Robot\nrobot = Robot()\nfor name in ('left wheel motor', 'right wheel motor'):\n    motor = robot.getDevice(name)\n    motor.setPosition(float('inf'))\n    motor.setVelocity(3.0)\nsteps = 0\nwhile robot.step(32) != -1:\n    steps += 1\nprint('stepped %d times' % steps)\n",
    )
    .unwrap();
    let (run, url) = run_waiting_for_extern(&world, "2");
    let controller = std::process::Command::new("python3")
        .arg(dir.join("drive.py"))
        .env("REGATTA_CONTROLLER_URL", &url)
        .env("PYTHONPATH", sdk.join("python"))
        .output()
        .unwrap();
    assert!(
        controller.status.success(),
        "{}",
        String::from_utf8_lossy(&controller.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&controller.stdout).trim(),
        "stepped 62 times"
    );
    let output = run.wait_with_output().unwrap();
    assert!(output.status.success());
    let stdout = String::from_utf8_lossy(&output.stdout);
    let x: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("e-puck: at x "))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    // 3 rad/s on the e-puck's 20.5 mm wheels for 2.016 s, as the C twin of this test drives.
    assert!((x - 3.0 * 0.0205 * 2.016).abs() < 0.01, "x = {x}");
}
