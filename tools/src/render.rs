//! `regatta render`: what each robot's vision device sees at its pose in the file, stage by
//! stage, as enlarged PNG strips or as JSON.

use std::path::{Path, PathBuf};

use anyhow::Context;
use image::{GrayImage, Luma, Rgb, RgbImage};
use regatta_runtime::compile::rig::TurretRig;
use regatta_runtime::optics::{
    LinearCamera, LinearCameraOutput, Panoramic, Renderer, RetinaOutput, FLAT_COLUMNS, FLAT_ROWS,
};
use regatta_runtime::render::Poses;
use serde_json::json;

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The world file (`-` reads standard input).
    world: PathBuf,
    /// Only this robot (by name).
    #[arg(long)]
    robot: Option<String>,
    /// Directory for the PNG images.
    #[arg(long, default_value = "out/render")]
    out: PathBuf,
    /// PNG images, or one JSON object per robot on standard output.
    #[arg(long, value_enum, default_value_t = Format::Png)]
    format: Format,
    #[command(flatten)]
    options: crate::world::WorldOptions,
    /// Render with the ray caster even where the column renderer applies (the reference).
    #[arg(long)]
    rays: bool,
    /// What renders vision devices (`wgpu`: paper optics on the GPU, every robot in one batch).
    #[arg(long, value_enum, default_value_t)]
    renderer: crate::vision::RendererKind,
    /// Instead of the robots' devices, the world seen from its first Viewpoint with the CPU
    /// rasteriser, as OUT/viewpoint.png (what a glTF viewer should show of the export).
    #[arg(long)]
    viewpoint: bool,
    /// With --viewpoint: every surface white and unlit on black, the world's silhouette (what
    /// the browser test compares a glTF viewer's picture with).
    #[arg(long, requires = "viewpoint")]
    silhouette: bool,
    /// The viewpoint picture's size in pixels (WIDTHxHEIGHT).
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    size: (usize, usize),
}

fn parse_size(text: &str) -> Result<(usize, usize), String> {
    let (w, h) = text
        .split_once('x')
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT"))?;
    let parse = |v: &str| v.parse::<usize>().ok().filter(|&n| (1..=4096).contains(&n));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("'{text}': each side is 1 to 4096 pixels")),
    }
}

/// The world from its first Viewpoint (VRML97: looking along −z with +y up, the field of view
/// across the smaller side), rasterised as a robot's camera is, every robot at its start.
fn render_viewpoint(args: &Args, compiled: &regatta_runtime::Compiled) -> anyhow::Result<()> {
    use glam::{DMat3, DVec3};
    let graph = &compiled.graph;
    let viewpoint = graph
        .viewpoint
        .as_ref()
        .context("the world has no Viewpoint")?;
    let (width, height) = args.size;
    // A camera looks along its +x with +y up and +z to the right.
    let turn = regatta_runtime::geometry::Frame {
        linear: DMat3::from_cols(DVec3::NEG_Z, DVec3::Y, DVec3::X),
        translation: DVec3::ZERO,
    };
    // Square pixels: across the wider side the half-angle's tangent grows with the aspect.
    let tan_small = (viewpoint.field_of_view / 2.0).tan();
    let aspect = width as f64 / height as f64;
    let horizontal = 2.0 * (tan_small * aspect.max(1.0)).atan();
    let rig = regatta_runtime::compile::rig::CameraRig {
        name: "viewpoint".to_owned(),
        frame: viewpoint.frame.then(&turn),
        width,
        height,
        field_of_view: horizontal,
        near: 0.01,
        far: 0.0,
        noise: 0.0,
        period: 0.0,
        renderer: regatta_runtime::compile::rig::CameraRenderer::Raster,
    };
    let silhouette;
    let graph = if args.silhouette {
        let mut white = graph.clone();
        for material in &mut white.materials {
            *material = regatta_runtime::compile::graph::Material::UNLIT;
        }
        white.background = regatta_runtime::compile::graph::Background {
            sky: [0.0; 3],
            ground: None,
        };
        silhouette = white;
        &silhouette
    } else {
        graph
    };
    // The robots' plan leaves out what no vision device can see (a floor under a linear
    // camera): a viewer sees everything, and every light.
    let mut plan = compiled.plan.clone();
    plan.visible = (0..graph.primitives.len()).collect();
    plan.lights = (0..graph.lights.len()).collect();
    let plan = &plan;
    let raster = regatta_runtime::render::raster::Rasterizer::new(graph, plan);
    let poses = Poses {
        poses: compiled.rig.robots.iter().map(|r| r.start).collect(),
        floor_y: compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
    };
    let mut camera = regatta_runtime::camera::Camera::new(&rig);
    let mut image = regatta_runtime::camera::CameraImage::default();
    let mut unused = regatta_runtime::sim::noise::Stream::new(0, 0, 0, 0);
    camera.update_raster_world(&raster, plan, &poses, &mut unused, &mut image);
    let picture = RgbImage::from_raw(width as u32, height as u32, image.rgb)
        .context("the rasteriser gave no picture")?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let path = args.out.join("viewpoint.png");
    picture
        .save(&path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("{}", path.display());
    Ok(())
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Format {
    Png,
    Json,
}

/// Pixels per photodiode horizontally, and strip height, in the pictures.
const SCALE: u32 = 6;
const STRIP_HEIGHT: u32 = 36;

pub fn run(args: Args, color: bool) -> anyhow::Result<Outcome> {
    let loaded = crate::world::load(&args.world, &args.options, color)?;
    let compiled = &loaded.compiled;
    if args.viewpoint {
        render_viewpoint(&args, compiled)?;
        return Ok(Outcome::Clean);
    }
    let robots: Vec<usize> = match &args.robot {
        Some(name) => vec![crate::world::robot_named(compiled, &args.world, name)?],
        None => (0..compiled.rig.robots.len()).collect(),
    };
    let with_cameras: Vec<usize> = robots
        .iter()
        .copied()
        .filter(|&r| !compiled.rig.robots[r].cameras.is_empty())
        .collect();
    let with_vision: Vec<usize> = robots
        .into_iter()
        .filter(|&r| compiled.rig.robots[r].turret.is_some())
        .collect();
    if with_vision.is_empty() && with_cameras.is_empty() {
        eprintln!("no robot carries a vision device: nothing to render");
        return Ok(Outcome::Clean);
    }
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, args.rays);
    let poses = Poses {
        poses: compiled.rig.robots.iter().map(|r| r.start).collect(),
        floor_y: compiled.rig.robots.iter().map(|r| r.floor_y).collect(),
    };
    // With the wgpu backend, every robot's device in one batch; the CPU renders otherwise.
    let mut gpu_luminance = Vec::new();
    if let Some(mut backend) = crate::vision::backend(args.renderer, compiled, &args.world)? {
        let requests: Vec<_> = with_vision
            .iter()
            .map(|&robot| regatta_runtime::vision::VisionRequest { instance: 0, robot })
            .collect();
        let instances = [regatta_runtime::vision::WorldInstance {
            scene: 0,
            poses: &poses,
        }];
        backend.render(&instances, &requests, &mut gpu_luminance)?;
        eprintln!("rendered by {}", backend.describe());
    }
    if args.format == Format::Png {
        std::fs::create_dir_all(&args.out)
            .with_context(|| format!("cannot create {}", args.out.display()))?;
    }
    render_cameras(&args, compiled, &poses, &with_cameras)?;
    for (slot, &robot) in with_vision.iter().enumerate() {
        let rig = &compiled.rig.robots[robot];
        let from_gpu = gpu_luminance.get(slot);
        let view = renderer.view(&compiled.plan, &poses, robot);
        match rig.turret.as_ref().expect("filtered above") {
            TurretRig::Panoramic(panoramic) => {
                let mut retina = Panoramic::new(panoramic);
                let mut output = RetinaOutput::default();
                match from_gpu {
                    Some(luminance) => retina.accept(luminance, &mut output),
                    None => retina.update(&renderer, &view, rig.start, rig.floor_y, &mut output),
                }
                match args.format {
                    Format::Json => {
                        println!("{}", panoramic_json(&rig.name, panoramic.roi, &output))
                    }
                    Format::Png => {
                        let written =
                            panoramic_pngs(&args.out, &rig.name, panoramic.bits, &output)?;
                        for path in written {
                            println!("{}", path.display());
                        }
                    }
                }
            }
            TurretRig::Linear(camera) => {
                let mut k213 = LinearCamera::new(camera);
                let mut output = LinearCameraOutput::default();
                match from_gpu {
                    Some(luminance) => k213.accept(luminance, &mut output),
                    None => k213.update(&renderer, &view, rig.start, rig.floor_y, &mut output),
                }
                match args.format {
                    Format::Json => println!(
                        "{}",
                        json!({"robot": rig.name, "device": "LinearCamera", "analog": output.analog, "digital": output.digital, "light_level": output.light_level, "dark": output.dark})
                    ),
                    Format::Png => {
                        let top = ((1u32 << camera.bits) - 1) as f64;
                        let stages = [
                            ("luminance", normalized(&output.luminance)),
                            ("analog", normalized(&output.analog)),
                            (
                                "digital",
                                output.digital.iter().map(|&d| d as f64 / top).collect(),
                            ),
                        ];
                        for (stage, values) in stages {
                            let path = args.out.join(format!("{}-k213-{stage}.png", rig.name));
                            strip(&values)
                                .save(&path)
                                .with_context(|| format!("cannot write {}", path.display()))?;
                            println!("{}", path.display());
                        }
                    }
                }
            }
        }
    }
    Ok(Outcome::Clean)
}

/// Enlargement of camera images in the PNGs.
const CAMERA_SCALE: u32 = 4;

/// Every 2-D camera of `robots`, rendered by the ray caster at the robots' poses in the file
/// (without noise: the picture of the scene, not of one noisy frame).
fn render_cameras(
    args: &Args,
    compiled: &regatta_runtime::Compiled,
    poses: &Poses,
    robots: &[usize],
) -> anyhow::Result<()> {
    if robots.is_empty() {
        return Ok(());
    }
    let caster = regatta_runtime::render::raycast::RayCaster::new(&compiled.graph, &compiled.plan);
    for &robot in robots {
        let rig = &compiled.rig.robots[robot];
        let view = caster.prepare(&compiled.plan, poses, Some(robot));
        for camera_rig in &rig.cameras {
            let camera_rig = regatta_runtime::compile::rig::CameraRig {
                noise: 0.0,
                ..camera_rig.clone()
            };
            let camera = regatta_runtime::camera::Camera::new(&camera_rig);
            let mut image = regatta_runtime::camera::CameraImage::default();
            let mut unused = regatta_runtime::sim::noise::Stream::new(0, robot, 0, 0);
            camera.update(
                &caster,
                &view,
                rig.start,
                rig.floor_y,
                &mut unused,
                &mut image,
            );
            match args.format {
                Format::Json => println!(
                    "{}",
                    json!({"robot": rig.name, "device": "Camera", "name": camera_rig.name, "width": image.width, "height": image.height, "rgb": image.rgb})
                ),
                Format::Png => {
                    let (w, h) = (image.width as u32, image.height as u32);
                    let picture = RgbImage::from_fn(w * CAMERA_SCALE, h * CAMERA_SCALE, |x, y| {
                        let at = 3 * ((y / CAMERA_SCALE) * w + x / CAMERA_SCALE) as usize;
                        Rgb([image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]])
                    });
                    let path = args
                        .out
                        .join(format!("{}-camera-{}.png", rig.name, camera_rig.name));
                    picture
                        .save(&path)
                        .with_context(|| format!("cannot write {}", path.display()))?;
                    println!("{}", path.display());
                }
            }
        }
    }
    Ok(())
}

fn panoramic_json(name: &str, roi: (usize, usize), output: &RetinaOutput) -> serde_json::Value {
    let filtered: serde_json::Map<String, serde_json::Value> = output
        .filtered
        .iter()
        .map(|(k, v)| (k.name().to_owned(), json!(v)))
        .collect();
    let digital: serde_json::Map<String, serde_json::Value> = output
        .digital
        .iter()
        .map(|(k, v)| (k.name().to_owned(), json!(v)))
        .collect();
    let i_bda: serde_json::Map<String, serde_json::Value> = output
        .i_bda
        .iter()
        .map(|(k, v)| (k.name().to_owned(), json!(v)))
        .collect();
    json!({
        "robot": name,
        "device": "PanoramicTurret",
        "analog": output.analog,
        "filtered": filtered,
        "digital": digital,
        "i_bda": i_bda,
        "region_of_interest": [roi.0, roi.1],
        "dark": output.dark,
    })
}

/// Values scaled to [0, 1] by their largest magnitude (a dark strip stays black).
fn normalized(values: &[f64]) -> Vec<f64> {
    let peak = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values
        .iter()
        .map(|v| if peak > 0.0 { v / peak } else { 0.0 })
        .collect()
}

/// Signed values mapped to grey around mid-grey.
fn signed(values: &[f64]) -> Vec<f64> {
    let peak = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values
        .iter()
        .map(|v| {
            if peak > 0.0 {
                0.5 + 0.5 * v / peak
            } else {
                0.5
            }
        })
        .collect()
}

fn grey(value: f64) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// A 1-D strip, enlarged.
fn strip(values: &[f64]) -> GrayImage {
    GrayImage::from_fn(values.len() as u32 * SCALE, STRIP_HEIGHT, |x, _| {
        Luma([grey(values[(x / SCALE) as usize])])
    })
}

fn panoramic_pngs(
    dir: &Path,
    robot: &str,
    bits: u32,
    output: &RetinaOutput,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let mut save = |name: String, image: image::DynamicImage| -> anyhow::Result<()> {
        let path = dir.join(name);
        image
            .save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        written.push(path);
        Ok(())
    };
    let enlarge = 8;
    for (v, flat) in output.flat_views.iter().enumerate() {
        let side = if v == 0 { "left" } else { "right" };
        let image = RgbImage::from_fn(
            FLAT_COLUMNS as u32 * enlarge,
            FLAT_ROWS as u32 * enlarge,
            |x, y| {
                let c = flat[(y / enlarge) as usize * FLAT_COLUMNS + (x / enlarge) as usize];
                Rgb(c.map(grey))
            },
        );
        save(format!("{robot}-flat-{side}.png"), image.into())?;
        let warped = &output.warped[v];
        let peak = warped.iter().fold(0.0f64, |m, v| m.max(*v));
        let image = GrayImage::from_fn(
            FLAT_COLUMNS as u32 * enlarge,
            FLAT_ROWS as u32 * enlarge,
            |x, y| {
                let value = warped[(y / enlarge) as usize * FLAT_COLUMNS + (x / enlarge) as usize];
                Luma([grey(if peak > 0.0 { value / peak } else { 0.0 })])
            },
        );
        save(format!("{robot}-warped-{side}.png"), image.into())?;
    }
    save(
        format!("{robot}-1-luminance.png"),
        strip(&normalized(&output.luminance)).into(),
    )?;
    save(
        format!("{robot}-2-analog.png"),
        strip(&normalized(&output.analog)).into(),
    )?;
    let top = ((1u32 << bits) - 1) as f64;
    for (kind, values) in &output.filtered {
        save(
            format!("{robot}-3-filtered-{}.png", kind.name()),
            strip(&signed(values)).into(),
        )?;
    }
    for (kind, values) in &output.digital {
        let scaled: Vec<f64> = values.iter().map(|&d| d as f64 / top).collect();
        save(
            format!("{robot}-4-digital-{}.png", kind.name()),
            strip(&scaled).into(),
        )?;
    }
    Ok(written)
}
