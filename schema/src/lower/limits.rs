//! The node and nesting limits: a PROTO's expansion estimated (and refused) before it is
//! built, the node-count message, and the expanded scene's size and depth through USE
//! checked once typing is done.

use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, Span};

use crate::scene::FileId;

use super::state::{Lowerer, ProtoDef, ProtoTable};

impl<'c> Lowerer<'c> {
    /// The scene grew past the node limit (or would, by `estimate`).
    pub(super) fn nodes_limit(&mut self, file: FileId, span: Span, estimate: Option<(&str, u64)>) {
        let limit = self.options.limits.nodes;
        let message = match estimate {
            Some((name, nodes)) => format!(
                "PROTO '{name}' expands to {} nodes, more than the limit of {limit}",
                if nodes == u64::MAX {
                    "more than 18446744073709551615".to_owned()
                } else {
                    nodes.to_string()
                }
            ),
            None => format!("the scene expands to more than {limit} nodes"),
        };
        self.limit_crossed(
            "nodes",
            file,
            Diagnostic::error(span, message)
                .with_label("expansion stopped here")
                .with_note(
                    "PROTOs or USEs multiply each other; check for accidental exponential nesting",
                ),
        );
    }

    /// At most how many nodes an instance of `def` makes (saturating): the nodes of its body
    /// and defaults, each PROTO instance in them counted by its own estimate. USE adds none.
    pub(super) fn estimate(&mut self, def: &Rc<ProtoDef>, depth: usize) -> u64 {
        let key = (def.file.0, def.proto.span.start);
        if let Some(&known) = self.estimates.get(&key) {
            return known;
        }
        if depth > self.options.limits.proto_depth {
            // Deeper than allowed: expansion stops there anyway, with its own message.
            return 1;
        }
        // A PROTO that contains itself is reported as recursion; count it once meanwhile.
        self.estimates.insert(key, 1);
        let visible = self.visible_protos(def);
        let mut nested: Vec<(String, Rc<ProtoDef>)> = Vec::new();
        let mut total = 0u64;
        for declaration in &def.proto.interface {
            if let Some(syntax::FieldValue::Value(value)) = &declaration.default {
                total = total.saturating_add(self.estimate_value(value, &visible, &nested, depth));
            }
        }
        for item in &def.proto.body {
            match item {
                Item::Proto(proto) => nested.push((
                    proto.name.text.clone(),
                    Rc::new(ProtoDef {
                        file: def.file,
                        proto: proto.clone(),
                        enclosing: def.enclosing.clone(),
                    }),
                )),
                Item::Node(node) => {
                    total =
                        total.saturating_add(self.estimate_node(node, &visible, &nested, depth));
                }
                _ => {}
            }
        }
        self.estimates.insert(key, total.max(1));
        total.max(1)
    }

    pub(super) fn estimate_node(
        &mut self,
        node: &syntax::Node,
        visible: &ProtoTable,
        nested: &[(String, Rc<ProtoDef>)],
        depth: usize,
    ) -> u64 {
        let NodeKind::Instance { type_name, body } = &node.kind else {
            return 0;
        };
        let proto = nested
            .iter()
            .rev()
            .chain(visible.iter().rev())
            .find(|(n, _)| *n == type_name.text)
            .map(|(_, p)| p.clone());
        let mut total = match proto {
            Some(proto) => self.estimate(&proto, depth + 1),
            None => 1,
        };
        if let Some(body) = body {
            for item in &body.items {
                if let BodyItem::Field(syntax::Field {
                    value: syntax::FieldValue::Value(value),
                    ..
                }) = item
                {
                    total =
                        total.saturating_add(self.estimate_value(value, visible, nested, depth));
                }
            }
        }
        total
    }

    pub(super) fn estimate_value(
        &mut self,
        value: &syntax::Value,
        visible: &ProtoTable,
        nested: &[(String, Rc<ProtoDef>)],
        depth: usize,
    ) -> u64 {
        let Items::Atoms(atoms) = &value.items else {
            return 0;
        };
        let mut total = 0u64;
        for atom in atoms {
            if let Atom::Node(node) = atom {
                total = total.saturating_add(self.estimate_node(node, visible, nested, depth));
            }
        }
        total
    }

    /// USE shares nodes, so the scene is a DAG whose expanded tree may be exponentially larger
    /// than the file: its size and depth are bounded here, at the first node that crosses
    /// either bound (node ids are a topological order: children are made first).
    pub(super) fn check_expanded_size(&mut self) {
        if self.limits_reported.contains("nodes") {
            return;
        }
        let limit = self.options.limits.nodes as u64;
        let depth_limit = self.options.limits.scene_depth() as u32;
        let mut sizes = vec![0u64; self.nodes.len()];
        let mut depths = vec![0u32; self.nodes.len()];
        for index in 0..self.nodes.len() {
            let (mut size, mut depth) = (1u64, 1u32);
            for value in self.nodes[index].fields.own() {
                for child in value.nodes() {
                    size = size.saturating_add(sizes[child.index()]);
                    depth = depth.max(depths[child.index()].saturating_add(1));
                }
            }
            sizes[index] = size;
            depths[index] = depth;
            let origin = self.nodes[index].origin;
            if size > limit {
                self.nodes_limit(origin.file, origin.span, None);
                return;
            }
            if depth > depth_limit && !self.limits_reported.contains("nesting") {
                self.limit_crossed(
                    "nesting",
                    origin.file,
                    Diagnostic::error(
                        origin.span,
                        format!(
                            "nodes nested deeper than {depth_limit} levels once USE is expanded"
                        ),
                    )
                    .with_label("this node's USEs reach that deep"),
                );
                return;
            }
        }
        let total = self
            .roots
            .iter()
            .fold(0u64, |sum, root| sum.saturating_add(sizes[root.index()]));
        if total > limit {
            if let Some(&last) = self.roots.last() {
                let origin = self.nodes[last.index()].origin;
                self.nodes_limit(origin.file, origin.span, None);
            }
        }
    }
}
