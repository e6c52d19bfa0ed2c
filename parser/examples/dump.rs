//! Prints a file's syntax tree (`--spans` adds byte ranges) and its diagnostics.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spans = args.iter().any(|a| a == "--spans");
    let fmt = args.iter().any(|a| a == "--fmt");
    for path in args.iter().filter(|a| !a.starts_with("--")) {
        let source =
            regatta_parser::SourceText::read(std::path::Path::new(path)).expect("readable file");
        let parse = regatta_parser::parse(&source.text);
        if fmt {
            print!(
                "{}",
                regatta_parser::format::format(&parse.file, &source.text)
            );
        } else {
            print!(
                "{}",
                regatta_parser::format::dump(&parse.file, &source.text, spans)
            );
        }
        for d in &parse.diagnostics {
            eprint!("{}", d.render(&source.name, &source.text, false));
        }
    }
}
