//! PROTO declarations checked where they stand, once each, whether anything instantiates them
//! or not (ISO/IEC 14772 4.8): the interface (each name declared once, no `set_x` or
//! `x_changed` beside an exposedField `x`; unknown field types are the parser's), a body with
//! a node in it, and in the body every IS (to a field of the interface, of the same type,
//! with an access table 4.4 joins, for built-in nodes and PROTO instances alike) and no value
//! written for an eventIn or eventOut; its ROUTEs between its own DEF'd nodes (4.10); PROTOs
//! nested in a body are declarations too. An instance's checks
//! say the same words at the same places, so each problem is reported once, at the body's
//! line, however many instances there are (or none).
//!
//! The PROTOs checked are those of the user's files (the world, its EXTERNPROTO and Inline
//! files): regatta's own and the Webots stand-ins are checked by their tests, and what goes
//! wrong inside them is an instance's doing. A body made by a template (statements, not
//! only `%<= … >%` values) is the text the template generates per instance: only its
//! interface is checked here.

use std::collections::HashMap;
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::Diagnostic;

use crate::protos::WEBOTS_STANDINS;
use crate::scene::FileId;
use crate::value::FieldType;

use super::events::{
    access_of, implied_event, interface_ends, is_access_mismatch, is_compatible, is_type_mismatch,
    node_event_with_value, proto_event_with_value, spec_ends, unknown_is,
};
use super::state::{has_template, Lowerer, ProtoDef};

/// An interface field as the body sees it: its type and its keyword.
type Interface<'a> = HashMap<&'a str, (FieldType, &'a str)>;

/// What a node in a body is, for its fields' access and types.
#[derive(Clone)]
enum NodeType {
    /// A catalogue node: its fields' types and accesses.
    Builtin(crate::catalogue::SpecId),
    /// A PROTO in scope: its interface.
    Proto(Rc<ProtoDef>),
    /// Unknown here (a Webots stand-in, a misspelling): the instance reports it.
    Unknown,
}

impl<'c> Lowerer<'c> {
    /// Checks the PROTOs a user's file defines, where they are defined (`table` is the file's
    /// PROTO table, already in `file_scopes`).
    pub(super) fn check_declarations(&mut self, file: FileId, table: &[(String, Rc<ProtoDef>)]) {
        let authoring = self
            .file_authoring
            .get(&file.0)
            .copied()
            .unwrap_or_default();
        if authoring != crate::webots::Authoring::World {
            return;
        }
        for (_, def) in table.iter().filter(|(_, def)| def.file == file) {
            self.check_declaration(def);
        }
    }

    /// One PROTO declaration, and the PROTOs declared in its body; once each.
    fn check_declaration(&mut self, def: &Rc<ProtoDef>) {
        if !self
            .declared_protos
            .insert((def.file.0, def.proto.span.start))
        {
            return;
        }
        let proto = &def.proto;
        self.check_interface_names(def);
        let mut interface: Interface = HashMap::new();
        for declaration in &proto.interface {
            // An unknown type is the parser's to report (it keeps no such declaration).
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            interface
                .entry(declaration.name.text.as_str())
                .or_insert((ty, declaration.keyword.text.as_str()));
        }
        if has_template(proto) {
            return;
        }
        let visible = self.visible_protos(def);
        let mut nested: Vec<(String, Rc<ProtoDef>)> = Vec::new();
        // The body's DEF names so far, for its ROUTEs.
        let mut defs: HashMap<String, NodeType> = HashMap::new();
        let mut has_node = false;
        for item in &proto.body {
            match item {
                Item::Proto(inner) => {
                    // As an instance's body sees it: the enclosing bodies' PROTOs, then
                    // those of this body declared before it.
                    let mut enclosing: Vec<(String, Rc<ProtoDef>)> =
                        def.enclosing.iter().cloned().collect();
                    enclosing.extend(nested.iter().cloned());
                    let inner = Rc::new(ProtoDef {
                        file: def.file,
                        proto: inner.clone(),
                        enclosing: Rc::new(enclosing),
                    });
                    nested.push((inner.proto.name.text.clone(), inner.clone()));
                    self.check_declaration(&inner);
                }
                Item::Node(node) => {
                    has_node = true;
                    let scope: Vec<(String, Rc<ProtoDef>)> =
                        visible.iter().chain(nested.iter()).cloned().collect();
                    self.check_body_node(def.file, node, &interface, &scope, &mut defs);
                }
                Item::Route(route) => self.check_body_route(def.file, route, &defs),
                _ => {}
            }
        }
        if !has_node {
            self.error(
                def.file,
                Diagnostic::error(
                    proto.name.span,
                    format!("PROTO '{}' has no node in its body", proto.name.text),
                )
                .with_code("empty-proto"),
            );
        }
    }

    /// One node of a body and the nodes in its fields: IS and event rules, field by field.
    fn check_body_node(
        &mut self,
        file: FileId,
        node: &syntax::Node,
        interface: &Interface,
        protos: &[(String, Rc<ProtoDef>)],
        defs: &mut HashMap<String, NodeType>,
    ) {
        let NodeKind::Instance {
            type_name,
            body: Some(body),
        } = &node.kind
        else {
            return;
        };
        let name = type_name.text.as_str();
        // Names resolve as an instance resolves them: PROTOs in scope, then the stand-ins,
        // then the catalogue.
        let node_type = match protos.iter().rev().find(|(n, _)| n == name) {
            Some((_, def)) => NodeType::Proto(def.clone()),
            None if WEBOTS_STANDINS.iter().any(|(n, _, _)| *n == name) => NodeType::Unknown,
            None => match self.catalogue().lookup(name) {
                Some(spec) => NodeType::Builtin(spec),
                None => NodeType::Unknown,
            },
        };
        for item in &body.items {
            let BodyItem::Field(field) = item else {
                continue;
            };
            if field.hidden {
                continue;
            }
            // The field's type and access, when this node has it.
            let target: Option<(FieldType, &str)> = match &node_type {
                NodeType::Builtin(spec) => {
                    let spec = self.catalogue().spec(*spec);
                    let access_of_index = |index: usize| {
                        let field_spec = &spec.fields[index];
                        let access = match field_spec.access.as_deref() {
                            Some("field") => "field",
                            Some("eventIn") => "eventIn",
                            Some("eventOut") => "eventOut",
                            _ => "exposedField",
                        };
                        (field_spec.ty(), access)
                    };
                    match spec.field_index(&field.name.text) {
                        Some(index) => Some(access_of_index(index)),
                        // `set_children`, `translation_changed`: an exposedField's events.
                        None => implied_event(&field.name.text).and_then(|(name, access)| {
                            let index = spec.field_index(name)?;
                            let (ty, own) = access_of_index(index);
                            (own == "exposedField").then_some((ty, access))
                        }),
                    }
                }
                NodeType::Proto(def) => {
                    let find = |name: &str| {
                        let d = def.proto.interface.iter().find(|d| d.name.text == name)?;
                        let ty = FieldType::parse(&d.field_type.text)?;
                        Some((ty, access_of(&d.keyword.text)))
                    };
                    find(&field.name.text).or_else(|| {
                        let (name, access) = implied_event(&field.name.text)?;
                        let (ty, own) = find(name)?;
                        (own == "exposedField").then_some((ty, access))
                    })
                }
                NodeType::Unknown => None,
            };
            match &field.value {
                syntax::FieldValue::Is(is) => {
                    let Some(&(interface_type, keyword)) = interface.get(is.text.as_str()) else {
                        self.error(file, unknown_is(is));
                        continue;
                    };
                    let Some((ty, access)) = target else {
                        continue;
                    };
                    if interface_type != ty {
                        self.error(
                            file,
                            is_type_mismatch(is, interface_type, &field.name.text, ty),
                        );
                    } else if !is_compatible(keyword, access) {
                        self.strict_or_warn(
                            file,
                            is_access_mismatch(is, keyword, &field.name.text, access),
                        );
                    }
                }
                syntax::FieldValue::Value(value) => {
                    if let Some((_, access @ ("eventIn" | "eventOut"))) = target {
                        let diagnostic = match &node_type {
                            NodeType::Builtin(spec) => {
                                let node = self.catalogue().spec(*spec).name.clone();
                                node_event_with_value(&field.name, access, &node)
                            }
                            NodeType::Proto(def) => {
                                proto_event_with_value(&field.name, access, &def.proto.name.text)
                            }
                            NodeType::Unknown => continue,
                        };
                        self.strict_or_warn(file, diagnostic);
                        continue;
                    }
                    if let Items::Atoms(atoms) = &value.items {
                        for atom in atoms {
                            if let Atom::Node(child) = atom {
                                self.check_body_node(file, child, interface, protos, defs);
                            }
                        }
                    }
                }
                syntax::FieldValue::Missing { .. } => {}
            }
        }
        // Bound once the node is complete, as an instance binds it.
        if let Some(def) = node.def.as_ref().filter(|d| !d.text.is_empty()) {
            defs.insert(def.text.clone(), node_type);
        }
    }

    /// A ROUTE of a body (VRML97 4.10): both ends DEF'd before it in the body, events of the
    /// right access, one type. A sound one says nothing here; each instance says it is not
    /// simulated.
    fn check_body_route(
        &mut self,
        file: FileId,
        route: &syntax::Route,
        defs: &HashMap<String, NodeType>,
    ) {
        let from = self.body_route_end(file, &route.from_node, &route.from_field, true, defs);
        let to = self.body_route_end(file, &route.to_node, &route.to_field, false, defs);
        self.route_types(route, file, from, to);
    }

    fn body_route_end(
        &mut self,
        file: FileId,
        node: &syntax::Ident,
        field: &syntax::Ident,
        source: bool,
        defs: &HashMap<String, NodeType>,
    ) -> Option<FieldType> {
        let (label, ends) = match defs.get(&node.text) {
            None => {
                self.route_without_node(node, file);
                return None;
            }
            Some(NodeType::Unknown) => return None,
            Some(NodeType::Builtin(spec)) => {
                let spec = self.catalogue().spec(*spec);
                (format!("{} node", spec.name), spec_ends(spec))
            }
            Some(NodeType::Proto(def)) => (
                format!("PROTO '{}'", def.proto.name.text),
                interface_ends(&def.proto.interface),
            ),
        };
        self.route_end_in(node, field, source, file, &label, &ends)
    }
}
