//! Python controllers: Webots' `controller` module (`webots/python/controller/`, written from
//! Webots' published reference and embedded in the binary) over the same C library C
//! controllers link, built as a shared library with the system's C compiler beside the
//! package in the cache. A Python controller `NAME` is `controllers/NAME/NAME.py`, run by the
//! user's Python 3 (`runtime.ini`'s `[python] COMMAND`, else `$REGATTA_PYTHON`, else
//! `python3` on the `PATH`) with `-u` (unbuffered, so its lines appear as printed), the
//! package first on `PYTHONPATH`, and the folder as its working directory.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

use crate::compile::{self, Program};
use crate::error::WebotsError;

/// The `controller` package, as `(file name, text)`.
pub const PACKAGE: &[(&str, &str)] = &[
    (
        "__init__.py",
        include_str!("../python/controller/__init__.py"),
    ),
    ("_wb.py", include_str!("../python/controller/_wb.py")),
    (
        "accelerometer.py",
        include_str!("../python/controller/accelerometer.py"),
    ),
    (
        "ansi_codes.py",
        include_str!("../python/controller/ansi_codes.py"),
    ),
    ("camera.py", include_str!("../python/controller/camera.py")),
    (
        "compass.py",
        include_str!("../python/controller/compass.py"),
    ),
    ("device.py", include_str!("../python/controller/device.py")),
    (
        "distance_sensor.py",
        include_str!("../python/controller/distance_sensor.py"),
    ),
    (
        "emitter.py",
        include_str!("../python/controller/emitter.py"),
    ),
    ("gps.py", include_str!("../python/controller/gps.py")),
    ("gyro.py", include_str!("../python/controller/gyro.py")),
    (
        "inertial_unit.py",
        include_str!("../python/controller/inertial_unit.py"),
    ),
    (
        "keyboard.py",
        include_str!("../python/controller/keyboard.py"),
    ),
    ("led.py", include_str!("../python/controller/led.py")),
    (
        "light_sensor.py",
        include_str!("../python/controller/light_sensor.py"),
    ),
    ("motor.py", include_str!("../python/controller/motor.py")),
    ("node.py", include_str!("../python/controller/node.py")),
    (
        "position_sensor.py",
        include_str!("../python/controller/position_sensor.py"),
    ),
    (
        "receiver.py",
        include_str!("../python/controller/receiver.py"),
    ),
    ("robot.py", include_str!("../python/controller/robot.py")),
    (
        "supervisor.py",
        include_str!("../python/controller/supervisor.py"),
    ),
    (
        "touch_sensor.py",
        include_str!("../python/controller/touch_sensor.py"),
    ),
];

/// How the library is built.
const FLAGS: [&str; 5] = ["-shared", "-fPIC", "-O2", "-std=gnu11", "-w"];

/// The shared library's file name inside the package.
pub const LIBRARY_FILE: &str = "libregatta_controller.so";

/// How to start a controller process: the program, the arguments before the controller's
/// own (`controllerArgs`), and the environment it adds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Launch {
    pub executable: PathBuf,
    pub args: Vec<String>,
    pub env: Vec<(OsString, OsString)>,
}

/// Writes the package and builds the library once into `cache/python/HASH/`, returning the
/// folder that holds `controller/` (what goes on `PYTHONPATH`), and whether it was built now.
pub fn package(cache: &Path) -> Result<(PathBuf, bool), WebotsError> {
    let sdk = compile::sdk(cache)?;
    let cc = compile::compiler();
    let mut hash = Sha256::new();
    hash.update(cc.as_bytes());
    for flag in FLAGS {
        hash.update(flag.as_bytes());
    }
    hash.update(sdk.as_os_str().as_encoded_bytes());
    for (name, text) in PACKAGE {
        hash.update(name.as_bytes());
        hash.update((text.len() as u64).to_le_bytes());
        hash.update(text.as_bytes());
    }
    let dir = cache.join("python").join(compile::hex(&hash.finalize()));
    if dir.join("controller").join(LIBRARY_FILE).is_file() {
        return Ok((dir, false));
    }
    // Built aside, then renamed into place: runs that start together never see half a package.
    let partial =
        cache
            .join("python")
            .join(format!(".partial.{}.{}", std::process::id(), unique()));
    if let Err(e) = build_package(&sdk, &partial) {
        let _ = std::fs::remove_dir_all(&partial);
        return Err(e);
    }
    if std::fs::rename(&partial, &dir).is_err() {
        // Another run put it there first.
        let _ = std::fs::remove_dir_all(&partial);
        if !dir.join("controller").join(LIBRARY_FILE).is_file() {
            return Err(WebotsError::io(
                &dir,
                std::io::Error::other("cannot move the Python controller package into place"),
            ));
        }
    }
    Ok((dir, true))
}

/// Writes `controller/` with its library, built from the SDK in `sdk` (headers and library
/// sources), into `dir`.
fn build_package(sdk: &Path, dir: &Path) -> Result<(), WebotsError> {
    let cc = compile::compiler();
    let package = dir.join("controller");
    std::fs::create_dir_all(&package).map_err(|source| WebotsError::io(&package, source))?;
    for (name, text) in PACKAGE {
        let path = package.join(name);
        std::fs::write(&path, text).map_err(|source| WebotsError::io(&path, source))?;
    }
    let output = Command::new(&cc)
        .args(FLAGS)
        .arg("-I")
        .arg(sdk.join("include"))
        .arg(sdk.join("regatta_controller.c"))
        .arg("-o")
        .arg(package.join(LIBRARY_FILE))
        .arg("-lm")
        .output()
        .map_err(|source| WebotsError::Compiler {
            compiler: cc.clone(),
            source: std::sync::Arc::new(source),
        })?;
    if !output.status.success() {
        return Err(WebotsError::DoesNotCompile {
            controller: "(regatta's Python controller library)".to_owned(),
            messages: String::from_utf8_lossy(&output.stderr)
                .trim_end()
                .to_owned(),
        });
    }
    Ok(())
}

/// The Python part of `regatta webots-sdk DIR`: `DIR/python/controller/` with its library
/// built (the C SDK must be in `DIR` already), for an `<extern>` Python controller started by
/// hand with `PYTHONPATH=DIR/python`. Returns `DIR/python`.
pub fn write_sdk(dir: &Path) -> Result<PathBuf, WebotsError> {
    let python = dir.join("python");
    build_package(dir, &python)?;
    Ok(python)
}

fn unique() -> u32 {
    static COUNTER: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// What `runtime.ini` of a controller's folder says (Webots' format): environment variables
/// (`[environment variables]`, and `[environment variables with paths]` whose values are
/// lists of paths relative to the folder), and the Python interpreter (`[python] COMMAND`,
/// `OPTIONS`). Sections for other systems and languages are ignored.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RuntimeIni {
    pub env: Vec<(String, String)>,
    pub command: Option<String>,
    pub options: Vec<String>,
}

/// Reads `folder/runtime.ini` (an absent file says nothing).
pub fn runtime_ini(folder: &Path) -> Result<RuntimeIni, WebotsError> {
    let path = folder.join("runtime.ini");
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(RuntimeIni::default()),
        Err(source) => return Err(WebotsError::io(&path, source)),
    };
    Ok(parse_runtime_ini(&text, folder, &|name| {
        std::env::var(name).ok()
    }))
}

/// `runtime.ini`'s text, paths made absolute from `folder`, `$(NAME)` read from `var`.
pub fn parse_runtime_ini(
    text: &str,
    folder: &Path,
    var: &dyn Fn(&str) -> Option<String>,
) -> RuntimeIni {
    #[derive(PartialEq)]
    enum Section {
        Variables,
        Paths,
        Python,
        Other,
    }
    let mut ini = RuntimeIni::default();
    let mut section = Section::Other;
    for line in text.lines() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') || line.starts_with('#') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            let name = name.trim().to_ascii_lowercase();
            section = match name.as_str() {
                "environment variables" | "environment variables for linux" => Section::Variables,
                "environment variables with paths"
                | "environment variables with paths for linux" => Section::Paths,
                "python" => Section::Python,
                _ => Section::Other,
            };
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let (key, value) = (key.trim(), expand(value.trim(), var));
        match section {
            Section::Variables => ini.env.push((key.to_owned(), value)),
            Section::Paths => {
                let paths: Vec<String> = value
                    .split([':', ';'])
                    .filter(|p| !p.is_empty())
                    .map(|p| {
                        let p = Path::new(p);
                        let path = if p.is_absolute() {
                            p.to_path_buf()
                        } else {
                            folder.join(p)
                        };
                        path.to_string_lossy().into_owned()
                    })
                    .collect();
                ini.env.push((key.to_owned(), paths.join(":")));
            }
            Section::Python if key.eq_ignore_ascii_case("COMMAND") && !value.is_empty() => {
                ini.command = Some(value)
            }
            Section::Python if key.eq_ignore_ascii_case("OPTIONS") => {
                ini.options = value.split_whitespace().map(str::to_owned).collect()
            }
            _ => {}
        }
    }
    ini
}

/// `$(NAME)` replaced by the variable's value (empty when unset).
fn expand(value: &str, var: &dyn Fn(&str) -> Option<String>) -> String {
    let mut out = String::new();
    let mut rest = value;
    while let Some(start) = rest.find("$(") {
        let Some(end) = rest[start..].find(')') else {
            break;
        };
        out.push_str(&rest[..start]);
        out.push_str(&var(&rest[start + 2..start + end]).unwrap_or_default());
        rest = &rest[start + end + 1..];
    }
    out.push_str(rest);
    out
}

/// The Python interpreter: `runtime.ini`'s `[python] COMMAND`, else `$REGATTA_PYTHON`, else
/// `python3`; a bare name is looked up on the `PATH`.
pub fn interpreter(ini: &RuntimeIni) -> (String, Option<PathBuf>) {
    let name = ini
        .command
        .clone()
        .or_else(|| {
            std::env::var("REGATTA_PYTHON")
                .ok()
                .filter(|p| !p.trim().is_empty())
        })
        .unwrap_or_else(|| "python3".to_owned());
    let found = if name.contains('/') {
        Some(PathBuf::from(&name)).filter(|p| p.is_file())
    } else {
        std::env::var_os("PATH").and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|dir| dir.join(&name))
                .find(|p| p.is_file())
        })
    };
    (name, found)
}

/// How to run the Python controller `program`: the interpreter, `-u NAME.py`, and
/// `PYTHONPATH` with the package first (then `runtime.ini`'s entries, then the caller's).
pub fn launch(program: &Program, cache: &Path) -> Result<(Launch, bool), WebotsError> {
    let Program::Python { name, folder } = program else {
        return Err(WebotsError::Unsupported {
            controller: program.name().to_owned(),
            language: program.language(),
        });
    };
    let ini = runtime_ini(folder)?;
    let (interpreter, found) = interpreter(&ini);
    let Some(executable) = found else {
        return Err(WebotsError::NoPython {
            controller: name.clone(),
            interpreter,
        });
    };
    let (package, built) = package(cache)?;
    let mut python_path = vec![package.into_os_string()];
    let mut env: Vec<(OsString, OsString)> = Vec::new();
    for (key, value) in &ini.env {
        if key == "PYTHONPATH" {
            python_path.push(value.into());
        } else {
            env.push((key.into(), value.into()));
        }
    }
    if let Some(inherited) = std::env::var_os("PYTHONPATH").filter(|p| !p.is_empty()) {
        python_path.push(inherited);
    }
    let mut joined = OsString::new();
    for (i, part) in python_path.iter().enumerate() {
        if i > 0 {
            joined.push(":");
        }
        joined.push(part);
    }
    env.push(("PYTHONPATH".into(), joined));
    let mut args = vec!["-u".to_owned()];
    args.extend(ini.options.iter().cloned());
    args.push(format!("{name}.py"));
    Ok((
        Launch {
            executable,
            args,
            env,
        },
        built,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runtime_ini_paths_are_the_folders() {
        let ini = parse_runtime_ini(
            "; a comment\n[environment variables with paths]\nPYTHONPATH=../driver/:$(HOME)/lib\n\n[environment variables]\nMODE = fast\n[environment variables for Windows]\nX=1\n[python]\nCOMMAND = python3.11\nOPTIONS = -X dev\n",
            Path::new("/p/controllers/slave"),
            &|name| (name == "HOME").then(|| "/home/u".to_owned()),
        );
        assert_eq!(
            ini.env,
            vec![
                (
                    "PYTHONPATH".to_owned(),
                    "/p/controllers/slave/../driver/:/home/u/lib".to_owned()
                ),
                ("MODE".to_owned(), "fast".to_owned()),
            ]
        );
        assert_eq!(ini.command.as_deref(), Some("python3.11"));
        assert_eq!(ini.options, vec!["-X", "dev"]);
    }

    #[test]
    fn the_package_holds_every_class() {
        let init = PACKAGE.iter().find(|(n, _)| *n == "__init__.py").unwrap().1;
        for class in [
            "Robot",
            "Supervisor",
            "Node",
            "Field",
            "Motor",
            "DistanceSensor",
            "Camera",
            "Receiver",
        ] {
            assert!(init.contains(&format!("'{class}'")), "{class}");
        }
        assert!(PACKAGE.iter().all(|(n, _)| n.ends_with(".py")));
    }
}
