//! `regatta test-webots DIR`: Webots' own API tests, run against regatta. DIR is laid out like
//! a Webots installation (`tests/api/worlds`, `tests/api/controllers`, `tests/lib`); each test
//! world runs its C controller, which checks what the controller API returns and prints
//! `OK: NAME` or `FAILURE with NAME: …`. The tests write their results beside themselves
//! (`../../../output.txt`), so they run from a copy of `tests/` in a temporary folder: the
//! installation is read, never written.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The Webots installation (or a folder laid out like one) whose tests/api to run.
    webots: PathBuf,
    /// Only the tests whose name contains this text; repeatable.
    #[arg(long)]
    only: Vec<String>,
    /// Simulated time a test may run (s).
    #[arg(long, default_value_t = 30.0)]
    duration: f64,
    /// Wall-clock time a test may take (s).
    #[arg(long, default_value_t = 60.0)]
    timeout: f64,
    /// Also write the table as tab-separated values to this file.
    #[arg(long, value_name = "FILE.tsv")]
    tsv: Option<PathBuf>,
    /// Fail (exit 1) unless at least this many tests pass.
    #[arg(long, value_name = "N")]
    expect: Option<usize>,
}

/// One test of the suite, as `TESTS.tsv` describes it.
struct Test {
    name: String,
    world: PathBuf,
    physics: Option<bool>,
}

/// What a test's run printed.
#[derive(Debug, PartialEq)]
enum Verdict {
    Passed,
    Failed(String),
    /// Neither OK nor FAILURE was printed: the last error regatta gave, if any.
    Silent(String),
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let api = args.webots.join("tests").join("api");
    if !api.join("worlds").is_dir() {
        bail!(
            "{} has no tests/api/worlds: point at a Webots installation (or ../shared/webots)",
            args.webots.display()
        );
    }
    let tests = list_tests(&args.webots, &api)?
        .into_iter()
        .filter(|t| args.only.is_empty() || args.only.iter().any(|o| t.name.contains(o)))
        .collect::<Vec<_>>();
    if tests.is_empty() {
        bail!("no test to run");
    }
    let scratch = std::env::temp_dir().join(format!("regatta-test-webots-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    copy_tree(&args.webots.join("tests"), &scratch.join("tests"))
        .with_context(|| format!("cannot copy the tests into {}", scratch.display()))?;
    let me = std::env::current_exe().context("cannot find regatta's own executable")?;
    let mut rows = Vec::new();
    println!(
        "{:<48} {:<8} {:<10} {:>7}  first failure",
        "test", "physics", "result", "time"
    );
    for test in &tests {
        let world = scratch.join(test.world.strip_prefix(&args.webots).unwrap_or(&test.world));
        let started = Instant::now();
        let output = run_one(&me, &scratch, &args, &world)?;
        let seconds = started.elapsed().as_secs_f64();
        let verdict = verdict(&output);
        let (result, message) = match &verdict {
            Verdict::Passed => ("passed", String::new()),
            Verdict::Failed(m) => ("failed", m.clone()),
            Verdict::Silent(m) => ("no verdict", m.clone()),
        };
        let physics = match test.physics {
            Some(true) => "yes",
            Some(false) => "no",
            None => "?",
        };
        println!(
            "{:<48} {physics:<8} {result:<10} {:>6.2}s  {}",
            test.name,
            seconds,
            shorten(&message, 100)
        );
        rows.push((test.name.clone(), physics, result, seconds, message));
    }
    let _ = std::fs::remove_dir_all(&scratch);
    let passed = rows.iter().filter(|r| r.2 == "passed").count();
    let without_physics = rows.iter().filter(|r| r.1 == "no").count();
    let passed_without = rows
        .iter()
        .filter(|r| r.1 == "no" && r.2 == "passed")
        .count();
    println!(
        "{passed} of {} passed ({passed_without} of {without_physics} that need no 3-D physics)",
        rows.len()
    );
    if let Some(path) = &args.tsv {
        let mut text = String::from("test\tneeds_3d_physics\tresult\tseconds\tfirst_failure\n");
        for (name, physics, result, seconds, message) in &rows {
            text.push_str(&format!(
                "{name}\t{physics}\t{result}\t{seconds:.3}\t{}\n",
                message.replace(['\t', '\n'], " ")
            ));
        }
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    match args.expect {
        Some(n) if passed < n => {
            eprintln!("error: {passed} tests passed, fewer than the {n} expected");
            Ok(Outcome::Errors)
        }
        _ => Ok(Outcome::Clean),
    }
}

/// The tests `TESTS.tsv` lists (or every world, when there is none).
fn list_tests(webots: &Path, api: &Path) -> anyhow::Result<Vec<Test>> {
    let table = api.join("TESTS.tsv");
    if let Ok(text) = std::fs::read_to_string(&table) {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split('\t').collect();
        let column = |name: &str| header.iter().position(|h| *h == name);
        let (Some(name), Some(world)) = (column("test"), column("world")) else {
            bail!("{}: no test and world columns", table.display());
        };
        let physics = column("needs_3d_physics");
        let mut tests = Vec::new();
        for line in lines.filter(|l| !l.trim().is_empty()) {
            let cells: Vec<&str> = line.split('\t').collect();
            let (Some(n), Some(w)) = (cells.get(name), cells.get(world)) else {
                continue;
            };
            tests.push(Test {
                name: n.to_string(),
                world: webots.join(w),
                physics: physics.and_then(|p| cells.get(p)).map(|c| *c == "yes"),
            });
        }
        return Ok(tests);
    }
    let mut tests = Vec::new();
    for entry in std::fs::read_dir(api.join("worlds"))? {
        let path = entry?.path();
        if path.extension().is_some_and(|e| e == "wbt") {
            tests.push(Test {
                name: path
                    .file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into(),
                world: path,
                physics: None,
            });
        }
    }
    tests.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(tests)
}

/// Runs one test world through `regatta run`, returning what it printed.
fn run_one(me: &Path, scratch: &Path, args: &Args, world: &Path) -> anyhow::Result<String> {
    let out_path = scratch.join("run.out");
    let out = std::fs::File::create(&out_path)?;
    let mut child = Command::new(me)
        .arg("--proto-path")
        .arg(scratch)
        .arg("--proto-path")
        .arg(&args.webots)
        .args(["run", "--lenient", "--duration"])
        .arg(args.duration.to_string())
        .arg(world)
        .stdin(Stdio::null())
        .stdout(out.try_clone()?)
        .stderr(out)
        .spawn()
        .context("cannot start regatta run")?;
    let deadline = Instant::now() + Duration::from_secs_f64(args.timeout);
    loop {
        if child.try_wait()?.is_some() {
            break;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            let mut text = std::fs::read_to_string(&out_path).unwrap_or_default();
            text.push_str(&format!(
                "\nerror: the test took longer than {} s of wall time\n",
                args.timeout
            ));
            return Ok(text);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(String::from_utf8_lossy(&std::fs::read(&out_path)?).into_owned())
}

fn verdict(output: &str) -> Verdict {
    let mut passed = false;
    for line in output.lines() {
        if let Some(at) = line.find("FAILURE with ") {
            return Verdict::Failed(line[at..].to_owned());
        }
        if line.contains("OK: ") {
            passed = true;
        }
    }
    if passed {
        return Verdict::Passed;
    }
    let last_error = output
        .lines()
        .rfind(|l| l.starts_with("error") || l.contains("Error"))
        .unwrap_or("the controller printed neither OK nor FAILURE");
    Verdict::Silent(last_error.to_owned())
}

fn shorten(text: &str, at: usize) -> String {
    match text.char_indices().nth(at) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text.to_owned(),
    }
}

/// Copies folders and regular files (links are skipped: the copy holds nothing from outside).
fn copy_tree(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let kind = entry.file_type()?;
        let target = to.join(entry.file_name());
        if kind.is_dir() {
            copy_tree(&entry.path(), &target)?;
        } else if kind.is_file() {
            std::fs::copy(entry.path(), &target)?;
            // The copy is the tests' own to write in, whatever the installation's modes.
            let mut permissions = std::fs::metadata(&target)?.permissions();
            #[allow(clippy::permissions_set_readonly_false)]
            permissions.set_readonly(false);
            std::fs::set_permissions(&target, permissions)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_read_the_suites_lines() {
        assert_eq!(verdict("[robot] OK: gps\n"), Verdict::Passed);
        assert_eq!(
            verdict("[r] FAILURE with gps: The X value\n[r] OK: x"),
            Verdict::Failed("FAILURE with gps: The X value".into())
        );
        assert!(matches!(verdict("error: boom\n"), Verdict::Silent(m) if m == "error: boom"));
    }
}
