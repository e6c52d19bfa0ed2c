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
    let mut end = start;
    for (value, keep) in candidates {
        // `end` never passes the candidate's own slot: the test always holds.
        if let Some(slot) = out.get_mut(end) {
            *slot = value;
        }
        end += usize::from(keep);
    }
    out.truncate(end);
}

#[cfg(test)]
mod tests {
    use super::*;

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
