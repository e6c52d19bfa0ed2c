//! The plan: what a scene needs computed, and what it can skip, with the reason for each skip.
//!
//! - No rendering at all when no robot carries a vision device.
//! - Only the enabled filters (the rig carries them; the plan reports them).
//! - No light that reaches nothing: switched off, zero intensity, or out of range of every
//!   visible primitive and every light sensor.
//! - No geometry no vision device can ever see. Robots are assumed to stay within the
//!   horizontal bounds of the static geometry and their start positions (the `region`): from
//!   there a vision device at height h with half band β sees heights within
//!   `h ± D·tan β`, D being the largest horizontal distance from the region to the primitive.
//!   A robot's own parts are tested from its own turret, where they are fixed.

use glam::{DVec2, DVec3};

use super::graph::{LightKind, Owner, RenderGraph};
use super::rig::{SensorRig, TurretRig};
use crate::geometry::Aabb;
use crate::retina::HALF_BAND;

/// Something the plan leaves out, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    pub what: String,
    pub why: String,
}

/// Which renderer computes the vision devices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RendererChoice {
    /// Nothing to render.
    None,
    /// Every visible primitive is upright and no light casts shadows: the analytic column
    /// renderer.
    Columns,
    /// Otherwise: ray casting (exact intersections, BVH, shadow rays).
    Rays,
}

/// What the compiled scene needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub renderer: RendererChoice,
    /// Primitives some vision device may see, in graph order.
    pub visible: Vec<usize>,
    /// For each robot, its own attached primitives its own turret may see.
    pub own_visible: Vec<Vec<usize>>,
    /// Lights that reach something, in graph order.
    pub lights: Vec<usize>,
    /// The horizontal region robots are assumed to stay in.
    pub region: Aabb,
    pub skipped: Vec<Skipped>,
}

impl Plan {
    pub fn new(graph: &RenderGraph, rig: &SensorRig) -> Plan {
        let mut skipped = Vec::new();
        let mut region = graph.static_bounds();
        for robot in &rig.robots {
            let r = robot.body_radius;
            region = region.union(Aabb {
                min: DVec3::new(robot.start.x - r, robot.floor_y, robot.start.z - r),
                max: DVec3::new(
                    robot.start.x + r,
                    robot.floor_y + robot.body_height,
                    robot.start.z + r,
                ),
            });
        }
        // Vision devices: (height above the floor of the robot's start, tan of half band).
        let eyes: Vec<(f64, f64)> = rig
            .robots
            .iter()
            .filter_map(|r| match &r.turret {
                Some(TurretRig::Panoramic(p)) => Some((r.floor_y + p.height, libm::tan(HALF_BAND))),
                Some(TurretRig::Linear(c)) => Some((
                    r.floor_y + c.height,
                    libm::tan(c.vertical_field_of_view / 2.0),
                )),
                None => None,
            })
            .chain(rig.robots.iter().flat_map(|r| {
                r.cameras
                    .iter()
                    .map(|c| (r.floor_y + c.frame.translation.y, c.tan_half_band()))
            }))
            .collect();
        let mut visible = Vec::new();
        let mut own_visible = vec![Vec::new(); rig.robots.len()];
        if eyes.is_empty() {
            if !graph.primitives.is_empty() {
                skipped.push(Skipped {
                    what: format!("rendering of all {} primitives", graph.primitives.len()),
                    why: "no robot carries a vision device".to_owned(),
                });
            }
        } else {
            let mut culled = 0usize;
            for (index, primitive) in graph.primitives.iter().enumerate() {
                match primitive.owner {
                    Owner::Static => {
                        let reach = horizontal_reach(&region, &primitive.bounds);
                        if eyes.iter().any(|&(h, t)| {
                            overlaps(
                                primitive.bounds.min.y,
                                primitive.bounds.max.y,
                                h - reach * t,
                                h + reach * t,
                            )
                        }) {
                            visible.push(index);
                        } else {
                            culled += 1;
                        }
                    }
                    Owner::Robot(robot) => {
                        // Seen by other robots from anywhere in the region…
                        let floor = rig.robots[robot].floor_y;
                        let extent = region.max - region.min;
                        let part = primitive.bounds.min.abs().max(primitive.bounds.max.abs());
                        let diagonal = DVec2::new(extent.x, extent.z).length()
                            + DVec2::new(part.x, part.z).length();
                        let seen_by_others = rig.robots.len() > 1
                            && eyes.iter().any(|&(h, t)| {
                                overlaps(
                                    floor + primitive.bounds.min.y,
                                    floor + primitive.bounds.max.y,
                                    h - diagonal * t,
                                    h + diagonal * t,
                                )
                            });
                        // …and by its own turret from a fixed place.
                        let seen_by_self = own_turret_sees(rig, robot, &primitive.bounds)
                            || rig.robots[robot]
                                .cameras
                                .iter()
                                .any(|c| own_camera_sees(c, &primitive.bounds));
                        if seen_by_self {
                            own_visible[robot].push(index);
                        }
                        if seen_by_others {
                            visible.push(index);
                        } else if !seen_by_self {
                            culled += 1;
                        }
                    }
                }
            }
            if culled > 0 {
                skipped.push(Skipped {
                    what: format!("{culled} of {} primitives", graph.primitives.len()),
                    why: "outside every vision device's elevation band from anywhere in the region"
                        .to_owned(),
                });
            }
        }
        let renderer = if eyes.is_empty() {
            RendererChoice::None
        } else if visible
            .iter()
            .chain(own_visible.iter().flatten())
            .all(|&p| graph.primitives[p].upright)
        {
            RendererChoice::Columns
        } else {
            RendererChoice::Rays
        };
        let has_light_sensors = rig.robots.iter().any(|r| !r.light_sensors.is_empty());
        let mut lights = Vec::new();
        for (index, light) in graph.lights.iter().enumerate() {
            let name = format!("light {index} ({})", light_name(&light.kind));
            let why = if !light.on {
                Some("it is switched off".to_owned())
            } else if light.intensity == 0.0 && light.ambient_intensity == 0.0 {
                Some("its intensity and ambient intensity are 0".to_owned())
            } else if eyes.is_empty() && !has_light_sensors {
                Some("nothing renders and no robot has a light sensor".to_owned())
            } else {
                match &light.kind {
                    LightKind::Point {
                        location, radius, ..
                    }
                    | LightKind::Spot {
                        location, radius, ..
                    } if light.owner == Owner::Static => {
                        let reaches_geometry = visible.iter().any(|&p| {
                            distance_to_box(*location, &graph.primitives[p].bounds) <= *radius
                        });
                        let reaches_sensor =
                            has_light_sensors && distance_to_box(*location, &region) <= *radius;
                        (!reaches_geometry && !reaches_sensor).then(|| {
                            format!("nothing it could light is within its radius {radius} m")
                        })
                    }
                    _ => None,
                }
            };
            match why {
                Some(why) => skipped.push(Skipped { what: name, why }),
                None => lights.push(index),
            }
        }
        // The column renderer casts no shadows: a light that asks for them needs rays.
        let renderer = if renderer == RendererChoice::Columns
            && lights.iter().any(|&l| graph.lights[l].shadows)
        {
            RendererChoice::Rays
        } else {
            renderer
        };
        Plan {
            renderer,
            visible,
            own_visible,
            lights,
            region,
            skipped,
        }
    }
}

fn light_name(kind: &LightKind) -> &'static str {
    match kind {
        LightKind::Directional { .. } => "DirectionalLight",
        LightKind::Point { .. } => "PointLight",
        LightKind::Spot { .. } => "SpotLight",
    }
}

fn overlaps(a0: f64, a1: f64, b0: f64, b1: f64) -> bool {
    a0 <= b1 && b0 <= a1
}

/// Largest horizontal distance between a point of `region` and a point of `bounds`.
fn horizontal_reach(region: &Aabb, bounds: &Aabb) -> f64 {
    let mut best = 0.0f64;
    for rx in [region.min.x, region.max.x] {
        for rz in [region.min.z, region.max.z] {
            for bx in [bounds.min.x, bounds.max.x] {
                for bz in [bounds.min.z, bounds.max.z] {
                    best = best.max(DVec2::new(rx - bx, rz - bz).length());
                }
            }
        }
    }
    best
}

fn distance_to_box(p: DVec3, b: &Aabb) -> f64 {
    (p.max(b.min).min(b.max) - p).length()
}

/// Whether a robot's own turret can see one of its own parts (robot-frame bounds): the part
/// spans tan-elevations between `(y − h)/d` over its corners' horizontal distances d.
/// Whether a 2-D camera can see a part of its own robot (bounds in the robot's frame): the
/// part is in front of the camera, inside its frustum, and does not enclose it (the housing
/// a camera sits in, or the body it is set into, would hide everything).
fn own_camera_sees(camera: &crate::compile::rig::CameraRig, bounds: &Aabb) -> bool {
    let eye = camera.frame.translation;
    let margin = 1e-9;
    let encloses = (bounds.min.x - margin..=bounds.max.x + margin).contains(&eye.x)
        && (bounds.min.y - margin..=bounds.max.y + margin).contains(&eye.y)
        && (bounds.min.z - margin..=bounds.max.z + margin).contains(&eye.z);
    if encloses {
        return false;
    }
    // The four side planes of the frustum, as inward normals in the robot's frame: a box with
    // every corner outside one plane is outside the frustum.
    let tan_h = libm::tan(camera.field_of_view / 2.0);
    let tan_v = camera.tan_half_vertical();
    let normals = [
        DVec3::new(tan_h, 0.0, 1.0),
        DVec3::new(tan_h, 0.0, -1.0),
        DVec3::new(tan_v, -1.0, 0.0),
        DVec3::new(tan_v, 1.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
    ]
    .map(|n| camera.frame.linear * n);
    let corners = (0..8).map(|i| {
        DVec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        ) - eye
    });
    let corners: Vec<DVec3> = corners.collect();
    normals
        .iter()
        .all(|n| corners.iter().any(|c| n.dot(*c) >= 0.0))
}

fn own_turret_sees(rig: &SensorRig, robot: usize, bounds: &Aabb) -> bool {
    let (height, tan_half) = match &rig.robots[robot].turret {
        Some(TurretRig::Panoramic(p)) => (p.height, libm::tan(HALF_BAND)),
        Some(TurretRig::Linear(c)) => (c.height, libm::tan(c.vertical_field_of_view / 2.0)),
        None => return false,
    };
    let far = [
        bounds.min.x.abs().max(bounds.max.x.abs()),
        bounds.min.z.abs().max(bounds.max.z.abs()),
    ];
    let d_max = DVec2::new(far[0], far[1]).length();
    if d_max == 0.0 {
        return false;
    }
    // Highest and lowest tan-elevation any point of the part can have.
    let top = bounds.max.y - height;
    let bottom = bounds.min.y - height;
    let highest = if top >= 0.0 {
        f64::INFINITY
    } else {
        top / d_max
    };
    let lowest = if bottom <= 0.0 {
        f64::NEG_INFINITY
    } else {
        bottom / d_max
    };
    highest >= -tan_half && lowest <= tan_half
}
