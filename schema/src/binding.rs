//! A PROTO instance's interface fields ([`Bindings`]): each field's type, the value the
//! instance gave it (or the default) and where the user wrote it. The lowerer fills them; a
//! PROTO body's IS and its templates (`template.rs`) read them.

use std::collections::BTreeMap;

use regatta_parser::Span;

use crate::scene::FileId;
use crate::value::{FieldType, Value};

/// A PROTO instance's interface fields, by name.
pub type Bindings = BTreeMap<String, Binding>;

/// One interface field of a PROTO instance.
#[derive(Clone, Debug)]
pub struct Binding {
    pub ty: FieldType,
    /// The instance's value, or the default.
    pub value: Option<Value>,
    /// Where the user wrote the value: the file, each string's span, the field's span (none
    /// for a default). A value passed on through IS keeps its first site.
    pub site: Option<(FileId, Vec<Span>, Span)>,
    /// `field`, `exposedField`, `eventIn`…
    pub keyword: String,
}

impl Binding {
    /// A binding to a plain `field` with no site (a default).
    pub fn new(ty: FieldType, value: Option<Value>) -> Binding {
        Binding {
            ty,
            value,
            site: None,
            keyword: "field".to_owned(),
        }
    }
}
