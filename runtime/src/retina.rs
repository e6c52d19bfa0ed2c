//! The EDI retina after its optics: photodetectors and normalisation, the resistive filtering
//! network, and the A/D converter (`../shared/reference/retina.md`, the paper's §3.2–3.4).
//!
//! Boundary rule of every network: the chain is mirrored at its ends (half-sample symmetric).
//! That is exactly the finite chain of 150 nodes whose end nodes have one neighbour, so the
//! O(n) recursions here equal the direct finite-chain solution everywhere, ends included.

/// Photodiodes of the EDI retina.
pub const PIXELS: usize = 150;
/// Angular width of one photodiode (rad): 1.6°.
pub const PIXEL_WIDTH: f64 = 1.6 * std::f64::consts::PI / 180.0;
/// Half the elevation band (rad): 5.5°.
pub const HALF_BAND: f64 = 5.5 * std::f64::consts::PI / 180.0;

/// Azimuth of pixel `i` (rad, counter-clockwise from forward): +120° − (i + ½)·1.6°.
pub fn pixel_azimuth(i: usize) -> f64 {
    (120.0 - (i as f64 + 0.5) * 1.6) * std::f64::consts::PI / 180.0
}

/// One output of the filtering layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FilterKind {
    /// The analog image itself.
    Raw,
    Lowpass,
    Highpass,
    Bandpass,
    Odd,
}

impl FilterKind {
    pub const ALL: [FilterKind; 5] = [
        FilterKind::Raw,
        FilterKind::Lowpass,
        FilterKind::Highpass,
        FilterKind::Bandpass,
        FilterKind::Odd,
    ];

    pub fn name(self) -> &'static str {
        match self {
            FilterKind::Raw => "raw",
            FilterKind::Lowpass => "lowpass",
            FilterKind::Highpass => "highpass",
            FilterKind::Bandpass => "bandpass",
            FilterKind::Odd => "odd",
        }
    }

    pub fn from_name(name: &str) -> Option<FilterKind> {
        FilterKind::ALL.into_iter().find(|k| k.name() == name)
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// A set of enabled filters (only these are computed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct FilterSet(u8);

impl FilterSet {
    pub fn insert(&mut self, kind: FilterKind) {
        self.0 |= kind.bit();
    }
    pub fn remove(&mut self, kind: FilterKind) {
        self.0 &= !kind.bit();
    }
    pub fn contains(self, kind: FilterKind) -> bool {
        self.0 & kind.bit() != 0
    }
    pub fn iter(self) -> impl Iterator<Item = FilterKind> {
        FilterKind::ALL
            .into_iter()
            .filter(move |k| self.contains(*k))
    }
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

/// Photodetectors: PAL/BT.601 luminance of linear RGB.
pub fn luminance(rgb: [f64; 3]) -> f64 {
    0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]
}

/// Normalisation circuit: `analog[i] = y[i] / mean(y)`. Returns false (and zeros) when the
/// mean is zero or not finite: a dark retina has no defined image, never NaN.
#[inline(always)]
pub fn normalize(y: &[f64], analog: &mut [f64]) -> bool {
    let n = y.len() as f64;
    // The usual image is finite: a peak that is finite and a sum that is not NaN prove it,
    // and then no element needs its own test. The peak in four lanes: max is exact, so
    // the order does not change it. A plain compare, not `f64::max`: a NaN never wins it
    // (and then shows in the sum), and it needs no NaN fix-up per element.
    let larger = |m: f64, v: f64| if v > m { v } else { m };
    // Fours as arrays (`as_chunks`): a pointer step each, where `chunks_exact` splits a slice.
    let (fours, rest) = y.as_chunks::<4>();
    let mut lanes = [0.0f64; 4];
    for chunk in fours {
        for (lane, &v) in lanes.iter_mut().zip(chunk) {
            *lane = larger(*lane, v.abs());
        }
    }
    let peak = rest.iter().fold(
        larger(larger(lanes[0], lanes[1]), larger(lanes[2], lanes[3])),
        |m, &v| larger(m, v.abs()),
    );
    if peak > 0.0 && peak.is_finite() {
        let inverse_peak = 1.0 / peak;
        // Four partial sums: a chain of 150 dependent additions would dominate the stage.
        let mut partial = [0.0f64; 4];
        for chunk in fours {
            for (sum, &v) in partial.iter_mut().zip(chunk) {
                *sum += v * inverse_peak;
            }
        }
        let sum = rest.iter().fold(
            (partial[0] + partial[1]) + (partial[2] + partial[3]),
            |s, &v| s + v * inverse_peak,
        );
        if !sum.is_nan() {
            return scale_by_mean(y, analog, inverse_peak, sum / n, |v| v);
        }
    }
    // Some photocurrent is infinite or NaN: those read 0.
    let finite_or_zero = |v: f64| if v.is_finite() { v } else { 0.0 };
    // Scale first so that 1e300-size radiances cannot overflow the sum.
    let peak = y
        .iter()
        .fold(0.0f64, |m, &v| m.max(finite_or_zero(v).abs()));
    if peak == 0.0 || !peak.is_finite() {
        analog.iter_mut().for_each(|a| *a = 0.0);
        return false;
    }
    let inverse_peak = 1.0 / peak;
    let mean = y
        .iter()
        .map(|&v| finite_or_zero(v) * inverse_peak)
        .sum::<f64>()
        / n;
    scale_by_mean(y, analog, inverse_peak, mean, finite_or_zero)
}

/// `analog = read(y) / mean`, from the mean of `read(y)` scaled by `inverse_peak`; false (and
/// zeros) when that mean is not positive.
#[inline(always)]
fn scale_by_mean(
    y: &[f64],
    analog: &mut [f64],
    inverse_peak: f64,
    mean: f64,
    read: impl Fn(f64) -> f64,
) -> bool {
    if mean <= 0.0 {
        analog.iter_mut().for_each(|a| *a = 0.0);
        return false;
    }
    let scale = inverse_peak / mean;
    for (a, &v) in analog.iter_mut().zip(y) {
        *a = read(v) * scale;
    }
    true
}

/// A resistive chain's constants for one λ and one length, computed once per setting so that
/// filtering an image runs no transcendental: `a = e^(−1/λ)`, `1 − a` (without cancellation
/// for large λ), `aⁿ` and `1 − a²ⁿ`, and the powers `a^k` for k = 0…n + 1 (each from λ
/// directly).
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    len: usize,
    a: f64,
    one_minus_a: f64,
    a_n: f64,
    period: f64,
    /// Shared by the chain's copies (a filter's two chains, the turrets of a swarm).
    powers: std::sync::Arc<[f64]>,
    /// `a^(n−i)` for i = 0…n − 1: the powers a left-going pass takes, in the order it writes
    /// them, so that its loops run forward (in vector lanes, no reversal).
    falling: std::sync::Arc<[f64]>,
}

/// Independent blocks a recursion is cut into, so that their dependency chains overlap.
const BLOCKS: usize = 4;

impl Chain {
    pub fn new(lambda: f64, len: usize) -> Chain {
        let lambda = lambda.max(1e-12);
        let n = len as f64;
        let powers: std::sync::Arc<[f64]> = (0..len + 2)
            .map(|k| libm::exp(-(k as f64) / lambda))
            .collect::<Vec<f64>>()
            .into();
        Chain {
            len,
            a: libm::exp(-1.0 / lambda),
            one_minus_a: -libm::expm1(-1.0 / lambda),
            a_n: libm::exp(-n / lambda),
            period: -libm::expm1(-2.0 * n / lambda),
            falling: (1..=len)
                .rev()
                .map(|k| powers[k])
                .collect::<Vec<f64>>()
                .into(),
            powers,
        }
    }

    /// The zero-state recursion `y[p] = a·y[p−1] + (1−a)·x[p]`, y[−1] = 0, in place, `p`
    /// running forward or (REVERSE) from the last element down.
    ///
    /// The chain is cut into [`BLOCKS`] blocks run side by side from zero, whose dependency
    /// chains overlap in the pipeline; each block then receives the previous block's true
    /// end value `e` as `a^(i+1)·e` at its i-th element. The result equals the sequential
    /// recursion up to rounding.
    #[inline(always)]
    fn recursion<const REVERSE: bool>(&self, data: &mut [f64]) {
        let n = data.len();
        let (a, c) = (self.a, self.one_minus_a);
        let at = |p: usize| if REVERSE { n - 1 - p } else { p };
        if n < 4 * BLOCKS {
            let mut state = 0.0;
            for p in 0..n {
                state = a * state + c * data[at(p)];
                data[at(p)] = state;
            }
            return;
        }
        let block = n.div_ceil(BLOCKS);
        let lengths: [usize; BLOCKS] =
            std::array::from_fn(|k| n.saturating_sub(k * block).min(block));
        let common = lengths[BLOCKS - 1];
        let mut state = [0.0; BLOCKS];
        for i in 0..common {
            for (k, s) in state.iter_mut().enumerate() {
                let p = at(k * block + i);
                *s = a * *s + c * data[p];
                data[p] = *s;
            }
        }
        for i in common..block {
            for (k, s) in state.iter_mut().enumerate() {
                if i < lengths[k] {
                    let p = at(k * block + i);
                    *s = a * *s + c * data[p];
                    data[p] = *s;
                }
            }
        }
        for k in 1..BLOCKS {
            let carry = data[at(k * block - 1)];
            for i in 0..lengths[k] {
                data[at(k * block + i)] += self.powers[i + 1] * carry;
            }
        }
    }

    /// Runs both zero-state passes over `x` (right-going into `right`, left-going into
    /// `left`) and returns where the true passes start: the recursions from each end over
    /// the mirrored continuation of `x` (period 2n) as they leave the image, `c·Σ_{k≥0} a^k
    /// s_k` for `s` = x[0], x[1], …, x[n−1], x[n−1], … (right-going) and its mirror image
    /// (left-going). With `L = Σ a^j x[j]` and `R = Σ a^(n−1−j) x[j]` they are
    /// `c·(L + aⁿ·R) / (1 − a²ⁿ)` and `c·(R + aⁿ·L) / (1 − a²ⁿ)`; the zero-state passes end
    /// on `c·R` and `c·L`.
    ///
    /// Out of line, in two copies (AVX2 where the CPU has it, as the retina's other stages,
    /// `Panoramic::process_photocurrents`): inlined into its callers, the baseline copy's
    /// eight chains no longer stay in registers and spill on every element (about 500
    /// instructions a retina more).
    #[inline(never)]
    fn zero_state_passes(&self, x: &[f64], right: &mut [f64], left: &mut [f64]) -> (f64, f64) {
        #[cfg(target_arch = "x86_64")]
        if crate::wide::avx2() {
            // SAFETY: the CPU has AVX2, as just tested.
            return unsafe { self.zero_state_passes_avx2(x, right, left) };
        }
        self.zero_state_passes_inlined(x, right, left)
    }

    /// [`Chain::zero_state_passes`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn zero_state_passes_avx2(&self, x: &[f64], right: &mut [f64], left: &mut [f64]) -> (f64, f64) {
        self.zero_state_passes_inlined(x, right, left)
    }

    #[inline(always)]
    fn zero_state_passes_inlined(
        &self,
        x: &[f64],
        right: &mut [f64],
        left: &mut [f64],
    ) -> (f64, f64) {
        let n = x.len();
        if n < 4 * BLOCKS {
            left.copy_from_slice(x);
            self.recursion::<true>(left);
            right.copy_from_slice(x);
            self.recursion::<false>(right);
        } else {
            // Both directions, each in blocks as in `recursion` and with the same arithmetic
            // per element.
            let (a, c) = (self.a, self.one_minus_a);
            let block = n.div_ceil(BLOCKS);
            let lengths: [usize; BLOCKS] =
                std::array::from_fn(|k| n.saturating_sub(k * block).min(block));
            let common = lengths[BLOCKS - 1];
            // Block k forward covers [k·block, k·block + len_k); backward, its mirror image,
            // read from its end. Slices cut to the lengths the loops run keep every index in
            // bounds by construction (no checks in the loops).
            let (x_lo, x_hi) = x.split_at(2 * block);
            let (x0, x1) = x_lo.split_at(block);
            let (x2, x3) = x_hi.split_at(block);
            let (right_lo, right_hi) = right[..n].split_at_mut(2 * block);
            let (r0, r1) = right_lo.split_at_mut(block);
            let (r2, r3) = right_hi.split_at_mut(block);
            let (left_lo, left_hi) = left[..n].split_at_mut(n - 2 * block);
            let (l3, l2) = left_lo.split_at_mut(n - 3 * block);
            let (l1, l0) = left_hi.split_at_mut(block);
            let (y_lo, y_hi) = x.split_at(n - 2 * block);
            let (y3, y2) = y_lo.split_at(n - 3 * block);
            let (y1, y0) = y_hi.split_at(block);
            let mut forward = [0.0; BLOCKS];
            let mut backward = [0.0; BLOCKS];
            macro_rules! sweep {
                ($range:expr, $len:expr, $([$k:expr, $x:ident, $r:ident, $y:ident, $l:ident]),+) => {
                    $(
                        let ($x, $r) = (&$x[..$len], &mut $r[..$len]);
                        let (skip_y, skip_l) = ($y.len() - $len, $l.len() - $len);
                        let ($y, $l) = (&$y[skip_y..], &mut $l[skip_l..]);
                    )+
                    // One direction at a time: four chains in flight each, with few enough
                    // pointers to stay in registers (both at once spill on every element).
                    for i in $range {
                        $(
                            forward[$k] = a * forward[$k] + c * $x[i];
                            $r[i] = forward[$k];
                        )+
                    }
                    for i in $range {
                        $(
                            let j = $len - 1 - i;
                            backward[$k] = a * backward[$k] + c * $y[j];
                            $l[j] = backward[$k];
                        )+
                    }
                };
            }
            {
                sweep!(
                    0..common,
                    common,
                    [0, x0, r0, y0, l0],
                    [1, x1, r1, y1, l1],
                    [2, x2, r2, y2, l2],
                    [3, x3, r3, y3, l3]
                );
            }
            {
                // The first three blocks are longer than the last by a pixel or two.
                let (x0, r0, y0, l0) = (
                    &x0[common..],
                    &mut r0[common..],
                    &y0[..block - common],
                    &mut l0[..block - common],
                );
                let (x1, r1, y1, l1) = (
                    &x1[common..],
                    &mut r1[common..],
                    &y1[..block - common],
                    &mut l1[..block - common],
                );
                let (x2, r2, y2, l2) = (
                    &x2[common..],
                    &mut r2[common..],
                    &y2[..block - common],
                    &mut l2[..block - common],
                );
                sweep!(
                    0..block - common,
                    block - common,
                    [0, x0, r0, y0, l0],
                    [1, x1, r1, y1, l1],
                    [2, x2, r2, y2, l2]
                );
            }
            for k in 1..BLOCKS {
                let carry = right[k * block - 1];
                let carried = &self.powers[1..=lengths[k]];
                for (r, power) in right[k * block..][..lengths[k]].iter_mut().zip(carried) {
                    *r += power * carry;
                }
                let carry = left[n - k * block];
                let end = n - k * block;
                // left[end − 1 − i] takes a^(i+1): a^(len_k − j) at end − len_k + j.
                let carried = &self.falling[self.len - lengths[k]..];
                for (l, power) in left[end - lengths[k]..end].iter_mut().zip(carried) {
                    *l += power * carry;
                }
            }
        }
        let (c_r, c_l) = (right[n - 1], left[0]);
        (
            (c_l + self.a_n * c_r) / self.period,
            (c_r + self.a_n * c_l) / self.period,
        )
    }

    /// Lowpass (symmetric exponential kernel `(1−a)/(1+a)·a^|n|`, unit DC gain) in O(n): a
    /// right-going pass, then a left-going pass over its output. Mirror symmetry of the
    /// result gives the left pass its start exactly: `y[n−1] = r[n−1]`.
    #[inline(always)]
    pub fn lowpass(&self, x: &[f64], out: &mut [f64]) {
        let Some(out) = self.with_passes(x, out, |out, _, (start, _)| {
            for (i, o) in out.iter_mut().enumerate() {
                *o += self.powers[i + 1] * start;
            }
        }) else {
            return;
        };
        let n = out.len();
        // The left-going pass over the right-going output, from y[n−1] = r[n−1].
        let end = out[n - 1];
        self.recursion::<true>(&mut out[..n - 1]);
        for (i, o) in out[..n - 1].iter_mut().enumerate() {
            *o += self.powers[n - 1 - i] * end;
        }
    }

    /// Odd (derivative): right-going minus left-going unidirectional network, kernel
    /// `(1−b)·sgn(n)·b^|n|` with `b = e^(−1/λ)`: zero at the centre, zero DC gain,
    /// antisymmetric. A rising edge to the right gives a positive response just after it.
    #[inline(always)]
    pub fn odd(&self, x: &[f64], out: &mut [f64]) {
        self.with_passes(x, out, |out, left, (right_start, left_start)| {
            // a^(i+1) rising for the right-going pass, a^(n−i) falling for the left-going one.
            let n = out.len();
            let weights = self.powers[1..=n].iter().zip(&self.falling[self.len - n..]);
            for ((o, l), (up, down)) in out.iter_mut().zip(left).zip(weights) {
                let right_going = *o + up * right_start;
                let left_going = *l + down * left_start;
                *o = right_going - left_going;
            }
        });
    }

    /// Runs [`Chain::zero_state_passes`] over the image (`x` and `out` cut to their common
    /// length: the right-going pass into `out`, the left-going one into scratch) and hands
    /// both, with the true starts, to `finish`; returns `out` so cut, or `None` when empty.
    #[inline(always)]
    fn with_passes<'o>(
        &self,
        x: &[f64],
        out: &'o mut [f64],
        finish: impl FnOnce(&mut [f64], &[f64], (f64, f64)),
    ) -> Option<&'o mut [f64]> {
        let n = x.len().min(out.len());
        if n == 0 {
            return None;
        }
        debug_assert_eq!(n, self.len, "a chain filters images of its own length");
        let (x, out) = (&x[..n], &mut out[..n]);
        // Every element of the left-going pass is written before it is read: the buffer
        // is kept from image to image, not zeroed. Taken out and put back, not used inside
        // `with`: the passes then stay inlined in their caller (the AVX2 copy of the
        // retina's stages, `Panoramic::process_photocurrents`).
        let mut left = LEFT_GOING.with(|cell| cell.take());
        if left.len() < n {
            left.resize(n, 0.0);
        }
        let starts = self.zero_state_passes(x, out, &mut left[..n]);
        finish(out, &left[..n], starts);
        LEFT_GOING.with(|cell| cell.set(left));
        Some(out)
    }
}

/// Lowpass over `x` with decay length `lambda` (see [`Chain::lowpass`]).
pub fn lowpass(x: &[f64], lambda: f64, out: &mut [f64]) {
    Chain::new(lambda, x.len()).lowpass(x, out);
}

/// Highpass: `x − lowpass_λ(x)`.
pub fn highpass(x: &[f64], lambda: f64, out: &mut [f64]) {
    let chain = Chain::new(lambda, x.len());
    Filter {
        kind: FilterKind::Highpass,
        chains: (chain.clone(), chain),
    }
    .apply(x, out);
}

thread_local! {
    /// The left-going pass of [`Chain::with_passes`], one buffer per thread.
    static LEFT_GOING: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Runs `f` with a scratch slice of `n` zeros: on the stack up to 256, else on the heap.
#[inline(always)]
fn with_scratch<R>(n: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    let mut stack = [0.0; 256];
    if n <= stack.len() {
        f(&mut stack[..n])
    } else {
        f(&mut vec![0.0; n])
    }
}

/// Bandpass: `lowpass_λ1(x) − lowpass_λ2(x)`, λ1 < λ2 (a difference of exponentials).
pub fn bandpass(x: &[f64], lambda1: f64, lambda2: f64, out: &mut [f64]) {
    let chains = (Chain::new(lambda1, x.len()), Chain::new(lambda2, x.len()));
    Filter {
        kind: FilterKind::Bandpass,
        chains,
    }
    .apply(x, out);
}

/// Odd filter over `x` with decay length `lambda` (see [`Chain::odd`]).
pub fn odd(x: &[f64], lambda: f64, out: &mut [f64]) {
    Chain::new(lambda, x.len()).odd(x, out);
}

/// Direct references the fast filters are tested against. They share nothing with the O(n)
/// code: the lowpass solves the finite resistive chain's linear system by Gaussian
/// elimination; the odd filter sums its kernel over the mirrored input.
pub mod reference {
    /// The finite chain: node i tied to its input by Gv and to each existing neighbour by Gh,
    /// with `a + 1/a = 2 + Gv/Gh`. Solves the dense system.
    pub fn lowpass(x: &[f64], lambda: f64) -> Vec<f64> {
        let n = x.len();
        let a = libm::exp(-1.0 / lambda);
        let c = a + 1.0 / a - 2.0; // Gv / Gh
        let mut m = vec![vec![0.0; n + 1]; n];
        for i in 0..n {
            let neighbours = (i > 0) as usize + (i + 1 < n) as usize;
            m[i][i] = c + neighbours as f64;
            if i > 0 {
                m[i][i - 1] = -1.0;
            }
            if i + 1 < n {
                m[i][i + 1] = -1.0;
            }
            m[i][n] = c * x[i];
        }
        // Gaussian elimination with partial pivoting.
        for col in 0..n {
            let pivot = (col..n)
                .max_by(|&p, &q| m[p][col].abs().total_cmp(&m[q][col].abs()))
                .unwrap();
            m.swap(col, pivot);
            for row in col + 1..n {
                let f = m[row][col] / m[col][col];
                if f != 0.0 {
                    for k in col..=n {
                        m[row][k] -= f * m[col][k];
                    }
                }
            }
        }
        let mut y = vec![0.0; n];
        for row in (0..n).rev() {
            let s: f64 = (row + 1..n).map(|k| m[row][k] * y[k]).sum();
            y[row] = (m[row][n] - s) / m[row][row];
        }
        y
    }

    /// The input continued by mirroring at both ends (period 2n).
    fn mirrored(x: &[f64], i: i64) -> f64 {
        let n = x.len() as i64;
        let k = i.rem_euclid(2 * n);
        if k < n {
            x[k as usize]
        } else {
            x[(2 * n - 1 - k) as usize]
        }
    }

    /// Dense convolution of the mirrored input with the odd kernel, to where it vanishes.
    pub fn odd(x: &[f64], lambda: f64) -> Vec<f64> {
        let b = libm::exp(-1.0 / lambda);
        let reach = ((lambda * 60.0).ceil() as i64).max(1);
        (0..x.len() as i64)
            .map(|i| {
                (1..=reach)
                    .map(|m| {
                        (1.0 - b)
                            * libm::pow(b, m as f64)
                            * (mirrored(x, i - m) - mirrored(x, i + m))
                    })
                    .sum()
            })
            .collect()
    }
}

/// Settings of the filtering layer and converter.
#[derive(Clone, Debug, PartialEq)]
pub struct FilterSettings {
    pub filters: FilterSet,
    pub lambda: f64,
    pub bandpass: (f64, f64),
    pub bits: u32,
    /// `None`: calibrated as the paper says.
    pub i_bda: Option<f64>,
}

impl FilterSettings {
    /// The same to the bit (where `==` takes 0.0 for −0.0): what builds the same filters.
    pub fn same_bits(&self, other: &FilterSettings) -> bool {
        self.filters == other.filters
            && self.lambda.to_bits() == other.lambda.to_bits()
            && self.bandpass.0.to_bits() == other.bandpass.0.to_bits()
            && self.bandpass.1.to_bits() == other.bandpass.1.to_bits()
            && self.bits == other.bits
            && self.i_bda.map(f64::to_bits) == other.i_bda.map(f64::to_bits)
    }
}

/// One filter with its chains built for one image length: what a turret runs every update.
#[derive(Clone, Debug, PartialEq)]
pub struct Filter {
    kind: FilterKind,
    /// The chain of λ (λ1 for the bandpass), and λ2's for the bandpass.
    chains: (Chain, Chain),
}

impl Filter {
    pub fn new(kind: FilterKind, settings: &FilterSettings, len: usize) -> Filter {
        let chains = match kind {
            FilterKind::Bandpass => (
                Chain::new(settings.bandpass.0, len),
                Chain::new(settings.bandpass.1, len),
            ),
            _ => {
                let chain = Chain::new(settings.lambda, len);
                (chain.clone(), chain)
            }
        };
        Filter { kind, chains }
    }

    pub fn kind(&self) -> FilterKind {
        self.kind
    }

    /// Filters `analog` (of the length the filter was built for) into `out`.
    #[inline(always)]
    pub fn apply(&self, analog: &[f64], out: &mut [f64]) {
        let (chain, wide_chain) = &self.chains;
        match self.kind {
            FilterKind::Raw => out.copy_from_slice(analog),
            FilterKind::Lowpass => chain.lowpass(analog, out),
            FilterKind::Highpass => {
                chain.lowpass(analog, out);
                for (o, &v) in out.iter_mut().zip(analog) {
                    *o = v - *o;
                }
            }
            FilterKind::Bandpass => {
                chain.lowpass(analog, out);
                with_scratch(analog.len(), |wide| {
                    wide_chain.lowpass(analog, wide);
                    for (o, w) in out.iter_mut().zip(wide.iter()) {
                        *o -= w;
                    }
                });
            }
            FilterKind::Odd => chain.odd(analog, out),
        }
    }
}

/// Applies one filter to `analog`.
pub fn apply(kind: FilterKind, settings: &FilterSettings, analog: &[f64], out: &mut [f64]) {
    Filter::new(kind, settings, analog.len()).apply(analog, out);
}

/// I_bda as the paper sets it: the largest |filtered| produced when one photodiode — the
/// central one, away from the chain's ends — is lit and all others are dark (analog 150 there,
/// mean 1). Near the ends the mirror doubles the response, so an end pixel lit alone saturates.
pub fn calibrate_i_bda(kind: FilterKind, settings: &FilterSettings, pixels: usize) -> f64 {
    let mut y = vec![0.0; pixels];
    y[pixels / 2] = 1.0;
    let mut analog = vec![0.0; pixels];
    normalize(&y, &mut analog);
    let mut out = vec![0.0; pixels];
    apply(kind, settings, &analog, &mut out);
    let peak = out.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if peak > 0.0 && peak.is_finite() {
        peak
    } else {
        1.0
    }
}

/// The b-bit converter: `(2^b − 1)/2 · (1 + filtered / I_bda)`, rounded half up (so the high
/// bit is exactly the sign of `filtered`: set when `filtered ≥ 0`), clamped to 0…2^b − 1.
pub fn convert(filtered: f64, i_bda: f64, bits: u32) -> u16 {
    let top = ((1u32 << bits) - 1) as f64;
    convert_scaled(filtered, top / 2.0, top / 2.0 / i_bda, top)
}

/// [`convert`] with its constants hoisted: `half + filtered·gain`, `gain = half / I_bda`.
/// Rounding is `floor(x + ½)` (by truncation of a non-negative value: exact everywhere).
#[inline(always)]
pub fn convert_scaled(filtered: f64, half: f64, gain: f64, top: f64) -> u16 {
    let value = half + filtered * gain + 0.5;
    // Clamped to [0, top] (and to the u16 range) by plain compares: NaN fails the first and
    // reads 0.
    let ceiling = if top < 65535.0 { top } else { 65535.0 };
    // Never below 0 either, whatever `top` a caller passes (the conversion below relies on it).
    let ceiling = if ceiling > 0.0 { ceiling } else { 0.0 };
    let clamped = if value > 0.0 { value } else { 0.0 };
    let clamped = if clamped < ceiling { clamped } else { ceiling };
    // Then floored by truncation (the value is not negative) without the saturating
    // conversion's fix-ups, so that a row of pixels converts in vector lanes, two a packed
    // conversion.
    // SAFETY: `clamped` lies in [0, 65535] (a NaN failed the first clamp and read 0): within
    // i32's range, and its truncation within u16's.
    unsafe { clamped.to_int_unchecked::<i32>() as u16 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_geometry_follows_the_reference() {
        assert!((pixel_azimuth(0) - 119.2f64.to_radians()).abs() < 1e-12);
        assert!(pixel_azimuth(74) > 0.0 && pixel_azimuth(75) < 0.0);
        assert!((pixel_azimuth(74) + pixel_azimuth(75)).abs() < 1e-12);
    }

    #[test]
    fn non_finite_photocurrents_read_zero() {
        let mut analog = [0.0; 4];
        assert!(normalize(&[2.0, f64::NAN, 6.0, f64::INFINITY], &mut analog));
        assert_eq!(analog, [1.0, 0.0, 3.0, 0.0], "the mean of 2, 0, 6, 0 is 2");
        assert!(!normalize(
            &[f64::INFINITY, f64::NAN, 0.0, 0.0],
            &mut analog
        ));
        assert_eq!(analog, [0.0; 4]);
        assert!(!normalize(&[0.0; 4], &mut analog));
    }

    /// The converter floors exactly as clamping and truncating does, at every kind of value:
    /// integers, halves, a hair either side, the ends of the range, beyond, and not finite.
    #[test]
    fn conversion_floors_as_truncation_does() {
        let truncated = |value: f64, top: f64| value.max(0.0).min(top) as u16;
        let mut values = vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            1e300,
            -1e300,
        ];
        for k in -3..70_000 {
            let k = k as f64;
            for x in [k, k + 0.5, k + 0.25, k + 0.75] {
                values.extend([x, x.next_up(), x.next_down()]);
            }
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            values.push((state >> 11) as f64 / (1u64 << 53) as f64 * 140_000.0 - 70_000.0);
        }
        for bits in [1u32, 6, 8, 12, 16] {
            let top = ((1u32 << bits) - 1) as f64;
            for &value in &values {
                // half + 0·gain + 0.5 is value itself when half = value − 0.5 is exact; test
                // the clamp and floor through gain 1 instead: half = 0.
                let converted = convert_scaled(value - 0.5, 0.0, 1.0, top);
                let expected = truncated(0.0 + (value - 0.5) * 1.0 + 0.5, top);
                assert_eq!(converted, expected, "value {value} top {top}");
            }
        }
        // Wider than the u16 range: saturated as the cast did.
        for value in [65_535.5, 70_000.0, 1e9, f64::INFINITY] {
            assert_eq!(convert_scaled(value, 0.0, 1.0, 1_048_575.0), 65_535);
        }
        // A top below 0 (no caller passes one) reads 0: never a value the conversion
        // cannot hold.
        for top in [-1.0, -1e300, f64::NEG_INFINITY] {
            for value in [-5.0, 0.0, 1e9, f64::NAN] {
                assert_eq!(convert_scaled(value, 0.0, 1.0, top), 0);
            }
        }
    }

    #[test]
    fn conversion_sign_bit() {
        assert_eq!(convert(0.0, 1.0, 6), 32);
        assert_eq!(convert(-1e-12, 1.0, 6), 31);
        assert_eq!(convert(1.0, 1.0, 6), 63);
        assert_eq!(convert(-1.0, 1.0, 6), 0);
        assert_eq!(convert(5.0, 1.0, 6), 63);
        assert_eq!(convert(f64::NAN, 1.0, 6), 0);
        assert_eq!(convert(f64::INFINITY, 1.0, 6), 63);
        assert_eq!(convert(f64::NEG_INFINITY, 1.0, 6), 0);
        assert_eq!(convert(-0.0, f64::INFINITY, 6), 32);
        assert_eq!(convert(0.0, 1.0, 8), 128);
    }
}
