//! The Thymio II and Pi-puck (e-puck2) stand-ins end to end through the `regatta` binary:
//! regatta's own worlds for them are canonical and avoid walls, and the corpus's worlds that
//! use them check leniently and run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// (x, z, longest contact in s) of the one robot a run's summary reports.
fn summary(output: &Output) -> (f64, f64, f64) {
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout
        .lines()
        .find(|l| l.contains(": at x "))
        .unwrap_or_else(|| panic!("no robot line: {}", text(output)));
    let number = |after: &str| -> f64 {
        let rest = line.split_once(after).expect("summary field").1;
        rest.split([' ', ';'])
            .next()
            .and_then(|w| w.parse().ok())
            .expect("a number")
    };
    (number(": at x "), number(" z "), number("(longest "))
}

fn run_for(world: &Path, seconds: u32, lenient: bool) -> Output {
    let mut command = regatta();
    command
        .arg("run")
        .arg(world)
        .args(["--duration", &seconds.to_string()]);
    if lenient {
        command.arg("--lenient");
    }
    command.output().expect("regatta runs")
}

#[test]
fn thymio_and_epuck2_worlds_are_canonical_and_avoid_walls() {
    for name in ["thymio.wbt", "epuck2.wbt"] {
        let world = root().join("worlds").join(name);
        let fmt = regatta()
            .args(["fmt", "--check"])
            .arg(&world)
            .output()
            .expect("regatta runs");
        assert!(fmt.status.success(), "{name}: {}", text(&fmt));
        // The path through samples every 5 s of the first 30 (the runs are deterministic,
        // so each sample is the same run stopped earlier).
        let mut path = 0.0;
        let mut last = None;
        for seconds in (0..=30).step_by(5) {
            let output = run_for(&world, seconds, false);
            assert!(output.status.success(), "{name}: {}", text(&output));
            let (x, z, _) = summary(&output);
            if let Some((x0, z0)) = last {
                path += f64::hypot(x - x0, z - z0);
            }
            last = Some((x, z));
        }
        assert!(
            path > 0.5,
            "{name}: the robot went only {path:.3} m in 30 s"
        );
        // A minute among walls and boxes without pushing against any for a second.
        let output = run_for(&world, 60, false);
        assert!(output.status.success(), "{name}: {}", text(&output));
        let (_, _, longest) = summary(&output);
        assert!(longest < 1.0, "{name}: a contact lasted {longest} s");
    }
}

fn corpus_worlds_with(needles: &[&str]) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![root().join("../shared/corpus")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("corpus folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "wbt") {
                let source = std::fs::read_to_string(&path).unwrap_or_default();
                if needles.iter().any(|n| source.contains(n)) {
                    found.push(path);
                }
            }
        }
    }
    found.sort();
    found
}

#[test]
fn corpus_thymio_and_pi_puck_worlds_check_leniently_and_run() {
    let worlds = corpus_worlds_with(&["Thymio2 {", "Pi-puck {"]);
    // webots_ros2's e-puck worlds at eight versions and its rats' life maze (Pi-puck), its
    // R2019b ROS example and the syllabus's obstacle avoidance benchmark (Thymio II).
    assert!(worlds.len() >= 11, "only {} worlds found", worlds.len());
    for world in &worlds {
        let shown = world.display();
        let check = regatta()
            .args(["check", "--lenient"])
            .arg(world)
            .output()
            .expect("regatta runs");
        let said = text(&check);
        assert!(check.status.success(), "{shown}: {said}");
        assert!(
            said.contains("'Thymio2' is regatta's built-in stand-in")
                || said.contains("'Pi-puck' is regatta's built-in stand-in"),
            "{shown}: {said}"
        );
        // Other Webots objects these worlds hold (the benchmark's furniture) are skipped with
        // a warning; the robots never are.
        for robot in ["Thymio2", "Pi-puck", "E-puck"] {
            let skipped = format!("Skipped unknown '{robot}'");
            assert!(!said.contains(&skipped), "{shown}: {said}");
        }
        let output = run_for(world, 5, true);
        assert!(output.status.success(), "{shown}: {}", text(&output));
        let (x, z, _) = summary(&output);
        assert!(x.is_finite() && z.is_finite(), "{shown}");
    }
}
