//! Rust errors as Python exceptions: a world that does not check raises `WorldError` (a
//! `ValueError`) whose message is the command line's rendered diagnostics, file:line:col
//! included, and whose attributes give the first error's place (`file`, `line`, `column`,
//! `message`) and every error (`errors`); a file that cannot be read the `OSError` subclass
//! of its errno (`FileNotFoundError`, `IsADirectoryError`…) with `errno`, `strerror` and the
//! absolute `filename`; bad arguments `ValueError`; a log that cannot be written `OSError`.

use std::path::Path;

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::types::PyAnyMethods;
use pyo3::{PyErr, Python};
use regatta_evolve::experiment::{EvalError, LoadError, Located};

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
        CoreError::Load(LoadError::Read(source)) => match &source {
            regatta_parser::SourceError::Io { path, source: io } => os_error(path, io),
            _ => world_error(source.to_string(), &[]),
        },
        CoreError::Load(error @ LoadError::Check { .. }) => {
            let LoadError::Check { located, .. } = &error else {
                unreachable!("matched above")
            };
            world_error(error.to_string(), located)
        }
        CoreError::Load(error) => world_error(error.to_string(), &[]),
        CoreError::Eval(error @ EvalError::Vision { .. }) => runtime_error(error.to_string()),
        CoreError::Eval(error) => value_error(error.to_string()),
        CoreError::UnknownRobot { .. } | CoreError::Usage(_) => value_error(error.to_string()),
        CoreError::Log { .. } => PyOSError::new_err(error.to_string()),
    }
}

/// `OSError(errno, strerror, filename)`, which Python turns into the subclass the errno
/// names (`FileNotFoundError`, `IsADirectoryError`, `PermissionError`…), with the path made
/// absolute so that the message says which file was meant wherever the program ran.
fn os_error(path: &Path, io: &std::io::Error) -> PyErr {
    let filename = std::path::absolute(path)
        .unwrap_or_else(|_| path.to_owned())
        .display()
        .to_string();
    // io::Error's text ends with " (os error N)": Python's strerror is the sentence alone.
    let text = io.to_string();
    let strerror = match text.rfind(" (os error ") {
        Some(at) => text[..at].to_owned(),
        None => text,
    };
    match io.raw_os_error() {
        Some(errno) => PyOSError::new_err((errno, strerror, filename)),
        None => PyOSError::new_err(format!("cannot read {filename}: {strerror}")),
    }
}

/// `WorldError` with what a program may read besides the message: `file`, `line`, `column`
/// and `message` of the first error (`None` when the world failed for another reason), and
/// `errors`, every error as a `(file, line, column, message)` tuple.
fn world_error(text: String, located: &[Located]) -> PyErr {
    let error = WorldError::new_err(text);
    Python::attach(|py| {
        let value = error.value(py);
        let first = located.first();
        let errors: Vec<(String, usize, usize, String)> = located
            .iter()
            .map(|l| (l.file.clone(), l.line, l.column, l.message.clone()))
            .collect();
        // Setting attributes on a fresh exception instance cannot fail.
        let _ = value.setattr("file", first.map(|l| l.file.clone()));
        let _ = value.setattr("line", first.map(|l| l.line));
        let _ = value.setattr("column", first.map(|l| l.column));
        let _ = value.setattr("message", first.map(|l| l.message.clone()));
        let _ = value.setattr("errors", errors);
    });
    error
}
