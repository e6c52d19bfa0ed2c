//! A heat map: a table of numbers as coloured cells (rows × columns, e.g. controllers ×
//! conditions → fitness), each cell with its value written in it, so that the figure reads
//! as the table it is. A table too wide for the page (sixty conditions, three controllers) is
//! turned, its columns running down the page in compact rows, so that every name and value
//! still has room.

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
/// Rows of a long table (more than [`FEW_ROWS`]) are this tall, their text smaller.
const COMPACT_CELL_HEIGHT: u32 = 40;
const FEW_ROWS: usize = 8;
const TITLE_HEIGHT: u32 = 70;
const HEADER_HEIGHT: u32 = 80;
const FOOTER_HEIGHT: u32 = 60;
const LEFT: u32 = 330;
/// The room for row names when the table is turned (condition names are long).
const TURNED_LEFT: u32 = 460;
const WIDTH: u32 = 1200;
/// The margin right of the cells.
const RIGHT: u32 = 30;
/// Narrower columns than this cannot hold their names or values: a table with more columns
/// than rows is then turned, its columns running down the page.
const MIN_CELL_WIDTH: u32 = 70;

/// Where a heat map's cells go: the table as given, or turned (rows and columns swapped).
struct Layout<'m> {
    rows: &'m [String],
    columns: &'m [String],
    turned: bool,
    cell_height: u32,
    left: u32,
    /// Characters a row name keeps.
    row_chars: usize,
    /// Text size of row names and cell values.
    text: u32,
}

impl Layout<'_> {
    fn cell_width(&self) -> u32 {
        cell_width(self.left, self.columns.len())
    }
}

/// The width of each of `columns` cells right of a margin of `left` pixels.
fn cell_width(left: u32, columns: usize) -> u32 {
    (WIDTH - left - RIGHT) / columns.max(1) as u32
}

impl HeatMap {
    /// The layout: turned when the columns are too many for the page's width and outnumber
    /// the rows (a transfer grid of many conditions and a few controllers).
    fn layout(&self) -> Layout<'_> {
        let turned = cell_width(LEFT, self.columns.len()) < MIN_CELL_WIDTH
            && self.columns.len() > self.rows.len();
        let (rows, columns) = if turned {
            (&self.columns, &self.rows)
        } else {
            (&self.rows, &self.columns)
        };
        let many = rows.len() > FEW_ROWS;
        Layout {
            rows,
            columns,
            turned,
            cell_height: if many {
                COMPACT_CELL_HEIGHT
            } else {
                CELL_HEIGHT
            },
            left: if turned { TURNED_LEFT } else { LEFT },
            row_chars: if turned { 34 } else { 20 },
            text: if many { style::TICK - 8 } else { style::TICK },
        }
    }

    /// The value at (row, column) of the layout.
    fn value(&self, layout: &Layout, row: usize, column: usize) -> Option<f64> {
        let (r, c) = if layout.turned {
            (column, row)
        } else {
            (row, column)
        };
        self.values
            .get(r)
            .and_then(|values| values.get(c))
            .copied()
            .flatten()
    }

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

/// A label in at most two lines of about `chars` characters, cut where it is longer. A word
/// too long for a line breaks after its underscores (world names such as
/// `regatta_evolved_transfer`).
fn wrapped(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        let pieces: Vec<&str> = if word.chars().count() > chars {
            word.split_inclusive('_').collect()
        } else {
            vec![word]
        };
        for (k, piece) in pieces.into_iter().enumerate() {
            let glue = if k == 0 { " " } else { "" };
            let full = lines.len() == 2;
            match lines.last_mut() {
                Some(line)
                    if full
                        || line.chars().count() + glue.len() + piece.chars().count() <= chars =>
                {
                    line.push_str(glue);
                    line.push_str(piece);
                }
                _ => lines.push(piece.to_owned()),
            }
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
        let layout = self.layout();
        let rows = layout.rows.len().max(1) as u32;
        (
            WIDTH,
            TITLE_HEIGHT + HEADER_HEIGHT + rows * layout.cell_height + FOOTER_HEIGHT,
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
        let layout = self.layout();
        let (left, cell_height) = (layout.left, layout.cell_height);
        let cell_width = layout.cell_width();
        let top = (TITLE_HEIGHT + HEADER_HEIGHT) as i32;
        // Column names over the cells, on two lines where columns are narrow (about 12
        // pixels a character at this size).
        let size = style::TICK - 4;
        let chars = (cell_width / 12).max(4) as usize;
        for (c, name) in layout.columns.iter().enumerate() {
            let x = left as i32 + (c as u32 * cell_width + cell_width / 2) as i32;
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
        for (r, name) in layout.rows.iter().enumerate() {
            let y = top + (r as u32 * cell_height) as i32;
            root.draw(&Text::new(
                shortened(name, layout.row_chars),
                (left as i32 - 16, y + cell_height as i32 / 2),
                font(layout.text).pos(Pos::new(HPos::Right, VPos::Center)),
            ))?;
            for c in 0..layout.columns.len() {
                let x = left as i32 + (c as u32 * cell_width) as i32;
                let value = self.value(&layout, r, c);
                let fill = match value {
                    Some(v) => {
                        ViridisRGB.get_color(((v - low) / (high - low)).clamp(0.0, 1.0) as f32)
                    }
                    None => style::GRID,
                };
                let corners = [(x, y), (x + cell_width as i32, y + cell_height as i32)];
                root.draw(&Rectangle::new(corners, fill.filled()))?;
                root.draw(&Rectangle::new(corners, WHITE.stroke_width(2)))?;
                if let Some(v) = value {
                    // Dark text on the light end of the scale, white on the dark end.
                    let luminance =
                        0.2126 * fill.0 as f64 + 0.7152 * fill.1 as f64 + 0.0722 * fill.2 as f64;
                    let ink = if luminance > 140.0 { style::INK } else { WHITE };
                    root.draw(&Text::new(
                        number_in_cell(v),
                        (x + cell_width as i32 / 2, y + cell_height as i32 / 2),
                        ("sans-serif", layout.text)
                            .into_font()
                            .color(&ink)
                            .pos(centred),
                    ))?;
                }
            }
        }
        let bottom = top + (layout.rows.len() as u32 * cell_height) as i32;
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
        assert!(!map.layout().turned, "three columns fit across the page");
    }

    #[test]
    fn long_names_break_after_underscores() {
        assert_eq!(
            wrapped("regatta_evolved_transfer", 19),
            ["regatta_evolved_", "transfer"]
        );
        assert_eq!(wrapped("dim 0.02", 19), ["dim 0.02"]);
        assert_eq!(
            wrapped("aa bb cc", 2),
            ["aa", "b…"],
            "two lines at most, cut"
        );
    }

    #[test]
    fn a_wide_table_is_turned_and_keeps_its_names_and_values() {
        let conditions: Vec<String> = (0..60)
            .map(|k| format!("layout {} lamps lit no film", k))
            .collect();
        let map = HeatMap {
            title: "transfer".into(),
            value_label: "mean fitness".into(),
            rows: vec!["hand-tuned".into(), "varied".into(), "transfer".into()],
            values: (0..3)
                .map(|r| (0..60).map(|c| Some((r * 100 + c) as f64)).collect())
                .collect(),
            columns: conditions,
        };
        let layout = map.layout();
        assert!(layout.turned);
        assert_eq!(layout.rows.len(), 60);
        assert_eq!(
            map.value(&layout, 59, 2),
            Some(259.0),
            "row 59 is condition 59"
        );
        let svg = crate::render_svg(&map).expect("draws");
        for text in ["layout 59 lamps lit no film", "transfer", "259", "0.00"] {
            assert!(svg.contains(text), "{text} missing");
        }
        let png = crate::render_png(&map).expect("draws");
        assert_eq!(
            (png.width(), png.height()),
            (
                WIDTH,
                TITLE_HEIGHT + HEADER_HEIGHT + 60 * COMPACT_CELL_HEIGHT + FOOTER_HEIGHT
            )
        );
    }
}
