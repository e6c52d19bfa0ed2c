//! The red spots of `laser` distance sensors, as cameras see them.
//!
//! Webots documents that a laser sensor "draws a red spot at the point where this ray hits an
//! obstacle", visible on camera images, its radius (m) the sensor's `aperture`. regatta's
//! renderers know nothing of sensors, so this room finds each enabled laser's spot once a
//! step and paints it over the images it hands to controllers: a pixel shows the spot when
//! its ray meets the spot's disc before (or at) the first surface it sees.

use glam::DVec3;
use regatta_runtime::compile::rig::CameraRig;
use regatta_runtime::geometry::Ray;
use regatta_runtime::render::raycast::Prepared;
use regatta_runtime::sim::Simulation;

use crate::rays::{RaySensor, Rays};

/// The spot's colour in a camera image (R, G, B): the value Webots' cameras record at a
/// laser spot's centre.
pub const SPOT_RGB: [u8; 3] = [0xEF, 0x00, 0x00];

/// How far in front of the surface the spot is drawn, relative to its distance from the eye
/// (Webots offsets its spot by `WorldInfo.lineScale` against depth fighting).
const DEPTH_SLACK: f64 = 1e-6;

/// One laser spot in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub point: DVec3,
    pub normal: DVec3,
    pub radius: f64,
}

/// The spot of `sensor` on robot `robot`, if its ray meets something within `far`.
pub fn spot_of(
    rays: &Rays,
    prepared: &Prepared,
    simulation: &Simulation,
    robot: usize,
    sensor: &RaySensor,
    far: f64,
) -> Option<Spot> {
    let hit = rays.first_hit(prepared, simulation, robot, sensor, far)?;
    Some(Spot {
        point: hit.point,
        normal: hit.normal,
        radius: sensor.aperture.max(0.0),
    })
}

/// Paints the spots a camera of robot `robot` sees over its image (`bgra`, 4 bytes a pixel,
/// the top row first). `prepared` is the world placed for that robot's sensors.
pub fn paint(
    bgra: &mut [u8],
    camera: &CameraRig,
    rays: &Rays,
    prepared: &Prepared,
    simulation: &Simulation,
    robot: usize,
    spots: &[Spot],
) {
    let state = &simulation.robots[robot];
    let floor = simulation.compiled.rig.robots[robot].floor_y;
    let placement = state.pose.placement(floor);
    let eye = placement.to_world(camera.frame.translation);
    let far = if camera.far > 0.0 {
        camera.far
    } else {
        f64::INFINITY
    };
    for (pixel, local) in camera.pixel_directions().enumerate() {
        let direction = placement
            .direction_to_world(camera.frame.linear * local)
            .normalize_or(DVec3::X);
        let mut seen = None;
        for spot in spots {
            let facing = direction.dot(spot.normal);
            if facing.abs() < 1e-12 {
                continue;
            }
            let t = (spot.point - eye).dot(spot.normal) / facing;
            if t < camera.near || t > far || seen.is_some_and(|s| s <= t) {
                continue;
            }
            if (eye + direction * t - spot.point).length() <= spot.radius {
                seen = Some(t);
            }
        }
        let Some(t) = seen else { continue };
        // Hidden when something stands between the eye and the spot.
        let ray = Ray {
            origin: eye,
            direction,
        };
        let blocked = rays
            .trace(prepared, &ray, t)
            .is_some_and(|hit| hit.t < t * (1.0 - DEPTH_SLACK) - 1e-9);
        if blocked {
            continue;
        }
        if let Some(bytes) = bgra.get_mut(pixel * 4..pixel * 4 + 3) {
            bytes.copy_from_slice(&[SPOT_RGB[2], SPOT_RGB[1], SPOT_RGB[0]]);
        }
    }
}
