//! Variations: values of a world drawn anew for each trial (`--vary NODE.FIELD=SPEC`, or a
//! TOML file), so that a controller is evaluated over conditions rather than one world.
//!
//! A room of its own: `spec.rs` reads what varies and how (flags and files, with where each
//! was written); `draw.rs` draws a trial's values from its seed, writes them into the world
//! text, and draws again when they break the world. The step loop knows nothing of it: a
//! varied trial is an ordinary world whose text differs.

mod draw;
mod spec;

pub use draw::{Drawn, Plan, TRIES};
pub use spec::{parse_file, How, Origin, Variation, VaryError};
