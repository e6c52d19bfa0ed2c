//! `regatta serve` with real sockets: where it listens, clients that misbehave (reset, half a
//! line, garbage) and what the next client sees, SIGTERM with a log, and real time that cannot
//! keep up.

#![cfg(unix)]

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::Duration;

use common::{regatta, root, temp_dir};

/// Starts `regatta serve ARGS`; returns the child and the address from its banner.
fn serve(args: &[&str]) -> (Child, String) {
    let mut child = regatta()
        .arg("serve")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let banner = lines.next().expect("a banner").unwrap();
    let address = banner
        .split("tcp ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no address in {banner:?}"))
        .to_owned();
    // Keep draining stdout so the server never blocks on it.
    std::thread::spawn(move || for _ in lines {});
    (child, address)
}

/// Sends `request` and returns the reply line, without its CR LF.
fn ask(stream: &mut TcpStream, request: &str) -> String {
    stream.write_all(request.as_bytes()).unwrap();
    let mut reply = Vec::new();
    let mut byte = [0u8; 1];
    while !reply.ends_with(b"\r\n") {
        if stream.read(&mut byte).unwrap() == 0 {
            break;
        }
        reply.push(byte[0]);
    }
    String::from_utf8_lossy(&reply).trim_end().to_owned()
}

fn connect(address: &str) -> TcpStream {
    let stream = TcpStream::connect(address).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    stream
}

/// Closes a stream with a TCP reset instead of an orderly close (SO_LINGER 0).
fn reset(stream: TcpStream) {
    use std::os::fd::AsRawFd;
    let linger = libc::linger {
        l_onoff: 1,
        l_linger: 0,
    };
    // SAFETY: setting a socket option on a socket we own, with a correctly sized value.
    unsafe {
        libc::setsockopt(
            stream.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_LINGER,
            (&linger as *const libc::linger).cast(),
            std::mem::size_of::<libc::linger>() as libc::socklen_t,
        );
    }
    drop(stream);
}

fn stop(child: &mut Child, signal: i32) -> (Option<i32>, String) {
    // SAFETY: sending a signal to our own child process.
    unsafe {
        libc::kill(child.id() as i32, signal);
    }
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    (child.wait().unwrap().code(), stderr)
}

#[test]
fn serve_listens_on_loopback_unless_told_otherwise() {
    let world = root().join("worlds/regatta.wbt");
    let (mut child, address) = serve(&["--tcp", "0", world.to_str().unwrap()]);
    assert!(address.starts_with("127.0.0.1:"), "{address}");
    let (code, stderr) = stop(&mut child, libc::SIGINT);
    assert_eq!(code, Some(130), "{stderr}");
    // All interfaces only when asked for, and a HOST:PORT that widens it is refused.
    let refused = regatta()
        .args(["serve", "--tcp", "0.0.0.0:0"])
        .arg(&world)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--bind"));
}

#[test]
fn misbehaving_clients_never_kill_the_server_nor_reach_the_next_one() {
    let dir = temp_dir("clients");
    let log = dir.join("served.mcap");
    let world = root().join("worlds/regatta.wbt");
    let (mut child, address) = serve(&[
        "--tcp",
        "0",
        "--log",
        log.to_str().unwrap(),
        world.to_str().unwrap(),
    ]);
    // Client 1: a step with the motors on, garbage, half a line, then a reset.
    let mut first = connect(&address);
    assert_eq!(ask(&mut first, "D,5,5\n"), "d");
    assert_eq!(ask(&mut first, "\u{1}garbage\u{7f}\n"), "Command not found");
    first.write_all(b"D,9").unwrap();
    first.flush().unwrap();
    std::thread::sleep(Duration::from_millis(200));
    reset(first);
    // Client 2: its first line is its own (no "D,9" glued in front), and the robot it finds
    // is standing still.
    std::thread::sleep(Duration::from_millis(200));
    let mut second = connect(&address);
    assert_eq!(ask(&mut second, "B\n"), "b,0,0");
    assert_eq!(ask(&mut second, "E\n"), "e,0,0");
    // Client 2 leaves in the middle of a line, politely this time.
    second.write_all(b"N").unwrap();
    drop(second);
    // Client 3: the server still answers, and lock-step still advances.
    std::thread::sleep(Duration::from_millis(200));
    let mut third = connect(&address);
    assert_eq!(ask(&mut third, "B\n"), "b,0,0");
    assert_eq!(ask(&mut third, "D,0,0\n"), "d");
    drop(third);
    std::thread::sleep(Duration::from_millis(200));
    // SIGTERM: exit 143, and the log is complete (summary and footer written).
    let (code, stderr) = stop(&mut child, libc::SIGTERM);
    assert_eq!(code, Some(143), "{stderr}");
    assert!(
        stderr.contains("lost") || stderr.contains("left"),
        "{stderr}"
    );
    assert!(stderr.contains("stopped by SIGTERM"), "{stderr}");
    let export = regatta()
        .args(["log", "export"])
        .arg(&log)
        .arg("--csv")
        .arg(dir.join("csv"))
        .output()
        .unwrap();
    let export_err = String::from_utf8_lossy(&export.stderr);
    assert!(
        export.status.success() && !export_err.contains("warning"),
        "{export_err}"
    );
    // Two steps were served (one per D): the pose channel says so.
    let pose = std::fs::read_to_string(dir.join("csv/pose.csv")).unwrap();
    assert_eq!(pose.lines().count(), 3, "{pose}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_real_time_world_that_cannot_keep_up_says_so_once_and_still_answers() {
    let dir = temp_dir("realtime");
    // A 1 ms step and a turret that ray-casts 150 × 32² rays per update: far slower than
    // real time on any machine.
    let world = dir.join("slow.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep 1 }\n\
         Transform { translation 0.3 0.05 0 children [ Shape { geometry Sphere { radius 0.02 } } ] }\n\
         Khepera { controller \"none\" turret PanoramicTurret { samples 32 samplingPeriod 0 } }\n",
    )
    .unwrap();
    let (mut child, address) = serve(&[
        "--tcp",
        "0",
        "--realtime",
        "--steps",
        "60",
        world.to_str().unwrap(),
    ]);
    let mut client = connect(&address);
    for _ in 0..3 {
        assert_eq!(ask(&mut client, "B\n"), "b,0,0");
        std::thread::sleep(Duration::from_millis(100));
    }
    drop(client);
    let (code, stderr) = stop(&mut child, libc::SIGINT);
    assert!(matches!(code, Some(0) | Some(130)), "{stderr}");
    assert_eq!(
        stderr.matches("cannot keep up with real time").count(),
        1,
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).ok();
}
