//! Impostors: the crowd level of detail's stand-ins for small static objects far from an eye
//! (a buoy and its lamp across the arena). An impostor cuts no silhouette edge into the strip
//! and joins no region's facing list; it is drawn once, after the strip is integrated, as a
//! box over its azimuth interval whose height is its effect on the column through its centre
//! (that column composited with it and without it), times the share of its interval that no
//! nearer object standing on the floor hides. This module owns which objects become
//! impostors (each look tests the scene's round groups, [`Viewpoint::far`]), and how much of
//! each shows (the occlusion bins); `far.rs` draws them.
//!
//! Why it is cheap: a far buoy used to cut the strip twice, each cut a region with its own
//! sampled columns; as an impostor it costs a few arithmetic operations to tell and a few
//! lookups in its column's running integrals to draw. Why the
//! error is small: beyond the crowd distance and narrower than a few photodiodes, what a
//! cylinder shows varies little across it (its distance within r²/2d, its lamp's radiance not
//! at all). `regatta bench crowd` measures the error against exact.

use glam::{DVec2, DVec3};

use super::photodiode::{larger, smaller, total_key};

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
    /// From the eye to its footprint's centre, and the footprint's radius.
    pub(super) distance: f64,
    pub(super) radius: f64,
    /// The foot of its pieces together, relative to the eye.
    pub(super) y0: f64,
    /// Its pieces: this many of the frame's static objects from `first_static` on.
    pub(super) first_static: u32,
    pub(super) pieces: u32,
    /// The tan-elevation of its pieces' top together at its centre's distance.
    pub(super) top: f64,
    /// The share of its interval no nearer standing object hides (set by [`settle`]).
    pub(super) visible: f64,
}

impl Impostor {
    /// The tan-elevation of its top seen from the eye, at its centre's distance.
    fn top(&self) -> f64 {
        self.top
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
/// that cover the whole bin, among those placed so far (nearest first). A look that has
/// impostors clears the bins the previous one wrote (`written`): the loops over bins are then
/// plain maxima and counts, which run in vector lanes, and a look with few impostors clears
/// few bins.
#[derive(Default)]
pub(super) struct Occlusion {
    top: Vec<f64>,
    /// The bins written since the last clearing.
    written: std::ops::Range<usize>,
}

impl Occlusion {
    fn begin(&mut self) {
        if self.top.len() != BINS {
            self.top = vec![f64::NEG_INFINITY; BINS];
        } else {
            self.top[self.written.clone()].fill(f64::NEG_INFINITY);
        }
        self.written = 0..0;
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
        let open_in = |k: usize| {
            let (b0, b1) = (k as f64, k as f64 + 1.0);
            if self.top[k] >= top {
                0.0
            } else {
                (u1.min(b1) - u0.max(b0)).max(0.0)
            }
        };
        let mut open = open_in(first);
        if last > first {
            open += open_in(last);
            // The bins between, each whole: a count.
            let between = self.top[first + 1..last]
                .iter()
                // Uncovered: lower, or unordered (as `!(t >= top)`, in vector lanes).
                .filter(|&&t| t < top || t.is_nan() || top.is_nan())
                .count();
            open += between as f64;
        }
        open * (std::f64::consts::TAU / BINS as f64)
    }

    /// [`Occlusion::uncovered`] for an interval that may pass ±π by less than a turn (told
    /// all around the eye): its two pieces, each within (−π, π].
    fn uncovered_around(&self, lo: f64, hi: f64, top: f64) -> f64 {
        use std::f64::consts::{PI, TAU};
        if lo < -PI {
            self.uncovered(lo + TAU, PI, top) + self.uncovered(-PI, hi, top)
        } else if hi > PI {
            self.uncovered(lo, PI, top) + self.uncovered(-PI, hi - TAU, top)
        } else {
            self.uncovered(lo, hi, top)
        }
    }

    /// [`Occlusion::cover`] for an interval that may pass ±π by less than a turn.
    fn cover_around(&mut self, lo: f64, hi: f64, top: f64) {
        use std::f64::consts::{PI, TAU};
        if lo < -PI {
            self.cover(lo + TAU, PI, top);
            self.cover(-PI, hi, top);
        } else if hi > PI {
            self.cover(lo, PI, top);
            self.cover(-PI, hi - TAU, top);
        } else {
            self.cover(lo, hi, top);
        }
    }

    /// Records an object covering `[lo, hi]` up to `top`, in the bins it covers whole.
    fn cover(&mut self, lo: f64, hi: f64, top: f64) {
        let (u0, u1) = (Self::position(lo), Self::position(hi));
        // Truncation floors a non-negative number; `ceil` and `floor` would be libm calls.
        let (u0, u1) = (u0.max(0.0), u1.max(0.0));
        let below = u0 as usize;
        let first = (below + usize::from((below as f64) < u0)).min(BINS);
        let end = (u1 as usize).min(BINS);
        if first < end {
            self.written = if self.written.is_empty() {
                first..end
            } else {
                self.written.start.min(first)..self.written.end.max(end)
            };
            for bin in &mut self.top[first..end] {
                *bin = if top > *bin { top } else { *bin };
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
    // A hider lower than every impostor's top hides none of them.
    let lowest_top = impostors
        .iter()
        .map(Impostor::top)
        .fold(
            f64::INFINITY,
            |lowest, t| if t < lowest { t } else { lowest },
        );
    for s in standing {
        if s.y0 <= base && s.distance > 0.0 && s.y1 / s.distance >= lowest_top {
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
            (occlusion.uncovered_around(impostor.lo, impostor.hi, top) / width).min(1.0)
        } else {
            0.0
        };
        if impostor.y0 <= base {
            occlusion.cover_around(impostor.lo, impostor.hi, top);
        }
    }
}

/// Which of 64 equal sectors of a turn the standing objects' intervals meet: a box in sectors
/// none meets is hidden by none, told by one mask test (most kept boxes are), not by a
/// pass over the standing objects.
#[derive(Clone, Copy)]
pub(super) struct NearSectors(u64);

impl NearSectors {
    /// The sectors `standing` meets.
    pub(super) fn of(standing: &[Standing]) -> NearSectors {
        let mut mask = 0u64;
        for s in standing {
            mask |= Self::over(s.lo, s.hi);
        }
        NearSectors(mask)
    }

    /// The sectors `[lo, hi]` meets (every one for an interval past ±π, or not a number).
    #[inline]
    fn over(lo: f64, hi: f64) -> u64 {
        use std::f64::consts::{PI, TAU};
        let (first, last) = ((lo + PI) * (64.0 / TAU), (hi + PI) * (64.0 / TAU));
        if !(first >= 0.0 && last < 64.0 && first <= last) {
            return u64::MAX;
        }
        // Truncation floors the non-negative positions.
        let (first, last) = (first as u32, last as u32);
        (u64::MAX >> (63 - (last - first))) << first
    }

    /// Whether a standing object may meet `[lo, hi]`.
    pub(super) fn may_meet(self, lo: f64, hi: f64) -> bool {
        self.0 & Self::over(lo, hi) != 0
    }
}

/// How much of the azimuth interval `[lo, hi]` (radians; it may pass ±π by less than a turn)
/// of a box whose foot is `y0` (relative to the eye), top's tan-elevation `top`, at
/// `distance`, the `standing` objects nearer than it hide: those standing no higher than its
/// foot, or whose foot's tan-elevation is at most `foot_below` (below a retina's band nothing
/// shows, so a near buoy's lamp, its body out of the band, hides as if it stood), and reaching
/// its top. Their intervals' union within the box, by interval arithmetic: a kept box is
/// settled each update against the few robots and buoys near the eye, where the occlusion
/// bins would clear and count thousands.
pub(super) fn covered_by_standing(
    standing: &[Standing],
    (lo, hi): (f64, f64),
    (y0, top, distance): (f64, f64, f64),
    foot_below: f64,
) -> f64 {
    use std::f64::consts::{PI, TAU};
    // A box passing ±π meets near objects a turn away as well.
    let shift = if lo < -PI {
        -TAU
    } else if hi > PI {
        TAU
    } else {
        0.0
    };
    // Tests combined by `&` and `|`, not `&&` and `||`: each is a compare, with no branch on
    // its answer (which near object meets a box is no pattern a processor learns).
    let meets = |s: &Standing, by: f64| (s.lo + by < hi) & (s.hi + by > lo);
    let hides = |s: &Standing| {
        (s.distance > 0.0)
            & (s.distance < distance)
            & ((s.y0 <= y0) | (s.y0 <= foot_below * s.distance))
            & (s.y1 >= top * s.distance)
    };
    let shifted = shift != 0.0;
    let hider = |s: &Standing| (meets(s, 0.0) | (shifted & meets(s, shift))) & hides(s);
    // Most boxes meet no near object: every one tested, one branch on the answer, and
    // nothing to merge.
    if !standing.iter().fold(false, |any, s| any | hider(s)) {
        return 0.0;
    }
    let first = standing.iter().position(hider).unwrap_or(standing.len());
    const MOST: usize = 16;
    let mut spans = [(0.0f64, 0.0f64); MOST];
    let mut count = 0;
    for s in &standing[first..] {
        for by in [0.0, shift] {
            if !meets(s, by) || !hides(s) {
                continue;
            }
            if count == MOST {
                // More hiders than a look near a box has: the box counts as hidden.
                return hi - lo;
            }
            spans[count] = (lo.max(s.lo + by), hi.min(s.hi + by));
            count += 1;
            if shift == 0.0 {
                break;
            }
        }
    }
    let spans = &mut spans[..count];
    // A handful at most: by insertion, then merged.
    for i in 1..spans.len() {
        let mut j = i;
        while j > 0 && spans[j - 1].0 > spans[j].0 {
            spans.swap(j - 1, j);
            j -= 1;
        }
    }
    let (mut covered, mut reached) = (0.0, f64::NEG_INFINITY);
    for &(a, b) in spans.iter() {
        let start = a.max(reached);
        if b > start {
            covered += b - start;
            reached = b;
        }
    }
    covered
}

/// What telling impostors needs of one look, worked out once: the eye, its heading's cosine
/// and sine, the crowd distance, the widest impostor (radians), and the cosine of the largest
/// angle from the heading at which an impostor may still meet the strip.
pub(super) struct Viewpoint {
    eye: DVec2,
    cos_h: f64,
    sin_h: f64,
    crowd_distance: f64,
    far_distance: f64,
    width: f64,
    reach_cos: f64,
    /// Whether impostors all around the eye are kept, their interval passing ±π where it does
    /// ([`Viewpoint::keep_all_around`]).
    around: bool,
}

impl Viewpoint {
    /// For an eye at `eye` facing the heading whose cosine and sine are `(cos_h, sin_h)`, with
    /// the crowd and far distances; `reach_cos` from [`Viewpoint::reach_cos`].
    pub(super) fn new(
        eye: DVec3,
        (cos_h, sin_h): (f64, f64),
        (crowd_distance, far_distance): (f64, f64),
        width: f64,
        reach_cos: f64,
    ) -> Viewpoint {
        Viewpoint {
            eye: DVec2::new(eye.x, eye.z),
            cos_h,
            sin_h,
            crowd_distance,
            far_distance,
            width,
            reach_cos,
            around: false,
        }
    }

    /// Keeps every impostor within the far distance, wherever it lies around the eye: none is
    /// behind the strip, and an interval may pass ±π (then its centre lies within (−π, π]).
    pub(super) fn keep_all_around(&mut self) {
        self.reach_cos = f64::NEG_INFINITY;
        self.around = true;
    }

    /// The cosine of the largest angle from the heading at which an impostor at most `width`
    /// wide may meet a strip over relative azimuths `(first, last)` (a margin over the
    /// polynomial arctangent's error); −∞ when any angle may.
    pub(super) fn reach_cos(width: f64, (first, last): (f64, f64)) -> f64 {
        let reach = first.abs().max(last.abs()) + 0.5 * width + 1e-6;
        if reach < std::f64::consts::PI {
            libm::cos(reach)
        } else {
            f64::NEG_INFINITY
        }
    }

    /// A round footprint's azimuth interval (relative to the heading, in (−π, π] and not
    /// passing ±π) and distance from the eye, if it is an impostor's: farther than the crowd
    /// distance beyond its radius, at most the widest impostor wide. `Some` with an empty
    /// interval (`lo > hi`) when it is one but is left out: wholly beyond the far distance,
    /// behind the strip, or passing ±π. The
    /// distance is tested first, so that near objects cost no square root; the interval
    /// comes from polynomials (within 2e-8 rad), as an impostor's place needs no more.
    #[inline]
    pub(super) fn far(&self, center: DVec2, radius: f64) -> Option<(f64, f64, f64)> {
        let offset = center - self.eye;
        // A margin keeps the squared test on the near side of the exact one below.
        let reach = (self.crowd_distance + radius) * (1.0 + 1e-9);
        let distance2 = offset.length_squared();
        if distance2 <= reach * reach {
            return None;
        }
        let distance = distance2.sqrt();
        // (A NaN distance is near: drawn exactly.)
        if distance - radius <= self.crowd_distance || distance.is_nan() {
            return None;
        }
        let ratio = radius / distance;
        // asin by its series: an impostor is narrower than a few photodiodes (ratio ≲ 0.06,
        // where the terms left out are below 1e-12); past 0.1 the series is not used.
        if ratio > 0.1 {
            return None;
        }
        let r2 = ratio * ratio;
        let half = ratio * (1.0 + r2 * (1.0 / 6.0 + r2 * (3.0 / 40.0 + r2 * (5.0 / 112.0))));
        if 2.0 * half > self.width {
            return None;
        }
        const BEHIND: Option<(f64, f64, f64)> = Some((1.0, 0.0, 0.0));
        if distance - radius > self.far_distance {
            return BEHIND;
        }
        // Azimuth is anticlockwise from +x towards −z: the offset turned by −heading.
        let (u, v) = (offset.x, -offset.y);
        let along = u * self.cos_h + v * self.sin_h;
        if along < distance * self.reach_cos {
            return BEHIND;
        }
        let middle = atan2(v * self.cos_h - u * self.sin_h, along);
        let (lo, hi) = (middle - half, middle + half);
        if (lo <= -std::f64::consts::PI || hi > std::f64::consts::PI) && !self.around {
            return BEHIND;
        }
        Some((lo, hi, distance))
    }
}

/// `atan2(y, x)` by an odd polynomial after reducing the argument to |w| ≤ tan(π/8)
/// (error below 2e-8 rad), plain arithmetic: the same on every platform.
///
/// Without a branch on the octant: a crowd's eye places its kept boxes all around it, and
/// branches on where each lies missed half the time. Each choice between two results is
/// `s·a + (1 − 2s)·b` or `b − s·c` with `s` 0 or 1, which gives the chosen one to the bit
/// (the values here are finite and no −0 arises where it would matter), and the sign is set
/// on the bits.
pub(super) fn atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let one_if = |condition: bool| f64::from(u8::from(condition));
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den) = (smaller(ax, ay), larger(ay, ax));
    if den == 0.0 {
        return 0.0;
    }
    // z = num/den, reduced past tan(π/8) by (z − 1)/(z + 1): one division either way.
    let reduce = one_if(num > (std::f64::consts::SQRT_2 - 1.0) * den);
    let w = (num - reduce * den) / (den + reduce * num);
    let w2 = w * w;
    let series = w
        * (1.0
            - w2 * (1.0 / 3.0
                - w2 * (1.0 / 5.0
                    - w2 * (1.0 / 7.0
                        - w2 * (1.0 / 9.0
                            - w2 * (1.0 / 11.0 - w2 * (1.0 / 13.0 - w2 * (1.0 / 15.0))))))));
    // From here on the angle is +0 or positive.
    let angle = reduce * FRAC_PI_4 + series;
    let swapped = one_if(ay > ax);
    let angle = swapped * FRAC_PI_2 + (1.0 - 2.0 * swapped) * angle;
    let left = one_if(x < 0.0);
    let angle = left * PI + (1.0 - 2.0 * left) * angle;
    f64::from_bits(angle.to_bits() | (u64::from(y < 0.0) << 63))
}

/// The visible impostors in the order they are drawn: by the centre of their interval,
/// ties by index.
pub(super) fn by_centre(impostors: &[Impostor], keys: &mut Vec<u128>, order: &mut Vec<u32>) {
    // Each centre's place in the order of numbers, the index below it breaking ties: one
    // integer compares both.
    keys.clear();
    keys.extend(
        impostors
            .iter()
            .enumerate()
            .filter(|(_, i)| i.visible > 0.0)
            .map(|(index, impostor)| {
                (total_key(0.5 * (impostor.lo + impostor.hi)) as u128) << 32 | index as u128
            }),
    );
    keys.sort_unstable();
    order.clear();
    order.extend(keys.iter().map(|&key| key as u32));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn impostor(lo: f64, hi: f64, distance: f64) -> Impostor {
        Impostor {
            lo,
            hi,
            distance,
            radius: 0.02,
            y0: -0.05,
            top: 0.02 / distance,
            first_static: 0,
            pieces: 1,
            visible: 1.0,
        }
    }

    /// A look's impostor test against libm's: the same near and far decisions (off by the
    /// squared test's margin at most), the same interval within 1e-7 rad, and nothing that
    /// meets the strip judged behind it.
    #[test]
    fn the_viewpoints_test_is_libms_and_never_drops_what_meets_the_strip() {
        let mut unit = crate::test_random::unit_stream(17);
        let pixel = 1.6f64.to_radians();
        let width = IMPOSTOR_PIXELS * pixel;
        let (mut far_ones, mut behind) = (0, 0);
        for case in 0..20_000 {
            let eye = DVec3::new(unit() * 8.0 - 4.0, 0.05, unit() * 8.0 - 4.0);
            let heading = unit() * 12.0 - 6.0;
            let extent = if case % 3 == 0 {
                (-0.5, 1.0)
            } else {
                (-120f64.to_radians(), 120f64.to_radians())
            };
            let crowd = [0.25, 0.5, 1.0][case % 3];
            let heading_turn = (libm::cos(heading), libm::sin(heading));
            let reach_cos = Viewpoint::reach_cos(width, extent);
            let viewpoint =
                Viewpoint::new(eye, heading_turn, (crowd, f64::INFINITY), width, reach_cos);
            let center = DVec2::new(unit() * 10.0 - 5.0, unit() * 10.0 - 5.0);
            let radius = 0.005 + 0.03 * unit();
            let offset = center - DVec2::new(eye.x, eye.z);
            let distance = offset.length();
            let half = libm::asin(radius / distance);
            let reference_far = distance - radius > crowd && 2.0 * half <= width;
            let got = viewpoint.far(center, radius);
            let margin = (crowd + radius) * 1e-8;
            if (distance - radius - crowd).abs() > margin && (2.0 * half - width).abs() > 1e-9 {
                assert_eq!(got.is_some(), reference_far, "case {case}");
            }
            let Some((lo, hi, d)) = got else {
                continue;
            };
            far_ones += 1;
            assert!(lo > hi || (d - distance).abs() <= 1e-12 * distance);
            let mut middle = libm::atan2(-offset.y, offset.x) - heading;
            while middle > std::f64::consts::PI {
                middle -= std::f64::consts::TAU;
            }
            while middle <= -std::f64::consts::PI {
                middle += std::f64::consts::TAU;
            }
            let (rlo, rhi) = (middle - half, middle + half);
            let meets = rlo > -std::f64::consts::PI
                && rhi <= std::f64::consts::PI
                && rhi >= extent.0
                && rlo <= extent.1;
            if lo > hi {
                behind += 1;
                assert!(!meets || (rhi - extent.0).abs() < 1e-6 || (rlo - extent.1).abs() < 1e-6);
            } else {
                assert!(
                    (lo - rlo).abs() < 1e-7 && (hi - rhi).abs() < 1e-7,
                    "case {case}"
                );
            }
        }
        assert!(
            far_ones > 1000 && behind > 100,
            "{far_ones} far, {behind} behind"
        );
    }

    #[test]
    fn the_polynomial_atan2_is_libms_within_2e_8() {
        for i in 0..20_000 {
            let angle = -3.2 + i as f64 * 6.4 / 20_000.0;
            for r in [1e-3, 0.7, 40.0] {
                let (y, x) = (r * libm::sin(angle), r * libm::cos(angle));
                let (a, b) = (atan2(y, x), libm::atan2(y, x));
                assert!((a - b).abs() < 2e-8, "atan2({y}, {x}): {a} vs {b}");
            }
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
        let whole = |v: f64| (v - 1.0).abs() < 1e-9;
        assert!(whole(impostors[1].visible), "nearest shows whole");
        assert!(whole(impostors[3].visible), "alone shows whole");
        assert!(whole(impostors[0].visible), "beside, not behind");
        // Half behind the nearest, to within a bin (0.0015 rad) at each end.
        let half = impostors[2].visible;
        assert!((half - 0.5).abs() < 0.1, "{half}");
    }

    /// Told all around the eye, an impostor may pass ±π: hidden and hiding across it as on
    /// either side.
    #[test]
    fn an_impostor_passing_half_a_turn_hides_and_is_hidden_across_it() {
        use std::f64::consts::PI;
        let mut impostors = [
            // Nearest, across +π from 3.12 to 3.16 (−3.1232 wrapped).
            impostor(PI - 0.02, PI + 0.02, 1.0),
            // Behind it, across −π the other way: hidden.
            impostor(-PI - 0.01, -PI + 0.01, 3.0),
            // Behind it on the −π side only, half under it.
            impostor(-PI + 0.01, -PI + 0.03, 4.0),
        ];
        let (mut occlusion, mut order) = (Occlusion::default(), Vec::new());
        settle(&mut impostors, &[], &mut occlusion, &mut order);
        assert!((impostors[0].visible - 1.0).abs() < 1e-9);
        assert_eq!(impostors[1].visible, 0.0);
        let half = impostors[2].visible;
        assert!((half - 0.5).abs() < 0.1, "{half}");
        // The same scene turned away from ±π: the same shares, to within a bin.
        let mut turned = [
            impostor(-0.02, 0.02, 1.0),
            impostor(-0.01, 0.01, 3.0),
            impostor(0.01, 0.03, 4.0),
        ];
        settle(&mut turned, &[], &mut occlusion, &mut order);
        for (a, b) in impostors.iter().zip(&turned) {
            assert!(
                (a.visible - b.visible).abs() < 0.08,
                "{} vs {}",
                a.visible,
                b.visible
            );
        }
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
            tall.top = 0.5 / 2.0;
            tall
        }];
        let (mut occlusion, mut order) = (Occlusion::default(), Vec::new());
        settle(&mut impostors, &standing, &mut occlusion, &mut order);
        let whole = |v: f64| (v - 1.0).abs() < 1e-9;
        assert_eq!(impostors[0].visible, 0.0);
        assert!(whole(impostors[1].visible), "{}", impostors[1].visible);
        // A new look starts with nothing covered.
        let mut alone = [impostor(-0.01, 0.01, 2.0)];
        settle(&mut alone, &[], &mut occlusion, &mut order);
        assert!(whole(alone[0].visible));
    }

    fn standing(lo: f64, hi: f64, distance: f64, (y0, y1): (f64, f64)) -> Standing {
        Standing {
            lo,
            hi,
            distance,
            y0,
            y1,
        }
    }

    /// A box 2 m away, its foot 5 cm below the eye and its top 2 cm above it.
    const BOX: (f64, f64, f64) = (-0.05, 0.02 / 2.0, 2.0);

    #[test]
    fn kept_boxes_are_covered_by_the_union_of_nearer_standing_objects_reaching_their_top() {
        let robot = (-0.05, 0.03);
        let cover = |standing: &[Standing], interval: (f64, f64)| {
            covered_by_standing(standing, interval, BOX, -0.1)
        };
        // Two overlapping robots over [0, 0.1]: their union, once.
        let two = [
            standing(-0.3, 0.04, 0.3, robot),
            standing(0.02, 0.07, 0.4, robot),
        ];
        assert!((cover(&two, (0.0, 0.1)) - 0.07).abs() < 1e-12);
        // Farther than the box, or lower than its top in view, or a piece in the band whose
        // foot is in it too: none hides it.
        let behind = [standing(-1.0, 1.0, 3.0, robot)];
        let low = [standing(-1.0, 1.0, 0.5, (-0.05, 0.004))];
        let floating = [standing(-1.0, 1.0, 0.5, (-0.02, 0.03))];
        for hiders in [&behind[..], &low[..], &floating[..]] {
            assert_eq!(cover(hiders, (0.0, 0.1)), 0.0);
        }
        // A lamp whose foot lies below the band (its body left out) hides as if it stood.
        let lamp = [standing(-1.0, 1.0, 0.12, (-0.02, 0.02))];
        assert!((cover(&lamp, (0.0, 0.1)) - 0.1).abs() < 1e-12);
        // A box passing +π meets what lies just past −π.
        let past = [standing(-3.13, -3.0, 0.3, robot)];
        let (lo, hi) = (3.1, 3.2);
        let expected = hi - (-3.13 + std::f64::consts::TAU);
        assert!((cover(&past, (lo, hi)) - expected).abs() < 1e-12);
    }

    #[test]
    fn near_sectors_never_miss_a_standing_object_that_covers_a_box() {
        let mut unit = crate::test_random::unit_stream(41);
        let pi = std::f64::consts::PI;
        for _ in 0..2_000 {
            let hiders: Vec<Standing> = (0..(unit() * 8.0) as usize)
                .map(|_| {
                    let middle = (unit() * 2.0 - 1.0) * pi;
                    let half = unit() * 0.4;
                    standing(
                        (middle - half).max(-pi),
                        (middle + half).min(pi),
                        0.3,
                        (-0.05, 0.03),
                    )
                })
                .collect();
            let sectors = NearSectors::of(&hiders);
            let middle = (unit() * 2.0 - 1.0) * pi;
            let interval = (middle - 0.03, middle + 0.03);
            if covered_by_standing(&hiders, interval, BOX, -0.1) > 0.0 {
                assert!(sectors.may_meet(interval.0, interval.1), "{interval:?}");
            }
        }
        assert!(!NearSectors::of(&[]).may_meet(-0.1, 0.1));
        // An interval that is not a number meets every sector a standing object meets.
        let one = [standing(2.0, 2.1, 0.3, (-0.05, 0.03))];
        assert!(NearSectors::of(&one).may_meet(f64::NAN, 0.1));
    }
}
