//! The CPU rasteriser of 2-D cameras: the render graph's primitives tessellated once
//! ([`crate::tessellate`] at [`Detail::RASTER`]; static ones in world space, robot-attached ones in their robot's frame and
//! placed per frame), near-plane clipping, a z-buffer, and per-vertex VRML97 lighting by the
//! same `shade` as the ray caster, interpolated perspective-correctly (Gouraud).
//!
//! One thread, primitives in graph order, f64 set-up: the same inputs give the same bytes.
//! Shadows (lights with `castShadows`) are the ray caster's shadow rays, cast at each vertex,
//! and at each pixel of a triangle whose corners disagree (a shadow's edge crosses it).
//! Lighting between vertices is interpolated, not evaluated (exact for flat faces under
//! directional lights). Colouring is deferred: triangles write depth and a coverage id, and
//! each pixel is coloured once when every part is drawn (the colour it would have had from
//! the triangle that won it), so hidden pixels are never shaded. `docs/camera-raster.md`
//! gives the measured agreement and speed.

mod triangle;

use glam::DVec3;

use super::raycast::{Prepared, RayCaster};
use super::{shade, world_lights, Poses};
use crate::compile::graph::{Owner, RenderGraph};
use crate::compile::plan::Plan;
use crate::geometry::Frame;
use crate::tessellate::{tessellate, Detail, Tessellation};
use triangle::{Buffers, Corner, Paint, Screen};

/// One primitive's triangles: world space for static parts, robot space for attached ones.
struct Part {
    primitive: usize,
    material: usize,
    robot: Option<usize>,
    set: Tessellation,
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
    /// The smallest and the largest of `lengths` ([`length_range`]).
    pub shortest: f64,
    pub longest: f64,
}

/// The smallest of a camera's per-pixel `lengths` (at most 1) and the largest (at least 1):
/// [`View::shortest`], [`View::longest`].
pub fn length_range(lengths: &[f64]) -> (f64, f64) {
    (
        lengths.iter().fold(1.0f64, |m, &l| m.min(l)),
        lengths.iter().fold(1.0f64, |m, &l| m.max(l)),
    )
}

/// Buffers reused from frame to frame.
#[derive(Default)]
pub struct Target {
    depth: Vec<f32>,
    /// Per pixel, which of `paints` covers it (its index plus one; 0: the background).
    ids: Vec<u32>,
    /// How each drawn triangle colours its pixels.
    paints: Vec<Paint>,
    /// Column centres, `column + 0.5`.
    centres: Vec<f64>,
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
            let mut set = tessellate(&primitive.shape, &graph.meshes, &Detail::RASTER);
            // Both kinds are stored after their primitive's own frame: world space for
            // static parts, the robot's frame for attached ones.
            for (p, n) in set.positions.iter_mut().zip(&mut set.normals) {
                *p = primitive.frame.apply(*p);
                *n = primitive.frame.apply_normal(&primitive.inverse, *n);
            }
            // A vertex that overflowed its frame takes its triangles with it (indices stay).
            let finite: Vec<bool> = set
                .positions
                .iter()
                .zip(&set.normals)
                .map(|(p, n)| p.is_finite() && n.is_finite())
                .collect();
            set.triangles.retain(|t| {
                t.iter()
                    .all(|&i| finite.get(i as usize).copied().unwrap_or(false))
            });
            if set.triangles.is_empty() {
                continue;
            }
            let (min, max) = set.positions.iter().filter(|p| p.is_finite()).fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
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
        target.clear(view, pixels);
        // The nearest depth worth drawing: the near sphere's closest approach to the frustum.
        let near_x = (view.near / view.longest).max(1e-6);
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
            shortest: view.shortest,
            longest: view.longest,
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
        let frame = Frame3 {
            view,
            screen: &screen,
            eye,
            lights: &lights,
            occluders: occluders.as_ref().map(|(c, p)| (*c, p)),
        };
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
            self.draw_part(part, placement.as_ref(), &frame, target);
        }
        self.resolve(&frame, quantise, target);
    }

    fn draw_part(
        &self,
        part: &Part,
        placement: Option<&Frame>,
        frame: &Frame3,
        target: &mut Target,
    ) {
        let (view, screen, eye, lights) = (frame.view, frame.screen, frame.eye, frame.lights);
        let n = part.set.positions.len();
        target.camera.clear();
        target.world.clear();
        for (&position, &normal) in part.set.positions.iter().zip(&part.set.normals) {
            let (p, normal) = match placement {
                // Robot frames are rigid: normals turn as vectors.
                Some(frame) => (frame.apply(position), frame.apply_vector(normal)),
                None => (position, normal),
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
                        color_at(&part.set, i),
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
            let color = color_at(&part.set, t[0] as usize);
            triangle::draw(
                screen,
                corners,
                &mut Buffers {
                    depth: &mut target.depth,
                    ids: &mut target.ids,
                    paints: &mut target.paints,
                    centres: &target.centres,
                },
                mixed.then_some((part.material, color)),
            );
        }
    }

    /// Colours every pixel from what covers it once every part is drawn: the background, or
    /// the nearest triangle's colour (flat, interpolated, or shaded at the pixel). Pixels are
    /// appended in order, so the image needs no clearing.
    fn resolve(&self, frame: &Frame3, quantise: bool, target: &mut Target) {
        let view = frame.view;
        let (width, height) = (view.width, view.height);
        let pixels = width * height;
        let background = &self.graph.background;
        let sky = background.sky;
        let ground = background.ground;
        let row_of = view.to_world.linear.row(1);
        let sky_colour = Colour::of(sky);
        let ground_colour = Colour::of(ground.unwrap_or(sky));
        let mut out = if quantise {
            target.bytes.clear();
            target.bytes.reserve(pixels * 3);
            Out::Bytes(&mut target.bytes)
        } else {
            target.linear.clear();
            target.linear.reserve(pixels);
            Out::Linear(&mut target.linear)
        };
        let rights: Vec<f64> = (0..width)
            .map(|c| (2.0 * (c as f64 + 0.5) / width as f64 - 1.0) * view.tan_h)
            .collect();
        let exact =
            |material: usize, color: Option<[f64; 3]>, pixel: usize, depth: f64, normal: DVec3| {
                let (column, row) = (pixel % width, pixel / width);
                let up = (1.0 - 2.0 * (row as f64 + 0.5) / height as f64) * view.tan_v;
                let right = (2.0 * (column as f64 + 0.5) / width as f64 - 1.0) * view.tan_h;
                let point = view.to_world.apply(DVec3::new(1.0, up, right) * depth);
                shade(
                    &self.graph.materials[material],
                    color,
                    point,
                    normal,
                    frame.eye,
                    frame.lights,
                    &mut |point, kind| {
                        frame
                            .occluders
                            .is_some_and(|(caster, view)| caster.occluded(view, point, kind))
                    },
                )
            };
        for r in 0..height {
            let y = r as f64 + 0.5;
            let up = (1.0 - 2.0 * (r as f64 + 0.5) / height as f64) * view.tan_v;
            // The ray caster's rule: the ground where the pixel's ray points down. The test
            // is linear along a row: equal at both ends, equal throughout.
            let below =
                |right: f64| ground.is_some() && row_of.x + row_of.y * up + row_of.z * right < 0.0;
            let (first, last) = (below(rights[0]), below(rights[width - 1]));
            let base = r * width;
            let (depths, ids) = (
                &target.depth[base..base + width],
                &target.ids[base..base + width],
            );
            let mut column = 0;
            while column < width {
                let id = id_at(depths[column], ids[column]);
                let past = column + 1 + run_length(&depths[column + 1..], &ids[column + 1..], id);
                match id.checked_sub(1).map(|i| target.paints[i as usize]) {
                    None if first == last => out.run(
                        if first { &ground_colour } else { &sky_colour },
                        past - column,
                    ),
                    None => {
                        for &right in &rights[column..past] {
                            out.run(
                                if below(right) {
                                    &ground_colour
                                } else {
                                    &sky_colour
                                },
                                1,
                            );
                        }
                    }
                    Some(Paint::Flat { bytes, linear }) => {
                        out.run(&Colour { bytes, linear }, past - column)
                    }
                    Some(paint) => {
                        for (k, i) in (base + column..base + past).enumerate() {
                            let x = target.centres[column + k];
                            let color = match paint {
                                Paint::Smooth { w, color } => {
                                    let wv = w.at(x, y);
                                    color.map(|plane| plane.at(x, y) / wv)
                                }
                                Paint::Exact {
                                    w,
                                    normal,
                                    material,
                                    color,
                                } => {
                                    let wv = w.at(x, y);
                                    let normal = normal.map(|plane| plane.at(x, y) / wv);
                                    exact(
                                        material,
                                        color,
                                        i,
                                        1.0 / wv,
                                        DVec3::from_array(normal).normalize_or_zero(),
                                    )
                                }
                                Paint::Flat { .. } => unreachable!("flat runs are filled whole"),
                            };
                            out.pixel(color);
                        }
                    }
                }
                column = past;
            }
        }
    }
}

/// A vertex's colour override (a mesh's Color node), if any.
fn color_at(set: &Tessellation, vertex: usize) -> Option<[f64; 3]> {
    set.colors.as_ref().and_then(|c| c.get(vertex).copied())
}

/// What covers a pixel: its id, or 0 (the background) where its depth says nothing was drawn
/// this frame (a drawn pixel is nearer than depth 0, or NaN); the ids of pixels not drawn are
/// left from an earlier frame.
fn id_at(depth: f32, id: u32) -> u32 {
    if depth == 0.0 {
        0
    } else {
        id
    }
}

/// How many pixels from the start of a row's rest `id` covers.
fn run_length(depths: &[f32], ids: &[u32], id: u32) -> usize {
    const LANES: usize = 8;
    let mut n = 0;
    for (d, i) in depths.chunks_exact(LANES).zip(ids.chunks_exact(LANES)) {
        // All eight at once (a vector compare), then one by one where one differs.
        let same = d
            .iter()
            .zip(i)
            .fold(true, |all, (&d, &i)| all & (id_at(d, i) == id));
        if !same {
            break;
        }
        n += LANES;
    }
    n + depths[n..]
        .iter()
        .zip(&ids[n..])
        .take_while(|&(&d, &i)| id_at(d, i) == id)
        .count()
}

/// A colour as the image stores it: bytes, or linear for noise to be added.
struct Colour {
    bytes: [u8; 3],
    linear: [f32; 3],
}

impl Colour {
    fn of(color: [f64; 3]) -> Colour {
        Colour {
            bytes: color.map(triangle::to_byte),
            linear: color.map(|v| v as f32),
        }
    }
}

/// The image being written, pixel after pixel.
enum Out<'a> {
    Bytes(&'a mut Vec<u8>),
    Linear(&'a mut Vec<[f32; 3]>),
}

impl Out<'_> {
    /// `n` pixels of one colour.
    fn run(&mut self, colour: &Colour, n: usize) {
        match self {
            Out::Bytes(bytes) => {
                const PIXELS: usize = 32;
                let mut pattern = [0u8; 3 * PIXELS];
                for pixel in pattern.chunks_exact_mut(3) {
                    pixel.copy_from_slice(&colour.bytes);
                }
                let mut left = n;
                while left >= PIXELS {
                    bytes.extend_from_slice(&pattern);
                    left -= PIXELS;
                }
                bytes.extend_from_slice(&pattern[..3 * left]);
            }
            Out::Linear(linear) => linear.extend(std::iter::repeat_n(colour.linear, n)),
        }
    }

    /// One pixel of a linear colour.
    fn pixel(&mut self, color: [f64; 3]) {
        match self {
            Out::Bytes(bytes) => bytes.extend_from_slice(&color.map(triangle::to_byte)),
            Out::Linear(linear) => linear.push(color.map(|v| v as f32)),
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
    /// Empties the depth and coverage buffers for a frame: nothing drawn, the background
    /// everywhere.
    fn clear(&mut self, view: &View, pixels: usize) {
        self.depth.clear();
        self.depth.resize(pixels, 0.0);
        // Ids are read only where the depth says something was drawn this frame.
        self.ids.resize(pixels, 0);
        self.paints.clear();
        if self.centres.len() != view.width {
            self.centres = (0..view.width).map(|c| c as f64 + 0.5).collect();
        }
    }
}
