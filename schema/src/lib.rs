//! The node catalogue and typing: from a syntax tree to a validated, typed [`Scene`].
//!
//! This crate owns the meaning of node and field names. The catalogue (`catalogue/*.toml`,
//! embedded) declares every built-in node type; [`check`] types a world against it, expands
//! PROTOs (the standard ones in `worlds/protos/` are built in) and resolves DEF/USE, returning
//! the scene and every diagnostic. It never fails on user input.

pub mod access;
mod binding;
pub mod catalogue;
mod lower;
mod procedural;
pub mod proto_path;
mod protos;
pub mod scene;
pub mod template;
mod typing;
pub mod value;
pub mod webots;

pub use access::{FileAccess, Limits, Refusal};
pub use binding::{Binding, Bindings};
pub use catalogue::{Catalogue, FieldSpec, NodeSpec};
pub use lower::{
    check, check_file, check_file_with_proto_path, check_path, Checked, FileDiagnostic, Options,
    Source, Substitution, UnbuiltRobot, MAX_DIAGNOSTICS, MAX_INSTANCE_DEPTH, MAX_NODES,
};
pub use protos::{
    standard_proto, standard_protos, ProtoField, ProtoSpec, BUILTIN_PROTOS, WEBOTS_STANDINS,
};
pub use scene::{Asset, Companion, Fields, FileId, Scene, SceneNode, UpAxis, Written};
pub use value::{BaseType, FieldType, NodeId, Value};
