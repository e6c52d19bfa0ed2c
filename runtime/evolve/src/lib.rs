//! Populations of runs: a world loaded once and evaluated for many seeds and candidate
//! weights in parallel (deterministic for any thread count), named fitness functions that a
//! live run and its log compute alike, and evolution of a world's `NeuralNetwork` by CMA-ES
//! or a genetic algorithm, with checkpoints that resume bit for bit.
//!
//! - [`record`]: the per-step record fitness is computed from, live or from a log.
//! - [`fitness`]: `avoidance`, `regatta`, `phototaxis`.
//! - [`experiment`]: [`Experiment`] (a compiled world), [`evaluate`], [`RunSummary`].
//! - [`world`]: `--set` overrides and weights written into a world.
//! - [`cmaes`], [`ga`], [`evolve`]: the optimisers and the generation loop.

// Vector formulas (`for i in 0..n`) read as the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod cmaes;
pub mod evolve;
pub mod experiment;
pub mod fitness;
pub mod ga;
pub mod programs;
pub mod record;
pub mod variations;
pub mod world;

pub use experiment::{evaluate, thread_pool, Driven, Experiment, Observer, RunSummary};
pub use fitness::Fitness;
