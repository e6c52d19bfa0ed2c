//! The geometry every world may hold, exported whether or not regatta simulates it: Webots'
//! Plane, Capsule, Mesh and CadShape (OBJ with MTL, STL), ElevationGrid in both field
//! conventions, Extrusion, IndexedLineSet and PointSet (glTF lines and points), and Pose. Mesh
//! files go through the world's file access and size limit; a missing, malformed, oversized or
//! outside file is a warning naming it (lenient) or an error at its line (strict), never a
//! panic, and the report says what became of each shape.

use std::path::{Path, PathBuf};

use regatta_gltf::{export, report, Options};
use regatta_schema::{check_path, Checked, Limits};

/// A fresh project folder for one test.
fn project(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "regatta-gltf-geometry-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    dir
}

const OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nusemtl red\nf 1 2 3 4\nusemtl blue\nf 1 2 5\n";
const MTL: &str = "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n";
const STL: &str = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";

fn check(world: &Path, strict: bool, limits: Limits) -> Checked {
    check_path(
        world,
        &regatta_schema::Options {
            strict,
            limits,
            ..regatta_schema::Options::default()
        },
    )
    .expect("world readable")
}

fn write_world(dir: &Path, body: &str) -> PathBuf {
    std::fs::write(dir.join("meshes/box.obj"), OBJ).unwrap();
    std::fs::write(dir.join("meshes/box.mtl"), MTL).unwrap();
    std::fs::write(dir.join("meshes/tri.stl"), STL).unwrap();
    let world = dir.join("world.wbt");
    std::fs::write(
        &world,
        format!("#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" }}\n{body}"),
    )
    .unwrap();
    world
}

const EVERY_GEOMETRY: &str = r#"
Pose { translation 1 0 0 children [
  Shape { geometry Plane { size 4 4 } }
] }
Shape { geometry Capsule { radius 0.1 height 0.2 } }
Shape { geometry Extrusion { } }
Shape { geometry ElevationGrid { xDimension 2 zDimension 2 height [0 0 0 0] } }
Shape { geometry ElevationGrid { xDimension 3 yDimension 2 height [0 0 0 1 1 1] } }
Shape { geometry IndexedLineSet { coord Coordinate { point [0 0 0, 1 0 0, 1 1 0] } coordIndex [0 1 2 -1] } }
Shape { geometry PointSet { coord Coordinate { point [0 0 0, 1 0 0] } color Color { color [1 0 0, 0 1 0] } } }
Shape { geometry Mesh { url "meshes/box.obj" } }
Shape { geometry Mesh { url "meshes/tri.stl" } }
CadShape { url "meshes/box.obj" }
"#;

#[test]
fn every_geometry_node_is_exported_and_reported() {
    let dir = project("every");
    let world = write_world(&dir, EVERY_GEOMETRY);
    let checked = check(&world, true, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let compiled = regatta_runtime::compile(&checked.scene);
    let rows = report(&compiled, 16);
    assert_eq!(rows.len(), 10, "{rows:#?}");
    for row in &rows {
        assert!(row.status.is_ok(), "{row:?}");
    }
    // Plane 2, grids 2 + 4, OBJ 3 (a quad and a triangle), STL 1, CadShape 3.
    let triangles: Vec<usize> = rows.iter().map(|r| *r.status.as_ref().unwrap()).collect();
    assert!(triangles.contains(&2) && triangles.contains(&4) && triangles.contains(&3));
    let document = export(&compiled, &Options { quality: 16 }, &[]).unwrap();
    let glb = document.to_glb();
    let gltf = gltf::Gltf::from_slice(&glb).expect("the gltf crate reads the export");
    let modes: Vec<gltf::mesh::Mode> = gltf
        .meshes()
        .flat_map(|m| m.primitives().map(|p| p.mode()).collect::<Vec<_>>())
        .collect();
    assert!(modes.contains(&gltf::mesh::Mode::Lines), "{modes:?}");
    assert!(modes.contains(&gltf::mesh::Mode::Points), "{modes:?}");
    // The CadShape keeps its MTL colours per triangle.
    let cad = compiled
        .graph
        .meshes
        .iter()
        .find(|m| m.triangle_colors.is_some())
        .expect("a coloured mesh");
    assert!(cad
        .triangle_colors
        .as_ref()
        .unwrap()
        .contains(&[1.0, 0.0, 0.0]));
    // The Plane lies in its Pose, 4 m wide.
    let plane = compiled
        .graph
        .primitives
        .iter()
        .find(|p| (p.bounds.max.x - p.bounds.min.x - 4.0).abs() < 1e-9)
        .expect("the plane");
    assert!(
        (plane.bounds.min.x - -1.0).abs() < 1e-9,
        "{:?}",
        plane.bounds
    );
}

#[test]
fn a_webots_elevation_grid_lies_along_y_in_a_flu_world() {
    let dir = project("flu");
    let world = dir.join("world.wbt");
    std::fs::write(
        &world,
        "#VRML_SIM R2023b utf8\nShape { geometry ElevationGrid { xDimension 2 yDimension 3 xSpacing 1 ySpacing 2 height [0 0 0 0 1 1] } }\n",
    )
    .unwrap();
    let checked = check(&world, true, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let compiled = regatta_runtime::compile(&checked.scene);
    let bounds = compiled.graph.primitives[0].bounds;
    // Webots: x 0…1, y 0…4, heights up along z; the scene is y-up, so file y is scene −z.
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    assert!(
        close(bounds.min.x, 0.0) && close(bounds.max.x, 1.0),
        "{bounds:?}"
    );
    assert!(
        close(bounds.min.y, 0.0) && close(bounds.max.y, 1.0),
        "{bounds:?}"
    );
    assert!(
        close(bounds.min.z, -4.0) && close(bounds.max.z, 0.0),
        "{bounds:?}"
    );
    // The raised row is the far one (file y = 4).
    let mesh = &compiled.graph.meshes[0];
    let frame = compiled.graph.primitives[0].frame;
    let high: Vec<f64> = mesh
        .positions
        .iter()
        .map(|&p| frame.apply(p))
        .filter(|p| p.y > 0.5)
        .map(|p| p.z)
        .collect();
    assert!(high.iter().all(|&z| close(z, -4.0)), "{high:?}");
}

#[test]
fn missing_malformed_outside_and_oversized_files_are_named_never_a_panic() {
    let dir = project("bad");
    std::fs::write(dir.join("meshes/garbage.stl"), b"\x00\x01\x02 not an stl").unwrap();
    std::fs::write(dir.join("meshes/big.stl"), vec![b' '; 4096]).unwrap();
    let body = r#"
Shape { geometry Mesh { url "meshes/missing.obj" } }
Shape { geometry Mesh { url "meshes/garbage.stl" } }
Shape { geometry Mesh { url "../../../../etc/passwd" } }
Shape { geometry Mesh { url "meshes/big.stl" } }
Shape { geometry Mesh { url "meshes/box.dae" } }
"#;
    let world = write_world(&dir, body);
    std::fs::write(dir.join("meshes/box.dae"), "<COLLADA/>").unwrap();
    let mut limits = Limits::default();
    limits.set("file-size=1k").unwrap();
    // Lenient: warnings naming each file; the shapes are reported skipped.
    let checked = check(&world, false, limits.clone());
    let text = checked.render(false);
    assert!(!checked.has_errors() || text.contains("passwd"), "{text}");
    for name in ["missing.obj", "passwd", "big.stl"] {
        assert!(text.contains(name), "{name} not named:\n{text}");
    }
    assert!(text.contains("file-size limit"), "{text}");
    let compiled = regatta_runtime::compile(&checked.scene);
    let rows = report(&compiled, 16);
    assert_eq!(rows.len(), 5, "{rows:#?}");
    assert!(rows.iter().all(|r| r.status.is_err()), "{rows:#?}");
    let warnings = compiled.warnings.join("\n");
    assert!(warnings.contains("garbage.stl"), "{warnings}");
    assert!(warnings.contains("Collada"), "{warnings}");
    // Strict: a missing file is an error at its line.
    let checked = check(&world, true, limits);
    assert!(checked.has_errors());
    let missing = checked
        .diagnostics
        .iter()
        .find(|d| d.diagnostic.message.contains("missing.obj"))
        .expect("the missing file is named");
    assert!(missing.diagnostic.is_error());
    let source = &checked.sources[missing.file.0 as usize].text;
    let (line, _) =
        regatta_parser::diagnostic::line_col(source, missing.diagnostic.span.start as usize);
    assert_eq!(line, 4);
}

/// Nodes regatta does not simulate keep the shapes they hold: a top-level Supervisor (R2018),
/// a joint's endPoint, a solid device's and a Servo's children, each at its transform.
#[test]
fn shapes_inside_unsimulated_nodes_are_exported_in_place() {
    let dir = project("unsimulated");
    let body = r#"
Supervisor { translation 1 0 0 controller "human" children [
  Transform { translation 0 1 0 children [ Shape { geometry Box { size 0.1 0.1 0.1 } } ] }
] }
Robot { children [
  HingeJoint {
    jointParameters HingeJointParameters { axis 0 0 1 }
    device [ RotationalMotor { name "m" } DEF SENSOR PositionSensor { } ]
    endPoint Solid { translation 0 0 2 children [ Shape { geometry Sphere { radius 0.1 } } ] }
  }
  LED { translation 0 3 0 color [1 0 0] children [ Shape { geometry Box { size 0.1 0.1 0.1 } } ] }
  Servo { translation 0 0 -2 maxVelocity 2 children [ Shape { geometry Capsule { } } ] }
] }
"#;
    let world = write_world(&dir, body);
    let checked = check(&world, false, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let text = checked.render(false);
    assert!(text.contains("'Servo' is read but not simulated"), "{text}");
    assert!(
        !text.contains("'maxVelocity' field"),
        "fields of open nodes are skipped quietly:\n{text}"
    );
    // The Supervisor's controller is a robot regatta does not build.
    assert!(checked.unbuilt_refusal().is_some());
    let compiled = regatta_runtime::compile(&checked.scene);
    let rows = report(&compiled, 16);
    assert_eq!(rows.len(), 4, "{rows:#?}");
    let centre =
        |p: &regatta_runtime::compile::graph::Primitive| (p.bounds.min + p.bounds.max) / 2.0;
    let centres: Vec<glam::DVec3> = compiled.graph.primitives.iter().map(centre).collect();
    for want in [
        glam::DVec3::new(1.0, 1.0, 0.0),
        glam::DVec3::new(0.0, 0.0, 2.0),
        glam::DVec3::new(0.0, 3.0, 0.0),
        glam::DVec3::new(0.0, 0.0, -2.0),
    ] {
        assert!(
            centres.iter().any(|c| c.distance(want) < 1e-9),
            "no shape at {want}: {centres:?}"
        );
    }
    // Strict mode refuses what it does not simulate, at its line.
    assert!(check(&world, true, Limits::default()).has_errors());
}

/// A Cylinder or Cone with none of its parts drawn has no surface: the export leaves it out
/// (glTF has no empty meshes) and the report says why; the other primitives are exported.
#[test]
fn a_shape_without_surface_is_left_out_and_reported() {
    let dir = project("empty");
    let world = write_world(
        &dir,
        "Shape { geometry Cylinder { side FALSE top FALSE bottom FALSE } }\n\
         Shape { geometry Cone { side FALSE bottom FALSE } }\n\
         Shape { geometry Cylinder { side FALSE top FALSE } }\n\
         Shape { geometry Sphere { } }\n",
    );
    let checked = check(&world, true, Limits::default());
    assert!(!checked.has_errors(), "{}", checked.render(false));
    let compiled = regatta_runtime::compile(&checked.scene);
    let rows = report(&compiled, 16);
    let skipped: Vec<&str> = rows
        .iter()
        .filter_map(|r| r.status.as_ref().err().map(String::as_str))
        .collect();
    assert_eq!(skipped.len(), 2, "{rows:#?}");
    assert!(
        skipped.iter().all(|r| r.starts_with("no surface")),
        "{skipped:?}"
    );
    let document = export(&compiled, &Options { quality: 16 }, &[]).unwrap();
    let glb = document.to_glb();
    let gltf = gltf::Gltf::from_slice(&glb).expect("the gltf crate reads the export");
    assert_eq!(gltf.meshes().count(), 2);
    for accessor in gltf.accessors() {
        assert!(accessor.count() > 0);
    }
}
