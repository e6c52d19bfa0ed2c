//! The end of a check: the whole-scene checks made once every node is typed (size, unique
//! robot names), diagnostics in their stable order, each node's axes, and the [`Checked`]
//! result.

use std::collections::HashMap;

use regatta_parser::Diagnostic;

use crate::scene::{NodeId, Scene};
use crate::value::Value;

use super::checked::{Checked, FileDiagnostic};
use super::state::Lowerer;

impl<'c> Lowerer<'c> {
    pub(super) fn finish(mut self) -> Checked {
        self.check_expanded_size();
        self.check_robot_names();
        let refined = std::mem::take(&mut self.refined_missing);
        let mut diagnostics: Vec<FileDiagnostic> = self
            .parse_diagnostics
            .drain(..)
            .filter(|d| {
                !(d.diagnostic.code == "missing-value"
                    && refined.contains(&(d.file.0, d.diagnostic.span.start)))
            })
            .collect();
        diagnostics.append(&mut self.diagnostics);
        // Stable order: by file, then position, then message; one message per place.
        diagnostics.sort_by(|a, b| {
            (a.file.0, a.diagnostic.span.start, &a.diagnostic.message).cmp(&(
                b.file.0,
                b.diagnostic.span.start,
                &b.diagnostic.message,
            ))
        });
        diagnostics.dedup_by(|a, b| {
            a.file == b.file
                && a.diagnostic.span == b.diagnostic.span
                && a.diagnostic.message == b.diagnostic.message
        });
        if self.dropped > 0 {
            if let Some(last) = diagnostics.last().cloned() {
                diagnostics.push(FileDiagnostic {
                    file: last.file,
                    diagnostic: Diagnostic::error(
                        last.diagnostic.span,
                        format!("too many problems: {} more were not reported", self.dropped),
                    )
                    .with_code("too-many"),
                });
            }
        }
        for (index, node) in self.nodes.iter_mut().enumerate() {
            let body = match self.body_authoring.get(&(index as u32)) {
                Some(&body) => body,
                None => self
                    .file_authoring
                    .get(&node.origin.file.0)
                    .copied()
                    .unwrap_or_default(),
            };
            let own = self
                .instance_authoring
                .get(&(index as u32))
                .copied()
                .unwrap_or(body);
            node.axes = crate::webots::Axes { own, body };
        }
        // The scene lives on through compilation: no spare room.
        self.nodes.shrink_to_fit();
        let scene = Scene {
            nodes: self.nodes,
            roots: self.roots,
            files: self.sources.iter().map(|s| s.name.clone()).collect(),
            up_axis: self.up_axis,
            objects: self.objects,
            assets: std::mem::take(&mut self.assets),
        };
        Checked {
            strict: self.options.strict,
            scene,
            diagnostics,
            sources: self.sources,
            substitutions: self.substitutions,
            unbuilt_robots: self.unbuilt_robots,
        }
    }

    /// A robot's name identifies it in logs, CSV and plots: a second robot with a name already
    /// taken is an error at its line; lenient mode renames it and says to what.
    pub(super) fn check_robot_names(&mut self) {
        if self.limits_reported.contains("nodes") {
            return;
        }
        let catalogue = self.catalogue();
        let scene = Scene {
            nodes: std::mem::take(&mut self.nodes),
            roots: self.roots.clone(),
            files: Vec::new(),
            up_axis: self.up_axis,
            objects: self.objects,
            assets: Vec::new(),
        };
        let robots: Vec<NodeId> = scene
            .walk()
            .into_iter()
            .filter(|&id| {
                catalogue
                    .spec(scene.node(id).spec)
                    .classes
                    .iter()
                    .any(|c| c == "robot")
            })
            .collect();
        self.nodes = scene.nodes;
        let mut taken: HashMap<String, NodeId> = HashMap::new();
        let mut renames = Vec::new();
        for &id in &robots {
            let spec = catalogue.spec(self.nodes[id.index()].spec);
            let Some(index) = spec.field_index("name") else {
                continue;
            };
            let name = self.nodes[id.index()].fields[index]
                .strings()
                .first()
                .cloned()
                .unwrap_or_default();
            match taken.get(&name) {
                None => {
                    taken.insert(name, id);
                }
                Some(&first) => renames.push((id, index, name, first)),
            }
        }
        for (id, index, name, first) in renames {
            let node = &self.nodes[id.index()];
            let at = node.value_span_at(index).unwrap_or(node.origin);
            let first_node = &self.nodes[first.index()];
            let first_at = first_node.value_span_at(index).unwrap_or(first_node.origin);
            let mut diagnostic = Diagnostic::error(
                at.span,
                format!("a robot named '{name}' already exists: robot names must be unique"),
            )
            .with_label("second robot with this name")
            .with_code("duplicate-robot");
            if first_at.file == at.file {
                diagnostic = diagnostic.with_secondary(first_at.span, "first named here");
            } else {
                diagnostic = diagnostic.with_secondary_in(
                    first_at.file.0 as usize,
                    first_at.span,
                    "first named here",
                );
            }
            let new_name = (2..)
                .map(|k| format!("{name}_{k}"))
                .find(|candidate| !taken.contains_key(candidate))
                .unwrap_or_default();
            if self.options.strict {
                self.error(
                    at.file,
                    diagnostic
                        .with_note("logs, CSV and plots tell robots apart by name")
                        .with_note(format!("give it a name of its own: name \"{new_name}\"")),
                );
                continue;
            }
            taken.insert(new_name.clone(), id);
            diagnostic.severity = regatta_parser::Severity::Warning;
            self.error(
                at.file,
                diagnostic.with_note(format!("renamed to '{new_name}'")),
            );
            self.nodes[id.index()].fields[index] = Value::String(new_name);
        }
    }
}
