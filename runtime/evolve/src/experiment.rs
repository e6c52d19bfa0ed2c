//! A world loaded once and evaluated many times: parsed, checked and compiled once, then run
//! for any seed and any candidate weights of its network, in parallel, with results in a
//! fixed order whatever the number of threads.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec2;
use rayon::prelude::*;
use regatta_runtime::compile::network::{NetworkError, Topology};
use regatta_runtime::controllers::neural::Neural;
use regatta_runtime::sim::{SimError, Simulation};
use regatta_runtime::Compiled;
use serde::Serialize;

use crate::fitness::{Fitness, FitnessTerms, Meters};
use crate::record::LiveRecords;
use crate::variations::{Drawn, Plan, Variation, VaryError};
use crate::world::{apply_overrides, EditError, Override};

/// Why a world cannot be loaded for evaluation.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error(transparent)]
    Read(#[from] regatta_parser::SourceError),
    #[error(transparent)]
    Edit(#[from] EditError),
    /// The diagnostics, rendered, and each error where it stands.
    #[error("{name} has {}:\n{rendered}", errors_phrase(*errors))]
    Check {
        name: String,
        errors: usize,
        rendered: String,
        located: Vec<Located>,
    },
    /// Robots regatta could not build, or a controller it does not have (strict mode).
    #[error("cannot run {name}: {reason}")]
    Refused { name: String, reason: String },
    #[error("cannot run {name}: {source}")]
    Start {
        name: String,
        #[source]
        source: SimError,
    },
}

/// One error of a world that does not check, for programs that read it: the file it is in,
/// its line and column (from 1, the column in characters) and its message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Located {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// Why an evaluation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    #[error("{world} has no robot with controller \"neural\" whose weights could be set")]
    NoNetwork { world: String },
    #[error("{world}: {source}")]
    Network {
        world: String,
        #[source]
        source: NetworkError,
    },
    #[error("{world}: {source}")]
    Start {
        world: String,
        #[source]
        source: SimError,
    },
    #[error("{world}: step {step}: {message}")]
    Vision {
        world: String,
        step: u64,
        message: String,
    },
    #[error("{world}: {source}")]
    Vary {
        world: String,
        #[source]
        source: VaryError,
    },
    #[error("{world}: {message}")]
    Controller { world: String, message: String },
}

/// The robots a world's network drives, and its topology.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldNetwork {
    /// Robots with controller "neural" (every one gets a candidate's weights).
    pub robots: Vec<usize>,
    pub topology: Arc<Topology>,
    /// The weights the world file holds.
    pub weights: Vec<f64>,
}

/// A world ready for many evaluations.
#[derive(Debug)]
pub struct Experiment {
    /// The world's name as given (a path).
    pub name: String,
    /// The world's text, overrides applied.
    pub text: String,
    pub lenient: bool,
    pub compiled: Compiled,
    /// The network of its `neural` robots, if any (the first robot's: they must share it).
    pub network: Option<WorldNetwork>,
    /// Warnings of the check, rendered, and notes on controllers mapped from Webots' names
    /// (empty when none).
    pub warnings: String,
    /// The values drawn for this world when it is one trial's variation (empty otherwise).
    pub drawn: Vec<Drawn>,
    /// How to read the world again with other text: what variations need.
    reading: Arc<Reading>,
    /// The variations each trial draws, if any.
    plan: Option<Arc<Plan>>,
    /// The robots that run their project's controllers (empty unless loaded with them).
    programs: crate::programs::Programs,
}

/// Everything but the text that reading a world took.
#[derive(Debug)]
struct Reading {
    base_dir: Option<PathBuf>,
    options: regatta_schema::Options,
    driven: DrivenBy,
    /// The file is ENU (z up): variations write positions and headings in its axes.
    z_up: bool,
    /// Robots run their project's controllers (`regatta batch`).
    programs: bool,
}

/// [`Driven`], owned.
#[derive(Clone, Debug)]
enum DrivenBy {
    Nobody,
    Every,
    First,
    Named(Vec<String>),
}

impl DrivenBy {
    fn of(driven: Driven<'_>) -> DrivenBy {
        match driven {
            Driven::Nobody => DrivenBy::Nobody,
            Driven::Every => DrivenBy::Every,
            Driven::First => DrivenBy::First,
            Driven::Named(names) => DrivenBy::Named(names.to_vec()),
        }
    }

    fn borrow(&self) -> Driven<'_> {
        match self {
            DrivenBy::Nobody => Driven::Nobody,
            DrivenBy::Every => Driven::Every,
            DrivenBy::First => Driven::First,
            DrivenBy::Named(names) => Driven::Named(names),
        }
    }
}

/// The robots driven from outside the simulator (by Python's actions): a world written for
/// that names an external controller for them (Webots' `"<extern>"`), which is then what they
/// should have rather than a controller to refuse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Driven<'a> {
    /// No robot: every robot runs its world's controller (`regatta batch`, `evolve`).
    #[default]
    Nobody,
    /// Every robot.
    Every,
    /// The first robot.
    First,
    /// The robots of these names.
    Named(&'a [String]),
}

impl Driven<'_> {
    fn drives(&self, index: usize, name: &str) -> bool {
        match self {
            Driven::Nobody => false,
            Driven::Every => true,
            Driven::First => index == 0,
            Driven::Named(names) => names.iter().any(|n| n == name),
        }
    }
}

/// The reading options of a world read with only a strict or lenient choice: its own folder,
/// default limits, no PROTO path.
fn reading(lenient: bool) -> regatta_schema::Options {
    regatta_schema::Options {
        strict: !lenient,
        ..regatta_schema::Options::default()
    }
}

impl Experiment {
    /// Reads, edits (`--set`), checks and compiles a world file.
    pub fn load(
        path: &Path,
        lenient: bool,
        overrides: &[Override],
    ) -> Result<Experiment, LoadError> {
        Experiment::load_driven(path, lenient, overrides, Driven::Nobody)
    }

    /// [`Experiment::load`], with the robots that are driven from outside.
    pub fn load_driven(
        path: &Path,
        lenient: bool,
        overrides: &[Override],
        driven: Driven<'_>,
    ) -> Result<Experiment, LoadError> {
        Experiment::load_with(path, &reading(lenient), overrides, driven)
    }

    /// [`Experiment::load_driven`] with every reading option of the command line: strict or
    /// lenient, folders the world may read beside its own (`--allow-path`), limits
    /// (`--limit`) and the PROTO path. The world's own folder is always added to the access.
    pub fn load_with(
        path: &Path,
        options: &regatta_schema::Options,
        overrides: &[Override],
        driven: Driven<'_>,
    ) -> Result<Experiment, LoadError> {
        Experiment::load_inner(path, options, overrides, driven, false)
    }

    /// [`Experiment::load_with`] for a world whose robots may run their project's controllers
    /// (Webots' `controllers/NAME/`): each is compiled now and started anew for every trial.
    /// This runs the project's code.
    pub fn load_with_programs(
        path: &Path,
        options: &regatta_schema::Options,
        overrides: &[Override],
    ) -> Result<Experiment, LoadError> {
        Experiment::load_inner(path, options, overrides, Driven::Nobody, true)
    }

    fn load_inner(
        path: &Path,
        options: &regatta_schema::Options,
        overrides: &[Override],
        driven: Driven<'_>,
        programs: bool,
    ) -> Result<Experiment, LoadError> {
        if path.as_os_str() == "-" {
            // Standard input: a world with no folder, which reads no file.
            let bytes = regatta_parser::source::read_bytes(
                std::io::stdin().lock(),
                options.limits.file_size,
            )
            .map_err(|error| {
                LoadError::Read(regatta_parser::SourceError::Io {
                    path: path.to_owned(),
                    source: std::io::Error::other(error.to_string()),
                })
            })?;
            let source = regatta_parser::SourceText::from_bytes("<stdin>".to_owned(), bytes);
            // A world from standard input has no project: no program of its own.
            let text = apply_overrides(&source.text, overrides)?;
            return Experiment::read(
                &source.name,
                text,
                None,
                options,
                DrivenBy::of(driven),
                false,
            );
        }
        let source = regatta_parser::SourceText::read_limited(path, options.limits.file_size)?;
        let base = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_owned(),
            _ => PathBuf::from("."),
        };
        let text = apply_overrides(&source.text, overrides)?;
        Experiment::read(
            &source.name,
            text,
            Some(base),
            options,
            DrivenBy::of(driven),
            programs,
        )
    }

    /// A world given as text; `base_dir` is where its EXTERNPROTOs and Inlines resolve
    /// (`None`: it may read no file).
    pub fn from_text(
        name: &str,
        text: &str,
        base_dir: Option<PathBuf>,
        lenient: bool,
        overrides: &[Override],
    ) -> Result<Experiment, LoadError> {
        Experiment::from_text_driven(name, text, base_dir, lenient, overrides, Driven::Nobody)
    }

    /// [`Experiment::from_text`], with the robots that are driven from outside.
    pub fn from_text_driven(
        name: &str,
        text: &str,
        base_dir: Option<PathBuf>,
        lenient: bool,
        overrides: &[Override],
        driven: Driven<'_>,
    ) -> Result<Experiment, LoadError> {
        Experiment::from_text_with(name, text, base_dir, &reading(lenient), overrides, driven)
    }

    /// [`Experiment::from_text_driven`] with every reading option (see
    /// [`Experiment::load_with`]); `options.base_dir` is replaced by `base_dir`.
    pub fn from_text_with(
        name: &str,
        text: &str,
        base_dir: Option<PathBuf>,
        options: &regatta_schema::Options,
        overrides: &[Override],
        driven: Driven<'_>,
    ) -> Result<Experiment, LoadError> {
        let text = apply_overrides(text, overrides)?;
        Experiment::read(name, text, base_dir, options, DrivenBy::of(driven), false)
    }

    /// Checks and compiles `text`, overrides already applied.
    fn read(
        name: &str,
        text: String,
        base_dir: Option<PathBuf>,
        options: &regatta_schema::Options,
        driven: DrivenBy,
        programs: bool,
    ) -> Result<Experiment, LoadError> {
        let lenient = !options.strict;
        // The world reads files under its project (its folder, or the folder above a
        // `worlds` folder), and the folders the options allow, only (see
        // regatta_schema::access).
        let base_dir = base_dir.and_then(|dir| dir.canonicalize().ok());
        let options = &regatta_schema::Options {
            base_dir: base_dir.clone(),
            ..options.clone()
        };
        let mut access = options.access.clone();
        if let Some(dir) = &base_dir {
            let _ = access.allow(&regatta_schema::access::project_root(dir));
        }
        let mut checked = regatta_schema::check(
            regatta_parser::SourceText::from_bytes(name.to_owned(), text.clone().into_bytes()),
            &regatta_schema::Options {
                access,
                base_dir,
                ..options.clone()
            },
        );
        if programs {
            regatta_runtime::check::check_scene_with(&mut checked, &|controller| {
                crate::programs::is_program(name, controller)
            });
        } else {
            regatta_runtime::check::check_scene(&mut checked);
        }
        let render = |errors: bool| -> String {
            checked
                .diagnostics
                .iter()
                .filter(|d| d.diagnostic.is_error() == errors)
                .map(|d| {
                    let source = &checked.sources[d.file.0 as usize];
                    d.diagnostic.render(&source.name, &source.text, false)
                })
                .collect()
        };
        let errors = checked
            .diagnostics
            .iter()
            .filter(|d| d.diagnostic.is_error())
            .count();
        if errors > 0 {
            let located = checked
                .diagnostics
                .iter()
                .filter(|d| d.diagnostic.is_error())
                .map(|d| {
                    let source = &checked.sources[d.file.0 as usize];
                    let (line, column) = d.diagnostic.line_col(&source.text);
                    Located {
                        file: source.name.clone(),
                        line,
                        column,
                        message: d.diagnostic.message.clone(),
                    }
                })
                .collect();
            return Err(LoadError::Check {
                name: name.to_owned(),
                errors,
                rendered: render(true),
                located,
            });
        }
        let mut warnings = if lenient {
            render(false)
        } else {
            String::new()
        };
        if let Some(reason) = checked.unbuilt_refusal() {
            return Err(LoadError::Refused {
                name: name.to_owned(),
                reason,
            });
        }
        let mut compiled = regatta_runtime::compile(&checked.scene);
        let found = if programs {
            let skip: Vec<usize> = compiled
                .rig
                .robots
                .iter()
                .enumerate()
                .filter(|(index, robot)| driven.borrow().drives(*index, &robot.name))
                .map(|(index, _)| index)
                .collect();
            crate::programs::Programs::find(&mut compiled, &checked.scene, name, &skip).map_err(
                |reason| LoadError::Refused {
                    name: name.to_owned(),
                    reason,
                },
            )?
        } else {
            crate::programs::Programs::default()
        };
        // Webots controller names, as `regatta run` maps them.
        for (index, robot) in compiled.rig.robots.iter_mut().enumerate() {
            use regatta_runtime::controllers::webots::{
                resolve, resolve_robot, Resolution, Resolved,
            };
            if driven.borrow().drives(index, &robot.name)
                && matches!(resolve(&robot.controller), Resolution::External(_))
            {
                // Waiting for a controller from outside, and it gets one: its own never runs.
                robot.controller = "none".to_owned();
                robot.controller_args.clear();
                continue;
            }
            match resolve_robot(robot, lenient) {
                Ok(Resolved::Same) => {}
                Ok(Resolved::Mapped(note)) => warnings.push_str(&format!("note: {note}\n")),
                Ok(Resolved::Replaced(warning)) => {
                    warnings.push_str(&format!("warning: {warning}\n"))
                }
                Err(reason) => {
                    return Err(LoadError::Refused {
                        name: name.to_owned(),
                        reason,
                    })
                }
            }
        }
        // A world that cannot start is refused now, not once per evaluation.
        Simulation::new(&compiled, None).map_err(|source| LoadError::Start {
            name: name.to_owned(),
            source,
        })?;
        let robots: Vec<usize> = compiled
            .rig
            .robots
            .iter()
            .enumerate()
            .filter(|(_, r)| r.controller == "neural")
            .map(|(i, _)| i)
            .collect();
        let network = robots
            .first()
            .and_then(|&first| match &compiled.rig.robots[first].network {
                Some(Ok(spec)) => Some(WorldNetwork {
                    robots: robots.clone(),
                    topology: spec.topology.clone(),
                    weights: spec.weights.clone(),
                }),
                _ => None,
            });
        let z_up = checked.scene.up_axis == regatta_schema::scene::UpAxis::Z;
        Ok(Experiment {
            name: name.to_owned(),
            text,
            lenient,
            compiled,
            network,
            warnings,
            drawn: Vec::new(),
            reading: Arc::new(Reading {
                base_dir: options.base_dir.clone(),
                options: options.clone(),
                driven,
                z_up,
                programs,
            }),
            plan: None,
            programs: found,
        })
    }

    /// The same world read again with other text (a trial's variation).
    fn reread(&self, text: String) -> Result<Experiment, LoadError> {
        let reading = &self.reading;
        let mut experiment = Experiment::read(
            &self.name,
            text,
            reading.base_dir.clone(),
            &reading.options,
            reading.driven.clone(),
            reading.programs,
        )?;
        experiment.reading = reading.clone();
        Ok(experiment)
    }

    /// This world with `variations` drawn anew for each trial ([`Experiment::for_seed`]).
    /// Each variation is tried once, so one that names no node, a field the nodes do not
    /// have or a value they do not take is refused here, naming the variation.
    pub fn with_variations(mut self, variations: Vec<Variation>) -> Result<Experiment, VaryError> {
        if variations.is_empty() {
            return Ok(self);
        }
        let plan = Plan::new(
            variations,
            &self.text,
            &self.compiled,
            self.reading.z_up,
            &mut |text| self.reread(text.to_owned()).map_err(refusal),
        )?;
        self.plan = Some(Arc::new(plan));
        Ok(self)
    }

    /// Whether trials draw variations.
    pub fn varies(&self) -> bool {
        self.plan.is_some()
    }

    /// The world of the trial under `seed` when something varies (`None` otherwise: the
    /// trial is this world): its text with the values drawn from `seed`
    /// ([`Experiment::drawn`] lists them).
    pub fn for_seed(&self, seed: u64) -> Result<Option<Experiment>, EvalError> {
        let Some(plan) = &self.plan else {
            return Ok(None);
        };
        let (_, mut experiment, drawn) = plan
            .draw(
                seed,
                &mut |text| self.reread(text.to_owned()).map_err(refusal),
                |e: &Experiment| &e.compiled,
            )
            .map_err(|source| EvalError::Vary {
                world: self.name.clone(),
                source,
            })?;
        experiment.drawn = drawn;
        Ok(Some(experiment))
    }

    /// How many weights a candidate has: the world's network's parameter count.
    pub fn parameter_count(&self) -> Option<usize> {
        self.network.as_ref().map(|n| n.topology.parameter_count())
    }

    /// Steps covering `duration` seconds (a partial step counts as one).
    pub fn steps_for(&self, duration: f64) -> u64 {
        (duration / self.compiled.settings.time_step)
            .ceil()
            .max(0.0) as u64
    }

    /// A simulation of the world under `seed`, its network robots given `weights` (the
    /// world's own when `None`).
    pub fn simulation(
        &self,
        seed: u64,
        weights: Option<&[f64]>,
    ) -> Result<Simulation<'_>, EvalError> {
        let mut simulation =
            Simulation::new(&self.compiled, Some(seed)).map_err(|source| EvalError::Start {
                world: self.name.clone(),
                source,
            })?;
        sense_for_fitness(&mut simulation);
        if let Some(weights) = weights {
            let network = self.network.as_ref().ok_or_else(|| EvalError::NoNetwork {
                world: self.name.clone(),
            })?;
            let shared: Arc<[f64]> = weights.into();
            for &robot in &network.robots {
                let controller =
                    Neural::new(network.topology.clone(), shared.clone()).map_err(|source| {
                        EvalError::Network {
                            world: self.name.clone(),
                            source,
                        }
                    })?;
                simulation.set_controller(robot, Box::new(controller));
            }
        }
        Ok(simulation)
    }

    /// One evaluation: `steps` steps under `seed`, summarised with `fitness`.
    pub fn evaluate(
        &self,
        seed: u64,
        steps: u64,
        weights: Option<&[f64]>,
        fitness: &Fitness,
    ) -> Result<RunSummary, EvalError> {
        let mut simulation = self.simulation(seed, weights)?;
        let mut observer = Observer::new(&simulation, fitness);
        let failed = |message: String| EvalError::Controller {
            world: self.name.clone(),
            message,
        };
        let mut programs = if self.programs.is_empty() {
            None
        } else {
            Some(self.programs.start(&mut simulation).map_err(failed)?)
        };
        for _ in 0..steps {
            match &mut programs {
                Some(programs) => {
                    simulation.sense();
                    programs
                        .exchange(&mut simulation)
                        .map_err(|e| failed(e.to_string()))?;
                    simulation.act();
                    observer.after_step(&simulation);
                    if programs.quit_requested().is_some() {
                        break;
                    }
                }
                None => {
                    simulation.step();
                    observer.after_step(&simulation);
                }
            }
        }
        if let Some(programs) = programs {
            programs.finish(&simulation);
        }
        if let Some(error) = &simulation.vision_error {
            return Err(EvalError::Vision {
                world: self.name.clone(),
                step: simulation.steps,
                message: error.to_string(),
            });
        }
        let mut summary = observer.summary(&simulation, &self.name, None);
        summary.variations = self.drawn.clone();
        Ok(summary)
    }
}

/// "1 error", "2 errors".
fn errors_phrase(errors: usize) -> String {
    if errors == 1 {
        "1 error".to_owned()
    } else {
        format!("{errors} errors")
    }
}

/// Why a varied world was refused, in a line: its first error (the edited text's lines are
/// the variation's, not the user's, so the error's message says more than its place).
fn refusal(error: LoadError) -> String {
    match error {
        LoadError::Check {
            errors, located, ..
        } => match located.first() {
            Some(first) if errors > 1 => format!("{} ({errors} errors)", first.message),
            Some(first) => first.message.clone(),
            None => errors_phrase(errors),
        },
        other => other.to_string(),
    }
}

/// Makes `simulation` refresh what the fitness functions read (the IR sensors) whether or
/// not a controller reads it. Each sensor draws from its own noise stream, so this changes
/// nothing else in the run.
pub fn sense_for_fitness(simulation: &mut Simulation) {
    simulation.always_sensed = simulation
        .always_sensed
        .union(regatta_runtime::khepera::Senses {
            proximity: true,
            ..regatta_runtime::khepera::Senses::NONE
        });
}

/// A thread pool of `threads` threads (0: one per core).
pub fn thread_pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap_or_else(|_| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("a one-thread pool")
        })
}

/// Evaluates every candidate (each row of `weights`; the world's own weights when `None`)
/// under every seed, in parallel on `pool`. Rows come back candidate by candidate, seeds in
/// the order given, whatever the number of threads; `done` is called after each evaluation.
pub fn evaluate(
    experiment: &Experiment,
    weights: Option<&[Vec<f64>]>,
    seeds: &[u64],
    fitness: &Fitness,
    steps: u64,
    pool: &rayon::ThreadPool,
    done: &(dyn Fn() + Sync),
) -> Result<Vec<RunSummary>, EvalError> {
    let candidates: Vec<Option<&[f64]>> = match weights {
        Some(rows) => rows.iter().map(|r| Some(r.as_slice())).collect(),
        None => vec![None],
    };
    let jobs: Vec<(usize, usize)> = (0..candidates.len())
        .flat_map(|c| (0..seeds.len()).map(move |s| (c, s)))
        .collect();
    // A varied trial's world depends on its seed only: drawn once per seed and shared by
    // every candidate when there are several (evolution), drawn in the job otherwise (a
    // batch, where holding every seed's world at once would cost memory for nothing).
    let per_seed = if experiment.varies() && candidates.len() > 1 {
        Some(pool.install(|| {
            seeds
                .par_iter()
                .map(|&seed| experiment.for_seed(seed))
                .collect::<Result<Vec<Option<Experiment>>, _>>()
        })?)
    } else {
        None
    };
    pool.install(|| {
        jobs.par_iter()
            .map(|&(candidate, index)| {
                let seed = seeds[index];
                let here;
                let world: &Experiment = match &per_seed {
                    Some(worlds) => worlds[index].as_ref().unwrap_or(experiment),
                    None => {
                        here = experiment.for_seed(seed)?;
                        here.as_ref().unwrap_or(experiment)
                    }
                };
                let mut summary = world.evaluate(seed, steps, candidates[candidate], fitness)?;
                if weights.is_some() {
                    summary.candidate = Some(candidate);
                }
                done();
                Ok(summary)
            })
            .collect()
    })
}

/// Watches a live run step by step: fitness meters and distances per robot, and what a
/// summary reports.
pub struct Observer {
    fitness: Fitness,
    records: LiveRecords,
    meters: Vec<Meters>,
    distance: Vec<f64>,
    last: Vec<DVec2>,
    /// Each robot's reward in the last step: its contribution to the chosen fitness.
    rewards: Vec<f64>,
}

impl Observer {
    pub fn new(simulation: &Simulation, fitness: &Fitness) -> Observer {
        let landmarks = &simulation.compiled.landmarks;
        Observer {
            fitness: *fitness,
            records: LiveRecords::new(simulation),
            meters: simulation
                .robots
                .iter()
                .map(|_| Meters::new(fitness, landmarks))
                .collect(),
            distance: vec![0.0; simulation.robots.len()],
            rewards: vec![0.0; simulation.robots.len()],
            last: simulation
                .robots
                .iter()
                .map(|r| DVec2::new(r.pose.x, r.pose.z))
                .collect(),
        }
    }

    /// Takes in the step just done.
    pub fn after_step(&mut self, simulation: &Simulation) {
        let (meters, distance, last) = (&mut self.meters, &mut self.distance, &mut self.last);
        let (rewards, fitness) = (&mut self.rewards, &self.fitness);
        self.records.after_step(simulation, |robot, record| {
            rewards[robot] = meters[robot].add_rewarded(record, fitness);
            let here = DVec2::new(record.pose.x, record.pose.z);
            distance[robot] += (here - last[robot]).length();
            last[robot] = here;
        });
    }

    /// Every fitness's terms so far for `robot` (file order), as the summary gives them.
    pub fn terms(&self, robot: usize) -> crate::fitness::FitnessTerms {
        self.meters[robot].terms()
    }

    /// Each robot's reward in the last step (the chosen fitness's step contribution, see
    /// [`crate::fitness::Meters::add_rewarded`]), robots in file order.
    pub fn rewards(&self) -> &[f64] {
        &self.rewards
    }

    /// The run so far as data; `wall_s` only where timing belongs (a single `run`).
    pub fn summary(&self, simulation: &Simulation, world: &str, wall_s: Option<f64>) -> RunSummary {
        let compiled = simulation.compiled;
        let names = simulation.obstacle_names();
        let robots: Vec<RobotSummary> = simulation
            .robots
            .iter()
            .enumerate()
            .map(|(index, robot)| {
                let terms = self.meters[index].terms();
                let contacts = &robot.contacts;
                RobotSummary {
                    name: robot.name.clone(),
                    controller: compiled.rig.robots[index]
                        .program
                        .clone()
                        .unwrap_or_else(|| compiled.rig.robots[index].controller.clone()),
                    final_pose: PoseSummary {
                        x: robot.pose.x,
                        z: robot.pose.z,
                        heading_deg: robot.pose.heading.to_degrees(),
                    },
                    distance_m: self.distance[index],
                    mean_speed_m_s: if simulation.time > 0.0 {
                        self.distance[index] / simulation.time
                    } else {
                        0.0
                    },
                    contacts: ContactSummary {
                        events: contacts.events,
                        steps: contacts.steps,
                        time_s: contacts.steps as f64 * simulation.time_step,
                        longest_s: contacts.longest,
                        with: contacts
                            .per_obstacle
                            .iter()
                            .map(|&(obstacle, n)| ObstacleContacts {
                                obstacle: names[obstacle as usize].clone(),
                                contacts: n,
                            })
                            .collect(),
                    },
                    visits: self.meters[index]
                        .regatta
                        .visits()
                        .iter()
                        .map(|&(buoy, t, cyclic)| VisitSummary {
                            buoy: buoy + 1,
                            name: compiled.landmarks[buoy].name.clone(),
                            t,
                            cyclic,
                        })
                        .collect(),
                    controller_errors: robot.controller_errors,
                    last_controller_error: robot.last_controller_error.clone(),
                    fitness: terms,
                }
            })
            .collect();
        let value = if robots.is_empty() {
            0.0
        } else {
            robots
                .iter()
                .map(|r| r.fitness.value(&self.fitness))
                .sum::<f64>()
                / robots.len() as f64
        };
        RunSummary {
            world: world.to_owned(),
            seed: simulation.seed,
            version: env!("CARGO_PKG_VERSION").to_owned(),
            candidate: None,
            steps: simulation.steps,
            time_step_s: simulation.time_step,
            simulated_s: simulation.time,
            wall_s,
            fitness: FitnessValue {
                name: self.fitness.name().to_owned(),
                value,
            },
            variations: Vec::new(),
            robots,
        }
    }
}

/// One run as data: what `regatta run --json` prints and `regatta batch` writes per row
/// (`docs/run.schema.json` documents it). Keys come in this order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    pub world: String,
    pub seed: u64,
    /// regatta's version.
    pub version: String,
    /// The candidate's row in an evaluation of many weights.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub candidate: Option<usize>,
    pub steps: u64,
    pub time_step_s: f64,
    pub simulated_s: f64,
    /// Wall-clock time of a single run (never in batch rows, which depend on nothing else).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_s: Option<f64>,
    /// The chosen fitness: the mean of the robots' values.
    pub fitness: FitnessValue,
    /// The values this trial's variations drew (absent when nothing varies).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub variations: Vec<Drawn>,
    pub robots: Vec<RobotSummary>,
}

/// A fitness's name and value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitnessValue {
    pub name: String,
    pub value: f64,
}

/// One robot's run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotSummary {
    pub name: String,
    pub controller: String,
    pub final_pose: PoseSummary,
    /// Path length of the robot's centre (m).
    pub distance_m: f64,
    pub mean_speed_m_s: f64,
    pub contacts: ContactSummary,
    /// Entries into the buoys' visit discs, in order.
    pub visits: Vec<VisitSummary>,
    pub controller_errors: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub last_controller_error: Option<String>,
    /// Every named fitness with its terms.
    pub fitness: FitnessTerms,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseSummary {
    pub x: f64,
    pub z: f64,
    pub heading_deg: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContactSummary {
    /// Contacts begun.
    pub events: u64,
    /// Steps that ended in contact.
    pub steps: u64,
    /// Time in contact (s).
    pub time_s: f64,
    /// Longest unbroken contact (s).
    pub longest_s: f64,
    /// What was touched, with the contacts begun with each.
    pub with: Vec<ObstacleContacts>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObstacleContacts {
    pub obstacle: String,
    pub contacts: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VisitSummary {
    /// Numbered from 1, in file order.
    pub buoy: usize,
    pub name: String,
    /// Simulated time (s).
    pub t: f64,
    /// Whether the visit continued the cyclic order around the buoys.
    pub cyclic: bool,
}

impl RunSummary {
    /// The CSV header of [`RunSummary::csv_row`] for these robots.
    pub fn csv_header(&self) -> String {
        let mut columns = vec![
            "world".to_owned(),
            "seed".to_owned(),
            "candidate".to_owned(),
            "steps".to_owned(),
            "simulated_s".to_owned(),
            "fitness".to_owned(),
        ];
        for robot in &self.robots {
            for column in [
                "distance_m",
                "mean_speed_m_s",
                "contacts",
                "contact_s",
                "visits",
                "cyclic_visits",
                "avoidance",
                "regatta",
                "phototaxis",
            ] {
                columns.push(format!("{}.{column}", robot.name));
            }
        }
        // Every trial of a world draws the same keys, so the first row's name the columns.
        for drawn in &self.variations {
            columns.push(format!("vary:{}", drawn.key()));
        }
        columns.join(",")
    }

    /// One CSV row: the run's fitness and each robot's main figures.
    pub fn csv_row(&self) -> String {
        let quote = |s: &str| {
            if s.contains([',', '"', '\n']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_owned()
            }
        };
        let mut cells = vec![
            quote(&self.world),
            self.seed.to_string(),
            self.candidate.map(|c| c.to_string()).unwrap_or_default(),
            self.steps.to_string(),
            format!("{:?}", self.simulated_s),
            format!("{:?}", self.fitness.value),
        ];
        for robot in &self.robots {
            let f = &robot.fitness;
            cells.extend([
                format!("{:?}", robot.distance_m),
                format!("{:?}", robot.mean_speed_m_s),
                robot.contacts.events.to_string(),
                format!("{:?}", robot.contacts.time_s),
                robot.visits.len().to_string(),
                f.regatta.cyclic_visits.to_string(),
                format!("{:?}", f.avoidance.value),
                format!("{:?}", f.regatta.value),
                format!("{:?}", f.phototaxis.value),
            ]);
        }
        cells.extend(self.variations.iter().map(|d| quote(&d.value)));
        cells.join(",")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A robot waiting for an external controller (Webots' `"<extern>"`) is what a world
    /// driven from outside asks for; nobody driving it is a refusal, as in `regatta run`.
    #[test]
    fn an_extern_robot_is_accepted_only_when_driven() {
        let world = "#VRML_SIM R2023b utf8\nRectangleArena { }\nE-puck { name \"puck\" controller \"<extern>\" }\nE-puck { name \"other\" translation 0.2 0 0 controller \"<extern>\" }\n";
        let load = |driven| Experiment::from_text_driven("w.wbt", world, None, false, &[], driven);
        let refused = load(Driven::Nobody).unwrap_err().to_string();
        assert!(refused.contains("\"<extern>\""), "{refused}");
        let refused = load(Driven::First).unwrap_err().to_string();
        assert!(refused.contains("robot 'other'"), "{refused}");
        let named = ["other".to_owned(), "puck".to_owned()];
        for driven in [Driven::Every, Driven::Named(&named)] {
            let experiment = load(driven).expect("driven from outside");
            for robot in &experiment.compiled.rig.robots {
                assert_eq!(robot.controller, "none");
            }
            assert!(!experiment.warnings.contains("braitenberg"));
        }
        // Lenient and not driven: the replacement `regatta run --lenient` makes.
        let lenient = Experiment::from_text_driven("w.wbt", world, None, true, &[], Driven::First)
            .expect("lenient");
        assert_eq!(lenient.compiled.rig.robots[0].controller, "none");
        assert_eq!(lenient.compiled.rig.robots[1].controller, "braitenberg");
    }
}
