//! Drawing a trial's values: each from the trial's seed through a stream of its own, written
//! into the world text at the parser's spans (as `--set` is), then checked, compiled and
//! tested for a world that no longer makes sense (a robot inside a buoy, a buoy outside the
//! arena), which is drawn again.
//!
//! The edited text is the trial's world: a log embeds it, so `replay --verify` re-runs the
//! drawn values without knowing they were drawn.

use glam::DVec2;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256StarStar;
use regatta_parser::syntax::{BodyItem, FieldValue, Node, NodeKind};
use regatta_runtime::sim::world2d::Slab;
use regatta_runtime::Compiled;
use serde::Serialize;

use super::spec::{How, Variation, VaryError};
use crate::world::{apply, set_field, world_nodes};

/// A text edit: the byte range replaced and its replacement.
type Edit = (usize, usize, String);

/// How many draws a trial may take before its variations are refused.
pub const TRIES: usize = 100;

/// One value a trial drew: the `index`-th node (from 1, in file order) of type or DEF name
/// `node` had `field` set to `value` (world-language text). A count has index 0, field
/// `count` and the value `K of N: I J …`, the nodes kept by their index.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Drawn {
    pub node: String,
    pub index: usize,
    pub field: String,
    pub value: String,
}

impl Drawn {
    /// `Buoy[2].translation`: the column name of CSV rows; `Buoy.count` for a count.
    pub fn key(&self) -> String {
        if self.index == 0 {
            format!("{}.{}", self.node, self.field)
        } else {
            format!("{}[{}].{}", self.node, self.index, self.field)
        }
    }
}

/// Variations ready to draw for a world: targets found, the arena measured, and what the
/// world itself already gets wrong (left alone: only what a draw breaks is drawn again).
#[derive(Clone, Debug)]
pub struct Plan {
    variations: Vec<Variation>,
    /// The world text (overrides applied) the draws edit.
    text: String,
    z_up: bool,
    /// The floor inside the walls, (x, z) of y-up: the bounding box of every static obstacle
    /// that is not a buoy.
    arena: Option<(DVec2, DVec2)>,
    base_problems: Vec<String>,
}

/// The stream a trial's variations draw from: separate from every stream of the simulation,
/// so drawing moves none of them.
fn stream(seed: u64) -> Xoshiro256StarStar {
    // "variatio" in ASCII, mixed by SplitMix64 inside seed_from_u64.
    Xoshiro256StarStar::seed_from_u64(seed ^ 0x7661_7269_6174_696f)
}

fn uniform(rng: &mut Xoshiro256StarStar) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A number as world text: the shortest text that reads back to the same bits.
fn text_of(v: f64) -> String {
    format!("{v:?}")
}

/// The value text of `node`'s field `field` where the file writes it.
fn written<'t>(node: &Node, field: &str, text: &'t str) -> Option<&'t str> {
    let NodeKind::Instance {
        body: Some(body), ..
    } = &node.kind
    else {
        return None;
    };
    body.items.iter().rev().find_map(|item| match item {
        BodyItem::Field(f) if f.name.text == field => match &f.value {
            FieldValue::Value(v) => text.get(v.span.start as usize..v.span.end as usize),
            _ => None,
        },
        _ => None,
    })
}

/// The world's nodes a variation applies to, in file order.
fn targets<'a>(file: &'a regatta_parser::syntax::SourceFile, node: &str) -> Vec<&'a Node> {
    world_nodes(file)
        .into_iter()
        .filter(|n| match &n.kind {
            NodeKind::Instance { type_name, .. } => {
                type_name.text == node || n.def.as_ref().is_some_and(|d| d.text == node)
            }
            NodeKind::Use(_) => false,
        })
        .collect()
}

fn line_of(text: &str, offset: u32) -> usize {
    text[..(offset as usize).min(text.len())]
        .matches('\n')
        .count()
        + 1
}

impl Plan {
    /// Prepares `variations` for the world `text` compiled as `base` (`z_up`: the file is
    /// ENU). Each variation is tried alone once through `check`, so a field that does not
    /// exist or does not take such a value is refused at the variation that names it.
    pub fn new<T>(
        variations: Vec<Variation>,
        text: &str,
        base: &Compiled,
        z_up: bool,
        check: &mut dyn FnMut(&str) -> Result<T, String>,
    ) -> Result<Plan, VaryError> {
        for (i, v) in variations.iter().enumerate() {
            if let Some(first) = variations[..i]
                .iter()
                .find(|w| w.node == v.node && w.field == v.field)
            {
                return Err(VaryError::Unfit {
                    origin: v.origin.clone(),
                    reason: format!(
                        "{}.{} is already varied by {}",
                        v.node, v.field, first.origin
                    ),
                });
            }
        }
        let arena = arena_of(base);
        let plan = Plan {
            variations,
            text: text.to_owned(),
            z_up,
            arena,
            base_problems: problems(base, arena),
        };
        let parsed = regatta_parser::parse(text);
        for v in &plan.variations {
            // Alone, and each of a choice's values once: a value the field does not take is
            // refused now rather than in the trial that happens to draw it.
            let alone: Vec<Variation> = match &v.how {
                How::Choice(values) => values
                    .iter()
                    .map(|value| Variation {
                        how: How::Choice(vec![value.clone()]),
                        ..v.clone()
                    })
                    .collect(),
                // The fewest nodes kept is the likeliest to break a USE of one taken out.
                How::Count(counts) => {
                    let mut extremes: Vec<usize> = (counts.iter().min().into_iter())
                        .chain(counts.iter().max())
                        .copied()
                        .collect();
                    extremes.dedup();
                    extremes
                        .into_iter()
                        .map(|count| Variation {
                            how: How::Count(vec![count]),
                            ..v.clone()
                        })
                        .collect()
                }
                _ => vec![v.clone()],
            };
            for one in alone {
                let trial = Plan {
                    variations: vec![one],
                    ..plan.clone()
                };
                let (edits, _) = trial.edits(&parsed.file, &mut stream(0))?;
                check(&apply(text, edits)).map_err(|rendered| VaryError::Check {
                    origins: v.origin.to_string(),
                    rendered,
                })?;
            }
        }
        Ok(plan)
    }

    pub fn variations(&self) -> &[Variation] {
        &self.variations
    }

    /// Where every variation was written, for a refusal that concerns them all.
    fn origins(&self) -> String {
        let all: Vec<String> = self
            .variations
            .iter()
            .map(|v| v.origin.to_string())
            .collect();
        all.join(", ")
    }

    /// The world of the trial under `seed`: its text, what `check` made of it, and the values
    /// drawn. A draw that breaks the world is drawn again from the same stream, up to
    /// [`TRIES`] times.
    pub fn draw<T>(
        &self,
        seed: u64,
        check: &mut dyn FnMut(&str) -> Result<T, String>,
        compiled: impl Fn(&T) -> &Compiled,
    ) -> Result<(String, T, Vec<Drawn>), VaryError> {
        let parsed = regatta_parser::parse(&self.text);
        let mut rng = stream(seed);
        let mut last = String::new();
        for _ in 0..TRIES {
            let (edits, drawn) = self.edits(&parsed.file, &mut rng)?;
            let text = apply(&self.text, edits);
            let checked = check(&text).map_err(|rendered| VaryError::Check {
                origins: self.origins(),
                rendered,
            })?;
            let broken = problems(compiled(&checked), self.arena)
                .into_iter()
                .find(|p| !self.base_problems.contains(p));
            match broken {
                None => return Ok((text, checked, drawn)),
                Some(problem) => last = problem,
            }
        }
        Err(VaryError::Broken {
            origins: self.origins(),
            tries: TRIES,
            seed,
            reason: last,
        })
    }

    /// The text edits of one draw of every variation: first the counts, as declared (the
    /// nodes they take out are out of every later draw), then the others as declared, each
    /// over its nodes in file order.
    fn edits(
        &self,
        file: &regatta_parser::syntax::SourceFile,
        rng: &mut Xoshiro256StarStar,
    ) -> Result<(Vec<Edit>, Vec<Drawn>), VaryError> {
        let mut edits = Vec::new();
        let mut drawn = Vec::new();
        let counts = self
            .variations
            .iter()
            .filter(|v| matches!(v.how, How::Count(_)));
        let fields = self
            .variations
            .iter()
            .filter(|v| !matches!(v.how, How::Count(_)));
        let mut removed: Vec<(u32, u32)> = Vec::new();
        let is_removed = |node: &Node, removed: &[(u32, u32)]| {
            removed
                .iter()
                .any(|&(start, end)| node.span.start >= start && node.span.end <= end)
        };
        for v in counts.chain(fields) {
            let nodes: Vec<&Node> = targets(file, &v.node)
                .into_iter()
                .filter(|n| !is_removed(n, &removed))
                .collect();
            if nodes.is_empty() {
                return Err(VaryError::NoSuchNode {
                    origin: v.origin.clone(),
                    node: v.node.clone(),
                });
            }
            if let How::Count(ref choices) = v.how {
                let kept = self.kept(v, choices, nodes.len(), rng)?;
                for (index, node) in nodes.iter().enumerate() {
                    if !kept.contains(&index) {
                        edits.push((
                            node.span.start as usize,
                            node.span.end as usize,
                            String::new(),
                        ));
                        removed.push((node.span.start, node.span.end));
                    }
                }
                let list: Vec<String> = kept.iter().map(|i| (i + 1).to_string()).collect();
                drawn.push(Drawn {
                    node: v.node.clone(),
                    index: 0,
                    field: v.field.clone(),
                    value: format!("{} of {}: {}", kept.len(), nodes.len(), list.join(" ")),
                });
                continue;
            }
            for (index, node) in nodes.into_iter().enumerate() {
                let value = self.value(v, node, rng)?;
                set_field(node, &v.field, &value, &mut edits);
                drawn.push(Drawn {
                    node: v.node.clone(),
                    index: index + 1,
                    field: v.field.clone(),
                    value,
                });
            }
        }
        Ok((edits, drawn))
    }

    /// Which of `total` nodes a count keeps (their positions, increasing): the count drawn
    /// among `choices`, then that many nodes drawn without replacement.
    fn kept(
        &self,
        v: &Variation,
        choices: &[usize],
        total: usize,
        rng: &mut Xoshiro256StarStar,
    ) -> Result<Vec<usize>, VaryError> {
        let k = (uniform(rng) * choices.len() as f64) as usize;
        let Some(&count) = choices.get(k.min(choices.len().saturating_sub(1))) else {
            return Err(VaryError::Unfit {
                origin: v.origin.clone(),
                reason: "a count of no values".to_owned(),
            });
        };
        if count > total {
            return Err(VaryError::Unfit {
                origin: v.origin.clone(),
                reason: format!(
                    "the world has {total} {} node{}, fewer than {count} to keep",
                    v.node,
                    if total == 1 { "" } else { "s" }
                ),
            });
        }
        // A partial Fisher-Yates shuffle: the first `count` positions are the kept ones.
        let mut order: Vec<usize> = (0..total).collect();
        for i in 0..count {
            let j = i + ((uniform(rng) * (total - i) as f64) as usize).min(total - i - 1);
            order.swap(i, j);
        }
        let mut kept = order[..count].to_vec();
        kept.sort_unstable();
        Ok(kept)
    }

    /// The numbers `node` writes for the variation's field; a `translation` not written is
    /// the origin (VRML's default for every node that has one).
    fn base(&self, v: &Variation, node: &Node) -> Result<Vec<f64>, VaryError> {
        let unwritten = || VaryError::Unwritten {
            origin: v.origin.clone(),
            node: v.node.clone(),
            line: line_of(&self.text, node.span.start),
            field: v.field.clone(),
        };
        match written(node, &v.field, &self.text) {
            Some(text) => text
                .replace(',', " ")
                .split_whitespace()
                .map(|n| n.parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .filter(|n| !n.is_empty())
                .ok_or_else(|| VaryError::Unfit {
                    origin: v.origin.clone(),
                    reason: format!(
                        "{} at line {} writes '{}' as {text}, not numbers",
                        v.node,
                        line_of(&self.text, node.span.start),
                        v.field
                    ),
                }),
            None if v.field == "translation" => Ok(vec![0.0; 3]),
            None => Err(unwritten()),
        }
    }

    /// One node's drawn value, as world text.
    fn value(
        &self,
        v: &Variation,
        node: &Node,
        rng: &mut Xoshiro256StarStar,
    ) -> Result<String, VaryError> {
        let unfit = |reason: String| VaryError::Unfit {
            origin: v.origin.clone(),
            reason,
        };
        let numbers = |n: &[f64]| n.iter().map(|&x| text_of(x)).collect::<Vec<_>>().join(" ");
        // The horizontal components of a position in the file's axes.
        let (h0, h1) = if self.z_up { (0, 1) } else { (0, 2) };
        Ok(match v.how {
            How::Range(lo, hi) => text_of(lo + (hi - lo) * uniform(rng)),
            How::Jitter(d) => {
                let mut n = self.base(v, node)?;
                let mut jitter = |x: &mut f64| *x += d * (2.0 * uniform(rng) - 1.0);
                match n.len() {
                    1 | 2 => n.iter_mut().for_each(&mut jitter),
                    3 => {
                        jitter(&mut n[h0]);
                        jitter(&mut n[h1]);
                    }
                    4 => jitter(&mut n[3]),
                    count => {
                        return Err(unfit(format!(
                            "'{}' holds {count} numbers; a jitter moves a scalar, a position or a rotation's angle",
                            v.field
                        )))
                    }
                }
                numbers(&n)
            }
            How::Arena => {
                let Some((lo, hi)) = self.arena else {
                    return Err(unfit(
                        "the world has no walls around its floor to draw a position inside"
                            .to_owned(),
                    ));
                };
                let mut n = self.base(v, node)?;
                if n.len() != 3 {
                    return Err(unfit(format!("'{}' is not a position", v.field)));
                }
                let x = lo.x + (hi.x - lo.x) * uniform(rng);
                let z = lo.y + (hi.y - lo.y) * uniform(rng);
                // Files with z up map (x, y, z) to regatta's (x, z, −y).
                n[h0] = x;
                n[h1] = if self.z_up { -z } else { z };
                numbers(&n)
            }
            How::Choice(ref values) => {
                let k = (uniform(rng) * values.len() as f64) as usize;
                match values.get(k.min(values.len().saturating_sub(1))) {
                    Some(value) => value.clone(),
                    None => return Err(unfit("a choice of no values".to_owned())),
                }
            }
            How::Count(_) => {
                return Err(unfit(
                    "a count keeps nodes; it sets no field's value".to_owned(),
                ))
            }
            How::AnyHeading => {
                let angle = std::f64::consts::PI * (2.0 * uniform(rng) - 1.0);
                let axis = if self.z_up { "0 0 1" } else { "0 1 0" };
                format!("{axis} {}", text_of(angle))
            }
        })
    }
}

/// The floor inside the walls: the box of every static obstacle that is not a buoy.
fn arena_of(compiled: &Compiled) -> Option<(DVec2, DVec2)> {
    let slab = Slab::new(&compiled.graph, &compiled.rig);
    let mut bounds: Option<(DVec2, DVec2)> = None;
    for obstacle in &slab.obstacles {
        if landmark_of(compiled, obstacle.primitive).is_some() {
            continue;
        }
        let (c, r) = obstacle.shape.bounding_circle();
        let corners: Vec<DVec2> = match obstacle.shape {
            regatta_runtime::sim::world2d::Footprint::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                .iter()
                .map(|&(a, b)| center + u * (a * half_u) + v * (b * half_v))
                .collect(),
            _ => vec![c - DVec2::splat(r), c + DVec2::splat(r)],
        };
        for p in corners {
            bounds = Some(match bounds {
                None => (p, p),
                Some((lo, hi)) => (lo.min(p), hi.max(p)),
            });
        }
    }
    bounds.filter(|(lo, hi)| hi.x > lo.x && hi.y > lo.y)
}

fn landmark_of(compiled: &Compiled, primitive: usize) -> Option<usize> {
    compiled
        .landmarks
        .iter()
        .position(|l| l.primitives.contains(&primitive))
}

fn inside(arena: (DVec2, DVec2), p: DVec2) -> bool {
    p.x > arena.0.x && p.x < arena.1.x && p.y > arena.0.y && p.y < arena.1.y
}

/// What makes no sense in a compiled world: robots starting inside an obstacle, a buoy or
/// each other, or outside the arena; buoys outside the arena, in a wall or in each other.
fn problems(compiled: &Compiled, arena: Option<(DVec2, DVec2)>) -> Vec<String> {
    let slab = Slab::new(&compiled.graph, &compiled.rig);
    let mut found = Vec::new();
    let buoy = |l: usize| {
        let name = &compiled.landmarks[l].name;
        if *name == format!("buoy {}", l + 1) {
            name.clone()
        } else {
            format!("buoy {} ('{name}')", l + 1)
        }
    };
    let what = |primitive: usize| match landmark_of(compiled, primitive) {
        Some(l) => buoy(l),
        None => "a wall or obstacle".to_owned(),
    };
    let robots = &compiled.rig.robots;
    for (i, robot) in robots.iter().enumerate() {
        let c = DVec2::new(robot.start.x, robot.start.z);
        if let Some(o) = slab
            .obstacles
            .iter()
            .find(|o| o.shape.penetration(c, robot.body_radius).is_some())
        {
            found.push(format!(
                "robot '{}' starts inside {}",
                robot.name,
                what(o.primitive)
            ));
        }
        if arena.is_some_and(|a| !inside(a, c)) {
            found.push(format!("robot '{}' starts outside the arena", robot.name));
        }
        for other in &robots[..i] {
            let d = c.distance(DVec2::new(other.start.x, other.start.z));
            if d < robot.body_radius + other.body_radius {
                found.push(format!(
                    "robots '{}' and '{}' overlap",
                    other.name, robot.name
                ));
            }
        }
    }
    let buoy_name = buoy;
    for (i, buoy) in compiled.landmarks.iter().enumerate() {
        if arena.is_some_and(|a| !inside(a, buoy.center)) {
            found.push(format!("{} stands outside the arena", buoy_name(i)));
            continue;
        }
        if slab.obstacles.iter().any(|o| {
            landmark_of(compiled, o.primitive).is_none()
                && o.shape.penetration(buoy.center, buoy.radius).is_some()
        }) {
            found.push(format!("{} stands in a wall", buoy_name(i)));
        }
        for (j, other) in compiled.landmarks[..i].iter().enumerate() {
            if buoy.center.distance(other.center) < buoy.radius + other.radius {
                found.push(format!("buoys {} and {} overlap", j + 1, i + 1));
            }
        }
    }
    found
}
