//! `regatta plot`: a log's figures, drawn by `regatta-figures`: the top view of the run, a
//! kymograph per robot and retina filter, and with `--series` each robot's sensors, wheels,
//! visits and contacts over time. PNG by default, SVG with `--format svg`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_figures::{
    average_rows, Buoy, ColorScale, ContactMark, Format, Kymograph, Mark, Obstacle, Outline, Panel,
    TimeSeries, TopView, Trace, Track,
};
use regatta_runtime::compile::rig::TurretRig;
use regatta_runtime::geometry::Footprint;
use regatta_runtime::log::{robot_tokens, CdrReader, LogContents, ShortMessage};
use regatta_runtime::retina::FilterKind;
use regatta_runtime::sim::world2d::Slab;
use regatta_runtime::sim::Visits;

use crate::outcome::Outcome;

/// The file format of figures (`--format`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum FigureFormat {
    #[default]
    Png,
    Svg,
}

impl From<FigureFormat> for Format {
    fn from(format: FigureFormat) -> Format {
        match format {
            FigureFormat::Png => Format::Png,
            FigureFormat::Svg => Format::Svg,
        }
    }
}

/// Writes `figure` as `dir/stem.ext` and prints the path.
pub fn save(
    figure: &impl regatta_figures::Figure,
    dir: &Path,
    stem: &str,
    format: FigureFormat,
) -> anyhow::Result<PathBuf> {
    let format = Format::from(format);
    let path = dir.join(format!("{stem}.{}", format.extension()));
    regatta_figures::save(figure, &path, format)?;
    println!("{}", path.display());
    Ok(path)
}

/// How the top view colours trajectories.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ColorBy {
    /// One colour per robot.
    #[default]
    Robot,
    /// Colour by simulated time, with a colour bar.
    Time,
}

#[derive(clap::Args)]
pub struct PlotArgs {
    /// The log.
    log: PathBuf,
    /// Directory for the figures.
    #[arg(long, default_value = "out/plots")]
    out: PathBuf,
    /// File format of the figures.
    #[arg(long, value_enum, default_value_t)]
    format: FigureFormat,
    /// How the top view colours trajectories: one colour per robot, or by time.
    #[arg(
        long = "trajectory-color",
        alias = "color-by",
        value_enum,
        default_value_t
    )]
    color_by: ColorBy,
    /// Also draw each robot's time series: IR, ambient, wheel speeds, visits and contacts.
    #[arg(long)]
    series: bool,
    /// Kymograph rows at most (longer runs are averaged into this many).
    #[arg(long, default_value_t = 600)]
    rows: usize,
    #[command(flatten)]
    world: crate::world::LogWorldOptions,
}

/// Everything the figures need from one robot's messages.
#[derive(Default)]
struct RobotData {
    /// (t, x, z, heading)
    poses: Vec<(f64, f64, f64, f64)>,
    /// (t, x, z) where a contact began, and (t, count) of contacts begun.
    contacts: Vec<(f64, f64, f64)>,
    contact_counts: Vec<(f64, f64)>,
    /// Per filter (or "analog"): (t, values over the region of interest).
    retina: BTreeMap<String, Vec<(f64, Vec<f64>)>>,
    proximity: Vec<(f64, [u16; 8])>,
    ambient: Vec<(f64, [u16; 8])>,
    /// (t, command left, command right, encoder left, encoder right)
    wheels: Vec<(f64, i32, i32, i32, i32)>,
    /// (t, landmark index)
    visits: Vec<(f64, usize)>,
}

pub fn plot(args: PlotArgs) -> anyhow::Result<Outcome> {
    let contents = crate::logs::load(&args.log)?;
    let compiled = crate::logs::compile_embedded(&contents.run, &args.world.clone().into())?;
    if args.rows == 0 {
        bail!("--rows must be at least 1");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut robots = decode(&contents, &compiled)?;
    // Visits: from the log's visit channels; a log without them (older, or written without
    // `visits`) gets them found as the simulation finds them, entering a visit disc.
    let logged_visits = contents
        .topics
        .iter()
        .any(|t| t.schema == "regatta/msg/Visit");
    for (data, rig) in robots.iter_mut().zip(&compiled.rig.robots) {
        if logged_visits {
            continue;
        }
        let mut inside = vec![false; compiled.landmarks.len()];
        for &(t, x, z, _) in &data.poses {
            for (k, landmark) in compiled.landmarks.iter().enumerate() {
                let d = ((x - landmark.center.x).powi(2) + (z - landmark.center.y).powi(2)).sqrt();
                let now = d <= Visits::disc_radius(landmark.radius, rig.body_radius);
                if now && !inside[k] {
                    data.visits.push((t, k));
                }
                inside[k] = now;
            }
        }
    }
    let end = contents
        .end
        .as_ref()
        .and_then(|e| e.get("time"))
        .and_then(|t| t.parse::<f64>().ok())
        .or_else(|| contents.messages.last().map(|m| m.1 as f64 / 1e9))
        .unwrap_or(0.0);
    let tokens = robot_tokens(compiled.rig.robots.iter().map(|r| r.name.as_str()));
    let world = Path::new(&contents.run.world_name)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| contents.run.world_name.clone());

    // The top view.
    let slab = Slab::new(&compiled.graph, &compiled.rig);
    let mut view = TopView::new(format!(
        "{world}, seed {}: {} s simulated",
        contents.run.seed,
        regatta_figures::number((end * 1000.0).round() / 1000.0)
    ));
    view.obstacles = slab
        .obstacles
        .iter()
        .map(|o| Obstacle {
            outline: match o.shape {
                Footprint::Circle { center, radius } => Outline::Circle {
                    center: (center.x, center.y),
                    radius,
                },
                Footprint::Rect {
                    center,
                    u,
                    v,
                    half_u,
                    half_v,
                } => Outline::Polygon(
                    [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
                        .iter()
                        .map(|&(a, b)| {
                            let p = center + u * (a * half_u) + v * (b * half_v);
                            (p.x, p.y)
                        })
                        .collect(),
                ),
            },
        })
        .collect();
    let body = compiled.rig.robots.first().map_or(0.0, |r| r.body_radius);
    view.buoys = compiled
        .landmarks
        .iter()
        .enumerate()
        .map(|(k, l)| Buoy {
            center: (l.center.x, l.center.y),
            radius: l.radius,
            label: (k + 1).to_string(),
            visit_radius: Some(Visits::disc_radius(l.radius, body)),
        })
        .collect();
    for (index, (data, rig)) in robots.iter().zip(&compiled.rig.robots).enumerate() {
        view.tracks.push(Track {
            name: rig.name.clone(),
            poses: data.poses.clone(),
            body_radius: rig.body_radius,
        });
        view.contacts
            .extend(data.contacts.iter().map(|&(t, x, z)| ContactMark {
                robot: index,
                t,
                at: (x, z),
            }));
    }
    view.color_by_time = args.color_by == ColorBy::Time;
    if view.tracks.iter().all(|t| t.poses.is_empty()) && view.obstacles.is_empty() {
        bail!("the log has neither geometry nor poses to plot");
    }
    save(&view, &args.out, "top", args.format)?;

    // Kymographs: one per robot and retina output.
    for ((data, rig), token) in robots.iter().zip(&compiled.rig.robots).zip(&tokens) {
        let Some(TurretRig::Panoramic(turret)) = &rig.turret else {
            continue;
        };
        let marks: Vec<Mark> = data
            .visits
            .iter()
            .map(|&(t, k)| Mark {
                t,
                label: (k + 1).to_string(),
            })
            .collect();
        let only_one = data.retina.len() == 1;
        for (output, frames) in &data.retina {
            let rows = average_rows(frames, args.rows, (0.0, end));
            let per_row = frames.len() as f64 / rows.len().max(1) as f64;
            let kind = FilterKind::ALL.iter().find(|k| k.name() == output).copied();
            let parameters = match kind {
                Some(FilterKind::Lowpass | FilterKind::Highpass | FilterKind::Odd) => {
                    format!(", λ = {}", turret.lambda)
                }
                Some(FilterKind::Bandpass) => {
                    format!(", λ = {} and {}", turret.bandpass.0, turret.bandpass.1)
                }
                _ => String::new(),
            };
            let averaged = if per_row > 1.0 {
                format!(" (rows: means of {per_row:.1} frames)")
            } else {
                String::new()
            };
            let mut figure = Kymograph::new(
                format!("{}: {output} filter{parameters}{averaged}", rig.name),
                rows,
                (0.0, end),
            );
            let roi = turret.roi;
            let (first, last) = if kind.is_some() {
                (roi.0, roi.1)
            } else {
                (0, 149)
            };
            figure.azimuth = (
                120.0 - 1.6 * first as f64,
                120.0 - 1.6 * (last as f64 + 1.0),
            );
            // The colour scale spans the values that occur (in LSB, so the bar reads as the
            // converter's output), about mid-scale for the signed filters.
            let (low, high) = figure
                .rows
                .iter()
                .flatten()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            match kind {
                Some(kind) => {
                    let top = ((1u64 << turret.bits.min(16)) - 1) as f64;
                    figure.value_label = format!("{output} output, digital (LSB)");
                    match kind {
                        FilterKind::Raw | FilterKind::Lowpass => {
                            figure.scale = ColorScale::Sequential;
                            figure.value_range = if high > low { (low, high) } else { (0.0, top) };
                        }
                        _ => {
                            let center = top / 2.0;
                            let reach = (high - center).abs().max((low - center).abs()).max(1.0);
                            figure.scale = ColorScale::Diverging { center };
                            figure.value_range =
                                ((center - reach).max(0.0), (center + reach).min(top));
                        }
                    }
                }
                None => {
                    figure.title = format!("{}: analog image{averaged}", rig.name);
                    figure.value_range = (0.0, 2.0);
                    figure.value_label = "analog, luminance / mean".into();
                }
            }
            figure.marks = marks.clone();
            let stem = if only_one {
                format!("{token}-kymograph")
            } else {
                format!("{token}-kymograph-{output}")
            };
            save(&figure, &args.out, &stem, args.format)?;
        }
    }

    // Time series.
    if args.series {
        for ((data, rig), token) in robots.iter().zip(&compiled.rig.robots).zip(&tokens) {
            let figure = series(rig, data, end, contents.run.seed);
            save(&figure, &args.out, &format!("{token}-series"), args.format)?;
        }
    }
    Ok(Outcome::Clean)
}

/// A robot's time series: IR, ambient, wheel speeds, cumulative visits and contacts.
fn series(
    rig: &regatta_runtime::compile::rig::RobotRig,
    data: &RobotData,
    end: f64,
    seed: u64,
) -> TimeSeries {
    let eight = |readings: &[(f64, [u16; 8])], name: &str| -> Vec<Trace> {
        (0..8)
            .map(|s| {
                Trace::new(
                    format!("{name} {s}"),
                    readings.iter().map(|(t, v)| (*t, v[s] as f64)).collect(),
                )
            })
            .collect()
    };
    // Speeds from the encoders: pulses per 10 ms over each logged interval.
    let measured = |side: usize| -> Vec<(f64, f64)> {
        data.wheels
            .windows(2)
            .filter(|w| w[1].0 > w[0].0)
            .map(|w| {
                let (a, b) = if side == 0 {
                    (w[0].3, w[1].3)
                } else {
                    (w[0].4, w[1].4)
                };
                (w[1].0, (b - a) as f64 / ((w[1].0 - w[0].0) / 0.01))
            })
            .collect()
    };
    let command = |side: usize| -> Vec<(f64, f64)> {
        data.wheels
            .iter()
            .map(|w| (w.0, if side == 0 { w.1 } else { w.2 } as f64))
            .collect()
    };
    let counted = |times: Vec<f64>| -> Vec<(f64, f64)> {
        let mut points = vec![(0.0, 0.0)];
        points.extend(times.iter().enumerate().map(|(k, &t)| (t, (k + 1) as f64)));
        points
    };
    let palette = regatta_figures::style::color;
    let mut wheel_traces = vec![
        Trace::new("left, command", command(0)).steps(),
        Trace::new("right, command", command(1)).steps(),
        Trace::new("left, encoders", measured(0)),
        Trace::new("right, encoders", measured(1)),
    ];
    for (k, trace) in wheel_traces.iter_mut().enumerate() {
        trace.color = Some(palette(k % 2));
        if k >= 2 {
            trace.color = Some(palette(k % 2 + 4));
        }
    }
    let mut cumulative = vec![
        Trace::new(
            "buoy visits",
            counted(data.visits.iter().map(|v| v.0).collect()),
        )
        .steps(),
        Trace::new(
            "contacts begun",
            counted(data.contacts.iter().map(|c| c.0).collect()),
        )
        .steps(),
    ];
    if data.contact_counts.is_empty() && data.contacts.is_empty() {
        cumulative[1].points.push((end, 0.0));
    }
    TimeSeries::new(
        format!("{}: sensors and wheels (seed {seed})", rig.name),
        (0.0, end),
    )
    .with(Panel::new("IR proximity (0–1023)", eight(&data.proximity, "IR")).range(0.0, 1023.0))
    .with(Panel::new("ambient light (0–1023)", eight(&data.ambient, "ambient")).range(0.0, 1023.0))
    .with(Panel::new("wheel speed (pulses / 10 ms)", wheel_traces))
    .with(Panel::new("cumulative count", cumulative))
}

/// Every robot's data, in the rig's order. Topics are `/{token}/{kind}`, where the token is
/// the robot's sanitised name (its channel's metadata also holds the name itself).
fn decode(
    contents: &LogContents,
    compiled: &regatta_runtime::Compiled,
) -> anyhow::Result<Vec<RobotData>> {
    let tokens = robot_tokens(compiled.rig.robots.iter().map(|r| r.name.as_str()));
    let mut robots: Vec<RobotData> = compiled
        .rig
        .robots
        .iter()
        .map(|_| RobotData::default())
        .collect();
    for (topic, _, data) in &contents.messages {
        let Some((token, kind)) = topic.trim_start_matches('/').split_once('/') else {
            continue;
        };
        let Some(index) = tokens.iter().position(|t| t == token) else {
            continue;
        };
        let robot = &mut robots[index];
        let decoded = (|| -> Result<(), ShortMessage> {
            let mut r = CdrReader::new(data);
            match kind {
                "pose" => {
                    let (t, pose) = regatta_runtime::log::decode_pose(data)?;
                    robot.poses.push((t, pose.x, pose.z, pose.heading));
                }
                "contacts" => {
                    let t = r.f64()?;
                    let touching = r.bool()?;
                    let count = r.u64()?;
                    if touching {
                        let (x, z) = robot.poses.last().map_or((0.0, 0.0), |p| (p.1, p.2));
                        robot.contacts.push((t, x, z));
                    }
                    robot.contact_counts.push((t, count as f64));
                }
                "visits" => {
                    let t = r.f64()?;
                    let buoy = r.u32()? as usize;
                    robot.visits.push((t, buoy.saturating_sub(1)));
                }
                "proximity" | "ambient" => {
                    let t = r.f64()?;
                    let values = r.u16s(Some(8))?;
                    let mut array = [0u16; 8];
                    array.copy_from_slice(&values);
                    if kind == "proximity" {
                        robot.proximity.push((t, array));
                    } else {
                        robot.ambient.push((t, array));
                    }
                }
                "wheels" => {
                    robot
                        .wheels
                        .push((r.f64()?, r.i32()?, r.i32()?, r.i32()?, r.i32()?));
                }
                "retina" => {
                    let t = r.f64()?;
                    r.bool()?;
                    let (first, last) = (r.u16()? as usize, r.u16()? as usize);
                    let analog = r.f32s()?;
                    let filters = r.strings()?;
                    r.f32s()?;
                    let digital = r.u16s(None)?;
                    if filters.is_empty() {
                        robot
                            .retina
                            .entry("analog".into())
                            .or_default()
                            .push((t, analog.iter().map(|&a| a as f64).collect()));
                    }
                    let width = last.saturating_sub(first) + 1;
                    for (k, name) in filters.iter().enumerate() {
                        let values = digital.iter().skip(k * width).take(width);
                        robot
                            .retina
                            .entry(name.clone())
                            .or_default()
                            .push((t, values.map(|&d| d as f64).collect()));
                    }
                }
                _ => {}
            }
            Ok(())
        })();
        decoded.with_context(|| format!("a {topic} message is damaged"))?;
    }
    Ok(robots)
}
