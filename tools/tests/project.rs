//! A Webots project read as Webots reads it: the folder above `worlds/` is what a world may
//! read, nothing outside it, and an unavailable PROTO is skipped in lenient mode.

mod common;

use common::{regatta, temp_dir};

/// A Webots project is a folder: `worlds/`, `protos/` and `controllers/` side by side, worlds
/// naming `../protos/X.proto`. Such a world reads its project without flags; nothing outside
/// the project is read (a `../../` escape is refused, in both modes); an unavailable PROTO is
/// a warning in lenient mode and its node skipped, and `run` then refuses the unbuilt robot.
#[test]
fn a_webots_project_is_read_as_webots_reads_it() {
    let dir = temp_dir("project");
    let project = dir.join("project");
    std::fs::create_dir_all(project.join("worlds")).unwrap();
    std::fs::create_dir_all(project.join("protos")).unwrap();
    std::fs::write(
        dir.join("Secret.proto"),
        "#VRML_SIM R2023b utf8\nPROTO Secret [] { Solid {} }\n",
    )
    .unwrap();
    std::fs::write(
        project.join("protos/Crate.proto"),
        "#VRML_SIM R2023b utf8\nPROTO Crate [ field SFVec3f translation 0 0 0 ] {\n  Solid {\n    translation IS translation\n    children [ Shape { geometry Box { size 0.1 0.1 0.1 } } ]\n    boundingObject Box { size 0.1 0.1 0.1 }\n  }\n}\n",
    )
    .unwrap();
    let header = "#VRML_SIM R2023b utf8\n";
    std::fs::write(
        project.join("worlds/good.wbt"),
        format!("{header}EXTERNPROTO \"../protos/Crate.proto\"\nWorldInfo {{ coordinateSystem \"NUE\" }}\nCrate {{ translation 0.2 0.05 0 }}\n"),
    )
    .unwrap();
    std::fs::write(
        project.join("worlds/escape.wbt"),
        format!("{header}EXTERNPROTO \"../../Secret.proto\"\nWorldInfo {{ coordinateSystem \"NUE\" }}\nSecret {{ }}\n"),
    )
    .unwrap();
    std::fs::write(
        project.join("worlds/missing.wbt"),
        format!("{header}EXTERNPROTO \"../protos/Robot.proto\"\nWorldInfo {{ coordinateSystem \"NUE\" }}\nRobot {{ }}\n"),
    )
    .unwrap();

    let good = regatta()
        .args(["check", "worlds/good.wbt"])
        .current_dir(&project)
        .output()
        .unwrap();
    assert_eq!(
        good.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&good.stderr)
    );
    let explain = regatta()
        .args(["explain", "worlds/good.wbt"])
        .current_dir(&project)
        .output()
        .unwrap();
    let shown = String::from_utf8_lossy(&explain.stdout);
    let root = project.canonicalize().unwrap();
    assert!(
        shown.contains(&format!("reads files under {}", root.display())),
        "explain names the project: {shown}"
    );

    for mode in [&["check"][..], &["check", "--lenient"][..]] {
        let escape = regatta()
            .args(mode)
            .arg("worlds/escape.wbt")
            .current_dir(&project)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&escape.stderr);
        assert!(
            stderr.contains("'../../Secret.proto' leads outside the world's project"),
            "{mode:?}: {stderr}"
        );
        if mode.len() == 1 {
            assert_eq!(escape.status.code(), Some(1), "{stderr}");
        }
    }

    let lenient = regatta()
        .args(["check", "--lenient", "worlds/missing.wbt"])
        .current_dir(&project)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&lenient.stderr);
    assert_eq!(lenient.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: EXTERNPROTO url '../protos/Robot.proto' does not exist"),
        "{stderr}"
    );
    let strict = regatta()
        .args(["check", "worlds/missing.wbt"])
        .current_dir(&project)
        .output()
        .unwrap();
    assert_eq!(strict.status.code(), Some(1));
    std::fs::remove_dir_all(&dir).ok();
}
