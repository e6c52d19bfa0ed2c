//! PROTOs: the built-in table and each file's own, what a PROTO body sees, and instancing:
//! recursion, depth and size checks, instance fields and defaults bound to the interface
//! (with their restrictions), the body expanded in a scope of its own, Webots stand-ins
//! recorded; each definition's interface checked once (unused fields, name clashes).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, Span};

use crate::binding::{Binding, Bindings};
use crate::catalogue::did_you_mean;
use crate::protos::{BUILTIN_PROTOS, WEBOTS_STANDINS};
use crate::scene::{FileId, NodeId, Origin};
use crate::value::{FieldType, Value};

use super::checked::Substitution;
use super::events::{implied_event, proto_event_with_value};
use super::state::{has_template, Frame, Lowerer, ProtoDef, ProtoTable, Scope, UrlBase};

impl<'c> Lowerer<'c> {
    /// regatta's own PROTOs (`Khepera`, `Buoy`, `Arena`), parsed once per check: the table
    /// every file's PROTOs come after.
    pub(super) fn builtins(&mut self) -> ProtoTable {
        if let Some(builtins) = &self.builtins {
            return builtins.clone();
        }
        let mut list = Vec::new();
        for (name, text) in BUILTIN_PROTOS {
            let file = self.add_text(
                &format!("<builtin>/protos/{name}.proto"),
                text,
                UrlBase::NoFiles,
            );
            self.file_authoring
                .insert(file.0, crate::webots::Authoring::Regatta);
            let parsed = self.parse(file);
            for item in &parsed.items {
                if let Item::Proto(proto) = item {
                    list.push(ProtoDef::file_level(file, proto));
                }
            }
        }
        let builtins = Rc::new(list);
        for (_, def) in builtins.iter() {
            self.file_scopes.insert(def.file.0, builtins.clone());
        }
        self.builtins = Some(builtins.clone());
        builtins
    }

    /// The Webots stand-in PROTO `name`, parsed the first time a node names it and no table
    /// in scope defines it (so a world's own or imported definition wins, as it would over
    /// a table entry). A check that meets no Webots PROTO parses none of them.
    pub(super) fn standin(&mut self, name: &str) -> Option<Rc<ProtoDef>> {
        if let Some(found) = self.standins.get(name) {
            return found.clone();
        }
        let &(file_name, text, authoring) = WEBOTS_STANDINS.iter().find(|(n, _, _)| *n == name)?;
        let file = self.add_text(
            &format!("<builtin>/protos/webots/{file_name}.proto"),
            text,
            UrlBase::NoFiles,
        );
        self.file_authoring.insert(file.0, authoring);
        let parsed = self.parse(file);
        let mut list: Vec<(String, Rc<ProtoDef>)> = self.builtins().iter().cloned().collect();
        let mut found = None;
        for item in &parsed.items {
            if let Item::Proto(proto) = item {
                let (proto_name, def) = ProtoDef::file_level(file, proto);
                if proto_name == name {
                    found = Some(def.clone());
                }
                list.push((proto_name, def));
            }
        }
        self.file_scopes.insert(file.0, Rc::new(list));
        self.standins.insert(name.to_owned(), found.clone());
        found
    }

    /// The PROTOs a file defines or imports, after the built-in ones (later entries win).
    pub(super) fn file_protos(&mut self, file: FileId, parsed: &syntax::SourceFile) -> ProtoTable {
        let mut list: Vec<(String, Rc<ProtoDef>)> = self.builtins().iter().cloned().collect();
        for item in &parsed.items {
            if let Item::ExternProto(extern_proto) = item {
                self.extern_proto(file, extern_proto, &mut list);
            }
        }
        let own: Vec<&syntax::Proto> = parsed
            .items
            .iter()
            .filter_map(|item| {
                if let Item::Proto(p) = item {
                    Some(p)
                } else {
                    None
                }
            })
            .collect();
        let mut seen: BTreeSet<&str> = BTreeSet::new();
        for proto in own {
            if !seen.insert(proto.name.text.as_str()) {
                self.error(
                    file,
                    Diagnostic::warning(
                        proto.name.span,
                        format!(
                            "PROTO '{}' is defined twice; the later definition is used",
                            proto.name.text
                        ),
                    )
                    .with_code("proto-redefined"),
                );
            }
            list.push(ProtoDef::file_level(file, proto));
        }
        let list = Rc::new(list);
        // PROTOs of one file see each other: bodies look the file's table up when instantiated.
        self.file_scopes.insert(file.0, list.clone());
        // Each declaration is checked where it stands, whether or not anything uses it.
        self.check_declarations(file, &list);
        list
    }

    /// What a PROTO's body sees: its file's PROTOs, then those of enclosing PROTO bodies.
    pub(super) fn visible_protos(&self, def: &ProtoDef) -> ProtoTable {
        let file_level = self
            .file_scopes
            .get(&def.file.0)
            .cloned()
            .unwrap_or_default();
        if def.enclosing.is_empty() {
            return file_level;
        }
        let mut all: Vec<(String, Rc<ProtoDef>)> = file_level.iter().cloned().collect();
        all.extend(def.enclosing.iter().cloned());
        Rc::new(all)
    }

    pub(super) fn instantiate(
        &mut self,
        def: &Rc<ProtoDef>,
        node: &syntax::Node,
        items: &[BodyItem],
        scope: &mut Scope,
    ) -> Option<NodeId> {
        let proto = &def.proto;
        let name = &proto.name.text;
        let key = (def.file.0, proto.span.start);
        if self
            .frames
            .iter()
            .any(|f| f.definition == def.file && f.key == key.1)
        {
            self.error(
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("Recursive definition of PROTO node '{name}' is not supported."),
                )
                .with_label("this instance is inside its own definition")
                .with_code("recursive-proto"),
            );
            return None;
        }
        if self.frames.len() >= self.options.limits.proto_depth {
            let limit = self.options.limits.proto_depth;
            self.limit_crossed(
                "proto-depth",
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("PROTO instances nested deeper than {limit} levels"),
                )
                .with_label("this instance is not expanded"),
            );
            return None;
        }
        // An exponential PROTO (ten copies of one that makes ten copies of …) is refused
        // before anything is built: the estimate is cheap and remembered per definition.
        let estimate = self.estimate(def, 0);
        if estimate.saturating_add(self.nodes.len() as u64) > self.options.limits.nodes as u64 {
            self.nodes_limit(scope.file, node.span, Some((name, estimate)));
            return None;
        }
        let statements = has_template(proto);
        if statements {
            let proto_file = &self.sources[def.file.0 as usize];
            if crate::procedural::is_lua(&proto_file.text)
                || proto_file.text[proto.span.range()].contains("%{")
            {
                let message = format!(
                    "PROTO '{name}' ({}) is written with a Lua template (Webots before R2022a); regatta runs JavaScript templates only, so this instance is skipped",
                    proto_file.name
                );
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(node.span, message).with_code("template"),
                );
                return None;
            }
        }
        let instantiating = self
            .file_authoring
            .get(&scope.file.0)
            .copied()
            .unwrap_or_default();
        let proto_authoring = self
            .file_authoring
            .get(&def.file.0)
            .copied()
            .unwrap_or_default();
        if proto_authoring == crate::webots::Authoring::World {
            // Built-in PROTOs accept documented fields they do not use.
            self.check_interface_once(def);
        } else if matches!(
            proto_authoring,
            crate::webots::Authoring::Webots
                | crate::webots::Authoring::WebotsRobot
                | crate::webots::Authoring::WebotsFlu
        ) && !self.substitutions.iter().any(|s| &s.name == name)
        {
            let url = self
                .standin_urls
                .get(name)
                .cloned()
                .unwrap_or_else(|| format!("webots://…/{name}.proto"));
            self.substitutions.push(Substitution {
                name: name.clone(),
                url,
                file: scope.file,
                span: node.span,
            });
        }
        // Instance fields, typed in the instance's scope.
        let mut bindings: Bindings = BTreeMap::new();
        for item in items {
            let BodyItem::Field(field) = item else {
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(
                        body_item_span(item),
                        format!("only field values may stand in an instance of PROTO '{name}'"),
                    )
                    .with_code("proto-instance"),
                );
                continue;
            };
            if field.hidden {
                continue;
            }
            let Some(declaration) = proto
                .interface
                .iter()
                .find(|d| d.name.text == field.name.text)
            else {
                // `set_x`, `x_changed` of an exposedField `x`: events, IS'd only.
                let event = implied_event(&field.name.text).filter(|(declared, _)| {
                    proto
                        .interface
                        .iter()
                        .any(|d| d.name.text == *declared && d.keyword.text == "exposedField")
                });
                if let Some((_, access)) = event {
                    if !matches!(field.value, syntax::FieldValue::Is(_)) {
                        self.strict_or_warn(
                            scope.file,
                            proto_event_with_value(&field.name, access, name),
                        );
                    }
                    continue;
                }
                let mut diagnostic = Diagnostic::error(
                    field.name.span,
                    format!(
                        "{} '{}' parameter in {name} PROTO.",
                        self.unknown(),
                        field.name.text
                    ),
                )
                .with_label("unknown PROTO field")
                .with_code("unknown-field");
                if let Some(close) = did_you_mean(
                    &field.name.text,
                    proto.interface.iter().map(|d| d.name.text.as_str()),
                ) {
                    diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                }
                self.strict_or_warn(scope.file, diagnostic);
                continue;
            };
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            // An event takes no value; IS joins it to an event of the enclosing PROTO.
            if matches!(declaration.keyword.text.as_str(), "eventIn" | "eventOut")
                && !matches!(field.value, syntax::FieldValue::Is(_))
            {
                self.strict_or_warn(
                    scope.file,
                    proto_event_with_value(&field.name, &declaration.keyword.text, name),
                );
                continue;
            }
            let site = self.value_site(field, scope);
            let value = self.lower_field_value(
                &field.value,
                ty,
                None,
                scope,
                &field.name.text,
                field.name.span,
            );
            if let Some(value) = value {
                self.check_restriction(declaration, &value, def.file, site.0, site.2);
                bindings.insert(
                    field.name.text.clone(),
                    Binding {
                        ty,
                        value: Some(value),
                        site: Some(site),
                        keyword: declaration.keyword.text.clone(),
                    },
                );
            }
        }
        // From here on the instance is being expanded: its defaults may name PROTOs too (even
        // itself, which is recursion).
        self.frames.push(Frame {
            name: name.clone(),
            instance: (scope.file, node.span),
            definition: def.file,
            key: key.1,
        });
        // Defaults, typed in the PROTO's own file, each in a DEF scope of its own (VRML97): a
        // default cannot USE a node another default DEFines.
        let visible = self.visible_protos(def);
        for declaration in &proto.interface {
            let mut default_scope = Scope {
                protos: visible.clone(),
                ..Scope::new(def.file)
            };
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            if let Some(bound) = bindings.get_mut(&declaration.name.text) {
                bound.keyword = declaration.keyword.text.clone();
                continue;
            }
            let value = match &declaration.default {
                Some(_) => {
                    let value = self.lower_default(declaration, ty, &mut default_scope);
                    if let Some(value) = &value {
                        self.check_restriction(
                            declaration,
                            value,
                            def.file,
                            def.file,
                            declaration.name.span,
                        );
                    }
                    value
                }
                None => None,
            };
            bindings.insert(
                declaration.name.text.clone(),
                Binding {
                    ty,
                    value,
                    site: None,
                    keyword: declaration.keyword.text.clone(),
                },
            );
        }
        // A template PROTO's body is the text its template generates, unless every template
        // in it is arithmetic over fields (regatta's own PROTOs): then no engine starts.
        let body_def = if statements || self.needs_engine(def, &bindings) {
            self.expand_template(def, &bindings, node, scope)?
        } else {
            def.clone()
        };
        let def = &body_def;
        let proto = &def.proto;
        // The body, in a scope of its own.
        let visible = self.visible_protos(def);
        let mut nested_protos: Vec<(String, Rc<ProtoDef>)> = Vec::new();
        let mut body_scope = Scope {
            file: def.file,
            defs: HashMap::new(),
            protos: visible.clone(),
            interface: Some(Rc::new(bindings)),
            skipped_defs: BTreeSet::new(),
        };
        let mut root = None;
        let mut found_root = false;
        for item in &proto.body {
            match item {
                Item::Proto(nested) => {
                    // Rare: only bodies that define PROTOs pay for a scope of their own.
                    let mut enclosing: Vec<(String, Rc<ProtoDef>)> =
                        def.enclosing.iter().cloned().collect();
                    enclosing.extend(nested_protos.iter().cloned());
                    nested_protos.push((
                        nested.name.text.clone(),
                        Rc::new(ProtoDef {
                            file: def.file,
                            proto: nested.clone(),
                            enclosing: Rc::new(enclosing),
                        }),
                    ));
                    let mut all: Vec<(String, Rc<ProtoDef>)> = visible.iter().cloned().collect();
                    all.extend(nested_protos.iter().cloned());
                    body_scope.protos = Rc::new(all);
                }
                Item::Node(body_node) if !found_root => {
                    found_root = true;
                    root = self.lower_node(
                        body_node,
                        &mut body_scope,
                        &[],
                        &format!("PROTO '{name}'"),
                    );
                }
                Item::Route(route) if found_root => self.route(route, &mut body_scope),
                _ => {}
            }
        }
        self.frames.pop();
        if !found_root {
            self.error(
                def.file,
                Diagnostic::error(
                    proto.name.span,
                    format!("PROTO '{name}' has no node in its body"),
                )
                .with_code("empty-proto"),
            );
        }
        let root = root?;
        let root_node = &mut self.nodes[root.index()];
        root_node.names_mut().proto_names.push(name.clone());
        // The instance is where the user wrote the node; its body's authoring (which axes it
        // was written in) is the innermost PROTO's, remembered before the origin moves.
        let body_file = root_node.origin.file;
        root_node.origin = Origin {
            file: scope.file,
            span: node.span,
        };
        let body = self
            .file_authoring
            .get(&body_file.0)
            .copied()
            .unwrap_or_default();
        self.body_authoring.entry(root.0).or_insert(body);
        self.instance_of.insert(root, def.clone());
        if instantiating != proto_authoring {
            self.instance_authoring.insert(root.0, instantiating);
        }
        Some(root)
    }

    /// A PROTO field's default value, typed in the PROTO's own file (`None` when it has none
    /// or it does not type, after reporting).
    pub(super) fn lower_default(
        &mut self,
        declaration: &syntax::Declaration,
        ty: FieldType,
        scope: &mut Scope,
    ) -> Option<Value> {
        let default = declaration.default.as_ref()?;
        self.lower_field_value(
            default,
            ty,
            None,
            scope,
            &declaration.name.text,
            declaration.name.span,
        )
    }

    /// Once per instantiated PROTO definition: Webots' "PROTO parameter 'x' has no matching
    /// IS field." (a PROTO no one uses is not nagged about fields no one sets), and VRML97's
    /// name rules (`check_interface_names`).
    pub(super) fn check_interface_once(&mut self, def: &Rc<ProtoDef>) {
        let key = (def.file.0, def.proto.span.start);
        if !self.checked_protos.insert(key) {
            return;
        }
        let mut targets: Vec<&syntax::Ident> = Vec::new();
        collect_is_targets(&def.proto.body, &mut targets);
        let targets: BTreeSet<&str> = targets.iter().map(|t| t.text.as_str()).collect();
        // Template expressions use fields too: every `fields.NAME.` of the body, in one pass.
        let text = self.sources[def.file.0 as usize].text.clone();
        let body_text = &text[def.proto.span.range()];
        let in_templates: BTreeSet<&str> = body_text
            .split("fields.")
            .skip(1)
            .filter_map(|rest| rest.split('.').next())
            .collect();
        for declaration in &def.proto.interface {
            let name = declaration.name.text.as_str();
            let is_event = matches!(
                declaration.keyword.text.as_str(),
                "eventIn" | "eventOut" | "unconnectedField"
            );
            if !is_event && !in_templates.contains(name) && !targets.contains(name) {
                self.error(
                    def.file,
                    Diagnostic::warning(
                        declaration.name.span,
                        format!("PROTO parameter '{name}' has no matching IS field."),
                    )
                    .with_code("unused-proto-field"),
                );
            }
        }
        self.check_interface_names(def);
    }

    /// VRML97's name rules of an interface (4.8.2): no name declared twice, no `set_x` or
    /// `x_changed` beside an exposedField `x`. Where the PROTO is declared, and again (the
    /// same messages, given once) where it is first instantiated.
    pub(super) fn check_interface_names(&mut self, def: &Rc<ProtoDef>) {
        let mut names: HashMap<&str, &syntax::Declaration> = HashMap::new();
        for declaration in &def.proto.interface {
            let name = declaration.name.text.as_str();
            if let Some(first) = names.insert(name, declaration) {
                self.strict_or_warn(
                    def.file,
                    Diagnostic::error(
                        declaration.name.span,
                        format!(
                            "'{name}' is declared twice in PROTO '{}'",
                            def.proto.name.text
                        ),
                    )
                    .with_secondary(first.name.span, "first declared here")
                    .with_code("name-clash"),
                );
            }
        }
        for declaration in &def.proto.interface {
            if declaration.keyword.text != "exposedField" {
                continue;
            }
            let name = &declaration.name.text;
            for implied in [format!("set_{name}"), format!("{name}_changed")] {
                if let Some(other) = names.get(implied.as_str()) {
                    self.strict_or_warn(
                        def.file,
                        Diagnostic::error(
                            other.name.span,
                            format!("'{implied}' clashes with the exposedField '{name}', which declares it"),
                        )
                        .with_secondary(declaration.name.span, format!("'{name}' is an exposedField: it has the events set_{name} and {name}_changed"))
                        .with_code("name-clash"),
                    );
                }
            }
        }
    }

    pub(super) fn check_restriction(
        &mut self,
        declaration: &syntax::Declaration,
        value: &Value,
        proto_file: FileId,
        file: FileId,
        span: Span,
    ) {
        let Some(restriction) = &declaration.restriction else {
            return;
        };
        let Items::Atoms(atoms) = &restriction.items else {
            return;
        };
        let allowed_numbers: Vec<f64> = atoms
            .iter()
            .filter_map(|a| {
                if let Atom::Number(n) = a {
                    Some(n.value)
                } else {
                    None
                }
            })
            .collect();
        let allowed_strings: Vec<&str> = atoms
            .iter()
            .filter_map(|a| {
                if let Atom::String(s) = a {
                    Some(s.value.as_str())
                } else {
                    None
                }
            })
            .collect();
        let ok = match value {
            Value::String(s) if !allowed_strings.is_empty() => {
                allowed_strings.contains(&s.as_str())
            }
            Value::Float(x) if !allowed_numbers.is_empty() => allowed_numbers.contains(x),
            Value::Int(i) if !allowed_numbers.is_empty() => allowed_numbers.contains(&(*i as f64)),
            Value::Vec3(v) if !allowed_numbers.is_empty() => {
                allowed_numbers.chunks(3).any(|c| c == v)
            }
            _ => true,
        };
        if !ok {
            let allowed =
                self.sources[proto_file.0 as usize].text[restriction.span.range()].to_owned();
            self.error(
                file,
                Diagnostic::error(
                    span,
                    format!(
                        "Invalid '{}': the value should be in the list: {allowed}.",
                        declaration.name.text
                    ),
                )
                .with_label("not an allowed value")
                .with_code("restricted-value"),
            );
        }
    }
}

fn body_item_span(item: &BodyItem) -> Span {
    match item {
        BodyItem::Field(f) => f.span,
        BodyItem::Proto(p) => p.span,
        BodyItem::Route(r) => r.span,
        BodyItem::Declaration(d) => d.span,
        BodyItem::Template(t) => t.span,
    }
}

fn collect_is_targets<'a>(items: &'a [Item], out: &mut Vec<&'a syntax::Ident>) {
    fn node<'a>(n: &'a syntax::Node, out: &mut Vec<&'a syntax::Ident>) {
        if let NodeKind::Instance {
            body: Some(body), ..
        } = &n.kind
        {
            for item in &body.items {
                if let BodyItem::Field(f) = item {
                    match &f.value {
                        syntax::FieldValue::Is(target) => out.push(target),
                        syntax::FieldValue::Value(v) => {
                            if let Items::Atoms(atoms) = &v.items {
                                for atom in atoms {
                                    if let Atom::Node(child) = atom {
                                        node(child, out);
                                    }
                                }
                            }
                        }
                        syntax::FieldValue::Missing { .. } => {}
                    }
                }
            }
        }
    }
    for item in items {
        match item {
            Item::Node(n) => node(n, out),
            Item::Proto(p) => collect_is_targets(&p.body, out),
            _ => {}
        }
    }
}
