//! The typed scene: a value type owning its data, held in an arena with typed handles.
//!
//! Every node is an instance of a catalogue type with every field present (defaults filled),
//! PROTOs expanded and USE resolved to the DEF'd node's handle, so the scene is a DAG. It is
//! always y-up, in metres, radians and seconds: z-up files are turned by [`Scene::root_rotation`].

use std::sync::Arc;

use regatta_parser::Span;

use crate::catalogue::{Catalogue, NodeSpec, SpecId};
// A node value names its nodes by handle, so the handle lives with the values.
pub use crate::value::NodeId;
use crate::value::Value;

/// Handle of a source file in [`Scene::files`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct FileId(pub u32);

/// Where a node came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Origin {
    pub file: FileId,
    pub span: Span,
}

/// One typed node.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneNode {
    pub spec: SpecId,
    /// One value per catalogue field, in catalogue order (defaults shared with the catalogue).
    pub fields: Fields,
    /// Whether each field was written (or bound through IS) rather than defaulted.
    pub written: Written,
    /// Its DEF name and the PROTOs it is the root of. Few nodes have either, and a swarm's
    /// world holds tens of thousands of nodes, so they are kept apart: a node is 64 bytes,
    /// not 104 (see [`SceneNode::def_name`], [`SceneNode::proto_names`]).
    pub(crate) names: Option<Box<NodeNames>>,
    /// Where the node was written: for a PROTO's root, the user's instance.
    pub origin: Origin,
    /// The axes its own transform and its children are written in (see [`crate::webots`]).
    pub axes: crate::webots::Axes,
}

/// What few nodes have: a DEF name, PROTOs whose instance the node is the root of.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct NodeNames {
    pub(crate) def_name: Option<String>,
    /// Innermost first when nested.
    pub(crate) proto_names: Vec<String>,
}

impl SceneNode {
    /// The name it was DEF'd with.
    pub fn def_name(&self) -> Option<&str> {
        self.names.as_ref()?.def_name.as_deref()
    }

    /// The PROTOs whose instance this node is the root of, innermost first when nested.
    pub fn proto_names(&self) -> &[String] {
        self.names.as_ref().map_or(&[], |names| &names.proto_names)
    }

    pub(crate) fn names_mut(&mut self) -> &mut NodeNames {
        self.names.get_or_insert_with(Default::default)
    }

    /// Where field `index`'s value was written, if it was: for a field bound through IS,
    /// where the PROTO instance wrote it, or the instance itself for a built-in PROTO's
    /// default; `None`: defaulted. Messages about values that only later checks reject (a
    /// controller's name and arguments, a network's sizes) point at the user's line.
    pub fn value_span_at(&self, index: usize) -> Option<Origin> {
        self.fields.span(index)
    }
}

/// A node's field values: the ones it has of its own, sparse, in front of its type's
/// defaults, which every node of the type shares with the catalogue. A swarm's thousand
/// robots each hold only what their instances wrote, not every field of every part, and the
/// parts a PROTO's body writes the same way for every instance share one copy of their values
/// (see [`SharedFields`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Fields {
    spec: u32,
    len: u32,
    /// Values of the node's own, by ascending field index.
    own: Arc<[OwnValue]>,
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) struct OwnValue {
    index: u32,
    /// Where the value was written (see [`SceneNode::value_span_at`]).
    span: Option<Origin>,
    value: Value,
}

impl OwnValue {
    /// The same to the bit (where `==` takes 0.0 for −0.0).
    fn same(&self, other: &OwnValue) -> bool {
        self.index == other.index && self.span == other.span && same_bits(&self.value, &other.value)
    }
}

/// Whether two values are the same to the bit.
fn same_bits(a: &Value, b: &Value) -> bool {
    fn floats(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }
    match (a, b) {
        (Value::Float(x), Value::Float(y)) => x.to_bits() == y.to_bits(),
        (Value::Vec2(x), Value::Vec2(y)) => floats(x, y),
        (Value::Vec3(x), Value::Vec3(y)) => floats(x, y),
        (Value::Rotation(x), Value::Rotation(y)) => floats(x, y),
        (Value::Floats(x), Value::Floats(y)) => floats(x, y),
        (Value::Vec2s(x), Value::Vec2s(y)) => floats(x.as_flattened(), y.as_flattened()),
        (Value::Vec3s(x), Value::Vec3s(y)) => floats(x.as_flattened(), y.as_flattened()),
        (Value::Rotations(x), Value::Rotations(y)) => floats(x.as_flattened(), y.as_flattened()),
        // No floats inside: equality is identity.
        _ => a == b,
    }
}

/// The values a node is given while it is typed, before it becomes [`Fields`].
pub(crate) struct FieldsBuilder {
    spec: u32,
    len: u32,
    own: Vec<OwnValue>,
}

impl FieldsBuilder {
    /// Every field of type `spec` (with `len` fields) at its default.
    pub(crate) fn new(spec: SpecId, len: usize) -> FieldsBuilder {
        FieldsBuilder {
            spec: spec as u32,
            len: len as u32,
            own: Vec::new(),
        }
    }

    /// Gives field `index` a value of its own, written at `span` (a later value replaces an
    /// earlier one).
    pub(crate) fn set(&mut self, index: usize, value: Value, span: Option<Origin>) {
        assert!(index < self.len as usize, "field {index} out of range");
        let own = OwnValue {
            index: index as u32,
            span,
            value,
        };
        match self.own.binary_search_by_key(&own.index, |own| own.index) {
            Ok(at) => self.own[at] = own,
            Err(at) => self.own.insert(at, own),
        }
    }

    /// The node's fields, sharing the values of the last node made at `key` when they are
    /// the same to the bit.
    pub(crate) fn finish(self, key: Origin, shared: &mut SharedFields) -> Fields {
        let own = match shared.made.get(&(key.file, key.span, self.spec)) {
            Some(made)
                if made.len() == self.own.len()
                    && made.iter().zip(&self.own).all(|(a, b)| a.same(b)) =>
            {
                made.clone()
            }
            _ => {
                let own: Arc<[OwnValue]> = self.own.into();
                if !own.is_empty() {
                    shared
                        .made
                        .insert((key.file, key.span, self.spec), own.clone());
                }
                own
            }
        };
        Fields {
            spec: self.spec,
            len: self.len,
            own,
        }
    }
}

/// The values of nodes made so far, by where the node was written: a PROTO's body makes its
/// nodes again for every instance, and those it writes without IS come out the same.
#[derive(Debug, Default)]
pub(crate) struct SharedFields {
    made: std::collections::HashMap<(FileId, Span, u32), Arc<[OwnValue]>>,
}

impl Fields {
    /// How many fields the node's type has.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn position(&self, index: usize) -> Result<usize, usize> {
        self.own
            .binary_search_by_key(&(index as u32), |own| own.index)
    }

    /// Where field `index`'s value was written, if it was.
    pub fn span(&self, index: usize) -> Option<Origin> {
        self.position(index).ok().and_then(|at| self.own[at].span)
    }

    /// The values the node has of its own, in catalogue order: all its children among them,
    /// since no default holds a node.
    pub fn own(&self) -> impl DoubleEndedIterator<Item = &Value> + '_ {
        self.own.iter().map(|own| &own.value)
    }

    /// The values in catalogue order.
    pub fn iter(&self) -> FieldsIter<'_> {
        FieldsIter {
            fields: self,
            indices: 0..self.len(),
        }
    }
}

impl std::ops::Index<usize> for Fields {
    type Output = Value;

    fn index(&self, index: usize) -> &Value {
        match self.position(index) {
            Ok(at) => &self.own[at].value,
            Err(_) => {
                assert!(index < self.len(), "field {index} out of range");
                Catalogue::get().spec(self.spec as SpecId).fields[index].default_value()
            }
        }
    }
}

impl std::ops::IndexMut<usize> for Fields {
    /// A value of the node's own (a copy of the default, the first time; a copy of a shared
    /// value), keeping where any earlier value was written.
    fn index_mut(&mut self, index: usize) -> &mut Value {
        let mut own = self.own.to_vec();
        let at = match self.position(index) {
            Ok(at) => at,
            Err(at) => {
                own.insert(
                    at,
                    OwnValue {
                        index: index as u32,
                        span: None,
                        value: self[index].clone(),
                    },
                );
                at
            }
        };
        self.own = own.into();
        let own = Arc::get_mut(&mut self.own).expect("a fresh copy is not shared");
        &mut own[at].value
    }
}

impl<'a> IntoIterator for &'a Fields {
    type Item = &'a Value;
    type IntoIter = FieldsIter<'a>;

    fn into_iter(self) -> FieldsIter<'a> {
        self.iter()
    }
}

/// A node's values in catalogue order (see [`Fields::iter`]).
#[derive(Clone, Debug)]
pub struct FieldsIter<'a> {
    fields: &'a Fields,
    indices: std::ops::Range<usize>,
}

impl<'a> Iterator for FieldsIter<'a> {
    type Item = &'a Value;

    fn next(&mut self) -> Option<&'a Value> {
        self.indices.next().map(|index| &self.fields[index])
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.indices.size_hint()
    }
}

impl DoubleEndedIterator for FieldsIter<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        self.indices.next_back().map(|index| &self.fields[index])
    }
}

impl ExactSizeIterator for FieldsIter<'_> {}

/// Which fields of a node were written, one bit per field, and in the top byte how many
/// fields there are (the catalogue checks that no type has more than 56).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Written(u64);

impl Written {
    const LEN_SHIFT: u32 = 56;

    /// No field of `len` written yet.
    pub fn none(len: usize) -> Written {
        assert!(
            len <= Self::LEN_SHIFT as usize,
            "a node type has at most 56 fields"
        );
        Written((len as u64) << Self::LEN_SHIFT)
    }

    pub fn set(&mut self, index: usize) {
        assert!(index < self.len(), "field {index} out of range");
        self.0 |= 1 << index;
    }

    pub fn get(&self, index: usize) -> bool {
        index < self.len() && self.0 & (1 << index) != 0
    }

    pub fn len(&self) -> usize {
        (self.0 >> Self::LEN_SHIFT) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether each field was written, in catalogue order.
    pub fn iter(&self) -> WrittenIter {
        WrittenIter {
            bits: self.0,
            indices: 0..self.len(),
        }
    }
}

impl IntoIterator for &Written {
    type Item = &'static bool;
    type IntoIter = WrittenIter;

    fn into_iter(self) -> WrittenIter {
        self.iter()
    }
}

/// Whether each field was written, in catalogue order (see [`Written::iter`]).
#[derive(Clone, Debug)]
pub struct WrittenIter {
    bits: u64,
    indices: std::ops::Range<usize>,
}

impl WrittenIter {
    fn bit(&self, index: usize) -> &'static bool {
        if self.bits & (1 << index) != 0 {
            &true
        } else {
            &false
        }
    }
}

impl Iterator for WrittenIter {
    type Item = &'static bool;

    fn next(&mut self) -> Option<&'static bool> {
        self.indices.next().map(|index| self.bit(index))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.indices.size_hint()
    }
}

impl DoubleEndedIterator for WrittenIter {
    fn next_back(&mut self) -> Option<&'static bool> {
        self.indices.next_back().map(|index| self.bit(index))
    }
}

impl ExactSizeIterator for WrittenIter {}

/// The axis convention of the file the scene was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpAxis {
    /// VRML97 and Webots before R2022a ("NUE").
    Y,
    /// Webots R2022a and later ("ENU").
    Z,
}

/// A whole typed world.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub nodes: Vec<SceneNode>,
    pub roots: Vec<NodeId>,
    /// The file names nodes refer to (the world first, then PROTO and Inline files).
    pub files: Vec<String>,
    pub up_axis: UpAxis,
    /// The convention of the world's objects (robots, devices, cylinder axes).
    pub objects: crate::webots::Objects,
    /// The files mesh and image nodes name, read through the world's file access rules, by
    /// ascending node (a node has at most one: the first of its urls that could be read).
    pub assets: Vec<Asset>,
}

/// A file a node names and the exporters need (a Mesh's or CadShape's model, an
/// ImageTexture's image), read once by the check and shared by every node naming it.
#[derive(Clone, Debug, PartialEq)]
pub struct Asset {
    pub node: NodeId,
    /// The url as written.
    pub url: String,
    /// The file's bytes, at most the file-size limit.
    pub bytes: Arc<[u8]>,
    /// Files the first one names (an OBJ's MTL libraries), each with its bytes or why they
    /// could not be read.
    pub companions: Vec<Companion>,
}

/// A file named inside an asset (an OBJ's `mtllib`).
#[derive(Clone, Debug, PartialEq)]
pub struct Companion {
    /// The name as the asset wrote it.
    pub name: String,
    pub bytes: Result<Arc<[u8]>, String>,
}

impl Scene {
    /// The file a mesh or image node names, if it could be read.
    pub fn asset(&self, id: NodeId) -> Option<&Asset> {
        self.assets
            .binary_search_by_key(&id, |a| a.node)
            .ok()
            .map(|i| &self.assets[i])
    }

    /// The node behind a handle.
    pub fn node(&self, id: NodeId) -> &SceneNode {
        &self.nodes[id.index()]
    }

    /// The catalogue type of a node.
    pub fn spec(&self, id: NodeId) -> &'static NodeSpec {
        Catalogue::get().spec(self.node(id).spec)
    }

    /// Where a field's value was written, else where the node was: what a message about the
    /// value points at.
    pub fn value_span(&self, id: NodeId, name: &str) -> Origin {
        let node = self.node(id);
        self.spec(id)
            .field_index(name)
            .and_then(|index| node.value_span_at(index))
            .unwrap_or(node.origin)
    }

    /// The type name of a node (the catalogue's, not an alias).
    pub fn type_name(&self, id: NodeId) -> &'static str {
        &self.spec(id).name
    }

    /// A field's value by name. Panics on a name the type does not have: that is a bug in the
    /// caller, never a property of user input.
    pub fn field(&self, id: NodeId, name: &str) -> &Value {
        let spec = self.spec(id);
        let index = spec
            .field_index(name)
            .unwrap_or_else(|| panic!("{} has no field {name}", spec.name));
        &self.node(id).fields[index]
    }

    pub fn float(&self, id: NodeId, name: &str) -> f64 {
        match self.field(id, name) {
            Value::Float(x) => *x,
            Value::Int(i) => *i as f64,
            other => panic!("{name} is not a float: {other:?}"),
        }
    }

    pub fn int(&self, id: NodeId, name: &str) -> i32 {
        match self.field(id, name) {
            Value::Int(i) => *i,
            other => panic!("{name} is not an integer: {other:?}"),
        }
    }

    pub fn bool(&self, id: NodeId, name: &str) -> bool {
        match self.field(id, name) {
            Value::Bool(b) => *b,
            other => panic!("{name} is not a boolean: {other:?}"),
        }
    }

    pub fn vec2(&self, id: NodeId, name: &str) -> [f64; 2] {
        match self.field(id, name) {
            Value::Vec2(v) => *v,
            other => panic!("{name} is not an SFVec2f: {other:?}"),
        }
    }

    pub fn vec3(&self, id: NodeId, name: &str) -> [f64; 3] {
        match self.field(id, name) {
            Value::Vec3(v) => *v,
            other => panic!("{name} is not an SFVec3f: {other:?}"),
        }
    }

    pub fn rotation(&self, id: NodeId, name: &str) -> [f64; 4] {
        match self.field(id, name) {
            Value::Rotation(v) => *v,
            other => panic!("{name} is not an SFRotation: {other:?}"),
        }
    }

    pub fn string(&self, id: NodeId, name: &str) -> &str {
        match self.field(id, name) {
            Value::String(s) => s,
            other => panic!("{name} is not an SFString: {other:?}"),
        }
    }

    pub fn strings(&self, id: NodeId, name: &str) -> &[String] {
        match self.field(id, name) {
            Value::Strings(s) => s,
            other => panic!("{name} is not an MFString: {other:?}"),
        }
    }

    pub fn child(&self, id: NodeId, name: &str) -> Option<NodeId> {
        match self.field(id, name) {
            Value::Node(node) => *node,
            other => panic!("{name} is not an SFNode: {other:?}"),
        }
    }

    pub fn children(&self, id: NodeId, name: &str) -> &[NodeId] {
        self.field(id, name).nodes()
    }

    /// Every node reachable from the roots, depth first, each once, in a stable order.
    pub fn walk(&self) -> Vec<NodeId> {
        let mut seen = vec![false; self.nodes.len()];
        let mut order = Vec::new();
        let mut stack: Vec<NodeId> = self.roots.iter().rev().copied().collect();
        while let Some(id) = stack.pop() {
            if std::mem::replace(&mut seen[id.index()], true) {
                continue;
            }
            order.push(id);
            for value in self.node(id).fields.own().rev() {
                stack.extend(value.nodes().iter().rev());
            }
        }
        order
    }

    /// Every node of type `name`, in walk order.
    pub fn find(&self, name: &str) -> Vec<NodeId> {
        self.walk()
            .into_iter()
            .filter(|&id| self.type_name(id) == name)
            .collect()
    }

    /// The rotation (axis, angle) that brings the file's axes to regatta's y-up frame:
    /// identity for y-up files; −90° about x for z-up files, mapping (x, y, z) to (x, z, −y).
    /// The rotation from `to`'s coordinates into `from`'s, for a node written by `to` placed
    /// among nodes written by `from` (a PROTO instance in a world, a world's node in a PROTO's
    /// slot); `None` when they agree.
    pub fn turn(
        &self,
        from: crate::webots::Authoring,
        to: crate::webots::Authoring,
    ) -> Option<[f64; 4]> {
        crate::webots::turn(from, to, self.objects)
    }

    pub fn root_rotation(&self) -> [f64; 4] {
        match self.up_axis {
            UpAxis::Y => [0.0, 1.0, 0.0, 0.0],
            UpAxis::Z => [1.0, 0.0, 0.0, -std::f64::consts::FRAC_PI_2],
        }
    }
}
