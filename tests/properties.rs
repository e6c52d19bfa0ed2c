//! Property tests: formatting is idempotent and keeps the tree on generated worlds, and no
//! input (arbitrary bytes, deep nesting, PROTO explosions) makes parsing or typing panic.

use proptest::prelude::*;
use regatta_parser::format::{dump, format};
use regatta_parser::{parse, SourceText};
use regatta_schema::{check, Options};

/// A number in one of the shapes real files use.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        (-1000i32..1000).prop_map(|i| i.to_string()),
        (-1.0e3f64..1.0e3).prop_map(|x| format!("{x}")),
        (0u32..1000).prop_map(|i| format!(".{i}")),
        (-50i32..50).prop_map(|e| format!("1e{e}")),
        (0u32..100).prop_map(|i| format!("{i}.")),
        (0u32..0xffffff).prop_map(|i| format!("0x{i:X}")),
    ]
}

fn string_literal() -> impl Strategy<Value = String> {
    "[a-z #{}\\[\\],\\\\\"]{0,12}".prop_map(|s| {
        let escaped: String = s
            .chars()
            .flat_map(|c| match c {
                '"' => vec!['\\', '"'],
                '\\' => vec!['\\', '\\'],
                other => vec![other],
            })
            .collect();
        format!("\"{escaped}\"")
    })
}

fn ident() -> impl Strategy<Value = String> {
    "[A-Za-z_][A-Za-z0-9_+-]{0,8}".prop_filter("not a keyword", |s| {
        !matches!(
            s.as_str(),
            "DEF"
                | "USE"
                | "PROTO"
                | "EXTERNPROTO"
                | "IS"
                | "TRUE"
                | "FALSE"
                | "NULL"
                | "ROUTE"
                | "TO"
                | "IMPORTABLE"
                | "hidden"
                | "field"
                | "vrmlField"
                | "hiddenField"
                | "deprecatedField"
                | "unconnectedField"
                | "exposedField"
                | "eventIn"
                | "eventOut"
        )
    })
}

/// Separators between tokens: blanks, commas, newlines and comments.
fn separator() -> impl Strategy<Value = String> {
    prop_oneof![
        Just(" ".to_owned()),
        Just("\n".to_owned()),
        Just(", ".to_owned()),
        Just("\n\n  ".to_owned()),
        "[a-z ]{0,10}".prop_map(|c| format!(" # {c}\n")),
    ]
}

fn node(depth: u32) -> BoxedStrategy<String> {
    let leaf_value = prop_oneof![
        prop::collection::vec(number(), 1..5).prop_map(|v| v.join(" ")),
        prop::collection::vec(number(), 0..7).prop_map(|v| format!("[ {} ]", v.join(", "))),
        string_literal(),
        prop::collection::vec(string_literal(), 0..3).prop_map(|v| format!("[{}]", v.join(" "))),
        Just("TRUE".to_owned()),
        Just("FALSE".to_owned()),
        Just("NULL".to_owned()),
    ];
    let value: BoxedStrategy<String> = if depth == 0 {
        leaf_value.boxed()
    } else {
        prop_oneof![
            3 => leaf_value,
            1 => node(depth - 1),
            1 => prop::collection::vec(node(depth - 1), 0..3).prop_map(|v| format!("[ {} ]", v.join(" "))),
            1 => ident().prop_map(|d| format!("USE {d}")),
        ]
        .boxed()
    };
    let field =
        (ident(), value, separator()).prop_map(|(name, value, sep)| format!("{name} {value}{sep}"));
    (
        prop::option::of(ident()),
        ident(),
        prop::collection::vec(field, 0..4),
        separator(),
    )
        .prop_map(|(def, type_name, fields, sep)| {
            let def = def.map(|d| format!("DEF {d} ")).unwrap_or_default();
            format!("{def}{type_name} {{{sep}{}}}", fields.concat())
        })
        .boxed()
}

fn world() -> impl Strategy<Value = String> {
    (
        prop::collection::vec((node(3), separator()), 0..5),
        any::<bool>(),
    )
        .prop_map(|(nodes, header)| {
            let mut text = if header {
                "#VRML_SIM R2023b utf8\n".to_owned()
            } else {
                String::new()
            };
            for (node, sep) in nodes {
                text.push_str(&node);
                text.push_str(&sep);
            }
            text
        })
}

/// An instance of one of `count` PROTOs, maybe with field values (which may instantiate more).
fn instance(count: usize, depth: u32) -> BoxedStrategy<String> {
    let plain = (0..count, prop::option::of(-2.0f64..2.0)).prop_map(|(k, size)| match size {
        Some(size) => format!("P{k} {{ size {size:.3} }}"),
        None => format!("P{k} {{ }}"),
    });
    if depth == 0 {
        return plain.boxed();
    }
    prop_oneof![
        3 => plain,
        1 => (0..count, prop::collection::vec(instance(count, depth - 1), 0..4))
            .prop_map(|(k, kids)| format!("P{k} {{ kids [ {} ] }}", kids.join(" "))),
        1 => (0..count, instance(count, depth - 1))
            .prop_map(|(k, one)| format!("DEF D{k} P{k} {{ one {one} }}")),
        1 => (0..count).prop_map(|k| format!("USE D{k}")),
    ]
    .boxed()
}

/// A system of PROTOs whose bodies and defaults instantiate each other (earlier ones, later
/// ones, themselves), pass fields on with IS, compute with templates, copy with USE.
fn proto_system() -> impl Strategy<Value = String> {
    (2usize..7).prop_flat_map(|count| {
        (
            prop::collection::vec(
                (
                    prop::collection::vec(instance(count, 2), 0..5),
                    prop::collection::vec(instance(count, 1), 0..3),
                    prop::option::of(instance(count, 1)),
                    1usize..12,
                ),
                count,
            ),
            prop::collection::vec(instance(count, 2), 1..4),
        )
            .prop_map(move |(protos, world)| {
                let mut text = String::from("#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\n");
                for (k, (body, defaults, one, copies)) in protos.iter().enumerate() {
                    let one = one.clone().unwrap_or_else(|| "NULL".to_owned());
                    let repeated = vec![body.join(" "); *copies].join(" ");
                    text.push_str(&format!(
                        "PROTO P{k} [\n  field SFFloat size 1\n  field MFNode kids [ {} ]\n  field SFNode one {one}\n] {{\n  Transform {{\n    scale %<= fields.size.value >% 1 1\n    children [ {repeated} Group {{ children IS kids }} Transform {{ children [ ] }} ]\n  }}\n}}\n",
                        defaults.join(" ")
                    ));
                }
                text.push_str(&world.join("\n"));
                text.push('\n');
                text
            })
    })
}

/// Checks `text` on a thread of its own (a test thread's 2 MiB stack) and gives up, failing,
/// if it has not finished after a minute: a hang detector, not a timing.
fn check_within_a_minute(text: String, options: Options) -> Result<usize, String> {
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            let checked = check(
                SourceText::from_bytes("system.wbt".to_owned(), text.into_bytes()),
                &options,
            );
            let _ = send.send(checked.scene.nodes.len());
        })
        .map_err(|e| e.to_string())?;
    receive
        .recv_timeout(std::time::Duration::from_secs(60))
        .map_err(|_| "the check did not finish within a minute".to_owned())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// PROTOs that instantiate each other in every way: no panic, no stack overflow, no hang,
    /// and never more nodes than the limit.
    #[test]
    fn proto_systems_expand_within_their_limits(text in proto_system(), nodes in 50usize..5000, depth in 2usize..40) {
        let mut options = Options::default();
        options.limits.nodes = nodes;
        options.limits.proto_depth = depth;
        let built = check_within_a_minute(text.clone(), options);
        prop_assert!(built.is_ok(), "{text}\n{built:?}");
        prop_assert!(built.unwrap_or(0) <= nodes, "{text}");
    }

    #[test]
    fn generated_worlds_parse_cleanly(text in world()) {
        let parsed = parse(&text);
        prop_assert!(parsed.diagnostics.is_empty(), "{text}\n{:?}", parsed.diagnostics);
    }

    #[test]
    fn fmt_is_idempotent(text in world()) {
        let parsed = parse(&text);
        let once = format(&parsed.file, &text);
        let reparsed = parse(&once);
        let twice = format(&reparsed.file, &once);
        prop_assert_eq!(&once, &twice);
    }

    #[test]
    fn parse_of_fmt_equals_parse(text in world()) {
        let parsed = parse(&text);
        let once = format(&parsed.file, &text);
        let reparsed = parse(&once);
        prop_assert!(reparsed.diagnostics.is_empty(), "{}", once);
        prop_assert_eq!(dump(&parsed.file, &text, false), dump(&reparsed.file, &once, false));
        prop_assert_eq!(parsed.file.comments.len(), reparsed.file.comments.len());
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let source = SourceText::from_bytes("fuzz".to_owned(), bytes);
        let parsed = parse(&source.text);
        let _ = format(&parsed.file, &source.text);
        let _ = check(source, &Options::default());
    }

    #[test]
    fn world_shaped_noise_never_panics(text in "[A-Za-z{}\\[\\]\"#%<>=,. 0-9\n-]{0,300}") {
        let parsed = parse(&text);
        let _ = format(&parsed.file, &text);
        for diagnostic in &parsed.diagnostics {
            let _ = diagnostic.render("noise", &text, false);
        }
        let _ = check(SourceText::from_bytes("noise".to_owned(), text.into_bytes()), &Options { strict: false, ..Options::default() });
    }
}

#[test]
fn deep_nesting_is_reported_not_overflowed() {
    let text = "Transform { children [ ".repeat(100_000);
    let parsed = parse(&text);
    assert!(parsed
        .diagnostics
        .iter()
        .any(|d| d.message.contains("nested deeper")));
    let _ = format(&parsed.file, &text);
    let _ = check(
        SourceText::from_bytes("deep.wbt".to_owned(), text.clone().into_bytes()),
        &Options::default(),
    );
    // Just under the limit, closed properly: typed and formatted without trouble.
    let depth = regatta_parser::MAX_DEPTH - 1;
    let closed = format!(
        "{}{}",
        "Transform { children [ ".repeat(depth),
        "] } ".repeat(depth)
    );
    let checked = check(
        SourceText::from_bytes("deep.wbt".to_owned(), closed.into_bytes()),
        &Options::default(),
    );
    assert!(!checked.has_errors(), "{:?}", checked.short());
    let brackets = "[".repeat(200_000);
    let parsed = parse(&format!("Group {{ children {brackets} }}"));
    assert!(parsed.has_errors());
}

#[test]
fn exponential_proto_expansion_is_bounded() {
    // Each level instantiates the one below twice: 2^40 nodes if unbounded.
    let mut text = String::from("#VRML_SIM R2023b utf8\nPROTO L0 [] { Group { } }\n");
    for level in 1..=40 {
        text.push_str(&format!(
            "PROTO L{level} [] {{ Group {{ children [ L{} {{ }} L{} {{ }} ] }} }}\n",
            level - 1,
            level - 1
        ));
    }
    text.push_str("L40 { }\n");
    let checked = check(
        SourceText::from_bytes("bomb.wbt".to_owned(), text.into_bytes()),
        &Options::default(),
    );
    let limits: Vec<&str> = checked
        .diagnostics
        .iter()
        .filter(|d| d.diagnostic.code == "limit")
        .map(|d| d.diagnostic.message.as_str())
        .collect();
    assert_eq!(limits.len(), 1, "{:?}", checked.short());
    assert!(
        limits[0].contains("more than the limit of 1000000"),
        "{limits:?}"
    );
    // Refused before anything was built.
    assert!(
        checked.scene.nodes.len() < 10,
        "{}",
        checked.scene.nodes.len()
    );
}

mod worlds_that_check {
    //! Worlds that pass the checker must compile, simulate and render without panicking,
    //! whatever their (valid) numbers: degenerate scales, far positions, zero lights.
    use proptest::prelude::*;
    use regatta_parser::SourceText;
    use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
    use regatta_runtime::sim::Simulation;
    use regatta_schema::{check, Options};

    fn number(range: std::ops::Range<f64>) -> impl Strategy<Value = String> {
        range.prop_map(|x| format!("{x:.4}"))
    }

    fn shape() -> impl Strategy<Value = String> {
        let geometry = prop_oneof![
            (number(0.001..2.0), number(0.001..2.0), number(0.001..2.0)).prop_map(|(a, b, c)| format!("Box {{ size {a} {b} {c} }}")),
            (number(0.001..1.0), number(0.001..1.0)).prop_map(|(r, h)| format!("Cylinder {{ radius {r} height {h} }}")),
            (number(0.001..1.0), number(0.001..1.0)).prop_map(|(r, h)| format!("Cone {{ bottomRadius {r} height {h} }}")),
            number(0.001..1.0).prop_map(|r| format!("Sphere {{ radius {r} }}")),
            Just("IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0.5 0.2 0, 0 1 0 ] } coordIndex [ 0 1 2 3 4 -1, 0 0 0 -1, 7 8 9 -1 ] }".to_owned()),
        ];
        let material = (number(0.0..1.0), number(0.0..1.0), number(0.0..1.0)).prop_map(|(d, e, r)| format!("Material {{ diffuseColor {d} {d} {d} emissiveColor {e} 0 0 irReflectance {r} }}"));
        let transform = (
            number(-3.0..3.0),
            number(-0.5..0.5),
            number(-3.0..3.0),
            number(-7.0..7.0),
            number(0.001..3.0),
            prop::bool::ANY,
        );
        (geometry, material, transform).prop_map(|(g, m, (x, y, z, angle, scale, tilt))| {
            let axis = if tilt { "1 0 0" } else { "0 1 0" };
            format!("Transform {{ translation {x} {y} {z} rotation {axis} {angle} scale {scale} {scale} {scale} children [ Shape {{ appearance Appearance {{ material {m} }} geometry {g} }} ] }}\n")
        })
    }

    fn world() -> impl Strategy<Value = String> {
        let light = prop_oneof![
            number(0.0..2.0).prop_map(|i| format!(
                "DirectionalLight {{ direction 0.2 -1 0.1 intensity {i} }}\n"
            )),
            (number(-1.0..1.0), number(0.0..5.0), prop::bool::ANY).prop_map(|(x, i, s)| format!(
                "PointLight {{ location {x} 0.2 0 intensity {i} castShadows {} }}\n",
                if s { "TRUE" } else { "FALSE" }
            )),
            Just(String::new()),
        ];
        let robot = (
            number(-2.0..2.0),
            number(-2.0..2.0),
            number(-4.0..4.0),
            prop_oneof![Just("regatta"), Just("braitenberg"), Just("none")],
            prop_oneof![Just("paper"), Just("exact")],
            1u32..4,
            1u32..17,
        );
        (prop::collection::vec(shape(), 0..6), light, prop::collection::vec(robot, 1..3)).prop_map(|(shapes, light, robots)| {
            let mut text = String::from("#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\n");
            text.push_str(&light);
            for s in shapes {
                text.push_str(&s);
            }
            for (i, (x, z, heading, controller, optics, samples, stride)) in robots.into_iter().enumerate() {
                text.push_str(&format!(
                    "Khepera {{ name \"k{i}\" translation {x} 0 {z} rotation 0 1 0 {heading} controller \"{controller}\" turret PanoramicTurret {{ optics \"{optics}\" samples {samples} stride {stride} filters [ \"raw\" \"odd\" \"bandpass\" ] }} }}\n"
                ));
            }
            text
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        #[test]
        fn checked_worlds_compile_simulate_and_render(text in world()) {
            let checked = check(SourceText::from_bytes("random.wbt".to_owned(), text.clone().into_bytes()), &Options::default());
            prop_assert!(!checked.has_errors(), "{}\n{}", text, checked.render(false));
            let compiled = regatta_runtime::compile(&checked.scene);
            let mut simulation = Simulation::new(&compiled, Some(3)).unwrap();
            simulation.run(20);
            for robot in &simulation.robots {
                prop_assert!(robot.pose.x.is_finite() && robot.pose.z.is_finite());
                if let Some(turret) = &robot.panoramic {
                    prop_assert!(turret.output.analog.iter().all(|a| a.is_finite()));
                }
            }
            // The ray-casting reference renders the same world too.
            let renderer = Renderer::new(&compiled.graph, &compiled.plan, true);
            let poses = regatta_tests::start_poses(&compiled);
            let view = renderer.view(&compiled.plan, &poses, 0);
            if let Some(regatta_runtime::compile::rig::TurretRig::Panoramic(rig)) = &compiled.rig.robots[0].turret {
                let mut retina = Panoramic::new(rig);
                let mut out = RetinaOutput::default();
                retina.update(&renderer, &view, compiled.rig.robots[0].start, 0.0, &mut out);
                prop_assert!(out.analog.iter().all(|a| a.is_finite()));
            }
        }
    }
}

/// Found by `arbitrary_bytes_never_panic`: a list left open whose last token ends in a
/// multi-byte character (here U+FFFD from an invalid byte) once made `fmt` slice inside it.
#[test]
fn an_unclosed_list_ending_inside_a_character_formats() {
    let source = SourceText::from_bytes("cut".to_owned(), vec![58, 123, 58, 91, 48, 0, 128]);
    let parsed = parse(&source.text);
    let _ = format(&parsed.file, &source.text);
    let text = "Group { children [ 0 1é";
    let parsed = parse(text);
    let _ = format(&parsed.file, text);
}
