//! The log's error type.

/// Why a log could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    #[error("cannot write the log: {0}")]
    Write(#[source] mcap::McapError),
    #[error("the log is not a readable MCAP file: {0}")]
    Read(#[source] mcap::McapError),
    #[error("the log has no regatta metadata record: it was not written by regatta run --log")]
    NoMetadata,
    #[error("the log's metadata is incomplete: missing {0}")]
    MissingField(&'static str),
}
