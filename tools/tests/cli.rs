//! The command line end to end: exit codes, standard input, formatting in place, the schema.
//! (These live beside the binary because Cargo only exposes a binary's path to its own
//! package's tests; the rest of the integration tests are in `tests/`.)

use std::io::Write;
use std::path::PathBuf;
use std::process::{Output, Stdio};

mod common;

use common::{regatta, root, run_logged};

fn run_with_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child = regatta()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("regatta runs");
    child.stdin.take().unwrap().write_all(input).unwrap();
    child.wait_with_output().unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir(&format!("cli-{name}"))
}

#[test]
fn project_worlds_check_clean() {
    let mut worlds: Vec<PathBuf> = std::fs::read_dir(root().join("worlds"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "wbt"))
        .collect();
    worlds.sort();
    assert!(worlds.len() >= 10, "{worlds:?}");
    let output = regatta().arg("check").args(&worlds).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "checked {} files: 0 errors, 0 warnings",
            worlds.len()
        )),
        "{stderr}"
    );
}

#[test]
fn errors_exit_1_with_file_line_col_caret_and_hint() {
    let output = run_with_stdin(
        &["check", "--color", "never", "-"],
        b"WorldInfo { coordinateSystem \"NUE\" }\nTransform {\n  translaton 0 1 0\n}\n",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: Unknown 'translaton' field in Transform node."),
        "{stderr}"
    );
    assert!(stderr.contains("<stdin>:3:3"), "{stderr}");
    assert!(stderr.contains("^^^^^^^^^^"), "{stderr}");
    assert!(stderr.contains("did you mean 'translation'?"), "{stderr}");
}

#[test]
fn lenient_mode_turns_unknown_nodes_into_warnings() {
    let input = b"#VRML_SIM R2023b utf8\nOilBarrel { height 1 }\n";
    let strict = run_with_stdin(&["check", "-"], input);
    assert_eq!(strict.status.code(), Some(1));
    let lenient = run_with_stdin(&["check", "--lenient", "-"], input);
    let stderr = String::from_utf8_lossy(&lenient.stderr);
    assert_eq!(lenient.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: Skipped unknown 'OilBarrel' node or PROTO."),
        "{stderr}"
    );
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(
        regatta().arg("check").output().unwrap().status.code(),
        Some(2)
    );
    assert_eq!(
        regatta()
            .arg("--no-such-flag")
            .output()
            .unwrap()
            .status
            .code(),
        Some(2)
    );
    assert_eq!(
        regatta().arg("frobnicate").output().unwrap().status.code(),
        Some(2)
    );
}

#[test]
fn unreadable_file_is_an_error_not_a_panic() {
    let output = regatta()
        .args(["check", "/nonexistent/world.wbt"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1));
    assert!(
        stderr.contains("cannot read /nonexistent/world.wbt"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
}

#[test]
fn fmt_prints_canonical_form_and_is_stable() {
    let input = b"#VRML_SIM R2023b utf8\nTransform{translation 1,2,3 # where\nchildren[Shape{geometry Box{}}]}\n";
    let once = run_with_stdin(&["fmt", "-"], input);
    assert_eq!(once.status.code(), Some(0));
    let text = String::from_utf8(once.stdout).unwrap();
    assert_eq!(
        text,
        "#VRML_SIM R2023b utf8\nTransform {\n  translation 1 2 3 # where\n  children [\n    Shape {\n      geometry Box {\n      }\n    }\n  ]\n}\n"
    );
    let twice = run_with_stdin(&["fmt", "-"], text.as_bytes());
    assert_eq!(String::from_utf8(twice.stdout).unwrap(), text);
    // --check says whether a file is canonical.
    let dir = temp_dir("fmt");
    let path = dir.join("world.wbt");
    std::fs::write(&path, input).unwrap();
    assert_eq!(
        regatta()
            .args(["fmt", "--check"])
            .arg(&path)
            .status()
            .unwrap()
            .code(),
        Some(1)
    );
    assert_eq!(
        regatta()
            .args(["fmt", "-w"])
            .arg(&path)
            .status()
            .unwrap()
            .code(),
        Some(0)
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
    assert_eq!(
        regatta()
            .args(["fmt", "--check"])
            .arg(&path)
            .status()
            .unwrap()
            .code(),
        Some(0)
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn fmt_refuses_a_file_with_syntax_errors_and_keeps_it() {
    let dir = temp_dir("fmt-broken");
    let path = dir.join("broken.wbt");
    let broken = "Transform { translation 1 2 3\n";
    std::fs::write(&path, broken).unwrap();
    let output = regatta().args(["fmt", "-w"]).arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), broken);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn schema_lists_fields_with_types_defaults_and_docs() {
    let output = regatta()
        .args(["schema", "PanoramicTurret"])
        .output()
        .unwrap();
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("## PanoramicTurret"));
    assert!(
        text.contains("| `optics` | SFString | `\"exact\"` | \"paper\", \"exact\" |"),
        "{text}"
    );
    let json = regatta()
        .args(["schema", "--format", "json"])
        .output()
        .unwrap();
    let text = String::from_utf8(json.stdout).unwrap();
    for node in [
        "WorldInfo",
        "Transform",
        "IndexedFaceSet",
        "DifferentialWheels",
        "DistanceSensor",
        "LightSensor",
        "LinearCamera",
    ] {
        assert!(
            text.contains(&format!("\"name\": \"{node}\"")),
            "{node} missing from the schema"
        );
    }
    let alias = regatta().args(["schema", "Pose"]).output().unwrap();
    assert!(String::from_utf8(alias.stdout)
        .unwrap()
        .contains("## Transform"));
    let unknown = regatta().args(["schema", "Transfrom"]).output().unwrap();
    assert_eq!(unknown.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("did you mean 'Transform'?"));
}

#[test]
fn a_closed_pipe_ends_quietly() {
    use std::io::Read;
    let mut child = regatta()
        .args(["schema", "--format", "json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // The reading end is dropped here, like `| head -c 16`.
    let output = child.wait_with_output().unwrap();
    assert!(!String::from_utf8_lossy(&output.stderr).contains("panicked"));
}

#[test]
fn logs_are_byte_identical_and_replay_verifies() {
    let dir = temp_dir("logs");
    let a = std::fs::read(run_logged(&dir, "a.mcap", "300")).unwrap();
    let b = std::fs::read(run_logged(&dir, "b.mcap", "300")).unwrap();
    assert!(a.len() > 1000);
    assert!(a == b, "the same world and seed give the same bytes");
    let replay = regatta()
        .args(["replay", "--verify"])
        .arg(dir.join("a.mcap"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&replay.stdout);
    assert_eq!(
        replay.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&replay.stderr)
    );
    assert!(text.starts_with("OK: "), "{text}");
    // Another seed is another run.
    let other = dir.join("c.mcap");
    regatta()
        .args(["run", "--steps", "300", "--seed", "9", "--log"])
        .arg(&other)
        .arg(root().join("worlds/regatta.wbt"))
        .status()
        .unwrap();
    assert!(std::fs::read(&other).unwrap() != a);
    std::fs::remove_dir_all(dir).ok();
}

/// A swarm with retinas logs the same bytes on 1 thread and on 4 (`RAYON_NUM_THREADS`), and
/// with `--threads 2`; the bench writes the swarm it measures.
#[test]
fn a_swarm_logs_the_same_bytes_on_any_number_of_threads() {
    let dir = temp_dir("threads");
    let written = regatta()
        .args(["bench", "step", "--robots", "30", "--write-worlds"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(
        written.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&written.stderr)
    );
    let world = dir.join("swarm-30.wbt");
    let run = |name: &str, threads: Option<&str>, flag: Option<&str>| {
        let log = dir.join(name);
        let mut command = regatta();
        command
            .args(["run", "--steps", "40", "--log"])
            .arg(&log)
            .arg(&world);
        if let Some(threads) = threads {
            command.env("RAYON_NUM_THREADS", threads);
        }
        if let Some(flag) = flag {
            command.args(["--threads", flag]);
        }
        let output = command.output().unwrap();
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        std::fs::read(log).unwrap()
    };
    let one = run("one.mcap", Some("1"), None);
    assert!(one.len() > 10_000);
    assert!(
        one == run("four.mcap", Some("4"), None),
        "1 and 4 threads differ"
    );
    assert!(
        one == run("two.mcap", None, Some("2")),
        "--threads 2 differs"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// `bench step --robots` measures generated swarms: a table, a CSV and a PNG.
#[test]
fn bench_step_measures_swarms_and_plots_them() {
    let dir = temp_dir("bench-swarm");
    let output = regatta()
        .args([
            "bench",
            "step",
            "--robots",
            "1,12",
            "--ir-only",
            "--millis",
            "20",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        text.contains("robot-steps/s") && text.contains("fitted exponent 1→12"),
        "{text}"
    );
    let csv = std::fs::read_to_string(dir.join("swarm-ir.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    let png = std::fs::read(dir.join("swarm-ir.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    std::fs::remove_dir_all(dir).ok();
}

/// A CSV's rows after its header, split at commas.
fn csv_rows(csv: &str) -> Vec<Vec<&str>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect()
}

/// `bench crowd --far-distances --keep-distances` adds a row per far and keep distance to
/// each crowd distance, and says which far distances it refuses.
#[test]
fn bench_crowd_measures_each_far_distance() {
    let dir = temp_dir("bench-crowd-far");
    let output = regatta()
        .args(["bench", "crowd", "--robots", "10", "--distances", "0.5"])
        .args(["--far-distances", "5", "--keep-distances", "0.05"])
        .args(["--viewers", "2", "--frames", "1", "--repeats", "1", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{text}");
    assert!(text.contains("0.5 m, far 5 m, keep 0.05 m"), "{text}");
    let csv = std::fs::read_to_string(dir.join("crowd.csv")).unwrap();
    let rows = csv_rows(&csv);
    // Exact, then 0.5 m without and with far 5 m, each without and with keep 5 cm: the
    // crowd, far and keep distance columns.
    let settings: Vec<(&str, &str, &str)> = rows.iter().map(|r| (r[1], r[2], r[3])).collect();
    assert_eq!(
        settings,
        [
            ("exact", "", ""),
            ("0.5", "", ""),
            ("0.5", "", "0.05"),
            ("0.5", "5", ""),
            ("0.5", "5", "0.05"),
        ],
        "{csv}"
    );
    std::fs::remove_dir_all(dir).ok();
    let refused = regatta()
        .args(["bench", "crowd", "--far-distances", "0"])
        .output()
        .unwrap();
    assert_ne!(refused.status.code(), Some(0));
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("is not a distance above 0 m"),
        "{}",
        String::from_utf8_lossy(&refused.stderr)
    );
}

/// `bench crowd` compares each crowd distance with every robot drawn: the exact row has no
/// error, a distance that leaves robots out some, and the CSV and chart are written.
#[test]
fn bench_crowd_measures_error_against_every_robot_drawn() {
    let dir = temp_dir("bench-crowd");
    let output = regatta()
        .args(["bench", "crowd", "--robots", "40", "--distances", "0.001,9"])
        .args([
            "--viewers",
            "6",
            "--frames",
            "2",
            "--spacing",
            "1",
            "--repeats",
            "1",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("crowd.csv")).unwrap();
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 3, "{csv}");
    // Found by its header, so that a column added to the file cannot shift it.
    let analog_column = csv
        .lines()
        .next()
        .and_then(|header| header.split(',').position(|c| c == "analog_rel_error_mean"))
        .unwrap_or_else(|| panic!("no analog_rel_error_mean column: {csv}"));
    let analog = |row: &[&str]| row[analog_column].parse::<f64>().unwrap();
    assert_eq!((rows[0][1], analog(&rows[0])), ("exact", 0.0), "{csv}");
    assert!(
        analog(&rows[1]) > 0.0,
        "leaving every robot out changed nothing: {csv}"
    );
    // 9 m reaches every robot of a 2 m arena: only the parts no photodiode sees and the
    // tucked wheels are left out (docs/crowd.md), far less than every robot.
    assert!(
        analog(&rows[2]) < 0.02 && analog(&rows[2]) < analog(&rows[1]) / 10.0,
        "9 m reaches every robot of a 2 m arena: {csv}"
    );
    assert!(std::fs::read(dir.join("crowd.png"))
        .unwrap()
        .starts_with(b"\x89PNG"));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn exported_csv_has_a_header_and_a_row_per_pose() {
    let dir = temp_dir("export");
    let log = run_logged(&dir, "run.mcap", "100");
    let out = dir.join("csv");
    let export = regatta()
        .args(["log", "export"])
        .arg(&log)
        .arg("--csv")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        export.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&export.stderr)
    );
    let pose = std::fs::read_to_string(out.join("pose.csv")).unwrap();
    let mut lines = pose.lines();
    assert_eq!(lines.next(), Some("step,t_ns,t,robot,x,z,heading"));
    // Integer steps and nanoseconds, and seconds written exactly: step 1 ends at 32 ms.
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("1,32000000,0.032000000,khepera,"),
        "{pose}"
    );
    assert_eq!(lines.count(), 99);
    assert!(
        pose.contains("\n100,3200000000,3.200000000,khepera,"),
        "{pose}"
    );
    for name in [
        "wheels.csv",
        "proximity.csv",
        "ambient.csv",
        "retina.csv",
        "units.csv",
    ] {
        assert!(out.join(name).exists(), "{name}");
    }
    let units = std::fs::read_to_string(out.join("units.csv")).unwrap();
    assert!(units.contains("pose,heading,rad,"), "{units}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn plot_draws_the_top_view_and_a_kymograph() {
    let dir = temp_dir("plot");
    let log = run_logged(&dir, "run.mcap", "200");
    let out = dir.join("plots");
    let plot = regatta()
        .arg("plot")
        .arg(&log)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        plot.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&plot.stderr)
    );
    for name in ["top.png", "khepera-kymograph.png"] {
        let bytes = std::fs::read(out.join(name)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{name} is a PNG");
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn gltf_exports_binary_and_text_and_animates_a_log() {
    let dir = temp_dir("gltf");
    let world = root().join("worlds/regatta.wbt");
    let glb = dir.join("arena.glb");
    let output = regatta()
        .arg("gltf")
        .arg(&world)
        .arg("-o")
        .arg(&glb)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );

    let text = dir.join("arena.gltf");
    let output = regatta()
        .arg("gltf")
        .arg(&world)
        .arg("-o")
        .arg(&text)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json = std::fs::read_to_string(&text).unwrap();
    assert!(json.contains("\"uri\": \"arena.bin\""), "{json}");
    assert!(dir.join("arena.bin").exists());

    let log = run_logged(&dir, "run", "40");
    let animated = dir.join("run.glb");
    let output = regatta()
        .arg("gltf")
        .arg(&world)
        .arg("--log")
        .arg(&log)
        .arg("-o")
        .arg(&animated)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("1 robot track(s) of up to 41 poses"),
        "{stderr}"
    );
    let size = std::fs::metadata(&animated).unwrap().len();
    assert!(size > bytes.len() as u64, "the animation adds data");
}

#[test]
fn gltf_refuses_bad_output_names_and_logs_of_other_worlds() {
    let dir = temp_dir("gltf-bad");
    let world = root().join("worlds/regatta.wbt");
    let output = regatta()
        .arg("gltf")
        .arg(&world)
        .arg("-o")
        .arg(dir.join("arena.obj"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("must end in .glb or .gltf"), "{stderr}");

    // A log whose robot the world does not have.
    let log = run_logged(&dir, "run", "5");
    let other = dir.join("other.wbt");
    std::fs::write(
        &other,
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nKhepera { name \"someone else\" }\n",
    )
    .unwrap();
    let output = regatta()
        .arg("gltf")
        .arg(&other)
        .arg("--log")
        .arg(&log)
        .arg("-o")
        .arg(dir.join("x.glb"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("is not in"), "{stderr}");
    assert!(!dir.join("x.glb").exists(), "nothing is written on error");

    // Garbage instead of a log.
    let garbage = dir.join("garbage.mcap");
    std::fs::write(&garbage, b"not a log at all").unwrap();
    let output = regatta()
        .arg("gltf")
        .arg(&world)
        .arg("--log")
        .arg(&garbage)
        .arg("-o")
        .arg(dir.join("y.glb"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("is not a regatta log"), "{stderr}");
}

#[test]
fn serve_and_drive_over_tcp_match_an_in_process_run() {
    use std::io::BufRead;
    let dir = temp_dir("serve");
    let world = root().join("worlds/regatta.wbt");
    let served_log = dir.join("served.mcap");
    let mut server = regatta()
        .args(["serve", "--tcp", "127.0.0.1:0", "--steps", "120", "--log"])
        .arg(&served_log)
        .arg(&world)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(server.stdout.take().unwrap()).lines();
    let banner = lines.next().unwrap().unwrap();
    let address = banner
        .split("tcp ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no address in {banner:?}"))
        .to_owned();
    let drive = regatta()
        .args([
            "drive",
            "--tcp",
            &address,
            "--controller",
            "regatta",
            "--steps",
            "120",
            "--period",
            "0",
        ])
        .output()
        .unwrap();
    let drive_out = String::from_utf8_lossy(&drive.stdout);
    assert!(
        drive.status.success(),
        "{drive_out}{}",
        String::from_utf8_lossy(&drive.stderr)
    );
    assert!(
        drive_out.contains("driving the simulated Khepera"),
        "{drive_out}"
    );
    let status = server.wait().unwrap();
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    assert!(status.success(), "{rest:?}");
    assert!(
        rest.iter().any(|l| l.starts_with("served 120 steps")),
        "{rest:?}"
    );

    let run_log = dir.join("run.mcap");
    let run = regatta()
        .args(["run", "--steps", "120", "--log"])
        .arg(&run_log)
        .arg(&world)
        .output()
        .unwrap();
    assert!(run.status.success());
    assert_eq!(
        std::fs::read(&run_log).unwrap(),
        std::fs::read(&served_log).unwrap(),
        "the served run's log differs from the in-process run's"
    );
}

#[test]
fn drive_reports_a_missing_robot_clearly_and_serve_an_unknown_name() {
    // Nothing listens on this port: connecting fails at once with the address in the message.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    drop(listener);
    let output = regatta()
        .args([
            "drive",
            "--tcp",
            &address,
            "--controller",
            "braitenberg",
            "--steps",
            "5",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("cannot connect to {address}")),
        "{stderr}"
    );

    let output = regatta()
        .args(["serve", "--tcp", "127.0.0.1:0", "--robot", "nobody"])
        .arg(root().join("worlds/regatta.wbt"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("has no robot named 'nobody' (it has: khepera)"),
        "{stderr}"
    );

    let output = regatta()
        .args(["drive", "--tcp", "127.0.0.1:1", "--controller", "nonsense"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot build controller 'nonsense'"),
        "{stderr}"
    );
}

#[test]
fn a_world_without_vision_never_starts_the_gpu() {
    let dir = temp_dir("no-vision");
    let world = dir.join("blind.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { }\nKhepera { controller \"braitenberg\" }\n",
    )
    .unwrap();
    let output = regatta()
        .args([
            "run",
            world.to_str().unwrap(),
            "--steps",
            "20",
            "--renderer",
            "wgpu",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("the GPU is not started"), "{stderr}");
    assert!(!String::from_utf8_lossy(&output.stdout).contains("vision rendered by"));
}

#[cfg(not(feature = "wgpu"))]
#[test]
fn the_wgpu_renderer_without_the_feature_is_a_clear_error() {
    let output = regatta()
        .current_dir(root())
        .args([
            "run",
            "worlds/regatta.wbt",
            "--steps",
            "5",
            "--renderer",
            "wgpu",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("built without the wgpu backend"),
        "{stderr}"
    );
    assert!(stderr.contains("--features wgpu"), "{stderr}");
}

/// With the feature: the regatta sails with the GPU rendering its retina (skipped, loudly,
/// where there is no adapter, unless REGATTA_REQUIRE_GPU=1).
#[cfg(feature = "wgpu")]
#[test]
fn run_and_render_with_wgpu() {
    let output = regatta()
        .current_dir(root())
        .args([
            "run",
            "worlds/regatta.wbt",
            "--duration",
            "60",
            "--renderer",
            "wgpu",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success()
        && stderr.contains("no GPU adapter")
        && std::env::var_os("REGATTA_REQUIRE_GPU").is_none()
    {
        eprintln!("skipped: {stderr}");
        return;
    }
    assert!(output.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("vision rendered by wgpu"), "{stdout}");
    assert!(stderr.contains("renders paper optics"), "{stderr}");
    // The regatta still emerges: buoys visited in cyclic order.
    let visits = stdout
        .split("buoy visits ")
        .nth(1)
        .and_then(|s| s.split(':').next())
        .and_then(|n| n.trim().parse::<u32>().ok())
        .expect("a buoy visit count");
    assert!(visits >= 3, "{stdout}");
    let output = regatta()
        .current_dir(root())
        .args([
            "render",
            "worlds/k213.wbt",
            "--renderer",
            "wgpu",
            "--format",
            "json",
        ])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(output.stdout.split(|&b| b == b'\n').next().unwrap()).unwrap();
    assert_eq!(json["digital"].as_array().unwrap().len(), 64);
}

/// No adapter (here: only a backend this platform lacks) is a clear error, never a panic.
#[cfg(feature = "wgpu")]
#[test]
fn no_gpu_adapter_is_a_clear_error() {
    let output = regatta()
        .current_dir(root())
        .env("WGPU_BACKEND", "dx12")
        .args([
            "run",
            "worlds/regatta.wbt",
            "--steps",
            "5",
            "--renderer",
            "wgpu",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no GPU adapter"), "{stderr}");
    assert!(stderr.contains("--renderer cpu"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn every_world_and_proto_in_the_repository_is_canonical() {
    let mut files = Vec::new();
    let mut folders = vec![
        root().join("worlds"),
        root().join("examples"),
        root().join("webots/tests/projects"),
    ];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path
                .extension()
                .is_some_and(|e| e == "wbt" || e == "proto" || e == "wrl")
            {
                files.push(path);
            }
        }
    }
    assert!(files.len() >= 6, "{files:?}");
    for file in files {
        let output = regatta()
            .args(["fmt", "--check"])
            .arg(&file)
            .output()
            .unwrap();
        assert_eq!(
            output.status.code(),
            Some(0),
            "{} is not canonical: regatta fmt -w it",
            file.display()
        );
    }
}

#[test]
fn csv_quotes_what_needs_it_and_is_byte_identical_run_to_run() {
    let dir = temp_dir("csv-quoting");
    let world = dir.join("named.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep 10 }\n\
         Arena { }\nKhepera { name \"scout, \\\"the first\\\"\" controller \"braitenberg\" }\n\
         Khepera { name \"second\" translation 0.2 0 0 }\n",
    )
    .unwrap();
    let mut exports = Vec::new();
    for k in 0..2 {
        let log = dir.join(format!("run{k}.mcap"));
        let run = regatta()
            .args(["run", "--steps", "25", "--seed", "7", "--log"])
            .arg(&log)
            .arg(&world)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let out = dir.join(format!("csv{k}"));
        let export = regatta()
            .args(["log", "export"])
            .arg(&log)
            .arg("--csv")
            .arg(&out)
            .output()
            .unwrap();
        assert!(export.status.success());
        exports.push(out);
    }
    let names: Vec<_> = std::fs::read_dir(&exports[0])
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(names.len() >= 5, "{names:?}");
    for name in names {
        assert_eq!(
            std::fs::read(exports[0].join(&name)).unwrap(),
            std::fs::read(exports[1].join(&name)).unwrap(),
            "{name:?} differs between two runs of the same world and seed"
        );
    }
    let pose = std::fs::read_to_string(exports[0].join("pose.csv")).unwrap();
    // The comma and the quotes survive, quoted as RFC 4180 says; times are exact.
    assert!(
        pose.contains("\n1,10000000,0.010000000,\"scout, \"\"the first\"\"\","),
        "{pose}"
    );
    assert!(
        pose.contains("\n25,250000000,0.250000000,second,"),
        "{pose}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn damaged_logs_are_refused_or_read_up_to_the_damage_never_a_crash() {
    let dir = temp_dir("damaged");
    let log = run_logged(&dir, "run.mcap", "200");
    let bytes = std::fs::read(&log).unwrap();
    // Deterministic damage all over the file: flipped bytes (chunk headers, lengths,
    // compressed data, CRCs), and cuts.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    for case in 0..24 {
        let mut damaged = bytes.clone();
        for _ in 0..1 + next(8) {
            let at = next(damaged.len());
            damaged[at] ^= 1 << next(8);
        }
        if case % 4 == 0 {
            damaged.truncate(next(damaged.len()));
        }
        let path = dir.join("damaged.mcap");
        std::fs::write(&path, &damaged).unwrap();
        for args in [
            vec!["log", "export", "{log}", "--csv", "{dir}/csv"],
            vec!["replay", "--verify", "{log}"],
            vec!["plot", "{log}", "--out", "{dir}/plots"],
        ] {
            let args: Vec<String> = args
                .iter()
                .map(|a| {
                    a.replace("{log}", path.to_str().unwrap())
                        .replace("{dir}", dir.to_str().unwrap())
                })
                .collect();
            let output = regatta().args(&args).output().unwrap();
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(
                matches!(output.status.code(), Some(0) | Some(1)) && !stderr.contains("panicked"),
                "case {case}, {args:?}: {:?}\n{stderr}",
                output.status
            );
        }
    }
    std::fs::remove_dir_all(dir).ok();
}
