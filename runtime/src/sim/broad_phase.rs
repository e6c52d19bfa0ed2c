//! The simulation's broad phase: three grids over the floor (static obstacles, landmarks'
//! visit discs, robots' centres) that hand the exact tests — IR rays, light occlusion,
//! collisions, contacts, visits — only the candidates that may pass them. The static grids
//! are filed once; the robots' grid is filed again whenever robots have moved (O(N), no
//! allocation once warm).

use glam::DVec2;

use super::world2d::Slab;
use crate::broad::{Clearance, Grid};
use crate::compile::Compiled;

/// How far a robot may move before its collision candidates are asked again (m).
pub(super) const SLACK: f64 = 0.005;

/// Relative and absolute margins that keep a candidate box on the safe side of rounding.
const MARGIN: f64 = 1e-9;

pub(super) struct BroadPhase {
    pub statics: Grid,
    pub landmarks: Grid,
    /// Where no static obstacle comes within [`BroadPhase::statics_reach`]: a robot there
    /// has no obstacle to sense or to touch without asking the grid (most robots, in an
    /// open arena).
    pub statics_clear: Clearance,
    /// The reach `statics_clear` answers for (m): the farthest any robot's IR sensors
    /// reach, or its body and a collision pass's slack do, with margins for rounding.
    pub statics_reach: f64,
    /// Where no landmark's visit disc reaches: a robot there visits nothing.
    pub landmarks_clear: Clearance,
    pub robots: Grid,
    /// The largest body radius (m).
    pub max_radius: f64,
    /// Each robot's body radius, and its centre as last filed: side by side in two short
    /// arrays, so that a crowd's neighbour tests read a few bytes a robot instead of a cache
    /// line of its placement and another of its rig (at 10,000 robots those misses were
    /// most of the IR phase).
    pub radii: Vec<f64>,
    pub centres: Vec<DVec2>,
}

impl BroadPhase {
    pub fn new(compiled: &Compiled, slab: &Slab) -> BroadPhase {
        let rigs = &compiled.rig.robots;
        let max_radius = rigs.iter().map(|r| r.body_radius).fold(0.0, f64::max);
        let ir_reach = rigs
            .iter()
            .flat_map(|r| r.distance_sensors.iter())
            .map(|s| DVec2::new(s.position.x, s.position.z).length() + s.range)
            .fold(0.0, f64::max);
        // A cell about as wide as what one robot's sensors and body reach: a query touches a
        // few cells, and a cell holds a few robots at any density robots can stand.
        let cell = (2.0 * max_radius + ir_reach).max(1e-3);
        // The region: static obstacles, landmarks and robots' starts (anything beyond is filed
        // in the edge cells).
        let mut min = DVec2::splat(f64::INFINITY);
        let mut max = DVec2::splat(f64::NEG_INFINITY);
        let mut grow = |(a, b): (DVec2, DVec2)| {
            min = min.min(a);
            max = max.max(b);
        };
        for obstacle in &slab.obstacles {
            grow(obstacle_box(&obstacle.shape));
        }
        for landmark in &compiled.landmarks {
            grow(landmark_box(landmark, max_radius));
        }
        for rig in rigs {
            let p = DVec2::new(rig.start.x, rig.start.z);
            grow((p, p));
        }
        if !min.is_finite() {
            (min, max) = (DVec2::ZERO, DVec2::ZERO);
        }
        let mut statics = Grid::new(min, max, cell, slab.obstacles.len());
        statics.rebuild(slab.obstacles.len(), |i| {
            obstacle_box(&slab.obstacles[i].shape)
        });
        let mut landmarks = Grid::new(min, max, cell, compiled.landmarks.len());
        landmarks.rebuild(compiled.landmarks.len(), |i| {
            landmark_box(&compiled.landmarks[i], max_radius)
        });
        let robots = Grid::new(min, max, cell, rigs.len());
        let statics_reach = statics_reach(rigs, max_radius);
        let statics_clear = Clearance::new(
            min,
            max,
            statics_reach,
            slab.obstacles.iter().map(|o| obstacle_box(&o.shape)),
        );
        let landmarks_clear = Clearance::new(
            min,
            max,
            0.0,
            compiled
                .landmarks
                .iter()
                .map(|l| landmark_box(l, max_radius)),
        );
        BroadPhase {
            statics,
            landmarks,
            statics_clear,
            statics_reach,
            landmarks_clear,
            robots,
            max_radius,
            radii: rigs.iter().map(|r| r.body_radius).collect(),
            centres: Vec::with_capacity(rigs.len()),
        }
    }

    /// Files the robots' centres (and keeps them in [`BroadPhase::centres`]).
    pub fn file_robots(&mut self, count: usize, center: impl Fn(usize) -> DVec2) {
        self.centres.clear();
        self.centres.extend((0..count).map(center));
        let centres = &self.centres;
        self.robots.rebuild_points(count, |i| centres[i]);
    }

    /// [`BroadPhase::file_robots`] from centres already gathered, one a robot in order:
    /// they become [`BroadPhase::centres`], and `centres` gets the buffer they replace.
    pub fn file_centres(&mut self, centres: &mut Vec<DVec2>) {
        std::mem::swap(&mut self.centres, centres);
        let centres = &self.centres;
        self.robots.rebuild_points(centres.len(), |i| centres[i]);
    }
}

/// The half side of the largest square about a robot's centre in which static obstacles are
/// asked for: its IR sensors' reach (`sensors::ir_reach`), or a collision pass's (its body,
/// 1 µm and the slack, widened as [`square`] widens it), whichever is larger, widened again.
fn statics_reach(rigs: &[crate::compile::rig::RobotRig], max_radius: f64) -> f64 {
    let ir = rigs
        .iter()
        .map(|r| super::sensors::ir_reach(&r.distance_sensors))
        .fold(0.0, f64::max);
    let collision = (max_radius + 1e-6 + SLACK) * (1.0 + MARGIN) + MARGIN;
    ir.max(collision) * (1.0 + MARGIN) + MARGIN
}

/// The square of half side `reach` about `center`, widened for rounding.
pub(super) fn square(center: DVec2, reach: f64) -> (DVec2, DVec2) {
    let r = reach * (1.0 + MARGIN) + MARGIN;
    (center - r, center + r)
}

fn obstacle_box(shape: &crate::geometry::Footprint) -> (DVec2, DVec2) {
    match *shape {
        crate::geometry::Footprint::Circle { center, radius } => square(center, radius),
        crate::geometry::Footprint::Rect {
            center,
            u,
            v,
            half_u,
            half_v,
        } => {
            let half = u.abs() * half_u + v.abs() * half_v;
            let widen = half * MARGIN + MARGIN;
            (center - half - widen, center + half + widen)
        }
    }
}

/// A landmark's visit disc (its radius plus two diameters of the largest body).
fn landmark_box(landmark: &crate::compile::Landmark, max_radius: f64) -> (DVec2, DVec2) {
    square(landmark.center, landmark.radius + 4.0 * max_radius)
}
