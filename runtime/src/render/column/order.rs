//! Ordering a look's impostors in linear time: by distance for their occlusion, by centre for
//! drawing. A look across a large arena has hundreds of impostors, and two comparison sorts
//! of them were a fifth of a retina's cost at 10,000 robots (issue 41). The keys are spread
//! evenly over a known range, so they are dealt into buckets by a monotone function of the
//! key, and each bucket is then ordered on its own: the result is exactly the comparison
//! sort's (the keys are unique, the index in their low bits), in about two passes.

/// Below this many keys a comparison sort is as cheap as dealing them out.
const FEW: usize = 96;

/// Buckets per key, at most: a bucket then holds one or two keys on average.
const BUCKETS_PER_KEY: usize = 2;

/// Reusable buffers for [`sort_by_buckets`].
#[derive(Default)]
pub(super) struct Buckets<K> {
    counts: Vec<u32>,
    dealt: Vec<K>,
}

/// Sorts `keys` (unique) ascending, as `sort_unstable` would. `position` maps a key to a
/// number that never decreases as the key grows (equal keys' numbers equal, NaN never); the
/// keys are dealt into buckets evenly over the numbers' range, and each bucket sorted.
pub(super) fn sort_by_buckets<K: Copy + Ord>(
    keys: &mut [K],
    buffers: &mut Buckets<K>,
    position: impl Fn(K) -> f64,
) {
    let n = keys.len();
    if n <= FEW {
        keys.sort_unstable();
        return;
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &key in keys.iter() {
        let p = position(key);
        if p.is_nan() {
            keys.sort_unstable();
            return;
        }
        lo = if p < lo { p } else { lo };
        hi = if p > hi { p } else { hi };
    }
    let buckets = n * BUCKETS_PER_KEY;
    let scale = buckets as f64 / (hi - lo);
    // One range (every position equal) or none that spreads: a comparison sort.
    if !(scale.is_finite() && scale > 0.0) {
        keys.sort_unstable();
        return;
    }
    // The last position lands on `buckets`: one bucket more. A position's bucket never
    // decreases as it grows (a product and a truncation of a non-negative number).
    let bucket = |key: K| (((position(key) - lo) * scale) as usize).min(buckets);
    let Buckets { counts, dealt } = buffers;
    counts.clear();
    counts.resize(buckets + 2, 0);
    for &key in keys.iter() {
        counts[bucket(key) + 1] += 1;
    }
    for b in 1..counts.len() {
        counts[b] += counts[b - 1];
    }
    dealt.clear();
    dealt.extend_from_slice(keys);
    for &key in dealt.iter() {
        let at = &mut counts[bucket(key)];
        keys[*at as usize] = key;
        *at += 1;
    }
    // Each bucket now ends where the next began: `counts[b]` is bucket b's end.
    let mut start = 0;
    for &end in &counts[..=buckets] {
        let end = end as usize;
        let bucket = &mut keys[start..end];
        match bucket.len() {
            0 | 1 => {}
            2 => {
                if bucket[1] < bucket[0] {
                    bucket.swap(0, 1);
                }
            }
            _ => bucket.sort_unstable(),
        }
        start = end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same order as `sort_unstable` on spread, clustered, equal and tiny key sets.
    #[test]
    fn buckets_order_keys_as_a_comparison_sort() {
        let mut unit = crate::test_random::unit_stream(5);
        let mut buffers = Buckets::default();
        for case in 0..400 {
            let n = [0, 1, 5, 96, 97, 300, 1000][case % 7];
            let values: Vec<f32> = (0..n)
                .map(|_| match case % 5 {
                    // Distances across an arena.
                    0 => 0.5 + 40.0 * unit() as f32,
                    // A ring: every key at one distance.
                    1 => 3.0,
                    // Two clusters far apart.
                    2 => {
                        if unit() < 0.5 {
                            1.0 + unit() as f32 * 1e-3
                        } else {
                            30.0
                        }
                    }
                    // Few distinct values.
                    3 => (unit() * 4.0).floor() as f32,
                    _ => (unit() as f32 - 0.5) * 6.0,
                })
                .collect();
            let mut keys: Vec<u64> = values
                .iter()
                .enumerate()
                .map(|(i, v)| u64::from(ordered(*v)) << 32 | i as u64)
                .collect();
            let mut expected = keys.clone();
            expected.sort_unstable();
            sort_by_buckets(&mut keys, &mut buffers, |key| {
                f64::from(from_ordered((key >> 32) as u32))
            });
            assert_eq!(keys, expected, "case {case}");
        }
    }

    /// An order-keeping u32 for an f32 (the total order of its bits).
    fn ordered(v: f32) -> u32 {
        let bits = v.to_bits();
        if bits >> 31 == 1 {
            !bits
        } else {
            bits | 1 << 31
        }
    }

    fn from_ordered(key: u32) -> f32 {
        f32::from_bits(if key >> 31 == 1 {
            key & !(1 << 31)
        } else {
            !key
        })
    }
}
