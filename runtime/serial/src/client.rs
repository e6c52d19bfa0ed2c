//! A real-robot backend of the Khepera API: each call is one request over the link, its reply
//! checked by its letter, with timeouts and retries (three tries, as LAMI's code did).
//! After a failed try the link is drained of late or garbled bytes before the request is
//! sent again, so a reply can never be taken for the answer to another request.

use std::io;
use std::time::{Duration, Instant};

use regatta_runtime::khepera::{
    Khepera, KheperaError, LedAction, LinearCameraTurret, PanoramicTurret,
};
use regatta_runtime::retina::FilterKind;

use crate::link::Link;
use crate::protocol::{reply_values, PanoramicRequest, Request};
use crate::server::is_timeout;

/// How patient the client is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClientOptions {
    /// How long one try waits for its reply.
    pub timeout: Duration,
    /// Tries per request (the first included).
    pub tries: u32,
}

impl Default for ClientOptions {
    fn default() -> ClientOptions {
        ClientOptions {
            timeout: Duration::from_millis(1000),
            tries: 3,
        }
    }
}

/// Counters a caller may report.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ClientStats {
    pub requests: u64,
    pub retries: u64,
}

/// A Khepera reached over a link.
pub struct RemoteKhepera<L: Link> {
    link: L,
    options: ClientOptions,
    /// Bytes received after the last complete reply line.
    pending: Vec<u8>,
    /// The version reply (`b,…`) read when connecting.
    pub version: String,
    has_panoramic: bool,
    has_k213: bool,
    pub stats: ClientStats,
}

/// What one try gave.
enum Try {
    Reply(Vec<i64>),
    TimedOut,
    Wrong(String),
}

impl<L: Link> RemoteKhepera<L> {
    /// Asks the robot's version (failing clearly if nothing answers), then which turret it
    /// carries: a turret that does not answer its read-settings message is taken as absent.
    pub fn connect(link: L, options: ClientOptions) -> Result<RemoteKhepera<L>, KheperaError> {
        let mut robot = RemoteKhepera {
            link,
            options,
            pending: Vec::new(),
            version: String::new(),
            has_panoramic: false,
            has_k213: false,
            stats: ClientStats::default(),
        };
        let version = robot.transact(&Request::Version)?;
        robot.version = format!(
            "b,{}",
            version
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
        robot.has_panoramic = robot
            .try_once(&Request::Panoramic(PanoramicRequest::Bits))?
            .is_some();
        robot.has_k213 = robot.try_once(&Request::K213Light)?.is_some();
        Ok(robot)
    }

    /// Whether the robot says it is a simulation (BIOS version 0).
    pub fn is_simulation(&self) -> bool {
        self.version == "b,0,0"
    }

    /// The link back, for a caller that is done with the robot.
    pub fn into_link(self) -> L {
        self.link
    }

    /// One try only: `None` when nothing valid comes back.
    fn try_once(&mut self, request: &Request) -> Result<Option<Vec<i64>>, KheperaError> {
        match self.attempt(request).map_err(link_error)? {
            Try::Reply(values) => Ok(Some(values)),
            Try::TimedOut | Try::Wrong(_) => {
                self.drain().map_err(link_error)?;
                Ok(None)
            }
        }
    }

    /// Sends a request and returns its reply's values, retrying as configured.
    pub fn transact(&mut self, request: &Request) -> Result<Vec<i64>, KheperaError> {
        self.stats.requests += 1;
        let mut last = Try::TimedOut;
        for attempt in 0..self.options.tries.max(1) {
            if attempt > 0 {
                self.stats.retries += 1;
                self.drain().map_err(link_error)?;
            }
            last = self.attempt(request).map_err(link_error)?;
            if let Try::Reply(values) = last {
                return Ok(values);
            }
        }
        let command = request.encode();
        Err(match last {
            Try::Wrong(got) => KheperaError::Protocol { command, got },
            _ => KheperaError::Link(format!(
                "no reply to {command:?} within {} ms, {} tries; is the robot on and the line at the right speed?",
                self.options.timeout.as_millis(),
                self.options.tries.max(1)
            )),
        })
    }

    fn attempt(&mut self, request: &Request) -> io::Result<Try> {
        let mut line = request.encode();
        line.push('\n');
        self.link.write_all(line.as_bytes())?;
        self.link.flush()?;
        let prefix = request.reply_prefix();
        let Some(reply) = self.read_line()? else {
            return Ok(Try::TimedOut);
        };
        Ok(match reply_values(&reply, &prefix) {
            Some(values) => Try::Reply(values),
            None => Try::Wrong(reply.trim_end().to_owned()),
        })
    }

    /// One reply line (up to LF), or `None` if the timeout passes first.
    fn read_line(&mut self) -> io::Result<Option<String>> {
        let deadline = Instant::now() + self.options.timeout;
        loop {
            if let Some(end) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=end).collect();
                return Ok(Some(String::from_utf8_lossy(&line).into_owned()));
            }
            if self.pending.len() > 64 * 1024 {
                // A link that never sends a line end: what is there is garbage.
                let line = String::from_utf8_lossy(&self.pending).into_owned();
                self.pending.clear();
                return Ok(Some(line));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.link.set_timeout(Some(left))?;
            let mut buffer = [0u8; 1024];
            match self.link.read(&mut buffer) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the robot closed the link",
                    ))
                }
                Ok(n) => self.pending.extend_from_slice(&buffer[..n]),
                Err(e) if is_timeout(&e) => return Ok(None),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }

    /// Discards what arrives within a short quiet period (late replies, garbage).
    fn drain(&mut self) -> io::Result<()> {
        self.pending.clear();
        let quiet =
            (self.options.timeout / 10).clamp(Duration::from_millis(5), Duration::from_millis(100));
        self.link.set_timeout(Some(quiet))?;
        let mut buffer = [0u8; 1024];
        for _ in 0..1000 {
            match self.link.read(&mut buffer) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the robot closed the link",
                    ))
                }
                Ok(_) => continue,
                Err(e) if is_timeout(&e) => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    fn values<const N: usize>(&mut self, request: &Request) -> Result<[i64; N], KheperaError> {
        let values = self.transact(request)?;
        <[i64; N]>::try_from(values.as_slice()).map_err(|_| KheperaError::Protocol {
            command: request.encode(),
            got: format!("{} values, expected {N}", values.len()),
        })
    }
}

fn link_error(error: io::Error) -> KheperaError {
    KheperaError::Link(error.to_string())
}

fn sensor(value: i64) -> u16 {
    value.clamp(0, u16::MAX as i64) as u16
}

impl<L: Link> Khepera for RemoteKhepera<L> {
    fn set_speed(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        self.transact(&Request::SetSpeed(left, right)).map(drop)
    }

    fn speed(&mut self) -> Result<(i32, i32), KheperaError> {
        let [l, r] = self.values(&Request::ReadSpeed)?;
        Ok((l as i32, r as i32))
    }

    fn position(&mut self) -> Result<(i32, i32), KheperaError> {
        let [l, r] = self.values(&Request::ReadPosition)?;
        Ok((l as i32, r as i32))
    }

    fn set_position(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        self.transact(&Request::SetPosition(left, right)).map(drop)
    }

    fn proximity(&mut self) -> Result<[u16; 8], KheperaError> {
        Ok(self.values::<8>(&Request::Proximity)?.map(sensor))
    }

    fn ambient(&mut self) -> Result<[u16; 8], KheperaError> {
        Ok(self.values::<8>(&Request::Ambient)?.map(sensor))
    }

    fn set_led(&mut self, led: u8, action: LedAction) -> Result<(), KheperaError> {
        self.transact(&Request::Led(led, action)).map(drop)
    }

    fn panoramic(&mut self) -> Option<&mut dyn PanoramicTurret> {
        if self.has_panoramic {
            Some(self)
        } else {
            None
        }
    }

    fn linear_camera(&mut self) -> Option<&mut dyn LinearCameraTurret> {
        if self.has_k213 {
            Some(self)
        } else {
            None
        }
    }
}

impl<L: Link> PanoramicTurret for RemoteKhepera<L> {
    fn enable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        self.transact(&Request::Panoramic(PanoramicRequest::Enable(filter)))
            .map(drop)
    }

    fn disable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        self.transact(&Request::Panoramic(PanoramicRequest::Disable(filter)))
            .map(drop)
    }

    fn read(&mut self, filter: FilterKind) -> Result<Vec<u16>, KheperaError> {
        let values = self.transact(&Request::Panoramic(PanoramicRequest::Read(filter)))?;
        Ok(values.into_iter().map(sensor).collect())
    }

    fn set_lambda(&mut self, lambda: f64) -> Result<(), KheperaError> {
        let milli = (lambda * 1000.0).round();
        if !(1.0..1e12).contains(&milli) {
            return Err(KheperaError::OutOfRange {
                what: "λ (×1000)",
                value: milli as i64,
                range: "1…10^12",
            });
        }
        self.transact(&Request::Panoramic(PanoramicRequest::SetLambda(
            milli as i64,
        )))
        .map(drop)
    }

    fn set_bits(&mut self, bits: u32) -> Result<(), KheperaError> {
        self.transact(&Request::Panoramic(PanoramicRequest::SetBits(bits)))
            .map(drop)
    }

    fn set_region_of_interest(&mut self, first: usize, last: usize) -> Result<(), KheperaError> {
        self.transact(&Request::Panoramic(PanoramicRequest::SetRegion(
            first, last,
        )))
        .map(drop)
    }

    fn region_of_interest(&mut self) -> Result<(usize, usize), KheperaError> {
        let [a, b] = self.values(&Request::Panoramic(PanoramicRequest::Region))?;
        Ok((a.max(0) as usize, b.max(0) as usize))
    }

    fn bits(&mut self) -> Result<u32, KheperaError> {
        let [b] = self.values(&Request::Panoramic(PanoramicRequest::Bits))?;
        Ok(b.clamp(0, 32) as u32)
    }

    fn lambda(&mut self) -> Result<f64, KheperaError> {
        let [x] = self.values(&Request::Panoramic(PanoramicRequest::Lambda))?;
        Ok(x as f64 / 1000.0)
    }
}

impl<L: Link> LinearCameraTurret for RemoteKhepera<L> {
    fn pixels(&mut self) -> Result<Vec<u16>, KheperaError> {
        let values = self.transact(&Request::K213Pixels)?;
        Ok(values.into_iter().map(sensor).collect())
    }

    fn light_level(&mut self) -> Result<u16, KheperaError> {
        let [v] = self.values(&Request::K213Light)?;
        Ok(sensor(v))
    }
}
