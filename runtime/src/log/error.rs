//! The log's error type.

/// Why a log could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    #[error("cannot write the log: {0}")]
    Write(#[source] mcap::McapError),
    /// MCAP numbers channels with 16 bits: a large swarm logging every channel of every robot
    /// passes that (`MOST_CHANNELS` in `budget.rs`).
    #[error(
        "cannot write the log: {robots} robots with these channels need more than the 65,534 \
         channels one MCAP file holds (one a robot for each kind); log fewer with --channels \
         (for example `--channels pose,visits`, two a robot)"
    )]
    TooManyChannels { robots: usize },
    #[error("the log is not a readable MCAP file: {0}")]
    Read(#[source] mcap::McapError),
    #[error("the log has no regatta metadata record: it was not written by regatta run --log")]
    NoMetadata,
    #[error("the log's metadata is incomplete: missing {0}")]
    MissingField(&'static str),
}
