//! Files and urls: registering texts, parsing each once, resolving urls through
//! [`FileAccess`](crate::access::FileAccess) (and refusing, with the reason, what it refuses),
//! reading EXTERNPROTO and Inline files once (include depth, cycles, size, not-a-world
//! files), EXTERNPROTO lookup (the PROTO path, then regatta's stand-ins), and Inline.

use std::path::{Path, PathBuf};
use std::rc::Rc;

use regatta_parser::syntax::{self, Item};
use regatta_parser::{Diagnostic, SourceText, Span};

use crate::access::Refusal;
use crate::protos::WEBOTS_STANDINS;
use crate::scene::{FieldsBuilder, FileId, NodeId, NodeNames, Origin, SceneNode, Written};
use crate::value::Value;

use super::checked::{FileDiagnostic, Source};
use super::state::{Lowerer, ProtoDef, Scope, UrlBase, UrlUse};

impl<'c> Lowerer<'c> {
    pub(super) fn add_text(&mut self, name: &str, text: &str, base: UrlBase) -> FileId {
        let id = FileId(self.sources.len() as u32);
        self.sources.push(Source {
            name: name.to_owned(),
            text: Rc::from(text),
        });
        self.file_bases.push(base);
        id
    }

    pub(super) fn add_file(&mut self, source: SourceText, base: UrlBase) -> FileId {
        let id = self.add_text(&source.name, &source.text, base);
        for diagnostic in source.diagnostics {
            self.parse_diagnostics.push(FileDiagnostic {
                file: id,
                diagnostic,
            });
        }
        id
    }

    pub(super) fn is_builtin(&self, file: FileId) -> bool {
        matches!(self.file_bases.get(file.0 as usize), Some(UrlBase::NoFiles))
    }

    /// Parses a registered file once, keeping its syntax diagnostics.
    pub(super) fn parse(&mut self, file: FileId) -> Rc<syntax::SourceFile> {
        if let Some(parsed) = self.parsed.get(&file.0) {
            return parsed.clone();
        }
        let text = self.sources[file.0 as usize].text.clone();
        let parse = regatta_parser::parse_with(&text, self.options.limits.nesting);
        for diagnostic in parse.diagnostics {
            self.parse_diagnostics
                .push(FileDiagnostic { file, diagnostic });
        }
        let parsed = Rc::new(parse.file);
        self.parsed.insert(file.0, parsed.clone());
        parsed
    }

    pub(super) fn extern_proto(
        &mut self,
        file: FileId,
        extern_proto: &syntax::ExternProto,
        list: &mut Vec<(String, Rc<ProtoDef>)>,
    ) {
        let mut refused = None;
        for url in &extern_proto.urls {
            let (path_part, fragment) = match url.value.split_once('#') {
                Some((p, f)) => (p, Some(f)),
                None => (url.value.as_str(), None),
            };
            let name = extern_proto
                .name
                .as_ref()
                .map(|n| n.text.clone())
                .or_else(|| fragment.map(str::to_owned))
                .unwrap_or_else(|| {
                    Path::new(path_part)
                        .file_stem()
                        .map(|s| s.to_string_lossy().into_owned())
                        .unwrap_or_default()
                });
            if let Some(inside) = crate::webots::webots_path(path_part) {
                // A Webots PROTO: from a folder of the PROTO path (the user's, trusted, and
                // confined to it), else regatta's stand-in, else unknown where it is used.
                match crate::proto_path::find(&self.options.proto_path, inside, &name) {
                    crate::proto_path::Lookup::Found(path) => {
                        if self.extern_from_file(file, &path, url, &name, list) {
                            return;
                        }
                        continue;
                    }
                    crate::proto_path::Lookup::Refused {
                        looked_up,
                        folder,
                        refusal,
                    } => {
                        // Nothing was read: an error in both modes, since the PROTO path is
                        // the user's own setting and a link out of it is a mistake there;
                        // the stand-in, if any, still stands in.
                        let why = match refusal {
                            Refusal::LinkOutsideRoot => {
                                "is a symbolic link to a place outside that folder"
                            }
                            Refusal::OutsideRoot => "leads outside that folder",
                            Refusal::Absolute => "is an absolute path",
                            Refusal::Network { .. } => "is a network url",
                            _ => "cannot be read",
                        };
                        let instead = if WEBOTS_STANDINS.iter().any(|(n, _, _)| *n == name) {
                            "regatta's stand-in is used instead"
                        } else {
                            "its PROTO stays unknown"
                        };
                        self.error(
                            file,
                            Diagnostic::error(
                                url.span,
                                format!(
                                    "EXTERNPROTO url '{}' is not read from the PROTO path: '{looked_up}' in '{}' {why}",
                                    url.value,
                                    folder.display()
                                ),
                            )
                            .with_label("refused")
                            .with_note(format!(
                                "{instead}; a PROTO-path folder is read only inside itself (no `..` out of it, no link leading out)"
                            ))
                            .with_code("file-access"),
                        );
                    }
                    crate::proto_path::Lookup::Absent => {}
                }
                if WEBOTS_STANDINS.iter().any(|(n, _, _)| *n == name) {
                    // The stand-in answers where the name is used (`Lowerer::standin`).
                    self.standin_urls
                        .entry(name)
                        .or_insert_with(|| url.value.clone());
                    return;
                }
            }
            let path = match self.resolve_url(file, path_part) {
                Ok(path) => path,
                Err(Refusal::Network { .. }) => {
                    // Said where the PROTO is used ("its EXTERNPROTO points to …").
                    self.unresolved
                        .entry(name)
                        .or_insert_with(|| url.value.clone());
                    continue;
                }
                Err(refusal) => {
                    self.unresolved
                        .entry(name)
                        .or_insert_with(|| url.value.clone());
                    refused.get_or_insert((refusal, url));
                    continue;
                }
            };
            if self.extern_from_file(file, &path, url, &name, list) {
                return;
            }
        }
        if let Some((refusal, url)) = refused {
            self.refuse(file, url.span, &url.value, refusal, UrlUse::ExternProto);
        }
        if extern_proto.urls.is_empty() {
            // ISO/IEC 14772-1, 4.9.3: a PROTO none of whose urls can be read is unavailable;
            // with no url at all, that is said where it is declared.
            if let Some(name) = &extern_proto.name {
                let diagnostic = Diagnostic::error(
                    name.span,
                    format!(
                        "EXTERNPROTO '{}' lists no url: its PROTO is unavailable",
                        name.text
                    ),
                )
                .with_label("no url")
                .with_note("its nodes are unknown; give the url of the file that defines it")
                .with_code("externproto");
                self.strict_or_warn(file, diagnostic);
            }
        }
    }

    /// Reads a PROTO from the file at `path` (already resolved) into `list`, under `name`;
    /// false (after reporting) when the file cannot be read or defines no such PROTO.
    ///
    /// Which PROTO (ISO/IEC 14772-1, 4.9.3): the one a `#Name` fragment of the url names;
    /// without one, the PROTO called `name` if the file has it, else the file's first. A url
    /// naming the very file the EXTERNPROTO stands in is no include loop: it refers to one of
    /// that file's own PROTOs.
    pub(super) fn extern_from_file(
        &mut self,
        file: FileId,
        path: &Path,
        url: &syntax::StringLit,
        name: &str,
        list: &mut Vec<(String, Rc<ProtoDef>)>,
    ) -> bool {
        let fragment = url.value.split_once('#').map(|(_, f)| f);
        let loaded = if self.loaded.get(path) == Some(&file) {
            file
        } else {
            let Some(loaded) = self.load_resolved(file, path, &url.value, url.span) else {
                return false;
            };
            loaded
        };
        let parsed = self.parse(loaded);
        let protos = || {
            parsed.items.iter().filter_map(|item| match item {
                Item::Proto(p) => Some(p),
                _ => None,
            })
        };
        let found = match fragment {
            Some(wanted) => protos().find(|p| p.name.text == wanted),
            None => protos()
                .find(|p| p.name.text == name)
                .or_else(|| protos().next()),
        }
        .cloned();
        let name_wanted = fragment.unwrap_or(name);
        match found {
            Some(proto) => {
                if loaded != file && !self.file_scopes.contains_key(&loaded.0) {
                    self.includes.push(loaded);
                    self.file_protos(loaded, &parsed);
                    self.includes.pop();
                }
                list.push((
                    name.to_owned(),
                    Rc::new(ProtoDef {
                        file: loaded,
                        proto,
                        enclosing: Rc::new(Vec::new()),
                    }),
                ));
                true
            }
            None => {
                self.error(
                    file,
                    Diagnostic::error(
                        url.span,
                        format!("'{}' defines no PROTO named '{name_wanted}'", url.value),
                    )
                    .with_code("externproto"),
                );
                false
            }
        }
    }

    /// Where `url`, written in `file`, leads, if the world may read it.
    pub(super) fn resolve_url(&self, file: FileId, url: &str) -> Result<PathBuf, Refusal> {
        let base = match &self.file_bases[file.0 as usize] {
            UrlBase::Dir(dir) => Some(dir.as_path()),
            UrlBase::CurrentDir => None,
            UrlBase::NoFiles => return Err(Refusal::NoAccess),
        };
        self.options.access.resolve(url, base)
    }

    /// Reports a url that was not followed, and what happens instead. Escapes are errors in
    /// both modes (nothing is read either way, and a world that reaches outside its folder
    /// should not look fine), except a texture's in lenient mode: projects written on a
    /// laptop name images there, and Webots warns and draws without them, as regatta then
    /// does (the file is still not read).
    pub(super) fn refuse(
        &mut self,
        file: FileId,
        span: Span,
        url: &str,
        refusal: Refusal,
        user: UrlUse,
    ) {
        let diagnostic = Diagnostic::error(
            span,
            format!("{} url {}", user.noun(), refusal.message(url)),
        )
        .with_label(match refusal {
            Refusal::Network { .. } => "not fetched",
            Refusal::Missing => "no such file",
            _ => "refused",
        })
        .with_note(format!("{}; {}", user.instead(), refusal.rule()))
        .with_code("file-access");
        match (&refusal, user) {
            // An unavailable PROTO (missing, not allowed, or on the network) is skipped in
            // lenient mode, as Webots skips it: its nodes are then unknown, and a robot among
            // them is what `run` refuses to simulate. Nothing refused is read in either mode.
            (_, UrlUse::ExternProto) => self.strict_or_warn(file, diagnostic),
            (Refusal::OutsideRoot | Refusal::LinkOutsideRoot | Refusal::Absolute, user)
                if user.is_texture() =>
            {
                self.strict_or_warn(file, diagnostic)
            }
            (Refusal::Missing | Refusal::Network { .. } | Refusal::Empty, UrlUse::Asset(_)) => {
                self.strict_or_warn(file, diagnostic)
            }
            (Refusal::Missing | Refusal::Network { .. }, UrlUse::Image(_)) => {
                let mut diagnostic = diagnostic;
                diagnostic.severity = regatta_parser::Severity::Warning;
                self.error(file, diagnostic);
            }
            (Refusal::Missing | Refusal::Network { .. } | Refusal::Empty, _) => {
                self.strict_or_warn(file, diagnostic)
            }
            _ => self.error(file, diagnostic),
        }
    }

    /// Reads a file named by EXTERNPROTO or Inline (already resolved to `path`), once; `url`
    /// is how the including file wrote it, for messages.
    pub(super) fn load_resolved(
        &mut self,
        from: FileId,
        path: &Path,
        url: &str,
        span: Span,
    ) -> Option<FileId> {
        if self.includes.len() >= self.options.limits.include_depth {
            let limit = self.options.limits.include_depth;
            self.limit_crossed(
                "include-depth",
                from,
                Diagnostic::error(
                    span,
                    format!("files include each other more than {limit} levels deep"),
                )
                .with_label("this file is not read"),
            );
            return None;
        }
        if let Some(&id) = self.loaded.get(path) {
            if self.includes.contains(&id) || id == FileId(0) {
                self.error(
                    from,
                    Diagnostic::error(span, format!("'{url}' includes itself"))
                        .with_label("a file that includes itself would never end")
                        .with_code("include-cycle"),
                );
                return None;
            }
            return Some(id);
        }
        let problem = |lowerer: &mut Self, message: String| {
            lowerer.error(
                from,
                Diagnostic::error(span, message)
                    .with_label("not read")
                    .with_code("not-a-world"),
            );
        };
        let source = match SourceText::read_limited(path, self.options.limits.file_size) {
            Ok(source) => source,
            Err(regatta_parser::SourceError::TooLarge { limit, .. }) => {
                self.limit_crossed(
                    "file-size",
                    from,
                    Diagnostic::error(
                        span,
                        format!("'{url}' is larger than the file-size limit of {limit} bytes"),
                    )
                    .with_label("not read"),
                );
                return None;
            }
            Err(regatta_parser::SourceError::Binary { .. }) => {
                problem(
                    self,
                    format!("'{url}' is not a world file: it holds binary data"),
                );
                return None;
            }
            Err(regatta_parser::SourceError::Gzip { .. }) => {
                problem(
                    self,
                    format!("'{url}' looks gzip-compressed but does not inflate"),
                );
                return None;
            }
            Err(regatta_parser::SourceError::Io { source, .. }) => {
                let reason = match source.kind() {
                    std::io::ErrorKind::PermissionDenied => "permission denied",
                    std::io::ErrorKind::IsADirectory => "it is a folder",
                    _ => "it cannot be read",
                };
                let reason = if path.is_dir() {
                    "it is a folder"
                } else {
                    reason
                };
                problem(self, format!("cannot read '{url}': {reason}"));
                return None;
            }
        };
        if !regatta_parser::source::has_world_header(&source.text) {
            problem(
                self,
                format!("'{url}' is not a world file: it does not start with a #VRML header"),
            );
            return None;
        }
        let name = included_name(&self.sources[from.0 as usize].name, url);
        let folder = path.parent().map(Path::to_owned).unwrap_or_default();
        let id = self.add_file(SourceText { name, ..source }, UrlBase::Dir(folder));
        self.loaded.insert(path.to_owned(), id);
        Some(id)
    }

    /// Inline becomes a Group holding the included file's nodes.
    pub(super) fn inline(
        &mut self,
        urls: &[(usize, String, FileId, Span)],
        node: &syntax::Node,
        scope: &Scope,
        origin: Origin,
    ) -> Option<NodeId> {
        let group = self
            .catalogue()
            .lookup("Group")
            .expect("catalogue has Group");
        let mut children = Vec::new();
        // VRML97: the urls are alternatives, the first one that can be read is used.
        let mut refused = None;
        let mut chosen: Option<(PathBuf, &String, FileId, Span)> = None;
        for (_, url, file, span) in urls {
            match self.resolve_url(*file, url) {
                Ok(path) => {
                    chosen = Some((path, url, *file, *span));
                    break;
                }
                Err(refusal) => {
                    refused.get_or_insert((refusal, url, *file, *span));
                }
            }
        }
        match (chosen, refused) {
            (Some((path, url, file, span)), _) => {
                if let Some(loaded) = self.load_resolved(file, &path, url, span) {
                    self.includes.push(loaded);
                    let parsed = self.parse(loaded);
                    let protos = self.file_protos(loaded, &parsed);
                    let mut inner = Scope {
                        protos,
                        ..Scope::new(loaded)
                    };
                    // The included file's nodes are the user's too: nothing is relocated.
                    let frames = std::mem::take(&mut self.frames);
                    let blame = self.blame.take();
                    children = self.lower_items(&parsed.items, &mut inner, true);
                    self.frames = frames;
                    self.blame = blame;
                    self.includes.pop();
                }
            }
            (None, Some((refusal, url, file, span))) => {
                self.refuse(file, span, url, refusal, UrlUse::Inline);
            }
            (None, None) => {}
        }
        let spec = self.catalogue().spec(group);
        let mut group_fields = FieldsBuilder::new(group, spec.fields.len());
        group_fields.set(0, Value::Nodes(children), None);
        let mut written = Written::none(spec.fields.len());
        written.set(0);
        let fields = group_fields.finish(origin, &mut self.shared_fields);
        self.alloc(
            SceneNode {
                spec: group,
                written,
                fields,
                names: Some(Box::new(NodeNames {
                    def_name: None,
                    proto_names: vec!["Inline".to_owned()],
                })),
                origin,
                axes: Default::default(),
            },
            scope.file,
            node.span,
        )
    }
}

/// How messages name a file included from `from` as `url`: beside the including file's own
/// name (relative paths stay relative, so messages do not depend on where the checkout is).
fn included_name(from: &str, url: &str) -> String {
    if from.starts_with('<') {
        return url.to_owned();
    }
    let mut parts: Vec<&str> = from.split('/').collect();
    parts.pop();
    for part in url.split('/') {
        match part {
            "" | "." => {}
            ".." if parts.last().is_some_and(|p| *p != ".." && !p.is_empty()) => {
                parts.pop();
            }
            other => parts.push(other),
        }
    }
    parts.join("/")
}
