//! What a world may read and how large it may grow: [`FileAccess`] (the folders a world's
//! urls may lead into) and [`Limits`] (include depth, PROTO depth, nodes, nesting, file size).
//!
//! A world is untrusted input. It reads only files under its **root**: its project, plus
//! folders the user names (`--allow-path DIR`). A world's project is the folder above it when
//! the world's folder is named `worlds` (Webots' layout: `worlds/`, `protos/`, `controllers/`
//! side by side, worlds naming `../protos/X.proto`), otherwise the world's own folder
//! ([`project_root`]). Every
//! url resolves relative to the file that names it; absolute paths, `..` that climbs out of
//! the root, and symbolic links whose target lies outside it are refused, as is every network
//! url (nothing is ever fetched). Refusals name the url and the rule, never a file's bytes.
//!
//! Anything that reads files for a world (Inline, EXTERNPROTO, ImageTexture, a PROTO search
//! path) goes through [`FileAccess::resolve`], so the rules cannot differ between them.

use std::fmt;
use std::path::{Component, Path, PathBuf};

/// The folders a world may read files from (canonical paths).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FileAccess {
    roots: Vec<PathBuf>,
}

/// The project of a world whose (canonical) folder is `world_folder`: the folder above it when
/// `world_folder` is named `worlds`, as Webots lays out a project, else `world_folder` itself.
pub fn project_root(world_folder: &Path) -> PathBuf {
    match (world_folder.file_name(), world_folder.parent()) {
        (Some(name), Some(parent)) if name == "worlds" && parent.parent().is_some() => {
            parent.to_owned()
        }
        _ => world_folder.to_owned(),
    }
}

/// Why a url was not read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// `http:`, `https:`, `webots:`… : never fetched.
    Network { scheme: String },
    /// `/etc/passwd`, `C:\x`, `file:///x`.
    Absolute,
    /// `../../x` that leaves every root.
    OutsideRoot,
    /// A path inside the root whose symbolic links lead outside it.
    LinkOutsideRoot,
    /// The world may read no file at all (standard input, a log's embedded world).
    NoAccess,
    /// The file the url names does not exist.
    Missing,
    /// The url is empty.
    Empty,
}

impl Refusal {
    /// The sentence of a diagnostic about `url`.
    pub fn message(&self, url: &str) -> String {
        match self {
            Refusal::Network { scheme } => {
                format!(
                    "'{url}' is a network url ({scheme}:); regatta never fetches from the network"
                )
            }
            Refusal::Absolute => format!("'{url}' is an absolute path; a world may not read it"),
            Refusal::OutsideRoot => format!("'{url}' leads outside the world's project"),
            Refusal::LinkOutsideRoot => {
                format!("'{url}' is a symbolic link to a place outside the world's project")
            }
            Refusal::NoAccess => {
                format!("'{url}' cannot be read: this world may read no file")
            }
            Refusal::Missing => format!("'{url}' does not exist"),
            Refusal::Empty => "an empty url names no file".to_owned(),
        }
    }

    /// The rule, as a note under the diagnostic.
    pub fn rule(&self) -> &'static str {
        match self {
            Refusal::Network { .. } => {
                "to use the file, put a copy in the world's folder and name it by a relative path"
            }
            Refusal::Absolute | Refusal::OutsideRoot | Refusal::LinkOutsideRoot => {
                "a world reads only files under its project (its folder, or the folder above it when that is named `worlds`, as in a Webots project) and folders given with --allow-path DIR; urls are relative to the file that names them"
            }
            Refusal::NoAccess => {
                "a world read from standard input or from a log reads no file unless --allow-path DIR names a folder"
            }
            Refusal::Missing => "urls are relative to the file that names them",
            Refusal::Empty => "write the path of a file relative to this one",
        }
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.rule())
    }
}

impl FileAccess {
    /// No file may be read.
    pub fn none() -> FileAccess {
        FileAccess::default()
    }

    /// The root of the world file at `path`: its project ([`project_root`]).
    pub fn for_world(path: &Path) -> std::io::Result<FileAccess> {
        let mut access = FileAccess::none();
        let folder = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_owned(),
            _ => PathBuf::from("."),
        };
        access.allow(&project_root(&folder.canonicalize()?))?;
        Ok(access)
    }

    /// Lets the world read files under `dir` too (`--allow-path`).
    pub fn allow(&mut self, dir: &Path) -> std::io::Result<()> {
        let canonical = dir.canonicalize()?;
        if !canonical.is_dir() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{} is not a folder", dir.display()),
            ));
        }
        if !self.roots.contains(&canonical) {
            self.roots.push(canonical);
        }
        Ok(())
    }

    /// The folders files may be read from.
    pub fn roots(&self) -> &[PathBuf] {
        &self.roots
    }

    /// Whether any file may be read.
    pub fn is_none(&self) -> bool {
        self.roots.is_empty()
    }

    /// The canonical path of the file `url` names, written in a file whose folder is `base`
    /// (`None`: a text with no folder, such as standard input, resolved against the current
    /// directory), if the rules allow reading it.
    pub fn resolve(&self, url: &str, base: Option<&Path>) -> Result<PathBuf, Refusal> {
        if url.is_empty() {
            return Err(Refusal::Empty);
        }
        if let Some(scheme) = url_scheme(url) {
            if scheme.eq_ignore_ascii_case("file") {
                return Err(Refusal::Absolute);
            }
            return Err(Refusal::Network {
                scheme: scheme.to_ascii_lowercase(),
            });
        }
        let relative = Path::new(url);
        if relative.has_root()
            || relative.is_absolute()
            || url.starts_with(['/', '\\'])
            || is_drive_path(url)
        {
            return Err(Refusal::Absolute);
        }
        if self.roots.is_empty() {
            return Err(Refusal::NoAccess);
        }
        // The base as the file system sees it (roots are canonical too), so that a relative
        // or linked base compares with them.
        let base = match base {
            Some(base) => base.canonicalize().unwrap_or_else(|_| base.to_owned()),
            None => std::env::current_dir()
                .and_then(|d| d.canonicalize())
                .map_err(|_| Refusal::NoAccess)?,
        };
        // Lexically first: `..` that leaves every root is refused even when the target does
        // not exist, so that a probe learns nothing about the file system.
        let mut lexical = base.clone();
        for component in relative.components() {
            match component {
                Component::Normal(part) => lexical.push(part),
                Component::CurDir => {}
                Component::ParentDir => {
                    if !lexical.pop() {
                        return Err(Refusal::OutsideRoot);
                    }
                }
                Component::RootDir | Component::Prefix(_) => return Err(Refusal::Absolute),
            }
        }
        if !self.contains(&lexical) {
            return Err(Refusal::OutsideRoot);
        }
        // Then where the links lead.
        let canonical = match lexical.canonicalize() {
            Ok(path) => path,
            Err(_) => {
                // A dangling link, or a link through a folder outside the root that does not
                // exist: say what is inside the root, nothing more.
                return Err(if std::fs::symlink_metadata(&lexical).is_ok() {
                    Refusal::LinkOutsideRoot
                } else {
                    Refusal::Missing
                });
            }
        };
        if !self.contains(&canonical) {
            return Err(Refusal::LinkOutsideRoot);
        }
        Ok(canonical)
    }

    fn contains(&self, path: &Path) -> bool {
        self.roots.iter().any(|root| path.starts_with(root))
    }
}

/// `http` in `http://x`, `webots` in `webots://x`; `None` for a path (a Windows drive letter
/// is not a scheme).
fn url_scheme(url: &str) -> Option<&str> {
    let colon = url.find(':')?;
    let scheme = &url[..colon];
    let valid = scheme.len() > 1
        && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'));
    valid.then_some(scheme)
}

fn is_drive_path(url: &str) -> bool {
    let bytes = url.as_bytes();
    bytes.len() >= 2 && bytes[0].is_ascii_alphabetic() && bytes[1] == b':'
}

/// Bounds that keep a hostile or mistaken world small and quick to reject. Each is reported
/// once, as an error at the place that crossed it, with the limit in the message; the command
/// line raises them with `--limit KEY=N`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Nesting of nodes in a file's text (`nesting`).
    pub nesting: usize,
    /// Inline and EXTERNPROTO files including each other (`include-depth`).
    pub include_depth: usize,
    /// PROTO instances inside PROTO bodies (`proto-depth`).
    pub proto_depth: usize,
    /// Nodes of the scene once PROTOs and USE are expanded (`nodes`).
    pub nodes: usize,
    /// Bytes of one file, after gzip inflation (`file-size`).
    pub file_size: u64,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            nesting: regatta_parser::MAX_DEPTH,
            include_depth: 16,
            proto_depth: 32,
            nodes: 1_000_000,
            file_size: regatta_parser::source::MAX_FILE_SIZE,
        }
    }
}

/// The keys of `--limit KEY=N`, with what each bounds and its largest value.
pub const LIMIT_KEYS: &[(&str, &str, u64)] = &[
    ("nesting", "nesting of nodes in a file's text", 1024),
    (
        "include-depth",
        "Inline and EXTERNPROTO files within each other",
        1024,
    ),
    ("proto-depth", "PROTO instances within PROTO bodies", 1024),
    ("nodes", "nodes after PROTO and USE expansion", 100_000_000),
    (
        "file-size",
        "bytes of one file (after gzip inflation)",
        1 << 34,
    ),
];

impl Limits {
    /// Sets one limit from `KEY=N` (`N` may end in k, M or G for file-size).
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let keys = LIMIT_KEYS
            .iter()
            .map(|(k, _, _)| *k)
            .collect::<Vec<_>>()
            .join(", ");
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| format!("'{assignment}' is not KEY=N (keys: {keys})"))?;
        let Some(&(_, _, most)) = LIMIT_KEYS.iter().find(|(k, _, _)| *k == key.trim()) else {
            return Err(format!("no limit named '{key}' (keys: {keys})"));
        };
        let value = value.trim();
        let (digits, scale) = match value.char_indices().last() {
            Some((i, 'k' | 'K')) => (&value[..i], 1u64 << 10),
            Some((i, 'M')) => (&value[..i], 1 << 20),
            Some((i, 'G')) => (&value[..i], 1 << 30),
            _ => (value, 1),
        };
        let number = digits
            .parse::<u64>()
            .ok()
            .and_then(|n| n.checked_mul(scale))
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                format!("the {key} limit must be a positive whole number, found '{value}'")
            })?;
        if number > most {
            return Err(format!(
                "the {key} limit can be raised to at most {most}, found {number}"
            ));
        }
        match key.trim() {
            "nesting" => self.nesting = number as usize,
            "include-depth" => self.include_depth = number as usize,
            "proto-depth" => self.proto_depth = number as usize,
            "nodes" => self.nodes = number as usize,
            _ => self.file_size = number,
        }
        Ok(())
    }

    /// The deepest a scene may be once PROTOs, Inline and USE are expanded: four times the
    /// text's nesting, so that what the parser accepts always fits.
    pub fn scene_depth(&self) -> usize {
        self.nesting.saturating_mul(4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_and_drives() {
        assert_eq!(url_scheme("http://x"), Some("http"));
        assert_eq!(url_scheme("webots://projects/x.proto"), Some("webots"));
        assert_eq!(url_scheme("C:\\x"), None);
        assert_eq!(url_scheme("protos/x.proto"), None);
        assert!(is_drive_path("C:\\x"));
    }

    #[test]
    fn limits_parse() {
        let mut limits = Limits::default();
        limits.set("nodes=5000").unwrap();
        limits.set("file-size=2M").unwrap();
        assert_eq!((limits.nodes, limits.file_size), (5000, 2 << 20));
        assert!(limits.set("nodes=0").is_err());
        assert!(limits.set("depth=3").is_err());
        assert!(limits.set("nesting=100000").is_err());
    }

    #[test]
    fn urls_stay_inside_the_root() {
        let dir = std::env::temp_dir().join(format!("regatta-access-{}", std::process::id()));
        let world = dir.join("world");
        std::fs::create_dir_all(world.join("parts")).unwrap();
        std::fs::write(world.join("parts/a.wrl"), "#VRML V2.0 utf8\n").unwrap();
        std::fs::write(dir.join("secret.txt"), "secret").unwrap();
        let access = FileAccess::for_world(&world.join("w.wbt")).unwrap();
        let base = world.canonicalize().unwrap();
        assert!(access.resolve("parts/a.wrl", Some(&base)).is_ok());
        assert!(access.resolve("parts/../parts/a.wrl", Some(&base)).is_ok());
        assert_eq!(
            access.resolve("../secret.txt", Some(&base)),
            Err(Refusal::OutsideRoot)
        );
        assert_eq!(
            access.resolve("/etc/passwd", Some(&base)),
            Err(Refusal::Absolute)
        );
        assert_eq!(
            access.resolve("parts/none.wrl", Some(&base)),
            Err(Refusal::Missing)
        );
        assert!(matches!(
            access.resolve("https://example.com/x.wrl", Some(&base)),
            Err(Refusal::Network { .. })
        ));
        #[cfg(unix)]
        {
            let link = world.join("link.wrl");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(dir.join("secret.txt"), &link).unwrap();
            assert_eq!(
                access.resolve("link.wrl", Some(&base)),
                Err(Refusal::LinkOutsideRoot)
            );
        }
        assert_eq!(
            FileAccess::none().resolve("parts/a.wrl", Some(&base)),
            Err(Refusal::NoAccess)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
