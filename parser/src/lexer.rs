//! Tokens of the world language, produced on demand (no token vector, to keep memory low on
//! multi-megabyte meshes). Whitespace includes the comma; comments are recorded as trivia.

use crate::diagnostic::Diagnostic;
use crate::span::Span;
use crate::word::{is_space, word_len};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TokenKind {
    LBrace,
    RBrace,
    LBracket,
    RBracket,
    /// Identifiers, keywords and numbers: told apart by the parser.
    Word,
    String,
    Template,
    Eof,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Token {
    pub kind: TokenKind,
    pub span: Span,
}

/// Reads a word as a number: a double (`1e-3`, `-.5`, `5.`, `+2`) or a VRML97 hex integer
/// (`0xFF00FF`). Returns the value and whether it was hex.
pub(crate) fn parse_number(word: &str) -> Option<(f64, bool)> {
    let bytes = word.as_bytes();
    let first = *bytes.first()?;
    if !(first.is_ascii_digit() || matches!(first, b'+' | b'-' | b'.')) {
        return None;
    }
    let (negative, unsigned) = match first {
        b'-' => (true, &word[1..]),
        b'+' => (false, &word[1..]),
        _ => (false, word),
    };
    let unsigned_bytes = unsigned.as_bytes();
    if unsigned_bytes.len() > 2 && unsigned_bytes[0] == b'0' && (unsigned_bytes[1] | 0x20) == b'x' {
        let magnitude = u64::from_str_radix(&unsigned[2..], 16).ok()? as f64;
        return Some((if negative { -magnitude } else { magnitude }, true));
    }
    // The character set keeps `inf` and `nan` words, not numbers; std then checks the shape
    // (`1.2.3`, `1e` fail) and converts exactly.
    if !bytes
        .iter()
        .all(|&b| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-'))
    {
        return None;
    }
    word.parse::<f64>().ok().map(|value| (value, false))
}

/// Resolves the escapes of a string token's inner text (`\"` and `\\`; any other escaped
/// character stands for itself, and Webots' `\n` stays two characters).
pub(crate) fn unescape(inner: &str) -> String {
    if !inner.contains('\\') {
        return inner.to_owned();
    }
    let mut out = String::with_capacity(inner.len());
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some(escaped @ ('"' | '\\')) => out.push(escaped),
                Some(other) => {
                    out.push('\\');
                    out.push(other);
                }
                None => out.push('\\'),
            }
        } else {
            out.push(c);
        }
    }
    out
}

pub(crate) struct Lexer<'s> {
    src: &'s [u8],
    pos: usize,
    /// Whether a raw newline ends a string (Webots) or belongs to it (VRML97).
    pub multiline_strings: bool,
    pub comments: Vec<Span>,
    pub diagnostics: Vec<Diagnostic>,
}

impl<'s> Lexer<'s> {
    pub fn new(src: &'s str, start: usize) -> Lexer<'s> {
        Lexer {
            src: src.as_bytes(),
            pos: start,
            multiline_strings: true,
            comments: Vec::new(),
            diagnostics: Vec::new(),
        }
    }

    pub fn pos(&self) -> usize {
        self.pos
    }

    pub fn set_pos(&mut self, pos: usize) {
        self.pos = pos;
    }

    /// Skips whitespace and comments, recording each comment once (peeking may pass twice).
    #[inline]
    fn skip_trivia(&mut self) {
        let src = self.src;
        loop {
            while self.pos < src.len() && is_space(src[self.pos]) {
                self.pos += 1;
            }
            if self.pos < src.len() && src[self.pos] == b'#' {
                let start = self.pos;
                while self.pos < src.len() && src[self.pos] != b'\n' && src[self.pos] != b'\r' {
                    self.pos += 1;
                }
                if self
                    .comments
                    .last()
                    .is_none_or(|last| (last.start as usize) < start)
                {
                    self.comments.push(Span::new(start, self.pos));
                }
            } else {
                return;
            }
        }
    }

    pub fn next_token(&mut self) -> Token {
        self.skip_trivia();
        let src = self.src;
        let start = self.pos;
        let Some(&byte) = src.get(start) else {
            return Token {
                kind: TokenKind::Eof,
                span: Span::new(start, start),
            };
        };
        let kind = match byte {
            b'{' => {
                self.pos += 1;
                TokenKind::LBrace
            }
            b'}' => {
                self.pos += 1;
                TokenKind::RBrace
            }
            b'[' => {
                self.pos += 1;
                TokenKind::LBracket
            }
            b']' => {
                self.pos += 1;
                TokenKind::RBracket
            }
            b'"' => {
                self.string(start);
                TokenKind::String
            }
            b'%' if matches!(src.get(start + 1), Some(b'<' | b'{')) => {
                self.template(start);
                TokenKind::Template
            }
            _ => {
                self.pos += word_len(&src[start..]);
                TokenKind::Word
            }
        };
        Token {
            kind,
            span: Span::new(start, self.pos),
        }
    }

    fn string(&mut self, start: usize) {
        let src = self.src;
        let mut i = start + 1;
        while i < src.len() {
            match src[i] {
                b'\\' => i += 2,
                b'"' => {
                    self.pos = i + 1;
                    return;
                }
                b'\n' | b'\r' if !self.multiline_strings => {
                    self.pos = i;
                    self.diagnostics.push(
                        Diagnostic::error(
                            Span::new(start, i),
                            "unterminated string: a Webots string ends on its line",
                        )
                        .with_note("write a line break inside a string as \\n"),
                    );
                    return;
                }
                _ => i += 1,
            }
        }
        self.pos = src.len();
        self.diagnostics.push(Diagnostic::error(
            Span::new(start, src.len()),
            "unterminated string: no closing '\"' before the end of the file",
        ));
    }

    fn template(&mut self, start: usize) {
        let src = self.src;
        let close = if src[start + 1] == b'<' { b'>' } else { b'}' };
        let mut i = start + 2;
        while i + 1 < src.len() {
            if src[i] == close && src[i + 1] == b'%' {
                self.pos = i + 2;
                return;
            }
            i += 1;
        }
        self.pos = src.len();
        self.diagnostics.push(Diagnostic::error(
            Span::new(start, src.len()),
            format!(
                "unterminated template block: no closing '{}%' before the end of the file",
                close as char
            ),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_take_every_vrml_shape() {
        for (text, value) in [
            ("1e-3", 1e-3),
            ("-.5", -0.5),
            ("5.", 5.0),
            ("+2", 2.0),
            ("1E5", 1e5),
            (".7", 0.7),
            ("0xFF", 255.0),
            ("-0x10", -16.0),
        ] {
            assert_eq!(parse_number(text).map(|n| n.0), Some(value), "{text}");
        }
        for text in ["inf", "nan", "-", ".", "1.2.3", "e5", "0x", "1e"] {
            assert_eq!(parse_number(text), None, "{text}");
        }
    }

    #[test]
    fn escapes_resolve_quotes_and_backslashes_only() {
        assert_eq!(unescape(r#"a\"b\\c\nd"#), "a\"b\\c\\nd");
    }
}
