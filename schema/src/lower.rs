//! Typing: from syntax trees to a [`Scene`], checking every field against the catalogue,
//! resolving DEF/USE, expanding PROTOs (built-in, file-local and local EXTERNPROTOs) and
//! Inline files.
//!
//! Rules worth knowing:
//! - A DEF name is bound once its node is complete, so USE inside the node it names is an
//!   error and the scene is always a DAG; among repeated DEFs the latest bound wins.
//! - Strict mode makes unknown nodes, fields and template code errors; lenient mode makes them
//!   warnings and skips them, as Webots does.
//! - Files are read through [`FileAccess`] only: urls resolve relative to the file naming
//!   them and never leave the world's root; no url is ever fetched.
//! - Every [`Limits`] bound is checked where it is crossed and reported there, once.
//! - A problem inside a PROTO's body that the instance caused (a value it passed, a template
//!   over its fields, any problem in a built-in PROTO) is reported at the instance's line, with
//!   the PROTO's line beside it, as rustc does for macros.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Dialect, Item, Items, NodeKind};
use regatta_parser::{Diagnostic, SourceMap, SourceText, Span};

use crate::access::{FileAccess, Limits, Refusal};
use crate::catalogue::{did_you_mean, Catalogue, FieldSpec, SpecId};
use crate::protos::{BUILTIN_PROTOS, WEBOTS_STANDINS};
use crate::scene::{
    FieldsBuilder, FileId, NodeId, Origin, Scene, SceneNode, SharedFields, UpAxis, Written,
};
use crate::value::{BaseType, FieldType, Image, Value};

/// Deepest nesting of PROTO instances, by default (see [`Limits`]).
pub const MAX_INSTANCE_DEPTH: usize = 32;
/// Largest scene, in nodes, after PROTO expansion, by default (see [`Limits`]).
pub const MAX_NODES: usize = 1_000_000;
/// Diagnostics kept per check; past it, one message says how many more there were.
pub const MAX_DIAGNOSTICS: usize = 500;

/// How to check a world.
#[derive(Clone, Debug)]
pub struct Options {
    /// Unknown nodes and fields are errors (regatta's own worlds) or warnings (foreign files).
    pub strict: bool,
    /// The folders the world may read files from; [`check_path`] adds the world's own folder.
    pub access: FileAccess,
    /// Bounds on includes, PROTO depth, nodes, nesting and file size.
    pub limits: Limits,
    /// The folder the main text's relative urls resolve against: the world file's folder
    /// ([`check_path`] sets it); `None` for a text with no folder (standard input), whose
    /// urls resolve against the current directory, still within `access`.
    pub base_dir: Option<PathBuf>,
    /// Folders where `webots://` PROTOs are looked for before regatta's stand-ins (a Webots
    /// installation, or any folder of PROTOs); see [`crate::proto_path`].
    pub proto_path: Vec<PathBuf>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            strict: true,
            access: FileAccess::none(),
            limits: Limits::default(),
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
    /// Whether unknown things were errors (or warnings, in lenient mode).
    pub strict: bool,
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

    /// Puts diagnostics added after the check (by later stages) in the stable order.
    pub fn sort_diagnostics(&mut self) {
        self.diagnostics.sort_by(|a, b| {
            (a.file.0, a.diagnostic.span.start, &a.diagnostic.message).cmp(&(
                b.file.0,
                b.diagnostic.span.start,
                &b.diagnostic.message,
            ))
        });
    }

    /// The files of this check, for rendering (indexed by [`FileId`]).
    pub fn source_map(&self) -> SourceMap<'_> {
        let mut map = SourceMap::new();
        for source in &self.sources {
            map.add(&source.name, &source.text);
        }
        map
    }

    /// Renders every diagnostic in rustc's style.
    pub fn render(&self, color: bool) -> String {
        self.render_where(|_| true, color)
    }

    /// Renders the diagnostics `keep` selects, in rustc's style.
    pub fn render_where(&self, keep: impl Fn(&FileDiagnostic) -> bool, color: bool) -> String {
        let map = self.source_map();
        self.diagnostics
            .iter()
            .filter(|d| keep(d))
            .map(|d| map.render(d.file.0 as usize, &d.diagnostic, color))
            .collect()
    }

    /// One line per diagnostic: `file:line:col: error: message`.
    pub fn short(&self) -> Vec<String> {
        let map = self.source_map();
        self.diagnostics
            .iter()
            .map(|d| map.short(d.file.0 as usize, &d.diagnostic))
            .collect()
    }
}

/// Checks a world given as text (its own parse diagnostics included).
pub fn check(source: SourceText, options: &Options) -> Checked {
    let mut lowerer = Lowerer::new(options.clone());
    let base = match &options.base_dir {
        Some(dir) => UrlBase::Dir(dir.clone()),
        None => UrlBase::CurrentDir,
    };
    let file = lowerer.add_file(source, base);
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

/// Reads and checks a world file: its folder joins `options.access`, and its urls resolve
/// against that folder. `Err` only when the file cannot be read at all.
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
    options.access.allow(&folder).map_err(io)?;
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
    let file = lowerer.add_text(
        "<catalogue>",
        &format!("Default {{ {text} }}"),
        UrlBase::NoFiles,
    );
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
/// A PROTO instance's interface fields, by name.
pub type Bindings = BTreeMap<String, Binding>;

/// One interface field of a PROTO instance.
#[derive(Clone, Debug)]
pub struct Binding {
    pub ty: FieldType,
    /// The instance's value, or the default.
    pub value: Option<Value>,
    /// Where the user wrote the value: the file, each string's span, the field's span (none
    /// for a default). A value passed on through IS keeps its first site.
    pub site: Option<(FileId, Vec<Span>, Span)>,
    /// `field`, `exposedField`, `eventIn`…
    pub keyword: String,
}

impl Binding {
    /// A binding to a plain `field` with no site (a default).
    pub fn new(ty: FieldType, value: Option<Value>) -> Binding {
        Binding {
            ty,
            value,
            site: None,
            keyword: "field".to_owned(),
        }
    }
}

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

/// What a file's relative urls resolve against.
#[derive(Clone, Debug)]
enum UrlBase {
    /// The folder of the file (canonical).
    Dir(PathBuf),
    /// A text with no folder (standard input): the current directory.
    CurrentDir,
    /// Built-in text (standard PROTOs, the catalogue): it names no file.
    NoFiles,
}

/// What a url is for: says what happens when it is not followed.
#[derive(Clone, Copy, Debug)]
enum UrlUse<'a> {
    Inline,
    ExternProto,
    /// A file a node names but regatta does not read (an ImageTexture's image).
    Image(&'a str),
}

impl UrlUse<'_> {
    fn noun(&self) -> &str {
        match self {
            UrlUse::Inline => "Inline",
            UrlUse::ExternProto => "EXTERNPROTO",
            UrlUse::Image(node) => node,
        }
    }

    fn instead(&self) -> &'static str {
        match self {
            UrlUse::Inline => "the Inline stays empty",
            UrlUse::ExternProto => "its PROTO stays unknown",
            UrlUse::Image(_) => "the image is not used (regatta does not read images yet)",
        }
    }
}

/// One PROTO instance being expanded.
struct Frame {
    name: String,
    /// The definition's offset in its file (with `definition`, its identity).
    key: u32,
    /// Where the instance was written.
    instance: (FileId, Span),
    /// The file holding the PROTO's definition.
    definition: FileId,
}

struct Lowerer<'c> {
    options: Options,
    catalogue: Option<&'c Catalogue>,
    nodes: Vec<SceneNode>,
    /// Whether each node is, or holds, a robot (a robot must not be USEd twice).
    holds_robot: Vec<bool>,
    /// Field values of nodes made so far, for the next instance of a PROTO to share.
    shared_fields: SharedFields,
    sources: Vec<Source>,
    /// What each file's urls resolve against, by file id.
    file_bases: Vec<UrlBase>,
    /// Parse diagnostics of each file, kept until the end so that typed messages can replace
    /// the parser's generic "missing value" ones.
    parse_diagnostics: Vec<FileDiagnostic>,
    diagnostics: Vec<FileDiagnostic>,
    /// Diagnostics dropped past [`MAX_DIAGNOSTICS`].
    dropped: usize,
    refined_missing: BTreeSet<(u32, u32)>,
    builtins: Option<ProtoTable>,
    /// EXTERNPROTO names that point where regatta does not go, with the URL.
    unresolved: HashMap<String, String>,
    /// The PROTO instances being expanded, outermost first.
    frames: Vec<Frame>,
    /// The Inline and EXTERNPROTO files being read, outermost first.
    includes: Vec<FileId>,
    /// Nodes being lowered inside each other (the expanded scene's depth).
    node_depth: usize,
    /// The user's line a value inside a PROTO body came from, while it is being typed.
    blame: Option<(FileId, Span)>,
    /// Places problems in PROTO bodies were moved to (each gets one message).
    relocated: BTreeSet<(u32, u32)>,
    /// PROTOs whose interface was already checked for unused fields.
    checked_protos: BTreeSet<(u32, u32)>,
    /// Nodes a PROTO expands to at most, by definition (file, offset).
    estimates: HashMap<(u32, u32), u64>,
    /// Files already loaded (EXTERNPROTO, Inline), by canonical path.
    loaded: HashMap<PathBuf, FileId>,
    /// Each file's syntax tree, parsed once.
    parsed: HashMap<u32, Rc<syntax::SourceFile>>,
    /// The PROTO table of each file, by file id.
    file_scopes: HashMap<u32, ProtoTable>,
    /// The PROTO each instance's root node was made by (the outermost one), for ROUTEs.
    instance_of: HashMap<NodeId, Rc<ProtoDef>>,
    /// Limits already reported (each is one cause: one message).
    limits_reported: BTreeSet<&'static str>,
    up_axis: UpAxis,
    objects: crate::webots::Objects,
    roots: Vec<NodeId>,
    /// Who wrote each file that is not the world's (built-in PROTO files).
    file_authoring: HashMap<u32, crate::webots::Authoring>,
    /// PROTO instance roots: the authoring of the file that wrote the instance.
    instance_authoring: HashMap<u32, crate::webots::Authoring>,
    /// PROTO instance roots: the authoring of the file their body was written in (their
    /// origin is the instance, in the user's file).
    body_authoring: HashMap<u32, crate::webots::Authoring>,
    /// The urls EXTERNPROTOs give for stand-in names.
    standin_urls: HashMap<String, String>,
    substitutions: Vec<Substitution>,
    unbuilt_robots: Vec<UnbuiltRobot>,
    /// The JavaScript engine, started by the first template that needs it.
    engine: Option<regatta_template::Engine>,
    /// Expanded template PROTOs by PROTO, field values and (for nonDeterministic ones)
    /// instance; `None` for an expansion that failed (reported once).
    expanded: HashMap<String, Option<Rc<ProtoDef>>>,
    /// Template instances so far: the next one's `context.id`.
    template_instances: u64,
    /// `WorldInfo.randomSeed` as written, which seeds templates.
    world_seed: i64,
    /// The world's Webots version (its header), which templates see in `context`.
    webots_version: String,
}

impl<'c> Lowerer<'c> {
    fn new(mut options: Options) -> Lowerer<'c> {
        // The PROTO path's folders are the user's: files there may be read, under the same
        // rules as the world's own (their PROTOs' urls stay inside them).
        for dir in options.proto_path.clone() {
            let _ = options.access.allow(&dir);
        }
        Lowerer {
            options,
            catalogue: None,
            nodes: Vec::new(),
            holds_robot: Vec::new(),
            shared_fields: SharedFields::default(),
            sources: Vec::new(),
            file_bases: Vec::new(),
            parse_diagnostics: Vec::new(),
            diagnostics: Vec::new(),
            dropped: 0,
            refined_missing: BTreeSet::new(),
            builtins: None,
            unresolved: HashMap::new(),
            frames: Vec::new(),
            includes: Vec::new(),
            node_depth: 0,
            blame: None,
            relocated: BTreeSet::new(),
            checked_protos: BTreeSet::new(),
            estimates: HashMap::new(),
            loaded: HashMap::new(),
            parsed: HashMap::new(),
            file_scopes: HashMap::new(),
            instance_of: HashMap::new(),
            limits_reported: BTreeSet::new(),
            up_axis: UpAxis::Y,
            objects: crate::webots::Objects::Legacy,
            roots: Vec::new(),
            file_authoring: HashMap::new(),
            instance_authoring: HashMap::new(),
            body_authoring: HashMap::new(),
            standin_urls: HashMap::new(),
            substitutions: Vec::new(),
            unbuilt_robots: Vec::new(),
            engine: None,
            expanded: HashMap::new(),
            template_instances: 0,
            world_seed: 0,
            webots_version: String::new(),
        }
    }

    fn catalogue(&self) -> &'c Catalogue {
        match self.catalogue {
            Some(catalogue) => catalogue,
            None => Catalogue::get(),
        }
    }

    fn add_text(&mut self, name: &str, text: &str, base: UrlBase) -> FileId {
        let id = FileId(self.sources.len() as u32);
        self.sources.push(Source {
            name: name.to_owned(),
            text: Rc::from(text),
        });
        self.file_bases.push(base);
        id
    }

    fn add_file(&mut self, source: SourceText, base: UrlBase) -> FileId {
        let id = self.add_text(&source.name, &source.text, base);
        for diagnostic in source.diagnostics {
            self.parse_diagnostics.push(FileDiagnostic {
                file: id,
                diagnostic,
            });
        }
        id
    }

    fn is_builtin(&self, file: FileId) -> bool {
        matches!(self.file_bases.get(file.0 as usize), Some(UrlBase::NoFiles))
    }

    /// Parses a registered file once, keeping its syntax diagnostics.
    fn parse(&mut self, file: FileId) -> Rc<syntax::SourceFile> {
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

    fn error(&mut self, file: FileId, diagnostic: Diagnostic) {
        let original = file;
        let (file, diagnostic) = self.relocate(file, diagnostic);
        // One mistake, one message: a user's value that breaks several parts of a PROTO's
        // body is reported once, at the value.
        if file != original && !self.relocated.insert((file.0, diagnostic.span.start)) {
            return;
        }
        if self.diagnostics.len() >= MAX_DIAGNOSTICS {
            self.dropped += 1;
            return;
        }
        self.diagnostics.push(FileDiagnostic { file, diagnostic });
    }

    /// The innermost PROTO instance being expanded that the user wrote (not a built-in
    /// PROTO's body).
    fn user_instance(&self) -> Option<(FileId, Span)> {
        self.frames
            .iter()
            .rev()
            .find(|f| !self.is_builtin(f.instance.0))
            .map(|f| f.instance)
    }

    /// Inside a PROTO's expansion, a problem the instance caused is shown at the instance's
    /// line, with the PROTO's line beside it: a value typed while `blame` is set (a template
    /// over the instance's fields), or any problem in a built-in PROTO, which the user cannot
    /// edit.
    fn relocate(&self, file: FileId, mut diagnostic: Diagnostic) -> (FileId, Diagnostic) {
        let target = match self.blame {
            Some((blamed, span)) if blamed != file || span != diagnostic.span => {
                Some((blamed, span))
            }
            _ if self.is_builtin(file) => self.user_instance(),
            _ => None,
        };
        let Some((user_file, user_span)) = target else {
            return (file, diagnostic);
        };
        let proto = self
            .frames
            .iter()
            .rev()
            .find(|f| f.definition == file)
            .map(|f| format!("in the body of PROTO '{}'", f.name))
            .unwrap_or_else(|| "in a PROTO body".to_owned());
        for label in &mut diagnostic.secondary {
            label.file.get_or_insert(file.0 as usize);
        }
        let original = diagnostic.span;
        let label = std::mem::take(&mut diagnostic.label);
        diagnostic.span = user_span;
        diagnostic.label = "caused by this".to_owned();
        diagnostic.secondary.insert(
            0,
            regatta_parser::Label {
                span: original,
                message: if label.is_empty() {
                    proto
                } else {
                    format!("{proto}: {label}")
                },
                file: Some(file.0 as usize),
            },
        );
        (user_file, diagnostic)
    }

    /// An error in strict mode, a warning in lenient mode.
    fn strict_or_warn(&mut self, file: FileId, mut diagnostic: Diagnostic) {
        if !self.options.strict {
            diagnostic.severity = regatta_parser::Severity::Warning;
        }
        self.error(file, diagnostic);
    }

    /// Reports a crossed limit once: one cause, one message.
    fn limit_crossed(&mut self, key: &'static str, file: FileId, diagnostic: Diagnostic) {
        if self.limits_reported.insert(key) {
            let diagnostic = diagnostic
                .with_note(format!("`--limit {key}=N` raises the limit"))
                .with_code("limit");
            self.error(file, diagnostic);
        }
    }

    fn finish(mut self) -> Checked {
        self.check_expanded_size();
        self.check_robot_names();
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
        // Stable order: by file, then position, then message; one message per place.
        diagnostics.sort_by(|a, b| {
            (a.file.0, a.diagnostic.span.start, &a.diagnostic.message).cmp(&(
                b.file.0,
                b.diagnostic.span.start,
                &b.diagnostic.message,
            ))
        });
        diagnostics.dedup_by(|a, b| {
            a.file == b.file
                && a.diagnostic.span == b.diagnostic.span
                && a.diagnostic.message == b.diagnostic.message
        });
        if self.dropped > 0 {
            if let Some(last) = diagnostics.last().cloned() {
                diagnostics.push(FileDiagnostic {
                    file: last.file,
                    diagnostic: Diagnostic::error(
                        last.diagnostic.span,
                        format!("too many problems: {} more were not reported", self.dropped),
                    )
                    .with_code("too-many"),
                });
            }
        }
        for (index, node) in self.nodes.iter_mut().enumerate() {
            let body = match self.body_authoring.get(&(index as u32)) {
                Some(&body) => body,
                None => self
                    .file_authoring
                    .get(&node.origin.file.0)
                    .copied()
                    .unwrap_or_default(),
            };
            let own = self
                .instance_authoring
                .get(&(index as u32))
                .copied()
                .unwrap_or(body);
            node.axes = crate::webots::Axes { own, body };
        }
        // The scene lives on through compilation: no spare room.
        self.nodes.shrink_to_fit();
        let scene = Scene {
            nodes: self.nodes,
            roots: self.roots,
            files: self.sources.iter().map(|s| s.name.clone()).collect(),
            up_axis: self.up_axis,
            objects: self.objects,
        };
        Checked {
            strict: self.options.strict,
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
            let file = self.add_text(
                &format!("<builtin>/{folder}/{name}.proto"),
                text,
                UrlBase::NoFiles,
            );
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
    fn file_protos(&mut self, file: FileId, parsed: &syntax::SourceFile) -> ProtoTable {
        let mut list: Vec<(String, Rc<ProtoDef>)> = self.builtins().iter().cloned().collect();
        for item in &parsed.items {
            if let Item::ExternProto(extern_proto) = item {
                self.extern_proto(file, extern_proto, &mut list);
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
                        // Nothing was read: an error in both modes, as for the world's own
                        // urls; the stand-in, if any, still stands in.
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
                    // The stand-in is already in the table, after regatta's own PROTOs.
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
    }

    /// Reads the PROTO `name` from the file at `path` (already resolved) into `list`; false
    /// (after reporting) when the file cannot be read or defines no such PROTO.
    fn extern_from_file(
        &mut self,
        file: FileId,
        path: &Path,
        url: &syntax::StringLit,
        name: &str,
        list: &mut Vec<(String, Rc<ProtoDef>)>,
    ) -> bool {
        let Some(loaded) = self.load_resolved(file, path, &url.value, url.span) else {
            return false;
        };
        let parsed = self.parse(loaded);
        let found = parsed.items.iter().find_map(|item| match item {
            Item::Proto(p) if p.name.text == name => Some(p.clone()),
            _ => None,
        });
        match found {
            Some(proto) => {
                if !self.file_scopes.contains_key(&loaded.0) {
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
                        format!("'{}' defines no PROTO named '{name}'", url.value),
                    )
                    .with_code("externproto"),
                );
                false
            }
        }
    }

    /// Where `url`, written in `file`, leads, if the world may read it.
    fn resolve_url(&self, file: FileId, url: &str) -> Result<PathBuf, Refusal> {
        let base = match &self.file_bases[file.0 as usize] {
            UrlBase::Dir(dir) => Some(dir.as_path()),
            UrlBase::CurrentDir => None,
            UrlBase::NoFiles => return Err(Refusal::NoAccess),
        };
        self.options.access.resolve(url, base)
    }

    /// Reports a url that was not followed, and what happens instead. Escapes are errors in
    /// both modes: nothing is read either way, and a world that reaches outside its folder
    /// should not look fine.
    fn refuse(&mut self, file: FileId, span: Span, url: &str, refusal: Refusal, user: UrlUse) {
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
    fn load_resolved(
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

    fn lower_world(&mut self, file: FileId) {
        let parsed = self.parse(file);
        let header = parsed.header.clone();
        let protos = self.file_protos(file, &parsed);
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
                Item::Route(route) => self.route(route, scope),
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
                    if f.name.text == "randomSeed" {
                        if let syntax::FieldValue::Value(syntax::Value {
                            items: Items::Numbers(list),
                            ..
                        }) = &f.value
                        {
                            if let Some(&seed) = list.values.first() {
                                self.world_seed = seed as i64;
                            }
                        }
                    }
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
        self.webots_version = match header {
            Some(syntax::Header {
                dialect: Dialect::Webots,
                version,
                ..
            }) => version.clone(),
            // Files that are not Webots': the release regatta's stand-ins are written for.
            _ => "R2023b".to_owned(),
        };
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
        if self.nodes.len() >= self.options.limits.nodes {
            self.nodes_limit(file, span, None);
            return None;
        }
        let spec = self.catalogue().spec(node.spec);
        let holds_robot = spec.classes.iter().any(|c| c == "robot")
            || node
                .fields
                .own()
                .any(|v| v.nodes().iter().any(|c| self.holds_robot[c.index()]));
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(node);
        self.holds_robot.push(holds_robot);
        Some(id)
    }

    /// The scene grew past the node limit (or would, by `estimate`).
    fn nodes_limit(&mut self, file: FileId, span: Span, estimate: Option<(&str, u64)>) {
        let limit = self.options.limits.nodes;
        let message = match estimate {
            Some((name, nodes)) => format!(
                "PROTO '{name}' expands to {} nodes, more than the limit of {limit}",
                if nodes == u64::MAX {
                    "more than 18446744073709551615".to_owned()
                } else {
                    nodes.to_string()
                }
            ),
            None => format!("the scene expands to more than {limit} nodes"),
        };
        self.limit_crossed(
            "nodes",
            file,
            Diagnostic::error(span, message)
                .with_label("expansion stopped here")
                .with_note(
                    "PROTOs or USEs multiply each other; check for accidental exponential nesting",
                ),
        );
    }

    /// Types one node where `accepted` classes may stand. `place` names the field, for messages.
    fn lower_node(
        &mut self,
        node: &syntax::Node,
        scope: &mut Scope,
        accepted: &[String],
        place: &str,
    ) -> Option<NodeId> {
        if self.limits_reported.contains("nodes") {
            // The scene is already too large: stop expanding anything.
            return None;
        }
        if self.node_depth >= self.options.limits.scene_depth() {
            let limit = self.options.limits.scene_depth();
            self.limit_crossed(
                "nesting",
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("nodes nested deeper than {limit} levels once PROTOs and Inline files are expanded"),
                )
                .with_label("this node is skipped"),
            );
            return None;
        }
        self.node_depth += 1;
        let id = self.lower_node_inner(node, scope, accepted, place);
        self.node_depth -= 1;
        id
    }

    fn lower_node_inner(
        &mut self,
        node: &syntax::Node,
        scope: &mut Scope,
        accepted: &[String],
        place: &str,
    ) -> Option<NodeId> {
        let id = match &node.kind {
            NodeKind::Use(name) => {
                if name.text.is_empty() {
                    return None;
                }
                match scope.defs.get(&name.text) {
                    Some(&id) if self.holds_robot[id.index()] => {
                        // A robot is one body with one name: a second copy would be a second
                        // robot under the same name.
                        self.strict_or_warn(
                            scope.file,
                            Diagnostic::error(
                                node.span,
                                format!("USE {} would copy a robot", name.text),
                            )
                            .with_label("a robot cannot be USEd")
                            .with_note("write a second robot with its own name instead; this USE is skipped")
                            .with_code("use-of-robot"),
                        );
                        return None;
                    }
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
            let diagnostic = self.wrong_class(spec, accepted, place, node.span);
            self.strict_or_warn(scope.file, diagnostic);
            return None;
        }
        Some(id)
    }

    /// "a Box node cannot stand in 'turret'", naming the node types that can.
    fn wrong_class(
        &self,
        spec: &crate::catalogue::NodeSpec,
        accepted: &[String],
        place: &str,
        span: Span,
    ) -> Diagnostic {
        let catalogue = self.catalogue();
        let types: Vec<&str> = catalogue
            .nodes
            .iter()
            .filter(|n| n.fits(accepted))
            .map(|n| n.name.as_str())
            .collect();
        let shown = if types.len() <= 8 {
            format!(": {}", types.join(", "))
        } else {
            format!(" ({} types, `regatta schema` lists them)", types.len())
        };
        Diagnostic::error(
            span,
            format!("a {} node cannot stand in {place}", spec.name),
        )
        .with_label(format!(
            "{} is a {} node",
            spec.name,
            spec.classes.join("/")
        ))
        .with_note(format!(
            "{place} accepts {} nodes{shown}",
            accepted.join(" or ")
        ))
        .with_code("wrong-node-class")
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
        let mut fields = FieldsBuilder::new(spec_id, spec.fields.len());
        let mut written = Written::none(spec.fields.len());
        // Each url of a `file` field, with where it was written and the file it is relative to.
        let mut urls: Vec<(usize, String, FileId, Span)> = Vec::new();
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
                    if matches!(field_spec.access.as_deref(), Some("eventIn" | "eventOut")) {
                        self.strict_or_warn(
                            scope.file,
                            Diagnostic::error(field.name.span, format!("'{}' is an {} of {}: it receives or sends events and takes no value", field.name.text, field_spec.access.as_deref().unwrap_or_default(), spec.name))
                                .with_code("event-as-field"),
                        );
                        continue;
                    }
                    let site = self.value_site(field, scope);
                    if let Some(value) = self.lower_field_value(&field.value, field_spec.ty(), Some(field_spec), scope, &field.name.text, field.name.span) {
                        if field_spec.file {
                            for (k, url) in value.strings().iter().enumerate() {
                                let span = site.1.get(k).copied().unwrap_or(site.2);
                                urls.push((index, url.clone(), site.0, span));
                            }
                        }
                        written.set(index);
                        // A value written here points at itself; one bound through IS at the
                        // instance that gave it.
                        let span = match &field.value {
                            syntax::FieldValue::Value(value) => value.span,
                            _ => site.2,
                        };
                        fields.set(index, value, Some(Origin { file: site.0, span }));
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
                BodyItem::Route(route) => self.route(route, scope),
            }
        }
        let origin = Origin {
            file: scope.file,
            span: node.span,
        };
        if spec.name == "Inline" {
            return self.inline(&urls, node, scope, origin);
        }
        // Other files are named, not read (textures): each must still lie inside the root.
        for (_, url, file, span) in &urls {
            if let Err(refusal) = self.resolve_url(*file, url) {
                self.refuse(*file, *span, url, refusal, UrlUse::Image(&spec.name));
            }
        }
        let fields = fields.finish(origin, &mut self.shared_fields);
        self.alloc(
            SceneNode {
                spec: spec_id,
                fields,
                written,
                def_name: None,
                proto_names: Vec::new(),
                origin,
                axes: Default::default(),
            },
            scope.file,
            node.span,
        )
    }

    /// Where a field's value was written: the file, each string's span, and the field's span.
    /// A value passed in through IS points at the instance that passed it.
    fn value_site(&self, field: &syntax::Field, scope: &Scope) -> (FileId, Vec<Span>, Span) {
        if let (syntax::FieldValue::Is(target), Some(interface)) = (&field.value, &scope.interface)
        {
            if let Some(binding) = interface.get(&target.text) {
                if let Some(site) = &binding.site {
                    return site.clone();
                }
            }
            // A default: the user's instance is where it came from, unless this PROTO is
            // the user's own (then its line is).
            if self.is_builtin(scope.file) {
                if let Some((file, span)) = self.user_instance() {
                    return (file, Vec::new(), span);
                }
            }
            return (scope.file, Vec::new(), field.span);
        }
        (scope.file, string_spans(&field.value), field.span)
    }

    /// Inline becomes a Group holding the included file's nodes.
    fn inline(
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
                def_name: None,
                proto_names: vec!["Inline".to_owned()],
                origin,
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
        let key = (def.file.0, proto.span.start);
        if self
            .frames
            .iter()
            .any(|f| f.definition == def.file && f.key == key.1)
        {
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
        if self.frames.len() >= self.options.limits.proto_depth {
            let limit = self.options.limits.proto_depth;
            self.limit_crossed(
                "proto-depth",
                scope.file,
                Diagnostic::error(
                    node.span,
                    format!("PROTO instances nested deeper than {limit} levels"),
                )
                .with_label("this instance is not expanded"),
            );
            return None;
        }
        // An exponential PROTO (ten copies of one that makes ten copies of …) is refused
        // before anything is built: the estimate is cheap and remembered per definition.
        let estimate = self.estimate(def, 0);
        if estimate.saturating_add(self.nodes.len() as u64) > self.options.limits.nodes as u64 {
            self.nodes_limit(scope.file, node.span, Some((name, estimate)));
            return None;
        }
        let statements = has_template(proto);
        if statements {
            let proto_file = &self.sources[def.file.0 as usize];
            if crate::procedural::is_lua(&proto_file.text)
                || proto_file.text[proto.span.range()].contains("%{")
            {
                let message = format!(
                    "PROTO '{name}' ({}) is written with a Lua template (Webots before R2022a); regatta runs JavaScript templates only, so this instance is skipped",
                    proto_file.name
                );
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(node.span, message).with_code("template"),
                );
                return None;
            }
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
            if matches!(declaration.keyword.text.as_str(), "eventIn" | "eventOut") {
                self.strict_or_warn(
                    scope.file,
                    Diagnostic::error(
                        field.name.span,
                        format!(
                            "'{}' is an {} of PROTO '{name}': it takes no value",
                            field.name.text, declaration.keyword.text
                        ),
                    )
                    .with_code("event-as-field"),
                );
                continue;
            }
            let site = self.value_site(field, scope);
            let value = self.lower_field_value(
                &field.value,
                ty,
                None,
                scope,
                &field.name.text,
                field.name.span,
            );
            if let Some(value) = value {
                self.check_restriction(declaration, &value, def.file, site.0, site.2);
                bindings.insert(
                    field.name.text.clone(),
                    Binding {
                        ty,
                        value: Some(value),
                        site: Some(site),
                        keyword: declaration.keyword.text.clone(),
                    },
                );
            }
        }
        // From here on the instance is being expanded: its defaults may name PROTOs too (even
        // itself, which is recursion).
        self.frames.push(Frame {
            name: name.clone(),
            instance: (scope.file, node.span),
            definition: def.file,
            key: key.1,
        });
        // Defaults, typed in the PROTO's own file.
        let mut default_scope = Scope {
            protos: self.visible_protos(def),
            ..Scope::new(def.file)
        };
        for declaration in &proto.interface {
            let Some(ty) = FieldType::parse(&declaration.field_type.text) else {
                continue;
            };
            if let Some(bound) = bindings.get_mut(&declaration.name.text) {
                bound.keyword = declaration.keyword.text.clone();
                continue;
            }
            let value = match &declaration.default {
                Some(_) => {
                    let value = self.lower_default(declaration, ty, &mut default_scope);
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
            bindings.insert(
                declaration.name.text.clone(),
                Binding {
                    ty,
                    value,
                    site: None,
                    keyword: declaration.keyword.text.clone(),
                },
            );
        }
        // A template PROTO's body is the text its template generates, unless every template
        // in it is arithmetic over fields (regatta's own PROTOs): then no engine starts.
        let body_def = if statements || self.needs_engine(def, &bindings) {
            self.expand_template(def, &bindings, node, scope)?
        } else {
            def.clone()
        };
        let def = &body_def;
        let proto = &def.proto;
        // The body, in a scope of its own.
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
                Item::Route(route) if found_root => self.route(route, &mut body_scope),
                _ => {}
            }
        }
        self.frames.pop();
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
        let root_node = &mut self.nodes[root.index()];
        root_node.proto_names.push(name.clone());
        // The instance is where the user wrote the node; its body's authoring (which axes it
        // was written in) is the innermost PROTO's, remembered before the origin moves.
        let body_file = root_node.origin.file;
        root_node.origin = Origin {
            file: scope.file,
            span: node.span,
        };
        let body = self
            .file_authoring
            .get(&body_file.0)
            .copied()
            .unwrap_or_default();
        self.body_authoring.entry(root.0).or_insert(body);
        self.instance_of.insert(root, def.clone());
        if instantiating != proto_authoring {
            self.instance_authoring.insert(root.0, instantiating);
        }
        Some(root)
    }

    /// A PROTO field's default value, typed in the PROTO's own file (`None` when it has none
    /// or it does not type, after reporting).
    fn lower_default(
        &mut self,
        declaration: &syntax::Declaration,
        ty: FieldType,
        scope: &mut Scope,
    ) -> Option<Value> {
        let default = declaration.default.as_ref()?;
        self.lower_field_value(
            default,
            ty,
            None,
            scope,
            &declaration.name.text,
            declaration.name.span,
        )
    }

    /// Whether a PROTO's templates need the JavaScript engine: some template block of its
    /// content is not an arithmetic expression in a field value that regatta evaluates itself.
    fn needs_engine(&self, def: &ProtoDef, bindings: &Bindings) -> bool {
        let text = &self.sources[def.file.0 as usize].text;
        let Some(content) = crate::procedural::content_range(text, def.proto.span.range()) else {
            return false;
        };
        let blocks = match regatta_template::blocks(&text[content.clone()]) {
            Ok(blocks) if blocks.is_empty() => return false,
            Ok(blocks) => blocks,
            Err(_) => return true,
        };
        let mut arithmetic = BTreeSet::new();
        fn walk(
            node: &syntax::Node,
            text: &str,
            bindings: &Bindings,
            arithmetic: &mut BTreeSet<usize>,
        ) {
            let NodeKind::Instance {
                body: Some(body), ..
            } = &node.kind
            else {
                return;
            };
            for item in &body.items {
                let BodyItem::Field(field) = item else {
                    continue;
                };
                let syntax::FieldValue::Value(syntax::Value {
                    items: Items::Atoms(atoms),
                    ..
                }) = &field.value
                else {
                    continue;
                };
                for atom in atoms {
                    match atom {
                        Atom::Template(t)
                            if t.expression
                                && crate::template::evaluate(&text[t.span.range()], bindings)
                                    .is_ok() =>
                        {
                            arithmetic.insert(t.span.start as usize);
                        }
                        Atom::Node(child) => walk(child, text, bindings, arithmetic),
                        _ => {}
                    }
                }
            }
        }
        for item in &def.proto.body {
            if let Item::Node(node) = item {
                walk(node, text, bindings, &mut arithmetic);
            }
        }
        blocks
            .iter()
            .any(|block| !arithmetic.contains(&(content.start + block.start)))
    }

    /// Runs a PROTO's JavaScript template for one instance and returns the PROTO as its
    /// template generated it (a file of its own, so that messages about the generated text
    /// show it). `None` after reporting a template that failed; the instance is skipped.
    fn expand_template(
        &mut self,
        def: &Rc<ProtoDef>,
        bindings: &Bindings,
        node: &syntax::Node,
        scope: &mut Scope,
    ) -> Option<Rc<ProtoDef>> {
        let proto = &def.proto;
        let name = proto.name.text.clone();
        let source = self.sources[def.file.0 as usize].clone();
        let Some(content) = crate::procedural::content_range(&source.text, proto.span.range())
        else {
            self.strict_or_warn(
                def.file,
                Diagnostic::error(
                    proto.name.span,
                    format!("PROTO '{name}': cannot find the body its template is in"),
                )
                .with_code("template"),
            );
            return None;
        };
        // Field values and defaults, in Webots' JavaScript shapes.
        let mut default_scope = Scope {
            protos: self.visible_protos(def),
            ..Scope::new(def.file)
        };
        let mut pairs = Vec::new();
        for declaration in &proto.interface {
            let Some(binding) = bindings.get(&declaration.name.text).cloned() else {
                continue;
            };
            let (ty, value, origin) = (binding.ty, binding.value, binding.site);
            let default = match origin {
                None => value.clone(),
                Some(_) => self.lower_default(declaration, ty, &mut default_scope),
            };
            pairs.push((declaration.name.text.clone(), ty, value, default));
        }
        let mut fields = serde_json::Map::new();
        let mut given = crate::procedural::FieldsJson::new(&self.nodes, self.catalogue());
        for (field, ty, value, default) in &pairs {
            fields.insert(
                field.clone(),
                given.field(*ty, value.as_ref(), default.as_ref()),
            );
        }
        let fields = serde_json::Value::Object(fields);
        self.template_instances += 1;
        let id = self.template_instances;
        let non_deterministic = crate::procedural::is_non_deterministic(&source.text);
        let key = format!(
            "{}:{}:{}:{}",
            def.file.0,
            proto.span.start,
            if non_deterministic { id } else { 0 },
            fields
        );
        if let Some(expanded) = self.expanded.get(&key) {
            return expanded.clone();
        }
        let coordinate_system = match self.up_axis {
            UpAxis::Y => "NUE",
            UpAxis::Z => "ENU",
        };
        let context = crate::procedural::context(
            &self.sources[0].name,
            &source.name,
            id,
            coordinate_system,
            &self.webots_version,
        );
        let seed = crate::procedural::seed(self.world_seed, if non_deterministic { id } else { 0 });
        let engine = match &self.engine {
            Some(engine) => engine,
            None => match regatta_template::Engine::new(regatta_template::Limits::default()) {
                Ok(engine) => self.engine.insert(engine),
                Err(error) => {
                    self.error(
                        scope.file,
                        Diagnostic::error(node.span, error.message).with_code("template"),
                    );
                    return None;
                }
            },
        };
        let request = regatta_template::Request {
            content: &source.text[content.clone()],
            name: &source.name,
            fields: &fields,
            context: &context,
            seed,
        };
        let expanded = match engine.expand(&request) {
            Ok(generated) => {
                for line in generated.console.iter().filter(|l| l.warning) {
                    self.error(
                        scope.file,
                        Diagnostic::warning(
                            node.span,
                            format!("PROTO '{name}' template: {}", line.text),
                        )
                        .with_label("printed while this instance was generated")
                        .with_code("template-console"),
                    );
                }
                let mut text = String::with_capacity(source.text.len() + generated.text.len());
                text.push_str(&source.text[..content.start]);
                text.push_str(&generated.text);
                text.push_str(&source.text[content.end..]);
                // Urls in the generated text resolve as in the PROTO's own file.
                let base = self
                    .file_bases
                    .get(def.file.0 as usize)
                    .cloned()
                    .unwrap_or(UrlBase::NoFiles);
                let file = self.add_text(&format!("{} (generated)", source.name), &text, base);
                if let Some(authoring) = self.file_authoring.get(&def.file.0).copied() {
                    self.file_authoring.insert(file.0, authoring);
                }
                if let Some(table) = self.file_scopes.get(&def.file.0).cloned() {
                    self.file_scopes.insert(file.0, table);
                }
                let parsed = self.parse(file);
                let found = parsed.items.iter().find_map(|item| match item {
                    Item::Proto(p) if p.span.start == proto.span.start && p.name.text == name => {
                        Some(p.clone())
                    }
                    _ => None,
                });
                if found.is_none() {
                    self.strict_or_warn(
                        file,
                        Diagnostic::error(
                            proto.name.span,
                            format!("PROTO '{name}': the text its template generated is not a PROTO body"),
                        )
                        .with_code("template"),
                    );
                }
                found.map(|generated| {
                    Rc::new(ProtoDef {
                        file,
                        proto: generated,
                        enclosing: def.enclosing.clone(),
                    })
                })
            }
            Err(error) => {
                let (instance_line, instance_column) = regatta_parser::diagnostic::line_col(
                    &self.sources[scope.file.0 as usize].text,
                    node.span.start as usize,
                );
                let span = match error.offset {
                    Some(offset) => {
                        let at = content.start + offset;
                        let end = source.text[at..]
                            .char_indices()
                            .nth(1)
                            .map_or(source.text.len(), |(next, _)| at + next);
                        Span::new(at, end)
                    }
                    None => proto.name.span,
                };
                self.strict_or_warn(
                    def.file,
                    Diagnostic::error(span, format!("PROTO '{name}' template: {}", error.message))
                        .with_label("in this template")
                        .with_note(format!(
                            "while generating the instance at {}:{instance_line}:{instance_column}, which is skipped",
                            self.sources[scope.file.0 as usize].name
                        ))
                        .with_code("template"),
                );
                None
            }
        };
        self.expanded.insert(key, expanded.clone());
        expanded
    }

    /// Checks a ROUTE as VRML97 does (4.10): both nodes DEF'd before it, the source an
    /// eventOut or exposedField, the target an eventIn or exposedField, the same type at both
    /// ends. Nothing is simulated: regatta has no event model, and says so for a sound ROUTE.
    fn route(&mut self, route: &syntax::Route, scope: &mut Scope) {
        let from = self.route_end(&route.from_node, &route.from_field, true, scope);
        let to = self.route_end(&route.to_node, &route.to_field, false, scope);
        let (Some(from), Some(to)) = (from, to) else {
            return;
        };
        if from != to {
            self.strict_or_warn(
                scope.file,
                Diagnostic::error(
                    route.span,
                    format!("ROUTE from {from} to {to}: both ends must have the same type"),
                )
                .with_secondary(route.from_field.span, format!("{from}"))
                .with_secondary(route.to_field.span, format!("{to}"))
                .with_code("route-type"),
            );
            return;
        }
        self.error(
            scope.file,
            Diagnostic::warning(
                route.span,
                "ROUTEs are read but not simulated: regatta has no event model",
            )
            .with_code("route"),
        );
    }

    /// The type of one end of a ROUTE, after reporting what is wrong with it.
    fn route_end(
        &mut self,
        node: &syntax::Ident,
        field: &syntax::Ident,
        source: bool,
        scope: &Scope,
    ) -> Option<FieldType> {
        let Some(&id) = scope.defs.get(&node.text) else {
            if scope.skipped_defs.contains(&node.text) {
                return None;
            }
            let diagnostic = Diagnostic::error(
                node.span,
                format!("no node was DEF'd as '{}' before this ROUTE", node.text),
            )
            .with_code("route-node");
            self.strict_or_warn(scope.file, diagnostic);
            return None;
        };
        // Every event and field the node has: (name, type, access).
        let mut ends: Vec<(String, FieldType, String)> = Vec::new();
        let node_type;
        if let Some(def) = self.instance_of.get(&id).cloned() {
            node_type = format!("PROTO '{}'", def.proto.name.text);
            for declaration in &def.proto.interface {
                if let Some(ty) = FieldType::parse(&declaration.field_type.text) {
                    let access = match declaration.keyword.text.as_str() {
                        "exposedField" | "eventIn" | "eventOut" => declaration.keyword.text.clone(),
                        _ => "field".to_owned(),
                    };
                    ends.push((declaration.name.text.clone(), ty, access));
                }
            }
        } else {
            let spec = self.catalogue().spec(self.nodes[id.index()].spec);
            node_type = format!("{} node", spec.name);
            for f in &spec.fields {
                let access = f
                    .access
                    .clone()
                    .unwrap_or_else(|| "exposedField".to_owned());
                ends.push((f.name.clone(), f.ty(), access));
            }
        }
        let wanted = if source { "eventOut" } else { "eventIn" };
        let name = field.text.as_str();
        let mut found = None;
        for (end, ty, access) in &ends {
            let matches = if access == "exposedField" {
                end == name
                    || (source && name.strip_suffix("_changed") == Some(end.as_str()))
                    || (!source && name.strip_prefix("set_") == Some(end.as_str()))
            } else {
                end == name
            };
            if matches {
                found = Some((*ty, access.clone()));
                break;
            }
        }
        let Some((ty, access)) = found else {
            let mut diagnostic = Diagnostic::error(
                field.span,
                format!("the {node_type} '{}' has no {wanted} '{name}'", node.text),
            )
            .with_code("route-field");
            if let Some(close) = did_you_mean(name, ends.iter().map(|(n, _, _)| n.as_str())) {
                diagnostic = diagnostic.with_note(format!("did you mean '{close}'?"));
            }
            self.strict_or_warn(scope.file, diagnostic);
            return None;
        };
        if access != "exposedField" && access != wanted {
            let role = if source { "send" } else { "receive" };
            self.strict_or_warn(
                scope.file,
                Diagnostic::error(
                    field.span,
                    format!("'{name}' of '{}' is {}: it cannot {role} events", node.text, with_article(&access)),
                )
                .with_label(if source {
                    "a ROUTE starts at an eventOut or exposedField"
                } else {
                    "a ROUTE ends at an eventIn or exposedField"
                })
                .with_note("VRML97 4.10: a ROUTE goes from an eventOut (or exposedField) to an eventIn (or exposedField)")
                .with_code("route-access"),
            );
            return None;
        }
        Some(ty)
    }

    /// At most how many nodes an instance of `def` makes (saturating): the nodes of its body
    /// and defaults, each PROTO instance in them counted by its own estimate. USE adds none.
    fn estimate(&mut self, def: &Rc<ProtoDef>, depth: usize) -> u64 {
        let key = (def.file.0, def.proto.span.start);
        if let Some(&known) = self.estimates.get(&key) {
            return known;
        }
        if depth > self.options.limits.proto_depth {
            // Deeper than allowed: expansion stops there anyway, with its own message.
            return 1;
        }
        // A PROTO that contains itself is reported as recursion; count it once meanwhile.
        self.estimates.insert(key, 1);
        let visible = self.visible_protos(def);
        let mut nested: Vec<(String, Rc<ProtoDef>)> = Vec::new();
        let mut total = 0u64;
        for declaration in &def.proto.interface {
            if let Some(syntax::FieldValue::Value(value)) = &declaration.default {
                total = total.saturating_add(self.estimate_value(value, &visible, &nested, depth));
            }
        }
        for item in &def.proto.body {
            match item {
                Item::Proto(proto) => nested.push((
                    proto.name.text.clone(),
                    Rc::new(ProtoDef {
                        file: def.file,
                        proto: proto.clone(),
                        enclosing: def.enclosing.clone(),
                    }),
                )),
                Item::Node(node) => {
                    total =
                        total.saturating_add(self.estimate_node(node, &visible, &nested, depth));
                }
                _ => {}
            }
        }
        self.estimates.insert(key, total.max(1));
        total.max(1)
    }

    fn estimate_node(
        &mut self,
        node: &syntax::Node,
        visible: &ProtoTable,
        nested: &[(String, Rc<ProtoDef>)],
        depth: usize,
    ) -> u64 {
        let NodeKind::Instance { type_name, body } = &node.kind else {
            return 0;
        };
        let proto = nested
            .iter()
            .rev()
            .chain(visible.iter().rev())
            .find(|(n, _)| *n == type_name.text)
            .map(|(_, p)| p.clone());
        let mut total = match proto {
            Some(proto) => self.estimate(&proto, depth + 1),
            None => 1,
        };
        if let Some(body) = body {
            for item in &body.items {
                if let BodyItem::Field(syntax::Field {
                    value: syntax::FieldValue::Value(value),
                    ..
                }) = item
                {
                    total =
                        total.saturating_add(self.estimate_value(value, visible, nested, depth));
                }
            }
        }
        total
    }

    fn estimate_value(
        &mut self,
        value: &syntax::Value,
        visible: &ProtoTable,
        nested: &[(String, Rc<ProtoDef>)],
        depth: usize,
    ) -> u64 {
        let Items::Atoms(atoms) = &value.items else {
            return 0;
        };
        let mut total = 0u64;
        for atom in atoms {
            if let Atom::Node(node) = atom {
                total = total.saturating_add(self.estimate_node(node, visible, nested, depth));
            }
        }
        total
    }

    /// Once per PROTO definition: Webots' "PROTO parameter 'x' has no matching IS field.",
    /// and VRML97's name rules (no name declared twice; no `set_x` or `x_changed` beside an
    /// exposedField `x`, which declares those events itself).
    fn check_interface_once(&mut self, def: &Rc<ProtoDef>) {
        let key = (def.file.0, def.proto.span.start);
        if !self.checked_protos.insert(key) {
            return;
        }
        let mut targets: Vec<&syntax::Ident> = Vec::new();
        collect_is_targets(&def.proto.body, &mut targets);
        let targets: BTreeSet<&str> = targets.iter().map(|t| t.text.as_str()).collect();
        // Template expressions use fields too: every `fields.NAME.` of the body, in one pass.
        let text = self.sources[def.file.0 as usize].text.clone();
        let body_text = &text[def.proto.span.range()];
        let in_templates: BTreeSet<&str> = body_text
            .split("fields.")
            .skip(1)
            .filter_map(|rest| rest.split('.').next())
            .collect();
        let mut names: HashMap<&str, &syntax::Declaration> = HashMap::new();
        for declaration in &def.proto.interface {
            let name = declaration.name.text.as_str();
            let is_event = matches!(
                declaration.keyword.text.as_str(),
                "eventIn" | "eventOut" | "unconnectedField"
            );
            if !is_event && !in_templates.contains(name) && !targets.contains(name) {
                self.error(
                    def.file,
                    Diagnostic::warning(
                        declaration.name.span,
                        format!("PROTO parameter '{name}' has no matching IS field."),
                    )
                    .with_code("unused-proto-field"),
                );
            }
            if let Some(first) = names.insert(name, declaration) {
                self.strict_or_warn(
                    def.file,
                    Diagnostic::error(
                        declaration.name.span,
                        format!(
                            "'{name}' is declared twice in PROTO '{}'",
                            def.proto.name.text
                        ),
                    )
                    .with_secondary(first.name.span, "first declared here")
                    .with_code("name-clash"),
                );
            }
        }
        for declaration in &def.proto.interface {
            if declaration.keyword.text != "exposedField" {
                continue;
            }
            let name = &declaration.name.text;
            for implied in [format!("set_{name}"), format!("{name}_changed")] {
                if let Some(other) = names.get(implied.as_str()) {
                    self.strict_or_warn(
                        def.file,
                        Diagnostic::error(
                            other.name.span,
                            format!("'{implied}' clashes with the exposedField '{name}', which declares it"),
                        )
                        .with_secondary(declaration.name.span, format!("'{name}' is an exposedField: it has the events set_{name} and {name}_changed"))
                        .with_code("name-clash"),
                    );
                }
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
                    text[found.range()].to_owned()
                } else {
                    String::new()
                };
                let bare_word = !found_text.is_empty()
                    && found_text
                        .chars()
                        .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-'));
                let shown = if found_text.is_empty() {
                    "end of file".to_owned()
                } else {
                    format!("'{}'", shorten(&found_text))
                };
                self.refined_missing.insert((file.0, field_span.start));
                self.refined_missing.insert((file.0, found.start));
                let diagnostic = if ty.base == BaseType::String && bare_word {
                    Diagnostic::error(
                        *found,
                        format!(
                            "Expected {}, found {shown}: strings are quoted.",
                            ty.base.item_noun()
                        ),
                    )
                    .with_label("this word needs quotes")
                    .with_note(format!("write: {field_name} \"{found_text}\""))
                } else {
                    Diagnostic::error(
                        field_span,
                        format!("Expected {}, found {shown}.", ty.base.item_noun()),
                    )
                    .with_label(format!("'{field_name}' needs a {ty} value"))
                    .with_secondary(*found, "found this instead")
                };
                self.error(file, diagnostic.with_code("missing-value"));
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
                let Some(binding) = interface.get(&target.text) else {
                    self.error(
                        file,
                        Diagnostic::error(
                            target.span,
                            format!("'{}' is not a field of this PROTO's interface", target.text),
                        )
                        .with_code("unknown-is"),
                    );
                    return None;
                };
                if binding.ty != ty {
                    self.error(
                        file,
                        Diagnostic::error(target.span, format!("Type mismatch between '{}' PROTO parameter and field '{field_name}'.", target.text))
                            .with_label(format!("'{}' is {}, '{field_name}' is {ty}", target.text, binding.ty))
                            .with_code("is-type-mismatch"),
                    );
                    return None;
                }
                if let Some(access) = spec.and_then(|s| s.access.as_deref()) {
                    if !is_compatible(&binding.keyword, access) {
                        self.strict_or_warn(
                            file,
                            Diagnostic::error(target.span, format!("{} cannot be IS'd to '{field_name}', which is {}", with_article(&binding.keyword), with_article(access)))
                                .with_label(format!("'{}' is {}", target.text, with_article(&binding.keyword)))
                                .with_note("VRML97 4.8.3: a field may be IS'd to a field or exposedField, an eventIn to an eventIn or exposedField, an eventOut to an eventOut or exposedField; an exposedField only to an exposedField")
                                .with_code("is-access-mismatch"),
                        );
                        return None;
                    }
                }
                let value = binding.value.clone()?;
                let Some(spec) = spec else {
                    return Some(value);
                };
                // A value an instance passed in is blamed where the instance wrote it, with
                // this IS beside it; the field keeps its default.
                let (blamed_file, blamed_span) = binding
                    .site
                    .as_ref()
                    .map(|(f, _, s)| (*f, *s))
                    .unwrap_or((file, target.span));
                if !spec.nodes.is_empty() {
                    for &child in value.nodes() {
                        let child_spec = self.catalogue().spec(self.nodes[child.index()].spec);
                        if !child_spec.fits(&spec.nodes) {
                            let mut diagnostic = self.wrong_class(
                                child_spec,
                                &spec.nodes,
                                &format!("'{}'", target.text),
                                blamed_span,
                            );
                            if blamed_file != file {
                                diagnostic = diagnostic.with_secondary_in(
                                    file.0 as usize,
                                    target.span,
                                    format!(
                                        "PROTO '{}' passes it to '{field_name}' here",
                                        self.frames.last().map_or("", |f| f.name.as_str())
                                    ),
                                );
                            }
                            self.strict_or_warn(blamed_file, diagnostic);
                            return None;
                        }
                    }
                }
                if let Some(bad) = value
                    .strings()
                    .iter()
                    .find(|s| !spec.values.is_empty() && !spec.values.contains(s))
                {
                    let allowed = spec
                        .values
                        .iter()
                        .map(|v| format!("\"{v}\""))
                        .collect::<Vec<_>>()
                        .join(", ");
                    let mut diagnostic = Diagnostic::error(
                        blamed_span,
                        format!("\"{bad}\" is not a valid value of '{field_name}'"),
                    )
                    .with_label(format!("expected one of {allowed}"))
                    .with_code("range");
                    if let Some(close) = did_you_mean(bad, spec.values.iter().map(String::as_str)) {
                        diagnostic = diagnostic.with_note(format!("did you mean \"{close}\"?"));
                    }
                    if blamed_file != file {
                        diagnostic = diagnostic.with_secondary_in(
                            file.0 as usize,
                            target.span,
                            format!("'{}' goes to '{field_name}' here", target.text),
                        );
                    }
                    self.error(blamed_file, diagnostic);
                    return None;
                }
                if !self.check_ranges(&value, spec, blamed_file, blamed_span) {
                    return None;
                }
                Some(value)
            }
            syntax::FieldValue::Value(value) => {
                // A template over the instance's fields: what goes wrong with its result is
                // the instance's value's doing.
                let blame = self.template_blame(value, scope);
                let saved = match blame {
                    Some(_) => std::mem::replace(&mut self.blame, blame),
                    None => self.blame,
                };
                let typed = self.lower_value(value, ty, spec, scope, field_name);
                let typed = match (typed, spec) {
                    (Some(typed), Some(spec)) => self
                        .check_ranges(&typed, spec, file, value.span)
                        .then_some(typed),
                    (typed, _) => typed,
                };
                self.blame = saved;
                typed
            }
        }
    }

    /// Where the user wrote the first instance field that a template of `value` reads.
    fn template_blame(&self, value: &syntax::Value, scope: &Scope) -> Option<(FileId, Span)> {
        let (Items::Atoms(atoms), Some(interface)) = (&value.items, &scope.interface) else {
            return None;
        };
        let text = &self.sources[scope.file.0 as usize].text;
        atoms.iter().find_map(|atom| {
            let Atom::Template(template) = atom else {
                return None;
            };
            let code = text.get(template.span.range())?;
            code.split("fields.").skip(1).find_map(|rest| {
                let name = rest.split('.').next()?;
                let (file, _, span) = interface.get(name)?.site.as_ref()?;
                Some((*file, *span))
            })
        })
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
            numbers.len().is_multiple_of(arity)
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
            let diagnostic = Diagnostic::error(
                span,
                format!(
                    "a rotation of {} about the axis 0 0 0 has no direction",
                    r[3]
                ),
            )
            .with_label("the axis is zero")
            .with_code("zero-axis");
            if self.options.strict {
                self.error(
                    file,
                    diagnostic.with_note(
                        "write an axis (0 1 0 for a heading), or 0 1 0 0 for no rotation",
                    ),
                );
                return None;
            }
            // Lenient: what viewers do with such files.
            let mut diagnostic = diagnostic.with_note("read as no rotation");
            diagnostic.severity = regatta_parser::Severity::Warning;
            self.error(file, diagnostic);
            return Some([0.0, 0.0, 1.0, 0.0]);
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

impl Lowerer<'_> {
    /// USE shares nodes, so the scene is a DAG whose expanded tree may be exponentially larger
    /// than the file: its size and depth are bounded here, at the first node that crosses
    /// either bound (node ids are a topological order: children are made first).
    fn check_expanded_size(&mut self) {
        if self.limits_reported.contains("nodes") {
            return;
        }
        let limit = self.options.limits.nodes as u64;
        let depth_limit = self.options.limits.scene_depth() as u32;
        let mut sizes = vec![0u64; self.nodes.len()];
        let mut depths = vec![0u32; self.nodes.len()];
        for index in 0..self.nodes.len() {
            let (mut size, mut depth) = (1u64, 1u32);
            for value in self.nodes[index].fields.own() {
                for child in value.nodes() {
                    size = size.saturating_add(sizes[child.index()]);
                    depth = depth.max(depths[child.index()].saturating_add(1));
                }
            }
            sizes[index] = size;
            depths[index] = depth;
            let origin = self.nodes[index].origin;
            if size > limit {
                self.nodes_limit(origin.file, origin.span, None);
                return;
            }
            if depth > depth_limit && !self.limits_reported.contains("nesting") {
                self.limit_crossed(
                    "nesting",
                    origin.file,
                    Diagnostic::error(
                        origin.span,
                        format!(
                            "nodes nested deeper than {depth_limit} levels once USE is expanded"
                        ),
                    )
                    .with_label("this node's USEs reach that deep"),
                );
                return;
            }
        }
        let total = self
            .roots
            .iter()
            .fold(0u64, |sum, root| sum.saturating_add(sizes[root.index()]));
        if total > limit {
            if let Some(&last) = self.roots.last() {
                let origin = self.nodes[last.index()].origin;
                self.nodes_limit(origin.file, origin.span, None);
            }
        }
    }

    /// A robot's name identifies it in logs, CSV and plots: a second robot with a name already
    /// taken is an error at its line; lenient mode renames it and says to what.
    fn check_robot_names(&mut self) {
        if self.limits_reported.contains("nodes") {
            return;
        }
        let catalogue = self.catalogue();
        let scene = Scene {
            nodes: std::mem::take(&mut self.nodes),
            roots: self.roots.clone(),
            files: Vec::new(),
            up_axis: self.up_axis,
            objects: self.objects,
        };
        let robots: Vec<NodeId> = scene
            .walk()
            .into_iter()
            .filter(|&id| {
                catalogue
                    .spec(scene.node(id).spec)
                    .classes
                    .iter()
                    .any(|c| c == "robot")
            })
            .collect();
        self.nodes = scene.nodes;
        let mut taken: HashMap<String, NodeId> = HashMap::new();
        let mut renames = Vec::new();
        for &id in &robots {
            let spec = catalogue.spec(self.nodes[id.index()].spec);
            let Some(index) = spec.field_index("name") else {
                continue;
            };
            let name = self.nodes[id.index()].fields[index]
                .strings()
                .first()
                .cloned()
                .unwrap_or_default();
            match taken.get(&name) {
                None => {
                    taken.insert(name, id);
                }
                Some(&first) => renames.push((id, index, name, first)),
            }
        }
        for (id, index, name, first) in renames {
            let node = &self.nodes[id.index()];
            let at = node.value_span_at(index).unwrap_or(node.origin);
            let first_node = &self.nodes[first.index()];
            let first_at = first_node.value_span_at(index).unwrap_or(first_node.origin);
            let mut diagnostic = Diagnostic::error(
                at.span,
                format!("a robot named '{name}' already exists: robot names must be unique"),
            )
            .with_label("second robot with this name")
            .with_code("duplicate-robot");
            if first_at.file == at.file {
                diagnostic = diagnostic.with_secondary(first_at.span, "first named here");
            } else {
                diagnostic = diagnostic.with_secondary_in(
                    first_at.file.0 as usize,
                    first_at.span,
                    "first named here",
                );
            }
            let new_name = (2..)
                .map(|k| format!("{name}_{k}"))
                .find(|candidate| !taken.contains_key(candidate))
                .unwrap_or_default();
            if self.options.strict {
                self.error(
                    at.file,
                    diagnostic
                        .with_note("logs, CSV and plots tell robots apart by name")
                        .with_note(format!("give it a name of its own: name \"{new_name}\"")),
                );
                continue;
            }
            taken.insert(new_name.clone(), id);
            diagnostic.severity = regatta_parser::Severity::Warning;
            self.error(
                at.file,
                diagnostic.with_note(format!("renamed to '{new_name}'")),
            );
            self.nodes[id.index()].fields[index] = Value::String(new_name);
        }
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

fn shorten(text: &str) -> String {
    let mut shown: String = text.chars().take(40).collect();
    if shown.len() < text.len() {
        shown.push('…');
    }
    shown
}

/// "a field", "an exposedField".
fn with_article(word: &str) -> String {
    let article = if word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {word}")
}

/// Whether an interface field declared with `interface` (a PROTO keyword) may be IS'd to a
/// node field of access `access` (VRML97 4.8.3, table 4.4).
fn is_compatible(interface: &str, access: &str) -> bool {
    let interface = match interface {
        "exposedField" => "exposedField",
        "eventIn" => "eventIn",
        "eventOut" => "eventOut",
        _ => "field",
    };
    match access {
        "exposedField" => true,
        "field" => interface == "field",
        "eventIn" => interface == "eventIn",
        "eventOut" => interface == "eventOut",
        _ => true,
    }
}

/// The span of each string of a written value.
fn string_spans(value: &syntax::FieldValue) -> Vec<Span> {
    match value {
        syntax::FieldValue::Value(syntax::Value {
            items: Items::Atoms(atoms),
            ..
        }) => atoms
            .iter()
            .filter_map(|a| match a {
                Atom::String(s) => Some(s.span),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
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
