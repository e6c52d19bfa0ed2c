//! regatta's figures: every picture regatta draws, drawn with `plotters`, as PNG or SVG.
//!
//! A figure is a plain value (data, titles, units) that implements [`Figure`]; [`save`] writes
//! it as PNG (an in-memory bitmap saved through `image`) or SVG (text stays text, so an SVG's
//! axis titles can be read back). This crate knows nothing of worlds or logs: the `regatta`
//! tool turns those into figures.
//!
//! - [`Chart`]: lines, markers and bands on linear or log axes (benchmarks, fitness curves).
//! - [`TopView`]: the arena from above in metres with obstacles, buoys, trajectories, contacts.
//! - [`Kymograph`]: a retina's values over azimuth and time, with a colour bar.
//! - [`TimeSeries`]: stacked panels sharing one time axis.
//!
//! Text is drawn with DejaVu Sans, embedded from the `dejavu` crate (the Bitstream Vera
//! licence allows embedding and redistribution; it is matplotlib's default face): a fresh
//! machine needs no system font and no fontconfig, and every machine draws the same pixels.

mod chart;
mod kymograph;
mod series;
mod top_view;

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

pub use chart::{Axis, Chart, Corner, Series, SeriesStyle};
pub use kymograph::{average_rows, ColorScale, Kymograph, Mark};
pub use series::{envelope, Panel, TimeSeries, Trace};
pub use top_view::{Buoy, ContactMark, Obstacle, Outline, TopView, Track};

/// Re-exported so that callers can name colours without depending on plotters.
pub use plotters::style::RGBColor;

/// The file format a figure is written in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    #[default]
    Png,
    Svg,
}

impl Format {
    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
}

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("cannot draw the figure: {0}")]
    Draw(String),
    #[error("cannot write {path}: {source}")]
    Write {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {source}")]
    Encode {
        path: String,
        #[source]
        source: image::ImageError,
    },
}

/// What drawing code returns: plotters' errors, boxed.
pub type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A picture: its size and how to draw it on any plotters backend.
pub trait Figure {
    /// Width and height in pixels (SVG user units are the same).
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root`, which covers [`Figure::size`]; pictures made of pixels
    /// (a kymograph) go through `rasters`.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        rasters: &mut Rasters,
    ) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Writes `figure` to `path` in `format` (the path is used as given).
pub fn save(figure: &impl Figure, path: &Path, format: Format) -> Result<(), FigureError> {
    let shown = path.display().to_string();
    match format {
        Format::Png => {
            // The best compression: figures are drawn once and kept (in papers, in docs/).
            let picture = render_png(figure)?;
            let file = std::fs::File::create(path).map_err(|source| FigureError::Write {
                path: shown.clone(),
                source,
            })?;
            let encoder = image::codecs::png::PngEncoder::new_with_quality(
                std::io::BufWriter::new(file),
                image::codecs::png::CompressionType::Best,
                image::codecs::png::FilterType::Adaptive,
            );
            picture
                .write_with_encoder(encoder)
                .map_err(|source| match source {
                    image::ImageError::IoError(source) => FigureError::Write {
                        path: shown,
                        source,
                    },
                    source => FigureError::Encode {
                        path: shown,
                        source,
                    },
                })
        }
        Format::Svg => {
            std::fs::write(path, render_svg(figure)?).map_err(|source| FigureError::Write {
                path: shown,
                source,
            })
        }
    }
}

/// Draws `figure` into an RGB image.
pub fn render_png(figure: &impl Figure) -> Result<image::RgbImage, FigureError> {
    register_fonts();
    let (width, height) = figure.size();
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        let mut rasters = Rasters { svg: None };
        draw_on(figure, &root, &mut rasters)?;
    }
    image::RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| FigureError::Draw("the bitmap has the wrong size".into()))
}

/// Draws `figure` as an SVG document.
pub fn render_svg(figure: &impl Figure) -> Result<String, FigureError> {
    register_fonts();
    let (width, height) = figure.size();
    let mut text = String::new();
    let mut rasters = Rasters {
        svg: Some(Vec::new()),
    };
    {
        let root = SVGBackend::with_string(&mut text, (width, height)).into_drawing_area();
        draw_on(figure, &root, &mut rasters)?;
    }
    Ok(rasters.embed(text))
}

fn draw_on<DB: DrawingBackend>(
    figure: &impl Figure,
    root: &DrawingArea<DB, Shift>,
    rasters: &mut Rasters,
) -> Result<(), FigureError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)
        .map_err(|e| FigureError::Draw(e.to_string()))?;
    figure
        .draw(root, rasters)
        .map_err(|e| FigureError::Draw(e.to_string()))?;
    root.present().map_err(|e| FigureError::Draw(e.to_string()))
}

/// Pixel pictures inside a figure. A bitmap is scaled (nearest neighbour, so that each value
/// stays a sharp block) and blitted; an SVG gets the picture at its own resolution as an
/// embedded PNG, which a viewer scales without smoothing.
pub struct Rasters {
    /// For SVG: the pictures placed so far.
    svg: Option<Vec<Placed>>,
}

/// A picture placed in an SVG: the marker text that stands in for it until the document is
/// complete, its rectangle (x, y, width, height), and the picture.
struct Placed {
    marker: String,
    rectangle: (i32, i32, u32, u32),
    picture: image::RgbImage,
}

impl Rasters {
    /// Places `picture` over the backend rectangle from `top_left`, `size` pixels large.
    pub fn place<DB: DrawingBackend>(
        &mut self,
        root: &DrawingArea<DB, Shift>,
        top_left: (i32, i32),
        size: (u32, u32),
        picture: &image::RgbImage,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        if size.0 == 0 || size.1 == 0 || picture.width() == 0 || picture.height() == 0 {
            return Ok(());
        }
        let (ox, oy) = root.get_base_pixel();
        let local = (top_left.0 - ox, top_left.1 - oy);
        match &mut self.svg {
            None => {
                let scaled = image::imageops::resize(
                    picture,
                    size.0,
                    size.1,
                    image::imageops::FilterType::Nearest,
                );
                let element = BitMapElement::with_owned_buffer(local, size, scaled.into_raw())
                    .ok_or("a raster has the wrong size")?;
                root.draw(&element)?;
            }
            Some(placed) => {
                let marker = format!("regatta-raster-{}", placed.len());
                root.draw(&Text::new(marker.clone(), local, ("sans-serif", 1)))?;
                placed.push(Placed {
                    marker,
                    rectangle: (top_left.0, top_left.1, size.0, size.1),
                    picture: picture.clone(),
                });
            }
        }
        Ok(())
    }

    /// Whether the figure is being drawn as SVG.
    pub fn is_svg(&self) -> bool {
        self.svg.is_some()
    }

    /// Replaces each marker's `<text>` element by an `<image>` holding its picture.
    fn embed(self, mut svg: String) -> String {
        use base64::Engine as _;
        for Placed {
            marker,
            rectangle: (x, y, w, h),
            picture,
        } in self.svg.unwrap_or_default()
        {
            let Some(at) = svg.find(&marker) else {
                continue;
            };
            let (Some(start), Some(end)) = (svg[..at].rfind("<text"), svg[at..].find("</text>"))
            else {
                continue;
            };
            let end = at + end + "</text>".len();
            let mut png = Vec::new();
            if picture
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .is_err()
            {
                continue;
            }
            let data = base64::engine::general_purpose::STANDARD.encode(&png);
            let element = format!(
                "<image x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\" href=\"data:image/png;base64,{data}\"/>"
            );
            svg.replace_range(start..end, &element);
        }
        svg
    }
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
    mesh.axis_desc_style(("sans-serif", style::LABEL).into_font().color(&style::INK))
        .label_style(("sans-serif", style::TICK).into_font().color(&style::INK))
        .light_line_style(style::GRID.mix(0.45))
        .bold_line_style(style::GRID)
        .axis_style(style::INK.stroke_width(2))
        .set_all_tick_mark_size(8)
}

/// Registers the embedded font once, for every family name plotters may ask for.
fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for family in ["sans-serif", "serif", "monospace"] {
            // The font is valid: `dejavu` ships it, and a test draws text with it.
            let _ =
                plotters::style::register_font(family, FontStyle::Normal, dejavu::sans::regular());
            let _ = plotters::style::register_font(family, FontStyle::Bold, dejavu::sans::bold());
        }
    });
}

/// The house style: sizes in pixels for figures about 1200 pixels wide (a column of print at
/// 300 dpi), and a palette that stays distinct for colour-blind readers (Okabe and Ito).
pub mod style {
    use plotters::style::RGBColor;

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
