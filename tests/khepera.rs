//! The simulated Khepera: kinematics, collisions, sensors against `khepera.md`, and the API.

use regatta_runtime::compile::rig::Pose2;
use regatta_runtime::khepera::{Controller, Khepera, KheperaError, LedAction};
use regatta_runtime::retina::FilterKind;
use regatta_runtime::sim::kinematics::advance;
use regatta_runtime::sim::Simulation;
use regatta_tests::compile_text;

#[test]
fn constant_wheel_speeds_drive_the_analytic_circle_for_a_million_steps() {
    let (left, right, axle, dt) = (0.05, 0.08, 0.053, 0.032);
    let omega = (right - left) / axle;
    let radius = 0.5 * (left + right) / omega;
    let mut pose = Pose2 {
        x: 0.0,
        z: 0.0,
        heading: 0.0,
    };
    for _ in 0..1_000_000 {
        pose = advance(pose, left, right, axle, dt);
    }
    // Centre of the circle: to the left of the start (−z) by the radius.
    let distance = (pose.x * pose.x + (pose.z + radius) * (pose.z + radius)).sqrt();
    assert!(
        (distance - radius).abs() < 1e-6,
        "off the circle by {} m",
        (distance - radius).abs()
    );
    let expected_heading = regatta_runtime::sim::kinematics::normalize_heading(omega * dt * 1e6);
    assert!((pose.heading - expected_heading).abs() < 1e-6);
}

#[test]
fn after_a_hundred_million_steps_the_pose_is_finite_and_the_heading_normalised() {
    let mut pose = Pose2 {
        x: 0.0,
        z: 0.0,
        heading: 0.0,
    };
    for i in 0..100_000_000u64 {
        // Changing speeds, spinning and straight runs.
        let (left, right) = match (i / 1000) % 3 {
            0 => (0.3, -0.3),
            1 => (0.1, 0.1),
            _ => (0.02, 0.9),
        };
        pose = advance(pose, left, right, 0.053, 0.032);
    }
    assert!(pose.x.is_finite() && pose.z.is_finite() && pose.heading.is_finite());
    assert!(pose.heading > -std::f64::consts::PI && pose.heading <= std::f64::consts::PI);
}

/// A robot facing a wall; returns its 8 proximity readings.
/// A robot with more IR sensors than the Khepera API reads (twelve) reads eight of them; its
/// sensors, due together until then, fall out of step at the first reading and are each
/// tested from then on. It reads the same numbers, step for step, as the same robot whose raw
/// readings are kept and who reads all twelve together, and moves the same.
#[test]
fn sensors_out_of_step_read_what_sensors_read_together_read() {
    let sensors: String = (0..12)
        .map(|k| {
            let angle = k as f64 * std::f64::consts::TAU / 12.0;
            format!(
                "DistanceSensor {{ name \"ir{k}\" translation {} 0.0145 {} rotation 0 1 0 {angle} }}\n",
                0.0245 * angle.cos(),
                -0.0245 * angle.sin()
            )
        })
        .collect();
    let text = format!(
        "#VRML_SIM R2023b utf8\n\
         WorldInfo {{ coordinateSystem \"NUE\" basicTimeStep 16 randomSeed 5 }}\n\
         Arena {{ size 0.6 0.6 }}\n\
         Buoy {{ translation -0.12 0 0.08 irReflectance 1 }}\n\
         DifferentialWheels {{ translation 0.1 0 -0.05 rotation 0 1 0 2.2 name \"twelve\" \
         controller \"braitenberg\" children [\n{sensors}] }}\n\
         Khepera {{ translation -0.1 0 -0.15 rotation 0 1 0 0.4 name \"k\" controller \"braitenberg\" }}\n"
    );
    let compiled = compile_text(&text);
    assert_eq!(compiled.rig.robots[0].distance_sensors.len(), 12);
    let mut eight = Simulation::new(&compiled, None).unwrap();
    let mut all = Simulation::new(&compiled, None).unwrap();
    for (robot, rig) in all.robots.iter_mut().zip(&compiled.rig.robots) {
        robot.keep_raw_readings(rig);
    }
    let mut changes = 0;
    let mut last = eight.robots[0].proximity;
    for step in 0..2000 {
        step_alike(&mut eight, &mut all, step);
        changes += (eight.robots[0].proximity != last) as u32;
        last = eight.robots[0].proximity;
    }
    // The readings moved: the robot came near the walls, the buoy and the other robot.
    assert!(changes > 200, "{changes} steps with new readings");
}

/// Steps both runs once and checks that every robot reads and stands alike in them.
fn step_alike(a: &mut Simulation, b: &mut Simulation, step: usize) {
    a.step();
    b.step();
    for (r, (a, b)) in a.robots.iter().zip(&b.robots).enumerate() {
        assert_eq!(a.proximity, b.proximity, "robot {r}, step {step}");
        assert_eq!(a.pose, b.pose, "robot {r}, step {step}");
    }
}

fn facing_wall(gap: f64, reflectance: f64, noise_free: bool) -> [u16; 8] {
    // The wall's face is at x = 0; the front sensors (x = 24.5 mm) are `gap` from it.
    let robot_x = -gap - 0.0245;
    let table = if noise_free {
        "lookupTable [ 0 1023 0 0.018 1023 0 0.021 900 0 0.025 550 0 0.027 400 0 0.029 210 0 0.033 100 0 0.037 10 0 0.045 0 0 ]"
    } else {
        ""
    };
    let text = format!(
        "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
Transform {{ translation 0.05 0.025 0 children [ Shape {{ appearance Appearance {{ material Material {{ irReflectance {reflectance} }} }} geometry Box {{ size 0.1 0.05 1 }} }} ] }}
DEF ROBOT DifferentialWheels {{ translation {robot_x} 0 0 controller \"none\" children [
  DistanceSensor {{ name \"front\" translation 0.0245 0.0145 0 {table} }}
] }}
"
    );
    let compiled = compile_text(&text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    simulation.step();
    simulation.robots[0].proximity
}

#[test]
fn ir_readings_follow_the_khepera_curve() {
    // Real Khepera I wall readings (khepera.md), distances from the sensor: saturated close,
    // about 550 at 25 mm, 100 at 33 mm, the noise floor beyond 37 mm.
    assert_eq!(facing_wall(0.010, 1.0, true)[0], 1023);
    assert_eq!(facing_wall(0.025, 1.0, true)[0], 550);
    assert_eq!(facing_wall(0.033, 1.0, true)[0], 100);
    assert!(facing_wall(0.040, 1.0, true)[0] < 10);
    assert_eq!(facing_wall(0.060, 1.0, true)[0], 0);
    // Larger when closer, everywhere.
    let mut previous = u16::MAX;
    for mm in 15..45 {
        let value = facing_wall(mm as f64 / 1000.0, 1.0, true)[0];
        assert!(value <= previous, "{mm} mm: {value} > {previous}");
        previous = value;
    }
    // IR reflectance scales the response: half-reflecting film gives half.
    assert_eq!(facing_wall(0.025, 0.5, true)[0], 275);
    // The default table carries noise; readings stay within 0…1023 and near the curve.
    let noisy = facing_wall(0.025, 1.0, false)[0];
    assert!((400..=700).contains(&noisy), "{noisy}");
}

#[test]
fn a_thin_cylinder_reflects_less_than_a_flat_wall() {
    let world = |geometry: &str| {
        format!(
            "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
Transform {{ translation 0.05 0.02 0 children [ Shape {{ geometry {geometry} }} ] }}
DifferentialWheels {{ translation -0.0245 0 0 controller \"none\" children [
  DistanceSensor {{ translation 0.0245 0.0145 0 lookupTable [ 0 1023 0 0.05 0 0 ] numberOfRays 3 aperture 0.5236 }}
] }}
"
        )
    };
    let read = |text: String| {
        let compiled = compile_text(&text);
        let mut simulation = Simulation::new(&compiled, None).unwrap();
        simulation.step();
        simulation.robots[0].proximity[0]
    };
    // Both 3 cm away at their nearest point.
    let wall = read(world("Box { size 0.04 0.04 1 }"));
    let cylinder = read(world("Cylinder { radius 0.02 height 0.04 }"));
    assert!(cylinder < wall, "cylinder {cylinder} vs wall {wall}");
}

#[test]
fn ambient_light_is_about_500_in_the_dark_and_lower_next_to_a_lamp() {
    let world = |light: &str| {
        format!(
            "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
{light}
DifferentialWheels {{ controller \"none\" children [
  LightSensor {{ translation 0.0245 0.0145 0 lookupTable [ 0 500 0  1 50 0  10 10 0 ] }}
] }}
"
        )
    };
    let read = |text: String| {
        let compiled = compile_text(&text);
        let mut simulation = Simulation::new(&compiled, None).unwrap();
        simulation.step();
        simulation.robots[0].ambient[0]
    };
    assert_eq!(read(world("")), 500);
    let lamp = read(world(
        "PointLight { location 0.1 0.0145 0 intensity 1 attenuation 0 0 50 }",
    ));
    assert!(lamp < 350, "a lamp 7.5 cm ahead reads {lamp}");
    let far = read(world(
        "PointLight { location 0.6 0.0145 0 intensity 1 attenuation 0 0 50 }",
    ));
    assert!(far > lamp && far < 500, "far {far}, near {lamp}");
}

/// Ambient sensors' noise streams are made when first read, from the seed the run started
/// with: setting `Simulation::seed` afterwards changes them no more than it changes the streams
/// made at the start, while another seed given at the start does.
#[test]
fn ambient_noise_comes_from_the_seed_the_run_started_with() {
    let compiled = compile_text(
        "#VRML_SIM R2023b utf8
WorldInfo { coordinateSystem \"NUE\" }
PointLight { location 0.3 0.0145 0 intensity 1 attenuation 0 0 50 }
DifferentialWheels { controller \"none\" children [
  LightSensor { translation 0.0245 0.0145 0 lookupTable [ 0 500 0.2  1 50 0.2  10 10 0.2 ] }
] }
",
    );
    let readings = |start: Option<u64>, later: Option<u64>| {
        let mut simulation = Simulation::new(&compiled, start).unwrap();
        if let Some(seed) = later {
            simulation.seed = seed;
        }
        (0..20)
            .map(|_| {
                simulation.step();
                simulation.robots[0].ambient[0]
            })
            .collect::<Vec<u16>>()
    };
    let plain = readings(None, None);
    assert_eq!(readings(None, Some(12_345)), plain);
    assert_ne!(readings(Some(12_345), None), plain, "the sensor has noise");
}

/// Drives at full speed (127 pulses/10 ms ≈ 1 m/s) into a 2 mm wall.
struct Ram;

impl Controller for Ram {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        robot.set_speed(127, 127)
    }
}

#[test]
fn no_tunnelling_through_a_thin_wall_at_full_speed() {
    let text = "#VRML_SIM R2023b utf8
WorldInfo { coordinateSystem \"NUE\" }
Transform { translation 0.2 0.025 0 children [ Shape { geometry Box { size 0.002 0.05 1 } } ] }
DifferentialWheels { controller \"none\" }
";
    let compiled = compile_text(text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    simulation.set_controller(0, Box::new(Ram));
    for _ in 0..200 {
        simulation.step();
        let x = simulation.robots[0].pose.x;
        // Body radius 27.5 mm, wall face at 0.199 m.
        assert!(
            x <= 0.199 - 0.0275 + regatta_runtime::sim::PENETRATION_TOLERANCE,
            "x = {x}"
        );
    }
    let contacts = &simulation.robots[0].contacts;
    assert_eq!(contacts.events, 1, "one contact that lasts");
    assert!(contacts.longest > 5.0);
}

struct ApiProbe {
    log: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Controller for ApiProbe {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        let mut log = self.log.lock().unwrap();
        log.push(format!("{:?}", robot.set_speed(200, 0)));
        log.push(format!("{:?}", robot.set_led(2, LedAction::On)));
        robot.set_led(1, LedAction::Toggle)?;
        robot.set_speed(10, 10)?;
        robot.set_position(100, -100)?;
        log.push(format!("{:?}", robot.position()));
        let turret = robot.panoramic().ok_or(KheperaError::NoDevice("turret"))?;
        log.push(format!(
            "{:?}",
            turret.read(FilterKind::Lowpass).map(|v| v.len())
        ));
        turret.enable_filter(FilterKind::Lowpass)?;
        turret.set_region_of_interest(70, 79)?;
        log.push(format!(
            "{:?}",
            turret.read(FilterKind::Lowpass).map(|v| v.len())
        ));
        log.push(format!("{:?}", turret.set_bits(0)));
        Ok(())
    }
}

#[test]
fn the_khepera_api_checks_its_arguments_and_its_filters() {
    let text = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nKhepera { controller \"none\" wheelSpeedNoise 0 turret PanoramicTurret { } }\n";
    let compiled = compile_text(text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    simulation.set_controller(0, Box::new(ApiProbe { log: log.clone() }));
    simulation.step();
    let log = log.lock().unwrap().clone();
    assert!(log[0].contains("OutOfRange"), "{log:?}");
    assert!(log[1].contains("OutOfRange"), "{log:?}");
    assert_eq!(log[2], "Ok((100, -100))");
    assert!(log[3].contains("FilterNotEnabled(\"lowpass\")"), "{log:?}");
    assert_eq!(
        log[4], "Ok(10)",
        "enabled, read over the region of interest"
    );
    assert!(log[5].contains("OutOfRange"), "{log:?}");
    assert_eq!(simulation.robots[0].leds, [false, true]);
    assert_eq!(simulation.robots[0].command, (10, 10));
    // Encoders: 10 pulses/10 ms for one 32 ms step is 32 pulses more on each wheel.
    let counters = simulation.robots[0].counters(&compiled.rig.robots[0]);
    assert!(
        (counters.0 - 132).abs() <= 1 && (counters.1 + 68).abs() <= 1,
        "{counters:?}"
    );
}

/// Another robot's body reflects IR like any obstacle: a Khepera 2 cm ahead lights the front
/// sensors, one 30 cm ahead leaves them at the noise floor (rays are traced only towards
/// bodies within range).
#[test]
fn another_khepera_ahead_is_seen_by_the_front_sensors() {
    let front = |gap: f64| {
        let text = format!(
            "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
Khepera {{ name \"a\" controller \"none\" }}
Khepera {{ name \"b\" translation {} 0 0 controller \"none\" }}
",
            0.055 + gap
        );
        let compiled = compile_text(&text);
        let mut simulation = Simulation::new(&compiled, None).unwrap();
        simulation.step();
        let p = simulation.robots[0].proximity;
        p[2].max(p[3])
    };
    let near = front(0.02);
    let far = front(0.30);
    assert!(near > 300, "2 cm: {near}");
    assert!(far < 10, "30 cm: {far}");
}

/// A robot with nothing near reads its far values and leaves its IR streams behind, to catch
/// up when a reading next needs a draw; a robot whose raw readings are kept draws every
/// reading as it comes. Both read the same numbers, step for step, through stretches of open
/// floor and stretches along the walls.
#[test]
fn owed_ir_draws_are_the_draws_every_reading_takes() {
    // Three Kheperas avoiding each other, two buoys and the walls of a 0.8 m arena.
    let compiled = compile_text(
        "#VRML_SIM R2023b utf8\n\
         WorldInfo { coordinateSystem \"NUE\" basicTimeStep 32 randomSeed 3 }\n\
         Arena { size 0.8 0.8 }\n\
         Buoy { translation -0.2 0 0.1 irReflectance 1 }\n\
         Buoy { translation 0.15 0 -0.2 irReflectance 1 }\n\
         Khepera { translation 0.25 0 0.1 rotation 0 1 0 2.8 name \"k0\" controller \"braitenberg\" }\n\
         Khepera { translation -0.1 0 -0.1 rotation 0 1 0 -0.7 name \"k1\" controller \"braitenberg\" }\n\
         Khepera { translation 0.0 0 0.3 rotation 0 1 0 1.6 name \"k2\" controller \"braitenberg\" }\n",
    );
    let mut owing = Simulation::new(&compiled, None).unwrap();
    let mut drawing = Simulation::new(&compiled, None).unwrap();
    for (robot, rig) in drawing.robots.iter_mut().zip(&compiled.rig.robots) {
        robot.keep_raw_readings(rig);
    }
    // Steps a robot read only far values, and steps it came near something after a stretch
    // apart (where the owed draws are paid).
    let mut far = vec![None; owing.robots.len()];
    let mut was_apart = vec![false; owing.robots.len()];
    let (mut apart, mut arrivals) = (0, 0);
    for step in 0..3000 {
        step_alike(&mut owing, &mut drawing, step);
        for (r, a) in owing.robots.iter().enumerate() {
            let alone = a.proximity == *far[r].get_or_insert(a.proximity);
            apart += alone as u32;
            arrivals += (was_apart[r] && !alone) as u32;
            was_apart[r] = alone;
        }
    }
    assert!(
        apart > 1000 && arrivals > 10,
        "{apart} robot-steps apart, {arrivals} arrivals"
    );
}
