//! Logs of runs that end badly or cannot start: a log cut short still exports its complete
//! chunks, a signal ends a run with a complete log, a full disk and a killed recording are
//! reported and salvaged, and a swarm past MCAP's channel numbering is refused with the way
//! out (`--channels`), leaving no half-written file.

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;

use common::{regatta, root, run_logged};

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir(&format!("log-ends-{name}"))
}

/// Exports a log that ends early: it succeeds with a warning; returns the pose.csv line count.
fn export_cut_log(log: &Path, out: &Path) -> usize {
    let export = regatta()
        .args(["log", "export"])
        .arg(log)
        .arg("--csv")
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&export.stderr);
    assert_eq!(export.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning:") && stderr.contains("ends early"),
        "{stderr}"
    );
    std::fs::read_to_string(out.join("pose.csv"))
        .unwrap()
        .lines()
        .count()
}

#[test]
fn a_cut_log_still_exports_its_complete_chunks_and_garbage_is_an_error() {
    let dir = temp_dir("cut");
    let log = run_logged(&dir, "run.mcap", "3000");
    let bytes = std::fs::read(&log).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 4]).unwrap();
    let out = dir.join("csv");
    let rows = export_cut_log(&cut, &out);
    assert!(rows > 100 && rows < 3001, "{rows} rows");
    let garbage = dir.join("garbage.mcap");
    std::fs::write(&garbage, b"this is not an mcap file at all").unwrap();
    for args in [vec!["log", "export"], vec!["replay", "--verify"]] {
        let mut command = regatta();
        command.args(&args).arg(&garbage);
        if args[0] == "log" {
            command.arg("--csv").arg(&out);
        }
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains("is not a regatta log") && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

#[cfg(unix)]
/// Runs a long logged run, sends it `signal` once it has started, and checks that it ends
/// with 128 + signal and a complete log marked interrupted, which replays.
fn a_signal_ends_a_run_with_a_complete_log(signal: i32, name: &str) {
    let dir = temp_dir(&format!("interrupt-{signal}"));
    let log = dir.join("run.mcap");
    let child = regatta()
        .args(["run", "--steps", "100000000", "--log"])
        .arg(&log)
        .arg(root().join("worlds/regatta.wbt"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The log exists once the world is loaded and the handlers are installed.
    let started = std::time::Instant::now();
    while std::fs::metadata(&log).map_or(true, |m| m.len() == 0) && started.elapsed().as_secs() < 30
    {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    // SAFETY: sending a signal to our own child process.
    unsafe {
        libc::kill(child.id() as i32, signal);
    }
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(128 + signal), "{stderr}");
    assert!(
        stderr.contains(&format!("interrupted by {name} after"))
            && stderr.contains("marked interrupted"),
        "{stderr}"
    );
    // Complete: no warning on reading (summary and footer written); and it replays.
    let export = regatta()
        .args(["log", "export"])
        .arg(&log)
        .arg("--csv")
        .arg(dir.join("csv"))
        .output()
        .unwrap();
    assert!(
        export.status.success() && !String::from_utf8_lossy(&export.stderr).contains("warning"),
        "{}",
        String::from_utf8_lossy(&export.stderr)
    );
    let replay = regatta()
        .args(["replay", "--verify"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        String::from_utf8_lossy(&replay.stdout).starts_with("OK"),
        "{}",
        String::from_utf8_lossy(&replay.stdout)
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn ctrl_c_ends_a_run_with_exit_130_and_a_complete_log() {
    a_signal_ends_a_run_with_a_complete_log(libc::SIGINT, "SIGINT");
}

#[test]
fn sigterm_ends_a_run_with_exit_143_and_a_complete_log() {
    a_signal_ends_a_run_with_a_complete_log(libc::SIGTERM, "SIGTERM");
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_is_reported_as_such() {
    let output = regatta()
        .args(["run", "--steps", "3000", "--log", "/dev/full"])
        .arg(root().join("worlds/regatta.wbt"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write the log") && stderr.contains("No space left on device"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // A log that fails is cleaned up only where it is a plain file: the device stays.
    use std::os::unix::fs::FileTypeExt;
    let device = std::fs::symlink_metadata("/dev/full").unwrap().file_type();
    assert!(device.is_char_device(), "/dev/full is no longer a device");
}

#[cfg(unix)]
#[test]
fn a_recording_killed_with_sigkill_still_exports_its_complete_chunks() {
    let dir = temp_dir("sigkill");
    let log = dir.join("run.mcap");
    let mut child = regatta()
        .args(["run", "--steps", "100000000", "--log"])
        .arg(&log)
        .arg(root().join("worlds/regatta.wbt"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until at least one 1 MB chunk is on disk, then kill without warning.
    let started = std::time::Instant::now();
    while std::fs::metadata(&log).map(|m| m.len()).unwrap_or(0) < 3_000_000
        && started.elapsed().as_secs() < 60
    {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let rows = export_cut_log(&log, &dir.join("csv"));
    assert!(rows > 1000, "{rows} poses recovered");
    std::fs::remove_dir_all(dir).ok();
}

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
    let dir = temp_dir("swarm");
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
