//! The look: what one eye sees, built once per update. Every object's azimuth interval and
//! relative footprint (`Look`), the silhouette edges sorted once, and what the look leaves out
//! (`Reach`, `Sector`). The angular sweep over it that hands each region between edges the
//! objects facing it is `angular.rs`.

use glam::{DVec2, DVec3};

use super::compact::kept_prefix;
use super::crowd::CrowdGrid;
use super::footprint::Relative;
use super::footprint::{azimuth_interval, corner_of, wrap, Interval, PendingEdge, Upright};
use super::impostor::{self, Impostor, Occlusion, Standing};
use super::photodiode::{from_total_key, rotate_small, total_key};
use super::scene::{ColumnFrame, ColumnScene};
use super::strip::{Strip, SECTOR_MARGIN};
use crate::geometry::Footprint;

/// An object as seen from one eye.
#[derive(Clone, Copy, Debug)]
pub struct EyeObject {
    /// Its azimuth interval's edges in (−π, π] (infinite when it surrounds the eye).
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// Whether the interval passes ±π: it is `[lo, π] ∪ (−π, hi]`.
    pub(super) wraps: bool,
    pub(super) relative: Relative,
    /// Heights relative to the eye.
    pub(super) y0: f64,
    pub(super) y1: f64,
    pub(super) side: bool,
    pub(super) top: bool,
    pub(super) bottom: bool,
    /// The primitive it shows (for its material).
    pub(super) primitive: u32,
}

impl EyeObject {
    /// Whether its azimuth interval holds `alpha` (in (−π, π]).
    #[inline]
    pub(super) fn holds(&self, alpha: f64) -> bool {
        let (after_lo, before_hi) = (alpha >= self.lo, alpha <= self.hi);
        // Bit operations, not a branch on `wraps`: lists are built from this test without a
        // branch per object (`compact.rs`).
        (after_lo & before_hi) | (self.wraps & (after_lo | before_hi))
    }

    /// Whether its azimuth interval meets the open interval `(a, b)` (within (−π, π]).
    #[inline]
    pub(super) fn meets(&self, a: f64, b: f64) -> bool {
        let (after_lo, before_hi) = (self.lo < b, self.hi > a);
        if self.wraps {
            after_lo | before_hi
        } else {
            after_lo & before_hi
        }
    }

    /// [`EyeObject::meets`] by bit operations, without a branch on `wraps`: for lists built
    /// without a branch per object (`compact.rs`).
    #[inline]
    pub(super) fn meets_unbranched(&self, a: f64, b: f64) -> bool {
        let (after_lo, before_hi) = (self.lo < b, self.hi > a);
        (after_lo & before_hi) | (self.wraps & (after_lo | before_hi))
    }
}

/// Everything about one eye, for one update.
#[derive(Default)]
pub struct Look {
    pub(super) eye: DVec3,
    /// Whether the look's frame holds a crowd (more than [`FEW`] robots): which objects face a
    /// region then follows no pattern a branch predictor learns, and its lists are built
    /// without a branch per object.
    crowd: bool,
    pub(super) cos_h: f64,
    pub(super) sin_h: f64,
    pub(super) objects: Vec<EyeObject>,
    /// Silhouette edges within the reach's extent (relative azimuths), sorted; hidden ones
    /// left out.
    pub(super) breaks: Vec<f64>,
    /// Each static object's index among `objects`.
    pub(super) static_slots: Vec<u32>,
    /// Edges waiting for the hidden-edge test.
    pub(super) edges: Vec<PendingEdge>,
    /// The robots within the crowd distance.
    near: Vec<u32>,
    /// Small static objects beyond the crowd distance, drawn as impostors (crowd level of
    /// detail only; not among `objects`: no region faces them).
    pub(super) impostors: Vec<Impostor>,
    /// The objects drawn exactly that may hide impostors, and the bins that say where.
    standing: Vec<Standing>,
    occlusion: Occlusion,
    /// Per round group of the scene, whether this look made it an impostor or left it out.
    round_far: Vec<bool>,
    /// With a far distance, the round groups this look tells (the others lie beyond it),
    /// then those of them it places; and a bitmap ordering them.
    round_visit: Vec<u32>,
    round_bits: Vec<u64>,
    /// Whether `round_visit` holds the groups placed (else `round_far` says which were not).
    rounds_listed: bool,
    /// The last strip's reach for impostors ([`impostor::Viewpoint::reach_cos`]), by the bits
    /// of its width and extent.
    reach_cos: ((u64, u64, u64), f64),
    /// Scratch for ordering impostors.
    impostor_keys: Vec<u64>,
    centre_keys: Vec<u128>,
    pub(super) impostor_order: Vec<u32>,
    /// The azimuth intervals of the scene floor's walls as tall as the eye (see
    /// [`super::scene::Floor`]), wrapped into (−π, π].
    wall_cover: Vec<(f64, f64)>,
    /// The floor's primitive when this look draws it as the ground below the horizon (its
    /// object then faces no region).
    pub(super) ground_floor: Option<u32>,
}

impl Look {
    /// The sectors of a turn its standing objects, which may hide impostors, meet (none
    /// when it placed none).
    pub(super) fn near_sectors(&self) -> impostor::NearSectors {
        impostor::NearSectors::of(&self.standing)
    }

    /// How much of the azimuth interval `[lo, hi]` (radians, within a turn of (−π, π]) of a
    /// box whose top's tan-elevation is `top`, foot `y0` and distance `distance`, the standing
    /// objects this look placed hide ([`impostor::covered_by_standing`]).
    pub(super) fn covered_by_standing(
        &self,
        (lo, hi): (f64, f64),
        (y0, top, distance): (f64, f64, f64),
        foot_below: f64,
    ) -> f64 {
        impostor::covered_by_standing(&self.standing, (lo, hi), (y0, top, distance), foot_below)
    }

    /// The objects whose azimuth interval holds relative azimuth `alpha`, in object order.
    pub fn facing<'o>(&self, alpha: f64, out: &'o mut Vec<u32>) -> &'o [u32] {
        let objects = &self.objects;
        kept_prefix(out, objects.len(), |k| {
            (k as u32, objects.get(k).is_some_and(|o| o.holds(alpha)))
        })
    }

    /// The objects whose azimuth interval meets the open interval `(a, b)`, last placed first:
    /// every object tested (the sweep's answer, and cheaper for a few objects). The robots,
    /// placed after the scene's static objects, then come before the floor and the walls,
    /// which lie behind them: a column's segments mostly come front to back, and sorting them
    /// moves little (what a column shows does not depend on the order).
    #[inline(always)]
    pub(super) fn facing_over<'o>(&self, a: f64, b: f64, out: &'o mut Vec<u32>) -> &'o [u32] {
        if self.crowd {
            return self.facing_over_unbranched(a, b, out);
        }
        // A few robots: the branches are learnt, and the filter costs fewer instructions.
        out.clear();
        out.extend(
            self.objects
                .iter()
                .enumerate()
                .rev()
                .filter(|(_, o)| o.meets(a, b))
                .map(|(index, _)| index as u32),
        );
        out
    }

    /// [`Look::facing_over`] in a crowd: without a branch per object.
    #[inline(never)]
    fn facing_over_unbranched<'o>(&self, a: f64, b: f64, out: &'o mut Vec<u32>) -> &'o [u32] {
        let objects = &self.objects;
        let last = objects.len().wrapping_sub(1);
        kept_prefix(out, objects.len(), |k| {
            let index = last - k;
            let meets = objects.get(index).is_some_and(|o| o.meets_unbranched(a, b));
            (index as u32, meets)
        })
    }

    /// The world direction (x, z) of relative azimuth `alpha`, near `strip`'s pixel `pixel`:
    /// the pixel centre's direction turned by the small remainder, no transcendental.
    #[inline]
    pub(super) fn turn(&self, strip: &Strip, pixel: usize, alpha: f64) -> DVec2 {
        let (cos_c, sin_c) = strip.directions[pixel];
        let (ca, sa) = rotate_small(cos_c, sin_c, alpha - strip.centers[pixel]);
        // World direction of azimuth heading + alpha: (cos, −sin) in (x, z).
        let (cw, sw) = (
            self.cos_h * ca - self.sin_h * sa,
            self.sin_h * ca + self.cos_h * sa,
        );
        DVec2::new(cw, -sw)
    }

    /// The world direction (x, z) of relative azimuth `alpha`.
    pub fn direction(&self, alpha: f64) -> DVec2 {
        let (ca, sa) = (libm::cos(alpha), libm::sin(alpha));
        let (cw, sw) = (
            self.cos_h * ca - self.sin_h * sa,
            self.sin_h * ca + self.cos_h * sa,
        );
        DVec2::new(cw, -sw)
    }

    /// Sets the round groups the next look with [`Rounds::Given`] places, ascending.
    pub(super) fn keep_rounds(&mut self, groups: &[u32]) {
        self.round_visit.clear();
        self.round_visit.extend_from_slice(groups);
    }

    /// The round groups this look placed exactly (told near, or too wide to be impostors),
    /// ascending, into `out`.
    pub(super) fn placed_rounds(&self, out: &mut Vec<u32>) {
        out.clear();
        if self.rounds_listed {
            out.extend_from_slice(&self.round_visit);
        } else {
            out.extend(
                self.round_far
                    .iter()
                    .enumerate()
                    .filter(|(_, &far)| !far)
                    .map(|(group, _)| group as u32),
            );
        }
    }
}

/// What became of an object placed in a look (and so of the pieces sharing its footprint).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fate {
    Placed,
    LeftOut,
}

/// An object as seen from `eye`, its interval `[lo, hi]` (wrapped).
pub(super) fn eye_object(object: &Upright, eye: DVec3, lo: f64, hi: f64) -> EyeObject {
    let eye2 = DVec2::new(eye.x, eye.z);
    let relative = match object.footprint {
        Footprint::Circle { center, radius } => {
            let oc = eye2 - center;
            Relative::Circle {
                oc,
                c: oc.length_squared() - radius * radius,
                radius,
            }
        }
        Footprint::Rect {
            center,
            u,
            v,
            half_u,
            half_v,
        } => {
            let oc = eye2 - center;
            Relative::Rect {
                pu: oc.dot(u),
                pv: oc.dot(v),
                u,
                v,
                half_u,
                half_v,
                axis_aligned: u == DVec2::X && v == DVec2::Y,
            }
        }
    };
    EyeObject {
        lo,
        hi,
        wraps: lo > hi,
        relative,
        y0: object.y0 - eye.y,
        y1: object.y1 - eye.y,
        side: object.side,
        top: object.top,
        bottom: object.bottom,
        primitive: object.primitive as u32,
    }
}

/// A closure over a frame's objects, typed so that it may keep references to them.
fn typed<'f, F: FnMut(usize, &'f Upright, bool) -> usize>(_frame: &'f ColumnFrame, f: F) -> F {
    f
}

/// Whether a look keeps each static object's place among its objects: where some may be left
/// out.
fn keep_slots_for(reach: Reach) -> bool {
    reach.sector.is_some() || reach.impostor_width > 0.0
}

/// Below this many objects (or edges), testing each is cheaper than keeping them in order.
pub(super) const FEW: usize = 32;

/// Sorts `values` (each below `bound`) ascending and drops repeats. Where the bound is small
/// beside their count, by a bitmap over `0..bound` read back word by word (a look's reachable
/// groups: dozens of a few hundred, where sorting cost 2,500 instructions a look); otherwise by
/// sorting.
fn ascending_once(values: &mut Vec<u32>, bound: usize, bits: &mut Vec<u64>) {
    let words = bound.div_ceil(64);
    if words > 4 * values.len().max(1) || values.iter().any(|&v| v as usize >= bound) {
        values.sort_unstable();
        values.dedup();
        return;
    }
    bits.clear();
    bits.resize(words, 0);
    for &v in values.iter() {
        bits[v as usize / 64] |= 1 << (v % 64);
    }
    values.clear();
    for (w, &word) in bits.iter().enumerate() {
        let mut word = word;
        while word != 0 {
            values.push((w * 64) as u32 + word.trailing_zeros());
            word &= word - 1;
        }
    }
}

/// Whether `intervals` (relative azimuths wrapped into (−π, π], `lo > hi` passing ±π) cover
/// `extent` (clamped to [−π, π]), each joint overlapping by a margin over the polynomial
/// arctangent's error (2e-8 rad); `intervals` is reordered.
fn covers(intervals: &mut Vec<(f64, f64)>, (first, last): (f64, f64)) -> bool {
    use std::f64::consts::PI;
    const MARGIN: f64 = 1e-7;
    for k in 0..intervals.len() {
        let (lo, hi) = intervals[k];
        if lo > hi {
            intervals[k] = (lo, PI);
            intervals.push((-PI, hi));
        }
    }
    // A handful (an arena's four walls): insertion.
    for i in 1..intervals.len() {
        let interval = intervals[i];
        let mut j = i;
        while j > 0 && intervals[j - 1].0 > interval.0 {
            intervals[j] = intervals[j - 1];
            j -= 1;
        }
        intervals[j] = interval;
    }
    let (mut reached, goal) = (first.max(-PI), last.min(PI));
    for &(lo, hi) in intervals.iter() {
        // Ends at ±π join the wrapped interval's other piece: no margin there.
        let lo = if lo <= -PI { lo } else { lo + MARGIN };
        if lo > reached {
            break;
        }
        let hi = if hi >= PI { hi } else { hi - MARGIN };
        reached = reached.max(hi);
    }
    reached >= goal
}

/// Sorts a few numbers ascending (insertion sort).
fn sort_small(values: &mut [f64]) {
    for i in 1..values.len() {
        let value = values[i];
        let mut j = i;
        while j > 0 && values[j - 1] > value {
            values[j] = values[j - 1];
            j -= 1;
        }
        values[j] = value;
    }
}

/// Sorts numbers in [`f64::total_cmp`]'s order, comparing integers (each number's key held
/// in its own bits meanwhile): no per-comparison bit twiddling.
fn sort_total(values: &mut [f64]) {
    for value in values.iter_mut() {
        *value = f64::from_bits(total_key(*value));
    }
    values.sort_unstable_by_key(|value| value.to_bits());
    for value in values.iter_mut() {
        *value = from_total_key(value.to_bits());
    }
}

/// What a look may leave out.
#[derive(Clone, Copy, Debug)]
pub(super) struct Reach {
    /// Robot parts wholly outside this sector face no photodiode.
    pub(super) sector: Option<Sector>,
    /// Other robots farther than this are not drawn (infinite: all are).
    pub(super) crowd_distance: f64,
    /// Static objects without hiders, round, farther than the crowd distance and at most this
    /// wide (radians) are drawn as impostors (0: none are).
    pub(super) impostor_width: f64,
    /// Would-be impostors wholly farther than this are left out (infinite: none are).
    pub(super) far_distance: f64,
    /// The strip's relative azimuths: impostors wholly outside are left out.
    pub(super) extent: (f64, f64),
    /// With a crowd distance, the band's half-height (tangent): robot parts and static
    /// objects no corner test names that lie wholly below or above the band, seen from
    /// anywhere on their footprint, face no photodiode and are left out (a robot's wheels,
    /// another robot nearer than about 17 cm, the viewer's own body). Infinite: none are.
    pub(super) out_of_band: f64,
    /// How the scene's round groups are told (with impostors).
    pub(super) rounds: Rounds,
    /// The heading's cosine and sine, where the caller has them.
    pub(super) turn: Option<(f64, f64)>,
}

/// How a look tells the scene's round groups (buoys with their lamps) apart, with impostors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Rounds {
    /// Each is told near (placed exactly), an impostor meeting the strip, or left out.
    Tell,
    /// As `Tell`, but every impostor around the eye is kept, whatever the strip, its interval
    /// passing ±π where it does (the kept impostors' refresh: `kept.rs`).
    TellAround,
    /// None is told: the look places the groups the caller gave ([`Look::keep_rounds`]) and
    /// makes no impostor (the kept impostors stand in for them).
    Given,
}

impl Reach {
    /// Nothing left out.
    pub(super) const EVERYTHING: Reach = Reach {
        sector: None,
        crowd_distance: f64::INFINITY,
        impostor_width: 0.0,
        far_distance: f64::INFINITY,
        extent: (f64::NEG_INFINITY, f64::INFINITY),
        out_of_band: f64::INFINITY,
        rounds: Rounds::Tell,
        turn: None,
    };
}

/// Whether `object`, seen from `eye`, lies wholly outside the band of half-height
/// `tan_half`: its top below the band's lower edge (or its bottom above the upper) even at its
/// footprint's farthest point. Its columns then show nothing of it.
pub(super) fn out_of_band(object: &Upright, eye: DVec3, tan_half: f64) -> bool {
    let (center, radius) = object.footprint.bounding_circle();
    // The farthest point, with a margin for rounding: never more than the object's extent.
    let farthest = (center - DVec2::new(eye.x, eye.z)).length() + radius;
    let reach = farthest * tan_half * (1.0 + 1e-9) + 1e-12;
    object.y1 - eye.y < -reach || object.y0 - eye.y > reach
}

/// The azimuth sector a strip covers, as the rays bounding its complement: a robot part whose
/// footprint lies wholly beyond both (behind the retina) faces no photodiode and is left out.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sector {
    /// Unit directions, in (x, −z), of the sector's ends: `lo` clockwise, `hi` anticlockwise.
    lo: DVec2,
    hi: DVec2,
    /// Whether the part left out (from `hi` anticlockwise round to `lo`) is under half a turn.
    narrow_back: bool,
}

impl Sector {
    /// The sector of `strip`'s relative azimuths, widened by [`SECTOR_MARGIN`], seen from a
    /// heading of cosine and sine `turn`: the strip's ends turned by it, no transcendental
    /// (the sector only leaves out what lies wholly outside it, with a margin far above
    /// rounding).
    pub(super) fn new(turn: (f64, f64), strip: &Strip) -> Option<Sector> {
        let (lo, hi) = strip.extent()?;
        let (lo, hi) = (lo - SECTOR_MARGIN, hi + SECTOR_MARGIN);
        // A full turn (or NaN) leaves nothing behind.
        if (hi - lo).partial_cmp(&std::f64::consts::TAU) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let (cos_h, sin_h) = turn;
        let at = |(cos_a, sin_a): (f64, f64)| {
            DVec2::new(cos_h * cos_a - sin_h * sin_a, sin_h * cos_a + cos_h * sin_a)
        };
        Some(Sector {
            lo: at(strip.sector_ends[0]),
            hi: at(strip.sector_ends[1]),
            narrow_back: hi - lo > std::f64::consts::PI,
        })
    }

    /// Whether a disc (centre relative to the eye, in (x, −z)) lies wholly outside the sector.
    #[inline]
    pub(super) fn excludes(&self, center: DVec2, radius: f64) -> bool {
        // Beyond `hi` anticlockwise and before `lo`.
        let (after_hi, before_lo) = (
            self.hi.perp_dot(center) > 0.0,
            center.perp_dot(self.lo) > 0.0,
        );
        let outside = if self.narrow_back {
            after_hi && before_lo
        } else {
            after_hi || before_lo
        };
        if !outside {
            return false;
        }
        // Clear of both bounding rays by the radius (with a margin for rounding).
        let clear = radius * (1.0 + 1e-9) + 1e-9 * (1.0 + center.length());
        let ray_distance = |ray: DVec2| {
            if ray.dot(center) > 0.0 {
                ray.perp_dot(center).abs()
            } else {
                center.length()
            }
        };
        ray_distance(self.lo) > clear && ray_distance(self.hi) > clear
    }
}

impl ColumnScene<'_> {
    /// What depends on the eye alone: each object's azimuth interval and its footprint
    /// relative to the eye, computed once per update.
    pub fn look(&self, frame: &ColumnFrame, eye: DVec3, heading: f64) -> Look {
        self.look_for(frame, frame.viewer, eye, heading)
    }

    /// [`ColumnScene::look`] for `viewer` in a frame shared by every viewer of a step.
    pub fn look_for(
        &self,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
    ) -> Look {
        let mut look = Look::default();
        self.look_into(frame, viewer, eye, heading, Reach::EVERYTHING, &mut look);
        look
    }

    /// With a far distance, the round groups a look must tell, ascending, into `out`: every
    /// other group lies wholly beyond the far distance and is narrow enough to be an impostor
    /// there, which [`impostor::Viewpoint::far`] leaves out. `None`: tell every group.
    fn reachable_rounds<'v>(
        &self,
        eye: DVec2,
        reach: Reach,
        out: &'v mut Vec<u32>,
        bits: &mut Vec<u64>,
    ) -> Option<&'v [u32]> {
        if !(reach.far_distance.is_finite() && reach.impostor_width > 0.0)
            || self.rounds.len() <= FEW
        {
            return None;
        }
        #[cfg(test)]
        if super::far::tests::EVERY_ROUND.with(std::cell::Cell::get) {
            return None;
        }
        let beyond = reach.far_distance.max(reach.crowd_distance);
        // A group of radius at most `small` wholly beyond `beyond` subtends a ratio r/d below
        // `q`: an impostor's (below 0.1, and its width below the impostor width), by a margin.
        let q = (0.09f64).min(0.9 * libm::sin(0.5 * reach.impostor_width.min(1.0)));
        let small = beyond * q / (1.0 - q);
        let index = &self.round_index;
        out.clear();
        index
            .grid
            .append_within(&index.centers, eye, (beyond + small) * (1.0 + 1e-9), out);
        let wide = index
            .widest
            .iter()
            // Wider than `small`, or a radius that is not a number (sorted first).
            .take_while(|&&k| {
                !matches!(
                    self.rounds[k as usize].radius.partial_cmp(&small),
                    Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
                )
            })
            .chain(&index.unplaced);
        out.extend(wide);
        ascending_once(out, self.rounds.len(), bits);
        Some(out)
    }

    /// [`ColumnScene::look`] into `look`, reusing its buffers, for `viewer`. With a sector,
    /// robot parts wholly outside it are left out (they could face no photodiode); with a
    /// crowd distance, other robots farther than it.
    pub(super) fn look_into(
        &self,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
        reach: Reach,
        look: &mut Look,
    ) {
        let sector = reach.sector;
        let eye2 = DVec2::new(eye.x, eye.z);
        let (cos_h, sin_h) = reach
            .turn
            .unwrap_or_else(|| (libm::cos(heading), libm::sin(heading)));
        let Look {
            objects,
            breaks,
            edges,
            static_slots,
            near,
            impostors,
            standing,
            round_far,
            round_visit,
            round_bits,
            rounds_listed,
            reach_cos,
            wall_cover,
            ..
        } = look;
        objects.clear();
        breaks.clear();
        edges.clear();
        static_slots.clear();
        if keep_slots_for(reach) {
            static_slots.resize(frame.statics.len(), 0);
        }
        impostors.clear();
        standing.clear();
        let statics = frame.statics.len();
        let impostor_width = reach.impostor_width;
        let crowd_look = reach.crowd_distance.is_finite();
        // Where objects may be left out, each static object's place among `objects`.
        let keep_slots = keep_slots_for(reach);
        // Far small round static objects first, with their pieces: each an impostor, or left
        // out beyond the strip or the far distance. A tight loop over the scene's round groups,
        // or with a far distance over those it may reach.
        round_far.clear();
        let mut limited = false;
        if impostor_width > 0.0 && reach.rounds == Rounds::Given {
            // The caller's groups are placed (`round_visit`, ascending); none is told.
            limited = true;
        } else if impostor_width > 0.0 {
            let (first, last) = reach.extent;
            // The strip's reach, worked out once per strip and width.
            let key = (
                impostor_width.to_bits(),
                reach.extent.0.to_bits(),
                reach.extent.1.to_bits(),
            );
            if reach_cos.0 != key {
                *reach_cos = (
                    key,
                    impostor::Viewpoint::reach_cos(impostor_width, reach.extent),
                );
            }
            let mut viewpoint = impostor::Viewpoint::new(
                eye,
                (cos_h, sin_h),
                (reach.crowd_distance, reach.far_distance),
                impostor_width,
                reach_cos.1,
            );
            if reach.rounds == Rounds::TellAround {
                viewpoint.keep_all_around();
            }
            let mut tell = |round: &super::scene::Round| {
                let Some((lo, hi, distance)) = viewpoint.far(round.center, round.radius) else {
                    return false;
                };
                if lo <= hi && hi >= first && lo <= last {
                    impostors.push(Impostor {
                        lo,
                        hi,
                        distance,
                        radius: round.radius,
                        y0: round.y0 - eye.y,
                        first_static: round.first,
                        pieces: round.pieces,
                        top: (round.y1 - eye.y) / distance,
                        visible: 1.0,
                    });
                }
                true
            };
            match self.reachable_rounds(eye2, reach, round_visit, round_bits) {
                Some(visit) => {
                    // The groups not visited lie wholly beyond the far distance: left out. The
                    // visited ones are told in group order, as the full loop would.
                    limited = true;
                    round_far.resize(self.rounds.len(), true);
                    for &group in visit.iter() {
                        round_far[group as usize] = tell(&self.rounds[group as usize]);
                    }
                }
                None => round_far.extend(self.rounds.iter().map(tell)),
            }
        }
        let round_far = &*round_far;
        // The groups told as impostors (or left out) are passed over, pieces and all, before
        // `place` is called: the loops below skip them. Their static slots are left as they
        // are: only hiders' slots are read, and a round group never hides.
        if limited && reach.rounds != Rounds::Given {
            round_visit.retain(|&group| !round_far[group as usize]);
        }
        *rounds_listed = limited;
        // The previous object placed, its interval, and what became of it.
        let mut previous: Option<(&Upright, Option<Interval>, Fate)> = None;
        // Static objects, then robot parts (each viewer's own as its turret sees them), by
        // two plain loops: the per-object work is small, so the iteration shows.
        // Each call places the object of order `order` (static objects first, robot parts
        // from `statics` on) and says how many static objects it took: a far buoy and its
        // lamp become one impostor at once.
        let (extent_lo, extent_hi) = reach.extent;
        // A look with impostors, told or kept, lists the standing objects that may hide them
        // (given the kept groups, it tells none: the kept boxes are settled against these).
        let lists_hiders = impostor_width > 0.0;
        // The crowd level of detail draws a floor its walls enclose as the ground; whether they
        // do is known once every wall is placed.
        let floor = self.floor.as_ref().filter(|floor| {
            let under = &frame.statics[floor.order];
            crowd_look
                && frame.all_fast
                && eye.y > under.y1
                && super::footprint::surrounds(&under.footprint, eye2)
        });
        wall_cover.clear();
        let mut floor_slot = None;
        let mut place = typed(frame, |order: usize, object, fresh: bool| -> usize {
            if fresh {
                previous = None;
            }
            let index = objects.len();
            // Static objects keep their order unless some may be left out.
            if order < statics && keep_slots {
                static_slots[order] = index as u32;
            }
            // A lamp on its buoy has the buoy's footprint: its interval is the buoy's.
            let shares_previous = |before: &Upright| match self.same_footprint.get(order) {
                Some(&same) => same,
                None => before.footprint == object.footprint,
            };
            let (interval, shared) = match previous {
                Some((before, interval, fate)) if shares_previous(before) => match fate {
                    Fate::LeftOut => return 1,
                    Fate::Placed => (interval, true),
                },
                _ => {
                    // Robot parts, and static objects no corner test names.
                    let may_leave = order >= statics || self.cullable[order];
                    if may_leave
                        && reach.out_of_band.is_finite()
                        && out_of_band(object, eye, reach.out_of_band)
                    {
                        // Stacked pieces of its footprint are tested each on its own.
                        previous = None;
                        return 1;
                    }
                    if let Some(sector) = sector.filter(|_| may_leave) {
                        let (center, radius) = object.footprint.bounding_circle();
                        let offset = center - eye2;
                        if sector.excludes(DVec2::new(offset.x, -offset.y), radius) {
                            previous = Some((object, None, Fate::LeftOut));
                            return 1;
                        }
                    }
                    (azimuth_interval(object, eye2, heading, crowd_look), false)
                }
            };
            previous = Some((object, interval, Fate::Placed));
            // A shared round silhouette's edges are already in (a rectangle's may yet be
            // hidden for one object and not for the other).
            let edges_in = shared && interval.is_some_and(|i| i.corners.is_none());
            // Edges wrapped into (−π, π]: an interval through ±π wraps to lo > hi.
            let (lo, hi) = interval.map_or((f64::NEG_INFINITY, f64::INFINITY), |i| {
                (wrap(i.lo), wrap(i.hi))
            });
            if let Some(interval) = interval.filter(|_| !edges_in) {
                // An interval may reach past ±π; its edges are where a column of (−π, π] meets
                // them. An edge another object may hide waits until every object is placed.
                // Only edges within the extent cut a region: the others are not kept (nor
                // tested for hiding), as the regions would leave them out.
                let hiders = self.hiders.get(order).map_or(&[][..], Vec::as_slice);
                for (angle, corner) in [
                    (lo, interval.corners.map(|c| c.0)),
                    (hi, interval.corners.map(|c| c.1)),
                ] {
                    if !(angle > extent_lo && angle < extent_hi) {
                        continue;
                    }
                    match corner {
                        Some(corner) if hiders.iter().any(|h| h.corner == corner) => {
                            match corner_of(&object.footprint, corner as usize) {
                                Some(point) => edges.push(PendingEdge {
                                    angle,
                                    object: index as u32,
                                    order: order as u32,
                                    corner,
                                    to_corner: point - eye2,
                                }),
                                None => breaks.push(angle),
                            }
                        }
                        _ => breaks.push(angle),
                    }
                }
            }
            let placed = eye_object(object, eye, lo, hi);
            if let Some(floor) = floor.filter(|_| order < statics) {
                if order == floor.order {
                    floor_slot = Some(index);
                } else if floor.walls[order] && interval.is_some() && object.y1 >= eye.y {
                    wall_cover.push((lo, hi));
                }
            }
            if lists_hiders {
                // Round objects drawn exactly may hide impostors: stacked pieces of one
                // footprint (a near buoy and its lamp) as one.
                if let (Footprint::Circle { center, .. }, false) = (object.footprint, placed.wraps)
                {
                    match standing.last_mut() {
                        Some(last) if shared && placed.y0 <= last.y1 => {
                            last.y0 = last.y0.min(placed.y0);
                            last.y1 = last.y1.max(placed.y1);
                        }
                        _ => standing.push(Standing {
                            lo,
                            hi,
                            distance: center.distance(eye2),
                            y0: placed.y0,
                            y1: placed.y1,
                        }),
                    }
                }
            }
            objects.push(placed);
            1
        });
        if limited {
            // The static objects in no round group and the visited groups, in static order.
            let (loose, visit) = (&self.round_index.loose, &*round_visit);
            let (mut l, mut g, mut next) = (0, 0, 0);
            loop {
                let loose_first = match (loose.get(l), visit.get(g)) {
                    (Some(&s), Some(&k)) => s < self.rounds[k as usize].first,
                    (Some(_), None) => true,
                    (None, Some(_)) => false,
                    (None, None) => break,
                };
                let (start, end) = if loose_first {
                    let s = loose[l] as usize;
                    l += 1;
                    (s, s + 1)
                } else {
                    let round = &self.rounds[visit[g] as usize];
                    g += 1;
                    (round.first as usize, (round.first + round.pieces) as usize)
                };
                let mut order = start;
                while order < end.min(statics) {
                    order += place(order, &frame.statics[order], order != next);
                    next = order;
                }
            }
        } else {
            // A group passed over ends the run of shared footprints, as a placed object would.
            let (mut order, mut fresh) = (0, false);
            while order < statics {
                let group = self.round_at.get(order).map_or(0, |&g| g as usize);
                if group > 0 && round_far.get(group - 1) == Some(&true) {
                    order += self.rounds[group - 1].pieces as usize;
                    fresh = true;
                    continue;
                }
                order += place(order, &frame.statics[order], fresh);
                fresh = false;
            }
        }
        let part = |entry: usize| {
            if Some(frame.part_robot[entry]) == viewer {
                frame.own.get(entry).and_then(Option::as_ref)
            } else {
                frame.others[entry].as_ref()
            }
        };
        match &self.parts_of {
            Some(parts_of) if reach.crowd_distance.is_finite() => {
                let mut place_robot = |robot: usize| {
                    let other = Some(robot) != viewer;
                    for entry in parts_of.get(robot).cloned().unwrap_or(0..0) {
                        // Other robots' parts tucked under their body are left out.
                        if other && self.tucked.get(entry).copied().unwrap_or(false) {
                            continue;
                        }
                        if let Some(object) = part(entry) {
                            place(statics, object, false);
                        }
                    }
                };
                if frame.robot_at.len() <= FEW {
                    // A few robots: tested each in order, the grid's answer (with the
                    // viewer's own parts, as its turret sees them, wherever the eye is)
                    // without building it.
                    let limit = reach.crowd_distance * reach.crowd_distance;
                    for (robot, at) in frame.robot_at.iter().enumerate() {
                        if Some(robot) == viewer || at.distance_squared(eye2) <= limit {
                            place_robot(robot);
                        }
                    }
                } else {
                    let grid = frame.crowd.get_or_init(|| {
                        Box::new(CrowdGrid::new(&frame.robot_at, reach.crowd_distance))
                    });
                    grid.within(&frame.robot_at, eye2, reach.crowd_distance, near);
                    // The viewer's own parts, as its turret sees them, wherever the eye is.
                    if let Some(viewer) = viewer.filter(|&v| v < frame.robot_at.len()) {
                        if let Err(at) = near.binary_search(&(viewer as u32)) {
                            near.insert(at, viewer as u32);
                        }
                    }
                    for &robot in near.iter() {
                        place_robot(robot as usize);
                    }
                }
            }
            _ => {
                // Exact (the usual case) tests no distance.
                let crowd = reach.crowd_distance.is_finite();
                let distance2 = reach.crowd_distance * reach.crowd_distance;
                for entry in 0..frame.part_robot.len() {
                    let robot = frame.part_robot[entry];
                    let far = crowd
                        && Some(robot) != viewer
                        && frame
                            .robot_at
                            .get(robot)
                            .is_some_and(|at| at.distance_squared(eye2) > distance2);
                    // Other robots' parts tucked under their body are left out too.
                    let tucked = crowd
                        && Some(robot) != viewer
                        && self.tucked.get(entry).copied().unwrap_or(false);
                    if let Some(object) = part(entry).filter(|_| !far && !tucked) {
                        place(statics, object, false);
                    }
                }
            }
        }
        for edge in edges.iter() {
            if !self.edge_hidden(objects, static_slots, edge) {
                breaks.push(edge.angle);
            }
        }
        look.ground_floor = None;
        if let Some(slot) = floor_slot {
            if covers(wall_cover, reach.extent) {
                // Facing no region: its interval is empty.
                let floor = &mut objects[slot];
                (floor.lo, floor.hi, floor.wraps) = (f64::INFINITY, f64::NEG_INFINITY, false);
                look.ground_floor = Some(floor.primitive);
            }
        }
        // Told all around for kept impostors, they are settled against one another alone:
        // which the near robots and buoys hide is settled at each update (`kept.rs`).
        let hiders: &[Standing] = if reach.rounds == Rounds::TellAround {
            &[]
        } else {
            &look.standing
        };
        impostor::settle(
            &mut look.impostors,
            hiders,
            &mut look.occlusion,
            &mut look.impostor_keys,
        );
        impostor::by_centre(
            &look.impostors,
            &mut look.centre_keys,
            &mut look.impostor_order,
        );
        let breaks = &mut look.breaks;
        // Equal edges are merged below, so their order does not matter: insertion for the
        // dozen edges of an arena, O(B log B) for a crowd.
        if breaks.len() <= FEW {
            sort_small(breaks);
        } else {
            sort_total(breaks);
        }
        // Objects may share an edge: one is enough.
        breaks.dedup();
        look.eye = eye;
        look.crowd = frame.robot_at.len() > FEW;
        look.cos_h = cos_h;
        look.sin_h = sin_h;
    }

    /// Whether a rectangle's silhouette edge is hidden where it stands: the sight line to
    /// its corner passes through another object (a hider, see [`super::footprint::Hider`])
    /// whose side covers the edge's whole elevation range. Then nothing of the rectangle shows
    /// near that azimuth, the column integrand is as smooth there as on either side, and the
    /// edge need not cut the strip (the end of one arena wall behind the next, at each
    /// corner). Only static objects have hiders.
    fn edge_hidden(&self, objects: &[EyeObject], slots: &[u32], edge: &PendingEdge) -> bool {
        let hidden = &objects[edge.object as usize];
        self.hiders[edge.order as usize]
            .iter()
            .filter(|h| h.corner == edge.corner)
            .any(|h| {
                // (A hider has a side: `corner_hiders` keeps no other. Objects that hide or
                // are hidden are never left out; with nothing left out, order is slot.)
                let slot = match slots.get(h.object as usize) {
                    Some(&slot) => slot as usize,
                    None => h.object as usize,
                };
                let hider = &objects[slot];
                // Along the sight line in units of the corner's distance (the corner at 1):
                // entered strictly before the corner, from outside, and its side there spans
                // the edge's tan-elevations (and so any cap of the hidden object, which meets
                // the edge at its height). Heights over distances compare as heights over
                // these units: both sides share the distance.
                let Some(entry) = hider.relative.entry(edge.to_corner) else {
                    return false;
                };
                entry > 0.0
                    && entry < 1.0 - 1e-9
                    && hider.y0 / entry <= hidden.y0
                    && hider.y1 / entry >= hidden.y1
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crowds_lists_are_the_filters_lists() {
        let mut unit = crate::test_random::unit_stream(11);
        let mut angle = || (unit() * 2.0 - 1.0) * std::f64::consts::PI;
        for trial in 0..200 {
            let mut look = Look::default();
            for _ in 0..(trial % 40) {
                let (lo, hi) = (angle(), angle());
                look.objects.push(EyeObject {
                    lo,
                    hi,
                    wraps: lo > hi,
                    relative: Relative::Circle {
                        oc: DVec2::ONE,
                        c: 1.0,
                        radius: 0.1,
                    },
                    y0: -0.05,
                    y1: 0.0,
                    side: true,
                    top: true,
                    bottom: false,
                    primitive: 0,
                });
            }
            let (a, b) = (angle(), angle());
            let (a, b) = (a.min(b), a.max(b));
            let (mut filtered, mut unbranched) = (Vec::new(), vec![7; 3]);
            look.crowd = false;
            let few = look.facing_over(a, b, &mut filtered).to_vec();
            look.crowd = true;
            assert_eq!(
                look.facing_over(a, b, &mut unbranched),
                few,
                "trial {trial}"
            );
            let holding: Vec<u32> = (0..look.objects.len() as u32)
                .filter(|&k| look.objects[k as usize].holds(a))
                .collect();
            assert_eq!(look.facing(a, &mut unbranched), holding, "trial {trial}");
        }
    }

    #[test]
    fn ascending_once_sorts_and_drops_repeats_by_bitmap_or_by_sorting() {
        let mut unit = crate::test_random::unit_stream(47);
        let mut bits = Vec::new();
        for case in 0..200 {
            // Bounds from one word to many words per value: both ways are taken.
            let bound = 1 + (unit() * [70.0, 700.0, 70_000.0][case % 3]) as usize;
            let count = (unit() * 120.0) as usize;
            let mut values: Vec<u32> = (0..count)
                .map(|_| (unit() * bound as f64) as u32 % bound as u32)
                .collect();
            let mut expected = values.clone();
            expected.sort_unstable();
            expected.dedup();
            ascending_once(&mut values, bound, &mut bits);
            assert_eq!(values, expected, "bound {bound}, {count} values");
        }
        // A value at or past the bound is sorted, not lost.
        let mut values = vec![9, 3, 70, 3];
        ascending_once(&mut values, 64, &mut bits);
        assert_eq!(values, [3, 9, 70]);
    }

    #[test]
    fn sorting_by_keys_is_total_cmp_order() {
        let mut values = vec![
            0.5,
            -0.0,
            0.0,
            -1.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
            3.25e-300,
            -3.25e-300,
            1.0,
            -2.0,
            0.5,
        ];
        for i in 0..200 {
            values.push(libm::sin(i as f64 * 1.7) * 3.0);
        }
        let mut expected = values.clone();
        expected.sort_by(f64::total_cmp);
        sort_total(&mut values);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&values), bits(&expected));
    }
}
