//! ROUTEs, checked as VRML97 says (both ends DEF'd, event access, one type) and reported as
//! read but not simulated. The checks of an end and of the two ends' types are shared with
//! the check of a PROTO declaration (`declared.rs`), which knows its body's nodes by syntax.

use regatta_parser::syntax::{self};
use regatta_parser::Diagnostic;

use crate::catalogue::did_you_mean;
use crate::scene::FileId;
use crate::value::FieldType;

use super::events::{interface_ends, spec_ends, with_article, Ends};
use super::state::{Lowerer, Scope};

impl<'c> Lowerer<'c> {
    /// Checks a ROUTE as VRML97 does (4.10): both nodes DEF'd before it, the source an
    /// eventOut or exposedField, the target an eventIn or exposedField, the same type at both
    /// ends. Nothing is simulated: regatta has no event model, and says so for a sound ROUTE.
    pub(super) fn route(&mut self, route: &syntax::Route, scope: &mut Scope) {
        let from = self.route_end(&route.from_node, &route.from_field, true, scope);
        let to = self.route_end(&route.to_node, &route.to_field, false, scope);
        if self.route_types(route, scope.file, from, to) {
            self.error(
                scope.file,
                Diagnostic::warning(
                    route.span,
                    "ROUTEs are read but not simulated: regatta has no event model",
                )
                .with_code("route"),
            );
        }
    }

    /// Whether both ends are known and of one type (after reporting when they are not).
    pub(super) fn route_types(
        &mut self,
        route: &syntax::Route,
        file: FileId,
        from: Option<FieldType>,
        to: Option<FieldType>,
    ) -> bool {
        let (Some(from), Some(to)) = (from, to) else {
            return false;
        };
        if from != to {
            self.strict_or_warn(
                file,
                Diagnostic::error(
                    route.span,
                    format!("ROUTE from {from} to {to}: both ends must have the same type"),
                )
                .with_secondary(route.from_field.span, format!("{from}"))
                .with_secondary(route.to_field.span, format!("{to}"))
                .with_code("route-type"),
            );
            return false;
        }
        true
    }

    /// The type of one end of a ROUTE, after reporting what is wrong with it.
    pub(super) fn route_end(
        &mut self,
        node: &syntax::Ident,
        field: &syntax::Ident,
        source: bool,
        scope: &Scope,
    ) -> Option<FieldType> {
        let Some(&id) = scope.defs.get(&node.text) else {
            if !scope.skipped_defs.contains(&node.text) {
                self.route_without_node(node, scope.file);
            }
            return None;
        };
        // Every event and field the node has: (name, type, access).
        let (node_type, ends) = match self.instance_of.get(&id).cloned() {
            Some(def) => (
                format!("PROTO '{}'", def.proto.name.text),
                interface_ends(&def.proto.interface),
            ),
            None => {
                let spec = self.catalogue().spec(self.nodes[id.index()].spec);
                (format!("{} node", spec.name), spec_ends(spec))
            }
        };
        self.route_end_in(node, field, source, scope.file, &node_type, &ends)
    }

    /// A ROUTE's end names no node DEF'd before it.
    pub(super) fn route_without_node(&mut self, node: &syntax::Ident, file: FileId) {
        let diagnostic = Diagnostic::error(
            node.span,
            format!("no node was DEF'd as '{}' before this ROUTE", node.text),
        )
        .with_code("route-node");
        self.strict_or_warn(file, diagnostic);
    }

    /// The type of one end of a ROUTE at a node of type `node_type` with events and fields
    /// `ends`, after reporting an end it does not have or that cannot send (`source`) or
    /// receive events.
    pub(super) fn route_end_in(
        &mut self,
        node: &syntax::Ident,
        field: &syntax::Ident,
        source: bool,
        file: FileId,
        node_type: &str,
        ends: &Ends,
    ) -> Option<FieldType> {
        let wanted = if source { "eventOut" } else { "eventIn" };
        let name = field.text.as_str();
        let mut found = None;
        for (end, ty, access) in ends {
            let matches = if access == "exposedField" {
                end == name
                    || (source && name.strip_suffix("_changed") == Some(end.as_str()))
                    || (!source && name.strip_prefix("set_") == Some(end.as_str()))
            } else {
                end == name
            };
            if matches {
                found = Some((*ty, access.clone()));
                break;
            }
        }
        let Some((ty, access)) = found else {
            let mut diagnostic = Diagnostic::error(
                field.span,
                format!("the {node_type} '{}' has no {wanted} '{name}'", node.text),
            )
            .with_code("route-field");
            if let Some(close) = did_you_mean(name, ends.iter().map(|(n, _, _)| n.as_str())) {
                diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
            }
            self.strict_or_warn(file, diagnostic);
            return None;
        };
        if access != "exposedField" && access != wanted {
            let role = if source { "send" } else { "receive" };
            self.strict_or_warn(
                file,
                Diagnostic::error(
                    field.span,
                    format!("'{name}' of '{}' is {}: it cannot {role} events", node.text, with_article(&access)),
                )
                .with_label(if source {
                    "a ROUTE starts at an eventOut or exposedField"
                } else {
                    "a ROUTE ends at an eventIn or exposedField"
                })
                .with_note("VRML97 4.10: a ROUTE goes from an eventOut (or exposedField) to an eventIn (or exposedField)")
                .with_code("route-access"),
            );
            return None;
        }
        Some(ty)
    }
}
