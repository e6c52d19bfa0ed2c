//! Reporting and blame: every diagnostic goes through [`Lowerer::error`], which moves a
//! problem an instance caused from inside a PROTO's body to the user's line (`relocate`, as
//! rustc does for macros), keeps one message per place, and caps their number; strict or
//! lenient severity; one message per crossed limit.

use regatta_parser::{Diagnostic, Span};

use crate::scene::FileId;

use super::checked::FileDiagnostic;
use super::options::MAX_DIAGNOSTICS;
use super::state::Lowerer;

impl<'c> Lowerer<'c> {
    pub(super) fn error(&mut self, file: FileId, diagnostic: Diagnostic) {
        let original = file;
        let (file, diagnostic) = self.relocate(file, diagnostic);
        // One mistake, one message: a user's value that breaks several parts of a PROTO's
        // body is reported once, at the value.
        if file != original && !self.relocated.insert((file.0, diagnostic.span.start)) {
            return;
        }
        if self.diagnostics.len() >= MAX_DIAGNOSTICS {
            self.dropped += 1;
            return;
        }
        self.diagnostics.push(FileDiagnostic { file, diagnostic });
    }

    /// The innermost PROTO instance being expanded that the user wrote (not a built-in
    /// PROTO's body).
    pub(super) fn user_instance(&self) -> Option<(FileId, Span)> {
        self.frames
            .iter()
            .rev()
            .find(|f| !self.is_builtin(f.instance.0))
            .map(|f| f.instance)
    }

    /// Inside a PROTO's expansion, a problem the instance caused is shown at the instance's
    /// line, with the PROTO's line beside it: a value typed while `blame` is set (a template
    /// over the instance's fields), or any problem in a built-in PROTO, which the user cannot
    /// edit.
    pub(super) fn relocate(
        &self,
        file: FileId,
        mut diagnostic: Diagnostic,
    ) -> (FileId, Diagnostic) {
        let target = match self.blame {
            Some((blamed, span)) if blamed != file || span != diagnostic.span => {
                Some((blamed, span))
            }
            _ if self.is_builtin(file) => self.user_instance(),
            _ => None,
        };
        let Some((user_file, user_span)) = target else {
            return (file, diagnostic);
        };
        let proto = self
            .frames
            .iter()
            .rev()
            .find(|f| f.definition == file)
            .map(|f| format!("in the body of PROTO '{}'", f.name))
            .unwrap_or_else(|| "in a PROTO body".to_owned());
        for label in &mut diagnostic.secondary {
            label.file.get_or_insert(file.0 as usize);
        }
        let original = diagnostic.span;
        let label = std::mem::take(&mut diagnostic.label);
        diagnostic.span = user_span;
        diagnostic.label = "caused by this".to_owned();
        diagnostic.secondary.insert(
            0,
            regatta_parser::Label {
                span: original,
                message: if label.is_empty() {
                    proto
                } else {
                    format!("{proto}: {label}")
                },
                file: Some(file.0 as usize),
            },
        );
        (user_file, diagnostic)
    }

    /// An error in strict mode, a warning in lenient mode.
    /// How a message begins about something unknown: a strict check refuses the world
    /// ("Unknown 'X' field in Y node."), a lenient one skips it and says so as Webots does
    /// ("Skipped unknown 'X' field in Y node.").
    pub(super) fn unknown(&self) -> &'static str {
        if self.options.strict {
            "Unknown"
        } else {
            "Skipped unknown"
        }
    }

    pub(super) fn strict_or_warn(&mut self, file: FileId, mut diagnostic: Diagnostic) {
        if !self.options.strict {
            diagnostic.severity = regatta_parser::Severity::Warning;
        }
        self.error(file, diagnostic);
    }

    /// Reports a crossed limit once: one cause, one message.
    pub(super) fn limit_crossed(
        &mut self,
        key: &'static str,
        file: FileId,
        diagnostic: Diagnostic,
    ) {
        if self.limits_reported.insert(key) {
            let diagnostic = diagnostic
                .with_note(format!("`--limit {key}=N` raises the limit"))
                .with_code("limit");
            self.error(file, diagnostic);
        }
    }
}
