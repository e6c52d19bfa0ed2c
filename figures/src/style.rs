//! The house style: sizes in pixels for figures about 1200 pixels wide (a column of print at
//! 300 dpi), and a palette that stays distinct for colour-blind readers (Okabe and Ito).
//!
//! It also holds what every figure draws the same way: the axes, thick polylines, numbers.

use plotters::coord::ranged1d::Ranged;
use plotters::prelude::*;
use plotters::style::RGBColor;

use crate::figure::{DrawResult, Rasters};

/// Titles.
pub const TITLE: u32 = 34;
/// Axis titles.
pub const LABEL: u32 = 30;
/// Tick labels, legends, annotations.
pub const TICK: u32 = 26;
/// Data lines.
pub const LINE: u32 = 3;
/// Ink for axes and text.
pub const INK: RGBColor = RGBColor(30, 30, 30);
/// Grid lines.
pub const GRID: RGBColor = RGBColor(225, 225, 225);

/// Okabe–Ito colours, the most distinct first (yellow, hard to see on white, last).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(240, 228, 66),  // yellow
];

/// The `index`-th colour of the palette (it repeats after eight).
pub fn color(index: usize) -> RGBColor {
    PALETTE[index % PALETTE.len()]
}

/// Draws a polyline through `points` (data coordinates). A bitmap gets one segment per pair
/// of points when the line is thicker than a pixel: plotters' bitmap rasteriser joins thick
/// polylines with unlimited miters, which shoot far out of the plot at every sharp turn of a
/// noisy trace. SVG joins lines itself and gets a single polyline.
pub(crate) fn polyline<DB, X, Y>(
    context: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    points: Vec<(f64, f64)>,
    style: ShapeStyle,
    rasters: &Rasters,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    if rasters.is_svg() || style.stroke_width <= 1 {
        context.draw_series(std::iter::once(PathElement::new(points, style)))?;
    } else {
        context.draw_series(
            points
                .windows(2)
                .filter(|w| w[0] != w[1])
                .map(|w| PathElement::new(vec![w[0], w[1]], style)),
        )?;
    }
    Ok(())
}

/// The house style of a chart's axes: fonts, grid, axis lines, tick marks. Callers add the
/// axis titles, formatters and tick counts.
pub(crate) fn house_axes<'m, 'a, 'b, X, Y, DB>(
    mesh: &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged,
    Y: Ranged,
    DB: DrawingBackend,
{
    mesh.axis_desc_style(("sans-serif", LABEL).into_font().color(&INK))
        .label_style(("sans-serif", TICK).into_font().color(&INK))
        .light_line_style(GRID.mix(0.45))
        .bold_line_style(GRID)
        .axis_style(INK.stroke_width(2))
        .set_all_tick_mark_size(8)
}

/// Readable tick labels: no trailing zeros, "−" for minus, scientific outside 1e-3…1e5, and
/// 0 for the rounding noise of a tick computed near zero (|value| < 1e-10).
pub fn number(value: f64) -> String {
    if value.abs() < 1e-10 {
        return "0".into();
    }
    let magnitude = value.abs();
    let text = if !(1e-3..1e5).contains(&magnitude) {
        let exponent = magnitude.log10().floor() as i32;
        let mantissa = value / 10f64.powi(exponent);
        if (mantissa.abs() - 1.0).abs() < 1e-9 {
            format!("{}1e{exponent}", if value < 0.0 { "-" } else { "" })
        } else {
            format!("{mantissa:.1}e{exponent}")
        }
    } else {
        let mut text = format!("{value:.6}");
        while text.ends_with('0') {
            text.pop();
        }
        if text.ends_with('.') {
            text.pop();
        }
        text
    };
    text.replace('-', "−")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(-5.551115123125783e-17), "0");
        assert_eq!(number(0.25), "0.25");
        assert_eq!(number(-120.0), "−120");
        assert_eq!(number(1e6), "1e6");
        assert_eq!(number(1e-4), "1e−4");
        assert_eq!(number(2.5e6), "2.5e6");
    }
}
