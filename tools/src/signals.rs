//! SIGINT and SIGTERM as a request to stop: long commands (`run`, `serve`, `drive`) check it
//! between steps, finish their logs (summary and footer written) and exit with 128 + the
//! signal's number (130 for Ctrl-C, 143 for SIGTERM), as a shell expects. A second signal of
//! the same kind ends the process at once, for a command that is stuck.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// The stop request: raised by the first SIGINT or SIGTERM.
#[derive(Clone)]
pub struct Stop {
    flag: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

impl Stop {
    /// Installs the handlers (once per process is enough; again is harmless).
    pub fn install() -> Stop {
        let stop = Stop {
            flag: Arc::new(AtomicBool::new(false)),
            signal: Arc::new(AtomicUsize::new(0)),
        };
        #[cfg(unix)]
        for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            // The order matters: the default action is restored only if the flag was already
            // raised, i.e. on the second signal.
            let _ = signal_hook::flag::register_conditional_default(signal, stop.flag.clone());
            let _ = signal_hook::flag::register_usize(signal, stop.signal.clone(), signal as usize);
            let _ = signal_hook::flag::register(signal, stop.flag.clone());
        }
        stop
    }

    /// Whether a signal asked to stop.
    pub fn requested(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }

    /// The flag itself, for loops that take one.
    pub fn flag(&self) -> &AtomicBool {
        &self.flag
    }

    /// The signal that asked to stop, if one did.
    pub fn signal(&self) -> Option<i32> {
        match self.signal.load(Ordering::SeqCst) {
            0 => None,
            n => Some(n as i32),
        }
    }

    /// How the command ends when a signal stopped it: 128 + the signal's number.
    pub fn outcome(&self) -> Option<crate::outcome::Outcome> {
        self.signal().map(crate::outcome::Outcome::Signalled)
    }

    /// The signal's name, for messages.
    pub fn name(&self) -> &'static str {
        match self.signal() {
            Some(2) => "SIGINT",
            Some(15) => "SIGTERM",
            _ => "a signal",
        }
    }
}
