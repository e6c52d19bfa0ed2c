//! What varies and how: `NODE.FIELD=SPEC` read from a `--vary` flag or from a variations
//! file, with where it was written so that every refusal can name it.

use std::fmt;

/// How one field varies from trial to trial.
#[derive(Clone, Debug, PartialEq)]
pub enum How {
    /// A number drawn uniformly in `[lo, hi]` (`LO..HI`).
    Range(f64, f64),
    /// The world's value moved by a uniform draw in `[-d, d]` (`±D` or `+-D`): every
    /// number of a scalar, the horizontal components of a position, the angle of a rotation.
    Jitter(f64),
    /// A position drawn uniformly over the arena's floor (`arena`).
    Arena,
    /// A heading drawn uniformly about the world's up axis (`any`).
    AnyHeading,
    /// One of these values (world-language text), each as likely (`A|B|…`): a film or none
    /// (`0.5|1`), a lamp lit or not (`TRUE|FALSE`).
    Choice(Vec<String>),
    /// How many of the nodes stay, each count as likely (`NODE.count=LO..HI` or `A|B|…`,
    /// whole numbers): the ones kept are drawn too, the others are taken out of the world.
    Count(Vec<usize>),
}

/// The pseudo-field that varies how many nodes of a type a world holds.
pub const COUNT: &str = "count";

/// The most counts a `count` variation may list.
const MAX_COUNTS: usize = 10_000;

/// Where a variation was written: the flag's text, or a file's line and column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    Flag(String),
    File {
        path: String,
        line: usize,
        column: usize,
    },
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Flag(text) => write!(f, "--vary '{text}'"),
            Origin::File { path, line, column } => write!(f, "{path}:{line}:{column}"),
        }
    }
}

/// One declared variation: every node of type (or DEF name) `node` has `field` drawn anew
/// for each trial, each node its own draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Variation {
    pub node: String,
    pub field: String,
    pub how: How,
    pub origin: Origin,
}

/// Why variations cannot be read or applied. Each names where the variation was written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VaryError {
    #[error("{origin}: {reason}")]
    Malformed { origin: Origin, reason: String },
    #[error("{origin}: the world has no node of type or DEF name '{node}'")]
    NoSuchNode { origin: Origin, node: String },
    #[error("{origin}: {node} at line {line} does not write '{field}', so there is no value to move; write it in the world or give a range LO..HI")]
    Unwritten {
        origin: Origin,
        node: String,
        line: usize,
        field: String,
    },
    #[error("{origin}: {reason}")]
    Unfit { origin: Origin, reason: String },
    /// `origins`: where the variations that were drawn were written.
    #[error("{origins}: the varied world does not check: {rendered}")]
    Check { origins: String, rendered: String },
    #[error("{origins}: {tries} draws for seed {seed} all broke the world (the last: {reason})")]
    Broken {
        origins: String,
        tries: usize,
        seed: u64,
        reason: String,
    },
    /// A file that is not a variations file; `message` starts with its line and column when
    /// known (`3:7: …`).
    #[error("{path}:{message}")]
    File { path: String, message: String },
}

/// The grammar of a SPEC, for messages.
const SPECS: &str =
    "a range LO..HI, a jitter ±D (or +-D), a choice A|B|…, arena (positions) or any (rotations); NODE.count=LO..HI keeps that many of the nodes";

impl Variation {
    /// Reads a `--vary` flag: `NODE.FIELD=SPEC`.
    pub fn parse_flag(text: &str) -> Result<Variation, VaryError> {
        let origin = Origin::Flag(text.to_owned());
        let malformed = |reason: String| VaryError::Malformed {
            origin: origin.clone(),
            reason,
        };
        let Some((target, spec)) = text.split_once('=') else {
            return Err(malformed(format!(
                "expected NODE.FIELD=SPEC, where SPEC is {SPECS}"
            )));
        };
        let Some((node, field)) = target.trim().split_once('.') else {
            return Err(malformed(format!(
                "expected NODE.FIELD before '=', found '{}'",
                target.trim()
            )));
        };
        Variation::new(node, field, spec, origin)
    }

    /// A variation from its parts; `origin` is where they were written.
    pub fn new(
        node: &str,
        field: &str,
        spec: &str,
        origin: Origin,
    ) -> Result<Variation, VaryError> {
        let malformed = |reason: String| VaryError::Malformed {
            origin: origin.clone(),
            reason,
        };
        let name = |s: &str| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        };
        if !name(node) || !name(field) {
            return Err(malformed(format!(
                "'{node}.{field}' is not NODE.FIELD (a node type or DEF name, a field name)"
            )));
        }
        let how = if field == COUNT {
            let spec = spec.trim();
            // A count may also be one number: the nodes kept vary, not how many.
            let how = match spec.parse::<f64>() {
                Ok(n) => Ok(How::Range(n, n)),
                Err(_) => parse_how(spec),
            };
            how.and_then(|how| counts(&how, spec)).map_err(malformed)?
        } else {
            parse_how(spec.trim()).map_err(malformed)?
        };
        Ok(Variation {
            node: node.to_owned(),
            field: field.to_owned(),
            how,
            origin,
        })
    }
}

/// A `count` variation's spec as the counts it may draw.
fn counts(how: &How, spec: &str) -> Result<How, String> {
    let whole = |v: f64| -> Result<usize, String> {
        if v >= 0.0 && v.fract() == 0.0 && v <= MAX_COUNTS as f64 {
            Ok(v as usize)
        } else {
            Err(format!(
                "'{v}' is not a count of nodes (a whole number from 0 to {MAX_COUNTS})"
            ))
        }
    };
    let values = match how {
        How::Range(lo, hi) => (whole(*lo)?..=whole(*hi)?).collect(),
        How::Choice(values) => values
            .iter()
            .map(|v| number(v).and_then(whole))
            .collect::<Result<Vec<usize>, String>>()?,
        _ => {
            return Err(format!(
                "a count is a range of whole numbers LO..HI or a choice A|B|…, not '{spec}'"
            ))
        }
    };
    Ok(How::Count(values))
}

fn number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{}' is not a finite number", text.trim())),
    }
}

fn parse_how(spec: &str) -> Result<How, String> {
    match spec {
        "arena" => return Ok(How::Arena),
        "any" => return Ok(How::AnyHeading),
        "" => return Err(format!("nothing after '=': expected {SPECS}")),
        _ => {}
    }
    if spec.contains('|') {
        let values: Vec<String> = spec.split('|').map(|v| v.trim().to_owned()).collect();
        if values.iter().any(String::is_empty) {
            return Err(format!("the choice {spec} has an empty value"));
        }
        return Ok(How::Choice(values));
    }
    if let Some(rest) = spec.strip_prefix('±').or_else(|| spec.strip_prefix("+-")) {
        let d = number(rest)?;
        if d < 0.0 {
            return Err(format!("the jitter {spec} is negative"));
        }
        return Ok(How::Jitter(d));
    }
    if let Some((lo, hi)) = spec.split_once("..") {
        let (lo, hi) = (number(lo)?, number(hi)?);
        if hi < lo {
            return Err(format!(
                "the range {spec} is empty (its end is below its start)"
            ));
        }
        return Ok(How::Range(lo, hi));
    }
    Err(format!("'{spec}' is not {SPECS}"))
}

/// Reads a variations file (TOML): one table per node type or DEF name, one key per field,
/// each value a SPEC string, in the order written:
///
/// ```toml
/// [DirectionalLight]
/// intensity = "0.02..0.8"
/// [Buoy]
/// translation = "±0.1"
/// ```
pub fn parse_file(path: &str, text: &str) -> Result<Vec<Variation>, VaryError> {
    let file_error = |message: String| VaryError::File {
        path: path.to_owned(),
        message,
    };
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        let at = e
            .span()
            .map(|s| {
                let (line, column) = line_col(text, s.start);
                format!("{line}:{column}: ")
            })
            .unwrap_or_else(|| " ".to_owned());
        file_error(format!("{at}{}", e.message()))
    })?;
    let mut variations = Vec::new();
    // toml's table is sorted by key; the file's order is found by position so that draws
    // follow the order the user wrote (and a file's reordering is the only thing that moves
    // them).
    let mut entries = Vec::new();
    for (node, fields) in &table {
        let Some(fields) = fields.as_table() else {
            let at = locate_key(text, None, node);
            return Err(file_error(format!(
                "{}:{}: '{node}' must be a table [{node}] of FIELD = \"SPEC\"",
                at.0, at.1
            )));
        };
        for (field, spec) in fields {
            let at = locate_key(text, Some(node), field);
            entries.push((at, node.clone(), field.clone(), spec.clone()));
        }
    }
    entries.sort_by_key(|e| e.0);
    for ((line, column), node, field, spec) in entries {
        let origin = Origin::File {
            path: path.to_owned(),
            line,
            column,
        };
        let Some(spec) = spec.as_str() else {
            return Err(VaryError::Malformed {
                origin,
                reason: format!("the value of {node}.{field} must be a string: {SPECS}"),
            });
        };
        variations.push(Variation::new(&node, &field, spec, origin)?);
    }
    Ok(variations)
}

/// Line and column (from 1, the column in characters) of byte `offset`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    // An offset inside a character (never expected from the TOML reader) counts as its start.
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Where `key` is written in `text`: under the header `[table]` when one is given (or as
/// `table.key`), else at the top. Only the files `parse_file` accepted are searched, whose
/// keys are bare words, so a line-wise search finds them.
fn locate_key(text: &str, table: Option<&str>, key: &str) -> (usize, usize) {
    let mut current: Option<String> = None;
    let mut offset = 0;
    for raw in text.split_inclusive('\n') {
        let line = raw.trim_start();
        let indent = raw.len() - line.len();
        if let Some(header) = line.strip_prefix('[') {
            let name = header
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
                .trim_matches('"');
            current = Some(name.to_owned());
            if table.is_none() && name == key {
                return line_col(text, offset + indent + 1);
            }
        } else if let Some((left, _)) = line.split_once('=') {
            let left = left.trim().trim_matches('"');
            let here = match (table, current.as_deref()) {
                (Some(t), Some(c)) => c == t && left == key,
                (Some(t), None) => left == format!("{t}.{key}"),
                (None, None) => left == key || left.starts_with(&format!("{key}.")),
                (None, Some(_)) => false,
            };
            if here {
                return line_col(text, offset + indent);
            }
        }
        offset += raw.len();
    }
    (1, 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_read_every_spec() {
        let v = Variation::parse_flag("DirectionalLight.intensity=0.02..0.8").unwrap();
        assert_eq!(v.how, How::Range(0.02, 0.8));
        assert_eq!(
            Variation::parse_flag("Buoy.translation=±0.1").unwrap().how,
            How::Jitter(0.1)
        );
        assert_eq!(
            Variation::parse_flag("Buoy.translation=+-0.1").unwrap().how,
            How::Jitter(0.1)
        );
        assert_eq!(
            Variation::parse_flag("Khepera.translation=arena")
                .unwrap()
                .how,
            How::Arena
        );
        assert_eq!(
            Variation::parse_flag("Khepera.rotation=any").unwrap().how,
            How::AnyHeading
        );
        assert_eq!(
            Variation::parse_flag("Buoy.irReflectance=0.5 | 1")
                .unwrap()
                .how,
            How::Choice(vec!["0.5".into(), "1".into()])
        );
        for bad in [
            "Buoy",
            "Buoy.x",
            "Buoy.x=1..0",
            "Buoy.x=nan..1",
            "Buoy.x=±-1",
            "Buoy.x=wide",
            "Buoy.x=1||2",
            ".x=1..2",
        ] {
            let error = Variation::parse_flag(bad).unwrap_err().to_string();
            assert!(error.starts_with(&format!("--vary '{bad}'")), "{error}");
        }
    }

    #[test]
    fn files_keep_their_order_and_locate_mistakes() {
        let text = "# lighting\n[DirectionalLight]\nintensity = \"0.02..0.8\"\n\n[Buoy]\ntranslation = \"±0.1\"\nirReflectance = \"0.5..1\"\n";
        let v = parse_file("v.toml", text).unwrap();
        let names: Vec<_> = v
            .iter()
            .map(|v| format!("{}.{}", v.node, v.field))
            .collect();
        assert_eq!(
            names,
            [
                "DirectionalLight.intensity",
                "Buoy.translation",
                "Buoy.irReflectance"
            ]
        );
        assert_eq!(v[1].origin.to_string(), "v.toml:6:1");
        let bad = "[Buoy]\ntranslation = \"±0.1\"\nradius = \"3..1\"\n";
        let error = parse_file("v.toml", bad).unwrap_err().to_string();
        assert!(
            error.starts_with("v.toml:3:1: the range 3..1 is empty"),
            "{error}"
        );
        let error = parse_file("v.toml", "[Buoy\n").unwrap_err().to_string();
        assert!(error.starts_with("v.toml:1:"), "{error}");
    }
}
