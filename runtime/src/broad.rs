//! The broad phase: a uniform grid over the floor plane (x, z) that answers "which items may
//! be near this box or this segment" without testing every item. Items are boxes (a
//! footprint's bounds, or a point); each is filed in every cell its box overlaps. Queries
//! return candidates only: callers keep their exact tests, so a grid changes what is tested,
//! never what is found.
//!
//! The grid is rebuilt in O(items + cells) by a counting pass into buffers that are kept,
//! so refreshing it every step allocates nothing once warm. Candidates come back sorted by
//! item index, so callers visit them in the same order as a full scan would. Nothing here
//! knows about robots or scenes.

use glam::DVec2;

/// Fewest cells a grid may have before it coarsens (see [`Grid::reshape`]).
const MIN_CELL_BUDGET: usize = 1024;

/// A uniform grid of square cells over a rectangle; items outside it are filed in the edge
/// cells (still found, only less selectively).
#[derive(Clone, Debug, Default)]
pub struct Grid {
    origin: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
    /// The last column and row, as floating point (what [`Grid::index`] clamps to, kept so
    /// that a query does not convert them again).
    last_column: f64,
    last_row: f64,
    /// `starts[c]..starts[c + 1]` indexes `entries` for cell `c` (row-major).
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// Each item's cell range (first column, first row, last column, last row).
    spans: Vec<[u32; 4]>,
    /// Counting buffer of the rebuild.
    cursor: Vec<u32>,
    /// Every item lies in one cell (points, such as robots' centres): a query meets each
    /// item once without asking where its box starts.
    single_cells: bool,
}

impl Grid {
    /// An empty grid over `[min, max]` with cells of about `cell` (m), for about `items`
    /// items.
    pub fn new(min: DVec2, max: DVec2, cell: f64, items: usize) -> Grid {
        let mut grid = Grid::default();
        grid.reshape(min, max, cell, items);
        grid
    }

    /// Sets the grid's rectangle and cell size (items must be filed again). Cells are
    /// doubled in size until there are at most max(1024, 4 × `items`) of them: memory follows
    /// the items, not the region.
    pub fn reshape(&mut self, min: DVec2, max: DVec2, cell: f64, items: usize) {
        let budget = MIN_CELL_BUDGET.max(items.saturating_mul(4));
        let (min, max) = if min.is_finite() && max.is_finite() && max.cmpge(min).all() {
            (min, max)
        } else {
            (DVec2::ZERO, DVec2::ZERO)
        };
        let extent = (max - min).max(DVec2::splat(1e-9));
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            extent.max_element()
        };
        // Coarsen until the cell count is bounded.
        let count =
            |cell: f64| ((extent.x / cell).ceil().max(1.0)) * ((extent.y / cell).ceil().max(1.0));
        while count(cell) > budget as f64 {
            cell *= 2.0;
        }
        self.origin = min;
        self.inverse_cell = 1.0 / cell;
        self.columns = (extent.x / cell).ceil().max(1.0) as usize;
        self.rows = (extent.y / cell).ceil().max(1.0) as usize;
        self.last_column = (self.columns - 1) as f64;
        self.last_row = (self.rows - 1) as f64;
        self.starts.clear();
        self.starts.resize(self.columns * self.rows + 1, 0);
        self.entries.clear();
        self.spans.clear();
    }

    /// The cell column (or row) of a coordinate, clamped to the grid (`last`: the last column
    /// or row).
    #[inline]
    fn index(&self, value: f64, origin: f64, last: f64) -> u32 {
        let x = (value - origin) * self.inverse_cell;
        // NaN and everything below go to 0, everything beyond to the last. Clamped in floating
        // point first, so that one signed conversion does (an unsigned one costs a dozen
        // instructions on x86-64).
        if x >= 1.0 {
            (if x < last { x } else { last }) as i64 as u32
        } else {
            0
        }
    }

    #[inline]
    fn span(&self, min: DVec2, max: DVec2) -> [u32; 4] {
        [
            self.index(min.x, self.origin.x, self.last_column),
            self.index(min.y, self.origin.y, self.last_row),
            self.index(max.x, self.origin.x, self.last_column),
            self.index(max.y, self.origin.y, self.last_row),
        ]
    }

    /// Files every item anew: `bounds(i)` is item `i`'s box (min, max).
    pub fn rebuild(&mut self, items: usize, mut bounds: impl FnMut(usize) -> (DVec2, DVec2)) {
        self.spans.clear();
        let mut single_cells = true;
        for item in 0..items {
            let (min, max) = bounds(item);
            let span = self.span(min, max);
            single_cells &= span[0] == span[2] && span[1] == span[3];
            self.spans.push(span);
        }
        self.single_cells = single_cells;
        self.file_spans();
    }

    /// Files points anew (`point(i)` is item `i`): [`Grid::rebuild`] with boxes of no size,
    /// one cell each, found in half the arithmetic.
    pub fn rebuild_points(&mut self, items: usize, mut point: impl FnMut(usize) -> DVec2) {
        self.spans.clear();
        for item in 0..items {
            let p = point(item);
            let column = self.index(p.x, self.origin.x, self.last_column);
            let row = self.index(p.y, self.origin.y, self.last_row);
            self.spans.push([column, row, column, row]);
        }
        self.single_cells = true;
        self.file_spans();
    }

    /// Fills the cells' lists from the items' spans.
    fn file_spans(&mut self) {
        let cells = self.columns * self.rows;
        self.starts.clear();
        self.starts.resize(cells + 1, 0);
        let cell_of =
            |span: &[u32; 4], columns: usize| span[1] as usize * columns + span[0] as usize;
        if self.single_cells {
            for span in &self.spans {
                self.starts[cell_of(span, self.columns) + 1] += 1;
            }
        } else {
            for span in &self.spans {
                for row in span[1]..=span[3] {
                    for column in span[0]..=span[2] {
                        self.starts[row as usize * self.columns + column as usize + 1] += 1;
                    }
                }
            }
        }
        for c in 0..cells {
            self.starts[c + 1] += self.starts[c];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.starts[..cells]);
        self.entries.clear();
        self.entries.resize(self.starts[cells] as usize, 0);
        // Items in ascending order: each cell's list is sorted.
        if self.single_cells {
            for (item, span) in self.spans.iter().enumerate() {
                let cell = cell_of(span, self.columns);
                self.entries[self.cursor[cell] as usize] = item as u32;
                self.cursor[cell] += 1;
            }
            return;
        }
        for (item, span) in self.spans.iter().enumerate() {
            for row in span[1]..=span[3] {
                for column in span[0]..=span[2] {
                    let cell = row as usize * self.columns + column as usize;
                    self.entries[self.cursor[cell] as usize] = item as u32;
                    self.cursor[cell] += 1;
                }
            }
        }
    }

    /// The items whose boxes may hold the point `p`, each once, ascending, into `out`:
    /// [`Grid::query`] of a box of no size.
    pub fn query_point(&self, p: DVec2, out: &mut Vec<u32>) {
        out.clear();
        if self.spans.is_empty() {
            return;
        }
        let column = self.index(p.x, self.origin.x, self.last_column) as usize;
        let row = self.index(p.y, self.origin.y, self.last_row) as usize;
        let cell = row * self.columns + column;
        out.extend_from_slice(
            &self.entries[self.starts[cell] as usize..self.starts[cell + 1] as usize],
        );
    }

    /// The items whose boxes may meet the box `[min, max]`, each once, ascending, into `out`.
    pub fn query(&self, min: DVec2, max: DVec2, out: &mut Vec<u32>) {
        self.query_where(min, max, out, |_| true);
    }

    /// [`Grid::query`], keeping only the items for which `keep` holds (asked once per item):
    /// a caller's exact test, run as the cells are read, leaves fewer items to sort.
    #[inline]
    pub fn query_where(
        &self,
        min: DVec2,
        max: DVec2,
        out: &mut Vec<u32>,
        mut keep: impl FnMut(u32) -> bool,
    ) {
        out.clear();
        if self.spans.is_empty() {
            return;
        }
        let [c0, r0, c1, r1] = self.span(min, max);
        let (c0, r0, c1, r1) = (c0 as usize, r0 as usize, c1 as usize, r1 as usize);
        if c0 == c1 && r0 == r1 {
            // One cell: each of its items once, ascending as filed.
            let cell = r0 * self.columns + c0;
            let items = &self.entries[self.starts[cell] as usize..self.starts[cell + 1] as usize];
            out.extend(items.iter().copied().filter(|&item| keep(item)));
            return;
        }
        let mut sorted = true;
        // Exclusive ranges and row slices: the loops are short, so their overhead shows.
        for row in r0..r1 + 1 {
            let base = row * self.columns;
            if self.single_cells {
                // One item per entry: a row's cells are one run of entries, ascending within
                // each cell.
                let items = &self.entries
                    [self.starts[base + c0] as usize..self.starts[base + c1 + 1] as usize];
                for &item in items {
                    if keep(item) {
                        sorted &= out.last().is_none_or(|&last| last < item);
                        out.push(item);
                    }
                }
                continue;
            }
            for column in c0..c1 + 1 {
                let cell = base + column;
                let (start, end) = (self.starts[cell] as usize, self.starts[cell + 1] as usize);
                for &item in &self.entries[start..end] {
                    // An item in several cells is reported from the first of them in range.
                    let span = &self.spans[item as usize];
                    if span[0].max(c0 as u32) as usize == column
                        && span[1].max(r0 as u32) as usize == row
                        && keep(item)
                    {
                        sorted &= out.last().is_none_or(|&last| last < item);
                        out.push(item);
                    }
                }
            }
        }
        if !sorted {
            out.sort_unstable();
        }
    }

    /// The items whose boxes may meet the segment from `a` to `b`, each once, ascending, into
    /// `out`: the cells the segment passes through, walked in order.
    pub fn query_segment(&self, a: DVec2, b: DVec2, out: &mut Vec<u32>) {
        out.clear();
        self.any_on_segment(a, b, |item| {
            out.push(item);
            false
        });
        out.sort_unstable();
        out.dedup();
    }

    /// Whether `hit` holds for some item whose box may meet the segment from `a` to `b`
    /// (items may be offered more than once, in no particular order; the walk stops at the
    /// first hit).
    pub fn any_on_segment(&self, a: DVec2, b: DVec2, mut hit: impl FnMut(u32) -> bool) -> bool {
        if self.spans.is_empty() {
            return false;
        }
        let inside = |p: DVec2| {
            let q = (p - self.origin) * self.inverse_cell;
            q.x >= 0.0 && q.y >= 0.0 && q.x < self.columns as f64 && q.y < self.rows as f64
        };
        let mut cell_hit = |column: i64, row: i64| {
            let cell = row as usize * self.columns + column as usize;
            let (start, end) = (self.starts[cell] as usize, self.starts[cell + 1] as usize);
            self.entries[start..end].iter().any(|&item| hit(item))
        };
        if !(inside(a) && inside(b)) {
            // An end beyond the grid: its edge cells hold everything out there.
            let [c0, r0, c1, r1] = self.span(a.min(b), a.max(b));
            return (r0..=r1)
                .any(|row| (c0..=c1).any(|column| cell_hit(column as i64, row as i64)));
        }
        // Cells along the segment (Amanatides–Woo), each with its neighbours, so that
        // rounding at a cell boundary loses nothing.
        let (mut column, mut row) = (
            self.index(a.x, self.origin.x, self.last_column) as i64,
            self.index(a.y, self.origin.y, self.last_row) as i64,
        );
        let (end_column, end_row) = (
            self.index(b.x, self.origin.x, self.last_column) as i64,
            self.index(b.y, self.origin.y, self.last_row) as i64,
        );
        let d = b - a;
        let cell = 1.0 / self.inverse_cell;
        let step_x: i64 = if d.x > 0.0 { 1 } else { -1 };
        let step_z: i64 = if d.y > 0.0 { 1 } else { -1 };
        let boundary = |i: i64, step: i64, origin: f64| {
            origin + (i + if step > 0 { 1 } else { 0 }) as f64 * cell
        };
        let mut t_x = if d.x != 0.0 {
            (boundary(column, step_x, self.origin.x) - a.x) / d.x
        } else {
            f64::INFINITY
        };
        let mut t_z = if d.y != 0.0 {
            (boundary(row, step_z, self.origin.y) - a.y) / d.y
        } else {
            f64::INFINITY
        };
        let delta_x = if d.x != 0.0 {
            cell / d.x.abs()
        } else {
            f64::INFINITY
        };
        let delta_z = if d.y != 0.0 {
            cell / d.y.abs()
        } else {
            f64::INFINITY
        };
        let (rows, columns) = (self.rows as i64, self.columns as i64);
        let limit = self.columns + self.rows + 2;
        for _ in 0..limit {
            for r in (row - 1).max(0)..=(row + 1).min(rows - 1) {
                for c in (column - 1).max(0)..=(column + 1).min(columns - 1) {
                    if cell_hit(c, r) {
                        return true;
                    }
                }
            }
            if column == end_column && row == end_row {
                break;
            }
            if t_x < t_z {
                column += step_x;
                t_x += delta_x;
            } else {
                row += step_z;
                t_z += delta_z;
            }
            if column < 0 || row < 0 || column >= columns || row >= rows {
                break;
            }
        }
        false
    }
}

/// Most cells a [`Clearance`] map may have (one bit each: 128 KiB), and most per box (its
/// bits then cost no more than the box's own entry in a grid): memory follows the boxes, not
/// the region.
const MAX_CLEARANCE_CELLS: usize = 1 << 20;
const CLEARANCE_CELLS_PER_BOX: usize = 64;
const MIN_CLEARANCE_CELLS: usize = 4096;

/// A bitmap over the floor that answers "is there surely no box within `reach` of this
/// point" in one lookup: the common answer in a sparse world, where a grid query would still
/// convert four coordinates and walk its cells to find nothing. A cell is marked when some
/// box comes within `reach` of any point of it (with a margin far wider than rounding), so
/// an unmarked cell's points have no box within `reach`; points outside the map are never
/// clear. It changes what a caller queries, never what it finds.
#[derive(Clone, Debug, Default)]
pub struct Clearance {
    origin: DVec2,
    inverse_cell: f64,
    columns: usize,
    /// Columns and rows as floating point, the bounds a point's cell is checked against.
    columns_f: f64,
    rows_f: f64,
    /// One bit per cell, row-major: set where some box may be within `reach`.
    marked: Vec<u64>,
}

impl Clearance {
    /// A map of `[min, max]` for boxes (min, max) and a `reach` (m): cells of about `reach`,
    /// coarser where the region would need more than 64 a box (at least 4096, at most
    /// [`MAX_CLEARANCE_CELLS`]).
    pub fn new(
        min: DVec2,
        max: DVec2,
        reach: f64,
        boxes: impl ExactSizeIterator<Item = (DVec2, DVec2)>,
    ) -> Clearance {
        let usable = min.is_finite()
            && max.is_finite()
            && max.cmpge(min).all()
            && reach.is_finite()
            && reach >= 0.0;
        if !usable {
            return Clearance::default();
        }
        let extent = (max - min).max(DVec2::splat(1e-9));
        let mut cell = reach.max(extent.max_element() / 4096.0).max(1e-6);
        let count =
            |cell: f64| (extent.x / cell).ceil().max(1.0) * (extent.y / cell).ceil().max(1.0);
        let budget = boxes
            .len()
            .saturating_mul(CLEARANCE_CELLS_PER_BOX)
            .clamp(MIN_CLEARANCE_CELLS, MAX_CLEARANCE_CELLS);
        while count(cell) > budget as f64 {
            cell *= 2.0;
        }
        let columns = (extent.x / cell).ceil().max(1.0) as usize;
        let rows = (extent.y / cell).ceil().max(1.0) as usize;
        let mut map = Clearance {
            origin: min,
            inverse_cell: 1.0 / cell,
            columns,
            columns_f: columns as f64,
            rows_f: rows as f64,
            marked: vec![0; (columns * rows).div_ceil(64)],
        };
        // Far wider than any rounding of a point's cell or of the boxes' own margins.
        let margin = 1e-9 * (1.0 + extent.max_element() + min.abs().max_element()) + 1e-9;
        let widen = reach + margin;
        let cell_of = |value: f64, origin: f64, last: usize| -> usize {
            let x = libm::floor((value - origin) * map.inverse_cell);
            if x >= last as f64 {
                last
            } else if x >= 0.0 {
                x as usize
            } else {
                0
            }
        };
        for (lo, hi) in boxes {
            if !(lo.is_finite() && hi.is_finite()) {
                // Anything may be near a box without bounds: the whole map is marked.
                map.marked.fill(u64::MAX);
                return map;
            }
            let c0 = cell_of(lo.x - widen, min.x, columns - 1);
            let c1 = cell_of(hi.x + widen, min.x, columns - 1);
            let r0 = cell_of(lo.y - widen, min.y, rows - 1);
            let r1 = cell_of(hi.y + widen, min.y, rows - 1);
            for row in r0..=r1 {
                for column in c0..=c1 {
                    let i = row * columns + column;
                    map.marked[i / 64] |= 1 << (i % 64);
                }
            }
        }
        map
    }

    /// Whether no box comes within the map's `reach` of `p` (false outside the map, and for
    /// NaN).
    #[inline]
    pub fn is_clear(&self, p: DVec2) -> bool {
        let x = (p.x - self.origin.x) * self.inverse_cell;
        let y = (p.y - self.origin.y) * self.inverse_cell;
        if !(x >= 0.0 && y >= 0.0 && x < self.columns_f && y < self.rows_f) {
            return false;
        }
        let i = y as i64 as usize * self.columns + x as i64 as usize;
        self.marked[i / 64] & (1 << (i % 64)) == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes() -> Vec<(DVec2, DVec2)> {
        let mut out = Vec::new();
        let mut next = crate::test_random::unit_stream(7);
        for _ in 0..300 {
            let c = DVec2::new(next() * 12.0 - 1.0, next() * 12.0 - 1.0);
            let h = DVec2::new(next() * next() * 3.0, next() * 0.2);
            out.push((c - h, c + h));
        }
        out
    }

    fn meets(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> bool {
        a.0.cmple(b.1).all() && b.0.cmple(a.1).all()
    }

    #[test]
    fn box_queries_find_every_overlap_once_in_order() {
        let items = boxes();
        let mut grid = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.7, 300);
        grid.rebuild(items.len(), |i| items[i]);
        let mut out = Vec::new();
        for query in boxes().iter().take(100) {
            grid.query(query.0, query.1, &mut out);
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending, once each");
            for (i, item) in items.iter().enumerate() {
                if meets(*item, *query) {
                    assert!(out.contains(&(i as u32)), "{i} missed");
                }
            }
        }
    }

    /// Points (one cell each, as robots' centres are filed) take the query's shortcuts: a
    /// row's cells copied as one run, a one-cell query copied whole. Each must still find
    /// every point in the box, once, ascending.
    #[test]
    fn point_queries_find_every_point_once_in_order() {
        let points: Vec<DVec2> = boxes().iter().map(|b| (b.0 + b.1) * 0.5).collect();
        let mut grid = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.7, points.len());
        grid.rebuild(points.len(), |i| (points[i], points[i]));
        assert!(grid.single_cells);
        let mut out = Vec::new();
        let mut one_cell = 0;
        for (k, centre) in points.iter().enumerate() {
            // Boxes from far inside a cell to several cells wide.
            let half = DVec2::splat([0.01, 0.2, 0.9, 2.5][k % 4]);
            let query = (*centre - half, *centre + half);
            let [c0, r0, c1, r1] = grid.span(query.0, query.1);
            one_cell += usize::from(c0 == c1 && r0 == r1);
            grid.query(query.0, query.1, &mut out);
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending, once each");
            for (i, point) in points.iter().enumerate() {
                if meets((*point, *point), query) {
                    assert!(out.contains(&(i as u32)), "{i} missed");
                }
            }
        }
        assert!(one_cell > 0, "some queries fall in one cell");
    }

    /// Points filed as points are filed as boxes of no size would be, and a point's query is
    /// a box query of no size.
    #[test]
    fn points_filed_as_points_match_points_filed_as_boxes() {
        let points: Vec<DVec2> = boxes().iter().map(|b| (b.0 + b.1) * 0.5).collect();
        let mut as_boxes = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.7, points.len());
        let mut as_points = as_boxes.clone();
        as_boxes.rebuild(points.len(), |i| (points[i], points[i]));
        as_points.rebuild_points(points.len(), |i| points[i]);
        assert!(as_points.single_cells);
        assert_eq!(as_points.starts, as_boxes.starts);
        assert_eq!(as_points.entries, as_boxes.entries);
        assert_eq!(as_points.spans, as_boxes.spans);
        let (mut by_box, mut by_point) = (Vec::new(), Vec::new());
        // Beyond the grid too, and a NaN (filed at the first cell).
        let probes = boxes().into_iter().map(|b| b.0 * 1.3 - 2.0).chain([
            DVec2::NAN,
            DVec2::splat(-50.0),
            DVec2::splat(50.0),
        ]);
        for p in probes {
            as_points.query(p, p, &mut by_box);
            as_points.query_point(p, &mut by_point);
            assert_eq!(by_box, by_point);
        }
    }

    /// `query_where` hands exactly the items `query` hands that pass its test, ascending, and
    /// asks the test once per item, on grids of boxes and of points.
    /// A point the map calls clear has no box within its reach, and the map is not
    /// trivially marked: in a sparse field most points are clear.
    #[test]
    fn clearance_never_calls_a_point_clear_that_a_box_is_near() {
        let mut next = crate::test_random::unit_stream(11);
        let boxes: Vec<(DVec2, DVec2)> = (0..60)
            .map(|_| {
                let c = DVec2::new(next() * 20.0 - 2.0, next() * 20.0 - 2.0);
                let h = DVec2::new(next() * 0.3, next() * 0.3);
                (c - h, c + h)
            })
            .collect();
        for reach in [0.0, 0.05, 0.117, 0.5] {
            let map = Clearance::new(
                DVec2::splat(-2.0),
                DVec2::splat(18.0),
                reach,
                boxes.iter().copied(),
            );
            let mut clear = 0;
            for i in 0..40_000 {
                // Points anywhere, some beyond the map; every tenth on a box's edge grown by
                // the reach, where rounding would show.
                let p = if i % 10 == 0 {
                    let (lo, hi) = boxes[i / 10 % boxes.len()];
                    DVec2::new(hi.x + reach, lo.y + next() * (hi.y - lo.y))
                } else {
                    DVec2::new(next() * 24.0 - 4.0, next() * 24.0 - 4.0)
                };
                if !map.is_clear(p) {
                    continue;
                }
                clear += 1;
                let square = (p - reach, p + reach);
                assert!(
                    boxes.iter().all(|&b| !meets(b, square)),
                    "{p} is called clear with a box within {reach}"
                );
            }
            assert!(clear > 12_000, "reach {reach}: only {clear} points clear");
        }
        // NaN and points off the map are never clear.
        let map = Clearance::new(DVec2::ZERO, DVec2::ONE, 0.1, [].into_iter());
        assert!(map.is_clear(DVec2::splat(0.5)));
        assert!(!map.is_clear(DVec2::new(f64::NAN, 0.5)));
        assert!(!map.is_clear(DVec2::new(1.5, 0.5)));
        assert!(!Clearance::default().is_clear(DVec2::ZERO));
    }

    #[test]
    fn query_where_keeps_what_passes_in_order() {
        let items = boxes();
        let points: Vec<DVec2> = items.iter().map(|b| (b.0 + b.1) * 0.5).collect();
        let mut of_boxes = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.7, items.len());
        of_boxes.rebuild(items.len(), |i| items[i]);
        let mut of_points = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.7, points.len());
        of_points.rebuild_points(points.len(), |i| points[i]);
        let (mut all, mut kept) = (Vec::new(), Vec::new());
        for grid in [&of_boxes, &of_points] {
            for (k, query) in boxes().iter().enumerate() {
                let keep = |item: u32| !(item as usize * 7 + k).is_multiple_of(3);
                grid.query(query.0, query.1, &mut all);
                let mut asked = Vec::new();
                grid.query_where(query.0, query.1, &mut kept, |item| {
                    asked.push(item);
                    keep(item)
                });
                let expected: Vec<u32> = all.iter().copied().filter(|&i| keep(i)).collect();
                assert_eq!(kept, expected);
                asked.sort_unstable();
                assert_eq!(asked, all, "each candidate asked once");
            }
        }
    }

    #[test]
    fn segment_queries_find_every_box_the_segment_crosses() {
        let items = boxes();
        let mut grid = Grid::new(DVec2::ZERO, DVec2::splat(10.0), 0.5, 300);
        grid.rebuild(items.len(), |i| items[i]);
        let mut out = Vec::new();
        for (a, b) in boxes().iter().map(|q| (q.0, q.1 + DVec2::new(-2.0, 4.0))) {
            grid.query_segment(a, b, &mut out);
            for (i, item) in items.iter().enumerate() {
                // Sampled along the segment: a box holding a sample point must be found.
                let hit = (0..=200).any(|k| {
                    let p = a + (b - a) * (k as f64 / 200.0);
                    meets(*item, (p, p))
                });
                if hit {
                    assert!(out.contains(&(i as u32)), "{i} missed");
                }
            }
        }
    }
}
