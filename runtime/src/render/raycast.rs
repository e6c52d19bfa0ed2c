//! Ray casting: exact intersections with the analytic primitives, a BVH per mesh and one over
//! the static primitives. The reference every faster path is measured against, and the
//! renderer for scenes the column renderer cannot draw.

use glam::DVec3;

use super::texels::Texels;
use super::{shade, world_lights, Poses, WorldLight};
use crate::compile::graph::{LightKind, Owner, Primitive, RenderGraph, Shape};
use crate::compile::plan::Plan;
use crate::geometry::{
    ray_box, ray_cone, ray_cylinder, ray_sphere, ray_triangle, Aabb, Bvh, Frame, LocalHit, Ray,
};
use crate::texcoord;

/// A surface hit in world space.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub primitive: usize,
    pub t: f64,
    pub point: DVec3,
    pub normal: DVec3,
    /// A mesh triangle's own colour, replacing the material's diffuse colour.
    pub color: Option<[f64; 3]>,
    /// The hit point in the primitive's own frame, and the mesh triangle it lies on: where a
    /// texture is read ([`RayCaster::diffuse_at`]).
    pub local: DVec3,
    pub triangle: Option<u32>,
}

/// What [`RayCaster::hit_primitive`] finds: the hit in the primitive's frame (its normal in
/// the world's), a mesh triangle's colour and index.
struct PrimitiveHit {
    hit: LocalHit,
    local: DVec3,
    color: Option<[f64; 3]>,
    triangle: Option<u32>,
}

impl Hit {
    fn new(primitive: usize, ray: &Ray, found: PrimitiveHit) -> Hit {
        Hit {
            primitive,
            t: found.hit.t,
            point: ray.at(found.hit.t),
            normal: found.hit.normal,
            color: found.color,
            local: found.local,
            triangle: found.triangle,
        }
    }
}

/// Per-graph data: BVHs over each mesh's triangles.
pub struct RayCaster<'g> {
    pub graph: &'g RenderGraph,
    mesh_bvhs: Vec<Bvh>,
    visible: Vec<bool>,
}

/// One frame for one viewer: robot-attached primitives placed, lights resolved.
pub struct Prepared {
    dynamic: Vec<(usize, Frame, Frame, Aabb)>,
    lights: Vec<WorldLight>,
}

impl<'g> RayCaster<'g> {
    pub fn new(graph: &'g RenderGraph, plan: &Plan) -> RayCaster<'g> {
        let mesh_bvhs = graph
            .meshes
            .iter()
            .map(|mesh| {
                let boxes: Vec<Aabb> = mesh
                    .triangles
                    .iter()
                    .map(|t| Aabb::from_points(t.iter().map(|&i| mesh.positions[i as usize])))
                    .collect();
                Bvh::build(&boxes)
            })
            .collect();
        let mut visible = vec![false; graph.primitives.len()];
        for &p in &plan.visible {
            visible[p] = true;
        }
        RayCaster {
            graph,
            mesh_bvhs,
            visible,
        }
    }

    /// Places robot parts for `poses`; `viewer` adds the viewer's own visible parts and removes
    /// its other parts (a robot does not see the inside of its own body).
    pub fn prepare(&self, plan: &Plan, poses: &Poses, viewer: Option<usize>) -> Prepared {
        let mut dynamic = Vec::new();
        for (index, primitive) in self.graph.primitives.iter().enumerate() {
            let Owner::Robot(robot) = primitive.owner else {
                continue;
            };
            if robot >= poses.poses.len() {
                continue;
            }
            let own = Some(robot) == viewer;
            let wanted = if own {
                plan.own_visible
                    .get(robot)
                    .is_some_and(|v| v.contains(&index))
            } else {
                self.visible[index]
            };
            if !wanted {
                continue;
            }
            let robot_frame = poses.frame(robot);
            let frame = robot_frame.then(&primitive.frame);
            let Some(inverse) = frame.inverse() else {
                continue;
            };
            let bounds = primitive
                .shape
                .local_bounds(&self.graph.meshes)
                .transformed(&frame);
            dynamic.push((index, frame, inverse, bounds));
        }
        Prepared {
            dynamic,
            lights: world_lights(self.graph, plan, poses),
        }
    }

    fn hit_primitive(
        &self,
        primitive: &Primitive,
        frame: &Frame,
        inverse: &Frame,
        ray: &Ray,
        t_max: f64,
    ) -> Option<PrimitiveHit> {
        let local = Ray {
            origin: inverse.apply(ray.origin),
            direction: inverse.apply_vector(ray.direction),
        };
        let hit = match &primitive.shape {
            Shape::Box { half } => ray_box(&local, *half, t_max).map(|h| (h, None, None)),
            Shape::Sphere { radius } => ray_sphere(&local, *radius, t_max).map(|h| (h, None, None)),
            Shape::Cylinder {
                radius,
                height,
                side,
                bottom,
                top,
            } => ray_cylinder(&local, *radius, *height, *side, *bottom, *top, t_max)
                .map(|h| (h, None, None)),
            Shape::Cone {
                radius,
                height,
                side,
                bottom,
            } => ray_cone(&local, *radius, *height, *side, *bottom, t_max).map(|h| (h, None, None)),
            Shape::Mesh(m) => {
                let mesh = &self.graph.meshes[*m];
                let mut best: Option<LocalHit> = None;
                let found = self.mesh_bvhs[*m].nearest(&local, t_max, |tri, limit| {
                    let [a, b, c] =
                        mesh.triangles[tri as usize].map(|i| mesh.positions[i as usize]);
                    let hit = ray_triangle(&local, a, b, c, limit)?;
                    best = Some(hit);
                    Some(hit.t)
                });
                found.map(|(tri, t)| {
                    let [a, b, c] =
                        mesh.triangles[tri as usize].map(|i| mesh.positions[i as usize]);
                    let hit = ray_triangle(&local, a, b, c, f64::INFINITY).unwrap_or(LocalHit {
                        t,
                        normal: DVec3::Y,
                    });
                    let color = mesh
                        .triangle_colors
                        .as_ref()
                        .and_then(|c| c.get(tri as usize).copied());
                    (
                        LocalHit {
                            t,
                            normal: hit.normal,
                        },
                        color,
                        Some(tri),
                    )
                })
            }
        }?;
        let normal = frame.apply_normal(inverse, hit.0.normal);
        Some(PrimitiveHit {
            hit: LocalHit { t: hit.0.t, normal },
            local: local.at(hit.0.t),
            color: hit.1,
            triangle: hit.2,
        })
    }

    /// The diffuse colour of the surface at `hit`: a mesh triangle's own colour, else the
    /// texel of its material's image there ([`Texels`]), else the material's colour.
    pub fn diffuse_at(&self, hit: &Hit, texels: &Texels) -> [f64; 3] {
        if let Some(color) = hit.color {
            return color;
        }
        let Some(primitive) = self.graph.primitives.get(hit.primitive) else {
            return [1.0; 3];
        };
        let Some(material) = self.graph.materials.get(primitive.material) else {
            return [1.0; 3];
        };
        if material.maps.base_color.is_some() {
            let uv = texcoord::at_point(
                &primitive.shape,
                &self.graph.meshes,
                hit.local,
                hit.triangle,
            );
            if let Some(texel) = uv.and_then(|uv| texels.diffuse(material, uv)) {
                return texel;
            }
        }
        material.diffuse
    }

    /// The nearest visible surface along a ray within `t_max`.
    pub fn trace(&self, frame: &Prepared, ray: &Ray, t_max: f64) -> Option<Hit> {
        let graph = self.graph;
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        graph.static_index.nearest(ray, t_max, |item, t_limit| {
            let index = graph.static_primitives[item as usize];
            if !self.visible[index] {
                return None;
            }
            let primitive = &graph.primitives[index];
            let found = self.hit_primitive(
                primitive,
                &primitive.frame,
                &primitive.inverse,
                ray,
                t_limit.min(limit),
            )?;
            limit = found.hit.t;
            best = Some(Hit::new(index, ray, found));
            Some(limit)
        });
        for (index, world, inverse, bounds) in &frame.dynamic {
            if bounds
                .ray_interval(ray, ray.direction.recip(), limit)
                .is_none()
            {
                continue;
            }
            let primitive = &graph.primitives[*index];
            if let Some(found) = self.hit_primitive(primitive, world, inverse, ray, limit) {
                limit = found.hit.t;
                best = Some(Hit::new(*index, ray, found));
            }
        }
        best
    }

    /// Linear RGB arriving at `origin` from `direction`.
    pub fn rgb(&self, frame: &Prepared, origin: DVec3, direction: DVec3) -> [f64; 3] {
        self.rgb_within(frame, origin, direction, f64::INFINITY)
    }

    /// [`RayCaster::rgb`] seeing nothing farther than `t_max` along `direction` (the
    /// background beyond).
    pub fn rgb_within(
        &self,
        frame: &Prepared,
        origin: DVec3,
        direction: DVec3,
        t_max: f64,
    ) -> [f64; 3] {
        let ray = Ray { origin, direction };
        match self.trace(frame, &ray, t_max) {
            Some(hit) => {
                let material = &self.graph.materials[self.graph.primitives[hit.primitive].material];
                let mut occluded =
                    |point: DVec3, kind: &LightKind| self.occluded(frame, point, kind);
                shade(
                    material,
                    hit.color,
                    hit.point,
                    hit.normal,
                    origin,
                    &frame.lights,
                    &mut occluded,
                )
            }
            None => self.background(direction),
        }
    }

    /// What is seen where nothing is hit.
    pub fn background(&self, direction: DVec3) -> [f64; 3] {
        let background = &self.graph.background;
        match background.ground {
            Some(ground) if direction.y < 0.0 => ground,
            _ => background.sky,
        }
    }

    pub(crate) fn occluded(&self, frame: &Prepared, point: DVec3, kind: &LightKind) -> bool {
        let (direction, distance) = match kind {
            LightKind::Directional { direction } => (-*direction, f64::INFINITY),
            LightKind::Point { location, .. } | LightKind::Spot { location, .. } => {
                let offset = *location - point;
                (offset, 1.0)
            }
        };
        let origin = point + direction.normalize_or_zero() * 1e-9;
        self.blocked(frame, &Ray { origin, direction }, distance * (1.0 - 1e-9))
    }

    /// Whether the ray hits anything before `t_max`: [`RayCaster::trace`]`.is_some()`, but
    /// stopping at the first hit (there is one exactly when there is a nearest).
    fn blocked(&self, frame: &Prepared, ray: &Ray, t_max: f64) -> bool {
        let graph = self.graph;
        let statics = graph.static_index.any(ray, t_max, |item, t_limit| {
            let index = graph.static_primitives[item as usize];
            let primitive = &graph.primitives[index];
            self.visible[index]
                && self
                    .hit_primitive(
                        primitive,
                        &primitive.frame,
                        &primitive.inverse,
                        ray,
                        t_limit,
                    )
                    .is_some()
        });
        statics
            || frame.dynamic.iter().any(|(index, world, inverse, bounds)| {
                bounds
                    .ray_interval(ray, ray.direction.recip(), t_max)
                    .is_some()
                    && self
                        .hit_primitive(&graph.primitives[*index], world, inverse, ray, t_max)
                        .is_some()
            })
    }
}
