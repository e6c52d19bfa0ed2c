//! The README's sample outputs are what its commands print. A sample is a ```text block
//! right after a comment `<!-- sample: COMMAND -->`; the test runs COMMAND with this build's
//! binary (for `regatta …`; `cd DIR && regatta …` runs it in DIR of the repository) in a
//! scratch folder where the repository's `worlds/` is visible, and compares what it printed
//! (standard output and error, as a terminal interleaves them) with the block. What depends on
//! the machine is masked on both sides: the wall-time line's figures. A log's size is not: the
//! same world, seed and version write the same bytes, so the sample's size is checked too.
//!
//! `REGATTA_BLESS=1` rewrites the blocks from the commands, as the other expectation tests do.

mod common;

use std::path::Path;

use common::{regatta, root, temp_dir};

const MARKER: &str = "<!-- sample: ";

/// One sample: the command and where its block's lines are in the README.
struct Sample {
    command: String,
    /// Byte range of the block's body (between the fences).
    body: std::ops::Range<usize>,
}

fn samples(readme: &str) -> Vec<Sample> {
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(found) = readme[at..].find(MARKER) {
        let start = at + found + MARKER.len();
        let end = start
            + readme[start..]
                .find("-->")
                .expect("a sample comment is closed");
        let command = readme[start..end].trim().to_owned();
        let after = &readme[end..];
        let fence = after
            .find("```text\n")
            .expect("a ```text block follows a sample comment");
        let body_start = end + fence + "```text\n".len();
        let body_end = body_start
            + readme[body_start..]
                .find("```")
                .expect("the block is closed");
        out.push(Sample {
            command,
            body: body_start..body_end,
        });
        at = body_end;
    }
    out
}

/// Runs `command` as the README gives it; returns what it printed.
fn run(command: &str, scratch: &Path) -> String {
    let (dir, command) = match command.strip_prefix("cd ") {
        Some(rest) => {
            let (dir, command) = rest.split_once(" && ").expect("cd DIR && COMMAND");
            (root().join(dir), command)
        }
        None => (scratch.to_owned(), command),
    };
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(words[0], "regatta", "a sample runs regatta: {command}");
    // Standard output and error into one file, in the order they were written, as a terminal
    // shows them.
    let capture = scratch.join("printed.txt");
    let file = std::fs::File::create(&capture).unwrap();
    regatta()
        .args(&words[1..])
        .current_dir(&dir)
        .stdout(file.try_clone().unwrap())
        .stderr(file)
        .status()
        .expect("regatta runs");
    String::from_utf8_lossy(&std::fs::read(&capture).unwrap()).into_owned()
}

/// The figures that depend on the machine, replaced by `…`.
fn masked(text: &str) -> String {
    text.lines()
        .map(|line| {
            if line.starts_with("wall time ") {
                // wall time 0.407 s: 46034 steps/s, 1473× real time (a busy machine turns
                // 404 ms into 1.3 s: the unit is the machine's too)
                "wall time …: … steps/s, …× real time".to_owned()
            } else {
                line.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn readme_samples_are_what_the_commands_print() {
    let path = root().join("README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let found = samples(&readme);
    assert!(!found.is_empty(), "the README has samples");
    let scratch = temp_dir("readme");
    // The commands name worlds as `worlds/…`, from the repository's root.
    let worlds = scratch.join("worlds");
    if !worlds.exists() {
        #[cfg(unix)]
        std::os::unix::fs::symlink(root().join("worlds"), &worlds).unwrap();
    }
    let bless = std::env::var_os("REGATTA_BLESS").is_some();
    let mut blessed = readme.clone();
    let mut failures = Vec::new();
    // Blocks are replaced from the last, so that earlier ranges stay valid.
    for sample in found.iter().rev() {
        let printed = run(&sample.command, &scratch);
        let expected = &readme[sample.body.clone()];
        if masked(&printed).trim_end() != masked(expected).trim_end() {
            if bless {
                blessed.replace_range(sample.body.clone(), &printed);
            } else {
                failures.push(format!(
                    "`{}` printed:\n{printed}\nthe README says:\n{expected}",
                    sample.command
                ));
            }
        }
    }
    std::fs::remove_dir_all(&scratch).ok();
    if bless {
        std::fs::write(&path, blessed).unwrap();
    }
    assert!(
        failures.is_empty(),
        "README samples differ from their commands (REGATTA_BLESS=1 rewrites them):\n{}",
        failures.join("\n")
    );
}

#[test]
fn masking_keeps_what_does_not_depend_on_the_machine() {
    assert_eq!(
        masked("wall time 0.407 s: 46034 steps/s, 1473× real time\nlog: out/x.mcap (1.2 MB, 45 messages)\nkept"),
        "wall time …: … steps/s, …× real time\nlog: out/x.mcap (1.2 MB, 45 messages)\nkept"
    );
}
