//! Schema-free parsing of VRML-style world files: Webots `.wbt`/`.proto` and VRML97 `.wrl`.
//!
//! This crate owns the syntax layer and nothing above it. [`parse`] never fails and never
//! panics: it returns a lossless [`syntax::SourceFile`] (every node, field and value carries
//! its byte [`Span`]) together with every [`Diagnostic`] it found, recovering at the next
//! field or node after an error. It knows no field types: how many numbers a field takes is
//! decided later by the schema crate.
//!
//! [`format`] prints a tree back in canonical form, keeping comments.

pub mod diagnostic;
pub mod format;
mod lexer;
mod parse;
pub mod source;
mod span;
pub mod syntax;
pub mod testgen;
mod word;

pub use diagnostic::{Diagnostic, Label, Severity, SourceMap};
pub use parse::{parse, parse_with, Parse, MAX_DEPTH, MAX_ERRORS};
pub use source::{SourceError, SourceText};
pub use span::Span;
