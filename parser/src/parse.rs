//! The recursive-descent parser: tokens to [`SourceFile`], with error recovery.
//!
//! Recovery rule: after an error inside a node body the parser skips one token (a whole
//! bracketed or braced group if the token opens one) and tries the next field; at top level it
//! does the same and tries the next node. Consecutive errors in the same body are reported
//! once, so that one mistake gives one message. Nesting deeper than [`MAX_DEPTH`] is reported
//! and skipped without recursion, so no input can overflow the stack.

use crate::diagnostic::Diagnostic;
use crate::lexer::{parse_number, unescape, Lexer, Token, TokenKind};
use crate::syntax::*;

/// Deepest nesting of nodes and PROTOs the parser follows by default. Real worlds stay under
/// 30; the bound keeps recursion far from the 2 MiB stack of a test thread, even in debug
/// builds. [`parse_with`] takes another bound (the command line's `--limit nesting=N`).
pub const MAX_DEPTH: usize = 64;

/// Syntax errors reported per file; past it, one message says so and parsing goes on quietly.
pub const MAX_ERRORS: usize = 200;

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
        return parser.finish(header, Vec::new());
    }
    parser.bump();
    let items = parser.items_until_eof();
    parser.finish(header, items)
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

const DECLARATION_KEYWORDS: &[&str] = &[
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
fn is_identifier(text: &str) -> bool {
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

struct Parser<'s> {
    src: &'s str,
    lexer: Lexer<'s>,
    current: Token,
    /// Span of the last token consumed: "expected X after this".
    previous: Span,
    diagnostics: Vec<Diagnostic>,
    depth: usize,
    max_depth: usize,
    /// Too-deep nesting is one cause: it is said once, where the limit was first crossed.
    depth_reported: bool,
    /// Unclosed groups all end at the end of the file: that is said once.
    eof_reported: bool,
    /// Offsets of the newlines, found at the first message that needs a line number.
    newlines: Option<Vec<u32>>,
    /// `[` lists open around the current token.
    open_lists: usize,
    /// Where a node that was never closed was noticed: the nodes around it end there quietly.
    unclosed_at: Option<u32>,
}

impl<'s> Parser<'s> {
    fn finish(mut self, header: Option<Header>, items: Vec<Item>) -> Parse {
        let mut diagnostics = std::mem::take(&mut self.lexer.diagnostics);
        diagnostics.append(&mut self.diagnostics);
        diagnostics.sort_by_key(|d| d.span.start);
        Parse {
            file: SourceFile {
                header,
                items,
                comments: std::mem::take(&mut self.lexer.comments),
            },
            diagnostics,
        }
    }

    fn bump(&mut self) -> Token {
        let token = self.current;
        if token.kind != TokenKind::Eof {
            self.previous = token.span;
        }
        self.current = self.lexer.next_token();
        token
    }

    /// The token after the current one, without consuming anything.
    fn peek_second(&mut self) -> Token {
        let pos = self.lexer.pos();
        let errors = self.lexer.diagnostics.len();
        let token = self.lexer.next_token();
        self.lexer.set_pos(pos);
        self.lexer.diagnostics.truncate(errors);
        token
    }

    fn text(&self, span: Span) -> &'s str {
        &self.src[span.range()]
    }

    fn current_text(&self) -> &'s str {
        self.text(self.current.span)
    }

    fn at_word(&self, word: &str) -> bool {
        self.current.kind == TokenKind::Word && self.current_text() == word
    }

    /// How the current token reads in a message: `'X'` or `end of file`.
    fn found(&self) -> String {
        describe(self.current, self.src)
    }

    fn error(&mut self, diagnostic: Diagnostic) {
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
    fn line_of(&mut self, offset: u32) -> usize {
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
    fn expected(&mut self, what: &str) {
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

    fn ident(&mut self) -> Ident {
        let token = self.bump();
        Ident {
            span: token.span,
            text: self.text(token.span).to_owned(),
        }
    }

    /// Consumes an identifier, or reports `what` expected and returns `None` without consuming.
    fn expect_ident(&mut self, what: &str) -> Option<Ident> {
        if self.current.kind == TokenKind::Word && is_identifier(self.current_text()) {
            Some(self.ident())
        } else {
            self.expected(what);
            None
        }
    }

    /// Skips the current token; a `{` or `[` takes its whole balanced group with it.
    fn skip_token_or_group(&mut self) {
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

    /// Top-level statements until the end of the file.
    fn items_until_eof(&mut self) -> Vec<Item> {
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
    fn item(&mut self) -> Option<Item> {
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

    fn template(&mut self) -> Template {
        let span = self.bump().span;
        let text = self.text(span).as_bytes();
        Template {
            span,
            expression: text.get(2) == Some(&b'='),
        }
    }

    /// `DEF name Type { … }`, `Type { … }` or `USE name`. Returns `None` only when nothing
    /// node-like was there (after reporting, for a DEF or USE without its name).
    fn node(&mut self) -> Option<Node> {
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

    fn node_body(&mut self, type_name: &Ident) -> NodeBody {
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
    fn at_node_start(&mut self) -> bool {
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

    /// What the secondary label of an unclosed node says.
    fn never_closed(&self, type_name: &Ident) -> String {
        if type_name.text.is_empty() {
            "this '{' is never closed".to_owned()
        } else {
            format!("this {} node is never closed", type_name.text)
        }
    }

    /// Reports a node whose `}` is missing, noticed at the current token (once per place).
    fn unclosed(&mut self, type_name: &Ident, open: Span) {
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
    fn too_deep(&mut self, open: Span, what: &str) {
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
    fn skip_rest_of_group(&mut self) {
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

    fn body_item(&mut self) -> Option<BodyItem> {
        match self.current.kind {
            TokenKind::Template => Some(BodyItem::Template(self.template())),
            TokenKind::Word => {
                let text = self.current_text();
                match text {
                    "PROTO" => Some(BodyItem::Proto(self.proto())),
                    "ROUTE" => self.route().map(BodyItem::Route),
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
                            self.declaration(true).map(BodyItem::Declaration)
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
    fn field(&mut self) -> Field {
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

    fn field_value(&mut self, name: &Ident) -> FieldValue {
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

    /// Whether the current token is a bare word on the field's line that ends a field: the
    /// next token closes the node or list, ends the file, or is on a later line.
    fn at_unquoted_string(&mut self) -> bool {
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

    fn on_later_line(&self, span: Span) -> bool {
        self.src[self.previous.end as usize..span.start as usize].contains('\n')
    }

    /// A value: a bracketed list, a run of numbers, or one other item. `None` (nothing
    /// consumed) if the current token cannot start a value.
    fn value(&mut self) -> Option<Value> {
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
    fn unbracketed_run(&mut self) -> Value {
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
    fn list(&mut self) -> Value {
        self.open_lists += 1;
        let value = self.list_inner();
        self.open_lists -= 1;
        value
    }

    fn list_inner(&mut self) -> Value {
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
                        self.diagnostics[last]
                            .secondary
                            .push(crate::diagnostic::Label {
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
    fn atom(&mut self) -> Option<Atom> {
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

    /// `PROTO Name [ declarations ] { body }`.
    fn proto(&mut self) -> Proto {
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
    fn declarations(&mut self) -> Vec<Declaration> {
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
    fn declaration(&mut self, with_default: bool) -> Option<Declaration> {
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
    fn restriction(&mut self) -> Value {
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
    fn extern_proto(&mut self) -> ExternProto {
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
                } else {
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
    fn route(&mut self) -> Option<Route> {
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
    fn dotted(&mut self) -> Option<(Ident, Ident)> {
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

fn empty_ident(at: Span) -> Ident {
    Ident {
        span: Span::new(at.end as usize, at.end as usize),
        text: String::new(),
    }
}

fn is_field_type(text: &str) -> bool {
    const BASES: &[&str] = &[
        "Bool", "Int32", "Float", "Vec2f", "Vec3f", "Color", "Rotation", "String", "Node", "Time",
        "Image", "Double", "Vec2d", "Vec3d",
    ];
    (text.starts_with("SF") || text.starts_with("MF")) && BASES.contains(&&text[2..])
}

/// How a token reads in a message.
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

/// Moves a pure-number prefix into `atoms` once the list turns out to be mixed.
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
