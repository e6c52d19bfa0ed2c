//! What can go wrong with a Webots controller: the room's one error type (a leaf: every
//! other file imports it).

use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a Webots controller could not run, or stopped.
#[derive(Debug, Clone, thiserror::Error)]
pub enum WebotsError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: Arc<std::io::Error>,
    },
    #[error("controller \"{controller}\": {path} leads outside the world's project")]
    OutsideProject { controller: String, path: PathBuf },
    #[error("controller \"{controller}\": {folder} holds no C source (NAME.c) or Python script (NAME.py)")]
    NoSources { controller: String, folder: PathBuf },
    #[error("controller \"{controller}\" ({language}) is not one regatta starts this way")]
    Unsupported {
        controller: String,
        language: &'static str,
    },
    #[error("controller \"{controller}\" is written in Python: no Python interpreter \"{interpreter}\" is installed (install Python 3, or name one with REGATTA_PYTHON=/path/to/python3)")]
    NoPython {
        controller: String,
        interpreter: String,
    },
    #[error("cannot run the C compiler \"{compiler}\" ({source}); install one (e.g. apt-get install gcc) or set CC")]
    Compiler {
        compiler: String,
        #[source]
        source: Arc<std::io::Error>,
    },
    #[error("controller \"{controller}\" does not compile:\n{messages}")]
    DoesNotCompile {
        controller: String,
        messages: String,
    },
    #[error("robot '{robot}': cannot start controller \"{controller}\": {source}")]
    Spawn {
        robot: String,
        controller: String,
        #[source]
        source: Arc<std::io::Error>,
    },
    #[error("robot '{robot}': controller \"{controller}\" failed at t = {time:.3} s: {what}")]
    Controller {
        robot: String,
        controller: String,
        time: f64,
        what: String,
    },
}

impl WebotsError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> WebotsError {
        WebotsError::Io {
            path: path.to_path_buf(),
            source: Arc::new(source),
        }
    }
}
