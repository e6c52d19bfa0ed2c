//! 2-D colour cameras (Webots' `Camera`, the e-puck's 52×39): a planar projection from the
//! camera's field of view, one ray per pixel through the ray caster, VRML97 shading, then 8-bit
//! RGB with the camera's Gaussian noise.
//!
//! Webots' model, as its Camera documentation gives it: `fieldOfView` is horizontal, pixels are
//! square (so the vertical field follows from width and height), `near` clips what is too
//! close, `far` (0: none) what is too far, and `noise` is the standard deviation of the
//! Gaussian noise added to each channel, as a fraction of full scale. The image is linear
//! (no gamma), row 0 at the top.

use glam::DVec3;

use crate::compile::rig::{CameraRig, Pose2};
use crate::render::raycast::{Prepared, RayCaster};
use crate::sim::noise::Stream;

/// A camera's last image.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraImage {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB, 3 bytes a pixel, the top row first.
    pub rgb: Vec<u8>,
}

/// A camera ready to render: its pixels' directions in its own frame, computed once.
pub struct Camera {
    pub rig: CameraRig,
    directions: Vec<DVec3>,
}

impl Camera {
    pub fn new(rig: &CameraRig) -> Camera {
        let directions = (0..rig.height)
            .flat_map(|row| (0..rig.width).map(move |column| (column, row)))
            .map(|(column, row)| {
                (rig.frame.linear * rig.pixel_direction(column, row)).normalize_or(DVec3::X)
            })
            .collect();
        Camera {
            rig: rig.clone(),
            directions,
        }
    }

    /// Renders the camera of a robot at `pose` (standing on the floor at `floor_y`) into `out`;
    /// `noise` draws the pixels' noise when the camera has any.
    pub fn update(
        &self,
        caster: &RayCaster,
        view: &Prepared,
        pose: Pose2,
        floor_y: f64,
        noise: &mut Stream,
        out: &mut CameraImage,
    ) {
        let placement = pose.placement(floor_y);
        let eye = placement.to_world(self.rig.frame.translation);
        let far = if self.rig.far > 0.0 {
            self.rig.far - self.rig.near
        } else {
            f64::INFINITY
        };
        out.width = self.rig.width;
        out.height = self.rig.height;
        out.rgb.clear();
        out.rgb.reserve(self.directions.len() * 3);
        for &local in &self.directions {
            let direction = placement.direction_to_world(local);
            let origin = eye + direction * self.rig.near;
            let color = caster.rgb_within(view, origin, direction, far);
            for channel in color {
                let mut value = channel;
                if self.rig.noise > 0.0 {
                    value += self.rig.noise * noise.gaussian();
                }
                out.rgb.push(to_byte(value));
            }
        }
    }
}

/// A linear channel value to 0…255, rounded half up, clamped.
fn to_byte(value: f64) -> u8 {
    if value.is_nan() {
        return 0;
    }
    libm::floor(value.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}
