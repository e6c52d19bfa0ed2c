//! VRML97's field access (`field`, `exposedField`, `eventIn`, `eventOut`): which interface
//! field may be IS'd to which node field, how messages name them, and the messages of the
//! rules a PROTO body can break (an IS of the wrong type or access, or to no interface field;
//! a value written for an event), shared by the check of a declaration and of an instance so
//! that both say the same words at the same place (and the message is given once).

use regatta_parser::syntax::{Declaration, Ident};
use regatta_parser::Diagnostic;

use crate::catalogue::NodeSpec;
use crate::value::FieldType;

/// A node type's events and fields, as a ROUTE names them: (name, type, access).
pub(super) type Ends = [(String, FieldType, String)];

/// The events and fields of a PROTO's interface.
pub(super) fn interface_ends(interface: &[Declaration]) -> Vec<(String, FieldType, String)> {
    interface
        .iter()
        .filter_map(|declaration| {
            let ty = FieldType::parse(&declaration.field_type.text)?;
            let access = access_of(&declaration.keyword.text).to_owned();
            Some((declaration.name.text.clone(), ty, access))
        })
        .collect()
}

/// The events and fields of a built-in node type (an exposedField when the catalogue says no
/// access).
pub(super) fn spec_ends(spec: &NodeSpec) -> Vec<(String, FieldType, String)> {
    spec.fields
        .iter()
        .map(|f| {
            let access = f
                .access
                .clone()
                .unwrap_or_else(|| "exposedField".to_owned());
            (f.name.clone(), f.ty(), access)
        })
        .collect()
}

/// "a field", "an exposedField".
pub(super) fn with_article(word: &str) -> String {
    let article = if word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {word}")
}

/// The access of an interface field declared with `keyword` (Webots' `hiddenField`,
/// `unconnectedField` and the like are fields).
pub(super) fn access_of(keyword: &str) -> &'static str {
    match keyword {
        "exposedField" => "exposedField",
        "eventIn" => "eventIn",
        "eventOut" => "eventOut",
        _ => "field",
    }
}

/// The event an exposedField declares by its name (VRML97 4.7): `set_x`, an eventIn, and
/// `x_changed`, an eventOut, of the exposedField `x`; the field's name and the access.
pub(super) fn implied_event(name: &str) -> Option<(&str, &'static str)> {
    if let Some(field) = name.strip_prefix("set_") {
        return Some((field, "eventIn"));
    }
    name.strip_suffix("_changed")
        .map(|field| (field, "eventOut"))
}

/// Whether an interface field declared with `interface` (a PROTO keyword) may be IS'd to a
/// node field of access `access` (VRML97 4.8.3, table 4.4).
pub(super) fn is_compatible(interface: &str, access: &str) -> bool {
    let interface = access_of(interface);
    match access {
        "exposedField" => true,
        "field" => interface == "field",
        "eventIn" => interface == "eventIn",
        "eventOut" => interface == "eventOut",
        _ => true,
    }
}

/// An IS naming no field of the PROTO's interface.
pub(super) fn unknown_is(target: &Ident) -> Diagnostic {
    Diagnostic::error(
        target.span,
        format!("'{}' is not a field of this PROTO's interface", target.text),
    )
    .with_code("unknown-is")
}

/// An IS between fields of different types.
pub(super) fn is_type_mismatch(
    target: &Ident,
    interface: FieldType,
    field_name: &str,
    ty: FieldType,
) -> Diagnostic {
    Diagnostic::error(
        target.span,
        format!(
            "Type mismatch between '{}' PROTO parameter and field '{field_name}'.",
            target.text
        ),
    )
    .with_label(format!(
        "'{}' is {interface}, '{field_name}' is {ty}",
        target.text
    ))
    .with_code("is-type-mismatch")
}

/// An IS between accesses table 4.4 does not join.
pub(super) fn is_access_mismatch(
    target: &Ident,
    keyword: &str,
    field_name: &str,
    access: &str,
) -> Diagnostic {
    Diagnostic::error(
        target.span,
        format!(
            "{} cannot be IS'd to '{field_name}', which is {}",
            with_article(keyword),
            with_article(access)
        ),
    )
    .with_label(format!("'{}' is {}", target.text, with_article(keyword)))
    .with_note("VRML97 4.8.3: a field may be IS'd to a field or exposedField, an eventIn to an eventIn or exposedField, an eventOut to an eventOut or exposedField; an exposedField only to an exposedField")
    .with_code("is-access-mismatch")
}

/// A value written for an eventIn or eventOut of a built-in node (VRML97 4.7).
pub(super) fn node_event_with_value(field: &Ident, access: &str, node: &str) -> Diagnostic {
    Diagnostic::error(
        field.span,
        format!(
            "'{}' is an {access} of {node}: it receives or sends events and takes no value",
            field.text
        ),
    )
    .with_code("event-as-field")
}

/// A value written for an eventIn or eventOut of a PROTO.
pub(super) fn proto_event_with_value(field: &Ident, keyword: &str, proto: &str) -> Diagnostic {
    Diagnostic::error(
        field.span,
        format!(
            "'{}' is an {keyword} of PROTO '{proto}': it takes no value",
            field.text
        ),
    )
    .with_code("event-as-field")
}
