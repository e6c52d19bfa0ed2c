//! The strip integrated region by region (a contiguous strip sampled with a stride): which
//! objects face each region, its samples, and the piecewise-linear model of the band over
//! them integrated over each pixel window.

use super::super::angular::Sweep;
use super::super::impostor::Impostor;
use super::super::photodiode::{index_below, nearest_index, Band, Raster, Scratch};
use super::super::scene::{ColumnFrame, ColumnScene};
use super::super::strip::Strip;
use super::super::sweep::{EyeObject, Look};
use super::RegionBuffers;

impl ColumnScene<'_> {
    /// The strip cut into smooth regions at silhouette edges; each region sampled at about one
    /// column per `stride` pixels (at least once), the integrand modelled as piecewise linear
    /// through the samples (extended linearly to the region's ends), and that model integrated
    /// exactly over each pixel window. Pixels are contiguous windows (`strip.contiguous`).
    /// Regions come left to right, each handed its facing objects by the sweep.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn integrate_regions(
        &self,
        look: &Look,
        sweep: &mut Sweep,
        frame: &ColumnFrame,
        strip: &Strip,
        stride: usize,
        band: f64,
        sky: f64,
        ground: f64,
        buffers: &mut RegionBuffers,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) {
        let pixels = out.len();
        if pixels == 0 {
            return;
        }
        let width = strip.width;
        out.fill(0.0);
        let (mut raster, (extent_lo, extent_hi)) = Raster::over(strip, out);
        let inverse_width = raster.inverse_width;
        let RegionBuffers {
            bounds,
            positions,
            values,
            facing,
            profile,
            profile_starts,
            pieces,
            masks,
        } = buffers;
        let column_band = Band {
            tan_half: strip.tan_half_band,
            band,
            sky,
            ground,
        };
        // Impostors by centre; each drawn in the region its centre falls in (the first and
        // last regions take those whose centre lies beyond the strip).
        let mut next_impostor = 0;
        // Region bounds, ascending.
        bounds.clear();
        bounds.push(extent_lo);
        bounds.extend(
            look.breaks
                .iter()
                .copied()
                .filter(|&b| b > extent_lo && b < extent_hi),
        );
        bounds.push(extent_hi);
        let step = width * stride as i64 as f64;
        let regions = bounds.len() - 1;
        // Where the sweep would test every object in every region, each object's run of
        // regions is found once instead: the same lists, in the same order.
        let by_masks = sweep.tests_every_object() && look.objects.len() <= 64;
        if by_masks {
            facing_masks(&look.objects, bounds, masks);
        }
        for (region, pair) in bounds.windows(2).enumerate() {
            let (r0, r1) = (pair[0], pair[1]);
            let span = r1 - r0;
            // A region lies within the strip: at most a sample per stride of its pixels.
            let count = if span <= width {
                1
            } else {
                1 + index_below(span / step, pixels)
            };
            // Between two edges the same objects face the eye (those whose hidden edge fell
            // inside face part of it, hidden there: they are tried throughout).
            let facing = if by_masks {
                facing.clear();
                // Last placed first, as the sweep lists them.
                let mut mask = masks[region];
                while mask != 0 {
                    let index = 63 - mask.leading_zeros();
                    facing.push(index);
                    mask ^= 1 << index;
                }
                &facing[..]
            } else {
                sweep.facing_over(look, r0, r1, facing)
            };
            // A region with impostors keeps what each sample shows (the same mean).
            let last = region + 1 == regions;
            let takes = |impostor: &Impostor| last || 0.5 * (impostor.lo + impostor.hi) < r1;
            let impostors_here = look
                .impostor_order
                .get(next_impostor)
                .is_some_and(|&i| takes(&look.impostors[i as usize]));
            if count == 1 && !impostors_here {
                // One sample at the middle, level across the region (most regions): the
                // general way's sums, without its lists.
                let alpha = r0 + 0.5 * span;
                let pixel = nearest_index((strip.centers[0] - alpha) * inverse_width, pixels - 1);
                let direction = look.turn(strip, pixel, alpha);
                let value = self.column(
                    frame,
                    look,
                    direction,
                    facing,
                    strip.tan_half_band,
                    band,
                    sky,
                    ground,
                    scratch,
                );
                raster.add(r0, r1, value, 0.0);
                continue;
            }
            positions.clear();
            values.clear();
            let piece = span / count as i64 as f64;
            let mut middle = 0.5;
            profile.clear();
            profile_starts.clear();
            for _ in 0..count {
                let alpha = r0 + middle * piece;
                middle += 1.0;
                // The nearest pixel's direction, turned by the small remainder.
                let pixel = nearest_index((strip.centers[0] - alpha) * inverse_width, pixels - 1);
                positions.push(alpha);
                let direction = look.turn(strip, pixel, alpha);
                values.push(if impostors_here {
                    profile_starts.push(profile.len());
                    self.profile(
                        frame,
                        look,
                        direction,
                        facing,
                        &column_band,
                        scratch,
                        profile,
                    )
                } else {
                    self.column(
                        frame,
                        look,
                        direction,
                        facing,
                        strip.tan_half_band,
                        band,
                        sky,
                        ground,
                        scratch,
                    )
                });
            }
            profile_starts.push(profile.len());
            // The region's impostors, each against what the sample nearest it shows (between
            // two edges the same objects face the eye: that changes little).
            while let Some(&index) = look.impostor_order.get(next_impostor) {
                let impostor = &look.impostors[index as usize];
                if !takes(impostor) {
                    break;
                }
                let centre = 0.5 * (impostor.lo + impostor.hi);
                next_impostor += 1;
                if impostor.hi <= extent_lo || impostor.lo >= extent_hi {
                    continue;
                }
                let k = nearest_index((centre - r0) / piece - 0.5, count - 1);
                let shown = &profile[profile_starts[k]..profile_starts[k + 1]];
                let pixel = nearest_index((strip.centers[0] - centre) * inverse_width, pixels - 1);
                let direction = look.turn(strip, pixel, centre);
                let effect = self.any_impostor_effect(
                    frame,
                    look,
                    direction,
                    impostor,
                    (shown, pieces),
                    &column_band,
                    scratch,
                );
                if effect != 0.0 {
                    raster.add(impostor.lo, impostor.hi, effect * impostor.visible, 0.0);
                }
            }
            if count == 1 {
                raster.add(r0, r1, values[0], 0.0);
                continue;
            }
            // Piece k joins samples k and k + 1; the first and last pieces reach the ends.
            for k in 0..count - 1 {
                let x0 = if k == 0 { r0 } else { positions[k] };
                let x1 = if k + 2 == count { r1 } else { positions[k + 1] };
                let slope = (values[k + 1] - values[k]) / (positions[k + 1] - positions[k]);
                raster.add(x0, x1, values[k] + slope * (x0 - positions[k]), slope);
            }
        }
    }
}

/// For each region between consecutive `bounds` (ascending), the objects (at most 64) whose
/// interval meets it, [`EyeObject::meets`]'s answer, as bits: an interval meets the regions
/// whose upper bound lies above its start and whose lower bound lies below its end, two runs
/// found by binary search.
fn facing_masks(objects: &[EyeObject], bounds: &[f64], masks: &mut Vec<u64>) {
    let regions = bounds.len() - 1;
    masks.clear();
    masks.resize(regions, 0);
    let (uppers, lowers) = (&bounds[1..], &bounds[..regions]);
    for (k, object) in objects.iter().enumerate() {
        let bit = 1u64 << k;
        if object.lo.is_nan() || object.hi.is_nan() {
            // No order to search by: each region asked.
            for (region, mask) in masks.iter_mut().enumerate() {
                if object.meets(bounds[region], bounds[region + 1]) {
                    *mask |= bit;
                }
            }
            continue;
        }
        if !object.wraps && (object.hi <= bounds[0] || object.lo >= bounds[regions]) {
            // Wholly outside the strip (an arena's wall behind the eye): no region.
            continue;
        }
        let first = uppers.partition_point(|&b| b <= object.lo);
        let end = lowers.partition_point(|&b| b < object.hi);
        if object.wraps {
            masks[first..].iter_mut().for_each(|mask| *mask |= bit);
            masks[..end].iter_mut().for_each(|mask| *mask |= bit);
        } else if first < end {
            masks[first..end].iter_mut().for_each(|mask| *mask |= bit);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::footprint::Relative;
    use super::*;
    use glam::DVec2;

    /// The masks hold each region's objects as testing each object against the region does
    /// (`EyeObject::meets`): intervals within, across and beyond the bounds, passing ±π,
    /// empty (a floor drawn as the ground), infinite (surrounding the eye) and NaN, and bounds
    /// with repeats.
    #[test]
    fn facing_masks_are_what_meets_finds() {
        let mut unit = crate::test_random::unit_stream(21);
        let mut turns = crate::test_random::unit_stream(22);
        let mut angle = || (turns() * 2.0 - 1.0) * 3.5;
        let special = [
            (f64::NEG_INFINITY, f64::INFINITY),
            (f64::INFINITY, f64::NEG_INFINITY),
            (f64::NAN, 0.5),
            (0.2, f64::NAN),
        ];
        let mut masks = Vec::new();
        for trial in 0..2_000 {
            let mut bounds: Vec<f64> = (0..2 + trial % 20).map(|_| angle()).collect();
            bounds.sort_by(f64::total_cmp);
            if trial % 3 == 0 && bounds.len() > 2 {
                bounds[1] = bounds[0];
            }
            let objects: Vec<EyeObject> = (0..trial % 64)
                .map(|k| {
                    // Most ends are bounds, as a look's are its edges.
                    let end = |pick: f64, other: f64| {
                        if pick < 0.6 {
                            bounds[(pick * 100.0) as usize % bounds.len()]
                        } else {
                            other
                        }
                    };
                    let (lo, hi) = if k % 17 == 5 {
                        special[(k / 17) % special.len()]
                    } else {
                        (end(unit(), angle()), end(unit(), angle()))
                    };
                    EyeObject {
                        lo,
                        hi,
                        wraps: lo > hi && lo.is_finite() && hi.is_finite(),
                        relative: Relative::Circle {
                            oc: DVec2::ONE,
                            c: 1.0,
                            radius: 0.1,
                        },
                        y0: -0.1,
                        y1: 0.1,
                        side: true,
                        top: false,
                        bottom: false,
                        primitive: 0,
                    }
                })
                .collect();
            facing_masks(&objects, &bounds, &mut masks);
            for (region, pair) in bounds.windows(2).enumerate() {
                let expected = objects
                    .iter()
                    .enumerate()
                    .filter(|(_, o)| o.meets(pair[0], pair[1]))
                    .fold(0u64, |mask, (k, _)| mask | 1 << k);
                assert_eq!(masks[region], expected, "trial {trial} region {region}");
            }
        }
    }
}
