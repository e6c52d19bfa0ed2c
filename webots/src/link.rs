//! One controller process and its connection: frames sent and received with a timeout, and
//! how a process that stopped answering ended, in words; the run's private socket folder.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use crate::error::WebotsError;
use crate::protocol;

/// A controller process (none for an `<extern>` controller the user started) and its socket.
pub struct Link {
    pub robot_name: String,
    pub controller: String,
    pub child: Option<Child>,
    pub stream: UnixStream,
    /// The last frame received.
    pub frame: Vec<u8>,
}

impl Link {
    /// Sends one frame.
    pub fn send(&mut self, frame: &[u8], time: f64) -> Result<(), WebotsError> {
        if let Err(e) = self.stream.write_all(frame) {
            return Err(self.lost(time, e));
        }
        Ok(())
    }

    /// Reads the controller's next frame into `self.frame`; `Ok(false)` when the controller
    /// ended with status 0 instead (a controller that returns from `main`).
    pub fn receive(&mut self, time: f64, timeout: Duration) -> Result<bool, WebotsError> {
        let mut length = [0u8; 4];
        if let Err(e) = self.stream.read_exact(&mut length) {
            if e.kind() == std::io::ErrorKind::UnexpectedEof && self.exited_cleanly() {
                return Ok(false);
            }
            return Err(if is_timeout(&e) {
                if let Some(child) = self.child.as_mut() {
                    let _ = child.kill();
                }
                WebotsError::Controller {
                    robot: self.robot_name.clone(),
                    controller: self.controller.clone(),
                    time,
                    what: format!(
                        "it stopped answering: no wb_robot_step within {} s",
                        timeout.as_secs_f64()
                    ),
                }
            } else {
                self.lost(time, e)
            });
        }
        let length = u32::from_le_bytes(length) as usize;
        if length > 64 << 20 {
            return Err(self.protocol_error(time, protocol::FrameError::Short(length)));
        }
        self.frame.resize(length, 0);
        let mut frame = std::mem::take(&mut self.frame);
        let read = self.stream.read_exact(&mut frame);
        self.frame = frame;
        read.map_err(|e| self.lost(time, e))?;
        Ok(true)
    }

    /// Whether the controller has exited with status 0 (waiting a moment for it to be reaped);
    /// an extern controller that closes its connection is done.
    fn exited_cleanly(&mut self) -> bool {
        let deadline = Instant::now() + Duration::from_millis(500);
        let Some(child) = self.child.as_mut() else {
            return true;
        };
        loop {
            match child.try_wait() {
                Ok(Some(status)) => return status.success(),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(1))
                }
                _ => return false,
            }
        }
    }

    /// The connection broke: the controller ended (how, if it has) or closed its socket.
    pub fn lost(&mut self, time: f64, error: std::io::Error) -> WebotsError {
        // A process that closed its socket is ending: give it a moment to be reaped.
        let deadline = Instant::now() + Duration::from_millis(500);
        let what = loop {
            let Some(child) = self.child.as_mut() else {
                break format!("its connection broke ({error})");
            };
            match child.try_wait() {
                Ok(Some(status)) => break format!("it {}", describe_exit(status)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(1))
                }
                _ => break format!("its connection broke ({error})"),
            }
        };
        WebotsError::Controller {
            robot: self.robot_name.clone(),
            controller: self.controller.clone(),
            time,
            what,
        }
    }

    pub fn protocol_error(&self, time: f64, error: protocol::FrameError) -> WebotsError {
        WebotsError::Controller {
            robot: self.robot_name.clone(),
            controller: self.controller.clone(),
            time,
            what: format!("it sent a malformed request ({error})"),
        }
    }
}

fn is_timeout(error: &std::io::Error) -> bool {
    matches!(
        error.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    )
}

/// How a process ended, in words.
pub fn describe_exit(status: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exited with status {code}"),
        (None, Some(signal)) => format!("was killed by signal {signal}{}", signal_name(signal)),
        _ => "ended".to_owned(),
    }
}

fn signal_name(signal: i32) -> &'static str {
    match signal {
        4 => " (SIGILL)",
        6 => " (SIGABRT)",
        8 => " (SIGFPE)",
        9 => " (SIGKILL)",
        11 => " (SIGSEGV: the controller crashed)",
        15 => " (SIGTERM)",
        _ => "",
    }
}

pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// A private folder (mode 0700) for the run's sockets.
pub fn socket_folder() -> Result<PathBuf, WebotsError> {
    use std::os::unix::fs::DirBuilderExt;
    static COUNTER: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let base = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_dir())
        .unwrap_or_else(std::env::temp_dir);
    // A folder of an earlier process with the same id (a killed run leaves its folder) is
    // not ours: the next name is tried, never the stale one reused.
    let mut attempts = 0;
    loop {
        let name = format!(
            "regatta-{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        );
        let dir = base.join(name);
        match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
            Ok(()) => return Ok(dir),
            Err(source)
                if source.kind() == std::io::ErrorKind::AlreadyExists && attempts < 1000 =>
            {
                attempts += 1;
            }
            Err(source) => return Err(WebotsError::io(&dir, source)),
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_stale_folder_of_the_same_process_id_is_stepped_over() {
        // Folders an earlier process with this id left behind (its next names included).
        let base = std::env::var_os("XDG_RUNTIME_DIR")
            .map(std::path::PathBuf::from)
            .filter(|p| p.is_dir())
            .unwrap_or_else(std::env::temp_dir);
        let stale: Vec<_> = (0..64)
            .map(|n| base.join(format!("regatta-{}-{n}", std::process::id())))
            .filter(|dir| std::fs::create_dir(dir).is_ok())
            .collect();
        let made = super::socket_folder();
        for dir in &stale {
            let _ = std::fs::remove_dir(dir);
        }
        let made = made.expect("a fresh folder");
        assert!(!stale.contains(&made), "{}", made.display());
        std::fs::remove_dir(&made).unwrap();
    }
}
