//! Lists built without a branch per candidate: which objects face a region, which robots lie
//! within reach. Whether a candidate is kept follows no pattern a branch predictor learns
//! (at 1000 robots a third of such branches missed, each some fifteen cycles), so every
//! candidate is written and the list's end moves on only past those kept.

/// Appends to `out` the values of `candidates` whose flag is set, in order.
#[inline(always)]
pub(super) fn extend_kept(
    out: &mut Vec<u32>,
    candidates: impl ExactSizeIterator<Item = (u32, bool)>,
) {
    let start = out.len();
    out.resize(start + candidates.len(), 0);
    let kept = write_kept(&mut out[start..], candidates);
    out.truncate(start + kept);
}

/// Writes the values `candidate(k)` gives for k = 0…count − 1 whose flag is set to the start of
/// `out`, in order, and returns them. `out` only grows (to `count`): what lies past the part
/// returned is left over from earlier lists, so that a list costs no clearing or filling.
#[inline(always)]
pub(super) fn kept_prefix(
    out: &mut Vec<u32>,
    count: usize,
    candidate: impl Fn(usize) -> (u32, bool),
) -> &[u32] {
    if out.len() < count {
        out.resize(count, 0);
    }
    let kept = write_kept(out, (0..count).map(candidate));
    &out[..kept]
}

/// Writes the flagged values of `candidates` to the start of `slots` (at least as many as the
/// candidates), every one written and the end moved on only past those kept; returns how many
/// were kept.
#[inline(always)]
fn write_kept(slots: &mut [u32], candidates: impl Iterator<Item = (u32, bool)>) -> usize {
    let mut end = 0;
    for (value, keep) in candidates {
        // `end` never passes the candidate's own slot: the test always holds.
        if let Some(slot) = slots.get_mut(end) {
            *slot = value;
        }
        end += usize::from(keep);
    }
    end
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prefix_holds_the_flagged_values_whatever_was_left_over() {
        let mut out = vec![9; 7];
        let kept = kept_prefix(&mut out, 3, |k| ([1, 2, 3][k], k != 1));
        assert_eq!(kept, [1, 3]);
        let mut out = Vec::new();
        let kept = kept_prefix(&mut out, 40, |k| (k as u32, k % 4 == 0));
        assert_eq!(kept, (0..40).step_by(4).collect::<Vec<u32>>());
        assert_eq!(
            kept_prefix(&mut out, 0, |k| (k as u32, true)),
            [] as [u32; 0]
        );
    }

    #[test]
    fn keeps_the_flagged_values_in_order_after_what_was_there() {
        let mut out = vec![7, 8];
        extend_kept(
            &mut out,
            [(1, true), (2, false), (3, false), (4, true), (5, true)].into_iter(),
        );
        assert_eq!(out, [7, 8, 1, 4, 5]);
        extend_kept(&mut out, [(9, false)].into_iter());
        assert_eq!(out, [7, 8, 1, 4, 5]);
        extend_kept(&mut out, std::iter::empty());
        assert_eq!(out, [7, 8, 1, 4, 5]);
    }
}
