//! `regatta plot`: a log's figures, drawn by `regatta-figures`: the top view of the run, a
//! kymograph per robot and retina filter, and with `--series` each robot's sensors, wheels,
//! visits and contacts over time. PNG by default, SVG with `--format svg`. `--from`/`--to`
//! narrow every figure to a window of simulated time.

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

mod floor;

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
        value_name = "BY",
        value_enum,
        default_value_t
    )]
    color_by: ColorBy,
    /// Also draw each robot's time series: IR and ambient light per mirror pair of sensors,
    /// each wheel's encoders and command, visits and contacts. A window with more samples than
    /// the plot has pixels across (a long run) is summarised per interval: the mean as a line,
    /// the minimum to maximum shaded.
    #[arg(long)]
    series: bool,
    /// Kymograph rows at most (longer runs are averaged into this many).
    #[arg(long, default_value_t = 600)]
    rows: usize,
    /// Start of the time window every figure shows (simulated seconds; default: the log's
    /// start). The top view draws the trajectory within it, the kymograph its rows, the series
    /// its time axis.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    from: Option<f64>,
    /// End of the time window (simulated seconds; default: the log's end).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    to: Option<f64>,
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
    let window = window(args.from, args.to, end)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let whole = window == (0.0, end);
    // Said in titles: the window, and of how long a run when it is not the whole.
    let span = |what: &str| {
        let seconds = |t: f64| regatta_figures::number((t * 1000.0).round() / 1000.0);
        if whole {
            format!("{} s {what}", seconds(end))
        } else {
            format!(
                "{}–{} s of {} s {what}",
                seconds(window.0),
                seconds(window.1),
                seconds(end)
            )
        }
    };
    let within = |t: f64| t >= window.0 && t <= window.1;
    let tokens = robot_tokens(compiled.rig.robots.iter().map(|r| r.name.as_str()));
    let world = Path::new(&contents.run.world_name)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| contents.run.world_name.clone());

    // The top view.
    let slab = Slab::new(&compiled.graph, &compiled.rig);
    let mut view = TopView::new(format!(
        "{world}, seed {}: {}",
        contents.run.seed,
        span("simulated")
    ));
    view.floor = floor::floor_image(&compiled);
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
            poses: data.poses.iter().copied().filter(|p| within(p.0)).collect(),
            body_radius: rig.body_radius,
        });
        view.contacts.extend(
            data.contacts
                .iter()
                .filter(|c| within(c.0))
                .map(|&(t, x, z)| ContactMark {
                    robot: index,
                    t,
                    at: (x, z),
                }),
        );
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
            let first = frames.partition_point(|f| f.0 < window.0);
            let last = frames.partition_point(|f| f.0 <= window.1);
            let frames = &frames[first..last.max(first)];
            let rows = average_rows(frames, args.rows, window);
            let per_row = frames.len() as f64 / rows.len().max(1) as f64;
            let kind = FilterKind::ALL.iter().find(|k| k.name() == output).copied();
            let parameters = match kind {
                // λ is a length along the retina, in photodiodes (pixels).
                Some(FilterKind::Lowpass | FilterKind::Highpass | FilterKind::Odd) => {
                    format!(", λ = {} px", turret.lambda)
                }
                Some(FilterKind::Bandpass) => {
                    format!(", λ = {} and {} px", turret.bandpass.0, turret.bandpass.1)
                }
                _ => String::new(),
            };
            // Bins of equal time hold whole frames: a whole number when they all hold the
            // same, else about the mean.
            let averaged = if per_row > 1.0 && per_row.fract() == 0.0 {
                format!(" (rows: means of {per_row} frames)")
            } else if per_row > 1.0 {
                format!(" (rows: means of about {} frames)", per_row.round())
            } else {
                String::new()
            };
            let mut figure = Kymograph::new(
                format!("{}: {output} filter{parameters}{averaged}", rig.name),
                rows,
                window,
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
            let title = format!(
                "{}: sensors and wheels (seed {}), {}",
                rig.name,
                contents.run.seed,
                span("simulated")
            );
            let figure = series(data, title, window, end);
            save(&figure, &args.out, &format!("{token}-series"), args.format)?;
        }
    }
    Ok(Outcome::Clean)
}

/// The time window `--from`/`--to` ask for, checked against the log's span `0..=end`.
fn window(from: Option<f64>, to: Option<f64>, end: f64) -> anyhow::Result<(f64, f64)> {
    let covers = format!(
        "the log covers 0 to {} s of simulated time",
        regatta_figures::number((end * 1000.0).round() / 1000.0)
    );
    for (flag, value) in [("--from", from), ("--to", to)] {
        let Some(value) = value else { continue };
        if !value.is_finite() {
            bail!("{flag} must be a finite number of seconds, found {value}");
        }
        // A thousandth of a millisecond of slack: the end is read back from printed text.
        if value < 0.0 || value > end + 1e-6 {
            bail!("{flag} {value} s is outside the log: {covers}");
        }
    }
    let window = (from.unwrap_or(0.0), to.unwrap_or(end).min(end));
    if window.0 >= window.1 {
        bail!(
            "the window is empty: --from {} s must come before --to {} s ({covers})",
            window.0,
            window.1
        );
    }
    Ok(window)
}

/// The Khepera's IR and ambient sensors in left/right mirror pairs, front to back: (left,
/// right, where). Sensor 0 looks left, 2 and 3 ahead, 5 right, 6 and 7 back.
const PAIRS: [(usize, usize, &str); 4] = [
    (2, 3, "front"),
    (1, 4, "diagonal"),
    (0, 5, "sides"),
    (7, 6, "back"),
];

/// A robot's time series as small multiples: one panel per mirror pair of IR sensors and of
/// ambient sensors (left in blue, right in vermillion), one per wheel (its encoders' speed in
/// colour, the command over it in black), and the cumulative visits and contacts. Long windows
/// are summarised per interval by the figure itself.
fn series(data: &RobotData, title: String, window: (f64, f64), end: f64) -> TimeSeries {
    let palette = regatta_figures::style::color;
    let ink = regatta_figures::style::INK;
    let sensor = |readings: &[(f64, [u16; 8])], s: usize| -> Vec<(f64, f64)> {
        readings.iter().map(|(t, v)| (*t, v[s] as f64)).collect()
    };
    let pairs = |readings: &[(f64, [u16; 8])], name: &str, heading: &str| -> Vec<Panel> {
        PAIRS
            .iter()
            .enumerate()
            .map(|(k, &(left, right, place))| {
                let panel = Panel::new(
                    place,
                    vec![
                        Trace::new(format!("{name} {left}, left"), sensor(readings, left))
                            .color(palette(0)),
                        Trace::new(format!("{name} {right}, right"), sensor(readings, right))
                            .color(palette(1)),
                    ],
                )
                .range(0.0, 1023.0)
                .height(125);
                if k == 0 {
                    panel.heading(heading)
                } else {
                    panel
                }
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
    // The encoders first and wide, the command last and thin: both stay visible where they
    // agree, which is almost everywhere.
    let wheel = |side: usize, name: &str| -> Panel {
        Panel::new(
            name,
            vec![
                Trace::new(format!("{name}, encoders"), measured(side))
                    .color(palette(side))
                    .width(4),
                Trace::new(format!("{name}, command"), command(side))
                    .steps()
                    .color(ink)
                    .width(1)
                    .without_band(),
            ],
        )
        .height(170)
    };
    let counted = |times: Vec<f64>| -> Vec<(f64, f64)> {
        let mut points = vec![(0.0, 0.0)];
        points.extend(times.iter().enumerate().map(|(k, &t)| (t, (k + 1) as f64)));
        points
    };
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
    let mut figure = TimeSeries::new(title, window);
    for panel in pairs(
        &data.proximity,
        "IR",
        "IR proximity (0–1023, higher is nearer), sensor pairs",
    )
    .into_iter()
    .chain(pairs(&data.ambient, "ambient", "ambient light (0–1023)"))
    {
        figure = figure.with(panel);
    }
    figure
        .with(
            wheel(0, "left")
                .heading("wheel speed (pulses / 10 ms): encoders, and the command in black"),
        )
        .with(wheel(1, "right"))
        .with(
            Panel::new("count", cumulative)
                .heading("buoy visits and contacts since the run began")
                .height(150),
        )
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
