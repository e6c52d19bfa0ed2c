//! Which channels a log holds (`--channels`), and the topic names they get.
//!
//! Topic names follow the ROS 2 rules (tokens of letters, digits and single underscores, not
//! starting with a digit), so robot names are sanitised: every run of characters other than
//! ASCII letters and digits becomes one `_`, leading and trailing `_` go, an empty name becomes
//! `robot`, and a name starting with a digit gets `robot_` in front. A sanitised name already
//! taken by an earlier robot (in file order) gets `_2`, `_3`, … (the first free one), so no two
//! robots share a topic. Each channel's metadata keeps the robot's own name (`robot`).

use std::fmt;
use std::str::FromStr;

/// One kind of channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Channel {
    // regatta's own record (custom `regatta/msg/*` schemas).
    Pose,
    Wheels,
    Proximity,
    Ambient,
    Retina,
    K213,
    Contacts,
    Visits,
    Controller,
    // Foxglove's well-known schemas.
    Scene,
    Transforms,
    WorldPose,
    Images,
    Events,
}

impl Channel {
    pub const ALL: [Channel; 14] = [
        Channel::Pose,
        Channel::Wheels,
        Channel::Proximity,
        Channel::Ambient,
        Channel::Retina,
        Channel::K213,
        Channel::Contacts,
        Channel::Visits,
        Channel::Controller,
        Channel::Scene,
        Channel::Transforms,
        Channel::WorldPose,
        Channel::Images,
        Channel::Events,
    ];

    /// Its name in `--channels` and in the log's metadata.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Pose => "pose",
            Channel::Wheels => "wheels",
            Channel::Proximity => "proximity",
            Channel::Ambient => "ambient",
            Channel::Retina => "retina",
            Channel::K213 => "k213",
            Channel::Contacts => "contacts",
            Channel::Visits => "visits",
            Channel::Controller => "controller",
            Channel::Scene => "scene",
            Channel::Transforms => "tf",
            Channel::WorldPose => "world_pose",
            Channel::Images => "images",
            Channel::Events => "events",
        }
    }

    fn bit(self) -> u16 {
        1 << self as u16
    }

    /// Whether it uses Foxglove's schemas.
    pub fn is_foxglove(self) -> bool {
        self >= Channel::Scene
    }
}

/// A set of channels.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Channels(u16);

impl Channels {
    /// regatta's own channels: what logs held before the Foxglove ones existed, and what a
    /// log without a `channels` entry holds.
    pub const REGATTA: Channels = Channels(0x1ff);
    pub const FOXGLOVE: Channels = Channels(0x3e00);
    pub const ALL: Channels = Channels(0x3fff);
    pub const NONE: Channels = Channels(0);

    pub fn contains(self, channel: Channel) -> bool {
        self.0 & channel.bit() != 0
    }

    pub fn with(self, channel: Channel) -> Channels {
        Channels(self.0 | channel.bit())
    }

    /// Whether any Foxglove channel is in the set.
    pub fn any_foxglove(self) -> bool {
        self.0 & Channels::FOXGLOVE.0 != 0
    }

    pub fn iter(self) -> impl Iterator<Item = Channel> {
        Channel::ALL.into_iter().filter(move |c| self.contains(*c))
    }
}

impl Default for Channels {
    fn default() -> Channels {
        Channels::ALL
    }
}

impl fmt::Debug for Channels {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Channels({self})")
    }
}

impl fmt::Display for Channels {
    /// The channel names, comma-separated, in a fixed order (as stored in a log).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(Channel::name).collect();
        f.write_str(&names.join(","))
    }
}

/// A `--channels` value that names no channel.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown channel '{0}': expected all, regatta, foxglove, or any of pose, wheels, proximity, ambient, retina, k213, contacts, visits, controller, scene, tf, world_pose, images, events (comma-separated)")]
pub struct UnknownChannel(pub String);

impl FromStr for Channels {
    type Err = UnknownChannel;

    /// Names and groups (`all`, `regatta`, `foxglove`), comma-separated; an empty string is
    /// no channel at all.
    fn from_str(text: &str) -> Result<Channels, UnknownChannel> {
        let mut set = Channels::NONE;
        for word in text.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            set = Channels(
                set.0
                    | match word {
                        "all" => Channels::ALL.0,
                        "regatta" => Channels::REGATTA.0,
                        "foxglove" => Channels::FOXGLOVE.0,
                        _ => Channel::ALL
                            .iter()
                            .find(|c| c.name() == word)
                            .ok_or_else(|| UnknownChannel(word.to_owned()))?
                            .bit(),
                    },
            );
        }
        Ok(set)
    }
}

/// A robot name made into a valid ROS 2 topic token (see the module's documentation).
pub fn sanitize(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    while out.ends_with('_') {
        out.pop();
    }
    if out.is_empty() {
        return "robot".to_owned();
    }
    if out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert_str(0, "robot_");
    }
    out
}

/// Topic tokens for robots named `names`, in order: sanitised, and made distinct.
pub fn robot_tokens<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut tokens: Vec<String> = Vec::new();
    for name in names {
        let base = sanitize(name);
        let mut token = base.clone();
        let mut n = 2;
        while tokens.contains(&token) {
            token = format!("{base}_{n}");
            n += 1;
        }
        tokens.push(token);
    }
    tokens
}

/// Whether `topic` is a valid ROS 2 topic name (absolute form).
pub fn is_ros2_topic(topic: &str) -> bool {
    let Some(rest) = topic.strip_prefix('/') else {
        return false;
    };
    !rest.is_empty()
        && rest.split('/').all(|token| {
            !token.is_empty()
                && !token.starts_with(|c: char| c.is_ascii_digit())
                && !token.contains("__")
                && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_valid_distinct_tokens() {
        let tokens = robot_tokens([
            "khepera",
            "Khepera II",
            "Khepera_II",
            "2nd robot",
            "",
            "--",
            "é/puck",
            "khepera",
        ]);
        assert_eq!(
            tokens,
            [
                "khepera",
                "Khepera_II",
                "Khepera_II_2",
                "robot_2nd_robot",
                "robot",
                "robot_2",
                "puck",
                "khepera_2"
            ]
        );
        for token in &tokens {
            assert!(is_ros2_topic(&format!("/{token}/pose")), "{token}");
        }
        assert!(!is_ros2_topic("/a__b"));
        assert!(!is_ros2_topic("/1a"));
        assert!(!is_ros2_topic("/a b"));
    }

    #[test]
    fn channel_sets_parse_and_print() {
        assert_eq!("all".parse::<Channels>().unwrap(), Channels::ALL);
        assert_eq!(
            "regatta,foxglove".parse::<Channels>().unwrap(),
            Channels::ALL
        );
        let some: Channels = "pose, tf,scene".parse().unwrap();
        assert_eq!(some.to_string(), "pose,scene,tf");
        assert_eq!(some.to_string().parse::<Channels>().unwrap(), some);
        assert_eq!(
            Channels::ALL.to_string().parse::<Channels>().unwrap(),
            Channels::ALL
        );
        assert!("pose,bogus".parse::<Channels>().is_err());
        assert_eq!("".parse::<Channels>().unwrap(), Channels::NONE);
    }
}
