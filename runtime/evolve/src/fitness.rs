//! Named fitness functions over [`StepRecord`]s, so that a live run and its log give the same
//! value bit for bit (the same records, in the same order, through the same arithmetic).
//!
//! - `avoidance` (Floreano and Mondada 1994): Φ = V · (1 − √Δv) · (1 − i), averaged over the
//!   steps, where V is the mean absolute speed of the two wheels, Δv the absolute difference
//!   of their signed speeds (both normalised to 0 … 1 by `vmax`), and i the normalised
//!   reading (0 … 1) of the IR sensor with the highest activity.
//! - `regatta`: buoy visits that continue a cyclic order around the buoys, minus `penalty`
//!   (0.5) per second spent in contact. `other` (0 by default: the strict measure,
//!   so that the value reads as visits) adds a shaping reward per visit to another buoy out
//!   of that order, for an evolution that finds no cyclic visit to start from.
//! - `phototaxis`: the time-weighted closeness to the brightest buoy, `max(0, 1 − d/range)`
//!   averaged over the steps.
//!
//! A fitness is named, with optional parameters: `avoidance`, `avoidance:vmax=15`,
//! `regatta:penalty=1,other=0.25`, `phototaxis:range=0.3`.

use glam::DVec2;
use regatta_runtime::compile::Landmark;
use serde::Serialize;

use crate::record::StepRecord;

/// Why a fitness name does not parse.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitnessError {
    #[error("unknown fitness \"{0}\"; known: avoidance, regatta, phototaxis")]
    Unknown(String),
    #[error("fitness {fitness} has no parameter \"{key}\"; it takes {known}")]
    UnknownKey {
        fitness: &'static str,
        key: String,
        known: &'static str,
    },
    #[error("fitness parameter \"{0}\" is not key=value with a finite number")]
    Malformed(String),
}

/// A fitness function with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fitness {
    Avoidance {
        /// Wheel command (pulses per 10 ms) that counts as full speed.
        vmax: f64,
    },
    Regatta {
        /// Subtracted per second of contact.
        penalty: f64,
        /// Added per visit to another buoy out of cyclic order.
        other: f64,
    },
    Phototaxis {
        /// Distance (m) from the buoy's centre at which closeness reaches 0.
        range: f64,
    },
}

impl Fitness {
    pub const AVOIDANCE: Fitness = Fitness::Avoidance { vmax: 20.0 };
    pub const REGATTA: Fitness = Fitness::Regatta {
        penalty: 0.5,
        other: 0.0,
    };
    pub const PHOTOTAXIS: Fitness = Fitness::Phototaxis { range: 0.5 };

    /// Reads `name[:key=value,...]`.
    pub fn parse(text: &str) -> Result<Fitness, FitnessError> {
        let (name, parameters) = text.split_once(':').unwrap_or((text, ""));
        let mut fitness = match name.trim() {
            "avoidance" => Fitness::AVOIDANCE,
            "regatta" => Fitness::REGATTA,
            "phototaxis" => Fitness::PHOTOTAXIS,
            other => return Err(FitnessError::Unknown(other.to_owned())),
        };
        for parameter in parameters.split(',').filter(|p| !p.trim().is_empty()) {
            let (key, value) = parameter
                .split_once('=')
                .ok_or_else(|| FitnessError::Malformed(parameter.to_owned()))?;
            let value: f64 = value
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| FitnessError::Malformed(parameter.to_owned()))?;
            let key = key.trim();
            match (&mut fitness, key) {
                (Fitness::Avoidance { vmax }, "vmax") if value > 0.0 => *vmax = value,
                (Fitness::Regatta { penalty, .. }, "penalty") => *penalty = value,
                (Fitness::Regatta { other, .. }, "other") => *other = value,
                (Fitness::Phototaxis { range }, "range") if value > 0.0 => *range = value,
                (Fitness::Avoidance { .. }, "vmax") | (Fitness::Phototaxis { .. }, "range") => {
                    return Err(FitnessError::Malformed(parameter.to_owned()))
                }
                (f, _) => {
                    return Err(FitnessError::UnknownKey {
                        fitness: f.name(),
                        key: key.to_owned(),
                        known: match f {
                            Fitness::Avoidance { .. } => "vmax",
                            Fitness::Regatta { .. } => "penalty, other",
                            Fitness::Phototaxis { .. } => "range",
                        },
                    })
                }
            }
        }
        Ok(fitness)
    }

    pub fn name(&self) -> &'static str {
        match self {
            Fitness::Avoidance { .. } => "avoidance",
            Fitness::Regatta { .. } => "regatta",
            Fitness::Phototaxis { .. } => "phototaxis",
        }
    }
}

/// Floreano and Mondada's avoidance terms, accumulated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AvoidanceMeter {
    vmax: f64,
    steps: u64,
    /// The last IR readings' largest value, normalised.
    i: f64,
    sum_phi: f64,
    sum_v: f64,
    sum_dv: f64,
    sum_i: f64,
}

/// The avoidance fitness and the means of its terms.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AvoidanceTerms {
    /// Φ averaged over the steps.
    pub value: f64,
    /// Mean V (mean absolute wheel speed / vmax).
    pub speed: f64,
    /// Mean Δv (|left − right| / (2 vmax)).
    pub turning: f64,
    /// Mean i (largest IR reading / 1023).
    pub proximity: f64,
}

impl AvoidanceMeter {
    pub fn new(vmax: f64) -> AvoidanceMeter {
        AvoidanceMeter {
            vmax,
            ..AvoidanceMeter::default()
        }
    }

    /// Takes in one step; returns its Φ (the step's reward: the fitness is their mean).
    pub fn add(&mut self, record: &StepRecord) -> f64 {
        if let Some(readings) = record.proximity {
            self.i = readings.iter().copied().max().unwrap_or(0) as f64 / 1023.0;
        }
        let unit = |c: i32| (c as f64 / self.vmax).clamp(-1.0, 1.0);
        let (left, right) = (unit(record.command.0), unit(record.command.1));
        let v = (left.abs() + right.abs()) / 2.0;
        let dv = (left - right).abs() / 2.0;
        let phi = v * (1.0 - dv.sqrt()) * (1.0 - self.i);
        self.sum_phi += phi;
        self.sum_v += v;
        self.sum_dv += dv;
        self.sum_i += self.i;
        self.steps += 1;
        phi
    }

    pub fn terms(&self) -> AvoidanceTerms {
        let n = self.steps.max(1) as f64;
        AvoidanceTerms {
            value: self.sum_phi / n,
            speed: self.sum_v / n,
            turning: self.sum_dv / n,
            proximity: self.sum_i / n,
        }
    }
}

/// Buoy visits in cyclic order and time in contact, accumulated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RegattaMeter {
    penalty: f64,
    other_weight: f64,
    /// Each buoy's place in the cyclic order (by angle around the buoys' centroid).
    place: Vec<usize>,
    last: Option<usize>,
    /// The last transition's step around the cycle (1 … n−1).
    last_step: Option<usize>,
    cyclic: u64,
    other: u64,
    contact_time: f64,
    /// Whether each visit (as entered, repeats included) continued the cyclic order.
    visits: Vec<(usize, f64, bool)>,
}

/// The regatta fitness and its terms.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegattaTerms {
    pub value: f64,
    /// Visits that continued a cyclic order.
    pub cyclic_visits: u64,
    /// Visits to another buoy out of cyclic order.
    pub other_visits: u64,
    /// Time spent in contact (s).
    pub contact_s: f64,
}

/// Each landmark's place in the cyclic order: sorted by angle about their centroid (ties by
/// file order).
pub fn cyclic_places(landmarks: &[Landmark]) -> Vec<usize> {
    let n = landmarks.len();
    if n == 0 {
        return Vec::new();
    }
    let centroid = landmarks.iter().map(|l| l.center).sum::<DVec2>() / n as f64;
    let angle = |l: &Landmark| libm::atan2(l.center.y - centroid.y, l.center.x - centroid.x);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        angle(&landmarks[a])
            .total_cmp(&angle(&landmarks[b]))
            .then(a.cmp(&b))
    });
    let mut place = vec![0; n];
    for (rank, &k) in order.iter().enumerate() {
        place[k] = rank;
    }
    place
}

impl RegattaMeter {
    pub fn new(penalty: f64, other: f64, landmarks: &[Landmark]) -> RegattaMeter {
        RegattaMeter {
            penalty,
            other_weight: other,
            place: cyclic_places(landmarks),
            ..RegattaMeter::default()
        }
    }

    /// Takes in one step; returns the change of the fitness it made (the step's reward: the
    /// fitness is their sum).
    pub fn add(&mut self, record: &StepRecord) -> f64 {
        let mut change = 0.0;
        if record.touching {
            self.contact_time += record.time_step;
            change -= self.penalty * record.time_step;
        }
        let n = self.place.len();
        for &buoy in record.entered {
            let Some(&place) = self.place.get(buoy) else {
                continue;
            };
            let mut cyclic = false;
            match self.last {
                // Entering the same buoy again (an orbit's wobble) is not a new visit.
                Some(last) if last == buoy => {}
                Some(last) => {
                    let step = (place + n - self.place[last]) % n;
                    let neighbour = step == 1 || step == n - 1;
                    cyclic = neighbour && self.last_step.is_none_or(|s| s == step);
                    if cyclic {
                        self.cyclic += 1;
                        change += 1.0;
                    } else {
                        self.other += 1;
                        change += self.other_weight;
                    }
                    self.last_step = Some(step);
                }
                None => {}
            }
            self.last = Some(buoy);
            self.visits.push((buoy, record.t, cyclic));
        }
        change
    }

    pub fn terms(&self) -> RegattaTerms {
        RegattaTerms {
            value: self.cyclic as f64 + self.other_weight * self.other as f64
                - self.penalty * self.contact_time,
            cyclic_visits: self.cyclic,
            other_visits: self.other,
            contact_s: self.contact_time,
        }
    }

    /// Every visit as entered: (landmark, time, whether it continued the cyclic order).
    pub fn visits(&self) -> &[(usize, f64, bool)] {
        &self.visits
    }
}

/// Closeness to the brightest buoy, accumulated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhototaxisMeter {
    range: f64,
    target: Option<(usize, DVec2)>,
    sum: f64,
    time: f64,
}

/// The phototaxis fitness and its target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhototaxisTerms {
    pub value: f64,
    /// The brightest buoy (numbered from 1), if the world has any.
    pub buoy: Option<usize>,
}

impl PhototaxisMeter {
    pub fn new(range: f64, landmarks: &[Landmark]) -> PhototaxisMeter {
        let target = landmarks
            .iter()
            .enumerate()
            .fold(None::<(usize, &Landmark)>, |best, (k, l)| match best {
                Some((_, b)) if b.brightness >= l.brightness => best,
                _ => Some((k, l)),
            })
            .map(|(k, l)| (k, l.center));
        PhototaxisMeter {
            range,
            target,
            ..PhototaxisMeter::default()
        }
    }

    /// Takes in one step; returns its closeness times its length (the step's reward: the
    /// fitness is their sum over the time).
    pub fn add(&mut self, record: &StepRecord) -> f64 {
        self.time += record.time_step;
        let Some((_, center)) = self.target else {
            return 0.0;
        };
        let d = (DVec2::new(record.pose.x, record.pose.z) - center).length();
        let weighted = (1.0 - d / self.range).max(0.0) * record.time_step;
        self.sum += weighted;
        weighted
    }

    pub fn terms(&self) -> PhototaxisTerms {
        PhototaxisTerms {
            value: if self.time > 0.0 {
                self.sum / self.time
            } else {
                0.0
            },
            buoy: self.target.map(|(k, _)| k + 1),
        }
    }
}

/// Every fitness of one robot, measured together (each is a few operations per step).
#[derive(Clone, Debug, PartialEq)]
pub struct Meters {
    pub avoidance: AvoidanceMeter,
    pub regatta: RegattaMeter,
    pub phototaxis: PhototaxisMeter,
}

/// Every fitness's terms for one robot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitnessTerms {
    pub avoidance: AvoidanceTerms,
    pub regatta: RegattaTerms,
    pub phototaxis: PhototaxisTerms,
}

impl FitnessTerms {
    /// The value of `fitness` (its parameters as the meters were built).
    pub fn value(&self, fitness: &Fitness) -> f64 {
        match fitness {
            Fitness::Avoidance { .. } => self.avoidance.value,
            Fitness::Regatta { .. } => self.regatta.value,
            Fitness::Phototaxis { .. } => self.phototaxis.value,
        }
    }
}

impl Meters {
    /// Meters with each fitness's parameters taken from `chosen` where it names that
    /// fitness, and the defaults otherwise.
    pub fn new(chosen: &Fitness, landmarks: &[Landmark]) -> Meters {
        let vmax = match chosen {
            Fitness::Avoidance { vmax } => *vmax,
            _ => 20.0,
        };
        let (penalty, other) = match chosen {
            Fitness::Regatta { penalty, other } => (*penalty, *other),
            _ => (0.5, 0.0),
        };
        let range = match chosen {
            Fitness::Phototaxis { range } => *range,
            _ => 0.5,
        };
        Meters {
            avoidance: AvoidanceMeter::new(vmax),
            regatta: RegattaMeter::new(penalty, other, landmarks),
            phototaxis: PhototaxisMeter::new(range, landmarks),
        }
    }

    pub fn add(&mut self, record: &StepRecord) {
        self.add_rewarded(record, &Fitness::AVOIDANCE);
    }

    /// [`Meters::add`], returning the step's reward under `chosen` (each meter's `add` says
    /// what that is).
    pub fn add_rewarded(&mut self, record: &StepRecord, chosen: &Fitness) -> f64 {
        let avoidance = self.avoidance.add(record);
        let regatta = self.regatta.add(record);
        let phototaxis = self.phototaxis.add(record);
        match chosen {
            Fitness::Avoidance { .. } => avoidance,
            Fitness::Regatta { .. } => regatta,
            Fitness::Phototaxis { .. } => phototaxis,
        }
    }

    pub fn terms(&self) -> FitnessTerms {
        FitnessTerms {
            avoidance: self.avoidance.terms(),
            regatta: self.regatta.terms(),
            phototaxis: self.phototaxis.terms(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use regatta_runtime::compile::rig::Pose2;

    fn landmark(x: f64, z: f64, brightness: f64) -> Landmark {
        Landmark {
            name: "buoy".into(),
            center: DVec2::new(x, z),
            radius: 0.02,
            brightness,
            primitives: 0..0,
        }
    }

    fn record(
        command: (i32, i32),
        proximity: Option<[u16; 8]>,
        entered: &[usize],
    ) -> StepRecord<'_> {
        StepRecord {
            t: 0.0,
            time_step: 0.5,
            pose: Pose2 {
                x: 0.0,
                z: 0.0,
                heading: 0.0,
            },
            command,
            proximity,
            touching: false,
            entered,
        }
    }

    #[test]
    fn names_and_parameters_parse() {
        assert_eq!(Fitness::parse("avoidance").unwrap(), Fitness::AVOIDANCE);
        assert_eq!(
            Fitness::parse("regatta:penalty=1,other=0").unwrap(),
            Fitness::Regatta {
                penalty: 1.0,
                other: 0.0
            }
        );
        assert!(matches!(
            Fitness::parse("speed"),
            Err(FitnessError::Unknown(_))
        ));
        assert!(matches!(
            Fitness::parse("avoidance:range=2"),
            Err(FitnessError::UnknownKey { .. })
        ));
        assert!(matches!(
            Fitness::parse("avoidance:vmax=0"),
            Err(FitnessError::Malformed(_))
        ));
    }

    #[test]
    fn avoidance_by_hand() {
        // vmax 20. Step 1: straight at full speed, nothing near: V = 1, Δv = 0, i = 0: Φ = 1.
        // Step 2: left 20, right 0, sensor 3 reads 1023·0.25 rounded (256/1023): V = 0.5,
        // Δv = 0.5, i = 256/1023: Φ = 0.5 · (1 − √0.5) · (1 − 256/1023).
        // Step 3: the reading is held (not refreshed); wheels −10, 10: V = 0.5, Δv = 0.5.
        let mut meter = AvoidanceMeter::new(20.0);
        meter.add(&record((20, 20), Some([0; 8]), &[]));
        let mut near = [0u16; 8];
        near[3] = 256;
        meter.add(&record((20, 0), Some(near), &[]));
        meter.add(&record((-10, 10), None, &[]));
        let i = 256.0 / 1023.0;
        let step2 = 0.5 * (1.0 - 0.5f64.sqrt()) * (1.0 - i);
        let terms = meter.terms();
        assert_eq!(terms.value, (1.0 + step2 + step2) / 3.0);
        assert_eq!(terms.speed, (1.0 + 0.5 + 0.5) / 3.0);
        assert_eq!(terms.turning, (0.0 + 0.5 + 0.5) / 3.0);
        assert_eq!(terms.proximity, (0.0 + i + i) / 3.0);
        // Commands beyond vmax count as full speed.
        let mut meter = AvoidanceMeter::new(10.0);
        meter.add(&record((40, 40), None, &[]));
        assert_eq!(meter.terms().value, 1.0);
    }

    #[test]
    fn regatta_counts_cyclic_visits_and_charges_contact() {
        // A triangle: buoy 0 at the top (angle −90°), 1 bottom left, 2 bottom right. Around
        // the centroid by angle: 0 (−90°), 2 (≈30°), 1 (≈150°).
        let buoys = [
            landmark(0.0, -0.3, 1.0),
            landmark(-0.26, 0.15, 1.0),
            landmark(0.26, 0.15, 1.0),
        ];
        assert_eq!(cyclic_places(&buoys), vec![0, 2, 1]);
        let mut meter = RegattaMeter::new(0.5, 0.25, &buoys);
        // Three steps in contact of 0.5 s each.
        let sequence = [0, 1, 1, 2, 0, 2, 0, 1];
        for (k, buoy) in sequence.iter().enumerate() {
            let mut r = record((0, 0), None, std::slice::from_ref(buoy));
            r.touching = k < 3;
            meter.add(&r);
        }
        // Places: 0→0, 1→2, 2→1. Transitions (step = place difference mod 3):
        // 0→1: 2 (first: cyclic); 1→2: 1−2 = 2 (cyclic); 2→0: 0−1 = 2 (cyclic);
        // 0→2: 1 (reversal: other); 2→0: 2 (reversal: other); 0→1: 2 (same as last: cyclic).
        let terms = meter.terms();
        assert_eq!((terms.cyclic_visits, terms.other_visits), (4, 2));
        assert_eq!(terms.contact_s, 1.5);
        assert_eq!(terms.value, 4.0 + 0.25 * 2.0 - 0.5 * 1.5);
        let flags: Vec<bool> = meter.visits().iter().map(|v| v.2).collect();
        assert_eq!(flags, [false, true, false, true, true, false, false, true]);
        // Two buoys: every alternation is cyclic.
        let mut pair = RegattaMeter::new(0.0, 0.0, &buoys[..2]);
        for buoy in [0, 1, 0, 1] {
            pair.add(&record((0, 0), None, &[buoy]));
        }
        assert_eq!(pair.terms().cyclic_visits, 3);
    }

    #[test]
    fn rewards_add_up_to_the_fitness() {
        let buoys = [
            landmark(0.0, -0.3, 1.0),
            landmark(-0.26, 0.15, 1.0),
            landmark(0.26, 0.15, 1.0),
        ];
        let mut near = [0u16; 8];
        near[2] = 300;
        for chosen in [Fitness::AVOIDANCE, Fitness::REGATTA, Fitness::PHOTOTAXIS] {
            let mut meters = Meters::new(&chosen, &buoys);
            let mut rewards = 0.0;
            for (k, buoy) in [0, 1, 2, 0, 2, 1].iter().enumerate() {
                let mut r = record((12, 3 * k as i32), Some(near), std::slice::from_ref(buoy));
                r.touching = k % 2 == 0;
                r.pose.x = 0.05 * k as f64;
                rewards += meters.add_rewarded(&r, &chosen);
            }
            let value = meters.terms().value(&chosen);
            // Avoidance is the mean of its rewards, phototaxis their sum over the 3 s, the
            // regatta their sum.
            let expected = match chosen {
                Fitness::Avoidance { .. } => rewards / 6.0,
                Fitness::Phototaxis { .. } => rewards / 3.0,
                Fitness::Regatta { .. } => rewards,
            };
            assert!(
                (expected - value).abs() < 1e-12,
                "{chosen:?}: {expected} {value}"
            );
            assert!(value != 0.0, "{chosen:?}");
        }
    }

    #[test]
    fn phototaxis_weights_closeness_by_time() {
        // The brighter buoy is the second; the robot sits 0.1 m from it, then 0.6 m.
        let buoys = [landmark(1.0, 1.0, 0.5), landmark(0.1, 0.0, 0.9)];
        let mut meter = PhototaxisMeter::new(0.5, &buoys);
        meter.add(&record((0, 0), None, &[]));
        let mut far = record((0, 0), None, &[]);
        far.pose.x = 0.7;
        far.time_step = 1.5;
        meter.add(&far);
        let terms = meter.terms();
        assert_eq!(terms.buoy, Some(2));
        // (1 − 0.1/0.5)·0.5 s + 0·1.5 s over 2 s.
        assert_eq!(terms.value, (1.0 - 0.1 / 0.5) * 0.5 / 2.0);
    }
}
