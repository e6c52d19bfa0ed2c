//! The Khepera's IR proximity and ambient light sensors.
//!
//! IR model: a sensor casts `numberOfRays` horizontal rays spread evenly over its aperture
//! (the extreme rays at ±aperture/2). Each ray's hit, taken at its depth along the sensor's
//! axis (distance × cos offset), gives a value from the lookup table (linear between rows, the
//! last row's value beyond `range`), scaled by the obstacle's `irReflectance`. The rays are
//! averaged with weights cos(offset), so a flat wall square ahead reads exactly the table's
//! value, while a thin cylinder, which the side rays miss or meet deeper, reads less — the
//! small IR cross-section of the paper's buoys.
//! Noise: the table's third column is a relative standard deviation, applied once per
//! reading from the sensor's own seeded stream. Values are rounded and clamped to 0…1023.
//!
//! Ambient model: the irradiance at the sensor is Σ over lights of
//! `colour luminance × attenuation × spot × (intensity·max(0, n·l) + ambientIntensity)`
//! (VRML97's terms without a surface colour), n the sensor's looking direction; with
//! `occlusion TRUE` a point or spot light hidden by an obstacle at the sensor's height gives
//! nothing. The lookup table maps irradiance to the value (about 500 in the dark, less when
//! bright), noise as for IR.

use glam::{DVec2, DVec3};

use super::noise::Stream;
use super::world2d::{Footprint, Slab};
use crate::broad::Grid;
use crate::compile::graph::LightKind;
use crate::compile::rig::{DistanceSensorRig, LightSensorRig, Placement};
use crate::render::{light_at_with, WorldLight};
use crate::retina::luminance;

/// Value and relative noise of a lookup table at `x` (rows sorted by their first column).
pub fn lookup(table: &[[f64; 3]], x: f64) -> (f64, f64) {
    let Some(first) = table.first() else {
        return (0.0, 0.0);
    };
    if x <= first[0] {
        return (first[1], first[2]);
    }
    for pair in table.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if x <= b[0] {
            let span = b[0] - a[0];
            let f = if span > 0.0 { (x - a[0]) / span } else { 1.0 };
            return (a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f);
        }
    }
    let last = table[table.len() - 1];
    (last[1], last[2])
}

/// How far from a robot's centre any of its IR sensors reaches: the farthest sensor's offset
/// plus its range (widened for rounding).
pub fn ir_reach(sensors: &[DistanceSensorRig]) -> f64 {
    let reach = sensors
        .iter()
        .map(|s| DVec2::new(s.position.x, s.position.z).length() + s.range)
        .fold(0.0f64, f64::max);
    reach * (1.0 + 1e-9) + 1e-9
}

/// The slab's obstacles that any of a robot's IR sensors could see: those within `reach`
/// (the robot's [`ir_reach`]) of the robot's centre (a superset of what each sensor's own
/// test keeps, by the triangle inequality), ascending, into `nearby`; `grid` files the slab's
/// obstacles.
pub fn nearby_obstacles(
    slab: &Slab,
    grid: &Grid,
    placement: &Placement,
    reach: f64,
    nearby: &mut Vec<u32>,
) {
    let center = DVec2::new(placement.x, placement.z);
    if slab.obstacles.len() <= 16 {
        // A few: each tested (the same list the grid would give).
        nearby.clear();
        nearby.extend(0..slab.obstacles.len() as u32);
        nearby.retain(|&index| slab.obstacles[index as usize].shape.distance(center) <= reach);
    } else {
        grid.query_where(center - reach, center + reach, nearby, |index| {
            slab.obstacles[index as usize].shape.distance(center) <= reach
        });
    }
}

/// One proximity reading, 0…1023; `nearby` lists the obstacles worth testing (see
/// [`nearby_obstacles`]) and `robots` the other robots that may be within reach, ascending (a
/// superset of those within [`ir_reach`] plus their body radius).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn proximity(
    slab: &Slab,
    nearby: &[u32],
    robots: &[u32],
    placements: &[Placement],
    robot: usize,
    sensor: &DistanceSensorRig,
    stream: &mut Stream,
) -> u16 {
    to_reading(proximity_value(
        slab, nearby, robots, placements, robot, sensor, stream,
    ))
}

/// One proximity reading as the lookup table and the noise give it, before the Khepera's
/// rounding and clamping to 0…1023 (what a Webots controller reads); [`proximity`] is this,
/// rounded.
#[allow(clippy::too_many_arguments)]
pub fn proximity_value(
    slab: &Slab,
    nearby: &[u32],
    robots: &[u32],
    placements: &[Placement],
    robot: usize,
    sensor: &DistanceSensorRig,
    stream: &mut Stream,
) -> f64 {
    let far = lookup(&sensor.lookup, f64::INFINITY);
    proximity_value_far(
        slab,
        (nearby, robots),
        (placements, robot, &placements[robot]),
        sensor,
        far,
        stream,
    )
}

/// [`proximity_value`] with what a ray that hits nothing reads (`far`, the table at
/// infinity: [`NothingInRange::far`]) looked up by the caller, once per sensor rather than
/// once per reading.
///
/// `placements` gives where the other robots are (their position and floor alone are read),
/// `placement` where robot `robot` is, turned.
#[inline]
pub fn proximity_value_far(
    slab: &Slab,
    (nearby, robots): (&[u32], &[u32]),
    (placements, robot, placement): (&[Placement], usize, &Placement),
    sensor: &DistanceSensorRig,
    far: (f64, f64),
    stream: &mut Stream,
) -> f64 {
    let origin = placement.to_world(sensor.position);
    let height = origin.y;
    let origin2 = DVec2::new(origin.x, origin.z);
    // Only obstacles at the sensor's height and within its range can answer any of its rays
    // (a hit is never nearer than the obstacle; the margin keeps rounding on the safe side).
    let reach = sensor.range * (1.0 + 1e-9) + 1e-12;
    let mut near = [0u32; 16];
    let mut count = 0;
    let mut overflow = Vec::new();
    for &index in nearby {
        let obstacle = &slab.obstacles[index as usize];
        if height < obstacle.y0 || height > obstacle.y1 {
            continue;
        }
        if obstacle.shape.distance(origin2) <= reach {
            if count < near.len() {
                near[count] = index;
                count += 1;
            } else {
                overflow.push(index);
            }
        }
    }
    // Other robots' bodies at the sensor's height and within its range, likewise: gathered
    // once, with what a hit reads of them, for every ray to test.
    let mut bodies = [(DVec2::ZERO, 0.0, 0.0); 8];
    let mut body_count = 0;
    let mut more_bodies = Vec::new();
    for &other in robots {
        let other = other as usize;
        let place = &placements[other];
        if other != robot
            && height >= place.floor_y
            && height <= place.floor_y + slab.robot_bodies[other].height
            && DVec2::new(place.x, place.z).distance(origin2)
                <= reach + slab.robot_bodies[other].radius
        {
            let body = (
                DVec2::new(place.x, place.z),
                slab.robot_bodies[other].radius,
                slab.robot_reflectance.get(other).copied().unwrap_or(1.0),
            );
            if body_count < bodies.len() {
                bodies[body_count] = body;
                body_count += 1;
            } else {
                more_bodies.push(body);
            }
        }
    }
    if count == 0 && body_count == 0 {
        // Every ray misses: the same sums with no ray traced.
        return sample(sensor, far, stream, |_| None);
    }
    let looking = placement.direction_to_world(sensor.direction);
    let direction = DVec2::new(looking.x, looking.z).normalize_or(DVec2::X);
    let candidates = near[..count]
        .iter()
        .chain(&overflow)
        .map(|&i| &slab.obstacles[i as usize]);
    let bodies = bodies[..body_count].iter().chain(&more_bodies);
    sample(sensor, far, stream, |(cos, sin)| {
        // Counter-clockwise seen from above, in (x, z): the same sense as headings.
        let ray = DVec2::new(
            cos * direction.x + sin * direction.y,
            -sin * direction.x + cos * direction.y,
        );
        let mut nearest = sensor.range;
        let mut reflectance = 0.0;
        for obstacle in candidates.clone() {
            if let Some(t) = obstacle.shape.ray(origin2, ray) {
                if t < nearest {
                    nearest = t;
                    reflectance = obstacle.ir_reflectance;
                }
            }
        }
        for &(center, radius, body_reflectance) in bodies.clone() {
            if let Some(t) = (Footprint::Circle { center, radius }).ray(origin2, ray) {
                if t < nearest {
                    nearest = t;
                    reflectance = body_reflectance;
                }
            }
        }
        (nearest < sensor.range).then_some((nearest, reflectance))
    })
}

/// What a proximity sensor reads when every ray misses, worked out once per sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NothingInRange {
    /// The table's response to nothing (its far row).
    pub mean: f64,
    /// Its relative noise.
    pub spread: f64,
    /// The reading, rounded and clamped, when `spread` is 0: with no noise to add, a robot
    /// alone in open floor reads this without rounding each step.
    pub reading: u16,
    /// What a ray that hits nothing reads from the table (value, relative noise): its row
    /// at infinity, looked up once.
    pub far: (f64, f64),
}

/// A proximity sensor's [`NothingInRange`]: what [`proximity`] reads with nothing in range.
pub fn nothing_in_range(sensor: &DistanceSensorRig) -> NothingInRange {
    let far = lookup(&sensor.lookup, f64::INFINITY);
    let (mean, spread) = sums(sensor, far, |_| None);
    NothingInRange {
        mean,
        spread,
        reading: to_reading(mean),
        far,
    }
}

/// One proximity reading when nothing at all is within the robot's IR reach (the same reading
/// [`proximity`] gives with empty lists), and its value before rounding and clamping.
#[inline]
pub fn proximity_of_nothing(nothing: &NothingInRange, stream: &mut Stream) -> (u16, f64) {
    if nothing.spread == 0.0 {
        // What `value` does without noise, with the rounding done once.
        stream.skip_gaussian();
        return (nothing.reading, nothing.mean);
    }
    let value = value(nothing.mean, nothing.spread, stream);
    (to_reading(value), value)
}

/// One reading from the rays' hits: `hit(cos, sin)` of each ray's turn gives its nearest hit
/// (distance, reflectance) within range, if any.
#[inline]
fn sample(
    sensor: &DistanceSensorRig,
    far: (f64, f64),
    stream: &mut Stream,
    hit: impl FnMut((f64, f64)) -> Option<(f64, f64)>,
) -> f64 {
    let (mean, spread) = sums(sensor, far, hit);
    value(mean, spread, stream)
}

/// The weighted mean and relative spread of the rays' responses. Each ray is weighted by its
/// cosine; the hit's depth along the sensor's axis reads the table (a wall square ahead is at
/// one depth for every ray and reads the table's value).
#[inline]
fn sums(
    sensor: &DistanceSensorRig,
    far: (f64, f64),
    mut hit: impl FnMut((f64, f64)) -> Option<(f64, f64)>,
) -> (f64, f64) {
    let (mut value_sum, mut noise_sum, mut weight_sum) = (0.0, 0.0, 0.0);
    for &(_, cos, sin) in sensor.ray_turns.iter() {
        let weight = cos;
        let (value, noise) = match hit((cos, sin)) {
            Some((nearest, reflectance)) => {
                let (value, noise) = lookup(&sensor.lookup, nearest * weight);
                (value * reflectance, noise)
            }
            None => far,
        };
        value_sum += weight * value;
        noise_sum += weight * noise * value;
        weight_sum += weight;
    }
    (value_sum / weight_sum, noise_sum / weight_sum)
}

/// The value, noise drawn from the sensor's stream.
#[inline]
fn value(mean: f64, spread: f64, stream: &mut Stream) -> f64 {
    if spread == 0.0 {
        // `mean + 0 · g` is `mean` whatever g is (the table's far row has no noise): the
        // stream moves on as if it had been drawn.
        stream.skip_gaussian();
        return mean;
    }
    mean + spread * stream.gaussian()
}

/// One ambient light reading, 0…1023; `grid` files the slab's obstacles.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn ambient(
    lights: &[WorldLight],
    slab: &Slab,
    grid: &Grid,
    placements: &[Placement],
    robot: usize,
    sensor: &LightSensorRig,
    stream: &mut Stream,
) -> u16 {
    to_reading(ambient_value(
        lights,
        slab,
        grid,
        &placements[robot],
        sensor,
        stream,
    ))
}

/// One ambient light reading before the Khepera's rounding and clamping (what a Webots
/// controller's light sensor reads), of a sensor on the robot at `placement`.
pub fn ambient_value(
    lights: &[WorldLight],
    slab: &Slab,
    grid: &Grid,
    placement: &Placement,
    sensor: &LightSensorRig,
    stream: &mut Stream,
) -> f64 {
    let position = placement.to_world(sensor.position);
    let normal = placement
        .direction_to_world(sensor.direction)
        .normalize_or(DVec3::X);
    let mut irradiance = 0.0;
    for light in lights {
        let Some((to_light, reach)) = light_at_with(&light.kind, position, sensor.attenuation)
        else {
            continue;
        };
        if sensor.occlusion {
            if let LightKind::Point { location, .. } | LightKind::Spot { location, .. } = light.kind
            {
                if blocked(slab, grid, position, location) {
                    continue;
                }
            }
        }
        irradiance += luminance(light.color)
            * reach
            * (light.intensity * normal.dot(to_light).max(0.0) + light.ambient_intensity);
    }
    let (value, noise) = lookup(&sensor.lookup, irradiance);
    if noise == 0.0 {
        // `value · (1 + 0 · g)` is `value`: the stream moves on as if it had been drawn.
        stream.skip_gaussian();
        return value;
    }
    value * (1.0 + noise * stream.gaussian())
}

/// `round(x)` clamped to 0…1023 (NaN reads 0); halves round up, as `round` does for the
/// non-negative values that remain.
#[inline]
pub fn to_reading(x: f64) -> u16 {
    let clamped = x.clamp(0.0, 1023.0);
    let whole = clamped as u16;
    whole + (clamped - whole as f64 >= 0.5) as u16
}

/// Whether an obstacle at the sensor's height stands between the sensor and a light (the
/// grid offers the obstacles along the way).
fn blocked(slab: &Slab, grid: &Grid, from: DVec3, to: DVec3) -> bool {
    let origin = DVec2::new(from.x, from.z);
    let offset = DVec2::new(to.x - from.x, to.z - from.z);
    let distance = offset.length();
    if distance == 0.0 {
        return false;
    }
    let direction = offset / distance;
    grid.any_on_segment(origin, origin + offset, |index| {
        let o = &slab.obstacles[index as usize];
        from.y >= o.y0
            && from.y <= o.y1
            && o.shape
                .ray(origin, direction)
                .is_some_and(|t| t > 1e-9 && t < distance)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readings_round_like_libm_and_clamp() {
        for x in [
            -3.0, -0.5, -0.2, 0.0, 0.49, 0.5, 1.5, 2.5, 511.499, 1022.5, 1023.4, 5e3,
        ] {
            let expected = libm::round(x).clamp(0.0, 1023.0) as u16;
            assert_eq!(to_reading(x), expected, "{x}");
        }
        assert_eq!(to_reading(f64::NAN), 0);
    }

    /// A reading of nothing, kept rounded where the far row has no noise, is the reading the
    /// rays give with nothing to hit, and moves the stream on as that reading does.
    #[test]
    fn readings_of_nothing_match_the_rays_with_nothing_to_hit() {
        let placements = [Placement {
            x: 0.3,
            z: -0.2,
            floor_y: 0.0,
            sin: 0.6,
            cos: 0.8,
        }];
        // Far rows without noise (the Khepera's), with noise, and past the 0…1023 clamp.
        for far_row in [[0.06, 3.0, 0.0], [0.06, 40.0, 0.1], [0.06, 1500.0, 0.0]] {
            let sensor = DistanceSensorRig {
                name: "ds0".into(),
                position: DVec3::new(0.02, 0.01, 0.0),
                direction: DVec3::X,
                lookup: vec![[0.0, 1023.0, 0.05], far_row].into(),
                rays: 3,
                aperture: 0.5,
                range: 0.06,
                period: 0.032,
                ray_turns: DistanceSensorRig::turns(3, 0.5).into(),
            };
            let nothing = nothing_in_range(&sensor);
            let (mut kept, mut traced) = (Stream::new(4, 0, 2, 0), Stream::new(4, 0, 2, 0));
            for _ in 0..50 {
                let (reading, value) = proximity_of_nothing(&nothing, &mut kept);
                let expected = proximity_value(
                    &Slab::default(),
                    &[],
                    &[],
                    &placements,
                    0,
                    &sensor,
                    &mut traced,
                );
                assert_eq!(value.to_bits(), expected.to_bits(), "{far_row:?}");
                assert_eq!(reading, to_reading(expected), "{far_row:?}");
            }
            assert_eq!(kept.uniform().to_bits(), traced.uniform().to_bits());
        }
    }

    #[test]
    fn lookup_interpolates_and_clamps() {
        let table = [[0.0, 1023.0, 0.0], [0.02, 1023.0, 0.01], [0.04, 0.0, 0.0]];
        assert_eq!(lookup(&table, -1.0).0, 1023.0);
        assert!((lookup(&table, 0.03).0 - 511.5).abs() < 1e-9);
        assert_eq!(lookup(&table, 1.0).0, 0.0);
    }
}
