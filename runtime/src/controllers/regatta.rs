//! The `regatta` controller: the paper's controller: the Braitenberg network plus light
//! seeking. The odd filter's output is scanned for light-intensity maxima (a negative lobe
//! followed by a positive one, both beyond `minContrast` LSB); the maximum nearest the centre
//! of the retina steers the robot by `lightGain` pulses/10 ms per pixel of distance from the
//! centre, added to the network's output. A robot that stalls facing an obstacle turns away
//! ([`super::escape`]). Every time here is in seconds and becomes a number of controller
//! calls through the control period the controller is built with, so the robot behaves the
//! same at any physics step.
//!
//! Habituation: a robot that has seen two lights at once (it knows there is more than one
//! buoy) and has kept the light it follows abeam (more than `ABEAM_PIXELS` from the
//! retina's centre: rounding it, not sailing to it) for `habituation` seconds loses
//! interest in it: the light is ignored until it leaves the view, and the robot sails on
//! to the light farthest to the other side (the first one the rounding turned its bow
//! to), as a sailor rounds a mark and leaves it. Near a buoy the retina's normalisation
//! (by the mean photocurrent) can dim the far ones below the lobe contrast, so that
//! without habituation the robot circles the near one for ever (worlds/regatta_wide.wbt).
//! In the paper's arena the next light almost always takes over before habituation would;
//! a robot that has only ever seen one light keeps circling it, as the paper's did. `habituation=0`
//! turns it off.

use std::ops::ControlFlow;

use super::braitenberg::braitenberg_speeds;
use super::escape::{calls, StallEscape};
use super::parameters::Parameters;
use crate::khepera::{to_command, Controller, Khepera, KheperaError, Senses};
use crate::retina::FilterKind;

/// Light-intensity maxima in an odd-filter output (digital, `bits` bits).
///
/// The odd filter answers a bright patch with a negative lobe at its left edge and a positive
/// lobe at its right edge (pixel index grows clockwise). Lobes are runs beyond `min_contrast`
/// LSB from zero; a negative lobe followed directly by a positive one is a maximum, placed
/// midway between them (in pixel-edge units from the region's first pixel), however wide the
/// patch is.
pub fn light_maxima(odd: &[u16], bits: u32, min_contrast: f64) -> Vec<f64> {
    let mut maxima = Vec::new();
    LobeThresholds::new(bits, min_contrast).for_each_maximum(odd, |p| {
        maxima.push(p);
        ControlFlow::Continue(())
    });
    maxima
}

/// The maximum of [`light_maxima`] nearest `centre` (the first of equals), without listing them.
pub fn nearest_light_maximum(
    odd: &[u16],
    bits: u32,
    min_contrast: f64,
    centre: f64,
) -> Option<f64> {
    LobeThresholds::new(bits, min_contrast).nearest_maximum(odd, centre)
}

/// The lobe tests of [`light_maxima`] for one resolution and contrast, as integer thresholds
/// on the digital value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LobeThresholds {
    /// Values below this are in a negative lobe.
    negative_below: u32,
    /// Values from this on are in a positive lobe.
    positive_from: u32,
}

impl LobeThresholds {
    /// The thresholds for `bits`-bit values and `min_contrast` LSB.
    pub fn new(bits: u32, min_contrast: f64) -> LobeThresholds {
        let zero = ((1u32 << bits) - 1) as f64 / 2.0;
        let negative = |d: u32| d as f64 - zero <= -min_contrast;
        let positive = |d: u32| !negative(d) && d as f64 - zero >= min_contrast;
        // Both tests are monotone in the digital value: negative on a prefix of 0…65535,
        // positive on a suffix. Found once with the float tests themselves, they become
        // integer compares.
        LobeThresholds {
            negative_below: partition_point_u16(negative),
            positive_from: partition_point_u16(|d| !positive(d)),
        }
    }

    /// [`nearest_light_maximum`] with these thresholds.
    pub fn nearest_maximum(&self, odd: &[u16], centre: f64) -> Option<f64> {
        let mut nearest: Option<f64> = None;
        self.for_each_maximum(odd, |p| {
            if nearest.is_none_or(|n| (p - centre).abs() < (n - centre).abs()) {
                nearest = Some(p);
            }
            // Maxima come in increasing order: past the centre, the rest are farther.
            if p >= centre {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        nearest
    }

    /// Calls `visit` on each maximum of [`light_maxima`], in pixel order, until it breaks.
    fn for_each_maximum(&self, odd: &[u16], mut visit: impl FnMut(f64) -> ControlFlow<()>) {
        // A positive lobe pixel starts a maximum where the nearest lobe pixel before it is
        // negative; that pixel ends the negative lobe. The lobes of 64 pixels at a time are two
        // bit masks, and the search goes from one sign change to the next by bit scans: most
        // pixels are in no lobe, and a lobe is a run of one sign, so neither is visited pixel
        // by pixel.
        // The last lobe pixel so far, if it is negative.
        let mut negative_end: Option<usize> = None;
        for (word, chunk) in odd.chunks(64).enumerate() {
            let base = word * 64;
            let (negative, positive) = self.lobe_bits(chunk);
            // The lobe pixels not passed yet.
            let mut ahead = negative | positive;
            while ahead != 0 {
                let Some(end) = negative_end else {
                    // After a positive lobe (or none): the next negative pixel.
                    let next = negative & ahead;
                    if next == 0 {
                        break;
                    }
                    let at = next.trailing_zeros();
                    negative_end = Some(base + at as usize);
                    ahead &= above(at);
                    continue;
                };
                let next = positive & ahead;
                let negatives = negative & ahead;
                if next == 0 {
                    // The negative lobe runs on to this word's last negative pixel, or beyond.
                    if negatives != 0 {
                        negative_end = Some(base + 63 - negatives.leading_zeros() as usize);
                    }
                    break;
                }
                let at = next.trailing_zeros();
                let before = negatives & !above_or_at(at);
                let last = if before != 0 {
                    base + 63 - before.leading_zeros() as usize
                } else {
                    end
                };
                if visit((last + 1 + base + at as usize) as f64 / 2.0).is_break() {
                    return;
                }
                negative_end = None;
                ahead &= above(at);
            }
        }
    }

    /// The negative and the positive lobe pixels of up to 64 values, as bits (value `k` at
    /// bit `k`).
    fn lobe_bits(&self, chunk: &[u16]) -> (u64, u64) {
        let (below, from) = (self.negative_below, self.positive_from);
        // Sixteen values at a time by [`below_bits`]; a threshold past the values' range
        // (65536: every value below it) needs no compare.
        let (sixteens, rest) = chunk.as_chunks::<16>();
        let (mut negative, mut positive) = (0u64, 0u64);
        for (k, sixteen) in sixteens.iter().enumerate() {
            let n = match u16::try_from(below) {
                Ok(threshold) => below_bits(sixteen, threshold),
                Err(_) => !0,
            };
            let p = match u16::try_from(from) {
                Ok(threshold) => !below_bits(sixteen, threshold),
                Err(_) => 0,
            };
            negative |= u64::from(n) << (16 * k);
            positive |= u64::from(p) << (16 * k);
        }
        let shift = 16 * sixteens.len();
        for (k, &d) in rest.iter().enumerate() {
            negative |= u64::from(u32::from(d) < below) << (shift + k);
            positive |= u64::from(u32::from(d) >= from) << (shift + k);
        }
        (negative, positive)
    }
}

/// Which of sixteen values lie below `threshold`, as bits (value `k` at bit `k`): two vector
/// compares and a byte mask, where value-by-value tests cost a dozen instructions each.
#[cfg(target_arch = "x86_64")]
fn below_bits(values: &[u16; 16], threshold: u16) -> u16 {
    use std::arch::x86_64::{
        _mm_cmplt_epi16, _mm_loadu_si128, _mm_movemask_epi8, _mm_packs_epi16, _mm_set1_epi16,
        _mm_xor_si128,
    };
    // SAFETY: SSE2 is part of x86-64 (every such processor runs these), and the two unaligned
    // loads read the 32 bytes of `values`, eight lanes each.
    unsafe {
        // SSE2 compares signed 16-bit lanes: flipping the sign bit of both sides orders
        // unsigned values as signed ones.
        let flip = _mm_set1_epi16(i16::MIN);
        let threshold = _mm_xor_si128(_mm_set1_epi16(threshold as i16), flip);
        let low = _mm_loadu_si128(values.as_ptr().cast());
        let high = _mm_loadu_si128(values.as_ptr().add(8).cast());
        let low = _mm_cmplt_epi16(_mm_xor_si128(low, flip), threshold);
        let high = _mm_cmplt_epi16(_mm_xor_si128(high, flip), threshold);
        // Lanes of all ones or all zeros pack to bytes of all ones or zeros: one bit each.
        _mm_movemask_epi8(_mm_packs_epi16(low, high)) as u16
    }
}

/// Which of sixteen values lie below `threshold`, as bits (value `k` at bit `k`).
#[cfg(not(target_arch = "x86_64"))]
fn below_bits(values: &[u16; 16], threshold: u16) -> u16 {
    values
        .iter()
        .enumerate()
        .fold(0, |bits, (k, &d)| bits | u16::from(d < threshold) << k)
}

/// The bits above bit `at` (< 64).
fn above(at: u32) -> u64 {
    (!0u64).checked_shl(at + 1).unwrap_or(0)
}

/// Bit `at` (< 64) and the bits above it.
fn above_or_at(at: u32) -> u64 {
    !0u64 << at
}

/// The number of values in 0…65535 that satisfy `holds`, which holds on a prefix of them.
fn partition_point_u16(holds: impl Fn(u32) -> bool) -> u32 {
    let (mut lo, mut hi) = (0u32, 1u32 << 16);
    while lo < hi {
        let middle = (lo + hi) / 2;
        if holds(middle) {
            lo = middle + 1;
        } else {
            hi = middle;
        }
    }
    lo
}

/// A light moves less than this many pixels from one controller call to the next while the
/// robot turns at its speeds (an orbit turns it by about 1.4 pixels per 32 ms): the maximum
/// nearest a light's last position, within it, is the same light. With calls further apart
/// the window widens at [`TRACK_PIXEL_RATE`].
pub const TRACK_PIXELS: f64 = 8.0;

/// How fast the tracking window grows with the time between calls (pixels per second: 8
/// pixels per 32 ms).
pub const TRACK_PIXEL_RATE: f64 = 250.0;

/// A followed light this many pixels or more from the retina's centre (80°) is abeam.
pub const ABEAM_PIXELS: f64 = 50.0;

/// Departing ends once the next mark is this close to the retina's centre (pixels).
pub const DEPARTED_PIXELS: f64 = 10.0;

/// The regatta controller's habituation to the light it follows (see the module's
/// documentation). Lights have no names: a light is followed from step to step by its
/// position on the retina.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Habituation {
    /// Whether two lights were ever seen at once.
    several: bool,
    /// The light followed (its position, in pixels from the region's first) and the steps
    /// it has been abeam.
    followed: Option<(f64, u32)>,
    /// The light the robot lost interest in, followed until it leaves the view.
    ignored: Option<f64>,
    /// Set on losing interest in a light: the side it was on (−1 left, +1 right).
    departing: Option<f64>,
}

/// The maximum in `maxima` nearest `position`, within `window` pixels.
fn track(maxima: &[f64], position: f64, window: f64) -> Option<f64> {
    maxima
        .iter()
        .copied()
        .filter(|m| (m - position).abs() <= window)
        .min_by(|a, b| (a - position).abs().total_cmp(&(b - position).abs()))
}

/// The maximum nearest `centre` (the first of equals, as [`nearest_light_maximum`]) other
/// than `except`.
fn nearest_to(maxima: &[f64], centre: f64, except: Option<f64>) -> Option<f64> {
    let mut nearest: Option<f64> = None;
    for &m in maxima {
        if Some(m) != except && nearest.is_none_or(|n| (m - centre).abs() < (n - centre).abs()) {
            nearest = Some(m);
        }
    }
    nearest
}

impl Habituation {
    /// The light to steer to among this call's `maxima` (in pixel order, `centre` the
    /// retina's centre in the same units), if any. `limit` is the habituation in calls (0:
    /// never), `window` the tracking window in pixels (see [`TRACK_PIXELS`]).
    pub fn choose(&mut self, maxima: &[f64], centre: f64, limit: u32, window: f64) -> Option<f64> {
        self.ignored = self.ignored.and_then(|p| track(maxima, p, window));
        let followed = self
            .followed
            .and_then(|(p, steps)| track(maxima, p, window).map(|m| (m, steps)));
        self.several |= maxima.len() >= 2;
        let target = match self.departing {
            // Leaving a light behind on one side: the next mark is the light farthest to
            // the other side (the first the rounding turned the bow to).
            Some(side) => maxima
                .iter()
                .copied()
                .filter(|&m| Some(m) != self.ignored)
                .max_by(|a, b| (side * (centre - a)).total_cmp(&(side * (centre - b)))),
            None => nearest_to(maxima, centre, self.ignored),
        };
        let Some(target) = target else {
            self.followed = None;
            return None;
        };
        if (target - centre).abs() <= DEPARTED_PIXELS {
            self.departing = None;
        }
        let abeam = u32::from((target - centre).abs() >= ABEAM_PIXELS);
        let steps = match followed {
            Some((p, steps)) if p == target => steps.saturating_add(abeam),
            _ => abeam,
        };
        if self.several && limit > 0 && steps > limit {
            self.ignored = Some(target);
            self.departing = Some((target - centre).signum());
            self.followed = None;
            return None;
        }
        self.followed = Some((target, steps));
        Some(target)
    }
}

/// The paper's regatta controller.
pub struct Regatta {
    pub parameters: Parameters,
    /// The lobe thresholds, with the resolution and contrast they were found for.
    thresholds: Option<(u32, u64, LobeThresholds)>,
    enabled: bool,
    /// The odd filter's maxima, the buffer reused.
    maxima: Vec<f64>,
    escape: StallEscape,
    habituation: Habituation,
    /// The habituation parameter in calls (0: never) and the tracking window (pixels).
    habituation_calls: u32,
    track_window: f64,
}

impl Regatta {
    /// The controller with its parameters, before its first call; it will be called every
    /// `period` seconds.
    pub fn new(parameters: Parameters, period: f64) -> Regatta {
        let habituation_calls = if parameters.habituation > 0.0 {
            calls(parameters.habituation, period)
        } else {
            0
        };
        Regatta {
            habituation_calls,
            track_window: TRACK_PIXELS.max(TRACK_PIXEL_RATE * period),
            parameters,
            thresholds: None,
            enabled: false,
            maxima: Vec::new(),
            escape: StallEscape::new(period),
            habituation: Habituation::default(),
        }
    }
}

thread_local! {
    /// The odd filter's reading, while a controller steps (see [`Regatta::step`]).
    static ODD_READING: std::cell::Cell<Vec<u16>> = const { std::cell::Cell::new(Vec::new()) };
}

impl Regatta {
    /// The light to steer to in `odd` (the odd filter's reading from pixel `first`, `bits`
    /// bits): a maximum's pixel on the whole retina's scale, as habituation chooses it.
    fn brightest(&mut self, odd: &[u16], first: usize, bits: u32) -> Option<f64> {
        let centre = crate::retina::PIXELS as f64 / 2.0;
        let contrast = self.parameters.min_contrast;
        let thresholds = match self.thresholds {
            Some((b, c, thresholds)) if b == bits && c == contrast.to_bits() => thresholds,
            _ => {
                let thresholds = LobeThresholds::new(bits, contrast);
                self.thresholds = Some((bits, contrast.to_bits(), thresholds));
                thresholds
            }
        };
        self.maxima.clear();
        thresholds.for_each_maximum(odd, |p| {
            self.maxima.push(p);
            ControlFlow::Continue(())
        });
        self.habituation.choose(
            &self.maxima,
            centre - first as f64,
            self.habituation_calls,
            self.track_window,
        )
    }
}

impl Controller for Regatta {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        let proximity = robot.proximity()?;
        let (mut left, mut right) = braitenberg_speeds(&proximity, &self.parameters);
        let turret = robot.panoramic().ok_or(KheperaError::NoDevice(
            "Panoramic turret (the regatta controller needs one)",
        ))?;
        if !self.enabled {
            turret.enable_filter(FilterKind::Odd)?;
            self.enabled = true;
        }
        // The reading goes to a buffer of the thread's, read only here: a crowd's controllers
        // then write one warm buffer, not each a cold one of its own (and keep 300 bytes less).
        let mut odd = ODD_READING.with(std::cell::Cell::take);
        let mut steer = || -> Result<(usize, Option<f64>), KheperaError> {
            turret.read_into(FilterKind::Odd, &mut odd)?;
            let (first, _) = turret.region_of_interest()?;
            let bits = turret.bits()?;
            Ok((first, self.brightest(&odd, first, bits)))
        };
        let steered = steer();
        ODD_READING.with(|cell| cell.set(odd));
        let (first, chosen) = steered?;
        let centre = crate::retina::PIXELS as f64 / 2.0;
        if let Some(maximum) = chosen {
            let offset = maximum + first as f64 - centre;
            // Right of centre (positive) turns right: left wheel faster.
            left += self.parameters.light_gain * offset;
            right -= self.parameters.light_gain * offset;
        }
        let command = (to_command(left), to_command(right));
        let (left, right) = self
            .escape
            .command(&proximity, command, self.parameters.bias);
        robot.set_speed(left, right)
    }

    fn senses(&self) -> Senses {
        Senses {
            proximity: true,
            vision: true,
            ..Senses::NONE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The block-skipping search finds the maxima the definition gives, pixel by pixel with the
    /// float tests: every resolution, contrasts from none to more than the range, images of
    /// every length, values crowding the thresholds.
    #[test]
    fn light_maxima_follow_the_definition_pixel_by_pixel() {
        let reference = |odd: &[u16], bits: u32, contrast: f64| {
            let zero = ((1u32 << bits) - 1) as f64 / 2.0;
            let sign = |d: u16| {
                let x = d as f64 - zero;
                if x <= -contrast {
                    -1
                } else if x >= contrast {
                    1
                } else {
                    0
                }
            };
            let (mut maxima, mut last) = (Vec::new(), None);
            for (i, &d) in odd.iter().enumerate() {
                let s = sign(d);
                if s == 0 {
                    continue;
                }
                if let (1, Some((-1, j))) = (s, last) {
                    maxima.push((j + 1 + i) as f64 / 2.0);
                }
                last = Some((s, i));
            }
            maxima
        };
        let mut state = 0x853c_49e6_748f_ea9bu64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for case in 0..20_000u32 {
            let bits = 1 + case % 16;
            let top = (1u32 << bits) - 1;
            let contrast = [0.0, 0.5, 1.0, 2.5, 7.0, 40_000.0][(case / 16 % 6) as usize];
            let len = (next() % 200) as usize;
            let zero = top / 2;
            let odd: Vec<u16> = (0..len)
                .map(|_| {
                    let r = next();
                    let near = |k: u32| (zero + k).saturating_sub(4).min(top);
                    let value = match r % 4 {
                        0 => near((r >> 8) as u32 % 9),
                        1 => (r >> 8) as u32 % (top + 1),
                        2 => [0, top][(r >> 8) as usize % 2],
                        _ => zero,
                    };
                    value as u16
                })
                .collect();
            assert_eq!(
                light_maxima(&odd, bits, contrast),
                reference(&odd, bits, contrast),
                "bits {bits} contrast {contrast} image {odd:?}"
            );
        }
    }

    #[test]
    fn a_light_kept_abeam_too_long_is_left_for_the_farthest_on_the_other_side() {
        let centre = 75.0;
        let limit = 3;
        // One light only, abeam on the left: the robot has never seen two, so it keeps it.
        let mut lone = Habituation::default();
        for _ in 0..10 {
            assert_eq!(
                lone.choose(&[20.0], centre, limit, TRACK_PIXELS),
                Some(20.0)
            );
        }
        // Two lights seen at once, then one abeam: kept for `limit` steps abeam, then left.
        let mut h = Habituation::default();
        assert_eq!(
            h.choose(&[20.0, 140.0], centre, limit, TRACK_PIXELS),
            Some(20.0)
        );
        // Sailing to a light near the centre never counts.
        for _ in 0..10 {
            assert_eq!(h.choose(&[70.0], centre, limit, TRACK_PIXELS), Some(70.0));
        }
        // It drifts abeam (moving a pixel a step: the same light).
        let mut position = 24.0;
        let mut chosen = Vec::new();
        for _ in 0..5 {
            position -= 1.0;
            chosen.push(h.choose(&[position], centre, limit, TRACK_PIXELS));
        }
        assert_eq!(
            chosen,
            [Some(23.0), Some(22.0), Some(21.0), None, None],
            "left after {limit} steps abeam, then ignored while in view"
        );
        // Other lights appear: the one farthest right (the light left was on the left) is
        // the next mark, even if another is nearer the centre.
        assert_eq!(
            h.choose(&[18.0, 60.0, 100.0], centre, limit, TRACK_PIXELS),
            Some(100.0)
        );
        // Once it is ahead, the usual rule again: the light nearest the centre.
        assert_eq!(
            h.choose(&[18.0, 72.0, 80.0], centre, limit, TRACK_PIXELS),
            Some(80.0)
        );
        assert_eq!(
            h.choose(&[18.0, 74.0, 80.0], centre, limit, TRACK_PIXELS),
            Some(74.0)
        );
        // The ignored light, lost from view, may be followed again.
        assert_eq!(h.choose(&[], centre, limit, TRACK_PIXELS), None);
        assert_eq!(h.choose(&[18.0], centre, limit, TRACK_PIXELS), Some(18.0));
        // habituation=0: never left.
        let mut off = Habituation::default();
        assert_eq!(
            off.choose(&[20.0, 140.0], centre, 0, TRACK_PIXELS),
            Some(20.0)
        );
        for _ in 0..100 {
            assert_eq!(off.choose(&[20.0], centre, 0, TRACK_PIXELS), Some(20.0));
        }
    }

    #[test]
    fn a_bright_blob_is_found_between_its_lobes() {
        // Negative lobe then positive lobe around pixel edge 40.
        let mut odd = vec![32u16; 150];
        for (i, v) in [(37, 30), (38, 28), (39, 25), (40, 40), (41, 36), (42, 34)] {
            odd[i] = v;
        }
        assert_eq!(light_maxima(&odd, 6, 1.5), vec![40.0]);
        // A wide patch: lobes at its edges only, the maximum in its middle.
        let mut wide = vec![32u16; 150];
        for (i, v) in [(60, 28), (61, 29), (90, 36), (91, 35)] {
            wide[i] = v;
        }
        assert_eq!(light_maxima(&wide, 6, 1.5), vec![76.0]);
        // Flicker between 31 and 32 is not a light.
        let flicker: Vec<u16> = (0..150).map(|i| if i % 2 == 0 { 31 } else { 32 }).collect();
        assert!(light_maxima(&flicker, 6, 1.5).is_empty());
    }

    /// The float tests of the lobes, pixel by pixel: what the integer thresholds replace.
    fn maxima_by_float_tests(odd: &[u16], bits: u32, min_contrast: f64) -> Vec<f64> {
        let zero = ((1u32 << bits) - 1) as f64 / 2.0;
        let mut maxima = Vec::new();
        let mut last: Option<(bool, usize)> = None;
        for (i, &d) in odd.iter().enumerate() {
            let value = d as f64 - zero;
            let negative = value <= -min_contrast;
            let positive = !negative && value >= min_contrast;
            if positive && matches!(last, Some((true, _))) {
                let (_, j) = last.unwrap();
                maxima.push((j as f64 + 1.0 + i as f64) / 2.0);
            }
            if negative || positive {
                last = Some((negative, i));
            }
        }
        maxima
    }

    #[test]
    fn integer_lobe_thresholds_agree_with_the_float_tests() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for bits in [1, 2, 6, 8, 12, 16] {
            for min_contrast in [-2.0, 0.0, 0.5, 1.0, 1.5, 2.25, 7.0, 1e9, f64::NAN] {
                for _ in 0..20 {
                    let top = (1u64 << bits) - 1;
                    let odd: Vec<u16> = (0..150)
                        .map(|_| {
                            state ^= state << 13;
                            state ^= state >> 7;
                            state ^= state << 17;
                            (state % (top + 1)) as u16
                        })
                        .collect();
                    let expected = maxima_by_float_tests(&odd, bits, min_contrast);
                    assert_eq!(light_maxima(&odd, bits, min_contrast), expected);
                    let centre = 61.5;
                    let nearest = expected
                        .iter()
                        .copied()
                        .min_by(|a, b| (a - centre).abs().total_cmp(&(b - centre).abs()));
                    assert_eq!(
                        nearest_light_maximum(&odd, bits, min_contrast, centre),
                        nearest
                    );
                }
            }
        }
    }
}
