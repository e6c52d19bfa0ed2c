//! Geometric queries, apart from any simulation: rays, boxes, exact ray–primitive
//! intersections in a primitive's local frame, rigid frames, and a BVH over bounding boxes.
//!
//! Transcendental functions go through `libm` so that results do not depend on the platform's
//! math library.

use glam::{DMat3, DVec2, DVec3};

/// A ray `origin + t·direction`, `t ≥ 0`; `direction` need not be unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
}

impl Ray {
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.direction * t
    }
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        b
    }

    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn center(self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    pub fn is_empty(self) -> bool {
        self.min.x > self.max.x
    }

    /// Entry and exit parameters of a ray through the box (slab test), if it hits within
    /// `[0, t_max]`. `inverse_direction` is `1 / ray.direction` per component.
    pub fn ray_interval(
        self,
        ray: &Ray,
        inverse_direction: DVec3,
        t_max: f64,
    ) -> Option<(f64, f64)> {
        let t0 = (self.min - ray.origin) * inverse_direction;
        let t1 = (self.max - ray.origin) * inverse_direction;
        let near = t0.min(t1);
        let far = t0.max(t1);
        // NaN (0·∞ on a slab boundary) must not widen the interval: max/min ignore NaN.
        let enter = near.x.max(near.y).max(near.z).max(0.0);
        let exit = far.x.min(far.y).min(far.z).min(t_max);
        (enter <= exit).then_some((enter, exit))
    }

    /// The box of the 8 corners of `self` under a frame.
    pub fn transformed(self, frame: &Frame) -> Aabb {
        if self.is_empty() {
            return self;
        }
        Aabb::from_points((0..8).map(|i| {
            let corner = DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            frame.apply(corner)
        }))
    }
}

/// A rotation about a unit axis, built with `libm` (platform-independent).
pub fn axis_angle(axis: DVec3, angle: f64) -> DMat3 {
    let axis = if axis.length_squared() > 0.0 {
        axis.normalize()
    } else {
        DVec3::Y
    };
    let (s, c) = (libm::sin(angle), libm::cos(angle));
    let t = 1.0 - c;
    let (x, y, z) = (axis.x, axis.y, axis.z);
    DMat3::from_cols(
        DVec3::new(t * x * x + c, t * x * y + s * z, t * x * z - s * y),
        DVec3::new(t * x * y - s * z, t * y * y + c, t * y * z + s * x),
        DVec3::new(t * x * z + s * y, t * y * z - s * x, t * z * z + c),
    )
}

/// An affine frame: `p ↦ linear·p + translation` (rotation and scale, no shear in practice).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub linear: DMat3,
    pub translation: DVec3,
}

impl Frame {
    pub const IDENTITY: Frame = Frame {
        linear: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// VRML97's Transform: `T·C·R·SR·S·SR⁻¹·C⁻¹`.
    pub fn vrml(
        translation: DVec3,
        rotation: [f64; 4],
        scale: DVec3,
        scale_orientation: [f64; 4],
        center: DVec3,
    ) -> Frame {
        let r = axis_angle(
            DVec3::new(rotation[0], rotation[1], rotation[2]),
            rotation[3],
        );
        let sr = axis_angle(
            DVec3::new(
                scale_orientation[0],
                scale_orientation[1],
                scale_orientation[2],
            ),
            scale_orientation[3],
        );
        let linear = r * sr * DMat3::from_diagonal(scale) * sr.transpose();
        // p ↦ T + C + linear·(p − C)
        Frame {
            linear,
            translation: translation + center - linear * center,
        }
    }

    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.linear * p + self.translation
    }

    pub fn apply_vector(&self, v: DVec3) -> DVec3 {
        self.linear * v
    }

    /// `self ∘ inner`: first `inner`, then `self`.
    pub fn then(&self, inner: &Frame) -> Frame {
        Frame {
            linear: self.linear * inner.linear,
            translation: self.apply(inner.translation),
        }
    }

    /// The inverse frame, if the linear part is invertible.
    pub fn inverse(&self) -> Option<Frame> {
        let det = self.linear.determinant();
        if !det.is_finite() || det.abs() < 1e-300 {
            return None;
        }
        let linear = self.linear.inverse();
        Some(Frame {
            linear,
            translation: -(linear * self.translation),
        })
    }

    /// Transforms a normal (inverse transpose).
    pub fn apply_normal(&self, inverse: &Frame, n: DVec3) -> DVec3 {
        (inverse.linear.transpose() * n).normalize_or_zero()
    }
}

/// A horizontal cross-section in (x, z): what upright objects look like from above.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Footprint {
    Circle {
        center: DVec2,
        radius: f64,
    },
    Rect {
        center: DVec2,
        u: DVec2,
        v: DVec2,
        half_u: f64,
        half_v: f64,
    },
}

impl Footprint {
    /// Centre and radius of a circle holding the footprint.
    pub fn bounding_circle(&self) -> (DVec2, f64) {
        match *self {
            Footprint::Circle { center, radius } => (center, radius),
            Footprint::Rect {
                center,
                half_u,
                half_v,
                ..
            } => (center, (half_u * half_u + half_v * half_v).sqrt()),
        }
    }

    /// Distance from `point` to the shape (0 inside it).
    pub fn distance(&self, point: DVec2) -> f64 {
        match *self {
            Footprint::Circle { center, radius } => ((point - center).length() - radius).max(0.0),
            Footprint::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let offset = point - center;
                let (du, dv) = (
                    (offset.dot(u).abs() - half_u).max(0.0),
                    (offset.dot(v).abs() - half_v).max(0.0),
                );
                (du * du + dv * dv).sqrt()
            }
        }
    }

    /// Distance along a unit ray to the boundary, if hit at `t ≥ 0` (from inside: 0).
    pub fn ray(&self, origin: DVec2, direction: DVec2) -> Option<f64> {
        match *self {
            Footprint::Circle { center, radius } => {
                let oc = origin - center;
                let b = oc.dot(direction);
                let c = oc.length_squared() - radius * radius;
                if c <= 0.0 {
                    return Some(0.0);
                }
                let disc = b * b - c;
                if disc < 0.0 || b > 0.0 {
                    return None;
                }
                Some(-b - disc.sqrt())
            }
            Footprint::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let oc = origin - center;
                rect_slabs(
                    oc.dot(u),
                    oc.dot(v),
                    direction.dot(u),
                    direction.dot(v),
                    half_u,
                    half_v,
                )
                .map(|(t_in, _, _)| t_in.max(0.0))
            }
        }
    }

    /// How far a circle of radius `r` at `c` reaches into the shape, and the unit direction to
    /// push it out; `None` when they do not touch.
    pub fn penetration(&self, c: DVec2, r: f64) -> Option<(f64, DVec2)> {
        match *self {
            Footprint::Circle { center, radius } => {
                let offset = c - center;
                let distance = offset.length();
                let depth = r + radius - distance;
                if depth <= 0.0 {
                    return None;
                }
                let normal = if distance > 1e-12 {
                    offset / distance
                } else {
                    DVec2::X
                };
                Some((depth, normal))
            }
            Footprint::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let offset = c - center;
                let (pu, pv) = (offset.dot(u), offset.dot(v));
                let (qu, qv) = (pu.clamp(-half_u, half_u), pv.clamp(-half_v, half_v));
                if pu.abs() <= half_u && pv.abs() <= half_v {
                    // Centre inside: out through the nearest face.
                    let (exit_u, exit_v) = (half_u - pu.abs(), half_v - pv.abs());
                    return Some(if exit_u < exit_v {
                        (exit_u + r, u * pu.signum())
                    } else {
                        (exit_v + r, v * pv.signum())
                    });
                }
                let closest = center + u * qu + v * qv;
                let away = c - closest;
                let distance = away.length();
                let depth = r - distance;
                (depth > 0.0).then(|| (depth, away / distance.max(1e-300)))
            }
        }
    }
}

/// A ray through a rectangle in its own axes: position `(pu, pv)` and direction `(du, dv)`
/// relative to the centre, half extents `half_u`, `half_v`. Returns the entry and exit
/// parameters (entry may be negative: the ray starts inside) and which face it enters by:
/// `(axis 0 for u or 1 for v, sign of the outward normal)`.
#[inline]
pub fn rect_slabs(
    pu: f64,
    pv: f64,
    du: f64,
    dv: f64,
    half_u: f64,
    half_v: f64,
) -> Option<(f64, f64, (usize, f64))> {
    rect_slabs_inverse(pu, pv, (du, 1.0 / du), (dv, 1.0 / dv), half_u, half_v)
}

/// [`rect_slabs`] with each direction component given with its reciprocal, for callers that
/// share reciprocals between rectangles of the same axes.
#[inline]
pub fn rect_slabs_inverse(
    pu: f64,
    pv: f64,
    (du, inverse_u): (f64, f64),
    (dv, inverse_v): (f64, f64),
    half_u: f64,
    half_v: f64,
) -> Option<(f64, f64, (usize, f64))> {
    let mut t_in = f64::NEG_INFINITY;
    let mut t_out = f64::INFINITY;
    let mut face = (0, 0.0);
    for (axis, (p, d, inverse, h)) in [(pu, du, inverse_u, half_u), (pv, dv, inverse_v, half_v)]
        .into_iter()
        .enumerate()
    {
        if d.abs() < 1e-300 {
            if p.abs() > h {
                return None;
            }
            continue;
        }
        let (a, b) = ((-h - p) * inverse, (h - p) * inverse);
        let (near, far) = if a < b { (a, b) } else { (b, a) };
        if near > t_in {
            t_in = near;
            face = (axis, if d > 0.0 { -1.0 } else { 1.0 });
        }
        t_out = t_out.min(far);
    }
    (t_in <= t_out && t_out >= 0.0).then_some((t_in, t_out, face))
}

/// A hit in a primitive's local frame.
#[derive(Clone, Copy, Debug)]
pub struct LocalHit {
    pub t: f64,
    pub normal: DVec3,
}

fn nearer(a: Option<LocalHit>, b: Option<LocalHit>) -> Option<LocalHit> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if b.t < a.t { b } else { a }),
        (a, None) => a,
        (None, b) => b,
    }
}

/// Box of half extents `half`, centred on the origin.
pub fn ray_box(ray: &Ray, half: DVec3, t_max: f64) -> Option<LocalHit> {
    let inverse = ray.direction.recip();
    let bounds = Aabb {
        min: -half,
        max: half,
    };
    let t0 = (bounds.min - ray.origin) * inverse;
    let t1 = (bounds.max - ray.origin) * inverse;
    let near = t0.min(t1);
    let enter = near.x.max(near.y).max(near.z);
    let far = t0.max(t1);
    let exit = far.x.min(far.y).min(far.z);
    if enter > exit || exit < 0.0 {
        return None;
    }
    // From inside a box the ray sees its inner faces: those are hits too (a floor seen from
    // inside a thick slab stays visible), with normals facing the ray.
    let (t, axis_t) = if enter >= 0.0 {
        (enter, near)
    } else {
        (exit, far)
    };
    if t > t_max {
        return None;
    }
    let normal = if axis_t.x == t {
        DVec3::new(-ray.direction.x.signum(), 0.0, 0.0)
    } else if axis_t.y == t {
        DVec3::new(0.0, -ray.direction.y.signum(), 0.0)
    } else {
        DVec3::new(0.0, 0.0, -ray.direction.z.signum())
    };
    Some(LocalHit { t, normal })
}

/// Sphere of radius `r` centred on the origin.
pub fn ray_sphere(ray: &Ray, r: f64, t_max: f64) -> Option<LocalHit> {
    let a = ray.direction.length_squared();
    let b = ray.origin.dot(ray.direction);
    let c = ray.origin.length_squared() - r * r;
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    // Stable roots (no cancellation when b is large).
    let q = -b - sq.copysign(b);
    let (mut t0, mut t1) = (q / a, c / q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let t = if t0 >= 0.0 { t0 } else { t1 };
    if !(0.0..=t_max).contains(&t) || !t.is_finite() {
        return None;
    }
    Some(LocalHit {
        t,
        normal: ray.at(t) / r,
    })
}

/// Cylinder along y: radius `r`, from −h/2 to h/2, with optional side and caps.
pub fn ray_cylinder(
    ray: &Ray,
    r: f64,
    h: f64,
    side: bool,
    bottom: bool,
    top: bool,
    t_max: f64,
) -> Option<LocalHit> {
    let half = h * 0.5;
    let mut best: Option<LocalHit> = None;
    if side {
        let (ox, oz, dx, dz) = (ray.origin.x, ray.origin.z, ray.direction.x, ray.direction.z);
        let a = dx * dx + dz * dz;
        if a > 0.0 {
            let b = ox * dx + oz * dz;
            let c = ox * ox + oz * oz - r * r;
            let disc = b * b - a * c;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                let q = -b - sq.copysign(b);
                for t in [q / a, c / q] {
                    if t >= 0.0 && t <= t_max && t.is_finite() {
                        let y = ray.origin.y + t * ray.direction.y;
                        if y.abs() <= half {
                            let p = ray.at(t);
                            best = nearer(
                                best,
                                Some(LocalHit {
                                    t,
                                    normal: DVec3::new(p.x / r, 0.0, p.z / r),
                                }),
                            );
                        }
                    }
                }
            }
        }
    }
    for (present, y, ny) in [(top, half, 1.0), (bottom, -half, -1.0)] {
        if present && ray.direction.y != 0.0 {
            let t = (y - ray.origin.y) / ray.direction.y;
            if t >= 0.0 && t <= t_max {
                let p = ray.at(t);
                if p.x * p.x + p.z * p.z <= r * r {
                    best = nearer(
                        best,
                        Some(LocalHit {
                            t,
                            normal: DVec3::new(0.0, ny, 0.0),
                        }),
                    );
                }
            }
        }
    }
    best
}

/// Cone along y: base radius `r` at −h/2, apex at h/2.
pub fn ray_cone(
    ray: &Ray,
    r: f64,
    h: f64,
    side: bool,
    bottom: bool,
    t_max: f64,
) -> Option<LocalHit> {
    let half = h * 0.5;
    let mut best: Option<LocalHit> = None;
    if side {
        // x² + z² = (k·(half − y))², k = r/h.
        let k = r / h;
        let k2 = k * k;
        let (o, d) = (ray.origin, ray.direction);
        let yo = half - o.y;
        let a = d.x * d.x + d.z * d.z - k2 * d.y * d.y;
        let b = o.x * d.x + o.z * d.z + k2 * yo * d.y;
        let c = o.x * o.x + o.z * o.z - k2 * yo * yo;
        let mut roots = [f64::NAN; 2];
        if a.abs() > 1e-300 {
            let disc = b * b - a * c;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                roots = [(-b - sq) / a, (-b + sq) / a];
            }
        } else if b != 0.0 {
            roots[0] = -c / (2.0 * b);
        }
        for t in roots {
            if t >= 0.0 && t <= t_max && t.is_finite() {
                let p = ray.at(t);
                if p.y >= -half && p.y <= half {
                    let radial = DVec3::new(p.x, 0.0, p.z).normalize_or_zero();
                    let normal = (radial * h + DVec3::new(0.0, r, 0.0)).normalize_or_zero();
                    best = nearer(best, Some(LocalHit { t, normal }));
                }
            }
        }
    }
    if bottom && ray.direction.y != 0.0 {
        let t = (-half - ray.origin.y) / ray.direction.y;
        if t >= 0.0 && t <= t_max {
            let p = ray.at(t);
            if p.x * p.x + p.z * p.z <= r * r {
                best = nearer(
                    best,
                    Some(LocalHit {
                        t,
                        normal: DVec3::NEG_Y,
                    }),
                );
            }
        }
    }
    best
}

/// Möller–Trumbore; returns `t` and the geometric normal (facing the ray).
pub fn ray_triangle(ray: &Ray, a: DVec3, b: DVec3, c: DVec3, t_max: f64) -> Option<LocalHit> {
    let e1 = b - a;
    let e2 = c - a;
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    if t < 0.0 || t > t_max {
        return None;
    }
    let mut normal = e1.cross(e2).normalize_or_zero();
    if normal.dot(ray.direction) > 0.0 {
        normal = -normal;
    }
    Some(LocalHit { t, normal })
}

/// A bounding volume hierarchy over items with boxes; built once, queried many times.
/// Node layout: leaves hold a range of `order`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    /// Item indices, grouped by leaf.
    pub order: Vec<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct BvhNode {
    bounds: Aabb,
    /// Leaf: first item in `order`; inner: index of the left child (right is left + 1).
    start: u32,
    /// Leaf: item count (> 0); inner: 0.
    count: u32,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Builds a BVH by median splits along the widest axis of the centroids (deterministic).
    pub fn build(boxes: &[Aabb]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(boxes.len().max(1) * 2),
            order: (0..boxes.len() as u32).collect(),
        };
        if boxes.is_empty() {
            return bvh;
        }
        let centers: Vec<DVec3> = boxes.iter().map(|b| b.center()).collect();
        bvh.nodes.push(BvhNode {
            bounds: Aabb::EMPTY,
            start: 0,
            count: boxes.len() as u32,
        });
        let mut stack = vec![(0usize, 0usize, boxes.len())];
        while let Some((node, start, end)) = stack.pop() {
            let bounds = bvh.order[start..end]
                .iter()
                .fold(Aabb::EMPTY, |acc, &i| acc.union(boxes[i as usize]));
            bvh.nodes[node].bounds = bounds;
            if end - start <= LEAF_SIZE {
                bvh.nodes[node].start = start as u32;
                bvh.nodes[node].count = (end - start) as u32;
                continue;
            }
            let cb = Aabb::from_points(bvh.order[start..end].iter().map(|&i| centers[i as usize]));
            let extent = cb.max - cb.min;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = (start + end) / 2;
            bvh.order[start..end].sort_by(|&a, &b| {
                centers[a as usize][axis]
                    .total_cmp(&centers[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let left = bvh.nodes.len();
            bvh.nodes.push(BvhNode {
                bounds: Aabb::EMPTY,
                start: 0,
                count: 0,
            });
            bvh.nodes.push(BvhNode {
                bounds: Aabb::EMPTY,
                start: 0,
                count: 0,
            });
            bvh.nodes[node].start = left as u32;
            bvh.nodes[node].count = 0;
            stack.push((left, start, mid));
            stack.push((left + 1, mid, end));
        }
        bvh
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Whether `hit(item, t_max)` holds for some item whose box the ray meets before `t_max`,
    /// stopping at the first: a shadow ray needs to know that something is in the way, not
    /// what is nearest.
    pub fn any(&self, ray: &Ray, t_max: f64, mut hit: impl FnMut(u32, f64) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inverse = ray.direction.recip();
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if node.bounds.ray_interval(ray, inverse, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let items = &self.order[node.start as usize..(node.start + node.count) as usize];
                if items.iter().any(|&item| hit(item, t_max)) {
                    return true;
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.start + 1;
                stack[top + 1] = node.start;
                top += 2;
            }
        }
        false
    }

    /// Calls `hit(item, t_max) -> Option<t>` for items whose boxes the ray may hit before the
    /// current nearest; returns the nearest item and its `t`.
    pub fn nearest(
        &self,
        ray: &Ray,
        mut t_max: f64,
        mut hit: impl FnMut(u32, f64) -> Option<f64>,
    ) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let inverse = ray.direction.recip();
        let mut best = None;
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if node.bounds.ray_interval(ray, inverse, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                for &item in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    if let Some(t) = hit(item, t_max) {
                        if t < t_max || best.is_none() {
                            t_max = t;
                            best = Some((item, t));
                        }
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.start + 1;
                stack[top + 1] = node.start;
                top += 2;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
        Ray {
            origin: DVec3::from_array(o),
            direction: DVec3::from_array(d),
        }
    }

    /// `any` answers whether `nearest` finds something, for every ray and limit.
    #[test]
    fn any_hit_is_whether_there_is_a_nearest() {
        let mut unit = crate::test_random::unit_stream(11);
        let boxes: Vec<Aabb> = (0..200)
            .map(|_| {
                let c = DVec3::new(unit() * 10.0 - 5.0, unit() * 2.0, unit() * 10.0 - 5.0);
                let h = DVec3::new(unit(), unit(), unit()) * 0.3;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let mut hits = 0;
        for _ in 0..500 {
            let r = ray(
                [unit() * 12.0 - 6.0, unit() * 2.0, unit() * 12.0 - 6.0],
                [unit() * 2.0 - 1.0, unit() * 0.2 - 0.1, unit() * 2.0 - 1.0],
            );
            let t_max = unit() * 8.0;
            let inverse = r.direction.recip();
            let item_hit = |item: u32, limit: f64| {
                boxes[item as usize]
                    .ray_interval(&r, inverse, limit)
                    .map(|(entry, _)| entry)
            };
            let nearest = bvh.nearest(&r, t_max, item_hit).is_some();
            hits += nearest as usize;
            assert_eq!(
                bvh.any(&r, t_max, |item, limit| item_hit(item, limit).is_some()),
                nearest
            );
        }
        assert!(
            hits > 20 && hits < 480,
            "{hits} of 500 rays hit: a poor test"
        );
    }

    #[test]
    fn footprint_distance_is_zero_inside_and_euclidean_outside() {
        let circle = Footprint::Circle {
            center: DVec2::new(1.0, 0.0),
            radius: 0.5,
        };
        assert_eq!(circle.distance(DVec2::new(1.2, 0.0)), 0.0);
        assert!((circle.distance(DVec2::new(3.0, 0.0)) - 1.5).abs() < 1e-15);
        let (c, s) = (0.6, 0.8);
        let rect = Footprint::Rect {
            center: DVec2::ZERO,
            u: DVec2::new(c, s),
            v: DVec2::new(-s, c),
            half_u: 1.0,
            half_v: 0.5,
        };
        assert_eq!(rect.distance(DVec2::new(0.3, 0.1)), 0.0);
        // 2 beyond the u face and 1 beyond the v face: the corner is √5 away.
        let point = DVec2::new(c, s) * 3.0 + DVec2::new(-s, c) * 1.5;
        assert!((rect.distance(point) - 5f64.sqrt()).abs() < 1e-12);
        // A ray never hits nearer than the distance (what IR culling relies on).
        let from = DVec2::new(-3.0, 0.2);
        let hit = rect.ray(from, DVec2::X).unwrap();
        assert!(hit >= rect.distance(from));
    }

    #[test]
    fn primitives_are_hit_exactly() {
        let hit = ray_box(
            &ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            DVec3::splat(1.0),
            100.0,
        )
        .unwrap();
        assert_eq!(hit.t, 4.0);
        assert_eq!(hit.normal, DVec3::NEG_X);
        let hit = ray_sphere(&ray([0.0, 0.0, -3.0], [0.0, 0.0, 1.0]), 1.0, 100.0).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-15);
        let hit = ray_cylinder(
            &ray([3.0, 0.2, 0.0], [-1.0, 0.0, 0.0]),
            0.5,
            1.0,
            true,
            true,
            true,
            100.0,
        )
        .unwrap();
        assert!((hit.t - 2.5).abs() < 1e-15);
        let hit = ray_cylinder(
            &ray([0.1, 5.0, 0.0], [0.0, -1.0, 0.0]),
            0.5,
            1.0,
            true,
            true,
            true,
            100.0,
        )
        .unwrap();
        assert!((hit.t - 4.5).abs() < 1e-15 && hit.normal == DVec3::Y);
        let hit = ray_cone(
            &ray([3.0, -0.5, 0.0], [-1.0, 0.0, 0.0]),
            1.0,
            2.0,
            true,
            true,
            100.0,
        )
        .unwrap();
        assert!((hit.t - 2.25).abs() < 1e-12, "{}", hit.t);
        let hit = ray_triangle(
            &ray([0.2, 0.2, 1.0], [0.0, 0.0, -1.0]),
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            10.0,
        )
        .unwrap();
        assert_eq!(hit.t, 1.0);
    }

    #[test]
    fn bvh_finds_the_nearest_of_many() {
        let boxes: Vec<Aabb> = (0..100)
            .map(|i| Aabb {
                min: DVec3::new(i as f64, -0.5, -0.5),
                max: DVec3::new(i as f64 + 0.5, 0.5, 0.5),
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let r = ray([-10.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let inverse = r.direction.recip();
        let found = bvh.nearest(&r, f64::INFINITY, |i, t_max| {
            boxes[i as usize]
                .ray_interval(&r, inverse, t_max)
                .map(|(t, _)| t)
        });
        assert_eq!(found, Some((0, 10.0)));
    }

    #[test]
    fn vrml_transform_order() {
        let frame = Frame::vrml(
            DVec3::new(1.0, 0.0, 0.0),
            [0.0, 1.0, 0.0, std::f64::consts::FRAC_PI_2],
            DVec3::ONE,
            [0.0, 0.0, 1.0, 0.0],
            DVec3::ZERO,
        );
        let p = frame.apply(DVec3::X);
        assert!((p - DVec3::new(1.0, 0.0, -1.0)).length() < 1e-15, "{p}");
    }
}
