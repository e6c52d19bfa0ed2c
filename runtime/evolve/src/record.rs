//! The per-step record every fitness is computed from, produced alike by a live run and by a
//! log read back, so that a fitness has one value whichever way it is measured.
//!
//! A record holds what the log's channels hold for one robot and one step: the time at the
//! step's end, the pose, the wheel commands, the IR readings if they were refreshed, whether
//! the robot ended the step touching something, and the buoys it entered.

use regatta_runtime::compile::rig::Pose2;
use regatta_runtime::log::{decode_pose, CdrReader, LogContents, ShortMessage};
use regatta_runtime::sim::Simulation;

/// One robot's step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord<'a> {
    /// Simulated time at the end of the step (s).
    pub t: f64,
    /// The step's length (s).
    pub time_step: f64,
    pub pose: Pose2,
    /// Wheel commands (pulses per 10 ms).
    pub command: (i32, i32),
    /// The IR readings, when the step refreshed them.
    pub proximity: Option<[u16; 8]>,
    /// Whether the step ended in contact.
    pub touching: bool,
    /// Landmarks entered during the step (indices, in order).
    pub entered: &'a [usize],
}

/// Turns a live simulation's steps into records, one robot at a time.
#[derive(Clone, Debug, Default)]
pub struct LiveRecords {
    /// Per robot: visits already handed out.
    visits_seen: Vec<usize>,
}

impl LiveRecords {
    pub fn new(simulation: &Simulation) -> LiveRecords {
        LiveRecords {
            visits_seen: vec![0; simulation.robots.len()],
        }
    }

    /// Calls `each(robot, record)` for every robot after a step.
    pub fn after_step(
        &mut self,
        simulation: &Simulation,
        mut each: impl FnMut(usize, &StepRecord),
    ) {
        for (index, robot) in simulation.robots.iter().enumerate() {
            let seen = self.visits_seen[index];
            let record = StepRecord {
                t: simulation.time,
                time_step: simulation.time_step,
                pose: robot.pose,
                command: robot.command,
                proximity: robot.updated.proximity.then_some(robot.proximity),
                touching: robot.contacts.is_touching(),
                entered: &robot.visits.sequence[seen..],
            };
            each(index, &record);
            self.visits_seen[index] = robot.visits.sequence.len();
        }
    }
}

/// Why a log's records cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordError {
    #[error("a {0} message is damaged: {1}")]
    Damaged(String, ShortMessage),
    #[error("the log's time step is missing or not a number")]
    TimeStep,
}

/// One robot's records read from a log, owning their visit lists.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotSteps {
    pub name: String,
    steps: Vec<OwnedStep>,
}

#[derive(Clone, Debug, Default, PartialEq)]
struct OwnedStep {
    t: f64,
    pose: Option<Pose2>,
    command: (i32, i32),
    proximity: Option<[u16; 8]>,
    /// The contact state a message set at this step, if one did.
    touching: Option<bool>,
    entered: Vec<usize>,
}

impl RobotSteps {
    /// Calls `each` with every complete step's record, in order.
    pub fn for_each(&self, time_step: f64, mut each: impl FnMut(&StepRecord)) {
        let mut touching = false;
        for step in &self.steps {
            touching = step.touching.unwrap_or(touching);
            let Some(pose) = step.pose else {
                continue;
            };
            each(&StepRecord {
                t: step.t,
                time_step,
                pose,
                command: step.command,
                proximity: step.proximity,
                touching,
                entered: &step.entered,
            });
        }
    }
}

/// Every robot's records from a log (robots in the order the log names them), and the time
/// step.
pub fn records_from_log(log: &LogContents) -> Result<(f64, Vec<RobotSteps>), RecordError> {
    let time_step = log.time_step.ok_or(RecordError::TimeStep)?;
    let mut robots: Vec<RobotSteps> = Vec::new();
    // Messages carry their step's end time (pose, wheels, contacts, visits) or its start
    // (sensors, read before the controllers ran): both give the step's number.
    let step_of = |t: f64| (t / time_step).round().max(0.0) as usize;
    for (topic, _, data) in &log.messages {
        let trimmed = topic.trim_start_matches('/');
        let Some((name, kind)) = trimmed.rsplit_once('/') else {
            continue;
        };
        if !matches!(
            kind,
            "pose" | "wheels" | "proximity" | "contacts" | "visits"
        ) {
            continue;
        }
        let robot = match robots.iter().position(|r| r.name == name) {
            Some(index) => index,
            None => {
                robots.push(RobotSteps {
                    name: name.to_owned(),
                    steps: Vec::new(),
                });
                robots.len() - 1
            }
        };
        let damaged = |e| RecordError::Damaged(topic.clone(), e);
        let mut r = CdrReader::new(data);
        let t = r.f64().map_err(damaged)?;
        let index = match kind {
            "proximity" => step_of(t) + 1,
            "visits" => step_of(t).max(1),
            _ => step_of(t),
        };
        let steps = &mut robots[robot].steps;
        if steps.len() <= index {
            steps.resize_with(index + 1, OwnedStep::default);
        }
        let step = &mut steps[index];
        match kind {
            "pose" => {
                let (t, pose) = decode_pose(data).map_err(damaged)?;
                step.t = t;
                step.pose = Some(pose);
            }
            "wheels" => step.command = (r.i32().map_err(damaged)?, r.i32().map_err(damaged)?),
            "proximity" => {
                let values = r.u16s(Some(8)).map_err(damaged)?;
                let mut readings = [0u16; 8];
                readings.copy_from_slice(&values);
                step.proximity = Some(readings);
            }
            "contacts" => step.touching = Some(r.bool().map_err(damaged)?),
            _ => {
                let buoy = r.u32().map_err(damaged)?;
                step.entered.push(buoy.saturating_sub(1) as usize);
            }
        }
    }
    Ok((time_step, robots))
}
