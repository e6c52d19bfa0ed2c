//! What a subcommand reports back to `main`, which turns it into the exit status.

/// What a subcommand reports back.
pub enum Outcome {
    Clean,
    /// The input had errors; they were printed.
    Errors,
    /// A signal stopped the command, which finished its work cleanly (logs closed).
    Signalled(i32),
}
