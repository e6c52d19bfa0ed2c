//! Emitters and receivers: packets in flight between robots, and who hears them.
//!
//! As Webots documents them: a packet sent in a step arrives at the next exchange, at every
//! receiver enabled then whose medium is the emitter's (radio, serial or infra-red), whose
//! channel is the packet's (or either is −1, every channel), and that stands within the
//! emitter's range (−1: unlimited). A receiver disabled when a packet arrives never gets it;
//! an enabled one keeps what arrives until its sampling period hands it to the controller.
//! The signal strength is 1/r², the emitter's direction a unit vector in the receiver's robot
//! frame. Infra-red is not blocked by obstacles here (a documented difference).

use glam::DVec3;

/// A packet on its way.
#[derive(Clone, Debug, PartialEq)]
pub struct Packet {
    /// The step it was sent in.
    pub sent: u64,
    pub medium: u8,
    pub channel: i32,
    /// Range (m; negative: unlimited).
    pub range: f64,
    /// Where the emitter was (world, regatta's axes).
    pub from: DVec3,
    pub data: Vec<u8>,
}

/// A packet a receiver holds for its controller.
#[derive(Clone, Debug, PartialEq)]
pub struct Delivered {
    pub strength: f64,
    pub direction: [f64; 3],
    pub data: Vec<u8>,
}

/// An emitter's or a receiver's state as the controller set it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Radio {
    pub channel: i32,
    pub range: f64,
    /// A receiver's packets not yet handed to its controller.
    pub pending: Vec<Delivered>,
}

/// An enabled receiver where it stands now.
pub struct Listener<'a> {
    pub medium: u8,
    /// Its position (world, regatta's axes).
    pub at: DVec3,
    /// The rotation from world to its robot's frame.
    pub to_robot: glam::DMat3,
    pub radio: &'a mut Radio,
}

/// Hands every packet sent before `step` to the listeners that hear it, then forgets it.
pub fn deliver(packets: &mut Vec<Packet>, step: u64, listeners: &mut [Listener]) {
    for packet in packets.iter().filter(|p| p.sent < step) {
        for listener in listeners.iter_mut() {
            let channel = listener.radio.channel;
            let tuned = channel == packet.channel || channel == -1 || packet.channel == -1;
            if listener.medium != packet.medium || !tuned {
                continue;
            }
            let offset = packet.from - listener.at;
            let distance = offset.length();
            if packet.range >= 0.0 && distance > packet.range {
                continue;
            }
            let direction = if distance > 0.0 {
                (listener.to_robot * (offset / distance)).to_array()
            } else {
                [0.0; 3]
            };
            listener.radio.pending.push(Delivered {
                strength: if distance > 0.0 {
                    1.0 / (distance * distance)
                } else {
                    f64::INFINITY
                },
                direction,
                data: packet.data.clone(),
            });
        }
    }
    packets.retain(|p| p.sent >= step);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packet(sent: u64, medium: u8, channel: i32, range: f64) -> Packet {
        Packet {
            sent,
            medium,
            channel,
            range,
            from: DVec3::ZERO,
            data: b"hi".to_vec(),
        }
    }

    #[test]
    fn packets_reach_the_receivers_tuned_to_them_within_range() {
        let mut radios = [
            Radio {
                channel: 1,
                ..Radio::default()
            },
            Radio {
                channel: 2,
                ..Radio::default()
            },
            Radio {
                channel: -1,
                ..Radio::default()
            },
            Radio {
                channel: 1,
                ..Radio::default()
            },
        ];
        let places = [
            (0, DVec3::new(0.5, 0.0, 0.0)),
            (0, DVec3::new(0.5, 0.0, 0.0)),
            (0, DVec3::new(2.0, 0.0, 0.0)),
            (1, DVec3::new(0.5, 0.0, 0.0)),
        ];
        let mut packets = vec![packet(3, 0, 1, 1.0), packet(4, 0, 1, -1.0)];
        {
            let mut listeners: Vec<Listener> = radios
                .iter_mut()
                .zip(places)
                .map(|(radio, (medium, at))| Listener {
                    medium,
                    at,
                    to_robot: glam::DMat3::IDENTITY,
                    radio,
                })
                .collect();
            deliver(&mut packets, 4, &mut listeners);
        }
        // Channel 1 radio at 0.5 m: yes; channel 2: no; every channel but 2 m away: out of
        // range; serial: another medium.
        assert_eq!(radios[0].pending.len(), 1);
        assert_eq!(radios[0].pending[0].strength, 4.0);
        assert_eq!(radios[0].pending[0].direction, [-1.0, 0.0, 0.0]);
        assert!(radios[1].pending.is_empty());
        assert!(radios[2].pending.is_empty());
        assert!(radios[3].pending.is_empty());
        // The packet sent in this step waits for the next.
        assert_eq!(packets.len(), 1);
    }
}
