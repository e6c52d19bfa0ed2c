//! The generation loop of `regatta evolve`: candidates from CMA-ES or the genetic algorithm,
//! each evaluated on `trials` seeds in every world, its fitness the mean or the minimum of
//! those runs; statistics per generation; the best candidate so far; checkpoints.
//!
//! Determinism: a generation's candidates and trial seeds depend only on the settings' seed
//! and the generation number, evaluations are independent runs collected in a fixed order,
//! and the state is saved with every f64 written so that it reads back to the same bits. The
//! same command and seed therefore give the same results for any thread count, and a run
//! resumed from a checkpoint continues exactly as the uninterrupted one.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cmaes::Cmaes;
use crate::experiment::{EvalError, Experiment};
use crate::fitness::Fitness;
use crate::ga::Genetic;
use regatta_runtime::sim::noise::Stream;

/// The optimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    Cmaes,
    Ga,
}

/// How a candidate's runs make one fitness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aggregate {
    Mean,
    Min,
}

/// What an evolution was started with; a checkpoint resumes only under the same settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub method: Method,
    /// The fitness as named on the command line (`regatta`, `avoidance:vmax=15`…).
    pub fitness: String,
    /// Candidates per generation.
    pub population: usize,
    pub generations: u64,
    /// Seeds per candidate and world.
    pub trials: usize,
    /// Steps per run.
    pub steps: u64,
    pub aggregate: Aggregate,
    pub seed: u64,
    /// Initial step size (CMA-ES) or mutation deviation (GA).
    pub sigma: f64,
    /// The worlds' names and a hash of each one's text.
    pub worlds: Vec<(String, String)>,
    /// Whether the evolution started from the first world's written weights
    /// ([`Evolution::starting_at`]) rather than from random ones.
    #[serde(default)]
    pub from_weights: bool,
}

/// The optimiser's state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Optimiser {
    Cmaes(Box<Cmaes>),
    Ga(Genetic),
}

/// One generation's figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenerationStats {
    /// Numbered from 1.
    pub generation: u64,
    /// Runs done so far.
    pub evaluations: u64,
    pub best: f64,
    pub mean: f64,
    pub worst: f64,
    /// The best candidate's fitness so far.
    pub best_ever: f64,
    /// CMA-ES: its step size after the generation; GA: the mutation deviation.
    pub sigma: f64,
}

/// The best candidate so far.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Best {
    pub weights: Vec<f64>,
    pub fitness: f64,
    pub generation: u64,
    /// The first trial seed of its generation: its logged run replays under it.
    pub seed: u64,
}

/// An evolution in progress.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evolution {
    pub settings: Settings,
    pub optimiser: Optimiser,
    pub history: Vec<GenerationStats>,
    pub best: Option<Best>,
}

/// Why a checkpoint cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read or write {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} is not an evolution checkpoint: {source}")]
    Format {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("the checkpoint was made with other settings ({0} differs); resume with the command that made it")]
    Mismatch(&'static str),
}

/// A hash of a world's text (FNV-1a, 64 bits), to recognise it in a checkpoint.
pub fn text_hash(text: &str) -> String {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for byte in text.bytes() {
        hash ^= byte as u64;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{hash:016x}")
}

/// The checkpoint file in a checkpoint directory.
pub fn checkpoint_path(dir: &Path) -> PathBuf {
    dir.join("checkpoint.json")
}

impl Evolution {
    /// A new evolution of `dimension` weights, starting from random weights drawn uniformly
    /// in −1 … 1 from the seed's stream.
    pub fn new(settings: Settings, dimension: usize) -> Evolution {
        let mut stream = Stream::new(settings.seed, 0, crate::cmaes::STREAM_KIND, 0);
        let start: Vec<f64> = (0..dimension)
            .map(|_| 2.0 * stream.uniform() - 1.0)
            .collect();
        let optimiser = Evolution::optimiser(&settings, start, vec![0.0; dimension]);
        Evolution {
            settings,
            optimiser,
            history: Vec::new(),
            best: None,
        }
    }

    /// A new evolution that starts from `start` (a network's written weights: CMA-ES's mean
    /// and the genetic algorithm's centre), to evolve on from a network evolved before.
    pub fn starting_at(settings: Settings, start: Vec<f64>) -> Evolution {
        let optimiser = Evolution::optimiser(&settings, start.clone(), start);
        Evolution {
            settings,
            optimiser,
            history: Vec::new(),
            best: None,
        }
    }

    /// The optimiser: CMA-ES about `mean`, or the genetic algorithm about `centre`.
    fn optimiser(settings: &Settings, mean: Vec<f64>, centre: Vec<f64>) -> Optimiser {
        match settings.method {
            Method::Cmaes => Optimiser::Cmaes(Box::new(Cmaes::new(
                mean,
                settings.sigma,
                settings.population,
            ))),
            Method::Ga => Optimiser::Ga(Genetic::new(
                &centre,
                1.0,
                settings.population,
                settings.sigma,
                settings.seed,
            )),
        }
    }

    /// Generations done.
    pub fn generation(&self) -> u64 {
        self.history.len() as u64
    }

    /// Whether every generation asked for is done.
    pub fn finished(&self) -> bool {
        self.generation() >= self.settings.generations
    }

    /// Candidates per generation (CMA-ES may choose its default).
    pub fn population(&self) -> usize {
        match &self.optimiser {
            Optimiser::Cmaes(es) => es.lambda,
            Optimiser::Ga(ga) => ga.population.len(),
        }
    }

    /// The trial seeds of generation `generation` (from 0): the same for every candidate,
    /// so that candidates are compared on the same conditions.
    pub fn trial_seeds(&self, generation: u64) -> Vec<u64> {
        let mut stream = Stream::new(
            self.settings.seed,
            generation as usize,
            crate::cmaes::STREAM_KIND,
            4,
        );
        (0..self.settings.trials)
            .map(|_| (stream.uniform() * 1e9) as u64)
            .collect()
    }

    /// Runs one generation on `experiments` (one per world, in the settings' order).
    /// `done` is called after each run.
    pub fn step(
        &mut self,
        experiments: &[Experiment],
        fitness: &Fitness,
        pool: &rayon::ThreadPool,
        done: &(dyn Fn() + Sync),
    ) -> Result<&GenerationStats, EvalError> {
        let generation = self.generation();
        let candidates = match &self.optimiser {
            Optimiser::Cmaes(es) => es.ask(self.settings.seed),
            Optimiser::Ga(ga) => ga.ask(),
        };
        let seeds = self.trial_seeds(generation);
        let steps = self.settings.steps;
        // A world with variations is drawn once per trial seed, and every candidate sails
        // that draw (so candidates are compared on the same conditions).
        let varied: Vec<Vec<Option<Experiment>>> = pool.install(|| {
            experiments
                .par_iter()
                .map(|experiment| {
                    seeds
                        .par_iter()
                        .map(|&seed| experiment.for_seed(seed))
                        .collect::<Result<Vec<_>, EvalError>>()
                })
                .collect::<Result<Vec<_>, EvalError>>()
        })?;
        let jobs: Vec<(usize, usize, usize)> = (0..candidates.len())
            .flat_map(|c| {
                let seeds = &seeds;
                (0..experiments.len()).flat_map(move |w| (0..seeds.len()).map(move |s| (c, w, s)))
            })
            .collect();
        let values: Vec<f64> = pool.install(|| {
            jobs.par_iter()
                .map(|&(c, w, s)| {
                    let world = varied[w][s].as_ref().unwrap_or(&experiments[w]);
                    let summary = world.evaluate(seeds[s], steps, Some(&candidates[c]), fitness)?;
                    done();
                    Ok(summary.fitness.value)
                })
                .collect::<Result<Vec<f64>, EvalError>>()
        })?;
        let runs = experiments.len() * seeds.len();
        let fitness: Vec<f64> = values
            .chunks(runs.max(1))
            .map(|runs| match self.settings.aggregate {
                Aggregate::Mean => runs.iter().sum::<f64>() / runs.len() as f64,
                Aggregate::Min => runs.iter().copied().fold(f64::INFINITY, f64::min),
            })
            .collect();
        let key = |f: f64| if f.is_nan() { f64::NEG_INFINITY } else { f };
        let best_index = (0..fitness.len()).fold(0, |b, k| {
            if key(fitness[k]) > key(fitness[b]) {
                k
            } else {
                b
            }
        });
        if self
            .best
            .as_ref()
            .is_none_or(|b| key(fitness[best_index]) > key(b.fitness))
        {
            self.best = Some(Best {
                weights: candidates[best_index].clone(),
                fitness: fitness[best_index],
                generation: generation + 1,
                seed: seeds.first().copied().unwrap_or(0),
            });
        }
        let sigma = match &mut self.optimiser {
            Optimiser::Cmaes(es) => {
                es.tell(&candidates, &fitness);
                es.sigma
            }
            Optimiser::Ga(ga) => {
                ga.tell(&fitness, self.settings.seed);
                ga.sigma
            }
        };
        let evaluations = self.history.last().map_or(0, |h| h.evaluations) + values.len() as u64;
        self.history.push(GenerationStats {
            generation: generation + 1,
            evaluations,
            best: key(fitness[best_index]),
            mean: fitness.iter().sum::<f64>() / fitness.len() as f64,
            worst: fitness
                .iter()
                .copied()
                .map(key)
                .fold(f64::INFINITY, f64::min),
            best_ever: self.best.as_ref().map_or(f64::NAN, |b| b.fitness),
            sigma,
        });
        Ok(self.history.last().expect("just pushed"))
    }

    /// Writes the checkpoint into `dir` (replacing the previous one only once written).
    pub fn save(&self, dir: &Path) -> Result<(), CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: dir.to_owned(),
            source,
        };
        std::fs::create_dir_all(dir).map_err(io)?;
        let path = checkpoint_path(dir);
        let temporary = dir.join("checkpoint.json.tmp");
        let text = serde_json::to_string(self).expect("an evolution serialises");
        std::fs::write(&temporary, text).map_err(io)?;
        std::fs::rename(&temporary, &path).map_err(io)?;
        Ok(())
    }

    /// Reads the checkpoint in `dir`.
    pub fn load(dir: &Path) -> Result<Evolution, CheckpointError> {
        let path = checkpoint_path(dir);
        let text = std::fs::read_to_string(&path).map_err(|source| CheckpointError::Io {
            path: path.clone(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|source| CheckpointError::Format { path, source })
    }

    /// Checks that a checkpoint continues the evolution `settings` describe; the number of
    /// generations may grow.
    pub fn resumes(&mut self, settings: &Settings) -> Result<(), CheckpointError> {
        let s = &self.settings;
        let differs = if s.method != settings.method {
            Some("--method")
        } else if s.fitness != settings.fitness {
            Some("--fitness")
        } else if s.population != settings.population {
            Some("--population")
        } else if s.trials != settings.trials {
            Some("--trials")
        } else if s.steps != settings.steps {
            Some("--duration")
        } else if s.aggregate != settings.aggregate {
            Some("--aggregate")
        } else if s.seed != settings.seed {
            Some("--seed")
        } else if s.sigma.to_bits() != settings.sigma.to_bits() {
            Some("--sigma")
        } else if s.worlds != settings.worlds {
            Some("the worlds")
        } else if s.from_weights != settings.from_weights {
            Some("--from-weights")
        } else {
            None
        };
        if let Some(what) = differs {
            return Err(CheckpointError::Mismatch(what));
        }
        self.settings.generations = settings.generations;
        Ok(())
    }
}
