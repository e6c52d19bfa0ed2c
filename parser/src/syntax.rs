//! The syntax tree: a plain value type that mirrors the text of a world file.
//!
//! It knows nothing of node types or field types. Every node, field and value has a byte
//! [`Span`] into the source it was parsed from; comments are kept aside in
//! [`SourceFile::comments`] so that the tree plus the comments reproduce the file's content.

pub use crate::span::Span;

/// A name as written: a node type, a field, a DEF name or a PROTO name.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub span: Span,
    pub text: String,
}

/// The first line of a world file, when it is a recognised header.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub span: Span,
    pub dialect: Dialect,
    /// The version word: `R2023b`, `V6.0`, `V2.0`…
    pub version: String,
    /// What follows the version, usually `utf8`.
    pub rest: String,
}

/// Which family of files a header announces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialect {
    /// `#VRML_SIM …`: Webots worlds and PROTOs.
    Webots,
    /// `#VRML V2.0 …`: ISO/IEC 14772-1 VRML97.
    Vrml97,
}

/// A whole parsed file.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SourceFile {
    pub header: Option<Header>,
    pub items: Vec<Item>,
    /// Every comment, in source order, the header excluded.
    pub comments: Vec<Span>,
}

/// A top-level statement.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    Node(Node),
    Proto(Proto),
    ExternProto(ExternProto),
    Route(Route),
    Template(Template),
}

/// A node: `DEF name Type { … }` or `USE name`.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub span: Span,
    pub def: Option<Ident>,
    pub kind: NodeKind,
}

/// What follows an optional DEF.
#[derive(Clone, Debug, PartialEq)]
pub enum NodeKind {
    /// `USE name`.
    Use(Ident),
    /// `Type { … }`; `body` is `None` when the braces are missing (an error was reported).
    Instance {
        type_name: Ident,
        body: Option<NodeBody>,
    },
}

/// The braces of a node and what is between them.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeBody {
    pub span: Span,
    pub items: Vec<BodyItem>,
}

/// A statement inside a node's braces.
#[derive(Clone, Debug, PartialEq)]
pub enum BodyItem {
    Field(Field),
    Proto(Proto),
    /// Boxed, as the declaration below: both are rare and twice a field's size, and a swarm's
    /// file holds thousands of fields.
    Route(Box<Route>),
    /// A field declaration in a node body, as in Webots' header-less node models
    /// (`vrmlField SFFloat ambientIntensity 0`) and VRML97 Script nodes.
    Declaration(Box<Declaration>),
    Template(Template),
}

/// `name value`, `name IS name`, or Webots' `hidden name value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub span: Span,
    pub hidden: bool,
    pub name: Ident,
    pub value: FieldValue,
}

/// The right-hand side of a field.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValue {
    Value(Value),
    /// `IS interfaceName`, inside a PROTO body.
    Is(Ident),
    /// No value was written; `found` is what stood where the value should have been.
    Missing {
        found: Span,
    },
}

/// A field's value: one or more items, bracketed or not.
#[derive(Clone, Debug, PartialEq)]
pub struct Value {
    pub span: Span,
    /// Whether the items were written between `[` and `]`.
    pub bracketed: bool,
    pub items: Items,
}

/// The items of a value. Pure number lists (coordinates, indices) get a compact form
/// because they dominate large files.
#[derive(Clone, Debug, PartialEq)]
pub enum Items {
    Numbers(NumberList),
    Atoms(Vec<Atom>),
}

impl Items {
    /// Number of items.
    pub fn len(&self) -> usize {
        match self {
            Items::Numbers(list) => list.values.len(),
            Items::Atoms(atoms) => atoms.len(),
        }
    }

    /// Whether there are no items.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A run of numbers with the start offset of each (its end is where its token ends).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct NumberList {
    pub values: Vec<f64>,
    pub starts: Vec<u32>,
}

impl NumberList {
    /// Span of item `index`, found from its start by the lexer's word rule.
    pub fn span_of(&self, index: usize, source: &str) -> Span {
        let start = self.starts[index] as usize;
        let len = crate::word::word_len(&source.as_bytes()[start..]);
        Span::new(start, start + len)
    }
}

/// One item of a value.
#[derive(Clone, Debug, PartialEq)]
pub enum Atom {
    Number(Number),
    Bool(Span, bool),
    String(StringLit),
    Null(Span),
    Node(Node),
    Template(Template),
}

impl Atom {
    /// Where the item stands in the source.
    pub fn span(&self) -> Span {
        match self {
            Atom::Number(number) => number.span,
            Atom::Bool(span, _) | Atom::Null(span) => *span,
            Atom::String(string) => string.span,
            Atom::Node(node) => node.span,
            Atom::Template(template) => template.span,
        }
    }
}

/// A numeric literal. `hex` marks VRML97's `0x…` integers.
#[derive(Clone, Debug, PartialEq)]
pub struct Number {
    pub span: Span,
    pub value: f64,
    pub hex: bool,
}

/// A string literal; `value` has its escapes resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct StringLit {
    pub span: Span,
    pub value: String,
}

/// `PROTO Name [ declarations ] { body }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Proto {
    pub span: Span,
    pub name: Ident,
    pub interface: Vec<Declaration>,
    /// The body's statements: nested PROTOs, ROUTEs, nodes (the first is the PROTO's node type)
    /// and template blocks.
    pub body: Vec<Item>,
}

/// An interface declaration: `field SFVec3f translation 0 0 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct Declaration {
    pub span: Span,
    /// `field`, `vrmlField`, `hiddenField`, `deprecatedField`, `unconnectedField`,
    /// `exposedField`, `eventIn`, `eventOut`.
    pub keyword: Ident,
    /// `SFVec3f`, `MFNode`…
    pub field_type: Ident,
    /// Webots' allowed values: `SFRotation{0 1 0 0, 0 0 1 0}`; the items as written.
    pub restriction: Option<Value>,
    pub name: Ident,
    /// Absent for `eventIn`/`eventOut` and in EXTERNPROTO interfaces.
    pub default: Option<FieldValue>,
}

/// `EXTERNPROTO "url"` (Webots) or `EXTERNPROTO Name [ interface ] urls` (VRML97).
#[derive(Clone, Debug, PartialEq)]
pub struct ExternProto {
    pub span: Span,
    pub importable: bool,
    /// VRML97 form only.
    pub name: Option<Ident>,
    pub interface: Vec<Declaration>,
    pub urls: Vec<StringLit>,
}

/// `ROUTE a.b TO c.d`.
#[derive(Clone, Debug, PartialEq)]
pub struct Route {
    pub span: Span,
    pub from_node: Ident,
    pub from_field: Ident,
    pub to_node: Ident,
    pub to_field: Ident,
}

/// An opaque template block: `%< … >%`, `%<= … >%`, `%{ … }%` or `%{= … }%`.
#[derive(Clone, Debug, PartialEq)]
pub struct Template {
    pub span: Span,
    /// True for the expression forms `%<=` and `%{=`.
    pub expression: bool,
}

/// Visits a node and every node inside it, depth first, in source order.
pub fn walk_node<'a>(node: &'a Node, visit: &mut dyn FnMut(&'a Node)) {
    walk_nodes_from(std::slice::from_ref(node), visit);
}

fn walk_nodes_from<'a>(nodes: &'a [Node], visit: &mut dyn FnMut(&'a Node)) {
    for node in nodes {
        visit(node);
        if let NodeKind::Instance {
            body: Some(body), ..
        } = &node.kind
        {
            for item in &body.items {
                if let BodyItem::Field(Field {
                    value:
                        FieldValue::Value(Value {
                            items: Items::Atoms(atoms),
                            ..
                        }),
                    ..
                }) = item
                {
                    for atom in atoms {
                        if let Atom::Node(child) = atom {
                            walk_nodes_from(std::slice::from_ref(child), visit);
                        }
                    }
                }
            }
        }
    }
}

/// Visits every node of a file, depth first, in source order (PROTO bodies included).
pub fn walk_nodes<'a>(file: &'a SourceFile, visit: &mut dyn FnMut(&'a Node)) {
    fn walk_item<'a>(item: &'a Item, visit: &mut dyn FnMut(&'a Node)) {
        match item {
            Item::Node(node) => walk_node(node, visit),
            Item::Proto(proto) => walk_proto(proto, visit),
            Item::ExternProto(_) | Item::Route(_) | Item::Template(_) => {}
        }
    }
    fn walk_proto<'a>(proto: &'a Proto, visit: &mut dyn FnMut(&'a Node)) {
        for declaration in &proto.interface {
            if let Some(FieldValue::Value(value)) = &declaration.default {
                walk_value(value, visit);
            }
        }
        for item in &proto.body {
            walk_item(item, visit);
        }
    }
    fn walk_value<'a>(value: &'a Value, visit: &mut dyn FnMut(&'a Node)) {
        if let Items::Atoms(atoms) = &value.items {
            for atom in atoms {
                if let Atom::Node(node) = atom {
                    walk_node(node, visit);
                }
            }
        }
    }
    fn walk_node<'a>(node: &'a Node, visit: &mut dyn FnMut(&'a Node)) {
        visit(node);
        if let NodeKind::Instance {
            body: Some(body), ..
        } = &node.kind
        {
            for item in &body.items {
                match item {
                    BodyItem::Field(field) => {
                        if let FieldValue::Value(value) = &field.value {
                            walk_value(value, visit);
                        }
                    }
                    BodyItem::Proto(proto) => walk_proto(proto, visit),
                    BodyItem::Declaration(declaration) => {
                        if let Some(FieldValue::Value(value)) = &declaration.default {
                            walk_value(value, visit);
                        }
                    }
                    BodyItem::Route(_) | BodyItem::Template(_) => {}
                }
            }
        }
    }
    for item in &file.items {
        walk_item(item, visit);
    }
}
