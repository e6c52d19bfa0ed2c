//! The compiler's render graph, rig and plan on the project's worlds.

use regatta_runtime::compile::graph::{Owner, Shape};
use regatta_runtime::compile::plan::RendererChoice;
use regatta_runtime::compile::rig::TurretRig;
use regatta_tests::{compile_text, compile_world};

#[test]
fn regatta_world_compiles_to_arena_buoys_and_one_khepera() {
    let compiled = compile_world("regatta.wbt");
    let rig = &compiled.rig;
    assert_eq!(rig.robots.len(), 1);
    let khepera = &rig.robots[0];
    assert_eq!(khepera.distance_sensors.len(), 8);
    assert_eq!(khepera.light_sensors.len(), 8);
    assert!(matches!(khepera.turret, Some(TurretRig::Panoramic(_))));
    assert_eq!(khepera.controller, "regatta");
    // Sensor 0 looks left (−z in the robot frame), sensor 2 forward.
    assert!(khepera.distance_sensors[0].direction.z < -0.99);
    assert!(khepera.distance_sensors[2].direction.x > 0.99);
    let cylinders = compiled
        .graph
        .primitives
        .iter()
        .filter(|p| p.owner == Owner::Static && matches!(p.shape, Shape::Cylinder { .. }))
        .count();
    assert_eq!(cylinders, 6, "three buoys, each a body and a lamp");
    assert_eq!(compiled.plan.renderer, RendererChoice::Columns);
    // The robot's own body is below its retina's band: culled.
    assert!(compiled.plan.own_visible[0].is_empty());
    // Switched-off buoy lights are skipped, with their reason.
    assert!(compiled
        .plan
        .skipped
        .iter()
        .any(|s| s.why.contains("switched off")));
}

#[test]
fn geometry_outside_every_band_is_culled() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { }\n\
        Transform { translation 0 3 0 children [ Shape { geometry Box { size 0.1 0.1 0.1 } } ] }\n\
        Khepera { turret PanoramicTurret { } }\n";
    let compiled = compile_text(world);
    let high = compiled
        .graph
        .primitives
        .iter()
        .position(|p| p.bounds.min.y > 2.0)
        .unwrap();
    assert!(
        !compiled.plan.visible.contains(&high),
        "a box 3 m up cannot enter a ±5.5° band within a 1 m arena"
    );
}

#[test]
fn lights_that_reach_nothing_are_skipped() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { }\n\
        PointLight { location 50 0 0 radius 1 }\nPointLight { location 0 0.3 0 radius 1 }\nDirectionalLight { intensity 0 ambientIntensity 0 }\n\
        Khepera { turret PanoramicTurret { } }\n";
    let compiled = compile_text(world);
    assert_eq!(compiled.plan.lights, vec![1]);
    assert_eq!(
        compiled
            .plan
            .skipped
            .iter()
            .filter(|s| s.what.starts_with("light"))
            .count(),
        2
    );
}

#[test]
fn meshes_make_the_plan_cast_rays() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\n\
        Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, 1 0.1 0, 0.5 0.05 0, 0 0.1 0 ] } coordIndex [ 0 1 2 3 4 -1 ] } }\n\
        Khepera { turret PanoramicTurret { } }\n";
    let compiled = compile_text(world);
    assert_eq!(
        compiled.graph.triangle_count(),
        3,
        "a concave pentagon gives 3 triangles"
    );
    assert_eq!(compiled.plan.renderer, RendererChoice::Rays);
}

#[test]
fn z_up_worlds_are_turned_to_y_up() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { }\nTransform { translation 1 2 3 children [ Shape { geometry Sphere { radius 0.1 } } ] }\n";
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("z.wbt".into(), world.as_bytes().to_vec()),
        &regatta_schema::Options::default(),
    );
    let compiled = regatta_runtime::compile(&checked.scene);
    let center = compiled.graph.primitives[0].bounds.center();
    assert!(
        (center - glam::DVec3::new(1.0, 3.0, -2.0)).length() < 1e-12,
        "{center}"
    );
}

#[test]
fn lights_with_shadows_make_the_plan_cast_rays() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { }\n\
        PointLight { location 0 0.3 0 castShadows TRUE }\n\
        Khepera { turret PanoramicTurret { } }\n";
    assert_eq!(compile_text(world).plan.renderer, RendererChoice::Rays);
}
