//! The `neural` controller: K-Team's Braitenberg network kept as data reproduces the built-in
//! `braitenberg` controller bit for bit, and `check` measures a network against its inputs
//! and outputs with file:line:col errors.

use regatta_runtime::log::{Recorder, RunInfo};
use regatta_runtime::sim::Simulation;
use regatta_tests::compile_text;

/// K-Team's weights (khepera.md) as a linear network: IR inputs are readings/1024, so
/// weights of 1024/400 = 2.56 per unit are split into the integer weights and
/// `outputScale 2.56`, and the bias neurons' 10 pulses become 10/2.56 = 3.90625.
const BRAITENBERG_NETWORK: &str = "NeuralNetwork {
    inputs [ \"bias\" \"ir\" ]
    outputActivation \"linear\"
    outputScale 2.56
    weights [ 3.90625 4 4 6 -18 -15 -5 5 3
              3.90625 -5 -15 -18 6 4 4 3 5 ]
  }";

/// An arena with obstacles to bump into, and one Khepera driven by `controller`.
fn arena(controller: &str) -> String {
    format!(
        "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" randomSeed 3 }}
Arena {{ size 0.6 0.6 }}
Buoy {{ translation 0.1 0 -0.1 }}
Buoy {{ translation -0.15 0 0.12 irReflectance 1 }}
Transform {{ translation 0.2 0.02 0.15 children [ Shape {{ geometry Box {{ size 0.05 0.04 0.12 }} }} ] }}
Khepera {{ translation 0 0 0.2 rotation 0 1 0 0.7 {controller} }}
"
    )
}

fn log_of(world: &str, steps: u64) -> Vec<u8> {
    let compiled = compile_text(world);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    let run = RunInfo {
        world_name: "arena.wbt".into(),
        world_text: String::new(),
        seed: simulation.seed,
        lenient: false,
        steps_requested: steps,
        channels: regatta_runtime::log::Channels::ALL,
        controllers: Vec::new(),
        variations: None,
    };
    let mut sink = std::io::Cursor::new(Vec::new());
    let mut recorder = Recorder::new(&mut sink, &mut simulation, &run).unwrap();
    for _ in 0..steps {
        simulation.step();
        recorder.record(&simulation).unwrap();
    }
    assert_eq!(simulation.robots[0].controller_errors, 0);
    recorder.finish(&simulation, false).unwrap();
    sink.into_inner()
}

#[test]
fn k_team_weights_as_a_network_reproduce_braitenberg_bit_for_bit() {
    let steps = 6000;
    let built_in = log_of(&arena("controller \"braitenberg\""), steps);
    let network = log_of(
        &arena(&format!(
            "controller \"neural\" network {BRAITENBERG_NETWORK}"
        )),
        steps,
    );
    assert!(built_in == network, "the logs differ");
    // The run is not trivial: the robot met obstacles (its IR network acted).
    let compiled = compile_text(&arena("controller \"braitenberg\""));
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    let mut turned = 0;
    for _ in 0..steps {
        simulation.step();
        let (l, r) = simulation.robots[0].command;
        turned += usize::from(l != r);
    }
    assert!(turned > 100, "the wheels differed in {turned} steps only");
}

fn check_short(text: &str) -> Vec<String> {
    let mut checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("net.wbt".to_owned(), text.as_bytes().to_vec()),
        &regatta_schema::Options::default(),
    );
    checked
        .diagnostics
        .extend(regatta_runtime::check::check_networks(&checked.scene));
    checked.short()
}

#[test]
fn check_measures_a_network_against_its_inputs_and_outputs() {
    let world = |network: &str, turret: &str| {
        format!(
            "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" }}\nKhepera {{\n  controller \"neural\"\n  {turret}\n  network NeuralNetwork {{\n{network}\n  }}\n}}\n"
        )
    };
    // bias + 8 IR + 4 retina sectors = 13 inputs, 3 hidden, 2 outputs: 3·13 + 2·4 = 47.
    let good =
        "    inputs [ \"bias\" \"ir\" \"retina\" ] retinaSectors 4 hidden [ 3 ]\n    weights [ "
            .to_owned()
            + &"0.1 ".repeat(47)
            + "]";
    let turret = "turret PanoramicTurret { }";
    assert_eq!(check_short(&world(&good, turret)), Vec::<String>::new());
    let short = good.replace("0.1 0.1 ]", "]");
    assert_eq!(
        check_short(&world(&short, turret)),
        vec!["net.wbt:8:13: error: the network takes 47 weights, found 45"]
    );
    // Retina inputs on a robot without a turret.
    let errors = check_short(&world(&good, ""));
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].starts_with("net.wbt:7:12: error: retina inputs need a PanoramicTurret"),
        "{errors:?}"
    );
    // A CTRNN whose time constants are shorter than the step, or too few.
    let ctrnn = "    inputs [ \"bias\" ] recurrence \"ctrnn\" timeConstants [ 0.01 0.5 ]\n    weights [ 0 0 0 0 0 0 ]";
    let errors = check_short(&world(ctrnn, ""));
    assert!(
        errors[0].starts_with(
            "net.wbt:7:56: error: time constant 0.01 s is shorter than the control period 0.032 s"
        ),
        "{errors:?}"
    );
    // controller "neural" without a network: the message points at the Khepera's field.
    let errors = check_short("#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nKhepera { controller \"neural\" }\n");
    assert_eq!(
        errors,
        vec!["net.wbt:3:11: error: controller \"neural\" needs a NeuralNetwork in the robot's 'network' field"]
    );
}

#[test]
fn a_network_with_hidden_layers_drives_the_robot_from_its_retina() {
    // A small Elman network on the regatta arena: it runs without errors and reads the retina.
    let text = std::fs::read_to_string(regatta_tests::root().join("worlds/regatta.wbt")).unwrap();
    let weights: Vec<String> = (0..(3 * (11 + 3) + 2 * 4))
        .map(|i| format!("{}", ((i * 37 % 19) as f64 - 9.0) / 10.0))
        .collect();
    let text = text.replace(
        "controller \"regatta\"",
        &format!(
            "controller \"neural\" network NeuralNetwork {{ inputs [ \"bias\" \"ir0\" \"ir5\" \"retina\" ] retinaSectors 8 hidden [ 3 ] recurrence \"elman\" weights [ {} ] }}",
            weights.join(" ")
        ),
    );
    let compiled = compile_text(&text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    simulation.run(300);
    let robot = &simulation.robots[0];
    assert_eq!(
        robot.controller_errors, 0,
        "{:?}",
        robot.last_controller_error
    );
    assert!(
        robot.updated.vision,
        "the retina is refreshed for the network"
    );
    assert!(
        robot.travel.0.abs() + robot.travel.1.abs() > 0.01,
        "the wheels turned: {:?}",
        robot.travel
    );
}

/// The regatta arena with a one-layer network over `inputs` and `weights`.
fn regatta_with_network(inputs: &str, extra: &str, weights: &[f64]) -> String {
    let text = std::fs::read_to_string(regatta_tests::root().join("worlds/regatta.wbt")).unwrap();
    let weights: Vec<String> = weights.iter().map(|w| format!("{w}")).collect();
    text.replace(
        "controller \"regatta\"",
        &format!(
            "controller \"neural\" network NeuralNetwork {{ inputs [ {inputs} ] retinaSectors 4 {extra} weights [ {} ] }}",
            weights.join(" ")
        ),
    )
}

#[test]
fn retina_inputs_name_the_turret_output_they_read() {
    // Weights for bias + 4 sectors, per wheel.
    let one: Vec<f64> = [[0.3, 0.5, -0.4, 0.2, -0.6], [0.3, -0.5, 0.4, -0.2, 0.6]].concat();
    // "retina:odd" reads what "retina" reads with retinaFilter "odd".
    let named = regatta_with_network("\"bias\" \"retina:odd\"", "", &one);
    let chosen = regatta_with_network("\"bias\" \"retina\"", "retinaFilter \"odd\"", &one);
    assert_eq!(log_of(&named, 400), log_of(&chosen, 400));
    // Two outputs side by side: with the odd filter's weights at zero the network drives as
    // the raw retina alone does, and with them it drives otherwise.
    let with = |odd: [f64; 4]| {
        let mut weights = Vec::new();
        for wheel in 0..2 {
            weights.extend_from_slice(&one[wheel * 5..wheel * 5 + 5]);
            weights.extend_from_slice(&odd);
        }
        regatta_with_network("\"bias\" \"retina\" \"retina:odd\"", "", &weights)
    };
    let raw = regatta_with_network("\"bias\" \"retina\"", "", &one);
    assert_eq!(log_of(&with([0.0; 4]), 400), log_of(&raw, 400));
    assert_ne!(
        log_of(&with([0.9, -0.9, 0.9, -0.9]), 400),
        log_of(&raw, 400)
    );
}
