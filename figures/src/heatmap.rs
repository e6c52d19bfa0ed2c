//! A heat map: a table of numbers as coloured cells (rows × columns, e.g. controllers ×
//! conditions → fitness), each cell with its value written in it, so that the figure reads
//! as the table it is.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figure::{DrawResult, Figure, Rasters};
use crate::style::{self, number};

/// Rows × columns of values with their names; `None` is a cell with no value (drawn grey).
#[derive(Clone, Debug, PartialEq)]
pub struct HeatMap {
    pub title: String,
    /// What the values are, with their unit (e.g. "mean fitness").
    pub value_label: String,
    pub rows: Vec<String>,
    pub columns: Vec<String>,
    /// `values[row][column]`.
    pub values: Vec<Vec<Option<f64>>>,
}

const CELL_HEIGHT: u32 = 90;
const TITLE_HEIGHT: u32 = 70;
const HEADER_HEIGHT: u32 = 80;
const FOOTER_HEIGHT: u32 = 60;
const LEFT: u32 = 330;
const WIDTH: u32 = 1200;

impl HeatMap {
    /// The colour scale's ends: the values' range (a little widened when flat).
    fn range(&self) -> (f64, f64) {
        let mut values = self.values.iter().flatten().flatten().copied();
        let first = values.next().unwrap_or(0.0);
        let (low, high) = values.fold((first, first), |(l, h), v| (l.min(v), h.max(v)));
        if high > low {
            (low, high)
        } else {
            (low - 0.5, high + 0.5)
        }
    }
}

/// A label in at most two lines of about `chars` characters, cut where it is longer.
fn wrapped(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        let full = lines.len() == 2;
        match lines.last_mut() {
            Some(line) if full || line.chars().count() + 1 + word.chars().count() <= chars => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_owned()),
        }
    }
    lines.iter().map(|l| shortened(l, chars)).collect()
}

/// A label cut to `chars` characters (an ellipsis marks the cut).
fn shortened(text: &str, chars: usize) -> String {
    if text.chars().count() <= chars {
        text.to_owned()
    } else {
        let kept: String = text.chars().take(chars.saturating_sub(1)).collect();
        format!("{kept}…")
    }
}

impl Figure for HeatMap {
    fn size(&self) -> (u32, u32) {
        let rows = self.rows.len().max(1) as u32;
        (
            WIDTH,
            TITLE_HEIGHT + HEADER_HEIGHT + rows * CELL_HEIGHT + FOOTER_HEIGHT,
        )
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _rasters: &mut Rasters,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let font = |size: u32| ("sans-serif", size).into_font().color(&style::INK);
        let centred = Pos::new(HPos::Center, VPos::Center);
        root.draw(&Text::new(
            self.title.clone(),
            (WIDTH as i32 / 2, TITLE_HEIGHT as i32 / 2),
            font(style::TITLE).pos(centred),
        ))?;
        let columns = self.columns.len().max(1) as u32;
        let cell_width = (WIDTH - LEFT - 30) / columns;
        let top = (TITLE_HEIGHT + HEADER_HEIGHT) as i32;
        // Column names over the cells, on two lines where columns are narrow (about 12
        // pixels a character at this size).
        let size = style::TICK - 4;
        let chars = (cell_width / 12).max(4) as usize;
        for (c, name) in self.columns.iter().enumerate() {
            let x = LEFT as i32 + (c as u32 * cell_width + cell_width / 2) as i32;
            let lines = wrapped(name, chars);
            let step = size as i32 + 4;
            let first = top - 12 - step * (lines.len() as i32 - 1) - step / 2;
            for (i, line) in lines.iter().enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (x, first + step * i as i32),
                    font(size).pos(centred),
                ))?;
            }
        }
        let (low, high) = self.range();
        for (r, name) in self.rows.iter().enumerate() {
            let y = top + (r as u32 * CELL_HEIGHT) as i32;
            root.draw(&Text::new(
                shortened(name, 20),
                (LEFT as i32 - 16, y + CELL_HEIGHT as i32 / 2),
                font(style::TICK).pos(Pos::new(HPos::Right, VPos::Center)),
            ))?;
            for c in 0..self.columns.len() {
                let x = LEFT as i32 + (c as u32 * cell_width) as i32;
                let value = self
                    .values
                    .get(r)
                    .and_then(|row| row.get(c))
                    .copied()
                    .flatten();
                let fill = match value {
                    Some(v) => {
                        ViridisRGB.get_color(((v - low) / (high - low)).clamp(0.0, 1.0) as f32)
                    }
                    None => style::GRID,
                };
                let corners = [(x, y), (x + cell_width as i32, y + CELL_HEIGHT as i32)];
                root.draw(&Rectangle::new(corners, fill.filled()))?;
                root.draw(&Rectangle::new(corners, WHITE.stroke_width(2)))?;
                if let Some(v) = value {
                    // Dark text on the light end of the scale, white on the dark end.
                    let luminance =
                        0.2126 * fill.0 as f64 + 0.7152 * fill.1 as f64 + 0.0722 * fill.2 as f64;
                    let ink = if luminance > 140.0 { style::INK } else { WHITE };
                    root.draw(&Text::new(
                        number_in_cell(v),
                        (x + cell_width as i32 / 2, y + CELL_HEIGHT as i32 / 2),
                        ("sans-serif", style::TICK)
                            .into_font()
                            .color(&ink)
                            .pos(centred),
                    ))?;
                }
            }
        }
        let bottom = top + (self.rows.len() as u32 * CELL_HEIGHT) as i32;
        root.draw(&Text::new(
            format!(
                "{} (colour from {} to {})",
                self.value_label,
                number(low),
                number(high)
            ),
            (WIDTH as i32 / 2, bottom + FOOTER_HEIGHT as i32 / 2),
            font(style::LABEL - 4).pos(centred),
        ))?;
        Ok(())
    }
}

/// A cell's value in three significant digits or so: the table's precision, not the data's.
fn number_in_cell(v: f64) -> String {
    if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_heat_map_draws_every_cell_and_label() {
        let map = HeatMap {
            title: "transfer".into(),
            value_label: "mean fitness".into(),
            rows: vec!["hand-tuned".into(), "evolved".into()],
            columns: vec![
                "dim".into(),
                "bright".into(),
                "a very long condition name".into(),
            ],
            values: vec![
                vec![Some(1.0), Some(12.5), None],
                vec![Some(250.0), Some(0.0), Some(3.0)],
            ],
        };
        let svg = crate::render_svg(&map).expect("draws");
        for text in [
            "hand-tuned",
            "evolved",
            "dim",
            "bright",
            "12.5",
            "250",
            "0.00",
            "mean fitness",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        let png = crate::render_png(&map).expect("draws");
        assert_eq!((png.width(), png.height()), map.size());
    }
}
