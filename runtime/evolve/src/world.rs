//! World text edits: `--set NODE.FIELD=VALUE` overrides, and evolved weights written into a
//! world's `NeuralNetwork`. Edits are made on the source text at the spans the parser gives,
//! then the world is checked as a whole, so an override can set any field a file could —
//! a PROTO's field as well as a built-in node's — and the log of a run embeds the edited text.

use regatta_parser::syntax::{BodyItem, FieldValue, Item, Node, NodeKind};

/// Why a world cannot be edited.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditError {
    #[error("--set takes NODE.FIELD=VALUE (e.g. Khepera.controllerArgs=irGain=2), found \"{0}\"")]
    Malformed(String),
    #[error("the world has no node of type or DEF name '{0}' to set")]
    NoSuchNode(String),
    #[error("the world's file has no NeuralNetwork node to write weights into")]
    NoNetwork,
    #[error("the world does not parse: {0}")]
    Syntax(String),
    #[error("the world has no robot with a NeuralNetwork in its 'network' field to take")]
    NoNeuralRobot,
    #[error("the world has no robot with a 'controller' field to take")]
    NoController,
}

/// One `--set NODE.FIELD=VALUE`: every node of type (or DEF name) `node` in the world file
/// gets `field` set to `value`, world-language text.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    pub node: String,
    pub field: String,
    pub value: String,
}

impl Override {
    /// Reads `NODE.FIELD=VALUE`. A value that is not a number, a boolean, NULL, a list, a
    /// node or already quoted is quoted: `Khepera.controllerArgs=irGain=2` sets
    /// `controllerArgs "irGain=2"`.
    pub fn parse(text: &str) -> Result<Override, EditError> {
        let malformed = || EditError::Malformed(text.to_owned());
        let (target, value) = text.split_once('=').ok_or_else(malformed)?;
        let (node, field) = target.split_once('.').ok_or_else(malformed)?;
        let valid = |s: &str| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        };
        if !valid(node) || !valid(field) {
            return Err(malformed());
        }
        let value = value.trim();
        let literal = value.starts_with(['"', '[', '-', '+', '.'])
            || value.starts_with(|c: char| c.is_ascii_digit())
            || matches!(value, "TRUE" | "FALSE" | "NULL")
            || value.contains('{');
        let value = if literal {
            value.to_owned()
        } else {
            format!("\"{}\"", value.replace('\\', "\\\\").replace('"', "\\\""))
        };
        Ok(Override {
            node: node.to_owned(),
            field: field.to_owned(),
            value,
        })
    }
}

/// The world file's nodes (PROTO definitions excluded), depth first.
pub(crate) fn world_nodes(file: &regatta_parser::syntax::SourceFile) -> Vec<&Node> {
    let mut nodes = Vec::new();
    for item in &file.items {
        if let Item::Node(node) = item {
            regatta_parser::syntax::walk_node(node, &mut |n| nodes.push(n));
        }
    }
    nodes
}

/// `(start, end, replacement)` edits to set `field` of `node` to `value`.
pub(crate) fn set_field(
    node: &Node,
    field: &str,
    value: &str,
    edits: &mut Vec<(usize, usize, String)>,
) {
    let NodeKind::Instance {
        body: Some(body), ..
    } = &node.kind
    else {
        return;
    };
    let existing = body.items.iter().rev().find_map(|item| match item {
        BodyItem::Field(f) if f.name.text == field => Some(f),
        _ => None,
    });
    match existing {
        Some(f) => {
            let span = match &f.value {
                FieldValue::Value(v) => v.span,
                FieldValue::Is(ident) => ident.span,
                FieldValue::Missing { found } => *found,
            };
            // The whole `name value`, so that `name IS x` becomes `name value`.
            let start = f.name.span.end as usize;
            edits.push((
                start,
                span.end.max(f.name.span.end) as usize,
                format!(" {value}"),
            ));
        }
        None => {
            let open = body.span.start as usize + 1;
            edits.push((open, open, format!(" {field} {value}")));
        }
    }
}

pub(crate) fn apply(text: &str, mut edits: Vec<(usize, usize, String)>) -> String {
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = text.to_owned();
    for (start, end, replacement) in edits {
        out.replace_range(start..end, &replacement);
    }
    out
}

/// The world text with every override applied, in order (a later one wins).
pub fn apply_overrides(text: &str, overrides: &[Override]) -> Result<String, EditError> {
    let mut text = text.to_owned();
    for o in overrides {
        let parsed = regatta_parser::parse(&text);
        let mut edits = Vec::new();
        for node in world_nodes(&parsed.file) {
            let type_name = match &node.kind {
                NodeKind::Instance { type_name, .. } => type_name.text.as_str(),
                NodeKind::Use(_) => continue,
            };
            let def = node.def.as_ref().map(|d| d.text.as_str());
            if type_name == o.node || def == Some(o.node.as_str()) {
                set_field(node, &o.field, &o.value, &mut edits);
            }
        }
        if edits.is_empty() {
            return Err(EditError::NoSuchNode(o.node.clone()));
        }
        text = apply(&text, edits);
    }
    Ok(text)
}

/// The node value of `node`'s field `field`, if it is one: the node and its source text.
fn node_field<'a>(node: &'a Node, field: &str, text: &'a str) -> Option<(&'a Node, &'a str)> {
    let NodeKind::Instance {
        body: Some(body), ..
    } = &node.kind
    else {
        return None;
    };
    body.items.iter().rev().find_map(|item| match item {
        BodyItem::Field(f) if f.name.text == field => match &f.value {
            FieldValue::Value(v) => match &v.items {
                regatta_parser::syntax::Items::Atoms(atoms) => match atoms.first() {
                    Some(regatta_parser::syntax::Atom::Node(n)) => {
                        Some((n, &text[n.span.start as usize..n.span.end as usize]))
                    }
                    _ => None,
                },
                _ => None,
            },
            _ => None,
        },
        _ => None,
    })
}

/// The overrides that put the first robot of `source` (a world's text) that carries a
/// `NeuralNetwork` into another world: every node of that robot's type gets controller
/// "neural", the network (weights included) and the turret it reads, so that a network
/// evolved or written for one arena runs in another exactly as it was built.
pub fn network_overrides(source: &str) -> Result<Vec<Override>, EditError> {
    let parsed = regatta_parser::parse(source);
    if let Some(error) = parsed.diagnostics.iter().find(|d| d.is_error()) {
        return Err(EditError::Syntax(error.message.clone()));
    }
    for node in world_nodes(&parsed.file) {
        let NodeKind::Instance { type_name, .. } = &node.kind else {
            continue;
        };
        let Some((network, network_text)) = node_field(node, "network", source) else {
            continue;
        };
        if !matches!(&network.kind, NodeKind::Instance { type_name, .. } if type_name.text == "NeuralNetwork")
        {
            continue;
        }
        let set = |field: &str, value: &str| Override {
            node: type_name.text.clone(),
            field: field.to_owned(),
            value: value.to_owned(),
        };
        let mut overrides = vec![
            set("controller", "\"neural\""),
            set("controllerArgs", "[ ]"),
            set("network", network_text),
        ];
        if let Some((_, turret)) = node_field(node, "turret", source) {
            overrides.push(set("turret", turret));
        }
        return Ok(overrides);
    }
    Err(EditError::NoNeuralRobot)
}

/// The overrides that put the controller of `source`'s first robot into another world: its
/// network's when it has one ([`network_overrides`]), else its `controller`,
/// `controllerArgs` and `turret` as written (a built-in controller such as the hand-tuned
/// regatta, with its parameters and the retina it reads).
pub fn controller_overrides(source: &str) -> Result<Vec<Override>, EditError> {
    match network_overrides(source) {
        Err(EditError::NoNeuralRobot) => {}
        other => return other,
    }
    let parsed = regatta_parser::parse(source);
    for node in world_nodes(&parsed.file) {
        let NodeKind::Instance {
            type_name,
            body: Some(body),
        } = &node.kind
        else {
            continue;
        };
        let written = |name: &str| {
            body.items.iter().rev().find_map(|item| match item {
                BodyItem::Field(f) if f.name.text == name => match &f.value {
                    FieldValue::Value(v) => {
                        Some(source[v.span.start as usize..v.span.end as usize].to_owned())
                    }
                    _ => None,
                },
                _ => None,
            })
        };
        let Some(controller) = written("controller") else {
            continue;
        };
        let set = |field: &str, value: String| Override {
            node: type_name.text.clone(),
            field: field.to_owned(),
            value,
        };
        let mut overrides = vec![
            set("controller", controller),
            set(
                "controllerArgs",
                written("controllerArgs").unwrap_or_else(|| "[ ]".to_owned()),
            ),
        ];
        if let Some((_, turret)) = node_field(node, "turret", source) {
            overrides.push(set("turret", turret.to_owned()));
        }
        return Ok(overrides);
    }
    Err(EditError::NoController)
}

/// The weights as world-language numbers: Rust's shortest text that reads back to the same
/// f64, so a written world runs exactly as the weights evaluated.
pub fn weights_text(weights: &[f64]) -> String {
    let numbers: Vec<String> = weights.iter().map(|w| format!("{w:?}")).collect();
    format!("[ {} ]", numbers.join(" "))
}

/// The world with `weights` in every `NeuralNetwork` of its file, in canonical `fmt` form.
pub fn with_weights(text: &str, weights: &[f64]) -> Result<String, EditError> {
    let parsed = regatta_parser::parse(text);
    let mut edits = Vec::new();
    let value = weights_text(weights);
    for node in world_nodes(&parsed.file) {
        if let NodeKind::Instance { type_name, .. } = &node.kind {
            if type_name.text == "NeuralNetwork" {
                set_field(node, "weights", &value, &mut edits);
            }
        }
    }
    if edits.is_empty() {
        return Err(EditError::NoNetwork);
    }
    let edited = apply(text, edits);
    let parsed = regatta_parser::parse(&edited);
    if let Some(error) = parsed.diagnostics.iter().find(|d| d.is_error()) {
        return Err(EditError::Syntax(error.message.clone()));
    }
    Ok(regatta_parser::format::format(&parsed.file, &edited))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_or_add_fields_by_type_or_def_name() {
        let world =
            "Khepera { controller \"regatta\" }\nDEF B Buoy { }\nBuoy { irReflectance 1 }\n";
        let o = Override::parse("Khepera.controllerArgs=irGain=2").unwrap();
        assert_eq!(o.value, "\"irGain=2\"");
        let out = apply_overrides(world, &[o]).unwrap();
        assert_eq!(
            out,
            "Khepera { controllerArgs \"irGain=2\" controller \"regatta\" }\nDEF B Buoy { }\nBuoy { irReflectance 1 }\n"
        );
        let out =
            apply_overrides(world, &[Override::parse("Buoy.irReflectance=0.5").unwrap()]).unwrap();
        assert!(out.contains("DEF B Buoy { irReflectance 0.5 }"), "{out}");
        assert!(out.contains("Buoy { irReflectance 0.5 }\n"), "{out}");
        let out =
            apply_overrides(world, &[Override::parse("B.irReflectance=0.7").unwrap()]).unwrap();
        assert!(out.contains("DEF B Buoy { irReflectance 0.7 }"), "{out}");
        assert_eq!(
            apply_overrides(world, &[Override::parse("Lamp.on=TRUE").unwrap()]),
            Err(EditError::NoSuchNode("Lamp".into()))
        );
        assert!(Override::parse("controllerArgs=2").is_err());
        assert!(Override::parse("Khepera.=2").is_err());
    }

    #[test]
    fn a_robot_with_a_network_moves_into_another_world() {
        let source = "Khepera { controller \"neural\" network NeuralNetwork { inputs [ \"bias\" ] weights [ 1 2 ] } turret PanoramicTurret { iBda 10 } }\n";
        let overrides = network_overrides(source).unwrap();
        let target = "Arena { }\nKhepera { controller \"regatta\" controllerArgs \"irGain=2\" turret PanoramicTurret { lambda 5 } }\n";
        let out = apply_overrides(target, &overrides).unwrap();
        assert_eq!(
            out,
            "Arena { }\nKhepera { network NeuralNetwork { inputs [ \"bias\" ] weights [ 1 2 ] } controller \"neural\" controllerArgs [ ] turret PanoramicTurret { iBda 10 } }\n"
        );
        assert_eq!(
            network_overrides("Khepera { controller \"regatta\" }"),
            Err(EditError::NoNeuralRobot)
        );
        // A world without that robot type says so.
        assert_eq!(
            apply_overrides("Arena { }", &overrides),
            Err(EditError::NoSuchNode("Khepera".into()))
        );
    }

    #[test]
    fn weights_are_written_exactly_in_canonical_form() {
        let world =
            "#VRML_SIM R2023b utf8\nKhepera { network NeuralNetwork { weights [ 1 2 ] } }\n";
        let weights = [0.1 + 0.2, -1e-300, 12345.678901234567];
        let out = with_weights(world, &weights).unwrap();
        let parsed = regatta_parser::parse(&out);
        let mut found = Vec::new();
        regatta_parser::syntax::walk_nodes(&parsed.file, &mut |n| {
            if let NodeKind::Instance {
                body: Some(body), ..
            } = &n.kind
            {
                for item in &body.items {
                    if let BodyItem::Field(f) = item {
                        if f.name.text == "weights" {
                            if let FieldValue::Value(v) = &f.value {
                                if let regatta_parser::syntax::Items::Numbers(list) = &v.items {
                                    found = list.values.clone();
                                }
                            }
                        }
                    }
                }
            }
        });
        assert_eq!(found, weights.to_vec());
        // Canonical: formatting again changes nothing.
        assert_eq!(regatta_parser::format::format(&parsed.file, &out), out);
        assert_eq!(
            with_weights("Khepera { }", &[1.0]),
            Err(EditError::NoNetwork)
        );
    }
}
