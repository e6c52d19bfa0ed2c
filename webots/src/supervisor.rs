//! A supervisor's view of the world: nodes by DEF name, fields read and written, positions,
//! orientations and velocities, resets and the simulation mode, answered from the typed scene
//! (kept for the run when a robot is a supervisor) and the running simulation.
//!
//! What a change does: a robot's `translation` and `rotation` move it (on the floor: the
//! height stays, the turn about the vertical is kept), its `customData` reaches its controller
//! at its next step; any other field keeps the value written, which later reads return, and
//! changes nothing simulated (a documented difference: the render graph is compiled once).
//! Nodes inside a PROTO's body are found by `get_from_proto_def` only, as in Webots.

use std::collections::HashMap;

use glam::{DMat3, DQuat, DVec3};
use regatta_runtime::compile::frames::local_frame;
use regatta_runtime::geometry::Frame;
use regatta_runtime::sim::Simulation;
use regatta_schema::{BaseType, FieldType, NodeId, Scene, Value};

use crate::protocol::{request, FrameError, Reader, Writer};

/// The simulation modes (`WbSimulationMode`).
pub const MODE_PAUSE: u32 = 0;
pub const MODE_REAL_TIME: u32 = 1;
pub const MODE_FAST: u32 = 2;

/// The supervisor's state over a run.
pub struct Supervisor {
    scene: Scene,
    z_up: bool,
    /// DEF names outside PROTO bodies, first in the scene's order.
    defs: HashMap<String, NodeId>,
    /// Whether each node lies inside a PROTO's body.
    internal: Vec<bool>,
    /// Each node's frame in its robot's (a robot's descendants) or the world's (file axes).
    frames: Vec<Option<(Option<usize>, Frame)>>,
    /// Robot node → robot index, and each robot's node, start heading and start rotation.
    robots: HashMap<NodeId, usize>,
    robot_nodes: Vec<NodeId>,
    start_headings: Vec<f64>,
    /// Fields handed out: (node, field index).
    fields: Vec<(NodeId, usize)>,
    written: HashMap<(NodeId, usize), Value>,
    /// Each robot's custom data, and whether a supervisor changed it since its last reply.
    pub custom_data: Vec<String>,
    pub custom_data_changed: Vec<bool>,
    pub mode: u32,
    /// Set by `wb_supervisor_simulation_quit`.
    pub quit: Option<i32>,
    /// Each robot's rotation as a supervisor last set it (file axes), with its heading then.
    orientations: Vec<Option<(DMat3, f64)>>,
}

/// Whether a node has a field `name` of type `ty`.
fn typed_field(scene: &Scene, node: NodeId, name: &str, ty: &str) -> bool {
    let spec = scene.spec(node);
    spec.field_index(name)
        .is_some_and(|i| spec.fields[i].type_name == ty)
}

/// Whether a node has a frame of its own: an SFVec3f `translation` and an SFRotation
/// `rotation` (a TextureTransform's are two-dimensional).
fn has_frame(scene: &Scene, node: NodeId) -> bool {
    typed_field(scene, node, "translation", "SFVec3f")
        && typed_field(scene, node, "rotation", "SFRotation")
}

impl Supervisor {
    /// The supervisor's view of `scene`, whose robots are the simulation's (in rig order).
    pub fn new(scene: Scene, simulation: &Simulation) -> Supervisor {
        let robot_nodes: Vec<NodeId> = simulation
            .compiled
            .rig
            .robots
            .iter()
            .map(|r| r.node)
            .collect();
        let robots = robot_nodes
            .iter()
            .enumerate()
            .map(|(i, &n)| (n, i))
            .collect();
        let mut supervisor = Supervisor {
            z_up: scene.up_axis == regatta_schema::UpAxis::Z,
            defs: HashMap::new(),
            internal: vec![false; scene.nodes.len()],
            frames: vec![None; scene.nodes.len()],
            robots,
            custom_data: robot_nodes
                .iter()
                .map(|&n| {
                    if typed_field(&scene, n, "customData", "SFString") {
                        scene.string(n, "customData").to_owned()
                    } else {
                        String::new()
                    }
                })
                .collect(),
            custom_data_changed: vec![false; robot_nodes.len()],
            start_headings: simulation.robots.iter().map(|r| r.pose.heading).collect(),
            robot_nodes,
            fields: Vec::new(),
            written: HashMap::new(),
            mode: MODE_FAST,
            quit: None,
            orientations: vec![None; simulation.robots.len()],
            scene,
        };
        for &root in &supervisor.scene.roots.clone() {
            supervisor.visit(root, None, &Frame::IDENTITY, None, 0);
        }
        for id in supervisor.scene.walk() {
            let node = supervisor.scene.node(id);
            if let (Some(def), false) = (node.def_name(), supervisor.internal[id.index()]) {
                supervisor.defs.entry(def.to_owned()).or_insert(id);
            }
        }
        supervisor
    }

    /// Records frames (in the file's axes) and which nodes are inside PROTO bodies.
    fn visit(
        &mut self,
        id: NodeId,
        robot: Option<usize>,
        frame: &Frame,
        body_file: Option<regatta_schema::FileId>,
        depth: usize,
    ) {
        if depth > 256 {
            return;
        }
        let node = self.scene.node(id);
        if let Some(file) = body_file {
            if node.origin.file != file {
                self.internal[id.index()] = true;
            }
        }
        let (robot, frame) = match self.robots.get(&id) {
            // A robot's parts are placed relative to it: it moves.
            Some(&index) => (Some(index), Frame::IDENTITY),
            None if has_frame(&self.scene, id) => {
                (robot, frame.then(&local_frame(&self.scene, id)))
            }
            None => (robot, *frame),
        };
        self.frames[id.index()] = Some((robot, frame));
        // Inside a PROTO instance, nodes written in the PROTO's file are its body's.
        let body_file = if node.proto_names().is_empty() {
            body_file
        } else {
            Some(node.origin.file)
        };
        let children: Vec<NodeId> = node.fields.own().flat_map(|v| v.nodes().to_vec()).collect();
        for child in children {
            self.visit(child, robot, &frame, body_file, depth + 1);
        }
    }

    /// The node a controller names by its id (its arena index plus one).
    fn node(&self, id: u32) -> Option<NodeId> {
        let index = id.checked_sub(1)?;
        ((index as usize) < self.scene.nodes.len()).then_some(NodeId(index))
    }

    /// A robot's rotation as a supervisor last set it, and its heading then.
    pub fn orientation(&self, robot: usize) -> Option<(DMat3, f64)> {
        self.orientations.get(robot).copied().flatten()
    }

    /// North as a supervisor set `WorldInfo.coordinateSystem`, if it did.
    pub fn north(&self) -> Option<DVec3> {
        self.written.iter().find_map(|(&(node, index), value)| {
            let name = &self.scene.spec(node).fields[index].name;
            match (self.scene.type_name(node), name.as_str(), value) {
                ("WorldInfo", "coordinateSystem", Value::String(system)) => {
                    Some(crate::devices::north_for(system, self.z_up))
                }
                _ => None,
            }
        })
    }

    /// A robot's frame now, in the file's axes: where it stands, turned as it has turned.
    fn robot_frame(&self, robot: usize, simulation: &Simulation) -> Frame {
        let node = self.robot_nodes[robot];
        let pose = simulation.robots[robot].pose;
        let floor = simulation.compiled.rig.robots[robot].floor_y;
        let (rotation, since) = self.orientation(robot).unwrap_or((
            local_frame(&self.scene, node).linear,
            self.start_headings[robot],
        ));
        let up = if self.z_up { DVec3::Z } else { DVec3::Y };
        Frame {
            linear: DMat3::from_quat(DQuat::from_axis_angle(up, pose.heading - since)) * rotation,
            translation: self.regatta_to_file(DVec3::new(pose.x, floor, pose.z)),
        }
    }

    /// regatta's y-up world to the file's axes.
    fn regatta_to_file(&self, p: DVec3) -> DVec3 {
        if self.z_up {
            DVec3::new(p.x, -p.z, p.y)
        } else {
            p
        }
    }

    /// The file's axes to regatta's y-up world.
    fn file_to_regatta(&self, p: DVec3) -> DVec3 {
        if self.z_up {
            DVec3::new(p.x, p.z, -p.y)
        } else {
            p
        }
    }

    fn world_frame(&self, id: NodeId, simulation: &Simulation) -> Frame {
        if let Some(&robot) = self.robots.get(&id) {
            return self.robot_frame(robot, simulation);
        }
        match self.frames.get(id.index()).copied().flatten() {
            Some((Some(robot), relative)) => self.robot_frame(robot, simulation).then(&relative),
            Some((None, frame)) => frame,
            None => Frame::IDENTITY,
        }
    }

    /// Answers one request (the payload after its kind byte) into `answer`.
    pub fn answer(
        &mut self,
        payload: &[u8],
        requester: usize,
        simulation: &mut Simulation,
        answer: &mut Writer,
    ) -> Result<(), FrameError> {
        let mut r = Reader::new(payload);
        let op = r.u8()?;
        answer.clear();
        match op {
            request::SELF => answer.u32(self.robot_nodes[requester].index() as u32 + 1),
            request::FROM_DEF => {
                let name = r.str()?;
                answer.u32(self.defs.get(&name).map_or(0, |n| n.index() as u32 + 1));
            }
            request::FROM_PROTO_DEF => {
                let node = self.node(r.u32()?);
                let name = r.str()?;
                let found = node
                    .filter(|&n| !self.scene.node(n).proto_names().is_empty())
                    .and_then(|n| self.find_inside(n, &name));
                answer.u32(found.map_or(0, |n| n.index() as u32 + 1));
            }
            request::NODE_INFO => match self.node(r.u32()?) {
                Some(n) => {
                    let node = self.scene.node(n);
                    let base = self.scene.type_name(n).to_owned();
                    answer.str(node.proto_names().first().unwrap_or(&base));
                    answer.str(&base);
                    answer.str(node.def_name().unwrap_or(""));
                    answer.u8(u8::from(!node.proto_names().is_empty()));
                }
                None => {
                    answer.str("");
                    answer.str("");
                    answer.str("");
                    answer.u8(0);
                }
            },
            request::FIELD => {
                let node = self.node(r.u32()?);
                let name = r.str()?;
                let found = node.and_then(|n| {
                    let spec = self.scene.spec(n);
                    let index = spec.field_index(&name)?;
                    Some((n, index, field_code(&spec.fields[index].type_name)))
                });
                match found {
                    Some((n, index, code)) => {
                        self.fields.push((n, index));
                        answer.u32(self.fields.len() as u32);
                        answer.u8(code);
                    }
                    None => {
                        answer.u32(0);
                        answer.u8(0);
                    }
                }
            }
            request::FIELD_GET => {
                let field = r.u32()? as usize;
                let (numbers, text) = match field.checked_sub(1).and_then(|f| self.fields.get(f)) {
                    Some(&(n, index)) => self.field_value(n, index, simulation),
                    None => (Vec::new(), String::new()),
                };
                answer.u8(numbers.len() as u8);
                for x in numbers {
                    answer.f64(x);
                }
                answer.str(&text);
            }
            request::FIELD_SET => {
                let field = r.u32()? as usize;
                let count = r.u8()? as usize;
                let mut numbers = Vec::with_capacity(count);
                for _ in 0..count {
                    numbers.push(r.f64()?);
                }
                let text = r.str()?;
                if let Some(&(n, index)) = field.checked_sub(1).and_then(|f| self.fields.get(f)) {
                    self.set_field(n, index, &numbers, text, simulation);
                }
            }
            request::NODE_STATE => {
                let node = self.node(r.u32()?);
                let (position, orientation, velocity) = match node {
                    Some(n) => self.state(n, simulation),
                    None => ([f64::NAN; 3], [f64::NAN; 9], [f64::NAN; 6]),
                };
                for x in position.iter().chain(&orientation).chain(&velocity) {
                    answer.f64(*x);
                }
            }
            request::SET_VELOCITY => {
                let _node = r.u32()?;
                for _ in 0..6 {
                    r.f64()?;
                }
                eprintln!("warning: wb_supervisor_node_set_velocity(): regatta's robots are kinematic; their wheels set their speed");
            }
            // Kinematic robots have no momentum: a physics reset changes nothing.
            request::RESET_PHYSICS => {
                r.u32()?;
            }
            request::SIMULATION_RESET_PHYSICS => {}
            request::SIMULATION_RESET => {
                for (index, robot) in simulation.robots.iter_mut().enumerate() {
                    robot.pose = simulation.compiled.rig.robots[index].start;
                }
                self.written.clear();
            }
            request::SIMULATION_MODE => self.mode = r.u32()?,
            request::SIMULATION_QUIT => self.quit = Some(r.u32()? as i32),
            _ => return Err(FrameError::Short(0)),
        }
        Ok(())
    }

    fn find_inside(&self, root: NodeId, name: &str) -> Option<NodeId> {
        let mut stack = vec![root];
        let mut seen = 0;
        while let Some(id) = stack.pop() {
            seen += 1;
            if seen > self.scene.nodes.len() {
                break;
            }
            let node = self.scene.node(id);
            if id != root && node.def_name() == Some(name) {
                return Some(id);
            }
            for value in node.fields.own() {
                stack.extend(value.nodes().iter().rev());
            }
        }
        None
    }

    fn field_value(
        &self,
        node: NodeId,
        index: usize,
        simulation: &Simulation,
    ) -> (Vec<f64>, String) {
        let name = self.scene.spec(node).fields[index].name.as_str();
        if let Some(&robot) = self.robots.get(&node) {
            match name {
                "translation" => {
                    let frame = self.robot_frame(robot, simulation);
                    return (frame.translation.to_array().to_vec(), String::new());
                }
                "rotation" => {
                    let frame = self.robot_frame(robot, simulation);
                    let (axis, angle) = DQuat::from_mat3(&frame.linear).to_axis_angle();
                    return (vec![axis.x, axis.y, axis.z, angle], String::new());
                }
                "customData" => return (Vec::new(), self.custom_data[robot].clone()),
                _ => {}
            }
        }
        let value = self
            .written
            .get(&(node, index))
            .cloned()
            .unwrap_or_else(|| self.scene.node(node).fields[index].clone());
        match value {
            Value::Bool(b) => (vec![f64::from(u8::from(b))], String::new()),
            Value::Int(i) => (vec![f64::from(i)], String::new()),
            Value::Float(x) => (vec![x], String::new()),
            Value::Vec2(v) => (v.to_vec(), String::new()),
            Value::Vec3(v) => (v.to_vec(), String::new()),
            Value::Rotation(v) => (v.to_vec(), String::new()),
            Value::String(s) => (Vec::new(), s),
            Value::Node(n) => (
                vec![n.map_or(0.0, |n| (n.index() + 1) as f64)],
                String::new(),
            ),
            _ => (Vec::new(), String::new()),
        }
    }

    fn set_field(
        &mut self,
        node: NodeId,
        index: usize,
        numbers: &[f64],
        text: String,
        simulation: &mut Simulation,
    ) {
        let name = self.scene.spec(node).fields[index].name.clone();
        if let Some(&robot) = self.robots.get(&node) {
            match (name.as_str(), numbers.len()) {
                ("translation", 3) => {
                    let p = self.file_to_regatta(DVec3::from_slice(numbers));
                    let pose = &mut simulation.robots[robot].pose;
                    pose.x = p.x;
                    pose.z = p.z;
                    return;
                }
                ("rotation", 4) => {
                    // The turn about the vertical the new rotation makes from the written one.
                    let up = if self.z_up { DVec3::Z } else { DVec3::Y };
                    let axis = DVec3::from_slice(&numbers[..3]).normalize_or(up);
                    let new = DMat3::from_quat(DQuat::from_axis_angle(axis, numbers[3]));
                    let start = local_frame(&self.scene, node).linear;
                    let yaw = |m: DMat3| {
                        let f = m * DVec3::X;
                        let (a, b) = if self.z_up { (f.x, f.y) } else { (f.x, -f.z) };
                        libm::atan2(b, a)
                    };
                    let heading = self.start_headings[robot] + yaw(new) - yaw(start);
                    simulation.robots[robot].pose.heading = heading;
                    self.orientations[robot] = Some((new, heading));
                    return;
                }
                ("customData", _) => {
                    self.custom_data[robot] = text;
                    self.custom_data_changed[robot] = true;
                    return;
                }
                _ => {}
            }
        }
        let current = &self.scene.node(node).fields[index];
        let value = match (current, numbers) {
            (Value::Bool(_), [x]) => Value::Bool(*x != 0.0),
            (Value::Int(_), [x]) => Value::Int(*x as i32),
            (Value::Float(_), [x]) => Value::Float(*x),
            (Value::Vec2(_), [a, b]) => Value::Vec2([*a, *b]),
            (Value::Vec3(_), [a, b, c]) => Value::Vec3([*a, *b, *c]),
            (Value::Rotation(_), [a, b, c, d]) => Value::Rotation([*a, *b, *c, *d]),
            (Value::String(_), []) => Value::String(text),
            _ => return,
        };
        self.written.insert((node, index), value);
    }

    fn state(&self, node: NodeId, simulation: &Simulation) -> ([f64; 3], [f64; 9], [f64; 6]) {
        let frame = self.world_frame(node, simulation);
        let m = frame.linear;
        let orientation = [
            m.x_axis.x, m.y_axis.x, m.z_axis.x, m.x_axis.y, m.y_axis.y, m.z_axis.y, m.x_axis.z,
            m.y_axis.z, m.z_axis.z,
        ];
        let mut velocity = [0.0; 6];
        if let Some(&robot) = self.robots.get(&node) {
            let state = &simulation.robots[robot];
            let rig = &simulation.compiled.rig.robots[robot];
            let (left, right) = state.wheel_velocity.unwrap_or((0.0, 0.0));
            let forward = self.regatta_to_file(state.pose.forward()) * 0.5 * (left + right);
            let up = if self.z_up { DVec3::Z } else { DVec3::Y };
            let turning = if rig.axle_length > 0.0 {
                up * (right - left) / rig.axle_length
            } else {
                DVec3::ZERO
            };
            velocity = [
                forward.x, forward.y, forward.z, turning.x, turning.y, turning.z,
            ];
        }
        (frame.translation.to_array(), orientation, velocity)
    }
}

/// `WbFieldType` of a catalogue type name.
fn field_code(type_name: &str) -> u8 {
    let Some(ty) = FieldType::parse(type_name) else {
        return 0;
    };
    let base = match ty.base {
        BaseType::Bool => 1,
        BaseType::Int32 => 2,
        BaseType::Float => 3,
        BaseType::Vec2f => 4,
        BaseType::Vec3f => 5,
        BaseType::Rotation => 6,
        BaseType::Color => 7,
        BaseType::String => 8,
        BaseType::Node => 9,
        _ => return 0,
    };
    if ty.multi {
        0x10 + base
    } else {
        base
    }
}
