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
    _slave: std::fs::File,
    slave_path: String,
    timeout: Option<Duration>,
}

#[cfg(unix)]
impl Pty {
    /// Opens a new pseudo-terminal in raw mode (no echo, no line editing, no CR/LF mapping).
    pub fn open() -> io::Result<Pty> {
        use std::os::fd::FromRawFd;
        // SAFETY: plain POSIX calls on descriptors this function owns; each result is checked.
        unsafe {
            let master = libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY);
            if master < 0 {
                return Err(io::Error::last_os_error());
            }
            let master_file = std::fs::File::from_raw_fd(master);
            if libc::grantpt(master) != 0 || libc::unlockpt(master) != 0 {
                return Err(io::Error::last_os_error());
            }
            let mut name = [0 as libc::c_char; 256];
            if libc::ptsname_r(master, name.as_mut_ptr(), name.len()) != 0 {
                return Err(io::Error::last_os_error());
            }
            let slave_path = std::ffi::CStr::from_ptr(name.as_ptr())
                .to_string_lossy()
                .into_owned();
            let c_path = std::ffi::CString::new(slave_path.clone())
                .map_err(|_| io::Error::other("pty name holds a NUL"))?;
            let slave = libc::open(c_path.as_ptr(), libc::O_RDWR | libc::O_NOCTTY);
            if slave < 0 {
                return Err(io::Error::last_os_error());
            }
            let slave_file = std::fs::File::from_raw_fd(slave);
            let mut termios: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(slave, &mut termios) != 0 {
                return Err(io::Error::last_os_error());
            }
            libc::cfmakeraw(&mut termios);
            if libc::tcsetattr(slave, libc::TCSANOW, &termios) != 0 {
                return Err(io::Error::last_os_error());
            }
            Ok(Pty {
                master: master_file,
                _slave: slave_file,
                slave_path,
                timeout: None,
            })
        }
    }

    /// The path a client opens as its serial port.
    pub fn slave_path(&self) -> &str {
        &self.slave_path
    }
}

#[cfg(unix)]
impl Read for Pty {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        use std::os::fd::AsRawFd;
        if let Some(timeout) = self.timeout {
            let mut poll = libc::pollfd {
                fd: self.master.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            let millis = timeout.as_millis().clamp(1, i32::MAX as u128) as i32;
            // SAFETY: one valid pollfd for the duration of the call.
            let ready = unsafe { libc::poll(&mut poll, 1, millis) };
            if ready < 0 {
                return Err(io::Error::last_os_error());
            }
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
