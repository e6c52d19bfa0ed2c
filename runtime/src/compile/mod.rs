//! The compiler: from a typed [`Scene`] to a [`RenderGraph`], a [`SensorRig`] and a [`Plan`].
//!
//! It walks the scene from its roots with the accumulated VRML97 transform (the z-up rotation
//! first, for z-up files). Shapes become primitives, lights become lights, and each
//! `DifferentialWheels` starts a robot: everything below it is attached to the robot, with
//! frames relative to it, and its devices go to the rig.

mod bounding;
pub mod drive;
mod exported;
pub mod frames;
pub mod graph;
mod materials;
pub mod meshfile;
pub mod network;
pub mod plan;
pub mod rig;
pub mod shapes;
pub mod solids;
mod textures;
pub mod triangulate;

use std::sync::Arc;

use glam::{DMat3, DVec3};
use regatta_schema::webots::{Authoring, Objects};
use regatta_schema::{NodeId, Scene, Value};

use crate::geometry::{axis_angle, Frame};
use graph::{
    index_static, Group, GroupId, Light, LightKind, Owner, Primitive, RenderGraph, Viewpoint,
};
pub use plan::Plan;
use rig::{
    filter_set, Attenuation, CameraRenderer, CameraRig, DistanceSensorRig, LightSensorRig,
    LinearCameraRig, Optics, PanoramicRig, Pose2, RobotRig, SensorRig, TurretRig,
};
use shapes::{background_of, shape_of, Geometry};

/// World-wide settings the runtime needs.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldSettings {
    pub title: String,
    /// Seconds.
    pub time_step: f64,
    pub seed: u64,
}

/// A landmark a run reports on: a `Buoy` instance, with the centre and radius of its
/// footprint.
#[derive(Clone, Debug, PartialEq)]
pub struct Landmark {
    pub name: String,
    /// (x, z) of its centre.
    pub center: glam::DVec2,
    pub radius: f64,
    /// Luminance of its brightest emissive part (Rec. 709 weights): what makes a buoy the
    /// brightest for the `phototaxis` fitness.
    pub brightness: f64,
    /// Its primitives in the render graph.
    pub primitives: std::ops::Range<usize>,
}

/// Everything a run needs, compiled from one scene.
#[derive(Clone, Debug)]
pub struct Compiled {
    pub graph: RenderGraph,
    pub rig: SensorRig,
    pub plan: Plan,
    pub settings: WorldSettings,
    /// The buoys, in file order.
    pub landmarks: Vec<Landmark>,
    /// Things the compiler noticed and worked around (a tilted robot, a device outside a robot).
    pub warnings: Vec<String>,
}

/// Compiles a scene.
pub fn compile(scene: &Scene) -> Compiled {
    compile_with(scene, true)
}

/// [`compile`] for a run, which exports nothing: without the grouping nodes inside robots
/// (17 per Khepera, the largest part of a crowd's render graph), which only exporters read.
/// A robot's parts stand in its own group; the static groups (what a robot touches is named
/// after) are all kept. Equal materials are one entry.
pub fn compile_for_run(scene: &Scene) -> Compiled {
    compile_with(scene, false)
}

fn compile_with(scene: &Scene, robot_groups: bool) -> Compiled {
    let settings = world_settings(scene);
    let mut compiler = Compiler {
        scene,
        robot_groups,
        sensors: Default::default(),
        time_step: settings.time_step,
        graph: RenderGraph {
            primitives: Vec::new(),
            meshes: Vec::new(),
            materials: Default::default(),
            lights: Vec::new(),
            lines: Vec::new(),
            textures: Vec::new(),
            skipped: Vec::new(),
            groups: Vec::new(),
            viewpoint: None,
            background: background_of(scene),
            static_primitives: Vec::new(),
            static_index: Default::default(),
        },
        rig: SensorRig::default(),
        warnings: Vec::new(),
        materials: Default::default(),
        texture_cache: Default::default(),
        landmarks: Vec::new(),
        group: None,
        tables: Shared::default(),
        turns: Shared::default(),
        body: Authoring::World,
        robot_names: Default::default(),
    };
    let root = scene.root_rotation();
    let root_frame = Frame {
        linear: axis_angle(DVec3::new(root[0], root[1], root[2]), root[3]),
        translation: DVec3::ZERO,
    };
    for &node in &scene.roots {
        compiler.walk(node, &root_frame, Owner::Static, 0);
    }
    index_static(&mut compiler.graph);
    find_floors(&mut compiler.graph, &mut compiler.rig);
    let plan = Plan::new(&compiler.graph, &compiler.rig);
    // The graph lives as long as the simulation: no spare room (a swarm's vectors are long).
    compiler.graph.primitives.shrink_to_fit();
    compiler.graph.groups.shrink_to_fit();
    compiler.graph.materials.shrink_to_fit();
    compiler.rig.robots.shrink_to_fit();
    Compiled {
        graph: compiler.graph,
        rig: compiler.rig,
        plan,
        settings,
        landmarks: compiler.landmarks,
        warnings: compiler.warnings,
    }
}

/// The world's WorldInfo settings (defaults where it has none).
pub fn world_settings(scene: &Scene) -> WorldSettings {
    match scene.find("WorldInfo").first() {
        Some(&info) => WorldSettings {
            title: scene.string(info, "title").to_owned(),
            time_step: scene.float(info, "basicTimeStep") / 1000.0,
            seed: scene.int(info, "randomSeed").max(0) as u64,
        },
        None => WorldSettings {
            title: String::new(),
            time_step: 0.032,
            seed: 0,
        },
    }
}

struct Compiler<'s> {
    scene: &'s Scene,
    /// WorldInfo.basicTimeStep (s), read once: finding WorldInfo walks the whole scene.
    time_step: f64,
    graph: RenderGraph,
    rig: SensorRig,
    warnings: Vec<String>,
    /// Material nodes already converted, to share entries.
    materials: std::collections::HashMap<Option<NodeId>, usize>,
    /// Texture nodes already read.
    texture_cache: textures::TextureCache,
    landmarks: Vec<Landmark>,
    /// The group the walk is inside.
    group: Option<GroupId>,
    /// Sensor tables already made, to share: a swarm's thousands of sensors have a few.
    tables: Shared<[f64; 3]>,
    turns: Shared<(f64, f64, f64)>,
    /// Who wrote the children being walked (their parent's body), for the turns between
    /// axis conventions.
    body: Authoring,
    /// The robots' names so far (a second robot of a name gets a warning).
    robot_names: std::collections::HashSet<String>,
    /// The distinct sets of sensors so far, which robots share as they are read.
    sensors: rig::SharedSensors,
    /// Whether the grouping nodes inside robots are kept and equal materials kept apart
    /// ([`compile_for_run`]).
    robot_groups: bool,
}

/// A frame turned by an axis-angle rotation (`None`: unchanged).
/// A generic Webots robot without a drive stands still; its wheel and body stand-ins (m) are
/// what its kinematics and collisions use when its shapes say nothing.
const GENERIC_WHEEL_RADIUS: f64 = 0.02;
const GENERIC_BODY_RADIUS: f64 = 0.05;

fn turned(frame: &Frame, turn: Option<[f64; 4]>) -> Frame {
    match turn {
        Some(r) => frame.then(&Frame {
            linear: axis_angle(DVec3::new(r[0], r[1], r[2]), r[3]),
            translation: DVec3::ZERO,
        }),
        None => *frame,
    }
}

/// For nodes whose axes carry meaning (cameras, viewpoints, cylinder-like geometry): the
/// rotation from regatta's frame for them (y up, +x forward) to the frame a world in FLU
/// writes them in.
fn flu_to_regatta(scene: &Scene, body: Authoring) -> Option<[f64; 4]> {
    (body == Authoring::World && scene.objects.flu_geometry()).then_some([
        1.0,
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
    ])
}

/// The same for a robot's body: turned only in z-up FLU worlds (in a y-up one its y is up).
fn flu_robot_to_regatta(scene: &Scene, body: Authoring) -> Option<[f64; 4]> {
    (body == Authoring::World && scene.objects == Objects::Flu).then_some([
        1.0,
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
    ])
}

const MAX_WALK_DEPTH: usize = 256;

impl Compiler<'_> {
    fn walk(&mut self, node: NodeId, frame: &Frame, owner: Owner, depth: usize) {
        if depth > MAX_WALK_DEPTH {
            return;
        }
        let scene = self.scene;
        let axes = scene.node(node).axes;
        let frame = &turned(frame, scene.turn(self.body, axes.own));
        let outer_body = std::mem::replace(&mut self.body, axes.body);
        self.walk_axes(node, frame, owner, depth);
        self.body = outer_body;
    }

    /// [`Compiler::walk`] once the frame is in the node's own axes; `self.body` is the axes of
    /// its children.
    fn walk_axes(&mut self, node: NodeId, frame: &Frame, owner: Owner, depth: usize) {
        let scene = self.scene;
        if owner == Owner::Static && scene.node(node).proto_names().iter().any(|n| n == "Buoy") {
            let first = self.graph.primitives.len();
            self.walk_inner(node, frame, owner, depth);
            let bounds = self.graph.primitives[first..]
                .iter()
                .fold(crate::geometry::Aabb::EMPTY, |b, p| b.union(p.bounds));
            if !bounds.is_empty() {
                let number = self.landmarks.len() + 1;
                let brightness = self.graph.primitives[first..]
                    .iter()
                    .map(|p| {
                        let [r, g, b] = self.graph.materials[p.material].emissive;
                        0.2126 * r + 0.7152 * g + 0.0722 * b
                    })
                    .fold(0.0, f64::max);
                self.landmarks.push(Landmark {
                    name: format!("buoy {number}"),
                    center: glam::DVec2::new(
                        (bounds.min.x + bounds.max.x) / 2.0,
                        (bounds.min.z + bounds.max.z) / 2.0,
                    ),
                    radius: (bounds.max.x - bounds.min.x).max(bounds.max.z - bounds.min.z) / 2.0,
                    brightness,
                    primitives: first..self.graph.primitives.len(),
                });
            }
            return;
        }
        self.walk_inner(node, frame, owner, depth);
    }

    fn walk_inner(&mut self, node: NodeId, frame: &Frame, owner: Owner, depth: usize) {
        let scene = self.scene;
        let axes = scene.node(node).axes;
        match scene.type_name(node) {
            "Transform" | "Solid" | "Pose" => {
                let spec = scene.spec(node);
                let local = Frame::vrml(
                    DVec3::from_array(scene.vec3(node, "translation")),
                    scene.rotation(node, "rotation"),
                    if spec.field_index("scale").is_some() {
                        DVec3::from_array(scene.vec3(node, "scale"))
                    } else {
                        DVec3::ONE
                    },
                    if scene.spec(node).field_index("scaleOrientation").is_some() {
                        scene.rotation(node, "scaleOrientation")
                    } else {
                        [0.0, 0.0, 1.0, 0.0]
                    },
                    if scene.spec(node).field_index("center").is_some() {
                        DVec3::from_array(scene.vec3(node, "center"))
                    } else {
                        DVec3::ZERO
                    },
                );
                let frame = turned(&frame.then(&local), scene.turn(axes.own, axes.body));
                let outer = self.enter_group(node, &frame, owner, None);
                for &child in scene.children(node, "children") {
                    self.walk(child, &frame, owner, depth + 1);
                }
                self.group = outer;
            }
            "Group" | "Anchor" | "Billboard" | "Collision" => {
                let frame = &turned(frame, scene.turn(axes.own, axes.body));
                let outer = self.enter_group(node, frame, owner, None);
                for &child in scene.children(node, "children") {
                    self.walk(child, frame, owner, depth + 1);
                }
                self.group = outer;
            }
            "Robot" => self.robot(node, frame, owner, depth),
            "Switch" => {
                let which = scene.int(node, "whichChoice");
                if let Some(&child) = usize::try_from(which)
                    .ok()
                    .and_then(|i| scene.children(node, "choice").get(i))
                {
                    let outer = self.enter_group(node, frame, owner, None);
                    self.walk(child, frame, owner, depth + 1);
                    self.group = outer;
                }
            }
            "Shape" => {
                // Webots' FLU geometry: cylinders, cones and elevation grids along z.
                let frame = match scene.child(node, "geometry").map(|g| scene.type_name(g)) {
                    Some("Cylinder" | "Cone" | "ElevationGrid" | "Capsule" | "Plane") => {
                        turned(frame, flu_to_regatta(scene, axes.body))
                    }
                    _ => *frame,
                };
                self.shape(node, &frame, owner)
            }
            "CadShape" => self.cad_shape(node, frame, owner),
            "PointLight" | "DirectionalLight" | "SpotLight" => self.light(node, frame, owner),
            "Viewpoint" if owner == Owner::Static && self.graph.viewpoint.is_none() => {
                let mut local = Frame::vrml(
                    DVec3::from_array(scene.vec3(node, "position")),
                    scene.rotation(node, "orientation"),
                    DVec3::ONE,
                    [0.0, 0.0, 1.0, 0.0],
                    DVec3::ZERO,
                );
                if flu_to_regatta(scene, axes.body).is_some() {
                    // FLU viewpoints look along +x with +z up; VRML's along -z with +y up.
                    local = local.then(&Frame {
                        linear: DMat3::from_cols(
                            DVec3::new(0.0, -1.0, 0.0),
                            DVec3::new(0.0, 0.0, 1.0),
                            DVec3::new(-1.0, 0.0, 0.0),
                        ),
                        translation: DVec3::ZERO,
                    });
                }
                let description = scene.string(node, "description");
                self.graph.viewpoint = Some(Viewpoint {
                    name: if description.is_empty() {
                        group_name(scene, node)
                    } else {
                        description.to_owned()
                    },
                    frame: frame.then(&local),
                    field_of_view: scene.float(node, "fieldOfView"),
                });
            }
            "DifferentialWheels" => self.robot(node, frame, owner, depth),
            // A hinge is rigid here (a wheel's turning is not drawn): its solid stays in place.
            "HingeJoint" => {
                if let Some(end) = scene.child(node, "endPoint") {
                    self.walk(end, frame, owner, depth + 1);
                }
            }
            "DistanceSensor" | "LightSensor" | "PanoramicTurret" | "LinearCamera" | "Camera" => {
                match owner {
                    Owner::Robot(robot) => self.device(node, frame, robot),
                    Owner::Static => self.warnings.push(format!(
                        "a {} outside any robot is ignored",
                        scene.type_name(node)
                    )),
                }
                // The shapes a device carries (a Webots camera's housing) are seen.
                if scene.spec(node).field_index("children").is_some() {
                    self.open_node(node, frame, owner, depth);
                }
            }
            // Nodes kept only for what they hold, and the other devices' shapes (an LED's).
            _ if scene.spec(node).open
                || (scene.spec(node).classes.iter().any(|c| c == "device")
                    && scene.spec(node).field_index("children").is_some()) =>
            {
                self.open_node(node, frame, owner, depth)
            }
            _ => {}
        }
    }

    /// Opens a group for `node` (its children are placed in `frame`); returns the group to
    /// restore when the node's children are done.
    fn enter_group(
        &mut self,
        node: NodeId,
        frame: &Frame,
        owner: Owner,
        robot: Option<usize>,
    ) -> Option<GroupId> {
        if !self.robot_groups && owner != Owner::Static {
            return self.group;
        }
        self.graph.groups.push(Group {
            name: group_name(self.scene, node),
            parent: self.group,
            frame: *frame,
            owner,
            node,
            robot,
        });
        self.group.replace(self.graph.groups.len() - 1)
    }

    fn shape(&mut self, node: NodeId, frame: &Frame, owner: Owner) {
        let scene = self.scene;
        let Some(geometry) = scene.child(node, "geometry") else {
            self.skip(node, "", "the Shape has no geometry".to_owned());
            return;
        };
        let shape = match shape_of(scene, geometry, &mut self.graph.meshes) {
            Ok(Geometry::Shape(shape)) => shape,
            Ok(Geometry::Lines(mut lines)) => {
                lines.frame = *frame;
                lines.material = self.material(scene.child(node, "appearance"));
                lines.owner = owner;
                lines.node = node;
                lines.group = self.group;
                self.graph.lines.push(lines);
                return;
            }
            Err(reason) => {
                self.skip(node, scene.type_name(geometry), reason);
                return;
            }
        };
        let material = self.material(scene.child(node, "appearance"));
        self.place(node, shape, material, frame, owner);
    }

    /// Adds a primitive for `shape` at `frame`.
    pub(super) fn place(
        &mut self,
        node: NodeId,
        shape: graph::Shape,
        material: usize,
        frame: &Frame,
        owner: Owner,
    ) {
        let Some(inverse) = frame.inverse() else {
            self.warnings
                .push("a shape with a degenerate (zero-scale) transform is ignored".to_owned());
            self.skip(
                node,
                shape.name(),
                "its transform has a zero scale".to_owned(),
            );
            return;
        };
        let bounds = shape.bounds_under(frame, &self.graph.meshes);
        let upright = is_upright(&shape, frame);
        self.graph.primitives.push(Primitive {
            shape,
            frame: *frame,
            inverse,
            material,
            owner,
            node,
            bounds,
            group: self.group,
            upright,
        });
    }

    fn light(&mut self, node: NodeId, frame: &Frame, owner: Owner) {
        let scene = self.scene;
        let kind = match scene.type_name(node) {
            "DirectionalLight" => LightKind::Directional {
                direction: frame
                    .apply_vector(DVec3::from_array(scene.vec3(node, "direction")))
                    .normalize_or(DVec3::NEG_Y),
            },
            "PointLight" => LightKind::Point {
                location: frame.apply(DVec3::from_array(scene.vec3(node, "location"))),
                radius: scene.float(node, "radius"),
                attenuation: DVec3::from_array(scene.vec3(node, "attenuation")),
            },
            _ => LightKind::Spot {
                location: frame.apply(DVec3::from_array(scene.vec3(node, "location"))),
                direction: frame
                    .apply_vector(DVec3::from_array(scene.vec3(node, "direction")))
                    .normalize_or(DVec3::NEG_Y),
                radius: scene.float(node, "radius"),
                attenuation: DVec3::from_array(scene.vec3(node, "attenuation")),
                beam_width: scene.float(node, "beamWidth"),
                cut_off: scene.float(node, "cutOffAngle"),
            },
        };
        self.graph.lights.push(Light {
            kind,
            color: scene.vec3(node, "color"),
            intensity: scene.float(node, "intensity"),
            ambient_intensity: scene.float(node, "ambientIntensity"),
            on: scene.bool(node, "on"),
            shadows: scene.bool(node, "castShadows"),
            owner,
            node,
            group: self.group,
        });
    }

    fn robot(&mut self, node: NodeId, frame: &Frame, owner: Owner, depth: usize) {
        let scene = self.scene;
        let name = scene.string(node, "name").to_owned();
        if owner != Owner::Static {
            self.warnings
                .push(format!("robot '{name}' inside another robot is ignored"));
            return;
        }
        let axes = scene.node(node).axes;
        // The robot's own frame, its children's (its body's axes), and regatta's robot frame
        // (y up, +x forward) in which the rig places devices.
        let own = frame.then(&Frame::vrml(
            DVec3::from_array(scene.vec3(node, "translation")),
            scene.rotation(node, "rotation"),
            DVec3::ONE,
            [0.0, 0.0, 1.0, 0.0],
            DVec3::ZERO,
        ));
        let body = turned(&own, scene.turn(axes.own, axes.body));
        let to_regatta = flu_robot_to_regatta(scene, axes.body);
        // A generic Webots robot moves when its wheels make a drive; it looks where they roll.
        let generic = scene.type_name(node) == "Robot";
        let drive = generic
            .then(|| {
                let up = if to_regatta.is_some() {
                    DVec3::Z
                } else {
                    DVec3::Y
                };
                drive::infer(scene, node, up)
                    .map(|drive| (drive::body_rotation(drive.forward, up), drive))
            })
            .flatten();
        let rotation = match &drive {
            Some((rotation, _)) => *rotation,
            None => turned(&Frame::IDENTITY, to_regatta),
        };
        let robot_frame = body.then(&rotation);
        let children_frame = rotation.inverse().unwrap_or(Frame::IDENTITY);
        let forward = robot_frame.apply_vector(DVec3::X);
        let up = robot_frame.apply_vector(DVec3::Y).normalize_or_zero();
        if up.y < 0.999 {
            self.warnings.push(format!(
                "robot '{name}' is tilted; it is set upright on the floor"
            ));
        }
        let start = Pose2 {
            x: robot_frame.translation.x,
            z: robot_frame.translation.z,
            heading: libm::atan2(-forward.z, forward.x),
        };
        let time_step = self.time_step;
        // `check` refuses a period that is not a whole number of steps; compiled unchecked,
        // it is rounded to the nearest (at least one).
        let period = if generic {
            0.0
        } else {
            scene.float(node, "controlPeriod")
        };
        let control_steps = rig::control_steps(period, time_step)
            .unwrap_or_else(|ratio| (libm::round(ratio).clamp(1.0, u32::MAX as f64) as u64).max(1));
        let index = self.rig.robots.len();
        if !self.robot_names.insert(name.clone()) {
            self.warnings.push(format!(
                "two robots are named '{name}'; --robot picks the first"
            ));
        }
        // A generic robot's body is sized from its shapes once they are placed (below).
        let (wheel_radius, axle_length, max_speed) = match (&drive, generic) {
            (Some((_, drive)), _) => (drive.wheel_radius, drive.axle_length, drive.max_speed),
            (None, true) => (GENERIC_WHEEL_RADIUS, GENERIC_WHEEL_RADIUS, 0.0),
            (None, false) => (
                scene.float(node, "wheelRadius"),
                scene.float(node, "axleLength"),
                scene.float(node, "maxSpeed"),
            ),
        };
        let field = |name: &str, generic_value: f64| {
            if generic {
                generic_value
            } else {
                scene.float(node, name)
            }
        };
        self.rig.robots.push(RobotRig {
            name,
            node,
            start,
            floor_y: robot_frame.translation.y,
            wheel_radius,
            axle_length,
            encoder_resolution: field("encoderResolution", 12000.0),
            max_speed,
            wheel_speed_noise: field("wheelSpeedNoise", 0.0),
            control_steps,
            control_period: control_steps as f64 * time_step,
            body_radius: field("bodyRadius", GENERIC_BODY_RADIUS),
            body_height: field("bodyHeight", GENERIC_BODY_RADIUS),
            controller: scene.string(node, "controller").to_owned(),
            controller_args: scene.strings(node, "controllerArgs").to_vec(),
            program: None,
            floors: Vec::new(),
            drive: drive.map(|(_, drive)| drive),
            body_to_robot: children_frame,
            network: (!generic)
                .then(|| scene.child(node, "network"))
                .flatten()
                .map(|network| {
                    let panoramic = scene
                        .child(node, "turret")
                        .is_some_and(|t| scene.type_name(t) == "PanoramicTurret");
                    // A CTRNN integrates once per controller call.
                    network::network_from_scene(
                        scene,
                        network,
                        panoramic,
                        control_steps as f64 * time_step,
                    )
                }),
            distance_sensors: Default::default(),
            light_sensors: Default::default(),
            turret: None,
            cameras: Vec::new(),
        });
        // The robot's group sits where the simulation puts the robot: upright on the floor.
        let start_frame = start.frame(robot_frame.translation.y);
        let outer = self.enter_group(node, &start_frame, Owner::Static, Some(index));
        let first_part = self.graph.primitives.len();
        // Attached parts: frames relative to the robot.
        for &child in scene.children(node, "children") {
            self.walk(child, &children_frame, Owner::Robot(index), depth + 1);
        }
        self.group = outer;
        if generic && self.rig.robots[index].drive.is_some() {
            self.size_generic_body(index, first_part, &children_frame);
        } else if generic {
            // A robot that cannot move is no body either: nothing pushes it, and it pushes
            // nothing (Webots' robots without physics stand where they are written).
            self.rig.robots[index].body_radius = 0.0;
            self.rig.robots[index].body_height = 0.0;
        } else if let Some(turret) = scene.child(node, "turret") {
            self.turret(turret, index);
        }
        self.sensors.share(&mut self.rig.robots[index]);
    }

    /// A generic robot's round body: the largest horizontal half-extent and the height of its
    /// `boundingObject` (what Webots collides), else of its own shapes (its devices' and
    /// wheels' included), or a 5 cm stand-in when it has neither. A bounding object keeps
    /// what a robot only shows (a translucent sphere marking its radio's range) out of its
    /// body.
    fn size_generic_body(&mut self, index: usize, first_part: usize, frame: &Frame) {
        let node = self.rig.robots[index].node;
        let bounding = self
            .scene
            .child(node, "boundingObject")
            .map(|b| bounding::bounds(self.scene, b, frame))
            .filter(|b| b.min.x <= b.max.x && b.min.is_finite() && b.max.is_finite());
        let (mut radius, mut height) = (0.0f64, 0.0f64);
        if let Some(bounds) = bounding {
            for extent in [bounds.min.x, bounds.max.x, bounds.min.z, bounds.max.z] {
                radius = radius.max(extent.abs());
            }
            height = bounds.max.y;
        }
        for primitive in &self.graph.primitives[first_part..] {
            if bounding.is_some() || primitive.owner != Owner::Robot(index) {
                continue;
            }
            // The largest horizontal half-extent: a round body's radius (a box's corners
            // reach further, a documented approximation).
            let (lo, hi) = (primitive.bounds.min, primitive.bounds.max);
            for extent in [lo.x, hi.x, lo.z, hi.z] {
                radius = radius.max(extent.abs());
            }
            height = height.max(hi.y);
        }
        if radius > 0.0 && radius.is_finite() {
            let robot = &mut self.rig.robots[index];
            robot.body_radius = radius;
            robot.body_height = height.max(1e-3);
        }
    }

    /// A device inside a robot; `frame` is relative to the robot.
    fn device(&mut self, node: NodeId, frame: &Frame, robot: usize) {
        let scene = self.scene;
        match scene.type_name(node) {
            "DistanceSensor" => {
                let (position, direction) = device_pose(scene, node, frame);
                // A sensor looking down (the Thymio's and e-puck's ground sensors) reads the
                // floor: the 2.5-D proximity model cannot, so it is kept out of the proximity
                // slots (where it would look ahead at wheel height); regatta-webots casts it
                // in 3-D for a Webots controller.
                if direction.y < -std::f64::consts::FRAC_1_SQRT_2 {
                    return;
                }
                // On a generic Webots robot, what a field leaves unwritten is Webots' default
                // (one ray, the table [0 0 0, 0.1 1000 0]), not the Khepera's.
                let generic = scene.type_name(self.rig.robots[robot].node) == "Robot";
                let table = if generic && !written(scene, node, "lookupTable") {
                    WEBOTS_DISTANCE_TABLE.to_vec()
                } else {
                    lookup_table(scene, node)
                };
                let rays = if generic && !written(scene, node, "numberOfRays") {
                    1
                } else {
                    scene.int(node, "numberOfRays").max(1) as usize
                };
                // Webots has no `range`: on a generic Webots robot, the table's farthest row is
                // where the sensor stops seeing.
                let range = match table.last() {
                    Some(last) if generic && last[0] > 0.0 => last[0],
                    _ => scene.float(node, "range"),
                };
                let rig = DistanceSensorRig {
                    name: scene.string(node, "name").to_owned(),
                    position,
                    direction,
                    lookup: self.tables.share(table),
                    rays,
                    aperture: scene.float(node, "aperture"),
                    range,
                    period: scene.float(node, "samplingPeriod"),
                    ray_turns: self.turns.share(DistanceSensorRig::turns(
                        rays,
                        scene.float(node, "aperture"),
                    )),
                };
                Arc::make_mut(&mut self.rig.robots[robot].distance_sensors).push(rig);
            }
            "LightSensor" => {
                let (position, direction) = device_pose(scene, node, frame);
                let rig = LightSensorRig {
                    name: scene.string(node, "name").to_owned(),
                    position,
                    direction,
                    lookup: self.tables.share(lookup_table(scene, node)),
                    occlusion: scene.bool(node, "occlusion"),
                    period: scene.float(node, "samplingPeriod"),
                    attenuation: if scene.objects == regatta_schema::webots::Objects::Legacy {
                        Attenuation::Vrml97
                    } else {
                        Attenuation::Unbounded
                    },
                };
                Arc::make_mut(&mut self.rig.robots[robot].light_sensors).push(rig);
            }
            "Camera" => self.camera(node, frame, robot),
            _ => self.turret(node, robot),
        }
    }

    /// A Webots Camera on a robot: one pixel high, it is the K213 linear camera turret (as
    /// Webots' khepera_k213.wbt builds it); otherwise a 2-D camera.
    fn camera(&mut self, node: NodeId, frame: &Frame, robot: usize) {
        let scene = self.scene;
        // Webots cameras look along -z before R2022a, along +x (z up) from then.
        let look = match (scene.node(node).axes.body, scene.objects) {
            (Authoring::World, Objects::Flu | Objects::FluYUp) => {
                Some([1.0, 0.0, 0.0, std::f64::consts::FRAC_PI_2])
            }
            (Authoring::World, Objects::Legacy) => {
                Some([0.0, 1.0, 0.0, std::f64::consts::FRAC_PI_2])
            }
            _ => None,
        };
        let local = Frame::vrml(
            DVec3::from_array(scene.vec3(node, "translation")),
            scene.rotation(node, "rotation"),
            DVec3::ONE,
            [0.0, 0.0, 1.0, 0.0],
            DVec3::ZERO,
        );
        let device = turned(&frame.then(&local), look);
        let name = scene.string(node, "name").to_owned();
        let robot_name = self.rig.robots[robot].name.clone();
        let width = scene.int(node, "width").max(1) as usize;
        let height = scene.int(node, "height").max(1) as usize;
        // A generic Webots Robot's cameras are cameras whatever their size (Webots' API tests
        // use 1×1 ones); on a robot regatta knows, one pixel high is the K213 turret.
        let generic = scene.type_name(self.rig.robots[robot].node) == "Robot";
        if height == 1 && !generic {
            let forward = device.apply_vector(DVec3::X).normalize_or(DVec3::X);
            if forward.y.abs() > 1e-6 || forward.x < 1.0 - 1e-6 {
                self.warnings.push(format!(
                    "camera '{name}' of robot '{robot_name}' does not look straight ahead; the linear camera is simulated looking along the robot's heading"
                ));
            }
            if self.rig.robots[robot].turret.is_some() {
                self.warnings.push(format!(
                    "robot '{robot_name}' has two turrets; camera '{name}' is left out"
                ));
                return;
            }
            self.rig.robots[robot].turret = Some(TurretRig::Linear(LinearCameraRig {
                name,
                height: device.translation.y,
                pixels: width,
                field_of_view: scene.float(node, "fieldOfView"),
                // The K213's pixels are about 2° high (catalogue LinearCamera).
                vertical_field_of_view: 0.0349,
                samples: 1,
                bits: 8,
                period: scene.float(node, "samplingPeriod"),
            }));
            return;
        }
        if scene.string(node, "projection") != "planar" || scene.bool(node, "spherical") {
            self.warnings.push(format!(
                "camera '{name}' of robot '{robot_name}' asks for a {} projection; regatta renders it planar",
                if scene.bool(node, "spherical") { "spherical" } else { scene.string(node, "projection") }
            ));
        }
        self.rig.robots[robot].cameras.push(CameraRig {
            name,
            frame: device,
            width,
            height,
            field_of_view: scene.float(node, "fieldOfView"),
            near: scene.float(node, "near"),
            far: scene.float(node, "far"),
            noise: scene.float(node, "noise"),
            period: scene.float(node, "samplingPeriod"),
            renderer: if scene.string(node, "rendering") == "rays" {
                CameraRenderer::Rays
            } else {
                CameraRenderer::Raster
            },
        });
    }

    fn turret(&mut self, node: NodeId, robot: usize) {
        let scene = self.scene;
        if self.rig.robots[robot].turret.is_some() {
            self.warnings.push(format!(
                "robot '{}' has two turrets; the first is used",
                self.rig.robots[robot].name
            ));
            return;
        }
        let turret = match scene.type_name(node) {
            "PanoramicTurret" => {
                let roi = match scene.field(node, "regionOfInterest") {
                    Value::Ints(v) if v.len() == 2 => {
                        (v[0].clamp(0, 149) as usize, v[1].clamp(0, 149) as usize)
                    }
                    _ => (0, 149),
                };
                let (first, last) = if roi.0 <= roi.1 { roi } else { (roi.1, roi.0) };
                let i_bda = scene.float(node, "iBda");
                let bandpass = scene.vec2(node, "bandpassLambdas");
                TurretRig::Panoramic(PanoramicRig {
                    name: scene.string(node, "name").to_owned(),
                    height: scene.float(node, "height"),
                    optics: if scene.string(node, "optics") == "paper" {
                        Optics::Paper
                    } else {
                        Optics::Exact
                    },
                    samples: scene.int(node, "samples").max(1) as usize,
                    stride: scene.int(node, "stride").max(1) as usize,
                    crowd_distance: match scene.float(node, "crowdDistance") {
                        d if d > 0.0 => d,
                        _ => f64::INFINITY,
                    },
                    far_distance: match scene.float(node, "crowdFarDistance") {
                        d if d > 0.0 => d,
                        _ => f64::INFINITY,
                    },
                    keep_distance: match scene.float(node, "crowdKeepDistance") {
                        d if d > 0.0 && d.is_finite() => d,
                        _ => 0.0,
                    },
                    filters: filter_set(scene.strings(node, "filters")),
                    lambda: scene.float(node, "lambda"),
                    bandpass: (bandpass[0].min(bandpass[1]), bandpass[0].max(bandpass[1])),
                    bits: scene.int(node, "bits").clamp(1, 16) as u32,
                    i_bda: (i_bda > 0.0).then_some(i_bda),
                    roi: (first, last),
                    quantize_views: scene.bool(node, "quantizeViews"),
                    period: scene.float(node, "samplingPeriod"),
                })
            }
            _ => TurretRig::Linear(LinearCameraRig {
                name: scene.string(node, "name").to_owned(),
                height: scene.float(node, "height"),
                pixels: scene.int(node, "pixels").max(1) as usize,
                field_of_view: scene.float(node, "fieldOfView"),
                vertical_field_of_view: scene.float(node, "verticalFieldOfView"),
                samples: scene.int(node, "samples").max(1) as usize,
                bits: scene.int(node, "bits").clamp(1, 16) as u32,
                period: scene.float(node, "samplingPeriod"),
            }),
        };
        self.rig.robots[robot].turret = Some(turret);
    }
}

/// The floors each robot stands on: thin static primitives under its start whose top is at
/// the height it stands at. Webots worlds leave robots a little above or below their floor
/// (where physics let them settle): a floor top within 1 cm below the robot's origin or 2 mm
/// above it is the floor, and the robot is set on it.
fn find_floors(graph: &mut RenderGraph, rig: &mut SensorRig) {
    const BELOW: f64 = 0.01;
    const ABOVE: f64 = 0.002;
    const THIN: f64 = 0.05;
    for robot in &mut rig.robots {
        let near = |b: &crate::geometry::Aabb| {
            b.max.y >= robot.floor_y - BELOW
                && b.max.y <= robot.floor_y + ABOVE
                && b.max.y - b.min.y <= THIN
        };
        let under = |b: &crate::geometry::Aabb| {
            (b.min.x..=b.max.x).contains(&robot.start.x)
                && (b.min.z..=b.max.z).contains(&robot.start.z)
        };
        // The static primitives in graph order (a swarm has many more robot parts).
        let statics = || {
            graph
                .static_primitives
                .iter()
                .map(|&p| graph.primitives[p].bounds)
        };
        // The highest floor under the robot is the one it stands on.
        let Some(top) = statics()
            .filter(|b| near(b) && under(b))
            .map(|b| b.max.y)
            .max_by(f64::total_cmp)
        else {
            continue;
        };
        robot.floors = statics()
            .filter(|b| (b.max.y - top).abs() <= 1e-9 && b.max.y - b.min.y <= THIN)
            .map(|b| [b.min.x, b.min.z, b.max.x, b.max.z])
            .collect();
        robot.floor_y = top;
    }
    // The robots' groups sit where the simulation puts them.
    for group in &mut graph.groups {
        if let Some(robot) = group.robot {
            let robot = &rig.robots[robot];
            group.frame = robot.start.frame(robot.floor_y);
        }
    }
}

/// A group's name: its DEF name, else (for a PROTO instance) its `name` field or the PROTO's
/// name, else its `name` field, else its type.
fn group_name(scene: &Scene, node: NodeId) -> String {
    let data = scene.node(node);
    if let Some(def) = data.def_name() {
        return def.to_owned();
    }
    let name_field = match scene.spec(node).field_index("name") {
        Some(index) => match &data.fields[index] {
            Value::String(name) if !name.is_empty() => Some(name.clone()),
            _ => None,
        },
        None => None,
    };
    if let Some(proto) = data.proto_names().last() {
        return name_field.unwrap_or_else(|| proto.clone());
    }
    name_field.unwrap_or_else(|| scene.type_name(node).to_owned())
}

/// A device's position and looking direction (+x of its frame) in the robot frame.
fn device_pose(scene: &Scene, node: NodeId, frame: &Frame) -> (DVec3, DVec3) {
    let local = Frame::vrml(
        DVec3::from_array(scene.vec3(node, "translation")),
        scene.rotation(node, "rotation"),
        DVec3::ONE,
        [0.0, 0.0, 1.0, 0.0],
        DVec3::ZERO,
    );
    let device = frame.then(&local);
    (
        device.translation,
        device.apply_vector(DVec3::X).normalize_or(DVec3::X),
    )
}

/// Webots' default lookup table of a DistanceSensor: 0 at 0 m to 1000 at 0.1 m.
const WEBOTS_DISTANCE_TABLE: [[f64; 3]; 2] = [[0.0, 0.0, 0.0], [0.1, 1000.0, 0.0]];

/// Whether a node's field was written (or bound through IS) rather than defaulted.
fn written(scene: &Scene, node: NodeId, name: &str) -> bool {
    scene
        .spec(node)
        .field_index(name)
        .is_some_and(|index| scene.node(node).value_span_at(index).is_some())
}

fn lookup_table(scene: &Scene, node: NodeId) -> Vec<[f64; 3]> {
    match scene.field(node, "lookupTable") {
        Value::Vec3s(rows) => rows.clone(),
        _ => Vec::new(),
    }
}

/// Sensor tables made so far, each once: a new table bit-identical to one of them is shared.
struct Shared<T> {
    made: std::collections::HashMap<Vec<[u64; 3]>, Arc<[T]>>,
}

impl<T> Default for Shared<T> {
    fn default() -> Self {
        Shared {
            made: Default::default(),
        }
    }
}

impl<T: Copy + Bits> Shared<T> {
    fn share(&mut self, table: Vec<T>) -> Arc<[T]> {
        let key: Vec<[u64; 3]> = table.iter().map(Bits::bits).collect();
        self.made.entry(key).or_insert_with(|| table.into()).clone()
    }
}

/// The exact bits of a table row: rows are shared only when they are the same to the bit.
trait Bits {
    fn bits(&self) -> [u64; 3];
}

impl Bits for [f64; 3] {
    fn bits(&self) -> [u64; 3] {
        self.map(f64::to_bits)
    }
}

impl Bits for (f64, f64, f64) {
    fn bits(&self) -> [u64; 3] {
        [self.0.to_bits(), self.1.to_bits(), self.2.to_bits()]
    }
}

/// Whether the column renderer can draw a primitive: vertical axis, horizontal cross-section
/// a circle (cylinders, cones) or a rectangle (boxes).
fn is_upright(shape: &graph::Shape, frame: &Frame) -> bool {
    let x = frame.apply_vector(DVec3::X);
    let y = frame.apply_vector(DVec3::Y);
    let z = frame.apply_vector(DVec3::Z);
    let tolerance = 1e-9;
    let vertical =
        y.x.abs() <= tolerance * y.length() && y.z.abs() <= tolerance * y.length() && y.y > 0.0;
    let horizontal = x.y.abs() <= tolerance * x.length() && z.y.abs() <= tolerance * z.length();
    if !(vertical && horizontal) {
        return false;
    }
    match shape {
        graph::Shape::Box { .. } => true,
        graph::Shape::Cylinder { .. } => (x.length() - z.length()).abs() <= tolerance * x.length(),
        _ => false,
    }
}
