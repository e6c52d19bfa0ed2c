//! How many channels a log has added, against what one MCAP file can number.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use super::error::LogError;

/// Channels one log may hold. MCAP numbers channels with 16 bits; the `mcap` writer numbers
/// them from 1 and cannot go past 65,534 (its counter overflows on the next), so the log
/// refuses the channel after that itself, with the way out.
pub const MOST_CHANNELS: usize = 65_534;

/// The channels a log has added, and its robots (for the error that names them).
pub(super) struct ChannelBudget {
    pub(super) added: usize,
    pub(super) robots: usize,
}

impl ChannelBudget {
    /// Adds a channel to `writer`, or refuses it past [`MOST_CHANNELS`].
    pub(super) fn add_channel<W: Write + Seek>(
        &mut self,
        writer: &mut mcap::Writer<W>,
        schema: u16,
        topic: &str,
        metadata: &BTreeMap<String, String>,
    ) -> Result<u16, LogError> {
        if self.added >= MOST_CHANNELS {
            return Err(LogError::TooManyChannels {
                robots: self.robots,
            });
        }
        let channel = writer
            .add_channel(schema, topic, "cdr", metadata)
            .map_err(LogError::Write)?;
        self.added += 1;
        Ok(channel)
    }
}
