//! The CPU renderer: radiance by the VRML97 lighting model (ISO/IEC 14772-1 §4.14), from exact
//! ray casting ([`raycast`]) or, for scenes of upright primitives, from analytic columns
//! ([`column`]). Deterministic, single-threaded per view, no GPU, no window.
//!
//! Radiance: `emissive + Σ on·attenuation·spot·colour·(ambient + diffuse + specular)` in linear
//! units, per RGB channel; attenuation `1/max(a0 + a1·d + a2·d², 1)`; lights beyond their
//! radius give nothing; shadows only for lights with `castShadows TRUE`.

pub mod column;
pub mod raster;
pub mod raycast;
pub mod texels;

use glam::DVec3;

use crate::compile::graph::{LightKind, Material, Owner, RenderGraph};
use crate::compile::plan::Plan;
use crate::compile::rig::{Attenuation, Pose2};
use crate::geometry::Frame;

/// How finely exact optics integrate a strip: the world file's dial between cost and error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detail {
    /// Evaluations per piece of a window between silhouette edges (columns), or rays per axis
    /// of a window (ray casting).
    pub samples: usize,
    /// Pixels between evaluated columns in edge-free runs (1: every pixel); columns only.
    pub stride: usize,
    /// Other robots whose centre is farther than this from the eye (m) are left out: the
    /// crowd level of detail. Infinite: every robot (the reference). Columns only.
    pub crowd_distance: f64,
    /// With a crowd distance: small static objects (buoys, their lamps) wholly farther than
    /// this from the eye (m) are left out instead of drawn as impostors. Infinite: none are.
    pub far_distance: f64,
}

impl Detail {
    /// `samples` and `stride`, every robot drawn.
    pub fn new(samples: usize, stride: usize) -> Detail {
        Detail {
            samples,
            stride,
            crowd_distance: f64::INFINITY,
            far_distance: f64::INFINITY,
        }
    }
}

/// Where every robot is now: what moves robot-attached primitives and lights.
#[derive(Clone, Debug, Default)]
pub struct Poses {
    pub poses: Vec<Pose2>,
    pub floor_y: Vec<f64>,
}

impl Poses {
    /// The robot's frame in the world.
    pub fn frame(&self, robot: usize) -> Frame {
        self.poses[robot].frame(self.floor_y[robot])
    }
}

/// A light resolved to world space for one frame.
#[derive(Clone, Debug)]
pub struct WorldLight {
    pub(crate) kind: LightKind,
    pub(crate) color: [f64; 3],
    pub(crate) intensity: f64,
    pub(crate) ambient_intensity: f64,
    pub(crate) shadows: bool,
}

/// The lights of the plan, with robot-carried ones moved to the robots' current poses.
pub fn world_lights(graph: &RenderGraph, plan: &Plan, poses: &Poses) -> Vec<WorldLight> {
    plan.lights
        .iter()
        .map(|&index| {
            let light = &graph.lights[index];
            let kind = match (light.owner, &light.kind) {
                (Owner::Robot(robot), kind) if robot < poses.poses.len() => {
                    let frame = poses.frame(robot);
                    match kind.clone() {
                        LightKind::Directional { direction } => LightKind::Directional {
                            direction: frame.apply_vector(direction),
                        },
                        LightKind::Point {
                            location,
                            radius,
                            attenuation,
                        } => LightKind::Point {
                            location: frame.apply(location),
                            radius,
                            attenuation,
                        },
                        LightKind::Spot {
                            location,
                            direction,
                            radius,
                            attenuation,
                            beam_width,
                            cut_off,
                        } => LightKind::Spot {
                            location: frame.apply(location),
                            direction: frame.apply_vector(direction),
                            radius,
                            attenuation,
                            beam_width,
                            cut_off,
                        },
                    }
                }
                (_, kind) => kind.clone(),
            };
            WorldLight {
                kind,
                color: light.color,
                intensity: light.intensity,
                ambient_intensity: light.ambient_intensity,
                shadows: light.shadows,
            }
        })
        .collect()
}

/// VRML97 radiance of a surface point seen from `eye`. `occluded(point, light_position or
/// direction)` answers shadow queries for lights that ask for them.
pub(crate) fn shade(
    material: &Material,
    color_override: Option<[f64; 3]>,
    point: DVec3,
    normal: DVec3,
    eye: DVec3,
    lights: &[WorldLight],
    occluded: &mut dyn FnMut(DVec3, &LightKind) -> bool,
) -> [f64; 3] {
    let diffuse = color_override.unwrap_or(material.diffuse);
    if material.unlit {
        return color_override.unwrap_or(material.emissive);
    }
    let mut out = material.emissive;
    let view = (eye - point).normalize_or_zero();
    // A surface seen from behind is lit as its front (two-sided lighting, as viewers do).
    let normal = if normal.dot(view) < 0.0 {
        -normal
    } else {
        normal
    };
    for light in lights {
        let Some((to_light, reach)) = light_at(&light.kind, point) else {
            continue;
        };
        if reach == 0.0 {
            continue;
        }
        let n_dot_l = normal.dot(to_light).max(0.0);
        let mut specular_factor = 0.0;
        if n_dot_l > 0.0 && material.specular.iter().any(|&c| c > 0.0) {
            let half = (to_light + view).normalize_or_zero();
            specular_factor = libm::pow(normal.dot(half).max(0.0), material.shininess * 128.0);
        }
        let lit = n_dot_l > 0.0 && !(light.shadows && occluded(point, &light.kind));
        let scale = reach;
        for k in 0..3 {
            let ambient = light.ambient_intensity * diffuse[k] * material.ambient_intensity;
            let direct = if lit {
                light.intensity * (diffuse[k] * n_dot_l + material.specular[k] * specular_factor)
            } else {
                0.0
            };
            out[k] += scale * light.color[k] * (ambient + direct);
        }
    }
    out
}

/// How a light reaches `point`: the unit direction towards the light, and attenuation × spot
/// factor (VRML97: `1/max(a0 + a1·d + a2·d², 1)`, full inside the beam width, linear to zero
/// at the cut-off angle). `None` beyond the light's radius.
pub(crate) fn light_at(kind: &LightKind, point: DVec3) -> Option<(DVec3, f64)> {
    light_at_with(kind, point, Attenuation::Vrml97)
}

/// [`light_at`] with the attenuation's bound chosen.
pub(crate) fn light_at_with(
    kind: &LightKind,
    point: DVec3,
    bound: Attenuation,
) -> Option<(DVec3, f64)> {
    match kind {
        LightKind::Directional { direction } => Some((-*direction, 1.0)),
        LightKind::Point {
            location,
            radius,
            attenuation,
        } => {
            let offset = *location - point;
            let distance = offset.length();
            (distance <= *radius).then(|| {
                (
                    offset / distance.max(1e-300),
                    attenuate(*attenuation, distance, bound),
                )
            })
        }
        LightKind::Spot {
            location,
            direction,
            radius,
            attenuation,
            beam_width,
            cut_off,
        } => {
            let offset = *location - point;
            let distance = offset.length();
            if distance > *radius {
                return None;
            }
            let to_light = offset / distance.max(1e-300);
            let angle = libm::acos((-to_light).dot(*direction).clamp(-1.0, 1.0));
            let spot = if angle >= *cut_off {
                0.0
            } else if angle <= *beam_width {
                1.0
            } else {
                (angle - cut_off) / (beam_width - cut_off)
            };
            Some((to_light, attenuate(*attenuation, distance, bound) * spot))
        }
    }
}

fn attenuate(coefficients: DVec3, distance: f64, bound: Attenuation) -> f64 {
    let divisor = coefficients.x + coefficients.y * distance + coefficients.z * distance * distance;
    1.0 / match bound {
        Attenuation::Vrml97 => divisor.max(1.0),
        Attenuation::Unbounded => divisor.max(f64::MIN_POSITIVE),
    }
}
