//! `regatta schema`: the node catalogue as a world author needs it.

use std::fmt::Write;

use anyhow::bail;
use regatta_schema::{catalogue::did_you_mean, Catalogue, NodeSpec};

use crate::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// Show only this node type (an alias such as Pose works too).
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
    let specs: Vec<&NodeSpec> = match &args.node {
        Some(name) => match catalogue.lookup(name) {
            Some(id) => vec![catalogue.spec(id)],
            None => {
                let hint = did_you_mean(name, catalogue.names())
                    .map(|c| format!(" (did you mean '{c}'?)"))
                    .unwrap_or_default();
                bail!("no node type named '{name}'{hint}; `regatta schema` lists them all");
            }
        },
        None => catalogue.nodes.iter().collect(),
    };
    match args.format {
        Format::Json => println!("{}", serde_json::to_string_pretty(&specs)?),
        Format::Markdown => print!("{}", markdown(&specs)),
    }
    Ok(Outcome::Clean)
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
