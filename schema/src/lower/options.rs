//! How a world is checked: [`Options`] (strict or lenient, file access, limits, the PROTO
//! path) and the default bounds.

use std::path::PathBuf;

use crate::access::{FileAccess, Limits};

/// Deepest nesting of PROTO instances, by default (see [`Limits`]).
pub const MAX_INSTANCE_DEPTH: usize = 32;
/// Largest scene, in nodes, after PROTO expansion, by default (see [`Limits`]).
pub const MAX_NODES: usize = 1_000_000;
/// Diagnostics kept per check; past it, one message says how many more there were.
pub const MAX_DIAGNOSTICS: usize = 500;

/// How to check a world.
#[derive(Clone, Debug)]
pub struct Options {
    /// Unknown nodes and fields are errors (regatta's own worlds) or warnings (foreign files).
    pub strict: bool,
    /// The folders the world may read files from; `check_path` adds the world's own folder.
    pub access: FileAccess,
    /// Bounds on includes, PROTO depth, nodes, nesting and file size.
    pub limits: Limits,
    /// The folder the main text's relative urls resolve against: the world file's folder
    /// (`check_path` sets it); `None` for a text with no folder (standard input), whose
    /// urls resolve against the current directory, still within `access`.
    pub base_dir: Option<PathBuf>,
    /// Folders where `webots://` PROTOs are looked for before regatta's stand-ins (a Webots
    /// installation, or any folder of PROTOs); see [`crate::proto_path`].
    pub proto_path: Vec<PathBuf>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            strict: true,
            access: FileAccess::none(),
            limits: Limits::default(),
            base_dir: None,
            proto_path: Vec::new(),
        }
    }
}
