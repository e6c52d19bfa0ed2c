//! `regatta._regatta`, the native half of the `regatta` Python package: worlds stepped from
//! Python ([`world::World`]), many worlds stepped at once on a thread pool
//! ([`vector::VectorWorld`], the core of the Gymnasium vector environment), and the parallel
//! evaluation of neural controllers (`evaluate`, `batch`, `parameter_count`). The Python half
//! (`python/regatta/`) adds the Gymnasium, PettingZoo and Ray layers on top.
//!
//! Every error a user can cause becomes a Python exception; nothing here panics on input.

mod core;
mod errors;
mod render;
mod vector;
mod world;

use std::path::{Path, PathBuf};

use numpy::{AllowTypeChange, PyArray2, PyArrayLike2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use regatta_evolve::world::Override;
use regatta_evolve::{Experiment, Fitness, RunSummary};

use crate::errors::{to_py, value_error};

/// Loads a world for evaluation: from its file, or from `text` already read (a Ray worker
/// gets the text from the driver; the world's folder is used for its EXTERNPROTOs and
/// Inlines when the worker can see it).
fn load_experiment(
    world: &Path,
    text: Option<&str>,
    lenient: bool,
    overrides: &[String],
    variations: &[String],
) -> PyResult<Experiment> {
    let overrides: Vec<Override> = overrides
        .iter()
        .map(|o| Override::parse(o).map_err(|e| value_error(e.to_string())))
        .collect::<PyResult<_>>()?;
    let loaded = match text {
        Some(text) => {
            let base = world
                .parent()
                .filter(|p| p.as_os_str().is_empty() || p.is_dir())
                .map(Path::to_owned);
            Experiment::from_text(
                &world.display().to_string(),
                text,
                base,
                lenient,
                &overrides,
            )
        }
        None => Experiment::load(world, lenient, &overrides),
    };
    world::vary(loaded.map_err(|e| to_py(e.into()))?, variations)
}

fn parse_fitness(fitness: &str) -> PyResult<Fitness> {
    Fitness::parse(fitness).map_err(|e| value_error(e.to_string()))
}

fn steps_for(experiment: &Experiment, duration: f64) -> PyResult<u64> {
    if !(duration >= 0.0 && duration.is_finite()) {
        return Err(value_error(format!(
            "duration must be a non-negative number of seconds, found {duration}"
        )));
    }
    Ok(experiment.steps_for(duration))
}

/// Runs the evaluations with the GIL released: rows candidate by candidate, seeds in order.
#[allow(clippy::too_many_arguments)]
fn summaries(
    py: Python<'_>,
    world: &Path,
    weights: Option<&Bound<'_, PyAny>>,
    seeds: &[u64],
    fitness: &str,
    duration: f64,
    threads: usize,
    lenient: bool,
    overrides: &[String],
    text: Option<&str>,
    variations: &[String],
) -> PyResult<(Fitness, Vec<RunSummary>, usize)> {
    let fitness = parse_fitness(fitness)?;
    let experiment = load_experiment(world, text, lenient, overrides, variations)?;
    let steps = steps_for(&experiment, duration)?;
    let rows: Option<Vec<Vec<f64>>> = match weights {
        None => None,
        Some(weights) => {
            let array: PyArrayLike2<'_, f64, AllowTypeChange> =
                weights.extract().map_err(|_| {
                    value_error("weights must be a 2-D array of numbers: one row per candidate")
                })?;
            let expected = experiment.parameter_count().ok_or_else(|| {
                value_error(format!(
                    "{} has no robot with controller \"neural\" whose weights could be set",
                    experiment.name
                ))
            })?;
            let shape = array.shape();
            if shape[1] != expected {
                return Err(value_error(format!(
                    "each row of weights must hold the network's {expected} parameters, found {} columns",
                    shape[1]
                )));
            }
            let view = array.as_array();
            if let Some(bad) = view.iter().find(|w| !w.is_finite()) {
                return Err(value_error(format!("weights must be finite, found {bad}")));
            }
            Some(view.outer_iter().map(|row| row.to_vec()).collect())
        }
    };
    let candidates = rows.as_ref().map_or(1, Vec::len);
    let result = py.detach(|| {
        let pool = regatta_evolve::thread_pool(threads);
        regatta_evolve::evaluate(
            &experiment,
            rows.as_deref(),
            seeds,
            &fitness,
            steps,
            &pool,
            &|| {},
        )
    });
    let rows = result.map_err(|e| to_py(e.into()))?;
    Ok((fitness, rows, candidates))
}

/// Evaluates neural controllers in parallel in Rust and returns their fitness.
///
/// `weights` is a 2-D array, one row per candidate, each row the world's `NeuralNetwork`
/// parameters (`parameter_count(world)` of them), given to every robot with controller
/// "neural"; `None` evaluates the weights the world file holds (one row). Each candidate runs
/// once per seed for `duration` simulated seconds. Returns a float64 array of shape
/// (candidates, seeds). The numbers are those of `regatta batch` for the same world, seeds,
/// fitness and duration (the same bits), whatever `threads` is (0: one per core). The GIL is
/// released while the runs go.
///
/// `fitness` is `avoidance`, `regatta` or `phototaxis`, optionally with parameters
/// (`regatta:penalty=1`); `overrides` are `regatta batch --set` edits (`Buoy.irReflectance=0.5`);
/// `vary` are `regatta batch --vary` variations (`DirectionalLight.intensity=0.02..0.8`),
/// drawn from each seed.
#[pyfunction]
#[pyo3(signature = (world, weights=None, seeds=vec![1], *, fitness="regatta", duration=60.0, threads=0, lenient=false, overrides=vec![], text=None, vary=vec![]))]
#[allow(clippy::too_many_arguments)]
fn evaluate<'py>(
    py: Python<'py>,
    world: PathBuf,
    weights: Option<Bound<'py, PyAny>>,
    seeds: Vec<u64>,
    fitness: &str,
    duration: f64,
    threads: usize,
    lenient: bool,
    overrides: Vec<String>,
    text: Option<String>,
    vary: Vec<String>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (fitness, rows, candidates) = summaries(
        py,
        &world,
        weights.as_ref(),
        &seeds,
        fitness,
        duration,
        threads,
        lenient,
        &overrides,
        text.as_deref(),
        &vary,
    )?;
    let values: Vec<f64> = rows.iter().map(|r| r.fitness.value).collect();
    let _ = fitness;
    numpy::PyArray1::from_vec(py, values).reshape([candidates, seeds.len()])
}

/// The runs of `evaluate` as `regatta batch --json` writes them: one JSON object per run
/// (a string each, the same bytes as the command's lines), candidates by candidate, seeds in
/// order.
#[pyfunction]
#[pyo3(signature = (world, seeds, *, weights=None, fitness="regatta", duration=60.0, threads=0, lenient=false, overrides=vec![], text=None, vary=vec![]))]
#[allow(clippy::too_many_arguments)]
fn batch(
    py: Python<'_>,
    world: PathBuf,
    seeds: Vec<u64>,
    weights: Option<Bound<'_, PyAny>>,
    fitness: &str,
    duration: f64,
    threads: usize,
    lenient: bool,
    overrides: Vec<String>,
    text: Option<String>,
    vary: Vec<String>,
) -> PyResult<Vec<String>> {
    let (_, rows, _) = summaries(
        py,
        &world,
        weights.as_ref(),
        &seeds,
        fitness,
        duration,
        threads,
        lenient,
        &overrides,
        text.as_deref(),
        &vary,
    )?;
    rows.iter()
        .map(|row| serde_json::to_string(row).map_err(|e| errors::runtime_error(e.to_string())))
        .collect()
}

/// How many parameters the world's `NeuralNetwork` takes: the length of a row of
/// `evaluate`'s weights. Raises ValueError when no robot has controller "neural".
#[pyfunction]
#[pyo3(signature = (world, *, lenient=false, overrides=vec![]))]
fn parameter_count(world: PathBuf, lenient: bool, overrides: Vec<String>) -> PyResult<usize> {
    let experiment = load_experiment(&world, None, lenient, &overrides, &[])?;
    experiment.parameter_count().ok_or_else(|| {
        value_error(format!(
            "{} has no robot with controller \"neural\" and a NeuralNetwork",
            experiment.name
        ))
    })
}

/// The weights the world's `NeuralNetwork` holds (a float64 array of
/// `parameter_count(world)` values): a starting point for an optimiser.
#[pyfunction]
#[pyo3(signature = (world, *, lenient=false, overrides=vec![]))]
fn network_weights<'py>(
    py: Python<'py>,
    world: PathBuf,
    lenient: bool,
    overrides: Vec<String>,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let experiment = load_experiment(&world, None, lenient, &overrides, &[])?;
    let network = experiment.network.as_ref().ok_or_else(|| {
        value_error(format!(
            "{} has no robot with controller \"neural\" and a NeuralNetwork",
            experiment.name
        ))
    })?;
    Ok(numpy::PyArray1::from_slice(py, &network.weights))
}

/// The world file with `weights` written into its `NeuralNetwork`, in canonical `regatta fmt`
/// form, as `regatta evolve` writes `best.wbt`: save it and `regatta run` it.
#[pyfunction]
fn with_weights(world: PathBuf, weights: Vec<f64>) -> PyResult<String> {
    let source = regatta_parser::SourceText::read(&world)
        .map_err(|e| to_py(regatta_evolve::experiment::LoadError::from(e).into()))?;
    regatta_evolve::world::with_weights(&source.text, &weights)
        .map_err(|e| value_error(e.to_string()))
}

/// The native module.
#[pymodule]
fn _regatta(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("WorldError", m.py().get_type::<errors::WorldError>())?;
    m.add_class::<world::World>()?;
    m.add_class::<world::Robot>()?;
    m.add_class::<vector::VectorWorld>()?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add_function(wrap_pyfunction!(parameter_count, m)?)?;
    m.add_function(wrap_pyfunction!(network_weights, m)?)?;
    m.add_function(wrap_pyfunction!(with_weights, m)?)?;
    m.add_function(wrap_pyfunction!(world::embedded_world, m)?)?;
    Ok(())
}
