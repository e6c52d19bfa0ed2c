//! Webots' distance sensors on generic robots, cast in three dimensions through the runtime's
//! ray caster: a sensor looks along its own +x, wherever it points (down at the floor, up, at
//! a slant), and sees every primitive of the world and of the other robots.
//!
//! As Webots documents the types: `laser` casts one ray; `sonar` takes the nearest hit among
//! its rays whose incidence is under 22.5° (a steeper echo is lost); `generic` and `infra-red`
//! average their rays' values with Gaussian weights over the aperture. A ray that meets
//! nothing within the table's farthest distance reads the table's last value. Rays beyond the
//! first spread across the aperture in the sensor's horizontal plane (a documented
//! simplification of Webots' cone). Noise is the table's relative standard deviation, drawn
//! from the sensor's own seeded stream.

use glam::DVec3;
use regatta_runtime::compile::plan::Plan;
use regatta_runtime::compile::Compiled;
use regatta_runtime::geometry::Ray;
use regatta_runtime::render::raycast::{Hit, Prepared, RayCaster};
use regatta_runtime::render::texels::Texels;
use regatta_runtime::render::Poses;
use regatta_runtime::sim::noise::Stream;
use regatta_runtime::sim::sensors::lookup;
use regatta_runtime::sim::Simulation;

/// The noise streams' kind for these sensors ("WB"), apart from the runtime's.
pub const STREAM_KIND: u64 = 0x5742;

/// The largest incidence a sonar echo returns from.
const SONAR_INCIDENCE: f64 = 22.5 * std::f64::consts::PI / 180.0;

/// A sensor's geometry and type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySensor {
    /// Position and looking direction in the robot's frame (regatta's: x forward, y up).
    pub position: DVec3,
    pub direction: DVec3,
    /// Its turns' axis (the sensor's own up), in the robot's frame.
    pub up: DVec3,
    /// 0 generic, 1 infra-red, 2 sonar, 3 laser.
    pub medium: u8,
    pub rays: u32,
    pub aperture: f64,
}

/// The ray caster over a world, every primitive visible.
pub struct Rays<'c> {
    caster: RayCaster<'c>,
    plan: Plan,
    /// The floor's and other surfaces' images, decoded when an infra-red ray first meets one.
    texels: Texels<'c>,
}

impl<'c> Rays<'c> {
    pub fn new(compiled: &'c Compiled) -> Rays<'c> {
        let mut plan = compiled.plan.clone();
        plan.visible = (0..compiled.graph.primitives.len()).collect();
        // A robot's sensors do not see its own body.
        for own in &mut plan.own_visible {
            own.clear();
        }
        Rays {
            caster: RayCaster::new(&compiled.graph, &plan),
            plan,
            texels: Texels::new(&compiled.graph.textures),
        }
    }

    /// The world placed for robot `robot`'s sensors.
    pub fn prepare(&self, simulation: &Simulation, robot: usize) -> Prepared {
        let poses = Poses {
            poses: simulation.robots.iter().map(|r| r.pose).collect(),
            floor_y: simulation
                .compiled
                .rig
                .robots
                .iter()
                .map(|r| r.floor_y)
                .collect(),
        };
        self.caster.prepare(&self.plan, &poses, Some(robot))
    }

    /// Where the axis of `sensor` on robot `robot` first meets something within `far` (a
    /// laser's spot).
    pub fn first_hit(
        &self,
        prepared: &Prepared,
        simulation: &Simulation,
        robot: usize,
        sensor: &RaySensor,
        far: f64,
    ) -> Option<Hit> {
        let state = &simulation.robots[robot];
        let floor = simulation.compiled.rig.robots[robot].floor_y;
        let origin = state.pose.to_world(sensor.position, floor);
        let direction = state
            .pose
            .frame(floor)
            .apply_vector(sensor.direction)
            .normalize_or(DVec3::X);
        self.caster
            .trace(prepared, &Ray { origin, direction }, far.max(0.0))
    }

    /// The first thing `ray` meets within `far`, in the world as `prepared` places it.
    pub fn trace(&self, prepared: &Prepared, ray: &Ray, far: f64) -> Option<Hit> {
        self.caster.trace(prepared, ray, far)
    }

    /// One reading of `sensor` on robot `robot`, through `table` (rows: distance, value,
    /// relative noise).
    pub fn measure(
        &self,
        prepared: &Prepared,
        simulation: &Simulation,
        robot: usize,
        sensor: &RaySensor,
        table: &[[f64; 3]],
        stream: &mut Stream,
    ) -> f64 {
        let state = &simulation.robots[robot];
        let floor = simulation.compiled.rig.robots[robot].floor_y;
        let origin = state.pose.to_world(sensor.position, floor);
        let frame = state.pose.frame(floor);
        let axis = frame.apply_vector(sensor.direction).normalize_or(DVec3::X);
        let up = frame.apply_vector(sensor.up).normalize_or(DVec3::Y);
        let far = table.last().map_or(0.0, |row| row[0]);
        let rays = if sensor.medium == 3 {
            1
        } else {
            sensor.rays.max(1)
        };
        let mut nearest: Option<f64> = None;
        let (mut sum, mut weights) = (0.0, 0.0);
        for i in 0..rays {
            let offset = if rays == 1 {
                0.0
            } else {
                -0.5 * sensor.aperture + sensor.aperture * f64::from(i) / f64::from(rays - 1)
            };
            let direction = glam::DQuat::from_axis_angle(up, offset) * axis;
            let ray = Ray { origin, direction };
            let hit = self.caster.trace(prepared, &ray, far.max(0.0));
            let distance = match (hit, sensor.medium) {
                (Some(hit), 2) => {
                    let incidence = libm::acos((-direction.dot(hit.normal)).clamp(-1.0, 1.0));
                    (incidence < SONAR_INCIDENCE).then_some(hit.t)
                }
                // Webots' infra-red rays see red: the distance is divided by
                // 0.2 + 0.8 × the red level of what they meet.
                (Some(hit), 1) => Some(hit.t / (0.2 + 0.8 * self.red_level(&hit))),
                (Some(hit), _) => Some(hit.t),
                (None, _) => None,
            };
            if sensor.medium == 2 {
                if let Some(d) = distance {
                    nearest = Some(nearest.map_or(d, |n: f64| n.min(d)));
                }
                continue;
            }
            let width = 0.5 * sensor.aperture.max(1e-9);
            let weight = libm::exp(-(offset / width) * (offset / width));
            sum += weight * lookup(table, distance.unwrap_or(f64::INFINITY)).0;
            weights += weight;
        }
        let (mean, noise) = if sensor.medium == 2 {
            lookup(table, nearest.unwrap_or(f64::INFINITY))
        } else {
            let mean = sum / weights.max(1e-300);
            (mean, relative_noise(table, mean))
        };
        if noise == 0.0 {
            stream.skip_gaussian();
            return mean;
        }
        mean * (1.0 + noise * stream.gaussian())
    }
}

impl Rays<'_> {
    /// The red level (0–1) of what a ray met: a mesh triangle's own colour, else the texel
    /// of its material's image where the ray landed (a line on the floor), else the
    /// material's diffuse colour.
    fn red_level(&self, hit: &Hit) -> f64 {
        self.caster.diffuse_at(hit, &self.texels)[0].clamp(0.0, 1.0)
    }
}

/// The table's noise at the row whose value is nearest `value` (the noise column is indexed by
/// distance; a mean of rays has no one distance).
fn relative_noise(table: &[[f64; 3]], value: f64) -> f64 {
    table
        .iter()
        .min_by(|a, b| (a[1] - value).abs().total_cmp(&(b[1] - value).abs()))
        .map_or(0.0, |row| row[2])
}
