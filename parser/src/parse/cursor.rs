//! The parser's state and what every rule uses: moving over tokens, looking at their text,
//! names and keywords, and reporting (with the cap on the number of messages).

use crate::diagnostic::Diagnostic;
use crate::lexer::{Lexer, Token, TokenKind};
use crate::span::Span;
use crate::syntax::Ident;

/// Syntax errors reported per file; past it, one message says so and parsing goes on quietly.
pub const MAX_ERRORS: usize = 200;

const KEYWORDS: &[&str] = &[
    "DEF",
    "USE",
    "PROTO",
    "EXTERNPROTO",
    "IS",
    "TRUE",
    "FALSE",
    "NULL",
    "ROUTE",
    "TO",
    "IMPORTABLE",
];

pub(super) const DECLARATION_KEYWORDS: &[&str] = &[
    "field",
    "vrmlField",
    "hiddenField",
    "deprecatedField",
    "unconnectedField",
    "exposedField",
    "eventIn",
    "eventOut",
];

/// Whether `text` may name a node, field or DEF: no forbidden character, no leading digit.
pub(super) fn is_identifier(text: &str) -> bool {
    let Some(first) = text.bytes().next() else {
        return false;
    };
    !first.is_ascii_digit()
        && !matches!(first, b'+' | b'-')
        && text.bytes().all(|b| {
            b >= b' '
                && !matches!(
                    b,
                    b'"' | b'#' | b'\'' | b',' | b'.' | b'[' | b'\\' | b']' | b'{' | b'}'
                )
        })
        && !KEYWORDS.contains(&text)
}

pub(super) struct Parser<'s> {
    pub(super) src: &'s str,
    pub(super) lexer: Lexer<'s>,
    pub(super) current: Token,
    /// Span of the last token consumed: "expected X after this".
    pub(super) previous: Span,
    pub(super) diagnostics: Vec<Diagnostic>,
    pub(super) depth: usize,
    pub(super) max_depth: usize,
    /// Too-deep nesting is one cause: it is said once, where the limit was first crossed.
    pub(super) depth_reported: bool,
    /// Unclosed groups all end at the end of the file: that is said once.
    pub(super) eof_reported: bool,
    /// Offsets of the newlines, found at the first message that needs a line number.
    pub(super) newlines: Option<Vec<u32>>,
    /// `[` lists open around the current token.
    pub(super) open_lists: usize,
    /// Where a node that was never closed was noticed: the nodes around it end there quietly.
    pub(super) unclosed_at: Option<u32>,
}

impl<'s> Parser<'s> {
    /// What the parse leaves: the comments, and every diagnostic sorted by where it starts.
    pub(super) fn into_comments_and_diagnostics(mut self) -> (Vec<Span>, Vec<Diagnostic>) {
        let mut diagnostics = std::mem::take(&mut self.lexer.diagnostics);
        diagnostics.append(&mut self.diagnostics);
        diagnostics.sort_by_key(|d| d.span.start);
        (std::mem::take(&mut self.lexer.comments), diagnostics)
    }

    pub(super) fn bump(&mut self) -> Token {
        let token = self.current;
        if token.kind != TokenKind::Eof {
            self.previous = token.span;
        }
        self.current = self.lexer.next_token();
        token
    }

    /// The token after the current one, without consuming anything.
    pub(super) fn peek_second(&mut self) -> Token {
        let pos = self.lexer.pos();
        let errors = self.lexer.diagnostics.len();
        let token = self.lexer.next_token();
        self.lexer.set_pos(pos);
        self.lexer.diagnostics.truncate(errors);
        token
    }

    pub(super) fn text(&self, span: Span) -> &'s str {
        &self.src[span.range()]
    }

    pub(super) fn current_text(&self) -> &'s str {
        self.text(self.current.span)
    }

    pub(super) fn at_word(&self, word: &str) -> bool {
        self.current.kind == TokenKind::Word && self.current_text() == word
    }

    /// How the current token reads in a message: `'X'` or `end of file`.
    pub(super) fn found(&self) -> String {
        describe(self.current, self.src)
    }

    pub(super) fn error(&mut self, diagnostic: Diagnostic) {
        if self.current.kind == TokenKind::Eof {
            if self.eof_reported {
                return;
            }
            self.eof_reported = true;
        }
        if self.diagnostics.len() >= MAX_ERRORS {
            // Garbage gives an error every few bytes: past the cap, messages would only cost
            // time and memory. The last one says so.
            if self.diagnostics.len() == MAX_ERRORS {
                self.diagnostics.push(
                    Diagnostic::error(
                        diagnostic.span,
                        format!("too many syntax errors: only the first {MAX_ERRORS} are reported"),
                    )
                    .with_label("parsing went on without reporting past here")
                    .with_note("is this a world file?"),
                );
            }
            return;
        }
        self.diagnostics.push(diagnostic);
    }

    /// The line (from 0) of byte `offset`, from line starts found once.
    pub(super) fn line_of(&mut self, offset: u32) -> usize {
        let newlines = self.newlines.get_or_insert_with(|| {
            self.src
                .bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i as u32)
                .collect()
        });
        newlines.partition_point(|&n| n < offset)
    }

    /// "Expected X, found Y": the caret on the previous token when Y is on a later line, so
    /// that the message lands on the line with the mistake; otherwise on Y.
    pub(super) fn expected(&mut self, what: &str) {
        let message = format!("Expected {what}, found {}.", self.found());
        let found_line = self.line_of(self.current.span.start);
        let previous_line = self.line_of(self.previous.start);
        let diagnostic = if found_line > previous_line && self.previous.end > 0 {
            Diagnostic::error(self.previous, message)
                .with_label(format!("expected {what} after this"))
                .with_secondary(self.current.span, format!("found {}", self.found()))
        } else {
            Diagnostic::error(self.current.span, message).with_label(format!("expected {what}"))
        };
        self.error(diagnostic);
    }

    pub(super) fn ident(&mut self) -> Ident {
        let token = self.bump();
        Ident {
            span: token.span,
            text: self.text(token.span).to_owned(),
        }
    }

    /// Consumes an identifier, or reports `what` expected and returns `None` without consuming.
    pub(super) fn expect_ident(&mut self, what: &str) -> Option<Ident> {
        if self.current.kind == TokenKind::Word && is_identifier(self.current_text()) {
            Some(self.ident())
        } else {
            self.expected(what);
            None
        }
    }
}

pub(super) fn empty_ident(at: Span) -> Ident {
    Ident {
        span: Span::new(at.end as usize, at.end as usize),
        text: String::new(),
    }
}

fn describe(token: Token, src: &str) -> String {
    if token.kind == TokenKind::Eof {
        return "end of file".to_owned();
    }
    let text = &src[token.span.range()];
    let mut shown: String = text.chars().take(40).collect();
    if shown.len() < text.len() {
        shown.push('…');
    }
    format!("'{shown}'")
}
