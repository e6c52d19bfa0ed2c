//! The simulated robot that speaks the protocol: request lines in, the real robot's replies
//! out, against one robot of a running [`Simulation`].
//!
//! Lock-step: the world advances one basic time step each time the client sends `D` (set
//! speeds), the command that ends every control cycle, so a controller's reads and its speed
//! command fall exactly where a built-in controller's would. Real time: a clock advances the
//! world, and commands act on whatever step is current.
//!
//! Every complete request line gets exactly one reply line, so the link never desynchronises:
//! garbage, unknown commands, wrong parameters, non-ASCII bytes and requests the robot cannot
//! carry out get the robot shell's `Command not found`; an overlong line is discarded up to
//! its terminator and answered once; an empty line is ignored, as the robot ignores it.

use std::io;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use regatta_runtime::khepera::{Khepera, KheperaError};
use regatta_runtime::sim::Simulation;

use crate::link::Link;
use crate::protocol::{Malformed, PanoramicRequest, Request, MAX_LINE, NOT_FOUND};

/// Splits a byte stream into request lines (LF or CR ends one), bounding their length.
#[derive(Debug, Default)]
pub struct LineSplitter {
    buffer: Vec<u8>,
    overlong: bool,
}

impl LineSplitter {
    /// Feeds bytes; complete lines (or `TooLong` for a discarded one) go to `lines`.
    pub fn push(&mut self, bytes: &[u8], lines: &mut Vec<Result<Vec<u8>, Malformed>>) {
        for &byte in bytes {
            if byte == b'\n' || byte == b'\r' {
                if self.overlong {
                    lines.push(Err(Malformed::TooLong));
                } else if !self.buffer.is_empty() {
                    lines.push(Ok(std::mem::take(&mut self.buffer)));
                }
                self.overlong = false;
                self.buffer.clear();
            } else if !self.overlong {
                self.buffer.push(byte);
                if self.buffer.len() > MAX_LINE {
                    self.overlong = true;
                    self.buffer.clear();
                }
            }
        }
    }
}

/// Carries out one request on a robot; the reply line without its CR LF.
pub fn answer(request: &Request, robot: &mut dyn Khepera) -> Result<String, KheperaError> {
    let list = |letter: &str, values: &[i64]| {
        let mut out = letter.to_owned();
        for v in values {
            out.push(',');
            out.push_str(&v.to_string());
        }
        out
    };
    let no = |what: &'static str| KheperaError::NoDevice(what);
    Ok(match request {
        Request::SpeedPid(_) => "a".into(),
        // BIOS 0, protocol 0: the convention by which a Khepera simulator says what it is.
        Request::Version => "b,0,0".into(),
        Request::SetSpeed(l, r) => {
            robot.set_speed(*l, *r)?;
            "d".into()
        }
        Request::ReadSpeed => {
            let (l, r) = robot.speed()?;
            list("e", &[l as i64, r as i64])
        }
        Request::PositionPid(_) => "f".into(),
        Request::SetPosition(l, r) => {
            robot.set_position(*l, *r)?;
            "g".into()
        }
        Request::ReadPosition => {
            let (l, r) = robot.position()?;
            list("h", &[l as i64, r as i64])
        }
        Request::SpeedProfile(_) => "j".into(),
        // Not at a position target, speed mode, no error, for both wheels.
        Request::MotionStatus => "k,0,1,0,0,1,0".into(),
        Request::Led(n, action) => {
            robot.set_led(*n, *action)?;
            "l".into()
        }
        Request::Proximity => list("n", &robot.proximity()?.map(i64::from)),
        Request::Ambient => list("o", &robot.ambient()?.map(i64::from)),
        Request::K213Pixels => {
            let camera = robot.linear_camera().ok_or(no("K213 turret"))?;
            let pixels: Vec<i64> = camera.pixels()?.into_iter().map(i64::from).collect();
            list("t,2,n", &pixels)
        }
        Request::K213Light => {
            let camera = robot.linear_camera().ok_or(no("K213 turret"))?;
            list("t,2,l", &[camera.light_level()? as i64])
        }
        Request::Panoramic(p) => {
            let turret = robot.panoramic().ok_or(no("Panoramic turret"))?;
            match p {
                PanoramicRequest::Enable(f) => {
                    turret.enable_filter(*f)?;
                    "t,3,e".into()
                }
                PanoramicRequest::Disable(f) => {
                    turret.disable_filter(*f)?;
                    "t,3,d".into()
                }
                PanoramicRequest::Read(f) => {
                    let values: Vec<i64> = turret.read(*f)?.into_iter().map(i64::from).collect();
                    list("t,3,r", &values)
                }
                PanoramicRequest::SetLambda(x) => {
                    turret.set_lambda(*x as f64 / 1000.0)?;
                    "t,3,l".into()
                }
                PanoramicRequest::Lambda => list("t,3,m", &[thousandths(turret.lambda()?)]),
                PanoramicRequest::SetBits(b) => {
                    turret.set_bits(*b)?;
                    "t,3,b".into()
                }
                PanoramicRequest::Bits => list("t,3,c", &[turret.bits()? as i64]),
                PanoramicRequest::SetRegion(a, b) => {
                    turret.set_region_of_interest(*a, *b)?;
                    "t,3,i".into()
                }
                PanoramicRequest::Region => {
                    let (a, b) = turret.region_of_interest()?;
                    list("t,3,j", &[a as i64, b as i64])
                }
            }
        }
    })
}

/// λ in the protocol's integer unit.
fn thousandths(x: f64) -> i64 {
    let milli = x * 1000.0;
    if milli.is_finite() {
        milli.round() as i64
    } else {
        0
    }
}

/// How the served world advances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pacing {
    /// One step per `D` command.
    LockStep,
    /// One step per basic time step of wall-clock time.
    RealTime,
}

/// What a session saw.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ServeStats {
    /// Request lines answered.
    pub requests: u64,
    /// Lines that were not requests (answered `Command not found`).
    pub malformed: u64,
    /// Requests the robot could not carry out (answered `Command not found`).
    pub refused: u64,
    /// The last line that was refused or malformed, and why.
    pub last_problem: Option<String>,
}

/// Whether serving should go on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// The requested number of steps is done.
    Done,
}

/// What runs after each served step.
pub type StepHook<'s> = Box<dyn FnMut(&Simulation) -> io::Result<()> + 's>;

/// A real-time world that fell behind the clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lag {
    /// Steps the world was behind when it was noticed.
    pub steps_behind: u64,
    /// Simulated time then (s).
    pub time: f64,
    /// The basic time step, in ms of wall time.
    pub period_ms: f64,
}

/// Steps a real-time world may lag (a slow step, a busy machine) before it is said once.
pub const LAG_WARNING_STEPS: u64 = 10;

/// One served robot of a simulation.
pub struct Server<'s, 'c> {
    pub simulation: &'s mut Simulation<'c>,
    pub robot: usize,
    pub pacing: Pacing,
    /// Stop after this many steps.
    pub max_steps: Option<u64>,
    pub stats: ServeStats,
    /// Called after each step, before the next step's sensors are read (where a log records).
    pub on_step: Option<StepHook<'s>>,
    /// The error the hook returned, which ended serving.
    pub hook_error: Option<io::Error>,
    /// Called once, the first time a real-time world falls behind the clock by more than
    /// [`LAG_WARNING_STEPS`].
    pub on_lag: Option<Box<dyn FnMut(Lag) + 's>>,
    splitter: LineSplitter,
    lines: Vec<Result<Vec<u8>, Malformed>>,
}

impl<'s, 'c> Server<'s, 'c> {
    /// Takes the robot's built-in controller away and reads its sensors for the first step.
    pub fn new(
        simulation: &'s mut Simulation<'c>,
        robot: usize,
        pacing: Pacing,
        max_steps: Option<u64>,
    ) -> Server<'s, 'c> {
        simulation.detach_controller(robot);
        simulation.sense();
        Server {
            simulation,
            robot,
            pacing,
            max_steps,
            stats: ServeStats::default(),
            on_step: None,
            hook_error: None,
            on_lag: None,
            splitter: LineSplitter::default(),
            lines: Vec::new(),
        }
    }

    /// Ends a client's session: its half-sent line is dropped and the robot stops, so that
    /// nothing of one client reaches the next.
    pub fn end_session(&mut self) {
        self.splitter = LineSplitter::default();
        self.lines.clear();
        let _ = self.simulation.khepera(self.robot).set_speed(0, 0);
    }

    fn done(&self) -> bool {
        self.max_steps
            .is_some_and(|max| self.simulation.steps >= max)
    }

    /// Ends the current control period: steps the world until the robot's controller is next
    /// due (its `controlPeriod`, a whole number of steps), reading the sensors at each step,
    /// so a served robot is read and commanded where a built-in controller would be.
    pub fn advance(&mut self) -> Flow {
        loop {
            if self.advance_step() == Flow::Done {
                return Flow::Done;
            }
            if self.simulation.control_due(self.robot) {
                return Flow::Continue;
            }
        }
    }

    /// Ends the current physics step and reads the sensors for the next.
    pub fn advance_step(&mut self) -> Flow {
        self.simulation.act();
        if let Some(hook) = &mut self.on_step {
            if let Err(error) = hook(self.simulation) {
                self.hook_error = Some(error);
                return Flow::Done;
            }
        }
        if self.done() {
            return Flow::Done;
        }
        self.simulation.sense();
        Flow::Continue
    }

    /// Handles received bytes; the replies are appended to `out`.
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<u8>) -> Flow {
        self.splitter.push(bytes, &mut self.lines);
        let lines = std::mem::take(&mut self.lines);
        let mut flow = Flow::Continue;
        for line in lines {
            if flow == Flow::Done {
                break;
            }
            let request = line.and_then(|l| Request::parse(&l));
            if request == Err(Malformed::Empty) {
                continue;
            }
            self.stats.requests += 1;
            let reply = match request {
                Ok(request) => {
                    let mut robot = self.simulation.khepera(self.robot);
                    match answer(&request, &mut robot) {
                        Ok(reply) => {
                            if matches!(request, Request::SetSpeed(..))
                                && self.pacing == Pacing::LockStep
                                && !self.done()
                            {
                                flow = self.advance();
                            }
                            reply
                        }
                        Err(error) => {
                            self.stats.refused += 1;
                            self.stats.last_problem =
                                Some(format!("{}: {error}", request.encode()));
                            NOT_FOUND.to_owned()
                        }
                    }
                }
                Err(problem) => {
                    self.stats.malformed += 1;
                    self.stats.last_problem = Some(problem.to_string());
                    NOT_FOUND.to_owned()
                }
            };
            out.extend_from_slice(reply.as_bytes());
            out.extend_from_slice(b"\r\n");
        }
        flow
    }
}

/// Why serving a link ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// The requested steps are done.
    Done,
    /// The client closed the link.
    Closed,
    /// `stop` was raised (Ctrl-C).
    Stopped,
}

/// Serves one link in lock-step until the client leaves, the steps are done or `stop` rises.
pub fn serve_lock_step(
    server: &mut Server,
    link: &mut dyn Link,
    stop: &AtomicBool,
) -> io::Result<Ended> {
    link.set_timeout(Some(Duration::from_millis(100)))?;
    let mut buffer = [0u8; 4096];
    let mut out = Vec::new();
    loop {
        if stop.load(Ordering::Relaxed) {
            return Ok(Ended::Stopped);
        }
        let n = match link.read(&mut buffer) {
            Ok(0) => return Ok(Ended::Closed),
            Ok(n) => n,
            Err(e) if is_timeout(&e) => continue,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        out.clear();
        let flow = server.feed(&buffer[..n], &mut out);
        link.write_all(&out)?;
        link.flush()?;
        if flow == Flow::Done {
            linger(server, link, stop)?;
            return Ok(Ended::Done);
        }
    }
}

/// After the last step, answers what the client still asks (the world stays as it ended, so
/// a final `D,0,0` is answered) until it leaves or falls silent for a second: closing at once
/// could drop the last reply before the client has read it.
fn linger(server: &mut Server, link: &mut dyn Link, stop: &AtomicBool) -> io::Result<()> {
    let mut buffer = [0u8; 4096];
    let mut out = Vec::new();
    let mut quiet = Instant::now();
    while quiet.elapsed() < Duration::from_secs(1) && !stop.load(Ordering::Relaxed) {
        let n = match link.read(&mut buffer) {
            Ok(0) => return Ok(()),
            Ok(n) => n,
            Err(e) if is_timeout(&e) || e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) if e.kind() == io::ErrorKind::BrokenPipe => return Ok(()),
            Err(e) if e.raw_os_error() == Some(5) => return Ok(()), // EIO: the pty's client left
            Err(e) => return Err(e),
        };
        quiet = Instant::now();
        out.clear();
        server.feed(&buffer[..n], &mut out);
        link.write_all(&out)?;
        link.flush()?;
    }
    Ok(())
}

/// Serves one link in real time: the world steps every basic time step of wall-clock time
/// whatever the client does.
pub fn serve_real_time(
    server: &mut Server,
    link: &mut dyn Link,
    stop: &AtomicBool,
) -> io::Result<Ended> {
    let period = Duration::from_secs_f64(server.simulation.time_step);
    link.set_timeout(Some(period.min(Duration::from_millis(10))))?;
    let mut buffer = [0u8; 4096];
    let mut out = Vec::new();
    let start = Instant::now();
    let first_step = server.simulation.steps;
    loop {
        if stop.load(Ordering::Relaxed) {
            return Ok(Ended::Stopped);
        }
        // Catch up with the clock.
        let due = (start.elapsed().as_secs_f64() / period.as_secs_f64()) as u64;
        let behind = due.saturating_sub(server.simulation.steps - first_step);
        if behind > LAG_WARNING_STEPS {
            if let Some(mut warn) = server.on_lag.take() {
                warn(Lag {
                    steps_behind: behind,
                    time: server.simulation.time,
                    period_ms: period.as_secs_f64() * 1000.0,
                });
            }
        }
        // A world that cannot keep up still answers its client: at most a few steps between
        // two reads of the link.
        let mut caught_up = 0;
        while server.simulation.steps - first_step < due && caught_up < LAG_WARNING_STEPS {
            if server.advance_step() == Flow::Done {
                return Ok(Ended::Done);
            }
            caught_up += 1;
        }
        let n = match link.read(&mut buffer) {
            Ok(0) => return Ok(Ended::Closed),
            Ok(n) => n,
            Err(e) if is_timeout(&e) || e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        out.clear();
        server.feed(&buffer[..n], &mut out);
        link.write_all(&out)?;
        link.flush()?;
    }
}

pub(crate) fn is_timeout(error: &io::Error) -> bool {
    matches!(
        error.kind(),
        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
    )
}
