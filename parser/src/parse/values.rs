//! Values: bracketed lists, unbracketed runs of numbers and templates, and single atoms.
//! Pure number lists take a tight path with a capacity estimate, since they are most of a
//! mesh-heavy file.

use crate::diagnostic::Label;
use crate::lexer::{parse_number, unescape, TokenKind};
use crate::span::Span;
use crate::syntax::*;

use super::cursor::{is_identifier, Parser};

impl Parser<'_> {
    /// Whether the current token is a bare word on the field's line that ends a field: the
    /// next token closes the node or list, ends the file, or is on a later line.
    pub(super) fn at_unquoted_string(&mut self) -> bool {
        if self.current.kind != TokenKind::Word
            || !is_identifier(self.current_text())
            || self.on_later_line(self.current.span)
        {
            return false;
        }
        let next = self.peek_second();
        match next.kind {
            TokenKind::RBrace | TokenKind::RBracket | TokenKind::Eof => true,
            _ => self.src[self.current.span.end as usize..next.span.start as usize].contains('\n'),
        }
    }

    pub(super) fn on_later_line(&self, span: Span) -> bool {
        self.src[self.previous.end as usize..span.start as usize].contains('\n')
    }

    /// A value: a bracketed list, a run of numbers, or one other item. `None` (nothing
    /// consumed) if the current token cannot start a value.
    pub(super) fn value(&mut self) -> Option<Value> {
        if self.current.kind == TokenKind::LBracket {
            return Some(self.list());
        }
        if self.current.kind == TokenKind::Word && parse_number(self.current_text()).is_some()
            || self.current.kind == TokenKind::Template
        {
            return Some(self.unbracketed_run());
        }
        let atom = self.atom()?;
        Some(Value {
            span: atom.span(),
            bracketed: false,
            items: Items::Atoms(vec![atom]),
        })
    }

    /// Numbers and template blocks without brackets: "numbers until the next identifier".
    pub(super) fn unbracketed_run(&mut self) -> Value {
        let start = self.current.span;
        let mut numbers = NumberList::default();
        let mut atoms: Vec<Atom> = Vec::new();
        loop {
            match self.current.kind {
                TokenKind::Word => {
                    let Some((value, hex)) = parse_number(self.current_text()) else {
                        break;
                    };
                    let span = self.bump().span;
                    if atoms.is_empty() && !hex {
                        numbers.values.push(value);
                        numbers.starts.push(span.start);
                    } else {
                        move_numbers_to_atoms(&mut numbers, &mut atoms, self.src);
                        atoms.push(Atom::Number(Number { span, value, hex }));
                    }
                }
                TokenKind::Template => {
                    move_numbers_to_atoms(&mut numbers, &mut atoms, self.src);
                    let template = self.template();
                    atoms.push(Atom::Template(template));
                }
                _ => break,
            }
        }
        let span = start.to(self.previous);
        let items = if atoms.is_empty() {
            Items::Numbers(numbers)
        } else {
            Items::Atoms(atoms)
        };
        Value {
            span,
            bracketed: false,
            items,
        }
    }

    /// `[ items ]`. Pure number lists are read by a tight loop with a capacity estimate,
    /// since they are most of a mesh-heavy file.
    pub(super) fn list(&mut self) -> Value {
        self.open_lists += 1;
        let value = self.list_inner();
        self.open_lists -= 1;
        value
    }

    pub(super) fn list_inner(&mut self) -> Value {
        let open = self.bump().span;
        let mut numbers = NumberList::default();
        let mut atoms: Vec<Atom> = Vec::new();
        if self.current.kind == TokenKind::Word && parse_number(self.current_text()).is_some() {
            let capacity = estimate_numbers(&self.src.as_bytes()[open.start as usize..]);
            numbers.values.reserve_exact(capacity);
            numbers.starts.reserve_exact(capacity);
        }
        let mut recovering = false;
        loop {
            match self.current.kind {
                TokenKind::RBracket => {
                    let close = self.bump().span;
                    let items = if atoms.is_empty() {
                        Items::Numbers(numbers)
                    } else {
                        Items::Atoms(atoms)
                    };
                    return Value {
                        span: open.to(close),
                        bracketed: true,
                        items,
                    };
                }
                TokenKind::RBrace | TokenKind::Eof => {
                    let reported = self.diagnostics.len();
                    self.expected("a value or ']'");
                    if self.diagnostics.len() > reported {
                        let last = self.diagnostics.len() - 1;
                        self.diagnostics[last].secondary.push(Label {
                            span: open,
                            message: "this '[' is not closed".to_owned(),
                            file: None,
                        });
                    }
                    let items = if atoms.is_empty() {
                        Items::Numbers(numbers)
                    } else {
                        Items::Atoms(atoms)
                    };
                    return Value {
                        span: open.to(self.previous),
                        bracketed: true,
                        items,
                    };
                }
                TokenKind::Word => {
                    if let Some((value, hex)) = parse_number(self.current_text()) {
                        let span = self.bump().span;
                        if atoms.is_empty() && !hex {
                            numbers.values.push(value);
                            numbers.starts.push(span.start);
                        } else {
                            move_numbers_to_atoms(&mut numbers, &mut atoms, self.src);
                            atoms.push(Atom::Number(Number { span, value, hex }));
                        }
                        recovering = false;
                        continue;
                    }
                }
                _ => {}
            }
            match self.atom() {
                Some(atom) => {
                    move_numbers_to_atoms(&mut numbers, &mut atoms, self.src);
                    atoms.push(atom);
                    recovering = false;
                }
                None => {
                    if !recovering {
                        self.expected("a value or ']'");
                    }
                    recovering = true;
                    self.skip_token_or_group();
                }
            }
        }
    }

    /// One non-numeric item: TRUE, FALSE, NULL, a string, a node, a template block.
    pub(super) fn atom(&mut self) -> Option<Atom> {
        match self.current.kind {
            TokenKind::String => {
                let span = self.bump().span;
                let inner = &self.src
                    [span.start as usize + 1..(span.end as usize).max(span.start as usize + 1)];
                let inner = inner.strip_suffix('"').unwrap_or(inner);
                Some(Atom::String(StringLit {
                    span,
                    value: unescape(inner),
                }))
            }
            TokenKind::Template => Some(Atom::Template(self.template())),
            TokenKind::Word => match self.current_text() {
                "TRUE" => Some(Atom::Bool(self.bump().span, true)),
                "FALSE" => Some(Atom::Bool(self.bump().span, false)),
                "NULL" => Some(Atom::Null(self.bump().span)),
                "DEF" | "USE" => self.node().map(Atom::Node),
                text if is_identifier(text) => {
                    if self.peek_second().kind == TokenKind::LBrace {
                        self.node().map(Atom::Node)
                    } else {
                        None
                    }
                }
                _ => None,
            },
            _ => None,
        }
    }
}

fn move_numbers_to_atoms(numbers: &mut NumberList, atoms: &mut Vec<Atom>, src: &str) {
    if numbers.values.is_empty() {
        return;
    }
    let list = std::mem::take(numbers);
    atoms.reserve(list.values.len());
    for (index, &value) in list.values.iter().enumerate() {
        atoms.push(Atom::Number(Number {
            span: list.span_of(index, src),
            value,
            hex: false,
        }));
    }
}

/// Counts the words from `[` to the next `]`, so that a number list is allocated once.
/// A `]` inside a comment ends the count early; the vector then grows as usual.
fn estimate_numbers(from_open: &[u8]) -> usize {
    let end = from_open
        .iter()
        .position(|&b| b == b']')
        .unwrap_or(from_open.len());
    let mut count = 0;
    let mut in_word = false;
    for &byte in &from_open[1..end.max(1)] {
        let word = byte > b' ' && byte != b',';
        count += (word && !in_word) as usize;
        in_word = word;
    }
    count
}
