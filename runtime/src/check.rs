//! Checks of a typed scene that need the runtime's knowledge, run by `regatta check` and by
//! every command before it runs a world: controllers and their arguments
//! ([`crate::controllers::check::check_scene`]), each robot's network against its inputs and
//! outputs ([`check_networks`]), and time steps the simulation cannot follow.

use regatta_parser::Diagnostic;
use regatta_schema::{Checked, FileDiagnostic, Scene, Value};

use crate::compile::network::{network_from_scene, NetworkError};
use crate::compile::rig::control_steps;
use crate::compile::world_settings;
use crate::sim::MAX_SUB_STEPS;

/// Largest |gaussian| a Box–Muller draw from 53-bit uniforms can give (√(−2 ln 2⁻⁵³)).
const GAUSSIAN_BOUND: f64 = 8.6;

/// Adds every runtime diagnostic to `checked`.
pub fn check_scene(checked: &mut Checked) {
    check_scene_with(checked, &|_| false);
}

/// [`check_scene`] for a world whose project has controller programs of its own:
/// `is_program(name)` says whether `name` is one (Webots' `controllers/NAME/`), which a robot
/// may then name whatever its arguments.
pub fn check_scene_with(checked: &mut Checked, is_program: &dyn Fn(&str) -> bool) {
    crate::controllers::check::check_scene(checked, is_program);
    let networks = check_networks(&checked.scene);
    checked.diagnostics.extend(networks);
    check_time_step(checked);
    check_control_periods(checked);
    checked.sort_diagnostics();
}

/// Every robot's network checked, as diagnostics at the field they are about (what
/// `regatta check` adds to the schema's): sizes against inputs and outputs, retina inputs
/// without a turret, and controller "neural" without a network.
pub fn check_networks(scene: &Scene) -> Vec<FileDiagnostic> {
    let time_step = world_settings(scene).time_step;
    let mut diagnostics = Vec::new();
    for robot in scene.find("DifferentialWheels") {
        // A CTRNN integrates once per controller call; a period that is not whole steps is
        // reported by `check_control_periods`.
        let period = control_steps(scene.float(robot, "controlPeriod"), time_step)
            .map_or(time_step, |steps| steps as f64 * time_step);
        let panoramic = scene
            .child(robot, "turret")
            .is_some_and(|t| scene.type_name(t) == "PanoramicTurret");
        let result = match scene.child(robot, "network") {
            Some(network) => network_from_scene(scene, network, panoramic, period)
                .map(|_| ())
                .map_err(|e| (network, e)),
            None if scene.string(robot, "controller") == "neural" => {
                Err((robot, NetworkError::NoNetwork))
            }
            None => Ok(()),
        };
        if let Err((node, error)) = result {
            let field = match error {
                NetworkError::NoNetwork => "controller",
                _ => error.field(),
            };
            let at = scene.value_span(node, field);
            let label = match &error {
                NetworkError::WeightCount { expected, .. } => {
                    format!("{expected} weights expected")
                }
                _ => format!("in '{field}'"),
            };
            diagnostics.push(FileDiagnostic {
                file: at.file,
                diagnostic: Diagnostic::error(at.span, error.to_string())
                    .with_label(label)
                    .with_code("network"),
            });
        }
    }
    diagnostics
}

/// Refuses a time step at which a robot could cross more than half its body radius in each of
/// [`MAX_SUB_STEPS`] collision sub-steps: beyond it, bodies could pass through walls or each
/// other. The bound is the robot's top speed (its commands' limit or `maxSpeed`, with the
/// largest wheel noise a draw can give).
fn check_time_step(checked: &mut Checked) {
    let scene = &checked.scene;
    let Some(&info) = scene.find("WorldInfo").first() else {
        return;
    };
    let time_step = scene.float(info, "basicTimeStep") / 1000.0;
    let mut worst: Option<(f64, String, f64)> = None;
    for id in scene.find("DifferentialWheels") {
        let top = (127.0 * 100.0 / scene.float(id, "encoderResolution"))
            .min(scene.float(id, "maxSpeed"))
            * (1.0 + GAUSSIAN_BOUND * scene.float(id, "wheelSpeedNoise"));
        let radius = scene.float(id, "bodyRadius");
        let longest = MAX_SUB_STEPS as f64 * 0.5 * radius / top;
        if worst.as_ref().is_none_or(|(l, _, _)| longest < *l) {
            let name = match scene.field(id, "name") {
                Value::String(name) => name.clone(),
                _ => String::new(),
            };
            worst = Some((longest, name, top));
        }
    }
    let Some((longest, robot, top)) = worst else {
        return;
    };
    if time_step <= longest {
        return;
    }
    let node = scene.node(info);
    let index = scene.spec(info).field_index("basicTimeStep");
    let at = index
        .and_then(|i| node.value_span_at(i))
        .unwrap_or(node.origin);
    checked.diagnostics.push(FileDiagnostic {
        file: at.file,
        diagnostic: Diagnostic::error(
            at.span,
            format!(
                "a basicTimeStep of {} ms is too long to simulate without bodies passing through each other",
                time_step * 1000.0
            ),
        )
        .with_label(format!("at most {:.0} ms here", (longest * 1000.0).floor()))
        .with_note(format!(
            "robot '{robot}' may move at {top:.3} m/s: in one step it could cross more than {MAX_SUB_STEPS} half body radii, the collision sub-steps a step may take"
        ))
        .with_code("time-step"),
    });
}

/// Refuses a robot's `controlPeriod` that is not a whole number of physics steps: a
/// controller runs on the step grid, so such a period could only be rounded, and the
/// rounding would change with the step.
fn check_control_periods(checked: &mut Checked) {
    let scene = &checked.scene;
    let time_step = world_settings(scene).time_step;
    let mut found = Vec::new();
    for id in scene.find("DifferentialWheels") {
        let period = scene.float(id, "controlPeriod");
        if control_steps(period, time_step).is_ok() {
            continue;
        }
        let at = scene.value_span(id, "controlPeriod");
        found.push(FileDiagnostic {
            file: at.file,
            diagnostic: Diagnostic::error(
                at.span,
                format!(
                    "a controlPeriod of {period} ms is not a whole number of {} ms steps",
                    time_step * 1000.0
                ),
            )
            .with_label("not a multiple of basicTimeStep")
            .with_note("a controller runs on the physics step's grid: make basicTimeStep divide the period, or the period a multiple of the step")
            .with_code("control-period"),
        });
    }
    checked.diagnostics.extend(found);
}
