//! One robot's sensing in a step: its due IR sensors (against the obstacles and robots
//! within their reach), ambient light sensors, 2-D cameras and vision device, from what the
//! step shares with every robot.

use glam::DVec2;

use super::broad_phase::{self, BroadPhase};
use super::noise::{kind, Stream};
use super::sensors;
use super::state::{NearbyLists, RobotState};
use super::world2d::Slab;
use crate::compile::rig::{CameraRenderer, Placement, Pose2};
use crate::compile::Compiled;
use crate::optics::{Renderer, ViewOf};
use crate::render::Poses;

/// What every robot's sensing reads in a step, shared and never written while robots sense:
/// so robots can be sensed side by side, each writing only its own state.
pub(super) struct SenseShared<'s, 'c> {
    pub(super) compiled: &'c Compiled,
    pub(super) slab: &'s Slab,
    pub(super) broad: &'s BroadPhase,
    pub(super) placements: &'s [crate::compile::rig::Placement],
    pub(super) lights: &'s [crate::render::WorldLight],
    pub(super) poses: &'s Poses,
    /// The CPU renderer, unless a batched backend renders vision.
    pub(super) renderer: Option<&'s Renderer<'c>>,
    /// The step's frame, when the renderer shares one between viewers.
    pub(super) frame: Option<&'s crate::render::column::ColumnFrame>,
    /// The ray caster of the 2-D cameras, when a robot has one.
    pub(super) camera_caster: Option<&'s crate::render::raycast::RayCaster<'c>>,
    /// The rasteriser of the 2-D cameras, when a robot has one that uses it.
    pub(super) camera_raster: Option<&'s crate::render::raster::Rasterizer<'c>>,
    pub(super) batched: bool,
    pub(super) t: f64,
    /// The seed of the run's noise streams, for those made on first use.
    pub(super) streams_seed: u64,
}

impl SenseShared<'_, '_> {
    /// Refreshes one robot's due sensors (`lists`: working lists, any content).
    pub(super) fn sense(&self, index: usize, robot: &mut RobotState, lists: &mut NearbyLists) {
        let (compiled, t) = (self.compiled, self.t);
        let rig = &compiled.rig.robots[index];
        let senses = robot.senses;
        robot.vision_requested = false;
        // Which devices are read in this step: their APIs refuse the others.
        if robot.has_devices {
            if let Some(turret) = &mut robot.panoramic {
                turret.sensed = senses.vision;
            }
            if let Some(camera) = &mut robot.linear_camera {
                camera.sensed = senses.vision;
            }
            for camera in &mut robot.cameras {
                camera.sensed = senses.camera;
            }
        }
        // The Khepera API reads eight; a robot whose raw readings are kept reads them all.
        let proximity_sensors = match (senses.proximity, robot.raw.is_some()) {
            (false, _) => 0,
            (true, false) => 8,
            (true, true) => usize::MAX,
        };
        self.sense_proximity(index, robot, proximity_sensors, lists);
        let ambient_sensors = match (senses.ambient, robot.raw.is_some()) {
            (false, _) => 0,
            (true, false) => 8,
            (true, true) => usize::MAX,
        };
        if ambient_sensors > 0 && robot.ambient_due.len() < rig.light_sensors.len() {
            robot.ambient_due = vec![0.0; rig.light_sensors.len()];
            robot.ambient_streams = (0..rig.light_sensors.len())
                .map(|s| Stream::new(self.streams_seed, index, kind::AMBIENT, s))
                .collect();
        }
        let mut turned = None;
        for (s, sensor) in rig.light_sensors.iter().enumerate().take(ambient_sensors) {
            if due(&mut robot.ambient_due[s], t, sensor.period) {
                robot.updated.ambient = true;
                let placement = *turned.get_or_insert_with(|| self.turned(index, robot.pose));
                let value = sensors::ambient_value(
                    self.lights,
                    self.slab,
                    &self.broad.statics,
                    &placement,
                    sensor,
                    &mut robot.ambient_streams[s],
                );
                if let Some(slot) = robot.ambient.get_mut(s) {
                    *slot = sensors::to_reading(value);
                }
                if let Some(raw) = &mut robot.raw {
                    raw.light[s] = value;
                }
            }
        }
        // 2-D cameras render on the CPU: rasterised, or ray cast where the rig asks for it.
        if senses.camera {
            let mut view = None;
            for (c, camera) in robot.cameras.iter_mut().enumerate() {
                if !due(&mut camera.due, t, camera.model.rig.period) {
                    continue;
                }
                robot.updated.cameras |= 1 << c.min(63);
                match (
                    camera.model.rig.renderer,
                    self.camera_raster,
                    self.camera_caster,
                ) {
                    (CameraRenderer::Raster, Some(raster), _) => camera.model.update_raster(
                        raster,
                        &compiled.plan,
                        self.poses,
                        index,
                        &mut camera.noise,
                        &mut camera.image,
                    ),
                    (CameraRenderer::Rays, _, Some(caster)) => {
                        let view = view.get_or_insert_with(|| {
                            caster.prepare(&compiled.plan, self.poses, Some(index))
                        });
                        camera.model.update(
                            caster,
                            view,
                            robot.pose,
                            rig.floor_y,
                            &mut camera.noise,
                            &mut camera.image,
                        );
                    }
                    _ => {}
                }
            }
        }
        if !senses.vision {
            return;
        }
        if self.batched {
            robot.vision_requested = match (&mut robot.panoramic, &mut robot.linear_camera) {
                (Some(turret), _) => due(&mut turret.due, t, turret.model.rig.period),
                (None, Some(camera)) => due(&mut camera.due, t, camera.model.rig.period),
                (None, None) => false,
            };
            return;
        }
        let Some(renderer) = self.renderer else {
            return;
        };
        // The shared frame, or a viewer's own (the ray caster's).
        let own;
        let view = match self.frame {
            Some(frame) => ViewOf::Columns(frame, Some(index)),
            None => {
                own = renderer.view(&compiled.plan, self.poses, index);
                own.of()
            }
        };
        if let Some(turret) = &mut robot.panoramic {
            if due(&mut turret.due, t, turret.model.rig.period) {
                robot.updated.vision = true;
                turret.model.update_of_unkept(
                    renderer,
                    view,
                    robot.pose,
                    rig.floor_y,
                    &mut turret.output,
                );
            }
        }
        if let Some(camera) = &mut robot.linear_camera {
            if due(&mut camera.due, t, camera.model.rig.period) {
                robot.updated.vision = true;
                camera
                    .model
                    .update_of(renderer, view, robot.pose, rig.floor_y, &mut camera.output);
            }
        }
    }

    /// Where robot `index` is, turned as `pose` heads: the step's placements hold the robots'
    /// positions and floors, turned only where a renderer reads them (a robot's own sensors
    /// need its turn only when something is within their reach).
    fn turned(&self, index: usize, pose: Pose2) -> Placement {
        pose.placement(self.placements[index].floor_y)
    }

    /// Refreshes a robot's first `count` due IR sensors.
    #[inline(never)]
    fn sense_proximity(
        &self,
        index: usize,
        robot: &mut RobotState,
        count: usize,
        lists: &mut NearbyLists,
    ) {
        let t = self.t;
        let count = count.min(robot.ir_due.len());
        if count == 0 {
            return;
        }
        // Sensors that share a period and a due time (a Khepera's eight always do) are due
        // alike: one test for all.
        if let Some(period) = robot.ir_period {
            if robot.ir_together {
                if count == robot.ir_due.len() {
                    if due(&mut robot.ir_next, t, period) {
                        self.read_all_due(index, robot, count, lists);
                    }
                    return;
                }
                // Some are to be read and not the others: from now on, each its own.
                robot.ir_due.fill(robot.ir_next);
                robot.ir_together = false;
            }
            let first = robot.ir_due[0];
            if robot.ir_due[1..count]
                .iter()
                .all(|d| d.to_bits() == first.to_bits())
            {
                let mut next = first;
                if due(&mut next, t, period) {
                    robot.ir_due[..count].fill(next);
                    self.read_all_due(index, robot, count, lists);
                }
                return;
            }
        }
        // Otherwise each sensor is tested; those that share a period and a due time with the
        // last one tested take its answer without a division.
        let rig = &self.compiled.rig.robots[index];
        robot.ir_streams_caught_up();
        let mut nearby_found = false;
        // Where the robot is, turned, once something is within reach (until then, unread).
        let mut turned = self.placements[index];
        let mut last_due: Option<(u64, f64, bool, f64)> = None;
        let ir_sensors = rig
            .distance_sensors
            .iter()
            .zip(robot.ir_due.iter_mut())
            .zip(robot.ir_streams.iter_mut())
            .zip(robot.ir_nothing.iter())
            .enumerate()
            .take(count);
        for (s, (((sensor, next_due), stream), nothing)) in ir_sensors {
            let period = robot.ir_period.unwrap_or(sensor.period);
            let before = *next_due;
            let is_due = match last_due {
                Some((bits, last_period, was_due, after))
                    if bits == before.to_bits() && last_period.to_bits() == period.to_bits() =>
                {
                    *next_due = after;
                    was_due
                }
                _ => {
                    let is_due = due(next_due, t, period);
                    last_due = Some((before.to_bits(), period, is_due, *next_due));
                    is_due
                }
            };
            if !is_due {
                continue;
            }
            if !nearby_found {
                self.find_nearby(index, robot.ir_reach, lists);
                nearby_found = true;
                robot.updated.proximity = true;
                if !(lists.obstacles.is_empty() && lists.robots.is_empty()) {
                    turned = self.turned(index, robot.pose);
                }
            }
            let read = self.read_proximity(
                index,
                (&lists.obstacles, &lists.robots),
                &turned,
                sensor,
                stream,
                nothing,
            );
            keep_reading(&mut robot.proximity, &mut robot.raw, s, read);
        }
    }

    /// Reads a robot's first `count` IR sensors, all due: with nothing in reach and no noise
    /// to add, readings that need no more than their streams moved on.
    #[inline]
    fn read_all_due(
        &self,
        index: usize,
        robot: &mut RobotState,
        count: usize,
        lists: &mut NearbyLists,
    ) {
        self.find_nearby(index, robot.ir_reach, lists);
        robot.updated.proximity = true;
        let nothing_near =
            lists.obstacles.is_empty() && lists.robots.is_empty() && robot.raw.is_none();
        if nothing_near && robot.ir_quiet && count == robot.ir_streams.len() {
            // Every sensor reads its far value, which has no noise: each stream owes one
            // draw more, paid when a reading next needs it (a robot alone leaves its streams'
            // memory untouched).
            robot.ir_skipped += 1;
            for (nothing, slot) in robot.ir_nothing.iter().zip(&mut robot.proximity) {
                *slot = nothing.reading;
            }
            return;
        }
        robot.ir_streams_caught_up();
        // Something is within reach unless `nothing_near`: the sensors' rays need the robot
        // turned.
        let turned = if nothing_near {
            self.placements[index]
        } else {
            self.turned(index, robot.pose)
        };
        let RobotState {
            ir_streams,
            ir_nothing,
            proximity,
            raw,
            ..
        } = &mut *robot;
        let sensors = ir_streams[..count].iter_mut().zip(ir_nothing.iter());
        if nothing_near {
            for ((stream, nothing), slot) in sensors.zip(proximity) {
                *slot = sensors::proximity_of_nothing(nothing, stream).0;
            }
            return;
        }
        let rig = &self.compiled.rig.robots[index];
        for (s, ((stream, nothing), sensor)) in sensors.zip(rig.distance_sensors.iter()).enumerate()
        {
            let read = self.read_proximity(
                index,
                (&lists.obstacles, &lists.robots),
                &turned,
                sensor,
                stream,
                nothing,
            );
            keep_reading(proximity, raw, s, read);
        }
    }

    /// One IR sensor's reading (rounded, and before rounding) from the obstacles and robots
    /// found near its robot.
    #[inline]
    fn read_proximity(
        &self,
        index: usize,
        (nearby, nearby_robots): (&[u32], &[u32]),
        turned: &Placement,
        sensor: &crate::compile::rig::DistanceSensorRig,
        stream: &mut super::noise::Stream,
        nothing: &sensors::NothingInRange,
    ) -> (u16, f64) {
        if nearby.is_empty() && nearby_robots.is_empty() {
            return sensors::proximity_of_nothing(nothing, stream);
        }
        let value = sensors::proximity_value_far(
            self.slab,
            (nearby, nearby_robots),
            (self.placements, index, turned),
            sensor,
            nothing.far,
            stream,
        );
        (sensors::to_reading(value), value)
    }

    /// Fills the lists of the static obstacles and the robots within robot `index`'s IR
    /// sensors' `reach` (m), ascending.
    #[inline(never)]
    fn find_nearby(&self, index: usize, reach: f64, lists: &mut NearbyLists) {
        let NearbyLists {
            obstacles: nearby,
            robots: nearby_robots,
        } = lists;
        let placement = &self.placements[index];
        if reach <= self.broad.statics_reach
            && self
                .broad
                .statics_clear
                .is_clear(DVec2::new(placement.x, placement.z))
        {
            // No obstacle comes within `reach`: the list the grid would give, empty.
            nearby.clear();
        } else {
            sensors::nearby_obstacles(self.slab, &self.broad.statics, placement, reach, nearby);
        }
        nearby_robots.clear();
        if self.placements.len() > 1 {
            let (lo, hi) = broad_phase::square(
                DVec2::new(placement.x, placement.z),
                reach + self.broad.max_radius,
            );
            // The grid's square holds its corners too: only robots whose bodies come within
            // reach are worth a sensor's test (in a crowd, most sensors then have none and
            // trace nothing). The centres just filed are the placements' (x, z).
            let center = DVec2::new(placement.x, placement.z);
            let (centres, radii) = (&self.broad.centres, &self.broad.radii);
            self.broad
                .robots
                .query_where(lo, hi, nearby_robots, |other| {
                    let other = other as usize;
                    other != index && centres[other].distance(center) <= reach + radii[other]
                });
        }
    }
}

/// Keeps IR sensor `s`'s reading: rounded in the Khepera API's eight slots, and before
/// rounding where the robot's raw readings are kept.
#[inline]
fn keep_reading(
    proximity: &mut [u16; 8],
    raw: &mut Option<Box<super::state::RawReadings>>,
    s: usize,
    (reading, value): (u16, f64),
) {
    if let Some(slot) = proximity.get_mut(s) {
        *slot = reading;
    }
    if let Some(raw) = raw {
        raw.distance[s] = value;
    }
}

/// Whether a sensor with `period` is due at `t`; moves its next due time on a regular grid.
fn due(next: &mut f64, t: f64, period: f64) -> bool {
    if period <= 0.0 {
        return true;
    }
    if t + 1e-12 < *next {
        return false;
    }
    *next = (libm::floor(t / period + 1e-9) + 1.0) * period;
    true
}
