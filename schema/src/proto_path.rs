//! Where `webots://` PROTOs are looked for before regatta's stand-ins: the folders of
//! `--proto-path DIR` (repeatable) and of the `REGATTA_PROTO_PATH` environment variable (a
//! list separated like `PATH`). A folder may be a Webots installation (`webots://projects/…`
//! resolves to `DIR/projects/…`) or a flat folder of PROTOs (`DIR/Name.proto`).
//!
//! The folders are trusted (the user named them); what a world's url makes of them is not:
//! each folder is a root of its own, and the path a url names inside it goes through
//! [`FileAccess::resolve`], the one way from a url to a path for everything a world reads. So
//! `..` out of the folder, absolute paths and symbolic links leading out are refused by the
//! same rules (and the same tests, in `access.rs`) as a world's own EXTERNPROTO and Inline
//! urls.

use std::path::PathBuf;

use crate::access::{FileAccess, Refusal};

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

/// What looking a `webots://` PROTO up in the PROTO path found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Lookup {
    /// The file, in the first folder that has it.
    Found(PathBuf),
    /// No folder has it.
    Absent,
    /// The url breaks the file rules: it climbs out of the folder (`..`) or is absolute, or a
    /// folder has a file there that is a symbolic link out of it. The path as looked up in
    /// the folder, the folder, and the rule. Nothing was read.
    Refused {
        looked_up: String,
        folder: PathBuf,
        refusal: Refusal,
    },
}

/// The file for the PROTO `name` that a `webots://` url names by `inside` (its path inside a
/// Webots installation), looked for as `DIR/inside` and then as `DIR/name.proto` in each
/// folder in turn.
pub fn find(dirs: &[PathBuf], inside: &str, name: &str) -> Lookup {
    let candidates = [inside.to_owned(), format!("{name}.proto")];
    let mut refused = None;
    for dir in dirs {
        let mut access = FileAccess::none();
        let Ok(()) = access.allow(dir) else {
            // A folder that does not exist (a stale environment variable) holds nothing.
            continue;
        };
        let root = access.roots()[0].clone();
        for looked_up in &candidates {
            let refusal = match access.resolve(looked_up, Some(&root)) {
                Ok(path) if path.is_file() => return Lookup::Found(path),
                Ok(_) | Err(Refusal::Missing) => continue,
                Err(refusal) => refusal,
            };
            let lookup = Lookup::Refused {
                looked_up: looked_up.clone(),
                folder: dir.clone(),
                refusal: refusal.clone(),
            };
            if refusal == Refusal::LinkOutsideRoot {
                // This folder's file is unusable; another folder may still have the PROTO.
                refused.get_or_insert(lookup);
            } else {
                // `..` out of the folder, an absolute path: the url itself reaches out, in
                // every folder alike.
                return lookup;
            }
        }
    }
    refused.unwrap_or(Lookup::Absent)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lookup order; confinement itself is `FileAccess`'s (tested in `access.rs`), and a
    /// refusal it makes reaches the caller.
    #[test]
    fn finds_by_path_then_by_name_through_file_access() {
        let dir = std::env::temp_dir().join(format!("regatta-proto-path-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let nested = dir.join("webots/projects/robots/x/protos");
        std::fs::create_dir_all(&nested).unwrap();
        std::fs::write(nested.join("X.proto"), "PROTO X [] { Group {} }").unwrap();
        std::fs::write(dir.join("webots/Y.proto"), "PROTO Y [] { Group {} }").unwrap();
        std::fs::write(dir.join("outside.proto"), "PROTO Z [] { Group {} }").unwrap();
        let dirs = vec![dir.join("missing"), dir.join("webots")];
        assert!(matches!(
            find(&dirs, "projects/robots/x/protos/X.proto", "X"),
            Lookup::Found(p) if p.ends_with("X.proto")
        ));
        assert!(matches!(
            find(&dirs, "projects/elsewhere/Y.proto", "Y"),
            Lookup::Found(p) if p.ends_with("Y.proto")
        ));
        // `..` out of the folder is refused before anything is looked at, even where the
        // file exists, and so is a name that climbs out.
        let outside = |looked_up: &str| Lookup::Refused {
            looked_up: looked_up.to_owned(),
            folder: dir.join("webots"),
            refusal: Refusal::OutsideRoot,
        };
        assert_eq!(
            find(&dirs, "projects/../../outside.proto", "outside"),
            outside("projects/../../outside.proto")
        );
        assert_eq!(
            find(&dirs, "projects/x/X.proto", "../outside"),
            outside("../outside.proto")
        );
        // `..` that stays inside is an ordinary path.
        assert!(matches!(
            find(&dirs, "projects/robots/../robots/x/protos/X.proto", "X"),
            Lookup::Found(p) if p.ends_with("X.proto")
        ));
        assert_eq!(find(&dirs, "projects/nothing/Z.proto", "Z"), Lookup::Absent);
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(dir.join("outside.proto"), dir.join("webots/L.proto"))
                .unwrap();
            assert_eq!(
                find(&dirs, "projects/l/L.proto", "L"),
                Lookup::Refused {
                    looked_up: "L.proto".to_owned(),
                    folder: dir.join("webots"),
                    refusal: Refusal::LinkOutsideRoot
                }
            );
            // A folder linked out as a whole is refused the same way.
            std::os::unix::fs::symlink(&dir, dir.join("webots/up")).unwrap();
            assert_eq!(
                find(&dirs, "up/outside.proto", "Q"),
                Lookup::Refused {
                    looked_up: "up/outside.proto".to_owned(),
                    folder: dir.join("webots"),
                    refusal: Refusal::LinkOutsideRoot
                }
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
