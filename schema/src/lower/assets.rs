//! Mesh and image files the exporters need: read once each, through the url rules of
//! `files.rs` and the file-size limit, into the scene's [`Asset`]s. An OBJ's MTL libraries are
//! read with it (relative to the OBJ, under the same rules). A file that cannot be read is a
//! warning naming it in lenient mode and an error at its line in strict mode: the shape is
//! then left out, never the world.

use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use regatta_parser::{Diagnostic, Span};

use crate::scene::{Asset, Companion, FileId, NodeId};

use super::state::Lowerer;

/// Whether nodes of this type have their url's file read.
pub(super) fn reads_asset(type_name: &str) -> bool {
    matches!(type_name, "Mesh" | "CadShape" | "ImageTexture")
}

/// An MTL library an OBJ names: at most this many are read.
const MAX_COMPANIONS: usize = 8;

impl Lowerer<'_> {
    /// Reads the file at `path` (already resolved from `url`, written in `file` at `span`);
    /// `None` when it cannot be read, after saying why.
    pub(super) fn read_asset(
        &mut self,
        path: &Path,
        url: &str,
        file: FileId,
        span: Span,
    ) -> Option<Asset> {
        let bytes = match self.asset_bytes(path) {
            Ok(bytes) => bytes,
            Err(reason) => {
                self.strict_or_warn(
                    file,
                    Diagnostic::error(span, format!("'{url}' is not read: {reason}"))
                        .with_label("not read")
                        .with_note("the shape or texture that names it is not exported")
                        .with_code(if reason.starts_with("larger than") {
                            "file-size"
                        } else {
                            "asset"
                        }),
                );
                return None;
            }
        };
        let companions = if url.to_ascii_lowercase().ends_with(".obj") {
            self.companions(path, &bytes)
        } else {
            Vec::new()
        };
        Some(Asset {
            node: NodeId(0),
            url: url.to_owned(),
            bytes,
            companions,
        })
    }

    /// The bytes of one file, read once however many nodes name it.
    fn asset_bytes(&mut self, path: &Path) -> Result<Arc<[u8]>, String> {
        if let Some(read) = self.asset_files.get(path) {
            return read.clone();
        }
        let limit = self.options.limits.file_size;
        let read = read_limited(path, limit);
        self.asset_files.insert(path.to_owned(), read.clone());
        read
    }

    /// The MTL libraries an OBJ names (`mtllib a.mtl b.mtl`), each resolved relative to the
    /// OBJ through the world's file access.
    fn companions(&mut self, obj: &Path, bytes: &[u8]) -> Vec<Companion> {
        let text = String::from_utf8_lossy(bytes);
        let names: Vec<String> = text
            .lines()
            .filter_map(|line| line.trim_start().strip_prefix("mtllib"))
            .filter(|rest| rest.starts_with(char::is_whitespace))
            .flat_map(|rest| rest.split_whitespace().map(str::to_owned))
            .take(MAX_COMPANIONS)
            .collect();
        names
            .into_iter()
            .map(|name| {
                let bytes = match self.options.access.resolve(&name, obj.parent()) {
                    Ok(path) => self.asset_bytes(&path),
                    Err(refusal) => Err(refusal.message(&name)),
                };
                Companion { name, bytes }
            })
            .collect()
    }
}

/// A file's bytes, refused past `limit` bytes.
fn read_limited(path: &Path, limit: u64) -> Result<Arc<[u8]>, String> {
    let file = std::fs::File::open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "it does not exist".to_owned(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
        _ => "it cannot be read".to_owned(),
    })?;
    if path.is_dir() {
        return Err("it is a folder".to_owned());
    }
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|_| "it cannot be read".to_owned())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "larger than the file-size limit of {limit} bytes (--limit file-size=BYTES)"
        ));
    }
    Ok(bytes.into())
}
