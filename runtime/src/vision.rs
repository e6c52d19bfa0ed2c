//! The seam between the simulation and a batched vision backend: one that renders the vision
//! devices of many robots, in many independent worlds, in one call (the wgpu backend of
//! `runtime/gpu`). It owns only the request and answer types and the trait; the CPU renderer
//! needs none of it, because the simulation calls it robot by robot.
//!
//! A backend answers photocurrents (luminance) only: 150 values per Panoramic turret and one
//! per K213 pixel. Normalisation, the filtering network and conversion stay on the CPU
//! ([`crate::optics::Panoramic::accept`]), so every backend shares them bit for bit.

use crate::render::Poses;

/// One independent world of a batch: which compiled scene it is (an index into the scenes the
/// backend was built for) and where its robots are.
#[derive(Clone, Copy, Debug)]
pub struct WorldInstance<'a> {
    pub scene: usize,
    pub poses: &'a Poses,
}

/// One vision device to render: the turret of `robot` in world instance `instance`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VisionRequest {
    pub instance: usize,
    pub robot: usize,
}

/// Why a backend could not render.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisionError {
    #[error("request {index}: {why}")]
    BadRequest { index: usize, why: String },
    #[error("the GPU failed: {0}")]
    Device(String),
}

/// A renderer of many vision devices at once.
pub trait VisionBackend: Send {
    /// What it runs on, for summaries (e.g. `wgpu: llvmpipe (Vulkan)`).
    fn describe(&self) -> String;

    /// Photocurrents of every requested device, in request order: `out[i]` is resized to the
    /// device's pixel count.
    fn render(
        &mut self,
        instances: &[WorldInstance],
        requests: &[VisionRequest],
        out: &mut Vec<Vec<f64>>,
    ) -> Result<(), VisionError>;
}
