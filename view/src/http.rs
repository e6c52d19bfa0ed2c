//! A small HTTP/1.1 server on the standard library: the page, the scene, the state, the
//! controls, and a Server-Sent Events stream of samples. Every connection gets a thread of
//! its own and closes after its response (the stream is the response); requests are bounded
//! in size and time, and nothing a client sends can panic the server. A request the run's
//! token does not allow (`token.rs`) is answered 403 before anything else is looked at.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::hub::{Control, Hub, Status};
use crate::sample::num;
use crate::token::Access;

const PAGE: &str = include_str!("../page/index.html");
const SCRIPT: &str = include_str!("../page/view.js");

/// Connections served at once; one more is answered 503 and closed.
pub const MAX_CONNECTIONS: usize = 64;
/// A request's head (line and headers) may not be longer.
const MAX_HEAD: usize = 8192;
/// How long a request may take to arrive, and a write to a client may block: a client that
/// reads nothing for this long is let go.
const IO_TIMEOUT: Duration = Duration::from_secs(2);
/// At most this many stream messages a second per client: samples between them are sent
/// together.
const MESSAGE_INTERVAL: Duration = Duration::from_millis(33);
/// A stream says something at least this often, so that a closed tab is noticed.
const KEEPALIVE: Duration = Duration::from_secs(1);

pub struct Shared {
    pub hub: Arc<Hub>,
    pub scene: String,
    pub stop: AtomicBool,
    pub access: Access,
}

pub fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    for stream in listener.incoming() {
        if shared.stop.load(Ordering::Relaxed) {
            break;
        }
        let Ok(stream) = stream else {
            // Out of descriptors and the like: wait a little rather than spin.
            std::thread::sleep(Duration::from_millis(10));
            continue;
        };
        let hub = &shared.hub;
        if hub.connections.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            hub.connections.fetch_sub(1, Ordering::SeqCst);
            let _ = stream.set_write_timeout(Some(IO_TIMEOUT));
            let _ = respond(&stream, "503 Service Unavailable", "text/plain", b"busy\n");
            continue;
        }
        let client = Arc::clone(&shared);
        let spawned = std::thread::Builder::new()
            .name("regatta-view-client".to_owned())
            .spawn(move || {
                serve(&stream, &client);
                let _ = stream.shutdown(Shutdown::Both);
                client.hub.connections.fetch_sub(1, Ordering::SeqCst);
            });
        if spawned.is_err() {
            shared.hub.connections.fetch_sub(1, Ordering::SeqCst);
        }
    }
}

/// A request's method, path, query and the headers the server reads.
struct Request {
    method: String,
    path: String,
    query: String,
    host: Option<String>,
    origin: Option<String>,
    /// The token the request carried: `?token=` or `Authorization: token …`.
    token: Option<String>,
}

fn read_request(mut stream: &TcpStream) -> Option<Request> {
    stream.set_read_timeout(Some(IO_TIMEOUT)).ok()?;
    let mut head = Vec::with_capacity(1024);
    let mut buffer = [0u8; 1024];
    let started = Instant::now();
    while !head.windows(4).any(|w| w == b"\r\n\r\n") {
        if head.len() > MAX_HEAD || started.elapsed() > IO_TIMEOUT {
            return None;
        }
        let n = stream.read(&mut buffer).ok()?;
        if n == 0 {
            return None;
        }
        head.extend_from_slice(&buffer[..n]);
    }
    let text = String::from_utf8_lossy(&head);
    let mut lines = text.split("\r\n");
    let mut first = lines.next()?.split(' ');
    let method = first.next()?.to_owned();
    let target = first.next()?;
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let mut request = Request {
        method,
        path: path.to_owned(),
        query: query.to_owned(),
        host: None,
        origin: None,
        token: query
            .split('&')
            .find_map(|p| p.strip_prefix("token="))
            .map(str::to_owned),
    };
    for line in lines {
        let Some((name, value)) = line.split_once(':') else {
            continue;
        };
        let value = value.trim().to_owned();
        match name.trim().to_ascii_lowercase().as_str() {
            "host" => request.host = Some(value),
            "origin" => request.origin = Some(value),
            "authorization" if request.token.is_none() => {
                request.token = value.strip_prefix("token ").map(|t| t.trim().to_owned());
            }
            _ => {}
        }
    }
    Some(request)
}

fn respond(mut stream: &TcpStream, status: &str, kind: &str, body: &[u8]) -> std::io::Result<()> {
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)?;
    stream.flush()
}

fn serve(stream: &TcpStream, shared: &Shared) {
    let _ = stream.set_write_timeout(Some(IO_TIMEOUT));
    let _ = stream.set_nodelay(true);
    let Some(request) = read_request(stream) else {
        let _ = respond(stream, "400 Bad Request", "text/plain", b"bad request\n");
        return;
    };
    let text = "text/plain; charset=utf-8";
    // Before anything else, even which paths exist: a stranger gets 403 and nothing more.
    if !shared.access.allows(request.token.as_deref()) {
        let _ = respond(stream, "403 Forbidden", text, b"forbidden\n");
        return;
    }
    let _ = match (request.method.as_str(), request.path.as_str()) {
        ("GET", "/") | ("GET", "/index.html") => respond(
            stream,
            "200 OK",
            "text/html; charset=utf-8",
            page(request.token.is_some().then_some(&shared.access.token)).as_bytes(),
        ),
        ("GET", "/view.js") => respond(
            stream,
            "200 OK",
            "text/javascript; charset=utf-8",
            SCRIPT.as_bytes(),
        ),
        ("GET", "/scene.json") => respond(
            stream,
            "200 OK",
            "application/json",
            shared.scene.as_bytes(),
        ),
        ("GET", "/state.json") => respond(
            stream,
            "200 OK",
            "application/json",
            state_json(&shared.hub).as_bytes(),
        ),
        ("GET", "/events") => {
            stream_events(stream, shared, &request.query);
            Ok(())
        }
        ("POST", "/control") => {
            // A page of another site may not drive the run (browsers send its Origin).
            let foreign = match (&request.origin, &request.host) {
                (Some(origin), Some(host)) => {
                    origin.split("://").nth(1).unwrap_or(origin) != host.as_str()
                }
                (Some(_), None) => true,
                _ => false,
            };
            match Control::parse(&request.query) {
                _ if foreign => respond(stream, "403 Forbidden", text, b"foreign origin\n"),
                Some(control) => {
                    shared.hub.send(control);
                    respond(stream, "200 OK", text, b"ok\n")
                }
                None => respond(stream, "400 Bad Request", text, b"unknown control\n"),
            }
        }
        _ => respond(stream, "404 Not Found", text, b"not found\n"),
    };
}

/// The page, its script's address carrying the token the page was opened with (the script
/// then adds it to every request it makes).
fn page(token: Option<&String>) -> String {
    match token {
        Some(token) => PAGE.replace(
            "<script src=\"view.js\">",
            &format!("<script src=\"view.js?token={token}\">"),
        ),
        None => PAGE.to_owned(),
    }
}

/// The latest sample and the status, for scripts and tests.
fn state_json(hub: &Hub) -> String {
    let state = hub.lock();
    let sample = state.samples.back().cloned();
    let status = state.status.clone();
    drop(state);
    let mut out = String::from("{\"status\":");
    write_status(&status, &mut out);
    out.push_str(",\"sample\":");
    match sample {
        Some(sample) => sample.write_json(usize::MAX, &mut out),
        None => out.push_str("null"),
    }
    out.push('}');
    out
}

fn write_status(status: &Status, out: &mut String) {
    out.push_str(&format!(
        "{{\"paused\":{},\"speed\":{},\"seed\":\"{}\",\"finished\":{},\"rate\":{},\"replay\":{},\"note\":{}}}",
        status.paused,
        status.speed.map_or("null".to_owned(), num),
        status.seed,
        status.finished,
        num(status.rate),
        status.replay,
        serde_json::Value::String(status.note.clone())
    ));
}

/// Counts a client among the watchers while it lives.
struct Watching<'a>(&'a Hub, usize);

impl<'a> Watching<'a> {
    fn new(hub: &'a Hub, robot: usize) -> Watching<'a> {
        hub.select(robot, true);
        hub.watchers.fetch_add(1, Ordering::SeqCst);
        Watching(hub, robot)
    }
}

impl Drop for Watching<'_> {
    fn drop(&mut self) {
        self.0.watchers.fetch_sub(1, Ordering::SeqCst);
        self.0.select(self.1, false);
    }
}

/// The stream of samples: at first every sample the ring holds (a client's trail starts with
/// them), then whatever came since the last message, at most ~30 messages a second. A client
/// too slow to take them loses the oldest (the ring moves on without it), never a step.
fn stream_events(mut stream: &TcpStream, shared: &Shared, query: &str) {
    let robot = query
        .split('&')
        .find_map(|p| p.strip_prefix("robot="))
        .and_then(|r| r.parse::<usize>().ok())
        .unwrap_or(0);
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
    if stream.write_all(head.as_bytes()).is_err() {
        return;
    }
    let hub = &shared.hub;
    let _watching = Watching::new(hub, robot);
    let (mut cursor, mut event_cursor, mut epoch) = (0u64, 0u64, u64::MAX);
    let mut last_status = None;
    let mut last_message = Instant::now();
    let mut out = String::new();
    while !shared.stop.load(Ordering::Relaxed) {
        let mut state = hub.lock();
        let fresh = |s: &crate::hub::State| {
            s.next() > cursor
                || s.first_event + s.events.len() as u64 > event_cursor
                || s.epoch != epoch
                || last_status.as_ref() != Some(&s.status)
        };
        if !fresh(&state) {
            state = hub.wait(state, KEEPALIVE);
        }
        let reset = state.epoch != epoch;
        if reset {
            epoch = state.epoch;
            cursor = 0;
            event_cursor = 0;
        }
        let start = cursor.max(state.first);
        let samples: Vec<_> = state
            .samples
            .iter()
            .skip((start - state.first) as usize)
            .cloned()
            .collect();
        cursor = state.next();
        let event_start = event_cursor.max(state.first_event);
        let events: Vec<_> = state
            .events
            .iter()
            .skip((event_start - state.first_event) as usize)
            .cloned()
            .collect();
        event_cursor = state.first_event + state.events.len() as u64;
        let status = state.status.clone();
        drop(state);
        let quiet = samples.is_empty() && events.is_empty() && !reset;
        if quiet && last_status.as_ref() == Some(&status) {
            if last_message.elapsed() >= KEEPALIVE {
                if stream.write_all(b": still here\n\n").is_err() {
                    return;
                }
                last_message = Instant::now();
            }
            continue;
        }
        out.clear();
        out.push_str("data: {\"reset\":");
        out.push_str(if reset { "true" } else { "false" });
        out.push_str(",\"status\":");
        write_status(&status, &mut out);
        out.push_str(",\"samples\":[");
        for (i, sample) in samples.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            sample.write_json(robot, &mut out);
        }
        out.push_str("],\"events\":[");
        for (i, event) in events.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            event.write_json(&mut out);
        }
        out.push_str("]}\n\n");
        if stream.write_all(out.as_bytes()).is_err() || stream.flush().is_err() {
            return;
        }
        last_status = Some(status);
        last_message = Instant::now();
        std::thread::sleep(MESSAGE_INTERVAL);
    }
}
