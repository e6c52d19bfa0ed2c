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
//! - [`HeatMap`]: a table as coloured cells with their values (the transfer table).
//! - [`TimeSeries`]: stacked panels sharing one time window, long traces summarised per
//!   interval.
//!
//! Text is drawn with DejaVu Sans, embedded from the `dejavu` crate (the Bitstream Vera
//! licence allows embedding and redistribution; it is matplotlib's default face): a fresh
//! machine needs no system font and no fontconfig, and every machine draws the same pixels.

mod chart;
mod figure;
mod heatmap;
mod kymograph;
mod series;
pub mod style;
mod top_view;

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

pub use chart::{Axis, Chart, Corner, Series, SeriesStyle};
pub use figure::{DrawResult, Figure, Rasters};
pub use heatmap::HeatMap;
pub use kymograph::{average_rows, ColorScale, Kymograph, Mark};
pub use series::{summarise, Panel, Summary, TimeSeries, Trace};
pub use style::number;
pub use top_view::{Buoy, ContactMark, FloorImage, Obstacle, Outline, TopView, Track};

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
        let mut rasters = Rasters::for_bitmap();
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
    let mut rasters = Rasters::for_svg();
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
