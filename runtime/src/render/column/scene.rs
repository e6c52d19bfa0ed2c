//! The column renderer's scene: the upright objects of a graph (the static ones placed once,
//! with what may hide their corners), robot parts to place, and lights and fast shading
//! cached while no light moves; and the frame of one step, every robot's parts placed once
//! for every viewer. What one eye sees of it is `sweep.rs`'s; integrating it,
//! `integrate/`'s.

use std::sync::{Arc, OnceLock};

use glam::DVec2;

use super::super::{world_lights, Poses, WorldLight};
use super::crowd::CrowdGrid;
use super::footprint::{corner_hiders, corner_of, upright_of, Hider, Upright};
use super::shading::{FastShade, Shades};
use crate::compile::graph::{Owner, RenderGraph};
use crate::compile::plan::Plan;
use crate::compile::rig::Placement;
use crate::geometry::{Footprint, Frame};

/// The upright objects of a graph. Immutable once built, so every viewer of a step can render
/// from it at once; each thread keeps its own working buffers ([`Workspace`]).
pub struct ColumnScene<'g> {
    pub(super) graph: &'g RenderGraph,
    /// The static objects, shared by every frame.
    pub(super) statics: Arc<[Upright]>,
    /// Whether each primitive is in the plan's visible set, and in its robot's own.
    pub(super) visible: Vec<bool>,
    pub(super) own_visible: Vec<bool>,
    /// Whether any robot part is seen by its own robot's devices (else frames keep no `own`).
    any_own_visible: bool,
    /// Whether every static object has fast shading (lights that do not move).
    pub(super) statics_fast: bool,
    /// Primitives attached to robots, in graph order, with their robot.
    pub(super) robot_parts: Vec<(usize, usize)>,
    /// Each robot's entries of `robot_parts`, when every robot's are contiguous (the crowd
    /// level of detail then visits the near robots' parts only).
    pub(super) parts_of: Option<Vec<std::ops::Range<usize>>>,
    /// Lights and every primitive's fast shading, when no light moves (shared by every frame).
    pub(super) cached: Option<(Arc<[WorldLight]>, Arc<Shades>)>,
    /// Per static object, what may hide its corners' silhouette edges.
    pub(super) hiders: Vec<Vec<Hider>>,
    /// Per static object, whether its footprint is the previous one's (a lamp on its buoy).
    pub(super) same_footprint: Vec<bool>,
    /// Per static object, whether an eye may leave it out when it is behind the strip: no
    /// corner test names it (robot parts always may).
    pub(super) cullable: Vec<bool>,
    /// The groups of static objects that may become one impostor: a round object no corner
    /// test names and those after it sharing its footprint (a buoy and its lamp). Found once,
    /// so that a look tests each far buoy with its lamp in a tight loop over this list.
    pub(super) rounds: Vec<Round>,
    /// Per static object, 1 + the index in `rounds` of the group it starts; 0 for the others.
    pub(super) round_at: Vec<u32>,
    /// The far distance's shortcut: the round groups binned by centre, so that a look with a
    /// far distance tells only those it may reach; the static objects in no round group; the
    /// round groups widest first (a wide one far away is drawn exactly, not left out).
    pub(super) round_index: RoundIndex,
    /// Per entry of `robot_parts`, whether the part is tucked under its robot's body: within
    /// [`TUCK`] of the body's round footprint and no higher than it (a Khepera's wheels). The
    /// crowd level of detail leaves such parts of other robots out.
    pub(super) tucked: Vec<bool>,
    /// A floor that walls stand on, for the crowd level of detail ([`Floor`]).
    pub(super) floor: Option<Floor>,
}

/// A static box seen from above (a floor) and the boxes standing on it (walls): their
/// footprints within its own, their bottoms at or below its top. Where an eye above the floor
/// has walls as tall as it is all across its strip, every sight line meets a wall before the
/// floor's edge, and the wall hides the floor from there on: what shows of the floor is then
/// what is left below the horizon once every other object is drawn, the ground a column
/// fills last, and the crowd level of detail draws it so (`sweep.rs`) instead of crossing it
/// in every column.
pub(super) struct Floor {
    /// The floor's place among the static objects.
    pub(super) order: usize,
    /// Per static object, whether it is one of the floor's walls.
    pub(super) walls: Vec<bool>,
}

impl Floor {
    /// The first static box with a top that has walls standing on it.
    fn find(statics: &[Upright]) -> Option<Floor> {
        statics.iter().enumerate().find_map(|(order, floor)| {
            let Footprint::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } = floor.footprint
            else {
                return None;
            };
            if !floor.top {
                return None;
            }
            // Within the floor's footprint, to rounding: a wall's outer face may be the floor's
            // edge (an arena's), and a sight line meets its inner face first.
            let within = |p: DVec2| {
                let offset = p - center;
                offset.dot(u).abs() <= half_u * (1.0 + 1e-9)
                    && offset.dot(v).abs() <= half_v * (1.0 + 1e-9)
            };
            let walls: Vec<bool> = statics
                .iter()
                .enumerate()
                .map(|(k, wall)| {
                    k != order
                        && wall.side
                        && wall.y0 <= floor.y1
                        && matches!(wall.footprint, Footprint::Rect { .. })
                        && (0..4)
                            .all(|corner| corner_of(&wall.footprint, corner).is_some_and(within))
                })
                .collect();
            walls.contains(&true).then_some(Floor { order, walls })
        })
    }
}

/// How far (m) a tucked part may reach beyond its robot's body: a Khepera's wheel corners
/// stick out 1.6 mm.
pub(super) const TUCK: f64 = 0.002;

/// The world placed for one step: the static objects, and every robot's parts placed once —
/// as other robots see them, and as their own turret does. Shared by every viewer of the step.
#[derive(Clone)]
pub struct ColumnFrame {
    pub(super) statics: Arc<[Upright]>,
    /// Per entry of the scene's `robot_parts`: the part placed, if other robots see it.
    pub(super) others: Vec<Option<Upright>>,
    /// Per entry of the scene's `robot_parts`: the part placed, if its own turret sees it;
    /// empty when no robot sees a part of its own (a crowd's 300 kB of `None`s saved).
    pub(super) own: Vec<Option<Upright>>,
    /// The robot of each entry.
    pub(super) part_robot: Vec<usize>,
    /// Where each robot stands (x, z).
    pub(super) robot_at: Vec<DVec2>,
    /// Each robot's heading with its cosine and sine, worked out once for every viewer.
    pub(super) turns: Vec<(f64, f64, f64)>,
    /// The robots binned for the crowd level of detail, by the first look that needs it.
    pub(super) crowd: OnceLock<Box<CrowdGrid>>,
    pub(super) lights: Arc<[WorldLight]>,
    pub(super) shades: Arc<Shades>,
    /// Whether every object of the frame has fast shading.
    pub(super) all_fast: bool,
    /// Whose frame this is when one viewer made it ([`ColumnScene::prepare`]).
    pub viewer: Option<usize>,
}

impl ColumnFrame {
    /// The cosine and sine of `heading`, from the frame where it is `viewer`'s.
    #[inline]
    pub(super) fn turn(&self, viewer: Option<usize>, heading: f64) -> (f64, f64) {
        match viewer.and_then(|v| self.turns.get(v)) {
            Some(&(known, cos, sin)) if known.to_bits() == heading.to_bits() => (cos, sin),
            _ => {
                let (sin, cos) = libm::sincos(heading);
                (cos, sin)
            }
        }
    }

    /// The fast shading of a primitive, if it has one.
    #[inline]
    pub(super) fn fast_shade(&self, primitive: u32) -> Option<&FastShade> {
        self.shades.get(primitive)
    }
}

impl<'g> ColumnScene<'g> {
    pub fn new(graph: &'g RenderGraph, plan: &Plan) -> ColumnScene<'g> {
        let statics: Arc<[Upright]> = plan
            .visible
            .iter()
            .filter(|&&p| graph.primitives[p].owner == Owner::Static)
            .filter_map(|&p| upright_of(graph, p, &graph.primitives[p].frame))
            .collect();
        let mut visible = vec![false; graph.primitives.len()];
        for &p in &plan.visible {
            visible[p] = true;
        }
        let mut own_visible = vec![false; graph.primitives.len()];
        for &p in plan.own_visible.iter().flatten() {
            own_visible[p] = true;
        }
        let robot_parts: Vec<(usize, usize)> = (0..graph.primitives.len())
            .filter_map(|p| match graph.primitives[p].owner {
                Owner::Robot(robot) => Some((p, robot)),
                Owner::Static => None,
            })
            .collect();
        let parts_of = contiguous_parts(&robot_parts);
        let tucked = tucked_parts(graph, &robot_parts);
        // With every light static, lighting is the same each frame: shade once.
        let static_lights = plan
            .lights
            .iter()
            .all(|&l| graph.lights[l].owner == Owner::Static);
        let cached = static_lights.then(|| {
            let lights = world_lights(graph, plan, &Poses::default());
            let mut shades = Shades::default();
            shades.fill(graph, 0..graph.primitives.len(), &lights);
            (Arc::from(lights), Arc::new(shades))
        });
        let hiders = corner_hiders(&statics);
        let same_footprint: Vec<bool> = (0..statics.len())
            .map(|i| i > 0 && statics[i].footprint == statics[i - 1].footprint)
            .collect();
        let statics_fast = cached.as_ref().is_some_and(|(_, shades)| {
            statics
                .iter()
                .all(|u| shades.get(u.primitive as u32).is_some())
        });
        let mut cullable: Vec<bool> = hiders.iter().map(Vec::is_empty).collect();
        for hider in hiders.iter().flatten() {
            cullable[hider.object as usize] = false;
        }
        let (rounds, round_at) = round_groups(&statics, &same_footprint, &cullable);
        let round_index = RoundIndex::new(&rounds, statics.len());
        let floor = Floor::find(&statics);
        ColumnScene {
            floor,
            round_index,
            rounds,
            round_at,
            graph,
            any_own_visible: own_visible.iter().any(|&own| own),
            own_visible,
            statics_fast,
            cullable,
            hiders,
            same_footprint,
            statics,
            visible,
            robot_parts,
            parts_of,
            cached,
            tucked,
        }
    }

    /// The frame for one viewer (`None`: every robot's parts as others see them).
    pub fn prepare(&self, plan: &Plan, poses: &Poses, viewer: Option<usize>) -> ColumnFrame {
        let mut frame = self.empty_frame();
        self.prepare_into(plan, poses, &mut frame);
        frame.viewer = viewer;
        frame
    }

    /// A frame with nothing placed yet.
    pub fn empty_frame(&self) -> ColumnFrame {
        ColumnFrame {
            statics: self.statics.clone(),
            others: Vec::new(),
            own: Vec::new(),
            part_robot: Vec::new(),
            robot_at: Vec::new(),
            turns: Vec::new(),
            crowd: OnceLock::new(),
            lights: self
                .cached
                .as_ref()
                .map_or_else(|| Arc::from([]), |(lights, _)| lights.clone()),
            shades: self
                .cached
                .as_ref()
                .map_or_else(Default::default, |(_, shades)| shades.clone()),
            all_fast: false,
            viewer: None,
        }
    }

    /// Places every robot's parts for `poses` into `frame`, reusing its buffers: once per
    /// step, for every viewer.
    pub fn prepare_into(&self, plan: &Plan, poses: &Poses, frame: &mut ColumnFrame) {
        self.prepare_placed(plan, poses, &[], false, frame);
    }

    /// [`ColumnScene::prepare_into`] with each robot's placement for the step, when there is
    /// one per pose: its heading's sine and cosine (`libm`'s, as `Pose2::placement` works
    /// them out) are not worked out again. `crowd_looks_only`: every look of this frame is
    /// a crowd look, which leaves out other robots' tucked parts (then not placed at all).
    pub fn prepare_placed(
        &self,
        plan: &Plan,
        poses: &Poses,
        placements: &[Placement],
        crowd_looks_only: bool,
        frame: &mut ColumnFrame,
    ) {
        if !Arc::ptr_eq(&frame.statics, &self.statics) {
            frame.statics = self.statics.clone();
        }
        frame.others.clear();
        frame.own.clear();
        // One entry per robot part, every step: no room to spare (a crowd has thousands).
        frame.others.reserve_exact(self.robot_parts.len());
        if self.any_own_visible {
            frame.own.reserve_exact(self.robot_parts.len());
        }
        frame.robot_at.clear();
        frame
            .robot_at
            .extend(poses.poses.iter().map(|p| DVec2::new(p.x, p.z)));
        frame.turns.clear();
        if placements.len() == poses.poses.len() {
            frame.turns.extend(
                poses
                    .poses
                    .iter()
                    .zip(placements)
                    .map(|(p, placed)| (p.heading, placed.cos, placed.sin)),
            );
        } else {
            frame.turns.extend(poses.poses.iter().map(|p| {
                let (sin, cos) = libm::sincos(p.heading);
                (p.heading, cos, sin)
            }));
        }
        frame.crowd = OnceLock::new();
        if frame.part_robot.len() != self.robot_parts.len() {
            frame.part_robot.clear();
            frame
                .part_robot
                .extend(self.robot_parts.iter().map(|&(_, robot)| robot));
        }
        // A robot's parts come together: its frame (a sine and a cosine) is made once for
        // them all.
        let mut robot_frame: Option<(usize, Frame)> = None;
        for (entry, &(index, robot)) in self.robot_parts.iter().enumerate() {
            let (mut other, mut own) = (None, None);
            if robot < poses.poses.len() {
                let primitive = &self.graph.primitives[index];
                let own_wanted = self.own_visible[index];
                let other_wanted = self.visible[index] && !(crowd_looks_only && self.tucked[entry]);
                if other_wanted || own_wanted {
                    let pose = match robot_frame {
                        Some((of, pose)) if of == robot => pose,
                        _ => {
                            let (_, cos, sin) = frame.turns[robot];
                            let pose =
                                poses.poses[robot].frame_turned(poses.floor_y[robot], (sin, cos));
                            robot_frame = Some((robot, pose));
                            pose
                        }
                    };
                    let placed = pose.then(&primitive.frame);
                    let upright = upright_of(self.graph, index, &placed);
                    other = upright.filter(|_| other_wanted);
                    own = upright.filter(|_| own_wanted);
                }
            }
            frame.others.push(other);
            if self.any_own_visible {
                frame.own.push(own);
            }
        }
        match &self.cached {
            Some((lights, shades)) => {
                if !Arc::ptr_eq(&frame.lights, lights) {
                    frame.lights = lights.clone();
                }
                if !Arc::ptr_eq(&frame.shades, shades) {
                    frame.shades = shades.clone();
                }
            }
            None => {
                let lights = world_lights(self.graph, plan, poses);
                let mut shades = std::mem::take(Arc::make_mut(&mut frame.shades));
                shades.fill(self.graph, 0..self.graph.primitives.len(), &lights);
                frame.shades = Arc::new(shades);
                frame.lights = Arc::from(lights);
            }
        }
        let shades = &frame.shades;
        let fast = |u: &Upright| shades.get(u.primitive as u32).is_some();
        let statics_fast = match &self.cached {
            Some(_) => self.statics_fast,
            None => frame.statics.iter().all(fast),
        };
        // The tucked parts left unplaced count as placed: a tucked part is upright in every
        // pose (`tucked_parts`), so whether the frame is all fast is what it was with them.
        let tucked_fast = !crowd_looks_only
            || self
                .robot_parts
                .iter()
                .zip(&self.tucked)
                .all(|(&(index, robot), &tucked)| {
                    !tucked
                        || robot >= poses.poses.len()
                        || !self.visible[index]
                        || shades.get(index as u32).is_some()
                });
        frame.all_fast = statics_fast
            && tucked_fast
            && frame.others.iter().chain(&frame.own).flatten().all(fast);
    }
}

/// Static objects that may become one impostor: the first (round, and named by no corner test,
/// not sharing the previous one's footprint) and the objects right after it sharing its
/// footprint; with their heights together.
#[derive(Clone, Copy, Debug)]
pub(super) struct Round {
    pub(super) center: DVec2,
    pub(super) radius: f64,
    pub(super) y0: f64,
    pub(super) y1: f64,
    pub(super) first: u32,
    pub(super) pieces: u32,
}

/// Where the round groups are, for a look with a far distance ([`ColumnScene::round_index`]).
pub(super) struct RoundIndex {
    /// Each group's centre, and the groups binned by it (1 m cells).
    pub(super) centers: Vec<DVec2>,
    pub(super) grid: CrowdGrid,
    /// The static objects in no round group, ascending.
    pub(super) loose: Vec<u32>,
    /// The groups by radius, widest first (a radius that is not a number first).
    pub(super) widest: Vec<u32>,
    /// The groups whose centre is not finite: the grid cannot say where they are.
    pub(super) unplaced: Vec<u32>,
}

impl RoundIndex {
    fn new(rounds: &[Round], statics: usize) -> RoundIndex {
        let centers: Vec<DVec2> = rounds.iter().map(|r| r.center).collect();
        let mut grouped = vec![false; statics];
        for round in rounds {
            grouped[round.first as usize..(round.first + round.pieces) as usize].fill(true);
        }
        let mut widest: Vec<u32> = (0..rounds.len() as u32).collect();
        let radius = |k: u32| {
            let r = rounds[k as usize].radius;
            if r.is_nan() {
                f64::INFINITY
            } else {
                r
            }
        };
        widest.sort_by(|&a, &b| radius(b).total_cmp(&radius(a)).then(a.cmp(&b)));
        RoundIndex {
            grid: CrowdGrid::new(&centers, 1.0),
            centers,
            loose: (0..statics as u32)
                .filter(|&s| !grouped[s as usize])
                .collect(),
            widest,
            unplaced: (0..rounds.len() as u32)
                .filter(|&k| !rounds[k as usize].center.is_finite())
                .collect(),
        }
    }
}

/// The round groups of `statics` (see [`ColumnScene::rounds`]), and per static object 1 + the
/// index of the group it starts (0: none).
fn round_groups(
    statics: &[Upright],
    same_footprint: &[bool],
    cullable: &[bool],
) -> (Vec<Round>, Vec<u32>) {
    let (mut rounds, mut round_at) = (Vec::new(), vec![0u32; statics.len()]);
    for (first, object) in statics.iter().enumerate() {
        let Footprint::Circle { center, radius } = object.footprint else {
            continue;
        };
        if !cullable[first] || same_footprint[first] {
            continue;
        }
        let more = same_footprint[first + 1..]
            .iter()
            .take_while(|&&same| same)
            .count();
        let group = &statics[first..first + 1 + more];
        rounds.push(Round {
            center,
            radius,
            y0: group.iter().map(|u| u.y0).fold(f64::INFINITY, f64::min),
            y1: group.iter().map(|u| u.y1).fold(f64::NEG_INFINITY, f64::max),
            first: first as u32,
            pieces: group.len() as u32,
        });
        round_at[first] = rounds.len() as u32;
    }
    (rounds, round_at)
}

/// Per entry of `parts` (primitive, robot), whether it is tucked under its robot's body, the
/// robot's part with the widest round footprint: its footprint within [`TUCK`] of the body's
/// and its top no higher. Robot parts are placed in the robot's frame: the relation holds in
/// every pose.
fn tucked_parts(graph: &RenderGraph, parts: &[(usize, usize)]) -> Vec<bool> {
    // Placed twice rather than kept: a large swarm's parts would raise the peak memory.
    let local = |p: usize| upright_of(graph, p, &graph.primitives[p].frame);
    let mut body: Vec<Option<(DVec2, f64, f64)>> = Vec::new();
    for &(p, robot) in parts {
        if body.len() <= robot {
            body.resize(robot + 1, None);
        }
        if let Some(Upright {
            footprint: Footprint::Circle { center, radius },
            y1,
            side: true,
            ..
        }) = local(p)
        {
            if body[robot].is_none_or(|(_, widest, _)| radius > widest) {
                body[robot] = Some((center, radius, y1));
            }
        }
    }
    parts
        .iter()
        .map(|&(p, robot)| {
            let (Some((center, radius, top)), Some(part)) = (body[robot], local(p)) else {
                return false;
            };
            let within = |point: DVec2| point.distance(center) <= radius + TUCK;
            let inside = match part.footprint {
                Footprint::Circle {
                    center: c,
                    radius: r,
                } => r < radius && c.distance(center) + r <= radius + TUCK,
                Footprint::Rect {
                    center: c,
                    u,
                    v,
                    half_u,
                    half_v,
                } => [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                    .iter()
                    .all(|&(a, b)| within(c + u * (a * half_u) + v * (b * half_v))),
            };
            inside && part.y1 <= top
        })
        .collect()
}

/// Each robot's range of entries in `parts` (primitive, robot), when each robot's entries are
/// contiguous; `None` otherwise.
fn contiguous_parts(parts: &[(usize, usize)]) -> Option<Vec<std::ops::Range<usize>>> {
    let robots = parts.iter().map(|&(_, robot)| robot + 1).max().unwrap_or(0);
    let mut ranges = vec![0..0; robots];
    let mut seen = vec![false; robots];
    let mut start = 0;
    for (index, &(_, robot)) in parts.iter().enumerate() {
        let ends_run = parts.get(index + 1).is_none_or(|&(_, next)| next != robot);
        if ends_run {
            if seen[robot] {
                return None;
            }
            seen[robot] = true;
            ranges[robot] = start..index + 1;
            start = index + 1;
        }
    }
    Some(ranges)
}
