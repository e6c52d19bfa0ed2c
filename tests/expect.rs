//! Data-driven tests: every input in `tests/data/parse` has its syntax tree (with spans) and
//! parse diagnostics in a `.tree` file beside it; every input in `tests/data/check` has its
//! typed diagnostics and a scene summary in a `.expected` file. `REGATTA_BLESS=1` rewrites them.

use std::fmt::Write;

use regatta_parser::{parse, SourceText};
use regatta_schema::{check, FileAccess, Options};
use regatta_tests::{expect_file, files_with, root};

#[test]
fn parse_trees_match_their_expectations() {
    let inputs = files_with(&root().join("tests/data/parse"), &["wbt", "wrl", "proto"]);
    assert!(inputs.len() >= 10, "the parse cases are missing");
    let mut failures = Vec::new();
    for input in inputs {
        let source = SourceText::read(&input).expect("test input is readable");
        let parsed = parse(&source.text);
        let mut actual = regatta_parser::format::dump(&parsed.file, &source.text, true);
        for diagnostic in source.diagnostics.iter().chain(&parsed.diagnostics) {
            let name = input.file_name().unwrap().to_string_lossy();
            let _ = writeln!(actual, "{}", diagnostic.short(&name, &source.text));
        }
        if let Err(message) = expect_file(&input.with_extension("tree"), &actual) {
            failures.push(message);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn typed_diagnostics_match_their_expectations() {
    let inputs = files_with(&root().join("tests/data/check"), &["wbt", "wrl"]);
    assert!(inputs.len() >= 10, "the check cases are missing");
    let mut failures = Vec::new();
    for input in inputs {
        let source = SourceText::read(&input).expect("test input is readable");
        let name = input.file_name().unwrap().to_string_lossy().into_owned();
        let source = SourceText { name, ..source };
        let lenient = source.text.contains("# mode: lenient");
        let options = Options {
            strict: !lenient,
            access: FileAccess::for_world(&input).expect("the test folder exists"),
            base_dir: Some(input.parent().unwrap().canonicalize().unwrap()),
            ..Options::default()
        };
        let checked = check(source, &options);
        let mut actual = String::new();
        for (line, diagnostic) in checked.short().iter().zip(&checked.diagnostics) {
            let _ = writeln!(actual, "{line}");
            for note in &diagnostic.diagnostic.notes {
                let _ = writeln!(actual, "  = note: {note}");
            }
        }
        let scene = &checked.scene;
        let _ = writeln!(
            actual,
            "-- scene: {} nodes, up axis {:?}",
            scene.nodes.len(),
            scene.up_axis
        );
        for id in scene.walk().into_iter().take(40) {
            let node = scene.node(id);
            let def = node
                .def_name()
                .map(|d| format!(" DEF {d}"))
                .unwrap_or_default();
            let protos = if node.proto_names().is_empty() {
                String::new()
            } else {
                format!(" from {}", node.proto_names().join(" < "))
            };
            let written: Vec<String> = scene
                .spec(id)
                .fields
                .iter()
                .zip(&node.fields)
                .zip(&node.written)
                .filter(|(_, &w)| w)
                .filter(|((f, _), _)| f.ty().base != regatta_schema::BaseType::Node)
                .map(|((f, v), _)| format!("{}={}", f.name, v.display()))
                .collect();
            let _ = writeln!(
                actual,
                "{}{def}{protos} {}",
                scene.type_name(id),
                written.join(" ")
            );
        }
        if let Err(message) = expect_file(&input.with_extension("expected"), &actual) {
            failures.push(message);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
