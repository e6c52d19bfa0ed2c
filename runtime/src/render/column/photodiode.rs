//! Photodiode integration: one column's segments composited front to back and integrated
//! exactly in angle over the elevation band (`Band`, `Free`), and the piecewise-linear model of
//! the band's mean across azimuth integrated over each photodiode's window (`Raster`). The
//! small numerical helpers they share live here too.

use glam::{DVec2, DVec3};

use super::shading::Shades;
use super::strip::Strip;

/// The part of a column an object covers.
#[derive(Clone, Copy, Debug)]
pub(super) struct Segment {
    pub(super) depth: f64,
    /// tan-elevation interval.
    pub(super) t0: f64,
    pub(super) t1: f64,
    /// The look's object (ties in depth go by it) and the primitive it shows.
    pub(super) object: u32,
    pub(super) primitive: u32,
    pub(super) face: Face,
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Face {
    /// A vertical face with this horizontal normal.
    Side(DVec2),
    /// A horizontal face at height `y`, facing up or down.
    Cap { y: f64, up: bool },
}

/// Integrates linear pieces of a function of azimuth over contiguous pixel windows of equal
/// width, pixel 0 starting at `origin` and azimuth falling with the index.
pub(super) struct Raster<'a> {
    pub(super) origin: f64,
    pub(super) inverse_width: f64,
    pub(super) width: f64,
    pub(super) out: &'a mut [f64],
}

impl<'a> Raster<'a> {
    /// A raster over the first `out.len()` windows (at least one) of the contiguous `strip`,
    /// and the relative azimuths those windows cover, lowest and highest.
    pub(super) fn over(strip: &Strip, out: &'a mut [f64]) -> (Raster<'a>, (f64, f64)) {
        let width = strip.width;
        let extent_hi = strip.centers[0] + width / 2.0;
        let extent_lo = strip.centers[out.len() - 1] - width / 2.0;
        let raster = Raster {
            origin: extent_hi,
            inverse_width: 1.0 / width,
            width,
            out,
        };
        (raster, (extent_lo, extent_hi))
    }
}

impl Raster<'_> {
    /// Adds the mean over each pixel window of `value + slope·(α − x0)` on `[x0, x1]`.
    #[inline]
    pub(super) fn add(&mut self, x0: f64, x1: f64, value: f64, slope: f64) {
        // α = origin − u·width, so the line is value + slope_u·(u1 − u), slope_u = slope·width.
        // A level piece (most: a region sampled once) leaves the line's slope terms out: they
        // add a zero to each value, and pixels summed from +0 take the same bits. Told once
        // here, not at each of the pixels it changes.
        let slope_u = slope * self.width;
        if slope_u == 0.0 {
            self.add_line::<true>(x0, x1, value, slope_u);
        } else {
            self.add_line::<false>(x0, x1, value, slope_u);
        }
    }

    /// [`Raster::add`] of the line of slope `slope_u` in pixel units, `LEVEL` where that is 0.
    #[inline(always)]
    fn add_line<const LEVEL: bool>(&mut self, x0: f64, x1: f64, value: f64, slope_u: f64) {
        // In pixel units u = (origin − α)/width, pixel i covering [i, i + 1].
        let (u0, u1) = (
            (self.origin - x1) * self.inverse_width,
            (self.origin - x0) * self.inverse_width,
        );
        if u1 <= u0 {
            return;
        }
        let pixels = self.out.len();
        let first = index_below(u0, pixels);
        // ⌈u1⌉ without a libm call: u1 > 0 here (u1 > u0, and a piece left of the strip
        // ends at u1 ≤ 0 only when empty below).
        let whole = index_below(u1, pixels);
        let last = (whole + (u1 > whole as i64 as f64) as usize).min(pixels);
        if first >= last {
            return;
        }
        // Windows the piece covers whole take the line's value at their centre; the one or
        // two it covers in part, the mean over the part times its share.
        let partial = |i: usize| {
            let i = i as i64 as f64;
            let (a, b) = (larger(u0, i), smaller(u1, i + 1.0));
            if b > a {
                if LEVEL {
                    (b - a) * value
                } else {
                    (b - a) * (value + slope_u * (u1 - 0.5 * (a + b)))
                }
            } else {
                0.0
            }
        };
        self.out[first] += partial(first);
        if last - first == 1 {
            return;
        }
        self.out[last - 1] += partial(last - 1);
        // Each centre read from a table (the same exact value as `i + 0.5`): no conversion
        // per pixel, and a running `center += 1` would chain every pixel's add behind the last
        // one's. Longer strips than the table convert the index (32-bit: packed i32 → f64
        // conversion exists on every x86-64, i64 → f64 does not; strips are far shorter than
        // 2³¹ pixels).
        let whole = &mut self.out[first + 1..last - 1];
        if LEVEL {
            whole.iter_mut().for_each(|out| *out += value);
            return;
        }
        match PIXEL_MIDDLES.get(first + 1..last - 1) {
            Some(middles) => {
                for (out, &center) in whole.iter_mut().zip(middles) {
                    *out += value + slope_u * (u1 - center);
                }
            }
            None => {
                let base = (first + 1) as i32;
                for (k, out) in whole.iter_mut().enumerate() {
                    let center = (base + k as i32) as f64 + 0.5;
                    *out += value + slope_u * (u1 - center);
                }
            }
        }
    }
}

impl Raster<'_> {
    /// [`Raster::add`] of a flat piece (`slope` 0), the same sums: a piece no wider than a
    /// pixel and within the strip (a kept box, most of them) meets one or two pixels, added
    /// without the general case's clamps and loop (a crowd's eye draws some thirty a update).
    #[inline]
    pub(super) fn add_flat(&mut self, x0: f64, x1: f64, value: f64) {
        let (u0, u1) = (
            (self.origin - x1) * self.inverse_width,
            (self.origin - x0) * self.inverse_width,
        );
        // A NaN fails every test and goes the general way.
        if u0 >= 0.0 && u1 > u0 && u1 - u0 <= 1.0 && u1 <= self.out.len() as i64 as f64 {
            // u0 ≥ 0: the conversion floors; u0 < u1 ≤ pixels keeps `first` in the strip,
            // and a piece reaching past `split` keeps `first + 1` in it too.
            let first = u0 as usize;
            let split = (first + 1) as i64 as f64;
            // Both pixels, without a branch on whether the piece reaches the second (half of
            // them do, at random): a piece within the first adds (split − split)·value, a zero,
            // to the second, and a pixel, summed from +0, is never −0, so that changes no bit.
            if let Some(left) = self.out.get_mut(first) {
                *left += (smaller(u1, split) - u0) * value;
            }
            if let Some(right) = self.out.get_mut(first + 1) {
                *right += (larger(u1, split) - split) * value;
            }
            return;
        }
        self.add(x0, x1, value, 0.0);
    }
}

/// `i + 0.5`, the centre of pixel `i` in pixel units, for strips of up to 256 pixels.
static PIXEL_MIDDLES: [f64; 256] = {
    let mut middles = [0.0; 256];
    let mut i = 0;
    while i < middles.len() {
        middles[i] = i as f64 + 0.5;
        i += 1;
    }
    middles
};

/// Odd polynomial atan for |t| ≲ 0.2 (exact to ~1e-10 within the retina's band); plain
/// `libm::atan` beyond.
#[inline]
pub(super) fn band_atan(t: f64) -> f64 {
    if t.abs() > 0.2 {
        return libm::atan(t);
    }
    // Reciprocals as constants: multiplications, no division on the hot path.
    const C3: f64 = 1.0 / 3.0;
    const C5: f64 = 1.0 / 5.0;
    const C7: f64 = 1.0 / 7.0;
    const C9: f64 = 1.0 / 9.0;
    const C11: f64 = 1.0 / 11.0;
    let t2 = t * t;
    t * (1.0 - t2 * (C3 - t2 * (C5 - t2 * (C7 - t2 * (C9 - t2 * C11)))))
}

/// `(cos, sin)` of `base + delta` from those of `base`, for small `delta` (|δ| ≤ a pixel).
#[inline]
pub(super) fn rotate_small(cos_base: f64, sin_base: f64, delta: f64) -> (f64, f64) {
    const HALF: f64 = 0.5;
    const TWELFTH: f64 = 1.0 / 12.0;
    const THIRTIETH: f64 = 1.0 / 30.0;
    const SIXTH: f64 = 1.0 / 6.0;
    const TWENTIETH: f64 = 1.0 / 20.0;
    const FORTY_SECOND: f64 = 1.0 / 42.0;
    let d2 = delta * delta;
    let c = 1.0 - d2 * HALF * (1.0 - d2 * TWELFTH * (1.0 - d2 * THIRTIETH));
    let s = delta * (1.0 - d2 * SIXTH * (1.0 - d2 * TWENTIETH * (1.0 - d2 * FORTY_SECOND)));
    (cos_base * c - sin_base * s, sin_base * c + cos_base * s)
}

/// `(x.round().max(0.0) as usize).min(limit)` without a call to the C library's `round`
/// (which the baseline x86-64 target has no instruction for): halves round up, negatives and
/// NaN give 0.
#[inline]
pub(super) fn nearest_index(x: f64, limit: usize) -> usize {
    let whole = index_below(x, limit);
    (whole + (x - whole as i64 as f64 >= 0.5) as usize).min(limit)
}

/// `(x.max(0.0) as usize).min(limit)`, `x` truncated, for limits below 2⁶² (a strip's
/// pixels): clamped in floating point first, so one signed conversion does (an unsigned one
/// costs a dozen instructions on x86-64). NaN gives 0. Indices go back to floating point
/// through `i64` likewise (`as i64 as f64`: one instruction, where `usize as f64` takes five;
/// the same value for any index).
#[inline(always)]
pub(super) fn index_below(x: f64, limit: usize) -> usize {
    // Below 2⁶², whatever the limit: the conversion then has nothing to saturate.
    const TOP: f64 = (1u64 << 62) as f64;
    let top = smaller(limit as i64 as f64, TOP);
    let clamped = if x > 0.0 { smaller(x, top) } else { 0.0 };
    // SAFETY: `clamped` is 0 or at most `top`, and at least `limit as i64` (≥ −2⁶³) where that
    // is negative: never NaN, and within i64's range. The checked `as i64` would spend five
    // instructions a call on a saturation that cannot happen (Raster::add converts twice a
    // piece, each sampled column once).
    unsafe { clamped.to_int_unchecked::<i64>() as usize }
}

/// `x`'s place in [`f64::total_cmp`]'s order, as an unsigned integer.
#[inline(always)]
pub(super) fn total_key(x: f64) -> u64 {
    let bits = x.to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | 1 << 63
    }
}

/// The number whose [`total_key`] is `key`.
#[inline(always)]
pub(super) fn from_total_key(key: u64) -> f64 {
    if key >> 63 == 1 {
        f64::from_bits(key & !(1 << 63))
    } else {
        f64::from_bits(!key)
    }
}

/// The larger of two numbers, by one compare: `f64::max` also settles NaN, at a cost on the
/// hot paths, and none arises there (finite geometry; a NaN here picks `b`).
#[inline(always)]
pub(super) fn larger(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The smaller of two numbers, by one compare (see [`larger`]).
#[inline(always)]
pub(super) fn smaller(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// Most segments one column keeps; beyond, the farthest are dropped (they are the most
/// likely hidden).
pub(super) const MAX_SEGMENTS: usize = 32;

/// A column's segments on the stack, with their order by depth kept on insertion (indices
/// move, not segments).
pub(super) struct Segments {
    pub(super) items: [Segment; MAX_SEGMENTS],
    /// Indices into `items`, front to back.
    pub(super) order: [u8; MAX_SEGMENTS],
    pub(super) len: usize,
}

impl Segments {
    pub(super) fn new() -> Segments {
        Segments {
            items: [Segment {
                depth: 0.0,
                t0: 0.0,
                t1: 0.0,
                object: 0,
                primitive: 0,
                face: Face::Cap { y: 0.0, up: true },
            }; MAX_SEGMENTS],
            order: [0; MAX_SEGMENTS],
            len: 0,
        }
    }

    #[inline]
    pub(super) fn insert(&mut self, segment: Segment) {
        let mut i = self.len;
        while i > 0 && {
            let before = &self.items[self.order[i - 1] as usize];
            before.depth > segment.depth
                || (before.depth == segment.depth && before.object > segment.object)
        } {
            i -= 1;
        }
        if i >= MAX_SEGMENTS {
            return;
        }
        // When full, the farthest segment's slot takes the new one.
        let slot = if self.len < MAX_SEGMENTS {
            self.len
        } else {
            self.order[MAX_SEGMENTS - 1] as usize
        };
        let end = self.len.min(MAX_SEGMENTS - 1);
        self.order.copy_within(i..end, i + 1);
        self.order[i] = slot as u8;
        self.items[slot] = segment;
        self.len = (self.len + 1).min(MAX_SEGMENTS);
    }

    /// The segments front to back.
    pub(super) fn iter(&self) -> impl Iterator<Item = &Segment> {
        self.order[..self.len]
            .iter()
            .map(|&slot| &self.items[slot as usize])
    }
}

/// Per-column buffers, allocated once per strip.
pub(super) struct Scratch {
    pub(super) segments: Segments,
    pub(super) lit: LitSegments,
    pub(super) free: Free,
}

/// Where [`ColumnScene::collect_segments`] puts a column's segments.
pub(super) trait SegmentSink {
    fn insert(&mut self, segment: Segment);
}

impl SegmentSink for Segments {
    #[inline(always)]
    fn insert(&mut self, segment: Segment) {
        Segments::insert(self, segment)
    }
}

/// A segment whose face's luminance is known (fast shading).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Lit {
    pub(super) depth: f64,
    pub(super) t0: f64,
    pub(super) t1: f64,
    pub(super) luminance: f64,
    /// The look's object: ties in depth go by it.
    pub(super) object: u32,
}

impl Extent for Lit {
    #[inline]
    fn extent(&self) -> (f64, f64) {
        (self.t0, self.t1)
    }

    #[inline]
    fn depth(&self) -> f64 {
        self.depth
    }
}

impl Extent for Segment {
    #[inline]
    fn extent(&self) -> (f64, f64) {
        (self.t0, self.t1)
    }

    #[inline]
    fn depth(&self) -> f64 {
        self.depth
    }
}

/// A column's lit segments on the stack, sorted front to back on insertion, equal depths by
/// object (an object's own segments in the order they come), as in [`Segments`]: the order
/// and the segments kept do not depend on the order the objects come in. The sweep hands
/// them nearest first, so that most insertions move nothing.
pub(super) struct LitSegments {
    pub(super) items: [Lit; MAX_SEGMENTS],
    pub(super) len: usize,
}

impl LitSegments {
    pub(super) fn new() -> LitSegments {
        LitSegments {
            items: [Lit::default(); MAX_SEGMENTS],
            len: 0,
        }
    }

    #[inline]
    pub(super) fn insert(&mut self, segment: Lit) {
        let behind = |before: &Lit| {
            before.depth > segment.depth
                || (before.depth == segment.depth && before.object > segment.object)
        };
        let mut i = self.len;
        if i == MAX_SEGMENTS {
            // Full: the farthest goes, unless the new one is farther still.
            if !behind(&self.items[i - 1]) {
                return;
            }
            i -= 1;
        } else {
            self.len += 1;
        }
        // Shifted one by one: a few moves, no call to memmove.
        while i > 0 && behind(&self.items[i - 1]) {
            self.items[i] = self.items[i - 1];
            i -= 1;
        }
        self.items[i] = segment;
    }

    pub(super) fn as_slice(&self) -> &[Lit] {
        &self.items[..self.len]
    }
}

/// Lights each segment as it comes, from its object's fast shading.
pub(super) struct LitSink<'a> {
    pub(super) lit: &'a mut LitSegments,
    pub(super) shades: &'a Shades,
}

impl SegmentSink for LitSink<'_> {
    #[inline(always)]
    fn insert(&mut self, segment: Segment) {
        let Some(fast) = self.shades.get(segment.primitive) else {
            return;
        };
        let luminance = match segment.face {
            Face::Side(n) => fast.luminance(DVec3::new(n.x, 0.0, n.y)),
            Face::Cap { up: true, .. } => fast.up_luminance,
            Face::Cap { up: false, .. } => fast.down_luminance,
        };
        self.lit.insert(Lit {
            depth: segment.depth,
            t0: segment.t0,
            t1: segment.t1,
            luminance,
            object: segment.object,
        });
    }
}

/// A segment's tan-elevation interval and depth.
pub(super) trait Extent {
    fn extent(&self) -> (f64, f64);
    fn depth(&self) -> f64;
}

/// What one column shows over a tan-elevation interval: the depth of the face there
/// (infinite: the sky or the ground) and its luminance.
#[derive(Clone, Copy, Debug)]
pub(super) struct Shown {
    pub(super) t0: f64,
    pub(super) t1: f64,
    /// The angle of `t0` ([`Band::angle`]), and the luminance integrated in angle from the
    /// band's lower edge up to it: a face in front of a run of pieces replaces their
    /// integral, read at its two ends (`far.rs`).
    pub(super) a0: f64,
    pub(super) sum0: f64,
    pub(super) depth: f64,
    pub(super) luminance: f64,
}

/// Most visible parts one face keeps track of in [`Band::profile`] and [`Band::effect`].
const PARTS: usize = 8;

/// The elevation band of a column and what lies beyond every object.
pub(super) struct Band {
    pub(super) tan_half: f64,
    /// The band's angle, 2·atan(tan_half).
    pub(super) band: f64,
    pub(super) sky: f64,
    pub(super) ground: f64,
}

impl Band {
    /// The angle of tan-elevation `x` within the band (the band's edges and the horizon
    /// exactly, as [`Band::composite`] takes them).
    #[inline]
    pub(super) fn angle(&self, x: f64) -> f64 {
        if x == self.tan_half {
            0.5 * self.band
        } else if x == -self.tan_half {
            -0.5 * self.band
        } else if x == 0.0 {
            0.0
        } else {
            band_atan(x)
        }
    }

    /// What a column of segments sorted front to back shows, appended to `out` as pieces in
    /// tan-elevation order covering the band, each visible part of a face with the luminance
    /// [`Band::composite`] gives it; returns the band's mean, [`Band::composite`]'s to the last
    /// bit (the same sums in the same order).
    pub(super) fn profile<'s, S: Extent + 's>(
        &self,
        segments: impl IntoIterator<Item = &'s S>,
        free: &mut Free,
        mut luminance: impl FnMut(&S, f64, f64) -> f64,
        out: &mut Vec<Shown>,
    ) -> f64 {
        let start = out.len();
        free.reset(
            (-self.tan_half, self.tan_half),
            (-0.5 * self.band, 0.5 * self.band),
        );
        let mut sum = 0.0;
        for segment in segments {
            if free.is_empty() {
                break;
            }
            let (t0, t1) = segment.extent();
            let (a, b) = (larger(t0, -self.tan_half), smaller(t1, self.tan_half));
            if a >= b {
                continue;
            }
            let first = out.len();
            let (mut covered, mut middle) = (0.0, 0.0);
            free.take(
                a,
                b,
                |x| self.angle(x),
                |Span { x0, x1, a0, a1 }| {
                    let weight = a1 - a0;
                    middle += 0.5 * (x0 + x1) * weight;
                    covered += weight;
                    out.push(Shown {
                        t0: x0,
                        t1: x1,
                        a0,
                        sum0: 0.0,
                        depth: segment.depth(),
                        luminance: 0.0,
                    });
                },
            );
            if covered > 0.0 {
                let value = luminance(segment, middle, covered);
                sum += value * covered;
                for shown in &mut out[first..] {
                    shown.luminance = value;
                }
            } else {
                out.truncate(first);
            }
        }
        for &Span { x0, x1, a0, a1 } in free.as_slice() {
            let mut background = |(t0, a0): (f64, f64), t1: f64, luminance: f64| {
                out.push(Shown {
                    t0,
                    t1,
                    a0,
                    sum0: 0.0,
                    depth: f64::INFINITY,
                    luminance,
                })
            };
            if x0 >= 0.0 {
                sum += self.sky * (a1 - a0);
                background((x0, a0), x1, self.sky);
            } else if x1 <= 0.0 {
                sum += self.ground * (a1 - a0);
                background((x0, a0), x1, self.ground);
            } else {
                sum += self.ground * -a0 + self.sky * a1;
                background((x0, a0), 0.0, self.ground);
                background((0.0, 0.0), x1, self.sky);
            }
        }
        // A few dozen pieces at most, mostly in order: insertion.
        let pieces = &mut out[start..];
        for i in 1..pieces.len() {
            let piece = pieces[i];
            let mut j = i;
            while j > 0 && pieces[j - 1].t0 > piece.t0 {
                pieces[j] = pieces[j - 1];
                j -= 1;
            }
            pieces[j] = piece;
        }
        // The pieces tile the band: each one's integral runs up to the next one's start.
        let mut integral = 0.0;
        for k in 0..pieces.len() {
            pieces[k].sum0 = integral;
            let a1 = pieces.get(k + 1).map_or(0.5 * self.band, |next| next.a0);
            integral += pieces[k].luminance * (a1 - pieces[k].a0);
        }
        sum / self.band
    }

    /// The change in a column's mean luminance over the band when `segments` (sorted front to
    /// back: an impostor's faces) join what `profile` shows: where a face is the nearest, its
    /// luminance replaces what showed there.
    pub(super) fn effect<'s, S: Extent + 's>(
        &self,
        profile: &[Shown],
        segments: impl IntoIterator<Item = &'s S>,
        free: &mut Free,
        mut luminance: impl FnMut(&S, f64, f64) -> f64,
    ) -> f64 {
        // Its parts' angles are those of the profile's pieces they meet: the free parts' are
        // not read (left 0).
        free.reset((-self.tan_half, self.tan_half), (0.0, 0.0));
        let mut sum = 0.0;
        for segment in segments {
            let (t0, t1) = segment.extent();
            let (a, b) = (larger(t0, -self.tan_half), smaller(t1, self.tan_half));
            if a >= b || free.is_empty() {
                continue;
            }
            let depth = segment.depth();
            // The parts its own nearer faces leave, each split where the profile shows
            // something nearer (kept) or farther (replaced).
            let mut parts = [(0.0, 0.0); PARTS];
            let mut count = 0;
            free.take(
                a,
                b,
                |_| 0.0,
                |part| {
                    if count < PARTS {
                        parts[count] = (part.x0, part.x1);
                        count += 1;
                    }
                },
            );
            let (mut covered, mut middle) = (0.0, 0.0);
            let mut replaced = 0.0;
            for &(x0, x1) in &parts[..count] {
                let start = profile.partition_point(|p| p.t1 <= x0);
                for p in &profile[start..] {
                    if p.t0 >= x1 {
                        break;
                    }
                    if p.depth <= depth {
                        continue;
                    }
                    let (c0, c1) = (larger(x0, p.t0), smaller(x1, p.t1));
                    if c1 > c0 {
                        let weight = self.angle(c1) - self.angle(c0);
                        middle += 0.5 * (c0 + c1) * weight;
                        covered += weight;
                        replaced += p.luminance * weight;
                    }
                }
            }
            if covered > 0.0 {
                sum += luminance(segment, middle, covered) * covered - replaced;
            }
        }
        sum / self.band
    }

    /// [`Band::composite`] of a column with one segment (most columns of an arena: a wall),
    /// `extent` and `luminance` its: the band's one free span cut where the segment meets it,
    /// the same sums in the same order to the last bit, without the free list. `None` where
    /// the clamped ends are NaN (a NaN band): the general way settles it.
    #[inline]
    pub(super) fn composite_one(&self, (t0, t1): (f64, f64), luminance: f64) -> Option<f64> {
        let Band {
            tan_half,
            band,
            sky,
            ground,
        } = *self;
        let half_band = 0.5 * band;
        let (a, b) = (larger(t0, -tan_half), smaller(t1, tan_half));
        if a.is_nan() || b.is_nan() {
            return None;
        }
        // What a free span adds, as `composite`'s last loop has it.
        let free = |x0: f64, x1: f64, a0: f64, a1: f64| {
            if x0 >= 0.0 {
                sky * (a1 - a0)
            } else if x1 <= 0.0 {
                ground * (a1 - a0)
            } else {
                ground * -a0 + sky * a1
            }
        };
        let mut sum = 0.0;
        if a >= b {
            sum += free(-tan_half, tan_half, -half_band, half_band);
            return Some(sum / band);
        }
        // The free span (−T, T) taken over [a, b]: cut below and above where they lie inside.
        let (cut_below, cut_above) = (-tan_half < a, b < tan_half);
        let a0 = if cut_below { self.angle(a) } else { -half_band };
        let a1 = if cut_above { self.angle(b) } else { half_band };
        let covered = 0.0 + (a1 - a0);
        if covered > 0.0 {
            sum += luminance * covered;
        }
        if cut_below {
            sum += free(-tan_half, a, -half_band, a0);
        }
        if cut_above {
            sum += free(b, tan_half, a1, half_band);
        }
        Some(sum / band)
    }

    /// Mean luminance over the band of segments sorted front to back, integrated exactly in
    /// angle; `luminance(segment, middle, covered)` gives a face's luminance from the visible
    /// parts' angle-weighted tan-elevation sum and their angle.
    #[inline]
    pub(super) fn composite<'s, S: Extent + 's>(
        &self,
        segments: impl IntoIterator<Item = &'s S>,
        free: &mut Free,
        mut luminance: impl FnMut(&S, f64, f64) -> f64,
    ) -> f64 {
        let Band {
            tan_half,
            band,
            sky,
            ground,
        } = *self;
        // The band's edges and the horizon are where most pieces start or end: their angles
        // are known (band_atan is odd, band = 2·band_atan(T)).
        let half_band = 0.5 * band;
        free.reset((-tan_half, tan_half), (-half_band, half_band));
        let angle = |x: f64| {
            if x == tan_half {
                half_band
            } else if x == -tan_half {
                -half_band
            } else if x == 0.0 {
                0.0
            } else {
                band_atan(x)
            }
        };
        let mut sum = 0.0;
        for segment in segments {
            if free.is_empty() {
                break;
            }
            let (t0, t1) = segment.extent();
            let (a, b) = (larger(t0, -tan_half), smaller(t1, tan_half));
            if a >= b {
                continue;
            }
            let mut covered = 0.0;
            let mut middle = 0.0;
            free.take(a, b, angle, |part| {
                let weight = part.a1 - part.a0;
                middle += 0.5 * (part.x0 + part.x1) * weight;
                covered += weight;
            });
            if covered > 0.0 {
                // One radiance per visible part of a face, at its weighted middle.
                sum += luminance(segment, middle, covered) * covered;
            }
        }
        for &Span { x0, x1, a0, a1 } in free.as_slice() {
            // Sky above the horizon, ground (if any) below.
            if x0 >= 0.0 {
                sum += sky * (a1 - a0);
            } else if x1 <= 0.0 {
                sum += ground * (a1 - a0);
            } else {
                sum += ground * -a0 + sky * a1;
            }
        }
        sum / band
    }
}

/// One free part of a band: its tan-elevation ends and their angles ([`Band::angle`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Span {
    pub(super) x0: f64,
    pub(super) x1: f64,
    pub(super) a0: f64,
    pub(super) a1: f64,
}

/// Free (uncovered) tan-intervals of a band, sorted and disjoint, on the stack. Each segment
/// splits at most one interval, so MAX_SEGMENTS + 1 always suffices. Each end keeps its
/// angle: an end a nearer face cut is worked out once, not again by the face, sky or ground
/// that later fills what it left (the arctangent is most of a column's arithmetic).
pub(super) struct Free {
    pub(super) items: [Span; MAX_SEGMENTS + 1],
    pub(super) len: usize,
}

impl Free {
    pub(super) fn new() -> Free {
        Free {
            items: [Span::default(); MAX_SEGMENTS + 1],
            len: 0,
        }
    }

    /// The whole band `[lo, hi]` free, its ends' angles `(a_lo, a_hi)`.
    pub(super) fn reset(&mut self, (lo, hi): (f64, f64), (a_lo, a_hi): (f64, f64)) {
        self.items[0] = Span {
            x0: lo,
            x1: hi,
            a0: a_lo,
            a1: a_hi,
        };
        self.len = 1;
    }

    pub(super) fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub(super) fn as_slice(&self) -> &[Span] {
        &self.items[..self.len]
    }

    /// Removes `[a, b]`, calling `visit` on each free part it covered; `angle` gives the angle
    /// of an end where `[a, b]` cuts a free part (a caller that reads no angle may give any).
    #[inline]
    pub(super) fn take(
        &mut self,
        a: f64,
        b: f64,
        angle: impl Fn(f64) -> f64,
        mut visit: impl FnMut(Span),
    ) {
        // The intervals wholly below `a` are skipped by halving (a crowd's column leaves a
        // long list: each robot further away peeks over the nearer ones).
        let mut i = if self.len > 8 {
            self.items[..self.len].partition_point(|span| span.x1 <= a)
        } else {
            0
        };
        while i < self.len {
            let span = self.items[i];
            if span.x1 <= a {
                i += 1;
                continue;
            }
            if span.x0 >= b {
                break;
            }
            let (c0, c1) = (larger(span.x0, a), smaller(span.x1, b));
            let (cut_below, cut_above) = (span.x0 < c0, c1 < span.x1);
            let covered = Span {
                x0: c0,
                x1: c1,
                a0: if cut_below { angle(c0) } else { span.a0 },
                a1: if cut_above { angle(c1) } else { span.a1 },
            };
            visit(covered);
            let below = Span {
                x1: c0,
                a1: covered.a0,
                ..span
            };
            let above = Span {
                x0: c1,
                a0: covered.a1,
                ..span
            };
            match (cut_below, cut_above) {
                (true, true) => {
                    // Split in two; the few intervals after it shift one by one (no memmove).
                    if self.len < self.items.len() {
                        let mut j = self.len;
                        while j > i + 1 {
                            self.items[j] = self.items[j - 1];
                            j -= 1;
                        }
                        self.items[i] = below;
                        self.items[i + 1] = above;
                        self.len += 1;
                    } else {
                        self.items[i] = below;
                    }
                    return;
                }
                (true, false) => {
                    self.items[i] = below;
                    i += 1;
                }
                (false, true) => {
                    self.items[i] = above;
                    return;
                }
                (false, false) => {
                    for j in i..self.len - 1 {
                        self.items[j] = self.items[j + 1];
                    }
                    self.len -= 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_atan_matches_libm() {
        for i in -100..=100 {
            let t = i as f64 * 0.002;
            assert!((band_atan(t) - libm::atan(t)).abs() < 1e-10, "{t}");
        }
    }

    #[test]
    fn nearest_index_rounds_like_round() {
        for x in [
            -2.5,
            -0.5,
            -0.2,
            0.0,
            0.2,
            0.5,
            0.7,
            1.5,
            2.4999,
            2.5,
            149.5,
            1e30,
            f64::NAN,
        ] {
            for limit in [0, 1, 149, 1 << 40] {
                let expected = ((x.round().max(0.0)) as usize).min(limit);
                assert_eq!(nearest_index(x, limit), expected, "{x} {limit}");
                let expected = (x.max(0.0) as usize).min(limit);
                assert_eq!(index_below(x, limit), expected, "{x} {limit}");
            }
        }
    }

    /// The flat fast path gives the general add's sums to the bit: pieces narrower and wider
    /// than a pixel, on pixel edges, and reaching past either end of the strip.
    #[test]
    fn a_flat_piece_adds_what_the_general_add_does() {
        let mut unit = crate::test_random::unit_stream(11);
        let (width, pixels) = (0.0279, 12);
        let origin = 0.5 * width * pixels as f64;
        for case in 0..20_000 {
            let centre = (unit() - 0.5) * width * (pixels as f64 + 4.0);
            let half = unit() * width * if case % 3 == 0 { 2.0 } else { 0.6 };
            let (mut x0, mut x1) = (centre - half, centre + half);
            if case % 7 == 0 {
                // Ends on pixel edges.
                x0 = origin - width * (unit() * pixels as f64).floor();
                x1 = x0 + width * if case % 2 == 0 { 1.0 } else { 0.5 };
            }
            let value = unit() - 0.3;
            let mut general = vec![0.25; pixels];
            let mut flat = general.clone();
            let raster = |out| Raster {
                origin,
                inverse_width: 1.0 / width,
                width,
                out,
            };
            raster(&mut general).add(x0, x1, value, 0.0);
            raster(&mut flat).add_flat(x0, x1, value);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&flat), bits(&general), "{x0} {x1} {value}");
        }
    }

    /// One segment composited alone gives the general composite's bits: segments within,
    /// across, at and beyond the band's edges and the horizon, infinite, empty and NaN ends.
    #[test]
    fn one_segment_composites_as_the_general_way_does() {
        let mut unit = crate::test_random::unit_stream(13);
        let tan_half = 0.0963;
        let band = Band {
            tan_half,
            band: 2.0 * band_atan(tan_half),
            sky: 0.013,
            ground: 0.41,
        };
        let special = [
            0.0,
            -0.0,
            tan_half,
            -tan_half,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            2.0 * tan_half,
            -2.0 * tan_half,
        ];
        let pick = |unit: &mut dyn FnMut() -> f64| {
            if unit() < 0.3 {
                special[(unit() * special.len() as f64) as usize % special.len()]
            } else {
                (unit() * 2.0 - 1.0) * 1.5 * tan_half
            }
        };
        let mut free = Free::new();
        let (mut fast, mut nan) = (0, 0);
        for _ in 0..50_000 {
            let (t0, t1) = (pick(&mut unit), pick(&mut unit));
            let luminance = unit();
            let lit = Lit {
                depth: 1.0,
                t0,
                t1,
                luminance,
                object: 0,
            };
            let general = band.composite([&lit], &mut free, |s, _, _| s.luminance);
            match band.composite_one((t0, t1), luminance) {
                Some(one) => {
                    assert_eq!(one.to_bits(), general.to_bits(), "{t0} {t1}");
                    fast += 1;
                }
                None => {
                    assert!(t0.is_nan() || t1.is_nan(), "{t0} {t1}");
                    nan += 1;
                }
            }
        }
        // A NaN end is clamped to the band's edge (`larger`, `smaller`), as the general way
        // clamps it: every case goes the fast way.
        assert_eq!((fast, nan), (50_000, 0));
    }

    /// A level piece (slope 0, or −0) adds the bits the line's formula gives with its slope
    /// terms kept: every piece, values of both signs and ±0, pixels from +0 or not.
    #[test]
    fn a_level_piece_adds_what_the_sloped_formula_gives() {
        let mut unit = crate::test_random::unit_stream(12);
        let (width, pixels) = (0.0279, 12);
        let origin = 0.5 * width * pixels as f64;
        for case in 0..20_000 {
            let centre = (unit() - 0.5) * width * (pixels as f64 + 4.0);
            let half = unit() * width * if case % 3 == 0 { 8.0 } else { 2.0 };
            let (x0, x1) = (centre - half, centre + half);
            let value = match case % 5 {
                0 => 0.0,
                1 => -0.0,
                _ => unit() - 0.3,
            };
            let slope = if case % 2 == 0 { 0.0 } else { -0.0 };
            let start = if case % 4 == 0 { 0.0 } else { 0.25 };
            let mut level = vec![start; pixels];
            Raster {
                origin,
                inverse_width: 1.0 / width,
                width,
                out: &mut level,
            }
            .add(x0, x1, value, slope);
            // The formula, pixel by pixel.
            let mut formula = vec![start; pixels];
            let inverse_width = 1.0 / width;
            let (u0, u1) = ((origin - x1) * inverse_width, (origin - x0) * inverse_width);
            let slope_u = slope * width;
            let first = index_below(u0, pixels);
            let whole = index_below(u1, pixels);
            let last = (whole + (u1 > whole as f64) as usize).min(pixels);
            for i in first..last {
                let (a, b) = (larger(u0, i as f64), smaller(u1, i as f64 + 1.0));
                formula[i] += if i == first || i + 1 == last {
                    if b > a {
                        (b - a) * (value + slope_u * (u1 - 0.5 * (a + b)))
                    } else {
                        0.0
                    }
                } else {
                    value + slope_u * (u1 - (i as f64 + 0.5))
                };
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&level), bits(&formula), "{x0} {x1} {value}");
        }
    }

    #[test]
    fn small_rotation_matches_libm() {
        let base = 0.7f64;
        for i in -10..=10 {
            let d = i as f64 * 0.0014;
            let (c, s) = rotate_small(libm::cos(base), libm::sin(base), d);
            assert!(
                (c - libm::cos(base + d)).abs() < 1e-14 && (s - libm::sin(base + d)).abs() < 1e-14
            );
        }
    }
}
