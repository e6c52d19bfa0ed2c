//! The column renderer: exact, analytic rendering of a thin elevation band for scenes whose
//! visible primitives are upright (vertical cylinders, yaw-rotated boxes) — the shape of a
//! robot arena.
//!
//! Along one azimuth, each upright object covers an interval of tan-elevation computed
//! exactly from its entry and exit distances (its side, and its top or bottom cap when the eye
//! is above or below it). Intervals are composited front to back and measured in angle, so a
//! column's band is integrated exactly. Across a photodiode's azimuth window, the window is
//! split at every silhouette edge; between edges the set of objects is constant and the
//! integrand smooth, so `samples` midpoints per piece converge fast.
//!
//! Numerical notes: angles within the band use an odd polynomial for atan (|t| ≤ tan 5.5°
//! ≈ 0.096 gives an error below 1e-10), sub-column directions use angle addition from
//! precomputed directions, the crowd level of detail places impostors, kept boxes and round
//! silhouettes by a polynomial `atan2` (within 2e-8 rad), and everything else goes through
//! `libm` where a transcendental is needed: results do not depend on the platform's math
//! library.
//!
//! `scene.rs` holds the scene and a step's frame, `sweep.rs` what one eye sees of it
//! (`angular.rs` the sweep that hands each region its facing objects),
//! `integrate/` the strip integrated (`regions.rs`: region by region), `photodiode.rs` a column's segments
//! and the band over each photodiode window, `footprint.rs` the placed upright objects,
//! `shading.rs` the fast shading, `crowd.rs` which other robots an eye draws (`compact.rs` builds
//! such lists without a branch per candidate), `impostor.rs`
//! which far small static objects stand in as impostors, `far.rs` how they are drawn and
//! `kept.rs` how an eye keeps them from one update to the next,
//! `strip.rs` the pixels to integrate.

mod angular;
mod compact;
mod crowd;
mod far;
mod footprint;
mod impostor;
mod integrate;
mod kept;
mod photodiode;
mod scene;
mod shading;
mod strip;
mod sweep;

pub use kept::KeptImpostors;
pub use scene::{ColumnFrame, ColumnScene};
pub use strip::Strip;
pub use sweep::{EyeObject, Look};
