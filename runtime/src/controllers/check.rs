//! Checks a world's `controller` and `controllerArgs` against the registry (Webots names
//! through [`super::webots`]), at the user's lines.

use regatta_parser::{Diagnostic, Severity};
use regatta_schema::catalogue::did_you_mean as did_you_mean_in;
use regatta_schema::{Checked, FileDiagnostic, Value};

use super::webots::{resolve, Resolution, LENIENT_DEFAULT, MAPPED};
use super::{argument, find, items, known_names, CONTROLLERS};

/// Checks every robot's `controller` and `controllerArgs` against the registry, adding a
/// diagnostic per problem at the line that wrote the value (the user's line, through PROTOs).
/// An unknown controller or argument is an error; in a check whose scene was read leniently
/// (every error a warning), it is a warning and the robot runs `none`, or without that
/// argument. A name for which `is_program` holds is a program of the world's project (run as
/// Webots runs it, its arguments its own), checked no further.
pub fn check_scene(checked: &mut Checked, is_program: &dyn Fn(&str) -> bool) {
    let lenient = !checked.strict;
    let catalogue = regatta_schema::Catalogue::get();
    let mut found = Vec::new();
    for id in checked.scene.walk() {
        let node = checked.scene.node(id);
        let spec = catalogue.spec(node.spec);
        let (Some(controller), Some(args)) = (
            spec.field_index("controller"),
            spec.field_index("controllerArgs"),
        ) else {
            continue;
        };
        found.push((id, controller, args));
    }
    for (id, controller_index, args_index) in found {
        let node = &checked.scene.nodes[id.index()];
        let name = node.fields[controller_index]
            .strings()
            .first()
            .cloned()
            .unwrap_or_default();
        let args = node.fields[args_index].strings().to_vec();
        let at = |index: usize| node.value_span_at(index).unwrap_or(node.origin);
        let (name_at, args_at) = (at(controller_index), at(args_index));
        let mut problems: Vec<(regatta_schema::scene::Origin, Diagnostic)> = Vec::new();
        let mut kept_args = Vec::new();
        let mut replacement = None;
        if is_program(&name) {
            continue;
        }
        match resolve(&name) {
            Resolution::Unknown => {
                let candidates = CONTROLLERS
                    .iter()
                    .map(|c| c.name)
                    .chain(MAPPED.iter().map(|(n, _, _)| *n));
                let mut diagnostic =
                    Diagnostic::error(name_at.span, format!("unknown controller \"{name}\""))
                        .with_label("no built-in controller has this name")
                        .with_note(format!(
                            "built in: {}, and the Webots names in the README",
                            known_names()
                        ))
                        .with_code("unknown-controller");
                if let Some(close) = did_you_mean_in(&name, candidates) {
                    diagnostic = diagnostic.with_note(format!("did you mean \"{close}\"?"));
                }
                if lenient {
                    diagnostic = diagnostic
                        .with_note(format!("lenient mode runs \"{LENIENT_DEFAULT}\" instead"));
                    replacement = Some((LENIENT_DEFAULT, Vec::new()));
                }
                problems.push((name_at, diagnostic));
            }
            // Driven from outside (`regatta serve`): `run` says so, `serve` drives it.
            Resolution::External(_) => {}
            Resolution::Builtin(builtin, why) if builtin != name && !why.is_empty() => {
                // A Webots name: its controllerArgs were for Webots' program, not regatta's.
                if items(&args).next().is_some() {
                    let diagnostic = Diagnostic::warning(
                        args_at.span,
                        format!(
                            "controllerArgs of Webots' \"{name}\" are not used: it runs as regatta's \"{builtin}\" ({why})"
                        ),
                    )
                    .with_label("ignored")
                    .with_code("controller-args");
                    problems.push((args_at, diagnostic));
                    replacement = Some((builtin, Vec::new()));
                }
            }
            Resolution::Builtin(builtin, _) => {
                let Some(spec) = find(builtin) else {
                    continue;
                };
                for item in items(&args) {
                    match argument(spec, item) {
                        Ok(_) => kept_args.push(item.to_owned()),
                        Err(error) => {
                            let mut diagnostic = Diagnostic::error(
                                args_at.span,
                                format!("controllerArgs of \"{}\": {error}", spec.name),
                            )
                            .with_label("in these arguments")
                            .with_code("controller-args");
                            if lenient {
                                diagnostic = diagnostic.with_note(format!("\"{item}\" is ignored"));
                            }
                            problems.push((args_at, diagnostic));
                        }
                    }
                }
                if lenient {
                    replacement = Some((spec.name, kept_args));
                }
            }
        }
        if problems.is_empty() {
            continue;
        }
        for (origin, mut diagnostic) in problems {
            if lenient {
                diagnostic.severity = Severity::Warning;
            }
            checked.diagnostics.push(FileDiagnostic {
                file: origin.file,
                diagnostic,
            });
        }
        // What runs instead, where the world goes on (lenient mode, ignored Webots arguments).
        if let Some((controller, args)) = replacement {
            let node = &mut checked.scene.nodes[id.index()];
            node.fields[controller_index] = Value::String(controller.to_owned());
            node.fields[args_index] = Value::Strings(args);
        }
    }
}
