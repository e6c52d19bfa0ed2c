//! The arena from above: metre axes at equal scale, the floor's image where it has one,
//! obstacles at their true pose and shape,
//! numbered buoys with their visit discs, each robot's trajectory in its own colour (or
//! coloured by time) with start and end markers, contacts, and a legend beside the plot.
//!
//! World x runs to the right and world z downwards (the view from +y, looking down), so
//! headings turn counter-clockwise on the page as they do in the world.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, house_axes, number, polyline};

/// An obstacle's footprint, in world (x, z) metres.
#[derive(Clone, Debug, PartialEq)]
pub enum Outline {
    Circle {
        center: (f64, f64),
        radius: f64,
    },
    /// Corners in order (a rotated box has four).
    Polygon(Vec<(f64, f64)>),
}

/// Something standing on the floor.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    pub outline: Outline,
}

/// A buoy: drawn over its obstacle with its number, and the disc a robot must enter to visit it.
#[derive(Clone, Debug, PartialEq)]
pub struct Buoy {
    pub center: (f64, f64),
    pub radius: f64,
    pub label: String,
    pub visit_radius: Option<f64>,
}

/// One robot's path: (t s, x m, z m, heading rad) samples in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub name: String,
    pub poses: Vec<(f64, f64, f64, f64)>,
    /// Its body's radius (m): the end marker is drawn at true size.
    pub body_radius: f64,
}

/// Where a contact began.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactMark {
    /// Index into [`TopView::tracks`].
    pub robot: usize,
    pub t: f64,
    pub at: (f64, f64),
}

/// The floor's image seen from above (a line to follow), over the world rectangle
/// `x.0..x.1` by `z.0..z.1`: the picture's first row at `z.0`, its first column at `x.0`.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorImage {
    pub x: (f64, f64),
    pub z: (f64, f64),
    pub picture: image::RgbImage,
}

/// The top view of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct TopView {
    pub title: String,
    /// Drawn under everything else.
    pub floor: Option<FloorImage>,
    pub obstacles: Vec<Obstacle>,
    pub buoys: Vec<Buoy>,
    pub tracks: Vec<Track>,
    pub contacts: Vec<ContactMark>,
    /// Colour trajectories by time (a colour bar in seconds) instead of by robot.
    pub color_by_time: bool,
    /// Width in pixels; the height follows the arena's aspect ratio.
    pub width: u32,
}

const LEGEND_WIDTH: u32 = 300;
const LEFT: u32 = 120;
const BOTTOM: u32 = 90;
const TOP: u32 = 70;
const MARGIN: u32 = 24;
/// Colour bins of a time-coloured path (each bin is one polyline).
const TIME_BINS: usize = 200;

impl TopView {
    pub fn new(title: impl Into<String>) -> TopView {
        TopView {
            title: title.into(),
            floor: None,
            obstacles: Vec::new(),
            buoys: Vec::new(),
            tracks: Vec::new(),
            contacts: Vec::new(),
            color_by_time: false,
            width: 1400,
        }
    }

    /// The world rectangle shown: everything, with a small margin, in x0..x1, z0..z1.
    fn extent(&self) -> (f64, f64, f64, f64) {
        let mut points: Vec<(f64, f64)> = Vec::new();
        if let Some(floor) = &self.floor {
            points.push((floor.x.0, floor.z.0));
            points.push((floor.x.1, floor.z.1));
        }
        for obstacle in &self.obstacles {
            match &obstacle.outline {
                Outline::Circle { center, radius } => {
                    points.push((center.0 - radius, center.1 - radius));
                    points.push((center.0 + radius, center.1 + radius));
                }
                Outline::Polygon(corners) => points.extend(corners),
            }
        }
        for buoy in &self.buoys {
            let r = buoy.visit_radius.unwrap_or(buoy.radius).max(buoy.radius);
            points.push((buoy.center.0 - r, buoy.center.1 - r));
            points.push((buoy.center.0 + r, buoy.center.1 + r));
        }
        for track in &self.tracks {
            for &(_, x, z, _) in &track.poses {
                points.push((x - track.body_radius, z - track.body_radius));
                points.push((x + track.body_radius, z + track.body_radius));
            }
        }
        let finite = points
            .into_iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let (mut x0, mut x1, mut z0, mut z1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for (x, z) in finite {
            x0 = x0.min(x);
            x1 = x1.max(x);
            z0 = z0.min(z);
            z1 = z1.max(z);
        }
        if !x0.is_finite() {
            return (-0.5, 0.5, -0.5, 0.5);
        }
        let pad = 0.04 * (x1 - x0).max(z1 - z0).max(0.05);
        (x0 - pad, x1 + pad, z0 - pad, z1 + pad)
    }

    /// The plot's pixel width, and its height at equal scale.
    fn plot_size(&self) -> (u32, u32) {
        let (x0, x1, z0, z1) = self.extent();
        let width = self
            .width
            .saturating_sub(LEGEND_WIDTH + LEFT + 2 * MARGIN)
            .max(200);
        let height = (width as f64 * (z1 - z0) / (x1 - x0)).round() as u32;
        (width, height.clamp(100, 4 * width))
    }

    /// The time span of every track.
    fn time_span(&self) -> (f64, f64) {
        let times = self.tracks.iter().flat_map(|t| t.poses.iter().map(|p| p.0));
        let (low, high) = times.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
        if low.is_finite() && high > low {
            (low, high)
        } else {
            (0.0, 1.0)
        }
    }
}

impl Figure for TopView {
    fn size(&self) -> (u32, u32) {
        let (_, plot_height) = self.plot_size();
        (self.width, plot_height + TOP + BOTTOM + 2 * MARGIN)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        rasters: &mut Rasters,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (x0, x1, z0, z1) = self.extent();
        let (main, side) = root.split_horizontally(self.width - LEGEND_WIDTH);
        // The plot's y is −z, so that z grows downwards; tick labels say z.
        let mut context = ChartBuilder::on(&main)
            .caption(&self.title, ("sans-serif", style::TITLE).into_font())
            .margin(MARGIN)
            .x_label_area_size(BOTTOM)
            .y_label_area_size(LEFT)
            .build_cartesian_2d(x0..x1, -z1..-z0)?;
        configure_axes_flipped(&mut context)?;
        let page = |(x, z): (f64, f64)| (x, -z);
        if let Some(floor) = &self.floor {
            let (left, top) = context.backend_coord(&page((floor.x.0, floor.z.0)));
            let (right, bottom) = context.backend_coord(&page((floor.x.1, floor.z.1)));
            let size = ((right - left).max(1) as u32, (bottom - top).max(1) as u32);
            rasters.place(&main, (left, top), size, &floor.picture)?;
        }
        // Obstacles.
        let fill = RGBColor(200, 200, 200).filled();
        let edge = RGBColor(90, 90, 90).stroke_width(2);
        for obstacle in &self.obstacles {
            match &obstacle.outline {
                Outline::Circle { center, radius } => {
                    let ring = circle_points(*center, *radius, 72);
                    context.draw_series(std::iter::once(Polygon::new(
                        ring.iter().copied().map(page).collect::<Vec<_>>(),
                        fill,
                    )))?;
                    context.draw_series(std::iter::once(PathElement::new(
                        ring.into_iter().map(page).collect::<Vec<_>>(),
                        edge,
                    )))?;
                }
                Outline::Polygon(corners) => {
                    let mut ring: Vec<(f64, f64)> = corners.iter().copied().map(page).collect();
                    context.draw_series(std::iter::once(Polygon::new(ring.clone(), fill)))?;
                    if let Some(&first) = ring.first() {
                        ring.push(first);
                    }
                    context.draw_series(std::iter::once(PathElement::new(ring, edge)))?;
                }
            }
        }
        // Buoys: visit disc (light, dashed), the buoy in orange, its number beside it.
        let buoy_color = RGBColor(230, 159, 0);
        for buoy in &self.buoys {
            if let Some(r) = buoy.visit_radius {
                let ring: Vec<(f64, f64)> = circle_points(buoy.center, r, 120)
                    .into_iter()
                    .map(page)
                    .collect();
                context.draw_series(DashedLineSeries::new(
                    ring,
                    10,
                    8,
                    buoy_color.mix(0.8).stroke_width(2),
                ))?;
            }
            let ring: Vec<(f64, f64)> = circle_points(buoy.center, buoy.radius, 72)
                .into_iter()
                .map(page)
                .collect();
            context.draw_series(std::iter::once(Polygon::new(
                ring.clone(),
                buoy_color.filled(),
            )))?;
            context.draw_series(std::iter::once(PathElement::new(
                ring,
                style::INK.stroke_width(2),
            )))?;
        }
        // Trajectories.
        let (t0, t1) = self.time_span();
        for (k, track) in self.tracks.iter().enumerate() {
            let color = style::color(k);
            if self.color_by_time {
                let mut run: Vec<(f64, f64)> = Vec::new();
                let mut run_bin = usize::MAX;
                let bin_of = |t: f64| {
                    (((t - t0) / (t1 - t0)) * TIME_BINS as f64).clamp(0.0, TIME_BINS as f64 - 1.0)
                        as usize
                };
                let mut flush = |run: &mut Vec<(f64, f64)>, bin: usize| -> DrawResult {
                    if run.len() >= 2 {
                        let c = time_color((bin as f64 + 0.5) / TIME_BINS as f64);
                        polyline(
                            &mut context,
                            std::mem::take(run),
                            c.stroke_width(style::LINE),
                            rasters,
                        )?;
                    }
                    Ok(())
                };
                for &(t, x, z, _) in &track.poses {
                    let bin = bin_of(t);
                    if bin != run_bin && !run.is_empty() {
                        let last = *run.last().expect("non-empty");
                        flush(&mut run, run_bin)?;
                        run.push(last);
                    }
                    run_bin = bin;
                    run.push(page((x, z)));
                }
                flush(&mut run, run_bin)?;
            } else {
                polyline(
                    &mut context,
                    track
                        .poses
                        .iter()
                        .map(|&(_, x, z, _)| page((x, z)))
                        .collect(),
                    color.stroke_width(style::LINE),
                    rasters,
                )?;
            }
            // Start: an open circle; end: the body at true size with a heading stroke.
            if let Some(&(_, x, z, _)) = track.poses.first() {
                context.draw_series(std::iter::once(Circle::new(
                    page((x, z)),
                    11,
                    color.stroke_width(4),
                )))?;
            }
            if let Some(&(_, x, z, heading)) = track.poses.last() {
                let body = circle_points((x, z), track.body_radius, 48);
                context.draw_series(std::iter::once(Polygon::new(
                    body.into_iter().map(page).collect::<Vec<_>>(),
                    color.filled(),
                )))?;
                // Forward is (cos θ, −sin θ) in (x, z).
                let nose = (
                    x + 1.6 * track.body_radius * heading.cos(),
                    z - 1.6 * track.body_radius * heading.sin(),
                );
                context.draw_series(std::iter::once(PathElement::new(
                    vec![page((x, z)), page(nose)],
                    style::INK.stroke_width(4),
                )))?;
            }
        }
        // Contacts: a cross where each began.
        for contact in &self.contacts {
            let color = if self.color_by_time {
                style::INK
            } else {
                style::color(contact.robot)
            };
            context.draw_series(std::iter::once(Cross::new(
                page(contact.at),
                10,
                color.stroke_width(4),
            )))?;
        }
        // Buoy numbers last, so that no trajectory covers them: outside the buoy, up and to
        // the right, each on an opaque white disc ringed in the buoy's colour.
        let offset = 0.02 * (x1 - x0).max(0.1);
        for buoy in &self.buoys {
            let offset = buoy.radius + offset;
            let label_at = page((buoy.center.0 + offset, buoy.center.1 - offset));
            let radius = style::LABEL as i32 * 2 / 3 + 2;
            context.draw_series(std::iter::once(Circle::new(
                label_at,
                radius,
                WHITE.filled(),
            )))?;
            context.draw_series(std::iter::once(Circle::new(
                label_at,
                radius,
                buoy_color.stroke_width(2),
            )))?;
            context.draw_series(std::iter::once(Text::new(
                buoy.label.clone(),
                label_at,
                ("sans-serif", style::LABEL)
                    .into_font()
                    .style(FontStyle::Bold)
                    .color(&style::INK)
                    .pos(Pos::new(HPos::Center, VPos::Center)),
            )))?;
        }
        self.draw_legend(&side, (t0, t1))
    }
}

impl TopView {
    /// The legend (and the time colour bar) in the column beside the plot.
    fn draw_legend<DB: DrawingBackend>(
        &self,
        side: &DrawingArea<DB, Shift>,
        (t0, t1): (f64, f64),
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let font = ("sans-serif", style::TICK).into_font().color(&style::INK);
        let mut y = (TOP + MARGIN + 10) as i32;
        let row = style::TICK as i32 + 16;
        let text_x = 64;
        let entry = |y: i32, label: &str| -> DrawResult {
            side.draw(&Text::new(
                label.to_owned(),
                (text_x, y),
                font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
            Ok(())
        };
        for (k, track) in self.tracks.iter().enumerate() {
            let color = style::color(k);
            if self.color_by_time {
                side.draw(&Circle::new((30, y), 12, color.filled()))?;
            } else {
                side.draw(&PathElement::new(
                    vec![(10, y), (50, y)],
                    color.stroke_width(style::LINE + 1),
                ))?;
            }
            entry(y, &track.name)?;
            y += row;
        }
        y += row / 2;
        let ink = style::INK;
        side.draw(&Circle::new((30, y), 11, ink.stroke_width(4)))?;
        entry(y, "start")?;
        y += row;
        side.draw(&Circle::new((30, y), 12, ink.filled()))?;
        side.draw(&PathElement::new(
            vec![(30, y), (50, y)],
            WHITE.stroke_width(3),
        ))?;
        entry(y, "end, heading")?;
        y += row;
        if !self.contacts.is_empty() {
            side.draw(&Cross::new((30, y), 10, ink.stroke_width(4)))?;
            entry(y, "contact began")?;
            y += row;
        }
        if !self.buoys.is_empty() {
            side.draw(&Circle::new((30, y), 14, RGBColor(230, 159, 0).filled()))?;
            side.draw(&Text::new(
                "n",
                (30, y),
                ("sans-serif", style::TICK)
                    .into_font()
                    .style(FontStyle::Bold)
                    .color(&ink)
                    .pos(Pos::new(HPos::Center, VPos::Center)),
            ))?;
            entry(y, "buoy n")?;
            y += row;
            if self.buoys.iter().any(|b| b.visit_radius.is_some()) {
                side.draw(&PathElement::new(
                    vec![(10, y), (22, y)],
                    RGBColor(230, 159, 0).stroke_width(2),
                ))?;
                side.draw(&PathElement::new(
                    vec![(38, y), (50, y)],
                    RGBColor(230, 159, 0).stroke_width(2),
                ))?;
                entry(y, "visit disc")?;
                y += row;
            }
        }
        if self.color_by_time {
            // A vertical colour bar for time, with its own axis.
            y += row;
            let (_, height) = side.dim_in_pixel();
            let bottom = (height as i32 - (BOTTOM + MARGIN) as i32).max(y + 120);
            let bar = side.margin(y as u32, (height as i32 - bottom).max(0) as u32, 0, 60);
            let mut context = ChartBuilder::on(&bar)
                .y_label_area_size(110)
                .build_cartesian_2d(0.0..1.0, t0..t1)?;
            let steps = 128;
            context.draw_series((0..steps).map(|i| {
                let a = t0 + (t1 - t0) * i as f64 / steps as f64;
                let b = t0 + (t1 - t0) * (i + 1) as f64 / steps as f64;
                Rectangle::new(
                    [(0.0, a), (1.0, b)],
                    time_color((i as f64 + 0.5) / steps as f64).filled(),
                )
            }))?;
            context
                .configure_mesh()
                .disable_x_mesh()
                .disable_y_mesh()
                .disable_x_axis()
                .y_desc("time (s)")
                .axis_desc_style(("sans-serif", style::LABEL).into_font().color(&style::INK))
                .label_style(("sans-serif", style::TICK).into_font().color(&style::INK))
                .y_label_formatter(&|v| number(*v))
                .y_labels(6)
                .axis_style(style::INK.stroke_width(2))
                .draw()?;
        }
        Ok(())
    }
}

/// Axes of the top view: x as it is, the plot's y (which is −z) labelled as z.
fn configure_axes_flipped<DB: DrawingBackend>(
    context: &mut ChartContext<DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    house_axes(&mut context.configure_mesh())
        .x_desc("x (m)")
        .y_desc("z (m)")
        .x_label_formatter(&|v| number(*v))
        .y_label_formatter(&|v| number(-*v))
        .x_labels(10)
        .y_labels(10)
        .draw()?;
    Ok(())
}

/// The colour of a fraction of the run's time (viridis: dark early, yellow late).
fn time_color(fraction: f64) -> RGBColor {
    ViridisRGB.get_color(fraction.clamp(0.0, 1.0) as f32)
}

/// A closed ring of `n` points around a circle.
fn circle_points(center: (f64, f64), radius: f64, n: usize) -> Vec<(f64, f64)> {
    (0..=n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            (center.0 + radius * a.cos(), center.1 + radius * a.sin())
        })
        .collect()
}
