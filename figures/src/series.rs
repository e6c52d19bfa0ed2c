//! Time series: panels stacked over one shared time axis (only the bottom panel labels it),
//! each with its quantity and unit, its traces and a legend beside it.
//!
//! Long traces are thinned by [`envelope`] (the minimum and maximum of each of a few thousand
//! time bins), which keeps every spike a reader could see at print resolution.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::chart::Axis;
use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, house_axes, number};

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
}

impl Trace {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Trace {
        Trace {
            name: name.into(),
            points,
            color: None,
            steps: false,
        }
    }

    pub fn steps(mut self) -> Trace {
        self.steps = true;
        self
    }
}

/// One panel: the quantity with its unit ("IR proximity (0–1023)"), its traces, its range.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    pub label: String,
    pub traces: Vec<Trace>,
    /// `None` fits the traces.
    pub range: Option<(f64, f64)>,
}

impl Panel {
    pub fn new(label: impl Into<String>, traces: Vec<Trace>) -> Panel {
        Panel {
            label: label.into(),
            traces,
            range: None,
        }
    }

    pub fn range(mut self, low: f64, high: f64) -> Panel {
        self.range = Some((low, high));
        self
    }
}

/// Panels over a shared time axis.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSeries {
    pub title: String,
    pub panels: Vec<Panel>,
    /// The time axis' span (s).
    pub time: (f64, f64),
    pub width: u32,
    pub panel_height: u32,
}

const LEGEND_WIDTH: u32 = 260;
const TITLE_HEIGHT: u32 = 70;
const X_AXIS_HEIGHT: u32 = 90;
/// Points kept per trace (as minima and maxima of half as many bins).
const KEPT_POINTS: usize = 4000;

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
}

impl Figure for TimeSeries {
    fn size(&self) -> (u32, u32) {
        (
            self.width,
            TITLE_HEIGHT + X_AXIS_HEIGHT + self.panel_height * self.panels.len().max(1) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, _: &mut Rasters) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (head, root) = root.split_vertically(TITLE_HEIGHT);
        head.draw(&Text::new(
            self.title.clone(),
            (self.width as i32 / 2, TITLE_HEIGHT as i32 / 2),
            ("sans-serif", style::TITLE)
                .into_font()
                .color(&style::INK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        let (t0, t1) = if self.time.1 > self.time.0 {
            self.time
        } else {
            (self.time.0, self.time.0 + 1.0)
        };
        let mut rest = root.clone();
        for (index, panel) in self.panels.iter().enumerate() {
            let last = index + 1 == self.panels.len();
            let height = self.panel_height + if last { X_AXIS_HEIGHT } else { 0 };
            let (area, below) = rest.split_vertically(height);
            rest = below;
            let (plot, side) = area.split_horizontally(self.width - LEGEND_WIDTH);
            let (low, high) = panel.range.unwrap_or_else(|| fit(panel));
            let mut context = ChartBuilder::on(&plot)
                .margin_left(24)
                .margin_right(24)
                .margin_top(12)
                .x_label_area_size(if last { X_AXIS_HEIGHT } else { 0 })
                .y_label_area_size(130)
                .build_cartesian_2d(t0..t1, low..high)?;
            let mut mesh = context.configure_mesh();
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
                .y_labels(5);
            if last {
                mesh.x_desc("simulated time (s)");
            }
            mesh.draw()?;
            for (k, trace) in panel.traces.iter().enumerate() {
                let color = trace.color.unwrap_or_else(|| style::color(k));
                let points = envelope(&trace.points, KEPT_POINTS);
                let points = if trace.steps {
                    as_steps(&points, t1)
                } else {
                    points
                };
                context.draw_series(LineSeries::new(points, color.stroke_width(1)))?;
            }
            // The legend beside the panel, one row per trace.
            let row = style::TICK as i32 + 8;
            let font = ("sans-serif", style::TICK).into_font().color(&style::INK);
            let rows_fit = ((self.panel_height as i32 - 24) / row).max(1) as usize;
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

/// The range that fits every trace of `panel`, padded by 5 %.
fn fit(panel: &Panel) -> (f64, f64) {
    Axis::linear("").fitted(
        panel
            .traces
            .iter()
            .flat_map(|t| t.points.iter().map(|p| p.1)),
    )
}

/// At most about `kept` points of `points`: for each of `kept / 2` equal index bins, its
/// minimum and maximum in time order. Shorter inputs come back unchanged.
pub fn envelope(points: &[(f64, f64)], kept: usize) -> Vec<(f64, f64)> {
    let bins = (kept / 2).max(1);
    if points.len() <= kept {
        return points.to_vec();
    }
    let mut out = Vec::with_capacity(2 * bins);
    let per_bin = points.len().div_ceil(bins);
    for chunk in points.chunks(per_bin) {
        let (low, high) = chunk.iter().enumerate().fold((0, 0), |(lo, hi), (i, p)| {
            (
                if p.1 < chunk[lo].1 { i } else { lo },
                if p.1 > chunk[hi].1 { i } else { hi },
            )
        });
        let (first, second) = if low <= high {
            (low, high)
        } else {
            (high, low)
        };
        out.push(chunk[first]);
        if second != first {
            out.push(chunk[second]);
        }
    }
    out
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
    fn the_envelope_keeps_spikes() {
        let mut points: Vec<(f64, f64)> = (0..100_000).map(|i| (i as f64, 0.0)).collect();
        points[54_321].1 = 9.0;
        points[77_777].1 = -3.0;
        let kept = envelope(&points, 1000);
        assert!(kept.len() <= 1000);
        assert!(kept.contains(&(54_321.0, 9.0)));
        assert!(kept.contains(&(77_777.0, -3.0)));
        assert!(kept.windows(2).all(|w| w[0].0 < w[1].0));
    }
}
