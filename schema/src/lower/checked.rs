//! What a check returns: [`Checked`] (the scene, every diagnostic, the files they refer to,
//! the stand-ins used, the robots that could not be built) and how it renders; the refusal of
//! a world whose robots were not built.

use std::rc::Rc;

use regatta_parser::{Diagnostic, SourceMap, Span};

use crate::scene::{FileId, Scene};

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
        let mut kept = self.diagnostics.iter().filter(|d| keep(d)).peekable();
        // The map finds every line of every file: only worth it for something to show.
        if kept.peek().is_none() {
            return String::new();
        }
        let map = self.source_map();
        kept.map(|d| map.render(d.file.0 as usize, &d.diagnostic, color))
            .collect()
    }

    /// One line per diagnostic: `file:line:col: error: message`.
    pub fn short(&self) -> Vec<String> {
        if self.diagnostics.is_empty() {
            return Vec::new();
        }
        let map = self.source_map();
        self.diagnostics
            .iter()
            .map(|d| map.short(d.file.0 as usize, &d.diagnostic))
            .collect()
    }

    /// Why a world whose robots regatta could not build is not simulated, naming each robot at
    /// its file:line:col and its PROTO's url; `None` when every robot was built.
    pub fn unbuilt_refusal(&self) -> Option<String> {
        let unbuilt = &self.unbuilt_robots;
        if unbuilt.is_empty() {
            return None;
        }
        let lines: Vec<String> = unbuilt
            .iter()
            .map(|robot| {
                let source = &self.sources[robot.file.0 as usize];
                let (line, column) =
                    regatta_parser::diagnostic::line_col(&source.text, robot.span.start as usize);
                let from = match &robot.url {
                    Some(url) => format!(" (its PROTO: {url})"),
                    None => String::new(),
                };
                format!(
                    "  {}:{line}:{column}: '{}'{from}",
                    source.name, robot.type_name
                )
            })
            .collect();
        Some(format!(
            "the world has {} robot(s) regatta could not build, so it is not simulated:\n{}\nregatta has stand-ins for Khepera1 to Khepera4, E-puck (and its e-puck2 version, with Pi-puck), E-puck_enu and Thymio2 (and its own Khepera); --proto-path DIR can point at a folder with the others' PROTOs",
            unbuilt.len(),
            lines.join("\n")
        ))
    }
}
