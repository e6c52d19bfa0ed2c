//! Fast shading: VRML97 radiance regrouped for faces whose shading depends on their normal
//! alone (directional lights without shadows, no specular term), and the table of each
//! primitive's fast shading, shared by the primitives with the same one.

use glam::DVec3;

use super::super::WorldLight;
use crate::compile::graph::{LightKind, Material, RenderGraph};
use crate::retina::luminance;

/// Most directional lights the fast shading path handles.
pub(super) const MAX_FAST_LIGHTS: usize = 8;

/// VRML97 radiance when it depends on the normal alone: `base + Σ cᵢ·max(0, n·lᵢ)`, with the
/// emissive and ambient terms in `base` (the same model as [`shade`], regrouped).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct FastShade {
    pub(super) base: [f64; 3],
    pub(super) lights: [([f64; 3], DVec3); MAX_FAST_LIGHTS],
    pub(super) count: usize,
    /// Luminance of `base` and of each light's coefficient.
    pub(super) base_luminance: f64,
    pub(super) light_luminance: [f64; MAX_FAST_LIGHTS],
    /// Luminance of a face looking up, and down.
    pub(super) up_luminance: f64,
    pub(super) down_luminance: f64,
}

impl FastShade {
    pub(super) fn new(material: &Material, lights: &[WorldLight]) -> FastShade {
        let mut fast = FastShade {
            base: material.emissive,
            lights: [([0.0; 3], DVec3::ZERO); MAX_FAST_LIGHTS],
            count: 0,
            base_luminance: 0.0,
            light_luminance: [0.0; MAX_FAST_LIGHTS],
            up_luminance: 0.0,
            down_luminance: 0.0,
        };
        if material.unlit {
            fast.base_luminance = luminance(fast.base);
            fast.up_luminance = fast.base_luminance;
            fast.down_luminance = fast.base_luminance;
            return fast;
        }
        for light in lights {
            let LightKind::Directional { direction } = light.kind else {
                continue;
            };
            let mut coefficient = [0.0; 3];
            for k in 0..3 {
                fast.base[k] += light.color[k]
                    * light.ambient_intensity
                    * material.diffuse[k]
                    * material.ambient_intensity;
                coefficient[k] = light.color[k] * light.intensity * material.diffuse[k];
            }
            fast.lights[fast.count] = (coefficient, -direction);
            fast.light_luminance[fast.count] = luminance(coefficient);
            fast.count += 1;
        }
        fast.base_luminance = luminance(fast.base);
        fast.up_luminance = fast.luminance(DVec3::Y);
        fast.down_luminance = fast.luminance(DVec3::NEG_Y);
        fast
    }

    /// Luminance of [`FastShade::radiance`] (linear, so it regroups the same way).
    #[inline]
    pub(super) fn luminance(&self, normal: DVec3) -> f64 {
        let mut out = self.base_luminance;
        for ((_, to_light), coefficient) in
            self.lights[..self.count].iter().zip(&self.light_luminance)
        {
            out += coefficient * normal.dot(*to_light).max(0.0);
        }
        out
    }

    #[inline]
    pub(super) fn radiance(&self, normal: DVec3) -> [f64; 3] {
        let mut out = self.base;
        for (coefficient, to_light) in &self.lights[..self.count] {
            let n_dot_l = normal.dot(*to_light).max(0.0);
            for k in 0..3 {
                out[k] += coefficient[k] * n_dot_l;
            }
        }
        out
    }
}

/// The fast shading of each primitive, where it applies: an index into a table of the
/// distinct ones (a thousand robots share a handful of materials).
#[derive(Clone, Debug, Default)]
pub(super) struct Shades {
    /// Per primitive, its entry in `table`, or `NO_SHADE`.
    index: Vec<u32>,
    table: Vec<FastShade>,
}

const NO_SHADE: u32 = u32::MAX;

impl Shades {
    /// Fills the table for `primitives` (others read `None`).
    pub(super) fn fill(
        &mut self,
        graph: &RenderGraph,
        primitives: impl Iterator<Item = usize>,
        lights: &[WorldLight],
    ) {
        self.index.clear();
        self.index.resize(graph.primitives.len(), NO_SHADE);
        self.table.clear();
        let point_independent = lights
            .iter()
            .all(|l| matches!(l.kind, LightKind::Directional { .. }) && !l.shadows)
            && lights.len() <= MAX_FAST_LIGHTS;
        if !point_independent {
            return;
        }
        for primitive in primitives {
            let material = &graph.materials[graph.primitives[primitive].material];
            if material.specular.iter().any(|&c| c != 0.0) {
                continue;
            }
            let fast = FastShade::new(material, lights);
            // The same values give the same shading: shared (a bounded search, so that a
            // world of distinct materials stays linear).
            let found = self.table.iter().rev().take(64).position(|t| *t == fast);
            self.index[primitive] = match found {
                Some(back) => (self.table.len() - 1 - back) as u32,
                None => {
                    self.table.push(fast);
                    (self.table.len() - 1) as u32
                }
            };
        }
    }

    #[inline]
    pub(super) fn get(&self, primitive: u32) -> Option<&FastShade> {
        match self.index.get(primitive as usize) {
            Some(&i) if i != NO_SHADE => Some(&self.table[i as usize]),
            _ => None,
        }
    }
}
