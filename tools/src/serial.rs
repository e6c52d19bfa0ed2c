//! `regatta serve` and `regatta drive`: the Khepera serial protocol from the command line. A
//! served world answers like a real robot on a pseudo-terminal or a TCP port; `drive` runs a
//! built-in controller on a real robot, or on a served one, through the real-robot backend.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use regatta_runtime::khepera::Khepera;
use regatta_runtime::sim::Simulation;
use regatta_serial::link::Link;
use regatta_serial::server::{serve_lock_step, serve_real_time, Ended};
use regatta_serial::{ClientOptions, Pacing, RemoteKhepera, Server};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct ServeArgs {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    /// The robot that answers (by name; the first robot if not given). The others keep their
    /// built-in controllers.
    #[arg(long)]
    robot: Option<String>,
    /// Answer on a new pseudo-terminal; its path is printed (a serial port for any program).
    #[arg(long, conflicts_with = "tcp", required_unless_present = "tcp")]
    pty: bool,
    /// Answer on a TCP port (0 picks a free one; the address is printed). `HOST:PORT` is
    /// accepted when HOST is the --bind address or a loopback address.
    #[arg(long, value_name = "PORT")]
    tcp: Option<String>,
    /// The address to listen on: 127.0.0.1 (this machine only) unless another is given;
    /// `--bind 0.0.0.0` answers anyone who can reach this machine.
    #[arg(long, value_name = "ADDR", requires = "tcp")]
    bind: Option<IpAddr>,
    /// Step the world in real time instead of one step per D (set speed) command.
    #[arg(long)]
    realtime: bool,
    /// Stop after this many steps.
    #[arg(long, conflicts_with = "duration")]
    steps: Option<u64>,
    /// Stop after this much simulated time (s).
    #[arg(long, allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Seed of every random stream (overrides WorldInfo.randomSeed).
    #[arg(long)]
    seed: Option<u64>,
    /// Record every sensor and actuator to this MCAP file, as `regatta run --log` does.
    #[arg(long, value_name = "FILE.mcap")]
    log: Option<PathBuf>,
    /// The log's channels, as for `regatta run`.
    #[arg(long, value_name = "LIST", default_value = "all", requires = "log")]
    channels: regatta_runtime::log::Channels,
    #[command(flatten)]
    options: crate::world::WorldOptions,
    #[command(flatten)]
    controllers: crate::webots::ControllerOverride,
}

/// Where `--tcp` and `--bind` say to listen: the --bind address (127.0.0.1 by default) and
/// the port; a `HOST:PORT` form must not widen the audience behind the user's back.
fn listen_address(tcp: &str, bind: Option<IpAddr>) -> anyhow::Result<SocketAddr> {
    let loopback = IpAddr::V4(Ipv4Addr::LOCALHOST);
    if let Ok(port) = tcp.parse::<u16>() {
        return Ok(SocketAddr::new(bind.unwrap_or(loopback), port));
    }
    let address: SocketAddr = tcp.parse().with_context(|| {
        format!("--tcp {tcp}: give a port (7000) or an address (127.0.0.1:7000)")
    })?;
    match bind {
        Some(bind) if bind != address.ip() => bail!(
            "--tcp {tcp} and --bind {bind} disagree; give the port alone with --bind"
        ),
        None if !address.ip().is_loopback() => bail!(
            "--tcp {tcp} would answer other machines; regatta serve listens on 127.0.0.1 unless --bind {} says otherwise",
            address.ip()
        ),
        _ => Ok(address),
    }
}

pub fn serve(args: ServeArgs, color: bool) -> anyhow::Result<Outcome> {
    let address = args
        .tcp
        .as_deref()
        .map(|tcp| listen_address(tcp, args.bind))
        .transpose()?;
    let mut loaded = crate::world::load(&args.world, &args.options, color)?;
    crate::webots::refuse_unbuilt_robots(&loaded)?;
    let served = match &args.robot {
        Some(name) => Some(crate::world::robot_named(
            &loaded.compiled,
            &args.world,
            name,
        )?),
        None => (!loaded.compiled.rig.robots.is_empty()).then_some(0),
    };
    crate::webots::resolve_controllers(
        &mut loaded.compiled,
        &args.controllers,
        args.options.lenient,
        served,
    )?;
    let compiled = &loaded.compiled;
    let world_name = crate::world::world_name(&args.world);
    let robot = match &args.robot {
        Some(name) => crate::world::robot_named(compiled, &args.world, name)?,
        None if compiled.rig.robots.is_empty() => {
            bail!("{world_name} has no robot to serve")
        }
        None => 0,
    };
    let mut simulation =
        Simulation::new(compiled, args.seed).with_context(|| format!("cannot run {world_name}"))?;
    let max_steps = crate::world::step_limit(args.steps, args.duration, simulation.time_step)?;
    let mut recorder = args
        .log
        .as_deref()
        .map(|path| {
            crate::world::create_recorder(
                path,
                &args.world,
                &loaded,
                &mut simulation,
                args.options.lenient,
                max_steps.unwrap_or(0),
                args.channels,
            )
        })
        .transpose()?;
    let stop = crate::signals::Stop::install();
    let pacing = if args.realtime {
        Pacing::RealTime
    } else {
        Pacing::LockStep
    };
    let name = compiled.rig.robots[robot].name.clone();
    let mode = match pacing {
        Pacing::LockStep => "lock-step: one step per D command",
        Pacing::RealTime => "real time",
    };
    let started = Instant::now();
    let (stats, ended, hook_error) = {
        let mut server = Server::new(&mut simulation, robot, pacing, max_steps);
        if let Some(recorder) = &mut recorder {
            server.on_step = Some(Box::new(|simulation: &Simulation| {
                recorder.record(simulation).map_err(std::io::Error::other)
            }));
        }
        server.on_lag = Some(Box::new(|lag: regatta_serial::server::Lag| {
            eprintln!(
                "warning: the world cannot keep up with real time: {} steps behind at t = {:.3} s (a step takes longer than {} ms of wall time); it catches up as fast as it can",
                lag.steps_behind,
                lag.time,
                lag.period_ms
            );
        }));
        let serve_one = |server: &mut Server, link: &mut dyn Link| match pacing {
            Pacing::LockStep => serve_lock_step(server, link, stop.flag()),
            Pacing::RealTime => serve_real_time(server, link, stop.flag()),
        };
        let ended = if let Some(address) = address {
            let listener = TcpListener::bind(address)
                .with_context(|| format!("cannot listen on {address}"))?;
            listener.set_nonblocking(true)?;
            println!(
                "serving robot '{name}' of {world_name} on tcp {} ({mode})",
                listener.local_addr()?
            );
            flush_stdout();
            loop {
                if stop.requested() {
                    break Ended::Stopped;
                }
                match listener.accept() {
                    Ok((mut stream, peer)) => {
                        eprintln!("client {peer} connected");
                        // One client's trouble is its own: a reset or a broken link ends its
                        // session, never the server, and nothing of it reaches the next one.
                        let outcome = stream
                            .set_nonblocking(false)
                            .and_then(|()| stream.set_nodelay(true))
                            .and_then(|()| serve_one(&mut server, &mut stream));
                        server.end_session();
                        match outcome {
                            Ok(Ended::Closed) => eprintln!("client {peer} left"),
                            Ok(other) => break other,
                            Err(error) => eprintln!("client {peer} lost: {error}"),
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_millis(20))
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    // Failures that concern one connection attempt (a client that reset
                    // before it was accepted, a file-descriptor shortage) end no session.
                    Err(e) => {
                        eprintln!("warning: cannot accept a client: {e}");
                        std::thread::sleep(Duration::from_millis(100));
                    }
                }
                if server.hook_error.is_some() {
                    break Ended::Done;
                }
            }
        } else {
            let mut pty =
                regatta_serial::link::Pty::open().context("cannot open a pseudo-terminal")?;
            println!(
                "serving robot '{name}' of {world_name} on {} ({mode})",
                pty.slave_path()
            );
            flush_stdout();
            serve_one(&mut server, &mut pty)?
        };
        (server.stats.clone(), ended, server.hook_error.take())
    };
    if let Some(error) = hook_error {
        return Err(error).context("cannot write the log");
    }
    if let Some(recorder) = recorder {
        recorder
            .finish(&simulation, ended == Ended::Stopped)
            .context("cannot close the log")?;
    }
    let pose = simulation.robots[robot].pose;
    println!(
        "served {} steps ({:.3} s simulated, {:.3} s wall): {} requests, {} malformed, {} refused{}",
        simulation.steps,
        simulation.time,
        started.elapsed().as_secs_f64(),
        stats.requests,
        stats.malformed,
        stats.refused,
        match &stats.last_problem {
            Some(problem) => format!(" (last: {problem})"),
            None => String::new(),
        }
    );
    println!(
        "final pose of '{name}': x {:.9} z {:.9} heading {:.9}",
        pose.x, pose.z, pose.heading
    );
    if ended == Ended::Stopped {
        eprintln!(
            "stopped by {}{}",
            stop.name(),
            if args.log.is_some() {
                "; the log is complete and marked interrupted"
            } else {
                ""
            }
        );
    }
    Ok(stop.outcome().unwrap_or(Outcome::Clean))
}

fn flush_stdout() {
    use std::io::Write;
    let _ = std::io::stdout().flush();
}

#[derive(clap::Args)]
pub struct DriveArgs {
    /// A serial port (the robot's cable, or a served pseudo-terminal).
    #[arg(long, conflicts_with = "tcp", required_unless_present = "tcp")]
    port: Option<String>,
    /// The serial port's speed: 9600, 19200 or 38400 baud.
    #[arg(long, default_value = "38400", value_parser = ["9600", "19200", "38400"])]
    baud: String,
    /// A TCP address (a serial-over-IP adapter, or `regatta serve --tcp`).
    #[arg(long, value_name = "HOST:PORT")]
    tcp: Option<String>,
    /// The built-in controller: braitenberg or regatta.
    #[arg(long)]
    controller: String,
    /// Controller parameters, as in a world's controllerArgs (`irGain=2`).
    #[arg(long = "arg", value_name = "KEY=VALUE")]
    args: Vec<String>,
    /// Control steps to run (the robot is stopped at the end).
    #[arg(long, default_value_t = 1875)]
    steps: u64,
    /// Milliseconds per control step; 0 runs as fast as replies come (for a lock-step world,
    /// whose control period, 32 ms unless the world's robot sets `controlPeriod`, is then
    /// the controller's: its timers count 32 ms per call).
    #[arg(long, default_value_t = 32)]
    period: u64,
    /// Milliseconds one try waits for a reply.
    #[arg(long, default_value_t = 1000)]
    timeout: u64,
    /// Tries per request.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    tries: u32,
}

pub fn drive(args: DriveArgs) -> anyhow::Result<Outcome> {
    // The controller's timers are in seconds: they count calls of this period.
    let control_period = if args.period == 0 {
        regatta_runtime::compile::rig::DEFAULT_CONTROL_PERIOD
    } else {
        args.period as f64 / 1000.0
    };
    let controller =
        regatta_runtime::controllers::build(&args.controller, &args.args, control_period)
            .with_context(|| format!("cannot build controller '{}'", args.controller))?;
    let options = ClientOptions {
        timeout: Duration::from_millis(args.timeout.max(1)),
        tries: args.tries,
    };
    match (&args.port, &args.tcp) {
        (Some(port), _) => {
            let baud: u32 = args.baud.parse().context("--baud")?;
            let link = regatta_serial::link::open_serial(port, baud)
                .with_context(|| format!("cannot open serial port {port}"))?;
            drive_link(link, port, controller, &args, options)
        }
        (None, Some(address)) => {
            let stream = TcpStream::connect(address)
                .with_context(|| format!("cannot connect to {address}"))?;
            stream.set_nodelay(true)?;
            drive_link(stream, address, controller, &args, options)
        }
        (None, None) => bail!("give --port or --tcp"),
    }
}

fn drive_link<L: Link>(
    link: L,
    name: &str,
    mut controller: Box<dyn regatta_runtime::khepera::Controller>,
    args: &DriveArgs,
    options: ClientOptions,
) -> anyhow::Result<Outcome> {
    let mut robot = RemoteKhepera::connect(link, options)
        .with_context(|| format!("no Khepera answers on {name}"))?;
    let panoramic = robot.panoramic().is_some();
    let k213 = robot.linear_camera().is_some();
    println!(
        "driving the {} on {name} with '{}' ({}{}{})",
        if robot.is_simulation() {
            "simulated Khepera"
        } else {
            "Khepera"
        },
        args.controller,
        robot.version,
        if panoramic { ", Panoramic turret" } else { "" },
        if k213 { ", K213 turret" } else { "" },
    );
    let stop = crate::signals::Stop::install();
    let period = Duration::from_millis(args.period);
    let started = Instant::now();
    let mut done = 0;
    let mut failure = None;
    for step in 0..args.steps {
        if stop.requested() {
            break;
        }
        if let Err(error) = controller.step(&mut robot) {
            failure = Some(format!("step {step}: {error}"));
            break;
        }
        done += 1;
        if !period.is_zero() {
            let next = started + period * (step as u32 + 1);
            std::thread::sleep(next.saturating_duration_since(Instant::now()));
        }
    }
    // Leave a real robot standing still, whatever happened.
    let stopped = robot.set_speed(0, 0);
    let wall = started.elapsed().as_secs_f64();
    println!(
        "{done} control steps in {wall:.3} s: {} requests, {} retries",
        robot.stats.requests, robot.stats.retries
    );
    if let Some(failure) = failure {
        bail!("{failure}");
    }
    if let Err(error) = stopped {
        eprintln!("warning: cannot stop the robot at the end: {error}");
    }
    Ok(stop.outcome().unwrap_or(Outcome::Clean))
}
