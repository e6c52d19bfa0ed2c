//! What a step's control does to one robot: its controller run where its control period is
//! due, and the wheel speeds (with their noise) that its commands give. A robot's drive reads
//! and writes only that robot, so robots are driven side by side, or each right after it
//! senses, with the same results.

use super::contacts::wheel_speeds;
use super::robot::SimulatedKhepera;
use super::state::{Bodies, RobotState};
use crate::compile::rig::RobotRig;

/// What driving a robot reads of the simulation, shared by every robot of a step.
pub(super) struct Drive<'a> {
    pub(super) rigs: &'a [RobotRig],
    pub(super) bodies: &'a Bodies,
    /// Steps done before this one.
    pub(super) steps: u64,
    /// The step (s).
    pub(super) dt: f64,
}

impl Drive<'_> {
    /// Runs robot `index`'s controller if due and sets its wheel speeds (m/s) for the step
    /// into `speeds`; returns the collision sub-steps they need.
    #[inline]
    pub(super) fn drive(
        &self,
        index: usize,
        robot: &mut RobotState,
        speeds: &mut (f64, f64),
    ) -> usize {
        let body = self.bodies.get(index);
        // A controller runs at its own period, on the step grid from time 0; its commands
        // hold in between.
        if self.steps.is_multiple_of(body.control_steps) {
            if let Some(mut controller) = robot.controller.take() {
                let mut io = SimulatedKhepera {
                    robot,
                    rig: &self.rigs[index],
                };
                if let Err(error) = controller.step(&mut io) {
                    robot.updated.controller_error = true;
                    robot.controller_errors += 1;
                    robot.last_controller_error = Some(error.to_string());
                }
                robot.controller = Some(controller);
            }
        }
        let (wheels, sub_steps) = wheel_speeds(robot, body, self.steps, self.dt);
        *speeds = wheels;
        sub_steps
    }
}
