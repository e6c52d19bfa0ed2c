//! One world as an environment: a simulation whose chosen robots Python drives, their
//! observation vectors and rewards, episodes and an optional log. [`crate::world::World`]
//! wraps one; [`crate::vector::VectorWorld`] steps many on a thread pool.
//!
//! A step from Python is the simulation's two halves in the other order: the actions are
//! applied and the world moves ([`Simulation::act`]), then the sensors are read for the next
//! observation ([`Simulation::sense`]). From a reset, `sense, act, sense, act, …` is exactly
//! the sequence of `regatta run`, so a world stepped from Python gives the same run, summary
//! and log as the command line.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::Arc;

use regatta_evolve::experiment::{EvalError, LoadError};
use regatta_evolve::{Experiment, Fitness, Observer};
use regatta_runtime::compile::network::{Input, Pooling};
use regatta_runtime::compile::rig::{RobotRig, TurretRig};
use regatta_runtime::controllers::neural::pool_sectors;
use regatta_runtime::khepera::{to_command, Controller, Khepera, KheperaError, Senses};
use regatta_runtime::log::{Channels, Recorder, RunInfo};
use regatta_runtime::retina::FilterKind;
use regatta_runtime::sim::{RobotState, Simulation};

self_cell::self_cell!(
    /// A simulation together with the compiled world it borrows.
    struct Running {
        owner: Arc<Experiment>,
        #[covariant]
        dependent: Simulation,
    }
);

/// Why an environment cannot be made or stepped.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Eval(#[from] EvalError),
    #[error("{world} has no robot named '{name}' (it has: {known})")]
    UnknownRobot {
        world: String,
        name: String,
        known: String,
    },
    #[error("{0}")]
    Usage(String),
    #[error("cannot write the log {path}: {message}")]
    Log { path: String, message: String },
}

/// The wheel speed unit of an action when a robot has no `NeuralNetwork` to take it from
/// (pulses per 10 ms per unit action): `NeuralNetwork.outputScale`'s default.
pub const DEFAULT_SPEED_SCALE: f64 = 20.0;

/// What a robot driven from Python observes: the inputs of its `NeuralNetwork` (the bias
/// left out), or of a network with the default fields reading IR, ambient light and (with a
/// Panoramic turret) the retina. Values are scaled as the network sees them: IR and ambient
/// readings / 1024, retina sectors (−1 … 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Observation {
    pub inputs: Vec<Input>,
    pub sectors: usize,
    pub pooling: Pooling,
    /// Wheel command (pulses per 10 ms) of action 1: the network's `outputScale`.
    pub speed_scale: f64,
}

impl Observation {
    pub fn for_robot(rig: &RobotRig) -> Observation {
        if let Some(Ok(spec)) = &rig.network {
            let t = &spec.topology;
            return Observation {
                inputs: t
                    .inputs
                    .iter()
                    .copied()
                    .filter(|i| *i != Input::Bias)
                    .collect(),
                sectors: t.retina_sectors,
                pooling: t.retina_pooling,
                speed_scale: t.output_scale,
            };
        }
        let mut inputs: Vec<Input> = (0..8)
            .map(Input::Ir)
            .chain((0..8).map(Input::Ambient))
            .collect();
        if matches!(rig.turret, Some(TurretRig::Panoramic(_))) {
            inputs.push(Input::Retina(FilterKind::Raw));
        }
        Observation {
            inputs,
            sectors: 8,
            pooling: Pooling::Max,
            speed_scale: DEFAULT_SPEED_SCALE,
        }
    }

    /// The turret output the first retina input reads.
    fn first_retina(&self) -> Option<FilterKind> {
        self.inputs.iter().find_map(|input| match *input {
            Input::Retina(filter) => Some(filter),
            _ => None,
        })
    }

    /// The observation vector's length.
    pub fn len(&self) -> usize {
        self.inputs
            .iter()
            .map(|i| match i {
                Input::Retina(_) => self.sectors,
                _ => 1,
            })
            .sum()
    }

    /// Each element's name (`ir0`, `ambient3`, `retina5`) and range.
    pub fn elements(&self) -> Vec<(String, f32, f32)> {
        let mut out = Vec::new();
        for input in &self.inputs {
            match *input {
                Input::Ir(i) => out.push((format!("ir{i}"), 0.0, 1023.0 / 1024.0)),
                Input::Ambient(i) => out.push((format!("ambient{i}"), 0.0, 1023.0 / 1024.0)),
                Input::Retina(filter) => {
                    // The first retina input keeps the plain names; others name their output.
                    let prefix = if Some(filter) == self.first_retina() {
                        "retina".to_owned()
                    } else {
                        format!("retina:{}:", filter.name())
                    };
                    out.extend((0..self.sectors).map(|s| (format!("{prefix}{s}"), -1.0, 1.0)))
                }
                Input::Bias => {}
            }
        }
        out
    }

    pub fn senses(&self) -> Senses {
        Senses {
            proximity: self.inputs.iter().any(|i| matches!(i, Input::Ir(_))),
            ambient: self.inputs.iter().any(|i| matches!(i, Input::Ambient(_))),
            vision: self.inputs.iter().any(Input::is_retina),
            camera: false,
        }
    }

    /// Writes the robot's observation into `out` (`self.len()` values).
    fn write(&self, robot: &RobotState, scratch: &mut Vec<f64>, out: &mut [f32]) {
        scratch.clear();
        for input in &self.inputs {
            match *input {
                Input::Ir(i) => scratch.push(robot.proximity[i] as f64 / 1024.0),
                Input::Ambient(i) => scratch.push(robot.ambient[i] as f64 / 1024.0),
                Input::Retina(filter) => {
                    let (digital, bits): (&[u16], u32) = match &robot.panoramic {
                        Some(turret) => (
                            turret
                                .output
                                .digital
                                .iter()
                                .find(|(k, _)| *k == filter)
                                .map_or(&[], |(_, d)| d.as_slice()),
                            turret.model.rig.bits,
                        ),
                        None => (&[], 1),
                    };
                    pool_sectors(digital, bits, self.sectors, self.pooling, scratch);
                }
                Input::Bias => {}
            }
        }
        for (o, &v) in out.iter_mut().zip(scratch.iter()) {
            *o = v as f32;
        }
    }
}

/// The wheel commands Python last gave a robot, shared with the controller that applies them.
type Command = Arc<[AtomicI32; 2]>;

/// The controller of a robot driven from Python: it applies the last action and declares
/// the sensors its observation reads, so that nothing else is computed for it.
struct External {
    command: Command,
    senses: Senses,
}

impl Controller for External {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        robot.set_speed(
            self.command[0].load(Ordering::Relaxed),
            self.command[1].load(Ordering::Relaxed),
        )
    }

    fn senses(&self) -> Senses {
        self.senses
    }
}

/// What `World.log` asks for.
#[derive(Clone, Copy)]
pub struct LogRequest<'a> {
    pub path: &'a Path,
    /// The run's length the log's metadata announces.
    pub steps_requested: u64,
    pub channels: Channels,
}

/// An open log and what it needs to close.
struct Log {
    recorder: Recorder<BufWriter<File>>,
    path: String,
}

/// The robots Python drives: by index, in the order actions and observations list them.
struct Drive {
    controlled: Vec<usize>,
    observations: Vec<Observation>,
    commands: Vec<Command>,
}

impl Drive {
    /// A simulation of `experiment` under `seed` with these robots driven from outside, its
    /// log opened when asked (before the first sensing, so that the log holds everything),
    /// and its sensors read for the first observation.
    fn launch(
        &self,
        experiment: &Arc<Experiment>,
        seed: u64,
        log: Option<&LogRequest>,
    ) -> Result<(Running, Option<Log>), CoreError> {
        // A world with variations is drawn anew for each seed; the trial's world owns its
        // simulation (and its log embeds the drawn text).
        let world = match experiment.for_seed(seed)? {
            Some(varied) => Arc::new(varied),
            None => experiment.clone(),
        };
        let experiment = &world;
        let mut running = Running::try_new(world.clone(), |e| e.simulation(seed, None))?;
        let opened = running.with_dependent_mut(|_, simulation| {
            for ((&robot, observation), command) in self
                .controlled
                .iter()
                .zip(&self.observations)
                .zip(&self.commands)
            {
                for c in command.iter() {
                    c.store(0, Ordering::Relaxed);
                }
                simulation.set_controller(
                    robot,
                    Box::new(External {
                        command: command.clone(),
                        senses: observation.senses(),
                    }),
                );
                for input in &observation.inputs {
                    if let Input::Retina(filter) = *input {
                        if let Some(turret) = simulation.khepera(robot).panoramic() {
                            // Enabling a filter of a Panoramic turret cannot fail.
                            let _ = turret.enable_filter(filter);
                        }
                    }
                }
            }
            let log = match log {
                Some(request) => Some(open_log(experiment, simulation, &self.controlled, request)?),
                None => None,
            };
            simulation.sense();
            Ok::<_, CoreError>(log)
        })?;
        Ok((running, opened))
    }
}

/// One world as an environment.
pub struct Core {
    experiment: Arc<Experiment>,
    running: Running,
    observer: Observer,
    fitness: Fitness,
    drive: Drive,
    /// Steps after which an episode is truncated (0: never).
    episode_steps: u64,
    log: Option<Log>,
    scratch: Vec<f64>,
    /// Each robot's reward over the last step of the environment: the sum over the
    /// physics steps of one control period.
    rewards: Vec<f64>,
}

impl Core {
    /// A world whose robots named in `controlled` (every robot when `None`) are driven by
    /// actions; the others run their own controllers.
    pub fn new(
        experiment: Arc<Experiment>,
        controlled: Option<&[String]>,
        fitness: Fitness,
        seed: Option<u64>,
        episode_steps: u64,
    ) -> Result<Core, CoreError> {
        let rigs = &experiment.compiled.rig.robots;
        let controlled: Vec<usize> = match controlled {
            None => (0..rigs.len()).collect(),
            Some(names) => names
                .iter()
                .map(|name| {
                    experiment
                        .compiled
                        .rig
                        .robot(name)
                        .ok_or_else(|| CoreError::UnknownRobot {
                            world: experiment.name.clone(),
                            name: name.clone(),
                            known: rigs
                                .iter()
                                .map(|r| r.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", "),
                        })
                })
                .collect::<Result<_, _>>()?,
        };
        for (k, a) in controlled.iter().enumerate() {
            if controlled[..k].contains(a) {
                return Err(CoreError::Usage(format!(
                    "robot '{}' is listed twice",
                    rigs[*a].name
                )));
            }
        }
        let observations = controlled
            .iter()
            .map(|&r| Observation::for_robot(&rigs[r]))
            .collect();
        let commands = controlled
            .iter()
            .map(|_| Arc::new([AtomicI32::new(0), AtomicI32::new(0)]))
            .collect();
        let drive = Drive {
            controlled,
            observations,
            commands,
        };
        let seed = seed.unwrap_or(experiment.compiled.settings.seed);
        let robots = rigs.len();
        let (running, log) = drive.launch(&experiment, seed, None)?;
        let observer = Observer::new(running.borrow_dependent(), &fitness);
        Ok(Core {
            experiment,
            running,
            observer,
            fitness,
            drive,
            episode_steps,
            log,
            scratch: Vec::new(),
            rewards: vec![0.0; robots],
        })
    }

    pub fn experiment(&self) -> &Arc<Experiment> {
        &self.experiment
    }

    /// The values the current episode's variations drew (empty when nothing varies).
    pub fn drawn(&self) -> &[regatta_evolve::variations::Drawn] {
        &self.running.borrow_owner().drawn
    }

    pub fn simulation(&self) -> &Simulation<'_> {
        self.running.borrow_dependent()
    }

    pub fn controlled(&self) -> &[usize] {
        &self.drive.controlled
    }

    pub fn observations(&self) -> &[Observation] {
        &self.drive.observations
    }

    pub fn episode_steps(&self) -> u64 {
        self.episode_steps
    }

    /// The observation's column names (the first driven robot's; all have the same length in
    /// a `World`, and there is one in a `VectorWorld`).
    pub fn observation_names(&self) -> Vec<String> {
        self.drive
            .observations
            .first()
            .map(|o| o.elements().into_iter().map(|(name, _, _)| name).collect())
            .unwrap_or_default()
    }

    /// The total observation length (every controlled robot's, in order).
    pub fn observation_len(&self) -> usize {
        self.drive.observations.iter().map(Observation::len).sum()
    }

    /// Starts the world afresh under `seed`, closing a log that was open.
    pub fn reset(&mut self, seed: u64) -> Result<(), CoreError> {
        self.close_log()?;
        self.start(seed, None)
    }

    /// Restarts the world under the same seed with a log recording it from step 0, as
    /// `regatta run --log` does; only at step 0 (a log holds a run from its start).
    pub fn start_log(&mut self, request: &LogRequest) -> Result<(), CoreError> {
        let steps = self.simulation().steps;
        if steps != 0 {
            return Err(CoreError::Usage(format!(
                "a log records a run from its start, and this one is at step {steps}: call reset() first"
            )));
        }
        self.close_log()?;
        let seed = self.simulation().seed;
        self.start(seed, Some(request))
    }

    fn start(&mut self, seed: u64, log: Option<&LogRequest>) -> Result<(), CoreError> {
        let (running, log) = self.drive.launch(&self.experiment, seed, log)?;
        self.running = running;
        self.log = log;
        self.observer = Observer::new(self.running.borrow_dependent(), &self.fitness);
        self.rewards.iter_mut().for_each(|r| *r = 0.0);
        Ok(())
    }

    /// One step: `actions` (two per controlled robot, in units of the robot's speed scale)
    /// are applied, the world moves for one control period (physics steps until a controlled
    /// robot's controller is next due, or the episode's end), the sensors are read for the
    /// next observation. Rewards add up over the period's steps.
    pub fn step(&mut self, actions: &[f64]) -> Result<(), CoreError> {
        for ((command, observation), pair) in self
            .drive
            .commands
            .iter()
            .zip(&self.drive.observations)
            .zip(actions.chunks_exact(2))
        {
            command[0].store(
                to_command(pair[0] * observation.speed_scale),
                Ordering::Relaxed,
            );
            command[1].store(
                to_command(pair[1] * observation.speed_scale),
                Ordering::Relaxed,
            );
        }
        let (observer, log) = (&mut self.observer, &mut self.log);
        let (controlled, rewards) = (&self.drive.controlled, &mut self.rewards);
        let episode_steps = self.episode_steps;
        rewards.iter_mut().for_each(|r| *r = 0.0);
        self.running.with_dependent_mut(|_, simulation| loop {
            simulation.act();
            observer.after_step(simulation);
            for (sum, &r) in rewards.iter_mut().zip(observer.rewards()) {
                *sum += r;
            }
            if let Some(log) = log {
                log.recorder
                    .record(simulation)
                    .map_err(|e| CoreError::Log {
                        path: log.path.clone(),
                        message: e.to_string(),
                    })?;
            }
            simulation.sense();
            let truncated = episode_steps > 0 && simulation.steps >= episode_steps;
            if truncated
                || controlled.is_empty()
                || controlled.iter().any(|&r| simulation.control_due(r))
            {
                return Ok(());
            }
        })
    }

    /// Whether the episode has run its steps.
    pub fn truncated(&self) -> bool {
        self.episode_steps > 0 && self.simulation().steps >= self.episode_steps
    }

    /// Each controlled robot's observation, in order, into `out`.
    pub fn write_observation(&mut self, out: &mut [f32]) {
        let simulation = self.running.borrow_dependent();
        let mut offset = 0;
        for (&robot, observation) in self.drive.controlled.iter().zip(&self.drive.observations) {
            let n = observation.len();
            observation.write(
                &simulation.robots[robot],
                &mut self.scratch,
                &mut out[offset..offset + n],
            );
            offset += n;
        }
    }

    /// Each controlled robot's reward in the last step.
    pub fn write_rewards(&self, out: &mut [f64]) {
        let rewards = &self.rewards;
        for (o, &robot) in out.iter_mut().zip(&self.drive.controlled) {
            *o = rewards[robot];
        }
    }

    /// The chosen fitness's terms so far for `robot` (file order): its value and what it is
    /// made of, named as `regatta run --json` names them (`cyclic_visits`, `contact_s`…).
    pub fn fitness_terms(&self, robot: usize) -> serde_json::Value {
        let terms = self.observer.terms(robot);
        match self.fitness {
            Fitness::Avoidance { .. } => serde_json::to_value(terms.avoidance),
            Fitness::Regatta { .. } => serde_json::to_value(terms.regatta),
            Fitness::Phototaxis { .. } => serde_json::to_value(terms.phototaxis),
        }
        .unwrap_or_default()
    }

    /// The chosen fitness's value so far for `robot` (file order).
    pub fn fitness_value(&self, robot: usize) -> f64 {
        self.observer.terms(robot).value(&self.fitness)
    }

    /// Every robot's reward in the last step, in file order.
    pub fn rewards(&self) -> &[f64] {
        &self.rewards
    }

    /// The run so far as `regatta run --json` prints it (without wall time).
    pub fn summary_json(&self) -> String {
        let mut summary = self
            .observer
            .summary(self.simulation(), &self.experiment.name, None);
        summary.variations = self.drawn().to_vec();
        serde_json::to_string_pretty(&summary).unwrap_or_default()
    }

    /// Closes the open log, if any.
    pub fn close_log(&mut self) -> Result<(), CoreError> {
        let Some(log) = self.log.take() else {
            return Ok(());
        };
        log.recorder
            .finish(self.running.borrow_dependent(), false)
            .map(|_| ())
            .map_err(|e| CoreError::Log {
                path: log.path,
                message: e.to_string(),
            })
    }
}

impl Drop for Core {
    fn drop(&mut self) {
        // A log left open is closed properly; an error here has nobody to go to.
        let _ = self.close_log();
    }
}

fn open_log(
    experiment: &Experiment,
    simulation: &mut Simulation,
    controlled: &[usize],
    request: &LogRequest,
) -> Result<Log, CoreError> {
    let LogRequest {
        path,
        steps_requested,
        channels,
    } = *request;
    let shown = path.display().to_string();
    let failed = |message: String| CoreError::Log {
        path: shown.clone(),
        message,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| failed(e.to_string()))?;
    }
    let file = File::create(path).map_err(|e| failed(e.to_string()))?;
    let run = RunInfo {
        world_name: experiment.name.clone(),
        world_text: experiment.text.clone(),
        seed: simulation.seed,
        lenient: experiment.lenient,
        steps_requested,
        channels,
        // The robots driven from Python: their commands came from outside the world.
        controllers: controlled
            .iter()
            .map(|&r| {
                (
                    simulation.robots[r].name.clone(),
                    "python".to_owned(),
                    Vec::new(),
                )
            })
            .collect(),
        variations: (!experiment.drawn.is_empty())
            .then(|| serde_json::to_string(&experiment.drawn).unwrap_or_default()),
    };
    let recorder = Recorder::new(BufWriter::new(file), simulation, &run).map_err(|e| {
        // A log that could not start holds no message: no half-written file is left behind
        // (only a plain file is removed: a device such as /dev/full stays).
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
            std::fs::remove_file(path).ok();
        }
        failed(e.to_string())
    })?;
    Ok(Log {
        recorder,
        path: shown,
    })
}
