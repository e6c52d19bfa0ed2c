//! The Khepera serial protocol's text: requests and replies, encoded and parsed. Both the
//! real-robot client and the simulated robot use this module, so they cannot disagree.
//!
//! A request is one upper-case letter, then `,value` per parameter, ended by LF (or CR). A
//! reply is the letter in lower case, then `,value`s, ended by CR LF. Turret messages are
//! `T,id,…` → `t,id,…`. The K213 is turret 2 (`N`: pixels, `L`: light level), as on the real
//! robot. The Panoramic turret's messages are regatta's own convention (no public source
//! documents them): turret id 3, sub-commands in [`PANORAMIC_COMMANDS`].

use regatta_runtime::khepera::LedAction;
use regatta_runtime::retina::FilterKind;

/// The longest request line the simulated robot accepts (the real robot's shell buffer is of
/// this order); longer lines are discarded whole and answered once with [`NOT_FOUND`].
pub const MAX_LINE: usize = 128;

/// The real robot's shell answer to a line it cannot run.
pub const NOT_FOUND: &str = "Command not found";

/// Turret ids on the extension bus.
pub const K213_ID: i64 = 2;
pub const PANORAMIC_ID: i64 = 3;

/// regatta's Panoramic turret sub-commands (`T,3,<letter>,…`), for documentation and `--help`.
pub const PANORAMIC_COMMANDS: &[(&str, &str, &str)] = &[
    (
        "T,3,E,f",
        "t,3,e",
        "enable filter f (0 raw, 1 lowpass, 2 highpass, 3 bandpass, 4 odd)",
    ),
    ("T,3,D,f", "t,3,d", "disable filter f"),
    (
        "T,3,R,f",
        "t,3,r,v…",
        "read filter f over the region of interest",
    ),
    ("T,3,L,x", "t,3,l", "set λ to x/1000 pixels"),
    ("T,3,M", "t,3,m,x", "read λ, in thousandths of a pixel"),
    ("T,3,B,b", "t,3,b", "set the converter's bits (1…16)"),
    ("T,3,C", "t,3,c,b", "read the converter's bits"),
    (
        "T,3,I,first,last",
        "t,3,i",
        "set the region of interest (0…149)",
    ),
    ("T,3,J", "t,3,j,first,last", "read the region of interest"),
];

/// A request the simulated robot understands.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    /// `A,Kp,Ki,Kd`: speed PID (the simulated motors follow their commands exactly).
    SpeedPid([i64; 3]),
    /// `B`: BIOS and protocol versions.
    Version,
    /// `D,l,r`: wheel speeds, pulses per 10 ms.
    SetSpeed(i32, i32),
    /// `E`: read wheel speeds.
    ReadSpeed,
    /// `F,Kp,Ki,Kd`: position PID (accepted; no effect in simulation).
    PositionPid([i64; 3]),
    /// `G,l,r`: set the position counters.
    SetPosition(i32, i32),
    /// `H`: read the position counters.
    ReadPosition,
    /// `J,vl,al,vr,ar`: speed profile (accepted; no effect in simulation).
    SpeedProfile([i64; 4]),
    /// `K`: motion status.
    MotionStatus,
    /// `L,n,a`: LED n off, on or toggled.
    Led(u8, LedAction),
    /// `N`: the eight proximity sensors.
    Proximity,
    /// `O`: the eight ambient light sensors.
    Ambient,
    /// `T,2,N`: the K213's 64 pixels.
    K213Pixels,
    /// `T,2,L`: the K213's light level.
    K213Light,
    /// `T,3,…`: the Panoramic turret.
    Panoramic(PanoramicRequest),
}

/// regatta's Panoramic turret messages.
#[derive(Clone, Debug, PartialEq)]
pub enum PanoramicRequest {
    Enable(FilterKind),
    Disable(FilterKind),
    Read(FilterKind),
    /// λ in thousandths of a pixel.
    SetLambda(i64),
    Lambda,
    SetBits(u32),
    Bits,
    SetRegion(usize, usize),
    Region,
}

/// Why a line is not a request.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Malformed {
    #[error("the line is empty")]
    Empty,
    #[error("the line is longer than {MAX_LINE} bytes")]
    TooLong,
    #[error("the line holds a byte that is not printable ASCII")]
    NotAscii,
    #[error("unknown command {0:?}")]
    UnknownCommand(String),
    #[error("{command} takes {wanted} parameter(s), found {found}")]
    Arity {
        command: String,
        wanted: usize,
        found: usize,
    },
    #[error("{0:?} is not a parameter of the right kind")]
    BadParameter(String),
}

fn filter_code(kind: FilterKind) -> i64 {
    FilterKind::ALL.iter().position(|&k| k == kind).unwrap_or(0) as i64
}

fn filter_of(code: i64) -> Option<FilterKind> {
    usize::try_from(code)
        .ok()
        .and_then(|i| FilterKind::ALL.get(i).copied())
}

impl Request {
    /// The request line, without its terminator.
    pub fn encode(&self) -> String {
        let join = |letter: &str, values: &[i64]| {
            let mut out = letter.to_owned();
            for v in values {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out
        };
        match self {
            Request::SpeedPid(p) => join("A", p),
            Request::Version => "B".into(),
            Request::SetSpeed(l, r) => join("D", &[*l as i64, *r as i64]),
            Request::ReadSpeed => "E".into(),
            Request::PositionPid(p) => join("F", p),
            Request::SetPosition(l, r) => join("G", &[*l as i64, *r as i64]),
            Request::ReadPosition => "H".into(),
            Request::SpeedProfile(p) => join("J", p),
            Request::MotionStatus => "K".into(),
            Request::Led(n, action) => {
                let a = match action {
                    LedAction::Off => 0,
                    LedAction::On => 1,
                    LedAction::Toggle => 2,
                };
                join("L", &[*n as i64, a])
            }
            Request::Proximity => "N".into(),
            Request::Ambient => "O".into(),
            Request::K213Pixels => format!("T,{K213_ID},N"),
            Request::K213Light => format!("T,{K213_ID},L"),
            Request::Panoramic(p) => {
                let head = format!("T,{PANORAMIC_ID},");
                match p {
                    PanoramicRequest::Enable(f) => join(&(head + "E"), &[filter_code(*f)]),
                    PanoramicRequest::Disable(f) => join(&(head + "D"), &[filter_code(*f)]),
                    PanoramicRequest::Read(f) => join(&(head + "R"), &[filter_code(*f)]),
                    PanoramicRequest::SetLambda(x) => join(&(head + "L"), &[*x]),
                    PanoramicRequest::Lambda => head + "M",
                    PanoramicRequest::SetBits(b) => join(&(head + "B"), &[*b as i64]),
                    PanoramicRequest::Bits => head + "C",
                    PanoramicRequest::SetRegion(a, b) => {
                        join(&(head + "I"), &[*a as i64, *b as i64])
                    }
                    PanoramicRequest::Region => head + "J",
                }
            }
        }
    }

    /// What a correct reply starts with: the command letter in lower case, and for turret
    /// messages the turret id and the sub-command letter in lower case.
    pub fn reply_prefix(&self) -> String {
        let line = self.encode();
        let mut fields: Vec<String> = line.split(',').map(str::to_owned).collect();
        fields[0] = fields[0].to_ascii_lowercase();
        if fields[0] == "t" {
            fields[2] = fields[2].to_ascii_lowercase();
            fields.truncate(3);
        } else {
            fields.truncate(1);
        }
        fields.join(",")
    }

    /// Parses a request line (terminator already removed).
    pub fn parse(line: &[u8]) -> Result<Request, Malformed> {
        if line.len() > MAX_LINE {
            return Err(Malformed::TooLong);
        }
        if line.iter().any(|&b| !(0x20..0x7f).contains(&b)) {
            return Err(Malformed::NotAscii);
        }
        let text = std::str::from_utf8(line).map_err(|_| Malformed::NotAscii)?;
        let text = text.trim();
        if text.is_empty() {
            return Err(Malformed::Empty);
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        let command = fields[0];
        let numbers = |from: usize, wanted: usize| -> Result<Vec<i64>, Malformed> {
            let found = fields.len() - from;
            if found != wanted {
                return Err(Malformed::Arity {
                    command: fields[..from].join(","),
                    wanted,
                    found,
                });
            }
            fields[from..]
                .iter()
                .map(|f| parse_int(f).ok_or_else(|| Malformed::BadParameter((*f).to_owned())))
                .collect()
        };
        let speed = |v: i64| i32::try_from(v).map_err(|_| Malformed::BadParameter(v.to_string()));
        Ok(match command {
            "A" => {
                let p = numbers(1, 3)?;
                Request::SpeedPid([p[0], p[1], p[2]])
            }
            "B" => {
                numbers(1, 0)?;
                Request::Version
            }
            "D" => {
                let p = numbers(1, 2)?;
                Request::SetSpeed(speed(p[0])?, speed(p[1])?)
            }
            "E" => {
                numbers(1, 0)?;
                Request::ReadSpeed
            }
            "F" => {
                let p = numbers(1, 3)?;
                Request::PositionPid([p[0], p[1], p[2]])
            }
            "G" => {
                let p = numbers(1, 2)?;
                Request::SetPosition(speed(p[0])?, speed(p[1])?)
            }
            "H" => {
                numbers(1, 0)?;
                Request::ReadPosition
            }
            "J" => {
                let p = numbers(1, 4)?;
                Request::SpeedProfile([p[0], p[1], p[2], p[3]])
            }
            "K" => {
                numbers(1, 0)?;
                Request::MotionStatus
            }
            "L" => {
                let p = numbers(1, 2)?;
                let led = u8::try_from(p[0])
                    .ok()
                    .filter(|&n| n <= 1)
                    .ok_or_else(|| Malformed::BadParameter(p[0].to_string()))?;
                let action = match p[1] {
                    0 => LedAction::Off,
                    1 => LedAction::On,
                    2 => LedAction::Toggle,
                    other => return Err(Malformed::BadParameter(other.to_string())),
                };
                Request::Led(led, action)
            }
            "N" => {
                numbers(1, 0)?;
                Request::Proximity
            }
            "O" => {
                numbers(1, 0)?;
                Request::Ambient
            }
            "T" => return parse_turret(&fields),
            other => return Err(Malformed::UnknownCommand(other.to_owned())),
        })
    }
}

fn parse_int(field: &str) -> Option<i64> {
    let digits = field.strip_prefix(['-', '+']).unwrap_or(field);
    if digits.is_empty() || digits.len() > 12 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    field.parse().ok()
}

fn parse_turret(fields: &[&str]) -> Result<Request, Malformed> {
    let unknown = || Malformed::UnknownCommand(fields[..fields.len().min(3)].join(","));
    if fields.len() < 3 {
        return Err(unknown());
    }
    let id = parse_int(fields[1]).ok_or_else(unknown)?;
    let sub = fields[2];
    let params: Vec<i64> = fields[3..]
        .iter()
        .map(|f| parse_int(f).ok_or_else(|| Malformed::BadParameter((*f).to_owned())))
        .collect::<Result<_, _>>()?;
    let arity = |wanted: usize| {
        if params.len() == wanted {
            Ok(())
        } else {
            Err(Malformed::Arity {
                command: fields[..3].join(","),
                wanted,
                found: params.len(),
            })
        }
    };
    let filter =
        |code: i64| filter_of(code).ok_or_else(|| Malformed::BadParameter(code.to_string()));
    let pixel = |v: i64| {
        usize::try_from(v)
            .ok()
            .filter(|&p| p < regatta_runtime::retina::PIXELS)
            .ok_or_else(|| Malformed::BadParameter(v.to_string()))
    };
    match (id, sub) {
        (K213_ID, "N") => arity(0).map(|_| Request::K213Pixels),
        (K213_ID, "L") => arity(0).map(|_| Request::K213Light),
        (PANORAMIC_ID, _) => {
            let request = match sub {
                "E" => {
                    arity(1)?;
                    PanoramicRequest::Enable(filter(params[0])?)
                }
                "D" => {
                    arity(1)?;
                    PanoramicRequest::Disable(filter(params[0])?)
                }
                "R" => {
                    arity(1)?;
                    PanoramicRequest::Read(filter(params[0])?)
                }
                "L" => {
                    arity(1)?;
                    PanoramicRequest::SetLambda(params[0])
                }
                "M" => {
                    arity(0)?;
                    PanoramicRequest::Lambda
                }
                "B" => {
                    arity(1)?;
                    let bits = u32::try_from(params[0])
                        .map_err(|_| Malformed::BadParameter(params[0].to_string()))?;
                    PanoramicRequest::SetBits(bits)
                }
                "C" => {
                    arity(0)?;
                    PanoramicRequest::Bits
                }
                "I" => {
                    arity(2)?;
                    PanoramicRequest::SetRegion(pixel(params[0])?, pixel(params[1])?)
                }
                "J" => {
                    arity(0)?;
                    PanoramicRequest::Region
                }
                _ => return Err(unknown()),
            };
            Ok(Request::Panoramic(request))
        }
        _ => Err(unknown()),
    }
}

/// The integer values of a reply after its expected prefix (`d` → [], `n,1,2` → [1, 2]).
/// `None` if the reply does not start with the prefix or holds something else than integers.
pub fn reply_values(reply: &str, prefix: &str) -> Option<Vec<i64>> {
    let rest = reply.trim_end_matches(['\r', '\n']).strip_prefix(prefix)?;
    if rest.is_empty() {
        return Some(Vec::new());
    }
    rest.strip_prefix(',')?
        .split(',')
        .map(|f| parse_int(f.trim()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_request_survives_encode_and_parse() {
        let requests = [
            Request::SpeedPid([3, 800, 100]),
            Request::Version,
            Request::SetSpeed(-20, 127),
            Request::ReadSpeed,
            Request::PositionPid([1, 2, 3]),
            Request::SetPosition(0, -5),
            Request::ReadPosition,
            Request::SpeedProfile([1, 2, 3, 4]),
            Request::MotionStatus,
            Request::Led(1, LedAction::Toggle),
            Request::Proximity,
            Request::Ambient,
            Request::K213Pixels,
            Request::K213Light,
            Request::Panoramic(PanoramicRequest::Enable(FilterKind::Odd)),
            Request::Panoramic(PanoramicRequest::Disable(FilterKind::Raw)),
            Request::Panoramic(PanoramicRequest::Read(FilterKind::Bandpass)),
            Request::Panoramic(PanoramicRequest::SetLambda(5000)),
            Request::Panoramic(PanoramicRequest::Lambda),
            Request::Panoramic(PanoramicRequest::SetBits(6)),
            Request::Panoramic(PanoramicRequest::Bits),
            Request::Panoramic(PanoramicRequest::SetRegion(10, 140)),
            Request::Panoramic(PanoramicRequest::Region),
        ];
        for request in requests {
            let line = request.encode();
            assert_eq!(
                Request::parse(line.as_bytes()),
                Ok(request.clone()),
                "{line}"
            );
        }
        assert_eq!(Request::SetSpeed(1, 2).reply_prefix(), "d");
        assert_eq!(Request::K213Pixels.reply_prefix(), "t,2,n");
    }

    #[test]
    fn malformed_lines_are_named() {
        assert_eq!(Request::parse(b""), Err(Malformed::Empty));
        assert_eq!(
            Request::parse(b"Q"),
            Err(Malformed::UnknownCommand("Q".into()))
        );
        assert!(matches!(
            Request::parse(b"D,1"),
            Err(Malformed::Arity { .. })
        ));
        assert!(matches!(
            Request::parse(b"D,1,x"),
            Err(Malformed::BadParameter(_))
        ));
        assert!(matches!(
            Request::parse(b"D,99999999999,0"),
            Err(Malformed::BadParameter(_))
        ));
        assert_eq!(
            Request::parse("D,1,\u{e9}".as_bytes()),
            Err(Malformed::NotAscii)
        );
        assert_eq!(Request::parse(&[b'N'; 200]), Err(Malformed::TooLong));
        assert!(matches!(
            Request::parse(b"T,3,R,9"),
            Err(Malformed::BadParameter(_))
        ));
        assert!(matches!(
            Request::parse(b"T,7,N"),
            Err(Malformed::UnknownCommand(_))
        ));
        assert_eq!(reply_values("n,1,2,3\r\n", "n"), Some(vec![1, 2, 3]));
        assert_eq!(reply_values("d\r\n", "d"), Some(vec![]));
        assert_eq!(reply_values("dx\r\n", "d"), None);
        assert_eq!(reply_values("Command not found\r\n", "n"), None);
    }
}
