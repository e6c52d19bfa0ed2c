//! The last lines a controller wrote on its standard error, kept when they are not shown (a
//! batch's controllers run quietly), so that the error that ends a run can quote them: a
//! Python controller's traceback, a C controller's last message.

use std::collections::VecDeque;
use std::io::Read;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// How many lines are kept: a traceback's usual depth.
const LINES: usize = 16;

pub(crate) struct Tail {
    lines: Arc<Mutex<VecDeque<String>>>,
    reader: Option<JoinHandle<()>>,
}

impl Tail {
    /// Reads `pipe` to its end on a thread of its own, keeping its last lines.
    pub(crate) fn keep(pipe: impl Read + Send + 'static) -> Tail {
        let lines = Arc::new(Mutex::new(VecDeque::new()));
        let kept = lines.clone();
        let reader = std::thread::spawn(move || {
            use std::io::BufRead;
            for line in std::io::BufReader::new(pipe).split(b'\n') {
                let Ok(line) = line else { break };
                let mut kept = kept.lock().unwrap_or_else(|e| e.into_inner());
                if kept.len() == LINES {
                    kept.pop_front();
                }
                kept.push_back(String::from_utf8_lossy(&line).trim_end().to_owned());
            }
        });
        Tail {
            lines,
            reader: Some(reader),
        }
    }

    /// Once the process has ended: its last lines, each indented on a line of its own after
    /// a colon (empty when it wrote none).
    pub(crate) fn last_words(&mut self) -> String {
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
        let lines = self.lines.lock().unwrap_or_else(|e| e.into_inner());
        if lines.is_empty() {
            return String::new();
        }
        let mut out = String::from("; its last words:");
        for line in lines.iter() {
            out.push_str("\n    ");
            out.push_str(line);
        }
        out
    }
}
