//! The standard PROTOs, written in the world language and shipped inside the binary: a world
//! uses them without any EXTERNPROTO line.

/// (name, source) of every built-in PROTO file.
pub const BUILTIN_PROTOS: &[(&str, &str)] = &[
    ("Arena", include_str!("../../worlds/protos/Arena.proto")),
    ("Buoy", include_str!("../../worlds/protos/Buoy.proto")),
    ("Khepera", include_str!("../../worlds/protos/Khepera.proto")),
];
