//! Time series: panels stacked over one shared time axis (only the bottom panel labels it),
//! each with its quantity, its traces and a legend beside it; a heading above a group of
//! panels can name their common quantity and unit (small multiples: one panel per pair of
//! sensors rather than eight traces on top of each other).
//!
//! Only the points inside the time window are drawn. When a window holds more points than the
//! plot has pixels across, each trace is summarised per interval of round length ([`summarise`]):
//! its minimum-to-maximum band, shaded, and its mean as the line. A noisy trace then reads as its
//! level and its spread instead of a solid smear, and a spike still shows as the band's top.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::chart::Axis;
use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, house_axes, number, polyline};

/// One trace of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    pub name: String,
    /// (t s, value) in time order.
    pub points: Vec<(f64, f64)>,
    /// `None` takes the palette's colour for the trace's position.
    pub color: Option<RGBColor>,
    /// Drawn as steps (a counter, a command held until the next one).
    pub steps: bool,
    /// Line width in pixels.
    pub width: u32,
    /// Whether a summarised trace shows its minimum-to-maximum band (a reference drawn over
    /// another trace, such as a wheel command over its encoders, shows its mean only, so that
    /// the other's band stays visible).
    pub band: bool,
}

impl Trace {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Trace {
        Trace {
            name: name.into(),
            points,
            color: None,
            steps: false,
            width: 2,
            band: true,
        }
    }

    pub fn steps(mut self) -> Trace {
        self.steps = true;
        self
    }

    pub fn color(mut self, color: RGBColor) -> Trace {
        self.color = Some(color);
        self
    }

    pub fn width(mut self, width: u32) -> Trace {
        self.width = width;
        self
    }

    pub fn without_band(mut self) -> Trace {
        self.band = false;
        self
    }
}

/// One panel: the quantity ("IR proximity (0–1023)", or "sides" under a heading that says
/// the quantity), its traces (drawn in order, so the last is on top), its range.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    pub label: String,
    pub traces: Vec<Trace>,
    /// `None` fits the traces.
    pub range: Option<(f64, f64)>,
    /// A line of text above the panel, across the figure: the quantity and unit of the panels
    /// that follow it.
    pub heading: Option<String>,
    /// The panel's height in pixels; `None` takes the figure's `panel_height`.
    pub height: Option<u32>,
}

impl Panel {
    pub fn new(label: impl Into<String>, traces: Vec<Trace>) -> Panel {
        Panel {
            label: label.into(),
            traces,
            range: None,
            heading: None,
            height: None,
        }
    }

    pub fn range(mut self, low: f64, high: f64) -> Panel {
        self.range = Some((low, high));
        self
    }

    pub fn heading(mut self, heading: impl Into<String>) -> Panel {
        self.heading = Some(heading.into());
        self
    }

    pub fn height(mut self, height: u32) -> Panel {
        self.height = Some(height);
        self
    }
}

/// Panels over a shared time axis.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSeries {
    pub title: String,
    pub panels: Vec<Panel>,
    /// The time window shown (s): points outside it are left out.
    pub time: (f64, f64),
    pub width: u32,
    pub panel_height: u32,
}

const LEGEND_WIDTH: u32 = 280;
const TITLE_HEIGHT: u32 = 70;
/// The line under the title that says how summarised traces read.
const NOTE_HEIGHT: u32 = 34;
const HEADING_HEIGHT: u32 = 44;
const X_AXIS_HEIGHT: u32 = 90;
const Y_AXIS_WIDTH: u32 = 130;
const SIDE_MARGIN: u32 = 24;

impl TimeSeries {
    pub fn new(title: impl Into<String>, time: (f64, f64)) -> TimeSeries {
        TimeSeries {
            title: title.into(),
            panels: Vec::new(),
            time,
            width: 1400,
            panel_height: 300,
        }
    }

    pub fn with(mut self, panel: Panel) -> TimeSeries {
        self.panels.push(panel);
        self
    }

    /// The window, never empty.
    fn window(&self) -> (f64, f64) {
        if self.time.1 > self.time.0 {
            self.time
        } else {
            (self.time.0, self.time.0 + 1.0)
        }
    }

    /// The plot's width in pixels (between the y axis and the legend).
    fn plot_width(&self) -> u32 {
        self.width
            .saturating_sub(LEGEND_WIDTH + Y_AXIS_WIDTH + 2 * SIDE_MARGIN)
            .max(100)
    }

    /// The summary interval (s) when some trace holds more points in the window than the plot
    /// has pixels across; `None` when every trace is drawn point by point.
    pub fn summary_interval(&self) -> Option<f64> {
        let (t0, t1) = self.window();
        let pixels = self.plot_width() as usize;
        let crowded = self
            .panels
            .iter()
            .flat_map(|p| &p.traces)
            .any(|trace| crowded(trace, (t0, t1), pixels));
        // Intervals of about two pixels, rounded up to 1, 2 or 5 × a power of ten seconds.
        crowded.then(|| round_up((t1 - t0) / (pixels as f64 / 2.0)))
    }

    fn panel_height(&self, panel: &Panel) -> u32 {
        panel.height.unwrap_or(self.panel_height)
    }
}

impl Figure for TimeSeries {
    fn size(&self) -> (u32, u32) {
        let panels: u32 = self
            .panels
            .iter()
            .map(|p| {
                self.panel_height(p)
                    + if p.heading.is_some() {
                        HEADING_HEIGHT
                    } else {
                        0
                    }
            })
            .sum();
        (
            self.width,
            TITLE_HEIGHT + NOTE_HEIGHT + X_AXIS_HEIGHT + panels.max(self.panel_height),
        )
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        rasters: &mut Rasters,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (head, root) = root.split_vertically(TITLE_HEIGHT + NOTE_HEIGHT);
        head.draw(&Text::new(
            self.title.clone(),
            (self.width as i32 / 2, TITLE_HEIGHT as i32 / 2),
            ("sans-serif", style::TITLE)
                .into_font()
                .color(&style::INK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        let interval = self.summary_interval();
        let note = match interval {
            Some(step) => format!(
                "each trace per {} s: the line is its mean, the shading its minimum to maximum",
                number(step)
            ),
            None => "every sample drawn".to_owned(),
        };
        head.draw(&Text::new(
            note,
            (
                self.width as i32 / 2,
                TITLE_HEIGHT as i32 + NOTE_HEIGHT as i32 / 2 - 8,
            ),
            ("sans-serif", style::TICK - 2)
                .into_font()
                .color(&style::INK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        let (t0, t1) = self.window();
        let mut rest = root.clone();
        for (index, panel) in self.panels.iter().enumerate() {
            if let Some(heading) = &panel.heading {
                let (strip, below) = rest.split_vertically(HEADING_HEIGHT);
                rest = below;
                strip.draw(&Text::new(
                    heading.clone(),
                    (SIDE_MARGIN as i32, HEADING_HEIGHT as i32 / 2 + 4),
                    ("sans-serif", style::LABEL - 2)
                        .into_font()
                        .style(FontStyle::Bold)
                        .color(&style::INK)
                        .pos(Pos::new(HPos::Left, VPos::Center)),
                ))?;
            }
            let last = index + 1 == self.panels.len();
            let panel_height = self.panel_height(panel);
            let height = panel_height + if last { X_AXIS_HEIGHT } else { 0 };
            let (area, below) = rest.split_vertically(height);
            rest = below;
            let (plot, side) = area.split_horizontally(self.width - LEGEND_WIDTH);
            let shown: Vec<Shown> = panel
                .traces
                .iter()
                .map(|trace| Shown::of(trace, (t0, t1), interval, self.plot_width() as usize))
                .collect();
            let (low, high) = panel.range.unwrap_or_else(|| fit(&shown));
            let mut context = ChartBuilder::on(&plot)
                .margin_left(SIDE_MARGIN)
                .margin_right(SIDE_MARGIN)
                .margin_top(12)
                // A gap under each panel, so that its lowest tick label and the next panel's
                // highest never touch.
                .margin_bottom(if last { 0 } else { 14 })
                .x_label_area_size(if last { X_AXIS_HEIGHT } else { 0 })
                .y_label_area_size(Y_AXIS_WIDTH)
                .build_cartesian_2d(t0..t1, low..high)?;
            let mut mesh = context.configure_mesh();
            // Few tick labels on a short panel, so that they never touch.
            let y_ticks = ((panel_height as usize) / 50).clamp(3, 5);
            house_axes(&mut mesh)
                .y_desc(&panel.label)
                .axis_desc_style(
                    ("sans-serif", style::LABEL - 4)
                        .into_font()
                        .color(&style::INK),
                )
                .x_label_formatter(&|v| number(*v))
                .y_label_formatter(&|v| number(*v))
                .x_labels(10)
                .y_labels(y_ticks);
            if last {
                mesh.x_desc("simulated time (s)");
            }
            mesh.draw()?;
            // Every band first, then every line in order: a line is never under a band.
            for (k, (trace, shown)) in panel.traces.iter().zip(&shown).enumerate() {
                let color = trace.color.unwrap_or_else(|| style::color(k));
                if let (Some(band), true) = (&shown.band, trace.band) {
                    context.draw_series(std::iter::once(Polygon::new(
                        band.clone(),
                        color.mix(0.3).filled(),
                    )))?;
                }
            }
            for (k, (trace, shown)) in panel.traces.iter().zip(&shown).enumerate() {
                let color = trace.color.unwrap_or_else(|| style::color(k));
                polyline(
                    &mut context,
                    shown.line.clone(),
                    color.stroke_width(trace.width),
                    rasters,
                )?;
            }
            // The legend beside the panel, one row per trace.
            let row = style::TICK as i32 + 8;
            let font = ("sans-serif", style::TICK).into_font().color(&style::INK);
            let rows_fit = ((panel_height as i32 - 20) / row).max(1) as usize;
            for (k, trace) in panel.traces.iter().enumerate().take(rows_fit) {
                let color = trace.color.unwrap_or_else(|| style::color(k));
                let y = 24 + row * k as i32;
                side.draw(&PathElement::new(
                    vec![(8, y), (44, y)],
                    color.stroke_width(style::LINE + 1),
                ))?;
                side.draw(&Text::new(
                    trace.name.clone(),
                    (54, y),
                    font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
                ))?;
            }
        }
        Ok(())
    }
}

/// Whether `trace` holds more points in the window than the plot has pixels across (and so
/// is summarised: a trace with fewer, such as a counter, is drawn point by point).
fn crowded(trace: &Trace, (t0, t1): (f64, f64), pixels: usize) -> bool {
    let start = trace.points.partition_point(|p| p.0 < t0);
    let end = trace.points.partition_point(|p| p.0 <= t1);
    end.saturating_sub(start) > pixels
}

/// What is drawn of a trace in a window: its line, and its band when summarised.
struct Shown {
    line: Vec<(f64, f64)>,
    /// The band's outline: maxima forwards, then minima backwards.
    band: Option<Vec<(f64, f64)>>,
}

impl Shown {
    fn of(trace: &Trace, (t0, t1): (f64, f64), interval: Option<f64>, pixels: usize) -> Shown {
        let inside = clip(&trace.points, (t0, t1), trace.steps);
        match interval {
            Some(step) if crowded(trace, (t0, t1), pixels) => {
                let summary = summarise(&inside, (t0, t1), step, trace.steps);
                let mut band: Vec<(f64, f64)> = summary.iter().map(|s| (s.t, s.max)).collect();
                band.extend(summary.iter().rev().map(|s| (s.t, s.min)));
                Shown {
                    line: summary.iter().map(|s| (s.t, s.mean)).collect(),
                    band: Some(band),
                }
            }
            _ => Shown {
                line: if trace.steps {
                    as_steps(&inside, t1)
                } else {
                    inside
                },
                band: None,
            },
        }
    }
}

/// The range that fits every trace as drawn, padded by 5 %.
fn fit(shown: &[Shown]) -> (f64, f64) {
    Axis::linear("").fitted(
        shown
            .iter()
            .flat_map(|s| s.line.iter().chain(s.band.iter().flatten()).map(|p| p.1)),
    )
}

/// One interval of a summarised trace: its middle, and the minimum, mean and maximum of the
/// points in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub t: f64,
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

/// `points` (in time order) summarised per interval of `step` seconds, the intervals aligned
/// on multiples of `step`; intervals without a point are left out. A step trace (a value held
/// until the next) is weighted by how long each value is held, so that its mean is the mean
/// over time.
pub fn summarise(
    points: &[(f64, f64)],
    (t0, t1): (f64, f64),
    step: f64,
    steps: bool,
) -> Vec<Summary> {
    if points.is_empty() || step.is_nan() || step <= 0.0 {
        return Vec::new();
    }
    let first = (t0 / step).floor();
    // A point exactly at the window's end belongs to the last interval, not one of its own.
    let last_bin = ((t1 / step).ceil() - first - 1.0).max(0.0);
    let bin_of = |t: f64| ((t / step).floor() - first).clamp(0.0, last_bin) as usize;
    let mut out: Vec<Summary> = Vec::new();
    let (mut bin, mut sum, mut weight) = (usize::MAX, 0.0, 0.0);
    let flush = |out: &mut Vec<Summary>, sum: f64, weight: f64| {
        if let Some(last) = out.last_mut() {
            last.mean = if weight > 0.0 {
                sum / weight
            } else {
                last.mean
            };
        }
    };
    for (i, &(t, v)) in points.iter().enumerate() {
        let b = bin_of(t);
        if b != bin {
            flush(&mut out, sum, weight);
            bin = b;
            (sum, weight) = (0.0, 0.0);
            let middle = ((first + b as f64 + 0.5) * step).clamp(t0, t1);
            out.push(Summary {
                t: middle,
                min: v,
                mean: v,
                max: v,
            });
        }
        let w = if steps {
            let next = points.get(i + 1).map_or(t1, |p| p.0.min(t1));
            (next.min((first + b as f64 + 1.0) * step) - t).max(0.0)
        } else {
            1.0
        };
        let last = out.last_mut().expect("pushed above");
        last.min = last.min.min(v);
        last.max = last.max.max(v);
        sum += v * w;
        weight += w;
    }
    flush(&mut out, sum, weight);
    out
}

/// The points of `points` inside `(t0, t1)`. A step trace also keeps the value held when the
/// window opens, moved to `t0`; a line is cut where it crosses the window's edges, so that it
/// runs to them and no further.
fn clip(points: &[(f64, f64)], (t0, t1): (f64, f64), steps: bool) -> Vec<(f64, f64)> {
    let start = points.partition_point(|p| p.0 < t0);
    let end = points.partition_point(|p| p.0 <= t1);
    let cut = |a: (f64, f64), b: (f64, f64), t: f64| {
        let f = if b.0 > a.0 {
            (t - a.0) / (b.0 - a.0)
        } else {
            0.0
        };
        (t, a.1 + f * (b.1 - a.1))
    };
    let mut out = Vec::with_capacity(end.saturating_sub(start) + 2);
    if start > 0 && start < points.len() && points[start].0 > t0 {
        let (before, after) = (points[start - 1], points[start]);
        out.push(if steps {
            (t0, before.1)
        } else {
            cut(before, after, t0)
        });
    } else if start > 0 && start == points.len() && steps {
        out.push((t0, points[start - 1].1));
    }
    out.extend_from_slice(&points[start.min(end)..end]);
    if !steps && end > 0 && end < points.len() && points[end - 1].0 < t1 {
        out.push(cut(points[end - 1], points[end], t1));
    }
    out
}

/// The smallest of 1, 2 or 5 × a power of ten that is at least `value`.
fn round_up(value: f64) -> f64 {
    let value = value.max(1e-9);
    let power = 10f64.powf(value.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| *s >= value * (1.0 - 1e-12))
        .unwrap_or(10.0 * power)
}

/// A step line through `points`, the last value held until `end`.
fn as_steps(points: &[(f64, f64)], end: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(points.len() * 2 + 1);
    for (i, &(t, v)) in points.iter().enumerate() {
        if i > 0 {
            out.push((t, points[i - 1].1));
        }
        out.push((t, v));
    }
    if let Some(&(t, v)) = points.last() {
        if end > t {
            out.push((end, v));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_keeps_spikes_and_means() {
        let mut points: Vec<(f64, f64)> = (0..100_000).map(|i| (i as f64 * 0.01, 1.0)).collect();
        points[54_321].1 = 9.0;
        points[77_777].1 = -3.0;
        let summary = summarise(&points, (0.0, 1000.0), 2.0, false);
        assert_eq!(summary.len(), 500);
        assert!(summary.windows(2).all(|w| w[0].t < w[1].t));
        let spike = summary.iter().find(|s| s.max == 9.0).unwrap();
        assert_eq!(spike.t, 543.0);
        assert!(summary.iter().any(|s| s.min == -3.0));
        assert!(summary
            .iter()
            .filter(|s| s.max == 1.0 && s.min == 1.0)
            .all(|s| s.mean == 1.0));
        // A step trace's mean weighs each value by how long it is held.
        let held = summarise(&[(0.0, 0.0), (0.5, 4.0), (1.0, 4.0)], (0.0, 1.0), 1.0, true);
        assert_eq!(held.len(), 1);
        assert_eq!((held[0].min, held[0].mean, held[0].max), (0.0, 2.0, 4.0));
    }

    #[test]
    fn a_window_clips_lines_and_holds_steps() {
        let points = [(0.0, 0.0), (2.0, 2.0), (4.0, 4.0), (6.0, 6.0)];
        assert_eq!(
            clip(&points, (1.0, 5.0), false),
            vec![(1.0, 1.0), (2.0, 2.0), (4.0, 4.0), (5.0, 5.0)]
        );
        assert_eq!(
            clip(&points, (1.0, 5.0), true),
            vec![(1.0, 0.0), (2.0, 2.0), (4.0, 4.0)]
        );
        // A counter whose last change came before the window holds its value through it.
        assert_eq!(clip(&points, (7.0, 9.0), true), vec![(7.0, 6.0)]);
        assert!(clip(&points, (7.0, 9.0), false).is_empty());
        assert_eq!(round_up(1.3), 2.0);
        assert_eq!(round_up(0.13), 0.2);
        assert_eq!(round_up(0.5), 0.5);
    }
}
