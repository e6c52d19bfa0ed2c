//! The crowd level of detail: which other robots an eye draws. With a crowd distance, only
//! robots whose centre lies within it are placed in a look, so a look's cost follows the
//! robots near the eye, not the crowd's size. The robots of a step are binned once into a
//! uniform grid, on the first look that asks (every viewer of the step shares it), and a look
//! reads the cells its distance reaches. The answer is a set, returned in robot order, so it
//! does not depend on the grid's cell size nor on which viewer built it: the image is the same
//! for any thread count. The scene bins its round static groups (buoys) in the same kind of
//! grid once, for the far distance (`scene.rs`'s `RoundIndex`).

use super::compact::extend_kept;
use glam::DVec2;

/// Robots binned by position.
#[derive(Clone, Debug)]
pub(super) struct CrowdGrid {
    origin: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
    /// Cell `c`'s robots are `robots[starts[c]..starts[c + 1]]`, in robot order.
    starts: Vec<u32>,
    robots: Vec<u32>,
}

/// At most this many cells per robot: a small distance in a sparse crowd would otherwise ask
/// for a grid larger than the crowd.
const CELLS_PER_ROBOT: f64 = 4.0;

impl CrowdGrid {
    /// Bins `positions` into cells of about `cell` metres (larger if that would make too many).
    pub(super) fn new(positions: &[DVec2], cell: f64) -> CrowdGrid {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &p in positions.iter().filter(|p| p.is_finite()) {
            min = min.min(p);
            max = max.max(p);
        }
        if !(min.x <= max.x && min.y <= max.y) {
            min = DVec2::ZERO;
            max = DVec2::ZERO;
        }
        let extent = (max - min).max(DVec2::splat(1e-9));
        let most = (positions.len() as f64 * CELLS_PER_ROBOT).max(1.0);
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            extent.max_element()
        };
        if (extent.x / cell).ceil() * (extent.y / cell).ceil() > most {
            cell = (extent.x * extent.y / most)
                .sqrt()
                .max(extent.max_element() / most);
        }
        let columns = ((extent.x / cell) as usize + 1).max(1);
        let rows = ((extent.y / cell) as usize + 1).max(1);
        let mut grid = CrowdGrid {
            origin: min,
            inverse_cell: 1.0 / cell,
            columns,
            rows,
            starts: vec![0; columns * rows + 1],
            robots: vec![0; positions.len()],
        };
        // A counting sort: robots stay in index order within their cell.
        let cells: Vec<usize> = positions.iter().map(|&p| grid.cell_of(p)).collect();
        for &c in &cells {
            grid.starts[c + 1] += 1;
        }
        for c in 0..columns * rows {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut next = grid.starts.clone();
        for (robot, &c) in cells.iter().enumerate() {
            grid.robots[next[c] as usize] = robot as u32;
            next[c] += 1;
        }
        grid
    }

    /// The cell holding `p` (positions outside, or not finite, go to the nearest cell).
    fn cell_of(&self, p: DVec2) -> usize {
        let (column, row) = self.coordinates(p);
        row * self.columns + column
    }

    fn coordinates(&self, p: DVec2) -> (usize, usize) {
        let at = (p - self.origin) * self.inverse_cell;
        let clamp = |v: f64, n: usize| {
            if v > 0.0 {
                (v as usize).min(n - 1)
            } else {
                0
            }
        };
        (clamp(at.x, self.columns), clamp(at.y, self.rows))
    }

    /// The robots whose position lies within `distance` of `eye`, in robot order, into `out`.
    pub(super) fn within(
        &self,
        positions: &[DVec2],
        eye: DVec2,
        distance: f64,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.append_within(positions, eye, distance, out);
        out.sort_unstable();
    }

    /// [`CrowdGrid::within`]'s robots appended to `out` cell by cell: each once, in no
    /// particular order (for a caller that orders them its own way).
    pub(super) fn append_within(
        &self,
        positions: &[DVec2],
        eye: DVec2,
        distance: f64,
        out: &mut Vec<u32>,
    ) {
        let reach = DVec2::splat(distance);
        let (c0, r0) = self.coordinates(eye - reach);
        let (c1, r1) = self.coordinates(eye + reach);
        let limit = distance * distance;
        for row in r0..=r1 {
            let cells = row * self.columns + c0..=row * self.columns + c1;
            let (start, end) = (
                self.starts[*cells.start()] as usize,
                self.starts[*cells.end() + 1] as usize,
            );
            extend_kept(
                out,
                self.robots[start..end].iter().map(|&robot| {
                    let within = positions
                        .get(robot as usize)
                        .is_some_and(|at| at.distance_squared(eye) <= limit);
                    (robot, within)
                }),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_answer_is_the_brute_force_set_for_any_cell_size() {
        let mut unit = crate::test_random::unit_stream(7);
        let positions: Vec<DVec2> = (0..500)
            .map(|_| DVec2::new(unit() * 3.0 - 1.5, unit() * 2.0))
            .collect();
        let mut out = Vec::new();
        for cell in [0.01, 0.1, 0.3, 1.0, 10.0, f64::INFINITY] {
            let grid = CrowdGrid::new(&positions, cell);
            for k in 0..40 {
                let eye = DVec2::new(unit() * 4.0 - 2.0, unit() * 3.0 - 0.5);
                let distance = [0.05, 0.3, 0.7, 5.0][k % 4];
                grid.within(&positions, eye, distance, &mut out);
                let expected: Vec<u32> = (0..positions.len() as u32)
                    .filter(|&r| positions[r as usize].distance_squared(eye) <= distance * distance)
                    .collect();
                assert_eq!(out, expected, "cell {cell}, eye {eye}, distance {distance}");
            }
        }
    }
}
