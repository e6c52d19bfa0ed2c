//! The byte links a Khepera is reached over: a serial port (8 data bits, no parity, 2 stop
//! bits, no flow control, as the robot wants), a TCP socket (serial-over-IP adapters, and
//! `regatta serve --tcp`), a Unix socket, and — for `regatta serve --pty` — the master side of
//! a pseudo-terminal.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// A byte link with a read timeout (a timed-out read fails with `TimedOut` or `WouldBlock`).
pub trait Link: Read + Write + Send {
    fn set_timeout(&mut self, timeout: Option<Duration>) -> io::Result<()>;
}

impl Link for TcpStream {
    fn set_timeout(&mut self, timeout: Option<Duration>) -> io::Result<()> {
        self.set_read_timeout(timeout.map(|t| t.max(Duration::from_millis(1))))
    }
}

#[cfg(unix)]
impl Link for std::os::unix::net::UnixStream {
    fn set_timeout(&mut self, timeout: Option<Duration>) -> io::Result<()> {
        self.set_read_timeout(timeout.map(|t| t.max(Duration::from_millis(1))))
    }
}

impl Link for Box<dyn serialport::SerialPort> {
    fn set_timeout(&mut self, timeout: Option<Duration>) -> io::Result<()> {
        serialport::SerialPort::set_timeout(
            self.as_mut(),
            timeout.unwrap_or(Duration::from_secs(3600)),
        )
        .map_err(io::Error::from)
    }
}

/// Opens a serial port at `baud` with the Khepera's line settings.
pub fn open_serial(path: &str, baud: u32) -> io::Result<Box<dyn serialport::SerialPort>> {
    serialport::new(path, baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::Two)
        .flow_control(serialport::FlowControl::None)
        .timeout(Duration::from_secs(1))
        .open()
        .map_err(io::Error::from)
}

/// The master side of a pseudo-terminal whose slave is a serial port for any program.
#[cfg(unix)]
pub struct Pty {
    master: std::fs::File,
    /// Held open so that the master never reads end-of-file between two clients.
    _slave: std::os::fd::OwnedFd,
    slave_path: String,
    timeout: Option<Duration>,
}

#[cfg(unix)]
impl Pty {
    /// Opens a new pseudo-terminal in raw mode (no echo, no line editing, no CR/LF mapping).
    pub fn open() -> io::Result<Pty> {
        use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
        let pair = nix::pty::openpty(None, None).map_err(io::Error::from)?;
        let mut termios = tcgetattr(&pair.slave).map_err(io::Error::from)?;
        cfmakeraw(&mut termios);
        tcsetattr(&pair.slave, SetArg::TCSANOW, &termios).map_err(io::Error::from)?;
        let slave_path = nix::unistd::ttyname(&pair.slave)
            .map_err(io::Error::from)?
            .to_string_lossy()
            .into_owned();
        Ok(Pty {
            master: std::fs::File::from(pair.master),
            _slave: pair.slave,
            slave_path,
            timeout: None,
        })
    }

    /// The path a client opens as its serial port.
    pub fn slave_path(&self) -> &str {
        &self.slave_path
    }
}

#[cfg(unix)]
impl Read for Pty {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        use std::os::fd::AsFd;
        if let Some(timeout) = self.timeout {
            let millis = timeout.as_millis().clamp(1, i32::MAX as u128) as i32;
            let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
            let ready = poll(
                &mut fds,
                PollTimeout::try_from(millis).unwrap_or(PollTimeout::MAX),
            )
            .map_err(io::Error::from)?;
            if ready == 0 {
                return Err(io::ErrorKind::TimedOut.into());
            }
        }
        self.master.read(buf)
    }
}

#[cfg(unix)]
impl Write for Pty {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.master.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.master.flush()
    }
}

#[cfg(unix)]
impl Link for Pty {
    fn set_timeout(&mut self, timeout: Option<Duration>) -> io::Result<()> {
        self.timeout = timeout;
        Ok(())
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn a_pty_is_raw_and_its_reads_time_out() {
        let mut pty = Pty::open().unwrap();
        let mut slave = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(pty.slave_path())
            .unwrap();
        pty.set_timeout(Some(Duration::from_millis(30))).unwrap();
        let mut buffer = [0u8; 16];
        let error = pty.read(&mut buffer).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::TimedOut);
        // Raw: carriage returns and newlines pass unchanged, nothing is echoed.
        slave.write_all(b"D,1\r\n").unwrap();
        let n = pty.read(&mut buffer).unwrap();
        assert_eq!(&buffer[..n], b"D,1\r\n");
        pty.write_all(b"d\r\n").unwrap();
        let n = slave.read(&mut buffer).unwrap();
        assert_eq!(&buffer[..n], b"d\r\n");
        assert_eq!(
            pty.read(&mut buffer).unwrap_err().kind(),
            io::ErrorKind::TimedOut,
            "no echo"
        );
    }
}
