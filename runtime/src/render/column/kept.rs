//! Kept impostors: the crowd setting's far buoys worked out once and drawn again on the
//! updates after, while the eye stays within a distance (`crowdKeepDistance`) of where they
//! were worked out. This module owns that state, one per eye ([`KeptImpostors`]), when it is
//! worked out again, and how a kept box is drawn.
//!
//! Why it is cheap: telling a hundred round groups, hiding the impostors behind one another
//! and compositing each into its column cost a retina at 1000 robots about 60,000
//! instructions, two thirds of its update. An eye moves a few millimetres an update, and what
//! a far buoy adds to the image depends on where the eye is, not on where it faces: its box's
//! height (its effect on its column against what lies behind it, times the share no nearer
//! far buoy hides) and its centre's azimuth are kept; each update turns the box by the angle
//! the eye's move subtends (a short series) and covers it by the robots and buoys near the
//! eye as they stand now. Why the error is small: beyond the crowd distance a buoy's box
//! changes by about the eye's offset over its distance (under 4 % at 0.5 m for 2 cm), and
//! what moves across it fast, the near objects, is settled anew; `regatta bench crowd
//! --keep-distances` measures it with the eye moved that far since the boxes were worked out.
//!
//! Reproducible: the state belongs to one eye and changes only with that eye's updates, so a
//! run is the same on any number of threads. It is worked out again when the eye has moved
//! farther than the distance horizontally, or at all vertically, or in another scene or
//! setting.

use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::footprint::{wrap, Upright};
use super::impostor;
use super::photodiode::{Band, Raster, Scratch, Shown};
use super::scene::{ColumnFrame, ColumnScene};
use super::strip::Strip;
use super::sweep::{EyeObject, Look};

/// One far round group's box, kept: its group (for its centre and radius), its height, and
/// its centre's azimuth from where it was worked out, in eight bytes (a thousand eyes keep
/// about sixty each, within the half megabyte a 1000-robot run has to spare). The height
/// keeps the 8 leading bits of its significand (a float's upper half, rounded to nearest):
/// within 0.2 % of a box's effect, a fraction of a 6-bit step of the photodiode under it.
/// The azimuth, a single float, is within 3e-7 rad (a photodiode is 0.028 wide).
#[derive(Clone, Copy, Debug, PartialEq)]
struct KeptBox {
    group: u16,
    amount: u16,
    azimuth: f32,
}

impl KeptBox {
    /// `None` for a group past the 16-bit index, or a height that is not finite or is zero.
    fn new(group: u32, amount: f64, azimuth: f64) -> Option<KeptBox> {
        let group = u16::try_from(group).ok()?;
        let bits = (amount as f32).to_bits();
        // Round the lower half to nearest, ties to even; a finite height stays finite short
        // of the largest floats, which no photodiode reads.
        let rounded = bits.checked_add(0x7FFF + ((bits >> 16) & 1))? >> 16;
        let amount = rounded as u16;
        let value = f32::from_bits(u32::from(amount) << 16);
        (value.is_finite() && value != 0.0).then_some(KeptBox {
            group,
            amount,
            azimuth: azimuth as f32,
        })
    }

    fn amount(self) -> f64 {
        f64::from(f32::from_bits(u32::from(self.amount) << 16))
    }
}

thread_local! {
    /// The boxes being worked out, before they are kept.
    static BOXES: std::cell::Cell<Vec<KeptBox>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Where and for what the boxes were worked out.
struct Anchor {
    /// The scene's static objects (the groups index them): kept alive, so compared by address.
    statics: Arc<[Upright]>,
    eye: DVec3,
    /// The bits of the crowd distance, far distance, impostor width and band they used.
    setting: [u64; 4],
}

/// One eye's kept impostors (see the module's notes). Empty until its first update.
pub struct KeptImpostors {
    /// How far the eye may move (m) before they are worked out again.
    distance: f64,
    anchor: Option<Anchor>,
    /// The round groups placed exactly (near the eye, or too wide to be impostors), ascending.
    near: Vec<u32>,
    /// Exactly as long as it needs: a crowd keeps a thousand.
    boxes: Box<[KeptBox]>,
}

impl KeptImpostors {
    /// Kept while the eye stays within `distance` (m, above 0) of where they were worked out.
    pub fn new(distance: f64) -> KeptImpostors {
        KeptImpostors {
            distance,
            anchor: None,
            near: Vec::new(),
            boxes: Box::default(),
        }
    }

    /// The distance the eye may move before they are worked out again (m).
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// Whether the boxes must be worked out again for an eye at `eye` in the scene of
    /// `statics` with `setting`.
    pub(super) fn stale(&self, statics: &Arc<[Upright]>, eye: DVec3, setting: [u64; 4]) -> bool {
        let Some(anchor) = &self.anchor else {
            return true;
        };
        let moved = DVec2::new(eye.x - anchor.eye.x, eye.z - anchor.eye.z);
        // A NaN offset compares false: worked out again.
        !(moved.length_squared() <= self.distance * self.distance
            && eye.y == anchor.eye.y
            && anchor.setting == setting
            && Arc::ptr_eq(&anchor.statics, statics))
    }

    /// The round groups to place exactly.
    pub(super) fn near(&self) -> &[u32] {
        &self.near
    }
}

/// What working the boxes out needs beside the scene: the look told all around the eye (its
/// impostors settled), the band, and buffers.
pub(super) struct Refresh<'b> {
    pub(super) band: &'b Band,
    pub(super) facing: &'b mut Vec<u32>,
    pub(super) pieces: &'b mut Vec<EyeObject>,
    pub(super) profile: &'b mut Vec<Shown>,
    pub(super) scratch: &'b mut Scratch,
}

impl ColumnScene<'_> {
    /// Works the boxes out anew from `look` (told all around the eye with
    /// [`super::sweep::Rounds::TellAround`], its impostors settled against one another
    /// alone): each visible impostor's effect on the column through its centre, against what
    /// lies behind it, times the share no nearer impostor hides; and the groups the look
    /// placed exactly. What a box keeps depends on the far buoys alone (one beyond the crowd
    /// distance moves across another little as the eye moves within the keep distance); the
    /// robots and buoys near the eye move across it, and are settled at each update
    /// (`draw_kept`). Out of line: an eye works them out once in some twenty updates.
    #[inline(never)]
    pub(super) fn keep_impostors(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        setting: [u64; 4],
        kept: &mut KeptImpostors,
        buffers: Refresh,
    ) {
        let Refresh {
            band,
            facing,
            pieces,
            profile,
            scratch,
        } = buffers;
        look.placed_rounds(&mut kept.near);
        kept.near.shrink_to_fit();
        // Worked out in the thread's buffer, then kept in a block of exactly their size, the
        // old one freed first (a crowd's thousand blocks then reuse one another's places).
        let mut boxes = BOXES.with(std::cell::Cell::take);
        boxes.clear();
        kept.boxes = Box::default();
        for impostor in &look.impostors {
            // Hidden (or a share that is not a number): nothing to keep.
            if impostor.visible.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                continue;
            }
            let Some(group) = self.round_of(impostor.first_static) else {
                continue;
            };
            // The column through its centre (its interval may pass ±π: the centre does not).
            let centre = wrap(0.5 * (impostor.lo + impostor.hi));
            let direction = look.direction(centre);
            // Against what lies behind the box alone: what stands before it (a near buoy, a
            // robot) is settled at each update.
            let facing_now = look.facing(centre, facing).len();
            facing.truncate(facing_now);
            let inverse = DVec2::new(1.0 / direction.x, 1.0 / direction.y);
            let near_side = impostor.distance - impostor.radius;
            facing.retain(|&object| {
                look.objects[object as usize]
                    .relative
                    .cross(direction, inverse)
                    .is_none_or(|(_, exit, _)| exit > near_side)
            });
            let facing = &facing[..];
            profile.clear();
            self.profile(frame, look, direction, facing, band, scratch, profile);
            let effect = self.any_impostor_effect(
                frame,
                look,
                direction,
                impostor,
                (profile, pieces),
                band,
                scratch,
            );
            // The centre's azimuth from here (anticlockwise from +x towards −z): an update
            // turns it by the angle the eye's move makes at the centre (`draw_kept`).
            let azimuth = self.rounds.get(group as usize).map_or(f64::NAN, |round| {
                let offset = round.center - DVec2::new(look.eye.x, look.eye.z);
                impostor::atan2(-offset.y, offset.x)
            });
            boxes.extend(KeptBox::new(group, effect * impostor.visible, azimuth));
        }
        kept.boxes = Box::from(boxes.as_slice());
        BOXES.with(|cell| cell.set(boxes));
        kept.anchor = Some(Anchor {
            statics: frame.statics.clone(),
            eye: look.eye,
            setting,
        });
    }

    /// The round group whose pieces start at static object `first`.
    fn round_of(&self, first: u32) -> Option<u32> {
        let group = *self.round_at.get(first as usize)?;
        group.checked_sub(1)
    }

    /// Adds each kept box where it lies now, seen from `look`'s eye facing `heading`: its
    /// centre's azimuth as kept, turned by the angle the eye's move since subtends at the
    /// centre, and its half-width from its radius over its distance, as a look tells an
    /// impostor; its height as kept, less the share the standing objects the look placed
    /// (robots and buoys near the eye) hide now.
    pub(super) fn draw_kept(
        &self,
        look: &Look,
        heading: f64,
        kept: &KeptImpostors,
        strip: &Strip,
        out: &mut [f64],
    ) {
        use std::f64::consts::{PI, TAU};
        let pixels = out.len();
        let Some(anchor) = kept.anchor.as_ref().filter(|_| pixels > 0) else {
            return;
        };
        let (mut raster, (extent_lo, extent_hi)) = Raster::over(strip, out);
        let eye = DVec2::new(look.eye.x, look.eye.z);
        // How far the eye moved since the boxes were worked out.
        let moved = eye - DVec2::new(anchor.eye.x, anchor.eye.z);
        let near = look.near_sectors();
        // Below the band nothing shows: a near piece whose foot is below it hides as if it
        // stood on the floor.
        let foot_below = -strip.tan_half_band;
        // Past ±π a box is drawn again a turn away, where a strip reaches that far.
        let shifts: &[f64] = if extent_lo <= -std::f64::consts::FRAC_PI_2 * 1.9
            || extent_hi >= std::f64::consts::FRAC_PI_2 * 1.9
        {
            &[0.0, TAU, -TAU]
        } else {
            &[0.0]
        };
        // A box whose centre lies farther from the heading than the strip's reach and the
        // widest box together meets no photodiode: passed over.
        let reach = extent_lo.abs().max(extent_hi.abs()) + 0.11;
        // Within (−π, π], as the kept azimuths are: their difference is then within a turn
        // and a half of (−π, π].
        let heading = wrap(heading);
        // In blocks: each block's boxes placed first, in straight-line code whose long chains
        // (a square root, two divisions, two series) the processor overlaps box with box,
        // then added in order. Placing a box that is then passed over costs less than the
        // branch that would skip it, which half missed.
        const BLOCK: usize = 16;
        // Whether a box (centre, half-width) meets the strip when drawn `shift` away.
        let meets = |middle: f64, half: f64, shift: f64| {
            let (lo, hi) = (middle - half + shift, middle + half + shift);
            (hi > extent_lo) & (lo < extent_hi)
        };
        for block in kept.boxes.chunks(BLOCK) {
            let mut placed = [Placed::default(); BLOCK];
            for (slot, kept_box) in placed.iter_mut().zip(block) {
                let Some(round) = self.rounds.get(kept_box.group as usize) else {
                    continue;
                };
                let now = round.center - eye;
                let then = now + moved;
                let distance = now.length();
                let ratio = round.radius / distance;
                let r2 = ratio * ratio;
                let half =
                    ratio * (1.0 + r2 * (1.0 / 6.0 + r2 * (3.0 / 40.0 + r2 * (5.0 / 112.0))));
                // The angle from `then` to `now`, with azimuth anticlockwise from +x towards
                // −z: small while the eye stays within the keep distance of a far centre
                // (under 0.1 rad for 5 cm at 0.5 m), where an odd series to t⁹ is within 2e-8
                // of the arctangent; the look's arctangent past that.
                let cross = then.y * now.x - then.x * now.y;
                let dot = then.dot(now);
                let t = cross / dot;
                let turned = if dot > 0.0 && t.abs() <= 0.25 {
                    let t2 = t * t;
                    t * (1.0 - t2 * (1.0 / 3.0 - t2 * (1.0 / 5.0 - t2 * (1.0 / 7.0 - t2 / 9.0))))
                } else {
                    impostor::atan2(cross, dot)
                };
                let middle = f64::from(kept_box.azimuth) + turned - heading;
                // Into (−π, π] (a turned box is within a quarter turn of its kept azimuth).
                let middle = middle
                    + TAU * (f64::from(u8::from(middle <= -PI)) - f64::from(u8::from(middle > PI)));
                *slot = Placed {
                    middle,
                    half,
                    amount: kept_box.amount(),
                    distance,
                    group: kept_box.group,
                    // Beyond the crowd distance a box is narrow (ratio ≲ 0.06); past 0.1 (an
                    // eye that came within a few radii, or not a number) the series would not
                    // hold. And it meets the strip, here or a turn away.
                    shown: (middle.abs() <= reach)
                        & (ratio <= 0.1)
                        & shifts
                            .iter()
                            .fold(false, |any, &shift| any | meets(middle, half, shift)),
                };
            }
            // The boxes shown, listed without a branch on each (about half are, in no
            // pattern): a slot written for every box, the count advanced by those shown.
            let mut shown = [0u8; BLOCK];
            let mut count = 0;
            for (k, placed) in placed.iter().take(block.len()).enumerate() {
                shown[count] = k as u8;
                count += usize::from(placed.shown);
            }
            for &k in &shown[..count] {
                let Placed {
                    middle,
                    half,
                    mut amount,
                    distance,
                    group,
                    ..
                } = placed[usize::from(k)];
                if near.may_meet(middle - half, middle + half) {
                    let round = &self.rounds[group as usize];
                    let foot = (round.y0 - look.eye.y).min(0.0);
                    let top = (round.y1 - look.eye.y) / distance;
                    let interval = (middle - half, middle + half);
                    let covered =
                        look.covered_by_standing(interval, (foot, top, distance), foot_below);
                    if covered >= 2.0 * half {
                        continue;
                    }
                    amount *= 1.0 - covered / (2.0 * half);
                }
                for &shift in shifts {
                    if meets(middle, half, shift) {
                        raster.add_flat(middle - half + shift, middle + half + shift, amount);
                    }
                }
            }
        }
    }
}

/// A kept box placed for the update: its centre's relative azimuth and half-width (radians),
/// its height, distance and group, and whether it may meet the strip.
#[derive(Clone, Copy, Default)]
struct Placed {
    middle: f64,
    half: f64,
    amount: f64,
    distance: f64,
    group: u16,
    shown: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_is_eight_bytes_and_keeps_its_height_within_a_quarter_percent() {
        assert_eq!(std::mem::size_of::<KeptBox>(), 8);
        let mut unit = crate::test_random::unit_stream(5);
        for _ in 0..10_000 {
            let amount = (unit() - 0.5) * libm::pow(10.0, unit() * 8.0 - 6.0);
            let kept = KeptBox::new(7, amount, 0.5).expect("a finite height");
            let error = (kept.amount() - amount).abs() / amount.abs();
            assert!(error <= 1.0 / 256.0 + 1e-9, "{amount}: {}", kept.amount());
            assert_eq!(kept.group, 7);
        }
        assert_eq!(KeptBox::new(70_000, 1.0, 0.0), None);
        assert_eq!(KeptBox::new(1, 0.0, 0.0), None);
        assert_eq!(KeptBox::new(1, f64::NAN, 0.0), None);
        assert_eq!(KeptBox::new(1, f64::INFINITY, 0.0), None);
    }
}
