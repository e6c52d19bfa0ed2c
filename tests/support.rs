//! Helpers shared by the integration tests: where the corpus and test data are, and the
//! expect-file harness (`REGATTA_BLESS=1` rewrites expectations, as rust-analyzer's
//! `UPDATE_EXPECT` does).

use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_owned()
}

/// `../shared/corpus`, beside the checkout.
pub fn corpus() -> PathBuf {
    root().join("../shared/corpus")
}

/// Every file below `dir` whose extension is one of `extensions`, sorted.
pub fn files_with(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.contains(&e))
            {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Compares `actual` with the file `expected`; with `REGATTA_BLESS=1`, writes it instead.
/// Returns a description of the mismatch, if any.
pub fn expect_file(expected: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("REGATTA_BLESS").is_some() {
        std::fs::write(expected, actual)
            .map_err(|e| format!("cannot write {}: {e}", expected.display()))?;
        return Ok(());
    }
    let wanted = std::fs::read_to_string(expected).map_err(|e| {
        format!(
            "{}: {e} (run with REGATTA_BLESS=1 to create it)",
            expected.display()
        )
    })?;
    if wanted == actual {
        return Ok(());
    }
    let first_difference = wanted
        .lines()
        .zip(actual.lines())
        .position(|(a, b)| a != b)
        .unwrap_or_else(|| wanted.lines().count().min(actual.lines().count()));
    Err(format!(
        "{} differs at line {}:\n  expected: {:?}\n  actual:   {:?}\n(run with REGATTA_BLESS=1 to accept)",
        expected.display(),
        first_difference + 1,
        wanted.lines().nth(first_difference).unwrap_or("<end>"),
        actual.lines().nth(first_difference).unwrap_or("<end>")
    ))
}
