//! What the stepping loop and the clients share: the recent samples (a ring), the events,
//! the run's status, the controls clients sent, and how many are watching. The stepping loop
//! only ever holds the lock to push a sample; clients copy what they need out of it and
//! serialise it after letting go, so a slow client slows nobody.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use crate::sample::{Event, Sample};

/// Samples kept for a client that connects late (its trail starts with them).
pub const RING: usize = 4096;
/// Events kept; the oldest go first.
const EVENTS: usize = 10_000;

/// What a client may ask of the run.
#[derive(Clone, Debug, PartialEq)]
pub enum Control {
    Play,
    Pause,
    /// Advance this many steps, then pause.
    Step(u64),
    /// Real time × factor; `None` is as fast as possible.
    Speed(Option<f64>),
    /// Start again from time 0 with this seed (the world's when `None`).
    Reset(Option<u64>),
}

impl Control {
    /// A control from its query string (`cmd=step&n=10`); `None` for anything else. Never
    /// panics, whatever the text.
    pub fn parse(query: &str) -> Option<Control> {
        let value = |key: &str| {
            query.split('&').find_map(|pair| {
                let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
                (k == key).then_some(v)
            })
        };
        match value("cmd")? {
            "play" => Some(Control::Play),
            "pause" => Some(Control::Pause),
            "step" => {
                let n = value("n").map_or(Some(1), |n| n.parse::<u64>().ok())?;
                Some(Control::Step(n.clamp(1, 1_000_000)))
            }
            "speed" => match value("x")? {
                "fast" => Some(Control::Speed(None)),
                x => {
                    let x = x
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite() && *x > 0.0)?;
                    Some(Control::Speed(Some(x.clamp(0.01, 1000.0))))
                }
            },
            "reset" => match value("seed").filter(|s| !s.is_empty()) {
                None => Some(Control::Reset(None)),
                Some(seed) => Some(Control::Reset(Some(seed.parse().ok()?))),
            },
            _ => None,
        }
    }
}

/// How the run stands, sent with every message.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Status {
    pub paused: bool,
    /// Real time × factor; `None` as fast as possible.
    pub speed: Option<f64>,
    pub seed: u64,
    /// The run reached its end (the world stays on view).
    pub finished: bool,
    /// Steps per second of wall time, lately.
    pub rate: f64,
    /// Why a control was refused, the last time one was.
    pub note: String,
    /// A replayed log: the page then plays the samples itself, with a timeline.
    pub replay: bool,
}

#[derive(Default)]
pub struct State {
    /// Samples, the oldest first; `first` is the number of the front one.
    pub samples: VecDeque<Arc<Sample>>,
    pub first: u64,
    pub events: VecDeque<Arc<Event>>,
    pub first_event: u64,
    pub status: Status,
    /// Bumped by a reset: clients then start their trails again.
    pub epoch: u64,
}

impl State {
    pub fn next(&self) -> u64 {
        self.first + self.samples.len() as u64
    }
}

pub struct Hub {
    state: Mutex<State>,
    changed: Condvar,
    /// Clients following `/events`.
    pub watchers: AtomicUsize,
    /// Open connections of every kind (bounded by the server).
    pub connections: AtomicUsize,
    controls: Mutex<Sender<Control>>,
    /// Per robot, how many clients watch it closely (their retina is copied into samples).
    selected: Mutex<Vec<usize>>,
    ring: usize,
}

impl Hub {
    pub fn new(ring: usize) -> (Arc<Hub>, Receiver<Control>) {
        let (sender, receiver) = std::sync::mpsc::channel();
        let hub = Hub {
            state: Mutex::new(State::default()),
            changed: Condvar::new(),
            watchers: AtomicUsize::new(0),
            connections: AtomicUsize::new(0),
            controls: Mutex::new(sender),
            selected: Mutex::new(Vec::new()),
            ring,
        };
        (Arc::new(hub), receiver)
    }

    /// The state, even if a client thread panicked while holding it (its data stays whole:
    /// every change to it is a single push or assignment).
    pub fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn push(&self, sample: Sample, events: Vec<Event>) {
        let mut state = self.lock();
        state.samples.push_back(Arc::new(sample));
        while state.samples.len() > self.ring {
            state.samples.pop_front();
            state.first += 1;
        }
        for event in events {
            state.events.push_back(Arc::new(event));
        }
        while state.events.len() > EVENTS {
            state.events.pop_front();
            state.first_event += 1;
        }
        drop(state);
        self.changed.notify_all();
    }

    pub fn update_status(&self, change: impl FnOnce(&mut Status)) {
        change(&mut self.lock().status);
        self.changed.notify_all();
    }

    /// Forgets the samples and events (a reset), so that clients start their trails again.
    pub fn clear(&self) {
        let mut state = self.lock();
        state.first = state.next();
        state.samples.clear();
        state.first_event += state.events.len() as u64;
        state.events.clear();
        state.epoch += 1;
        drop(state);
        self.changed.notify_all();
    }

    /// Waits until something changes or `timeout` passes.
    pub fn wait<'a>(
        &self,
        guard: MutexGuard<'a, State>,
        timeout: Duration,
    ) -> MutexGuard<'a, State> {
        match self.changed.wait_timeout(guard, timeout) {
            Ok((guard, _)) => guard,
            Err(poisoned) => poisoned.into_inner().0,
        }
    }

    pub fn send(&self, control: Control) {
        let sender = self.controls.lock().unwrap_or_else(|e| e.into_inner());
        // Nobody reading (a replay, or the run's end) is not the client's problem.
        let _ = sender.send(control);
    }

    /// A client starts (`true`) or stops watching `robot` closely.
    pub fn select(&self, robot: usize, on: bool) {
        let mut selected = self.selected.lock().unwrap_or_else(|e| e.into_inner());
        if selected.len() <= robot {
            if !on || robot > 1 << 20 {
                return;
            }
            selected.resize(robot + 1, 0);
        }
        if on {
            selected[robot] += 1;
        } else {
            selected[robot] = selected[robot].saturating_sub(1);
        }
    }

    /// Which robots some client watches closely.
    pub fn selected(&self) -> Vec<bool> {
        let selected = self.selected.lock().unwrap_or_else(|e| e.into_inner());
        selected.iter().map(|&n| n > 0).collect()
    }

    pub fn watched(&self) -> bool {
        self.watchers.load(Ordering::Relaxed) > 0
    }
}

#[cfg(test)]
mod tests {
    use super::Control;

    #[test]
    fn controls_parse_and_anything_else_is_refused() {
        assert_eq!(Control::parse("cmd=play"), Some(Control::Play));
        assert_eq!(Control::parse("cmd=step"), Some(Control::Step(1)));
        assert_eq!(Control::parse("cmd=step&n=0"), Some(Control::Step(1)));
        assert_eq!(
            Control::parse("cmd=speed&x=fast"),
            Some(Control::Speed(None))
        );
        assert_eq!(
            Control::parse("x=4&cmd=speed"),
            Some(Control::Speed(Some(4.0)))
        );
        assert_eq!(
            Control::parse("cmd=reset&seed="),
            Some(Control::Reset(None))
        );
        assert_eq!(
            Control::parse("cmd=reset&seed=7"),
            Some(Control::Reset(Some(7)))
        );
        for bad in [
            "",
            "cmd",
            "cmd=",
            "cmd=step&n=-1",
            "cmd=step&n=1e3",
            "cmd=speed&x=NaN",
            "cmd=speed&x=inf",
            "cmd=speed&x=-2",
            "cmd=speed",
            "cmd=reset&seed=99999999999999999999999",
            "cmd=launch",
            "&&&===",
        ] {
            assert_eq!(Control::parse(bad), None, "{bad:?}");
        }
    }
}
