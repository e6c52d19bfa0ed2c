//! The arena seen from straight above, for `render_mode="rgb_array"`: the floor-level
//! cross-sections robots collide with (walls, buoys, obstacles) in their materials' colours,
//! and each robot as a disc with a line from its centre to its heading. +x is to the right
//! and +z down, as the world looks from above with its y axis toward the viewer.

use glam::DVec2;
use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use regatta_runtime::geometry::Footprint;
use regatta_runtime::sim::Simulation;

use crate::errors::value_error;

const FLOOR: [u8; 3] = [226, 222, 212];
const ROBOT: [u8; 3] = [40, 110, 60];
const HEADING: [u8; 3] = [250, 250, 250];

/// The top view as rows of RGB pixels, `size` × `size`.
pub fn top_view(simulation: &Simulation, size: usize) -> Vec<u8> {
    let compiled = simulation.compiled;
    let rigs = &compiled.rig.robots;
    // The world's extent on the floor: every obstacle and robot, with a margin.
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut include = |center: DVec2, radius: f64| {
        lo = lo.min(center - radius);
        hi = hi.max(center + radius);
    };
    for obstacle in &simulation.slab.obstacles {
        let (center, radius) = obstacle.shape.bounding_circle();
        include(center, radius);
    }
    for (robot, rig) in simulation.robots.iter().zip(rigs) {
        include(DVec2::new(robot.pose.x, robot.pose.z), rig.body_radius);
    }
    if !(lo.x.is_finite() && hi.x.is_finite()) {
        lo = DVec2::splat(-0.5);
        hi = DVec2::splat(0.5);
    }
    let span = (hi - lo).max_element().max(1e-3) * 1.04;
    let middle = (lo + hi) / 2.0;
    let origin = middle - DVec2::splat(span / 2.0);
    let metres_per_pixel = span / size as f64;
    let mut image = vec![0u8; size * size * 3];
    for pixel in image.chunks_exact_mut(3) {
        pixel.copy_from_slice(&FLOOR);
    }
    let to_pixel = |p: DVec2| (p - origin) / metres_per_pixel;
    let at = |col: usize, row: usize| {
        origin + DVec2::new(col as f64 + 0.5, row as f64 + 0.5) * metres_per_pixel
    };
    let fill = |shape: &Footprint, colour: [u8; 3], image: &mut [u8]| {
        let (center, radius) = shape.bounding_circle();
        let (a, b) = (to_pixel(center - radius), to_pixel(center + radius));
        let clampi = |v: f64| (v.max(0.0) as usize).min(size);
        for row in clampi(a.y.floor())..clampi(b.y.ceil()) {
            for col in clampi(a.x.floor())..clampi(b.x.ceil()) {
                if shape.distance(at(col, row)) == 0.0 {
                    image[(row * size + col) * 3..][..3].copy_from_slice(&colour);
                }
            }
        }
    };
    let graph = &compiled.graph;
    for obstacle in &simulation.slab.obstacles {
        let material = &graph.materials[graph.primitives[obstacle.primitive].material];
        let colour = std::array::from_fn(|k| {
            let c = (material.diffuse[k] + material.emissive[k]).clamp(0.0, 1.0);
            (c * 255.0).round() as u8
        });
        fill(&obstacle.shape, colour, &mut image);
    }
    for (robot, rig) in simulation.robots.iter().zip(rigs) {
        let center = DVec2::new(robot.pose.x, robot.pose.z);
        let body = Footprint::Circle {
            center,
            radius: rig.body_radius,
        };
        fill(&body, ROBOT, &mut image);
        // Heading: +x forward; a rotation by θ about +y turns x toward −z.
        let forward = DVec2::new(
            libm::cos(robot.pose.heading),
            -libm::sin(robot.pose.heading),
        );
        let steps = (rig.body_radius / metres_per_pixel * 2.0).ceil().max(1.0) as usize;
        for k in 0..=steps {
            let p = to_pixel(center + forward * rig.body_radius * k as f64 / steps as f64);
            if p.x >= 0.0 && p.y >= 0.0 && (p.x as usize) < size && (p.y as usize) < size {
                let (col, row) = (p.x as usize, p.y as usize);
                image[(row * size + col) * 3..][..3].copy_from_slice(&HEADING);
            }
        }
    }
    image
}

pub fn top_view_array<'py>(
    py: Python<'py>,
    simulation: &Simulation,
    size: usize,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    if !(16..=4096).contains(&size) {
        return Err(value_error(format!(
            "size must be 16 to 4096 pixels, found {size}"
        )));
    }
    PyArray1::from_vec(py, top_view(simulation, size)).reshape([size, size, 3])
}
