//! Seeded random streams: one independent stream per robot and per sensor, all derived from
//! the world's seed, so a run is reproducible bit for bit and adding a sensor does not change
//! another sensor's noise.

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256StarStar;

/// A named stream of uniform and Gaussian numbers.
#[derive(Clone, Debug)]
pub struct Stream {
    rng: Xoshiro256StarStar,
    /// Box–Muller makes pairs; the second waits here.
    spare: Spare,
}

/// The second number of a Box–Muller pair.
#[derive(Clone, Copy, Debug)]
enum Spare {
    None,
    /// Computed with the first.
    Ready(f64),
    /// Its uniforms drawn by [`Stream::skip_gaussian`], its value not yet needed: a sensor
    /// whose noise is zero advances its stream without the transcendental functions.
    Drawn {
        u1: f64,
        u2: f64,
    },
}

/// Mixes the seed with a stream's identity (SplitMix64's finaliser over an FNV-1a hash of
/// the path), giving well-separated seeds for neighbouring identities.
fn derive(seed: u64, path: &[u64]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64 ^ seed;
    for &part in path {
        for byte in part.to_le_bytes() {
            hash ^= byte as u64;
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    }
    let mut z = hash.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Kinds of stream, part of each stream's identity.
pub mod kind {
    pub const WHEELS: u64 = 1;
    pub const PROXIMITY: u64 = 2;
    pub const AMBIENT: u64 = 3;
    pub const CONTROLLER: u64 = 4;
    pub const CAMERA: u64 = 5;
}

impl Stream {
    /// The stream of `kind` for robot `robot`, device `device`, under `seed`.
    pub fn new(seed: u64, robot: usize, kind: u64, device: usize) -> Stream {
        Stream {
            rng: Xoshiro256StarStar::seed_from_u64(derive(
                seed,
                &[robot as u64, kind, device as u64],
            )),
            spare: Spare::None,
        }
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal, by Box–Muller with `libm` (platform-independent).
    pub fn gaussian(&mut self) -> f64 {
        match std::mem::replace(&mut self.spare, Spare::None) {
            Spare::Ready(value) => value,
            Spare::Drawn { u1, u2 } => Self::box_muller(u1, u2).1,
            Spare::None => {
                let u1 = 1.0 - self.uniform(); // (0, 1]: the log is finite
                let u2 = self.uniform();
                let (first, second) = Self::box_muller(u1, u2);
                self.spare = Spare::Ready(second);
                first
            }
        }
    }

    /// Advances the stream past one [`Stream::gaussian`] without computing it: the numbers
    /// that follow are the same as if it had been drawn.
    pub fn skip_gaussian(&mut self) {
        match std::mem::replace(&mut self.spare, Spare::None) {
            Spare::Ready(_) | Spare::Drawn { .. } => {}
            Spare::None => {
                let u1 = 1.0 - self.uniform();
                let u2 = self.uniform();
                self.spare = Spare::Drawn { u1, u2 };
            }
        }
    }

    /// [`Stream::skip_gaussian`] `n` times, the pairs' uniforms drawn and dropped: the
    /// numbers that follow are the same as after `n` single skips.
    pub fn skip_gaussians(&mut self, mut n: u64) {
        if n == 0 {
            return;
        }
        if !matches!(self.spare, Spare::None) {
            // The first skip takes the waiting second number of a pair.
            self.spare = Spare::None;
            n -= 1;
        }
        // Two skips from no spare draw a pair's two uniforms and leave no spare.
        for _ in 0..n / 2 {
            self.rng.next_u64();
            self.rng.next_u64();
        }
        if n % 2 == 1 {
            self.skip_gaussian();
        }
    }

    /// Both numbers of a Box–Muller pair (cosine first).
    #[inline]
    fn box_muller(u1: f64, u2: f64) -> (f64, f64) {
        let radius = libm::sqrt(-2.0 * libm::log(u1));
        let angle = 2.0 * std::f64::consts::PI * u2;
        // One range reduction for both (the same values as `sin` and `cos` apart).
        let (sin, cos) = libm::sincos(angle);
        (radius * cos, radius * sin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_independent() {
        let mut a = Stream::new(7, 0, kind::PROXIMITY, 3);
        let mut b = Stream::new(7, 0, kind::PROXIMITY, 3);
        let mut c = Stream::new(7, 0, kind::PROXIMITY, 4);
        let xs: Vec<f64> = (0..8).map(|_| a.gaussian()).collect();
        let ys: Vec<f64> = (0..8).map(|_| b.gaussian()).collect();
        let zs: Vec<f64> = (0..8).map(|_| c.gaussian()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs, zs);
        let mut d = Stream::new(1, 0, kind::WHEELS, 0);
        let n = 20000;
        let samples: Vec<f64> = (0..n).map(|_| d.gaussian()).collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let variance = samples.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        assert!(
            mean.abs() < 0.03 && (variance - 1.0).abs() < 0.05,
            "{mean} {variance}"
        );
    }

    /// Skipping a draw leaves the stream where drawing it would have: any pattern of skips
    /// and draws gives the same drawn numbers as drawing everything.
    #[test]
    fn skipping_a_gaussian_changes_nothing_that_follows() {
        let mut all = Stream::new(5, 2, kind::PROXIMITY, 1);
        let mut some = Stream::new(5, 2, kind::PROXIMITY, 1);
        let mut pattern = Stream::new(9, 0, kind::WHEELS, 0);
        for _ in 0..10_000 {
            let value = all.gaussian();
            if pattern.uniform() < 0.4 {
                some.skip_gaussian();
            } else {
                assert_eq!(some.gaussian().to_bits(), value.to_bits());
            }
        }
        assert_eq!(all.uniform().to_bits(), some.uniform().to_bits());
    }

    /// Many skips at once are the same as one at a time, from any spare state.
    #[test]
    fn skipping_many_gaussians_is_skipping_each() {
        let mut pattern = Stream::new(2, 0, kind::WHEELS, 0);
        for case in 0..2_000 {
            let mut one_by_one = Stream::new(8, case, kind::PROXIMITY, 0);
            // A spare waiting (computed or only drawn), or none.
            match case % 3 {
                0 => {}
                1 => {
                    one_by_one.gaussian();
                }
                _ => one_by_one.skip_gaussian(),
            }
            let mut at_once = one_by_one.clone();
            let n = (pattern.uniform() * 9.0) as u64 + if case % 50 == 0 { 1000 } else { 0 };
            for _ in 0..n {
                one_by_one.skip_gaussian();
            }
            at_once.skip_gaussians(n);
            for _ in 0..3 {
                assert_eq!(
                    one_by_one.gaussian().to_bits(),
                    at_once.gaussian().to_bits(),
                    "case {case}, {n} skips"
                );
            }
            assert_eq!(one_by_one.uniform().to_bits(), at_once.uniform().to_bits());
        }
    }

    /// `gaussian` takes sine and cosine from one `sincos`: the noise must stay what separate
    /// `sin` and `cos` give (the streams are part of a run's identity).
    #[test]
    fn sincos_equals_sin_and_cos_bit_for_bit() {
        let mut stream = Stream::new(3, 0, kind::WHEELS, 0);
        for i in 0..200_000 {
            let angle = if i < 8 {
                [
                    0.0,
                    1e-300,
                    0.5,
                    1.0,
                    3.0,
                    std::f64::consts::PI,
                    6.0,
                    std::f64::consts::TAU,
                ][i]
            } else {
                2.0 * std::f64::consts::PI * stream.uniform()
            };
            let (sin, cos) = libm::sincos(angle);
            assert_eq!(sin.to_bits(), libm::sin(angle).to_bits(), "{angle}");
            assert_eq!(cos.to_bits(), libm::cos(angle).to_bits(), "{angle}");
        }
        // Headings too (placements take both from one `sincos`): a robot that has turned
        // for a long time, either way, has a heading far past a turn.
        for i in 0..20_000 {
            let scale = [1.0, 10.0, 1e3, 1e6, 1e12][i % 5];
            let heading = (2.0 * stream.uniform() - 1.0) * scale;
            let (sin, cos) = libm::sincos(heading);
            assert_eq!(sin.to_bits(), libm::sin(heading).to_bits(), "{heading}");
            assert_eq!(cos.to_bits(), libm::cos(heading).to_bits(), "{heading}");
        }
    }
}
