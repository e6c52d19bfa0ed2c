//! PROTO and EXTERNPROTO statements with their interface declarations, and ROUTE statements.

use crate::diagnostic::Diagnostic;
use crate::lexer::{parse_number, TokenKind};
use crate::syntax::*;

use super::cursor::{is_identifier, Parser, DECLARATION_KEYWORDS};

impl Parser<'_> {
    /// `PROTO Name [ declarations ] { body }`.
    pub(super) fn proto(&mut self) -> Proto {
        let start = self.bump().span;
        let name = self.expect_ident("PROTO name").unwrap_or(Ident {
            span: self.previous,
            text: String::new(),
        });
        let interface = if self.current.kind == TokenKind::LBracket {
            self.bump();
            self.declarations()
        } else {
            self.expected("'[' to open the PROTO interface");
            Vec::new()
        };
        let mut body = Vec::new();
        if self.current.kind == TokenKind::LBrace {
            let open = self.bump().span;
            if self.depth >= self.max_depth {
                self.too_deep(open, "PROTOs");
                self.skip_rest_of_group();
            } else {
                self.depth += 1;
                let mut recovering = false;
                loop {
                    match self.current.kind {
                        TokenKind::RBrace => {
                            self.bump();
                            break;
                        }
                        TokenKind::Eof => {
                            let diagnostic = Diagnostic::error(
                                self.current.span,
                                format!("Expected node or '}}', found {}.", self.found()),
                            )
                            .with_label("the file ends here")
                            .with_secondary(open, "this PROTO body is never closed");
                            self.error(diagnostic);
                            break;
                        }
                        _ => {}
                    }
                    match self.item() {
                        Some(item) => {
                            body.push(item);
                            recovering = false;
                        }
                        None => {
                            if !recovering {
                                self.expected("node or '}'");
                            }
                            recovering = true;
                            self.skip_token_or_group();
                        }
                    }
                }
                self.depth -= 1;
            }
        } else {
            self.expected("'{' to open the PROTO body");
        }
        Proto {
            span: start.to(self.previous),
            name,
            interface,
            body,
        }
    }

    /// Declarations up to and including the closing `]`.
    pub(super) fn declarations(&mut self) -> Vec<Declaration> {
        let mut declarations = Vec::new();
        let mut recovering = false;
        loop {
            match self.current.kind {
                TokenKind::RBracket => {
                    self.bump();
                    return declarations;
                }
                TokenKind::Eof | TokenKind::LBrace | TokenKind::RBrace => {
                    if !recovering {
                        self.expected("field declaration or ']'");
                    }
                    return declarations;
                }
                _ => {}
            }
            if self.current.kind == TokenKind::Word
                && DECLARATION_KEYWORDS.contains(&self.current_text())
            {
                if let Some(declaration) = self.declaration(true) {
                    declarations.push(declaration);
                    recovering = false;
                    continue;
                }
            } else if !recovering {
                self.expected("'field', 'unconnectedField', 'vrmlField' or 'hiddenField' keywords");
            }
            recovering = true;
            self.skip_token_or_group();
        }
    }

    /// `kind TYPE [ {allowed} ] name [default]`; the current token is the kind.
    pub(super) fn declaration(&mut self, with_default: bool) -> Option<Declaration> {
        let keyword = self.ident();
        let field_type = match self.current.kind {
            TokenKind::Word if is_field_type(self.current_text()) => self.ident(),
            _ => {
                self.expected("field type name");
                return None;
            }
        };
        let restriction = if self.current.kind == TokenKind::LBrace {
            Some(self.restriction())
        } else {
            None
        };
        let name = self.expect_ident("field name")?;
        let events = matches!(keyword.text.as_str(), "eventIn" | "eventOut");
        let default = if with_default && !events {
            let value = if self.at_word("IS") {
                self.field_value(&name)
            } else {
                match self.value() {
                    Some(value) => FieldValue::Value(value),
                    None => {
                        self.expected(&format!("a default value for '{}'", name.text));
                        FieldValue::Missing {
                            found: self.current.span,
                        }
                    }
                }
            };
            Some(value)
        } else if self.at_word("IS") {
            Some(self.field_value(&name))
        } else {
            None
        };
        let end = match &default {
            Some(FieldValue::Value(value)) => value.span,
            Some(FieldValue::Is(target)) => target.span,
            _ => name.span,
        };
        Some(Declaration {
            span: keyword.span.to(end),
            keyword,
            field_type,
            restriction,
            name,
            default,
        })
    }

    /// Webots' allowed values: `{ item, item … }`, items being values separated by commas
    /// (commas are whitespace, so the items are kept as one flat run).
    pub(super) fn restriction(&mut self) -> Value {
        let open = self.bump().span;
        let mut atoms = Vec::new();
        loop {
            match self.current.kind {
                TokenKind::RBrace => {
                    let close = self.bump().span;
                    return Value {
                        span: open.to(close),
                        bracketed: true,
                        items: Items::Atoms(atoms),
                    };
                }
                TokenKind::Eof => {
                    self.expected("'}' to close the allowed values");
                    return Value {
                        span: open.to(self.previous),
                        bracketed: true,
                        items: Items::Atoms(atoms),
                    };
                }
                TokenKind::Word => {
                    if let Some((value, hex)) = parse_number(self.current_text()) {
                        let span = self.bump().span;
                        atoms.push(Atom::Number(Number { span, value, hex }));
                        continue;
                    }
                }
                _ => {}
            }
            match self.atom() {
                Some(atom) => atoms.push(atom),
                None => {
                    self.expected("an allowed value or '}'");
                    self.skip_token_or_group();
                }
            }
        }
    }

    /// `EXTERNPROTO "url"` (Webots, optionally IMPORTABLE) or
    /// `EXTERNPROTO Name [ interface ] "url" | [ "url" … ]` (VRML97).
    pub(super) fn extern_proto(&mut self) -> ExternProto {
        let start = self.current.span;
        let importable = self.at_word("IMPORTABLE");
        if importable {
            self.bump();
            if !self.at_word("EXTERNPROTO") {
                self.expected("EXTERNPROTO after IMPORTABLE");
                return ExternProto {
                    span: start,
                    importable,
                    name: None,
                    interface: Vec::new(),
                    urls: Vec::new(),
                };
            }
        }
        self.bump();
        let mut name = None;
        let mut interface = Vec::new();
        if self.current.kind == TokenKind::Word {
            name = self.expect_ident("PROTO name");
            if self.current.kind == TokenKind::LBracket {
                self.bump();
                let mut recovering = false;
                loop {
                    match self.current.kind {
                        TokenKind::RBracket => {
                            self.bump();
                            break;
                        }
                        TokenKind::Eof | TokenKind::LBrace | TokenKind::RBrace => {
                            self.expected("field declaration or ']'");
                            break;
                        }
                        _ => {}
                    }
                    if self.current.kind == TokenKind::Word
                        && DECLARATION_KEYWORDS.contains(&self.current_text())
                    {
                        if let Some(declaration) = self.declaration(false) {
                            interface.push(declaration);
                            recovering = false;
                            continue;
                        }
                    } else if !recovering {
                        self.expected("field declaration or ']'");
                    }
                    recovering = true;
                    self.skip_token_or_group();
                }
            } else {
                self.expected("'[' to open the EXTERNPROTO interface");
            }
        }
        let mut urls = Vec::new();
        match self.value() {
            Some(value) => {
                if let Items::Atoms(atoms) = value.items {
                    for atom in atoms {
                        match atom {
                            Atom::String(url) => urls.push(url),
                            other => self.error(
                                Diagnostic::error(other.span(), "Expected a URL string.")
                                    .with_label("EXTERNPROTO takes strings here"),
                            ),
                        }
                    }
                } else if !matches!(&value.items, Items::Numbers(numbers) if numbers.values.is_empty())
                {
                    // `[ ]` is an empty url list (an unavailable PROTO, said when typing).
                    self.error(Diagnostic::error(
                        value.span,
                        "Expected a URL string, found numbers.",
                    ));
                }
            }
            None => self.expected("the EXTERNPROTO's URL string"),
        }
        ExternProto {
            span: start.to(self.previous),
            importable,
            name,
            interface,
            urls,
        }
    }

    /// `ROUTE a.b TO c.d`.
    pub(super) fn route(&mut self) -> Option<Route> {
        let start = self.bump().span;
        let (from_node, from_field) = self.dotted()?;
        if !self.at_word("TO") {
            self.expected("TO");
            return None;
        }
        self.bump();
        let (to_node, to_field) = self.dotted()?;
        Some(Route {
            span: start.to(to_field.span),
            from_node,
            from_field,
            to_node,
            to_field,
        })
    }

    /// `node.field`, written as one word.
    pub(super) fn dotted(&mut self) -> Option<(Ident, Ident)> {
        let token = self.current;
        let text = self.current_text();
        let split = (token.kind == TokenKind::Word)
            .then(|| text.split_once('.'))
            .flatten();
        match split {
            Some((node, field)) if is_identifier(node) && is_identifier(field) => {
                self.bump();
                let dot = token.span.start as usize + node.len();
                Some((
                    Ident {
                        span: Span::new(token.span.start as usize, dot),
                        text: node.to_owned(),
                    },
                    Ident {
                        span: Span::new(dot + 1, token.span.end as usize),
                        text: field.to_owned(),
                    },
                ))
            }
            _ => {
                self.expected("node.field");
                None
            }
        }
    }
}

fn is_field_type(text: &str) -> bool {
    const BASES: &[&str] = &[
        "Bool", "Int32", "Float", "Vec2f", "Vec3f", "Color", "Rotation", "String", "Node", "Time",
        "Image", "Double", "Vec2d", "Vec3d",
    ];
    (text.starts_with("SF") || text.starts_with("MF")) && BASES.contains(&&text[2..])
}
