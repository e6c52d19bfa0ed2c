//! Template PROTOs: arithmetic expressions over fields (`%<= … >%`) evaluated in place
//! without an engine, JavaScript templates run through `regatta_template` for each instance
//! (cached per PROTO and field values), and the instance field a template's result blames.

use std::collections::BTreeSet;
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, Span};

use crate::binding::Bindings;
use crate::scene::{FileId, UpAxis};

use super::state::{Lowerer, ProtoDef, Scope, UrlBase};

impl<'c> Lowerer<'c> {
    /// Whether a PROTO's templates need the JavaScript engine: some template block of its
    /// content is not an arithmetic expression in a field value that regatta evaluates itself.
    pub(super) fn needs_engine(&self, def: &ProtoDef, bindings: &Bindings) -> bool {
        let text = &self.sources[def.file.0 as usize].text;
        let Some(content) = crate::procedural::content_range(text, def.proto.span.range()) else {
            return false;
        };
        let blocks = match regatta_template::blocks(&text[content.clone()]) {
            Ok(blocks) if blocks.is_empty() => return false,
            Ok(blocks) => blocks,
            Err(_) => return true,
        };
        let mut arithmetic = BTreeSet::new();
        fn walk(
            node: &syntax::Node,
            text: &str,
            bindings: &Bindings,
            arithmetic: &mut BTreeSet<usize>,
        ) {
            let NodeKind::Instance {
                body: Some(body), ..
            } = &node.kind
            else {
                return;
            };
            for item in &body.items {
                let BodyItem::Field(field) = item else {
                    continue;
                };
                let syntax::FieldValue::Value(syntax::Value {
                    items: Items::Atoms(atoms),
                    ..
                }) = &field.value
                else {
                    continue;
                };
                for atom in atoms {
                    match atom {
                        Atom::Template(t)
                            if t.expression
                                && crate::template::evaluate(&text[t.span.range()], bindings)
                                    .is_ok() =>
                        {
                            arithmetic.insert(t.span.start as usize);
                        }
                        Atom::Node(child) => walk(child, text, bindings, arithmetic),
                        _ => {}
                    }
                }
            }
        }
        for item in &def.proto.body {
            if let Item::Node(node) = item {
                walk(node, text, bindings, &mut arithmetic);
            }
        }
        blocks
            .iter()
            .any(|block| !arithmetic.contains(&(content.start + block.start)))
    }

    /// Runs a PROTO's JavaScript template for one instance and returns the PROTO as its
    /// template generated it (a file of its own, so that messages about the generated text
    /// show it). `None` after reporting a template that failed; the instance is skipped.
    pub(super) fn expand_template(
        &mut self,
        def: &Rc<ProtoDef>,
        bindings: &Bindings,
        node: &syntax::Node,
        scope: &mut Scope,
    ) -> Option<Rc<ProtoDef>> {
        let proto = &def.proto;
        let name = proto.name.text.clone();
        let source = self.sources[def.file.0 as usize].clone();
        let Some(content) = crate::procedural::content_range(&source.text, proto.span.range())
        else {
            self.strict_or_warn(
                def.file,
                Diagnostic::error(
                    proto.name.span,
                    format!("PROTO '{name}': cannot find the body its template is in"),
                )
                .with_code("template"),
            );
            return None;
        };
        // Field values and defaults, in Webots' JavaScript shapes.
        let mut default_scope = Scope {
            protos: self.visible_protos(def),
            ..Scope::new(def.file)
        };
        let mut pairs = Vec::new();
        for declaration in &proto.interface {
            let Some(binding) = bindings.get(&declaration.name.text).cloned() else {
                continue;
            };
            let (ty, value, origin) = (binding.ty, binding.value, binding.site);
            let default = match origin {
                None => value.clone(),
                Some(_) => self.lower_default(declaration, ty, &mut default_scope),
            };
            pairs.push((declaration.name.text.clone(), ty, value, default));
        }
        let mut fields = serde_json::Map::new();
        let mut given = crate::procedural::FieldsJson::new(&self.nodes, self.catalogue());
        for (field, ty, value, default) in &pairs {
            fields.insert(
                field.clone(),
                given.field(*ty, value.as_ref(), default.as_ref()),
            );
        }
        let fields = serde_json::Value::Object(fields);
        self.template_instances += 1;
        let id = self.template_instances;
        let non_deterministic = crate::procedural::is_non_deterministic(&source.text);
        let key = format!(
            "{}:{}:{}:{}",
            def.file.0,
            proto.span.start,
            if non_deterministic { id } else { 0 },
            fields
        );
        if let Some(expanded) = self.expanded.get(&key) {
            return expanded.clone();
        }
        let coordinate_system = match self.up_axis {
            UpAxis::Y => "NUE",
            UpAxis::Z => "ENU",
        };
        let context = crate::procedural::context(
            &self.sources[0].name,
            &source.name,
            id,
            coordinate_system,
            &self.webots_version,
        );
        let seed = crate::procedural::seed(self.world_seed, if non_deterministic { id } else { 0 });
        let engine = match &self.engine {
            Some(engine) => engine,
            None => match regatta_template::Engine::new(regatta_template::Limits::default()) {
                Ok(engine) => self.engine.insert(engine),
                Err(error) => {
                    self.error(
                        scope.file,
                        Diagnostic::error(node.span, error.message).with_code("template"),
                    );
                    return None;
                }
            },
        };
        let request = regatta_template::Request {
            content: &source.text[content.clone()],
            name: &source.name,
            fields: &fields,
            context: &context,
            seed,
        };
        let expanded = match engine.expand(&request) {
            Ok(generated) => {
                for line in generated.console.iter().filter(|l| l.warning) {
                    self.error(
                        scope.file,
                        Diagnostic::warning(
                            node.span,
                            format!("PROTO '{name}' template: {}", line.text),
                        )
                        .with_label("printed while this instance was generated")
                        .with_code("template-console"),
                    );
                }
                let mut text = String::with_capacity(source.text.len() + generated.text.len());
                text.push_str(&source.text[..content.start]);
                text.push_str(&generated.text);
                text.push_str(&source.text[content.end..]);
                // Urls in the generated text resolve as in the PROTO's own file.
                let base = self
                    .file_bases
                    .get(def.file.0 as usize)
                    .cloned()
                    .unwrap_or(UrlBase::NoFiles);
                let file = self.add_text(&format!("{} (generated)", source.name), &text, base);
                if let Some(authoring) = self.file_authoring.get(&def.file.0).copied() {
                    self.file_authoring.insert(file.0, authoring);
                }
                if let Some(table) = self.file_scopes.get(&def.file.0).cloned() {
                    self.file_scopes.insert(file.0, table);
                }
                let parsed = self.parse(file);
                let found = parsed.items.iter().find_map(|item| match item {
                    Item::Proto(p) if p.span.start == proto.span.start && p.name.text == name => {
                        Some(p.clone())
                    }
                    _ => None,
                });
                if found.is_none() {
                    self.strict_or_warn(
                        file,
                        Diagnostic::error(
                            proto.name.span,
                            format!("PROTO '{name}': the text its template generated is not a PROTO body"),
                        )
                        .with_code("template"),
                    );
                }
                found.map(|generated| {
                    Rc::new(ProtoDef {
                        file,
                        proto: generated,
                        enclosing: def.enclosing.clone(),
                    })
                })
            }
            Err(error) => {
                let (instance_line, instance_column) = regatta_parser::diagnostic::line_col(
                    &self.sources[scope.file.0 as usize].text,
                    node.span.start as usize,
                );
                let span = match error.offset {
                    Some(offset) => {
                        let at = content.start + offset;
                        let end = source.text[at..]
                            .char_indices()
                            .nth(1)
                            .map_or(source.text.len(), |(next, _)| at + next);
                        Span::new(at, end)
                    }
                    None => proto.name.span,
                };
                self.strict_or_warn(
                    def.file,
                    Diagnostic::error(span, format!("PROTO '{name}' template: {}", error.message))
                        .with_label("in this template")
                        .with_note(format!(
                            "while generating the instance at {}:{instance_line}:{instance_column}, which is skipped",
                            self.sources[scope.file.0 as usize].name
                        ))
                        .with_code("template"),
                );
                None
            }
        };
        self.expanded.insert(key, expanded.clone());
        expanded
    }

    /// Where the user wrote the first instance field that a template of `value` reads.
    pub(super) fn template_blame(
        &self,
        value: &syntax::Value,
        scope: &Scope,
    ) -> Option<(FileId, Span)> {
        let (Items::Atoms(atoms), Some(interface)) = (&value.items, &scope.interface) else {
            return None;
        };
        let text = &self.sources[scope.file.0 as usize].text;
        atoms.iter().find_map(|atom| {
            let Atom::Template(template) = atom else {
                return None;
            };
            let code = text.get(template.span.range())?;
            code.split("fields.").skip(1).find_map(|rest| {
                let name = rest.split('.').next()?;
                let (file, _, span) = interface.get(name)?.site.as_ref()?;
                Some((*file, *span))
            })
        })
    }

    /// Replaces expression templates by the numbers they evaluate to (inside PROTO bodies).
    pub(super) fn expand_templates(
        &mut self,
        value: &syntax::Value,
        atoms: &[Atom],
        scope: &Scope,
    ) -> Option<syntax::Value> {
        let file = scope.file;
        let mut out = Vec::with_capacity(atoms.len());
        for atom in atoms {
            let Atom::Template(template) = atom else {
                out.push(atom.clone());
                continue;
            };
            let text = self.sources[file.0 as usize].text[template.span.range()].to_owned();
            let result = match (&scope.interface, template.expression) {
                (Some(fields), true) => crate::template::evaluate(&text, fields),
                (None, _) => Err("template code outside a PROTO body is not evaluated".to_owned()),
                (_, false) => Err("template statements are not evaluated by regatta; only arithmetic expressions (%<= … >%) are".to_owned()),
            };
            match result {
                Ok(crate::template::Evaluated::Number(x)) => {
                    out.push(Atom::Number(syntax::Number {
                        span: template.span,
                        value: x,
                        hex: false,
                    }))
                }
                Ok(crate::template::Evaluated::Vector(v)) => out.extend(v.into_iter().map(|x| {
                    Atom::Number(syntax::Number {
                        span: template.span,
                        value: x,
                        hex: false,
                    })
                })),
                Err(message) => {
                    self.strict_or_warn(
                        file,
                        Diagnostic::error(template.span, message)
                            .with_label("this template")
                            .with_code("template"),
                    );
                    return None;
                }
            }
        }
        Some(syntax::Value {
            span: value.span,
            bracketed: value.bracketed,
            items: Items::Atoms(out),
        })
    }
}
