//! `regatta gltf`: a world as a glTF 2.0 file (binary .glb or text .gltf with a .bin beside
//! it), optionally animated with the robot poses of a recorded run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_gltf::{export, Options, Track};
use regatta_runtime::compile::rig::Pose2;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    /// Output file: .glb (binary, one file) or .gltf (JSON, with a .bin beside it).
    #[arg(short, long)]
    output: PathBuf,
    /// Segments around a full circle for cylinders, cones and spheres (a multiple of 4,
    /// 8…4096).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(8..=4096))]
    quality: u32,
    /// A log recorded from this world: each robot's poses become an animation.
    #[arg(long)]
    log: Option<PathBuf>,
    /// Print each shape of the world: exported (with its triangles) or skipped, and why.
    #[arg(long)]
    report: bool,
    #[command(flatten)]
    options: crate::world::WorldOptions,
}

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let extension = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let binary = match extension.as_deref() {
        Some("glb") => true,
        Some("gltf") => false,
        _ => bail!(
            "{}: the output must end in .glb or .gltf",
            args.output.display()
        ),
    };
    let loaded = crate::world::load(&args.world, &args.options, color)?;
    let compiled = &loaded.compiled;
    let tracks = match &args.log {
        Some(log) => tracks_from_log(log, &args.world, compiled)?,
        None => Vec::new(),
    };
    let document = export(
        compiled,
        &Options {
            quality: args.quality,
        },
        &tracks,
    )?;
    if binary {
        write(&args.output, &document.to_glb())?;
    } else {
        let bin = args.output.with_extension("bin");
        let bin_name = bin
            .file_name()
            .and_then(|n| n.to_str())
            .context("the output's name is not valid UTF-8")?
            .to_owned();
        write(&bin, &document.bin)?;
        write(&args.output, document.to_gltf(&bin_name).as_bytes())?;
    }
    if args.report {
        print!("{}", report(&loaded, args.quality));
    }
    let frames: usize = tracks.iter().map(|t| t.times.len()).max().unwrap_or(0);
    eprintln!(
        "wrote {}: {} nodes, {} triangles{}",
        args.output.display(),
        document.node_count,
        document.triangle_count,
        if tracks.is_empty() {
            String::new()
        } else {
            format!(", {} robot track(s) of up to {frames} poses", tracks.len())
        }
    );
    Ok(Outcome::Clean)
}

/// The export's report: one line per shape (its place in the files, its geometry, what became
/// of it), then the totals.
fn report(loaded: &crate::world::Loaded, quality: u32) -> String {
    let scene = &loaded.checked.scene;
    let rows = regatta_gltf::report(&loaded.compiled, quality);
    let mut out = String::new();
    let (mut exported, mut triangles) = (0, 0);
    for row in &rows {
        let origin = scene.node(row.node).origin;
        let file = origin.file.0 as usize;
        let place = match loaded.checked.sources.get(file) {
            Some(source) => {
                let (line, col) =
                    regatta_parser::diagnostic::line_col(&source.text, origin.span.start as usize);
                format!("{}:{line}:{col}", source.name)
            }
            None => "?".to_owned(),
        };
        // The geometry node's own type (the graph calls every triangulated one "Mesh").
        let own = scene.spec(row.node).field_index("geometry").is_some();
        let geometry = match own.then(|| scene.child(row.node, "geometry")).flatten() {
            Some(g) => scene.type_name(g).to_owned(),
            None if !own || row.geometry.is_empty() => scene.type_name(row.node).to_owned(),
            None => row.geometry.clone(),
        };
        match &row.status {
            Ok(n) => {
                exported += 1;
                triangles += n;
                out.push_str(&format!("exported {place} {geometry}: {n} triangles\n"));
            }
            Err(reason) => out.push_str(&format!("skipped {place} {geometry}: {reason}\n")),
        }
    }
    out.push_str(&format!(
        "{} shapes: {exported} exported, {} skipped; {triangles} triangles\n",
        rows.len(),
        rows.len() - exported
    ));
    out
}

fn write(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

/// Each robot's `/{robot}/pose` messages, matched to the world's robots by name.
fn tracks_from_log(
    log: &Path,
    world: &Path,
    compiled: &regatta_runtime::Compiled,
) -> anyhow::Result<Vec<Track>> {
    let bytes = std::fs::read(log).with_context(|| format!("cannot read {}", log.display()))?;
    let contents = regatta_runtime::log::read(&bytes)
        .with_context(|| format!("{} is not a regatta log", log.display()))?;
    if let Some(reason) = &contents.truncated {
        eprintln!(
            "warning: {} ends early ({reason}); animating what its complete chunks hold",
            log.display()
        );
    }
    let world_text = std::fs::read_to_string(world).unwrap_or_default();
    if world_text != contents.run.world_text {
        eprintln!(
            "warning: {} was recorded from another version of {}; robots are matched by name",
            log.display(),
            world.display()
        );
    }
    let mut poses: BTreeMap<&str, (Vec<f64>, Vec<Pose2>)> = BTreeMap::new();
    for (topic, _, data) in &contents.messages {
        let (robot, kind) = crate::logs::robot_of(&contents, topic);
        if kind != "pose" {
            continue;
        }
        let Ok((t, pose)) = regatta_runtime::log::decode_pose(data) else {
            bail!("{}: a pose message on {topic} is cut short", log.display());
        };
        let entry = poses.entry(robot).or_default();
        // Keep times strictly increasing in single precision, as glTF stores them.
        if entry
            .0
            .last()
            .is_none_or(|&last| (t as f32) > (last as f32))
        {
            entry.0.push(t);
            entry.1.push(pose);
        }
    }
    if poses.is_empty() {
        bail!("{} holds no robot poses", log.display());
    }
    poses
        .into_iter()
        .map(|(name, (times, poses))| {
            let robot = compiled.rig.robot(name).with_context(|| {
                format!("the log's robot '{name}' is not in {}", world.display())
            })?;
            let (mut times, mut poses) = (times, poses);
            // Poses are logged at the end of each step: the run starts at the file's pose.
            if times.first().is_some_and(|&t| t > 0.0) {
                times.insert(0, 0.0);
                poses.insert(0, compiled.rig.robots[robot].start);
            }
            Ok(Track {
                robot,
                times,
                poses,
            })
        })
        .collect()
}
