//! Webots worlds at the library level: each stand-in's test world compiles to what its
//! expected summary says (`tests/data/webots/*.expected`, `REGATTA_BLESS=1` rewrites them), and
//! the corpus's R2020a and R2023b khepera.wbt are the same world up to the axis change, and
//! `braitenberg` weighs the Thymio's seven sensors by heading.

use regatta_runtime::compile::rig::TurretRig;
use regatta_runtime::compile::Compiled;
use regatta_runtime::sim::Simulation;
use regatta_tests::{corpus, expect_file, files_with, root};

fn round(x: f64) -> f64 {
    let r = (x * 1e6).round() / 1e6;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// What a test world compiles to, in a few stable lines.
fn summary(checked: &regatta_schema::Checked, compiled: &Compiled) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let scene = &checked.scene;
    let _ = writeln!(out, "up {:?}, objects {:?}", scene.up_axis, scene.objects);
    for s in &checked.substitutions {
        let _ = writeln!(out, "stand-in {} for {}", s.name, s.url);
    }
    for p in &compiled.graph.primitives {
        let kind = format!("{:?}", p.shape);
        let kind = kind.split([' ', '(', '{']).next().unwrap_or("");
        let material = &compiled.graph.materials[p.material];
        let b = p.bounds;
        let _ = writeln!(
            out,
            "{kind} {:?} x {}…{} y {}…{} z {}…{} diffuse {:?} ir {}",
            p.owner,
            round(b.min.x),
            round(b.max.x),
            round(b.min.y),
            round(b.max.y),
            round(b.min.z),
            round(b.max.z),
            material.diffuse.map(round),
            round(material.ir_reflectance),
        );
    }
    for l in &compiled.graph.lights {
        let _ = writeln!(out, "light {:?} intensity {}", l.kind, round(l.intensity));
    }
    for r in &compiled.rig.robots {
        let _ = writeln!(
            out,
            "robot {} at x {} z {} heading {} floor {} ({} floors) wheels {} axle {} body {} controller {}",
            r.name,
            round(r.start.x),
            round(r.start.z),
            round(r.start.heading),
            round(r.floor_y),
            r.floors.len(),
            r.wheel_radius,
            r.axle_length,
            r.body_radius,
            r.controller
        );
        for d in r.distance_sensors.iter() {
            let _ = writeln!(
                out,
                "  {} at {:?} looking {:?}",
                d.name,
                d.position.to_array().map(round),
                d.direction.to_array().map(round)
            );
        }
        for c in &r.cameras {
            let _ = writeln!(
                out,
                "  camera {} {}×{} fov {} at {:?} looking {:?}",
                c.name,
                c.width,
                c.height,
                c.field_of_view,
                c.frame.translation.to_array().map(round),
                (c.frame.linear * glam::DVec3::X).to_array().map(round)
            );
        }
        if let Some(TurretRig::Linear(c)) = &r.turret {
            let _ = writeln!(
                out,
                "  linear camera {} at height {} pixels {} fov {}",
                c.name,
                round(c.height),
                c.pixels,
                c.field_of_view
            );
        }
    }
    for w in &compiled.warnings {
        let _ = writeln!(out, "warning: {w}");
    }
    out
}

#[test]
fn every_stand_in_world_compiles_to_its_summary() {
    let dir = root().join("tests/data/webots");
    let worlds = files_with(&dir, &["wbt"]);
    assert!(worlds.len() >= 12);
    let mut failures = Vec::new();
    for world in worlds {
        let checked = regatta_schema::check_file(&world, true).expect("readable");
        assert!(
            !checked.has_errors() && checked.diagnostics.is_empty(),
            "{}: {}",
            world.display(),
            checked.render(false)
        );
        let compiled = regatta_runtime::compile(&checked.scene);
        if let Err(e) = expect_file(
            &world.with_extension("expected"),
            &summary(&checked, &compiled),
        ) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn load(path: &std::path::Path, text: Option<&str>) -> Compiled {
    let checked = match text {
        Some(text) => regatta_schema::check(
            regatta_parser::SourceText::from_bytes(
                path.display().to_string(),
                text.as_bytes().to_vec(),
            ),
            &regatta_schema::Options {
                strict: false,
                access: regatta_schema::FileAccess::for_world(path).expect("the world's folder"),
                base_dir: path.parent().map(|p| p.to_owned()),
                ..regatta_schema::Options::default()
            },
        ),
        None => regatta_schema::check_file(path, false).expect("readable"),
    };
    assert!(!checked.has_errors(), "{}", checked.render(false));
    regatta_runtime::compile(&checked.scene)
}

fn trajectory(compiled: &Compiled, steps: usize) -> Vec<(f64, f64, f64)> {
    let mut simulation = Simulation::new(compiled, Some(1)).expect("runs");
    (0..steps)
        .map(|_| {
            simulation.step();
            let pose = simulation.robots[0].pose;
            (pose.x, pose.z, pose.heading)
        })
        .collect()
}

/// Webots' conversion of the Khepera world from NUE (R2020a) to ENU (R2023b) moved every
/// object by the axis change; regatta reads both into the same scene. The R2020a robot is
/// turned by 1.57 rad from Webots' legacy forward (−z), which faces −x, while the R2023b one
/// faces +x: with the R2020a robot turned to face +x too (rotation −π/2), both runs give the
/// same trajectory, within 1 µm for 17.6 s (550 steps). Later the two part: Webots' converter
/// rewrote the boxes' rotations with rounding of about 1e-6 rad, which the IR sensors feel
/// once the robot meets a box, and obstacle avoidance amplifies it (at 18.3 s the stall
/// escape's decision, a threshold on the commands' running means, falls a call apart).
#[test]
fn khepera_world_in_r2020a_and_r2023b_is_the_same_up_to_the_axis_change() {
    let old =
        corpus().join("webots/_versions/R2020a/projects/robots/k-team/khepera1/worlds/khepera.wbt");
    let new = corpus().join("webots/projects/robots/k-team/khepera1/worlds/khepera.wbt");
    let (a, b) = (load(&old, None), load(&new, None));
    // The same static scene: every primitive's bounds within 1 µm.
    let bounds = |c: &Compiled| {
        let mut v: Vec<[i64; 6]> = c
            .graph
            .primitives
            .iter()
            .filter(|p| p.owner == regatta_runtime::compile::graph::Owner::Static)
            .map(|p| {
                let q = |x: f64| (x * 1e6).round() as i64;
                [
                    q(p.bounds.min.x),
                    q(p.bounds.min.y),
                    q(p.bounds.min.z),
                    q(p.bounds.max.x),
                    q(p.bounds.max.y),
                    q(p.bounds.max.z),
                ]
            })
            .collect();
        v.sort();
        v
    };
    let (ba, bb) = (bounds(&a), bounds(&b));
    assert_eq!(ba.len(), bb.len());
    for (p, q) in ba.iter().zip(&bb) {
        assert!(
            p.iter().zip(q).all(|(x, y)| (x - y).abs() <= 1),
            "{p:?} vs {q:?}"
        );
    }
    let (ra, rb) = (&a.rig.robots[0], &b.rig.robots[0]);
    assert!((ra.start.x - rb.start.x).abs() < 1e-9 && (ra.start.z - rb.start.z).abs() < 1e-9);
    // Documented conventions: the R2020a robot faces -x, the R2023b one +x.
    assert!((ra.start.heading.abs() - std::f64::consts::PI).abs() < 1e-3);
    assert!(rb.start.heading.abs() < 1e-12);
    // Turned to face +x, the R2020a world runs the R2023b world's trajectory.
    let text = std::fs::read_to_string(&old).unwrap().replace(
        "rotation 0 1 0 1.57\n  name \"khepera\"",
        "rotation 0 1 0 -1.5707963267948966\n  name \"khepera\"",
    );
    let turned = load(&old, Some(&text));
    let (ta, tb) = (trajectory(&turned, 550), trajectory(&b, 550));
    let mut travelled = 0.0;
    for (step, (p, q)) in ta.iter().zip(&tb).enumerate() {
        assert!(
            (p.0 - q.0).abs() < 1e-6 && (p.1 - q.1).abs() < 1e-6,
            "step {step}: {p:?} vs {q:?}"
        );
        travelled = p.0.hypot(p.1).max(travelled);
    }
    assert!(travelled > 0.3, "the robot hardly moved");
}

/// The e-puck's camera is a real vision device: the ray caster draws a planar projection of
/// what is in front of it, it costs nothing while nobody reads it, and a log records it.
#[test]
fn epuck_camera_sees_what_is_ahead_only_when_read() {
    let world = root().join("tests/data/webots/e-puck_camera.wbt");
    let compiled = load(&world, None);
    let rig = &compiled.rig.robots[0];
    assert_eq!(rig.cameras.len(), 1);
    let camera = &rig.cameras[0];
    assert_eq!((camera.width, camera.height), (52, 39));
    // "void" reads nothing from the camera: no image is taken.
    let mut simulation = Simulation::new(&compiled, Some(1)).expect("runs");
    simulation.step();
    assert!(simulation.robots[0].cameras[0].image.rgb.is_empty());
    assert_eq!(simulation.robots[0].updated.cameras, 0);
    // What a log records, it renders.
    simulation.sense_everything();
    simulation.step();
    let image = &simulation.robots[0].cameras[0].image;
    assert_eq!(
        (image.width, image.height, image.rgb.len()),
        (52, 39, 52 * 39 * 3)
    );
    let pixel = |column: usize, row: usize| {
        let at = 3 * (row * 52 + column);
        [image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]]
    };
    // The red box ahead, lit on the face the camera sees.
    let centre = pixel(26, 19);
    assert!(
        centre[0] > 100 && centre[1] == 0 && centre[2] == 0,
        "{centre:?}"
    );
    // The box is 0.05 m wide, 0.275 m from the camera: its image is 2·atan(0.025/0.275)
    // of the 0.84 rad field, about 11 of the 52 columns.
    let red: Vec<usize> = (0..52).filter(|&c| pixel(c, 19) == centre).collect();
    assert!((10..=12).contains(&red.len()), "{red:?}");
    assert_eq!(red[0] + red[red.len() - 1], 51, "centred: {red:?}");
    // The blue sky above the box and the wall.
    assert_eq!(pixel(26, 0), [0, 0, 255]);
    // Through the Khepera API too.
    use regatta_runtime::khepera::Khepera;
    let mut io = simulation.khepera(0);
    let mut cameras = io.cameras();
    assert_eq!(cameras.len(), 1);
    assert_eq!(cameras[0].size(), (52, 39));
    assert_eq!(cameras[0].image().unwrap().len(), 52 * 39 * 3);
}

#[test]
fn braitenberg_weighs_the_thymios_sensors_by_heading_and_the_epucks_as_k_team() {
    use regatta_runtime::controllers::braitenberg::Weights;
    let weights = |name: &str| {
        let world = root().join("tests/data/webots").join(name);
        let checked = regatta_schema::check_file(&world, true).expect("readable");
        let compiled = regatta_runtime::compile(&checked.scene);
        Weights::for_robot(Some(&compiled.rig.robots[0]))
    };
    // The e-puck lists its eight sensors in the Khepera's order: K-Team's weights unchanged.
    assert_eq!(weights("pi-puck.wbt"), Weights::KTEAM);
    let thymio = weights("thymio2.wbt");
    // Something seen on the left (prox.horizontal.0, 1) speeds the left wheel and slows the
    // right one, turning the robot away; the right side (3, 4) mirrors it.
    for slot in [0, 1] {
        assert!(thymio.left[slot] > thymio.right[slot], "{thymio:?}");
    }
    for slot in [3, 4] {
        assert!(thymio.left[slot] < thymio.right[slot], "{thymio:?}");
    }
    assert_eq!(thymio.left[4], thymio.right[0]);
    // Seven sensors: the eighth slot weighs nothing, and the ground sensors have no slot.
    assert_eq!((thymio.left[7], thymio.right[7]), (0.0, 0.0));
}
