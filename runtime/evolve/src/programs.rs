//! A batch's robots that run their project's controllers (Webots controllers, through
//! `regatta-webots`): found and compiled once when the world is read, started anew for each
//! trial, in lock-step with its simulation. A leaf: `experiment.rs` calls it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use regatta_runtime::compile::Compiled;
use regatta_runtime::sim::Simulation;
use regatta_schema::Scene;
use regatta_webots::python::Launch;
use regatta_webots::{Controllers, Options, Planned, Program};

/// The programs of a world's robots, compiled.
#[derive(Clone, Debug, Default)]
pub struct Programs {
    robots: Vec<(Planned, Launch)>,
    /// The typed scene, kept when a robot is a supervisor.
    scene: Option<Arc<Scene>>,
    world: PathBuf,
    project: PathBuf,
}

impl Programs {
    /// Finds the robots of `compiled` whose controller is a C or Python program of the world's project
    /// (not those in `skip`), readies `compiled` for them and makes each runnable; `Err` names what
    /// stands in the way (a compiler error, no Python).
    pub fn find(
        compiled: &mut Compiled,
        scene: &Scene,
        world: &str,
        skip: &[usize],
    ) -> Result<Programs, String> {
        let world = PathBuf::from(world);
        let project = regatta_webots::project_of(&world);
        let planned =
            regatta_webots::plan(compiled, scene, &project, skip).map_err(|e| e.to_string())?;
        if planned.is_empty() {
            return Ok(Programs::default());
        }
        let cache = regatta_webots::compile::cache_dir();
        let mut robots = Vec::new();
        for item in planned {
            if let Program::Extern { .. } = item.program {
                return Err(format!(
                    "robot '{}' has an <extern> controller, which a batch cannot start (run the world with `regatta run` and start the controller by hand)",
                    compiled.rig.robots[item.robot].name
                ));
            }
            let (launch, _) = regatta_webots::runnable(&item.program, &cache)
                .map_err(|e| format!("robot '{}': {e}", compiled.rig.robots[item.robot].name))?;
            robots.push((item, launch));
        }
        let planned: Vec<Planned> = robots.iter().map(|(p, _)| p.clone()).collect();
        regatta_webots::prepare(compiled, &planned);
        let scene = planned
            .iter()
            .any(|p| p.supervisor)
            .then(|| Arc::new(scene.clone()));
        Ok(Programs {
            robots,
            scene,
            world,
            project,
        })
    }

    pub fn is_empty(&self) -> bool {
        self.robots.is_empty()
    }

    /// The controller processes of one trial, started and connected to `simulation`; their
    /// output is not shown (a batch runs many).
    pub fn start<'c>(&self, simulation: &mut Simulation<'c>) -> Result<Controllers<'c>, String> {
        let starts = self
            .robots
            .iter()
            .map(|(item, launch)| item.start_with(launch))
            .collect();
        let options = Options {
            echo: false,
            ..Options::default()
        };
        Controllers::start(
            simulation,
            starts,
            self.scene.as_deref().cloned(),
            &self.world,
            &self.project,
            &options,
        )
        .map_err(|e| e.to_string())
    }
}

/// Whether `name` is a controller folder of the project of the world `world`.
pub fn is_program(world: &str, name: &str) -> bool {
    regatta_webots::is_program(&regatta_webots::project_of(Path::new(world)), name)
}
