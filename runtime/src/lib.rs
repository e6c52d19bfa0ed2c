//! The runtime: compiles a typed scene into a render graph, a sensor rig and a plan, renders
//! what vision devices see on the CPU, and simulates the EDI retina stage by stage.
//!
//! Data flow: [`compile::compile`] → [`optics::Renderer`] (analytic columns or ray casting) →
//! [`optics::Panoramic`] / [`optics::LinearCamera`] → [`retina`] stages. Geometric queries live
//! apart in [`geometry`]. Batched backends (wgpu) plug in through [`vision`].

// Channel loops (`for k in 0..3`) read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod broad;
pub mod camera;
pub mod check;
pub mod compile;
pub mod controllers;
pub mod geometry;
pub mod khepera;
pub mod log;
pub mod optics;
pub mod render;
pub mod retina;
pub mod sim;
pub mod tessellate;
#[cfg(test)]
mod test_random;
pub mod texcoord;
pub mod vision;
mod wide;

pub use compile::{compile, compile_for_run, Compiled};
