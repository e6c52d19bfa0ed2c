//! Reading a world file's bytes into text: gzip-compressed `.wrl.gz`/`.wrz` files are
//! inflated, and invalid UTF-8 becomes a diagnostic at the offending byte, not a failure.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::diagnostic::Diagnostic;
use crate::syntax::Span;

/// Why a file could not be read at all.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} looks gzip-compressed but does not inflate: {source}")]
    Gzip {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The text of one world file, ready to parse.
#[derive(Clone, Debug)]
pub struct SourceText {
    /// The name diagnostics print: the path as given, or `<stdin>`.
    pub name: String,
    pub text: String,
    /// Decoding problems (invalid UTF-8), with spans into `text`.
    pub diagnostics: Vec<Diagnostic>,
}

impl SourceText {
    /// Reads `path`, inflating gzip and decoding UTF-8.
    pub fn read(path: &Path) -> Result<SourceText, SourceError> {
        let bytes = std::fs::read(path).map_err(|source| SourceError::Io {
            path: path.to_owned(),
            source,
        })?;
        let bytes = inflate_if_gzip(bytes).map_err(|source| SourceError::Gzip {
            path: path.to_owned(),
            source,
        })?;
        Ok(SourceText::from_bytes(path.display().to_string(), bytes))
    }

    /// Decodes bytes already in memory (standard input, embedded files).
    pub fn from_bytes(name: String, bytes: Vec<u8>) -> SourceText {
        match String::from_utf8(bytes) {
            Ok(text) => SourceText {
                name,
                text,
                diagnostics: Vec::new(),
            },
            Err(error) => {
                let offset = error.utf8_error().valid_up_to();
                let text = String::from_utf8_lossy(error.as_bytes()).into_owned();
                let diagnostic = Diagnostic::error(
                    Span::new(offset, offset + 1),
                    "invalid UTF-8: world files are UTF-8 text",
                )
                .with_label("this byte is not UTF-8")
                .with_note("invalid bytes were replaced by U+FFFD and parsing went on");
                SourceText {
                    name,
                    text,
                    diagnostics: vec![diagnostic],
                }
            }
        }
    }
}

/// Inflates `bytes` if they start with the gzip magic number.
pub fn inflate_if_gzip(bytes: Vec<u8>) -> std::io::Result<Vec<u8>> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(&bytes[..]).read_to_end(&mut out)?;
        Ok(out)
    } else {
        Ok(bytes)
    }
}
