//! Where `webots://` PROTOs are looked for before regatta's stand-ins: the folders of
//! `--proto-path DIR` (repeatable) and of the `REGATTA_PROTO_PATH` environment variable (a
//! list separated like `PATH`). A folder may be a Webots installation (`webots://projects/…`
//! resolves to `DIR/projects/…`) or a flat folder of PROTOs (`DIR/Name.proto`).
//!
//! The folders are trusted (the user named them); what a world's url makes of them is not: a
//! path with `..`, an absolute path, or one that leaves the folder through a symbolic link is
//! never opened.

use std::path::{Component, Path, PathBuf};

/// The environment variable that adds folders to the PROTO path.
pub const ENV: &str = "REGATTA_PROTO_PATH";

/// `flags` followed by the folders of `REGATTA_PROTO_PATH`.
pub fn from_flags_and_env(flags: &[PathBuf]) -> Vec<PathBuf> {
    let mut dirs = flags.to_vec();
    if let Some(value) = std::env::var_os(ENV) {
        dirs.extend(std::env::split_paths(&value).filter(|p| !p.as_os_str().is_empty()));
    }
    dirs
}

/// The file for the PROTO `name` that a `webots://` url names by `inside` (its path inside a
/// Webots installation), in the first folder that has it.
pub fn find(dirs: &[PathBuf], inside: &str, name: &str) -> Option<PathBuf> {
    let relative = Path::new(inside);
    let safe = relative
        .components()
        .all(|c| matches!(c, Component::Normal(_)));
    for dir in dirs {
        let Ok(root) = dir.canonicalize() else {
            continue;
        };
        let mut candidates = Vec::new();
        if safe {
            candidates.push(root.join(relative));
        }
        candidates.push(root.join(format!("{name}.proto")));
        for candidate in candidates {
            // Inside the folder once links are followed, and a file.
            match candidate.canonicalize() {
                Ok(real) if real.starts_with(&root) && real.is_file() => return Some(real),
                _ => {}
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_by_path_then_by_name_and_never_leaves_the_folder() {
        let dir = std::env::temp_dir().join(format!("regatta-proto-path-{}", std::process::id()));
        let nested = dir.join("projects/robots/x/protos");
        std::fs::create_dir_all(&nested).unwrap();
        std::fs::write(nested.join("X.proto"), "PROTO X [] { Group {} }").unwrap();
        std::fs::write(dir.join("Y.proto"), "PROTO Y [] { Group {} }").unwrap();
        let dirs = vec![dir.clone()];
        assert!(find(&dirs, "projects/robots/x/protos/X.proto", "X").is_some());
        assert!(find(&dirs, "projects/elsewhere/Y.proto", "Y").is_some());
        assert!(find(&dirs, "../../etc/passwd", "passwd").is_none());
        assert!(find(&dirs, "/etc/passwd", "passwd").is_none());
        assert!(find(&dirs, "projects/nothing/Z.proto", "Z").is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
