//! Where robots end up after a step, in one sweep: their contacts counted, entries into each
//! landmark's visit disc (buoy visits), and robots that left every floor (fallen off the
//! world).

use glam::DVec2;

use super::broad_phase::BroadPhase;
use super::state::{Bodies, Body, Fall, RobotState, StepScratch, Visits};
use crate::compile::rig::RobotRig;
use crate::compile::Compiled;

/// The floors each robot started on, each distinct set kept once: most robots of a world
/// share one, so the end of a step reads one small table, not a line of every robot's rig
/// and then its list.
#[derive(Debug, Default)]
pub(super) struct FloorSets {
    sets: Vec<Vec<[f64; 4]>>,
    /// Each robot's set, an index into `sets`.
    of: Vec<u32>,
}

impl FloorSets {
    pub(super) fn of(rigs: &[RobotRig]) -> FloorSets {
        let mut table = FloorSets::default();
        let bits = |floors: &[[f64; 4]]| -> Vec<u64> {
            floors.iter().flatten().map(|v| v.to_bits()).collect()
        };
        for rig in rigs {
            let key = bits(&rig.floors);
            let set = match table.sets.iter().position(|s| bits(s) == key) {
                Some(set) => set,
                None => {
                    table.sets.push(rig.floors.clone());
                    table.sets.len() - 1
                }
            };
            table.of.push(set as u32);
        }
        table
    }

    /// The floors robot `robot` started on.
    #[inline]
    pub(super) fn floors(&self, robot: usize) -> &[[f64; 4]] {
        &self.sets[self.of[robot] as usize]
    }
}

/// Below this many landmarks, each is tested rather than looked up in the grid.
const FEW_LANDMARKS: usize = 8;

/// The end of a step, robot by robot in one sweep (each robot's state is read once, not once
/// per kind of bookkeeping): its contacts counted over the step of `dt` seconds and its fall
/// kept (where a step of `dt` ended: `None` before the first, visits only), then its entries
/// into visit discs counted, at `time`.
pub(super) fn finish_step(
    robots: &mut [RobotState],
    (compiled, bodies, floors): (&Compiled, &Bodies, &FloorSets),
    broad: &BroadPhase,
    (dt, time): (Option<f64>, f64),
    scratch: &mut StepScratch,
) {
    let mut candidates = std::mem::take(&mut scratch.candidates);
    let mut was = std::mem::take(&mut scratch.was_inside);
    for (index, robot) in robots.iter_mut().enumerate() {
        let body = bodies.get(index);
        if let Some(dt) = dt {
            super::contacts::count_contacts(robot, dt);
            track_fall(robot, floors.floors(index), time);
        }
        track_visits_of(
            robot,
            body,
            compiled,
            broad,
            time,
            (&mut candidates, &mut was),
        );
    }
    scratch.was_inside = was;
    scratch.candidates = candidates;
}

/// One robot's entries into visit discs (`candidates` and `was`: working lists).
#[inline]
fn track_visits_of(
    robot: &mut RobotState,
    rig: &Body,
    compiled: &Compiled,
    broad: &BroadPhase,
    time: f64,
    (candidates, was): (&mut Vec<u32>, &mut Vec<u32>),
) {
    let center = DVec2::new(robot.pose.x, robot.pose.z);
    if compiled.landmarks.len() <= FEW_LANDMARKS {
        // A few: each tested, as the grid would hand them (ascending).
        candidates.clear();
        candidates.extend(0..compiled.landmarks.len() as u32);
    } else if broad.landmarks_clear.is_clear(center) {
        // No visit disc holds the centre.
        candidates.clear();
    } else {
        broad.landmarks.query_point(center, candidates);
    }
    if candidates.is_empty() && robot.visiting.is_empty() {
        // In no disc, then or now: nothing to count, and nothing of the robot written.
        return;
    }
    let (visits, inside) = (&mut robot.visits, &mut robot.visiting);
    was.clear();
    was.extend_from_slice(inside);
    inside.clear();
    for &k in candidates.iter() {
        let landmark = &compiled.landmarks[k as usize];
        let distance = DVec2::new(
            robot.pose.x - landmark.center.x,
            robot.pose.z - landmark.center.y,
        )
        .length();
        if distance <= Visits::disc_radius(landmark.radius, rig.body_radius) {
            if was.binary_search(&k).is_err() {
                visits.sequence.push(k as usize);
                visits.times.push(time);
            }
            inside.push(k);
        }
    }
}

/// A robot whose centre has left every floor it started on has fallen off the world: the
/// event is kept, and the robot stays where it fell.
#[inline]
fn track_fall(robot: &mut RobotState, floors: &[[f64; 4]], time: f64) {
    if let Some(fall) = &robot.fell {
        robot.pose = fall.pose;
        return;
    }
    if floors.is_empty() {
        return;
    }
    let (x, z) = (robot.pose.x, robot.pose.z);
    let on_floor = floors
        .iter()
        .any(|f| (f[0]..=f[2]).contains(&x) && (f[1]..=f[3]).contains(&z));
    if !on_floor {
        robot.fell = Some(Box::new(Fall {
            time,
            pose: robot.pose,
        }));
    }
}
