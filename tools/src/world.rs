//! Loading a world for the commands that run it: check (printing diagnostics), then compile.

use std::path::Path;

use anyhow::bail;
use regatta_runtime::{compile, Compiled};
use regatta_schema::{check_file, Checked};

/// A checked and compiled world.
pub struct Loaded {
    pub checked: Checked,
    pub compiled: Compiled,
}

/// Checks `path` (printing warnings and errors to stderr) and compiles it; fails on errors.
pub fn load(path: &Path, lenient: bool, color: bool) -> anyhow::Result<Loaded> {
    let checked = check_file(path, !lenient)?;
    let shown: Vec<_> = checked
        .diagnostics
        .iter()
        .filter(|d| d.diagnostic.is_error() || lenient)
        .collect();
    for diagnostic in &shown {
        let source = &checked.sources[diagnostic.file.0 as usize];
        eprint!(
            "{}",
            diagnostic
                .diagnostic
                .render(&source.name, &source.text, color)
        );
    }
    if checked.has_errors() {
        let errors = checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .count();
        bail!(
            "{} has {errors} error(s); `regatta check` lists them",
            path.display()
        );
    }
    let compiled = compile(&checked.scene);
    for warning in &compiled.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(Loaded { checked, compiled })
}
