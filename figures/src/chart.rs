//! The general chart: named series of lines, markers or bands over linear or log axes, with
//! axis titles (units in brackets), a legend, and ticks that read as plain numbers. Benchmarks
//! (time against error, cost against population) and fitness curves are charts.

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, house_axes, number, polyline};

/// One axis: its title (with the unit, e.g. "time per update (µs)"), scale and range.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub label: String,
    pub log: bool,
    /// The range shown; `None` fits the data (log axes to whole decades).
    pub range: Option<(f64, f64)>,
}

impl Axis {
    pub fn linear(label: impl Into<String>) -> Axis {
        Axis {
            label: label.into(),
            log: false,
            range: None,
        }
    }

    pub fn log(label: impl Into<String>) -> Axis {
        Axis {
            log: true,
            ..Axis::linear(label)
        }
    }

    /// Shows `low..high` whatever the data.
    pub fn range(mut self, low: f64, high: f64) -> Axis {
        self.range = Some((low, high));
        self
    }

    /// The range to show for `values`.
    pub(crate) fn fitted(&self, values: impl Iterator<Item = f64>) -> (f64, f64) {
        if let Some(range) = self.range {
            return range;
        }
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && (!self.log || *v > 0.0)) {
            low = low.min(v);
            high = high.max(v);
        }
        if !low.is_finite() {
            return if self.log { (1.0, 10.0) } else { (0.0, 1.0) };
        }
        if self.log {
            let low = 10f64.powf(low.log10().floor());
            let high = 10f64.powf(high.log10().ceil());
            (low, if high > low { high } else { low * 10.0 })
        } else {
            let pad = if high > low {
                (high - low) * 0.05
            } else {
                low.abs().max(1.0) * 0.5
            };
            (low - pad, high + pad)
        }
    }
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    Line,
    Markers,
    LineMarkers,
    /// A shaded band between `points`' y and `upper` (for spreads: min–max, mean ± sd).
    Band,
}

/// One named series.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// For [`SeriesStyle::Band`]: the upper edge at each point's x.
    pub upper: Vec<f64>,
    pub style: SeriesStyle,
    /// `None` takes the palette's colour for the series' position.
    pub color: Option<RGBColor>,
    /// Marker radius in pixels; one per point when given (benchmarks size dots by samples).
    pub marker_sizes: Vec<u32>,
}

impl Series {
    fn new(name: impl Into<String>, points: Vec<(f64, f64)>, style: SeriesStyle) -> Series {
        Series {
            name: name.into(),
            points,
            upper: Vec::new(),
            style,
            color: None,
            marker_sizes: Vec::new(),
        }
    }

    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series::new(name, points, SeriesStyle::Line)
    }

    pub fn markers(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series::new(name, points, SeriesStyle::Markers)
    }

    pub fn line_markers(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series::new(name, points, SeriesStyle::LineMarkers)
    }

    /// A band from (x, low, high) triples.
    pub fn band(name: impl Into<String>, points: Vec<(f64, f64, f64)>) -> Series {
        let mut series = Series::new(
            name,
            points.iter().map(|&(x, low, _)| (x, low)).collect(),
            SeriesStyle::Band,
        );
        series.upper = points.iter().map(|&(_, _, high)| high).collect();
        series
    }

    pub fn color(mut self, color: RGBColor) -> Series {
        self.color = Some(color);
        self
    }

    /// One marker radius per point.
    pub fn marker_sizes(mut self, sizes: Vec<u32>) -> Series {
        self.marker_sizes = sizes;
        self
    }
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Corner {
    UpperLeft,
    #[default]
    UpperRight,
    LowerLeft,
    LowerRight,
}

/// A chart of series over two axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    pub legend: Corner,
    pub size: (u32, u32),
}

impl Chart {
    pub fn new(title: impl Into<String>, x: Axis, y: Axis) -> Chart {
        Chart {
            title: title.into(),
            x,
            y,
            series: Vec::new(),
            legend: Corner::default(),
            size: (1200, 800),
        }
    }

    /// Adds a series.
    pub fn with(mut self, series: Series) -> Chart {
        self.series.push(series);
        self
    }

    pub fn legend(mut self, corner: Corner) -> Chart {
        self.legend = corner;
        self
    }

    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0));
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1).chain(s.upper.iter().copied()));
        (self.x.fitted(xs), self.y.fitted(ys))
    }
}

impl Figure for Chart {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        rasters: &mut Rasters,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let ((x0, x1), (y0, y1)) = self.ranges();
        match (self.x.log, self.y.log) {
            (false, false) => draw_chart(self, root, x0..x1, y0..y1, rasters),
            (true, false) => draw_chart(self, root, (x0..x1).log_scale(), y0..y1, rasters),
            (false, true) => draw_chart(self, root, x0..x1, (y0..y1).log_scale(), rasters),
            (true, true) => draw_chart(
                self,
                root,
                (x0..x1).log_scale(),
                (y0..y1).log_scale(),
                rasters,
            ),
        }
    }
}

/// The chart on any pair of axis kinds.
fn draw_chart<DB, X, Y>(
    chart: &Chart,
    root: &DrawingArea<DB, Shift>,
    x: X,
    y: Y,
    rasters: &Rasters,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut context = ChartBuilder::on(root)
        .caption(&chart.title, ("sans-serif", style::TITLE).into_font())
        .margin(24)
        // Room for the last tick label, centred on the right edge of the plot.
        .margin_right(48)
        .x_label_area_size(90)
        .y_label_area_size(120)
        .build_cartesian_2d(x, y)?;
    configure_axes(
        &mut context,
        &chart.x.label,
        &chart.y.label,
        chart.x.log,
        chart.y.log,
    )?;
    draw_series(&mut context, &chart.series, rasters)?;
    if chart.series.iter().any(|s| !s.name.is_empty()) {
        legend(&mut context, chart.legend)?;
    }
    Ok(())
}

/// Grid, axes, tick labels and axis titles in the house style.
pub(crate) fn configure_axes<DB, X, Y>(
    context: &mut ChartContext<DB, Cartesian2d<X, Y>>,
    x_label: &str,
    y_label: &str,
    x_log: bool,
    y_log: bool,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let format = |log: bool| {
        move |v: &f64| {
            if log && !is_decade(*v) {
                String::new()
            } else {
                number(*v)
            }
        }
    };
    let x_format = format(x_log);
    let y_format = format(y_log);
    house_axes(&mut context.configure_mesh())
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&x_format)
        .y_label_formatter(&y_format)
        .x_labels(8)
        .y_labels(8)
        .draw()?;
    Ok(())
}

/// Whether `v` is a power of ten (log axes label decades only).
fn is_decade(v: f64) -> bool {
    v > 0.0 && (v.log10() - v.log10().round()).abs() < 1e-9
}

pub(crate) fn draw_series<'a, DB, X, Y>(
    context: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    series: &[Series],
    rasters: &Rasters,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    // Bands first, so that lines stay on top of them.
    let order = series
        .iter()
        .enumerate()
        .filter(|(_, s)| s.style == SeriesStyle::Band)
        .chain(
            series
                .iter()
                .enumerate()
                .filter(|(_, s)| s.style != SeriesStyle::Band),
        );
    for (index, s) in order {
        let color = s.color.unwrap_or_else(|| style::color(index));
        let finite: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let legend_style = s.style;
        match s.style {
            SeriesStyle::Band => {
                let mut outline: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .zip(&s.upper)
                    .map(|(&(x, _), &high)| (x, high))
                    .collect();
                outline.extend(s.points.iter().rev().copied());
                context.draw_series(std::iter::once(Polygon::new(
                    outline,
                    color.mix(0.25).filled(),
                )))?;
            }
            SeriesStyle::Line => {
                polyline(context, finite, color.stroke_width(style::LINE), rasters)?;
            }
            SeriesStyle::Markers | SeriesStyle::LineMarkers => {
                if s.style == SeriesStyle::LineMarkers {
                    polyline(context, finite, color.stroke_width(style::LINE), rasters)?;
                }
                context.draw_series(s.points.iter().enumerate().map(|(i, &p)| {
                    let radius = s.marker_sizes.get(i).copied().unwrap_or(7) as i32;
                    Circle::new(p, radius, color.filled())
                }))?;
            }
        }
        // The legend entry hangs on an empty series.
        let drawn = context.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?;
        if !s.name.is_empty() {
            drawn
                .label(&s.name)
                .legend(move |at| legend_mark(legend_style, color, at));
        }
    }
    Ok(())
}

/// The legend's sample of a series: a line, a dot, both, or a shaded box, in a 30-pixel slot.
/// (One element type for every kind; the parts a kind does not show are transparent.)
pub(crate) fn legend_mark<'a, DB: DrawingBackend + 'a>(
    kind: SeriesStyle,
    color: RGBColor,
    at: (i32, i32),
) -> impl IntoDynElement<'a, DB, (i32, i32)> {
    let (line, dot, shade) = match kind {
        SeriesStyle::Line => (1.0, 0.0, 0.0),
        SeriesStyle::Markers => (0.0, 1.0, 0.0),
        SeriesStyle::LineMarkers => (1.0, 1.0, 0.0),
        SeriesStyle::Band => (0.0, 0.0, 0.25),
    };
    EmptyElement::at(at)
        + Rectangle::new([(0, -9), (30, 9)], color.mix(shade).filled())
        + PathElement::new(
            vec![(0, 0), (30, 0)],
            color.mix(line).stroke_width(style::LINE),
        )
        + Circle::new((15, 0), 7, color.mix(dot).filled())
}

/// The legend box in the house style.
pub(crate) fn legend<'a, DB, X, Y>(
    context: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    corner: Corner,
) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    context
        .configure_series_labels()
        .position(match corner {
            Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
            Corner::UpperRight => SeriesLabelPosition::UpperRight,
            Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
            Corner::LowerRight => SeriesLabelPosition::LowerRight,
        })
        .legend_area_size(40)
        .margin(16)
        .background_style(WHITE.mix(0.85))
        .border_style(style::INK.stroke_width(1))
        .label_font(("sans-serif", style::TICK).into_font().color(&style::INK))
        .draw()?;
    Ok(())
}
