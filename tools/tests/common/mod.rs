//! Helpers shared by the command line's end-to-end tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `regatta` binary of this build.
pub fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

/// The standard output of a command that must have succeeded (else its standard error).
pub fn ok(output: &Output) -> String {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    String::from_utf8(output.stdout.clone()).unwrap()
}

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tools/ has a parent")
        .to_owned()
}

/// A fresh folder for one test: `regatta-{name}-{process id}-{n}` in Cargo's temporary
/// directory for integration tests (`target/tmp`): the system's stays clean, and `cargo clean`
/// removes them.
pub fn temp_dir(name: &str) -> PathBuf {
    // Unique within the process too (tests run side by side), and emptied first: a folder
    // left by an earlier process with the same id would hold its files.
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-{name}-{}-{n}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `regatta run worlds/regatta.wbt --steps STEPS --log DIR/NAME`, which must succeed; the
/// log's path.
pub fn run_logged(dir: &Path, name: &str, steps: &str) -> PathBuf {
    let log = dir.join(name);
    let status = regatta()
        .args(["run", "--steps", steps, "--log"])
        .arg(&log)
        .arg(root().join("worlds/regatta.wbt"))
        .output()
        .unwrap();
    assert_eq!(
        status.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    log
}

/// `regatta run WORLD --duration SECONDS --extern`, started, and the REGATTA_CONTROLLER_URL it
/// prints for its `<extern>` robot (read from its standard error as it comes).
pub fn run_waiting_for_extern(world: &Path, seconds: &str) -> (std::process::Child, String) {
    use std::io::BufRead;
    let mut run = regatta()
        .arg("run")
        .arg(world)
        .args(["--duration", seconds, "--extern"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(run.stderr.take().unwrap());
    let mut line = String::new();
    while stderr.read_line(&mut line).unwrap() > 0 {
        if let Some(at) = line.find("REGATTA_CONTROLLER_URL=") {
            let rest = &line[at + "REGATTA_CONTROLLER_URL=".len()..];
            if let Some(url) = rest.split_whitespace().next() {
                return (run, url.to_owned());
            }
        }
        line.clear();
    }
    let _ = run.kill();
    let _ = run.wait();
    panic!("the run did not say where the extern controller connects");
}
