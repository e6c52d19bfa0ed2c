//! Fuzzes the whole front end: decoding, parsing, formatting, rendering diagnostics and typing.
//! Run by hand: `cargo +nightly fuzz run parse` from `parser/`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let source = regatta_parser::SourceText::from_bytes("fuzz.wbt".to_owned(), data.to_vec());
    let parsed = regatta_parser::parse(&source.text);
    let formatted = regatta_parser::format::format(&parsed.file, &source.text);
    if !parsed.has_errors() {
        // Canonical form must parse back to the same tree.
        let again = regatta_parser::parse(&formatted);
        assert!(!again.has_errors());
    }
    for diagnostic in &parsed.diagnostics {
        let _ = diagnostic.render(&source.name, &source.text, false);
    }
    let _ = regatta_schema::check(source, &regatta_schema::Options::default());
});
