//! VRML97's field access (`field`, `exposedField`, `eventIn`, `eventOut`): which interface
//! field may be IS'd to which node field, and how messages name them.

/// "a field", "an exposedField".
pub(super) fn with_article(word: &str) -> String {
    let article = if word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {word}")
}

/// Whether an interface field declared with `interface` (a PROTO keyword) may be IS'd to a
/// node field of access `access` (VRML97 4.8.3, table 4.4).
pub(super) fn is_compatible(interface: &str, access: &str) -> bool {
    let interface = match interface {
        "exposedField" => "exposedField",
        "eventIn" => "eventIn",
        "eventOut" => "eventOut",
        _ => "field",
    };
    match access {
        "exposedField" => true,
        "field" => interface == "field",
        "eventIn" => interface == "eventIn",
        "eventOut" => interface == "eventOut",
        _ => true,
    }
}
