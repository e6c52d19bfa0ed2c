//! `regatta check`: parse and type world files, check their controllers, and print
//! diagnostics in rustc's style.

use std::path::PathBuf;

use crate::outcome::Outcome;
use crate::world::{check_world, WorldOptions};

#[derive(clap::Args)]
pub struct Args {
    /// World files to check; `-` reads standard input.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    world: WorldOptions,
    /// Print one line per diagnostic (`file:line:col: error: message`).
    #[arg(long)]
    short: bool,
    /// Do not print warnings.
    #[arg(long, short = 'q')]
    quiet: bool,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    // Flags are checked once, before any file: a bad --limit is a usage error.
    args.world.options()?;
    let mut any_error = false;
    let (mut errors, mut warnings) = (0usize, 0usize);
    for path in &args.files {
        let mut checked = match check_world(path, &args.world) {
            Ok(checked) => checked,
            Err(error) => {
                eprintln!("error: {error:#}");
                any_error = true;
                errors += 1;
                continue;
            }
        };
        regatta_runtime::check::check_scene_with(&mut checked, &regatta_webots::programs_of(path));
        crate::world::warn_about_cost(&mut checked);
        for diagnostic in &checked.diagnostics {
            if diagnostic.diagnostic.is_error() {
                errors += 1;
            } else {
                warnings += 1;
            }
        }
        any_error |= checked.has_errors();
        if !args.quiet {
            crate::world::print_substitutions(&checked);
        }
        let keep = |d: &regatta_schema::FileDiagnostic| !args.quiet || d.diagnostic.is_error();
        if args.short {
            // The map finds every line of every file: built only when something is shown.
            if checked.diagnostics.iter().any(keep) {
                let map = checked.source_map();
                for diagnostic in checked.diagnostics.iter().filter(|d| keep(d)) {
                    eprintln!(
                        "{}",
                        map.short(diagnostic.file.0 as usize, &diagnostic.diagnostic)
                    );
                }
            }
        } else {
            eprint!("{}", checked.render_where(keep, color));
        }
    }
    let files = args.files.len();
    let noun = if files == 1 { "file" } else { "files" };
    let counted =
        |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    eprintln!(
        "checked {files} {noun}: {}, {}",
        counted(errors, "error", "errors"),
        counted(warnings, "warning", "warnings")
    );
    Ok(if any_error {
        Outcome::Errors
    } else {
        Outcome::Clean
    })
}
