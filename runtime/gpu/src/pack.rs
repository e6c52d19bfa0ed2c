//! Packs compiled worlds into the GPU's storage layout (`retina.wgsl`): primitives, materials,
//! lights and scenes of every world, mesh triangles, and the sampling tables of paper optics.
//! Pure CPU work, so that it is tested without a device.
//!
//! Positions are stored relative to each scene's origin (the centre of its plan's region),
//! computed in f64 before the cast to f32: a world 1 km from (0, 0, 0) renders as precisely
//! as one at the origin.

use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use regatta_runtime::compile::graph::{LightKind, Owner, Shape};
use regatta_runtime::compile::rig::{Optics, TurretRig};
use regatta_runtime::optics::{flat_samples, warp_coordinates, FLAT_COLUMNS, FLAT_ROWS};
use regatta_runtime::Compiled;

const KIND_BOX: u32 = 0;
const KIND_CYLINDER: u32 = 1;
const KIND_CONE: u32 = 2;
const KIND_SPHERE: u32 = 3;
const KIND_MESH: u32 = 4;
const FLAG_SIDE: u32 = 1;
const FLAG_BOTTOM: u32 = 2;
const FLAG_TOP: u32 = 4;
const FLAG_VISIBLE: u32 = 8;
const FLAG_OWN_VISIBLE: u32 = 16;
const STATIC_OWNER: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct GpuPrim {
    inverse: [[f32; 4]; 3],
    params: [f32; 4],
    bounds_min: [f32; 4],
    bounds_max: [f32; 4],
    info: [u32; 4],
    mesh: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct GpuMaterial {
    diffuse: [f32; 4],
    specular: [f32; 4],
    emissive: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct GpuLight {
    color: [f32; 4],
    location: [f32; 4],
    direction: [f32; 4],
    attenuation: [f32; 4],
    spot: [f32; 4],
    info: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct GpuScene {
    ranges: [u32; 4],
    sky: [f32; 4],
    ground: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(crate) struct GpuView {
    pub a: [u32; 4],
    pub b: [u32; 4],
    pub c: [u32; 4],
    pub eye: [f32; 4],
    pub geo: [f32; 4],
}

/// What one robot's vision device needs per update.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Device {
    /// A Panoramic turret: two flat views with `samples`² supersampling.
    Panoramic {
        height: f64,
        samples: u32,
        quantize: bool,
        /// Offsets of its sub-column and sub-row tables in `tables`.
        columns: u32,
        rows: u32,
    },
    /// A K213: one strip of `pixels` windows, `samples`² rays each.
    Linear {
        height: f64,
        pixels: u32,
        samples: u32,
        field_of_view: f64,
        vertical_field_of_view: f64,
    },
}

/// One packed world.
#[derive(Clone, Debug)]
pub(crate) struct SceneInfo {
    pub origin: DVec3,
    /// Per robot: its floor height and its vision device, if any.
    pub robots: Vec<(f64, Option<Device>)>,
    /// Turrets whose world asked for exact optics (rendered here in paper mode).
    pub exact_turrets: Vec<String>,
}

/// Every buffer the scenes need, ready to upload.
#[derive(Default)]
pub(crate) struct Packed {
    pub prims: Vec<GpuPrim>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    pub scenes: Vec<GpuScene>,
    pub triangles: Vec<[f32; 4]>,
    pub tables: Vec<f32>,
    /// Offset of the warp table (2 views × 75 columns × 7 rows × (u, w)) in `tables`.
    pub warp_table: u32,
    pub infos: Vec<SceneInfo>,
}

fn flag(on: bool, bit: u32) -> u32 {
    if on {
        bit
    } else {
        0
    }
}

fn f4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

fn rgb4(c: [f64; 3], w: f64) -> [f32; 4] {
    [c[0] as f32, c[1] as f32, c[2] as f32, w as f32]
}

/// Packs `worlds` (scene indices follow their order).
pub(crate) fn pack(worlds: &[&Compiled]) -> Packed {
    let mut packed = Packed::default();
    // One table pair per distinct supersampling, shared by every turret that uses it.
    let mut flat_tables: Vec<(u32, u32, u32)> = Vec::new();
    for compiled in worlds {
        let graph = &compiled.graph;
        let plan = &compiled.plan;
        let region = plan.region;
        let origin = if region.is_empty() {
            DVec3::ZERO
        } else {
            region.center()
        };
        let material_base = packed.materials.len() as u32;
        for m in &graph.materials {
            packed.materials.push(GpuMaterial {
                diffuse: rgb4(m.diffuse, m.ambient_intensity),
                specular: rgb4(m.specular, m.shininess),
                emissive: rgb4(m.emissive, if m.unlit { 1.0 } else { 0.0 }),
            });
        }
        let mut mesh_ranges = Vec::with_capacity(graph.meshes.len());
        for mesh in &graph.meshes {
            let first = (packed.triangles.len() / 4) as u32;
            for (t, triangle) in mesh.triangles.iter().enumerate() {
                for &corner in triangle {
                    packed
                        .triangles
                        .push(f4(mesh.positions[corner as usize], 0.0));
                }
                packed
                    .triangles
                    .push(match mesh.triangle_colors.as_ref().and_then(|c| c.get(t)) {
                        Some(&color) => rgb4(color, 1.0),
                        None => [0.0; 4],
                    });
            }
            mesh_ranges.push([first, mesh.triangles.len() as u32]);
        }
        let mut visible = vec![false; graph.primitives.len()];
        for &p in &plan.visible {
            visible[p] = true;
        }
        let mut own_visible = vec![false; graph.primitives.len()];
        for list in &plan.own_visible {
            for &p in list {
                own_visible[p] = true;
            }
        }
        let prim_first = packed.prims.len() as u32;
        for (index, primitive) in graph.primitives.iter().enumerate() {
            if !visible[index] && !own_visible[index] {
                continue;
            }
            // Static parts are placed relative to the scene origin; robot parts stay in
            // their robot's frame.
            let (owner, shift) = match primitive.owner {
                Owner::Static => (STATIC_OWNER, origin),
                Owner::Robot(r) => (r as u32, DVec3::ZERO),
            };
            let inverse = &primitive.inverse;
            let translation = inverse.linear * shift + inverse.translation;
            let rows = [0, 1, 2].map(|i| f4(inverse.linear.row(i), translation[i]));
            let mut flags = 0;
            if visible[index] {
                flags |= FLAG_VISIBLE;
            }
            if own_visible[index] {
                flags |= FLAG_OWN_VISIBLE;
            }
            let mut mesh = [0; 4];
            let (kind, params) = match &primitive.shape {
                Shape::Box { half } => (KIND_BOX, f4(*half, 0.0)),
                Shape::Cylinder {
                    radius,
                    height,
                    side,
                    bottom,
                    top,
                } => {
                    flags |=
                        flag(*side, FLAG_SIDE) | flag(*bottom, FLAG_BOTTOM) | flag(*top, FLAG_TOP);
                    (KIND_CYLINDER, [*radius as f32, *height as f32, 0.0, 0.0])
                }
                Shape::Cone {
                    radius,
                    height,
                    side,
                    bottom,
                } => {
                    flags |= flag(*side, FLAG_SIDE) | flag(*bottom, FLAG_BOTTOM);
                    (KIND_CONE, [*radius as f32, *height as f32, 0.0, 0.0])
                }
                Shape::Sphere { radius } => (KIND_SPHERE, [*radius as f32, 0.0, 0.0, 0.0]),
                Shape::Mesh(m) => {
                    mesh[..2].copy_from_slice(&mesh_ranges[*m]);
                    (KIND_MESH, [0.0; 4])
                }
            };
            // Bounds grow by a hair so that f32 rounding never culls a grazing hit.
            let pad = DVec3::splat(1e-6 * (1.0 + primitive.bounds.max.abs().max_element()));
            packed.prims.push(GpuPrim {
                inverse: rows,
                params,
                bounds_min: f4(primitive.bounds.min - shift - pad, 0.0),
                bounds_max: f4(primitive.bounds.max - shift + pad, 0.0),
                info: [
                    kind,
                    flags,
                    material_base + primitive.material as u32,
                    owner,
                ],
                mesh,
            });
        }
        let light_first = packed.lights.len() as u32;
        for &l in &plan.lights {
            let light = &graph.lights[l];
            let (owner, shift) = match light.owner {
                Owner::Static => (STATIC_OWNER, origin),
                Owner::Robot(r) => (r as u32, DVec3::ZERO),
            };
            let mut record = GpuLight {
                color: rgb4(light.color, light.intensity),
                location: [0.0; 4],
                direction: [0.0, 0.0, 0.0, light.ambient_intensity as f32],
                attenuation: [0.0; 4],
                spot: [0.0; 4],
                info: [0, owner, light.shadows as u32, 0],
            };
            match &light.kind {
                LightKind::Directional { direction } => {
                    record.direction = f4(*direction, light.ambient_intensity);
                }
                LightKind::Point {
                    location,
                    radius,
                    attenuation,
                } => {
                    record.info[0] = 1;
                    record.location = f4(*location - shift, radius.min(f32::MAX as f64));
                    record.attenuation = f4(*attenuation, 0.0);
                }
                LightKind::Spot {
                    location,
                    direction,
                    radius,
                    attenuation,
                    beam_width,
                    cut_off,
                } => {
                    record.info[0] = 2;
                    record.location = f4(*location - shift, radius.min(f32::MAX as f64));
                    record.direction = f4(*direction, light.ambient_intensity);
                    record.attenuation = f4(*attenuation, *beam_width);
                    record.spot = [*cut_off as f32, 0.0, 0.0, 0.0];
                }
            }
            packed.lights.push(record);
        }
        let background = &graph.background;
        packed.scenes.push(GpuScene {
            ranges: [
                prim_first,
                packed.prims.len() as u32 - prim_first,
                light_first,
                packed.lights.len() as u32 - light_first,
            ],
            sky: rgb4(background.sky, 0.0),
            ground: match background.ground {
                Some(ground) => rgb4(ground, 1.0),
                None => [0.0; 4],
            },
        });
        let mut exact_turrets = Vec::new();
        let robots = compiled
            .rig
            .robots
            .iter()
            .map(|robot| {
                let device = match &robot.turret {
                    Some(TurretRig::Panoramic(p)) => {
                        if p.optics == Optics::Exact {
                            exact_turrets.push(format!("{}/{}", robot.name, p.name));
                        }
                        let samples = p.samples.max(1) as u32;
                        let (columns, rows) = match flat_tables.iter().find(|t| t.0 == samples) {
                            Some(&(_, c, r)) => (c, r),
                            None => {
                                let (sub_columns, sub_rows) = flat_samples(samples as usize);
                                let c = packed.tables.len() as u32;
                                for (offset, slant) in sub_columns {
                                    packed.tables.push(offset as f32);
                                    packed.tables.push((1.0 / slant) as f32);
                                }
                                let r = packed.tables.len() as u32;
                                packed.tables.extend(sub_rows.iter().map(|&y| y as f32));
                                flat_tables.push((samples, c, r));
                                (c, r)
                            }
                        };
                        Some(Device::Panoramic {
                            height: p.height,
                            samples,
                            quantize: p.quantize_views,
                            columns,
                            rows,
                        })
                    }
                    Some(TurretRig::Linear(c)) => Some(Device::Linear {
                        height: c.height,
                        pixels: c.pixels as u32,
                        samples: c.samples.max(1) as u32,
                        field_of_view: c.field_of_view,
                        vertical_field_of_view: c.vertical_field_of_view,
                    }),
                    None => None,
                };
                (robot.floor_y, device)
            })
            .collect();
        packed.infos.push(SceneInfo {
            origin,
            robots,
            exact_turrets,
        });
    }
    packed.warp_table = packed.tables.len() as u32;
    for v in 0..2 {
        for j in 0..FLAT_COLUMNS {
            for k in 0..FLAT_ROWS {
                let (u, w) = warp_coordinates(v, j, k);
                packed.tables.push(u as f32);
                packed.tables.push(w as f32);
            }
        }
    }
    // Storage bindings may not be empty.
    if packed.prims.is_empty() {
        packed.prims.push(GpuPrim::zeroed());
    }
    if packed.materials.is_empty() {
        packed.materials.push(GpuMaterial::zeroed());
    }
    if packed.lights.is_empty() {
        packed.lights.push(GpuLight::zeroed());
    }
    if packed.triangles.is_empty() {
        packed.triangles.push([0.0; 4]);
    }
    packed
}
