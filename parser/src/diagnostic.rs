//! Diagnostics shared by every layer (syntax, typing, compiling), and their rendering in the
//! style of rustc: `file:line:col`, the source line, a caret, what was expected and found.

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{Files, SimpleFiles};
use codespan_reporting::term;

use crate::span::Span;

/// How bad a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Severity {
    Warning,
    Error,
}

/// A secondary place worth showing, with a word about it.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    pub span: Span,
    pub message: String,
    /// The file it is in, as an index of the [`SourceMap`] the diagnostic is rendered with;
    /// `None` is the diagnostic's own file. (A PROTO's body, shown beside the user's line.)
    pub file: Option<usize>,
}

/// One message about one place in one file.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// The main sentence: "Expected '{', found 'RectangleArena'."
    pub message: String,
    /// Where the caret goes.
    pub span: Span,
    /// What to print under the caret.
    pub label: String,
    pub secondary: Vec<Label>,
    /// Hints printed after the snippet ("did you mean …").
    pub notes: Vec<String>,
    /// A stable machine-readable kind, for tools and tests.
    pub code: &'static str,
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            message: message.into(),
            span,
            label: String::new(),
            secondary: Vec::new(),
            notes: Vec::new(),
            code: "syntax",
        }
    }

    /// A warning at `span`.
    pub fn warning(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(span, message)
        }
    }

    /// Sets the text under the caret.
    pub fn with_label(mut self, label: impl Into<String>) -> Diagnostic {
        self.label = label.into();
        self
    }

    /// Adds a secondary place.
    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.secondary.push(Label {
            span,
            message: message.into(),
            file: None,
        });
        self
    }

    /// Adds a secondary place in another file of the same [`SourceMap`].
    pub fn with_secondary_in(
        mut self,
        file: usize,
        span: Span,
        message: impl Into<String>,
    ) -> Diagnostic {
        self.secondary.push(Label {
            span,
            message: message.into(),
            file: Some(file),
        });
        self
    }

    /// Adds a hint.
    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    /// Sets the machine-readable kind.
    pub fn with_code(mut self, code: &'static str) -> Diagnostic {
        self.code = code;
        self
    }

    /// Whether this is an error (not a warning).
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// `line:col` (both from 1, col counted in characters) of the caret.
    pub fn line_col(&self, source: &str) -> (usize, usize) {
        line_col(source, self.span.start as usize)
    }

    /// Renders in rustc's style: header, `--> file:line:col`, the line and a caret.
    pub fn render(&self, file_name: &str, source: &str, color: bool) -> String {
        let mut map = SourceMap::new();
        let file = map.add(file_name, source);
        map.render(file, self, color)
    }

    /// `file:line:col: error: message` on one line, for logs and tests.
    pub fn short(&self, file_name: &str, source: &str) -> String {
        let (line, col) = self.line_col(source);
        format!(
            "{file_name}:{line}:{col}: {}: {}",
            self.severity_word(),
            self.message
        )
    }

    fn severity_word(&self) -> &'static str {
        match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        }
    }
}

/// The files diagnostics point into, with their line starts found once: rendering many
/// diagnostics of a large file costs one pass over it, not one per diagnostic.
pub struct SourceMap<'a> {
    files: SimpleFiles<&'a str, &'a str>,
}

impl Default for SourceMap<'_> {
    fn default() -> Self {
        SourceMap::new()
    }
}

impl<'a> SourceMap<'a> {
    pub fn new() -> SourceMap<'a> {
        SourceMap {
            files: SimpleFiles::new(),
        }
    }

    /// Adds a file; returns its index.
    pub fn add(&mut self, name: &'a str, source: &'a str) -> usize {
        self.files.add(name, source)
    }

    fn range(&self, file: usize, span: Span) -> std::ops::Range<usize> {
        let source = self.files.get(file).map(|f| *f.source()).unwrap_or("");
        let end = (span.end as usize).min(source.len());
        let start = (span.start as usize).min(end);
        floor_char_boundary(source, start)..floor_char_boundary(source, end)
    }

    /// `line:col` (both from 1; col in characters) of byte `offset` of `file`.
    pub fn line_col(&self, file: usize, offset: usize) -> (usize, usize) {
        let Ok(entry) = self.files.get(file) else {
            return (1, 1);
        };
        let source = *entry.source();
        let offset = floor_char_boundary(source, offset.min(source.len()));
        match self.files.location(file, offset) {
            Ok(location) => (location.line_number, location.column_number),
            Err(_) => line_col(source, offset),
        }
    }

    /// `file:line:col: error: message`.
    pub fn short(&self, file: usize, diagnostic: &Diagnostic) -> String {
        let name = self.files.get(file).map(|f| *f.name()).unwrap_or("?");
        let (line, col) = self.line_col(file, diagnostic.span.start as usize);
        format!(
            "{name}:{line}:{col}: {}: {}",
            diagnostic.severity_word(),
            diagnostic.message
        )
    }

    /// Renders `diagnostic`, which is about `file`, in rustc's style.
    pub fn render(&self, file: usize, diagnostic: &Diagnostic, color: bool) -> String {
        let mut labels = vec![cs::Label::primary(file, self.range(file, diagnostic.span))
            .with_message(&diagnostic.label)];
        for label in &diagnostic.secondary {
            let in_file = label.file.unwrap_or(file);
            labels.push(
                cs::Label::secondary(in_file, self.range(in_file, label.span))
                    .with_message(&label.message),
            );
        }
        let rendered = match diagnostic.severity {
            Severity::Error => cs::Diagnostic::error(),
            Severity::Warning => cs::Diagnostic::warning(),
        }
        .with_message(&diagnostic.message)
        .with_labels(labels)
        .with_notes(diagnostic.notes.clone());
        let config = term::Config::default();
        let mut out = Vec::new();
        let result = if color {
            let mut writer = term::termcolor::Ansi::new(&mut out);
            term::emit_to_write_style(&mut writer, &config, &self.files, &rendered)
        } else {
            let mut writer = term::termcolor::NoColor::new(&mut out);
            term::emit_to_write_style(&mut writer, &config, &self.files, &rendered)
        };
        match result {
            Ok(()) => String::from_utf8_lossy(&out).into_owned(),
            Err(_) => format!("{}\n", self.short(file, diagnostic)),
        }
    }
}

fn floor_char_boundary(source: &str, mut index: usize) -> usize {
    while index > 0 && !source.is_char_boundary(index) {
        index -= 1;
    }
    index
}

/// `line:col` (both from 1; col in characters) of byte `offset`.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = floor_char_boundary(source, offset.min(source.len()));
    let before = &source[..offset];
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}
