//! Webots controllers run by `regatta run`: a C controller compiled and stepped in lock-step
//! (the e-puck project of webots/tests/projects), the same log on any thread count, a robot
//! built from hinge joints driving the arc its wheel speeds imply, controllers that crash,
//! hang, fail to compile or exit early (one clear error each), `--builtin-only`, and Webots'
//! own API tests from ../shared/webots.

mod common;

use std::path::{Path, PathBuf};

use common::{regatta, root, run_waiting_for_extern, temp_dir};

/// A cache of compiled controllers shared by these tests.
fn cache() -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-controller-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A project with one world and one C controller `name`.
fn project(world: &str, name: &str, source: &str) -> PathBuf {
    let dir = temp_dir("webots-project");
    std::fs::create_dir_all(dir.join("worlds")).unwrap();
    std::fs::create_dir_all(dir.join("controllers").join(name)).unwrap();
    std::fs::write(dir.join("worlds").join("w.wbt"), world).unwrap();
    std::fs::write(
        dir.join("controllers").join(name).join(format!("{name}.c")),
        source,
    )
    .unwrap();
    dir
}

fn run(world: &Path, args: &[&str]) -> std::process::Output {
    regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .arg("run")
        .arg(world)
        .args(args)
        .output()
        .unwrap()
}

/// The `NAME: at x X z Z heading H°` line of a run's summary.
fn pose(stdout: &str, robot: &str) -> (f64, f64, f64) {
    let line = stdout
        .lines()
        .find(|l| l.starts_with(&format!("{robot}: at x ")))
        .unwrap_or_else(|| panic!("no pose of {robot} in:\n{stdout}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let number = |w: &str| w.trim_end_matches(['°', ';']).parse::<f64>().unwrap();
    (number(words[3]), number(words[5]), number(words[7]))
}

const EPUCK: &str = "webots/tests/projects/avoid/worlds/epuck_avoid.wbt";

#[test]
fn a_c_controller_drives_the_e_puck_and_its_log_is_the_same_on_any_thread_count() {
    let dir = temp_dir("webots-threads");
    let world = root().join(EPUCK);
    let mut logs = Vec::new();
    for threads in ["1", "2"] {
        let log = dir.join(format!("run{threads}.mcap"));
        let output = run(
            &world,
            &[
                "--duration",
                "30",
                "--threads",
                threads,
                "--log",
                log.to_str().unwrap(),
            ],
        );
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stderr}");
        assert!(
            stderr.contains("runs its project's controller"),
            "the run says it runs the project's code: {stderr}"
        );
        // The controller's own output, behind the robot's name.
        assert!(stderr.contains("[e-puck] t = "), "{stderr}");
        let (x, z, _) = pose(&stdout, "e-puck");
        assert!(
            (x + 0.1).abs() + (z + 0.1).abs() > 0.1,
            "the e-puck moved from its start: {stdout}"
        );
        logs.push(std::fs::read(&log).unwrap());
    }
    assert!(logs[0] == logs[1], "the logs of 1 and 2 threads differ");
    program_records_are_in_the_log(&logs[0]);
}

/// The controller's lines and its LED's changes are in the log, at the steps they happened:
/// it prints `t = …` every 625 steps (20 s) and toggles led9 every 16 steps (0.512 s).
fn program_records_are_in_the_log(log: &[u8]) {
    use regatta_runtime::log::CdrReader;
    let contents = regatta_runtime::log::read(log).unwrap();
    let mut lines = Vec::new();
    let mut leds = Vec::new();
    for (topic, _, data) in &contents.messages {
        let mut r = CdrReader::new(data);
        match topic.as_str() {
            "/e_puck/output" => lines.push((r.f64().unwrap(), r.string().unwrap())),
            "/e_puck/leds" => {
                let t = r.f64().unwrap();
                let names = r.strings().unwrap();
                let count = r.u32().unwrap() as usize;
                let values: Vec<i32> = (0..count).map(|_| r.i32().unwrap()).collect();
                assert_eq!(names.len(), values.len());
                let led9 = names.iter().position(|n| n == "led9").unwrap();
                leds.push((t, values[led9]));
            }
            _ => {}
        }
    }
    assert_eq!(lines.len(), 1, "{lines:?}");
    let (t, line) = &lines[0];
    let printed: f64 = line
        .strip_prefix("t = ")
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!((t - printed).abs() < 1e-9, "stamped {t}, printed {line}");
    // 30 s: the LED changes at 0.032 s (first step) and every 0.512 s after.
    assert!(leds.len() >= 55, "{} LED changes", leds.len());
    for (i, pair) in leds.windows(2).enumerate() {
        assert!(
            (pair[1].0 - pair[0].0 - 0.512).abs() < 1e-9,
            "{i}: {pair:?}"
        );
        assert_ne!(pair[1].1, pair[0].1, "{i}: {pair:?}");
    }
}

/// A robot built as Webots' tutorials build them: a body and two wheel hinges.
const HINGE_WORLD: &str = r#"#VRML_SIM R2023b utf8
WorldInfo {
  basicTimeStep 16
}
Robot {
  children [
    HingeJoint {
      jointParameters HingeJointParameters {
        axis 0 1 0
        anchor 0 0 0.025
      }
      device [
        RotationalMotor {
          name "left wheel motor"
        }
        PositionSensor {
          name "left wheel sensor"
        }
      ]
      endPoint Solid {
        translation 0 0.045 0.025
        rotation 1 0 0 1.5708
        children [
          Shape {
            geometry Cylinder {
              height 0.01
              radius 0.025
            }
          }
        ]
      }
    }
    HingeJoint {
      jointParameters HingeJointParameters {
        axis 0 1 0
        anchor 0 0 0.025
      }
      device [
        RotationalMotor {
          name "right wheel motor"
        }
        PositionSensor {
          name "right wheel sensor"
        }
      ]
      endPoint Solid {
        translation 0 -0.045 0.025
        rotation 1 0 0 1.5708
        children [
          Shape {
            geometry Cylinder {
              height 0.01
              radius 0.025
            }
          }
        ]
      }
    }
  ]
  name "hinged"
  controller "arc"
}
"#;

const ARC: &str = r#"
#include <stdio.h>
#include <webots/motor.h>
#include <webots/position_sensor.h>
#include <webots/robot.h>

int main() {
  wb_robot_init();
  WbDeviceTag left = wb_robot_get_device("left wheel motor");
  WbDeviceTag right = wb_robot_get_device("right wheel motor");
  WbDeviceTag sensor = wb_robot_get_device("left wheel sensor");
  wb_position_sensor_enable(sensor, 16);
  wb_motor_set_position(left, INFINITY);
  wb_motor_set_position(right, INFINITY);
  wb_motor_set_velocity(left, 2.0);
  wb_motor_set_velocity(right, 4.0);
  while (wb_robot_step(16) != -1) {
    if (wb_robot_get_time() > 0.9599 && wb_robot_get_time() < 0.9601)
      printf("left wheel at %.6f rad\n", wb_position_sensor_get_value(sensor));
  }
  wb_robot_cleanup();
  return 0;
}
"#;

#[test]
fn a_robot_built_from_hinge_joints_drives_the_arc_its_wheel_speeds_imply() {
    let dir = project(HINGE_WORLD, "arc", ARC);
    let world = dir.join("worlds").join("w.wbt");
    let explain = regatta().arg("explain").arg(&world).output().unwrap();
    let text = String::from_utf8_lossy(&explain.stdout);
    assert!(
        text.contains("differential drive inferred from 2 wheel hinges"),
        "{text}"
    );
    let output = run(&world, &["--duration", "2"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    // 2 and 4 rad/s on 25 mm wheels, 90 mm apart: an arc of radius 0.135 m at 0.075 m/s.
    let (v, omega): (f64, f64) = (0.075, 0.05 / 0.09);
    let theta = omega * 2.0;
    let radius = v / omega;
    // The file is z-up: its (x, y) is regatta's (x, −z).
    let (x, z, heading) = pose(&stdout, "hinged");
    assert!((x - radius * theta.sin()).abs() < 2e-3, "{stdout}");
    assert!((-z - radius * (1.0 - theta.cos())).abs() < 2e-3, "{stdout}");
    assert!((heading - theta.to_degrees()).abs() < 0.2, "{stdout}");
    // Its position sensor: 2 rad/s for 0.96 s.
    assert!(stderr.contains("left wheel at 1.920000 rad"), "{stderr}");
}

const STILL_WORLD: &str = r#"#VRML_SIM R2023b utf8
WorldInfo {
}
Robot {
  name "r"
  controller "c"
}
"#;

fn fails_with(source: &str, args: &[&str], expected: &[&str]) {
    let dir = project(STILL_WORLD, "c", source);
    let log = dir.join("run.mcap");
    let mut args = args.to_vec();
    args.extend(["--log", log.to_str().unwrap()]);
    let output = run(&dir.join("worlds").join("w.wbt"), &args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    for text in expected {
        assert!(stderr.contains(text), "{text:?} not in:\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_controller_that_crashes_ends_the_run_with_one_clear_error() {
    fails_with(
        "#include <webots/robot.h>\nint main() { wb_robot_init(); wb_robot_step(32); int *p = 0; *p = 1; return 0; }\n",
        &["--duration", "5"],
        &["robot 'r': controller \"c\" failed", "SIGSEGV"],
    );
}

#[test]
fn a_controller_that_hangs_ends_the_run_after_its_timeout() {
    fails_with(
        "#include <webots/robot.h>\nint main() { wb_robot_init(); wb_robot_step(32); for (;;) {} }\n",
        &["--duration", "5", "--controller-timeout", "0.5"],
        &["robot 'r': controller \"c\"", "stopped answering"],
    );
}

#[test]
fn a_controller_that_does_not_compile_is_named_with_the_compilers_message() {
    fails_with(
        "int main( {\n",
        &["--duration", "1"],
        &["controller \"c\" does not compile", "c.c:1"],
    );
}

#[test]
fn a_controller_that_exits_early_with_an_error_ends_the_run() {
    fails_with(
        "#include <webots/robot.h>\nint main() { wb_robot_init(); wb_robot_step(32); return 3; }\n",
        &["--duration", "5"],
        &[
            "exited with status 3",
            "the log is complete up to the failed step",
        ],
    );
}

#[test]
fn builtin_only_runs_no_code_of_the_project() {
    let dir = project(
        STILL_WORLD,
        "c",
        "#include <stdio.h>\nint main() { printf(\"ran\\n\"); return 0; }\n",
    );
    let world = dir.join("worlds").join("w.wbt");
    let output = run(&world, &["--duration", "1", "--builtin-only"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("controller \"c\""), "{stderr}");
    assert!(!stderr.contains("ran"), "{stderr}");
    // Lenient: a built-in one runs instead, still no code of the project.
    let output = run(&world, &["--duration", "1", "--builtin-only", "--lenient"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(!stderr.contains("[r] ran"), "{stderr}");
    // `check` accepts the project's controller without running it.
    let output = regatta().arg("check").arg(&world).output().unwrap();
    assert!(output.status.success());
}

#[test]
fn webots_api_tests_pass_against_regatta() {
    let webots = root().join("../shared/webots");
    if !webots.join("tests/api").is_dir() {
        eprintln!("skipped: ../shared/webots is not there");
        return;
    }
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .arg("test-webots")
        .arg(&webots)
        .args(["--expect", "15"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    // Issue 38's target: 15 of the 18 that need no 3-D physics (the three others depend on
    // Webots' OpenGL shading or a texture on the network; README, "Webots' API tests").
    for test in [
        "compass",
        "gps",
        "inertial_unit",
        "device",
        "robot_data",
        "robot_synchronous_time",
        "distance_sensor_laser",
        "distance_sensor_sonar",
        "distance_sensor_resolution",
        "distance_sensor_enable_disable",
        "light_sensor_point_spot_light_no_occlusion",
        "emitter_receiver_enable_disable",
        "emitter_set_channel",
        "supervisor_get_from_def",
        "supervisor_simulation_mode",
    ] {
        let line = stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(test))
            .unwrap_or_else(|| panic!("{test} not run:\n{stdout}"));
        assert!(line.contains(" passed "), "{line}");
    }
}

#[test]
fn a_batch_of_a_c_controllers_world_reproduces_its_single_runs() {
    let world = root().join(EPUCK);
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
        let mut single: serde_json::Value = serde_json::from_slice(&single.stdout).unwrap();
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
fn an_extern_controller_started_by_hand_drives_its_robot() {
    let dir = temp_dir("webots-extern");
    std::fs::create_dir_all(dir.join("worlds")).unwrap();
    let world = dir.join("worlds").join("w.wbt");
    std::fs::write(
        &world,
        r#"#VRML_SIM R2023b utf8
EXTERNPROTO "webots://projects/robots/gctronic/e-puck/protos/E-puck.proto"
WorldInfo {
  basicTimeStep 32
}
E-puck {
  controller "<extern>"
}
"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("drive.c"),
        r#"#include <math.h>
#include <stdio.h>
#include <webots/motor.h>
#include <webots/robot.h>
int main() {
  wb_robot_init();
  WbDeviceTag l = wb_robot_get_device("left wheel motor");
  WbDeviceTag r = wb_robot_get_device("right wheel motor");
  wb_motor_set_position(l, INFINITY);
  wb_motor_set_position(r, INFINITY);
  wb_motor_set_velocity(l, 3.0);
  wb_motor_set_velocity(r, 3.0);
  int steps = 0;
  while (wb_robot_step(32) != -1)
    steps++;
  printf("stepped %d times\n", steps);
  return 0;
}
"#,
    )
    .unwrap();
    // The SDK a user builds an extern controller with.
    let sdk = dir.join("sdk");
    let output = regatta().arg("webots-sdk").arg(&sdk).output().unwrap();
    assert!(output.status.success());
    let compiled = std::process::Command::new("cc")
        .args(["-O2", "-I"])
        .arg(sdk.join("include"))
        .arg(dir.join("drive.c"))
        .arg(sdk.join("regatta_controller.c"))
        .args(["-lm", "-o"])
        .arg(dir.join("drive"))
        .status()
        .unwrap();
    assert!(compiled.success());
    let (run, url) = run_waiting_for_extern(&world, "2");
    let controller = std::process::Command::new(dir.join("drive"))
        .env("REGATTA_CONTROLLER_URL", &url)
        .output()
        .unwrap();
    assert!(controller.status.success());
    // 2 s of simulated time in 32 ms steps: the run ends at its 63rd step.
    assert_eq!(
        String::from_utf8_lossy(&controller.stdout).trim(),
        "stepped 62 times"
    );
    let output = run.wait_with_output().unwrap();
    assert!(output.status.success());
    let (x, _, _) = pose(&String::from_utf8_lossy(&output.stdout), "e-puck");
    // 3 rad/s on the e-puck's 20.5 mm wheels for 2.016 s.
    assert!((x - 3.0 * 0.0205 * 2.016).abs() < 0.01, "x = {x}");
}

#[test]
fn view_runs_a_projects_controller_as_run_does() {
    let world = root().join(EPUCK);
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .arg("view")
        .arg(&world)
        .args([
            "--exit",
            "--duration",
            "3",
            "--speed",
            "fast",
            "--port",
            "0",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("runs its project's controller"), "{stderr}");
    assert!(stdout.contains("simulated 3.008 s in 94 steps"), "{stdout}");
}

#[test]
fn controller_args_from_the_command_line_are_a_programs_arguments() {
    let dir = project(
        r#"#VRML_SIM R2023b utf8
EXTERNPROTO "webots://projects/robots/gctronic/e-puck/protos/E-puck.proto"
E-puck {
  controller "args"
  controllerArgs [ "from" "world" ]
}
"#,
        "args",
        r#"#include <stdio.h>
#include <webots/robot.h>
int main(int argc, char **argv) {
  wb_robot_init();
  for (int i = 1; i < argc; i++)
    printf("arg %d: %s\n", i, argv[i]);
  wb_robot_cleanup();
  return 0;
}
"#,
    );
    let world = dir.join("worlds").join("w.wbt");
    let output = run(&world, &["--duration", "0.1"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("[e-puck] arg 1: from") && stderr.contains("[e-puck] arg 2: world"),
        "{stderr}"
    );
    let output = run(
        &world,
        &["--duration", "0.1", "--controller-args", "given=1"],
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("[e-puck] arg 1: given=1"), "{stderr}");
    assert!(!stderr.contains("arg 2"), "{stderr}");
}

#[test]
fn the_e_pucks_ground_sensors_read_the_floor_through_webots_infra_red_model() {
    let dir = project(
        r#"#VRML_SIM R2023b utf8
EXTERNPROTO "webots://projects/objects/floors/protos/RectangleArena.proto"
EXTERNPROTO "webots://projects/robots/gctronic/e-puck/protos/E-puck.proto"
EXTERNPROTO "webots://projects/robots/gctronic/e-puck/protos/E-puckGroundSensors.proto"
RectangleArena {
}
E-puck {
  controller "ground"
  groundSensorsSlot [
    E-puckGroundSensors {
    }
  ]
}
"#,
        "ground",
        r#"#include <stdio.h>
#include <webots/distance_sensor.h>
#include <webots/robot.h>
int main() {
  wb_robot_init();
  WbDeviceTag gs[3];
  char name[4];
  for (int i = 0; i < 3; i++) {
    sprintf(name, "gs%d", i);
    gs[i] = wb_robot_get_device(name);
    wb_distance_sensor_enable(gs[i], 32);
  }
  int n = 0;
  while (wb_robot_step(32) != -1)
    if (++n == 3)
      printf("type %d gs %.1f %.1f %.1f\n", wb_distance_sensor_get_type(gs[1]), wb_distance_sensor_get_value(gs[0]),
             wb_distance_sensor_get_value(gs[1]), wb_distance_sensor_get_value(gs[2]));
  return 0;
}
"#,
    );
    let world = dir.join("worlds").join("w.wbt");
    let output = run(&world, &["--duration", "0.2"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find_map(|l| l.strip_prefix("[e-puck] type "))
        .unwrap_or_else(|| panic!("{stderr}"));
    let words: Vec<f64> = line
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    // WB_DISTANCE_SENSOR_INFRA_RED.
    assert_eq!(words[0], 1.0, "{line}");
    // 5 mm above the arena's floor (red 0.72): 0.005 / (0.2 + 0.8 × 0.72) m through the
    // module's table [0 1000, 0.016 300], with its noise of a few tenths of a percent.
    let expected = 1000.0 - 700.0 * (0.005 / (0.2 + 0.8 * 0.72)) / 0.016;
    for value in &words[1..] {
        assert!(
            (value - expected).abs() < 10.0,
            "{value} against {expected}: {line}"
        );
    }
}
