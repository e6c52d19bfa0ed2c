//! Finding a robot's controller in its project and making it runnable: a C controller is
//! compiled once with the system's C compiler against regatta's headers and library (embedded
//! in the binary, so an installed `regatta` needs no files beside it), into a cache keyed by
//! every input, and rebuilt when a source changes.
//!
//! As Webots does, a controller `NAME` is the folder `controllers/NAME/` of the world's
//! project (the folder above `worlds/`), compiled from every `.c` file in it. The name is one
//! path component and the folder must lie inside the project: a world reaches nothing outside
//! it.

use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

use crate::error::WebotsError;

/// regatta's Webots headers, as `(file name under include/webots/, text)`.
pub const HEADERS: &[(&str, &str)] = &[
    ("types.h", include_str!("../include/webots/types.h")),
    ("nodes.h", include_str!("../include/webots/nodes.h")),
    ("device.h", include_str!("../include/webots/device.h")),
    ("robot.h", include_str!("../include/webots/robot.h")),
    ("motor.h", include_str!("../include/webots/motor.h")),
    (
        "position_sensor.h",
        include_str!("../include/webots/position_sensor.h"),
    ),
    (
        "distance_sensor.h",
        include_str!("../include/webots/distance_sensor.h"),
    ),
    (
        "light_sensor.h",
        include_str!("../include/webots/light_sensor.h"),
    ),
    ("led.h", include_str!("../include/webots/led.h")),
    ("camera.h", include_str!("../include/webots/camera.h")),
    ("gps.h", include_str!("../include/webots/gps.h")),
    ("compass.h", include_str!("../include/webots/compass.h")),
    (
        "inertial_unit.h",
        include_str!("../include/webots/inertial_unit.h"),
    ),
    (
        "accelerometer.h",
        include_str!("../include/webots/accelerometer.h"),
    ),
    ("gyro.h", include_str!("../include/webots/gyro.h")),
    (
        "touch_sensor.h",
        include_str!("../include/webots/touch_sensor.h"),
    ),
    ("emitter.h", include_str!("../include/webots/emitter.h")),
    ("receiver.h", include_str!("../include/webots/receiver.h")),
    ("keyboard.h", include_str!("../include/webots/keyboard.h")),
    (
        "supervisor.h",
        include_str!("../include/webots/supervisor.h"),
    ),
];

/// The controller library's C source, and the supervisor's part it includes.
pub const LIBRARY: &str = include_str!("../c/regatta_controller.c");
pub const LIBRARY_SUPERVISOR: &str = include_str!("../c/supervisor.c");

/// A controller found in a project.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Program {
    /// C sources (every `.c` of the folder, sorted).
    C {
        name: String,
        folder: PathBuf,
        sources: Vec<PathBuf>,
    },
    /// A Python controller (`NAME.py`), run by the user's Python 3 ([`crate::python`]).
    Python { name: String, folder: PathBuf },
    /// `<extern>`: a program the user starts, which connects by itself (its folder: the
    /// project's).
    Extern { folder: PathBuf },
}

impl Program {
    /// The controller's folder: its working directory when it runs.
    pub fn folder(&self) -> &Path {
        match self {
            Program::C { folder, .. }
            | Program::Python { folder, .. }
            | Program::Extern { folder } => folder,
        }
    }

    /// The controller's name (its folder's).
    pub fn name(&self) -> &str {
        match self {
            Program::C { name, .. } | Program::Python { name, .. } => name,
            Program::Extern { .. } => "<extern>",
        }
    }

    /// The language, for messages.
    pub fn language(&self) -> &'static str {
        match self {
            Program::C { .. } => "C",
            Program::Python { .. } => "Python",
            Program::Extern { .. } => "extern",
        }
    }
}

/// The project of a world file: the folder above its `worlds/` folder (Webots' layout), or
/// the world's own folder when it is not in one named `worlds`.
pub fn project_of(world: &Path) -> PathBuf {
    let folder = world.parent().unwrap_or(Path::new("."));
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    if folder.file_name().is_some_and(|n| n == "worlds") {
        match folder.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    } else {
        folder.to_path_buf()
    }
}

/// Whether `name` may name a controller folder: one plain path component.
fn plain_name(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\', '\0'])
        && !name.starts_with('<')
}

/// Whether `name` names a controller folder of `project` (what `regatta check` accepts as a
/// program of the world's own, without reading or running it).
pub fn is_program(project: &Path, name: &str) -> bool {
    plain_name(name) && project.join("controllers").join(name).is_dir()
}

/// The controller `name` of `project`, if the project has one (`Ok(None)`: no such folder).
pub fn find(project: &Path, name: &str) -> Result<Option<Program>, WebotsError> {
    if !plain_name(name) {
        return Ok(None);
    }
    let folder = project.join("controllers").join(name);
    if !folder.is_dir() {
        return Ok(None);
    }
    // Absolute: the compiler and the controller run in the folder itself.
    let folder = std::path::absolute(&folder).map_err(|source| WebotsError::io(&folder, source))?;
    // The folder must be the project's own: a link out of it is refused.
    let inside = |path: &Path| -> Result<(), WebotsError> {
        let root = project
            .canonicalize()
            .map_err(|source| WebotsError::io(project, source))?;
        let real = path
            .canonicalize()
            .map_err(|source| WebotsError::io(path, source))?;
        if real.starts_with(&root) {
            Ok(())
        } else {
            Err(WebotsError::OutsideProject {
                controller: name.to_owned(),
                path: path.to_path_buf(),
            })
        }
    };
    inside(&folder)?;
    let mut sources = Vec::new();
    let entries = std::fs::read_dir(&folder).map_err(|source| WebotsError::io(&folder, source))?;
    for entry in entries {
        let path = entry
            .map_err(|source| WebotsError::io(&folder, source))?
            .path();
        if path.extension().is_some_and(|e| e == "c") && path.is_file() {
            inside(&path)?;
            sources.push(path);
        }
    }
    sources.sort();
    if !sources.is_empty() {
        return Ok(Some(Program::C {
            name: name.to_owned(),
            folder,
            sources,
        }));
    }
    if folder.join(format!("{name}.py")).is_file() {
        return Ok(Some(Program::Python {
            name: name.to_owned(),
            folder,
        }));
    }
    Err(WebotsError::NoSources {
        controller: name.to_owned(),
        folder,
    })
}

/// Where compiled controllers are kept: `$REGATTA_CACHE_DIR`, else `$XDG_CACHE_HOME/regatta`,
/// else `~/.cache/regatta`, else the system's temporary folder.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("REGATTA_CACHE_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir).join("regatta");
    }
    if let Some(home) = std::env::var_os("HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(home).join(".cache").join("regatta");
    }
    std::env::temp_dir().join("regatta-cache")
}

/// The C compiler: `$CC`, else `cc`.
pub(crate) fn compiler() -> String {
    std::env::var("CC")
        .ok()
        .filter(|c| !c.trim().is_empty())
        .unwrap_or_else(|| "cc".to_owned())
}

pub(crate) fn hex(digest: &[u8]) -> String {
    digest.iter().take(12).map(|b| format!("{b:02x}")).collect()
}

/// Writes the headers and the library once into `cache/sdk/HASH/`, returning that folder.
pub fn sdk(cache: &Path) -> Result<PathBuf, WebotsError> {
    let mut hash = Sha256::new();
    for (name, text) in HEADERS {
        hash.update(name.as_bytes());
        hash.update(text.as_bytes());
    }
    hash.update(LIBRARY.as_bytes());
    hash.update(LIBRARY_SUPERVISOR.as_bytes());
    let dir = cache.join("sdk").join(hex(&hash.finalize()));
    if dir.join("complete").is_file() {
        return Ok(dir);
    }
    write_sdk(&dir)?;
    let mark = dir.join("complete");
    std::fs::write(&mark, b"").map_err(|source| WebotsError::io(&mark, source))?;
    Ok(dir)
}

/// Writes the headers (`dir/include/webots/`) and the controller library's sources
/// (`dir/regatta_controller.c`, which includes `dir/supervisor.c`) into `dir`.
pub fn write_sdk(dir: &Path) -> Result<(), WebotsError> {
    let include = dir.join("include").join("webots");
    std::fs::create_dir_all(&include).map_err(|source| WebotsError::io(&include, source))?;
    for (name, text) in HEADERS {
        let path = include.join(name);
        std::fs::write(&path, text).map_err(|source| WebotsError::io(&path, source))?;
    }
    let library = dir.join("regatta_controller.c");
    std::fs::write(&library, LIBRARY).map_err(|source| WebotsError::io(&library, source))?;
    let part = dir.join("supervisor.c");
    std::fs::write(&part, LIBRARY_SUPERVISOR).map_err(|source| WebotsError::io(&part, source))?;
    Ok(())
}

/// Compiles a C controller (or finds it compiled), returning the executable's path and
/// whether it was built now.
pub fn compile(program: &Program, cache: &Path) -> Result<(PathBuf, bool), WebotsError> {
    let Program::C {
        name,
        folder,
        sources,
    } = program
    else {
        return Err(WebotsError::Unsupported {
            controller: program.name().to_owned(),
            language: program.language(),
        });
    };
    let sdk = sdk(cache)?;
    let cc = compiler();
    let flags = ["-O2", "-std=gnu11", "-w"];
    // The key: the compiler and flags, the library, and every C source and header of the
    // folder (a header included from elsewhere is not followed; `touch` a source to rebuild).
    let mut hash = Sha256::new();
    hash.update(cc.as_bytes());
    for flag in flags {
        hash.update(flag.as_bytes());
    }
    hash.update(sdk.as_os_str().as_encoded_bytes());
    let mut inputs: Vec<PathBuf> = sources.clone();
    if let Ok(entries) = std::fs::read_dir(folder) {
        for entry in entries.flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|e| e == "h") {
                inputs.push(path);
            }
        }
    }
    inputs.sort();
    for path in &inputs {
        let bytes = std::fs::read(path).map_err(|source| WebotsError::io(path, source))?;
        hash.update(path.file_name().unwrap_or_default().as_encoded_bytes());
        hash.update((bytes.len() as u64).to_le_bytes());
        hash.update(&bytes);
    }
    let dir = cache.join("controllers").join(hex(&hash.finalize()));
    let executable = dir.join(name);
    if executable.is_file() {
        return Ok((executable, false));
    }
    std::fs::create_dir_all(&dir).map_err(|source| WebotsError::io(&dir, source))?;
    let partial = dir.join(format!(".{name}.partial.{}", std::process::id()));
    let output = Command::new(&cc)
        .args(flags)
        .arg("-I")
        .arg(sdk.join("include"))
        .arg("-I")
        .arg(folder)
        .args(sources)
        .arg(sdk.join("regatta_controller.c"))
        .arg("-o")
        .arg(&partial)
        .arg("-lm")
        .current_dir(folder)
        .output()
        .map_err(|source| WebotsError::Compiler {
            compiler: cc.clone(),
            source: std::sync::Arc::new(source),
        })?;
    if !output.status.success() {
        let _ = std::fs::remove_file(&partial);
        return Err(WebotsError::DoesNotCompile {
            controller: name.clone(),
            messages: String::from_utf8_lossy(&output.stderr)
                .trim_end()
                .to_owned(),
        });
    }
    std::fs::rename(&partial, &executable)
        .map_err(|source| WebotsError::io(&executable, source))?;
    Ok((executable, true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_project_is_the_folder_above_worlds() {
        assert_eq!(project_of(Path::new("p/worlds/w.wbt")), PathBuf::from("p"));
        assert_eq!(project_of(Path::new("worlds/w.wbt")), PathBuf::from("."));
        assert_eq!(project_of(Path::new("w.wbt")), PathBuf::from("."));
        assert_eq!(project_of(Path::new("a/w.wbt")), PathBuf::from("a"));
    }

    #[test]
    fn controller_names_are_plain() {
        for bad in ["", ".", "..", "../x", "a/b", "<extern>"] {
            assert!(!plain_name(bad), "{bad}");
        }
        assert!(plain_name("e-puck_line"));
    }
}
