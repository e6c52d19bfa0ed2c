//! The floor's image under the top view: what a textured floor shows (a line to follow), read
//! from above through the same texture lookup the ground sensors use. Worlds without a
//! textured floor get none and pay nothing.

use regatta_figures::FloorImage;
use regatta_runtime::compile::Compiled;
use regatta_runtime::geometry::{Aabb, Ray};
use regatta_runtime::render::raycast::RayCaster;
use regatta_runtime::render::texels::Texels;
use regatta_runtime::render::Poses;

/// Cells along the picture's longer side.
const CELLS: f64 = 500.0;

/// The textured floor seen from straight above, unlit; `None` when no static surface at the
/// floor's height maps an image. Cells that see no textured floor are white.
pub fn floor_image(compiled: &Compiled) -> Option<FloorImage> {
    let graph = &compiled.graph;
    let floor = compiled
        .rig
        .robots
        .iter()
        .map(|r| r.floor_y)
        .fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { floor } else { 0.0 };
    let textured: Vec<usize> = graph
        .static_primitives
        .iter()
        .copied()
        .filter(|&p| {
            let primitive = &graph.primitives[p];
            primitive.bounds.max.y <= floor + 1e-6
                && graph
                    .materials
                    .get(primitive.material)
                    .is_some_and(|m| m.maps.base_color.is_some())
        })
        .collect();
    let bounds = textured
        .iter()
        .fold(Aabb::EMPTY, |b, &p| b.union(graph.primitives[p].bounds));
    let (width, depth) = (bounds.max.x - bounds.min.x, bounds.max.z - bounds.min.z);
    if textured.is_empty() || !(width > 0.0 && depth > 0.0) || !width.is_finite() {
        return None;
    }
    let mut plan = compiled.plan.clone();
    plan.visible = textured;
    let caster = RayCaster::new(graph, &plan);
    let prepared = caster.prepare(
        &plan,
        &Poses {
            poses: Vec::new(),
            floor_y: Vec::new(),
        },
        None,
    );
    let texels = Texels::new(&graph.textures);
    let cell = width.max(depth) / CELLS;
    let columns = ((width / cell).ceil() as u32).max(1);
    let rows = ((depth / cell).ceil() as u32).max(1);
    let above = bounds.max.y + 1.0;
    let reach = above - bounds.min.y + 1.0;
    let picture = image::RgbImage::from_fn(columns, rows, |column, row| {
        let origin = glam::DVec3::new(
            bounds.min.x + (f64::from(column) + 0.5) * cell,
            above,
            bounds.min.z + (f64::from(row) + 0.5) * cell,
        );
        let ray = Ray {
            origin,
            direction: glam::DVec3::NEG_Y,
        };
        let rgb = caster
            .trace(&prepared, &ray, reach)
            .map_or([1.0; 3], |hit| caster.diffuse_at(&hit, &texels));
        image::Rgb(rgb.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
    });
    Some(FloorImage {
        x: (bounds.min.x, bounds.min.x + f64::from(columns) * cell),
        z: (bounds.min.z, bounds.min.z + f64::from(rows) * cell),
        picture,
    })
}
