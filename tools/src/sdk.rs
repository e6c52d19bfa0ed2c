//! `regatta webots-sdk DIR`: regatta's Webots C API (the headers and the controller library's
//! sources) written into DIR, for building a controller outside a project: an `<extern>`
//! controller started by hand, or one run under a debugger; and the Python `controller`
//! package with its library built (DIR/python), for an `<extern>` Python controller.

use std::path::PathBuf;

use anyhow::Context;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The folder to write into (made if missing; files of the same names are replaced).
    dir: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    regatta_webots::compile::write_sdk(&args.dir)
        .with_context(|| format!("cannot write the SDK into {}", args.dir.display()))?;
    let dir = args.dir.display();
    println!("wrote regatta's Webots C API into {dir}; build a controller with");
    println!(
        "  cc -O2 -I {dir}/include my_controller.c {dir}/regatta_controller.c -lm -o my_controller"
    );
    let python = regatta_webots::python::write_sdk(&args.dir)
        .with_context(|| format!("cannot build the Python controller package in {dir}"))?;
    println!("and run it for a robot whose controller is \"<extern>\" with the REGATTA_CONTROLLER_URL that `regatta run` prints;");
    println!(
        "a Python controller runs so with PYTHONPATH={} python3 my_controller.py",
        python.display()
    );
    Ok(Outcome::Clean)
}
