//! The runtime loop: fixed steps of `WorldInfo.basicTimeStep`. In each step, sensors that are
//! due update (each at its own period), controllers read them and set wheel speeds, then
//! kinematics and collisions run. All randomness comes from the run's seed, one stream per
//! robot and per sensor; robots are visited in file order; nothing depends on wall time.
//!
//! [`Simulation`] and its step loop are in `step.rs`; a step's phases each have their file:
//! `sense.rs` (one robot's sensing), `drive.rs` (one robot's controller and wheel speeds),
//! `contacts.rs` (motion, collisions and contacts),
//! `visits.rs` (buoy visits and falls). `state.rs` holds what is kept of each robot,
//! `robot.rs` the simulated robot behind the Khepera API.

mod broad_phase;
mod contacts;
mod drive;
pub mod kinematics;
pub mod noise;
mod robot;
mod sense;
pub mod sensors;
mod state;
mod step;
mod visits;
pub mod world2d;

pub use contacts::{MAX_SUB_STEPS, PENETRATION_TOLERANCE};
pub use robot::SimulatedKhepera;
pub use state::{
    CameraState, Contacts, Fall, LinearCameraState, PanoramicState, PhaseTimes, RawReadings,
    RobotState, Updated, Visits,
};
pub use step::{SimError, Simulation};
