//! Field types and typed field values.

use std::fmt;

/// Handle of a node in the scene (`Scene::nodes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

impl NodeId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The element type of a field, shared by its SF and MF forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BaseType {
    Bool,
    Int32,
    Float,
    Time,
    Vec2f,
    Vec3f,
    Color,
    Rotation,
    String,
    Node,
    Image,
}

impl BaseType {
    /// How many numbers one item takes, for numeric types.
    pub fn arity(self) -> usize {
        match self {
            BaseType::Int32 | BaseType::Float | BaseType::Time => 1,
            BaseType::Vec2f => 2,
            BaseType::Vec3f | BaseType::Color => 3,
            BaseType::Rotation => 4,
            BaseType::Bool | BaseType::String | BaseType::Node | BaseType::Image => 1,
        }
    }

    /// Whether items are written as numbers.
    pub fn is_numeric(self) -> bool {
        matches!(
            self,
            BaseType::Int32
                | BaseType::Float
                | BaseType::Time
                | BaseType::Vec2f
                | BaseType::Vec3f
                | BaseType::Color
                | BaseType::Rotation
                | BaseType::Image
        )
    }

    /// What one item is called in Webots' messages: "Expected floating point value".
    pub fn item_noun(self) -> &'static str {
        match self {
            BaseType::Bool => "boolean value",
            BaseType::Int32 | BaseType::Image => "integer value",
            BaseType::Float
            | BaseType::Time
            | BaseType::Vec2f
            | BaseType::Vec3f
            | BaseType::Color
            | BaseType::Rotation => "floating point value",
            BaseType::String => "string value",
            BaseType::Node => "node or PROTO name",
        }
    }
}

/// A field type: `SFVec3f`, `MFNode`…
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FieldType {
    pub multi: bool,
    pub base: BaseType,
}

impl FieldType {
    /// Reads `SFVec3f`, `MFString`…; Webots' double-precision names map to the float ones.
    pub fn parse(name: &str) -> Option<FieldType> {
        let multi = match name.get(..2)? {
            "SF" => false,
            "MF" => true,
            _ => return None,
        };
        let base = match &name[2..] {
            "Bool" => BaseType::Bool,
            "Int32" => BaseType::Int32,
            "Float" | "Double" => BaseType::Float,
            "Time" => BaseType::Time,
            "Vec2f" | "Vec2d" => BaseType::Vec2f,
            "Vec3f" | "Vec3d" => BaseType::Vec3f,
            "Color" => BaseType::Color,
            "Rotation" => BaseType::Rotation,
            "String" => BaseType::String,
            "Node" => BaseType::Node,
            "Image" if !multi => BaseType::Image,
            _ => return None,
        };
        Some(FieldType { multi, base })
    }
}

impl fmt::Display for FieldType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let prefix = if self.multi { "MF" } else { "SF" };
        let base = match self.base {
            BaseType::Bool => "Bool",
            BaseType::Int32 => "Int32",
            BaseType::Float => "Float",
            BaseType::Time => "Time",
            BaseType::Vec2f => "Vec2f",
            BaseType::Vec3f => "Vec3f",
            BaseType::Color => "Color",
            BaseType::Rotation => "Rotation",
            BaseType::String => "String",
            BaseType::Node => "Node",
            BaseType::Image => "Image",
        };
        write!(f, "{prefix}{base}")
    }
}

/// An SFImage: width, height, components (1–4) and one packed integer per pixel.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub components: u8,
    pub pixels: Vec<u32>,
}

/// A typed field value. Numbers are f64 throughout so that a scene far from the origin keeps
/// its precision; rotations keep their axis normalised.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    Int(i32),
    Float(f64),
    Vec2([f64; 2]),
    Vec3([f64; 3]),
    Rotation([f64; 4]),
    String(String),
    Node(Option<NodeId>),
    Image(Image),
    Bools(Vec<bool>),
    Ints(Vec<i32>),
    Floats(Vec<f64>),
    Vec2s(Vec<[f64; 2]>),
    Vec3s(Vec<[f64; 3]>),
    Rotations(Vec<[f64; 4]>),
    Strings(Vec<String>),
    Nodes(Vec<NodeId>),
}

impl Value {
    /// The strings of an SFString or MFString value, in order.
    pub fn strings(&self) -> &[String] {
        match self {
            Value::String(s) => std::slice::from_ref(s),
            Value::Strings(s) => s,
            _ => &[],
        }
    }

    /// The nodes a value refers to, in order.
    pub fn nodes(&self) -> &[NodeId] {
        match self {
            Value::Node(Some(id)) => std::slice::from_ref(id),
            Value::Nodes(ids) => ids,
            _ => &[],
        }
    }

    /// A short rendering for messages and `regatta schema`.
    pub fn display(&self) -> String {
        fn nums(values: &[f64]) -> String {
            values
                .iter()
                .map(|v| format!("{v}"))
                .collect::<Vec<_>>()
                .join(" ")
        }
        match self {
            Value::Bool(b) => if *b { "TRUE" } else { "FALSE" }.to_owned(),
            Value::Int(i) => i.to_string(),
            Value::Float(x) => format!("{x}"),
            Value::Vec2(v) => nums(v),
            Value::Vec3(v) => nums(v),
            Value::Rotation(v) => nums(v),
            Value::String(s) => format!("{s:?}"),
            Value::Node(None) => "NULL".to_owned(),
            Value::Node(Some(_)) => "node".to_owned(),
            Value::Image(image) => {
                format!("{} {} {} …", image.width, image.height, image.components)
            }
            Value::Bools(v) => format!(
                "[ {} ]",
                v.iter()
                    .map(|b| if *b { "TRUE" } else { "FALSE" })
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            Value::Ints(v) => format!(
                "[ {} ]",
                v.iter()
                    .map(|i| i.to_string())
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            Value::Floats(v) => format!("[ {} ]", nums(v)),
            Value::Vec2s(v) => format!(
                "[ {} ]",
                v.iter().map(|x| nums(x)).collect::<Vec<_>>().join(", ")
            ),
            Value::Vec3s(v) => format!(
                "[ {} ]",
                v.iter().map(|x| nums(x)).collect::<Vec<_>>().join(", ")
            ),
            Value::Rotations(v) => format!(
                "[ {} ]",
                v.iter().map(|x| nums(x)).collect::<Vec<_>>().join(", ")
            ),
            Value::Strings(v) => format!(
                "[ {} ]",
                v.iter()
                    .map(|s| format!("{s:?}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            Value::Nodes(v) => format!("[ {} nodes ]", v.len()),
        }
    }
}
