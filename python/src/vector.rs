//! `regatta.VectorWorld`: N copies of a world, one robot of each driven by Python, stepped
//! together in one call on a thread pool with the GIL released (the core of the Gymnasium
//! vector environment). Each copy is an independent simulation, so the results are the same
//! for any number of threads. Episodes end by truncation after `duration` simulated seconds;
//! autoreset follows Gymnasium 1.x (`next_step`, `same_step`, or `disabled`).

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use rayon::prelude::*;
use regatta_evolve::Fitness;

use crate::core::{Core, CoreError};
use crate::errors::{to_py, value_error};
use crate::world::{load, read_actions};

/// When a finished episode's world starts again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Autoreset {
    /// On the step after the one that ended it: that step's action is ignored and it returns
    /// the first observation of the new episode with reward 0 (Gymnasium's default).
    NextStep,
    /// In the step that ended it: the step returns the new episode's first observation, the
    /// last one of the old is returned apart.
    SameStep,
    /// Never: the caller resets finished worlds with `reset(mask=…)`.
    Disabled,
}

impl Autoreset {
    fn parse(text: &str) -> PyResult<Autoreset> {
        match text {
            "next_step" | "NextStep" | "NEXT_STEP" => Ok(Autoreset::NextStep),
            "same_step" | "SameStep" | "SAME_STEP" => Ok(Autoreset::SameStep),
            "disabled" | "Disabled" | "DISABLED" => Ok(Autoreset::Disabled),
            other => Err(value_error(format!(
                "autoreset must be next_step, same_step or disabled, found \"{other}\""
            ))),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Autoreset::NextStep => "next_step",
            Autoreset::SameStep => "same_step",
            Autoreset::Disabled => "disabled",
        }
    }
}

/// SplitMix64: the seeds of a world's later episodes, from the seed of its first.
fn next_seed(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// One world of the batch with its episode bookkeeping.
struct Slot {
    core: Core,
    /// Where the seeds of its next episodes come from.
    seed_state: u64,
    /// The last step ended its episode (`next_step`: it restarts on the next step).
    done: bool,
    episode: u64,
}

impl Slot {
    fn restart(&mut self, seed: Option<u64>) -> Result<(), CoreError> {
        let seed = match seed {
            Some(seed) => {
                self.seed_state = seed;
                seed
            }
            None => next_seed(&mut self.seed_state),
        };
        self.done = false;
        self.episode += 1;
        self.core.reset(seed)
    }
}

/// What one world's step hands back.
struct StepOut<'a> {
    observation: &'a mut [f32],
    reward: &'a mut f64,
    truncated: &'a mut bool,
    final_observation: Option<&'a mut [f32]>,
    restarted: &'a mut bool,
}

impl Slot {
    fn step(&mut self, action: &[f64], mode: Autoreset, out: StepOut<'_>) -> Result<(), CoreError> {
        *out.restarted = false;
        if mode == Autoreset::NextStep && self.done {
            self.restart(None)?;
            *out.restarted = true;
            *out.reward = 0.0;
            *out.truncated = false;
            self.core.write_observation(out.observation);
            return Ok(());
        }
        self.core.step(action)?;
        let mut reward = [0.0];
        self.core.write_rewards(&mut reward);
        *out.reward = reward[0];
        let truncated = self.core.truncated();
        *out.truncated = truncated;
        self.done = truncated;
        if truncated && mode == Autoreset::SameStep {
            if let Some(last) = out.final_observation {
                self.core.write_observation(last);
            }
            self.restart(None)?;
            *out.restarted = true;
        }
        self.core.write_observation(out.observation);
        Ok(())
    }
}

struct Batch {
    slots: Vec<Slot>,
    pool: rayon::ThreadPool,
}

/// N copies of a world stepped together in Rust.
///
/// `VectorWorld(path, num_envs, seed=None, lenient=False, robot=None, fitness="regatta",
/// duration=60.0, threads=0, autoreset="next_step")`: `robot` names the robot the actions
/// drive in every copy (the first robot when None; the others run their own controllers).
/// Observations, actions and rewards are those of `World`. An episode is truncated after
/// `duration` simulated seconds (0: never); nothing terminates one (the tasks have no
/// terminal state). `threads` is the size of the pool the copies step on (0: one per core);
/// the results do not depend on it.
///
/// Seeds: `reset(seed=s)` starts copy i under seed s + i (or the i-th of a list of seeds);
/// each copy's later episodes take their seeds from a SplitMix64 stream of its first, so a
/// whole training run is reproducible from one seed.
#[pyclass(module = "regatta")]
pub struct VectorWorld {
    batch: Mutex<Batch>,
    num_envs: usize,
    observation_len: usize,
    autoreset: Autoreset,
    actions: Vec<f64>,
    name: String,
}

impl VectorWorld {
    fn batch(&mut self) -> &mut Batch {
        self.batch
            .get_mut()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn slot(&mut self, index: usize) -> PyResult<&Slot> {
        let n = self.num_envs;
        self.batch()
            .slots
            .get(index)
            .ok_or_else(|| value_error(format!("index {index} is out of range (0..{n})")))
    }

    fn observations<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let (n, d) = (self.num_envs, self.observation_len);
        let array = PyArray2::<f32>::zeros(py, [n, d], false);
        // SAFETY: the array was just made here and nothing else refers to it yet.
        if let Ok(out) = unsafe { array.as_slice_mut() } {
            for (slot, row) in self
                .batch()
                .slots
                .iter_mut()
                .zip(out.chunks_exact_mut(d.max(1)))
            {
                slot.core.write_observation(row);
            }
        }
        array
    }
}

#[pymethods]
impl VectorWorld {
    #[new]
    #[pyo3(signature = (path, num_envs, *, seed=None, lenient=false, robot=None, fitness="regatta", duration=60.0, threads=0, autoreset="next_step", text=None, vary=vec![]))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        path: PathBuf,
        num_envs: usize,
        seed: Option<u64>,
        lenient: bool,
        robot: Option<String>,
        fitness: &str,
        duration: f64,
        threads: usize,
        autoreset: &str,
        text: Option<&str>,
        vary: Vec<String>,
    ) -> PyResult<VectorWorld> {
        if num_envs == 0 {
            return Err(value_error("num_envs must be at least 1"));
        }
        if !(duration >= 0.0 && duration.is_finite()) {
            return Err(value_error(format!(
                "duration must be a non-negative number of seconds, found {duration}"
            )));
        }
        let autoreset = Autoreset::parse(autoreset)?;
        let fitness = Fitness::parse(fitness).map_err(|e| value_error(e.to_string()))?;
        let named = robot.clone().map(|name| vec![name]);
        let driven = match &named {
            Some(names) => regatta_evolve::Driven::Named(names),
            None => regatta_evolve::Driven::First,
        };
        let experiment = load(&path, text, lenient, driven, &vary)?;
        let robot = match robot {
            Some(name) => name,
            None => experiment
                .compiled
                .rig
                .robots
                .first()
                .map(|r| r.name.clone())
                .ok_or_else(|| value_error(format!("{} has no robot", experiment.name)))?,
        };
        let steps = experiment.steps_for(duration);
        let base = seed.unwrap_or(experiment.compiled.settings.seed);
        let name = experiment.name.clone();
        let pool = regatta_evolve::thread_pool(threads);
        let slots = py
            .detach(|| {
                pool.install(|| {
                    (0..num_envs)
                        .into_par_iter()
                        .map(|i| {
                            let seed = base.wrapping_add(i as u64);
                            let core = Core::new(
                                experiment.clone(),
                                Some(std::slice::from_ref(&robot)),
                                fitness,
                                Some(seed),
                                steps,
                            )?;
                            Ok(Slot {
                                core,
                                seed_state: seed,
                                done: false,
                                episode: 0,
                            })
                        })
                        .collect::<Result<Vec<Slot>, CoreError>>()
                })
            })
            .map_err(to_py)?;
        let observation_len = slots[0].core.observation_len();
        Ok(VectorWorld {
            batch: Mutex::new(Batch { slots, pool }),
            num_envs,
            observation_len,
            autoreset,
            actions: vec![0.0; 2 * num_envs],
            name,
        })
    }

    /// Restarts every copy (or those where `mask` is true) and returns the observations,
    /// float32 (num_envs, observation length). `seed`: None continues each copy's seed
    /// stream; an int s seeds copy i with s + i; a list gives each copy its seed.
    #[pyo3(signature = (seed=None, mask=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<&Bound<'py, PyAny>>,
        mask: Option<Vec<bool>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.num_envs;
        let seeds: Vec<Option<u64>> = match seed {
            None => vec![None; n],
            Some(s) if s.is_none() => vec![None; n],
            Some(s) => match s.extract::<u64>() {
                Ok(base) => (0..n).map(|i| Some(base.wrapping_add(i as u64))).collect(),
                Err(_) => {
                    let list: Vec<Option<u64>> = s.extract().map_err(|_| {
                        value_error("seed must be None, a non-negative int or a list of them")
                    })?;
                    if list.len() != n {
                        return Err(value_error(format!(
                            "expected {n} seeds (one per copy), found {}",
                            list.len()
                        )));
                    }
                    list
                }
            },
        };
        let mask = match mask {
            Some(mask) if mask.len() != n => {
                return Err(value_error(format!(
                    "expected a mask of {n} booleans, found {}",
                    mask.len()
                )))
            }
            Some(mask) => mask,
            None => vec![true; n],
        };
        let batch = self.batch();
        let (slots, pool) = (&mut batch.slots, &batch.pool);
        py.detach(|| {
            pool.install(|| {
                slots
                    .par_iter_mut()
                    .zip(seeds.par_iter())
                    .zip(mask.par_iter())
                    .filter(|(_, &chosen)| chosen)
                    .try_for_each(|((slot, &seed), _)| slot.restart(seed))
            })
        })
        .map_err(to_py)?;
        Ok(self.observations(py))
    }

    /// Steps every copy with `actions` (num_envs × 2) in one call. Returns (observations,
    /// rewards, terminated, truncated, restarted, final_observations): float32 (num_envs,
    /// observation length), float64, bool, bool, bool (which copies started a new episode in
    /// this call), and with `same_step` autoreset the last observations of the episodes that
    /// ended (rows of the others are zero; None in the other modes).
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: &Bound<'py, PyAny>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
        Option<Bound<'py, PyArray2<f32>>>,
    )> {
        read_actions(actions, &mut self.actions)?;
        let (n, d) = (self.num_envs, self.observation_len);
        let observations = PyArray2::<f32>::zeros(py, [n, d], false);
        let rewards = PyArray1::<f64>::zeros(py, n, false);
        let terminated = PyArray1::<bool>::zeros(py, n, false);
        let truncated = PyArray1::<bool>::zeros(py, n, false);
        let restarted = PyArray1::<bool>::zeros(py, n, false);
        let finals = (self.autoreset == Autoreset::SameStep)
            .then(|| PyArray2::<f32>::zeros(py, [n, d], false));
        let mode = self.autoreset;
        let chunk = d.max(1);
        {
            // SAFETY: every array was just made here and nothing else refers to them yet;
            // they are written only while this call holds them.
            let (obs, rew, trunc, rest) = unsafe {
                (
                    observations.as_slice_mut(),
                    rewards.as_slice_mut(),
                    truncated.as_slice_mut(),
                    restarted.as_slice_mut(),
                )
            };
            let (Ok(obs), Ok(rew), Ok(trunc), Ok(rest)) = (obs, rew, trunc, rest) else {
                return Err(crate::errors::runtime_error(
                    "a fresh array is not contiguous",
                ));
            };
            // A robot that observes nothing still steps: one unused value per copy to zip.
            let mut nothing = Vec::new();
            let obs = if d == 0 {
                nothing.resize(n, 0.0f32);
                nothing.as_mut_slice()
            } else {
                obs
            };
            let mut final_rows: Vec<Option<&mut [f32]>> = match &finals {
                // SAFETY: as above.
                Some(f) if d > 0 => match unsafe { f.as_slice_mut() } {
                    Ok(slice) => slice.chunks_exact_mut(d).map(Some).collect(),
                    Err(_) => (0..n).map(|_| None).collect(),
                },
                _ => (0..n).map(|_| None).collect(),
            };
            let actions = &self.actions;
            let batch = self
                .batch
                .get_mut()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            let (slots, pool) = (&mut batch.slots, &batch.pool);
            py.detach(|| {
                pool.install(|| {
                    slots
                        .par_iter_mut()
                        .zip(actions.par_chunks_exact(2))
                        .zip(obs.par_chunks_exact_mut(chunk))
                        .zip(rew.par_iter_mut())
                        .zip(trunc.par_iter_mut())
                        .zip(rest.par_iter_mut())
                        .zip(final_rows.par_iter_mut())
                        .try_for_each(
                            |(
                                (((((slot, action), observation), reward), truncated), restarted),
                                last,
                            )| {
                                slot.step(
                                    action,
                                    mode,
                                    StepOut {
                                        observation,
                                        reward,
                                        truncated,
                                        final_observation: last.take(),
                                        restarted,
                                    },
                                )
                            },
                        )
                })
            })
            .map_err(to_py)?;
        }
        Ok((
            observations,
            rewards,
            terminated,
            truncated,
            restarted,
            finals,
        ))
    }

    /// The current observations (float32, num_envs × observation length).
    #[getter]
    fn observation<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        self.observations(py)
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.num_envs
    }

    #[getter]
    fn observation_len(&self) -> usize {
        self.observation_len
    }

    /// The observation's column names (see `World.observation_names`).
    #[getter]
    fn observation_names(&mut self) -> Vec<String> {
        self.batch().slots[0].core.observation_names()
    }

    /// Lowest and highest value of each observation column.
    #[getter]
    fn observation_bounds<'py>(
        &mut self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<f32>>) {
        crate::world::bounds(py, &self.batch().slots[0].core)
    }

    /// Steps in an episode before it is truncated (0: never).
    #[getter]
    fn episode_steps(&mut self) -> u64 {
        self.batch().slots[0].core.episode_steps()
    }

    /// The world's time step (s).
    #[getter]
    fn time_step(&mut self) -> f64 {
        self.batch().slots[0].core.simulation().time_step
    }

    #[getter]
    fn autoreset(&self) -> &'static str {
        self.autoreset.name()
    }

    /// Threads of the pool the copies step on.
    #[getter]
    fn threads(&mut self) -> usize {
        self.batch().pool.current_num_threads()
    }

    /// Each copy's current seed and steps into its episode.
    fn episodes(&mut self) -> Vec<(u64, u64, u64)> {
        self.batch()
            .slots
            .iter()
            .map(|s| {
                (
                    s.core.simulation().seed,
                    s.core.simulation().steps,
                    s.episode,
                )
            })
            .collect()
    }

    /// Each copy's driven robot after the last step, as arrays of `num_envs`: `time` (s into
    /// the episode), `visits` (buoy visits so far), `contacts` (contacts begun so far),
    /// `touching`, and `fitness` (the chosen fitness's value so far). A copy that restarted
    /// in the last step gives its new episode's.
    fn info<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let slots = &self.batch().slots;
        let mut time = Vec::with_capacity(slots.len());
        let mut visits = Vec::with_capacity(slots.len());
        let mut contacts = Vec::with_capacity(slots.len());
        let mut touching = Vec::with_capacity(slots.len());
        let mut fitness = Vec::with_capacity(slots.len());
        for slot in slots {
            let simulation = slot.core.simulation();
            let robot = slot.core.controlled().first().copied().unwrap_or(0);
            time.push(simulation.time);
            let Some(state) = simulation.robots.get(robot) else {
                visits.push(0);
                contacts.push(0);
                touching.push(false);
                fitness.push(0.0);
                continue;
            };
            visits.push(state.visits.sequence.len() as i64);
            contacts.push(state.contacts.events);
            touching.push(state.contacts.is_touching());
            fitness.push(slot.core.fitness_value(robot));
        }
        let dict = pyo3::types::PyDict::new(py);
        dict.set_item("time", PyArray1::from_vec(py, time))?;
        dict.set_item("visits", PyArray1::from_vec(py, visits))?;
        dict.set_item("contacts", PyArray1::from_vec(py, contacts))?;
        dict.set_item("touching", PyArray1::from_vec(py, touching))?;
        dict.set_item("fitness", PyArray1::from_vec(py, fitness))?;
        Ok(dict)
    }

    /// Copy `index`'s episode so far as `World.summary_json()` gives it.
    fn summary_json(&mut self, index: usize) -> PyResult<String> {
        Ok(self.slot(index)?.core.summary_json())
    }

    /// Copy `index` from above (see `World.render`).
    #[pyo3(signature = (index=0, size=256))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        index: usize,
        size: usize,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let slot = self.slot(index)?;
        crate::render::top_view_array(py, slot.core.simulation(), size)
    }

    fn __repr__(&self) -> String {
        format!(
            "VectorWorld({:?}, num_envs={}, autoreset={:?})",
            self.name,
            self.num_envs,
            self.autoreset.name()
        )
    }
}
