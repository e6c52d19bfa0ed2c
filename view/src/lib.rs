//! `regatta view`: a running world (or a log) shown live in the browser. The binary serves
//! one self-contained page (HTML and a hand-written canvas renderer, embedded with
//! `include_str!`; no CDN, no library, nothing beyond the loopback), the scene's triangles
//! as the glTF export tessellates them, and a stream of samples (Server-Sent Events).
//!
//! It costs nothing when nobody watches: [`Viewer::after_step`] is one atomic load then.
//! When someone does, a sample is copied out at most every 1/30 s of simulated time and
//! 4 ms of wall time; clients serialise and send it on their own threads, and one that
//! cannot keep up loses samples, never steps. The stepping loop never waits on a client.
//!
//! Each run has a token (as Jupyter's): 128 random bits from the operating system, printed
//! in the page's URL. Listening beyond the loopback, every request needs it (`?token=` or an
//! `Authorization: token …` header) and one without it, or with another, gets 403 and nothing
//! else; on the loopback it may be left out, and a wrong one is refused all the same.

mod http;
pub mod hub;
pub mod sample;
pub mod scene;
mod token;

use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::Ordering;
use std::sync::mpsc::Receiver;
use std::sync::Arc;
use std::time::{Duration, Instant};

use regatta_runtime::sim::Simulation;
use regatta_runtime::Compiled;

pub use hub::{Control, Status};
pub use sample::{Event, RobotSample, Sample};

/// Why the viewer could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("cannot listen on {address}")]
    Bind {
        address: SocketAddr,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot start the viewer's server thread")]
    Thread(#[source] std::io::Error),
    #[error("cannot draw the viewer's token from the operating system's randomness")]
    Token(#[source] getrandom::Error),
}

/// Simulated time between samples (about a frame at real time).
const SAMPLE_PERIOD: f64 = 1.0 / 30.0;
/// Wall time between samples, at least: as fast as possible, samples then cost a bounded
/// share of the run whatever its speed.
const SAMPLE_WALL: Duration = Duration::from_millis(4);

/// The served viewer: the stepping loop's side of it.
pub struct Viewer {
    shared: Arc<http::Shared>,
    controls: Receiver<Control>,
    address: SocketAddr,
    server: Option<std::thread::JoinHandle<()>>,
    last_t: f64,
    last_wall: Option<Instant>,
    /// Per robot: visits and contacts already sent as events.
    visits_seen: Vec<usize>,
    contacts_seen: Vec<u64>,
    /// Steps and time at the last rate measurement.
    rate_mark: (Instant, u64),
    /// Whether someone watched at the last step: samples stop while nobody does, so the
    /// first watcher after a gap starts from a clean ring (no trail jumps across the gap).
    was_watched: bool,
}

impl Viewer {
    /// Serves the viewer of `compiled` on `bind:port` (port 0: a free one).
    pub fn serve(compiled: &Compiled, bind: IpAddr, port: u16) -> Result<Viewer, ViewError> {
        Viewer::start(compiled, bind, port, hub::RING)
    }

    /// Serves a recorded run: every sample at once, for the page to play with a timeline.
    pub fn replay(
        compiled: &Compiled,
        bind: IpAddr,
        port: u16,
        samples: Vec<Sample>,
        events: Vec<Event>,
    ) -> Result<Viewer, ViewError> {
        let viewer = Viewer::start(compiled, bind, port, samples.len().max(1))?;
        let hub = &viewer.shared.hub;
        hub.update_status(|s| {
            s.replay = true;
            s.finished = true;
            s.paused = true;
        });
        let last = samples.len().saturating_sub(1);
        let mut events = Some(events);
        for (index, sample) in samples.into_iter().enumerate() {
            let events = if index == last {
                events.take().unwrap_or_default()
            } else {
                Vec::new()
            };
            hub.push(sample, events);
        }
        Ok(viewer)
    }

    fn start(
        compiled: &Compiled,
        bind: IpAddr,
        port: u16,
        ring: usize,
    ) -> Result<Viewer, ViewError> {
        let address = SocketAddr::new(bind, port);
        let listener =
            TcpListener::bind(address).map_err(|source| ViewError::Bind { address, source })?;
        let address = listener
            .local_addr()
            .map_err(|source| ViewError::Bind { address, source })?;
        let (hub, controls) = hub::Hub::new(ring);
        let shared = Arc::new(http::Shared {
            hub,
            scene: scene::scene_json(compiled),
            stop: Default::default(),
            access: token::Access {
                token: token::new_token().map_err(ViewError::Token)?,
                required: !bind.is_loopback(),
            },
        });
        let server = {
            let shared = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("regatta-view".to_owned())
                .spawn(move || http::accept_loop(listener, shared))
                .map_err(ViewError::Thread)?
        };
        let robots = compiled.rig.robots.len();
        Ok(Viewer {
            shared,
            controls,
            address,
            server: Some(server),
            last_t: f64::NEG_INFINITY,
            last_wall: None,
            visits_seen: vec![0; robots],
            contacts_seen: vec![0; robots],
            rate_mark: (Instant::now(), 0),
            was_watched: false,
        })
    }

    /// The page's address, with the run's token: what a person opens.
    pub fn url(&self) -> String {
        format!("{}?token={}", self.base_url(), self.token())
    }

    /// The server's address without the token (`http://HOST:PORT/`): its paths need the
    /// token beyond the loopback.
    pub fn base_url(&self) -> String {
        match self.address.ip() {
            IpAddr::V6(ip) => format!("http://[{ip}]:{}/", self.address.port()),
            IpAddr::V4(ip) => format!("http://{ip}:{}/", self.address.port()),
        }
    }

    /// The run's token (32 hexadecimal digits), drawn from the operating system when the
    /// viewer started.
    pub fn token(&self) -> &str {
        &self.shared.access.token
    }

    /// Whether every request needs the token (the viewer listens beyond the loopback).
    pub fn token_required(&self) -> bool {
        self.shared.access.required
    }

    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Clients following the run now.
    pub fn watchers(&self) -> usize {
        self.shared.hub.watchers.load(Ordering::Relaxed)
    }

    /// After each step: a sample when someone watches and one is due; nothing otherwise.
    #[inline]
    pub fn after_step(&mut self, simulation: &Simulation) {
        if !self.shared.hub.watched() {
            self.was_watched = false;
            return;
        }
        if !self.was_watched {
            self.was_watched = true;
            self.shared.hub.clear();
            // Every visit so far again (they carry their times); contacts only from now.
            self.visits_seen.iter_mut().for_each(|v| *v = 0);
            self.publish(simulation);
            return;
        }
        if simulation.time - self.last_t < SAMPLE_PERIOD
            || self.last_wall.is_some_and(|w| w.elapsed() < SAMPLE_WALL)
        {
            return;
        }
        self.publish(simulation);
    }

    /// A sample now, whoever watches (after a single step, a reset, at the end).
    pub fn publish(&mut self, simulation: &Simulation) {
        let selected = self.shared.hub.selected();
        let sample = Sample::capture(simulation, |i| selected.get(i).copied().unwrap_or(false));
        let mut events = Vec::new();
        for (index, robot) in simulation.robots.iter().enumerate() {
            let Some(seen) = self.visits_seen.get_mut(index) else {
                continue;
            };
            for k in *seen..robot.visits.sequence.len() {
                events.push(Event {
                    t: robot
                        .visits
                        .times
                        .get(k)
                        .copied()
                        .unwrap_or(simulation.time),
                    robot: index,
                    kind: "visit",
                    buoy: Some(robot.visits.sequence[k]),
                });
            }
            *seen = robot.visits.sequence.len();
            // Contacts are counted, not timed: one began since the last sample.
            if let Some(seen) = self.contacts_seen.get_mut(index) {
                if robot.contacts.events > *seen {
                    events.push(Event {
                        t: simulation.time,
                        robot: index,
                        kind: "contact",
                        buoy: None,
                    });
                }
                *seen = robot.contacts.events;
            }
        }
        self.last_t = simulation.time;
        let now = Instant::now();
        self.last_wall = Some(now);
        let elapsed = now.duration_since(self.rate_mark.0).as_secs_f64();
        if elapsed >= 0.5 {
            let rate = simulation.steps.saturating_sub(self.rate_mark.1) as f64 / elapsed;
            self.rate_mark = (now, simulation.steps);
            self.shared.hub.update_status(|s| s.rate = rate);
        }
        self.shared.hub.push(sample, events);
    }

    /// A control a client sent, if any (never waits).
    #[inline]
    pub fn control(&self) -> Option<Control> {
        self.controls.try_recv().ok()
    }

    /// A control, waiting up to `timeout` for one (while paused).
    pub fn wait_control(&self, timeout: Duration) -> Option<Control> {
        self.controls.recv_timeout(timeout).ok()
    }

    pub fn update_status(&self, change: impl FnOnce(&mut Status)) {
        self.shared.hub.update_status(change);
    }

    /// Forgets the run shown so far (a reset): clients clear their trails and events.
    pub fn restart(&mut self, simulation: &Simulation) {
        self.shared.hub.clear();
        self.visits_seen.iter_mut().for_each(|v| *v = 0);
        self.contacts_seen.iter_mut().for_each(|v| *v = 0);
        self.last_t = f64::NEG_INFINITY;
        self.rate_mark = (Instant::now(), simulation.steps);
        self.publish(simulation);
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        // The accept loop blocks in accept: a connection of our own wakes it to see `stop`.
        let _ = TcpStream::connect_timeout(&self.address, Duration::from_millis(200));
        if let Some(server) = self.server.take() {
            let _ = server.join();
        }
    }
}
