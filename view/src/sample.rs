//! What the viewer shows of one moment of a run: every robot's pose, wheel commands, IR
//! readings and retina, copied out of the simulation so that clients serialise it on their
//! own threads, never on the stepping one.

use std::fmt::Write;

use regatta_runtime::sim::Simulation;

/// One robot at one moment.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotSample {
    pub x: f64,
    pub z: f64,
    pub heading: f64,
    /// Wheel commands (pulses per 10 ms), left and right.
    pub wheels: (i32, i32),
    pub proximity: [u16; 8],
    pub touching: bool,
    /// The retina's rows: the normalised image (photocurrent / mean, halved so that 1 is
    /// twice the mean), then each enabled filter's output over I_bda, 150 values each.
    pub retina: Vec<(String, Vec<f32>)>,
}

/// One moment of the run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    pub t: f64,
    pub steps: u64,
    pub robots: Vec<RobotSample>,
}

/// A buoy visit or a contact that began, for the events list.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    pub t: f64,
    pub robot: usize,
    /// `visit` (with the buoy's index) or `contact`.
    pub kind: &'static str,
    pub buoy: Option<usize>,
}

impl Sample {
    /// Copies what the viewer shows out of a simulation; `retina` says which robots' retinas
    /// to copy (every other robot's is left empty, as a crowd's would be large).
    pub fn capture(simulation: &Simulation, retina: impl Fn(usize) -> bool) -> Sample {
        let robots = simulation
            .robots
            .iter()
            .enumerate()
            .map(|(index, robot)| {
                let mut rows = Vec::new();
                if let Some(panoramic) = robot.panoramic.as_ref().filter(|_| retina(index)) {
                    let output = &panoramic.output;
                    rows.push((
                        "image".to_owned(),
                        output.analog.iter().map(|&v| (v / 2.0) as f32).collect(),
                    ));
                    for (kind, values) in &output.filtered {
                        let i_bda = output
                            .i_bda
                            .iter()
                            .find(|(k, _)| k == kind)
                            .map_or(1.0, |(_, v)| *v)
                            .max(1e-12);
                        rows.push((
                            kind.name().to_owned(),
                            values.iter().map(|&v| (v / i_bda) as f32).collect(),
                        ));
                    }
                }
                RobotSample {
                    x: robot.pose.x,
                    z: robot.pose.z,
                    heading: robot.pose.heading,
                    wheels: robot.command,
                    proximity: robot.proximity,
                    touching: robot.contacts.is_touching(),
                    retina: rows,
                }
            })
            .collect();
        Sample {
            t: simulation.time,
            steps: simulation.steps,
            robots,
        }
    }

    /// The sample as JSON for a client that watches `selected` closely (its retina); the
    /// others' poses, wheels and IR are always sent, being small.
    pub fn write_json(&self, selected: usize, out: &mut String) {
        let _ = write!(
            out,
            "{{\"t\":{},\"steps\":{},\"robots\":[",
            num(self.t),
            self.steps
        );
        for (index, robot) in self.robots.iter().enumerate() {
            if index > 0 {
                out.push(',');
            }
            let _ = write!(
                out,
                "[{},{},{},{},{},{},[",
                num(robot.x),
                num(robot.z),
                num(robot.heading),
                robot.wheels.0,
                robot.wheels.1,
                u8::from(robot.touching)
            );
            for (k, v) in robot.proximity.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                let _ = write!(out, "{v}");
            }
            out.push(']');
            if index == selected && !robot.retina.is_empty() {
                out.push_str(",{");
                for (k, (name, values)) in robot.retina.iter().enumerate() {
                    if k > 0 {
                        out.push(',');
                    }
                    let _ = write!(out, "\"{name}\":[");
                    for (i, v) in values.iter().enumerate() {
                        if i > 0 {
                            out.push(',');
                        }
                        let _ = write!(out, "{}", (f64::from(*v) * 1000.0).round() / 1000.0);
                    }
                    out.push(']');
                }
                out.push('}');
            }
            out.push(']');
        }
        out.push_str("]}");
    }
}

impl Event {
    pub fn write_json(&self, out: &mut String) {
        let _ = write!(
            out,
            "{{\"t\":{},\"robot\":{},\"kind\":\"{}\"",
            num(self.t),
            self.robot,
            self.kind
        );
        if let Some(buoy) = self.buoy {
            let _ = write!(out, ",\"buoy\":{buoy}");
        }
        out.push('}');
    }
}

/// A number for JSON: to a tenth of a millimetre (or microsecond), which is finer than any
/// screen pixel; never NaN or infinite (JSON has neither).
pub fn num(value: f64) -> String {
    if value.is_finite() {
        let rounded = (value * 1e4).round() / 1e4;
        format!("{rounded}")
    } else {
        "0".to_owned()
    }
}
