//! Nodes: the world's items, DEF/USE in a [`Scope`], built-in nodes field by field
//! (unknown, repeated and event fields; urls of `file` fields), node classes where a node
//! stands, unknown node types (and the robots among them), and the arena nodes go into.

use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, Span};

use crate::catalogue::{did_you_mean, SpecId};
use crate::scene::{FieldsBuilder, FileId, NodeId, Origin, SceneNode, Written};

use super::checked::UnbuiltRobot;
use super::events::{implied_event, node_event_with_value};
use super::state::{Lowerer, Scope, UrlUse};

impl<'c> Lowerer<'c> {
    pub(super) fn lower_world(&mut self, file: FileId) {
        let parsed = self.parse(file);
        let header = parsed.header.clone();
        let protos = self.file_protos(file, &parsed);
        let mut scope = Scope {
            protos,
            ..Scope::new(file)
        };
        self.decide_axes(header.as_ref(), &parsed);
        // The world's tree is read once, item by item, and a crowd's world is much of what a
        // check holds at its peak: each item is dropped once lowered, so that the nodes it
        // becomes reuse its place. Nothing parses the world again: its PROTOs were copied and
        // its EXTERNPROTOs read above, and a file that includes the world is refused.
        self.parsed.remove(&file.0);
        let roots = match Rc::try_unwrap(parsed) {
            Ok(owned) => {
                let mut roots = Vec::new();
                for item in owned.items {
                    self.lower_item(&item, &mut scope, true, &mut roots);
                }
                roots
            }
            Err(shared) => self.lower_items(&shared.items, &mut scope, true),
        };
        self.roots = roots;
    }

    pub(super) fn lower_items(
        &mut self,
        items: &[Item],
        scope: &mut Scope,
        top_level: bool,
    ) -> Vec<NodeId> {
        let mut roots = Vec::new();
        for item in items {
            self.lower_item(item, scope, top_level, &mut roots);
        }
        roots
    }

    /// Lowers one of a file's or body's items; a node's id goes to `roots`.
    fn lower_item(
        &mut self,
        item: &Item,
        scope: &mut Scope,
        top_level: bool,
        roots: &mut Vec<NodeId>,
    ) {
        match item {
            Item::Node(node) => {
                if let Some(id) = self.lower_node(
                    node,
                    scope,
                    &["child".to_owned(), "robot".to_owned()],
                    "the world",
                ) {
                    roots.push(id);
                }
            }
            Item::Template(template) if top_level => self.strict_or_warn(
                scope.file,
                Diagnostic::error(
                    template.span,
                    "template code outside a PROTO is not evaluated",
                )
                .with_code("template"),
            ),
            Item::Route(route) => self.route(route, scope),
            _ => {}
        }
    }

    pub(super) fn alloc(&mut self, node: SceneNode, file: FileId, span: Span) -> Option<NodeId> {
        if self.nodes.len() >= self.options.limits.nodes {
            self.nodes_limit(file, span, None);
            return None;
        }
        let spec = self.catalogue().spec(node.spec);
        let holds_robot = spec.classes.iter().any(|c| c == "robot")
            || node
                .fields
                .own()
                .any(|v| v.nodes().iter().any(|c| self.holds_robot[c.index()]));
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(node);
        self.holds_robot.push(holds_robot);
        Some(id)
    }

    /// Types one node where `accepted` classes may stand. `place` names the field, for messages.
    pub(super) fn lower_node(
        &mut self,
        node: &syntax::Node,
        scope: &mut Scope,
        accepted: &[String],
        place: &str,
    ) -> Option<NodeId> {
        if self.limits_reported.contains("nodes") {
            // The scene is already too large: stop expanding anything.
            return None;
        }
        if self.node_depth >= self.options.limits.scene_depth() {
            let limit = self.options.limits.scene_depth();
            self.limit_crossed(
                "nesting",
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("nodes nested deeper than {limit} levels once PROTOs and Inline files are expanded"),
                )
                .with_label("this node is skipped"),
            );
            return None;
        }
        self.node_depth += 1;
        let id = self.lower_node_inner(node, scope, accepted, place);
        self.node_depth -= 1;
        id
    }

    pub(super) fn lower_node_inner(
        &mut self,
        node: &syntax::Node,
        scope: &mut Scope,
        accepted: &[String],
        place: &str,
    ) -> Option<NodeId> {
        let id = match &node.kind {
            NodeKind::Use(name) => {
                if name.text.is_empty() {
                    return None;
                }
                match scope.defs.get(&name.text) {
                    Some(&id) if self.holds_robot[id.index()] => {
                        // A robot is one body with one name: a second copy would be a second
                        // robot under the same name.
                        self.strict_or_warn(
                            scope.file,
                            Diagnostic::error(
                                node.span,
                                format!("USE {} would copy a robot", name.text),
                            )
                            .with_label("a robot cannot be USEd")
                            .with_note("write a second robot with its own name instead; this USE is skipped")
                            .with_code("use-of-robot"),
                        );
                        return None;
                    }
                    Some(&id) => id,
                    None if scope.skipped_defs.contains(&name.text) => {
                        self.error(
                            scope.file,
                            Diagnostic::warning(
                                name.span,
                                format!("USE {} refers to a node that was skipped", name.text),
                            )
                            .with_code("use-of-skipped"),
                        );
                        return None;
                    }
                    None => {
                        let mut diagnostic = Diagnostic::error(
                            name.span,
                            format!("no node was DEF'd as '{}' before this USE", name.text),
                        )
                        .with_label("unknown DEF name")
                        .with_code("unknown-use");
                        if let Some(close) =
                            did_you_mean(&name.text, scope.defs.keys().map(String::as_str))
                        {
                            diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                        }
                        self.error(scope.file, diagnostic);
                        return None;
                    }
                }
            }
            NodeKind::Instance { type_name, body } => {
                if type_name.text.is_empty() {
                    return None;
                }
                let empty = Vec::new();
                let items = body.as_ref().map_or(&empty, |b| &b.items);
                let proto = scope
                    .find_proto(&type_name.text)
                    .or_else(|| self.standin(&type_name.text));
                let id = if let Some(proto) = proto {
                    self.instantiate(&proto, node, items, scope)?
                } else if let Some(spec) = self.catalogue().lookup(&type_name.text) {
                    if self.catalogue().spec(spec).open {
                        self.unsimulated_node(type_name, items, place, scope);
                    }
                    self.lower_builtin(spec, node, items, scope)?
                } else {
                    let url = self.unresolved.get(&type_name.text).cloned();
                    let sets_controller = items.iter().any(
                        |item| matches!(item, BodyItem::Field(f) if f.name.text == "controller"),
                    );
                    // Robots stand at the top of a world; a PROTO of Webots' robots folder met
                    // deeper is an extension (a turret board, a gripper).
                    let in_robots_folder = |u: &str| {
                        let resolved = match &self.options.base_dir {
                            Some(base) if !u.contains("://") => base.join(u),
                            _ => PathBuf::from(u),
                        };
                        resolved
                            .to_string_lossy()
                            .replace('\\', "/")
                            .contains("/robots/")
                    };
                    let robot_proto =
                        place == "the world" && url.as_deref().is_some_and(in_robots_folder);
                    if sets_controller || robot_proto {
                        self.unbuilt_robots.push(UnbuiltRobot {
                            type_name: type_name.text.clone(),
                            url,
                            file: scope.file,
                            span: type_name.span,
                        });
                    }
                    self.unknown_node(type_name, scope);
                    syntax::walk_node(node, &mut |inner| {
                        if let Some(def) = &inner.def {
                            scope.skipped_defs.insert(def.text.clone());
                        }
                    });
                    return None;
                };
                if let Some(def) = &node.def {
                    if !def.text.is_empty() {
                        self.nodes[id.index()].names_mut().def_name = Some(def.text.clone());
                        scope.defs.insert(def.text.clone(), id);
                    }
                }
                id
            }
        };
        let spec = self.catalogue().spec(self.nodes[id.index()].spec);
        if !spec.fits(accepted) {
            let diagnostic = self.wrong_class(spec, accepted, place, node.span);
            self.strict_or_warn(scope.file, diagnostic);
            return None;
        }
        Some(id)
    }

    /// "a Box node cannot stand in 'turret'", naming the node types that can.
    pub(super) fn wrong_class(
        &self,
        spec: &crate::catalogue::NodeSpec,
        accepted: &[String],
        place: &str,
        span: Span,
    ) -> Diagnostic {
        let catalogue = self.catalogue();
        let types: Vec<&str> = catalogue
            .nodes
            .iter()
            .filter(|n| n.fits(accepted))
            .map(|n| n.name.as_str())
            .collect();
        let shown = if types.len() <= 8 {
            format!(": {}", types.join(", "))
        } else {
            format!(" ({} types, `regatta schema` lists them)", types.len())
        };
        Diagnostic::error(
            span,
            format!("a {} node cannot stand in {place}", spec.name),
        )
        .with_label(format!(
            "{} is a {} node",
            spec.name,
            spec.classes.join("/")
        ))
        .with_note(format!(
            "{place} accepts {} nodes{shown}",
            accepted.join(" or ")
        ))
        .with_code("wrong-node-class")
    }

    pub(super) fn unknown_node(&mut self, type_name: &syntax::Ident, scope: &Scope) {
        let name = &type_name.text;
        let diagnostic = if let Some(url) = self.unresolved.get(name) {
            Diagnostic::error(
                type_name.span,
                format!("{} '{name}' node or PROTO.", self.unknown()),
            )
            .with_label("its PROTO is not available")
            .with_note(if crate::webots::webots_path(url).is_some() {
                format!(
                    "its EXTERNPROTO points to {url}: regatta has no built-in stand-in for it and never fetches from the network; --proto-path DIR (or REGATTA_PROTO_PATH) can point at a Webots installation that has it"
                )
            } else {
                format!(
                    "its EXTERNPROTO points to {url}, and regatta never fetches from the network"
                )
            })
        } else {
            let mut diagnostic = Diagnostic::error(
                type_name.span,
                format!("{} '{name}' node or PROTO.", self.unknown()),
            )
            .with_label("unknown node type");
            if let Some(reason) = crate::webots::unsimulated(name) {
                diagnostic = diagnostic.with_note(format!("{name}: {reason}"));
            }
            let mut candidates: Vec<&str> = self.catalogue().names().collect();
            candidates.extend(scope.protos.iter().map(|(n, _)| n.as_str()));
            candidates.extend(crate::protos::WEBOTS_STANDINS.iter().map(|(n, _, _)| *n));
            if let Some(close) = did_you_mean(name, candidates) {
                diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
            }
            diagnostic
        };
        self.strict_or_warn(scope.file, diagnostic.with_code("unknown-node"));
    }

    /// A Webots node the catalogue keeps only for what it holds (`open`): said to be not
    /// simulated (an error in strict mode, as an unknown node is); at the top of a world, one
    /// that names a controller is a robot regatta does not build.
    fn unsimulated_node(
        &mut self,
        type_name: &syntax::Ident,
        items: &[BodyItem],
        place: &str,
        scope: &Scope,
    ) {
        let name = &type_name.text;
        let sets_controller = items
            .iter()
            .any(|item| matches!(item, BodyItem::Field(f) if f.name.text == "controller"));
        if place == "the world" && sets_controller {
            self.unbuilt_robots.push(UnbuiltRobot {
                type_name: name.clone(),
                url: None,
                file: scope.file,
                span: type_name.span,
            });
        }
        let mut diagnostic = Diagnostic::error(
            type_name.span,
            format!("'{name}' is read but not simulated by regatta"),
        )
        .with_label("not simulated")
        .with_code("unsimulated-node");
        if let Some(reason) = crate::webots::unsimulated(name) {
            diagnostic = diagnostic.with_note(format!("{name}: {reason}"));
        }
        self.strict_or_warn(
            scope.file,
            diagnostic
                .with_note("the shapes it holds are kept in place (the glTF export shows them)"),
        );
    }

    pub(super) fn lower_builtin(
        &mut self,
        spec_id: SpecId,
        node: &syntax::Node,
        items: &[BodyItem],
        scope: &mut Scope,
    ) -> Option<NodeId> {
        let catalogue = self.catalogue();
        let spec = catalogue.spec(spec_id);
        let mut fields = FieldsBuilder::new(spec_id, spec.fields.len());
        let mut written = Written::none(spec.fields.len());
        // Each url of a `file` field, with where it was written and the file it is relative to.
        let mut urls: Vec<(usize, String, FileId, Span)> = Vec::new();
        let mut seen: HashMap<&str, Span> = HashMap::new();
        for item in items {
            match item {
                BodyItem::Field(field) => {
                    if field.hidden {
                        continue;
                    }
                    let Some(index) = spec.field_index(&field.name.text) else {
                        // `set_children`, `translation_changed`: an exposedField's events take
                        // no value, and are IS'd only (where the PROTO's declaration was checked).
                        let event = implied_event(&field.name.text).filter(|(name, _)| {
                            spec.field_index(name).is_some_and(|i| matches!(spec.fields[i].access.as_deref(), None | Some("exposedField")))
                        });
                        if let Some((_, access)) = event {
                            if !matches!(field.value, syntax::FieldValue::Is(_)) {
                                self.strict_or_warn(scope.file, node_event_with_value(&field.name, access, &spec.name));
                            }
                            continue;
                        }
                        if spec.open {
                            // Read, not typed: DEFs inside are skipped, as an unknown node's.
                            skip_defs(&field.value, scope);
                            continue;
                        }
                        let mut diagnostic = Diagnostic::error(field.name.span, format!("{} '{}' field in {} node.", self.unknown(), field.name.text, spec.name))
                            .with_label("unknown field")
                            .with_code("unknown-field");
                        if let Some(close) = did_you_mean(&field.name.text, spec.fields.iter().map(|f| f.name.as_str())) {
                            diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                        }
                        self.strict_or_warn(scope.file, diagnostic);
                        continue;
                    };
                    if let Some(previous) = seen.insert(field.name.text.as_str(), field.name.span) {
                        self.error(
                            scope.file,
                            Diagnostic::warning(field.name.span, format!("'{}' is set twice; the last value is used", field.name.text))
                                .with_secondary(previous, "first set here")
                                .with_code("duplicate-field"),
                        );
                    }
                    let field_spec = &spec.fields[index];
                    // An event takes no value; IS joins it to an event of the PROTO (VRML97 4.8.3).
                    if let Some(access @ ("eventIn" | "eventOut")) = field_spec.access.as_deref() {
                        if !matches!(field.value, syntax::FieldValue::Is(_)) {
                            self.strict_or_warn(scope.file, node_event_with_value(&field.name, access, &spec.name));
                            continue;
                        }
                    }
                    let site = self.value_site(field, scope);
                    if let Some(value) = self.lower_field_value(&field.value, field_spec.ty(), Some(field_spec), scope, &field.name.text, field.name.span) {
                        if field_spec.file {
                            for (k, url) in value.strings().iter().enumerate() {
                                let span = site.1.get(k).copied().unwrap_or(site.2);
                                urls.push((index, url.clone(), site.0, span));
                            }
                        }
                        written.set(index);
                        // A value written here points at itself; one bound through IS at the
                        // instance that gave it.
                        let span = match &field.value {
                            syntax::FieldValue::Value(value) => value.span,
                            _ => site.2,
                        };
                        fields.set(index, value, Some(Origin { file: site.0, span }));
                    }
                }
                BodyItem::Declaration(declaration) => self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(declaration.span, "a field declaration belongs in a PROTO interface, not in a node")
                        .with_note("files like Webots' resources/nodes/*.wrl declare node models; they are not worlds")
                        .with_code("declaration-in-node"),
                ),
                BodyItem::Template(template) => self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(template.span, "template code is not evaluated by regatta").with_code("template"),
                ),
                BodyItem::Proto(proto) => self.error(
                    scope.file,
                    Diagnostic::warning(proto.name.span, "a PROTO inside a node is not visible outside it and is ignored").with_code("nested-proto"),
                ),
                BodyItem::Route(route) => self.route(route, scope),
            }
        }
        let origin = Origin {
            file: scope.file,
            span: node.span,
        };
        if spec.name == "Inline" {
            return self.inline(&urls, node, scope, origin);
        }
        // Meshes and images are read for the exporters (the first url that can be); other
        // files are named, not read: each must still lie inside the root.
        let reads = super::assets::reads_asset(&spec.name);
        let mut asset = None;
        for (_, url, file, span) in &urls {
            match self.resolve_url(*file, url) {
                Ok(path) if reads && asset.is_none() => {
                    asset = self.read_asset(&path, url, *file, *span);
                }
                Ok(_) => {}
                Err(refusal) => {
                    let user = if reads {
                        UrlUse::Asset(&spec.name)
                    } else {
                        UrlUse::Image(&spec.name)
                    };
                    self.refuse(*file, *span, url, refusal, user);
                }
            }
        }
        let fields = fields.finish(origin, &mut self.shared_fields);
        let id = self.alloc(
            SceneNode {
                spec: spec_id,
                fields,
                written,
                names: None,
                origin,
                axes: Default::default(),
            },
            scope.file,
            node.span,
        )?;
        if let Some(mut asset) = asset {
            asset.node = id;
            self.assets.push(asset);
        }
        Some(id)
    }

    /// Where a field's value was written: the file, each string's span, and the field's span.
    /// A value passed in through IS points at the instance that passed it.
    pub(super) fn value_site(
        &self,
        field: &syntax::Field,
        scope: &Scope,
    ) -> (FileId, Vec<Span>, Span) {
        if let (syntax::FieldValue::Is(target), Some(interface)) = (&field.value, &scope.interface)
        {
            if let Some(binding) = interface.get(&target.text) {
                if let Some(site) = &binding.site {
                    return site.clone();
                }
            }
            // A default: the user's instance is where it came from, unless this PROTO is
            // the user's own (then its line is).
            if self.is_builtin(scope.file) {
                if let Some((file, span)) = self.user_instance() {
                    return (file, Vec::new(), span);
                }
            }
            return (scope.file, Vec::new(), field.span);
        }
        (scope.file, string_spans(&field.value), field.span)
    }
}

/// The span of each string of a written value.
fn string_spans(value: &syntax::FieldValue) -> Vec<Span> {
    match value {
        syntax::FieldValue::Value(syntax::Value {
            items: Items::Atoms(atoms),
            ..
        }) => atoms
            .iter()
            .filter_map(|a| match a {
                Atom::String(s) => Some(s.span),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
}

/// Records the DEFs of the nodes inside a value that is not typed, so that a USE of them says
/// they were skipped.
fn skip_defs(value: &syntax::FieldValue, scope: &mut Scope) {
    if let syntax::FieldValue::Value(syntax::Value {
        items: Items::Atoms(atoms),
        ..
    }) = value
    {
        for atom in atoms {
            if let Atom::Node(child) = atom {
                syntax::walk_node(child, &mut |inner| {
                    if let Some(def) = &inner.def {
                        scope.skipped_defs.insert(def.text.clone());
                    }
                });
            }
        }
    }
}
