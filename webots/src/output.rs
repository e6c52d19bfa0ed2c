//! A controller's standard output and error, read at the steps where it printed them.
//!
//! Both streams go to one file in the run's private folder (one open file, so lines keep the
//! order the program wrote them in). The controller library makes stdout line-buffered, so a
//! line printed before a `wb_robot_step` is in the file before its request reaches regatta;
//! reading the file after each request gives every line at the step it was printed, whatever
//! the scheduling: the log that records them stays reproducible.

use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::process::Stdio;

use crate::WebotsError;

/// A line a controller printed.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramLine {
    /// The robot, by index.
    pub robot: usize,
    /// Simulated time of the step at which it was printed (s).
    pub time: f64,
    pub line: String,
}

/// The longest line kept whole; a longer one is cut there (a controller printing without
/// newlines must not grow regatta's memory).
const LONGEST_LINE: usize = 64 * 1024;

/// The reading side of one controller's output.
pub struct Output {
    file: File,
    robot: usize,
    robot_name: String,
    echo: bool,
    partial: Vec<u8>,
    chunk: Vec<u8>,
    buffer: Vec<u8>,
}

impl Output {
    /// Makes the file at `path` and the child's stdout and stderr writing into it.
    pub fn create(
        path: &Path,
        robot: usize,
        robot_name: &str,
        echo: bool,
    ) -> Result<(Output, Stdio, Stdio), WebotsError> {
        let io = |source| WebotsError::io(path, source);
        let writer = File::create(path).map_err(io)?;
        let second = writer.try_clone().map_err(io)?;
        let file = File::open(path).map_err(io)?;
        Ok((
            Output {
                file,
                robot,
                robot_name: robot_name.to_owned(),
                echo,
                partial: Vec::new(),
                chunk: Vec::new(),
                buffer: vec![0; 8192],
            },
            Stdio::from(writer),
            Stdio::from(second),
        ))
    }

    /// The complete lines printed since the last call, stamped `time`, into `lines` (and onto
    /// standard error behind the robot's name when echoing).
    pub fn drain(&mut self, time: f64, lines: &mut Vec<ProgramLine>) {
        // Plain reads until the end: one system call a step when nothing was printed
        // (`read_to_end` would ask the file's size first).
        // The buffer is kept: zeroing a fresh one each step cost more than the rest of the
        // exchange.
        self.chunk.clear();
        loop {
            match self.file.read(&mut self.buffer) {
                Ok(0) | Err(_) => break,
                Ok(n) => self.chunk.extend_from_slice(&self.buffer[..n]),
            }
        }
        let mut rest = &self.chunk[..];
        while let Some(end) = rest.iter().position(|&b| b == b'\n') {
            self.partial.extend_from_slice(&rest[..end]);
            rest = &rest[end + 1..];
            let line = std::mem::take(&mut self.partial);
            self.emit(time, &line, lines);
        }
        self.partial.extend_from_slice(rest);
        if self.partial.len() > LONGEST_LINE {
            let line = std::mem::take(&mut self.partial);
            self.emit(time, &line, lines);
        }
    }

    /// What is left when the controller has ended: the lines, and a last one without its
    /// newline.
    pub fn finish(&mut self, time: f64, lines: &mut Vec<ProgramLine>) {
        self.drain(time, lines);
        if !self.partial.is_empty() {
            let line = std::mem::take(&mut self.partial);
            self.emit(time, &line, lines);
        }
    }

    /// What the controller printed last (a Python traceback), for the error that ends its
    /// run: echoed, the lines are shown now and nothing is quoted; else its last 16 lines
    /// after a colon, each on a line of its own (empty when it printed nothing).
    pub fn last_words(&mut self, time: f64) -> String {
        let mut lines = Vec::new();
        self.finish(time, &mut lines);
        if self.echo || lines.is_empty() {
            return String::new();
        }
        let mut words = String::from("; its last words:");
        for line in &lines[lines.len().saturating_sub(16)..] {
            words.push_str("\n    ");
            words.push_str(&line.line);
        }
        words
    }

    fn emit(&self, time: f64, bytes: &[u8], lines: &mut Vec<ProgramLine>) {
        // Text as printed, less a carriage return before the newline and NUL bytes (which
        // no log string may hold).
        let text = String::from_utf8_lossy(bytes);
        let text = text.trim_end_matches('\r').replace('\0', "\u{FFFD}");
        if self.echo {
            eprintln!("[{}] {text}", self.robot_name);
        }
        lines.push(ProgramLine {
            robot: self.robot,
            time,
            line: text,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn lines_come_whole_in_order_and_the_last_one_at_the_end() {
        let dir = std::env::temp_dir().join(format!("regatta-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("0.out");
        let (mut output, _, _) = Output::create(&path, 3, "r", false).unwrap();
        let mut writer = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        let mut lines = Vec::new();
        writer.write_all(b"one\ntw").unwrap();
        output.drain(0.032, &mut lines);
        writer.write_all(b"o\r\nthree\0").unwrap();
        output.drain(0.064, &mut lines);
        output.finish(0.096, &mut lines);
        let got: Vec<(f64, &str)> = lines.iter().map(|l| (l.time, l.line.as_str())).collect();
        assert_eq!(
            got,
            [(0.032, "one"), (0.064, "two"), (0.096, "three\u{FFFD}")]
        );
        assert!(lines.iter().all(|l| l.robot == 3));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
