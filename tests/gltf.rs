//! glTF export read back with the `gltf` crate: one node per group, primitive, light,
//! viewpoint and sensor; every mesh's bounds equal to its render-graph primitive's; y-up
//! metres for z-up files; robot tracks as animation channels.

use glam::DMat4;
use regatta_gltf::{export, segments, Options, Track};
use regatta_runtime::compile::graph::Shape;
use regatta_runtime::compile::rig::Pose2;
use regatta_runtime::geometry::Aabb;
use regatta_runtime::Compiled;
use regatta_tests::{compile_text, compile_world, corpus};

/// Nodes the export must write for a compiled world.
fn expected_nodes(compiled: &Compiled) -> usize {
    let graph = &compiled.graph;
    let sensors: usize = compiled
        .rig
        .robots
        .iter()
        .map(|r| r.distance_sensors.len() + r.light_sensors.len() + r.turret.iter().count())
        .sum();
    graph.groups.len()
        + graph.primitives.len()
        + graph.lines.len()
        + graph.lights.len()
        + graph.viewpoint.iter().count()
        + sensors
}

/// World matrices of every node, from the scene's roots.
fn world_matrices(document: &gltf::Document) -> Vec<Option<DMat4>> {
    let mut out = vec![None; document.nodes().count()];
    let mut stack: Vec<(gltf::Node, DMat4)> = document
        .default_scene()
        .map(|s| s.nodes().map(|n| (n, DMat4::IDENTITY)).collect())
        .unwrap_or_default();
    while let Some((node, parent)) = stack.pop() {
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        assert!(
            out[node.index()].is_none(),
            "node {} has two parents",
            node.index()
        );
        out[node.index()] = Some(world);
        stack.extend(node.children().map(|c| (c, world)));
    }
    out
}

/// The largest coordinate of a box, in absolute value.
fn want_magnitude(bounds: Aabb) -> f64 {
    bounds.min.abs().max(bounds.max.abs()).max_element()
}

/// Exports, writes GLB, reads it back and checks node count and per-primitive bounds.
/// Returns the read-back document and blob.
fn round_trip(compiled: &Compiled, quality: u32, what: &str) -> (gltf::Document, Vec<u8>) {
    let exported = export(compiled, &Options { quality }, &[]).expect("export");
    let glb = exported.to_glb();
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(&glb)
        .unwrap_or_else(|e| panic!("{what}: the gltf crate cannot read the export: {e}"));
    let blob = blob.unwrap_or_default();
    assert_eq!(
        document.nodes().count(),
        expected_nodes(compiled),
        "{what}: node count"
    );
    let worlds = world_matrices(&document);
    assert!(
        worlds.iter().all(Option::is_some),
        "{what}: a node outside the scene"
    );
    let mesh_nodes: Vec<gltf::Node> = document.nodes().filter(|n| n.mesh().is_some()).collect();
    let graph = &compiled.graph;
    assert_eq!(
        mesh_nodes.len(),
        graph.primitives.len() + graph.lines.len(),
        "{what}: one mesh node per primitive and per line or point set"
    );
    let chord = 1.0 - (std::f64::consts::PI / segments(quality) as f64).cos();
    for (primitive, node) in graph.primitives.iter().zip(&mesh_nodes) {
        // Bounds are compared in the owner's frame (the robot's for attached parts).
        let to_owner = match primitive.owner {
            regatta_runtime::compile::graph::Owner::Static => DMat4::IDENTITY,
            regatta_runtime::compile::graph::Owner::Robot(r) => {
                let rig = &compiled.rig.robots[r];
                let start = rig.start.frame(rig.floor_y);
                let m = DMat4::from_mat3_translation(start.linear, start.translation);
                m.inverse()
            }
        };
        let matrix = to_owner * worlds[node.index()].unwrap();
        let mut bounds = Aabb::EMPTY;
        for p in node.mesh().unwrap().primitives() {
            let reader = p.reader(|_| Some(&blob));
            for position in reader.read_positions().expect("positions") {
                let point = matrix.transform_point3(glam::Vec3::from(position).as_dvec3());
                bounds = bounds.union(Aabb {
                    min: point,
                    max: point,
                });
            }
        }
        let scale = primitive
            .frame
            .linear
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            * 3.0;
        // glTF stores single precision: far from the origin, a position is off by its ulp.
        let magnitude = want_magnitude(primitive.bounds);
        let tolerance = 1e-6
            + magnitude * f32::EPSILON as f64
            + match primitive.shape {
                Shape::Cylinder { radius, .. }
                | Shape::Cone { radius, .. }
                | Shape::Sphere { radius } => radius * scale * chord,
                _ => 0.0,
            };
        let want = primitive.bounds;
        let error = (bounds.min - want.min)
            .abs()
            .max((bounds.max - want.max).abs())
            .max_element();
        assert!(
            error <= tolerance,
            "{what}: {} bounds {bounds:?} against {want:?} (error {error:e} > {tolerance:e})",
            primitive.shape.name()
        );
    }
    (document, blob)
}

#[test]
fn project_worlds_read_back_with_matching_nodes_and_bounds() {
    for world in ["regatta.wbt", "single_buoy.wbt", "k213.wbt"] {
        let compiled = compile_world(world);
        let (document, _) = round_trip(&compiled, 32, world);
        // Robots are named nodes carrying a child node per sensor.
        for robot in &compiled.rig.robots {
            let node = document
                .nodes()
                .find(|n| n.name() == Some(robot.name.as_str()))
                .unwrap_or_else(|| panic!("{world}: no node named {}", robot.name));
            let sensors = node
                .children()
                .filter(|c| {
                    c.extras()
                        .as_ref()
                        .is_some_and(|e| e.get().contains("\"type\""))
                })
                .count();
            assert_eq!(
                sensors,
                robot.distance_sensors.len()
                    + robot.light_sensors.len()
                    + robot.turret.iter().count(),
                "{world}: sensors under {}",
                robot.name
            );
        }
    }
}

#[test]
fn tricky_geometry_keeps_its_bounds() {
    // Rotations, non-uniform scale with scaleOrientation (a shear), all analytic shapes, a
    // concave coloured face set, an elevation grid, every light kind and a viewpoint.
    let compiled = compile_text(
        "#VRML_SIM R2023b utf8\n\
         WorldInfo { coordinateSystem \"NUE\" }\n\
         Viewpoint { position 0 1 3 orientation 1 0 0 -0.3 description \"overview\" }\n\
         DEF SHEARED Transform {\n\
           translation 0.5 0 0 rotation 0 1 0 0.4 scale 2 1 0.5 scaleOrientation 0 0 1 0.6\n\
           children [\n\
             Shape { geometry Box { size 0.1 0.2 0.3 } }\n\
             Shape { geometry Cylinder { radius 0.05 height 0.1 top FALSE } }\n\
             Shape { geometry Sphere { radius 0.07 } }\n\
             PointLight { location 0 0.3 0 attenuation 0 0 2 }\n\
           ]\n\
         }\n\
         Transform {\n\
           rotation 1 1 0 0.7\n\
           children [\n\
             Shape { appearance Appearance { material Material { diffuseColor 1 0 0 transparency 0.5 emissiveColor 0.2 0.2 0 } } geometry Cone { bottomRadius 0.1 height 0.2 } }\n\
             SpotLight { location 0 1 0 direction 0 -1 0 beamWidth 0.3 cutOffAngle 0.5 }\n\
             DirectionalLight { direction 1 -1 0 }\n\
           ]\n\
         }\n\
         Shape {\n\
           geometry IndexedFaceSet {\n\
             coord Coordinate { point [ 0 0 0, 2 0 0, 2 0 1, 1 0 1, 1 0 2, 0 0 2, 0 1 0 ] }\n\
             color Color { color [ 1 0 0, 0 1 0, 0 0 1 ] }\n\
             coordIndex [ 0 1 2 3 4 5 -1, 0 6 1 -1 ]\n\
             colorIndex [ 0 1 2 0 1 2 -1, 0 1 2 -1 ]\n\
             creaseAngle 1.0 solid FALSE\n\
           }\n\
         }\n\
         Transform { translation -2 0 -2 children [ Shape { geometry ElevationGrid { xDimension 3 zDimension 3 xSpacing 0.5 zSpacing 0.5 height [ 0 0.1 0 0.2 0.4 0.2 0 0.1 0 ] creaseAngle 0.5 } } ] }\n",
    );
    for quality in [8, 32] {
        let (document, _) = round_trip(&compiled, quality, "tricky");
        assert_eq!(document.cameras().count(), 1);
        assert_eq!(document.lights().map(|l| l.count()), Some(3));
        let sheared = document
            .nodes()
            .find(|n| n.name() == Some("SHEARED"))
            .expect("DEF name");
        assert_eq!(sheared.children().count(), 4);
    }
}

#[test]
fn z_up_files_come_out_y_up() {
    let compiled = compile_text(
        "#VRML_SIM R2023b utf8\n\
         WorldInfo { }\n\
         DEF HIGH Transform { translation 0 0 1 children [ Shape { geometry Box { size 0.2 0.2 0.2 } } ] }\n",
    );
    let (document, blob) = round_trip(&compiled, 32, "z-up");
    let node = document.nodes().find(|n| n.mesh().is_some()).unwrap();
    let world = world_matrices(&document)[node.index()].unwrap();
    let primitive = node.mesh().unwrap().primitives().next().unwrap();
    let reader = primitive.reader(|_| Some(&blob));
    let top = reader
        .read_positions()
        .unwrap()
        .map(|p| world.transform_point3(glam::Vec3::from(p).as_dvec3()).y)
        .fold(f64::MIN, f64::max);
    assert!(
        (top - 1.1).abs() < 1e-6,
        "the box top is at y = {top}, not 1.1"
    );
}

#[test]
fn corpus_worlds_read_back() {
    let files = regatta_tests::files_with(&corpus(), &["wbt"]);
    assert!(!files.is_empty(), "no corpus at {}", corpus().display());
    let mut exported = 0;
    for file in files {
        let Ok(checked) = regatta_schema::check_file(&file, false) else {
            continue;
        };
        if checked.has_errors() {
            continue;
        }
        let compiled = regatta_runtime::compile(&checked.scene);
        round_trip(&compiled, 16, &file.display().to_string());
        exported += 1;
    }
    assert!(exported >= 20, "only {exported} corpus worlds exported");
}

#[test]
fn tracks_become_translation_and_rotation_channels() {
    let compiled = compile_world("regatta.wbt");
    let times: Vec<f64> = (0..50).map(|i| i as f64 * 0.032).collect();
    let poses: Vec<Pose2> = times
        .iter()
        .map(|&t| Pose2 {
            x: 0.1 * t,
            z: -0.05 * t,
            heading: 3.0 * t,
        })
        .collect();
    let track = Track {
        robot: 0,
        times: times.clone(),
        poses,
    };
    let exported = export(&compiled, &Options::default(), &[track]).unwrap();
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(&exported.to_glb()).unwrap();
    let blob = blob.unwrap();
    let animation = document.animations().next().expect("an animation");
    let robot = &compiled.rig.robots[0].name;
    let mut paths = Vec::new();
    for channel in animation.channels() {
        assert_eq!(channel.target().node().name(), Some(robot.as_str()));
        paths.push(format!("{:?}", channel.target().property()));
        let reader = channel.reader(|_| Some(&blob));
        let inputs: Vec<f32> = reader.read_inputs().unwrap().collect();
        assert_eq!(inputs.len(), times.len());
        if let Some(gltf::animation::util::ReadOutputs::Rotations(rotations)) =
            reader.read_outputs()
        {
            let last = rotations.into_f32().last().unwrap();
            let heading = 2.0 * (last[1] as f64).atan2(last[3] as f64);
            let want = 3.0 * times[times.len() - 1];
            let wrapped = (heading - want).rem_euclid(std::f64::consts::TAU);
            assert!(wrapped.min(std::f64::consts::TAU - wrapped) < 1e-5);
        }
    }
    paths.sort();
    assert_eq!(paths, ["Rotation", "Translation"]);
    // A robot index the world does not have is refused, not exported.
    let bad = Track {
        robot: 7,
        times: vec![0.0],
        poses: vec![Pose2 {
            x: 0.0,
            z: 0.0,
            heading: 0.0,
        }],
    };
    assert!(export(&compiled, &Options::default(), &[bad]).is_err());
}
