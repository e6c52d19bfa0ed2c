//! 2-D colour cameras (Webots' `Camera`, the e-puck's 52×39): a planar projection from the
//! camera's field of view, rasterised (`render/raster`, the default) or one ray per pixel
//! through the ray caster (the reference), VRML97 shading, then 8-bit RGB with the camera's
//! Gaussian noise.
//!
//! Webots' model, as its Camera documentation gives it: `fieldOfView` is horizontal, pixels are
//! square (so the vertical field follows from width and height), `near` clips what is too
//! close, `far` (0: none) what is too far, and `noise` is the standard deviation of the
//! Gaussian noise added to each channel, as a fraction of full scale. The image is linear
//! (no gamma), row 0 at the top.

use glam::DVec3;

use crate::compile::plan::Plan;
use crate::compile::rig::{CameraRig, Pose2};
use crate::render::raster::{Rasterizer, Target, View};
use crate::render::raycast::{Prepared, RayCaster};
use crate::render::Poses;
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
    /// Per pixel, the length of its unnormalised direction `(1, up, right)` in the robot's
    /// frame: world distance per unit of the camera's depth (the rasteriser's near/far test).
    lengths: Vec<f64>,
    /// The smallest of `lengths` (at most 1) and the largest (at least 1).
    shortest: f64,
    longest: f64,
    target: Target,
}

impl Camera {
    pub fn new(rig: &CameraRig) -> Camera {
        let pixels: Vec<DVec3> = rig
            .pixel_directions()
            .map(|d| rig.frame.linear * d)
            .collect();
        let lengths: Vec<f64> = pixels.iter().map(|d| d.length()).collect();
        let (shortest, longest) = crate::render::raster::length_range(&lengths);
        Camera {
            rig: rig.clone(),
            directions: pixels.iter().map(|d| d.normalize_or(DVec3::X)).collect(),
            shortest,
            longest,
            lengths,
            target: Target::default(),
        }
    }

    /// Renders robot `viewer`'s camera by rasterisation (see [`Camera::update`] for the
    /// rest): the same pixels, noise drawn in the same order.
    #[allow(clippy::too_many_arguments)]
    pub fn update_raster(
        &mut self,
        raster: &Rasterizer,
        plan: &Plan,
        poses: &Poses,
        viewer: usize,
        noise: &mut Stream,
        out: &mut CameraImage,
    ) {
        let Some(robot_frame) = poses.poses.get(viewer).map(|_| poses.frame(viewer)) else {
            let (width, height) = (self.rig.width, self.rig.height);
            (out.width, out.height) = (width, height);
            out.rgb.clear();
            return;
        };
        let to_world = robot_frame.then(&self.rig.frame);
        self.draw(raster, plan, poses, Some(viewer), to_world, noise, out);
    }

    /// Renders by rasterisation a camera whose rig frame is in world coordinates (a world's
    /// Viewpoint, as `regatta render --viewpoint` draws it), with every robot seen.
    pub fn update_raster_world(
        &mut self,
        raster: &Rasterizer,
        plan: &Plan,
        poses: &Poses,
        noise: &mut Stream,
        out: &mut CameraImage,
    ) {
        let to_world = self.rig.frame;
        self.draw(raster, plan, poses, None, to_world, noise, out);
    }

    #[allow(clippy::too_many_arguments)]
    fn draw(
        &mut self,
        raster: &Rasterizer,
        plan: &Plan,
        poses: &Poses,
        viewer: Option<usize>,
        to_world: crate::geometry::Frame,
        noise: &mut Stream,
        out: &mut CameraImage,
    ) {
        let (width, height) = (self.rig.width, self.rig.height);
        out.width = width;
        out.height = height;
        out.rgb.clear();
        let to_camera = to_world.inverse().unwrap_or(crate::geometry::Frame {
            linear: glam::DMat3::ZERO,
            translation: DVec3::ZERO,
        });
        let tan_h = libm::tan(self.rig.field_of_view / 2.0);
        let view = View {
            to_camera,
            to_world,
            width,
            height,
            tan_h,
            tan_v: self.rig.tan_half_vertical(),
            near: self.rig.near.max(0.0),
            far: self.rig.far.max(0.0),
            lengths: &self.lengths,
            shortest: self.shortest,
            longest: self.longest,
        };
        let quantise = self.rig.noise <= 0.0;
        raster.draw(plan, poses, viewer, &view, quantise, &mut self.target);
        if quantise {
            std::mem::swap(&mut out.rgb, &mut self.target.bytes);
            return;
        }
        out.rgb.reserve(width * height * 3);
        for pixel in &self.target.linear {
            for &channel in pixel {
                out.rgb
                    .push(to_byte(channel as f64 + self.rig.noise * noise.gaussian()));
            }
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
