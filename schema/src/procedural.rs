//! What a JavaScript template PROTO is given and where its text lives: the content scope of a
//! PROTO in its file, the field values in Webots' JavaScript shapes, the `context` object and
//! the seed of its randomness. The evaluation itself is `regatta-template`'s job.

use std::ops::Range;

use serde_json::{json, Map, Value as Json};

use crate::catalogue::Catalogue;
use crate::scene::SceneNode;
use crate::value::{BaseType, FieldType, Value};

/// Deepest SFNode nesting given to a template, and most nodes in all; deeper or further
/// nodes are given as `undefined`.
const MAX_NODE_DEPTH: usize = 16;
const MAX_NODES_GIVEN: usize = 10_000;

/// The byte range of a PROTO's content scope (between the braces of its body) in `text`, the
/// text of its file; `proto` is the PROTO's span there.
pub(crate) fn content_range(text: &str, proto: Range<usize>) -> Option<Range<usize>> {
    let bytes = text.as_bytes();
    let mut i = proto.start;
    // The interface: from its '[' to the matching ']', past strings and comments.
    let mut depth = 0usize;
    let mut opened = false;
    while i < proto.end {
        match bytes[i] {
            b'#' => {
                while i < proto.end && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' => {
                i += 1;
                while i < proto.end && bytes[i] != b'"' {
                    if bytes[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
            }
            b'[' => {
                depth += 1;
                opened = true;
            }
            b']' => {
                depth = depth.saturating_sub(1);
                if opened && depth == 0 {
                    i += 1;
                    break;
                }
            }
            b'{' if !opened => return None,
            _ => {}
        }
        i += 1;
    }
    // The body's braces.
    while i < proto.end {
        match bytes[i] {
            b'#' => {
                while i < proto.end && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'{' => break,
            _ => i += 1,
        }
    }
    let end = proto.end.checked_sub(1)?;
    (i < end && bytes[end] == b'}').then_some(i + 1..end)
}

/// The header lines of a PROTO file (its leading comments).
fn header(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .take_while(|l| l.starts_with('#') || l.trim().is_empty())
}

/// Whether a PROTO file says its templates are Lua (Webots before R2022a).
pub(crate) fn is_lua(text: &str) -> bool {
    header(text).any(|l| l.contains("template language: lua"))
}

/// Whether a PROTO file is tagged `nonDeterministic`: each instance is evaluated with its own
/// seed, instead of once for every instance with the same fields.
pub(crate) fn is_non_deterministic(text: &str) -> bool {
    header(text).any(|l| {
        l.trim_start_matches('#').trim_start().starts_with("tags:")
            && l.contains("nonDeterministic")
    })
}

/// `{ NAME: { value, defaultValue } }` for a PROTO's interface; `value` is absent (undefined)
/// for a NULL node, as in Webots.
pub(crate) struct FieldsJson<'a> {
    pub nodes: &'a [SceneNode],
    pub catalogue: &'a Catalogue,
    given: usize,
}

impl<'a> FieldsJson<'a> {
    pub fn new(nodes: &'a [SceneNode], catalogue: &'a Catalogue) -> FieldsJson<'a> {
        FieldsJson {
            nodes,
            catalogue,
            given: 0,
        }
    }

    /// One field's `{ value, defaultValue }`.
    pub fn field(&mut self, ty: FieldType, value: Option<&Value>, default: Option<&Value>) -> Json {
        let mut object = Map::new();
        if let Some(value) = value.and_then(|v| self.value(ty, v, 0)) {
            object.insert("value".to_owned(), value);
        }
        if let Some(default) = default.and_then(|v| self.value(ty, v, 0)) {
            object.insert("defaultValue".to_owned(), default);
        }
        Json::Object(object)
    }

    /// A value in Webots' JavaScript shape; `None` stands for `undefined`.
    fn value(&mut self, ty: FieldType, value: &Value, depth: usize) -> Option<Json> {
        let vec3 = |v: &[f64; 3]| match ty.base {
            BaseType::Color => json!({"r": v[0], "g": v[1], "b": v[2]}),
            _ => json!({"x": v[0], "y": v[1], "z": v[2]}),
        };
        let vec2 = |v: &[f64; 2]| json!({"x": v[0], "y": v[1]});
        let rotation = |r: &[f64; 4]| json!({"x": r[0], "y": r[1], "z": r[2], "a": r[3]});
        Some(match value {
            Value::Bool(b) => json!(b),
            Value::Int(i) => json!(i),
            Value::Float(x) => json!(x),
            Value::Vec2(v) => vec2(v),
            Value::Vec3(v) => vec3(v),
            Value::Rotation(r) => rotation(r),
            Value::String(s) => json!(s),
            Value::Image(image) => json!({
                "width": image.width,
                "height": image.height,
                "components": image.components,
                "pixels": image.pixels,
            }),
            Value::Node(None) => return None,
            Value::Node(Some(id)) => self.node(id.index(), depth)?,
            Value::Bools(v) => json!(v),
            Value::Ints(v) => json!(v),
            Value::Floats(v) => json!(v),
            Value::Vec2s(v) => Json::Array(v.iter().map(vec2).collect()),
            Value::Vec3s(v) => Json::Array(v.iter().map(vec3).collect()),
            Value::Rotations(v) => Json::Array(v.iter().map(rotation).collect()),
            Value::Strings(v) => json!(v),
            Value::Nodes(ids) => Json::Array(
                ids.iter()
                    .map(|id| self.node(id.index(), depth).unwrap_or(Json::Null))
                    .collect(),
            ),
        })
    }

    /// `{ node_name, fields }`: the node's type as the world wrote it (the PROTO's name for a
    /// PROTO instance) and the fields of the node it stands for.
    fn node(&mut self, index: usize, depth: usize) -> Option<Json> {
        if depth >= MAX_NODE_DEPTH || self.given >= MAX_NODES_GIVEN {
            return None;
        }
        self.given += 1;
        let node = self.nodes.get(index)?;
        let spec = self.catalogue.spec(node.spec);
        let name = node.proto_names().last().unwrap_or(&spec.name).clone();
        let mut fields = Map::new();
        for (field, value) in spec.fields.iter().zip(&node.fields) {
            let ty = field.ty();
            let mut object = Map::new();
            if let Some(value) = self.value(ty, value, depth + 1) {
                object.insert("value".to_owned(), value);
            }
            if let Some(default) = self.value(ty, field.default_value(), depth + 1) {
                object.insert("defaultValue".to_owned(), default);
            }
            fields.insert(field.name.clone(), Json::Object(object));
        }
        Some(json!({"node_name": name, "fields": fields}))
    }
}

/// Webots' `context` object. Paths are file names only and the machine's folders are empty
/// strings: nothing of the machine reaches a template, so the same world generates the same
/// scene anywhere.
pub(crate) fn context(
    world: &str,
    proto: &str,
    id: u64,
    coordinate_system: &str,
    webots_version: &str,
) -> Json {
    let file_name = |path: &str| path.rsplit(['/', '\\']).next().unwrap_or(path).to_owned();
    json!({
        "world": file_name(world),
        "proto": file_name(proto),
        "project_path": "",
        "webots_home": "",
        "temporary_files_path": "",
        "os": "linux",
        "id": id,
        "coordinate_system": coordinate_system,
        "webots_version": {"major": webots_version, "revision": "0"},
    })
}

/// The seed of a template's randomness: the world's `WorldInfo.randomSeed`, and the instance's
/// id for `nonDeterministic` PROTOs (a fixed mix, the same on every platform).
pub(crate) fn seed(world_seed: i64, id: u64) -> u32 {
    let mut x = (world_seed as u64) ^ id.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 31;
    x as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_scope_skips_the_interface() {
        let text = "#VRML_SIM R2023b utf8\n# template language: javascript\nPROTO A [\n  field MFString s [\"]{\" ] # ] {\n  field SFInt32 n 2\n]\n# {\n{\n  Group {}\n}\n";
        let start = text.find("PROTO").unwrap();
        let end = text.rfind('}').unwrap() + 1;
        let range = content_range(text, start..end).unwrap();
        assert_eq!(&text[range], "\n  Group {}\n");
        assert!(!is_lua(text));
        assert!(is_lua("# template language: lua\nPROTO A [] {}"));
        assert!(is_non_deterministic(
            "#VRML_SIM R2023b utf8\n# tags: nonDeterministic, hidden\n"
        ));
        assert!(!is_non_deterministic(
            "#VRML_SIM R2023b utf8\nPROTO A [] { Group {} }\n# tags: nonDeterministic\n"
        ));
    }
}
