//! `regatta.World`: one world stepped from Python, its robots by name, its log and summary.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use numpy::{
    AllowTypeChange, PyArray1, PyArray2, PyArray3, PyArrayLikeDyn, PyArrayMethods,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use regatta_evolve::{Driven, Experiment, Fitness};
use regatta_runtime::retina::FilterKind;

use crate::core::{Core, CoreError, LogRequest};
use crate::errors::{to_py, value_error};
use regatta_runtime::log::Channels;

/// The worlds the package carries (the Gymnasium environments' defaults).
pub const EMBEDDED: &[(&str, &str)] = &[
    ("regatta.wbt", include_str!("../../worlds/regatta.wbt")),
    ("avoidance.wbt", include_str!("../../worlds/avoidance.wbt")),
];

/// The text of a world the package carries (`regatta.wbt`, `avoidance.wbt`).
#[pyfunction]
pub fn embedded_world(name: &str) -> PyResult<&'static str> {
    EMBEDDED
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
        .ok_or_else(|| {
            let known: Vec<&str> = EMBEDDED.iter().map(|(n, _)| *n).collect();
            value_error(format!(
                "no embedded world '{name}' (there are: {})",
                known.join(", ")
            ))
        })
}

/// Loads a world from its file, or from `text` (named `path`, reading no other file); the
/// robots Python drives may wait for an external controller (Webots' `"<extern>"`).
pub fn load(
    path: &std::path::Path,
    text: Option<&str>,
    lenient: bool,
    driven: Driven<'_>,
    vary: &[String],
) -> PyResult<Arc<Experiment>> {
    let experiment = match text {
        Some(text) => Experiment::from_text_driven(
            &path.display().to_string(),
            text,
            None,
            lenient,
            &[],
            driven,
        ),
        None => Experiment::load_driven(path, lenient, &[], driven),
    };
    let experiment = experiment.map_err(|e| to_py(CoreError::Load(e)))?;
    self::vary(experiment, vary).map(Arc::new)
}

/// `experiment` with `vary` (`regatta batch --vary` texts) drawn anew for each seed.
pub fn vary(experiment: Experiment, vary: &[String]) -> PyResult<Experiment> {
    let variations = vary
        .iter()
        .map(|v| {
            regatta_evolve::variations::Variation::parse_flag(v)
                .map_err(|e| value_error(e.to_string()))
        })
        .collect::<PyResult<Vec<_>>>()?;
    experiment
        .with_variations(variations)
        .map_err(|e| value_error(e.to_string()))
}

/// Reads actions (any array-like of numbers) into `out`, which must match its size.
pub fn read_actions(actions: &Bound<'_, PyAny>, out: &mut [f64]) -> PyResult<()> {
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = actions
        .extract()
        .map_err(|_| value_error("actions must be an array of numbers"))?;
    if array.len() != out.len() {
        return Err(value_error(format!(
            "expected {} action values (2 wheel speeds per driven robot), found {} (shape {:?})",
            out.len(),
            array.len(),
            array.shape()
        )));
    }
    match array.as_slice() {
        Ok(slice) => out.copy_from_slice(slice),
        Err(_) => {
            for (o, v) in out.iter_mut().zip(array.as_array().iter()) {
                *o = *v;
            }
        }
    }
    Ok(())
}

/// A world stepped from Python.
///
/// `World(path, *, seed=None, lenient=False, control=None, fitness="regatta", text=None)`
/// reads, checks and compiles a world file (a world that does not check raises `WorldError`
/// with the diagnostics at file:line:col, and `file`, `line`, `column`, `message` for
/// programs). `seed=None` takes the world's own `WorldInfo.randomSeed` (0 when it has none),
/// so that a world runs as `regatta run` runs it; `reset(seed)` starts again under another.
/// `text` gives the world's text instead of reading `path` (which still names it in messages
/// and is where its relative urls are read from). `world["name"]` (or `world.robot("name")`)
/// is one robot as it is after the last step. The robots named in `control` (every robot when `None`) are
/// driven by the actions given to `step`; the others run the controllers their world gives
/// them (`control=[]` runs the world as `regatta run` does). A driven robot may have an
/// external controller in its world (Webots' `"<extern>"`, as webots_ros2's worlds give the
/// e-puck): that is what such a world asks for; one that is not driven is refused (`lenient`:
/// it runs `braitenberg`), as `regatta run` does.
///
/// An action is two numbers per driven robot, the left and right wheel, in units of the
/// robot's speed scale (its `NeuralNetwork.outputScale`, else 20 pulses per 10 ms): 1 is
/// what a network's output of 1 commands. Commands are rounded and clamped to the real
/// robot's -127..127 pulses per 10 ms.
///
/// An observation is one row per driven robot: what its `NeuralNetwork` reads (the bias left
/// out), or by default its 8 IR readings and 8 ambient readings divided by 1024, then, with a
/// Panoramic turret, the raw retina pooled by maximum into 8 sectors (-1..1);
/// `observation_names` names the columns. The reward of a step is each driven robot's
/// contribution to `fitness` (`avoidance`: the step's Φ; `regatta`: cyclic visits, other
/// visits and the contact penalty it added; `phototaxis`: closeness times the step's length).
///
/// The same world, seed and actions give the same observations, bit for bit.
#[pyclass(module = "regatta")]
pub struct World {
    /// Locked only by `&self` readers; `&mut self` methods reach it without locking.
    core: Mutex<Core>,
    controlled_names: Vec<String>,
    observation_len: usize,
    actions: Vec<f64>,
    /// The live viewer (`view=True`), shown what Python steps; its page's controls are off.
    viewer: Mutex<Option<regatta_view::Viewer>>,
}

impl World {
    /// After Python moved the world: a sample for the page if someone watches (after a reset,
    /// always, so that trails start again).
    fn show(&mut self, reset: bool) {
        let viewer = self.viewer.get_mut().unwrap_or_else(|p| p.into_inner());
        let Some(viewer) = viewer.as_mut() else {
            return;
        };
        let core = self.core.get_mut().unwrap_or_else(|p| p.into_inner());
        if reset {
            viewer.restart(core.simulation());
        } else {
            viewer.after_step(core.simulation());
        }
        if viewer.control().is_some() {
            while viewer.control().is_some() {}
            viewer.update_status(|s| {
                s.note = "stepped from Python: the page's controls are off".to_owned()
            });
        }
    }

    fn core(&self) -> MutexGuard<'_, Core> {
        self.core
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn core_mut(&mut self) -> &mut Core {
        self.core
            .get_mut()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[pymethods]
impl World {
    #[new]
    #[pyo3(signature = (path, *, seed=None, lenient=false, control=None, fitness="regatta", text=None, vary=vec![], view=false, view_port=0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        path: PathBuf,
        seed: Option<u64>,
        lenient: bool,
        control: Option<Vec<String>>,
        fitness: &str,
        text: Option<&str>,
        vary: Vec<String>,
        view: bool,
        view_port: u16,
    ) -> PyResult<World> {
        let fitness = Fitness::parse(fitness).map_err(|e| value_error(e.to_string()))?;
        let driven = match &control {
            Some(names) => Driven::Named(names),
            None => Driven::Every,
        };
        let experiment = load(&path, text, lenient, driven, &vary)?;
        let core = Core::new(experiment, control.as_deref(), fitness, seed, 0).map_err(to_py)?;
        let lengths: Vec<usize> = core.observations().iter().map(|o| o.len()).collect();
        if lengths.windows(2).any(|w| w[0] != w[1]) {
            return Err(value_error(format!(
                "the driven robots observe vectors of different lengths ({lengths:?}); drive them \
                 from separate worlds, or give them NeuralNetworks with the same inputs"
            )));
        }
        let rigs = &core.experiment().compiled.rig.robots;
        let controlled_names = core
            .controlled()
            .iter()
            .map(|&r| rigs[r].name.clone())
            .collect();
        let observation_len = lengths.first().copied().unwrap_or(0);
        let actions = vec![0.0; 2 * core.controlled().len()];
        let viewer = if view {
            let loopback = std::net::IpAddr::from([127, 0, 0, 1]);
            let mut viewer =
                regatta_view::Viewer::serve(&core.experiment().compiled, loopback, view_port)
                    .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
            let seed = core.simulation().seed;
            viewer.update_status(|s| {
                s.seed = seed;
                s.speed = None;
            });
            viewer.publish(core.simulation());
            eprintln!("regatta: viewing at {}", viewer.url());
            Some(viewer)
        } else {
            None
        };
        Ok(World {
            core: Mutex::new(core),
            controlled_names,
            observation_len,
            actions,
            viewer: Mutex::new(viewer),
        })
    }

    /// Restarts the world under `seed` (the current seed when None) and returns the first
    /// observation. A log that was open is closed.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let seed = seed.unwrap_or(self.core_mut().simulation().seed);
        self.core_mut().reset(seed).map_err(to_py)?;
        self.show(true);
        Ok(self.observation(py))
    }

    /// Applies `actions` (2 per driven robot: left and right wheel; None keeps the last),
    /// advances the world one time step and returns the new observation, a float32 array of
    /// shape (driven robots, observation length). `rewards` then holds the step's rewards.
    #[pyo3(signature = (actions=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        if let Some(actions) = actions {
            read_actions(actions, &mut self.actions)?;
        }
        let core = self.core.get_mut().unwrap_or_else(|p| p.into_inner());
        core.step(&self.actions).map_err(to_py)?;
        self.show(false);
        Ok(self.observation(py))
    }

    /// Runs `steps` steps with the current actions (and the world's own controllers), without
    /// coming back to Python in between; returns the last observation.
    fn run<'py>(&mut self, py: Python<'py>, steps: u64) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let (core, actions, viewer) = (
            self.core.get_mut().unwrap_or_else(|p| p.into_inner()),
            &self.actions,
            self.viewer.get_mut().unwrap_or_else(|p| p.into_inner()),
        );
        py.detach(|| {
            for _ in 0..steps {
                core.step(actions)?;
                if let Some(viewer) = viewer.as_mut() {
                    viewer.after_step(core.simulation());
                }
            }
            Ok::<_, CoreError>(())
        })
        .map_err(to_py)?;
        Ok(self.observation(py))
    }

    /// The current observation: float32, shape (driven robots, observation length).
    #[getter]
    fn observation<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let array = PyArray2::<f32>::zeros(
            py,
            [self.controlled_names.len(), self.observation_len],
            false,
        );
        // SAFETY: the array was just made here and nothing else refers to it yet.
        if let Ok(out) = unsafe { array.as_slice_mut() } {
            self.core_mut().write_observation(out);
        }
        array
    }

    /// The last step's reward of each driven robot (float64).
    #[getter]
    fn rewards<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let mut out = vec![0.0; self.controlled_names.len()];
        self.core().write_rewards(&mut out);
        PyArray1::from_vec(py, out)
    }

    /// The names of the observation's columns (`ir0`, …, `ambient7`, `retina0`, …).
    /// The values this episode's variations drew (`vary=`), as (`Node[i].field`, value
    /// text) pairs; empty when nothing varies.
    #[getter]
    fn variations(&self) -> Vec<(String, String)> {
        self.core()
            .drawn()
            .iter()
            .map(|d| (d.key(), d.value.clone()))
            .collect()
    }

    #[getter]
    fn observation_names(&self) -> Vec<String> {
        self.core().observation_names()
    }

    /// Lowest and highest value of each observation column.
    #[getter]
    fn observation_bounds<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<f32>>) {
        bounds(py, &self.core())
    }

    /// Wheel command (pulses per 10 ms) of an action of 1, per driven robot.
    #[getter]
    fn speed_scale(&self) -> Vec<f64> {
        self.core()
            .observations()
            .iter()
            .map(|o| o.speed_scale)
            .collect()
    }

    /// The names of the robots `step`'s actions drive, in order.
    #[getter]
    fn controlled(&self) -> Vec<String> {
        self.controlled_names.clone()
    }

    /// Every robot, in file order.
    #[getter]
    fn robots(slf: &Bound<'_, Self>) -> Vec<Robot> {
        let count = slf.borrow().core().simulation().robots.len();
        (0..count)
            .map(|index| Robot {
                world: slf.clone().unbind(),
                index,
            })
            .collect()
    }

    /// The robot called `name` (KeyError names the robots there are).
    fn robot(slf: &Bound<'_, Self>, name: &str) -> PyResult<Robot> {
        let index = slf.borrow().core().experiment().compiled.rig.robot(name);
        match index {
            Some(index) => Ok(Robot {
                world: slf.clone().unbind(),
                index,
            }),
            None => {
                let world = slf.borrow();
                let core = world.core();
                let names: Vec<&str> = core
                    .simulation()
                    .robots
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect();
                Err(pyo3::exceptions::PyKeyError::new_err(format!(
                    "{} has no robot named '{name}' (it has: {})",
                    core.experiment().name,
                    names.join(", ")
                )))
            }
        }
    }

    /// `world["name"]`: the robot of that name as it is after the last step (`KeyError`
    /// naming the robots there are, when none has that name).
    fn __getitem__(slf: &Bound<'_, Self>, name: &str) -> PyResult<Robot> {
        World::robot(slf, name)
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.core().simulation().time
    }

    /// The live viewer's page (`view=True`), its URL with the run's token, or None.
    #[getter]
    fn view_url(&self) -> Option<String> {
        let viewer = self.viewer.lock().unwrap_or_else(|p| p.into_inner());
        viewer.as_ref().map(regatta_view::Viewer::url)
    }

    /// Steps done since the start.
    #[getter]
    fn steps(&self) -> u64 {
        self.core().simulation().steps
    }

    /// The world's time step (s).
    #[getter]
    fn time_step(&self) -> f64 {
        self.core().simulation().time_step
    }

    /// The seed of the run.
    #[getter]
    fn seed(&self) -> u64 {
        self.core().simulation().seed
    }

    /// The world's name as given.
    #[getter]
    fn name(&self) -> String {
        self.core().experiment().name.clone()
    }

    /// Records the run to an MCAP log, as `regatta run --log` does (the same bytes for the
    /// same world, seed and steps). A log holds a run from its start: call it at step 0 (after
    /// construction or `reset`). `steps` is the length the log's metadata announces. The log
    /// is closed by `close`, `reset`, or when the world is dropped. `channels` as
    /// `regatta run --channels`: `all`, `regatta` (the reproducible record), `foxglove`, or
    /// channel names, comma-separated. Robots driven from Python are named in the log's
    /// metadata with controller "python".
    #[pyo3(signature = (path, steps=0, channels="all"))]
    fn log(&mut self, path: PathBuf, steps: u64, channels: &str) -> PyResult<()> {
        let channels: Channels = channels
            .parse()
            .map_err(|e: regatta_runtime::log::UnknownChannel| value_error(e.to_string()))?;
        let request = LogRequest {
            path: &path,
            steps_requested: steps,
            channels,
        };
        self.core_mut().start_log(&request).map_err(to_py)
    }

    /// Closes the log, if one is open.
    fn close(&mut self) -> PyResult<()> {
        self.core_mut().close_log().map_err(to_py)
    }

    /// The run so far as the object `regatta run --json` prints (without `wall_s`): per
    /// robot distance, contacts (with what), buoy visits and every fitness with its terms.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = py.import("json")?;
        json.call_method1("loads", (self.core().summary_json(),))
    }

    /// `summary()` as JSON text (pretty-printed, keys in the documented order).
    fn summary_json(&self) -> String {
        self.core().summary_json()
    }

    /// The arena from above as an RGB image (uint8, shape (size, size, 3)): obstacles in
    /// their colours, robots as discs with a line to their heading.
    #[pyo3(signature = (size=256))]
    fn render<'py>(&self, py: Python<'py>, size: usize) -> PyResult<Bound<'py, PyArray3<u8>>> {
        crate::render::top_view_array(py, self.core().simulation(), size)
    }

    fn __repr__(&self) -> String {
        let core = self.core();
        let simulation = core.simulation();
        format!(
            "World({:?}, seed={}, steps={}, robots={:?}, controlled={:?})",
            core.experiment().name,
            simulation.seed,
            simulation.steps,
            simulation
                .robots
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>(),
            self.controlled_names
        )
    }
}

pub fn bounds<'py>(
    py: Python<'py>,
    core: &Core,
) -> (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<f32>>) {
    let elements = core
        .observations()
        .first()
        .map(|o| o.elements())
        .unwrap_or_default();
    (
        PyArray1::from_iter(py, elements.iter().map(|e| e.1)),
        PyArray1::from_iter(py, elements.iter().map(|e| e.2)),
    )
}

/// One robot of a `World`, read by name: its pose, sensors, wheels, contacts and visits as
/// they are after the last step.
#[pyclass(module = "regatta")]
pub struct Robot {
    world: Py<World>,
    index: usize,
}

impl Robot {
    fn with<R>(&self, py: Python<'_>, f: impl FnOnce(&regatta_runtime::sim::RobotState) -> R) -> R {
        let world = self.world.borrow(py);
        let core = world.core();
        f(&core.simulation().robots[self.index])
    }
}

#[pymethods]
impl Robot {
    #[getter]
    fn name(&self, py: Python<'_>) -> String {
        self.with(py, |r| r.name.clone())
    }

    /// (x, z, heading): position (m) and heading (rad, counter-clockwise from +x seen from
    /// above).
    #[getter]
    fn pose(&self, py: Python<'_>) -> (f64, f64, f64) {
        self.with(py, |r| (r.pose.x, r.pose.z, r.pose.heading))
    }

    /// The 8 IR proximity readings (0..1023, larger when closer), uint16.
    #[getter]
    fn proximity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u16>> {
        let values = self.with(py, |r| r.proximity);
        PyArray1::from_slice(py, &values)
    }

    /// The 8 ambient light readings (0..1023, larger when darker), uint16.
    #[getter]
    fn ambient<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u16>> {
        let values = self.with(py, |r| r.ambient);
        PyArray1::from_slice(py, &values)
    }

    /// One enabled filter's converted retina output over the region of interest (uint16), as
    /// the turret's API reads it; `raw`, `lowpass`, `highpass`, `bandpass` or `odd`.
    #[pyo3(signature = (filter="odd"))]
    fn retina<'py>(&self, py: Python<'py>, filter: &str) -> PyResult<Bound<'py, PyArray1<u16>>> {
        let kind = FilterKind::from_name(filter).ok_or_else(|| {
            value_error(format!(
                "unknown filter \"{filter}\"; filters: raw, lowpass, highpass, bandpass, odd"
            ))
        })?;
        let values = self.with(py, |r| match &r.panoramic {
            None => Err(value_error(format!("robot '{}' has no Panoramic turret", r.name))),
            Some(turret) => turret
                .output
                .digital
                .iter()
                .find(|(k, _)| *k == kind)
                .map(|(_, d)| d.clone())
                .ok_or_else(|| {
                    value_error(format!(
                        "filter {filter} of robot '{}' is not enabled or not yet read (enable it in the world's PanoramicTurret)",
                        r.name
                    ))
                }),
        })?;
        Ok(PyArray1::from_vec(py, values))
    }

    /// The wheel commands of the last step (pulses per 10 ms).
    #[getter]
    fn wheels(&self, py: Python<'_>) -> (i32, i32) {
        self.with(py, |r| r.command)
    }

    /// Contacts begun since the start.
    #[getter]
    fn contacts(&self, py: Python<'_>) -> u64 {
        self.with(py, |r| r.contacts.events)
    }

    /// Whether the robot ended the last step touching something.
    #[getter]
    fn touching(&self, py: Python<'_>) -> bool {
        self.with(py, |r| r.contacts.is_touching())
    }

    /// Buoys entered, in order (numbered from 1, in file order).
    #[getter]
    fn visits(&self, py: Python<'_>) -> Vec<usize> {
        self.with(py, |r| r.visits.sequence.iter().map(|k| k + 1).collect())
    }

    /// The robot's reward in the last step.
    #[getter]
    fn reward(&self, py: Python<'_>) -> f64 {
        let world = self.world.borrow(py);
        let reward = world.core().rewards()[self.index];
        reward
    }

    /// The chosen fitness so far: its `value` and its terms, named as `regatta run --json`
    /// names them (`regatta`: `cyclic_visits`, `other_visits`, `contact_s`; `avoidance`: the
    /// means `speed`, `turning`, `proximity`; `phototaxis`: the `buoy` it is drawn to).
    #[getter]
    fn fitness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let terms = {
            let world = self.world.borrow(py);
            let terms = world.core().fitness_terms(self.index);
            terms
        };
        let dict = PyDict::new(py);
        if let serde_json::Value::Object(map) = terms {
            for (name, value) in map {
                match value {
                    // Counts stay whole numbers; seconds and means are floats.
                    serde_json::Value::Number(n) => match (n.as_u64(), n.as_f64()) {
                        (Some(whole), _) => dict.set_item(name, whole)?,
                        (None, Some(real)) => dict.set_item(name, real)?,
                        (None, None) => dict.set_item(name, py.None())?,
                    },
                    serde_json::Value::Bool(b) => dict.set_item(name, b)?,
                    _ => dict.set_item(name, py.None())?,
                }
            }
        }
        Ok(dict)
    }

    /// Everything above as a dict.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        dict.set_item("name", self.name(py))?;
        dict.set_item("pose", self.pose(py))?;
        dict.set_item("proximity", self.proximity(py))?;
        dict.set_item("ambient", self.ambient(py))?;
        dict.set_item("wheels", self.wheels(py))?;
        dict.set_item("contacts", self.contacts(py))?;
        dict.set_item("visits", self.visits(py))?;
        Ok(dict)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        self.with(py, |r| {
            format!(
                "Robot({:?}, x={:.3}, z={:.3}, heading={:.3})",
                r.name, r.pose.x, r.pose.z, r.pose.heading
            )
        })
    }
}
