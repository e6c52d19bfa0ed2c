use super::super::super::Poses;
use super::*;

/// The hidden-edge test only drops edges that change nothing: integrating regatta.wbt's
/// arena finely with and without it gives the same images, from eyes near every corner
/// and in the middle, facing eight ways; and it does drop some (one per corner in view).
#[test]
fn hidden_wall_ends_do_not_cut_the_strip_and_change_no_image() {
    use crate::retina::{pixel_azimuth, HALF_BAND, PIXELS, PIXEL_WIDTH};
    let world = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/regatta.wbt");
    let checked = regatta_schema::check_file(&world, true).expect("regatta.wbt readable");
    let compiled = crate::compile(&checked.scene);
    let with = ColumnScene::new(&compiled.graph, &compiled.plan);
    let mut without = ColumnScene::new(&compiled.graph, &compiled.plan);
    assert!(
        with.hiders.iter().any(|h| !h.is_empty()),
        "the arena's walls meet"
    );
    without.hiders.iter_mut().for_each(Vec::clear);
    let poses = Poses::default();
    let (frame_with, frame_without) = (
        with.prepare(&compiled.plan, &poses, None),
        without.prepare(&compiled.plan, &poses, None),
    );
    let centers: Vec<f64> = (0..PIXELS).map(pixel_azimuth).collect();
    let strip = Strip::new(centers, PIXEL_WIDTH, HALF_BAND);
    let (mut dropped, mut views) = (0, 0);
    for (x, z) in [
        (0.0, 0.0),
        (0.45, 0.45),
        (-0.45, 0.4),
        (0.4, -0.45),
        (-0.3, -0.48),
    ] {
        for k in 0..8 {
            let eye = DVec3::new(x, 0.05, z);
            let heading = k as f64 * std::f64::consts::TAU / 8.0 + 0.1;
            let (a, b) = (
                with.look(&frame_with, eye, heading),
                without.look(&frame_without, eye, heading),
            );
            dropped += b.breaks.len() - a.breaks.len();
            views += 1;
            let (mut image_a, mut image_b) = (vec![0.0; PIXELS], vec![0.0; PIXELS]);
            with.integrate(
                &frame_with,
                eye,
                heading,
                &strip,
                Detail::new(512, 1),
                &mut image_a,
            );
            without.integrate(
                &frame_without,
                eye,
                heading,
                &strip,
                Detail::new(512, 1),
                &mut image_b,
            );
            // Finely, not to the last bit: a wall's foot crossing the band's edge is a kink
            // that no edge marks, and near a corner the dropped edge used to split its
            // piece. The two differ by 2e-5 at 64 samples a piece, 1e-8 at 2048: the same
            // integral. A visible edge dropped would leave a step in a piece: ~1e-3.
            for (i, (p, q)) in image_a.iter().zip(&image_b).enumerate() {
                assert!(
                    (p - q).abs() <= 1e-6 * q.abs().max(1e-3),
                    "eye ({x}, {z}) heading {k}/8 pixel {i}: {p} vs {q}"
                );
            }
        }
    }
    assert!(
        dropped >= views,
        "{dropped} edges dropped in {views} views: a corner is always in view"
    );
}

/// The crowd level of detail's floor drawn as the ground shows what crossing it in every
/// column shows (to rounding: where the floor shows in two parts, they are summed apart;
/// mostly it is one, and the same to the bit), from eyes near
/// every corner and in the middle, facing eight ways, with and without kept impostors; and
/// in the arena with a wall gone, a look whose strip meets the doorway crosses the floor in
/// each column again, to the bit.
#[test]
fn a_floor_its_walls_enclose_drawn_as_the_ground_shows_the_same() {
    use crate::retina::{pixel_azimuth, HALF_BAND, PIXELS, PIXEL_WIDTH};
    let world = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/regatta.wbt");
    let checked = regatta_schema::check_file(&world, true).expect("regatta.wbt readable");
    let compiled = crate::compile(&checked.scene);
    let with = ColumnScene::new(&compiled.graph, &compiled.plan);
    let floor = with
        .floor
        .as_ref()
        .expect("the arena's walls stand on its floor");
    assert_eq!(
        floor.walls.iter().filter(|&&wall| wall).count(),
        4,
        "four walls"
    );
    let mut without = ColumnScene::new(&compiled.graph, &compiled.plan);
    without.floor = None;
    // The arena with a doorway: one wall gone.
    let missing = floor.walls.iter().position(|&wall| wall).unwrap();
    let mut doorway = compiled.plan.clone();
    doorway
        .visible
        .retain(|&p| p != with.statics[missing].primitive);
    let gap = ColumnScene::new(&compiled.graph, &doorway);
    let mut gap_without = ColumnScene::new(&compiled.graph, &doorway);
    gap_without.floor = None;
    let poses = Poses::default();
    let frames = [&with, &without].map(|scene| scene.prepare(&compiled.plan, &poses, None));
    let gap_frames = [&gap, &gap_without].map(|scene| scene.prepare(&doorway, &poses, None));
    let centers: Vec<f64> = (0..PIXELS).map(pixel_azimuth).collect();
    let strip = Strip::new(centers, PIXEL_WIDTH, HALF_BAND);
    let detail = Detail {
        crowd_distance: 0.5,
        ..Detail::new(1, 16)
    };
    let (mut grounds, mut gapped) = (0, 0);
    for (x, z) in [
        (0.0, 0.0),
        (0.45, 0.45),
        (-0.45, 0.4),
        (0.4, -0.45),
        (-0.3, -0.48),
    ] {
        for k in 0..8 {
            let eye = DVec3::new(x, 0.05, z);
            let heading = k as f64 * std::f64::consts::TAU / 8.0 + 0.1;
            let scenes = [&with, &without, &gap, &gap_without];
            let images: Vec<Vec<f64>> = scenes
                .iter()
                .zip(frames.iter().chain(&gap_frames))
                .map(|(scene, frame)| {
                    let mut image = vec![0.0; PIXELS];
                    scene.integrate(frame, eye, heading, &strip, detail, &mut image);
                    image
                })
                .collect();
            // Kept impostors: told all around the eye, the first time.
            let kept_images = [0, 1].map(|k| {
                let mut kept = KeptImpostors::new(0.05);
                let mut image = vec![0.0; PIXELS];
                scenes[k].integrate_kept(
                    &frames[k], None, eye, heading, &strip, detail, &mut kept, &mut image,
                );
                image
            });
            let look = with_workspace(|workspace| {
                let reach = Reach {
                    crowd_distance: detail.crowd_distance,
                    extent: strip.extent().unwrap(),
                    ..Reach::EVERYTHING
                };
                with.look_into(&frames[0], None, eye, heading, reach, &mut workspace.look);
                workspace.look.ground_floor
            });
            grounds += look.is_some() as usize;
            for (a, b) in [(&images[0], &images[1]), (&kept_images[0], &kept_images[1])] {
                for (i, (p, q)) in a.iter().zip(b).enumerate() {
                    assert!(
                        (p - q).abs() <= 1e-12 * q.abs().max(1e-3),
                        "eye ({x}, {z}) heading {k}/8 pixel {i}: {p} vs {q}"
                    );
                }
            }
            // Where the strip meets the doorway (the missing wall's interval), the floor's
            // edge shows: the floor is crossed in each column again.
            let wall = &with.statics[missing];
            let interval = super::super::footprint::azimuth_interval(
                wall,
                DVec2::new(eye.x, eye.z),
                heading,
                true,
            )
            .unwrap();
            let (lo, hi) = strip.extent().unwrap();
            let wrapped = (
                super::super::footprint::wrap(interval.lo),
                super::super::footprint::wrap(interval.hi),
            );
            let meets = if wrapped.0 <= wrapped.1 {
                wrapped.0 < hi && wrapped.1 > lo
            } else {
                wrapped.0 < hi || wrapped.1 > lo
            };
            if meets {
                assert_eq!(images[2], images[3], "eye ({x}, {z}) heading {k}/8");
                gapped += 1;
            }
        }
    }
    assert_eq!(grounds, 40, "every eye is inside the arena");
    assert!(
        gapped > 0,
        "some strip crosses the missing wall's directions"
    );
}
