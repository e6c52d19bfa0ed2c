//! CMA-ES (Hansen's (μ/μ_w, λ) evolution strategy with rank-one and rank-μ covariance updates
//! and cumulative step-size adaptation, default parameters of Hansen's 2016 tutorial),
//! written for reproducibility: a generation's samples come from a random stream seeded by
//! the run's seed and the generation number, so the whole state is plain numbers that a
//! checkpoint stores and a resumed run continues bit for bit; the eigendecomposition is a
//! cyclic Jacobi sweep (no platform library), and ties in fitness are broken by index.
//!
//! (The `cmaes` crate was considered: its state cannot be saved, so it cannot resume a run
//! bit for bit, and it draws from its own generator.)

use serde::{Deserialize, Serialize};

use regatta_runtime::sim::noise::Stream;

/// Identity of the evolution's random streams (distinct from the simulation's kinds).
pub const STREAM_KIND: u64 = 0x45_564f;

/// The strategy's state between generations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cmaes {
    pub dimension: usize,
    pub lambda: usize,
    pub mu: usize,
    pub weights: Vec<f64>,
    pub mu_eff: f64,
    pub c_sigma: f64,
    pub d_sigma: f64,
    pub c_c: f64,
    pub c_1: f64,
    pub c_mu: f64,
    pub chi_n: f64,
    pub mean: Vec<f64>,
    pub sigma: f64,
    /// Covariance, row-major.
    pub covariance: Vec<f64>,
    /// Eigenvectors of the covariance (columns), row-major, and the square roots of its
    /// eigenvalues.
    pub basis: Vec<f64>,
    pub scales: Vec<f64>,
    pub path_sigma: Vec<f64>,
    pub path_c: Vec<f64>,
    /// Generations told.
    pub generation: u64,
}

impl Cmaes {
    /// A strategy around `mean` with step size `sigma` and `lambda` samples per generation
    /// (0: Hansen's default 4 + ⌊3 ln n⌋).
    pub fn new(mean: Vec<f64>, sigma: f64, lambda: usize) -> Cmaes {
        let n = mean.len().max(1);
        let nf = n as f64;
        let lambda = if lambda == 0 {
            4 + (3.0 * libm::log(nf)) as usize
        } else {
            lambda.max(2)
        };
        let mu = lambda / 2;
        let raw: Vec<f64> = (1..=mu)
            .map(|i| libm::log(mu as f64 + 0.5) - libm::log(i as f64))
            .collect();
        let total: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / total).collect();
        let mu_eff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let c_sigma = (mu_eff + 2.0) / (nf + mu_eff + 5.0);
        let d_sigma =
            1.0 + 2.0 * (libm::sqrt((mu_eff - 1.0) / (nf + 1.0)) - 1.0).max(0.0) + c_sigma;
        let c_c = (4.0 + mu_eff / nf) / (nf + 4.0 + 2.0 * mu_eff / nf);
        let c_1 = 2.0 / ((nf + 1.3) * (nf + 1.3) + mu_eff);
        let c_mu = (1.0 - c_1)
            .min(2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((nf + 2.0) * (nf + 2.0) + mu_eff));
        let chi_n = libm::sqrt(nf) * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        let dimension = mean.len();
        Cmaes {
            dimension,
            lambda,
            mu,
            weights,
            mu_eff,
            c_sigma,
            d_sigma,
            c_c,
            c_1,
            c_mu,
            chi_n,
            mean,
            sigma,
            covariance: identity(dimension),
            basis: identity(dimension),
            scales: vec![1.0; dimension],
            path_sigma: vec![0.0; dimension],
            path_c: vec![0.0; dimension],
            generation: 0,
        }
    }

    /// The `lambda` candidates of the next generation, drawn from the stream of
    /// (`seed`, generation).
    pub fn ask(&self, seed: u64) -> Vec<Vec<f64>> {
        let n = self.dimension;
        let mut stream = Stream::new(seed, self.generation as usize, STREAM_KIND, 1);
        (0..self.lambda)
            .map(|_| {
                let z: Vec<f64> = (0..n).map(|_| stream.gaussian()).collect();
                let y = self.transform(&z);
                (0..n).map(|i| self.mean[i] + self.sigma * y[i]).collect()
            })
            .collect()
    }

    /// B · D · z.
    fn transform(&self, z: &[f64]) -> Vec<f64> {
        let n = self.dimension;
        let scaled: Vec<f64> = z.iter().zip(&self.scales).map(|(z, d)| z * d).collect();
        (0..n)
            .map(|i| {
                let row = &self.basis[i * n..(i + 1) * n];
                row.iter().zip(&scaled).map(|(b, s)| b * s).sum()
            })
            .collect()
    }

    /// Updates the strategy from the candidates [`Cmaes::ask`] gave and their fitness
    /// (larger is better; NaN is worst).
    pub fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) {
        let n = self.dimension;
        let nf = n as f64;
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        let key = |f: f64| if f.is_nan() { f64::NEG_INFINITY } else { f };
        order.sort_by(|&a, &b| key(fitness[b]).total_cmp(&key(fitness[a])).then(a.cmp(&b)));
        // Steps y = (x − m)/σ of the best μ, and their weighted mean.
        let steps: Vec<Vec<f64>> = order[..self.mu]
            .iter()
            .map(|&k| {
                candidates[k]
                    .iter()
                    .zip(&self.mean)
                    .map(|(x, m)| (x - m) / self.sigma)
                    .collect()
            })
            .collect();
        let mut y_w = vec![0.0; n];
        for (w, y) in self.weights.iter().zip(&steps) {
            for i in 0..n {
                y_w[i] += w * y[i];
            }
        }
        for i in 0..n {
            self.mean[i] += self.sigma * y_w[i];
        }
        // C^{−1/2} y_w = B D^{−1} Bᵀ y_w.
        let bt_y: Vec<f64> = (0..n)
            .map(|j| (0..n).map(|i| self.basis[i * n + j] * y_w[i]).sum::<f64>())
            .collect();
        let scaled: Vec<f64> = bt_y
            .iter()
            .zip(&self.scales)
            .map(|(v, d)| v / d.max(1e-300))
            .collect();
        let whitened: Vec<f64> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| self.basis[i * n + j] * scaled[j])
                    .sum::<f64>()
            })
            .collect();
        let cs = self.c_sigma;
        let norm_cs = libm::sqrt(cs * (2.0 - cs) * self.mu_eff);
        for i in 0..n {
            self.path_sigma[i] = (1.0 - cs) * self.path_sigma[i] + norm_cs * whitened[i];
        }
        let ps_norm = libm::sqrt(self.path_sigma.iter().map(|p| p * p).sum::<f64>());
        let generations = self.generation as f64 + 1.0;
        let h_sigma = ps_norm / libm::sqrt(1.0 - libm::pow(1.0 - cs, 2.0 * generations))
            < (1.4 + 2.0 / (nf + 1.0)) * self.chi_n;
        let cc = self.c_c;
        let norm_cc = libm::sqrt(cc * (2.0 - cc) * self.mu_eff);
        for i in 0..n {
            self.path_c[i] =
                (1.0 - cc) * self.path_c[i] + if h_sigma { norm_cc * y_w[i] } else { 0.0 };
        }
        let delta = if h_sigma { 0.0 } else { cc * (2.0 - cc) };
        let (c1, cmu) = (self.c_1, self.c_mu);
        for i in 0..n {
            for j in 0..=i {
                let mut rank_mu = 0.0;
                for (w, y) in self.weights.iter().zip(&steps) {
                    rank_mu += w * y[i] * y[j];
                }
                let old = self.covariance[i * n + j];
                let value = (1.0 - c1 - cmu) * old
                    + c1 * (self.path_c[i] * self.path_c[j] + delta * old)
                    + cmu * rank_mu;
                self.covariance[i * n + j] = value;
                self.covariance[j * n + i] = value;
            }
        }
        self.sigma *= libm::exp((cs / self.d_sigma) * (ps_norm / self.chi_n - 1.0));
        let (values, vectors) = jacobi_eigen(&self.covariance, n);
        self.scales = values.iter().map(|&v| libm::sqrt(v.max(1e-300))).collect();
        self.basis = vectors;
        self.generation += 1;
    }
}

fn identity(n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
    }
    m
}

/// Eigenvalues and eigenvectors (columns, row-major) of a symmetric matrix by cyclic Jacobi
/// rotations, until the off-diagonal part is negligible (or 64 sweeps).
///
/// A rotation updates two columns and then two rows of the matrix, and two columns of the
/// eigenvectors. The eigenvectors are kept transposed while rotating, so that their update
/// runs along two contiguous rows; every element gets the same arithmetic in the same order
/// as in the textbook loops, so the result is the same to the bit.
pub fn jacobi_eigen(matrix: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = matrix.to_vec();
    let mut vt = identity(n);
    if n == 0 {
        return (Vec::new(), vt);
    }
    // Two rows `p < q` of a row-major n-column matrix, for updating in step.
    fn rows(m: &mut [f64], n: usize, p: usize, q: usize) -> (&mut [f64], &mut [f64]) {
        let (head, tail) = m.split_at_mut(q * n);
        (&mut head[p * n..(p + 1) * n], &mut tail[..n])
    }
    // c·x − s·y and s·x + c·y of each pair, in place.
    fn rotate<'a>(pairs: impl Iterator<Item = (&'a mut f64, &'a mut f64)>, c: f64, s: f64) {
        for (x, y) in pairs {
            let (old_x, old_y) = (*x, *y);
            *x = c * old_x - s * old_y;
            *y = s * old_x + c * old_y;
        }
    }
    for _ in 0..64 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        let diagonal: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-30 * diagonal.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + libm::sqrt(theta * theta + 1.0));
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / libm::sqrt(t * t + 1.0);
                let s = t * c;
                // Columns p and q of the matrix, then its rows p and q, then columns p and q
                // of the eigenvectors (rows of their transpose).
                for row in a.chunks_exact_mut(n) {
                    let (x, y) = (row[p], row[q]);
                    row[p] = c * x - s * y;
                    row[q] = s * x + c * y;
                }
                let (row_p, row_q) = rows(&mut a, n, p, q);
                rotate(row_p.iter_mut().zip(row_q.iter_mut()), c, s);
                let (vt_p, vt_q) = rows(&mut vt, n, p, q);
                rotate(vt_p.iter_mut().zip(vt_q.iter_mut()), c, s);
            }
        }
    }
    let mut v = vec![0.0; n * n];
    for (p, row) in vt.chunks_exact(n).enumerate() {
        for (k, &value) in row.iter().enumerate() {
            v[k * n + p] = value;
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_diagonalises_a_symmetric_matrix() {
        let m = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0];
        let (values, vectors) = jacobi_eigen(&m, 3);
        // M v = λ v for each column.
        for k in 0..3 {
            for i in 0..3 {
                let mv: f64 = (0..3).map(|j| m[i * 3 + j] * vectors[j * 3 + k]).sum();
                assert!((mv - values[k] * vectors[i * 3 + k]).abs() < 1e-12);
            }
        }
        let trace: f64 = values.iter().sum();
        assert!((trace - 8.0).abs() < 1e-12);
    }

    fn sphere(x: &[f64]) -> f64 {
        -x.iter().map(|v| (v - 1.0) * (v - 1.0)).sum::<f64>()
    }

    fn rosenbrock(x: &[f64]) -> f64 {
        -x.windows(2)
            .map(|w| {
                let (a, b) = (w[1] - w[0] * w[0], 1.0 - w[0]);
                100.0 * a * a + b * b
            })
            .sum::<f64>()
    }

    fn optimise(f: fn(&[f64]) -> f64, n: usize, generations: usize) -> (f64, Cmaes) {
        let mut es = Cmaes::new(vec![0.0; n], 0.5, 0);
        let mut best = f64::NEG_INFINITY;
        for _ in 0..generations {
            let xs = es.ask(7);
            let fs: Vec<f64> = xs.iter().map(|x| f(x)).collect();
            best = fs.iter().copied().fold(best, f64::max);
            es.tell(&xs, &fs);
        }
        (best, es)
    }

    #[test]
    fn it_finds_the_optimum_of_a_sphere_and_rosenbrock() {
        let (best, es) = optimise(sphere, 10, 200);
        assert!(best > -1e-12, "sphere: {best}");
        assert!(es.mean.iter().all(|m| (m - 1.0).abs() < 1e-5));
        // Rosenbrock needs the covariance to learn its curved valley.
        let (best, _) = optimise(rosenbrock, 6, 1500);
        assert!(best > -1e-8, "rosenbrock: {best}");
    }

    #[test]
    fn a_saved_state_continues_identically() {
        let (_, es) = optimise(rosenbrock, 5, 30);
        let text = serde_json::to_string(&es).unwrap();
        let restored: Cmaes = serde_json::from_str(&text).unwrap();
        assert_eq!(restored, es);
        let (mut a, mut b) = (es, restored);
        for _ in 0..20 {
            let (xa, xb) = (a.ask(3), b.ask(3));
            assert_eq!(xa, xb);
            let fa: Vec<f64> = xa.iter().map(|x| rosenbrock(x)).collect();
            a.tell(&xa, &fa);
            b.tell(&xb, &fa);
        }
        assert_eq!(a, b);
    }
}
