//! `regatta view` end to end: the URL on the first line, clients that vanish, read slowly or
//! come twenty at once (the run ends with the same log bytes as `regatta run`), garbage
//! requests, a log replayed, and the page in a real browser (Debian's Chromium, headless,
//! driven by `tests/browser/view.js`): the lamps and the robot drawn where the run says, and
//! the robot moving between two screenshots.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, ChildStdout, Stdio};
use std::time::{Duration, Instant};

use common::{ok, regatta, root, temp_dir};

/// Starts `regatta view ARGS`; returns the child, its URL's address (host:port, on the
/// loopback), the run's token and the rest of its standard output.
fn view(args: &[&str]) -> (Child, String, String, BufReader<ChildStdout>) {
    let mut child = regatta()
        .arg("view")
        .args(args)
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    let (address, token) = first
        .trim()
        .strip_prefix("http://")
        .and_then(|rest| rest.split_once("/?token="))
        .unwrap_or_else(|| panic!("the first line is not the URL with its token: {first:?}"));
    assert!(
        token.len() == 32 && token.bytes().all(|c| c.is_ascii_hexdigit()),
        "{token}"
    );
    // Listening on every address, the loopback is one of them.
    let address = address.replace("0.0.0.0:", "127.0.0.1:");
    assert!(address.starts_with("127.0.0.1:"), "{address}");
    (child, address, token.to_owned(), out)
}

/// Kills a viewer left running when a test fails.
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One HTTP request; the whole response as text.
fn request(address: &str, method: &str, target: &str) -> String {
    request_with(address, method, target, "")
}

/// One HTTP request with more header lines (each ending in CRLF); the whole response.
fn request_with(address: &str, method: &str, target: &str, headers: &str) -> String {
    let mut stream = TcpStream::connect(address).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    write!(
        stream,
        "{method} {target} HTTP/1.1\r\nHost: {address}\r\n{headers}\r\n"
    )
    .unwrap();
    let mut response = String::new();
    stream.read_to_string(&mut response).unwrap();
    response
}

/// A stream client: connected to /events, its header read.
fn follow(address: &str) -> TcpStream {
    let mut stream = TcpStream::connect(address).unwrap();
    write!(
        stream,
        "GET /events?robot=0 HTTP/1.1\r\nHost: {address}\r\n\r\n"
    )
    .unwrap();
    stream
}

fn wait(child: &mut Child, seconds: u64) -> std::process::ExitStatus {
    let started = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if started.elapsed() > Duration::from_secs(seconds) {
            let _ = child.kill();
            panic!("regatta view did not end within {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn clients_that_vanish_read_slowly_or_crowd_change_no_byte_of_the_log() {
    let dir = temp_dir("view-clients");
    let (plain, viewed) = (dir.join("run.mcap"), dir.join("view.mcap"));
    let world = "worlds/single_buoy.wbt";
    let steps = "1500";
    let run = regatta()
        .current_dir(root())
        .args(["run", world, "--steps", steps, "--log"])
        .arg(&plain)
        .output()
        .unwrap();
    ok(&run);

    let (child, address, _token, _out) = view(&[
        world,
        "--paused",
        "--speed",
        "25",
        "--steps",
        steps,
        "--exit",
        "--log",
        viewed.to_str().unwrap(),
    ]);
    let mut running = Running(child);
    // Garbage first: none of it may stop the server.
    for garbage in [
        &b"\x00\xff\xfe garbage\r\n\r\n"[..],
        b"GET",
        &[b'A'; 20_000][..],
        b"POST /control?cmd=step&n=-1 HTTP/1.1\r\n\r\n",
        b"POST /control?cmd=speed&x=NaN HTTP/1.1\r\n\r\n",
        b"GET /events?robot=99999999999999999999 HTTP/1.1\r\n\r\n",
    ] {
        if let Ok(mut stream) = TcpStream::connect(&address) {
            let _ = stream.write_all(garbage);
        }
    }
    let state = request(&address, "GET", "/state.json");
    assert!(state.contains("\"paused\":true"), "{state}");
    assert!(request(&address, "POST", "/control?cmd=launch").starts_with("HTTP/1.1 400"));
    // One that vanishes after its first message, one that never reads (at 25× real time
    // for 2 s its socket's buffers fill, and the server's writes to it block), twenty that
    // read.
    let mut vanishing = follow(&address);
    let mut first = [0u8; 64];
    let _ = vanishing.read(&mut first);
    drop(vanishing);
    let slow = follow(&address);
    let crowd: Vec<_> = (0..20)
        .map(|_| {
            let mut stream = follow(&address);
            std::thread::spawn(move || {
                let mut bytes = 0usize;
                let mut buffer = [0u8; 65536];
                while let Ok(n) = stream.read(&mut buffer) {
                    if n == 0 {
                        break;
                    }
                    bytes += n;
                }
                bytes
            })
        })
        .collect();
    std::thread::sleep(Duration::from_millis(300));
    assert!(request(&address, "POST", "/control?cmd=play").starts_with("HTTP/1.1 200"));
    let status = wait(&mut running.0, 120);
    assert!(status.success(), "regatta view failed: {status}");
    drop(slow);
    for reader in crowd {
        assert!(reader.join().unwrap() > 0, "a client received nothing");
    }
    let (a, b) = (
        std::fs::read(&plain).unwrap(),
        std::fs::read(&viewed).unwrap(),
    );
    assert!(a == b, "the viewed run's log differs from the plain run's");
}

#[test]
fn a_log_replays_with_every_sample_at_once() {
    let dir = temp_dir("view-replay");
    let log = dir.join("run.mcap");
    let run = regatta()
        .current_dir(root())
        .args(["run", "worlds/single_buoy.wbt", "--duration", "20", "--log"])
        .arg(&log)
        .output()
        .unwrap();
    ok(&run);
    let (child, address, _token, _out) = view(&[log.to_str().unwrap()]);
    let _running = Running(child);
    let state = request(&address, "GET", "/state.json");
    assert!(state.contains("\"replay\":true"), "{state}");
    // The first message of the stream holds the whole run, up to its last pose.
    let mut stream = follow(&address);
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut text = String::new();
    let mut buffer = [0u8; 65536];
    let started = Instant::now();
    while !text.contains("]}\n\n") {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "no whole message: {text}"
        );
        let n = stream.read(&mut buffer).unwrap();
        assert!(n > 0, "the stream ended early");
        text.push_str(&String::from_utf8_lossy(&buffer[..n]));
    }
    assert!(
        text.contains("\"t\":20,"),
        "the replay stops before the run's end"
    );
    assert!(
        text.contains("\"kind\":\"visit\""),
        "no buoy visit replayed"
    );
}

/// The status line of a response, and whether its body holds anything of the run.
fn refused(response: &str) -> bool {
    response.starts_with("HTTP/1.1 403 ")
        && response.ends_with("\r\n\r\nforbidden\n")
        && !response.contains("robots")
}

/// The status code of a request whose response is a stream (only its head is read).
fn stream_status(address: &str, target: &str, headers: &str) -> String {
    let mut stream = TcpStream::connect(address).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    write!(
        stream,
        "GET {target} HTTP/1.1\r\nHost: {address}\r\n{headers}\r\n"
    )
    .unwrap();
    let mut line = String::new();
    BufReader::new(stream).read_line(&mut line).unwrap();
    line.trim().to_owned()
}

#[test]
fn beyond_the_loopback_every_request_needs_the_token_and_a_wrong_one_is_refused_everywhere() {
    let (child, address, token, _out) =
        view(&["worlds/single_buoy.wbt", "--paused", "--bind", "0.0.0.0"]);
    let _running = Running(child);
    // The token with its last digit changed: the same length, wrong at the end.
    let last = if token.ends_with('0') { '1' } else { '0' };
    let wrong = format!("{}{last}", &token[..31]);
    let targets = [
        ("GET", "/"),
        ("GET", "/index.html"),
        ("GET", "/view.js"),
        ("GET", "/scene.json"),
        ("GET", "/state.json"),
        ("POST", "/control?cmd=step&n=1"),
        ("GET", "/no-such-page"),
    ];
    for (method, path) in targets {
        let joined = |extra: &str| {
            let separator = if path.contains('?') { '&' } else { '?' };
            format!("{path}{separator}{extra}")
        };
        // No token, a wrong one of the same length, a short one, an empty one, one in the
        // header: 403 and nothing else.
        for target in [
            path.to_owned(),
            joined(&format!("token={wrong}")),
            joined(&format!("token={}", &token[..16])),
            joined("token="),
        ] {
            let response = request(&address, method, &target);
            assert!(refused(&response), "{method} {target}: {response}");
        }
        let response = request_with(
            &address,
            method,
            path,
            &format!("Authorization: token {wrong}\r\n"),
        );
        assert!(refused(&response), "{method} {path} (header): {response}");
        // The right one, in the query or the header.
        let right = request(&address, method, &joined(&format!("token={token}")));
        let expected = if path == "/no-such-page" {
            "404"
        } else {
            "200"
        };
        assert!(
            right.starts_with(&format!("HTTP/1.1 {expected} ")),
            "{method} {path} with the token: {right}"
        );
        let header = request_with(
            &address,
            method,
            path,
            &format!("Authorization: token {token}\r\n"),
        );
        assert!(
            header.starts_with(&format!("HTTP/1.1 {expected} ")),
            "{method} {path} with the token in the header: {header}"
        );
    }
    // The page hands the token to its script, which adds it to every request.
    let page = request(&address, "GET", &format!("/?token={token}"));
    assert!(
        page.contains(&format!("src=\"view.js?token={token}\"")),
        "{page}"
    );
    // The stream: refused without the token or with a wrong one, served with it.
    for target in [
        "/events?robot=0".to_owned(),
        format!("/events?robot=0&token={wrong}"),
    ] {
        assert_eq!(
            stream_status(&address, &target, ""),
            "HTTP/1.1 403 Forbidden"
        );
    }
    assert_eq!(
        stream_status(&address, &format!("/events?robot=0&token={token}"), ""),
        "HTTP/1.1 200 OK"
    );
    // The controls went through only with the token: two single steps (query and header),
    // and none of the ten refused ones.
    let started = Instant::now();
    loop {
        let state = request(&address, "GET", &format!("/state.json?token={token}"));
        if state.contains("\"steps\":2,") {
            break;
        }
        assert!(
            !state.contains("\"steps\":3,") && started.elapsed() < Duration::from_secs(20),
            "{state}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    let state = request(&address, "GET", &format!("/state.json?token={token}"));
    assert!(state.contains("\"steps\":2,"), "{state}");
}

#[test]
fn on_the_loopback_the_token_may_be_left_out_but_a_wrong_one_is_refused() {
    let (child, address, token, _out) = view(&["worlds/single_buoy.wbt", "--paused"]);
    let _running = Running(child);
    for path in ["/", "/scene.json", "/state.json"] {
        assert!(request(&address, "GET", path).starts_with("HTTP/1.1 200 "));
        let right = request(&address, "GET", &format!("{path}?token={token}"));
        assert!(right.starts_with("HTTP/1.1 200 "), "{path}: {right}");
        let wrong = request(&address, "GET", &format!("{path}?token={}", "0".repeat(32)));
        assert!(refused(&wrong), "{path}: {wrong}");
    }
    assert_eq!(
        stream_status(&address, "/events?robot=0", ""),
        "HTTP/1.1 200 OK"
    );
    assert_eq!(
        stream_status(
            &address,
            &format!("/events?robot=0&token={}", "0".repeat(32)),
            ""
        ),
        "HTTP/1.1 403 Forbidden"
    );
}

/// Whether the browser test can run here; in CI (REGATTA_REQUIRE_BROWSER=1) it must.
fn browser_available() -> bool {
    let found = |program: &str| {
        std::process::Command::new(program)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "chromium".to_owned());
    let (has_browser, has_node) = (found(&chromium), found("node"));
    if has_browser && has_node {
        return true;
    }
    let missing = if has_browser { "node" } else { "chromium" };
    assert!(
        std::env::var("REGATTA_REQUIRE_BROWSER").as_deref() != Ok("1"),
        "REGATTA_REQUIRE_BROWSER=1 but {missing} is not installed"
    );
    eprintln!("SKIPPED: the viewer's browser test needs {missing} (apt-get install chromium)");
    false
}

#[test]
fn the_page_draws_the_lamps_and_the_robot_where_the_run_says_and_the_robot_moves() {
    if !browser_available() {
        return;
    }
    let dir = temp_dir("view-browser");
    // Beyond the loopback, so that the page must carry the token to every request it makes.
    let (child, address, token, _out) =
        view(&["worlds/regatta.wbt", "--speed", "8", "--bind", "0.0.0.0"]);
    let running = Running(child);
    assert!(request(&address, "GET", "/").starts_with("HTTP/1.1 403"));
    let script = root().join("tools/tests/browser/view.js");
    let output = std::process::Command::new("node")
        .arg(&script)
        .arg(format!("http://{address}/?token={token}"))
        .arg(&dir)
        .arg("90")
        .output()
        .unwrap();
    drop(running);
    assert!(
        output.status.success(),
        "the browser script failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let shots = report["shots"].as_array().unwrap();
    let images: Vec<image::RgbaImage> = shots
        .iter()
        .map(|s| image::open(s["file"].as_str().unwrap()).unwrap().to_rgba8())
        .collect();
    for (shot, image) in shots.iter().zip(&images) {
        // A heading arrow is drawn over everything: a lamp right behind one is not looked at.
        let robots: Vec<(f64, f64)> = shot["probes"]["robots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| point(&r["at"]))
            .collect();
        let mut checked = 0;
        for lamp in shot["probes"]["lamps"].as_array().unwrap() {
            let (x, y) = point(&lamp["at"]);
            if robots
                .iter()
                .any(|r| (r.0 - x).powi(2) + (r.1 - y).powi(2) < 30.0f64.powi(2))
            {
                continue;
            }
            assert_near_colour(image, &lamp["at"], &lamp["colour"], "a buoy's lamp");
            checked += 1;
        }
        assert!(checked > 0, "no lamp in view to check");
        for robot in shot["probes"]["robots"].as_array().unwrap() {
            assert_near_colour(image, &robot["at"], &robot["colour"], "the robot");
        }
    }
    // The robot moved: where it stood first is drawn differently now, and the other way.
    let at = |shot: &serde_json::Value| point(&shot["probes"]["robots"][0]["at"]);
    let (first, second) = (at(&shots[0]), at(&shots[1]));
    let distance = ((first.0 - second.0).powi(2) + (first.1 - second.1).powi(2)).sqrt();
    assert!(
        distance > 6.0,
        "the robot moved {distance:.1} px on the page"
    );
    assert_ne!(
        images[0].get_pixel(first.0 as u32, first.1 as u32),
        images[1].get_pixel(first.0 as u32, first.1 as u32),
        "nothing changed where the robot first stood"
    );
    if std::env::var("REGATTA_BLESS").as_deref() == Ok("1") {
        std::fs::copy(
            shots[1]["file"].as_str().unwrap(),
            root().join("docs/view.png"),
        )
        .unwrap();
    }
}

fn point(value: &serde_json::Value) -> (f64, f64) {
    (value[0].as_f64().unwrap(), value[1].as_f64().unwrap())
}

/// Some pixel within 3 px of `at` has `colour` (each channel within 24).
fn assert_near_colour(
    image: &image::RgbaImage,
    at: &serde_json::Value,
    colour: &serde_json::Value,
    what: &str,
) {
    let (x, y) = point(at);
    let want: Vec<i32> = (0..3).map(|k| colour[k].as_i64().unwrap() as i32).collect();
    let found = (-3..=3).any(|dy| {
        (-3..=3).any(|dx| {
            let (px, py) = (x as i64 + dx, y as i64 + dy);
            if px < 0 || py < 0 || px >= image.width() as i64 || py >= image.height() as i64 {
                return false;
            }
            let p = image.get_pixel(px as u32, py as u32);
            (0..3).all(|k| (i32::from(p[k]) - want[k]).abs() <= 24)
        })
    });
    let seen = image.get_pixel(x.clamp(0.0, 1e6) as u32, y.clamp(0.0, 1e6) as u32);
    assert!(
        found,
        "{what} is not drawn at ({x:.0}, {y:.0}): wanted {want:?}, the pixel there is {seen:?}"
    );
}
