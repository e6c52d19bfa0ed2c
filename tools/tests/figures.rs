//! Figures and logs from the command line: `plot` (PNG and SVG, top view, kymograph, time
//! series), `log info`, and `--channels`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_owned()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-figures-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(output: Output) -> String {
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
}

fn run(dir: &Path, name: &str, steps: &str, extra: &[&str]) -> PathBuf {
    let log = dir.join(name);
    ok(regatta()
        .args(["run", "--steps", steps, "--log"])
        .arg(&log)
        .args(extra)
        .arg(root().join("worlds/regatta.wbt"))
        .output()
        .unwrap());
    log
}

#[test]
fn plot_writes_png_and_svg_figures_with_labelled_axes() {
    let dir = temp_dir("plot");
    let log = run(&dir, "run.mcap", "400", &[]);
    let png = dir.join("png");
    let printed = ok(regatta()
        .arg("plot")
        .arg(&log)
        .arg("--out")
        .arg(&png)
        .arg("--series")
        .output()
        .unwrap());
    for name in ["top.png", "khepera-kymograph.png", "khepera-series.png"] {
        let bytes = std::fs::read(png.join(name)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{name} is a PNG");
        assert!(printed.contains(name), "{printed}");
    }
    let svg = dir.join("svg");
    ok(regatta()
        .arg("plot")
        .arg(&log)
        .args([
            "--format",
            "svg",
            "--trajectory-color",
            "time",
            "--series",
            "--out",
        ])
        .arg(&svg)
        .output()
        .unwrap());
    for (name, labels) in [
        ("top.svg", vec!["x (m)", "z (m)", "time (s)", "khepera"]),
        (
            "khepera-kymograph.svg",
            vec![
                "azimuth (°, left of heading &gt; 0)",
                "simulated time (s)",
                "odd output, digital (LSB)",
                "λ = 5 px",
            ],
        ),
        (
            "khepera-series.svg",
            vec![
                "IR proximity (0–1023, higher is nearer), sensor pairs",
                "wheel speed (pulses / 10 ms): encoders, and the command in black",
                "simulated time (s)",
            ],
        ),
    ] {
        let text = std::fs::read_to_string(svg.join(name)).unwrap();
        assert!(text.starts_with("<svg"), "{name}");
        for label in labels {
            assert!(text.contains(label), "{name} has no '{label}'");
        }
    }
    // A bad option is a usage error; a log that is no log is an error, not a panic.
    let bad = regatta()
        .arg("plot")
        .arg(&log)
        .args(["--format", "gif"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(dir).ok();
}

/// The texts of an SVG file's `<text>` elements (unescaped enough for titles and numbers).
fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    svg.split("<text")
        .skip(1)
        .filter_map(|part| {
            let start = part.find('>')? + 1;
            let end = part.find("</text>")?;
            Some(
                part[start..end]
                    .trim()
                    .replace("&gt;", ">")
                    .replace("&amp;", "&"),
            )
        })
        .collect()
}

#[test]
fn a_time_window_narrows_every_figure_and_is_checked() {
    let dir = temp_dir("window");
    // 400 steps of 32 ms: 12.8 s.
    let log = run(&dir, "run.mcap", "400", &[]);
    let out = dir.join("window");
    ok(regatta()
        .arg("plot")
        .arg(&log)
        .args([
            "--format", "svg", "--series", "--from", "2", "--to", "10", "--rows", "50", "--out",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let top = svg_texts(&out.join("top.svg"));
    assert!(
        top.iter()
            .any(|t| t == "regatta.wbt, seed 1: 2–10 s of 12.8 s simulated"),
        "{top:?}"
    );
    // 250 frames in the window, 50 rows: five frames each; λ with its unit.
    let kymograph = svg_texts(&out.join("khepera-kymograph.svg"));
    assert!(
        kymograph
            .iter()
            .any(|t| t == "khepera: odd filter, λ = 5 px (rows: means of 5 frames)"),
        "{kymograph:?}"
    );
    let series = svg_texts(&out.join("khepera-series.svg"));
    assert!(
        series
            .iter()
            .any(|t| t == "khepera: sensors and wheels (seed 1), 2–10 s of 12.8 s simulated"),
        "{series:?}"
    );
    for label in [
        "IR 0, left",
        "IR 5, right",
        "left, command",
        "right, encoders",
        "sides",
    ] {
        assert!(
            series.iter().any(|t| t == label),
            "no '{label}' in {series:?}"
        );
    }
    // The time axes: ticks inside the window only (the kymograph's run downwards).
    for (name, texts) in [("kymograph", &kymograph), ("series", &series)] {
        assert!(
            texts.iter().any(|t| t == "2") && texts.iter().any(|t| t == "10"),
            "{name}: {texts:?}"
        );
        assert!(!texts.iter().any(|t| t == "12"), "{name}: {texts:?}");
    }
    // Rows that hold unequal numbers of frames say "about".
    ok(regatta()
        .arg("plot")
        .arg(&log)
        .args([
            "--format", "svg", "--from", "2", "--to", "10", "--rows", "60", "--out",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let kymograph = svg_texts(&out.join("khepera-kymograph.svg"));
    assert!(
        kymograph
            .iter()
            .any(|t| t == "khepera: odd filter, λ = 5 px (rows: means of about 4 frames)"),
        "{kymograph:?}"
    );
    // A window outside the log, empty or not a number: a clear error, and no figure.
    for (window, message) in [
        (
            vec!["--from", "20"],
            "--from 20 s is outside the log: the log covers 0 to 12.8 s of simulated time",
        ),
        (
            vec!["--from", "-1"],
            "--from -1 s is outside the log: the log covers 0 to 12.8 s of simulated time",
        ),
        (vec!["--to", "13"], "--to 13 s is outside the log"),
        (
            vec!["--from", "5", "--to", "3"],
            "the window is empty: --from 5 s must come before --to 3 s",
        ),
        (
            vec!["--to", "0"],
            "the window is empty: --from 0 s must come before --to 0 s",
        ),
        (
            vec!["--to", "NaN"],
            "--to must be a finite number of seconds, found NaN",
        ),
    ] {
        let none = dir.join("none");
        let output = regatta()
            .arg("plot")
            .arg(&log)
            .args(&window)
            .arg("--out")
            .arg(&none)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{window:?}: {stderr}");
        assert!(stderr.contains(message), "{window:?}: {stderr}");
        assert!(!none.exists(), "{window:?}");
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn log_info_lists_the_run_and_every_channel() {
    let dir = temp_dir("info");
    let log = run(&dir, "run.mcap", "100", &[]);
    let info = ok(regatta().args(["log", "info"]).arg(&log).output().unwrap());
    for expected in [
        "world:        ",
        "regatta.wbt",
        "seed:         1",
        "steps:        100 of 100 requested; complete",
        "duration:     3.200 s simulated",
    ] {
        assert!(info.contains(expected), "no '{expected}' in:\n{info}");
    }
    // One row per channel: topic, schema, messages, first and last time.
    let rows: Vec<Vec<&str>> = info
        .lines()
        .filter(|l| l.starts_with('/'))
        .map(|l| l.split_whitespace().collect())
        .collect();
    for (topic, schema, count) in [
        ("/khepera/pose", "regatta/msg/Pose", "100"),
        ("/khepera/retina", "regatta/msg/Retina", "100"),
        ("/khepera/contacts", "regatta/msg/Contact", "0"),
        ("/tf", "foxglove_msgs/msg/FrameTransform", "100"),
        ("/scene", "foxglove_msgs/msg/SceneUpdate", "1"),
        (
            "/khepera/world_pose",
            "foxglove_msgs/msg/PoseInFrame",
            "100",
        ),
        (
            "/khepera/retina/odd/image",
            "foxglove_msgs/msg/RawImage",
            "100",
        ),
        ("/events", "foxglove_msgs/msg/Log", "0"),
    ] {
        assert!(
            rows.iter().any(|r| r[..3] == [topic, schema, count]),
            "no row {topic} {schema} {count} in:\n{info}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn channels_pick_what_is_written_and_replay_covers_them() {
    let dir = temp_dir("channels");
    let log = run(&dir, "fox.mcap", "200", &["--channels", "foxglove,pose"]);
    let info = ok(regatta().args(["log", "info"]).arg(&log).output().unwrap());
    assert!(
        info.contains("channels:     pose,scene,tf,world_pose,images,events"),
        "{info}"
    );
    assert!(!info.contains("/khepera/retina "), "{info}");
    assert!(!info.contains("regatta/msg/Readings8"), "{info}");
    let replay = ok(regatta()
        .args(["replay", "--verify"])
        .arg(&log)
        .output()
        .unwrap());
    assert!(replay.starts_with("OK: "), "{replay}");
    let all = std::fs::metadata(run(&dir, "all.mcap", "200", &[]))
        .unwrap()
        .len();
    let regatta_only = std::fs::metadata(run(&dir, "own.mcap", "200", &["--channels", "regatta"]))
        .unwrap()
        .len();
    assert!(regatta_only < all);
    let bad = regatta()
        .args(["run", "--steps", "1", "--channels", "pose,nope", "--log"])
        .arg(dir.join("x.mcap"))
        .arg(root().join("worlds/regatta.wbt"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown channel 'nope'"));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn robots_with_spaces_in_their_names_keep_them_across_export_gltf_and_plot() {
    let dir = temp_dir("names");
    let world = dir.join("names.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { size 1 1 }\n\
         Khepera { name \"my robot\" translation 0.2 0 0.2 }\n\
         Khepera { name \"my-robot\" translation -0.2 0 0.2 }\n",
    )
    .unwrap();
    let log = dir.join("run.mcap");
    ok(regatta()
        .args(["run", "--steps", "50", "--log"])
        .arg(&log)
        .arg(&world)
        .output()
        .unwrap());
    let info = ok(regatta().args(["log", "info"]).arg(&log).output().unwrap());
    assert!(
        info.contains("/my_robot/pose ") && info.contains("/my_robot_2/pose "),
        "{info}"
    );
    ok(regatta()
        .args(["log", "export"])
        .arg(&log)
        .arg("--csv")
        .arg(dir.join("csv"))
        .output()
        .unwrap());
    let poses = std::fs::read_to_string(dir.join("csv/pose.csv")).unwrap();
    assert!(
        poses.contains(",my robot,") && poses.contains(",my-robot,"),
        "{poses}"
    );
    ok(regatta()
        .arg("gltf")
        .arg(&world)
        .arg("-o")
        .arg(dir.join("run.glb"))
        .arg("--log")
        .arg(&log)
        .output()
        .unwrap());
    let printed = ok(regatta()
        .arg("plot")
        .arg(&log)
        .arg("--out")
        .arg(dir.join("plots"))
        .output()
        .unwrap());
    assert!(printed.contains("top.png"), "{printed}");
    std::fs::remove_dir_all(dir).ok();
}
