//! The real-world corpus in `../shared/corpus`: every file parses without a syntax error and
//! types without an error in lenient mode, the broken Webots parser files fail at the right
//! line with Webots' own message, and formatting is stable on all of them.

use std::collections::BTreeMap;

use regatta_parser::{parse, SourceText};
use regatta_schema::check_file;
use regatta_tests::{corpus, files_with};

/// The corpus's world-like files (the README and manifest excluded).
fn corpus_files() -> Vec<std::path::PathBuf> {
    let files = files_with(&corpus(), &["wbt", "wrl", "proto", "gz"]);
    assert!(
        files.len() >= 50,
        "../shared/corpus is missing or incomplete: {} files",
        files.len()
    );
    files
}

/// Webots' broken parser inputs present in the corpus, with the message Webots gives.
fn expected_webots_messages() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(corpus().join("webots/tests/parser/expected_results.txt"))
        .expect("expected_results.txt");
    text.lines()
        .filter_map(|line| {
            let (file, message) = line.split_once(' ')?;
            let message = message.trim().strip_prefix('"')?.strip_suffix('"')?;
            Some((
                file.trim_start_matches("parser/").to_owned(),
                message.to_owned(),
            ))
        })
        .collect()
}

fn is_broken_on_purpose(path: &std::path::Path) -> bool {
    let name = path.to_string_lossy();
    name.ends_with("tests/parser/worlds/empty_value.wbt")
        || name.ends_with("tests/parser/worlds/node_without_brackets.wbt")
}

#[test]
fn every_corpus_file_parses_without_syntax_errors() {
    let mut failures = Vec::new();
    let mut count = 0;
    for path in corpus_files()
        .into_iter()
        .filter(|p| !is_broken_on_purpose(p))
    {
        count += 1;
        let source = SourceText::read(&path).expect("corpus file is readable");
        let parsed = parse(&source.text);
        for diagnostic in parsed.diagnostics.iter().filter(|d| d.is_error()) {
            failures.push(diagnostic.short(&path.display().to_string(), &source.text));
        }
    }
    assert!(count >= 50);
    assert!(
        failures.is_empty(),
        "syntax errors in the corpus:\n{}",
        failures.join("\n")
    );
}

#[test]
fn every_corpus_file_types_without_errors_in_lenient_mode() {
    let mut failures = Vec::new();
    for path in corpus_files()
        .into_iter()
        .filter(|p| !is_broken_on_purpose(p))
    {
        // A Webots project keeps its PROTOs beside `worlds/`, in `protos/`: a user allows the
        // project's folder (`--allow-path ..`), as here; anything further stays refused.
        let mut options = regatta_schema::Options {
            strict: false,
            ..regatta_schema::Options::default()
        };
        let folder = path.parent().expect("a corpus file is in a folder");
        if folder.file_name().is_some_and(|n| n == "worlds") {
            options
                .access
                .allow(folder.parent().expect("worlds/ is in a project"))
                .expect("the project folder exists");
        }
        let checked = regatta_schema::check_path(&path, &options).expect("corpus file is readable");
        if checked.has_errors() {
            failures.extend(
                checked
                    .short()
                    .into_iter()
                    .filter(|l| l.contains(": error: ")),
            );
        }
    }
    assert!(
        failures.is_empty(),
        "errors in lenient mode:\n{}",
        failures.join("\n")
    );
}

#[test]
fn broken_webots_files_fail_at_the_right_line_with_webots_message() {
    let expected = expected_webots_messages();
    // The line each file's comment marks with "error here".
    let mut checked_any = 0;
    for path in corpus_files()
        .into_iter()
        .filter(|p| is_broken_on_purpose(p))
    {
        let key = path
            .to_string_lossy()
            .split("tests/parser/")
            .nth(1)
            .expect("parser test path")
            .to_owned();
        let message = expected
            .get(&key)
            .unwrap_or_else(|| panic!("no expected message for {key}"));
        let source = std::fs::read_to_string(&path).unwrap();
        let error_line = source
            .lines()
            .position(|l| l.contains("error here"))
            .expect("marked line")
            + 1;
        let checked = check_file(&path, false).unwrap();
        let errors: Vec<_> = checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .collect();
        assert_eq!(errors.len(), 1, "{key}: {:?}", checked.short());
        assert_eq!(&errors[0].diagnostic.message, message, "{key}");
        let (line, _) = errors[0].diagnostic.line_col(&source);
        assert_eq!(line, error_line, "{key}: error reported on the wrong line");
        checked_any += 1;
    }
    assert_eq!(checked_any, 2);
}

#[test]
fn valid_webots_parser_files_give_no_error() {
    let expected = expected_webots_messages();
    for path in files_with(&corpus().join("webots/tests/parser/worlds"), &["wbt"]) {
        let key = format!("worlds/{}", path.file_name().unwrap().to_string_lossy());
        if expected.get(&key).map(String::as_str) == Some("VOID") {
            let checked = check_file(&path, false).unwrap();
            assert!(!checked.has_errors(), "{key}: {:?}", checked.short());
        }
    }
}

#[test]
fn formatting_is_idempotent_and_keeps_the_tree_on_the_corpus() {
    for path in corpus_files()
        .into_iter()
        .filter(|p| !is_broken_on_purpose(p))
    {
        let source = SourceText::read(&path).unwrap();
        let parsed = parse(&source.text);
        let once = regatta_parser::format::format(&parsed.file, &source.text);
        let reparsed = parse(&once);
        assert!(
            reparsed.diagnostics.is_empty(),
            "{}: formatted output does not parse: {:?}",
            path.display(),
            reparsed.diagnostics
        );
        let twice = regatta_parser::format::format(&reparsed.file, &once);
        assert_eq!(once, twice, "{}: fmt is not idempotent", path.display());
        assert_eq!(
            regatta_parser::format::dump(&parsed.file, &source.text, false),
            regatta_parser::format::dump(&reparsed.file, &once, false),
            "{}: fmt changed the tree",
            path.display()
        );
        let comments = |text: &str, file: &regatta_parser::syntax::SourceFile| {
            file.comments
                .iter()
                .map(|c| text[c.range()].trim_end().to_owned())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            comments(&source.text, &parsed.file),
            comments(&once, &reparsed.file),
            "{}: fmt lost comments",
            path.display()
        );
    }
}

#[test]
fn gzip_compressed_worlds_are_read() {
    use std::io::Write;
    let path = corpus().join("vrml97/mrdoob+three.js/examples/models/vrml/simple.wrl");
    let plain = std::fs::read(&path).unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-gz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gz = dir.join("simple.wrl.gz");
    let mut encoder = flate2_encoder(std::fs::File::create(&gz).unwrap());
    encoder.write_all(&plain).unwrap();
    drop(encoder);
    let source = SourceText::read(&gz).unwrap();
    assert_eq!(source.text.as_bytes(), &plain[..]);
    let checked = check_file(&gz, false).unwrap();
    assert!(!checked.has_errors());
    assert!(checked.scene.nodes.len() >= 4);
    std::fs::remove_dir_all(&dir).ok();
}

fn flate2_encoder(file: std::fs::File) -> impl std::io::Write {
    flate2::write::GzEncoder::new(file, flate2::Compression::default())
}
