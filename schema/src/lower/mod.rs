//! Typing: from syntax trees to a [`Scene`](crate::scene::Scene), checking every field against the catalogue,
//! resolving DEF/USE, expanding PROTOs (built-in, file-local and local EXTERNPROTOs) and
//! Inline files.
//!
//! Rules worth knowing:
//! - A DEF name is bound once its node is complete, so USE inside the node it names is an
//!   error and the scene is always a DAG; among repeated DEFs the latest bound wins.
//! - Strict mode makes unknown nodes, fields and template code errors; lenient mode makes them
//!   warnings and skips them, as Webots does.
//! - Files are read through [`FileAccess`](crate::access::FileAccess) only: urls resolve relative to the file naming
//!   them and never leave the world's root; no url is ever fetched.
//! - Every [`Limits`](crate::access::Limits) bound is checked where it is crossed and reported there, once.
//! - A problem inside a PROTO's body that the instance caused (a value it passed, a template
//!   over its fields, any problem in a built-in PROTO) is reported at the instance's line, with
//!   the PROTO's line beside it, as rustc does for macros.
//! - A PROTO declaration of the user's is checked where it stands, once, used or not (VRML97
//!   4.8); its instances repeat none of those messages.
//!
//! This file holds the entry points. The lowerer's state is `state.rs`; each of its jobs is a
//! file: `nodes.rs` (DEF/USE, built-in nodes), `fields.rs` (field values, IS), `protos.rs`
//! (PROTO instances), `declared.rs` (PROTO declarations where they stand), `templates.rs`,
//! `files.rs` (urls, EXTERNPROTO, Inline), `routes.rs`, `assets.rs` (mesh and image files),
//! `axes.rs`, `limits.rs`, `report.rs` (diagnostics and blame), `finish.rs`; what a check is
//! given and returns are `options.rs` and `checked.rs`.

use std::path::{Path, PathBuf};

use regatta_parser::SourceText;

mod assets;
mod axes;
mod checked;
mod declared;
mod events;
mod fields;
mod files;
mod finish;
mod limits;
mod nodes;
mod options;
mod protos;
mod report;
mod routes;
mod state;
mod templates;

pub use checked::{Checked, FileDiagnostic, Source, Substitution, UnbuiltRobot};
pub use options::{Options, MAX_DIAGNOSTICS, MAX_INSTANCE_DEPTH, MAX_NODES};
use state::{Lowerer, UrlBase};

/// Checks a world given as text (its own parse diagnostics included).
pub fn check(source: SourceText, options: &Options) -> Checked {
    let mut lowerer = Lowerer::new(options.clone());
    let base = match &options.base_dir {
        Some(dir) => UrlBase::Dir(dir.clone()),
        None => UrlBase::CurrentDir,
    };
    // The file the text was read from, when it is there: an EXTERNPROTO naming it refers to
    // this text's own PROTOs, and an Inline of it is an include loop.
    let on_disk = options.base_dir.as_ref().and_then(|dir| {
        let name = Path::new(&source.name).file_name()?;
        dir.join(name).canonicalize().ok()
    });
    let file = lowerer.add_file(source, base);
    if let Some(path) = on_disk {
        lowerer.loaded.insert(path, file);
    }
    lowerer.lower_world(file);
    lowerer.finish()
}

/// Reads and checks a world file with the default limits, reading files under its folder
/// only; `Err` only when the file cannot be read at all.
pub fn check_file(path: &Path, strict: bool) -> Result<Checked, regatta_parser::SourceError> {
    check_path(
        path,
        &Options {
            strict,
            ..Options::default()
        },
    )
}

/// [`check_file`], looking for `webots://` PROTOs in `proto_path` before the stand-ins.
pub fn check_file_with_proto_path(
    path: &Path,
    strict: bool,
    proto_path: Vec<PathBuf>,
) -> Result<Checked, regatta_parser::SourceError> {
    check_path(
        path,
        &Options {
            strict,
            proto_path,
            ..Options::default()
        },
    )
}

/// Reads and checks a world file: its project (its folder, or the folder above a `worlds`
/// folder) joins `options.access`, and its urls resolve against its folder. `Err` only when the file cannot be read at all.
pub fn check_path(path: &Path, options: &Options) -> Result<Checked, regatta_parser::SourceError> {
    let source = SourceText::read_limited(path, options.limits.file_size)?;
    let mut options = options.clone();
    let io = |source| regatta_parser::SourceError::Io {
        path: path.to_owned(),
        source,
    };
    let canonical = path.canonicalize().map_err(io)?;
    let folder = canonical
        .parent()
        .map(Path::to_owned)
        .unwrap_or_else(|| PathBuf::from("/"));
    options
        .access
        .allow(&crate::access::project_root(&folder))
        .map_err(io)?;
    options.base_dir = Some(folder);
    let mut lowerer = Lowerer::new(options.clone());
    let file = lowerer.add_file(
        source,
        UrlBase::Dir(options.base_dir.clone().unwrap_or_default()),
    );
    lowerer.loaded.insert(canonical, file);
    lowerer.lower_world(file);
    Ok(lowerer.finish())
}
