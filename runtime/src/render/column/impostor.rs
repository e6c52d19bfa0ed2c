//! Impostors: the crowd level of detail's stand-ins for small static objects far from an eye
//! (a buoy and its lamp across the arena). An impostor cuts no silhouette edge into the strip
//! and joins no region's facing list; it is drawn once, after the strip is integrated, as a
//! box over its azimuth interval whose height is its effect on the column through its centre
//! (that column composited with it and without it), times the share of its interval that no
//! nearer object standing on the floor hides. This module owns which objects become
//! impostors, and how much of each shows (the occlusion bins); `integrate.rs` draws them.
//!
//! Why it is cheap: a far buoy used to cut the strip twice, each cut a region with its own
//! sampled columns; as an impostor it costs one column's segments composited twice. Why the
//! error is small: beyond the crowd distance and narrower than a few photodiodes, what a
//! cylinder shows varies little across it (its distance within r²/2d, its lamp's radiance not
//! at all). `regatta bench crowd` measures the error against exact.

use std::cmp::Ordering;

/// Impostors are at most this many photodiode windows wide: wider objects would show their
/// shading's variation across them, and are drawn exactly.
pub(super) const IMPOSTOR_PIXELS: f64 = 4.0;

/// Occlusion bins over a turn of azimuth: about 0.09° each, a photodiode window's eighteenth.
const BINS: usize = 4096;

/// A small static object far from the eye, drawn as a box (its pieces: the objects sharing its
/// footprint, a lamp on its buoy).
#[derive(Clone, Copy, Debug)]
pub(super) struct Impostor {
    /// Its azimuth interval, relative to the heading, in (−π, π] and not wrapping.
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// From the eye to its footprint's centre.
    pub(super) distance: f64,
    /// Heights of its pieces together, relative to the eye.
    pub(super) y0: f64,
    pub(super) y1: f64,
    /// Its pieces, a range of the look's impostor pieces.
    pub(super) first_piece: u32,
    pub(super) pieces: u32,
    /// The share of its interval no nearer standing object hides (set by [`settle`]).
    pub(super) visible: f64,
}

impl Impostor {
    /// The tan-elevation of its top seen from the eye, at its centre's distance.
    fn top(&self) -> f64 {
        self.y1 / self.distance
    }
}

/// An object drawn exactly (near the eye) that may hide impostors: a round footprint, its
/// pieces stacked (a buoy with its lamp).
#[derive(Clone, Copy, Debug)]
pub(super) struct Standing {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) distance: f64,
    pub(super) y0: f64,
    pub(super) y1: f64,
}

/// Per azimuth bin, the highest top (tan-elevation) of the objects standing on the floor
/// that cover the whole bin, among those placed so far (nearest first). Stamped, so that a
/// new look clears nothing.
#[derive(Default)]
pub(super) struct Occlusion {
    stamp: Vec<u32>,
    top: Vec<f64>,
    epoch: u32,
}

impl Occlusion {
    fn begin(&mut self) {
        if self.stamp.len() != BINS {
            self.stamp = vec![0; BINS];
            self.top = vec![f64::NEG_INFINITY; BINS];
            self.epoch = 0;
        }
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            // Every stamp might now look current: clear them once per 2³² looks.
            self.stamp.fill(0);
            self.epoch = 1;
        }
    }

    /// Azimuth `angle` (in (−π, π]) as a position in bins.
    #[inline]
    fn position(angle: f64) -> f64 {
        (angle + std::f64::consts::PI) * (BINS as f64 / std::f64::consts::TAU)
    }

    /// How much of `[lo, hi]` (radians) no placed object with a top at or above `top` covers.
    fn uncovered(&self, lo: f64, hi: f64, top: f64) -> f64 {
        let (u0, u1) = (Self::position(lo), Self::position(hi));
        let first = (u0.max(0.0) as usize).min(BINS - 1);
        let last = (u1.max(0.0) as usize).min(BINS - 1);
        let mut open = 0.0;
        for k in first..=last {
            let covered = self.stamp[k] == self.epoch && self.top[k] >= top;
            if !covered {
                let (b0, b1) = (k as f64, k as f64 + 1.0);
                open += (u1.min(b1) - u0.max(b0)).max(0.0);
            }
        }
        open * (std::f64::consts::TAU / BINS as f64)
    }

    /// Records an object covering `[lo, hi]` up to `top`, in the bins it covers whole.
    fn cover(&mut self, lo: f64, hi: f64, top: f64) {
        let (u0, u1) = (Self::position(lo), Self::position(hi));
        let first = u0.max(0.0).ceil() as usize;
        let end = (u1.max(0.0).floor() as usize).min(BINS);
        for k in first..end {
            if self.stamp[k] != self.epoch {
                self.stamp[k] = self.epoch;
                self.top[k] = top;
            } else if top > self.top[k] {
                self.top[k] = top;
            }
        }
    }
}

/// Sets each impostor's visible share: nearest first, the part of its interval where no
/// nearer object standing on the floor reaches higher than its top.
///
/// An object standing on the floor nearer than an impostor whose base is no lower than its
/// own hides all of it below its top (the floor hides the rest): only tops are compared.
/// Distances are the footprints' centres', so two impostors at nearly the same distance may
/// both show where they overlap; the error that leaves is measured with the rest.
pub(super) fn settle(
    impostors: &mut [Impostor],
    standing: &[Standing],
    occlusion: &mut Occlusion,
    order: &mut Vec<u64>,
) {
    if impostors.is_empty() {
        return;
    }
    occlusion.begin();
    // Only objects whose base is at or below every impostor's, and the eye's, may hide.
    let base = impostors
        .iter()
        .map(|i| i.y0)
        .fold(0.0f64, |lowest, y| if y < lowest { y } else { lowest });
    for s in standing {
        if s.y0 <= base && s.distance > 0.0 {
            occlusion.cover(s.lo, s.hi, s.y1 / s.distance);
        }
    }
    order.clear();
    order.extend(
        impostors
            .iter()
            .enumerate()
            .map(|(index, i)| ((i.distance as f32).to_bits() as u64) << 32 | index as u64),
    );
    order.sort_unstable();
    for &key in order.iter() {
        let impostor = &mut impostors[key as u32 as usize];
        let width = impostor.hi - impostor.lo;
        let top = impostor.top();
        impostor.visible = if width > 0.0 {
            (occlusion.uncovered(impostor.lo, impostor.hi, top) / width).min(1.0)
        } else {
            0.0
        };
        if impostor.y0 <= base {
            occlusion.cover(impostor.lo, impostor.hi, top);
        }
    }
}

/// The impostors in the order they are drawn: by interval start, ties by index (the sweep
/// answers facing queries whose starts never fall).
pub(super) fn by_start(impostors: &[Impostor], order: &mut Vec<u32>) {
    order.clear();
    order.extend(
        impostors
            .iter()
            .enumerate()
            .filter(|(_, i)| i.visible > 0.0)
            .map(|(index, _)| index as u32),
    );
    order.sort_unstable_by(|&a, &b| {
        impostors[a as usize]
            .lo
            .partial_cmp(&impostors[b as usize].lo)
            .unwrap_or(Ordering::Equal)
            .then(a.cmp(&b))
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn impostor(lo: f64, hi: f64, distance: f64) -> Impostor {
        Impostor {
            lo,
            hi,
            distance,
            y0: -0.05,
            y1: 0.02,
            first_piece: 0,
            pieces: 1,
            visible: 1.0,
        }
    }

    #[test]
    fn a_nearer_buoy_hides_a_farther_one_behind_it_and_half_of_one_beside_it() {
        let mut impostors = [
            impostor(0.10, 0.11, 3.0),
            impostor(0.0, 0.02, 1.0),
            impostor(0.01, 0.03, 4.0),
            impostor(-0.5, -0.49, 5.0),
        ];
        let (mut occlusion, mut order) = (Occlusion::default(), Vec::new());
        settle(&mut impostors, &[], &mut occlusion, &mut order);
        assert_eq!(impostors[1].visible, 1.0, "nearest shows whole");
        assert_eq!(impostors[3].visible, 1.0, "alone shows whole");
        assert_eq!(impostors[0].visible, 1.0, "beside, not behind");
        // Half behind the nearest, to within a bin (0.0015 rad) at each end.
        let half = impostors[2].visible;
        assert!((half - 0.5).abs() < 0.1, "{half}");
    }

    #[test]
    fn a_near_standing_object_hides_impostors_below_its_top_only() {
        let standing = [Standing {
            lo: -0.2,
            hi: 0.2,
            distance: 0.3,
            y0: -0.05,
            y1: 0.02,
        }];
        // Behind it and lower in view: hidden. A tall one far behind: its top shows.
        let mut impostors = [impostor(-0.01, 0.01, 2.0), {
            let mut tall = impostor(0.05, 0.06, 2.0);
            tall.y1 = 0.5;
            tall
        }];
        let (mut occlusion, mut order) = (Occlusion::default(), Vec::new());
        settle(&mut impostors, &standing, &mut occlusion, &mut order);
        assert_eq!(impostors[0].visible, 0.0);
        assert_eq!(impostors[1].visible, 1.0);
        // A new look starts with nothing covered.
        let mut alone = [impostor(-0.01, 0.01, 2.0)];
        settle(&mut alone, &[], &mut occlusion, &mut order);
        assert_eq!(alone[0].visible, 1.0);
    }
}
