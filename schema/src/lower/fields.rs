//! Field values: IS (type, access, node classes and allowed values checked at the IS), a
//! written value typed against its field ([`Typing`] for numbers, bools and strings; nodes
//! here), the parser's "missing value" made precise, and the catalogue's ranges.

use regatta_parser::syntax::{self, Atom, Items};
use regatta_parser::{Diagnostic, Span};

use crate::catalogue::FieldSpec;
use crate::scene::FileId;
use crate::typing::{self, Literal, Typing};
use crate::value::{BaseType, FieldType, Value};

use super::events::{is_access_mismatch, is_compatible, is_type_mismatch, unknown_is};
use super::state::{Lowerer, Scope};

impl<'c> Lowerer<'c> {
    /// Types one field value against `ty`; `spec` adds the catalogue's range checks.
    pub(super) fn lower_field_value(
        &mut self,
        value: &syntax::FieldValue,
        ty: FieldType,
        spec: Option<&FieldSpec>,
        scope: &mut Scope,
        field_name: &str,
        field_span: Span,
    ) -> Option<Value> {
        let file = scope.file;
        match value {
            syntax::FieldValue::Missing { found } => {
                let text = &self.sources[file.0 as usize].text;
                let found_text = if (found.start as usize) < text.len() && !found.is_empty() {
                    text[found.range()].to_owned()
                } else {
                    String::new()
                };
                let bare_word = !found_text.is_empty()
                    && found_text
                        .chars()
                        .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-'));
                let shown = if found_text.is_empty() {
                    "end of file".to_owned()
                } else {
                    format!("'{}'", typing::shorten(&found_text))
                };
                self.refined_missing.insert((file.0, field_span.start));
                self.refined_missing.insert((file.0, found.start));
                let diagnostic = if ty.base == BaseType::String && bare_word {
                    Diagnostic::error(
                        *found,
                        format!(
                            "Expected {}, found {shown}: strings are quoted.",
                            ty.base.item_noun()
                        ),
                    )
                    .with_label("this word needs quotes")
                    .with_note(format!("write: {field_name} \"{found_text}\""))
                } else {
                    Diagnostic::error(
                        field_span,
                        format!("Expected {}, found {shown}.", ty.base.item_noun()),
                    )
                    .with_label(format!("'{field_name}' needs a {ty} value"))
                    .with_secondary(*found, "found this instead")
                };
                self.error(file, diagnostic.with_code("missing-value"));
                None
            }
            syntax::FieldValue::Is(target) => {
                let Some(interface) = scope.interface.clone() else {
                    self.error(
                        file,
                        Diagnostic::error(target.span, "IS may only be used inside a PROTO body")
                            .with_code("is-outside-proto"),
                    );
                    return None;
                };
                let Some(binding) = interface.get(&target.text) else {
                    self.error(file, unknown_is(target));
                    return None;
                };
                if binding.ty != ty {
                    self.error(file, is_type_mismatch(target, binding.ty, field_name, ty));
                    return None;
                }
                if let Some(access) = spec.and_then(|s| s.access.as_deref()) {
                    if !is_compatible(&binding.keyword, access) {
                        self.strict_or_warn(
                            file,
                            is_access_mismatch(target, &binding.keyword, field_name, access),
                        );
                        return None;
                    }
                }
                let value = binding.value.clone()?;
                let Some(spec) = spec else {
                    return Some(value);
                };
                // A value an instance passed in is blamed where the instance wrote it, with
                // this IS beside it; the field keeps its default.
                let (blamed_file, blamed_span) = binding
                    .site
                    .as_ref()
                    .map(|(f, _, s)| (*f, *s))
                    .unwrap_or((file, target.span));
                if !spec.nodes.is_empty() {
                    for &child in value.nodes() {
                        let child_spec = self.catalogue().spec(self.nodes[child.index()].spec);
                        if !child_spec.fits(&spec.nodes) {
                            let mut diagnostic = self.wrong_class(
                                child_spec,
                                &spec.nodes,
                                &format!("'{}'", target.text),
                                blamed_span,
                            );
                            if blamed_file != file {
                                diagnostic = diagnostic.with_secondary_in(
                                    file.0 as usize,
                                    target.span,
                                    format!(
                                        "PROTO '{}' passes it to '{field_name}' here",
                                        self.frames.last().map_or("", |f| f.name.as_str())
                                    ),
                                );
                            }
                            self.strict_or_warn(blamed_file, diagnostic);
                            return None;
                        }
                    }
                }
                if let Some(mut diagnostic) = value
                    .strings()
                    .iter()
                    .find_map(|s| spec.disallowed(s, blamed_span, field_name))
                {
                    if blamed_file != file {
                        diagnostic = diagnostic.with_secondary_in(
                            file.0 as usize,
                            target.span,
                            format!("'{}' goes to '{field_name}' here", target.text),
                        );
                    }
                    self.error(blamed_file, diagnostic);
                    return None;
                }
                if !self.check_ranges(&value, spec, blamed_file, blamed_span) {
                    return None;
                }
                Some(value)
            }
            syntax::FieldValue::Value(value) => {
                // A template over the instance's fields: what goes wrong with its result is
                // the instance's value's doing.
                let blame = self.template_blame(value, scope);
                let saved = match blame {
                    Some(_) => std::mem::replace(&mut self.blame, blame),
                    None => self.blame,
                };
                let typed = self.lower_value(value, ty, spec, scope, field_name);
                let typed = match (typed, spec) {
                    (Some(typed), Some(spec)) => self
                        .check_ranges(&typed, spec, file, value.span)
                        .then_some(typed),
                    (typed, _) => typed,
                };
                self.blame = saved;
                typed
            }
        }
    }

    pub(super) fn lower_value(
        &mut self,
        value: &syntax::Value,
        ty: FieldType,
        spec: Option<&FieldSpec>,
        scope: &mut Scope,
        field_name: &str,
    ) -> Option<Value> {
        let file = scope.file;
        if let Some(diagnostic) = typing::bracketed(value, ty) {
            self.error(file, diagnostic);
            return None;
        }
        let expanded;
        let value = if let Items::Atoms(atoms) = &value.items {
            if atoms.iter().any(|a| matches!(a, Atom::Template(_))) {
                expanded = self.expand_templates(value, atoms, scope)?;
                &expanded
            } else {
                value
            }
        } else {
            value
        };
        let disallowed = |s: &syntax::StringLit| {
            spec.and_then(|spec| spec.disallowed(&s.value, s.span, field_name))
        };
        let typing = Typing {
            text: &self.sources[file.0 as usize].text,
            ty,
            field_name,
            strict: self.options.strict,
            disallowed: &disallowed,
        };
        let mut problems = Vec::new();
        let typed = typing.literal(value, &mut problems);
        for problem in problems {
            self.error(file, problem);
        }
        let atoms = match typed? {
            Literal::Value(value) => return Some(value),
            Literal::Nodes(atoms) => atoms,
        };
        let mut accepted: Vec<String> = spec.map(|s| s.nodes.clone()).unwrap_or_default();
        // Webots places a bounding object's primitives straight in its Pose, Transform or
        // Group (`children [ USE BODY ]`, BODY a Cylinder): geometry stands in children there.
        if self.in_bounding_object > 0 && field_name == "children" {
            accepted.push("geometry".to_owned());
        }
        let place = format!("'{field_name}'");
        let wrong = |lowerer: &mut Self, atom: &Atom| {
            let typing = Typing {
                text: &lowerer.sources[file.0 as usize].text,
                ty,
                field_name,
                strict: lowerer.options.strict,
                disallowed: &disallowed,
            };
            let diagnostic = typing.wrong(atom);
            lowerer.error(file, diagnostic);
        };
        if !ty.multi {
            return match &atoms[0] {
                Atom::Null(_) => Some(Value::Node(None)),
                Atom::Node(node) => {
                    let bounding = field_name == "boundingObject";
                    self.in_bounding_object += usize::from(bounding);
                    let id = self.lower_node(node, scope, &accepted, &place);
                    self.in_bounding_object -= usize::from(bounding);
                    Some(Value::Node(id))
                }
                other => {
                    wrong(self, other);
                    None
                }
            };
        }
        let mut ids = Vec::with_capacity(atoms.len());
        for atom in atoms {
            match atom {
                Atom::Node(node) => {
                    if let Some(id) = self.lower_node(node, scope, &accepted, &place) {
                        ids.push(id);
                    }
                }
                Atom::Null(span) => self.error(
                    file,
                    Diagnostic::warning(
                        *span,
                        format!("NULL in the MFNode field '{field_name}' is skipped"),
                    )
                    .with_code("null-in-mfnode"),
                ),
                other => {
                    wrong(self, other);
                    return None;
                }
            }
        }
        Some(Value::Nodes(ids))
    }

    /// Checks min/max/above/count of a catalogue field; false (after reporting) if violated.
    pub(super) fn check_ranges(
        &mut self,
        value: &Value,
        spec: &FieldSpec,
        file: FileId,
        span: Span,
    ) -> bool {
        match spec.out_of_range(value, span) {
            Some(diagnostic) => {
                self.error(file, diagnostic);
                false
            }
            None => true,
        }
    }
}
