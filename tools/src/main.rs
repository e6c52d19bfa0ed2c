//! `regatta`: the command line. Each subcommand lives in its own module; this file only
//! dispatches and maps results to exit codes (0 clean, 1 errors found, 2 usage errors,
//! 128 + n when signal n stopped a run: 130 for Ctrl-C, 143 for SIGTERM).

mod batch;
mod bench;
mod bench_accuracy;
mod bench_controllers;
mod bench_crowd;
mod bench_retina;
mod bench_step;
mod bench_swarm;
mod bench_webots;
mod check;
mod evolve;
mod explain;
mod fmt;
mod gltf;
mod logs;
mod memory;
mod outcome;
mod plot;
mod render;
mod run;
mod schema;
mod sdk;
mod serial;
mod signals;
mod test_webots;
mod transfer;
mod vary;
mod view;
mod view_replay;
mod vision;
mod webots;
mod world;

use std::io::IsTerminal;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use outcome::Outcome;

/// regatta: VRML-style robot worlds — checked, simulated and logged reproducibly.
#[derive(Parser)]
#[command(name = "regatta", version, about, long_about = None, propagate_version = true)]
struct Cli {
    /// When to colour error messages and diagnostics on the terminal (not figures).
    #[arg(long, global = true, value_enum, default_value_t = Color::Auto, value_name = "WHEN")]
    color: Color,
    /// A folder where `webots://` PROTOs are looked for before regatta's stand-ins (a Webots
    /// installation or any folder of PROTOs); repeatable, after it REGATTA_PROTO_PATH's.
    #[arg(long = "proto-path", global = true, value_name = "DIR")]
    proto_path: Vec<std::path::PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Color {
    Auto,
    Always,
    Never,
}

#[derive(Subcommand)]
enum Command {
    /// Check world files and print their diagnostics (`-` reads standard input).
    Check(check::Args),
    /// Print the node catalogue: every field with its type, default and doc.
    Schema(schema::Args),
    /// Print a world file in canonical form (comments kept).
    Fmt(fmt::Args),
    /// Run a benchmark and print its figures.
    Bench(bench::Args),
    /// Print what a world compiles to: render graph, sensor rig, and the plan with its skips.
    Explain(explain::Args),
    /// Render what each robot's vision device sees, stage by stage (PNG or JSON).
    Render(render::Args),
    /// Export a world to glTF 2.0 (.glb or .gltf), optionally animated from a log.
    Gltf(gltf::Args),
    /// Answer like a real Khepera on a pseudo-terminal or a TCP port (the serial protocol).
    Serve(serial::ServeArgs),
    /// Run a built-in controller on a real Khepera, or a served one, over the serial protocol.
    Drive(serial::DriveArgs),
    /// Step a world and print a summary: time, speed, contacts, buoy visits (--json: as data).
    Run(run::Args),
    /// Run one world under many seeds in parallel; one JSON or CSV row per run.
    Batch(batch::Args),
    /// Evolve the weights of a world's NeuralNetwork (CMA-ES or a genetic algorithm).
    Evolve(evolve::Args),
    /// Evaluate controllers (worlds) on a grid of named conditions: a table, CSV and a heat
    /// map of controller × condition → fitness.
    Transfer(transfer::Args),
    /// Re-run a log's world and seed and check that every message is the same.
    Replay(logs::ReplayArgs),
    /// Work with sensor logs (export to CSV, print what a log holds).
    Log(logs::LogArgs),
    /// Figures of a log: the arena from above, retina kymographs, and (--series) sensor time series.
    Plot(plot::PlotArgs),
    /// Step a world and watch it live in the browser (or replay a .mcap log with a timeline).
    View(view::Args),
    /// Run Webots' own API tests (a Webots installation's tests/api) against regatta and print
    /// a table: test, result, first failure, time.
    TestWebots(test_webots::Args),
    /// Write regatta's Webots C API (headers and controller library) into a folder, to build
    /// controllers by hand (an `<extern>` controller).
    WebotsSdk(sdk::Args),
}

/// Piping into `head` closes our standard output early: like other Unix tools, end quietly
/// (the default SIGPIPE action) instead of failing on a write.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The main thread's stack: the parser and the typing recurse once per nesting level, and
/// `--limit nesting=N` may ask for 1024 levels (4096 once PROTOs are expanded).
const STACK_SIZE: usize = 256 << 20;

fn main() -> ExitCode {
    restore_sigpipe();
    // Reserved address space, not memory: pages are touched only as deep as a run goes.
    match std::thread::Builder::new()
        .name("regatta".to_owned())
        .stack_size(STACK_SIZE)
        .spawn(run)
    {
        Ok(handle) => handle.join().unwrap_or(ExitCode::from(101)),
        Err(_) => run(),
    }
}

/// The command line's grammar, every flag that takes a value taking one that starts with a
/// minus: `--steps -5` then reaches the flag's own check ("invalid value '-5' for '--steps
/// <N>'") instead of clap's "unexpected argument '-5'", whose tip (`-- -5`) does not work for
/// a flag. No flag of regatta is a negative number, so nothing is lost.
fn command() -> clap::Command {
    fn negatives(command: clap::Command) -> clap::Command {
        command
            .mut_args(|arg| {
                if arg.get_action().takes_values() {
                    arg.allow_negative_numbers(true)
                } else {
                    arg
                }
            })
            .mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

fn parse() -> Result<Cli, clap::Error> {
    let mut command = command();
    let matches = command.try_get_matches_from_mut(std::env::args_os())?;
    Cli::from_arg_matches(&matches).map_err(|error| error.format(&mut command))
}

fn run() -> ExitCode {
    let cli = match parse() {
        Ok(cli) => cli,
        Err(error) => {
            let _ = error.print();
            return match error.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    ExitCode::SUCCESS
                }
                _ => ExitCode::from(2),
            };
        }
    };
    let color = match cli.color {
        Color::Always => true,
        Color::Never => false,
        Color::Auto => std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    };
    world::set_proto_path(regatta_schema::proto_path::from_flags_and_env(
        &cli.proto_path,
    ));
    let result = match cli.command {
        Command::Check(args) => check::run(args, color),
        Command::Schema(args) => schema::run(args),
        Command::Fmt(args) => fmt::run(args, color),
        Command::Bench(args) => bench::run(args),
        Command::Explain(args) => explain::run(args, color),
        Command::Render(args) => render::run(args, color),
        Command::Gltf(args) => gltf::run(args, color),
        Command::Run(args) => run::run(args, color),
        Command::Batch(args) => batch::run(args),
        Command::Evolve(args) => evolve::run(args),
        Command::Transfer(args) => transfer::run(args),
        Command::Serve(args) => serial::serve(args, color),
        Command::Drive(args) => serial::drive(args),
        Command::Replay(args) => logs::replay(args),
        Command::Log(args) => logs::log(args),
        Command::Plot(args) => plot::plot(args),
        Command::View(args) => view::run(args, color),
        Command::TestWebots(args) => test_webots::run(args),
        Command::WebotsSdk(args) => sdk::run(args),
    };
    match result {
        Ok(Outcome::Clean) => ExitCode::SUCCESS,
        Ok(Outcome::Errors) => ExitCode::from(1),
        Ok(Outcome::Signalled(signal)) => {
            ExitCode::from(u8::try_from(128 + signal.clamp(0, 127)).unwrap_or(1))
        }
        Err(error) => {
            eprintln!("error: {}", report(&error));
            ExitCode::from(1)
        }
    }
}

/// An error and its causes on one line, `a: b: c`, each cause said once: libraries often put
/// their source's text in their own message too, which `{:#}` would then repeat.
fn report(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.ends_with(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::{command, report};

    #[test]
    fn every_flag_that_takes_a_value_takes_a_negative_number() {
        fn check(command: &clap::Command, path: &str) {
            for arg in command.get_arguments() {
                if arg.get_action().takes_values() {
                    assert!(
                        arg.is_allow_negative_numbers_set(),
                        "{path} {}",
                        arg.get_id()
                    );
                }
            }
            for sub in command.get_subcommands() {
                check(sub, &format!("{path} {}", sub.get_name()));
            }
        }
        let mut command = command();
        command.build();
        check(&command, "regatta");
    }

    #[derive(Debug, thiserror::Error)]
    #[error("cannot write the log: {0}")]
    struct Outer(#[source] Inner);

    #[derive(Debug, thiserror::Error)]
    #[error("I/O error")]
    struct Inner(#[source] std::io::Error);

    #[test]
    fn a_cause_already_said_is_not_said_again() {
        let io = std::io::Error::other("No space left on device");
        let error = anyhow::Error::new(Outer(Inner(io))).context("while logging step 938");
        assert_eq!(
            report(&error),
            "while logging step 938: cannot write the log: I/O error: No space left on device"
        );
    }
}
