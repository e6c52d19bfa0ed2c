//! The bad-input corpus (`tests/bad/`, see its README): every case runs through the real
//! command line, and its exit code and first diagnostic must match the `.expected` file beside
//! it (`REGATTA_BLESS=1` rewrites them). Whatever the case, nothing may panic or hang, and no
//! `# never:` text (a secret's bytes) may appear in what regatta prints.

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{regatta, root};
use regatta_tests::expect_file;

/// One case: its directives.
struct Case {
    /// Relative to `tests/bad`, with `/` separators.
    name: String,
    args: Vec<String>,
    stdin: bool,
    symlinks: Vec<(String, String)>,
    never: Vec<String>,
}

fn cases(dir: &Path, base: &Path, out: &mut Vec<Case>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            cases(&path, base, out);
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        if !text.lines().any(|l| l.starts_with("# case:")) {
            continue;
        }
        let name = path
            .strip_prefix(base)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let directive = |key: &str| -> Vec<String> {
            text.lines()
                .filter_map(|l| l.strip_prefix(&format!("# {key}:")))
                .map(|v| v.trim().to_owned())
                .collect()
        };
        let args = directive("args")
            .first()
            .cloned()
            .unwrap_or_else(|| "check {file}".to_owned())
            .split_whitespace()
            .map(|a| a.replace("{file}", &name))
            .collect();
        let folder = Path::new(&name)
            .parent()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let symlinks = directive("symlink")
            .iter()
            .map(|l| {
                let (link, target) = l.split_once("->").expect("symlink: NAME -> TARGET");
                (
                    format!("{folder}/{}", link.trim()),
                    target.trim().to_owned(),
                )
            })
            .collect();
        out.push(Case {
            name,
            args,
            stdin: text.lines().any(|l| l.trim() == "# stdin"),
            symlinks,
            never: directive("never"),
        });
    }
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// The first diagnostic of rendered output, as `file:line:col: severity: message`; when no
/// message has a place, the first `error:`/`warning:` line as it is; `(none)` when there is
/// none.
fn first_diagnostic(stderr: &str) -> String {
    let lines: Vec<&str> = stderr.lines().collect();
    let mut plain = None;
    for (i, line) in lines.iter().enumerate() {
        let Some((severity, message)) = ["error", "warning"]
            .iter()
            .find_map(|s| line.strip_prefix(&format!("{s}: ")).map(|m| (*s, m)))
        else {
            continue;
        };
        if let Some(place) = lines
            .get(i + 1)
            .and_then(|next| next.trim_start().strip_prefix("┌─ "))
        {
            return format!("{}: {severity}: {message}", place.trim());
        }
        plain.get_or_insert_with(|| line.to_string());
    }
    plain.unwrap_or_else(|| "(none)".to_owned())
}

#[test]
fn every_bad_input_gets_its_one_clear_error() {
    let source = root().join("tests/bad");
    let mut all = Vec::new();
    cases(&source, &source, &mut all);
    assert!(
        all.len() >= 60,
        "the bad-input corpus is missing ({})",
        all.len()
    );
    let work = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-bad-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    copy_tree(&source, &work);
    let mut failures = Vec::new();
    for case in &all {
        #[cfg(unix)]
        for (link, target) in &case.symlinks {
            std::os::unix::fs::symlink(target, work.join(link)).unwrap();
        }
        #[cfg(not(unix))]
        if !case.symlinks.is_empty() {
            continue;
        }
        let mut command = regatta();
        command
            .arg("--color")
            .arg("never")
            .args(&case.args)
            .current_dir(&work)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .stdin(if case.stdin {
                Stdio::from(std::fs::File::open(work.join(&case.name)).unwrap())
            } else {
                Stdio::null()
            });
        let mut child = command.spawn().unwrap();
        // Hang detection only (tests assert no timing): a case runs in well under a second.
        let started = Instant::now();
        while child.try_wait().unwrap().is_none() {
            if started.elapsed() > Duration::from_secs(120) {
                let _ = child.kill();
                failures.push(format!("{}: still running after 120 s", case.name));
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let output = child.wait_with_output().unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        if stderr.contains("panicked") || stderr.contains("overflowed its stack") {
            failures.push(format!("{}: crashed:\n{stderr}", case.name));
        }
        for secret in &case.never {
            if stderr.contains(secret.as_str()) || stdout.contains(secret.as_str()) {
                failures.push(format!("{}: printed '{secret}':\n{stderr}", case.name));
            }
        }
        let code = output
            .status
            .code()
            .map_or("killed".to_owned(), |c| c.to_string());
        let actual = format!("exit: {code}\nfirst: {}\n", first_diagnostic(&stderr));
        let expected = source.join(&case.name).with_extension("expected");
        if let Err(message) = expect_file(&expected, &actual) {
            failures.push(format!("{message}\n--- stderr:\n{stderr}"));
        }
        #[cfg(unix)]
        for (link, _) in &case.symlinks {
            let _ = std::fs::remove_file(work.join(link));
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
