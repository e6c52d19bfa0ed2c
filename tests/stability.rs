//! The stress suite: long runs, a lone robot in a small arena for hours, invariance under
//! moving and turning the whole world, crowds pushing at full speed, and extreme but
//! accepted values (or their refusal at `check`, located). Every run checks, at every step,
//! that what a log would record (poses, wheel travel, readings, the retina) is finite.

use regatta_runtime::sim::{Simulation, PENETRATION_TOLERANCE};
use regatta_runtime::Compiled;
use regatta_tests::{compile_text, root};

/// Panics when anything a log records of a robot is NaN or infinite.
fn assert_finite(simulation: &Simulation) {
    for robot in &simulation.robots {
        let p = robot.pose;
        let values = [p.x, p.z, p.heading, robot.travel.0, robot.travel.1];
        assert!(
            values.iter().all(|v| v.is_finite()),
            "robot '{}' at step {}: {values:?}",
            robot.name,
            simulation.steps
        );
        if let Some(turret) = &robot.panoramic {
            let out = &turret.output;
            assert!(
                out.luminance
                    .iter()
                    .chain(&out.analog)
                    .all(|v| v.is_finite())
                    && out
                        .filtered
                        .iter()
                        .all(|(_, f)| f.iter().all(|v| v.is_finite())),
                "robot '{}' retina at step {}",
                robot.name,
                simulation.steps
            );
        }
    }
}

/// Runs `steps` steps, checking values after each.
fn run_checked(simulation: &mut Simulation, steps: u64) {
    for _ in 0..steps {
        simulation.step();
        assert_finite(simulation);
    }
}

fn world_text(name: &str) -> String {
    std::fs::read_to_string(root().join("worlds").join(name)).expect("world readable")
}

/// A simulated hour of the regatta: no NaN, the robot always inside the arena, and the
/// buoys visited steadily, every ten minutes.
#[test]
fn an_hour_of_the_regatta_stays_finite_inside_and_steady() {
    let compiled = compile_text(&world_text("regatta.wbt"));
    let mut simulation = Simulation::new(&compiled, Some(1)).unwrap();
    simulation.sense_everything();
    let per_window = (600.0 / simulation.time_step).round() as u64;
    let mut visits_before = 0;
    let mut windows = Vec::new();
    for _ in 0..6 {
        for _ in 0..per_window {
            simulation.step();
            assert_finite(&simulation);
            let p = simulation.robots[0].pose;
            // The arena's inner walls are at ±0.5 m; the body is 27.5 mm in radius.
            assert!(
                p.x.abs() <= 0.5 - 0.0275 + 1e-6 && p.z.abs() <= 0.5 - 0.0275 + 1e-6,
                "outside the arena at {p:?}"
            );
        }
        let visits = simulation.robots[0].visits.sequence.len();
        windows.push(visits - visits_before);
        visits_before = visits;
    }
    // Today's figure is about 70 visits per ten minutes (README); steady means no window
    // falls below half of it.
    assert!(
        windows.iter().all(|&v| v >= 35),
        "visits per 10 min: {windows:?}"
    );
}

/// A lone `braitenberg` robot in a 1 m arena for two simulated hours: it never stays wedged
/// in a corner. Facing a corner at 45° its IR network's two sides cancel and the heading is
/// a stable fixed point (commands about (−1, 0) pulses) that the sensors' noise does not
/// leave; the stall escape turns it away.
#[test]
fn a_lone_braitenberg_robot_never_wedges_itself_for_long() {
    let compiled = compile_text(
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { size 1 1 }\n\
         Khepera { translation 0.3 0 0.3 rotation 0 1 0 -0.7854 controller \"braitenberg\" }\n",
    );
    // Seeds 2 and 6 wedged within five minutes before the escape.
    for seed in [1, 2, 6] {
        let mut simulation = Simulation::new(&compiled, Some(seed)).unwrap();
        let per_minute = (60.0 / simulation.time_step).round() as u64;
        let mut still_minutes = 0;
        let mut worst = 0;
        for _ in 0..120 {
            let before = simulation.robots[0].pose;
            run_checked(&mut simulation, per_minute);
            let after = simulation.robots[0].pose;
            // A minute with less than 5 cm of displacement is a minute stuck.
            if (after.x - before.x).hypot(after.z - before.z) < 0.05 {
                still_minutes += 1;
                worst = worst.max(still_minutes);
            } else {
                still_minutes = 0;
            }
        }
        assert!(
            worst <= 2,
            "seed {seed}: stuck for {worst} minutes in a row"
        );
    }
}

/// The regatta moved 1000 m away and turned about the vertical behaves as at home: the pose
/// relative to the world agrees within 1e-6 m after 5 s (round-off in the turned frames is
/// about 1e-13 m at 1000 m, and the controller's rounding to whole pulses amplifies it only
/// where a command sits on a rounding edge), and the buoy visits of two minutes agree within
/// a fifth (beyond seconds the run is chaotic: the same robot with another seed is another
/// path).
#[test]
fn the_regatta_is_the_same_moved_far_and_turned() {
    let home = world_text("regatta.wbt");
    let compiled = compile_text(&home);
    let reference = trajectory(&compiled, 2.0);
    for (dx, dz, angle) in [
        (1000.0, -1000.0, 0.0),
        (0.0, 0.0, 1.0),
        (1000.0, 500.0, 2.5),
    ] {
        let moved = compile_text(&transformed(&home, dx, dz, angle));
        let run = trajectory(&moved, 2.0);
        let (s, c) = (f64::sin(angle), f64::cos(angle));
        // Back into the home frame: undo the translation, then the rotation.
        let home_of = |x: f64, z: f64| {
            let (x, z) = (x - dx, z - dz);
            (c * x - s * z, s * x + c * z)
        };
        let at_5s = (5.0 / compiled.settings.time_step).round() as usize;
        let (x, z) = home_of(run.poses[at_5s].0, run.poses[at_5s].1);
        let (hx, hz) = reference.poses[at_5s];
        let error = (x - hx).hypot(z - hz);
        assert!(
            error < 1e-6,
            "moved by ({dx}, {dz}) turned {angle}: pose differs by {error} m after 5 s"
        );
        let (a, b) = (run.visits as f64, reference.visits as f64);
        assert!(
            (a - b).abs() <= 0.2 * b.max(5.0),
            "moved by ({dx}, {dz}) turned {angle}: {a} visits against {b}"
        );
    }
}

struct Trajectory {
    poses: Vec<(f64, f64)>,
    visits: usize,
}

fn trajectory(compiled: &Compiled, minutes: f64) -> Trajectory {
    let mut simulation = Simulation::new(compiled, Some(1)).unwrap();
    let steps = (minutes * 60.0 / simulation.time_step).round() as u64;
    let mut poses = vec![(simulation.robots[0].pose.x, simulation.robots[0].pose.z)];
    for _ in 0..steps {
        simulation.step();
        assert_finite(&simulation);
        poses.push((simulation.robots[0].pose.x, simulation.robots[0].pose.z));
    }
    Trajectory {
        poses,
        visits: simulation.robots[0].visits.sequence.len(),
    }
}

/// The world's items (everything after WorldInfo, Viewpoint, Background and the light) in a
/// Transform that turns them by `angle` about +y and moves them by (dx, 0, dz); the light's
/// direction turned alike.
fn transformed(world: &str, dx: f64, dz: f64, angle: f64) -> String {
    let start = world.find("Arena {").expect("an Arena");
    let (head, items) = world.split_at(start);
    let (s, c) = (f64::sin(angle), f64::cos(angle));
    // A rotation by θ about +y takes (x, z) to (x cos θ + z sin θ, −x sin θ + z cos θ).
    let (lx, lz) = (0.3, 0.2);
    let light = format!("direction {} -1 {}", lx * c + lz * s, -lx * s + lz * c);
    let head = head.replace("direction 0.3 -1 0.2", &light);
    format!(
        "{head}Transform {{\n  translation {dx} 0 {dz}\n  rotation 0 1 0 {angle}\n  children [\n{items}\n  ]\n}}\n"
    )
}

/// Twenty robots packed in a small arena drive at full speed into each other and the walls
/// for 30 s: no two bodies overlap by more than the documented tolerance (1e-9 m), no body
/// crosses a wall, and no robot moves faster than its wheels allow.
#[test]
fn a_packed_crowd_at_full_speed_never_overlaps_nor_speeds_up() {
    let mut text = String::from(
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep 16 }\nArena { size 0.4 0.4 }\n",
    );
    let mut k = 0;
    for i in 0..5 {
        for j in 0..4 {
            let (x, z) = (-0.15 + 0.07 * i as f64, -0.12 + 0.07 * j as f64);
            let heading = 0.7 * k as f64;
            text.push_str(&format!(
                "Khepera {{ translation {x} 0 {z} rotation 0 1 0 {heading} name \"k{k}\" controller \"braitenberg\" controllerArgs \"bias=127 irGain=0\" wheelSpeedNoise 0.05 }}\n"
            ));
            k += 1;
        }
    }
    let compiled = compile_text(&text);
    let mut simulation = Simulation::new(&compiled, Some(3)).unwrap();
    let dt = simulation.time_step;
    let rig = &compiled.rig.robots[0];
    let (radius, top) = (rig.body_radius, rig.max_speed);
    // A wheel's noise factor is at most 1 + 8.6 σ (the largest Gaussian a draw gives).
    let fastest = top * (1.0 + 8.6 * rig.wheel_speed_noise);
    let mut worst_speed: f64 = 0.0;
    for _ in 0..(30.0 / dt) as u64 {
        let before: Vec<(f64, f64)> = simulation
            .robots
            .iter()
            .map(|r| (r.pose.x, r.pose.z))
            .collect();
        simulation.step();
        assert_finite(&simulation);
        let robots = &simulation.robots;
        for (a, ra) in robots.iter().enumerate() {
            let p = ra.pose;
            assert!(
                p.x.abs() <= 0.2 - radius + PENETRATION_TOLERANCE
                    && p.z.abs() <= 0.2 - radius + PENETRATION_TOLERANCE,
                "robot {a} through a wall at {p:?}"
            );
            for rb in &robots[a + 1..] {
                let gap = (p.x - rb.pose.x).hypot(p.z - rb.pose.z) - 2.0 * radius;
                assert!(
                    gap >= -PENETRATION_TOLERANCE * 2.0,
                    "overlap {gap} m at step {}",
                    simulation.steps
                );
            }
            let speed = (p.x - before[a].0).hypot(p.z - before[a].1) / dt;
            worst_speed = worst_speed.max(speed);
        }
    }
    assert!(
        worst_speed <= fastest * (1.0 + 1e-9),
        "a robot moved at {worst_speed} m/s; its wheels allow {fastest}"
    );
}

/// What an extreme world does: runs with finite values, or is refused at `check` with an
/// error on the given line.
enum Expect {
    Runs,
    Refused { line: usize },
}

/// Extreme but accepted values, and a few just past what is accepted.
#[test]
fn extreme_values_run_finite_or_are_refused_where_written() {
    let header = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep ";
    let cases: &[(&str, &str, &str, Expect)] = &[
        ("one-millisecond step", "1", "Arena { size 1 1 }\nKhepera { }\n", Expect::Runs),
        (
            "the longest step a Khepera allows",
            "39000",
            "Arena { size 1 1 }\nKhepera { }\n",
            Expect::Runs,
        ),
        (
            "a step too long to follow",
            "100000",
            "Arena { size 1 1 }\nKhepera { }\n",
            Expect::Refused { line: 2 },
        ),
        (
            "a control period off the step grid",
            "32",
            "Arena { size 1 1 }\nKhepera {\n  controlPeriod 33\n}\n",
            Expect::Refused { line: 5 },
        ),
        (
            "a control period of hours",
            "32",
            "Arena { size 1 1 }\nKhepera { controlPeriod 3600000 }\n",
            Expect::Runs,
        ),
        ("a tiny arena", "32", "Arena { size 0.06 0.06 }\nKhepera { }\n", Expect::Runs),
        (
            "a huge arena",
            "32",
            "Arena { size 10000 10000 }\nKhepera { translation 4000 0 -4000 }\n",
            Expect::Runs,
        ),
        (
            "full speed ahead",
            "32",
            "Arena { size 1 1 }\nKhepera { controllerArgs \"bias=127\" }\n",
            Expect::Runs,
        ),
        (
            "full speed astern",
            "32",
            "Arena { size 1 1 }\nKhepera { controllerArgs \"bias=-127\" }\n",
            Expect::Runs,
        ),
        (
            "a robot starting inside a buoy",
            "32",
            "Arena { size 1 1 }\nBuoy { }\nKhepera { controller \"regatta\" turret PanoramicTurret { } }\n",
            Expect::Runs,
        ),
        (
            "robots starting on one point",
            "32",
            "Arena { size 1 1 }\nKhepera { name \"a\" }\nKhepera { name \"b\" }\nKhepera { name \"c\" controllerArgs \"bias=-10\" }\n",
            Expect::Runs,
        ),
        (
            "a robot starting in a wall",
            "32",
            "Arena { size 1 1 }\nKhepera { translation 0.5 0 0 }\n",
            Expect::Runs,
        ),
        (
            "zero-area faces and repeated points",
            "32",
            "Arena { size 1 1 }\nShape { geometry IndexedFaceSet { coord Coordinate { point [ 0.1 0 0.1, 0.1 0 0.1, 0.1 0.05 0.1, 0.2 0 0.1, 0.2 0.05 0.1 ] } coordIndex [ 0 1 2 -1 0 0 0 -1 0 3 4 2 -1 ] } }\nKhepera { }\n",
            Expect::Runs,
        ),
        (
            "a zero-size box",
            "32",
            "Arena { size 1 1 }\nShape {\n  geometry Box { size 0 0 0 }\n}\nKhepera { }\n",
            Expect::Refused { line: 5 },
        ),
        (
            "a huge robot",
            "32",
            "Arena { size 100 100 }\nKhepera { }\nDifferentialWheels { name \"big\" translation 20 0 0 bodyRadius 10 bodyHeight 5 controller \"braitenberg\" }\n",
            Expect::Runs,
        ),
        (
            "a tiny robot at the default step",
            "32",
            "Arena { size 1 1 }\nDifferentialWheels { bodyRadius 0.000001 controller \"braitenberg\" }\n",
            Expect::Refused { line: 2 },
        ),
        (
            "a tiny robot at a step it can follow",
            "1",
            "Arena { size 1 1 }\nDifferentialWheels { bodyRadius 0.0001 bodyHeight 0.0001 maxSpeed 0.01 controller \"braitenberg\" }\n",
            Expect::Runs,
        ),
    ];
    for (name, step, body, expect) in cases {
        let text = format!("{header}{step} }}\n{body}");
        let mut checked = regatta_schema::check(
            regatta_parser::SourceText::from_bytes(
                "extreme.wbt".to_owned(),
                text.as_bytes().to_vec(),
            ),
            &regatta_schema::Options::default(),
        );
        regatta_runtime::check::check_scene(&mut checked);
        let rendered = checked.render(false);
        match expect {
            Expect::Refused { line } => {
                assert!(checked.has_errors(), "{name}: accepted\n{text}");
                assert!(
                    rendered.contains(&format!("extreme.wbt:{line}:")),
                    "{name}: not located on line {line}:\n{rendered}"
                );
            }
            Expect::Runs => {
                assert!(!checked.has_errors(), "{name}: refused\n{rendered}");
                let compiled = regatta_runtime::compile(&checked.scene);
                let mut simulation = Simulation::new(&compiled, Some(1)).unwrap();
                simulation.sense_everything();
                // Ten simulated seconds, or 200 steps of a very long step.
                let steps = ((10.0 / simulation.time_step) as u64).clamp(200, 10_000);
                run_checked(&mut simulation, steps);
            }
        }
    }
}
