//! Swarms: the column renderer's sweep against the exhaustive reference on random crowded
//! scenes (bit for bit), one simulation across thread counts, and a packed crowd that never
//! overlaps beyond the documented tolerance. The crowd level of detail: exact where every
//! robot is within its distance, within its documented error bound on random crowds, and the
//! same on any number of threads.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use regatta_runtime::compile::rig::TurretRig;
use regatta_runtime::optics::{Panoramic, Renderer, RetinaOutput};
use regatta_runtime::render::column::{ColumnFrame, ColumnScene, KeptImpostors, Strip};
use regatta_runtime::render::Detail;
use regatta_runtime::retina::{pixel_azimuth, HALF_BAND, PIXELS, PIXEL_WIDTH};
use regatta_runtime::sim::{Simulation, PENETRATION_TOLERANCE};
use regatta_tests::{compile_text, start_poses};

/// A crowded arena: robots anywhere (overlapping or not: only vision is tested), buoys, and
/// turned boxes.
fn crowd_world(
    side: f64,
    robots: &[(f64, f64, f64)],
    buoys: &[(f64, f64)],
    boxes: &[(f64, f64, f64)],
    stride: u32,
    samples: u32,
) -> String {
    let mut out = format!(
        "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" }}\n\
         DirectionalLight {{ direction 0.3 -1 0.2 intensity 0.6 ambientIntensity 0.2 }}\n\
         Arena {{ size {side} {side} }}\n"
    );
    let at = |u: f64| (u - 0.5) * side * 0.96;
    for &(x, z) in buoys {
        out += &format!("Buoy {{ translation {} 0 {} }}\n", at(x), at(z));
    }
    for &(x, z, yaw) in boxes {
        out += &format!(
            "Transform {{ translation {} 0.02 {} rotation 0 1 0 {yaw} children [ Shape {{ \
             appearance Appearance {{ material Material {{ diffuseColor 0.8 0.3 0.2 }} }} \
             geometry Box {{ size 0.06 0.04 0.02 }} }} ] }}\n",
            at(x),
            at(z)
        );
    }
    for (i, &(x, z, heading)) in robots.iter().enumerate() {
        out += &format!(
            "Khepera {{ translation {} 0 {} rotation 0 1 0 {heading} name \"r{i}\" \
             turret PanoramicTurret {{ stride {stride} samples {samples} }} }}\n",
            at(x),
            at(z)
        );
    }
    out
}

fn strip() -> Strip {
    Strip::new(
        (0..PIXELS).map(pixel_azimuth).collect(),
        PIXEL_WIDTH,
        HALF_BAND,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Every robot's photocurrents from the step's shared frame, through the sweep (and, past
    /// a few dozen parts, with the parts behind it left out), are the exhaustive reference's
    /// to the last bit, and so are the 6-bit outputs.
    #[test]
    fn the_sweep_renders_crowds_as_the_exhaustive_reference(
        side in 0.3f64..1.6,
        robots in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, -3.2f64..3.2), 2..60),
        buoys in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0), 0..6),
        boxes in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, -3.2f64..3.2), 0..4),
        stride in prop::sample::select(vec![1u32, 4, 16]),
        samples in 1u32..3,
    ) {
        let text = crowd_world(side, &robots, &buoys, &boxes, stride, samples);
        let fast = crowd_retinas(&text, |d| d);
        let reference = start_retinas(&text, |scene, frame, strip, start, analog| {
            scene.integrate_exhaustive(frame, Some(start.index), start.eye, start.heading,
                strip, start.detail, analog);
        });
        for (robot, ((fast, out_fast), (reference, out_reference))) in
            fast.iter().zip(&reference).enumerate()
        {
            for (pixel, (a, b)) in fast.iter().zip(reference).enumerate() {
                prop_assert_eq!(a.to_bits(), b.to_bits(), "retina {} pixel {}: {} vs {}",
                    robot, pixel, a, b);
            }
            prop_assert_eq!(&out_fast.digital, &out_reference.digital);
        }
    }
}

/// `text` compiled and its scene's frame at the robots' start poses, handed to `f`.
fn with_start_frame<R>(
    text: &str,
    f: impl FnOnce(&regatta_runtime::Compiled, &ColumnScene, &ColumnFrame) -> R,
) -> R {
    let compiled = compile_text(text);
    let renderer = Renderer::new(&compiled.graph, &compiled.plan, false);
    let Renderer::Columns(scene) = &renderer else {
        panic!("an upright crowd renders by columns");
    };
    let poses = start_poses(&compiled);
    let mut shared = None;
    renderer.prepare_shared(&compiled.plan, &poses, &[], false, &mut shared);
    let frame = shared.expect("the column renderer shares its frame");
    f(&compiled, scene, &frame)
}

/// One retina at its robot's start: the robot, its eye and heading, and its turret's detail.
struct StartEye {
    index: usize,
    eye: DVec3,
    heading: f64,
    detail: Detail,
}

/// Every retina of `text`'s crowd at its start, through the shared frame, its photocurrents
/// drawn by `render` over the test strip: each robot's photocurrents and 6-bit outputs.
fn start_retinas(
    text: &str,
    mut render: impl FnMut(&ColumnScene, &ColumnFrame, &Strip, StartEye, &mut [f64]),
) -> Vec<(Vec<f64>, RetinaOutput)> {
    with_start_frame(text, |compiled, scene, frame| {
        let strip = strip();
        let mut out = Vec::new();
        for (index, rig) in compiled.rig.robots.iter().enumerate() {
            let Some(TurretRig::Panoramic(turret)) = &rig.turret else {
                continue;
            };
            let start = StartEye {
                index,
                eye: DVec3::new(rig.start.x, rig.floor_y + turret.height, rig.start.z),
                heading: rig.start.heading,
                detail: Detail::new(turret.samples, turret.stride),
            };
            let mut analog = vec![0.0; PIXELS];
            render(scene, frame, &strip, start, &mut analog);
            let mut output = RetinaOutput::default();
            Panoramic::new(turret).accept(&analog, &mut output);
            out.push((analog, output));
        }
        out
    })
}

/// Every retina of a crowd at its start, with `detail`: each robot's photocurrents and 6-bit
/// outputs.
fn crowd_retinas(text: &str, detail: impl Fn(Detail) -> Detail) -> Vec<(Vec<f64>, RetinaOutput)> {
    start_retinas(text, |scene, frame, strip, start, analog| {
        let StartEye {
            index,
            eye,
            heading,
            detail: base,
        } = start;
        scene.integrate_for(
            frame,
            Some(index),
            eye,
            heading,
            strip,
            detail(base),
            analog,
        );
    })
}

/// Each robot's retina with impostors kept (`crowdKeepDistance` `keep`, crowd distance 0.5 m,
/// far distance 5 m): worked out with the eye up to `keep` away from its start and turned by
/// up to a radian (`unit`'s draws), then drawn from its start.
fn kept_retinas(
    text: &str,
    keep: f64,
    unit: &mut impl FnMut() -> f64,
) -> Vec<(Vec<f64>, RetinaOutput)> {
    start_retinas(text, |scene, frame, strip, start, analog| {
        let StartEye {
            index,
            eye,
            heading,
            detail,
        } = start;
        let detail = Detail {
            crowd_distance: 0.5,
            far_distance: 5.0,
            ..detail
        };
        let (radius, angle) = (0.999 * keep * unit().sqrt(), std::f64::consts::TAU * unit());
        let then = eye + DVec3::new(radius * libm::cos(angle), 0.0, radius * libm::sin(angle));
        let heading_then = heading + 2.0 * unit() - 1.0;
        let mut kept = KeptImpostors::new(keep);
        for (at, heading) in [(then, heading_then), (eye, heading)] {
            scene.integrate_kept(
                frame,
                Some(index),
                at,
                heading,
                strip,
                detail,
                &mut kept,
                analog,
            );
        }
    })
}

/// How far `crowd`'s 6-bit outputs are from `exact`'s: the mean over every output (LSB), the
/// count of outputs compared, and the largest.
fn digital_error(
    crowd: &[(Vec<f64>, RetinaOutput)],
    exact: &[(Vec<f64>, RetinaOutput)],
) -> (f64, u64, u32) {
    let (mut sum, mut outputs, mut worst) = (0u64, 0u64, 0u32);
    for ((_, a), (_, b)) in crowd.iter().zip(exact) {
        for ((_, x), (_, y)) in a.digital.iter().zip(&b.digital) {
            for (p, q) in x.iter().zip(y) {
                let error = (*p as i32 - *q as i32).unsigned_abs();
                sum += error as u64;
                worst = worst.max(error);
                outputs += 1;
            }
        }
    }
    (sum as f64 / outputs.max(1) as f64, outputs, worst)
}

/// A seeded stream of uniform numbers in [0, 1) (xorshift), for scenes drawn from one seed.
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The documented bound of the crowd level of detail with every robot within reach
/// (docs/crowd.md): the mean error of a scene's 6-bit outputs, the largest, and the
/// photocurrents' error relative to their mean ([`normalised_error`]).
/// A retina's flat stretches sit at the converter's mid-scale, where the slightest change of
/// the mean photocurrent turns 31 into 32 over the whole stretch: tiny, overlapping crowds
/// (4 robots in 0.5 m²: 0.077 LSB) flip whole images, hence crowds of the swarms' density.
/// 3,000 cases: at most 0.062 LSB, 2 LSB, 0.54 %.
const WITHIN_REACH_MEAN_LSB: f64 = 0.1;
const WITHIN_REACH_MAX_LSB: u32 = 2;
const WITHIN_REACH_MEAN_RELATIVE: f64 = 0.02;

/// The photocurrents' error of `crowd` against `exact`, relative to their mean: the sum of
/// the differences over the sum of the exact photocurrents (a photodiode that exact sees all
/// but dark does not weigh more than the others).
fn normalised_error(crowd: &[(Vec<f64>, RetinaOutput)], exact: &[(Vec<f64>, RetinaOutput)]) -> f64 {
    let (mut difference, mut total) = (0.0, 0.0);
    for ((a, _), (b, _)) in crowd.iter().zip(exact) {
        for (x, y) in a.iter().zip(b) {
            difference += (x - y).abs();
            total += y.abs();
        }
    }
    difference / total.max(1e-300)
}

/// The photocurrents' mean relative error of `crowd` against `exact`.
fn mean_relative_error(
    crowd: &[(Vec<f64>, RetinaOutput)],
    exact: &[(Vec<f64>, RetinaOutput)],
) -> f64 {
    let (mut relative, mut currents) = (0.0, 0usize);
    for ((a, _), (b, _)) in crowd.iter().zip(exact) {
        for (x, y) in a.iter().zip(b) {
            relative += (x - y).abs() / y.abs().max(1e-12);
            currents += 1;
        }
    }
    relative / currents.max(1) as f64
}

/// The documented bound of the crowd level of detail at 0.5 m on crowds of 10 robots/m²
/// (docs/crowd.md): the mean error of a scene's 6-bit outputs, and the largest.
const CROWD_MEAN_LSB: f64 = 0.3;
const CROWD_MAX_LSB: u32 = 3;

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// With every robot within the crowd distance, the crowd level of detail leaves out only
    /// what no photodiode sees (parts wholly below or above the band: another robot nearer
    /// than about 17 cm, wheels nearer than about 35 cm, the viewer's own body) and the parts
    /// tucked under another robot's body (a Khepera's wheels, 1.6 mm of their corners
    /// showing): within the documented bound of those two alone, on crowds of 10 to 40 robots
    /// at about 10 robots/m².
    #[test]
    fn the_crowd_level_of_detail_within_reach_leaves_out_only_hidden_and_tucked_parts(
        count in 10usize..40,
        seed in 0u64..1_000_000,
        buoys in 0usize..4,
        stride in prop::sample::select(vec![1u32, 16]),
    ) {
        // A crowd of about 10 robots/m², as the swarms are, every robot within reach.
        let side = (count as f64 / 10.0).sqrt();
        let mut unit = uniform(seed);
        let robots: Vec<(f64, f64, f64)> = (0..count)
            .map(|_| (unit(), unit(), unit() * 6.4 - 3.2))
            .collect();
        let buoys: Vec<(f64, f64)> = (0..buoys).map(|_| (unit(), unit())).collect();
        let text = crowd_world(side, &robots, &buoys, &[], stride, 1);
        let exact = crowd_retinas(&text, |d| d);
        let reach = side * 1.5;
        let crowd = crowd_retinas(&text, |d| Detail { crowd_distance: reach, ..d });
        let (mean, outputs, worst) = digital_error(&crowd, &exact);
        let relative = normalised_error(&crowd, &exact);
        prop_assert!(mean <= WITHIN_REACH_MEAN_LSB, "mean error {} LSB over {} outputs", mean, outputs);
        prop_assert!(worst <= WITHIN_REACH_MAX_LSB, "largest error {} LSB", worst);
        prop_assert!(relative <= WITHIN_REACH_MEAN_RELATIVE, "photocurrents off by {} on average", relative);
    }

    /// On random crowds of about 10 robots/m², leaving out the robots beyond 0.5 m keeps
    /// each scene's 6-bit outputs within the documented bound of the exact ones.
    #[test]
    fn the_crowd_level_of_detail_stays_within_its_documented_error(
        count in 20usize..60,
        seed in 0u64..1_000_000,
    ) {
        let side = (count as f64 / 10.0).sqrt();
        let mut unit = uniform(seed);
        let robots: Vec<(f64, f64, f64)> = (0..count)
            .map(|_| (unit(), unit(), unit() * 6.4 - 3.2))
            .collect();
        let buoys: Vec<(f64, f64)> = (0..count / 10).map(|_| (unit(), unit())).collect();
        let text = crowd_world(side, &robots, &buoys, &[], 16, 1);
        let exact = crowd_retinas(&text, |d| d);
        let crowd = crowd_retinas(&text, |d| Detail { crowd_distance: 0.5, ..d });
        let (mean, outputs, worst) = digital_error(&crowd, &exact);
        prop_assert!(mean <= CROWD_MEAN_LSB, "mean error {} LSB over {} outputs", mean, outputs);
        prop_assert!(worst <= CROWD_MAX_LSB, "largest error {} LSB", worst);
    }
}

/// Six robots, headings any, within 0.3 m of `centre` (in `crowd_world`'s units of the arena's
/// side): all within the crowd distance of each other.
fn robots_near(
    unit: &mut impl FnMut() -> f64,
    centre: (f64, f64),
    side: f64,
) -> Vec<(f64, f64, f64)> {
    let near = 0.3 / (side * 0.96);
    (0..6)
        .map(|_| {
            (
                centre.0 + near * (unit() - 0.5),
                centre.1 + near * (unit() - 0.5),
                unit() * 6.4 - 3.2,
            )
        })
        .collect()
}

/// The documented bound of impostors alone (docs/crowd.md): a buoy field's mean 6-bit error,
/// its largest, and the photocurrents' mean relative error. Leaving the far buoys out instead
/// fails it (0.26 LSB on the first field tried), and so does drawing them at 4 times their
/// effect (0.14 LSB).
const IMPOSTOR_MEAN_LSB: f64 = 0.1;
const IMPOSTOR_MAX_LSB: u32 = 2;
const IMPOSTOR_MEAN_RELATIVE: f64 = 0.1;

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// A field of buoys, most of them beyond the crowd distance and drawn as impostors (a box
    /// of their effect on the column through their centre, hidden where a nearer buoy stands),
    /// seen by robots all within the crowd distance of each other (so that only the impostors
    /// differ from exact): within the documented bound.
    #[test]
    fn impostors_in_a_buoy_field_stay_within_their_documented_error(
        buoys in 40usize..240,
        side in 2.0f64..7.0,
        seed in 0u64..1_000_000,
        stride in prop::sample::select(vec![1u32, 16]),
    ) {
        let mut unit = uniform(seed);
        let robots = robots_near(&mut unit, (0.5, 0.5), side);
        let field: Vec<(f64, f64)> = (0..buoys).map(|_| (unit(), unit())).collect();
        let text = crowd_world(side, &robots, &field, &[], stride, 1);
        let exact = crowd_retinas(&text, |d| d);
        let crowd = crowd_retinas(&text, |d| Detail { crowd_distance: 0.5, ..d });
        let (mean, outputs, worst) = digital_error(&crowd, &exact);
        let relative = mean_relative_error(&crowd, &exact);
        prop_assert!(mean <= IMPOSTOR_MEAN_LSB, "mean error {} LSB over {} outputs", mean, outputs);
        prop_assert!(worst <= IMPOSTOR_MAX_LSB, "largest error {} LSB", worst);
        prop_assert!(relative <= IMPOSTOR_MEAN_RELATIVE, "photocurrents off by {} on average", relative);
    }
}

/// A large buoy field's world: `density` buoys/m² in an arena of `side` m, with robots within
/// reach of each other somewhere in it (turrets sampled with `stride`), drawn from `unit`.
fn buoy_field(density: f64, side: f64, unit: &mut impl FnMut() -> f64, stride: u32) -> String {
    let centre = (0.2 + 0.6 * unit(), 0.2 + 0.6 * unit());
    let robots = robots_near(unit, centre, side);
    let field: Vec<(f64, f64)> = (0..(density * side * side) as usize)
        .map(|_| (unit(), unit()))
        .collect();
    crowd_world(side, &robots, &field, &[], stride, 1)
}

/// The documented bound of the far distance (docs/crowd.md): a large buoy field seen with
/// impostors up to 5 m and the buoys beyond left out, against exact: the mean 6-bit error,
/// the largest, and the photocurrents' mean relative error. 5,000 fields of this generator
/// (`buoy_field_errors_over_many_fields`): 0.034 LSB on average, 10 fields above 0.1 and
/// none above 0.124, none off by more than 1 LSB (impostors however far: 0.021 LSB; under
/// this test's bright light a far lamp shows more than under the swarms' dim one, where
/// leaving it out is the more accurate). A field is a few hundred outputs: its mean
/// scatters above the budget's 0.1, which `regatta bench crowd` holds over many.
const FAR_MEAN_LSB: f64 = 0.15;
const FAR_MAX_LSB: u32 = 2;
const FAR_MEAN_RELATIVE: f64 = 0.05;

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    /// A large field of buoys (1 to 3 per square metre in an 8 to 14 m arena), seen by robots
    /// within reach of each other somewhere in it, with the crowd distance and a far distance
    /// of 5 m (the bench's setting): the buoys beyond 5 m are left out, those between drawn
    /// as impostors. Within the documented bound of exact.
    #[test]
    fn the_far_distance_in_a_large_buoy_field_stays_within_its_documented_error(
        density in 1.0f64..3.0,
        side in 8.0f64..14.0,
        seed in 0u64..1_000_000,
        stride in prop::sample::select(vec![1u32, 16]),
    ) {
        let (mean, outputs, worst, relative) = far_field_error(density, side, seed, stride);
        prop_assert!(mean <= FAR_MEAN_LSB, "mean error {} LSB over {} outputs", mean, outputs);
        prop_assert!(worst <= FAR_MAX_LSB, "largest error {} LSB", worst);
        prop_assert!(relative <= FAR_MEAN_RELATIVE, "photocurrents off by {} on average", relative);
    }
}

/// A large buoy field of `density` buoys/m² in an arena of `side` m, drawn from `seed` with
/// robots within reach of each other somewhere in it (turrets sampled with `stride`), seen
/// with the crowd distance and a far distance of 5 m against exact: the mean 6-bit error, the
/// outputs compared, the largest error and the photocurrents' mean relative error.
fn far_field_error(density: f64, side: f64, seed: u64, stride: u32) -> (f64, u64, u32, f64) {
    let text = buoy_field(density, side, &mut uniform(seed), stride);
    let exact = crowd_retinas(&text, |d| d);
    let far = crowd_retinas(&text, |d| Detail {
        crowd_distance: 0.5,
        far_distance: 5.0,
        ..d
    });
    let (mean, outputs, worst) = digital_error(&far, &exact);
    (mean, outputs, worst, mean_relative_error(&far, &exact))
}

/// The far distance's buoy field of `density` buoys/m² in an arena of `side` m, drawn from
/// `seed` with robots within reach of each other somewhere in it, seen with impostors kept
/// within `keep` against exact: the mean 6-bit error, the outputs compared, the largest error
/// and the photocurrents' mean relative error.
fn kept_field_error(density: f64, side: f64, seed: u64, keep: f64) -> (f64, u64, u32, f64) {
    let mut unit = uniform(seed);
    let text = buoy_field(density, side, &mut unit, 16);
    let exact = crowd_retinas(&text, |d| d);
    let kept = kept_retinas(&text, keep, &mut unit);
    let (mean, outputs, worst) = digital_error(&kept, &exact);
    (mean, outputs, worst, mean_relative_error(&kept, &exact))
}

/// The documented bound of kept impostors (docs/crowd.md), the far distance's with the eye
/// moved up to the keep distance since they were worked out. 5,000 fields of this generator:
/// 0.041 LSB on average, 10 above 0.1 and none above 0.130 (the fields where the far distance
/// alone is worst), none off by more than 1 LSB.
const KEPT_MEAN_LSB: f64 = 0.15;
const KEPT_MAX_LSB: u32 = 2;
const KEPT_MEAN_RELATIVE: f64 = 0.05;

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    /// The far distance's buoy fields, with the impostors kept (`crowdKeepDistance` 2 or
    /// 5 cm): worked out with each eye up to that far from where it is drawn, and turned.
    /// Within the documented bound of exact.
    #[test]
    fn kept_impostors_in_a_large_buoy_field_stay_within_their_documented_error(
        density in 1.0f64..3.0,
        side in 8.0f64..14.0,
        seed in 0u64..1_000_000,
        keep in prop::sample::select(vec![0.02f64, 0.05]),
    ) {
        let (mean, outputs, worst, relative) = kept_field_error(density, side, seed, keep);
        prop_assert!(mean <= KEPT_MEAN_LSB, "mean error {} LSB over {} outputs", mean, outputs);
        prop_assert!(worst <= KEPT_MAX_LSB, "largest error {} LSB", worst);
        prop_assert!(relative <= KEPT_MEAN_RELATIVE, "photocurrents off by {} on average", relative);
    }
}

/// A field that once broke the kept impostors' bound (0.144 LSB, as a proptest drew it): an
/// eye about 12 cm from a buoy whose body lies below the band, its lamp alone in it. The
/// lamp hid far buoys in the columns their boxes' heights were worked out in, and moved
/// across others as the eye moved. Heights are now worked out against what lies behind the
/// box alone, and which boxes a near piece hides is settled at each update.
#[test]
fn kept_impostors_behind_a_near_lamp_stay_within_their_documented_error() {
    let (mean, outputs, worst, relative) =
        kept_field_error(2.61249789874211, 9.76908581178875, 524460, 0.05);
    assert!(
        mean <= KEPT_MEAN_LSB,
        "mean error {mean} LSB over {outputs} outputs"
    );
    assert!(worst <= KEPT_MAX_LSB, "largest error {worst} LSB");
    assert!(
        relative <= KEPT_MEAN_RELATIVE,
        "photocurrents off by {relative} on average"
    );
}

/// The far distance's and the kept impostors' errors over many fields drawn as their property
/// tests draw them (density, side and seed from one seeded stream), to set and check their
/// documented bounds; run by hand: `REGATTA_FIELDS=400 cargo test --release -p regatta-tests
/// --test swarm -- --ignored --nocapture buoy_field_errors`.
#[test]
#[ignore]
fn buoy_field_errors_over_many_fields() {
    let fields: usize = std::env::var("REGATTA_FIELDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100);
    /// A setting's errors over the fields: their sum, how many above its bound, and the
    /// worst field (mean, largest output error, density, side, seed).
    #[derive(Default)]
    struct Tally {
        sum: f64,
        over: usize,
        worst: (f64, u32, f64, f64, u64),
    }
    impl Tally {
        fn add(
            &mut self,
            (mean, _, largest, _): (f64, u64, u32, f64),
            bound: f64,
            field: (f64, f64, u64),
        ) {
            self.sum += mean;
            self.over += usize::from(mean > bound);
            if mean > self.worst.0 {
                self.worst = (mean, largest, field.0, field.1, field.2);
            }
        }
        fn line(&self, fields: usize) -> String {
            let (mean, largest, density, side, seed) = self.worst;
            format!(
                "mean of means {:.4}, worst {mean:.4} LSB (largest output error {largest}, \
                 {density:.2} buoys/m², side {side:.2} m, seed {seed}), {} above the bound",
                self.sum / fields as f64,
                self.over
            )
        }
    }
    let mut unit = uniform(2026);
    let (mut far, mut kept) = (Tally::default(), Tally::default());
    for _ in 0..fields {
        let density = 1.0 + 2.0 * unit();
        let side = 8.0 + 6.0 * unit();
        let seed = (unit() * 1e6) as u64;
        let stride = if unit() < 0.5 { 1 } else { 16 };
        let keep = if unit() < 0.5 { 0.02 } else { 0.05 };
        let field = (density, side, seed);
        far.add(
            far_field_error(density, side, seed, stride),
            FAR_MEAN_LSB,
            field,
        );
        kept.add(
            kept_field_error(density, side, seed, keep),
            KEPT_MEAN_LSB,
            field,
        );
    }
    println!(
        "{fields} fields. far: {}; kept: {}",
        far.line(fields),
        kept.line(fields)
    );
}

/// Kept impostors moved past their distance are worked out again: the image is bit for bit
/// a fresh eye's there. Within it they are kept: drawn where the eye is now, they differ
/// from the fresh eye's (which works them out from there) but not by much (1.3 % of the
/// photocurrents here, 4 cm on under a bright light).
#[test]
fn kept_impostors_are_worked_out_again_once_the_eye_moves_past_their_distance() {
    let mut unit = uniform(7);
    let robots = robots_near(&mut unit, (0.5, 0.5), 10.0);
    let field: Vec<(f64, f64)> = (0..200).map(|_| (unit(), unit())).collect();
    let text = crowd_world(10.0, &robots, &field, &[], 16, 1);
    with_start_frame(&text, |compiled, scene, frame| {
        let strip = strip();
        let detail = Detail {
            crowd_distance: 0.5,
            far_distance: 5.0,
            ..Detail::new(1, 16)
        };
        let rig = &compiled.rig.robots[0];
        let eye = DVec3::new(rig.start.x, rig.floor_y + 0.05, rig.start.z);
        let heading = rig.start.heading;
        let image = |kept: &mut KeptImpostors, at: DVec3, heading: f64| {
            let mut analog = vec![0.0; PIXELS];
            scene.integrate_kept(
                frame,
                Some(0),
                at,
                heading,
                &strip,
                detail,
                kept,
                &mut analog,
            );
            analog
        };
        let mut kept = KeptImpostors::new(0.05);
        image(&mut kept, eye, heading + 0.7);
        // Past the distance: worked out again, as a fresh eye's.
        let far_off = eye + DVec3::new(0.06, 0.0, 0.0);
        assert_eq!(
            image(&mut kept, far_off, heading),
            image(&mut KeptImpostors::new(0.05), far_off, heading)
        );
        // Within it: kept, so not a fresh eye's, yet close to it.
        let near_by = far_off + DVec3::new(0.0, 0.0, 0.04);
        let (held, fresh) = (
            image(&mut kept, near_by, heading - 0.4),
            image(&mut KeptImpostors::new(0.05), near_by, heading - 0.4),
        );
        assert_ne!(held, fresh, "the kept boxes were worked out again");
        let difference: f64 = held.iter().zip(&fresh).map(|(a, b)| (a - b).abs()).sum();
        let total: f64 = fresh.iter().map(|b| b.abs()).sum();
        assert!(
            difference / total < 0.03,
            "kept boxes off by {}",
            difference / total
        );
        // Raised or lowered at all: worked out again.
        let raised = near_by + DVec3::new(0.0, 0.001, 0.0);
        assert_eq!(
            image(&mut kept, raised, heading),
            image(&mut KeptImpostors::new(0.05), raised, heading)
        );
    });
}

/// Kept impostors run the same on any number of threads (each eye keeps its own, changed
/// only by its own updates), and change the image.
#[test]
fn kept_impostors_run_the_same_on_any_number_of_threads() {
    let mut text = swarm_text(30, 5.0);
    let mut unit = uniform(44);
    for _ in 0..80 {
        let (x, z) = ((unit() - 0.5) * 4.8, (unit() - 0.5) * 4.8);
        text += &format!("Buoy {{ translation {x} 0 {z} irReflectance 1 }}\n");
    }
    let with = |setting: &str| {
        compile_text(&text.replace(
            "PanoramicTurret { lambda 5 }",
            &format!(
                "PanoramicTurret {{ lambda 5 crowdDistance 0.4 crowdFarDistance 3 {setting} }}"
            ),
        ))
    };
    let kept = with("crowdKeepDistance 0.05");
    let one = run_on_threads(&kept, 1, 40);
    assert_eq!(one, run_on_threads(&kept, 2, 40));
    assert_eq!(one, run_on_threads(&kept, 3, 40));
    assert_ne!(one, run_on_threads(&with(""), 1, 40), "nothing was kept");
}

/// A far distance runs the same on any number of threads (each thread tells the round groups
/// its grid reaches), and leaves something out.
#[test]
fn the_far_distance_runs_the_same_on_any_number_of_threads() {
    let mut text = swarm_text(30, 5.0);
    let mut unit = uniform(43);
    for _ in 0..80 {
        let (x, z) = ((unit() - 0.5) * 4.8, (unit() - 0.5) * 4.8);
        text += &format!("Buoy {{ translation {x} 0 {z} irReflectance 1 }}\n");
    }
    let with = |setting: &str| {
        compile_text(&text.replace(
            "PanoramicTurret { lambda 5 }",
            &format!("PanoramicTurret {{ lambda 5 crowdDistance 0.4 {setting} }}"),
        ))
    };
    let far = with("crowdFarDistance 1.5");
    let one = run_on_threads(&far, 1, 30);
    assert_eq!(one, run_on_threads(&far, 2, 30));
    assert_eq!(one, run_on_threads(&far, 3, 30));
    assert_ne!(
        one,
        run_on_threads(&with(""), 1, 30),
        "nothing was left out"
    );
}

/// The crowd level of detail runs the same on any number of threads (the robots' grid is
/// built by whichever viewer comes first, and must not matter).
#[test]
fn a_crowd_with_its_level_of_detail_runs_the_same_on_any_number_of_threads() {
    let text = swarm_text(40, 2.0).replace(
        "PanoramicTurret { lambda 5 }",
        "PanoramicTurret { lambda 5 crowdDistance 0.4 }",
    );
    let compiled = compile_text(&text);
    let one = run_on_threads(&compiled, 1, 40);
    assert_eq!(one, run_on_threads(&compiled, 2, 40));
    assert_eq!(one, run_on_threads(&compiled, 3, 40));
    // And it is a crowd setting: some robot's retina differs from the exact run's.
    let exact = compile_text(&swarm_text(40, 2.0));
    assert_ne!(one, run_on_threads(&exact, 1, 40), "nothing was left out");
}

/// Impostors in numbers (a buoy field, most buoys beyond the crowd distance: told by each
/// look's loop over the scene's round groups, hidden by the occlusion bins, drawn by the
/// short path against the sampled columns' running integrals) run the same on any number of
/// threads, each thread keeping its own look and bins from update to update.
#[test]
fn impostors_run_the_same_on_any_number_of_threads() {
    let mut text = swarm_text(30, 3.0).replace(
        "PanoramicTurret { lambda 5 }",
        "PanoramicTurret { lambda 5 crowdDistance 0.4 }",
    );
    let mut unit = uniform(41);
    for _ in 0..40 {
        let (x, z) = ((unit() - 0.5) * 2.8, (unit() - 0.5) * 2.8);
        text += &format!("Buoy {{ translation {x} 0 {z} irReflectance 1 }}\n");
    }
    let compiled = compile_text(&text);
    let one = run_on_threads(&compiled, 1, 30);
    assert_eq!(one, run_on_threads(&compiled, 2, 30));
    assert_eq!(one, run_on_threads(&compiled, 3, 30));
}

/// A generated swarm with retinas (the bench's kind of world, small).
fn swarm_text(robots: usize, side: f64) -> String {
    let per_row = (robots as f64).sqrt().ceil() as usize;
    let cell = side / per_row as f64;
    let mut out = format!(
        "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" basicTimeStep 32 randomSeed 7 }}\n\
         DirectionalLight {{ direction 0.3 -1 0.2 intensity 0.05 ambientIntensity 0.05 }}\n\
         Arena {{ size {side} {side} }}\n\
         Buoy {{ translation 0.03 0 0.02 irReflectance 1 }}\n"
    );
    for i in 0..robots {
        let x = -side / 2.0 + ((i % per_row) as f64 + 0.5) * cell;
        let z = -side / 2.0 + ((i / per_row) as f64 + 0.5) * cell;
        out += &format!(
            "Khepera {{ translation {x} 0 {z} rotation 0 1 0 {} name \"k{i}\" controller \"regatta\" \
             turret PanoramicTurret {{ lambda 5 }} }}\n",
            i as f64 * 0.9
        );
    }
    out
}

/// What a run leaves that a log would record.
fn fingerprint(simulation: &Simulation) -> Vec<String> {
    simulation
        .robots
        .iter()
        .map(|r| {
            let digital = r
                .panoramic
                .as_ref()
                .map(|p| format!("{:?}", p.output.digital))
                .unwrap_or_default();
            format!(
                "{:?} {:?} {:?} {:?} {} {digital}",
                (
                    r.pose.x.to_bits(),
                    r.pose.z.to_bits(),
                    r.pose.heading.to_bits()
                ),
                r.proximity,
                r.ambient,
                r.command,
                r.contacts.events
            )
        })
        .collect()
}

/// Sensing and control side by side on 1, 2 or 4 threads give the same run, bit for bit.
#[test]
fn a_swarm_runs_the_same_on_any_number_of_threads() {
    let compiled = compile_text(&swarm_text(24, 0.8));
    let one = run_on_threads(&compiled, 1, 60);
    assert_eq!(one, run_on_threads(&compiled, 2, 60));
    assert_eq!(one, run_on_threads(&compiled, 4, 60));
}

/// The fingerprint of `steps` steps, every sensor refreshed, on a pool of `threads`.
fn run_on_threads(compiled: &regatta_runtime::Compiled, threads: usize, steps: u64) -> Vec<String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            let mut simulation = Simulation::new(compiled, None).unwrap();
            simulation.sense_everything();
            simulation.run(steps);
            fingerprint(&simulation)
        })
}

/// A thousand robots packed into a small arena, driving into each other for 1000 steps: no
/// two bodies, and no body and wall, overlap by more than the documented tolerance.
#[test]
fn a_packed_thousand_never_overlaps() {
    let side = 2.0;
    let per_row = 32;
    let cell = side / per_row as f64;
    let mut text = format!(
        "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" basicTimeStep 32 }}\n\
         Arena {{ size {side} {side} }}\n"
    );
    for i in 0..1000 {
        let x = -side / 2.0 + ((i % per_row) as f64 + 0.5) * cell;
        let z = -side / 2.0 + ((i / per_row) as f64 + 0.5) * cell;
        // Fast and blind to each other half the time: they push.
        let controller = if i % 2 == 0 { "braitenberg" } else { "none" };
        text += &format!(
            "Khepera {{ translation {x:.4} 0 {z:.4} rotation 0 1 0 {:.3} name \"p{i}\" \
             controller \"{controller}\" controllerArgs \"bias=80\" }}\n",
            (i * 37 % 628) as f64 / 100.0
        );
    }
    let text = text.replace(
        "controller \"none\" controllerArgs \"bias=80\"",
        "controller \"none\"",
    );
    let compiled = compile_text(&text);
    let mut simulation = Simulation::new(&compiled, None).unwrap();
    let radius = compiled.rig.robots[0].body_radius;
    let limit = side / 2.0 - radius + PENETRATION_TOLERANCE;
    let mut worst = 0.0f64;
    for step in 0..1000 {
        simulation.step();
        if step % 100 != 99 {
            continue;
        }
        let centers: Vec<DVec2> = simulation
            .robots
            .iter()
            .map(|r| DVec2::new(r.pose.x, r.pose.z))
            .collect();
        for (a, ca) in centers.iter().enumerate() {
            worst = worst.max(ca.x.abs().max(ca.y.abs()) - (limit - PENETRATION_TOLERANCE));
            for cb in &centers[a + 1..] {
                worst = worst.max(2.0 * radius - ca.distance(*cb));
            }
        }
    }
    assert!(
        worst <= PENETRATION_TOLERANCE,
        "bodies overlap (each other or a wall) by {worst} m (tolerance {PENETRATION_TOLERANCE} m)"
    );
    // They did press on each other and on the walls.
    let pressed = simulation
        .robots
        .iter()
        .filter(|r| r.contacts.steps > 100)
        .count();
    assert!(pressed > 200, "{pressed} robots pressed for over 100 steps");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A frame prepared for crowd looks only (other robots' tucked parts not placed) gives
    /// every crowd look, with or without a far distance, the photocurrents of the full frame
    /// to the last bit.
    #[test]
    fn a_frame_for_crowd_looks_only_draws_them_as_the_full_frame_does(
        side in 0.3f64..1.6,
        robots in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, -3.2f64..3.2), 2..40),
        buoys in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0), 0..6),
        boxes in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, -3.2f64..3.2), 0..4),
    ) {
        let text = crowd_world(side, &robots, &buoys, &boxes, 1, 1);
        let compiled = compile_text(&text);
        let renderer = Renderer::new(&compiled.graph, &compiled.plan, false);
        let Renderer::Columns(scene) = &renderer else {
            panic!("an upright crowd renders by columns");
        };
        let poses = start_poses(&compiled);
        let (mut full, mut crowd_only) = (None, None);
        renderer.prepare_shared(&compiled.plan, &poses, &[], false, &mut full);
        renderer.prepare_shared(&compiled.plan, &poses, &[], true, &mut crowd_only);
        let (full, crowd_only) = (full.unwrap(), crowd_only.unwrap());
        let strip = strip();
        for (index, rig) in compiled.rig.robots.iter().enumerate() {
            let Some(TurretRig::Panoramic(turret)) = &rig.turret else {
                continue;
            };
            let eye = DVec3::new(rig.start.x, rig.floor_y + turret.height, rig.start.z);
            let base = Detail::new(turret.samples, turret.stride);
            for detail in [
                Detail { crowd_distance: 0.5, ..base },
                Detail { crowd_distance: 0.4, far_distance: 3.0, ..base },
            ] {
                let look = |frame: &ColumnFrame| {
                    let mut analog = vec![0.0; PIXELS];
                    scene.integrate_for(frame, Some(index), eye, rig.start.heading, &strip,
                        detail, &mut analog);
                    analog
                };
                let (a, b) = (look(&full), look(&crowd_only));
                for (pixel, (a, b)) in a.iter().zip(&b).enumerate() {
                    prop_assert_eq!(a.to_bits(), b.to_bits(), "retina {} pixel {}", index, pixel);
                }
            }
        }
    }
}
