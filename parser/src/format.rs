//! The canonical form of a world file (`regatta fmt`) and a plain-text dump of the tree.
//!
//! Canonical form: two-space indentation, one field per line, commas dropped, numbers and
//! strings exactly as written, line breaks inside number lists kept where the source had them,
//! at most one blank line where the source had one or more, and every comment kept on its own
//! line or at the end of the line it ended. Formatting its own output changes nothing.

use std::fmt::Write;

use crate::syntax::*;

/// Formats a parsed file. `source` must be the text `file` was parsed from.
pub fn format(file: &SourceFile, source: &str) -> String {
    let mut printer = Printer {
        src: source,
        out: String::with_capacity(source.len() + source.len() / 8),
        indent: 0,
        comments: &file.comments,
        next_comment: 0,
        last_source_end: 0,
    };
    if let Some(header) = &file.header {
        printer.out.push_str(&source[header.span.range()]);
        printer.out.push('\n');
        printer.last_source_end = header.span.end as usize;
    }
    for item in &file.items {
        printer.statement_start(item_span(item));
        printer.item(item);
    }
    printer.flush_comments_before(source.len() + 1);
    if !printer.out.ends_with('\n') {
        printer.out.push('\n');
    }
    printer.out
}

fn item_span(item: &Item) -> Span {
    match item {
        Item::Node(node) => node.span,
        Item::Proto(proto) => proto.span,
        Item::ExternProto(extern_proto) => extern_proto.span,
        Item::Route(route) => route.span,
        Item::Template(template) => template.span,
    }
}

fn body_item_span(item: &BodyItem) -> Span {
    match item {
        BodyItem::Field(field) => field.span,
        BodyItem::Proto(proto) => proto.span,
        BodyItem::Route(route) => route.span,
        BodyItem::Declaration(declaration) => declaration.span,
        BodyItem::Template(template) => template.span,
    }
}

struct Printer<'a> {
    src: &'a str,
    out: String,
    indent: usize,
    comments: &'a [Span],
    next_comment: usize,
    /// End of the last source element printed, to tell trailing comments from leading ones.
    last_source_end: usize,
}

impl Printer<'_> {
    fn newline(&mut self) {
        while self.out.ends_with(' ') {
            self.out.pop();
        }
        self.out.push('\n');
    }

    fn at_line_start(&self) -> bool {
        self.out.is_empty() || self.out.ends_with('\n')
    }

    fn pad(&mut self) {
        if self.at_line_start() {
            for _ in 0..self.indent {
                self.out.push_str("  ");
            }
        }
    }

    /// Prints the comments that stand before source offset `before`.
    fn flush_comments_before(&mut self, before: usize) {
        while let Some(&comment) = self.comments.get(self.next_comment) {
            if comment.start as usize >= before {
                break;
            }
            let gap =
                &self.src[self.last_source_end.min(comment.start as usize)..comment.start as usize];
            let trailing = !gap.contains(['\n', '\r']) && !self.at_line_start();
            if trailing {
                self.out.push(' ');
            } else {
                if !self.at_line_start() {
                    self.newline();
                }
                if has_blank_line(gap) && !self.out.is_empty() && !self.out.ends_with("\n\n") {
                    self.out.push('\n');
                }
                self.pad();
            }
            self.out.push_str(self.src[comment.range()].trim_end());
            self.newline();
            self.last_source_end = comment.end as usize;
            self.next_comment += 1;
        }
    }

    /// Starts a statement (item, field, declaration) on its own line, keeping one blank line
    /// where the source had any.
    fn statement_start(&mut self, span: Span) {
        self.flush_comments_before(span.start as usize);
        if !self.at_line_start() {
            self.newline();
        }
        let gap = &self.src[self.last_source_end.min(span.start as usize)..span.start as usize];
        if has_blank_line(gap)
            && !self.out.is_empty()
            && !self.out.ends_with("\n\n")
            && !self.out.ends_with("{\n")
            && !self.out.ends_with("[\n")
        {
            self.out.push('\n');
        }
    }

    /// Prints source text `span` as a token, after the comments before it.
    fn token(&mut self, span: Span) {
        self.flush_comments_before(span.start as usize);
        self.space_if_needed();
        self.out.push_str(&self.src[span.range()]);
        self.last_source_end = span.end as usize;
    }

    /// Prints fixed text as a token at source offset `at`.
    fn word(&mut self, text: &str, at: usize) {
        self.flush_comments_before(at);
        self.space_if_needed();
        self.out.push_str(text);
        self.last_source_end = self.last_source_end.max(at);
    }

    fn space_if_needed(&mut self) {
        if self.at_line_start() {
            self.pad();
        } else if !self.out.ends_with(' ') {
            self.out.push(' ');
        }
    }

    fn ident(&mut self, ident: &Ident) {
        if !ident.text.is_empty() {
            self.token(ident.span);
        }
    }

    fn item(&mut self, item: &Item) {
        match item {
            Item::Node(node) => self.node(node),
            Item::Proto(proto) => self.proto(proto),
            Item::ExternProto(extern_proto) => self.extern_proto(extern_proto),
            Item::Route(route) => self.route(route),
            Item::Template(template) => self.token(template.span),
        }
    }

    fn node(&mut self, node: &Node) {
        if let Some(def) = &node.def {
            self.word("DEF", node.span.start as usize);
            self.ident(def);
        }
        match &node.kind {
            NodeKind::Use(name) => {
                self.word("USE", node.span.start as usize);
                self.ident(name);
            }
            NodeKind::Instance { type_name, body } => {
                self.ident(type_name);
                let Some(body) = body else {
                    return;
                };
                self.word("{", body.span.start as usize);
                self.indent += 1;
                for item in &body.items {
                    self.statement_start(body_item_span(item));
                    self.body_item(item);
                }
                let close = (body.span.end as usize).saturating_sub(1);
                self.flush_comments_before(close);
                self.indent -= 1;
                if !self.at_line_start() {
                    self.newline();
                }
                self.word("}", close);
                self.last_source_end = body.span.end as usize;
            }
        }
    }

    fn body_item(&mut self, item: &BodyItem) {
        match item {
            BodyItem::Field(field) => {
                if field.hidden {
                    self.word("hidden", field.span.start as usize);
                }
                self.ident(&field.name);
                self.field_value(&field.value);
            }
            BodyItem::Proto(proto) => self.proto(proto),
            BodyItem::Route(route) => self.route(route),
            BodyItem::Declaration(declaration) => self.declaration(declaration),
            BodyItem::Template(template) => self.token(template.span),
        }
    }

    fn field_value(&mut self, value: &FieldValue) {
        match value {
            FieldValue::Value(value) => self.value(value),
            FieldValue::Is(target) => {
                self.word("IS", target.span.start as usize);
                self.ident(target);
            }
            FieldValue::Missing { .. } => {}
        }
    }

    fn value(&mut self, value: &Value) {
        let open = value.span.start as usize;
        if value.bracketed {
            self.word("[", open);
        }
        let close = (value.span.end as usize).saturating_sub(1);
        // A flat list keeps a line break after `[` and before `]` where the source had one,
        // like the breaks between its items: a table stays a table.
        let flat_items: Option<(usize, usize)> = match &value.items {
            Items::Numbers(list) if !list.values.is_empty() => Some((
                list.span_of(0, self.src).start as usize,
                list.span_of(list.values.len() - 1, self.src).end as usize,
            )),
            Items::Atoms(atoms) if !atoms.is_empty() => Some((
                atoms[0].span().start as usize,
                atoms[atoms.len() - 1].span().end as usize,
            )),
            _ => None,
        };
        let multiline = matches!(&value.items, Items::Atoms(atoms) if value.bracketed
        && atoms.iter().any(|atom| {
            matches!(atom, Atom::Node(_) | Atom::String(_) | Atom::Template(_))
        }));
        if let (true, false, Some((first, _))) = (value.bracketed, multiline, flat_items) {
            self.break_if_source_did(Some(open + 1), first);
        }
        match &value.items {
            Items::Numbers(list) => self.numbers(list),
            Items::Atoms(atoms) => {
                if multiline {
                    self.indent += 1;
                    for atom in atoms {
                        self.statement_start(atom.span());
                        self.atom(atom);
                    }
                    self.flush_comments_before(close);
                    self.indent -= 1;
                    self.newline();
                } else {
                    let mut previous_end = None;
                    for atom in atoms {
                        self.break_if_source_did(previous_end, atom.span().start as usize);
                        self.atom(atom);
                        previous_end = Some(atom.span().end as usize);
                    }
                }
            }
        }
        if value.bracketed {
            if let (false, Some((_, last))) = (multiline, flat_items) {
                // Bytes, not text: an unclosed list may end inside a character.
                let between = self.src.as_bytes().get(last.min(close)..close);
                if between.is_some_and(|gap| gap.contains(&b'\n')) {
                    self.flush_comments_before(close);
                    if !self.at_line_start() {
                        self.newline();
                    }
                }
            }
            self.word("]", close);
            self.last_source_end = value.span.end as usize;
        }
    }

    /// Inside number lists, keeps the source's line breaks (canonical, and stable).
    fn break_if_source_did(&mut self, previous_end: Option<usize>, start: usize) {
        if let Some(end) = previous_end {
            if self.src[end.min(start)..start].contains('\n') {
                self.flush_comments_before(start);
                if !self.at_line_start() {
                    self.newline();
                }
                self.indent += 1;
                self.pad();
                self.indent -= 1;
            }
        }
    }

    fn numbers(&mut self, list: &NumberList) {
        let mut previous_end: Option<usize> = None;
        let indent_extra = 1;
        for index in 0..list.values.len() {
            let span = list.span_of(index, self.src);
            let start = span.start as usize;
            if let Some(end) = previous_end {
                if self.src[end..start].contains('\n') {
                    self.flush_comments_before(start);
                    if !self.at_line_start() {
                        self.newline();
                    }
                    self.indent += indent_extra;
                    self.pad();
                    self.indent -= indent_extra;
                }
            }
            self.token(span);
            previous_end = Some(span.end as usize);
        }
    }

    fn atom(&mut self, atom: &Atom) {
        match atom {
            Atom::Node(node) => self.node(node),
            other => self.token(other.span()),
        }
    }

    fn proto(&mut self, proto: &Proto) {
        self.word("PROTO", proto.span.start as usize);
        self.ident(&proto.name);
        self.word("[", proto.name.span.end as usize);
        self.indent += 1;
        for declaration in &proto.interface {
            self.statement_start(declaration.span);
            self.declaration(declaration);
        }
        let body_start = proto.body.first().map_or(proto.span.end as usize, |item| {
            item_span(item).start as usize
        });
        self.flush_comments_before(self.interface_end(proto, body_start));
        self.indent -= 1;
        if !self.at_line_start() {
            self.newline();
        }
        self.word("]", proto.name.span.end as usize);
        self.newline();
        self.word("{", proto.name.span.end as usize);
        self.indent += 1;
        for item in &proto.body {
            self.statement_start(item_span(item));
            self.item(item);
        }
        let close = (proto.span.end as usize).saturating_sub(1);
        self.flush_comments_before(close);
        self.indent -= 1;
        if !self.at_line_start() {
            self.newline();
        }
        self.word("}", close);
        self.last_source_end = proto.span.end as usize;
    }

    /// Where a PROTO's interface ends in the source: its `]`, found by scanning back from the
    /// body's first statement past the `{`.
    fn interface_end(&self, proto: &Proto, body_start: usize) -> usize {
        let region = &self.src[proto.name.span.end as usize..body_start];
        let mut end = region.len();
        // Skip back over the `{` and whitespace to the `]`; comments inside the interface stay
        // inside it, comments between `]` and `{` follow it.
        if let Some(brace) = region.rfind('{') {
            end = brace;
        }
        match region[..end].rfind(']') {
            Some(bracket) => proto.name.span.end as usize + bracket,
            None => proto.name.span.end as usize + end,
        }
    }

    fn declaration(&mut self, declaration: &Declaration) {
        self.ident(&declaration.keyword);
        self.ident(&declaration.field_type);
        if let Some(restriction) = &declaration.restriction {
            // Glued to the type, as Webots writes it: `SFRotation{0 1 0 0, 0 0 1 0}`.
            self.flush_comments_before(restriction.span.start as usize);
            self.out.push('{');
            let mut first = true;
            if let Items::Atoms(atoms) = &restriction.items {
                for atom in atoms {
                    if !first && !self.out.ends_with('{') {
                        self.out.push(' ');
                    }
                    first = false;
                    match atom {
                        Atom::Node(node) => {
                            let text = self.src[node.span.range()]
                                .split_whitespace()
                                .collect::<Vec<_>>()
                                .join(" ");
                            self.out.push_str(&text);
                        }
                        other => self.out.push_str(&self.src[other.span().range()]),
                    }
                }
            }
            self.out.push('}');
            self.last_source_end = restriction.span.end as usize;
        }
        self.ident(&declaration.name);
        if let Some(default) = &declaration.default {
            self.field_value(default);
        }
    }

    fn extern_proto(&mut self, extern_proto: &ExternProto) {
        if extern_proto.importable {
            self.word("IMPORTABLE", extern_proto.span.start as usize);
        }
        self.word("EXTERNPROTO", extern_proto.span.start as usize);
        if let Some(name) = &extern_proto.name {
            self.ident(name);
            self.word("[", name.span.end as usize);
            self.indent += 1;
            for declaration in &extern_proto.interface {
                self.statement_start(declaration.span);
                self.declaration(declaration);
            }
            self.indent -= 1;
            if !self.at_line_start() {
                self.newline();
            }
            self.word("]", self.last_source_end);
        }
        let bracketed = extern_proto.urls.len() != 1;
        if bracketed {
            self.word("[", self.last_source_end);
        }
        for url in &extern_proto.urls {
            self.token(url.span);
        }
        if bracketed {
            self.word("]", self.last_source_end);
        }
    }

    fn route(&mut self, route: &Route) {
        self.word("ROUTE", route.span.start as usize);
        let from = format!("{}.{}", route.from_node.text, route.from_field.text);
        self.word(&from, route.from_node.span.start as usize);
        self.word("TO", route.from_field.span.end as usize);
        let to = format!("{}.{}", route.to_node.text, route.to_field.text);
        self.word(&to, route.to_node.span.start as usize);
        self.last_source_end = route.span.end as usize;
    }
}

fn has_blank_line(gap: &str) -> bool {
    let mut newlines = 0;
    for byte in gap.bytes() {
        match byte {
            b'\n' => newlines += 1,
            b' ' | b'\t' | b'\r' | b',' => {}
            _ => newlines = 0,
        }
        if newlines >= 2 {
            return true;
        }
    }
    false
}

/// An indented outline of the tree, for tests and `--dump`. With `spans`, every element shows
/// its byte range; without, two files that differ only in layout dump the same.
pub fn dump(file: &SourceFile, source: &str, spans: bool) -> String {
    let mut out = String::new();
    let mut d = Dumper {
        out: &mut out,
        src: source,
        spans,
        depth: 0,
    };
    if let Some(header) = &file.header {
        d.line(
            &format!(
                "Header {:?} {} {:?}",
                header.dialect, header.version, header.rest
            ),
            header.span,
        );
    }
    for item in &file.items {
        d.item(item);
    }
    if spans {
        for comment in &file.comments {
            d.line("Comment", *comment);
        }
    }
    out
}

struct Dumper<'a> {
    out: &'a mut String,
    src: &'a str,
    spans: bool,
    depth: usize,
}

impl Dumper<'_> {
    fn line(&mut self, text: &str, span: Span) {
        for _ in 0..self.depth {
            self.out.push_str("  ");
        }
        self.out.push_str(text);
        if self.spans {
            let _ = write!(self.out, " @{span:?}");
        }
        self.out.push('\n');
    }

    fn nested(&mut self, f: impl FnOnce(&mut Self)) {
        self.depth += 1;
        f(self);
        self.depth -= 1;
    }

    fn item(&mut self, item: &Item) {
        match item {
            Item::Node(node) => self.node(node),
            Item::Proto(proto) => self.proto(proto),
            Item::ExternProto(e) => {
                let name = e.name.as_ref().map_or("", |n| n.text.as_str());
                let urls: Vec<&str> = e.urls.iter().map(|u| u.value.as_str()).collect();
                self.line(
                    &format!("ExternProto {name} {urls:?} importable={}", e.importable),
                    e.span,
                );
                self.nested(|d| e.interface.iter().for_each(|decl| d.declaration(decl)));
            }
            Item::Route(r) => self.line(
                &format!(
                    "Route {}.{} TO {}.{}",
                    r.from_node.text, r.from_field.text, r.to_node.text, r.to_field.text
                ),
                r.span,
            ),
            Item::Template(t) => {
                self.line(&format!("Template {:?}", &self.src[t.span.range()]), t.span)
            }
        }
    }

    fn node(&mut self, node: &Node) {
        let def = node
            .def
            .as_ref()
            .map_or(String::new(), |d| format!("DEF {} ", d.text));
        match &node.kind {
            NodeKind::Use(name) => self.line(&format!("{def}USE {}", name.text), node.span),
            NodeKind::Instance { type_name, body } => {
                let braces = if body.is_some() { "" } else { " (no body)" };
                self.line(&format!("{def}Node {}{braces}", type_name.text), node.span);
                if let Some(body) = body {
                    self.nested(|d| {
                        for item in &body.items {
                            match item {
                                BodyItem::Field(f) => {
                                    let hidden = if f.hidden { "hidden " } else { "" };
                                    d.line(&format!("{hidden}Field {}", f.name.text), f.span);
                                    d.nested(|d| d.field_value(&f.value));
                                }
                                BodyItem::Proto(p) => d.proto(p),
                                BodyItem::Route(r) => d.item(&Item::Route((**r).clone())),
                                BodyItem::Declaration(decl) => d.declaration(decl),
                                BodyItem::Template(t) => d.item(&Item::Template(t.clone())),
                            }
                        }
                    });
                }
            }
        }
    }

    fn field_value(&mut self, value: &FieldValue) {
        match value {
            FieldValue::Value(v) => self.value(v),
            FieldValue::Is(target) => self.line(&format!("IS {}", target.text), target.span),
            FieldValue::Missing { .. } => self.line("Missing", Span::default()),
        }
    }

    fn value(&mut self, value: &Value) {
        let kind = if value.bracketed { "List" } else { "Value" };
        match &value.items {
            Items::Numbers(list) => {
                let shown: Vec<String> = list.values.iter().map(|v| format!("{v}")).collect();
                self.line(&format!("{kind} Numbers [{}]", shown.join(" ")), value.span);
            }
            Items::Atoms(atoms) => {
                self.line(kind, value.span);
                self.nested(|d| {
                    for atom in atoms {
                        match atom {
                            Atom::Number(n) => {
                                let hex = if n.hex { " hex" } else { "" };
                                d.line(&format!("Number {}{hex}", n.value), n.span)
                            }
                            Atom::Bool(span, b) => d.line(&format!("Bool {b}"), *span),
                            Atom::String(s) => d.line(&format!("String {:?}", s.value), s.span),
                            Atom::Null(span) => d.line("NULL", *span),
                            Atom::Node(node) => d.node(node),
                            Atom::Template(t) => d.item(&Item::Template(t.clone())),
                        }
                    }
                });
            }
        }
    }

    fn proto(&mut self, proto: &Proto) {
        self.line(&format!("Proto {}", proto.name.text), proto.span);
        self.nested(|d| {
            for decl in &proto.interface {
                d.declaration(decl);
            }
            for item in &proto.body {
                d.item(item);
            }
        });
    }

    fn declaration(&mut self, decl: &Declaration) {
        self.line(
            &format!(
                "Declaration {} {} {}",
                decl.keyword.text, decl.field_type.text, decl.name.text
            ),
            decl.span,
        );
        self.nested(|d| {
            if let Some(restriction) = &decl.restriction {
                d.line("Restriction", restriction.span);
                d.nested(|d| d.value(restriction));
            }
            if let Some(default) = &decl.default {
                d.field_value(default);
            }
        });
    }
}
