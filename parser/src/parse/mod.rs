//! The recursive-descent parser: tokens to [`SourceFile`], with error recovery.
//!
//! Recovery rule: after an error inside a node body the parser skips one token (a whole
//! bracketed or braced group if the token opens one) and tries the next field; at top level it
//! does the same and tries the next node. Consecutive errors in the same body are reported
//! once, so that one mistake gives one message. Nesting deeper than [`MAX_DEPTH`] is reported
//! and skipped without recursion, so no input can overflow the stack.
//!
//! This file owns the entry points and the header line. The parser's state and its token and
//! message helpers are in `cursor`; what it reads is in `nodes` (nodes, bodies, fields),
//! `protos` (PROTO, EXTERNPROTO and ROUTE statements, interface declarations) and `values`
//! (values, lists, atoms); `recovery` holds how it skips past mistakes.

mod cursor;
mod nodes;
mod protos;
mod recovery;
mod values;

use crate::diagnostic::Diagnostic;
use crate::lexer::{Lexer, Token, TokenKind};
use crate::span::Span;
use crate::syntax::{Dialect, Header, SourceFile};
use cursor::Parser;
pub use cursor::MAX_ERRORS;

/// Deepest nesting of nodes and PROTOs the parser follows by default. Real worlds stay under
/// 30; the bound keeps recursion far from the 2 MiB stack of a test thread, even in debug
/// builds. [`parse_with`] takes another bound (the command line's `--limit nesting=N`).
pub const MAX_DEPTH: usize = 64;

/// What [`parse`] returns: always a tree, and every problem found on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct Parse {
    pub file: SourceFile,
    pub diagnostics: Vec<Diagnostic>,
}

impl Parse {
    /// Whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Parses a whole world or PROTO file. Never fails, never panics.
pub fn parse(source: &str) -> Parse {
    parse_with(source, MAX_DEPTH)
}

/// [`parse`] with another bound on the nesting of nodes and PROTOs: deeper groups are
/// reported once (with the limit in the message) and skipped without recursion.
pub fn parse_with(source: &str, max_depth: usize) -> Parse {
    let (header, start) = read_header(source);
    let mut lexer = Lexer::new(source, start);
    lexer.multiline_strings = !matches!(
        header,
        Some(Header {
            dialect: Dialect::Webots,
            ..
        })
    );
    let mut parser = Parser {
        src: source,
        current: Token {
            kind: TokenKind::Eof,
            span: Span::default(),
        },
        previous: Span::new(start, start),
        lexer,
        diagnostics: Vec::new(),
        depth: 0,
        max_depth,
        depth_reported: false,
        eof_reported: false,
        newlines: None,
        open_lists: 0,
        unclosed_at: None,
    };
    if source.len() > u32::MAX as usize {
        parser.diagnostics.push(Diagnostic::error(
            Span::default(),
            "file too large: world files are limited to 4 GiB",
        ));
        return finish(parser, header, Vec::new());
    }
    parser.bump();
    let items = parser.items_until_eof();
    finish(parser, header, items)
}

/// Recognises `#VRML_SIM version rest` or `#VRML V2.0 rest` on the first non-blank line.
fn read_header(source: &str) -> (Option<Header>, usize) {
    let bom = if source.starts_with('\u{feff}') { 3 } else { 0 };
    let trimmed = source[bom..].trim_start_matches([' ', '\t', '\r', '\n']);
    let offset = source.len() - trimmed.len();
    let line_end = trimmed.find(['\n', '\r']).unwrap_or(trimmed.len());
    let line = &trimmed[..line_end];
    let (dialect, after) = if let Some(after) = line.strip_prefix("#VRML_SIM") {
        (Dialect::Webots, after)
    } else if let Some(after) = line.strip_prefix("#VRML") {
        (Dialect::Vrml97, after)
    } else {
        return (None, bom);
    };
    let mut words = after.split_whitespace();
    let version = words.next().unwrap_or("").to_owned();
    let rest = words.collect::<Vec<_>>().join(" ");
    let header = Header {
        span: Span::new(offset, offset + line_end),
        dialect,
        version,
        rest,
    };
    (Some(header), offset + line_end)
}

/// The tree and every diagnostic, the lexer's and the parser's, in source order.
fn finish(parser: Parser<'_>, header: Option<Header>, items: Vec<crate::syntax::Item>) -> Parse {
    let (comments, diagnostics) = parser.into_comments_and_diagnostics();
    Parse {
        file: SourceFile {
            header,
            items,
            comments,
        },
        diagnostics,
    }
}
