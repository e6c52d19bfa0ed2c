//! Line following on a textured floor: the e-puck's ground sensors read the texel of the
//! floor's image under them, as Webots reads it. regatta's own line-following project
//! (examples/line_following) keeps its robot on its line for a minute, and loses it when the
//! image is not there; the image lies on the floor as seen from above, repeated every floor
//! tile; `regatta plot` draws it under the trajectory.
//!
//! The controllers are Python (`python3` from the PATH, the standard library only).

mod common;

use std::path::{Path, PathBuf};

use common::{ok, regatta, root, temp_dir};

const WORLD: &str = "examples/line_following/worlds/line_following.wbt";

fn cache() -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-line-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The distance of floor point (x, y) (Webots' axes) from the middle of the track's line: a
/// stadium of two 0.4 m straights and half circles of 0.25 m radius
/// (scripts/line_track.py).
fn off_line(x: f64, y: f64) -> f64 {
    let dx = (x.abs() - 0.2).max(0.0);
    (dx.hypot(y) - 0.25).abs()
}

/// Runs `world` for `seconds` with a log, and returns the robot's poses (x, Webots' y) and
/// the run's standard error.
fn poses(world: &Path, seconds: &str, extra: &[&str]) -> (Vec<(f64, f64)>, String) {
    let dir = temp_dir("line-run");
    let log = dir.join("run.mcap");
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env_remove("REGATTA_PYTHON")
        .arg("run")
        .arg(world)
        .args(["--duration", seconds, "--log"])
        .arg(&log)
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    ok(&regatta()
        .args(["log", "export", "--csv"])
        .arg(dir.join("csv"))
        .arg(&log)
        .output()
        .unwrap());
    let mut reader = csv::Reader::from_path(dir.join("csv").join("pose.csv")).unwrap();
    let header = reader.headers().unwrap().clone();
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (x, z) = (column("x"), column("z"));
    let poses = reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            // regatta's z points the other way from Webots' y.
            (r[x].parse::<f64>().unwrap(), -r[z].parse::<f64>().unwrap())
        })
        .collect();
    (poses, stderr)
}

fn path_length(poses: &[(f64, f64)]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum()
}

#[test]
fn the_line_follower_stays_on_its_line_for_a_minute() {
    let (poses, stderr) = poses(&root().join(WORLD), "60", &[]);
    assert!(
        stderr.contains("note: robot 'e-puck' runs its project's controller")
            && stderr.contains("(Python)"),
        "{stderr}"
    );
    assert_eq!(poses.len(), 3750, "60 s of 16 ms steps");
    let worst = poses
        .iter()
        .map(|&(x, y)| off_line(x, y))
        .fold(0.0, f64::max);
    // The line is 24 mm wide; its middle is followed within a few millimetres (1.7 mm when
    // this was written).
    assert!(worst < 0.005, "{worst} m off the line's middle");
    // More than a lap of the 2.37 m track.
    let length = path_length(&poses);
    assert!(length > 3.0, "{length} m driven");
}

/// A copy of the line-following project; `image` decides whether its floor image comes too.
fn copy_of_project(image: bool) -> PathBuf {
    let from = root().join("examples/line_following");
    let to = temp_dir("line-project");
    for file in [
        "worlds/line_following.wbt",
        "controllers/line_follower/line_follower.py",
    ] {
        std::fs::create_dir_all(to.join(file).parent().unwrap()).unwrap();
        std::fs::copy(from.join(file), to.join(file)).unwrap();
    }
    if image {
        std::fs::create_dir_all(to.join("worlds/textures")).unwrap();
        std::fs::copy(
            from.join("worlds/textures/track.png"),
            to.join("worlds/textures/track.png"),
        )
        .unwrap();
    }
    to.join("worlds/line_following.wbt")
}

#[test]
fn without_its_image_the_floor_is_plain_and_the_line_is_lost() {
    let world = copy_of_project(false);
    // Strict: a missing image is an error at its line.
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .arg("run")
        .arg(&world)
        .args(["--duration", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(stderr.contains("line_following.wbt:31:"), "{stderr}");
    // Lenient: a warning at its line, and the robot, seeing a light floor everywhere, turns
    // on the spot looking for its line instead of going round.
    let (poses, stderr) = poses(&world, "20", &["--lenient"]);
    assert!(stderr.contains("line_following.wbt:31:"), "{stderr}");
    assert!(stderr.contains("track.png"), "{stderr}");
    let start = poses[0];
    let farthest = poses
        .iter()
        .map(|&(x, y)| (x - start.0).hypot(y - start.1))
        .fold(0.0, f64::max);
    assert!(farthest < 0.05, "{farthest} m from its start");
}

/// A project whose floor shows `image` (`floorTileSize` `tile`), with one e-puck per entry of
/// `at` ((x, y), facing +x) printing its centre ground sensor's first reading.
fn probes(image: &image::GrayImage, tile: f64, at: &[(f64, f64)]) -> Vec<f64> {
    let dir = temp_dir("line-probes");
    std::fs::create_dir_all(dir.join("worlds/textures")).unwrap();
    std::fs::create_dir_all(dir.join("controllers/probe")).unwrap();
    image.save(dir.join("worlds/textures/floor.png")).unwrap();
    std::fs::write(
        dir.join("controllers/probe/probe.py"),
        "from controller import Robot\n\
         robot = Robot()\n\
         gs = robot.getDevice('gs1')\n\
         gs.enable(16)\n\
         robot.step(16)\n\
         print('gs1', gs.getValue())\n\
         while robot.step(16) != -1:\n    pass\n",
    )
    .unwrap();
    let mut world = format!(
        "#VRML_SIM R2023b utf8\n\
         EXTERNPROTO \"webots://projects/objects/floors/protos/RectangleArena.proto\"\n\
         EXTERNPROTO \"webots://projects/robots/gctronic/e-puck/protos/E-puck.proto\"\n\
         EXTERNPROTO \"webots://projects/robots/gctronic/e-puck/protos/E-puckGroundSensors.proto\"\n\
         WorldInfo {{ basicTimeStep 16 }}\n\
         RectangleArena {{\n  floorSize 1 1\n  floorTileSize {tile} {tile}\n  \
         floorAppearance PBRAppearance {{ baseColorMap ImageTexture {{ url [ \"textures/floor.png\" ] }} }}\n}}\n"
    );
    for (k, (x, y)) in at.iter().enumerate() {
        world.push_str(&format!(
            "E-puck {{\n  translation {x} {y} 0\n  name \"probe{k}\"\n  controller \"probe\"\n  \
             groundSensorsSlot [ E-puckGroundSensors {{ }} ]\n}}\n"
        ));
    }
    std::fs::write(dir.join("worlds/w.wbt"), world).unwrap();
    let stderr = two_steps(&dir.join("worlds/w.wbt"));
    (0..at.len())
        .map(|k| numbers_after(&stderr, &format!("[probe{k}] gs1 "))[0])
        .collect()
}

/// What the probe controllers of `world` print in its first two steps.
fn two_steps(world: &Path) -> String {
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env_remove("REGATTA_PYTHON")
        .arg("run")
        .arg(world)
        .args(["--steps", "2"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    stderr
}

/// The numbers of the line of `stderr` that starts with `prefix`.
fn numbers_after(stderr: &str, prefix: &str) -> Vec<f64> {
    stderr
        .lines()
        .find_map(|l| l.strip_prefix(prefix))
        .unwrap_or_else(|| panic!("no line {prefix:?} in {stderr}"))
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

#[test]
fn the_floor_image_lies_as_seen_from_above_repeated_every_tile() {
    // Black in the image's top-left quarter: the floor's −x, +y corner.
    let image = image::GrayImage::from_fn(64, 64, |x, y| {
        image::Luma([if x < 32 && y < 32 { 0 } else { 255 }])
    });
    // The sensors sit about 3 cm ahead of the robot's centre: every probe is well inside
    // its quarter.
    let quarters = [(-0.27, 0.25), (0.23, 0.25), (-0.27, -0.25), (0.23, -0.25)];
    let read = probes(&image, 1.0, &quarters);
    assert!(read[0] < 400.0, "{read:?}");
    for value in &read[1..] {
        assert!(*value > 700.0, "{read:?}");
    }
    // Tiles of 0.5 m: the pattern four times, black at the −x, +y corner of each tile.
    let tiles = [
        (-0.395, 0.375),
        (0.105, 0.375),
        (0.105, -0.125),
        (-0.145, 0.375),
    ];
    let read = probes(&image, 0.5, &tiles);
    assert!(read[..3].iter().all(|v| *v < 400.0), "{read:?}");
    assert!(read[3] > 700.0, "{read:?}");
}

#[test]
fn the_plot_draws_the_floor_image_under_the_trajectory() {
    let dir = temp_dir("line-plot");
    let log = dir.join("run.mcap");
    let output = regatta()
        .env("REGATTA_CACHE_DIR", cache())
        .env_remove("REGATTA_PYTHON")
        .current_dir(root())
        .arg("run")
        .arg(WORLD)
        .args(["--duration", "2", "--log"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    ok(&regatta()
        .current_dir(root())
        .arg("plot")
        .arg(&log)
        .arg("--out")
        .arg(dir.join("plots"))
        .output()
        .unwrap());
    let top = image::open(dir.join("plots/top.png")).unwrap().to_rgb8();
    // The line is the only black area of the figure bigger than text: count black pixels in
    // rows and columns inside the plot.
    let black = top.pixels().filter(|p| p.0 == [0, 0, 0]).count();
    assert!(black > 20_000, "{black} black pixels");
}

#[test]
fn the_thymios_ground_sensors_read_the_line_too() {
    // prox.ground.0 (left) and prox.ground.1 (right), 5 cm ahead of the centre and 11 mm to
    // either side: on the line's middle both read black (0); 11 mm to the left of it, the
    // left one reads the white floor (600 at 8 mm).
    let dir = temp_dir("line-thymio");
    std::fs::create_dir_all(dir.join("worlds/textures")).unwrap();
    std::fs::create_dir_all(dir.join("controllers/probe")).unwrap();
    std::fs::copy(
        root().join("examples/line_following/worlds/textures/track.png"),
        dir.join("worlds/textures/track.png"),
    )
    .unwrap();
    std::fs::write(
        dir.join("controllers/probe/probe.py"),
        "from controller import Robot\n\
         robot = Robot()\n\
         ground = [robot.getDevice('prox.ground.%d' % i) for i in range(2)]\n\
         for sensor in ground:\n    sensor.enable(16)\n\
         robot.step(16)\n\
         print('ground', ground[0].getValue(), ground[1].getValue())\n\
         while robot.step(16) != -1:\n    pass\n",
    )
    .unwrap();
    let read = |y: f64| -> (f64, f64) {
        let world = format!(
            "#VRML_SIM R2023b utf8\n\
             EXTERNPROTO \"webots://projects/objects/floors/protos/RectangleArena.proto\"\n\
             EXTERNPROTO \"webots://projects/robots/mobsya/thymio/protos/Thymio2.proto\"\n\
             WorldInfo {{ basicTimeStep 16 }}\n\
             RectangleArena {{\n  floorSize 1 1\n  floorTileSize 1 1\n  \
             floorAppearance PBRAppearance {{ baseColorMap ImageTexture {{ url [ \"textures/track.png\" ] }} }}\n}}\n\
             Thymio2 {{ translation -0.05 {y} 0 controller \"probe\" }}\n"
        );
        std::fs::write(dir.join("worlds/w.wbt"), world).unwrap();
        let values = numbers_after(&two_steps(&dir.join("worlds/w.wbt")), "[Thymio II] ground ");
        (values[0], values[1])
    };
    let (left, right) = read(-0.25);
    assert!(left < 50.0 && right < 50.0, "{left} {right}");
    let (left, right) = read(-0.239);
    assert!(left > 550.0 && right < 50.0, "{left} {right}");
}
