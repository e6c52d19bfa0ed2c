//! The angular sweep over one look: which objects face each region between silhouette
//! edges, asked left to right, at a cost that follows the objects open there rather than every
//! object (`sweep.rs` builds the look it sweeps).

use super::footprint::Relative;
use super::photodiode::total_key;
use super::sweep::{Look, FEW};

/// The angular sweep over one look: asked for the objects facing azimuth intervals `(a, b)`
/// with `a` never decreasing, it keeps the objects whose intervals have opened and not yet
/// closed, so each answer costs the objects open there, not every object. Its answers are
/// exactly [`EyeObject::meets`]'s, nearest first (by the distance to their footprint's
/// centre; ties by object order): a column's segments then mostly come front to back, and
/// sorting them moves little.
#[derive(Default)]
pub(super) struct Sweep {
    /// Objects with an ordinary interval (their start's [`total_key`], their index), by
    /// their interval's start.
    order: Vec<(u64, u32)>,
    /// How many of `order` have opened.
    opened: usize,
    /// Objects open now (and those whose interval passes ±π, always), as (rank, index),
    /// by rank.
    open: Vec<(u32, u32)>,
    /// Objects nearest first, each its distance key above its index.
    nearest: Vec<u64>,
    /// Each object's place in `nearest`.
    rank: Vec<u32>,
    /// The last query's start.
    last: f64,
    /// Few objects: each query tests them all.
    brute: bool,
}

/// The squared distance from the eye to a footprint's centre, to single precision (an
/// order, not a measure), above `index`: sorted, nearest first, ties by index.
#[inline]
fn nearness_key(relative: &Relative, index: usize) -> u64 {
    let distance2 = match *relative {
        Relative::Circle { oc, .. } => oc.length_squared(),
        Relative::Rect { pu, pv, .. } => pu * pu + pv * pv,
    };
    // A non-negative float's bits rise with it (a NaN sorts last).
    ((distance2 as f32).to_bits() as u64) << 32 | index as u64
}

impl Sweep {
    /// Starts a sweep over `look` from the far left (−∞); `exhaustive` tests every object
    /// at each query instead.
    pub(super) fn start(&mut self, look: &Look, exhaustive: bool) {
        self.order.clear();
        self.open.clear();
        self.brute = exhaustive || look.objects.len() <= FEW;
        if self.brute {
            return;
        }
        self.nearest.clear();
        self.nearest.extend(
            look.objects
                .iter()
                .enumerate()
                .map(|(index, object)| nearness_key(&object.relative, index)),
        );
        self.nearest.sort_unstable();
        self.rank.clear();
        self.rank.resize(look.objects.len(), 0);
        for (rank, &key) in self.nearest.iter().enumerate() {
            self.rank[key as u32 as usize] = rank as u32;
        }
        for (index, object) in look.objects.iter().enumerate() {
            if object.wraps {
                self.open.push((self.rank[index], index as u32));
            } else {
                self.order.push((total_key(object.lo), index as u32));
            }
        }
        self.open.sort_unstable();
        // Objects with equal starts open together, so their order here does not matter.
        self.order.sort_unstable_by_key(|&(key, _)| key);
        self.opened = 0;
        self.last = f64::NEG_INFINITY;
    }

    /// Whether each query tests every object (few objects, or exhaustive): its answers are then
    /// [`Look::facing_over`]'s, last placed first.
    pub(super) fn tests_every_object(&self) -> bool {
        self.brute
    }

    /// The objects whose azimuth interval meets `(a, b)`, nearest first (last placed first
    /// where there are few), into `out`.
    #[inline]
    pub(super) fn facing_over<'o>(
        &mut self,
        look: &Look,
        a: f64,
        b: f64,
        out: &'o mut Vec<u32>,
    ) -> &'o [u32] {
        if self.brute {
            return look.facing_over(a, b, out);
        }
        if a < self.last {
            // Backwards (overlapping windows): start again.
            self.start(look, false);
        }
        self.last = a;
        let objects = &look.objects;
        // Intervals that closed at or before `a` meet nothing from here on.
        self.open.retain(|&(_, index)| {
            let o = &objects[index as usize];
            o.wraps || o.hi > a
        });
        while let Some(&(_, next)) = self.order.get(self.opened) {
            if objects[next as usize].lo >= b {
                break;
            }
            self.opened += 1;
            if objects[next as usize].hi > a {
                let rank = self.rank[next as usize];
                let at = self.open.partition_point(|&(r, _)| r < rank);
                self.open.insert(at, (rank, next));
            }
        }
        out.clear();
        out.extend(
            self.open
                .iter()
                .filter(|&&(_, index)| objects[index as usize].meets(a, b))
                .map(|&(_, index)| index),
        );
        out
    }
}
