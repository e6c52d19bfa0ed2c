//! The house rules ARCHITECTURE.md states about the code's shape, checked from the code's own
//! text so that they stay true:
//!
//! - within a crate, source files import each other without circles;
//! - no source file passes [`MAX_LINES`] lines;
//! - every crate but those that draw, time and check is under the root `clippy.toml`, which
//!   bans the platform's transcendental functions (logs are the same bytes on every machine).
//!
//! "Import" is read as a reader of the code would: a `use` of `crate::`, `super::`, `self::` or
//! of a child module, or such a path written in the code; a path through a module's
//! `pub use` counts as an import of the file that defines the item. Code under `#[cfg(test)]`
//! does not count (a unit test may look at its parent). A parent module that only declares
//! its children (`mod child;`) does not import them; one that uses their items does.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest source file allowed, in lines.
const MAX_LINES: usize = 1_200;

#[test]
fn files_within_a_crate_import_each_other_without_circles() {
    let mut report = String::new();
    for krate in workspace_crates() {
        let graph = ImportGraph::read(&krate);
        for circle in graph.circles() {
            report.push_str(&format!("circle in {}:\n", krate.display()));
            for file in &circle {
                for (to, names) in &graph.edges[file] {
                    if circle.contains(to) {
                        report.push_str(&format!(
                            "  {} -> {}: {}\n",
                            graph.files[*file].display,
                            graph.files[*to].display,
                            names.iter().cloned().collect::<Vec<_>>().join(", ")
                        ));
                    }
                }
            }
        }
    }
    assert!(
        report.is_empty(),
        "files that import each other in a circle:\n{report}"
    );
}

#[test]
fn no_source_file_is_too_long() {
    let mut long = Vec::new();
    for krate in workspace_crates() {
        for path in regatta_tests::files_with(&krate.join("src"), &["rs"]) {
            let lines = std::fs::read_to_string(&path).map_or(0, |text| text.lines().count());
            if lines > MAX_LINES {
                long.push(format!("{} ({lines} lines)", path.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "source files past {MAX_LINES} lines: split them where a seam is natural:\n{}",
        long.join("\n")
    );
}

/// The checker itself: a circle through a parent and its child, one through a re-export, and
/// test code that is left out.
#[test]
fn the_checker_finds_circles_and_leaves_tests_out() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-architecture-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    let write = |name: &str, text: &str| std::fs::write(src.join(name), text).unwrap();
    write("lib.rs", "mod a;\nmod b;\nmod c;\npub use c::Gamma;\n");
    // a/mod.rs uses its child's item and the child uses the parent's: a circle.
    write(
        "a/mod.rs",
        "mod leaf;\npub struct Alpha;\nfn f() -> leaf::Leaf { todo!() }\n",
    );
    write("a/leaf.rs", "use super::Alpha;\npub struct Leaf(Alpha);\n");
    // b uses crate::Gamma (defined in c, re-exported by lib.rs); c uses b only in tests.
    write(
        "b.rs",
        "/* crate::a::Alpha in a comment */\nconst S: &str = \"crate::a::Alpha\";\n\
         pub fn beta(_: crate::Gamma) {}\n",
    );
    write(
        "c.rs",
        "pub struct Gamma;\n#[cfg(test)]\nmod tests {\n    use crate::b::beta;\n}\n",
    );
    let graph = ImportGraph::read(&dir);
    let circles: Vec<Vec<String>> = graph
        .circles()
        .into_iter()
        .map(|c| c.iter().map(|&f| graph.files[f].display.clone()).collect())
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        circles,
        vec![vec!["a/leaf.rs".to_owned(), "a/mod.rs".to_owned()]]
    );
    let b = graph.index("b.rs");
    let c = graph.index("c.rs");
    assert!(
        graph.edges[&b].contains_key(&c),
        "b uses Gamma through lib.rs's pub use"
    );
    assert!(!graph.edges[&c].contains_key(&b), "tests do not count");
    assert_eq!(
        graph.edges[&b].len(),
        1,
        "comments and strings do not count"
    );
}

/// The crates that may use the platform's math: they draw figures, time benchmarks and check
/// results; nothing of theirs reaches a sensor, a pose or a log.
const STD_MATH_CRATES: [&str; 3] = ["figures", "tools", "tests"];

#[test]
fn the_platforms_transcendental_functions_are_banned_where_results_reach_a_log() {
    let root = regatta_tests::root();
    // Clippy reads the clippy.toml nearest above a crate's manifest.
    for krate in workspace_crates() {
        let name = krate
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let used = krate
            .ancestors()
            .take_while(|dir| dir.starts_with(&root))
            .map(|dir| dir.join("clippy.toml"))
            .find(|file| file.is_file())
            .unwrap_or_else(|| panic!("no clippy.toml holds for {name}"));
        if STD_MATH_CRATES.contains(&name.as_str()) {
            assert_eq!(
                used,
                krate.join("clippy.toml"),
                "{name} opts out in its own"
            );
        } else {
            assert_eq!(
                used,
                root.join("clippy.toml"),
                "{name} is not under the root clippy.toml's ban on the platform's math"
            );
        }
    }
    let config = std::fs::read_to_string(root.join("clippy.toml")).unwrap();
    for function in [
        "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sin_cos", "sinh", "cosh", "tanh",
        "asinh", "acosh", "atanh", "exp", "exp2", "exp_m1", "ln", "ln_1p", "log", "log2", "log10",
        "powf", "powi", "hypot", "cbrt",
    ] {
        for float in ["f32", "f64"] {
            let path = format!("path = \"{float}::{function}\"");
            assert!(
                config.contains(&path),
                "clippy.toml does not ban {float}::{function}"
            );
        }
    }
}

/// The workspace members' folders that hold a `src/`.
fn workspace_crates() -> Vec<PathBuf> {
    let root = regatta_tests::root();
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("the root Cargo.toml");
    let members = manifest
        .lines()
        .find(|line| line.trim_start().starts_with("members"))
        .expect("a members list");
    let crates: Vec<PathBuf> = members
        .split('"')
        .skip(1)
        .step_by(2)
        .map(|member| root.join(member))
        .filter(|dir| dir.join("src").is_dir())
        .collect();
    assert!(
        crates.len() > 5,
        "the workspace's crates were found: {crates:?}"
    );
    crates
}

struct SourceFile {
    /// Path from `src/`, for messages.
    display: String,
    /// Module path from the crate root (empty for `lib.rs`/`main.rs`).
    module: Vec<String>,
    /// The text with comments, strings and test-only items blanked out.
    code: String,
}

struct ImportGraph {
    files: Vec<SourceFile>,
    by_module: BTreeMap<Vec<String>, usize>,
    /// File → file it imports → the paths that make the import.
    edges: BTreeMap<usize, BTreeMap<usize, BTreeSet<String>>>,
}

impl ImportGraph {
    fn read(krate: &Path) -> ImportGraph {
        let src = krate.join("src");
        let mut files = Vec::new();
        for path in regatta_tests::files_with(&src, &["rs"]) {
            let relative = path.strip_prefix(&src).unwrap();
            let mut module: Vec<String> = relative
                .with_extension("")
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if matches!(
                module.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                module.pop();
            }
            let text = std::fs::read_to_string(&path).unwrap();
            files.push(SourceFile {
                display: relative.to_string_lossy().replace('\\', "/"),
                module,
                code: without_tests(&blank_comments_and_strings(&text)),
            });
        }
        files.sort_by(|a, b| a.display.cmp(&b.display));
        let by_module = files
            .iter()
            .enumerate()
            .map(|(i, f)| (f.module.clone(), i))
            .collect();
        let mut graph = ImportGraph {
            files,
            by_module,
            edges: BTreeMap::new(),
        };
        let reexports = graph.reexports();
        for index in 0..graph.files.len() {
            let mut edges: BTreeMap<usize, BTreeSet<String>> = BTreeMap::new();
            for path in graph.paths_of(index) {
                if let Some(to) = graph.resolve(index, &path, &reexports, 0) {
                    if to != index {
                        edges.entry(to).or_default().insert(path.join("::"));
                    }
                }
            }
            graph.edges.insert(index, edges);
        }
        graph
    }

    fn index(&self, display: &str) -> usize {
        self.files
            .iter()
            .position(|f| f.display == display)
            .unwrap()
    }

    /// Names each file makes public through `pub use`, with the path they stand for.
    fn reexports(&self) -> BTreeMap<(usize, String), Vec<String>> {
        let mut out = BTreeMap::new();
        for (index, file) in self.files.iter().enumerate() {
            for (public, tree) in use_statements(&file.code) {
                if !public {
                    continue;
                }
                for path in expand_use_tree(&tree) {
                    let mut path: Vec<String> = path;
                    let name = match path.iter().position(|s| s == "as") {
                        Some(at) => {
                            let alias = path[at + 1..].first().cloned().unwrap_or_default();
                            path.truncate(at);
                            alias
                        }
                        None => path.last().cloned().unwrap_or_default(),
                    };
                    out.insert((index, name), path);
                }
            }
        }
        out
    }

    /// Every path the file writes that may lead into its crate: `use` trees expanded, and
    /// paths in code starting at `crate`, `super`, `self` or a child module.
    fn paths_of(&self, index: usize) -> Vec<Vec<String>> {
        let file = &self.files[index];
        let mut paths = Vec::new();
        for (_, tree) in use_statements(&file.code) {
            for mut path in expand_use_tree(&tree) {
                if let Some(at) = path.iter().position(|s| s == "as") {
                    path.truncate(at);
                }
                paths.push(path);
            }
        }
        let code = without_use_statements(&file.code);
        let bytes = code.as_bytes();
        let mut at = 0;
        while at < bytes.len() {
            if !is_ident_start(bytes[at]) || (at > 0 && is_ident_byte(bytes[at - 1])) {
                at += 1;
                continue;
            }
            let preceded_by_path =
                at >= 2 && &code[at - 2..at] == "::" || at >= 1 && bytes[at - 1] == b'.';
            let mut segments = Vec::new();
            let mut end = at;
            loop {
                let start = end;
                while end < bytes.len() && is_ident_byte(bytes[end]) {
                    end += 1;
                }
                segments.push(code[start..end].to_owned());
                let rest = &code[end..];
                let trimmed = rest.trim_start();
                if let Some(after) = trimmed.strip_prefix("::") {
                    let after_trimmed = after.trim_start();
                    if after_trimmed.bytes().next().is_some_and(is_ident_start) {
                        end = code.len() - after_trimmed.len();
                        continue;
                    }
                }
                break;
            }
            if !preceded_by_path && segments.len() > 1 {
                paths.push(segments);
            }
            at = end.max(at + 1);
        }
        paths
    }

    /// The file a path leads to, following `pub use` to where a name is defined.
    fn resolve(
        &self,
        from: usize,
        path: &[String],
        reexports: &BTreeMap<(usize, String), Vec<String>>,
        depth: usize,
    ) -> Option<usize> {
        let here = &self.files[from].module;
        let (mut module, rest): (Vec<String>, &[String]) = match path.first()?.as_str() {
            "crate" => (Vec::new(), &path[1..]),
            "self" => (here.clone(), &path[1..]),
            "super" => {
                let supers = path.iter().take_while(|s| *s == "super").count();
                let keep = here.len().checked_sub(supers)?;
                (here[..keep].to_vec(), &path[supers..])
            }
            child => {
                let mut child_module = here.clone();
                child_module.push(child.to_owned());
                if !self.by_module.contains_key(&child_module)
                    || !declares_module(&self.files[from].code, child)
                {
                    return None;
                }
                (child_module, &path[1..])
            }
        };
        let mut rest = rest;
        while let Some(first) = rest.first() {
            let mut deeper = module.clone();
            deeper.push(first.clone());
            if self.by_module.contains_key(&deeper) {
                module = deeper;
                rest = &rest[1..];
            } else {
                break;
            }
        }
        let file = *self.by_module.get(&module)?;
        if let Some(name) = rest.first() {
            if let Some(target) = reexports.get(&(file, name.clone())) {
                // Follow the re-export from the re-exporting file, a few levels at most.
                if depth < 8 {
                    if let Some(to) = self.resolve(file, target, reexports, depth + 1) {
                        return Some(to);
                    }
                }
            }
        }
        Some(file)
    }

    /// Strongly connected sets of more than one file (Tarjan), in a stable order.
    fn circles(&self) -> Vec<Vec<usize>> {
        struct State<'g> {
            edges: &'g BTreeMap<usize, BTreeMap<usize, BTreeSet<String>>>,
            index: Vec<Option<usize>>,
            low: Vec<usize>,
            on_stack: Vec<bool>,
            stack: Vec<usize>,
            next: usize,
            out: Vec<Vec<usize>>,
        }
        fn visit(state: &mut State<'_>, v: usize) {
            state.index[v] = Some(state.next);
            state.low[v] = state.next;
            state.next += 1;
            state.stack.push(v);
            state.on_stack[v] = true;
            let targets: Vec<usize> = state.edges[&v].keys().copied().collect();
            for w in targets {
                match state.index[w] {
                    None => {
                        visit(state, w);
                        state.low[v] = state.low[v].min(state.low[w]);
                    }
                    Some(index) if state.on_stack[w] => state.low[v] = state.low[v].min(index),
                    Some(_) => {}
                }
            }
            if Some(state.low[v]) == state.index[v] {
                let mut component = Vec::new();
                loop {
                    let w = state.stack.pop().unwrap();
                    state.on_stack[w] = false;
                    component.push(w);
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort_unstable();
                    state.out.push(component);
                }
            }
        }
        let n = self.files.len();
        let mut state = State {
            edges: &self.edges,
            index: vec![None; n],
            low: vec![0; n],
            on_stack: vec![false; n],
            stack: Vec::new(),
            next: 0,
            out: Vec::new(),
        };
        for v in 0..n {
            if state.index[v].is_none() {
                visit(&mut state, v);
            }
        }
        state.out.sort();
        state.out
    }
}

fn is_ident_start(byte: u8) -> bool {
    byte.is_ascii_alphabetic() || byte == b'_'
}

fn is_ident_byte(byte: u8) -> bool {
    byte.is_ascii_alphanumeric() || byte == b'_'
}

/// Whether the file declares `mod name;` (a child in a file of its own).
fn declares_module(code: &str, name: &str) -> bool {
    code.split(';').any(|statement| {
        let words: Vec<&str> = statement.split_whitespace().collect();
        words.len() >= 2 && words[words.len() - 2] == "mod" && words[words.len() - 1] == name
    })
}

/// `use` statements as (public, tree text).
fn use_statements(code: &str) -> Vec<(bool, String)> {
    let mut out = Vec::new();
    for (start, end) in use_spans(code) {
        let statement = &code[start..end];
        let public = statement.trim_start().starts_with("pub");
        let tree = statement[statement.find("use").unwrap() + 3..]
            .trim()
            .trim_end_matches(';');
        out.push((public, tree.to_owned()));
    }
    out
}

/// Byte ranges of the `use` statements (with any `pub(...)` before them).
fn use_spans(code: &str) -> Vec<(usize, usize)> {
    let bytes = code.as_bytes();
    let mut spans = Vec::new();
    let mut at = 0;
    while let Some(found) = code[at..].find("use") {
        let start = at + found;
        at = start + 3;
        let before_ok = start == 0 || !is_ident_byte(bytes[start - 1]);
        let after_ok = bytes
            .get(start + 3)
            .is_some_and(|b| b.is_ascii_whitespace());
        if !(before_ok && after_ok) {
            continue;
        }
        // A `use` statement stands where a statement starts.
        let line_start = code[..start]
            .rfind(['\n', ';', '{', '}'])
            .map_or(0, |i| i + 1);
        let prefix = code[line_start..start].trim();
        let statement_start = if prefix.is_empty() {
            start
        } else if prefix.starts_with("pub") && !prefix.contains(' ') || prefix == "pub" {
            line_start + code[line_start..start].find("pub").unwrap()
        } else {
            continue;
        };
        let Some(end) = code[start..].find(';') else {
            break;
        };
        spans.push((statement_start, start + end + 1));
        at = start + end + 1;
    }
    spans
}

fn without_use_statements(code: &str) -> String {
    let mut out = code.to_owned();
    for (start, end) in use_spans(code) {
        out.replace_range(start..end, &" ".repeat(end - start));
    }
    out
}

/// `a::{b, c::{d, self}}` into `[a, b]`, `[a, c, d]`, `[a, c]`.
fn expand_use_tree(tree: &str) -> Vec<Vec<String>> {
    fn expand(tree: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
        let tree = tree.trim();
        if tree.is_empty() {
            return;
        }
        if let Some(open) = tree.find('{') {
            let head = tree[..open].trim().trim_end_matches("::").trim();
            let mut base = prefix.to_vec();
            base.extend(split_path(head));
            let close = tree.rfind('}').unwrap_or(tree.len());
            let inner = &tree[open + 1..close];
            for part in split_top_level(inner) {
                if part.trim() == "self" {
                    out.push(base.clone());
                } else {
                    expand(part, &base, out);
                }
            }
        } else {
            let mut path = prefix.to_vec();
            let (path_text, alias) = match tree.split_once(" as ") {
                Some((path, alias)) => (path, Some(alias.trim())),
                None => (tree, None),
            };
            path.extend(split_path(path_text));
            if path.last().map(String::as_str) == Some("*") {
                path.pop();
            }
            if let Some(alias) = alias {
                path.push("as".to_owned());
                path.push(alias.to_owned());
            }
            out.push(path);
        }
    }
    let mut out = Vec::new();
    expand(tree, &[], &mut out);
    out
}

fn split_path(text: &str) -> Vec<String> {
    text.split("::")
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect()
}

/// Splits at commas outside braces.
fn split_top_level(text: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let mut depth = 0;
    let mut start = 0;
    for (i, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// Comments, string and character literals replaced by spaces (newlines kept), so that what
/// remains is code.
fn blank_comments_and_strings(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = bytes.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for byte in &mut out[from..to] {
            if *byte != b'\n' {
                *byte = b' ';
            }
        }
    };
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                let end = text[i..].find('\n').map_or(bytes.len(), |n| i + n);
                blank(&mut out, i, end);
                i = end;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                let mut depth = 0;
                let mut j = i;
                while j < bytes.len() {
                    if bytes[j..].starts_with(b"/*") {
                        depth += 1;
                        j += 2;
                    } else if bytes[j..].starts_with(b"*/") {
                        depth -= 1;
                        j += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        j += 1;
                    }
                }
                blank(&mut out, i, j);
                i = j;
            }
            b'r' if (i == 0 || !is_ident_byte(bytes[i - 1]))
                && matches!(bytes.get(i + 1), Some(b'"' | b'#')) =>
            {
                let hashes = bytes[i + 1..].iter().take_while(|&&b| b == b'#').count();
                if bytes.get(i + 1 + hashes) != Some(&b'"') {
                    i += 1;
                    continue;
                }
                let closing = format!("\"{}", "#".repeat(hashes));
                let body = i + 2 + hashes;
                let end = text[body..]
                    .find(&closing)
                    .map_or(bytes.len(), |n| body + n + closing.len());
                blank(&mut out, i, end);
                i = end;
            }
            b'"' => {
                let mut j = i + 1;
                while j < bytes.len() && bytes[j] != b'"' {
                    j += if bytes[j] == b'\\' { 2 } else { 1 };
                }
                let end = (j + 1).min(bytes.len());
                blank(&mut out, i, end);
                i = end;
            }
            b'\'' => {
                // A character literal ('x', '\n', '\u{..}'); a lifetime has no closing quote.
                let end = if bytes.get(i + 1) == Some(&b'\\') {
                    text[i + 2..].find('\'').map(|n| i + 2 + n + 1)
                } else {
                    text[i + 1..]
                        .chars()
                        .next()
                        .map(|c| i + 1 + c.len_utf8())
                        .filter(|&e| bytes.get(e) == Some(&b'\''))
                        .map(|e| e + 1)
                };
                match end {
                    Some(end) => {
                        blank(&mut out, i, end);
                        i = end;
                    }
                    None => i += 1,
                }
            }
            _ => i += 1,
        }
    }
    String::from_utf8(out).expect("only ASCII bytes were replaced")
}

/// Items under `#[cfg(test)]` (or `#[cfg(all(test, …))]`) blanked out: through the matching
/// `}` of their first `{`, or to their `;`.
fn without_tests(code: &str) -> String {
    let mut out = code.to_owned();
    let mut from = 0;
    while let Some(found) = out[from..].find("#[cfg(") {
        let start = from + found;
        let bytes = out.as_bytes();
        // The attribute ends at the `]` that closes its `[`.
        let mut j = start + 1;
        let mut depth = 0usize;
        while j < bytes.len() {
            match bytes[j] {
                b'[' | b'(' => depth += 1,
                b']' | b')' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                _ => {}
            }
            j += 1;
        }
        let attribute = &out[start..(j + 1).min(out.len())];
        let test_only = attribute
            .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
            .any(|word| word == "test")
            && !attribute.contains("not(");
        if !test_only {
            from = start + 1;
            continue;
        }
        let mut depth = 0usize;
        let mut end = bytes.len();
        j += 1;
        while j < bytes.len() {
            match bytes[j] {
                b';' if depth == 0 => {
                    end = j + 1;
                    break;
                }
                b'{' => depth += 1,
                b'}' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        end = j + 1;
                        break;
                    }
                }
                _ => {}
            }
            j += 1;
        }
        let blanked: String = out[start..end]
            .chars()
            .map(|c| if c == '\n' { '\n' } else { ' ' })
            .collect();
        out.replace_range(start..end, &blanked);
        from = end;
    }
    out
}
