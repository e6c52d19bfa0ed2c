//! `regatta schema`: the node catalogue and the standard PROTOs as a world author needs them.

use std::fmt::Write;

use anyhow::bail;
use regatta_schema::{catalogue::did_you_mean, standard_protos, Catalogue, NodeSpec, ProtoSpec};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// Show only this node type or standard PROTO (an alias such as Pose works too).
    node: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Markdown)]
    format: Format,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Format {
    Markdown,
    Json,
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let catalogue = Catalogue::get();
    let all_protos = standard_protos();
    let (specs, protos): (Vec<&NodeSpec>, Vec<&ProtoSpec>) = match &args.node {
        Some(name) => {
            match (
                catalogue.lookup(name),
                all_protos.iter().find(|p| &p.name == name),
            ) {
                (_, Some(proto)) => (Vec::new(), vec![proto]),
                (Some(id), None) => (vec![catalogue.spec(id)], Vec::new()),
                (None, None) => {
                    let names = catalogue
                        .names()
                        .chain(all_protos.iter().map(|p| p.name.as_str()));
                    let hint = did_you_mean(name, names)
                        .map(|c| format!(" (did you mean '{c}'?)"))
                        .unwrap_or_default();
                    bail!("no node type or PROTO named '{name}'{hint}; `regatta schema` lists them all");
                }
            }
        }
        None => (
            catalogue.nodes.iter().collect(),
            all_protos.iter().collect(),
        ),
    };
    match args.format {
        Format::Json => {
            let mut entries: Vec<serde_json::Value> = Vec::new();
            for spec in &specs {
                entries.push(serde_json::to_value(spec)?);
            }
            for proto in &protos {
                entries.push(serde_json::to_value(proto)?);
            }
            println!("{}", serde_json::to_string_pretty(&entries)?);
        }
        Format::Markdown => {
            print!("{}", markdown(&specs));
            if !protos.is_empty() && args.node.is_none() {
                println!("# Standard PROTOs\n\nBuilt in: a world uses them without an EXTERNPROTO line.\n");
            }
            print!("{}", proto_markdown(&protos));
        }
    }
    Ok(Outcome::Clean)
}

fn proto_markdown(protos: &[&ProtoSpec]) -> String {
    let mut out = String::new();
    for proto in protos {
        let _ = writeln!(out, "## {} (PROTO)\n\n{}\n", proto.name, proto.doc);
        let _ = writeln!(
            out,
            "A {} underneath; stands where {} nodes go.\n",
            proto.root,
            proto.classes.join(" or ")
        );
        let _ = writeln!(out, "| field | type | default | doc |\n|---|---|---|---|");
        for field in &proto.fields {
            let _ = writeln!(
                out,
                "| `{}` | {} | `{}` | {} |",
                field.name,
                field.type_name,
                field.default.replace('|', "\\|"),
                field.doc.replace('|', "\\|")
            );
        }
        out.push('\n');
    }
    out
}

fn markdown(specs: &[&NodeSpec]) -> String {
    let mut out = String::new();
    for spec in specs {
        let _ = writeln!(out, "## {}\n\n{}\n", spec.name, spec.doc);
        if !spec.aliases.is_empty() {
            let _ = writeln!(out, "Also written: {}.\n", spec.aliases.join(", "));
        }
        let _ = writeln!(
            out,
            "Stands where {} nodes go.\n",
            spec.classes.join(" or ")
        );
        let _ = writeln!(
            out,
            "| field | type | default | allowed | doc |\n|---|---|---|---|---|"
        );
        for field in &spec.fields {
            let mut allowed = Vec::new();
            if let Some(above) = field.above {
                allowed.push(format!("> {above}"));
            }
            if let Some(min) = field.min {
                allowed.push(format!("≥ {min}"));
            }
            if let Some(max) = field.max {
                allowed.push(format!("≤ {max}"));
            }
            if !field.values.is_empty() {
                allowed.push(
                    field
                        .values
                        .iter()
                        .map(|v| format!("\"{v}\""))
                        .collect::<Vec<_>>()
                        .join(", "),
                );
            }
            if !field.nodes.is_empty() {
                allowed.push(format!("{} nodes", field.nodes.join("/")));
            }
            if let Some(count) = field.count {
                allowed.push(format!("{count} items"));
            }
            let _ = writeln!(
                out,
                "| `{}` | {} | `{}` | {} | {} |",
                field.name,
                field.type_name,
                field.default.replace('|', "\\|"),
                allowed.join("; "),
                field.doc.replace('|', "\\|")
            );
        }
        out.push('\n');
    }
    out
}
