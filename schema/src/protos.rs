//! The standard PROTOs, written in the world language and shipped inside the binary: a world
//! uses them without any EXTERNPROTO line.

/// (name, source) of every built-in PROTO file.
pub const BUILTIN_PROTOS: &[(&str, &str)] = &[
    ("Arena", include_str!("../../worlds/protos/Arena.proto")),
    ("Buoy", include_str!("../../worlds/protos/Buoy.proto")),
    ("Khepera", include_str!("../../worlds/protos/Khepera.proto")),
];

/// (name, source, authoring) of every built-in stand-in for a Webots PROTO: a world that names
/// the Webots PROTO (by `webots://` EXTERNPROTO, or by name in files from before R2022b that
/// have no EXTERNPROTO lines) gets the stand-in. Each is written from the PROTO's documented
/// interface (see `docs/reference/webots-robots.md`), never from Webots' source.
pub const WEBOTS_STANDINS: &[(&str, &str, crate::webots::Authoring)] = {
    use crate::webots::Authoring::{Webots, WebotsFlu, WebotsRobot};
    &[
        (
            "CircleArena",
            include_str!("../../worlds/protos/webots/CircleArena.proto"),
            Webots,
        ),
        (
            "E-puck",
            include_str!("../../worlds/protos/webots/E-puck.proto"),
            WebotsRobot,
        ),
        (
            "E-puck_enu",
            include_str!("../../worlds/protos/webots/E-puck_enu.proto"),
            WebotsFlu,
        ),
        (
            "Floor",
            include_str!("../../worlds/protos/webots/Floor.proto"),
            Webots,
        ),
        (
            "Khepera1",
            include_str!("../../worlds/protos/webots/Khepera1.proto"),
            WebotsRobot,
        ),
        (
            "Khepera2",
            include_str!("../../worlds/protos/webots/Khepera2.proto"),
            WebotsRobot,
        ),
        (
            "Khepera3",
            include_str!("../../worlds/protos/webots/Khepera3.proto"),
            WebotsRobot,
        ),
        (
            "Khepera4",
            include_str!("../../worlds/protos/webots/Khepera4.proto"),
            WebotsRobot,
        ),
        (
            "RectangleArena",
            include_str!("../../worlds/protos/webots/RectangleArena.proto"),
            Webots,
        ),
        (
            "TexturedBackground",
            include_str!("../../worlds/protos/webots/TexturedBackground.proto"),
            Webots,
        ),
        (
            "TexturedBackgroundLight",
            include_str!("../../worlds/protos/webots/TexturedBackgroundLight.proto"),
            Webots,
        ),
        (
            "WoodenBox",
            include_str!("../../worlds/protos/webots/WoodenBox.proto"),
            Webots,
        ),
    ]
};
