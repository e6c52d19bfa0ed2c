//! `regatta check`: parse and type world files, print diagnostics in rustc's style.

use std::io::Read;
use std::path::PathBuf;

use anyhow::Context;
use regatta_parser::SourceText;
use regatta_schema::{check, check_file_with_proto_path, Options};

use crate::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// World files to check; `-` reads standard input.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Treat unknown nodes and fields as warnings and skip them, as Webots does (for foreign files).
    #[arg(long)]
    lenient: bool,
    /// Print one line per diagnostic (`file:line:col: error: message`).
    #[arg(long)]
    short: bool,
    /// Do not print warnings.
    #[arg(long, short = 'q')]
    quiet: bool,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let mut any_error = false;
    let (mut errors, mut warnings) = (0usize, 0usize);
    for path in &args.files {
        let checked = if path.as_os_str() == "-" {
            let mut bytes = Vec::new();
            std::io::stdin()
                .read_to_end(&mut bytes)
                .context("cannot read standard input")?;
            let bytes = regatta_parser::source::inflate_if_gzip(bytes)
                .context("standard input looks gzip-compressed but does not inflate")?;
            let options = Options {
                strict: !args.lenient,
                base_dir: None,
                proto_path: crate::world::proto_path(),
            };
            check(
                SourceText::from_bytes("<stdin>".to_owned(), bytes),
                &options,
            )
        } else {
            match check_file_with_proto_path(path, !args.lenient, crate::world::proto_path()) {
                Ok(checked) => checked,
                Err(error) => {
                    eprintln!("error: {error}");
                    any_error = true;
                    errors += 1;
                    continue;
                }
            }
        };
        let mut checked = checked;
        crate::world::check_runtime(&mut checked);
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
        let shown: Vec<_> = checked
            .diagnostics
            .iter()
            .filter(|d| !args.quiet || d.diagnostic.is_error())
            .collect();
        for diagnostic in shown {
            let source = &checked.sources[diagnostic.file.0 as usize];
            if args.short {
                eprintln!(
                    "{}",
                    diagnostic.diagnostic.short(&source.name, &source.text)
                );
            } else {
                eprint!(
                    "{}",
                    diagnostic
                        .diagnostic
                        .render(&source.name, &source.text, color)
                );
            }
        }
    }
    let files = args.files.len();
    let noun = if files == 1 { "file" } else { "files" };
    eprintln!("checked {files} {noun}: {errors} errors, {warnings} warnings");
    Ok(if any_error {
        Outcome::Errors
    } else {
        Outcome::Clean
    })
}
