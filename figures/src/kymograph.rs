//! A kymograph: one row per time bin, one column per photodiode, coloured by value, with
//! azimuth in degrees across, simulated time in seconds downwards, a colour bar with its unit,
//! and marks (buoy visits) at their times.
//!
//! Rows are means: [`average_rows`] folds any number of frames into at most a given number of
//! equal time bins, so a long run is averaged, never subsampled.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::{ColorMap, DerivedColorMap, ViridisRGB};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, house_axes, number};

/// How values map to colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorScale {
    /// Dark to bright (viridis), for values that only grow (light, lowpass).
    Sequential,
    /// Blue through white to red about `center` (the converter's mid-scale, for signed filters).
    Diverging { center: f64 },
}

/// Something that happened at a time, drawn as a line across the kymograph.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    pub t: f64,
    pub label: String,
}

/// A retina's values over azimuth and time.
#[derive(Clone, Debug, PartialEq)]
pub struct Kymograph {
    pub title: String,
    /// Rows in time order; each row holds one value per photodiode, the first at `azimuth.0`.
    pub rows: Vec<Vec<f64>>,
    /// The time at the top of the first row and at the bottom of the last (s).
    pub time: (f64, f64),
    /// The azimuth (degrees, counter-clockwise from the heading) of the first column's outer
    /// edge and of the last column's: (120, −120) for the EDI retina, whose pixel 0 looks left.
    pub azimuth: (f64, f64),
    /// The colour bar's title, with the unit: "odd filter, digital (LSB)".
    pub value_label: String,
    /// Values mapped to the ends of the colour scale.
    pub value_range: (f64, f64),
    pub scale: ColorScale,
    pub marks: Vec<Mark>,
    pub size: (u32, u32),
}

const COLOR_BAR: u32 = 250;
const TITLE_HEIGHT: u32 = 60;
/// The column right of the picture for marks: ticks and up to two columns of labels.
const MARK_COLUMN: u32 = 100;

impl Kymograph {
    pub fn new(title: impl Into<String>, rows: Vec<Vec<f64>>, time: (f64, f64)) -> Kymograph {
        Kymograph {
            title: title.into(),
            rows,
            time,
            azimuth: (120.0, -120.0),
            value_label: "value".into(),
            value_range: (0.0, 1.0),
            scale: ColorScale::Sequential,
            marks: Vec::new(),
            size: (1200, 1400),
        }
    }

    fn color(&self, value: f64) -> RGBColor {
        let (low, high) = self.value_range;
        let fraction = if high > low {
            ((value - low) / (high - low)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        match self.scale {
            ColorScale::Sequential => ViridisRGB.get_color(fraction as f32),
            ColorScale::Diverging { center } => {
                // Equal distances from the centre get equally strong colours on both sides.
                let half = (center - low).abs().max((high - center).abs()).max(1e-12);
                let f = (0.5 + (value - center) / (2.0 * half)).clamp(0.0, 1.0);
                DerivedColorMap::new(&[
                    RGBColor(33, 102, 172),
                    RGBColor(247, 247, 247),
                    RGBColor(178, 24, 43),
                ])
                .get_color(f as f32)
            }
        }
    }

    /// The rows as a picture, one pixel per value.
    fn picture(&self) -> image::RgbImage {
        let width = self.rows.iter().map(Vec::len).max().unwrap_or(0) as u32;
        let mut picture = image::RgbImage::new(width, self.rows.len() as u32);
        for (y, row) in self.rows.iter().enumerate() {
            for (x, &value) in row.iter().enumerate() {
                let c = self.color(value);
                picture.put_pixel(x as u32, y as u32, image::Rgb([c.0, c.1, c.2]));
            }
        }
        picture
    }
}

/// Folds frames `(t, values)` (in time order) into at most `max_rows` rows of equal time span
/// over `time`; each row is the mean of the frames that fall in it. A bin with no frame repeats
/// the row before it (a sensor slower than the bins). Returns the rows and their time span.
pub fn average_rows(
    frames: &[(f64, Vec<f64>)],
    max_rows: usize,
    time: (f64, f64),
) -> Vec<Vec<f64>> {
    let width = frames.iter().map(|f| f.1.len()).max().unwrap_or(0);
    if frames.is_empty() || width == 0 || max_rows == 0 {
        return Vec::new();
    }
    let rows = frames.len().min(max_rows);
    let span = (time.1 - time.0).max(f64::MIN_POSITIVE);
    let mut sums = vec![vec![0.0; width]; rows];
    let mut counts = vec![0usize; rows];
    for (t, values) in frames {
        let bin = (((t - time.0) / span) * rows as f64).floor();
        let bin = (bin.max(0.0) as usize).min(rows - 1);
        counts[bin] += 1;
        for (sum, v) in sums[bin].iter_mut().zip(values) {
            *sum += v;
        }
    }
    let mut previous: Option<usize> = None;
    for bin in 0..rows {
        if counts[bin] > 0 {
            let n = counts[bin] as f64;
            sums[bin].iter_mut().for_each(|s| *s /= n);
            previous = Some(bin);
        } else if let Some(p) = previous {
            sums[bin] = sums[p].clone();
        }
    }
    sums
}

impl Figure for Kymograph {
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
        let (width, _) = self.size;
        // The title across the whole figure, above the marks' column and the colour bar, in
        // the largest size that fits (a window and the rows' caption make it long).
        let (head, body) = root.split_vertically(TITLE_HEIGHT);
        let mut size = style::TITLE;
        while size > style::TICK - 4
            && head
                .estimate_text_size(&self.title, &("sans-serif", size).into_text_style(&head))
                .is_ok_and(|(w, _)| w + 48 > width)
        {
            size -= 2;
        }
        head.draw(&Text::new(
            self.title.clone(),
            (width as i32 / 2, TITLE_HEIGHT as i32 / 2 + 6),
            ("sans-serif", size)
                .into_font()
                .color(&style::INK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        let (main, bar) = body.split_horizontally(width - COLOR_BAR);
        let (t0, t1) = if self.time.1 > self.time.0 {
            self.time
        } else {
            (self.time.0, self.time.0 + 1.0)
        };
        // Plot coordinates: x is −azimuth (so that +120°, the robot's left, is at the left),
        // y is −t (so that time runs downwards); the tick labels undo both signs.
        let (a0, a1) = (-self.azimuth.0, -self.azimuth.1);
        let mut context = ChartBuilder::on(&main)
            .margin(24)
            .margin_top(40)
            .margin_right(MARK_COLUMN)
            .x_label_area_size(90)
            .y_label_area_size(120)
            .build_cartesian_2d(a0.min(a1)..a0.max(a1), -t1..-t0)?;
        let (xs, ys) = context.plotting_area().get_pixel_range();
        let picture = self.picture();
        rasters.place(
            &main,
            (xs.start, ys.start),
            ((xs.end - xs.start) as u32, (ys.end - ys.start) as u32),
            &picture,
        )?;
        house_axes(&mut context.configure_mesh())
            .disable_mesh()
            .x_desc("azimuth (°, left of heading > 0)")
            .y_desc("simulated time (s)")
            .x_label_formatter(&|v| number(-*v))
            .y_label_formatter(&|v| number(-*v))
            .x_labels(9)
            .y_labels(10)
            .draw()?;
        // Marks: a tick in the column to the right of the picture at each time (over the
        // picture it would hide the data at the last azimuths), and its label beside it. Every
        // tick is labelled: labels closer than a line of text to the one before go to a second
        // column, and shrink (to 14 px) before two would touch in both.
        // Each distinct label gets its own colour, so that ticks read without their labels.
        let mut kinds: Vec<&str> = Vec::new();
        for mark in &self.marks {
            if !kinds.contains(&mark.label.as_str()) {
                kinds.push(&mark.label);
            }
        }
        let shown: Vec<&Mark> = self
            .marks
            .iter()
            .filter(|m| m.t >= t0 && m.t <= t1)
            .collect();
        let times: Vec<i32> = shown
            .iter()
            .map(|m| context.backend_coord(&(0.0, -m.t)).1)
            .collect();
        // Two columns: a label's neighbour in its own column is two marks away.
        let gap = times
            .windows(3)
            .map(|w| (w[2] - w[0]).abs())
            .min()
            .unwrap_or(i32::MAX);
        let size = (gap as f64 * 0.95).clamp(14.0, (style::TICK - 4) as f64) as u32;
        let widest = shown
            .iter()
            .map(|m| m.label.chars().count())
            .max()
            .unwrap_or(1) as i32;
        let column = widest * size as i32 * 2 / 3 + 6;
        let (tick_from, tick_to) = (xs.end + 4, xs.end + 26);
        let mut last_label: [Option<i32>; 2] = [None, None];
        let base = main.get_base_pixel();
        for (mark, &y) in shown.iter().zip(&times) {
            let kind = kinds.iter().position(|k| *k == mark.label).unwrap_or(0);
            let ink = style::color(kind);
            main.draw(&PathElement::new(
                vec![
                    (tick_from - base.0, y - base.1),
                    (tick_to - base.0, y - base.1),
                ],
                ink.stroke_width(3),
            ))?;
            let free = |c: usize| last_label[c].is_none_or(|last| y - last >= size as i32);
            let c = if free(0) {
                0
            } else if free(1) {
                1
            } else if last_label[0] <= last_label[1] {
                0
            } else {
                1
            };
            main.draw(&Text::new(
                mark.label.clone(),
                (tick_to + 6 + c as i32 * column - base.0, y - base.1),
                ("sans-serif", size)
                    .into_font()
                    .color(&ink)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
            last_label[c] = Some(y);
        }
        if !self.marks.is_empty() {
            let font = ("sans-serif", style::TICK - 4)
                .into_font()
                .color(&style::INK);
            main.draw(&Text::new(
                "visits".to_owned(),
                (
                    xs.end + 8 - main.get_base_pixel().0,
                    ys.start - 12 - main.get_base_pixel().1,
                ),
                font.clone().pos(Pos::new(HPos::Left, VPos::Bottom)),
            ))?;
        }
        self.draw_color_bar(
            &bar,
            ys.start - bar.get_base_pixel().1,
            ys.end - bar.get_base_pixel().1,
        )
    }
}

impl Kymograph {
    /// The colour bar, as tall as the plot: a 50-pixel strip, its ticks, and its title.
    fn draw_color_bar<DB: DrawingBackend>(
        &self,
        bar: &DrawingArea<DB, Shift>,
        top: i32,
        bottom: i32,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (width, height) = bar.dim_in_pixel();
        let strip = 50;
        let area = bar.margin(
            top.max(0) as u32,
            (height as i32 - bottom).max(0) as u32,
            10,
            width.saturating_sub(10 + strip),
        );
        let (low, high) = if self.value_range.1 > self.value_range.0 {
            self.value_range
        } else {
            (self.value_range.0, self.value_range.0 + 1.0)
        };
        let mut context = ChartBuilder::on(&area).build_cartesian_2d(0.0..1.0, low..high)?;
        let steps = 128;
        context.draw_series((0..steps).map(|i| {
            let a = low + (high - low) * i as f64 / steps as f64;
            let b = low + (high - low) * (i + 1) as f64 / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], self.color((a + b) / 2.0).filled())
        }))?;
        context.draw_series(std::iter::once(Rectangle::new(
            [(0.0, low), (1.0, high)],
            style::INK.stroke_width(2),
        )))?;
        // Ticks and the title to the right of the strip, in the bar column's coordinates.
        let font = ("sans-serif", style::TICK).into_font().color(&style::INK);
        let base = bar.get_base_pixel();
        let right = 10 + strip as i32;
        for tick in ticks(low, high, 6) {
            let (_, y) = context.backend_coord(&(1.0, tick));
            let y = y - base.1;
            bar.draw(&PathElement::new(
                vec![(right, y), (right + 8, y)],
                style::INK.stroke_width(2),
            ))?;
            bar.draw(&Text::new(
                number(tick),
                (right + 14, y),
                font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
        bar.draw(&Text::new(
            self.value_label.clone(),
            (width as i32 - 40, (top + bottom) / 2),
            ("sans-serif", style::LABEL)
                .into_font()
                .transform(FontTransform::Rotate270)
                .color(&style::INK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        Ok(())
    }
}

/// About `n` round ticks between `low` and `high` (steps of 1, 2 or 5 × a power of ten).
pub(crate) fn ticks(low: f64, high: f64, n: usize) -> Vec<f64> {
    if high.partial_cmp(&low) != Some(std::cmp::Ordering::Greater) || n == 0 {
        return vec![low];
    }
    let raw = (high - low) / n as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * power);
    let first = (low / step).ceil() as i64;
    let last = (high / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_means_of_their_frames() {
        let frames: Vec<(f64, Vec<f64>)> = (0..10).map(|i| (i as f64, vec![i as f64])).collect();
        let rows = average_rows(&frames, 5, (0.0, 10.0));
        assert_eq!(
            rows,
            vec![vec![0.5], vec![2.5], vec![4.5], vec![6.5], vec![8.5]]
        );
        // Fewer frames than rows: one row per frame.
        assert_eq!(average_rows(&frames[..3], 5, (0.0, 3.0)).len(), 3);
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(ticks(0.0, 63.0, 6), vec![0.0, 20.0, 40.0, 60.0]);
        assert_eq!(ticks(-1.0, 1.0, 4), vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
    }
}
