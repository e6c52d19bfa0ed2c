//! What a figure is ([`Figure`]: a size and a way to draw on any plotters backend) and the
//! pixel pictures placed inside one ([`Rasters`]).

use plotters::coord::Shift;
use plotters::prelude::*;

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
    /// For a bitmap: pictures are blitted as they are placed.
    pub(crate) fn for_bitmap() -> Rasters {
        Rasters { svg: None }
    }

    /// For an SVG: pictures are embedded when the document is complete ([`Rasters::embed`]).
    pub(crate) fn for_svg() -> Rasters {
        Rasters {
            svg: Some(Vec::new()),
        }
    }

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
    pub(crate) fn embed(self, mut svg: String) -> String {
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
