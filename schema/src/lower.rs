//! Typing: from syntax trees to a [`Scene`], checking every field against the catalogue,
//! resolving DEF/USE, expanding PROTOs (built-in, file-local and local EXTERNPROTOs) and
//! Inline files.
//!
//! Rules worth knowing:
//! - A DEF name is bound once its node is complete, so USE inside the node it names is an
//!   error and the scene is always a DAG; among repeated DEFs the latest bound wins.
//! - Strict mode makes unknown nodes, fields and template code errors; lenient mode makes them
//!   warnings and skips them, as Webots does.
//! - No URL is ever fetched: `webots://` and `http(s)://` PROTOs are unknown types.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Dialect, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, SourceText, Span};

use crate::catalogue::{did_you_mean, Catalogue, FieldSpec, SpecId};
use crate::protos::{BUILTIN_PROTOS, WEBOTS_STANDINS};
use crate::scene::{FileId, NodeId, Origin, Scene, SceneNode, UpAxis};
use crate::value::{BaseType, FieldType, Image, Value};

/// Deepest nesting of PROTO instances and Inline files.
pub const MAX_INSTANCE_DEPTH: usize = 32;
/// Largest scene, in nodes, after PROTO expansion.
pub const MAX_NODES: usize = 1_000_000;

/// How to check a world.
#[derive(Clone, Debug)]
pub struct Options {
    /// Unknown nodes and fields are errors (regatta's own worlds) or warnings (foreign files).
    pub strict: bool,
    /// Directory against which EXTERNPROTO and Inline paths resolve; `None` forbids file access.
    pub base_dir: Option<PathBuf>,
    /// Folders where `webots://` PROTOs are looked for before regatta's stand-ins (a Webots
    /// installation, or any folder of PROTOs); see [`crate::proto_path`].
    pub proto_path: Vec<PathBuf>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            strict: true,
            base_dir: None,
            proto_path: Vec::new(),
        }
    }
}

/// A diagnostic and the file it is about.
#[derive(Clone, Debug, PartialEq)]
pub struct FileDiagnostic {
    pub file: FileId,
    pub diagnostic: Diagnostic,
}

/// One file that took part in a check.
#[derive(Clone, Debug)]
pub struct Source {
    pub name: String,
    pub text: Rc<str>,
}

/// The result of checking a world: always a scene (possibly partial) and every diagnostic.
#[derive(Debug)]
pub struct Checked {
    pub scene: Scene,
    pub diagnostics: Vec<FileDiagnostic>,
    /// The files diagnostics refer to, indexed by [`FileId`].
    pub sources: Vec<Source>,
    /// The Webots PROTOs that regatta's built-in stand-ins replaced, in order of first use.
    pub substitutions: Vec<Substitution>,
    /// Robots that could not be built: instances of unknown node types that are robots (they
    /// set a `controller`, or their PROTO lives in a Webots `robots` folder).
    pub unbuilt_robots: Vec<UnbuiltRobot>,
}

/// A robot the world has that regatta could not build.
#[derive(Clone, Debug, PartialEq)]
pub struct UnbuiltRobot {
    /// Its node type (the PROTO's name).
    pub type_name: String,
    /// Where its PROTO was to come from, when an EXTERNPROTO says.
    pub url: Option<String>,
    pub file: FileId,
    pub span: Span,
}

/// A Webots PROTO replaced by regatta's built-in stand-in of the same name.
#[derive(Clone, Debug, PartialEq)]
pub struct Substitution {
    pub name: String,
    /// The url the world names (its EXTERNPROTO), or the standard place of the PROTO when the
    /// world names it without one (files from before R2022b).
    pub url: String,
    /// The first instance.
    pub file: FileId,
    pub span: Span,
}

impl Checked {
    /// Whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(|d| d.diagnostic.is_error())
    }

    /// Renders every diagnostic in rustc's style.
    pub fn render(&self, color: bool) -> String {
        self.diagnostics
            .iter()
            .map(|d| {
                let source = &self.sources[d.file.0 as usize];
                d.diagnostic.render(&source.name, &source.text, color)
            })
            .collect()
    }

    /// One line per diagnostic: `file:line:col: error: message`.
    pub fn short(&self) -> Vec<String> {
        self.diagnostics
            .iter()
            .map(|d| {
                let source = &self.sources[d.file.0 as usize];
                d.diagnostic.short(&source.name, &source.text)
            })
            .collect()
    }
}

/// Checks a world given as text (its own parse diagnostics included).
pub fn check(source: SourceText, options: &Options) -> Checked {
    let mut lowerer = Lowerer::new(options.clone());
    let file = lowerer.add_file(source);
    lowerer.lower_world(file);
    lowerer.finish()
}

/// Reads and checks a world file; `Err` only when the file cannot be read at all.
pub fn check_file(path: &Path, strict: bool) -> Result<Checked, regatta_parser::SourceError> {
    check_file_with_proto_path(path, strict, Vec::new())
}

/// [`check_file`], looking for `webots://` PROTOs in `proto_path` before the stand-ins.
pub fn check_file_with_proto_path(
    path: &Path,
    strict: bool,
    proto_path: Vec<PathBuf>,
) -> Result<Checked, regatta_parser::SourceError> {
    let source = SourceText::read(path)?;
    let options = Options {
        strict,
        base_dir: Some(path.parent().map(Path::to_owned).unwrap_or_default()),
        proto_path,
    };
    Ok(check(source, &options))
}

/// Types a catalogue default (used when the catalogue loads).
pub(crate) fn type_default(
    catalogue: &Catalogue,
    spec: SpecId,
    index: usize,
) -> Result<Value, String> {
    let field = &catalogue.nodes[spec].fields[index];
    let text = format!("{} {}", field.name, field.default);
    let parse = regatta_parser::parse(&format!("Default {{ {text} }}"));
    let value = match parse.file.items.first() {
        Some(Item::Node(syntax::Node {
            kind: NodeKind::Instance {
                body: Some(body), ..
            },
            ..
        })) => match body.items.first() {
            Some(BodyItem::Field(f)) => f.value.clone(),
            _ => {
                return Err(format!(
                    "{}.{}: unreadable default",
                    catalogue.nodes[spec].name, field.name
                ))
            }
        },
        _ => {
            return Err(format!(
                "{}.{}: unreadable default",
                catalogue.nodes[spec].name, field.name
            ))
        }
    };
    let mut lowerer = Lowerer::new(Options::default());
    lowerer.catalogue = Some(catalogue);
    let file = lowerer.add_text("<catalogue>", &format!("Default {{ {text} }}"));
    let mut scope = Scope::new(file);
    let typed = lowerer.lower_field_value(
        &value,
        field.ty(),
        Some(field),
        &mut scope,
        &field.name,
        Span::default(),
    );
    match typed {
        Some(value) if lowerer.diagnostics.is_empty() => Ok(value),
        _ => Err(format!(
            "{}.{}: default {:?} does not type: {:?}",
            catalogue.nodes[spec].name,
            field.name,
            field.default,
            lowerer.diagnostics.first().map(|d| &d.diagnostic.message)
        )),
    }
}

/// PROTOs visible at some point, in order of definition (later entries win).
type ProtoTable = Rc<Vec<(String, Rc<ProtoDef>)>>;
/// A PROTO instance's interface fields: declared type and bound value.
/// Declared type, bound value, and where an instance wrote it (defaults have no origin).
pub(crate) type Bindings = BTreeMap<String, (FieldType, Option<Value>, Option<(FileId, Span)>)>;

/// A PROTO definition and the file it was read from.
struct ProtoDef {
    file: FileId,
    proto: syntax::Proto,
    /// PROTOs of the PROTO bodies it is nested in (empty at file level); its own file's
    /// PROTOs are found through [`Lowerer::file_scopes`].
    enclosing: ProtoTable,
}

impl ProtoDef {
    /// A PROTO defined at the top level of `file`, as a table entry.
    fn file_level(file: FileId, proto: &syntax::Proto) -> (String, Rc<ProtoDef>) {
        (
            proto.name.text.clone(),
            Rc::new(ProtoDef {
                file,
                proto: proto.clone(),
                enclosing: Rc::new(Vec::new()),
            }),
        )
    }
}

/// What names mean at some point of a file or PROTO body.
#[derive(Clone)]
struct Scope {
    file: FileId,
    defs: HashMap<String, NodeId>,
    protos: ProtoTable,
    /// PROTO interface bindings, inside a PROTO body.
    interface: Option<Rc<Bindings>>,
    /// DEF names inside nodes that were skipped (lenient mode), so that their USEs are
    /// skipped quietly too.
    skipped_defs: BTreeSet<String>,
}

impl Scope {
    fn new(file: FileId) -> Scope {
        Scope {
            file,
            defs: HashMap::new(),
            protos: Rc::new(Vec::new()),
            interface: None,
            skipped_defs: BTreeSet::new(),
        }
    }

    fn find_proto(&self, name: &str) -> Option<Rc<ProtoDef>> {
        self.protos
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, p)| p.clone())
    }
}

struct Lowerer<'c> {
    options: Options,
    catalogue: Option<&'c Catalogue>,
    nodes: Vec<SceneNode>,
    sources: Vec<Source>,
    /// Parse diagnostics of each file, kept until the end so that typed messages can replace
    /// the parser's generic "missing value" ones.
    parse_diagnostics: Vec<FileDiagnostic>,
    diagnostics: Vec<FileDiagnostic>,
    refined_missing: BTreeSet<(u32, u32)>,
    builtins: Option<ProtoTable>,
    /// EXTERNPROTO names that point where regatta does not go, with the URL.
    unresolved: HashMap<String, String>,
    instance_stack: Vec<String>,
    /// PROTOs whose interface was already checked for unused fields.
    checked_protos: BTreeSet<(u32, u32)>,
    /// Files already loaded (EXTERNPROTO, Inline), by canonical path.
    loaded: HashMap<PathBuf, FileId>,
    /// The PROTO table of each file, by file id.
    file_scopes: HashMap<u32, ProtoTable>,
    budget_reported: bool,
    /// Too-deep instance nesting is reported once: one cause, one message.
    depth_reported: bool,
    up_axis: UpAxis,
    objects: crate::webots::Objects,
    roots: Vec<NodeId>,
    /// Who wrote each file that is not the world's (built-in PROTO files).
    file_authoring: HashMap<u32, crate::webots::Authoring>,
    /// PROTO instance roots: the authoring of the file that wrote the instance.
    instance_authoring: HashMap<u32, crate::webots::Authoring>,
    /// The urls EXTERNPROTOs give for stand-in names.
    standin_urls: HashMap<String, String>,
    substitutions: Vec<Substitution>,
    unbuilt_robots: Vec<UnbuiltRobot>,
}

impl<'c> Lowerer<'c> {
    fn new(options: Options) -> Lowerer<'c> {
        Lowerer {
            options,
            catalogue: None,
            nodes: Vec::new(),
            sources: Vec::new(),
            parse_diagnostics: Vec::new(),
            diagnostics: Vec::new(),
            refined_missing: BTreeSet::new(),
            builtins: None,
            unresolved: HashMap::new(),
            instance_stack: Vec::new(),
            checked_protos: BTreeSet::new(),
            loaded: HashMap::new(),
            file_scopes: HashMap::new(),
            budget_reported: false,
            depth_reported: false,
            up_axis: UpAxis::Y,
            objects: crate::webots::Objects::Legacy,
            roots: Vec::new(),
            file_authoring: HashMap::new(),
            instance_authoring: HashMap::new(),
            standin_urls: HashMap::new(),
            substitutions: Vec::new(),
            unbuilt_robots: Vec::new(),
        }
    }

    fn catalogue(&self) -> &'c Catalogue {
        match self.catalogue {
            Some(catalogue) => catalogue,
            None => Catalogue::get(),
        }
    }

    fn add_text(&mut self, name: &str, text: &str) -> FileId {
        let id = FileId(self.sources.len() as u32);
        self.sources.push(Source {
            name: name.to_owned(),
            text: Rc::from(text),
        });
        id
    }

    fn add_file(&mut self, source: SourceText) -> FileId {
        let id = self.add_text(&source.name, &source.text);
        for diagnostic in source.diagnostics {
            self.parse_diagnostics.push(FileDiagnostic {
                file: id,
                diagnostic,
            });
        }
        id
    }

    /// Parses a registered file, keeping its syntax diagnostics.
    fn parse(&mut self, file: FileId) -> Rc<syntax::SourceFile> {
        let text = self.sources[file.0 as usize].text.clone();
        let parse = regatta_parser::parse(&text);
        for diagnostic in parse.diagnostics {
            self.parse_diagnostics
                .push(FileDiagnostic { file, diagnostic });
        }
        Rc::new(parse.file)
    }

    fn error(&mut self, file: FileId, diagnostic: Diagnostic) {
        self.diagnostics.push(FileDiagnostic { file, diagnostic });
    }

    /// An error in strict mode, a warning in lenient mode.
    fn strict_or_warn(&mut self, file: FileId, mut diagnostic: Diagnostic) {
        if !self.options.strict {
            diagnostic.severity = regatta_parser::Severity::Warning;
        }
        self.error(file, diagnostic);
    }

    fn finish(mut self) -> Checked {
        let refined = std::mem::take(&mut self.refined_missing);
        let mut diagnostics: Vec<FileDiagnostic> = self
            .parse_diagnostics
            .drain(..)
            .filter(|d| {
                !(d.diagnostic.code == "missing-value"
                    && refined.contains(&(d.file.0, d.diagnostic.span.start)))
            })
            .collect();
        diagnostics.append(&mut self.diagnostics);
        // Stable order: by file, then position, then message.
        diagnostics.sort_by(|a, b| {
            (a.file.0, a.diagnostic.span.start, &a.diagnostic.message).cmp(&(
                b.file.0,
                b.diagnostic.span.start,
                &b.diagnostic.message,
            ))
        });
        diagnostics.dedup();
        for (index, node) in self.nodes.iter_mut().enumerate() {
            let body = self
                .file_authoring
                .get(&node.origin.file.0)
                .copied()
                .unwrap_or_default();
            let own = self
                .instance_authoring
                .get(&(index as u32))
                .copied()
                .unwrap_or(body);
            node.axes = crate::webots::Axes { own, body };
        }
        let scene = Scene {
            nodes: self.nodes,
            roots: self.roots,
            files: self.sources.iter().map(|s| s.name.clone()).collect(),
            up_axis: self.up_axis,
            objects: self.objects,
        };
        Checked {
            scene,
            diagnostics,
            sources: self.sources,
            substitutions: self.substitutions,
            unbuilt_robots: self.unbuilt_robots,
        }
    }

    fn builtins(&mut self) -> ProtoTable {
        if let Some(builtins) = &self.builtins {
            return builtins.clone();
        }
        let mut list = Vec::new();
        let regatta = BUILTIN_PROTOS
            .iter()
            .map(|(name, text)| (*name, *text, crate::webots::Authoring::Regatta));
        let webots = WEBOTS_STANDINS.iter().copied();
        for (name, text, authoring) in regatta.chain(webots) {
            let folder = if authoring == crate::webots::Authoring::Regatta {
                "protos"
            } else {
                "protos/webots"
            };
            let file = self.add_text(&format!("<builtin>/{folder}/{name}.proto"), text);
            self.file_authoring.insert(file.0, authoring);
            let parsed = self.parse(file);
            for item in &parsed.items {
                if let Item::Proto(proto) = item {
                    list.push(ProtoDef::file_level(file, proto));
                }
            }
        }
        let builtins = Rc::new(list);
        for (_, def) in builtins.iter() {
            self.file_scopes.insert(def.file.0, builtins.clone());
        }
        self.builtins = Some(builtins.clone());
        builtins
    }

    /// The PROTOs a file defines or imports, after the built-in ones (later entries win).
    fn file_protos(
        &mut self,
        file: FileId,
        parsed: &syntax::SourceFile,
        depth: usize,
    ) -> ProtoTable {
        let mut list: Vec<(String, Rc<ProtoDef>)> = self.builtins().iter().cloned().collect();
        for item in &parsed.items {
            if let Item::ExternProto(extern_proto) = item {
                self.extern_proto(file, extern_proto, &mut list, depth);
            }
        }
        let own: Vec<&syntax::Proto> = parsed
            .items
            .iter()
            .filter_map(|item| {
                if let Item::Proto(p) = item {
                    Some(p)
                } else {
                    None
                }
            })
            .collect();
        let mut seen: BTreeSet<&str> = BTreeSet::new();
        for proto in own {
            if !seen.insert(proto.name.text.as_str()) {
                self.error(
                    file,
                    Diagnostic::warning(
                        proto.name.span,
                        format!(
                            "PROTO '{}' is defined twice; the later definition is used",
                            proto.name.text
                        ),
                    )
                    .with_code("proto-redefined"),
                );
            }
            list.push(ProtoDef::file_level(file, proto));
        }
        let list = Rc::new(list);
        // PROTOs of one file see each other: bodies look the file's table up when instantiated.
        self.file_scopes.insert(file.0, list.clone());
        list
    }

    /// What a PROTO's body sees: its file's PROTOs, then those of enclosing PROTO bodies.
    fn visible_protos(&self, def: &ProtoDef) -> ProtoTable {
        let file_level = self
            .file_scopes
            .get(&def.file.0)
            .cloned()
            .unwrap_or_default();
        if def.enclosing.is_empty() {
            return file_level;
        }
        let mut all: Vec<(String, Rc<ProtoDef>)> = file_level.iter().cloned().collect();
        all.extend(def.enclosing.iter().cloned());
        Rc::new(all)
    }

    fn extern_proto(
        &mut self,
        file: FileId,
        extern_proto: &syntax::ExternProto,
        list: &mut Vec<(String, Rc<ProtoDef>)>,
        depth: usize,
    ) {
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
            if path_part.contains("://") {
                if let Some(inside) = crate::webots::webots_path(path_part) {
                    if let Some(path) =
                        crate::proto_path::find(&self.options.proto_path, inside, &name)
                    {
                        if self.extern_from_file(file, &path, url, &name, list, depth) {
                            return;
                        }
                        continue;
                    }
                    if WEBOTS_STANDINS.iter().any(|(n, _, _)| *n == name) {
                        // The stand-in is already in the table, after regatta's own PROTOs.
                        self.standin_urls
                            .entry(name)
                            .or_insert_with(|| url.value.clone());
                        return;
                    }
                }
                self.unresolved
                    .entry(name)
                    .or_insert_with(|| url.value.clone());
                continue;
            }
            let Some(base) = self.options.base_dir.clone() else {
                self.unresolved
                    .entry(name)
                    .or_insert_with(|| url.value.clone());
                continue;
            };
            let path = base.join(path_part);
            if !path.exists() {
                self.strict_or_warn(
                    file,
                    Diagnostic::error(
                        url.span,
                        format!("EXTERNPROTO file '{path_part}' does not exist"),
                    )
                    .with_code("externproto"),
                );
                self.unresolved
                    .entry(name)
                    .or_insert_with(|| url.value.clone());
                continue;
            }
            if self.extern_from_file(file, &path, url, &name, list, depth) {
                return;
            }
        }
    }

    /// Reads the PROTO `name` from the file at `path` into `list`; false (after reporting)
    /// when the file cannot be read or defines no such PROTO.
    fn extern_from_file(
        &mut self,
        file: FileId,
        path: &Path,
        url: &syntax::StringLit,
        name: &str,
        list: &mut Vec<(String, Rc<ProtoDef>)>,
        depth: usize,
    ) -> bool {
        let Some(loaded) = self.load_file(file, path, url.span, depth) else {
            return false;
        };
        let parsed = self.parse(loaded);
        let found = parsed.items.iter().find_map(|item| match item {
            Item::Proto(p) if p.name.text == name => Some(p.clone()),
            _ => None,
        });
        match found {
            Some(proto) => {
                self.file_protos(loaded, &parsed, depth + 1);
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
                        format!("'{}' defines no PROTO named '{name}'", url.value),
                    )
                    .with_code("externproto"),
                );
                false
            }
        }
    }

    /// Reads a file named by EXTERNPROTO or Inline, once.
    fn load_file(&mut self, from: FileId, path: &Path, span: Span, depth: usize) -> Option<FileId> {
        if depth >= MAX_INSTANCE_DEPTH {
            self.error(
                from,
                Diagnostic::error(span, "files include each other too deeply").with_code("depth"),
            );
            return None;
        }
        let key = path.canonicalize().unwrap_or_else(|_| path.to_owned());
        if let Some(&id) = self.loaded.get(&key) {
            return Some(id);
        }
        match SourceText::read(path) {
            Ok(source) => {
                let id = self.add_file(source);
                self.loaded.insert(key, id);
                Some(id)
            }
            Err(error) => {
                // Name the file as written (relative), so messages do not depend on the checkout.
                let reason = match &error {
                    regatta_parser::SourceError::Io { source, .. } => source.to_string(),
                    other => other.to_string(),
                };
                let shown = path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                self.error(
                    from,
                    Diagnostic::error(span, format!("cannot read '{shown}': {reason}"))
                        .with_code("io"),
                );
                None
            }
        }
    }

    fn lower_world(&mut self, file: FileId) {
        let parsed = self.parse(file);
        let header = parsed.header.clone();
        let protos = self.file_protos(file, &parsed, 0);
        let mut scope = Scope {
            protos,
            ..Scope::new(file)
        };
        self.decide_axes(header.as_ref(), &parsed);
        let roots = self.lower_items(&parsed.items, &mut scope, true);
        self.roots = roots;
    }

    fn lower_items(&mut self, items: &[Item], scope: &mut Scope, top_level: bool) -> Vec<NodeId> {
        let mut roots = Vec::new();
        for item in items {
            match item {
                Item::Node(node) => {
                    if let Some(id) = self.lower_node(
                        node,
                        scope,
                        &["child".to_owned(), "robot".to_owned()],
                        "the world",
                    ) {
                        roots.push(id);
                    }
                }
                Item::Template(template) if top_level => self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(
                        template.span,
                        "template code outside a PROTO is not evaluated",
                    )
                    .with_code("template"),
                ),
                Item::Route(route) => self.error(
                    scope.file,
                    Diagnostic::warning(
                        route.span,
                        "ROUTEs are read but not simulated: regatta has no event model",
                    )
                    .with_code("route"),
                ),
                _ => {}
            }
        }
        roots
    }

    /// The world's up axis and object convention (see [`crate::webots`]), read before its
    /// nodes are typed: `WorldInfo.coordinateSystem` if written, else the header.
    fn decide_axes(&mut self, header: Option<&syntax::Header>, parsed: &syntax::SourceFile) {
        let mut declared = None;
        for item in &parsed.items {
            let Item::Node(syntax::Node {
                kind:
                    NodeKind::Instance {
                        type_name,
                        body: Some(body),
                    },
                ..
            }) = item
            else {
                continue;
            };
            if type_name.text != "WorldInfo" {
                continue;
            }
            for field in &body.items {
                if let BodyItem::Field(f) = field {
                    if f.name.text == "coordinateSystem" {
                        if let syntax::FieldValue::Value(syntax::Value {
                            items: Items::Atoms(atoms),
                            ..
                        }) = &f.value
                        {
                            if let Some(Atom::String(system)) = atoms.first() {
                                declared = Some(system.value.clone());
                            }
                        }
                    }
                }
            }
        }
        // (year, letter) of a Webots header.
        let version = match header {
            Some(syntax::Header {
                dialect: Dialect::Webots,
                version,
                ..
            }) => version.strip_prefix('R').and_then(|v| {
                let year = v.get(..4)?.parse::<u32>().ok()?;
                let letter = v[4..].chars().next().unwrap_or('a');
                Some((year, letter))
            }),
            _ => None,
        };
        self.up_axis = match declared.as_deref() {
            Some("NUE" | "EUN") => UpAxis::Y,
            Some("ENU") => UpAxis::Z,
            // WorldInfo.coordinateSystem appeared in R2020b with "ENU" as its default.
            _ => match version {
                Some(v) if v >= (2020, 'b') => UpAxis::Z,
                _ => UpAxis::Y,
            },
        };
        self.objects = match (self.up_axis, version) {
            (UpAxis::Z, Some(v)) if v >= (2022, 'a') => crate::webots::Objects::Flu,
            _ => crate::webots::Objects::Legacy,
        };
    }

    fn alloc(&mut self, node: SceneNode, file: FileId, span: Span) -> Option<NodeId> {
        if self.nodes.len() >= MAX_NODES {
            if !self.budget_reported {
                self.budget_reported = true;
                self.error(
                    file,
                    Diagnostic::error(span, format!("the scene expands to more than {MAX_NODES} nodes"))
                        .with_label("expansion stopped here")
                        .with_note("PROTOs or USEs multiply each other; check for accidental exponential nesting")
                        .with_code("too-large"),
                );
            }
            return None;
        }
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(node);
        Some(id)
    }

    /// Types one node where `accepted` classes may stand. `place` names the field, for messages.
    fn lower_node(
        &mut self,
        node: &syntax::Node,
        scope: &mut Scope,
        accepted: &[String],
        place: &str,
    ) -> Option<NodeId> {
        if self.budget_reported {
            // The scene is already too large: stop expanding anything.
            return None;
        }
        let id = match &node.kind {
            NodeKind::Use(name) => {
                if name.text.is_empty() {
                    return None;
                }
                match scope.defs.get(&name.text) {
                    Some(&id) => id,
                    None if scope.skipped_defs.contains(&name.text) => {
                        self.error(
                            scope.file,
                            Diagnostic::warning(
                                name.span,
                                format!("USE {} refers to a node that was skipped", name.text),
                            )
                            .with_code("use-of-skipped"),
                        );
                        return None;
                    }
                    None => {
                        let mut diagnostic = Diagnostic::error(
                            name.span,
                            format!("no node was DEF'd as '{}' before this USE", name.text),
                        )
                        .with_label("unknown DEF name")
                        .with_code("unknown-use");
                        if let Some(close) =
                            did_you_mean(&name.text, scope.defs.keys().map(String::as_str))
                        {
                            diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                        }
                        self.error(scope.file, diagnostic);
                        return None;
                    }
                }
            }
            NodeKind::Instance { type_name, body } => {
                if type_name.text.is_empty() {
                    return None;
                }
                let empty = Vec::new();
                let items = body.as_ref().map_or(&empty, |b| &b.items);
                let id = if let Some(proto) = scope.find_proto(&type_name.text) {
                    self.instantiate(&proto, node, items, scope)?
                } else if let Some(spec) = self.catalogue().lookup(&type_name.text) {
                    self.lower_builtin(spec, node, items, scope)?
                } else {
                    let url = self.unresolved.get(&type_name.text).cloned();
                    let sets_controller = items.iter().any(
                        |item| matches!(item, BodyItem::Field(f) if f.name.text == "controller"),
                    );
                    // Robots stand at the top of a world; a PROTO of Webots' robots folder met
                    // deeper is an extension (a turret board, a gripper).
                    let in_robots_folder = |u: &str| {
                        let resolved = match &self.options.base_dir {
                            Some(base) if !u.contains("://") => base.join(u),
                            _ => PathBuf::from(u),
                        };
                        resolved
                            .to_string_lossy()
                            .replace('\\', "/")
                            .contains("/robots/")
                    };
                    let robot_proto =
                        place == "the world" && url.as_deref().is_some_and(in_robots_folder);
                    if sets_controller || robot_proto {
                        self.unbuilt_robots.push(UnbuiltRobot {
                            type_name: type_name.text.clone(),
                            url,
                            file: scope.file,
                            span: type_name.span,
                        });
                    }
                    self.unknown_node(type_name, scope);
                    syntax::walk_node(node, &mut |inner| {
                        if let Some(def) = &inner.def {
                            scope.skipped_defs.insert(def.text.clone());
                        }
                    });
                    return None;
                };
                if let Some(def) = &node.def {
                    if !def.text.is_empty() {
                        self.nodes[id.index()].def_name = Some(def.text.clone());
                        scope.defs.insert(def.text.clone(), id);
                    }
                }
                id
            }
        };
        let spec = self.catalogue().spec(self.nodes[id.index()].spec);
        if !spec.fits(accepted) {
            let accepted_list = accepted.join(" or ");
            self.strict_or_warn(
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("a {} node cannot stand in {place}", spec.name),
                )
                .with_label(format!(
                    "{} is a {} node",
                    spec.name,
                    spec.classes.join("/")
                ))
                .with_note(format!("{place} accepts {accepted_list} nodes"))
                .with_code("wrong-node-class"),
            );
            return None;
        }
        Some(id)
    }

    fn unknown_node(&mut self, type_name: &syntax::Ident, scope: &Scope) {
        let name = &type_name.text;
        let diagnostic = if let Some(url) = self.unresolved.get(name) {
            Diagnostic::error(
                type_name.span,
                format!("Skipped unknown '{name}' node or PROTO."),
            )
            .with_label("its PROTO is not available")
            .with_note(if crate::webots::webots_path(url).is_some() {
                format!(
                    "its EXTERNPROTO points to {url}: regatta has no built-in stand-in for it and never fetches from the network; --proto-path DIR (or REGATTA_PROTO_PATH) can point at a Webots installation that has it"
                )
            } else {
                format!(
                    "its EXTERNPROTO points to {url}, and regatta never fetches from the network"
                )
            })
        } else {
            let mut diagnostic = Diagnostic::error(
                type_name.span,
                format!("Skipped unknown '{name}' node or PROTO."),
            )
            .with_label("unknown node type");
            if let Some(reason) = crate::webots::unsimulated(name) {
                diagnostic = diagnostic.with_note(format!("{name}: {reason}"));
            }
            let mut candidates: Vec<&str> = self.catalogue().names().collect();
            candidates.extend(scope.protos.iter().map(|(n, _)| n.as_str()));
            if let Some(close) = did_you_mean(name, candidates) {
                diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
            }
            diagnostic
        };
        self.strict_or_warn(scope.file, diagnostic.with_code("unknown-node"));
    }

    fn lower_builtin(
        &mut self,
        spec_id: SpecId,
        node: &syntax::Node,
        items: &[BodyItem],
        scope: &mut Scope,
    ) -> Option<NodeId> {
        let catalogue = self.catalogue();
        let spec = catalogue.spec(spec_id);
        let mut fields: Vec<Value> = spec
            .fields
            .iter()
            .map(|f| f.default_value.clone().unwrap_or(Value::Bool(false)))
            .collect();
        let mut written = vec![false; fields.len()];
        let mut value_spans = vec![None; fields.len()];
        let mut seen: HashMap<&str, Span> = HashMap::new();
        for item in items {
            match item {
                BodyItem::Field(field) => {
                    if field.hidden {
                        continue;
                    }
                    let Some(index) = spec.field_index(&field.name.text) else {
                        let mut diagnostic = Diagnostic::error(field.name.span, format!("Skipped unknown '{}' field in {} node.", field.name.text, spec.name))
                            .with_label("unknown field")
                            .with_code("unknown-field");
                        if let Some(close) = did_you_mean(&field.name.text, spec.fields.iter().map(|f| f.name.as_str())) {
                            diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                        }
                        self.strict_or_warn(scope.file, diagnostic);
                        continue;
                    };
                    if let Some(previous) = seen.insert(field.name.text.as_str(), field.name.span) {
                        self.error(
                            scope.file,
                            Diagnostic::warning(field.name.span, format!("'{}' is set twice; the last value is used", field.name.text))
                                .with_secondary(previous, "first set here")
                                .with_code("duplicate-field"),
                        );
                    }
                    let field_spec = &spec.fields[index];
                    if let Some(value) = self.lower_field_value(&field.value, field_spec.ty(), Some(field_spec), scope, &field.name.text, field.name.span) {
                        fields[index] = value;
                        written[index] = true;
                        value_spans[index] = match &field.value {
                            syntax::FieldValue::Value(value) => Some(Origin {
                                file: scope.file,
                                span: value.span,
                            }),
                            // Bound through IS: where the instance wrote it, if it did.
                            syntax::FieldValue::Is(target) => scope
                                .interface
                                .as_ref()
                                .and_then(|i| i.get(&target.text))
                                .and_then(|(_, _, origin)| *origin)
                                .map(|(file, span)| Origin { file, span }),
                            syntax::FieldValue::Missing { .. } => None,
                        };
                    }
                }
                BodyItem::Declaration(declaration) => self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(declaration.span, "a field declaration belongs in a PROTO interface, not in a node")
                        .with_note("files like Webots' resources/nodes/*.wrl declare node models; they are not worlds")
                        .with_code("declaration-in-node"),
                ),
                BodyItem::Template(template) => self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(template.span, "template code is not evaluated by regatta").with_code("template"),
                ),
                BodyItem::Proto(proto) => self.error(
                    scope.file,
                    Diagnostic::warning(proto.name.span, "a PROTO inside a node is not visible outside it and is ignored").with_code("nested-proto"),
                ),
                BodyItem::Route(route) => self.error(
                    scope.file,
                    Diagnostic::warning(route.span, "ROUTEs are read but not simulated: regatta has no event model").with_code("route"),
                ),
            }
        }
        let origin = Origin {
            file: scope.file,
            span: node.span,
        };
        if spec.name == "Inline" {
            return self.inline(&fields, written[0], node, scope);
        }
        self.alloc(
            SceneNode {
                spec: spec_id,
                fields,
                written,
                value_spans,
                def_name: None,
                proto_names: Vec::new(),
                origin,
                axes: Default::default(),
            },
            scope.file,
            node.span,
        )
    }

    /// Inline becomes a Group holding the included file's nodes.
    fn inline(
        &mut self,
        fields: &[Value],
        written: bool,
        node: &syntax::Node,
        scope: &Scope,
    ) -> Option<NodeId> {
        let group = self
            .catalogue()
            .lookup("Group")
            .expect("catalogue has Group");
        let mut children = Vec::new();
        let urls = match &fields[0] {
            Value::Strings(urls) if written => urls.clone(),
            _ => Vec::new(),
        };
        if let Some(url) = urls.first() {
            if url.contains("://") {
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(node.span, format!("Inline url '{url}' is not a local file; regatta never fetches from the network")).with_code("inline"),
                );
            } else if let Some(base) = self.options.base_dir.clone() {
                if self.instance_stack.len() < MAX_INSTANCE_DEPTH
                    && !self.instance_stack.iter().any(|s| s == url)
                {
                    if let Some(file) = self.load_file(
                        scope.file,
                        &base.join(url),
                        node.span,
                        self.instance_stack.len(),
                    ) {
                        self.instance_stack.push(url.clone());
                        let parsed = self.parse(file);
                        let protos = self.file_protos(file, &parsed, self.instance_stack.len());
                        let mut inner = Scope {
                            protos,
                            ..Scope::new(file)
                        };
                        children = self.lower_items(&parsed.items, &mut inner, true);
                        self.instance_stack.pop();
                    }
                } else {
                    self.error(
                        scope.file,
                        Diagnostic::error(node.span, format!("Inline '{url}' includes itself"))
                            .with_code("inline"),
                    );
                }
            } else {
                self.error(
                    scope.file,
                    Diagnostic::error(
                        node.span,
                        "Inline files cannot be read when the world comes from standard input",
                    )
                    .with_code("inline"),
                );
            }
        }
        let spec = self.catalogue().spec(group);
        let mut group_fields: Vec<Value> = spec
            .fields
            .iter()
            .map(|f| f.default_value().clone())
            .collect();
        group_fields[0] = Value::Nodes(children);
        self.alloc(
            SceneNode {
                spec: group,
                written: vec![true],
                value_spans: vec![None; group_fields.len()],
                fields: group_fields,
                def_name: None,
                proto_names: vec!["Inline".to_owned()],
                origin: Origin {
                    file: scope.file,
                    span: node.span,
                },
                axes: Default::default(),
            },
            scope.file,
            node.span,
        )
    }

    fn instantiate(
        &mut self,
        def: &Rc<ProtoDef>,
        node: &syntax::Node,
        items: &[BodyItem],
        scope: &mut Scope,
    ) -> Option<NodeId> {
        let proto = &def.proto;
        let name = &proto.name.text;
        if self.instance_stack.iter().any(|n| n == name) {
            self.error(
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("Recursive definition of PROTO node '{name}' is not supported."),
                )
                .with_label("this instance is inside its own definition")
                .with_code("recursive-proto"),
            );
            return None;
        }
        if self.instance_stack.len() >= MAX_INSTANCE_DEPTH {
            if std::mem::replace(&mut self.depth_reported, true) {
                return None;
            }
            self.error(
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("PROTO instances nested deeper than {MAX_INSTANCE_DEPTH} levels"),
                )
                .with_code("depth"),
            );
            return None;
        }
        if has_template(proto) {
            let proto_file = &self.sources[def.file.0 as usize];
            let lua = proto_file
                .text
                .lines()
                .take_while(|l| l.starts_with('#') || l.trim().is_empty())
                .any(|l| l.contains("template language: lua"))
                || proto_file.text[proto.span.range()].contains("%{");
            let message = if lua {
                format!(
                    "PROTO '{name}' ({}) is written with a Lua template (Webots before R2022a); regatta does not run Lua templates, so this instance is skipped",
                    proto_file.name
                )
            } else {
                format!(
                    "PROTO '{name}' ({}) contains JavaScript template statements, which regatta does not run (only arithmetic expressions %<= … >% are evaluated); this instance is skipped",
                    proto_file.name
                )
            };
            self.strict_or_warn(
                scope.file,
                Diagnostic::error(node.span, message).with_code("template"),
            );
            return None;
        }
        let instantiating = self
            .file_authoring
            .get(&scope.file.0)
            .copied()
            .unwrap_or_default();
        let proto_authoring = self
            .file_authoring
            .get(&def.file.0)
            .copied()
            .unwrap_or_default();
        if proto_authoring == crate::webots::Authoring::World {
            // Built-in PROTOs accept documented fields they do not use.
            self.check_interface_once(def);
        } else if matches!(
            proto_authoring,
            crate::webots::Authoring::Webots
                | crate::webots::Authoring::WebotsRobot
                | crate::webots::Authoring::WebotsFlu
        ) && !self.substitutions.iter().any(|s| &s.name == name)
        {
            let url = self
                .standin_urls
                .get(name)
                .cloned()
                .unwrap_or_else(|| format!("webots://…/{name}.proto"));
            self.substitutions.push(Substitution {
                name: name.clone(),
                url,
                file: scope.file,
                span: node.span,
            });
        }
        // Instance fields, typed in the instance's scope.
        let mut bindings: Bindings = BTreeMap::new();
        for item in items {
            let BodyItem::Field(field) = item else {
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(
                        body_item_span(item),
                        format!("only field values may stand in an instance of PROTO '{name}'"),
                    )
                    .with_code("proto-instance"),
                );
                continue;
            };
            if field.hidden {
                continue;
            }
            let Some(declaration) = proto
                .interface
                .iter()
                .find(|d| d.name.text == field.name.text)
            else {
                let mut diagnostic = Diagnostic::error(
                    field.name.span,
                    format!(
                        "Skipped unknown '{}' parameter in {name} PROTO.",
                        field.name.text
                    ),
                )
                .with_label("unknown PROTO field")
                .with_code("unknown-field");
                if let Some(close) = did_you_mean(
                    &field.name.text,
                    proto.interface.iter().map(|d| d.name.text.as_str()),
                ) {
                    diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
                }
                self.strict_or_warn(scope.file, diagnostic);
                continue;
            };
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            let value = self.lower_field_value(
                &field.value,
                ty,
                None,
                scope,
                &field.name.text,
                field.name.span,
            );
            if let Some(value) = value {
                self.check_restriction(declaration, &value, def.file, scope.file, field.name.span);
                bindings.insert(
                    field.name.text.clone(),
                    (ty, Some(value), Some((scope.file, field.span))),
                );
            }
        }
        // Defaults, typed in the PROTO's own file.
        let mut default_scope = Scope {
            protos: self.visible_protos(def),
            ..Scope::new(def.file)
        };
        for declaration in &proto.interface {
            if bindings.contains_key(&declaration.name.text) {
                continue;
            }
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            let value = match &declaration.default {
                Some(default) => {
                    let value = self.lower_field_value(
                        default,
                        ty,
                        None,
                        &mut default_scope,
                        &declaration.name.text,
                        declaration.name.span,
                    );
                    if let Some(value) = &value {
                        self.check_restriction(
                            declaration,
                            value,
                            def.file,
                            def.file,
                            declaration.name.span,
                        );
                    }
                    value
                }
                None => None,
            };
            bindings.insert(declaration.name.text.clone(), (ty, value, None));
        }
        // The body, in a scope of its own.
        self.instance_stack.push(name.clone());
        let visible = self.visible_protos(def);
        let mut nested_protos: Vec<(String, Rc<ProtoDef>)> = Vec::new();
        let mut body_scope = Scope {
            file: def.file,
            defs: HashMap::new(),
            protos: visible.clone(),
            interface: Some(Rc::new(bindings)),
            skipped_defs: BTreeSet::new(),
        };
        let mut root = None;
        let mut found_root = false;
        for item in &proto.body {
            match item {
                Item::Proto(nested) => {
                    // Rare: only bodies that define PROTOs pay for a scope of their own.
                    let mut enclosing: Vec<(String, Rc<ProtoDef>)> =
                        def.enclosing.iter().cloned().collect();
                    enclosing.extend(nested_protos.iter().cloned());
                    nested_protos.push((
                        nested.name.text.clone(),
                        Rc::new(ProtoDef {
                            file: def.file,
                            proto: nested.clone(),
                            enclosing: Rc::new(enclosing),
                        }),
                    ));
                    let mut all: Vec<(String, Rc<ProtoDef>)> = visible.iter().cloned().collect();
                    all.extend(nested_protos.iter().cloned());
                    body_scope.protos = Rc::new(all);
                }
                Item::Node(body_node) if !found_root => {
                    found_root = true;
                    root = self.lower_node(
                        body_node,
                        &mut body_scope,
                        &[],
                        &format!("PROTO '{name}'"),
                    );
                }
                _ => {}
            }
        }
        self.instance_stack.pop();
        if !found_root {
            self.error(
                def.file,
                Diagnostic::error(
                    proto.name.span,
                    format!("PROTO '{name}' has no node in its body"),
                )
                .with_code("empty-proto"),
            );
        }
        let root = root?;
        self.nodes[root.index()].proto_names.push(name.clone());
        if instantiating != proto_authoring {
            self.instance_authoring.insert(root.0, instantiating);
        }
        Some(root)
    }

    /// Webots' "PROTO parameter 'x' has no matching IS field." and IS targets that name no
    /// interface field, once per PROTO definition.
    fn check_interface_once(&mut self, def: &Rc<ProtoDef>) {
        let key = (def.file.0, def.proto.span.start);
        if !self.checked_protos.insert(key) {
            return;
        }
        let mut targets: Vec<&syntax::Ident> = Vec::new();
        collect_is_targets(&def.proto.body, &mut targets);
        // Template expressions use fields too.
        let text = self.sources[def.file.0 as usize].text.clone();
        let body_text = &text[def.proto.span.range()];
        for declaration in &def.proto.interface {
            let is_event = matches!(
                declaration.keyword.text.as_str(),
                "eventIn" | "eventOut" | "unconnectedField"
            );
            let in_template = body_text.contains(&format!("fields.{}.", declaration.name.text));
            if !is_event && !in_template && !targets.iter().any(|t| t.text == declaration.name.text)
            {
                self.error(
                    def.file,
                    Diagnostic::warning(
                        declaration.name.span,
                        format!(
                            "PROTO parameter '{}' has no matching IS field.",
                            declaration.name.text
                        ),
                    )
                    .with_code("unused-proto-field"),
                );
            }
        }
    }

    fn check_restriction(
        &mut self,
        declaration: &syntax::Declaration,
        value: &Value,
        proto_file: FileId,
        file: FileId,
        span: Span,
    ) {
        let Some(restriction) = &declaration.restriction else {
            return;
        };
        let Items::Atoms(atoms) = &restriction.items else {
            return;
        };
        let allowed_numbers: Vec<f64> = atoms
            .iter()
            .filter_map(|a| {
                if let Atom::Number(n) = a {
                    Some(n.value)
                } else {
                    None
                }
            })
            .collect();
        let allowed_strings: Vec<&str> = atoms
            .iter()
            .filter_map(|a| {
                if let Atom::String(s) = a {
                    Some(s.value.as_str())
                } else {
                    None
                }
            })
            .collect();
        let ok = match value {
            Value::String(s) if !allowed_strings.is_empty() => {
                allowed_strings.contains(&s.as_str())
            }
            Value::Float(x) if !allowed_numbers.is_empty() => allowed_numbers.contains(x),
            Value::Int(i) if !allowed_numbers.is_empty() => allowed_numbers.contains(&(*i as f64)),
            Value::Vec3(v) if !allowed_numbers.is_empty() => {
                allowed_numbers.chunks(3).any(|c| c == v)
            }
            _ => true,
        };
        if !ok {
            let allowed =
                self.sources[proto_file.0 as usize].text[restriction.span.range()].to_owned();
            self.error(
                file,
                Diagnostic::error(
                    span,
                    format!(
                        "Invalid '{}': the value should be in the list: {allowed}.",
                        declaration.name.text
                    ),
                )
                .with_label("not an allowed value")
                .with_code("restricted-value"),
            );
        }
    }

    /// Types one field value against `ty`; `spec` adds the catalogue's range checks.
    fn lower_field_value(
        &mut self,
        value: &syntax::FieldValue,
        ty: FieldType,
        spec: Option<&FieldSpec>,
        scope: &mut Scope,
        field_name: &str,
        field_span: Span,
    ) -> Option<Value> {
        let file = scope.file;
        match value {
            syntax::FieldValue::Missing { found } => {
                let text = &self.sources[file.0 as usize].text;
                let found_text = if (found.start as usize) < text.len() && !found.is_empty() {
                    format!("'{}'", &text[found.range()])
                } else {
                    "end of file".to_owned()
                };
                let message = format!("Expected {}, found {found_text}.", ty.base.item_noun());
                self.refined_missing.insert((file.0, field_span.start));
                self.error(
                    file,
                    Diagnostic::error(field_span, message)
                        .with_label(format!("'{field_name}' needs a {ty} value"))
                        .with_secondary(*found, "found this instead")
                        .with_code("missing-value"),
                );
                None
            }
            syntax::FieldValue::Is(target) => {
                let Some(interface) = scope.interface.clone() else {
                    self.error(
                        file,
                        Diagnostic::error(target.span, "IS may only be used inside a PROTO body")
                            .with_code("is-outside-proto"),
                    );
                    return None;
                };
                match interface.get(&target.text) {
                    Some((declared, bound, origin)) => {
                        if *declared != ty {
                            self.error(
                                file,
                                Diagnostic::error(target.span, format!("Type mismatch between '{}' PROTO parameter and field '{field_name}'.", target.text))
                                    .with_label(format!("'{}' is {declared}, '{field_name}' is {ty}", target.text))
                                    .with_code("is-type-mismatch"),
                            );
                            return None;
                        }
                        let value = bound.clone()?;
                        if let Some(spec) = spec {
                            // A value an instance passed in is blamed where the instance wrote
                            // it; the field keeps its default.
                            let (blamed_file, blamed_span) = origin.unwrap_or((file, target.span));
                            if !self.check_ranges(&value, spec, blamed_file, blamed_span) {
                                return None;
                            }
                        }
                        Some(value)
                    }
                    None => {
                        self.error(
                            file,
                            Diagnostic::error(
                                target.span,
                                format!(
                                    "'{}' is not a field of this PROTO's interface",
                                    target.text
                                ),
                            )
                            .with_code("unknown-is"),
                        );
                        None
                    }
                }
            }
            syntax::FieldValue::Value(value) => {
                let typed = self.lower_value(value, ty, spec, scope, field_name)?;
                if let Some(spec) = spec {
                    if !self.check_ranges(&typed, spec, file, value.span) {
                        return None;
                    }
                }
                Some(typed)
            }
        }
    }

    fn lower_value(
        &mut self,
        value: &syntax::Value,
        ty: FieldType,
        spec: Option<&FieldSpec>,
        scope: &mut Scope,
        field_name: &str,
    ) -> Option<Value> {
        let file = scope.file;
        if !ty.multi && value.bracketed {
            self.error(
                file,
                Diagnostic::error(
                    value.span,
                    format!("{ty} takes a single value, not a bracketed list"),
                )
                .with_code("type"),
            );
            return None;
        }
        let expanded;
        let value = if let Items::Atoms(atoms) = &value.items {
            if atoms.iter().any(|a| matches!(a, Atom::Template(_))) {
                expanded = self.expand_templates(value, atoms, scope)?;
                &expanded
            } else {
                value
            }
        } else {
            value
        };
        let base = ty.base;
        if base.is_numeric() {
            let numbers: std::borrow::Cow<[f64]> = match &value.items {
                Items::Numbers(list) => std::borrow::Cow::Borrowed(&list.values),
                Items::Atoms(atoms) => {
                    let mut numbers = Vec::with_capacity(atoms.len());
                    for atom in atoms {
                        match atom {
                            Atom::Number(n) => numbers.push(n.value),
                            other => {
                                let text =
                                    &self.sources[file.0 as usize].text[other.span().range()];
                                self.error(
                                    file,
                                    Diagnostic::error(
                                        other.span(),
                                        format!(
                                            "Expected {}, found '{}'.",
                                            base.item_noun(),
                                            shorten(text)
                                        ),
                                    )
                                    .with_label(format!("'{field_name}' is {ty}"))
                                    .with_code("type"),
                                );
                                return None;
                            }
                        }
                    }
                    std::borrow::Cow::Owned(numbers)
                }
            };
            return self.numeric_value(&numbers, ty, value.span, file, field_name);
        }
        let no_atoms = Vec::new();
        let atoms = match &value.items {
            Items::Atoms(atoms) => atoms,
            Items::Numbers(list) if list.values.is_empty() => &no_atoms,
            Items::Numbers(_) => {
                self.error(
                    file,
                    Diagnostic::error(
                        value.span,
                        format!("Expected {}, found a number.", base.item_noun()),
                    )
                    .with_label(format!("'{field_name}' is {ty}"))
                    .with_code("type"),
                );
                return None;
            }
        };
        if !ty.multi && atoms.len() != 1 {
            self.error(
                file,
                Diagnostic::error(
                    value.span,
                    format!("expected 1 value for {ty}, found {}", atoms.len()),
                )
                .with_code("arity"),
            );
            return None;
        }
        let wrong = |lowerer: &mut Self, atom: &Atom| {
            let text = lowerer.sources[file.0 as usize].text[atom.span().range()].to_owned();
            lowerer.error(
                file,
                Diagnostic::error(
                    atom.span(),
                    format!("Expected {}, found '{}'.", base.item_noun(), shorten(&text)),
                )
                .with_label(format!("'{field_name}' is {ty}"))
                .with_code("type"),
            );
        };
        match base {
            BaseType::Bool => {
                let mut values = Vec::with_capacity(atoms.len());
                for atom in atoms {
                    match atom {
                        Atom::Bool(_, b) => values.push(*b),
                        other => {
                            wrong(self, other);
                            return None;
                        }
                    }
                }
                Some(if ty.multi {
                    Value::Bools(values)
                } else {
                    Value::Bool(values[0])
                })
            }
            BaseType::String => {
                let mut values = Vec::with_capacity(atoms.len());
                for atom in atoms {
                    match atom {
                        Atom::String(s) => {
                            if let Some(spec) = spec {
                                if !spec.values.is_empty() && !spec.values.contains(&s.value) {
                                    let allowed = spec
                                        .values
                                        .iter()
                                        .map(|v| format!("\"{v}\""))
                                        .collect::<Vec<_>>()
                                        .join(", ");
                                    let mut diagnostic = Diagnostic::error(
                                        s.span,
                                        format!(
                                            "\"{}\" is not a valid value of '{field_name}'",
                                            s.value
                                        ),
                                    )
                                    .with_label(format!("expected one of {allowed}"))
                                    .with_code("range");
                                    if let Some(close) = did_you_mean(
                                        &s.value,
                                        spec.values.iter().map(String::as_str),
                                    ) {
                                        diagnostic = diagnostic
                                            .with_note(format!("did you mean \"{close}\"?"));
                                    }
                                    self.error(file, diagnostic);
                                    return None;
                                }
                            }
                            values.push(s.value.clone());
                        }
                        other => {
                            wrong(self, other);
                            return None;
                        }
                    }
                }
                Some(if ty.multi {
                    Value::Strings(values)
                } else {
                    Value::String(values.pop().unwrap_or_default())
                })
            }
            BaseType::Node => {
                let accepted: Vec<String> = spec.map(|s| s.nodes.clone()).unwrap_or_default();
                let place = format!("'{field_name}'");
                if !ty.multi {
                    return match &atoms[0] {
                        Atom::Null(_) => Some(Value::Node(None)),
                        Atom::Node(node) => {
                            Some(Value::Node(self.lower_node(node, scope, &accepted, &place)))
                        }
                        other => {
                            wrong(self, other);
                            None
                        }
                    };
                }
                let mut ids = Vec::with_capacity(atoms.len());
                for atom in atoms {
                    match atom {
                        Atom::Node(node) => {
                            if let Some(id) = self.lower_node(node, scope, &accepted, &place) {
                                ids.push(id);
                            }
                        }
                        Atom::Null(span) => self.error(
                            file,
                            Diagnostic::warning(
                                *span,
                                format!("NULL in the MFNode field '{field_name}' is skipped"),
                            )
                            .with_code("null-in-mfnode"),
                        ),
                        other => {
                            wrong(self, other);
                            return None;
                        }
                    }
                }
                Some(Value::Nodes(ids))
            }
            _ => unreachable!("numeric types are handled above"),
        }
    }

    /// Replaces expression templates by the numbers they evaluate to (inside PROTO bodies).
    fn expand_templates(
        &mut self,
        value: &syntax::Value,
        atoms: &[Atom],
        scope: &Scope,
    ) -> Option<syntax::Value> {
        let file = scope.file;
        let mut out = Vec::with_capacity(atoms.len());
        for atom in atoms {
            let Atom::Template(template) = atom else {
                out.push(atom.clone());
                continue;
            };
            let text = self.sources[file.0 as usize].text[template.span.range()].to_owned();
            let result = match (&scope.interface, template.expression) {
                (Some(fields), true) => crate::template::evaluate(&text, fields),
                (None, _) => Err("template code outside a PROTO body is not evaluated".to_owned()),
                (_, false) => Err("template statements are not evaluated by regatta; only arithmetic expressions (%<= … >%) are".to_owned()),
            };
            match result {
                Ok(crate::template::Evaluated::Number(x)) => {
                    out.push(Atom::Number(syntax::Number {
                        span: template.span,
                        value: x,
                        hex: false,
                    }))
                }
                Ok(crate::template::Evaluated::Vector(v)) => out.extend(v.into_iter().map(|x| {
                    Atom::Number(syntax::Number {
                        span: template.span,
                        value: x,
                        hex: false,
                    })
                })),
                Err(message) => {
                    self.strict_or_warn(
                        file,
                        Diagnostic::error(template.span, message)
                            .with_label("this template")
                            .with_code("template"),
                    );
                    return None;
                }
            }
        }
        Some(syntax::Value {
            span: value.span,
            bracketed: value.bracketed,
            items: Items::Atoms(out),
        })
    }

    fn numeric_value(
        &mut self,
        numbers: &[f64],
        ty: FieldType,
        span: Span,
        file: FileId,
        field_name: &str,
    ) -> Option<Value> {
        let base = ty.base;
        let integral = matches!(base, BaseType::Int32 | BaseType::Image);
        if integral {
            if let Some(bad) = numbers
                .iter()
                .find(|x| x.fract() != 0.0 || **x < i32::MIN as f64 || **x > u32::MAX as f64)
            {
                self.error(
                    file,
                    Diagnostic::error(span, format!("Expected integer value, found {bad}."))
                        .with_label(format!("'{field_name}' is {ty}"))
                        .with_code("type"),
                );
                return None;
            }
        }
        if base == BaseType::Image {
            return self.image_value(numbers, span, file);
        }
        let arity = base.arity();
        let count_ok = if ty.multi {
            numbers.len() % arity == 0
        } else {
            numbers.len() == arity
        };
        if !count_ok {
            let plural = if arity == 1 { "number" } else { "numbers" };
            let message = if ty.multi {
                format!(
                    "expected a multiple of {arity} numbers for {ty}, found {}",
                    numbers.len()
                )
            } else {
                format!(
                    "expected {arity} {plural} for {ty}, found {}",
                    numbers.len()
                )
            };
            self.error(
                file,
                Diagnostic::error(span, message)
                    .with_label(format!("'{field_name}' is {ty}"))
                    .with_code("arity"),
            );
            return None;
        }
        if let Some(bad) = numbers.iter().find(|x| !x.is_finite()) {
            self.error(
                file,
                Diagnostic::error(span, format!("{bad} is out of range for '{field_name}'"))
                    .with_code("range"),
            );
            return None;
        }
        let value = match (base, ty.multi) {
            (BaseType::Int32, false) => Value::Int(numbers[0] as i32),
            (BaseType::Int32, true) => Value::Ints(numbers.iter().map(|&x| x as i32).collect()),
            (BaseType::Float | BaseType::Time, false) => Value::Float(numbers[0]),
            (BaseType::Float | BaseType::Time, true) => Value::Floats(numbers.to_vec()),
            (BaseType::Vec2f, false) => Value::Vec2([numbers[0], numbers[1]]),
            (BaseType::Vec2f, true) => {
                Value::Vec2s(numbers.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
            }
            (BaseType::Vec3f | BaseType::Color, false) => {
                Value::Vec3([numbers[0], numbers[1], numbers[2]])
            }
            (BaseType::Vec3f | BaseType::Color, true) => Value::Vec3s(
                numbers
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            ),
            (BaseType::Rotation, false) => Value::Rotation(self.normalize_rotation(
                [numbers[0], numbers[1], numbers[2], numbers[3]],
                span,
                file,
            )?),
            (BaseType::Rotation, true) => {
                let mut rotations = Vec::with_capacity(numbers.len() / 4);
                for c in numbers.chunks_exact(4) {
                    rotations.push(self.normalize_rotation(
                        [c[0], c[1], c[2], c[3]],
                        span,
                        file,
                    )?);
                }
                Value::Rotations(rotations)
            }
            _ => unreachable!("non-numeric base types are handled by the caller"),
        };
        if base == BaseType::Color {
            let components: &[f64] = numbers;
            if let Some(bad) = components.iter().find(|c| !(0.0..=1.0).contains(*c)) {
                self.error(
                    file,
                    Diagnostic::error(span, format!("colour component {bad} is outside [0, 1]"))
                        .with_label(format!("'{field_name}' is {ty}"))
                        .with_code("range"),
                );
                return None;
            }
        }
        Some(value)
    }

    /// Old files leave rotation axes unnormalised: the axis is normalised; a zero axis is only
    /// accepted with a zero angle.
    fn normalize_rotation(&mut self, r: [f64; 4], span: Span, file: FileId) -> Option<[f64; 4]> {
        let length = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if length == 0.0 {
            if r[3] == 0.0 {
                return Some([0.0, 0.0, 1.0, 0.0]);
            }
            self.error(
                file,
                Diagnostic::error(span, "a rotation needs a non-zero axis").with_code("range"),
            );
            return None;
        }
        Some([r[0] / length, r[1] / length, r[2] / length, r[3]])
    }

    fn image_value(&mut self, numbers: &[f64], span: Span, file: FileId) -> Option<Value> {
        if numbers.len() < 3 {
            self.error(
                file,
                Diagnostic::error(span, "an SFImage starts with width, height and components")
                    .with_code("arity"),
            );
            return None;
        }
        let (width, height, components) = (numbers[0], numbers[1], numbers[2]);
        if width < 0.0 || height < 0.0 || !(0.0..=4.0).contains(&components) {
            self.error(
                file,
                Diagnostic::error(
                    span,
                    "SFImage width and height must be ≥ 0, components 0 to 4",
                )
                .with_code("range"),
            );
            return None;
        }
        let expected = (width * height) as usize;
        if numbers.len() - 3 != expected {
            self.error(
                file,
                Diagnostic::error(
                    span,
                    format!(
                        "an SFImage of {width}×{height} needs {expected} pixel values, found {}",
                        numbers.len() - 3
                    ),
                )
                .with_code("arity"),
            );
            return None;
        }
        Some(Value::Image(Image {
            width: width as u32,
            height: height as u32,
            components: components as u8,
            pixels: numbers[3..].iter().map(|&x| x as u32).collect(),
        }))
    }

    /// Checks min/max/above/count of a catalogue field; false (after reporting) if violated.
    fn check_ranges(&mut self, value: &Value, spec: &FieldSpec, file: FileId, span: Span) -> bool {
        let numbers: Vec<f64> = match value {
            Value::Int(i) => vec![*i as f64],
            Value::Float(x) => vec![*x],
            Value::Vec2(v) => v.to_vec(),
            Value::Vec3(v) => v.to_vec(),
            Value::Ints(v) => v.iter().map(|&i| i as f64).collect(),
            Value::Floats(v) => v.clone(),
            Value::Vec2s(v) => v.iter().flatten().copied().collect(),
            Value::Vec3s(v) => v.iter().flatten().copied().collect(),
            _ => Vec::new(),
        };
        let count = match value {
            Value::Ints(v) => Some(v.len()),
            Value::Floats(v) => Some(v.len()),
            Value::Strings(v) => Some(v.len()),
            Value::Nodes(v) => Some(v.len()),
            Value::Vec3s(v) => Some(v.len()),
            Value::Vec2s(v) => Some(v.len()),
            _ => None,
        };
        if let (Some(expected), Some(found)) = (spec.count, count) {
            if expected != found {
                self.error(
                    file,
                    Diagnostic::error(
                        span,
                        format!(
                            "'{}' takes exactly {expected} values, found {found}",
                            spec.name
                        ),
                    )
                    .with_code("arity"),
                );
                return false;
            }
        }
        for x in numbers {
            let problem = if spec.above.is_some_and(|a| x <= a) {
                Some(format!(
                    "must be greater than {}",
                    spec.above.unwrap_or_default()
                ))
            } else if spec.min.is_some_and(|m| x < m) {
                Some(format!("must be at least {}", spec.min.unwrap_or_default()))
            } else if spec.max.is_some_and(|m| x > m) {
                Some(format!("must be at most {}", spec.max.unwrap_or_default()))
            } else {
                None
            };
            if let Some(problem) = problem {
                self.error(
                    file,
                    Diagnostic::error(span, format!("'{}' {problem}, found {x}", spec.name))
                        .with_label(spec.doc.clone())
                        .with_code("range"),
                );
                return false;
            }
        }
        true
    }
}

fn shorten(text: &str) -> String {
    let mut shown: String = text.chars().take(40).collect();
    if shown.len() < text.len() {
        shown.push('…');
    }
    shown
}

fn body_item_span(item: &BodyItem) -> Span {
    match item {
        BodyItem::Field(f) => f.span,
        BodyItem::Proto(p) => p.span,
        BodyItem::Route(r) => r.span,
        BodyItem::Declaration(d) => d.span,
        BodyItem::Template(t) => t.span,
    }
}

fn has_template(proto: &syntax::Proto) -> bool {
    fn in_value(value: &syntax::Value) -> bool {
        match &value.items {
            Items::Numbers(_) => false,
            Items::Atoms(atoms) => atoms.iter().any(|a| match a {
                Atom::Template(t) => !t.expression,
                Atom::Node(n) => in_node(n),
                _ => false,
            }),
        }
    }
    fn in_node(node: &syntax::Node) -> bool {
        match &node.kind {
            NodeKind::Instance {
                body: Some(body), ..
            } => body.items.iter().any(|item| match item {
                BodyItem::Template(_) => true,
                BodyItem::Field(f) => {
                    matches!(&f.value, syntax::FieldValue::Value(v) if in_value(v))
                }
                _ => false,
            }),
            _ => false,
        }
    }
    proto.body.iter().any(|item| match item {
        Item::Template(_) => true,
        Item::Node(node) => in_node(node),
        _ => false,
    })
}

fn collect_is_targets<'a>(items: &'a [Item], out: &mut Vec<&'a syntax::Ident>) {
    fn node<'a>(n: &'a syntax::Node, out: &mut Vec<&'a syntax::Ident>) {
        if let NodeKind::Instance {
            body: Some(body), ..
        } = &n.kind
        {
            for item in &body.items {
                if let BodyItem::Field(f) = item {
                    match &f.value {
                        syntax::FieldValue::Is(target) => out.push(target),
                        syntax::FieldValue::Value(v) => {
                            if let Items::Atoms(atoms) = &v.items {
                                for atom in atoms {
                                    if let Atom::Node(child) = atom {
                                        node(child, out);
                                    }
                                }
                            }
                        }
                        syntax::FieldValue::Missing { .. } => {}
                    }
                }
            }
        }
    }
    for item in items {
        match item {
            Item::Node(n) => node(n, out),
            Item::Proto(p) => collect_is_targets(&p.body, out),
            _ => {}
        }
    }
}
