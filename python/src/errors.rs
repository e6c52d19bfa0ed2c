//! Rust errors as Python exceptions: a world that does not check raises `WorldError` (a
//! `ValueError`) whose message is the command line's rendered diagnostics, file:line:col
//! included; a missing file `FileNotFoundError`; bad arguments `ValueError`; a log that cannot
//! be written `OSError`.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;
use regatta_evolve::experiment::{EvalError, LoadError};

use crate::core::CoreError;

pyo3::create_exception!(
    regatta,
    WorldError,
    PyValueError,
    "A world that cannot be loaded: it does not parse or check (the message holds the diagnostics with file:line:col, as `regatta check` prints them), or it cannot start."
);

pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

pub fn runtime_error(message: impl Into<String>) -> PyErr {
    PyRuntimeError::new_err(message.into())
}

pub fn to_py(error: CoreError) -> PyErr {
    match error {
        CoreError::Load(LoadError::Read(source)) => {
            let message = source.to_string();
            match &source {
                regatta_parser::SourceError::Io { source: io, .. }
                    if io.kind() == std::io::ErrorKind::NotFound =>
                {
                    PyFileNotFoundError::new_err(message)
                }
                regatta_parser::SourceError::Io { .. } => PyOSError::new_err(message),
                _ => WorldError::new_err(message),
            }
        }
        CoreError::Load(error) => WorldError::new_err(error.to_string()),
        CoreError::Eval(error @ EvalError::Vision { .. }) => runtime_error(error.to_string()),
        CoreError::Eval(error) => value_error(error.to_string()),
        CoreError::UnknownRobot { .. } | CoreError::Usage(_) => value_error(error.to_string()),
        CoreError::Log { .. } => PyOSError::new_err(error.to_string()),
    }
}
