//! Helpers shared by the command line's end-to-end tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The `regatta` binary of this build.
pub fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tools/ has a parent")
        .to_owned()
}

/// A fresh folder for one test: `regatta-{name}-{process id}` in the temporary directory.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("regatta-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
