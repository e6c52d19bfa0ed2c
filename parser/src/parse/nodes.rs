//! Statements and nodes: the top-level items, `DEF`/`USE`, node bodies and their fields (with
//! the unquoted-string rule for a word alone where a value goes).

use crate::diagnostic::Diagnostic;
use crate::lexer::TokenKind;
use crate::syntax::*;

use super::cursor::{empty_ident, is_identifier, Parser, DECLARATION_KEYWORDS};

impl Parser<'_> {
    /// Top-level statements until the end of the file.
    pub(super) fn items_until_eof(&mut self) -> Vec<Item> {
        let mut items = Vec::new();
        let mut recovering = false;
        while self.current.kind != TokenKind::Eof {
            match self.item() {
                Some(item) => {
                    items.push(item);
                    recovering = false;
                }
                None => {
                    if !recovering {
                        self.expected("node or PROTO name");
                    }
                    recovering = true;
                    self.skip_token_or_group();
                }
            }
        }
        items
    }

    /// A statement that may stand at top level or in a PROTO body; `None` (nothing consumed)
    /// if the current token cannot start one.
    pub(super) fn item(&mut self) -> Option<Item> {
        match self.current.kind {
            TokenKind::Template => Some(Item::Template(self.template())),
            TokenKind::Word => match self.current_text() {
                "PROTO" => Some(Item::Proto(self.proto())),
                "EXTERNPROTO" | "IMPORTABLE" => Some(Item::ExternProto(self.extern_proto())),
                "ROUTE" => Some(Item::Route(self.route()?)),
                "DEF" | "USE" => self.node().map(Item::Node),
                text if is_identifier(text) => self.node().map(Item::Node),
                _ => None,
            },
            _ => None,
        }
    }

    pub(super) fn template(&mut self) -> Template {
        let span = self.bump().span;
        let text = self.text(span).as_bytes();
        Template {
            span,
            expression: text.get(2) == Some(&b'='),
        }
    }

    /// `DEF name Type { … }`, `Type { … }` or `USE name`. Returns `None` only when nothing
    /// node-like was there (after reporting, for a DEF or USE without its name).
    pub(super) fn node(&mut self) -> Option<Node> {
        let start = self.current.span;
        if self.at_word("USE") {
            self.bump();
            let name = self
                .expect_ident("DEF name after USE")
                .unwrap_or_else(|| empty_ident(self.previous));
            return Some(Node {
                span: start.to(name.span),
                def: None,
                kind: NodeKind::Use(name),
            });
        }
        let def = if self.at_word("DEF") {
            self.bump();
            Some(self.expect_ident("DEF name")?)
        } else {
            None
        };
        let type_name = self.expect_ident("node or PROTO name");
        if type_name.is_none() && def.is_none() {
            return None;
        }
        // After `DEF name` with no type, a following body is still read, so that one mistake
        // gives one message; the node keeps an empty type name.
        let type_name = type_name.unwrap_or_else(|| empty_ident(self.previous));
        let body = if self.current.kind == TokenKind::LBrace {
            Some(self.node_body(&type_name))
        } else {
            if !type_name.text.is_empty() {
                self.expected("'{'");
            }
            None
        };
        let end = body.as_ref().map_or(type_name.span, |b| b.span);
        Some(Node {
            span: start.to(end),
            def,
            kind: NodeKind::Instance { type_name, body },
        })
    }

    pub(super) fn node_body(&mut self, type_name: &Ident) -> NodeBody {
        let open = self.bump().span;
        if self.depth >= self.max_depth {
            self.too_deep(open, "nodes");
            self.skip_rest_of_group();
            return NodeBody {
                span: open.to(self.previous),
                items: Vec::new(),
            };
        }
        self.depth += 1;
        let mut items = Vec::new();
        let mut recovering = false;
        loop {
            match self.current.kind {
                TokenKind::RBrace => {
                    let close = self.bump().span;
                    self.depth -= 1;
                    // A world's tree lives while its scene is built (a crowd's thousands of
                    // node bodies): no spare room.
                    items.shrink_to_fit();
                    return NodeBody {
                        span: open.to(close),
                        items,
                    };
                }
                TokenKind::Eof => {
                    if !recovering {
                        let diagnostic = Diagnostic::error(
                            self.current.span,
                            format!("Expected field name or '}}', found {}.", self.found()),
                        )
                        .with_label("the file ends here")
                        .with_secondary(open, self.never_closed(type_name));
                        self.error(diagnostic);
                    }
                    self.depth -= 1;
                    return NodeBody {
                        span: open.to(self.previous),
                        items,
                    };
                }
                // A `]` cannot stand in a node: the list around this node ends here, so this
                // node (and any between it and that list) was never closed.
                TokenKind::RBracket if self.open_lists > 0 => {
                    self.unclosed(type_name, open);
                    self.depth -= 1;
                    return NodeBody {
                        span: open.to(self.previous),
                        items,
                    };
                }
                _ => {}
            }
            if self.at_node_start() {
                // A node where a field name goes: most likely the `}` of this one is missing.
                if self.unclosed_at == Some(self.current.span.start) {
                    // Already said by the node inside this one: the stray node is read and
                    // dropped, and this node goes on.
                    self.node();
                    continue;
                }
                self.unclosed(type_name, open);
                self.depth -= 1;
                return NodeBody {
                    span: open.to(self.previous),
                    items,
                };
            }
            match self.body_item() {
                Some(item) => {
                    items.push(item);
                    recovering = false;
                }
                None => {
                    if !recovering {
                        self.expected("field name or '}'");
                    }
                    recovering = true;
                    self.skip_token_or_group();
                }
            }
        }
    }

    /// Whether the current token starts a node: `DEF`, `USE`, or a name followed by `{`.
    pub(super) fn at_node_start(&mut self) -> bool {
        if self.current.kind != TokenKind::Word {
            return false;
        }
        match self.current_text() {
            "DEF" | "USE" => true,
            text if is_identifier(text) && !DECLARATION_KEYWORDS.contains(&text) => {
                self.peek_second().kind == TokenKind::LBrace
            }
            _ => false,
        }
    }

    pub(super) fn body_item(&mut self) -> Option<BodyItem> {
        match self.current.kind {
            TokenKind::Template => Some(BodyItem::Template(self.template())),
            TokenKind::Word => {
                let text = self.current_text();
                match text {
                    "PROTO" => Some(BodyItem::Proto(self.proto())),
                    "ROUTE" => self.route().map(|route| BodyItem::Route(Box::new(route))),
                    "hidden" => {
                        // `hidden` is a field name in its own right unless a name follows.
                        let next = self.peek_second();
                        if next.kind == TokenKind::Word && is_identifier(self.text(next.span)) {
                            let start = self.bump().span;
                            let mut field = self.field();
                            field.span = start.to(field.span);
                            field.hidden = true;
                            Some(BodyItem::Field(field))
                        } else {
                            Some(BodyItem::Field(self.field()))
                        }
                    }
                    _ if DECLARATION_KEYWORDS.contains(&text) => {
                        let next = self.peek_second();
                        if next.kind == TokenKind::Word
                            && self.text(next.span).starts_with(['S', 'M'])
                            && self.text(next.span)[1..].starts_with('F')
                        {
                            self.declaration(true)
                                .map(|d| BodyItem::Declaration(Box::new(d)))
                        } else {
                            Some(BodyItem::Field(self.field()))
                        }
                    }
                    _ if is_identifier(text) => Some(BodyItem::Field(self.field())),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// `name value` or `name IS name`; the current token is the name.
    pub(super) fn field(&mut self) -> Field {
        let name = self.ident();
        let value = self.field_value(&name);
        let end = match &value {
            FieldValue::Value(value) => value.span,
            FieldValue::Is(target) => target.span,
            FieldValue::Missing { .. } => name.span,
        };
        Field {
            span: name.span.to(end),
            hidden: false,
            name,
            value,
        }
    }

    pub(super) fn field_value(&mut self, name: &Ident) -> FieldValue {
        if self.at_word("IS") {
            self.bump();
            return match self.expect_ident("PROTO field name after IS") {
                Some(target) => FieldValue::Is(target),
                None => FieldValue::Missing {
                    found: self.current.span,
                },
            };
        }
        match self.value() {
            Some(value) => FieldValue::Value(value),
            None if self.at_unquoted_string() => {
                // `name khepera`: one word alone where a value goes is a string without its
                // quotes. It is taken, so that it is not read as the next field's name.
                let found = self.bump().span;
                let word = self.text(found);
                let diagnostic = Diagnostic::error(
                    found,
                    format!(
                        "Expected a value for '{}', found '{word}': strings are quoted.",
                        name.text
                    ),
                )
                .with_label("a word alone is not a value")
                .with_note(format!(
                    "if it is a string, write: {} \"{word}\"",
                    name.text
                ))
                .with_code("missing-value");
                self.error(diagnostic);
                FieldValue::Missing { found }
            }
            None => {
                let found = self.current.span;
                let message = format!(
                    "Expected a value for '{}', found {}.",
                    name.text,
                    self.found()
                );
                let diagnostic = if self.on_later_line(found) {
                    Diagnostic::error(name.span, message)
                        .with_label("this field has no value")
                        .with_secondary(found, "the next thing found")
                } else {
                    Diagnostic::error(found, message).with_label("expected a value here")
                };
                self.error(diagnostic.with_code("missing-value"));
                FieldValue::Missing { found }
            }
        }
    }
}
