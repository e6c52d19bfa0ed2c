//! `regatta fmt`: print a world in canonical form, or rewrite it in place.

use std::io::Read;
use std::path::PathBuf;

use anyhow::Context;
use regatta_parser::SourceText;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file; `-` reads standard input.
    file: PathBuf,
    /// Rewrite the file instead of printing.
    #[arg(long, short = 'w')]
    write: bool,
    /// Exit with 1 if the file is not in canonical form (prints nothing).
    #[arg(long, conflicts_with = "write")]
    check: bool,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let source = if args.file.as_os_str() == "-" {
        let mut bytes = Vec::new();
        std::io::stdin()
            .read_to_end(&mut bytes)
            .context("cannot read standard input")?;
        SourceText::from_bytes("<stdin>".to_owned(), bytes)
    } else {
        SourceText::read(&args.file)?
    };
    let parse = regatta_parser::parse(&source.text);
    let errors: Vec<_> = source
        .diagnostics
        .iter()
        .chain(&parse.diagnostics)
        .filter(|d| d.is_error())
        .collect();
    if !errors.is_empty() {
        // Formatting a broken file would move text around a mistake: refuse and say why.
        for diagnostic in errors {
            eprint!("{}", diagnostic.render(&source.name, &source.text, color));
        }
        eprintln!("{} has syntax errors; it was not formatted", source.name);
        return Ok(Outcome::Errors);
    }
    let formatted = regatta_parser::format::format(&parse.file, &source.text);
    if args.check {
        return Ok(if formatted == source.text {
            Outcome::Clean
        } else {
            Outcome::Errors
        });
    }
    if args.write && args.file.as_os_str() != "-" {
        if formatted != source.text {
            let temporary = args.file.with_extension("regatta-fmt.tmp");
            std::fs::write(&temporary, &formatted)
                .with_context(|| format!("cannot write {}", temporary.display()))?;
            std::fs::rename(&temporary, &args.file)
                .with_context(|| format!("cannot replace {}", args.file.display()))?;
        }
    } else {
        print!("{formatted}");
    }
    Ok(Outcome::Clean)
}
