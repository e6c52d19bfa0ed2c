//! What a run keeps of a world (issue 41, peak memory): compiled for a run (no grouping
//! nodes inside robots, equal materials and sensors shared) and with its retinas' filter
//! outputs over every pixel unkept, a crowd steps exactly as one compiled for export that
//! keeps everything.

use regatta_runtime::sim::Simulation;

/// A crowd close enough to touch, half of it with the crowd level of detail, buoys to visit.
fn crowd() -> String {
    let mut text = String::from(
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep 32 }\n\
         DirectionalLight { direction 0.3 -1 0.2 intensity 0.5 }\nArena { size 0.8 0.8 }\n\
         Buoy { translation 0 0 0 irReflectance 1 }\nBuoy { translation 0.25 0 -0.25 }\n",
    );
    for i in 0..24 {
        let (x, z) = (-0.33 + 0.095 * (i % 8) as f64, -0.3 + 0.2 * (i / 8) as f64);
        let crowd = if i % 2 == 0 { "crowdDistance 0.3" } else { "" };
        text += &format!(
            "Khepera {{ translation {x} 0 {z} rotation 0 1 0 {} name \"k{i}\" controller \"regatta\" \
             turret PanoramicTurret {{ lambda 5 {crowd} }} }}\n",
            i as f64 * 1.3
        );
    }
    text
}

#[test]
fn a_lean_run_steps_as_a_full_one() {
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("crowd.wbt".to_owned(), crowd().into_bytes()),
        &regatta_schema::Options::default(),
    );
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let full = regatta_runtime::compile(&checked.scene);
    let lean = regatta_runtime::compile_for_run(&checked.scene);
    assert!(lean.graph.groups.len() < full.graph.groups.len());
    assert!(lean.graph.materials.len() < full.graph.materials.len());
    let robots = &lean.rig.robots;
    assert!(std::sync::Arc::ptr_eq(
        &robots[0].distance_sensors,
        &robots[23].distance_sensors
    ));
    assert_eq!(full.rig, lean.rig);

    let mut kept = Simulation::new(&full, None).unwrap();
    let mut unkept = Simulation::new(&lean, None).unwrap();
    unkept.keep_filter_outputs(false);
    assert_eq!(kept.obstacle_names(), unkept.obstacle_names());
    for _ in 0..150 {
        kept.run(1);
        unkept.run(1);
        for (a, b) in kept.robots.iter().zip(&unkept.robots) {
            assert_eq!(a.pose, b.pose, "{}", a.name);
            let (a, b) = (
                &a.panoramic.as_ref().unwrap().output,
                &b.panoramic.as_ref().unwrap().output,
            );
            assert_eq!(
                (&a.digital, &a.analog, a.dark),
                (&b.digital, &b.analog, b.dark)
            );
            assert!(!a.filtered.is_empty() && b.filtered.is_empty() && b.luminance.is_empty());
        }
    }
    for (a, b) in kept.robots.iter().zip(&unkept.robots) {
        assert_eq!(format!("{:?}", a.contacts), format!("{:?}", b.contacts));
        assert_eq!(format!("{:?}", a.visits), format!("{:?}", b.visits));
    }
}
