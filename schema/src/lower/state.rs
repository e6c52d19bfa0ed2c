//! The lowerer's state and the types its jobs share: [`Lowerer`] (every table a check
//! keeps while it types a world), [`Scope`] (what names mean at a point of a file or PROTO
//! body: DEF names, visible PROTOs, the interface of the PROTO being expanded), [`ProtoDef`],
//! [`Frame`] (one PROTO instance being expanded), and what a url resolves against.

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::rc::Rc;

use regatta_parser::syntax::{self, Atom, BodyItem, Item, Items, NodeKind};
use regatta_parser::Span;

use crate::binding::Bindings;
use crate::catalogue::Catalogue;
use crate::scene::{FileId, NodeId, SceneNode, SharedFields, UpAxis};

use super::checked::{FileDiagnostic, Source, Substitution, UnbuiltRobot};
use super::options::Options;

/// PROTOs visible at some point, in order of definition (later entries win).
pub(super) type ProtoTable = Rc<Vec<(String, Rc<ProtoDef>)>>;

/// A PROTO definition and the file it was read from.
pub(super) struct ProtoDef {
    pub(super) file: FileId,
    pub(super) proto: syntax::Proto,
    /// PROTOs of the PROTO bodies it is nested in (empty at file level); its own file's
    /// PROTOs are found through [`Lowerer::file_scopes`].
    pub(super) enclosing: ProtoTable,
}

impl ProtoDef {
    /// A PROTO defined at the top level of `file`, as a table entry.
    pub(super) fn file_level(file: FileId, proto: &syntax::Proto) -> (String, Rc<ProtoDef>) {
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
pub(super) struct Scope {
    pub(super) file: FileId,
    pub(super) defs: HashMap<String, NodeId>,
    pub(super) protos: ProtoTable,
    /// PROTO interface bindings, inside a PROTO body.
    pub(super) interface: Option<Rc<Bindings>>,
    /// DEF names inside nodes that were skipped (lenient mode), so that their USEs are
    /// skipped quietly too.
    pub(super) skipped_defs: BTreeSet<String>,
}

impl Scope {
    pub(super) fn new(file: FileId) -> Scope {
        Scope {
            file,
            defs: HashMap::new(),
            protos: Rc::new(Vec::new()),
            interface: None,
            skipped_defs: BTreeSet::new(),
        }
    }

    pub(super) fn find_proto(&self, name: &str) -> Option<Rc<ProtoDef>> {
        self.protos
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, p)| p.clone())
    }
}

/// What a file's relative urls resolve against.
#[derive(Clone, Debug)]
pub(super) enum UrlBase {
    /// The folder of the file (canonical).
    Dir(PathBuf),
    /// A text with no folder (standard input): the current directory.
    CurrentDir,
    /// Built-in text (standard PROTOs, the catalogue): it names no file.
    NoFiles,
}

/// What a url is for: says what happens when it is not followed.
#[derive(Clone, Copy, Debug)]
pub(super) enum UrlUse<'a> {
    Inline,
    ExternProto,
    /// A file a node names but regatta does not read (an ImageTexture's image).
    Image(&'a str),
    /// A file the exporters read (a Mesh's model).
    Asset(&'a str),
}

impl UrlUse<'_> {
    /// An image drawn on a shape (an ImageTexture's, or any image regatta does not read).
    pub(super) fn is_texture(&self) -> bool {
        matches!(self, UrlUse::Image(_) | UrlUse::Asset("ImageTexture"))
    }

    pub(super) fn noun(&self) -> &str {
        match self {
            UrlUse::Inline => "Inline",
            UrlUse::ExternProto => "EXTERNPROTO",
            UrlUse::Image(node) | UrlUse::Asset(node) => node,
        }
    }

    pub(super) fn instead(&self) -> &'static str {
        match self {
            UrlUse::Inline => "the Inline stays empty",
            UrlUse::ExternProto => "its PROTO stays unknown",
            UrlUse::Image(_) => "the image is not used",
            UrlUse::Asset("ImageTexture") => "the texture is not exported",
            UrlUse::Asset(_) => "the shape is not exported",
        }
    }
}

/// One PROTO instance being expanded.
pub(super) struct Frame {
    pub(super) name: String,
    /// The definition's offset in its file (with `definition`, its identity).
    pub(super) key: u32,
    /// Where the instance was written.
    pub(super) instance: (FileId, Span),
    /// The file holding the PROTO's definition.
    pub(super) definition: FileId,
}

pub(super) struct Lowerer<'c> {
    pub(super) options: Options,
    pub(super) catalogue: Option<&'c Catalogue>,
    pub(super) nodes: Vec<SceneNode>,
    /// Whether each node is, or holds, a robot (a robot must not be USEd twice).
    pub(super) holds_robot: Vec<bool>,
    /// Field values of nodes made so far, for the next instance of a PROTO to share.
    pub(super) shared_fields: SharedFields,
    pub(super) sources: Vec<Source>,
    /// What each file's urls resolve against, by file id.
    pub(super) file_bases: Vec<UrlBase>,
    /// Parse diagnostics of each file, kept until the end so that typed messages can replace
    /// the parser's generic "missing value" ones.
    pub(super) parse_diagnostics: Vec<FileDiagnostic>,
    pub(super) diagnostics: Vec<FileDiagnostic>,
    /// Diagnostics dropped past `MAX_DIAGNOSTICS`.
    pub(super) dropped: usize,
    pub(super) refined_missing: BTreeSet<(u32, u32)>,
    pub(super) builtins: Option<ProtoTable>,
    /// Webots stand-ins parsed so far, by name (`None`: looked for, not a stand-in's name).
    pub(super) standins: HashMap<String, Option<Rc<ProtoDef>>>,
    /// EXTERNPROTO names that point where regatta does not go, with the URL.
    pub(super) unresolved: HashMap<String, String>,
    /// The PROTO instances being expanded, outermost first.
    pub(super) frames: Vec<Frame>,
    /// The Inline and EXTERNPROTO files being read, outermost first.
    pub(super) includes: Vec<FileId>,
    /// Nodes being lowered inside each other (the expanded scene's depth).
    pub(super) node_depth: usize,
    /// Bounding objects being lowered (inside one, geometry may stand in `children`).
    pub(super) in_bounding_object: usize,
    /// The user's line a value inside a PROTO body came from, while it is being typed.
    pub(super) blame: Option<(FileId, Span)>,
    /// Places problems in PROTO bodies were moved to (each gets one message).
    pub(super) relocated: BTreeSet<(u32, u32)>,
    /// PROTOs whose interface was already checked for unused fields.
    pub(super) checked_protos: BTreeSet<(u32, u32)>,
    /// PROTO declarations already checked where they stand (`declared.rs`).
    pub(super) declared_protos: BTreeSet<(u32, u32)>,
    /// Nodes a PROTO expands to at most, by definition (file, offset).
    pub(super) estimates: HashMap<(u32, u32), u64>,
    /// Files already loaded (EXTERNPROTO, Inline), by canonical path.
    pub(super) loaded: HashMap<PathBuf, FileId>,
    /// Each file's syntax tree, parsed once.
    pub(super) parsed: HashMap<u32, Rc<syntax::SourceFile>>,
    /// The PROTO table of each file, by file id.
    pub(super) file_scopes: HashMap<u32, ProtoTable>,
    /// The PROTO each instance's root node was made by (the outermost one), for ROUTEs.
    pub(super) instance_of: HashMap<NodeId, Rc<ProtoDef>>,
    /// Limits already reported (each is one cause: one message).
    pub(super) limits_reported: BTreeSet<&'static str>,
    pub(super) up_axis: UpAxis,
    pub(super) objects: crate::webots::Objects,
    pub(super) roots: Vec<NodeId>,
    /// Who wrote each file that is not the world's (built-in PROTO files).
    pub(super) file_authoring: HashMap<u32, crate::webots::Authoring>,
    /// PROTO instance roots: the authoring of the file that wrote the instance.
    pub(super) instance_authoring: HashMap<u32, crate::webots::Authoring>,
    /// PROTO instance roots: the authoring of the file their body was written in (their
    /// origin is the instance, in the user's file).
    pub(super) body_authoring: HashMap<u32, crate::webots::Authoring>,
    /// The urls EXTERNPROTOs give for stand-in names.
    pub(super) standin_urls: HashMap<String, String>,
    pub(super) substitutions: Vec<Substitution>,
    pub(super) unbuilt_robots: Vec<UnbuiltRobot>,
    /// The JavaScript engine, started by the first template that needs it.
    pub(super) engine: Option<regatta_template::Engine>,
    /// Expanded template PROTOs by PROTO, field values and (for nonDeterministic ones)
    /// instance; `None` for an expansion that failed (reported once).
    pub(super) expanded: HashMap<String, Option<Rc<ProtoDef>>>,
    /// Template instances so far: the next one's `context.id`.
    pub(super) template_instances: u64,
    /// `WorldInfo.randomSeed` as written, which seeds templates.
    pub(super) world_seed: i64,
    /// The world's Webots version (its header), which templates see in `context`.
    pub(super) webots_version: String,
    /// Mesh and image files read so far, by node.
    pub(super) assets: Vec<crate::scene::Asset>,
    /// Each file read for an asset, once, by canonical path (`Err`: why it was not).
    pub(super) asset_files: HashMap<PathBuf, Result<std::sync::Arc<[u8]>, String>>,
}

impl<'c> Lowerer<'c> {
    pub(super) fn new(mut options: Options) -> Lowerer<'c> {
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
            in_bounding_object: 0,
            blame: None,
            relocated: BTreeSet::new(),
            checked_protos: BTreeSet::new(),
            declared_protos: BTreeSet::new(),
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
            standins: HashMap::new(),
            standin_urls: HashMap::new(),
            substitutions: Vec::new(),
            unbuilt_robots: Vec::new(),
            engine: None,
            expanded: HashMap::new(),
            template_instances: 0,
            world_seed: 0,
            webots_version: String::new(),
            assets: Vec::new(),
            asset_files: HashMap::new(),
        }
    }

    pub(super) fn catalogue(&self) -> &'c Catalogue {
        match self.catalogue {
            Some(catalogue) => catalogue,
            None => Catalogue::get(),
        }
    }
}

/// Whether a PROTO's body holds template statements (not only `%<= … >%` values): its body is
/// then the text the template generates for each instance.
pub(super) fn has_template(proto: &syntax::Proto) -> bool {
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
