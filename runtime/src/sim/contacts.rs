//! A step's motion: wheel speeds (with their noise) turned into sub-steps short enough that
//! nothing tunnels, each robot moved along its arc, bodies pushed out of obstacles and out of
//! each other (a crowd that stays pressed settles back), and the step's contacts counted.

use glam::DVec2;

use super::broad_phase::{self, BroadPhase, SLACK};
use super::state::{Bodies, Body, PhaseClock, PhaseTimes, RobotState, StepScratch};
use super::world2d::{Footprint, Slab};

/// Most collision sub-steps in one step. A world whose robots could need more (a long time
/// step at a high top speed) is refused when it is checked (`check.rs`), so the bound
/// never cuts a step short and nothing tunnels at any accepted time step.
pub const MAX_SUB_STEPS: usize = 4096;

/// Largest penetration left after a step's collision handling (m).
pub const PENETRATION_TOLERANCE: f64 = 1e-9;

/// Collision passes in one sub-step, at most.
const PASSES: usize = 3;

/// Counts a robot's contacts at the end of a step of `dt` seconds: what it touched in the
/// step's sub-steps (`touched`) against what it touched at the end of the last step.
#[inline]
pub(super) fn count_contacts(robot: &mut RobotState, dt: f64) {
    if robot.touched.is_empty() && robot.contacts.touching.is_empty() {
        // Touching nothing, then or now: only an unbroken contact's length to end, and
        // nothing of the robot written when there was none (most robots, most steps).
        if robot.contacts.current != 0.0 {
            robot.contacts.current = 0.0;
        }
        return;
    }
    robot.touched.sort_unstable();
    robot.touched.dedup();
    let RobotState {
        contacts, touched, ..
    } = robot;
    let any = !touched.is_empty();
    for &k in touched.iter() {
        if contacts.touching.binary_search(&k).is_err() {
            contacts.count_event(k);
        }
    }
    let was = !contacts.touching.is_empty();
    if any && !was {
        contacts.events += 1;
    }
    robot.updated.contact |= any != was;
    if any {
        contacts.steps += 1;
        contacts.current += dt;
        contacts.longest = contacts.longest.max(contacts.current);
    } else {
        contacts.current = 0.0;
    }
    contacts.touching.clone_from(touched);
    // Emptied here, where it was just read, for the next step's sub-steps to fill: the
    // motion's sweep then writes nothing of a robot that touches nothing.
    touched.clear();
}

/// A robot's wheel speeds (m/s) for a step of `dt` seconds, the step after `steps` steps
/// (its wheel noise drawn anew where its control period starts), and the sub-steps they need:
/// short enough that its body crosses no more than half its radius in one (no tunnelling).
#[inline]
pub(super) fn wheel_speeds(
    robot: &mut RobotState,
    rig: &Body,
    steps: u64,
    dt: f64,
) -> ((f64, f64), usize) {
    let to_metres = 100.0 / rig.encoder_resolution;
    let clamp = |command: i32| (command as f64 * to_metres).clamp(-rig.max_speed, rig.max_speed);
    let (mut left, mut right) = match robot.wheel_velocity {
        Some((left, right)) => (
            left.clamp(-rig.max_speed, rig.max_speed),
            right.clamp(-rig.max_speed, rig.max_speed),
        ),
        None => (clamp(robot.command.0), clamp(robot.command.1)),
    };
    if rig.wheel_speed_noise > 0.0 {
        // Drawn with each control command and held for its period, so that the noise a
        // robot's path integrates is the same at any physics step.
        if steps.is_multiple_of(rig.control_steps) {
            robot.wheel_noise = (
                1.0 + rig.wheel_speed_noise * robot.wheel_stream.gaussian(),
                1.0 + rig.wheel_speed_noise * robot.wheel_stream.gaussian(),
            );
        }
        left *= robot.wheel_noise.0;
        right *= robot.wheel_noise.1;
    }
    let needed = libm::ceil(left.abs().max(right.abs()) * dt / (0.5 * rig.body_radius)) as usize;
    ((left, right), needed)
}

/// Where robot `i` is in a collision pass: where the robots' grid filed it (`filed`) while no
/// push has moved it since (`drift`), so that a robot with no neighbour costs the pass no
/// line of its state.
#[inline]
fn centre_of(robots: &[RobotState], filed: &[DVec2], drift: &[f64], i: usize) -> DVec2 {
    if drift[i] == 0.0 {
        filed[i]
    } else {
        DVec2::new(robots[i].pose.x, robots[i].pose.z)
    }
}

/// One sub-step's motion, done robot by robot as the first collision pass reaches each.
struct Moving<'a> {
    /// Each robot's wheel speeds (m/s).
    speeds: &'a [(f64, f64)],
    /// The sub-step (s).
    h: f64,
    /// Where each robot was before the sub-step, pushed as it moves (what `settle` returns
    /// a robot to).
    before: &'a mut Vec<DVec2>,
}

impl Moving<'_> {
    #[inline]
    fn advance(&mut self, robot: &mut RobotState, rig: &Body, index: usize) {
        self.before.push(DVec2::new(robot.pose.x, robot.pose.z));
        let (left, right) = self.speeds[index];
        robot.pose = super::kinematics::advance(robot.pose, left, right, rig.axle_length, self.h);
        robot.travel.0 += left * self.h;
        robot.travel.1 += right * self.h;
    }
}

/// What a step's motion reads and writes of a simulation.
pub(super) struct Motion<'a> {
    /// Each robot's [`Body`]: what motion reads of its rig.
    pub(super) rigs: &'a Bodies,
    pub(super) slab: &'a Slab,
    /// Grids over the floor: what pairs bodies without testing every pair.
    pub(super) broad: &'a mut BroadPhase,
    pub(super) robots: &'a mut [RobotState],
    pub(super) scratch: &'a mut StepScratch,
    /// Wall time spent in each phase, when profiling.
    pub(super) profile: &'a mut Option<PhaseTimes>,
    pub(super) time_step: f64,
}

impl Motion<'_> {
    /// Moves the robots at `speeds` (each robot's wheel speeds, m/s, from
    /// [`wheel_speeds`]), in sub-steps enough for the fastest (`most_sub_steps`, the largest
    /// count [`wheel_speeds`] gave).
    pub(super) fn move_robots(
        &mut self,
        clock: &mut PhaseClock,
        speeds: &[(f64, f64)],
        most_sub_steps: usize,
    ) {
        let dt = self.time_step;
        let sub_steps = most_sub_steps.clamp(1, MAX_SUB_STEPS);
        let h = dt / sub_steps as f64;
        let mut before = std::mem::take(&mut self.scratch.before);
        for _ in 0..sub_steps {
            // Each robot moves along its arc as the first collision pass reaches it: one
            // sweep over the robots, not three (their motions are independent of each
            // other and of every other robot's pass against the static obstacles).
            before.clear();
            let moving = Moving {
                speeds,
                h,
                before: &mut before,
            };
            if self.resolve_collisions(moving, clock) {
                self.settle(&before);
            }
            clock.lap(self.profile.as_mut().map(|p| &mut p.collisions));
        }
        self.scratch.before = before;
        // Each robot's contacts are counted where its visits are, in the step's last sweep
        // (`visits::finish_step`).
    }

    /// Pushes bodies out of obstacles and out of each other: up to 3 passes, each robot
    /// against each static obstacle in order, then each pair of robots in order, every push
    /// seen by the tests after it. The grids only leave out pairs that cannot touch, so the
    /// pushes are those of testing every pair.
    fn resolve_collisions(&mut self, mut moving: Moving, clock: &mut PhaseClock) -> bool {
        let rigs = self.rigs;
        let statics = self.slab.obstacles.len();
        let mut candidates = std::mem::take(&mut self.scratch.candidates);
        let mut drift = std::mem::take(&mut self.scratch.drift);
        // Each robot's centre after its pass against the static obstacles, in robot order:
        // what the robots' grid is filed from without a second sweep over the robots.
        let mut centres = std::mem::take(&mut self.scratch.centres);
        let max_radius = self.broad.max_radius;
        let mut unsettled = false;
        for pass in 0..PASSES {
            // A pass that pushes nothing leaves the next one nothing new to find.
            let mut pushed = false;
            centres.clear();
            for (index, robot) in self.robots.iter_mut().enumerate() {
                let rig = rigs.get(index);
                if pass == 0 {
                    moving.advance(robot, rig, index);
                }
                let (floor, top) = (rig.floor_y, rig.floor_y + rig.body_height);
                let reach = rig.body_radius + 1e-6;
                // Candidates from where the robot is; asked again if pushes carry it further
                // than SLACK from there.
                let mut anchor = DVec2::new(robot.pose.x, robot.pose.z);
                if rig.body_radius <= max_radius && self.broad.statics_clear.is_clear(anchor) {
                    // No obstacle within the square below (`statics_reach` covers it).
                    candidates.clear();
                } else {
                    let (lo, hi) = broad_phase::square(anchor, reach + SLACK);
                    self.broad.statics.query(lo, hi, &mut candidates);
                }
                let mut next = 0;
                while let Some(&k) = candidates.get(next) {
                    next += 1;
                    let center = DVec2::new(robot.pose.x, robot.pose.z);
                    if center.distance(anchor) > SLACK {
                        anchor = center;
                        let (lo, hi) = broad_phase::square(anchor, reach + SLACK);
                        self.broad.statics.query(lo, hi, &mut candidates);
                        next = candidates.partition_point(|&c| c < k);
                        continue;
                    }
                    let obstacle = &self.slab.obstacles[k as usize];
                    if obstacle.y1 <= floor + 1e-6 || obstacle.y0 >= top {
                        continue;
                    }
                    if let Some((depth, normal)) =
                        obstacle.shape.penetration(center, rig.body_radius)
                    {
                        let moved = center + normal * depth;
                        robot.pose.x = moved.x;
                        robot.pose.z = moved.y;
                        robot.touched.push(k);
                        pushed = true;
                    } else if obstacle
                        .shape
                        .penetration(center, rig.body_radius + 1e-6)
                        .is_some()
                    {
                        robot.touched.push(k);
                    }
                }
                centres.push(DVec2::new(robot.pose.x, robot.pose.z));
            }
            if pass == 0 {
                // The motion and the first pass against static obstacles, timed together.
                clock.lap(self.profile.as_mut().map(|p| &mut p.kinematics));
            }
            let count = self.robots.len();
            if count > 1 {
                self.broad.file_centres(&mut centres);
                drift.clear();
                drift.resize(count, 0.0);
            }
            // The largest drift of any robot since the grid was filed.
            let mut max_drift = 0.0f64;
            for a in 0..count.saturating_sub(1) {
                let ra = rigs.get(a).body_radius;
                // Candidates b > a whose filed centre is near enough that they might touch a,
                // allowing for SLACK of motion of a, or of anyone, before they are asked again.
                let (mut anchor, mut drift_then) = (
                    centre_of(self.robots, &self.broad.centres, &drift, a),
                    max_drift,
                );
                // Only b > a, and only those whose filed centre lies within the square's
                // half side of the anchor: b touches a only if |anchor − filed b| < ra + rb +
                // (a's motion since the anchor) + (b's drift), which the asking again below
                // keeps under that half side. The rest would fail the exact test anyway, so
                // the pushes are the same; their lines are never read.
                let centres = &self.broad.centres;
                let query = |anchor: DVec2, drift_then: f64, out: &mut Vec<u32>| {
                    let half = ra + max_radius + drift_then + SLACK;
                    let (lo, hi) = broad_phase::square(anchor, half);
                    let within = hi.x - anchor.x;
                    self.broad.robots.query_where(lo, hi, out, |b| {
                        b as usize > a && centres[b as usize].distance(anchor) <= within
                    });
                };
                query(anchor, drift_then, &mut candidates);
                let mut next = 0;
                let mut moved = 0.0;
                while let Some(&b) = candidates.get(next) {
                    next += 1;
                    let b = b as usize;
                    if moved + (max_drift - drift_then) > SLACK {
                        anchor = centre_of(self.robots, centres, &drift, a);
                        drift_then = max_drift;
                        moved = 0.0;
                        query(anchor, drift_then, &mut candidates);
                        next = candidates.partition_point(|&c| (c as usize) < b);
                        continue;
                    }
                    // The compact copy: a candidate that touches nothing costs no rig line.
                    let rb = self.broad.radii[b];
                    let ca = centre_of(self.robots, centres, &drift, a);
                    let cb = centre_of(self.robots, centres, &drift, b);
                    if let Some((depth, normal)) = (Footprint::Circle {
                        center: cb,
                        radius: rb,
                    })
                    .penetration(ca, ra)
                    {
                        let half = normal * (0.5 * depth);
                        self.robots[a].pose.x += half.x;
                        self.robots[a].pose.z += half.y;
                        self.robots[b].pose.x -= half.x;
                        self.robots[b].pose.z -= half.y;
                        self.robots[a].touched.push((statics + b) as u32);
                        self.robots[b].touched.push((statics + a) as u32);
                        pushed = true;
                        // Bounds on how far each has gone since the grid was filed: never 0
                        // for a push (`centre_of` reads a robot's state once it has one).
                        let step = (half.length() * (1.0 + 1e-9)).max(f64::MIN_POSITIVE);
                        drift[a] += step;
                        drift[b] += step;
                        moved += step;
                        max_drift = max_drift.max(drift[a]).max(drift[b]);
                    }
                }
                let _ = anchor;
            }
            if !pushed {
                break;
            }
            // The last pass still pushed: what it left may overlap (a pressing crowd).
            unsettled = pass + 1 == PASSES;
        }
        self.scratch.candidates = candidates;
        self.scratch.drift = drift;
        self.scratch.centres = centres;
        unsettled
    }

    /// After the passes of a crowd: every robot still overlapping something beyond the
    /// tolerance goes back to where it was before this sub-step (where nothing overlapped),
    /// until nothing does (`before`: where each robot was). Blocked robots stay put; the
    /// others keep their motion.
    fn settle(&mut self, before: &[DVec2]) {
        let rigs = self.rigs;
        let mut candidates = std::mem::take(&mut self.scratch.candidates);
        let mut marked = std::mem::take(&mut self.scratch.marked);
        let max_radius = self.broad.max_radius;
        for _ in 0..=self.robots.len() {
            marked.clear();
            marked.resize(self.robots.len(), false);
            let mut any = false;
            for (index, robot) in self.robots.iter().enumerate() {
                let rig = rigs.get(index);
                let (floor, top) = (rig.floor_y, rig.floor_y + rig.body_height);
                let center = DVec2::new(robot.pose.x, robot.pose.z);
                let (lo, hi) = broad_phase::square(center, rig.body_radius);
                self.broad.statics.query(lo, hi, &mut candidates);
                let in_wall = candidates.iter().any(|&k| {
                    let obstacle = &self.slab.obstacles[k as usize];
                    !(obstacle.y1 <= floor + 1e-6 || obstacle.y0 >= top)
                        && obstacle
                            .shape
                            .penetration(center, rig.body_radius)
                            .is_some_and(|(depth, _)| depth > PENETRATION_TOLERANCE)
                });
                if in_wall {
                    marked[index] = true;
                    any = true;
                }
            }
            let robots = &self.robots;
            self.broad.file_robots(robots.len(), |i| {
                DVec2::new(robots[i].pose.x, robots[i].pose.z)
            });
            for a in 0..robots.len() {
                let ca = DVec2::new(robots[a].pose.x, robots[a].pose.z);
                let ra = rigs.get(a).body_radius;
                let (lo, hi) = broad_phase::square(ca, ra + max_radius);
                self.broad.robots.query(lo, hi, &mut candidates);
                for &b in candidates.iter().filter(|&&b| b as usize > a) {
                    let b = b as usize;
                    let cb = DVec2::new(robots[b].pose.x, robots[b].pose.z);
                    if ca.distance(cb) < ra + self.broad.radii[b] - PENETRATION_TOLERANCE {
                        marked[a] = true;
                        marked[b] = true;
                        any = true;
                    }
                }
            }
            if !any {
                break;
            }
            for ((robot, &back), before) in self.robots.iter_mut().zip(&marked).zip(before) {
                if back {
                    robot.pose.x = before.x;
                    robot.pose.z = before.y;
                }
            }
        }
        self.scratch.candidates = candidates;
        self.scratch.marked = marked;
    }
}
