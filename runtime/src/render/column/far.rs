//! Drawing impostors. Each is a box over its azimuth interval whose height is its effect on
//! the column through its centre: the sampled column nearest it in its region (what that
//! column shows kept piece by piece, `Band::profile`), or, in a strip sampled pixel by pixel,
//! the column through its own centre. The usual impostor, a buoy with its lamp, is a stack of
//! sides seen straight on, in front of everything that column shows there: its effect is its
//! sides' luminance over their angle less the column's own integral over the same span, read
//! off the running integrals the profile keeps (an arctangent per side's end). The general
//! path (`integrate/`: every piece crossed with the column and composited into its pieces,
//! two arctangents per piece met) draws any other; it cost 1,400 instructions an impostor at
//! 1000 robots, the short one about 550.

use std::cmp::Ordering;

use glam::{DVec2, DVec3};

use super::impostor::Impostor;
use super::photodiode::{nearest_index, Band, Raster, Scratch, Shown};
use super::scene::{ColumnFrame, ColumnScene};
use super::strip::Strip;
use super::sweep::{EyeObject, Look};

impl ColumnScene<'_> {
    /// Adds each visible impostor as a box over its interval: its effect on the column through
    /// its centre (its faces composited into what that column shows), times its visible share.
    /// The strip's windows are contiguous (impostors are made only then).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn draw_impostors(
        &self,
        look: &Look,
        frame: &ColumnFrame,
        strip: &Strip,
        band: f64,
        sky: f64,
        ground: f64,
        (facing, pieces, profile): (&mut Vec<u32>, &mut Vec<EyeObject>, &mut Vec<Shown>),
        scratch: &mut Scratch,
        out: &mut [f64],
    ) {
        let pixels = out.len();
        if look.impostor_order.is_empty() || pixels == 0 {
            return;
        }
        let (mut raster, (extent_lo, extent_hi)) = Raster::over(strip, out);
        let inverse_width = raster.inverse_width;
        let column_band = Band {
            tan_half: strip.tan_half_band,
            band,
            sky,
            ground,
        };
        for &index in &look.impostor_order {
            let impostor = &look.impostors[index as usize];
            if impostor.hi <= extent_lo || impostor.lo >= extent_hi {
                continue;
            }
            // What the column through its centre shows (within the strip), then its faces
            // there (its true centre).
            let centre = 0.5 * (impostor.lo + impostor.hi);
            let alpha = centre.clamp(extent_lo, extent_hi);
            let pixel = nearest_index((strip.centers[0] - alpha) * inverse_width, pixels - 1);
            let facing = look.facing_over(impostor.lo, impostor.hi, facing);
            profile.clear();
            self.profile(
                frame,
                look,
                look.turn(strip, pixel, alpha),
                facing,
                &column_band,
                scratch,
                profile,
            );
            let direction = look.turn(strip, pixel, centre);
            let effect = self.any_impostor_effect(
                frame,
                look,
                direction,
                impostor,
                (profile, pieces),
                &column_band,
                scratch,
            );
            if effect != 0.0 {
                raster.add(impostor.lo, impostor.hi, effect * impostor.visible, 0.0);
            }
        }
    }

    /// [`ColumnScene::impostor_effect`], by `far.rs`'s short way where its faces have fast
    /// shading.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn any_impostor_effect(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        impostor: &Impostor,
        (profile, pieces): (&[Shown], &mut Vec<EyeObject>),
        band: &Band,
        scratch: &mut Scratch,
    ) -> f64 {
        fast_effect(frame, impostor, look.eye.y, direction, profile, band).unwrap_or_else(|| {
            self.impostor_effect(
                frame,
                look,
                direction,
                impostor,
                (profile, pieces),
                band,
                scratch,
            )
        })
    }
}

/// Most pieces a stack drawn here has (a buoy and its lamp: two); more take the general path.
const MOST_PIECES: usize = 4;

/// The change in the band's mean along `direction` (through the impostor's centre) when its
/// faces join what `profile` shows, for the usual impostor: pieces stacked on one round
/// footprint (a buoy and its lamp), each showing its side (every cap hidden by the piece
/// beside it, or facing away), in front of every piece of `profile` they span. Then the
/// stack's sides are contiguous bands of tan-elevation, each with one luminance (its normal
/// faces the eye), and they replace the profile's integral over their span, read off its
/// running integrals: an arctangent per side's end and no compositing. `None` for anything
/// else, which the general path draws.
pub(super) fn fast_effect(
    frame: &ColumnFrame,
    impostor: &Impostor,
    eye_y: f64,
    direction: DVec2,
    profile: &[Shown],
    band: &Band,
) -> Option<f64> {
    #[cfg(test)]
    if tests::GENERAL_ONLY.with(std::cell::Cell::get) {
        return None;
    }
    let first = impostor.first_static as usize;
    let pieces = frame.statics.get(first..first + impostor.pieces as usize)?;
    if pieces.len() > MOST_PIECES || profile.is_empty() {
        return None;
    }
    // An impostor lies beyond the crowd distance: the eye is outside its footprint.
    let (t_in, t_out) = (
        impostor.distance - impostor.radius,
        impostor.distance + impostor.radius,
    );
    if t_in.partial_cmp(&0.0) != Some(Ordering::Greater) {
        return None;
    }
    let inv_in = 1.0 / t_in;
    let normal = DVec3::new(-direction.x, 0.0, -direction.y);
    // The sides' tan-elevations from the bottom up, and their luminances.
    let mut ends = [0.0; MOST_PIECES + 1];
    let mut luminances = [0.0; MOST_PIECES];
    let mut below: Option<(f64, f64, bool)> = None;
    for (k, piece) in pieces.iter().enumerate() {
        let fast = frame.fast_shade(piece.primitive as u32)?;
        let (y0, y1) = (piece.y0 - eye_y, piece.y1 - eye_y);
        if !piece.side || y0.partial_cmp(&y1) != Some(Ordering::Less) {
            return None;
        }
        match below {
            None => {
                // A bottom seen from below would show under the stack.
                if piece.bottom && y0 > 0.0 {
                    return None;
                }
            }
            Some((y0_below, y1_below, top_below)) => {
                // Stacked on the piece below (to rounding), each hiding the other's cap: a
                // top below the eye spans [y/t_in, y/t_out], under this side's top; a bottom
                // above it, [y/t_out, y/t_in], over the lower side's foot.
                if (y0 - y1_below).abs() > 1e-12 * (1.0 + y0.abs()) {
                    return None;
                }
                if top_below && y1_below < 0.0 && y1 * t_out < y1_below * t_in {
                    return None;
                }
                if piece.bottom && y0 > 0.0 && y0_below * t_out > y0 * t_in {
                    return None;
                }
            }
        }
        ends[k] = y0 * inv_in;
        luminances[k] = fast.luminance(normal);
        below = Some((y0, y1, piece.top));
    }
    let (_, y_top, top_cap) = below?;
    // A top below the eye would show over the stack.
    if top_cap && y_top < 0.0 {
        return None;
    }
    let n = pieces.len();
    ends[n] = y_top * inv_in;
    let tan_half = band.tan_half;
    let clip = |x: f64| x.max(-tan_half).min(tan_half);
    let (lo, hi) = (clip(ends[0]), clip(ends[n]));
    if lo.partial_cmp(&hi) != Some(Ordering::Less) {
        return Some(0.0);
    }
    // Every piece of the profile the stack spans lies behind it.
    let start = profile
        .partition_point(|p| p.t1 <= lo)
        .min(profile.len() - 1);
    let mut end = start;
    for (k, piece) in profile.iter().enumerate().skip(start) {
        if piece.t0 >= hi {
            break;
        }
        if piece.depth.partial_cmp(&t_in) != Some(Ordering::Greater) {
            return None;
        }
        end = k;
    }
    // Consecutive sides share ends: the last angle is kept.
    let mut last = (f64::NAN, 0.0);
    let mut angle = |x: f64| {
        if x != last.0 {
            last = (x, band.angle(x));
        }
        last.1
    };
    let a_lo = angle(lo);
    let (mut a0, mut sum) = (a_lo, 0.0);
    for k in 0..n {
        let a1 = angle(clip(ends[k + 1]));
        if a1 > a0 {
            sum += luminances[k] * (a1 - a0);
            a0 = a1;
        }
    }
    let a_hi = angle(hi);
    let (first, last_piece) = (&profile[start], &profile[end]);
    let behind = (last_piece.sum0 + last_piece.luminance * (a_hi - last_piece.a0))
        - (first.sum0 + first.luminance * (a_lo - first.a0));
    Some((sum - behind) / band.band)
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::super::Poses;
    use super::*;
    use crate::render::Detail;
    use crate::retina::{pixel_azimuth, HALF_BAND, PIXELS, PIXEL_WIDTH};
    use crate::Compiled;
    use glam::DVec3;

    thread_local! {
        /// Every impostor by the general path (a test's switch).
        pub(super) static GENERAL_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
        /// Every round group told, the far distance's grid unused (a test's switch).
        pub(in super::super) static EVERY_ROUND: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// The short path draws the same impostors as the general one: random buoy fields (most
    /// buoys beyond the crowd distance, some near), eyes anywhere, strips sampled pixel by
    /// pixel and by regions. Not to the last bit: the column through an impostor's centre
    /// comes from a polynomial arctangent (within 2e-8 rad), along which the general path meets
    /// the footprint a little off its centre, with a normal turned by up to 2e-8·d/r (2e-6 rad
    /// at 2 m); the short path takes the face straight on. Pixels differ by at most 7e-8 of their
    /// value here, the level of detail's own error being 1e-2.
    #[test]
    fn the_short_path_draws_impostors_as_the_general_one() {
        let mut unit = crate::test_random::unit_stream(41);
        // Pixels where the impostors changed the image (a robot's turret makes the arena
        // visible; the robot itself is not placed).
        let (mut drawn, mut worst) = (0, 0.0f64);
        for field in 0..6 {
            let side = 2.0 + field as f64;
            let buoys: Vec<(f64, f64)> = (0..(30 + 20 * field))
                .map(|_| ((unit() - 0.5) * side * 0.9, (unit() - 0.5) * side * 0.9))
                .collect();
            let compiled = field_world(side, &buoys);
            let scene = ColumnScene::new(&compiled.graph, &compiled.plan);
            let frame = scene.prepare(&compiled.plan, &Poses::default(), None);
            let centers: Vec<f64> = (0..PIXELS).map(pixel_azimuth).collect();
            let strip = Strip::new(centers, PIXEL_WIDTH, HALF_BAND);
            for _ in 0..8 {
                let eye = DVec3::new(
                    (unit() - 0.5) * side * 0.8,
                    0.05,
                    (unit() - 0.5) * side * 0.8,
                );
                let heading = unit() * std::f64::consts::TAU;
                for stride in [1, 16] {
                    let detail = Detail {
                        crowd_distance: 0.5,
                        ..Detail::new(1, stride)
                    };
                    let (mut short, mut general) = (vec![0.0; PIXELS], vec![0.0; PIXELS]);
                    scene.integrate(&frame, eye, heading, &strip, detail, &mut short);
                    GENERAL_ONLY.with(|g| g.set(true));
                    scene.integrate(&frame, eye, heading, &strip, detail, &mut general);
                    GENERAL_ONLY.with(|g| g.set(false));
                    let mut without = vec![0.0; PIXELS];
                    let exact = Detail::new(1, stride);
                    scene.integrate(&frame, eye, heading, &strip, exact, &mut without);
                    for (pixel, (a, b)) in short.iter().zip(&general).enumerate() {
                        assert!(
                            (a - b).abs() <= 1e-7 * b.abs().max(1e-6),
                            "field {field}, eye {eye}, stride {stride}, pixel {pixel}: {a} vs {b}"
                        );
                        drawn += (a != &without[pixel]) as usize;
                        worst = worst.max((a - b).abs() / b.abs().max(1e-6));
                    }
                }
            }
        }
        assert!(drawn > 0);
        assert!(worst <= 1e-7, "{worst:e}");
    }

    /// A buoy field's world text: a lit arena of `side` metres with a robot (whose turret
    /// makes the arena visible; it is not placed) and buoys at `buoys`.
    fn field_world(side: f64, buoys: &[(f64, f64)]) -> Compiled {
        let mut text = format!(
            "#VRML_SIM R2023b utf8\nWorldInfo {{ coordinateSystem \"NUE\" }}\n\
             DirectionalLight {{ direction 0.3 -1 0.2 intensity 0.6 ambientIntensity 0.2 }}\n\
             Arena {{ size {side} {side} }}\n\
             Khepera {{ turret PanoramicTurret {{ }} }}\n"
        );
        for (x, z) in buoys {
            text += &format!("Buoy {{ translation {x} 0 {z} }}\n");
        }
        let source = regatta_parser::SourceText::from_bytes("t.wbt".to_owned(), text.into_bytes());
        let checked = regatta_schema::check(source, &regatta_schema::Options::default());
        assert!(!checked.has_errors(), "{}", checked.render(false));
        crate::compile(&checked.scene)
    }

    /// With a far distance, the buoys wholly beyond it are left out: the image is the one of
    /// the same field without them (to rounding: the scene's objects are numbered
    /// differently), and the grid that spares a look from telling them gives the full loop's
    /// image bit for bit.
    #[test]
    fn the_far_distance_leaves_out_the_buoys_beyond_it_and_its_grid_changes_nothing() {
        let mut unit = crate::test_random::unit_stream(43);
        let centers: Vec<f64> = (0..PIXELS).map(pixel_azimuth).collect();
        let strip = Strip::new(centers, PIXEL_WIDTH, HALF_BAND);
        let (mut left_out, mut compared) = (0, 0);
        for field in 0..6 {
            let side = 4.0 + field as f64;
            let buoys: Vec<(f64, f64)> = (0..(40 + 15 * field))
                .map(|_| ((unit() - 0.5) * side * 0.9, (unit() - 0.5) * side * 0.9))
                .collect();
            let compiled = field_world(side, &buoys);
            let scene = ColumnScene::new(&compiled.graph, &compiled.plan);
            let frame = scene.prepare(&compiled.plan, &Poses::default(), None);
            for _ in 0..6 {
                let eye = DVec3::new(
                    (unit() - 0.5) * side * 0.8,
                    0.05,
                    (unit() - 0.5) * side * 0.8,
                );
                let heading = unit() * std::f64::consts::TAU;
                let far = 0.6 + 3.0 * unit();
                for stride in [1, 16] {
                    let detail = Detail {
                        crowd_distance: 0.5,
                        far_distance: far,
                        ..Detail::new(1, stride)
                    };
                    let (mut grid, mut every) = (vec![0.0; PIXELS], vec![0.0; PIXELS]);
                    scene.integrate(&frame, eye, heading, &strip, detail, &mut grid);
                    EVERY_ROUND.with(|e| e.set(true));
                    scene.integrate(&frame, eye, heading, &strip, detail, &mut every);
                    EVERY_ROUND.with(|e| e.set(false));
                    assert_eq!(grid, every, "field {field}, eye {eye}, far {far}");
                    // The field without the buoys wholly beyond the far distance.
                    let kept: Vec<(f64, f64)> = buoys
                        .iter()
                        .copied()
                        .filter(|&(x, z)| DVec2::new(x - eye.x, z - eye.z).length() - 0.02 <= far)
                        .collect();
                    left_out += buoys.len() - kept.len();
                    let fewer = field_world(side, &kept);
                    let fewer_scene = ColumnScene::new(&fewer.graph, &fewer.plan);
                    let fewer_frame = fewer_scene.prepare(&fewer.plan, &Poses::default(), None);
                    let without_far = Detail {
                        far_distance: f64::INFINITY,
                        ..detail
                    };
                    let mut expected = vec![0.0; PIXELS];
                    fewer_scene.integrate(
                        &fewer_frame,
                        eye,
                        heading,
                        &strip,
                        without_far,
                        &mut expected,
                    );
                    for (pixel, (a, b)) in grid.iter().zip(&expected).enumerate() {
                        assert!(
                            (a - b).abs() <= 1e-9 * b.abs().max(1e-6),
                            "field {field}, eye {eye}, far {far}, pixel {pixel}: {a} vs {b}"
                        );
                    }
                    compared += 1;
                }
            }
        }
        assert!(left_out > 100 && compared == 72, "{left_out} left out");
    }
}
