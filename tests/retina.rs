#![allow(clippy::needless_range_loop)]
//! The EDI retina's stages against what `retina.md` and the paper say.

use regatta_runtime::retina::{
    self, calibrate_i_bda, convert, normalize, FilterKind, FilterSet, FilterSettings, PIXELS,
};
use regatta_tests::{compile_text, panoramic_at_start};

/// The stripe world with a Panoramic turret reading the raw filter.
fn stripe_world(azimuth_deg: f64, width_deg: f64, optics: &str, samples: u32) -> String {
    regatta_tests::stripe_world(
        azimuth_deg,
        width_deg,
        &format!("PanoramicTurret {{ optics \"{optics}\" samples {samples} filters [ \"raw\" ] }}"),
    )
}

fn argmax(values: &[f64]) -> usize {
    values
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)
        .unwrap()
}

#[test]
fn a_stripe_peaks_at_its_computed_pixel_in_both_modes() {
    for pixel in [3usize, 20, 37, 60, 74, 75, 90, 112, 131, 146] {
        let azimuth = 120.0 - (pixel as f64 + 0.5) * 1.6;
        for (optics, samples) in [("exact", 1), ("exact", 3), ("paper", 4)] {
            let compiled = compile_text(&stripe_world(azimuth, 1.2, optics, samples));
            let out = panoramic_at_start(&compiled, false);
            assert_eq!(
                argmax(&out.analog),
                pixel,
                "{optics} samples {samples}: stripe at {azimuth}°"
            );
        }
        // The ray-casting reference agrees.
        let compiled = compile_text(&stripe_world(azimuth, 1.2, "exact", 4));
        assert_eq!(argmax(&panoramic_at_start(&compiled, true).analog), pixel);
    }
}

#[test]
fn a_uniform_scene_gives_analog_one_everywhere() {
    // Only a background: every photodiode sees the same sky.
    let sky = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nBackground { skyColor [ 0.3 0.5 0.7 ] }\nKhepera { controller \"none\" turret PanoramicTurret { } }\n";
    // Inside a uniformly emissive round room: every photodiode sees its wall.
    let room = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nShape { appearance Appearance { material Material { diffuseColor 0 0 0 emissiveColor 0.4 0.4 0.4 } } geometry Cylinder { radius 2 height 10 } }\nKhepera { controller \"none\" turret PanoramicTurret { } }\n";
    for world in [sky, room] {
        for optics in ["exact", "paper"] {
            let compiled = compile_text(&world.replace(
                "PanoramicTurret { }",
                &format!("PanoramicTurret {{ optics \"{optics}\" }}"),
            ));
            for force_rays in [false, true] {
                let out = panoramic_at_start(&compiled, force_rays);
                assert!(!out.dark);
                for (i, a) in out.analog.iter().enumerate() {
                    assert!(
                        (a - 1.0).abs() < 1e-9,
                        "{optics} rays={force_rays}: analog[{i}] = {a}"
                    );
                }
            }
        }
    }
}

#[test]
fn scaling_every_light_leaves_digital_unchanged() {
    let world = |k: f64| {
        format!(
            "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
DirectionalLight {{ direction 0.3 -1 0.2 intensity {} ambientIntensity {} }}
PointLight {{ location 0.2 0.3 0.1 intensity {} attenuation 0 0 1 }}
Arena {{ size 1 1 }}
Buoy {{ translation 0.2 0 -0.2 color 0.9 0.2 0.1 lampColor 0 0 0 }}
Buoy {{ translation -0.3 0 0.1 color 0.1 0.8 0.2 lampColor 0 0 0 }}
Khepera {{ controller \"none\" turret PanoramicTurret {{ filters [ \"raw\" \"lowpass\" \"highpass\" \"bandpass\" \"odd\" ] }} }}
",
            0.3 * k,
            0.2 * k,
            0.5 * k
        )
    };
    let reference = panoramic_at_start(&compile_text(&world(1.0)), false);
    for k in [1e-3, 0.5, 2.0, 7.0] {
        let scaled = panoramic_at_start(&compile_text(&world(k)), false);
        assert_eq!(reference.digital, scaled.digital, "k = {k}");
    }
}

fn settings(lambda: f64) -> FilterSettings {
    let mut filters = FilterSet::default();
    for kind in FilterKind::ALL {
        filters.insert(kind);
    }
    FilterSettings {
        filters,
        lambda,
        bandpass: (lambda, 3.0 * lambda),
        bits: 6,
        i_bda: None,
    }
}

#[test]
fn filter_kernels_match_their_closed_forms() {
    for lambda in [0.5, 2.0, 5.0] {
        let a = (-1.0f64 / lambda).exp();
        let mut delta = vec![0.0; PIXELS];
        delta[75] = 1.0;
        let mut out = vec![0.0; PIXELS];
        retina::lowpass(&delta, lambda, &mut out);
        for n in 40..110usize {
            let d = (n as i64 - 75).unsigned_abs() as i32;
            let expected = (1.0 - a) / (1.0 + a) * a.powi(d);
            assert!(
                (out[n] - expected).abs() < 1e-10,
                "lowpass λ {lambda} n {n}: {} vs {expected}",
                out[n]
            );
        }
        retina::highpass(&delta, lambda, &mut out);
        assert!((out[75] - (1.0 - (1.0 - a) / (1.0 + a))).abs() < 1e-12);
        retina::odd(&delta, lambda, &mut out);
        assert!(out[75].abs() < 1e-12, "odd kernel is zero at the centre");
        for n in 40..110usize {
            let m = n as i64 - 75;
            let expected = (1.0 - a) * (m.signum() as f64) * a.powi(m.unsigned_abs() as i32);
            assert!((out[n] - expected).abs() < 1e-10, "odd λ {lambda} n {n}");
        }
        // The bandpass's wide network reaches the chain's ends when 3λ is large: check its
        // closed form where the ends are negligible (a2^75 < 1e-10).
        let (l1, l2) = (lambda, 3.0 * lambda);
        if l2 > 3.2 {
            continue;
        }
        retina::bandpass(&delta, l1, l2, &mut out);
        let (a1, a2) = ((-1.0 / l1).exp(), (-1.0 / l2).exp());
        for n in 60..90usize {
            let d = (n as i64 - 75).unsigned_abs() as i32;
            let expected =
                (1.0 - a1) / (1.0 + a1) * a1.powi(d) - (1.0 - a2) / (1.0 + a2) * a2.powi(d);
            assert!((out[n] - expected).abs() < 1e-12);
        }
        // Zero DC gain for the odd, highpass and bandpass filters, unit for the lowpass.
        let flat = vec![2.5; PIXELS];
        retina::lowpass(&flat, lambda, &mut out);
        assert!(out.iter().all(|v| (v - 2.5).abs() < 1e-12));
        retina::odd(&flat, lambda, &mut out);
        assert!(out.iter().all(|v| v.abs() < 1e-12));
    }
}

#[test]
fn fast_filters_equal_the_finite_chain_reference() {
    let mut state = 12345u64;
    let mut noise = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for lambda in [0.01, 0.3, 1.0, 2.0, 7.5, 30.0, 100.0] {
        let x: Vec<f64> = (0..PIXELS).map(|_| noise() * 3.0).collect();
        let mut fast = vec![0.0; PIXELS];
        retina::lowpass(&x, lambda, &mut fast);
        let slow = retina::reference::lowpass(&x, lambda);
        for i in 0..PIXELS {
            assert!(
                (fast[i] - slow[i]).abs() < 1e-9,
                "lowpass λ {lambda} pixel {i}: {} vs {}",
                fast[i],
                slow[i]
            );
        }
        retina::odd(&x, lambda, &mut fast);
        let slow = retina::reference::odd(&x, lambda);
        for i in 0..PIXELS {
            assert!(
                (fast[i] - slow[i]).abs() < 1e-9,
                "odd λ {lambda} pixel {i}: {} vs {}",
                fast[i],
                slow[i]
            );
        }
    }
}

#[test]
fn a_single_lit_photodiode_barely_saturates() {
    for lambda in [0.5, 2.0, 10.0] {
        let s = settings(lambda);
        for kind in FilterKind::ALL {
            let i_bda = calibrate_i_bda(kind, &s, PIXELS);
            for lit in [40usize, 75, 110] {
                let mut y = vec![0.0; PIXELS];
                y[lit] = 1.0;
                let mut analog = vec![0.0; PIXELS];
                assert!(normalize(&y, &mut analog));
                assert!((analog[lit] - 150.0).abs() < 1e-9);
                let mut filtered = vec![0.0; PIXELS];
                retina::apply(kind, &s, &analog, &mut filtered);
                let top = filtered
                    .iter()
                    .map(|&f| convert(f, i_bda, 6))
                    .max()
                    .unwrap();
                if lit == 75 {
                    assert_eq!(top, 63, "{kind:?} λ {lambda} lit {lit}");
                }
                // Barely: at the calibration pixel the filter's peak is exactly I_bda (full
                // scale, not beyond).
                let peak = filtered.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if lit == 75 {
                    assert!(
                        (peak - i_bda).abs() < 1e-9 * i_bda,
                        "{kind:?}: peak {peak} vs I_bda {i_bda}"
                    );
                } else {
                    // Away from the centre the chain's mirrored ends change the peak a little.
                    assert!(
                        (peak / i_bda - 1.0).abs() < 0.05,
                        "{kind:?} λ {lambda} lit {lit}: {peak} vs {i_bda}"
                    );
                }
            }
        }
    }
}

#[test]
fn an_all_dark_scene_gives_no_nan() {
    let dark = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nArena { }\nBuoy { lampColor 0 0 0 }\nKhepera { controller \"none\" turret PanoramicTurret { filters [ \"raw\" \"lowpass\" \"highpass\" \"bandpass\" \"odd\" ] } }\n";
    for optics in ["exact", "paper"] {
        let compiled =
            compile_text(&dark.replace("filters", &format!("optics \"{optics}\" filters")));
        for force_rays in [false, true] {
            let out = panoramic_at_start(&compiled, force_rays);
            assert!(out.dark, "a scene with no light is dark");
            assert!(out.analog.iter().all(|&a| a == 0.0));
            for (_, filtered) in &out.filtered {
                assert!(filtered.iter().all(|v| v.is_finite()));
            }
            for (_, digital) in &out.digital {
                assert!(
                    digital.iter().all(|&d| d == 32),
                    "no light reads as zero signal"
                );
            }
        }
    }
}

#[test]
fn a_world_without_vision_renders_nothing() {
    let world = "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" }\nDirectionalLight { }\nArena { }\nKhepera { controller \"braitenberg\" }\n";
    let compiled = compile_text(world);
    assert_eq!(
        compiled.plan.renderer,
        regatta_runtime::compile::plan::RendererChoice::None
    );
    assert!(compiled.plan.visible.is_empty());
    assert!(compiled
        .plan
        .skipped
        .iter()
        .any(|s| s.why.contains("no robot carries a vision device")));
}

#[test]
fn the_k213_sees_a_stripe_at_its_pixel() {
    for pixel in [5usize, 31, 32, 60] {
        let azimuth = 18.0 - (pixel as f64 + 0.5) * 36.0 / 64.0;
        let text = stripe_world(azimuth, 0.4, "exact", 1).replace(
            "turret PanoramicTurret { optics \"exact\" samples 1 filters [ \"raw\" ] }",
            "turret LinearCamera { }",
        );
        let compiled = compile_text(&text);
        use regatta_runtime::compile::rig::TurretRig;
        use regatta_runtime::optics::{LinearCamera, LinearCameraOutput, Renderer};
        let renderer = Renderer::new(&compiled.graph, &compiled.plan, false);
        let poses = regatta_tests::start_poses(&compiled);
        let view = renderer.view(&compiled.plan, &poses, 0);
        let robot = &compiled.rig.robots[0];
        let Some(TurretRig::Linear(rig)) = &robot.turret else {
            panic!()
        };
        let mut camera = LinearCamera::new(rig);
        let mut out = LinearCameraOutput::default();
        camera.update(&renderer, &view, robot.start, robot.floor_y, &mut out);
        assert_eq!(out.digital.len(), 64);
        assert_eq!(argmax(&out.analog), pixel);
        assert_eq!(*out.digital.iter().max().unwrap(), 255);
    }
}

mod stability {
    //! Numerical stability: λ from 0.01 to 10⁴ pixels, radiances from 1e-9 to 1e9, a robot
    //! 1 km from the origin. Documented tolerances: filters stay finite with DC gain within
    //! 1e-9 of its exact value; analog[] is invariant to a global scale within 1e-9 relative;
    //! moving the whole world by 1 km changes analog[] by less than 1e-6.
    use proptest::prelude::*;
    use regatta_runtime::retina::{self, normalize, PIXELS};
    use regatta_tests::{compile_text, panoramic_at_start};

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        #[test]
        fn filters_stay_finite_and_keep_their_dc_gain(exponent in -2.0f64..4.0, level in 0.0f64..1e3, values in prop::collection::vec(0.0f64..10.0, PIXELS)) {
            let lambda = 10f64.powf(exponent);
            let mut out = vec![0.0; PIXELS];
            for filter in [retina::lowpass as fn(&[f64], f64, &mut [f64]), retina::highpass, retina::odd] {
                filter(&values, lambda, &mut out);
                prop_assert!(out.iter().all(|v| v.is_finite()), "λ {}", lambda);
            }
            let flat = vec![level; PIXELS];
            retina::lowpass(&flat, lambda, &mut out);
            prop_assert!(out.iter().all(|v| (v - level).abs() <= 1e-9 * level.max(1.0)), "lowpass DC at λ {}", lambda);
            retina::odd(&flat, lambda, &mut out);
            prop_assert!(out.iter().all(|v| v.abs() <= 1e-9 * level.max(1.0)), "odd DC at λ {}", lambda);
        }

        #[test]
        fn photodetectors_are_scale_invariant_from_1e_minus_9_to_1e9(exponent in -9.0f64..9.0, values in prop::collection::vec(0.0f64..1.0, PIXELS)) {
            let scale = 10f64.powf(exponent);
            let scaled: Vec<f64> = values.iter().map(|v| v * scale).collect();
            let (mut a, mut b) = (vec![0.0; PIXELS], vec![0.0; PIXELS]);
            let lit = normalize(&values, &mut a);
            prop_assert_eq!(lit, normalize(&scaled, &mut b));
            for (x, y) in a.iter().zip(&b) {
                prop_assert!(x.is_finite() && (x - y).abs() <= 1e-9 * x.abs().max(1.0));
            }
        }
    }

    fn world(offset: f64, light_scale: f64) -> String {
        format!(
            "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
DirectionalLight {{ direction 0.3 -1 0.2 intensity {} ambientIntensity {} }}
Transform {{ translation {offset} 0 {offset} children [
  Arena {{ size 1 1 }}
  Buoy {{ translation 0.2 0 -0.2 color 0.9 0.2 0.1 lampColor 0 0 0 }}
  Buoy {{ translation -0.3 0 0.1 color 0.1 0.8 0.2 lampColor 0 0 0 }}
] }}
Khepera {{ translation {} 0 {} rotation 0 1 0 0.3 controller \"none\" turret PanoramicTurret {{ filters [ \"raw\" \"odd\" \"bandpass\" ] }} }}
",
            0.3 * light_scale,
            0.2 * light_scale,
            offset + 0.05,
            offset - 0.1
        )
    }

    #[test]
    fn a_robot_1_km_from_the_origin_sees_what_it_sees_at_the_origin() {
        let here = panoramic_at_start(&compile_text(&world(0.0, 1.0)), false);
        let far = panoramic_at_start(&compile_text(&world(1000.0, 1.0)), false);
        for (a, b) in here.analog.iter().zip(&far.analog) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
        assert_eq!(here.digital, far.digital);
    }

    #[test]
    fn lights_from_1e_minus_9_to_1e9_give_the_same_image() {
        let reference = panoramic_at_start(&compile_text(&world(0.0, 1.0)), false);
        for scale in [1e-9, 1e-3, 1e3, 1e9] {
            let scaled = panoramic_at_start(&compile_text(&world(0.0, scale)), false);
            assert!(scaled.analog.iter().all(|a| a.is_finite()));
            for (a, b) in reference.analog.iter().zip(&scaled.analog) {
                assert!(
                    (a - b).abs() <= 1e-9 * a.abs().max(1.0),
                    "scale {scale}: {a} vs {b}"
                );
            }
            assert_eq!(reference.digital, scaled.digital, "scale {scale}");
        }
    }
}

/// Paper optics point-sample both CPU renderers at the same directions, so they must agree:
/// in regatta.wbt this covers buoys standing on the floor and lamps on buoys (a cap is composited
/// at its far edge) and walls whose azimuth interval reaches past ±π behind the robot.
#[test]
fn column_renderer_equals_the_ray_caster_in_paper_optics() {
    use regatta_runtime::compile::rig::{Optics, TurretRig};
    let mut compiled = regatta_tests::compile_world("regatta.wbt");
    for robot in &mut compiled.rig.robots {
        if let Some(TurretRig::Panoramic(p)) = &mut robot.turret {
            p.optics = Optics::Paper;
            p.quantize_views = false;
        }
    }
    assert_eq!(
        compiled.plan.renderer,
        regatta_runtime::compile::plan::RendererChoice::Columns
    );
    for k in 0..8 {
        let mut turned = compiled.clone();
        turned.rig.robots[0].start.heading += k as f64 * std::f64::consts::TAU / 8.0;
        let columns = panoramic_at_start(&turned, false);
        let rays = panoramic_at_start(&turned, true);
        for (i, (a, b)) in columns.luminance.iter().zip(&rays.luminance).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
                "heading {k}/8, pixel {i}: columns {a}, rays {b}"
            );
        }
    }
}

/// A part of a robot that its own turret sees (a bright pole on its front, up through the
/// band) is drawn in its own retina, in the exact setting and the crowd's: frames keep their
/// own-view list only when some robot sees a part of its own, and this one does.
#[test]
fn a_robots_own_pole_shows_in_its_own_retina() {
    for turret in [
        "PanoramicTurret { filters [ \"raw\" ] }",
        "PanoramicTurret { filters [ \"raw\" ] crowdDistance 0.5 }",
    ] {
        let world = |pole: &str| {
            format!(
                "#VRML_SIM R2023b utf8
WorldInfo {{ coordinateSystem \"NUE\" }}
Background {{ skyColor [ 0.05 0.05 0.05 ] }}
DirectionalLight {{ direction 0 -1 0 intensity 0.5 }}
DifferentialWheels {{ controller \"none\" turret {turret} children [ {pole} ] }}
"
            )
        };
        let pole = "Transform { translation 0.04 0.06 0 children [ Shape { appearance \
                    Appearance { material Material { emissiveColor 1 1 1 } } geometry \
                    Cylinder { radius 0.004 height 0.12 } } ] }";
        let with_pole = compile_text(&world(pole));
        assert!(
            !with_pole.plan.own_visible[0].is_empty(),
            "{turret}: the pole is in the robot's own view"
        );
        let bare = panoramic_at_start(&compile_text(&world("")), false);
        let seen = panoramic_at_start(&with_pole, false);
        let brightest = |out: &regatta_runtime::optics::RetinaOutput| {
            out.luminance
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
        };
        assert!(
            brightest(&seen) > 2.0 * brightest(&bare),
            "{turret}: {} with the pole, {} without",
            brightest(&seen),
            brightest(&bare)
        );
    }
}
