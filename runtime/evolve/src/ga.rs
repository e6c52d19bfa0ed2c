//! A generational genetic algorithm on real-valued genomes: the best tenth kept unchanged
//! (elitism), parents chosen by tournaments of three, uniform crossover, and Gaussian
//! mutation of each gene with probability `max(1/n, 0.05)` and standard deviation `sigma`.
//! Like [`crate::cmaes`], a generation draws from the stream of (seed, generation), so the
//! state is plain numbers and a checkpoint resumes bit for bit.

use serde::{Deserialize, Serialize};

use regatta_runtime::sim::noise::Stream;

/// The population between generations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Genetic {
    pub population: Vec<Vec<f64>>,
    pub sigma: f64,
    /// Generations told.
    pub generation: u64,
}

impl Genetic {
    /// `size` genomes drawn uniformly from ±`spread` around `center`.
    pub fn new(center: &[f64], spread: f64, size: usize, sigma: f64, seed: u64) -> Genetic {
        let mut stream = Stream::new(seed, 0, crate::cmaes::STREAM_KIND, 2);
        let population = (0..size.max(2))
            .map(|_| {
                center
                    .iter()
                    .map(|c| c + spread * (2.0 * stream.uniform() - 1.0))
                    .collect()
            })
            .collect();
        Genetic {
            population,
            sigma,
            generation: 0,
        }
    }

    /// The genomes to evaluate this generation.
    pub fn ask(&self) -> Vec<Vec<f64>> {
        self.population.clone()
    }

    /// Breeds the next generation from the fitness of [`Genetic::ask`]'s genomes (larger is
    /// better; NaN is worst).
    pub fn tell(&mut self, fitness: &[f64], seed: u64) {
        let size = self.population.len();
        let n = self.population.first().map_or(0, Vec::len);
        let key = |f: f64| if f.is_nan() { f64::NEG_INFINITY } else { f };
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&a, &b| key(fitness[b]).total_cmp(&key(fitness[a])).then(a.cmp(&b)));
        let mut stream = Stream::new(
            seed,
            self.generation as usize + 1,
            crate::cmaes::STREAM_KIND,
            3,
        );
        let elites = (size / 10).max(1);
        let mut next: Vec<Vec<f64>> = order[..elites]
            .iter()
            .map(|&k| self.population[k].clone())
            .collect();
        let pick = |stream: &mut Stream| -> usize {
            // Tournament of three: the best rank wins.
            (0..3)
                .map(|_| ((stream.uniform() * size as f64) as usize).min(size - 1))
                .map(|k| order.iter().position(|&o| o == k).unwrap_or(size))
                .min()
                .map_or(0, |rank| order[rank.min(size - 1)])
        };
        let rate = (1.0 / n.max(1) as f64).max(0.05);
        while next.len() < size {
            let (a, b) = (pick(&mut stream), pick(&mut stream));
            let child: Vec<f64> = (0..n)
                .map(|i| {
                    let gene = if stream.uniform() < 0.5 {
                        self.population[a][i]
                    } else {
                        self.population[b][i]
                    };
                    if stream.uniform() < rate {
                        gene + self.sigma * stream.gaussian()
                    } else {
                        gene
                    }
                })
                .collect();
            next.push(child);
        }
        self.population = next;
        self.generation += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_climbs_a_sphere_and_keeps_its_best() {
        let f = |x: &[f64]| -x.iter().map(|v| (v - 0.5) * (v - 0.5)).sum::<f64>();
        let mut ga = Genetic::new(&[0.0; 5], 1.0, 40, 0.1, 11);
        let mut best_per_generation = Vec::new();
        for _ in 0..150 {
            let xs = ga.ask();
            let fs: Vec<f64> = xs.iter().map(|x| f(x)).collect();
            best_per_generation.push(fs.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            ga.tell(&fs, 11);
        }
        // Elitism: the best never gets worse.
        assert!(best_per_generation.windows(2).all(|w| w[1] >= w[0]));
        assert!(*best_per_generation.last().unwrap() > -0.01);
    }
}
