//! The CPU rasteriser of 2-D cameras: the render graph's primitives tessellated once
//! ([`tessellate`]; static ones in world space, robot-attached ones in their robot's frame and
//! placed per frame), near-plane clipping, a z-buffer, and per-vertex VRML97 lighting by the
//! same `shade` as the ray caster, interpolated perspective-correctly (Gouraud).
//!
//! One thread, primitives in graph order, f64 set-up: the same inputs give the same bytes.
//! Shadows (lights with `castShadows`) are the ray caster's shadow rays, cast at each vertex,
//! and at each pixel of a triangle whose corners disagree (a shadow's edge crosses it).
//! Lighting between vertices is interpolated, not evaluated (exact for flat faces under
//! directional lights). `docs/camera-raster.md` gives the measured agreement.

pub mod tessellate;
mod triangle;

use glam::DVec3;

use super::raycast::{Prepared, RayCaster};
use super::{shade, world_lights, Poses};
use crate::compile::graph::{Owner, RenderGraph};
use crate::compile::plan::Plan;
use crate::geometry::Frame;
use tessellate::{tessellate, TriangleSet};
use triangle::{Corner, Screen};

/// One primitive's triangles: world space for static parts, robot space for attached ones.
struct Part {
    primitive: usize,
    material: usize,
    robot: Option<usize>,
    set: TriangleSet,
    /// Bounding sphere, in the same space as the vertices.
    centre: DVec3,
    radius: f64,
}

/// Per-world data: every visible primitive tessellated once.
pub struct Rasterizer<'g> {
    graph: &'g RenderGraph,
    parts: Vec<Part>,
    visible: Vec<bool>,
    /// Shadow rays, when a light casts shadows: tested at each vertex, and per pixel in the
    /// triangles whose corners disagree.
    shadows: Option<RayCaster<'g>>,
}

/// A camera for one frame: where it is and how it projects.
pub struct View<'a> {
    /// World to camera coordinates (x forward, y up, z right).
    pub to_camera: Frame,
    /// Camera to world.
    pub to_world: Frame,
    pub width: usize,
    pub height: usize,
    /// Tangents of half the horizontal and vertical fields.
    pub tan_h: f64,
    pub tan_v: f64,
    pub near: f64,
    /// 0: no limit.
    pub far: f64,
    /// Per pixel, the world distance per unit of camera depth along its ray.
    pub lengths: &'a [f64],
}

/// Buffers reused from frame to frame.
#[derive(Default)]
pub struct Target {
    depth: Vec<f32>,
    /// Linear colour (when noise is added afterwards) ...
    pub linear: Vec<[f32; 3]>,
    /// ... or bytes, written straight (no noise).
    pub bytes: Vec<u8>,
    camera: Vec<DVec3>,
    world: Vec<(DVec3, DVec3)>,
    shaded: Vec<[f64; 3]>,
    /// Per vertex, which shadow tests it made and their answers (a bit each, in order).
    shadowed: Vec<(u32, u64)>,
    stamp: Vec<u32>,
    generation: u32,
}

impl<'g> Rasterizer<'g> {
    pub fn new(graph: &'g RenderGraph, plan: &Plan) -> Rasterizer<'g> {
        let mut visible = vec![false; graph.primitives.len()];
        for &p in &plan.visible {
            visible[p] = true;
        }
        let mut wanted = visible.clone();
        for own in &plan.own_visible {
            for &p in own {
                if let Some(w) = wanted.get_mut(p) {
                    *w = true;
                }
            }
        }
        let mut parts = Vec::new();
        for (index, primitive) in graph.primitives.iter().enumerate() {
            if !wanted[index] {
                continue;
            }
            let mut set = tessellate(&primitive.shape, &graph.meshes);
            // Both kinds are stored after their primitive's own frame: world space for
            // static parts, the robot's frame for attached ones.
            for v in &mut set.vertices {
                v.position = primitive.frame.apply(v.position);
                v.normal = primitive.frame.apply_normal(&primitive.inverse, v.normal);
            }
            // A vertex that overflowed its frame takes its triangles with it (indices stay).
            let finite: Vec<bool> = set
                .vertices
                .iter()
                .map(|v| v.position.is_finite() && v.normal.is_finite())
                .collect();
            set.triangles.retain(|t| {
                t.iter()
                    .all(|&i| finite.get(i as usize).copied().unwrap_or(false))
            });
            if set.triangles.is_empty() {
                continue;
            }
            let (min, max) = set.vertices.iter().filter(|v| v.position.is_finite()).fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), v| (lo.min(v.position), hi.max(v.position)),
            );
            let centre = (min + max) / 2.0;
            let radius = (max - min).length() / 2.0;
            if !(centre.is_finite() && radius.is_finite()) {
                continue;
            }
            parts.push(Part {
                primitive: index,
                material: primitive.material,
                robot: match primitive.owner {
                    Owner::Robot(robot) => Some(robot),
                    _ => None,
                },
                set,
                centre,
                radius,
            });
        }
        let shadows = plan
            .lights
            .iter()
            .any(|&l| graph.lights[l].shadows)
            .then(|| RayCaster::new(graph, plan));
        Rasterizer {
            graph,
            parts,
            visible,
            shadows,
        }
    }

    /// Draws what `viewer`'s camera sees into `target` (bytes when `quantise`, else linear).
    pub fn draw(
        &self,
        plan: &Plan,
        poses: &Poses,
        viewer: Option<usize>,
        view: &View,
        quantise: bool,
        target: &mut Target,
    ) {
        let pixels = view.width * view.height;
        if pixels == 0 || view.lengths.len() < pixels {
            target.bytes.clear();
            target.linear.clear();
            return;
        }
        let lights = world_lights(self.graph, plan, poses);
        let occluders = self
            .shadows
            .as_ref()
            .map(|caster| (caster, caster.prepare(plan, poses, viewer)));
        target.clear(self, view, quantise, pixels);
        // The nearest depth worth drawing: the near sphere's closest approach to the frustum.
        let longest = view.lengths.iter().fold(1.0f64, |m, &l| m.max(l));
        let near_x = (view.near / longest).max(1e-6);
        let eye = view.to_world.translation;
        let screen = Screen {
            width: view.width,
            height: view.height,
            near_x,
            near: view.near,
            far: view.far,
            tan_h: view.tan_h,
            tan_v: view.tan_v,
            lengths: view.lengths,
        };
        // How much the camera's frame may stretch a bounding sphere.
        let l = view.to_camera.linear;
        let stretch = l
            .x_axis
            .length()
            .max(l.y_axis.length())
            .max(l.z_axis.length());
        let slope_h = (1.0 + view.tan_h * view.tan_h).sqrt();
        let slope_v = (1.0 + view.tan_v * view.tan_v).sqrt();
        for part in &self.parts {
            let placement = match part.robot {
                None => {
                    if !self.visible[part.primitive] {
                        continue;
                    }
                    None
                }
                Some(robot) => {
                    if robot >= poses.poses.len() {
                        continue;
                    }
                    let wanted = if Some(robot) == viewer {
                        plan.own_visible
                            .get(robot)
                            .is_some_and(|v| v.contains(&part.primitive))
                    } else {
                        self.visible[part.primitive]
                    };
                    if !wanted {
                        continue;
                    }
                    Some(poses.frame(robot))
                }
            };
            let centre = match &placement {
                Some(frame) => frame.apply(part.centre),
                None => part.centre,
            };
            let c = view.to_camera.apply(centre);
            let r = part.radius * stretch;
            // Outside the frustum: behind the near plane, beyond far, or beside the view.
            if c.x + r < near_x
                || (view.far > 0.0 && c.x - r > view.far)
                || c.z.abs() - c.x * view.tan_h > r * slope_h
                || c.y.abs() - c.x * view.tan_v > r * slope_v
            {
                continue;
            }
            let frame = Frame3 {
                view,
                screen: &screen,
                eye,
                lights: &lights,
                occluders: occluders.as_ref().map(|(c, p)| (*c, p)),
            };
            self.draw_part(part, placement.as_ref(), &frame, quantise, target);
        }
    }

    fn draw_part(
        &self,
        part: &Part,
        placement: Option<&Frame>,
        frame: &Frame3,
        quantise: bool,
        target: &mut Target,
    ) {
        let (view, screen, eye, lights) = (frame.view, frame.screen, frame.eye, frame.lights);
        let n = part.set.vertices.len();
        target.camera.clear();
        target.world.clear();
        for v in &part.set.vertices {
            let (p, normal) = match placement {
                // Robot frames are rigid: normals turn as vectors.
                Some(frame) => (frame.apply(v.position), frame.apply_vector(v.normal)),
                None => (v.position, v.normal),
            };
            target.world.push((p, normal));
            target.camera.push(view.to_camera.apply(p));
        }
        target.generation = target.generation.wrapping_add(1);
        if target.generation == 0 {
            target.stamp.iter_mut().for_each(|s| *s = u32::MAX);
            target.generation = 1;
        }
        if target.stamp.len() < n {
            target.stamp.resize(n, 0);
            target.shaded.resize(n, [0.0; 3]);
            target.shadowed.resize(n, (0, 0));
        }
        let material = &self.graph.materials[part.material];
        let (tan_h, tan_v) = (view.tan_h, view.tan_v);
        for t in &part.set.triangles {
            let q = t.map(|i| target.camera[i as usize]);
            // Entirely beside one side of the frustum: nothing to shade or draw.
            if q.iter().all(|p| p.x < screen.near_x)
                || q.iter().all(|p| p.z > p.x * tan_h)
                || q.iter().all(|p| -p.z > p.x * tan_h)
                || q.iter().all(|p| p.y > p.x * tan_v)
                || q.iter().all(|p| -p.y > p.x * tan_v)
            {
                continue;
            }
            let mut corners = [Corner::default(); 3];
            for (corner, &i) in corners.iter_mut().zip(t) {
                let i = i as usize;
                if target.stamp[i] != target.generation {
                    target.stamp[i] = target.generation;
                    let (point, normal) = target.world[i];
                    let mut record = (0u32, 0u64);
                    target.shaded[i] = shade(
                        material,
                        part.set.vertices[i].color,
                        point,
                        normal,
                        eye,
                        lights,
                        &mut |point, kind| {
                            let hidden = frame
                                .occluders
                                .is_some_and(|(caster, view)| caster.occluded(view, point, kind));
                            record = (record.0 + 1, (record.1 << 1) | u64::from(hidden));
                            hidden
                        },
                    );
                    target.shadowed[i] = record;
                }
                *corner = Corner {
                    position: target.camera[i],
                    color: target.shaded[i],
                    normal: target.world[i].1,
                };
            }
            let [a, b, c] = t.map(|i| target.shadowed[i as usize]);
            // A shadow's edge crosses the triangle: its pixels are shaded one by one.
            let mixed = frame.occluders.is_some() && (a != b || b != c);
            let color = part.set.vertices[t[0] as usize].color;
            let mut exact = |pixel: usize, depth: f64, normal: DVec3| {
                let (column, row) = (pixel % view.width, pixel / view.width);
                let up = (1.0 - 2.0 * (row as f64 + 0.5) / view.height as f64) * view.tan_v;
                let right = (2.0 * (column as f64 + 0.5) / view.width as f64 - 1.0) * view.tan_h;
                let point = view.to_world.apply(DVec3::new(1.0, up, right) * depth);
                shade(
                    material,
                    color,
                    point,
                    normal,
                    eye,
                    lights,
                    &mut |point, kind| {
                        frame
                            .occluders
                            .is_some_and(|(caster, view)| caster.occluded(view, point, kind))
                    },
                )
            };
            triangle::draw(
                screen,
                corners,
                quantise,
                &mut target.depth,
                &mut target.linear,
                &mut target.bytes,
                if mixed { Some(&mut exact) } else { None },
            );
        }
    }
}

/// What every part of a frame is drawn with.
struct Frame3<'a> {
    view: &'a View<'a>,
    screen: &'a Screen<'a>,
    eye: DVec3,
    lights: &'a [super::WorldLight],
    occluders: Option<(&'a RayCaster<'a>, &'a Prepared)>,
}

impl Target {
    /// Fills the buffers with the background: the sky, or the ground below the horizon.
    fn clear(&mut self, raster: &Rasterizer, view: &View, quantise: bool, pixels: usize) {
        self.depth.clear();
        self.depth.resize(pixels, 0.0);
        let background = &raster.graph.background;
        let sky = background.sky;
        let row = view.to_world.linear.row(1);
        let byte = |c: [f64; 3]| c.map(triangle::to_byte);
        let (sky_bytes, ground_bytes) = (byte(sky), background.ground.map(byte));
        let (sky_linear, ground_linear) = (
            sky.map(|v| v as f32),
            background.ground.map(|g| g.map(|v| v as f32)),
        );
        if quantise {
            self.bytes.clear();
            self.bytes.reserve(pixels * 3);
        } else {
            self.linear.clear();
            self.linear.reserve(pixels);
        }
        let rights: Vec<f64> = (0..view.width)
            .map(|c| (2.0 * (c as f64 + 0.5) / view.width as f64 - 1.0) * view.tan_h)
            .collect();
        for r in 0..view.height {
            let up = (1.0 - 2.0 * (r as f64 + 0.5) / view.height as f64) * view.tan_v;
            // The ray caster's rule: the ground where the pixel's ray points down. A row
            // wholly above or below the horizon is filled at once.
            let below = |right: f64| {
                background.ground.is_some() && row.x + row.y * up + row.z * right < 0.0
            };
            let (first, last) = (below(rights[0]), below(rights[view.width - 1]));
            // (the test is linear along a row: equal at both ends, equal throughout).
            if first == last {
                let pick = first;
                if quantise {
                    let b = if pick {
                        ground_bytes.unwrap_or(sky_bytes)
                    } else {
                        sky_bytes
                    };
                    for _ in 0..view.width {
                        self.bytes.extend_from_slice(&b);
                    }
                } else {
                    let l = if pick {
                        ground_linear.unwrap_or(sky_linear)
                    } else {
                        sky_linear
                    };
                    self.linear.extend(std::iter::repeat_n(l, view.width));
                }
                continue;
            }
            for &right in &rights {
                let below = below(right);
                if quantise {
                    let b = if below {
                        ground_bytes.unwrap_or(sky_bytes)
                    } else {
                        sky_bytes
                    };
                    self.bytes.extend_from_slice(&b);
                } else {
                    self.linear.push(if below {
                        ground_linear.unwrap_or(sky_linear)
                    } else {
                        sky_linear
                    });
                }
            }
        }
    }
}
