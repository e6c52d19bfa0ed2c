//! Logs as Foxglove and ROS 2 tools read them: every message of a log, read back with the
//! `mcap` crate, is decoded field by field from its channel's own `ros2msg` schema text (a
//! small reader written here from the ROS 2 and CDR rules, independent of regatta's writer);
//! each must use exactly its bytes. Then the Foxglove messages are checked for what they say:
//! the scene, the transforms against the poses, the images against the retina, the events.

use std::collections::BTreeMap;

use regatta_runtime::log::{is_ros2_topic, Channels, Recorder, RunInfo};
use regatta_runtime::sim::Simulation;

/// A decoded value.
#[derive(Clone, Debug, PartialEq)]
enum Value {
    Bool(bool),
    Int(i128),
    Float(f64),
    Str(String),
    List(Vec<Value>),
    Struct(Vec<(String, Value)>),
}

impl Value {
    fn get(&self, field: &str) -> &Value {
        match self {
            Value::Struct(fields) => {
                &fields
                    .iter()
                    .find(|(name, _)| name == field)
                    .unwrap_or_else(|| panic!("no field {field} in {self:?}"))
                    .1
            }
            _ => panic!("{field} of a non-struct"),
        }
    }
    fn f(&self) -> f64 {
        match self {
            Value::Float(x) => *x,
            Value::Int(x) => *x as f64,
            _ => panic!("not a number: {self:?}"),
        }
    }
    fn s(&self) -> &str {
        match self {
            Value::Str(s) => s,
            _ => panic!("not a string: {self:?}"),
        }
    }
    fn list(&self) -> &[Value] {
        match self {
            Value::List(items) => items,
            _ => panic!("not a list: {self:?}"),
        }
    }
}

/// One field of a message definition: type, array length (None: not an array, Some(None):
/// unbounded), name.
type Field = (String, Option<Option<usize>>, String);

/// A ros2msg schema: the main definition and its dependencies by full name.
struct Schema {
    main: Vec<Field>,
    main_package: String,
    types: BTreeMap<String, Vec<Field>>,
}

fn parse_definition(text: &str) -> Vec<Field> {
    let mut fields = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap().trim();
        if line.is_empty() {
            continue;
        }
        let mut words = line.split_whitespace();
        let (Some(kind), Some(name)) = (words.next(), words.next()) else {
            panic!("bad line {line:?}");
        };
        if name.contains('=') || words.next().is_some_and(|w| w.starts_with('=')) {
            continue; // a constant
        }
        let (base, array) = match kind.find('[') {
            Some(at) => {
                let inner = &kind[at + 1..kind.len() - 1];
                (
                    &kind[..at],
                    Some(if inner.is_empty() {
                        None
                    } else {
                        Some(inner.parse().unwrap())
                    }),
                )
            }
            None => (kind, None),
        };
        fields.push((base.to_owned(), array, name.to_owned()));
    }
    fields
}

fn parse_schema(name: &str, text: &str) -> Schema {
    let separator = format!("{}\n", "=".repeat(80));
    let mut sections = text.split(separator.as_str());
    let main = parse_definition(sections.next().unwrap());
    let mut types = BTreeMap::new();
    for section in sections {
        let (header, body) = section.split_once('\n').unwrap_or((section, ""));
        let full = header.strip_prefix("MSG: ").expect("MSG: header");
        types.insert(full.to_owned(), parse_definition(body));
    }
    Schema {
        main,
        main_package: name.split('/').next().unwrap().to_owned(),
        types,
    }
}

struct Cdr<'a> {
    data: &'a [u8],
    at: usize,
}

impl Cdr<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        // Primitives are aligned to their size, counted after the 4-byte header.
        while !(self.at - 4).is_multiple_of(n.min(8)) {
            self.at += 1;
        }
        let bytes = self
            .data
            .get(self.at..self.at + n)
            .unwrap_or_else(|| panic!("message too short at byte {}", self.at));
        self.at += n;
        bytes
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }
}

fn decode_type(schema: &Schema, package: &str, kind: &str, cdr: &mut Cdr) -> Value {
    let le = |b: &[u8]| {
        let mut a = [0u8; 16];
        a[..b.len()].copy_from_slice(b);
        a
    };
    match kind {
        "bool" => Value::Bool(cdr.take(1)[0] != 0),
        "byte" | "char" | "uint8" => Value::Int(cdr.take(1)[0] as i128),
        "int8" => Value::Int(cdr.take(1)[0] as i8 as i128),
        "int16" => Value::Int(i16::from_le_bytes(cdr.take(2).try_into().unwrap()) as i128),
        "uint16" => Value::Int(u16::from_le_bytes(cdr.take(2).try_into().unwrap()) as i128),
        "int32" => Value::Int(i32::from_le_bytes(cdr.take(4).try_into().unwrap()) as i128),
        "uint32" => Value::Int(cdr.u32() as i128),
        "int64" => Value::Int(i64::from_le_bytes(cdr.take(8).try_into().unwrap()) as i128),
        "uint64" => Value::Int(u128::from_le_bytes(le(cdr.take(8))) as i128),
        "float32" => Value::Float(f32::from_le_bytes(cdr.take(4).try_into().unwrap()) as f64),
        "float64" => Value::Float(f64::from_le_bytes(cdr.take(8).try_into().unwrap())),
        "string" => {
            let n = cdr.u32() as usize;
            assert!(n >= 1, "a CDR string holds at least its NUL");
            let at = cdr.at;
            let bytes = cdr.data.get(at..at + n).expect("string within the message");
            cdr.at += n;
            assert_eq!(bytes[n - 1], 0, "strings end with NUL");
            Value::Str(String::from_utf8(bytes[..n - 1].to_vec()).expect("UTF-8"))
        }
        "builtin_interfaces/Time" | "builtin_interfaces/Duration" => Value::Struct(vec![
            (
                "sec".into(),
                Value::Int(i32::from_le_bytes(cdr.take(4).try_into().unwrap()) as i128),
            ),
            ("nanosec".into(), Value::Int(cdr.u32() as i128)),
        ]),
        _ => {
            let full = if kind.contains('/') {
                kind.to_owned()
            } else {
                format!("{package}/{kind}")
            };
            let fields = schema
                .types
                .get(&full)
                .unwrap_or_else(|| panic!("the schema does not define {full}"));
            let package = full.split('/').next().unwrap().to_owned();
            decode_fields(schema, &package, fields, cdr)
        }
    }
}

fn decode_fields(schema: &Schema, package: &str, fields: &[Field], cdr: &mut Cdr) -> Value {
    let mut out = Vec::new();
    for (kind, array, name) in fields {
        let value = match array {
            None => decode_type(schema, package, kind, cdr),
            Some(length) => {
                let n = length.unwrap_or_else(|| cdr.u32() as usize);
                assert!(n <= cdr.data.len(), "array length {n} is past the message");
                Value::List(
                    (0..n)
                        .map(|_| decode_type(schema, package, kind, cdr))
                        .collect(),
                )
            }
        };
        out.push((name.clone(), value));
    }
    Value::Struct(out)
}

/// Decodes `data` against `schema`, which must use exactly its bytes.
fn decode(schema: &Schema, data: &[u8]) -> Value {
    assert_eq!(&data[..4], &[0, 1, 0, 0], "CDR little-endian header");
    let mut cdr = Cdr { data, at: 4 };
    let value = decode_fields(schema, &schema.main_package, &schema.main, &mut cdr);
    assert_eq!(
        cdr.at,
        data.len(),
        "the message has bytes its schema does not explain"
    );
    value
}

/// A run's log.
fn record(world: &str, steps: u64, channels: Channels) -> Vec<u8> {
    let (compiled, text) = compile(world);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    let run = RunInfo {
        world_name: "test.wbt".into(),
        world_text: text,
        seed: simulation.seed,
        lenient: false,
        steps_requested: steps,
        channels,
        controllers: Vec::new(),
        variations: None,
    };
    let mut sink = std::io::Cursor::new(Vec::new());
    let mut recorder = Recorder::new(&mut sink, &mut simulation, &run).unwrap();
    for _ in 0..steps {
        simulation.step();
        recorder.record(&simulation).unwrap();
    }
    recorder.finish(&simulation, false).unwrap();
    sink.into_inner()
}

fn compile(world: &str) -> (regatta_runtime::Compiled, String) {
    let text = if world.ends_with(".wbt") {
        std::fs::read_to_string(regatta_tests::root().join("worlds").join(world)).unwrap()
    } else {
        world.to_owned()
    };
    let checked = regatta_schema::check(
        regatta_parser::SourceText::from_bytes("test.wbt".into(), text.clone().into_bytes()),
        &regatta_schema::Options {
            strict: true,
            base_dir: Some(regatta_tests::root().join("worlds")),
            ..regatta_schema::Options::default()
        },
    );
    assert!(!checked.has_errors(), "{}", checked.render(false));
    (regatta_runtime::compile(&checked.scene), text)
}

/// Every message, decoded: (topic, schema name, log time, value), and channel metadata.
#[allow(clippy::type_complexity)]
fn read_all(
    bytes: &[u8],
) -> (
    Vec<(String, String, u64, Value)>,
    BTreeMap<String, BTreeMap<String, String>>,
) {
    let mut schemas: BTreeMap<String, Schema> = BTreeMap::new();
    let mut messages = Vec::new();
    let mut metadata = BTreeMap::new();
    for message in mcap::MessageStream::new(bytes).unwrap() {
        let message = message.unwrap();
        let schema = message
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        assert_eq!(schema.encoding, "ros2msg");
        assert_eq!(message.channel.message_encoding, "cdr");
        let parsed = schemas.entry(schema.name.clone()).or_insert_with(|| {
            parse_schema(&schema.name, std::str::from_utf8(&schema.data).unwrap())
        });
        metadata.insert(
            message.channel.topic.clone(),
            message.channel.metadata.clone(),
        );
        let value = decode(parsed, &message.data);
        messages.push((
            message.channel.topic.clone(),
            schema.name.clone(),
            message.log_time,
            value,
        ));
    }
    (messages, metadata)
}

#[test]
fn every_message_decodes_against_its_schema_and_says_what_the_run_did() {
    let steps = 400;
    let log = record("regatta.wbt", steps, Channels::ALL);
    let (messages, metadata) = read_all(&log);
    let count = |topic: &str| messages.iter().filter(|m| m.0 == topic).count();
    for topic in metadata.keys() {
        assert!(is_ros2_topic(topic), "{topic} is a valid ROS 2 topic name");
    }
    assert_eq!(count("/scene"), 1);
    assert_eq!(count("/tf"), steps as usize);
    assert_eq!(count("/khepera/world_pose"), steps as usize);
    assert_eq!(count("/khepera/retina/odd/image"), steps as usize);
    assert_eq!(metadata["/khepera/pose"]["robot"], "khepera");
    assert!(metadata["/scene"]["offered_qos_profiles"].contains("durability: 1"));

    // The scene: the world's solids and buoy numbers, the robot's body in its own frame.
    let scene = &messages.iter().find(|m| m.0 == "/scene").unwrap();
    assert_eq!(scene.1, "foxglove_msgs/msg/SceneUpdate");
    assert_eq!(scene.2, 0);
    let entities = scene.3.get("entities").list();
    let world = &entities[0];
    assert_eq!(world.get("frame_id").s(), "world");
    assert!(world.get("cubes").list().len() >= 4, "the arena's walls");
    let labels: Vec<&str> = world
        .get("texts")
        .list()
        .iter()
        .map(|t| t.get("text").s())
        .collect();
    assert_eq!(labels, ["1", "2", "3"]);
    // Buoys stand upright: their cylinders' axes are the world's z.
    for cylinder in world.get("cylinders").list() {
        let q = cylinder.get("pose").get("orientation");
        let (x, y) = (q.get("x").f(), q.get("y").f());
        assert!(
            x.abs() < 1e-9 && y.abs() < 1e-9,
            "an upright cylinder: {q:?}"
        );
        assert!(cylinder.get("size").get("z").f() > 0.0);
    }
    let robot = &entities[1];
    assert_eq!(robot.get("frame_id").s(), "khepera");
    assert_eq!(robot.get("frame_locked"), &Value::Bool(true));
    assert!(!robot.get("cylinders").list().is_empty(), "the body");

    // Transforms and poses say where regatta's own pose channel says the robot is.
    let poses: Vec<&(String, String, u64, Value)> =
        messages.iter().filter(|m| m.0 == "/khepera/pose").collect();
    let transforms: Vec<&(String, String, u64, Value)> =
        messages.iter().filter(|m| m.0 == "/tf").collect();
    for (pose, transform) in poses.iter().zip(&transforms) {
        assert_eq!(pose.2, transform.2, "same log time");
        let t = &transform.3;
        assert_eq!(t.get("parent_frame_id").s(), "world");
        assert_eq!(t.get("child_frame_id").s(), "khepera");
        let stamp = t.get("timestamp");
        assert_eq!(
            stamp.get("sec").f() as u64 * 1_000_000_000 + stamp.get("nanosec").f() as u64,
            transform.2
        );
        let (x, z, heading) = (
            pose.3.get("x").f(),
            pose.3.get("z").f(),
            pose.3.get("heading").f(),
        );
        let translation = t.get("translation");
        assert_eq!(translation.get("x").f(), x);
        assert_eq!(translation.get("y").f(), -z);
        let q = t.get("rotation");
        let yaw = 2.0 * q.get("z").f().atan2(q.get("w").f());
        let turn = (yaw - heading).rem_euclid(std::f64::consts::TAU);
        assert!(
            turn.min(std::f64::consts::TAU - turn) < 1e-9,
            "yaw {yaw} heading {heading}"
        );
    }

    // Images: one row of the region of interest, the digital values scaled to 0…255.
    let retinas: Vec<&(String, String, u64, Value)> = messages
        .iter()
        .filter(|m| m.0 == "/khepera/retina")
        .collect();
    let images: Vec<&(String, String, u64, Value)> = messages
        .iter()
        .filter(|m| m.0 == "/khepera/retina/odd/image")
        .collect();
    for (retina, image) in retinas.iter().zip(&images) {
        assert_eq!(retina.2, image.2);
        let i = &image.3;
        let digital: Vec<f64> = retina
            .3
            .get("digital")
            .list()
            .iter()
            .map(Value::f)
            .collect();
        assert_eq!(i.get("height").f(), 1.0);
        assert_eq!(i.get("width").f() as usize, digital.len());
        assert_eq!(i.get("step").f() as usize, digital.len());
        assert_eq!(i.get("encoding").s(), "mono8");
        let data: Vec<f64> = i.get("data").list().iter().map(Value::f).collect();
        for (d, p) in digital.iter().zip(&data) {
            assert_eq!(
                *p,
                (d * 255.0 / 63.0 + 0.5).floor(),
                "pixel {p} from {d} LSB"
            );
        }
    }

    // Events: one per visit, in order, named after the robot.
    let (compiled, _) = compile("regatta.wbt");
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    simulation.run(steps);
    let visits = &simulation.robots[0].visits.sequence;
    let events: Vec<&Value> = messages
        .iter()
        .filter(|m| m.0 == "/events")
        .map(|m| &m.3)
        .collect();
    assert_eq!(events.len(), visits.len());
    for (k, (event, buoy)) in events.iter().zip(visits).enumerate() {
        assert_eq!(event.get("name").s(), "khepera");
        assert_eq!(event.get("level").f(), 2.0);
        assert_eq!(
            event.get("message").s(),
            format!("visit {}: buoy {}", k + 1, buoy + 1)
        );
    }
}

#[test]
fn robot_names_become_distinct_ros2_topics() {
    let world = r#"#VRML_SIM R2023b utf8
WorldInfo { coordinateSystem "NUE" }
Arena { size 1 1 }
Khepera { name "my robot" translation 0.2 0 0.2 controller "braitenberg" }
Khepera { name "my-robot" translation -0.2 0 0.2 controller "braitenberg" }
Khepera { name "2nd" translation 0 0 -0.2 controller "braitenberg" }
"#;
    let log = record(world, 20, Channels::ALL);
    let (messages, metadata) = read_all(&log);
    for (topic, robot) in [
        ("/my_robot/pose", "my robot"),
        ("/my_robot_2/pose", "my-robot"),
        ("/robot_2nd/world_pose", "2nd"),
    ] {
        assert_eq!(
            metadata.get(topic).map(|m| m["robot"].as_str()),
            Some(robot),
            "{topic} in {:?}",
            metadata.keys()
        );
    }
    let children: std::collections::BTreeSet<&str> = messages
        .iter()
        .filter(|m| m.0 == "/tf")
        .map(|m| m.3.get("child_frame_id").s())
        .collect();
    assert_eq!(
        children.into_iter().collect::<Vec<_>>(),
        ["my_robot", "my_robot_2", "robot_2nd"]
    );
}

#[test]
fn channels_choose_what_a_log_holds_and_change_no_result() {
    let all = record("regatta.wbt", 150, Channels::ALL);
    let some = record("regatta.wbt", 150, "pose,tf,scene".parse().unwrap());
    let (all_messages, _) = read_all(&all);
    let (some_messages, metadata) = read_all(&some);
    assert_eq!(
        metadata.keys().collect::<Vec<_>>(),
        ["/khepera/pose", "/scene", "/tf"]
    );
    let of = |messages: &[(String, String, u64, Value)], topic: &str| -> Vec<Value> {
        messages
            .iter()
            .filter(|m| m.0 == topic)
            .map(|m| m.3.clone())
            .collect()
    };
    // Sensors nobody records are not computed, and that moves nothing.
    assert_eq!(
        of(&all_messages, "/khepera/pose"),
        of(&some_messages, "/khepera/pose")
    );
    assert_eq!(of(&all_messages, "/tf"), of(&some_messages, "/tf"));
    // The same world and seed give the same bytes, channels and all.
    assert!(all == record("regatta.wbt", 150, Channels::ALL));
    let read = regatta_runtime::log::read(&some).unwrap();
    assert_eq!(read.run.channels.to_string(), "pose,scene,tf");
}

/// A 2-D camera's images are `rgb8` RawImages, each the image the camera took at that step.
#[test]
fn camera_images_are_logged_as_the_camera_took_them() {
    let text =
        std::fs::read_to_string(regatta_tests::root().join("tests/data/webots/e-puck_camera.wbt"))
            .unwrap();
    let bytes = record(&text, 3, Channels::ALL);
    let (messages, metadata) = read_all(&bytes);
    let images: Vec<&Value> = messages
        .iter()
        .filter(|(topic, schema, _, _)| {
            topic == "/e_puck/camera/camera/image" && schema == "foxglove_msgs/msg/RawImage"
        })
        .map(|(_, _, _, value)| value)
        .collect();
    assert_eq!(images.len(), 3, "one image a step (samplingPeriod 0)");
    assert_eq!(metadata["/e_puck/camera/camera/image"]["robot"], "e-puck");
    let (compiled, _) = compile(&text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    simulation.sense_everything();
    simulation.step();
    let taken = &simulation.robots[0].cameras[0].image.rgb;
    let first = images[0];
    assert_eq!(first.get("width").f(), 52.0);
    assert_eq!(first.get("height").f(), 39.0);
    assert_eq!(first.get("encoding").s(), "rgb8");
    assert_eq!(first.get("step").f(), 156.0);
    let data: Vec<u8> = first
        .get("data")
        .list()
        .iter()
        .map(|v| v.f() as u8)
        .collect();
    assert_eq!(&data, taken);
    // Without the images channel, no image is taken (nor logged).
    let bytes = record(&text, 3, "regatta".parse().unwrap());
    let (messages, _) = read_all(&bytes);
    assert!(messages.iter().all(|(topic, ..)| !topic.contains("camera")));
}

/// A log cut anywhere (a crash, a full disk) keeps its complete chunks, and chunks close
/// every `CHUNK_SECONDS` of simulated time: what is lost is at most the last chunk's span.
#[test]
fn a_log_cut_short_keeps_all_but_its_last_seconds() {
    use regatta_runtime::log::CHUNK_SECONDS;
    let steps = 1900; // 60.8 s of 32 ms steps: six chunks
    let log = record("regatta.wbt", steps, Channels::ALL);
    let whole = regatta_runtime::log::read(&log).unwrap();
    assert!(whole.truncated.is_none());
    let end = whole.messages.iter().map(|m| m.1).max().unwrap() as f64 * 1e-9;
    for fraction in [0.3, 0.6, 0.9] {
        let cut = (log.len() as f64 * fraction) as usize;
        let kept = regatta_runtime::log::read(&log[..cut]).unwrap();
        assert!(kept.truncated.is_some(), "a log cut at {cut} bytes says so");
        let last = kept.messages.iter().map(|m| m.1).max().unwrap_or(0) as f64 * 1e-9;
        // The chunks before the cut are whole: the time they reach is the cut's place in the
        // run, less at most one chunk (the messages are spread evenly over the run).
        let expected = end * fraction;
        assert!(
            last >= expected - CHUNK_SECONDS - 1.0,
            "cut at {fraction} of the file: messages up to {last} s kept, expected about {expected} s"
        );
    }
}
