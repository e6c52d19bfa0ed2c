//! The standard PROTOs, written in the world language and shipped inside the binary: a world
//! uses them without any EXTERNPROTO line. [`standard_protos`] describes them for
//! `regatta schema`: each PROTO's doc is the comment block above it, each field's doc the
//! comment at the end of its declaration line.

use serde::Serialize;

use regatta_parser::syntax::{Item, NodeKind};

use crate::catalogue::Catalogue;

/// (name, source) of every built-in PROTO file.
pub const BUILTIN_PROTOS: &[(&str, &str)] = &[
    ("Arena", include_str!("../../worlds/protos/Arena.proto")),
    ("Buoy", include_str!("../../worlds/protos/Buoy.proto")),
    ("Khepera", include_str!("../../worlds/protos/Khepera.proto")),
];

/// (name, source, authoring) of every built-in stand-in for a Webots PROTO: a world that names
/// the Webots PROTO (by `webots://` EXTERNPROTO, or by name in files from before R2022b that
/// have no EXTERNPROTO lines) gets the stand-in. Each is written from the PROTO's documented
/// interface (see `docs/reference/webots-robots.md`), never from Webots' source.
pub const WEBOTS_STANDINS: &[(&str, &str, crate::webots::Authoring)] = {
    use crate::webots::Authoring::{Webots, WebotsFlu, WebotsRobot};
    &[
        (
            "CircleArena",
            include_str!("../../worlds/protos/webots/CircleArena.proto"),
            Webots,
        ),
        (
            "E-puck",
            include_str!("../../worlds/protos/webots/E-puck.proto"),
            WebotsRobot,
        ),
        (
            "E-puckGroundSensors",
            include_str!("../../worlds/protos/webots/E-puckGroundSensors.proto"),
            WebotsRobot,
        ),
        (
            "E-puck_enu",
            include_str!("../../worlds/protos/webots/E-puck_enu.proto"),
            WebotsFlu,
        ),
        (
            "Floor",
            include_str!("../../worlds/protos/webots/Floor.proto"),
            Webots,
        ),
        (
            "Khepera1",
            include_str!("../../worlds/protos/webots/Khepera1.proto"),
            WebotsRobot,
        ),
        (
            "Khepera2",
            include_str!("../../worlds/protos/webots/Khepera2.proto"),
            WebotsRobot,
        ),
        (
            "Khepera3",
            include_str!("../../worlds/protos/webots/Khepera3.proto"),
            WebotsRobot,
        ),
        (
            "Khepera4",
            include_str!("../../worlds/protos/webots/Khepera4.proto"),
            WebotsRobot,
        ),
        (
            "Pi-puck",
            include_str!("../../worlds/protos/webots/Pi-puck.proto"),
            WebotsRobot,
        ),
        (
            "RectangleArena",
            include_str!("../../worlds/protos/webots/RectangleArena.proto"),
            Webots,
        ),
        (
            "TexturedBackground",
            include_str!("../../worlds/protos/webots/TexturedBackground.proto"),
            Webots,
        ),
        (
            "TexturedBackgroundLight",
            include_str!("../../worlds/protos/webots/TexturedBackgroundLight.proto"),
            Webots,
        ),
        (
            "Thymio2",
            include_str!("../../worlds/protos/webots/Thymio2.proto"),
            WebotsRobot,
        ),
        (
            "WoodenBox",
            include_str!("../../worlds/protos/webots/WoodenBox.proto"),
            Webots,
        ),
    ]
};

/// A standard PROTO as `regatta schema` shows it.
#[derive(Clone, Debug, Serialize)]
pub struct ProtoSpec {
    pub name: String,
    pub doc: String,
    /// Always true: tells PROTOs from built-in node types in `regatta schema --format json`.
    pub proto: bool,
    /// The node type its body is made of.
    pub root: String,
    /// Where it may stand (its root's classes).
    pub classes: Vec<String>,
    pub fields: Vec<ProtoField>,
}

/// One interface field of a standard PROTO.
#[derive(Clone, Debug, Serialize)]
pub struct ProtoField {
    pub name: String,
    #[serde(rename = "type")]
    pub type_name: String,
    /// The default, as written in the PROTO.
    pub default: String,
    pub doc: String,
}

/// Every standard PROTO: regatta's own, then the stand-ins for Webots PROTOs.
pub fn standard_protos() -> Vec<ProtoSpec> {
    BUILTIN_PROTOS
        .iter()
        .map(|(_, text)| *text)
        .chain(WEBOTS_STANDINS.iter().map(|(_, text, _)| *text))
        .filter_map(describe)
        .collect()
}

/// The standard PROTO called `name`.
pub fn standard_proto(name: &str) -> Option<ProtoSpec> {
    standard_protos().into_iter().find(|p| p.name == name)
}

fn describe(text: &str) -> Option<ProtoSpec> {
    let parsed = regatta_parser::parse(text);
    let proto = parsed.file.items.iter().find_map(|item| match item {
        Item::Proto(proto) => Some(proto),
        _ => None,
    })?;
    // The comment lines just above `PROTO` (the header line excluded).
    let before = &text[..proto.span.start as usize];
    let mut doc_lines: Vec<&str> = before
        .lines()
        .rev()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| l.trim_start().starts_with('#') && !l.starts_with("#VRML"))
        .map(|l| l.trim_start().trim_start_matches('#').trim())
        .collect();
    doc_lines.reverse();
    let doc = doc_lines.join(" ");
    let line_end = |offset: usize| text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    let fields = proto
        .interface
        .iter()
        .map(|declaration| {
            let end = line_end(declaration.span.end as usize);
            let rest = &text[declaration.span.end as usize..end];
            let doc = rest
                .split_once('#')
                .map(|(_, comment)| comment.trim().to_owned())
                .unwrap_or_default();
            let default = match &declaration.default {
                Some(regatta_parser::syntax::FieldValue::Value(value)) => {
                    text[value.span.range()].to_owned()
                }
                _ => String::new(),
            };
            ProtoField {
                name: declaration.name.text.clone(),
                type_name: declaration.field_type.text.clone(),
                default,
                doc,
            }
        })
        .collect();
    let root = proto.body.iter().find_map(|item| match item {
        Item::Node(node) => match &node.kind {
            NodeKind::Instance { type_name, .. } => Some(type_name.text.clone()),
            NodeKind::Use(_) => None,
        },
        _ => None,
    })?;
    let catalogue = Catalogue::get();
    let classes = catalogue
        .lookup(&root)
        .map(|id| catalogue.spec(id).classes.clone())
        .unwrap_or_default();
    Some(ProtoSpec {
        name: proto.name.text.clone(),
        doc,
        proto: true,
        root,
        classes,
        fields,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_standard_proto_field_is_documented() {
        let protos = super::standard_protos();
        assert_eq!(
            protos.len(),
            super::BUILTIN_PROTOS.len() + super::WEBOTS_STANDINS.len()
        );
        // regatta's own PROTOs document every field; the stand-ins follow Webots' interfaces.
        for proto in protos.into_iter().take(super::BUILTIN_PROTOS.len()) {
            assert!(!proto.doc.is_empty(), "{} has no doc", proto.name);
            for field in &proto.fields {
                assert!(
                    !field.doc.is_empty(),
                    "{}.{} has no doc",
                    proto.name,
                    field.name
                );
            }
        }
    }
}
