//! How the parser gets past a mistake: skipping a token or a whole group, and the messages for
//! nodes never closed and nesting past the limit (each said once, where it was noticed).

use crate::diagnostic::Diagnostic;
use crate::lexer::TokenKind;
use crate::span::Span;
use crate::syntax::Ident;

use super::cursor::Parser;

impl Parser<'_> {
    /// Skips the current token; a `{` or `[` takes its whole balanced group with it.
    pub(super) fn skip_token_or_group(&mut self) {
        let open = self.bump();
        if !matches!(open.kind, TokenKind::LBrace | TokenKind::LBracket) {
            return;
        }
        let mut depth = 1usize;
        while depth > 0 {
            match self.current.kind {
                TokenKind::LBrace | TokenKind::LBracket => depth += 1,
                TokenKind::RBrace | TokenKind::RBracket => depth -= 1,
                TokenKind::Eof => return,
                _ => {}
            }
            self.bump();
        }
    }

    /// What the secondary label of an unclosed node says.
    pub(super) fn never_closed(&self, type_name: &Ident) -> String {
        if type_name.text.is_empty() {
            "this '{' is never closed".to_owned()
        } else {
            format!("this {} node is never closed", type_name.text)
        }
    }

    /// Reports a node whose `}` is missing, noticed at the current token (once per place).
    pub(super) fn unclosed(&mut self, type_name: &Ident, open: Span) {
        if self.unclosed_at == Some(self.current.span.start) {
            return;
        }
        self.unclosed_at = Some(self.current.span.start);
        let line = self.line_of(open.start) + 1;
        let node = if type_name.text.is_empty() {
            "node".to_owned()
        } else {
            format!("{} node", type_name.text)
        };
        let found = if self.current.kind == TokenKind::RBracket {
            "']'".to_owned()
        } else {
            format!("the next node, {}", self.found())
        };
        let diagnostic = Diagnostic::error(
            self.current.span,
            format!("Expected '}}' to close the {node} of line {line}, found {found}."),
        )
        .with_label("expected '}' before this")
        .with_secondary(open, self.never_closed(type_name))
        .with_code("unclosed");
        self.error(diagnostic);
    }

    /// Nesting beyond the limit: one message, where it was first crossed.
    pub(super) fn too_deep(&mut self, open: Span, what: &str) {
        if std::mem::replace(&mut self.depth_reported, true) {
            return;
        }
        let limit = self.max_depth;
        self.error(
            Diagnostic::error(open, format!("{what} nested deeper than {limit} levels"))
                .with_label("this group and everything in it is skipped")
                .with_note(format!(
                    "the nesting limit is {limit}; `--limit nesting=N` raises it"
                ))
                .with_code("too-deep"),
        );
    }

    /// After a `{` that is not followed: skip to its matching `}` without recursion.
    pub(super) fn skip_rest_of_group(&mut self) {
        let mut depth = 1usize;
        while depth > 0 && self.current.kind != TokenKind::Eof {
            match self.current.kind {
                TokenKind::LBrace | TokenKind::LBracket => depth += 1,
                TokenKind::RBrace | TokenKind::RBracket => depth -= 1,
                _ => {}
            }
            self.bump();
        }
    }
}
