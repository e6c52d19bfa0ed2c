//! The node catalogue: every built-in node type with its fields, read from the TOML files in
//! `schema/catalogue/` (embedded in the binary). Defaults are written in the world language
//! and typed by the same code as user values, so a default can never disagree with its type.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, NodeKind};
use regatta_parser::{Diagnostic, Span};
use serde::{Deserialize, Serialize};

use crate::typing::{self, Literal, Typing};
use crate::value::{FieldType, Value};

const CATALOGUE_FILES: &[(&str, &str)] = &[
    ("vrml97.toml", include_str!("../catalogue/vrml97.toml")),
    ("devices.toml", include_str!("../catalogue/devices.toml")),
    ("webots.toml", include_str!("../catalogue/webots.toml")),
    (
        "webots_devices.toml",
        include_str!("../catalogue/webots_devices.toml"),
    ),
    (
        "unsimulated.toml",
        include_str!("../catalogue/unsimulated.toml"),
    ),
];

/// One field of a node type, as the catalogue declares it.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FieldSpec {
    pub name: String,
    #[serde(rename = "type")]
    pub type_name: String,
    /// The default, in world-language syntax.
    pub default: String,
    pub doc: String,
    /// Smallest allowed number (inclusive), per component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Largest allowed number (inclusive), per component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Exclusive lower bound, per component ("must be positive").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub above: Option<f64>,
    /// Allowed strings.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<String>,
    /// Node classes accepted by an SFNode/MFNode field.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub nodes: Vec<String>,
    /// Exact number of items of an MF field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<usize>,
    /// The strings are urls of local files: each is checked against the world's root.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub file: bool,
    /// VRML97's access: `field` (set in the file only), `exposedField` (the default: set in
    /// the file and by events), `eventIn` or `eventOut` (events only; never written).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub access: Option<String>,
    /// The parsed type (filled when the catalogue loads).
    #[serde(skip)]
    pub field_type: Option<FieldType>,
    /// The typed default (filled when the catalogue loads).
    #[serde(skip)]
    pub default_value: Option<Value>,
}

impl FieldSpec {
    /// The field's type.
    pub fn ty(&self) -> FieldType {
        self.field_type
            .expect("catalogue types are checked when it loads")
    }

    /// The typed default value.
    pub fn default_value(&self) -> &Value {
        self.default_value
            .as_ref()
            .expect("catalogue defaults are typed when it loads")
    }

    /// Why the string `value`, written at `span` for the field `field_name`, is not one of
    /// the field's allowed values; `None` when it is (or the field allows any string).
    pub(crate) fn disallowed(
        &self,
        value: &str,
        span: Span,
        field_name: &str,
    ) -> Option<Diagnostic> {
        if self.values.is_empty() || self.values.iter().any(|v| v == value) {
            return None;
        }
        let allowed = self
            .values
            .iter()
            .map(|v| format!("\"{v}\""))
            .collect::<Vec<_>>()
            .join(", ");
        let mut diagnostic = Diagnostic::error(
            span,
            format!("\"{value}\" is not a valid value of '{field_name}'"),
        )
        .with_label(format!("expected one of {allowed}"))
        .with_code("range");
        if let Some(close) = did_you_mean(value, self.values.iter().map(String::as_str)) {
            diagnostic = diagnostic.with_note(format!("did you mean \"{close}\"?"));
        }
        Some(diagnostic)
    }

    /// Why a typed value, written at `span`, breaks the field's min/max/above/count; `None`
    /// when it does not.
    pub(crate) fn out_of_range(&self, value: &Value, span: Span) -> Option<Diagnostic> {
        let numbers: Vec<f64> = match value {
            Value::Int(i) => vec![*i as f64],
            Value::Float(x) => vec![*x],
            Value::Vec2(v) => v.to_vec(),
            Value::Vec3(v) => v.to_vec(),
            Value::Ints(v) => v.iter().map(|&i| i as f64).collect(),
            Value::Floats(v) => v.clone(),
            Value::Vec2s(v) => v.iter().flatten().copied().collect(),
            Value::Vec3s(v) => v.iter().flatten().copied().collect(),
            _ => Vec::new(),
        };
        let count = match value {
            Value::Ints(v) => Some(v.len()),
            Value::Floats(v) => Some(v.len()),
            Value::Strings(v) => Some(v.len()),
            Value::Nodes(v) => Some(v.len()),
            Value::Vec3s(v) => Some(v.len()),
            Value::Vec2s(v) => Some(v.len()),
            _ => None,
        };
        if let (Some(expected), Some(found)) = (self.count, count) {
            if expected != found {
                return Some(
                    Diagnostic::error(
                        span,
                        format!(
                            "'{}' takes exactly {expected} values, found {found}",
                            self.name
                        ),
                    )
                    .with_code("arity"),
                );
            }
        }
        for x in numbers {
            let problem = if self.above.is_some_and(|a| x <= a) {
                Some(format!(
                    "must be greater than {}",
                    self.above.unwrap_or_default()
                ))
            } else if self.min.is_some_and(|m| x < m) {
                Some(format!("must be at least {}", self.min.unwrap_or_default()))
            } else if self.max.is_some_and(|m| x > m) {
                Some(format!("must be at most {}", self.max.unwrap_or_default()))
            } else {
                None
            };
            if let Some(problem) = problem {
                return Some(
                    Diagnostic::error(span, format!("'{}' {problem}, found {x}", self.name))
                        .with_label(self.doc.clone())
                        .with_code("range"),
                );
            }
        }
        None
    }
}

/// A node type of the catalogue.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    #[serde(skip_deserializing)]
    pub name: String,
    pub doc: String,
    /// Where the node may stand (`child`, `geometry`, `device`…).
    pub classes: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub aliases: Vec<String>,
    /// A Webots node read only for the nodes it holds: fields it does not list are skipped
    /// without a message (the node itself is reported as not simulated).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub open: bool,
    pub fields: Vec<FieldSpec>,
}

impl NodeSpec {
    /// Index of field `name`, if the type has it.
    pub fn field_index(&self, name: &str) -> Option<usize> {
        self.fields.iter().position(|f| f.name == name)
    }

    /// Whether the node may stand where one of `classes` is accepted.
    pub fn fits(&self, classes: &[String]) -> bool {
        classes.is_empty() || self.classes.iter().any(|c| classes.contains(c))
    }
}

/// Handle of a node type in the catalogue.
pub type SpecId = usize;

/// All built-in node types.
#[derive(Debug)]
pub struct Catalogue {
    pub nodes: Vec<NodeSpec>,
    by_name: BTreeMap<String, SpecId>,
}

impl Catalogue {
    /// The embedded catalogue, loaded and checked once.
    pub fn get() -> &'static Catalogue {
        static CATALOGUE: OnceLock<Catalogue> = OnceLock::new();
        CATALOGUE.get_or_init(|| {
            Catalogue::load()
                .unwrap_or_else(|error| panic!("the embedded node catalogue is broken: {error}"))
        })
    }

    fn load() -> Result<Catalogue, String> {
        let mut nodes = Vec::new();
        for (file, text) in CATALOGUE_FILES {
            let table: BTreeMap<String, NodeSpec> =
                toml::from_str(text).map_err(|e| format!("{file}: {e}"))?;
            for (name, mut spec) in table {
                spec.name = name;
                nodes.push(spec);
            }
        }
        nodes.sort_by(|a, b| a.name.cmp(&b.name));
        let mut by_name = BTreeMap::new();
        for (id, spec) in nodes.iter_mut().enumerate() {
            // A node's written fields are one bit each (`scene::Written`).
            if spec.fields.len() > 56 {
                return Err(format!("{}: more than 56 fields", spec.name));
            }
            for field in &mut spec.fields {
                field.field_type = Some(FieldType::parse(&field.type_name).ok_or_else(|| {
                    format!(
                        "{}.{}: unknown type {}",
                        spec.name, field.name, field.type_name
                    )
                })?);
            }
            by_name.insert(spec.name.clone(), id);
            for alias in &spec.aliases {
                by_name.insert(alias.clone(), id);
            }
        }
        let mut catalogue = Catalogue { nodes, by_name };
        // Type every default with the same code as user values.
        for id in 0..catalogue.nodes.len() {
            for index in 0..catalogue.nodes[id].fields.len() {
                let value = type_default(&catalogue, id, index)?;
                // A node's children are among its own values (`scene::Fields::own`).
                if !value.nodes().is_empty() {
                    return Err(format!(
                        "{}.{}: a default holds no node",
                        catalogue.nodes[id].name, catalogue.nodes[id].fields[index].name
                    ));
                }
                catalogue.nodes[id].fields[index].default_value = Some(value);
            }
        }
        Ok(catalogue)
    }

    /// The node type called `name` (aliases included).
    pub fn lookup(&self, name: &str) -> Option<SpecId> {
        self.by_name.get(name).copied()
    }

    /// The spec of a node type.
    pub fn spec(&self, id: SpecId) -> &NodeSpec {
        &self.nodes[id]
    }

    /// Every name a node type can be written with, for "did you mean".
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.by_name.keys().map(String::as_str)
    }
}

/// Types a catalogue default with the code that types user values ([`Typing`]), as the
/// field `NAME DEFAULT` of a node: a default holds no node, and keeps to the field's ranges.
fn type_default(catalogue: &Catalogue, spec: SpecId, index: usize) -> Result<Value, String> {
    let node = &catalogue.nodes[spec];
    let field = &node.fields[index];
    let text = format!("Default {{ {} {} }}", field.name, field.default);
    let parse = regatta_parser::parse(&text);
    let value = match parse.file.items.first() {
        Some(Item::Node(syntax::Node {
            kind: NodeKind::Instance {
                body: Some(body), ..
            },
            ..
        })) => match body.items.first() {
            Some(BodyItem::Field(f)) => &f.value,
            _ => return Err(format!("{}.{}: unreadable default", node.name, field.name)),
        },
        _ => return Err(format!("{}.{}: unreadable default", node.name, field.name)),
    };
    let does_not_type = |problem: Option<&str>| {
        format!(
            "{}.{}: default {:?} does not type: {problem:?}",
            node.name, field.name, field.default
        )
    };
    let syntax::FieldValue::Value(value) = value else {
        return Err(does_not_type(Some("not a value")));
    };
    let ty = field.ty();
    if let Some(problem) = typing::bracketed(value, ty) {
        return Err(does_not_type(Some(&problem.message)));
    }
    let disallowed = |s: &syntax::StringLit| field.disallowed(&s.value, s.span, &field.name);
    let typing = Typing {
        text: &text,
        ty,
        field_name: &field.name,
        strict: true,
        disallowed: &disallowed,
    };
    let mut problems = Vec::new();
    let typed = match typing.literal(value, &mut problems) {
        Some(Literal::Value(value)) => Some(value),
        // No node but NULL or an empty list.
        Some(Literal::Nodes([Atom::Null(_)])) if !ty.multi => Some(Value::Node(None)),
        Some(Literal::Nodes([])) if ty.multi => Some(Value::Nodes(Vec::new())),
        Some(Literal::Nodes(_)) => {
            return Err(format!(
                "{}.{}: a default holds no node",
                node.name, field.name
            ))
        }
        None => None,
    };
    if let Some(problem) = typed
        .as_ref()
        .and_then(|v| field.out_of_range(v, value.span))
    {
        problems.push(problem);
    }
    match typed {
        Some(value) if problems.is_empty() => Ok(value),
        _ => Err(does_not_type(problems.first().map(|d| d.message.as_str()))),
    }
}

/// The closest candidate to `name`, if one is close enough to suggest.
pub fn did_you_mean<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|candidate| {
            (
                strsim::jaro_winkler(&name.to_lowercase(), &candidate.to_lowercase()),
                candidate,
            )
        })
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, candidate)| candidate)
}
