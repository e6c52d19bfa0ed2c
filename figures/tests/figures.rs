//! Every kind of figure, drawn from fixed data: PNGs compared with golden images within a
//! tolerance (font rasterisation and anti-aliasing may move a few pixels between versions),
//! and SVGs read back for their axis titles and tick labels.
//!
//! `REGATTA_BLESS=1 cargo test -p regatta-figures` rewrites the golden images;
//! `REGATTA_FIGURES_OUT=DIR` also writes every PNG and SVG there, to look at them.

use std::path::PathBuf;

use regatta_figures::{
    average_rows, render_png, render_svg, Axis, Buoy, Chart, ColorScale, ContactMark, Corner,
    Figure, Kymograph, Mark, Obstacle, Outline, Panel, Series, TimeSeries, TopView, Trace, Track,
};

fn chart() -> Chart {
    let dots = |a: f64, b: f64| -> Vec<(f64, f64)> {
        (0..5)
            .map(|i| (a * 3f64.powi(i), b / 2f64.powi(i)))
            .collect()
    };
    Chart::new(
        "retina update: time against error",
        Axis::log("time per update (µs)"),
        Axis::log("mean digital error (LSB)"),
    )
    .with(Series::markers("exact, columns", dots(2.0, 3.0)).marker_sizes(vec![6, 7, 8, 9, 10]))
    .with(Series::markers("exact, rays", dots(40.0, 1.0)))
    .with(Series::line_markers("paper", dots(10.0, 0.3)))
    .legend(Corner::UpperRight)
}

fn fitness() -> Chart {
    let generations: Vec<f64> = (0..40).map(f64::from).collect();
    Chart::new(
        "fitness over generations",
        Axis::linear("generation"),
        Axis::linear("fitness (visits per minute)"),
    )
    .with(Series::band(
        "population min–max",
        generations
            .iter()
            .map(|&g| {
                (
                    g,
                    2.0 * (1.0 - (-g / 10.0).exp()),
                    6.0 * (1.0 - (-g / 8.0).exp()) + 1.0,
                )
            })
            .collect(),
    ))
    .with(Series::line(
        "best",
        generations
            .iter()
            .map(|&g| (g, 6.0 * (1.0 - (-g / 8.0).exp()) + 1.0))
            .collect(),
    ))
    .legend(Corner::LowerRight)
}

fn top_view(color_by_time: bool) -> TopView {
    let wall = |x0: f64, z0: f64, x1: f64, z1: f64| Obstacle {
        outline: Outline::Polygon(vec![(x0, z0), (x1, z0), (x1, z1), (x0, z1)]),
    };
    let mut view = TopView::new("regatta.wbt, seed 1: 60 s");
    view.obstacles = vec![
        wall(-0.51, -0.51, 0.51, -0.5),
        wall(-0.51, 0.5, 0.51, 0.51),
        wall(-0.51, -0.5, -0.5, 0.5),
        wall(0.5, -0.5, 0.51, 0.5),
        // A box turned by 30°.
        Obstacle {
            outline: Outline::Polygon(
                [(-0.06, -0.03), (0.06, -0.03), (0.06, 0.03), (-0.06, 0.03)]
                    .iter()
                    .map(|&(x, z): &(f64, f64)| {
                        let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
                        (0.3 + c * x - s * z, 0.3 + s * x + c * z)
                    })
                    .collect(),
            ),
        },
    ];
    for (k, &(x, z)) in [(0.0, -0.3), (-0.26, 0.15), (0.26, 0.15)]
        .iter()
        .enumerate()
    {
        view.obstacles.push(Obstacle {
            outline: Outline::Circle {
                center: (x, z),
                radius: 0.02,
            },
        });
        view.buoys.push(Buoy {
            center: (x, z),
            radius: 0.02,
            label: (k + 1).to_string(),
            visit_radius: Some(0.125),
        });
    }
    for (k, name) in ["khepera", "khepera_2"].iter().enumerate() {
        let poses = (0..600)
            .map(|i| {
                let t = i as f64 * 0.1;
                let a = t * 0.4 + k as f64 * 2.0;
                let r = 0.15 + 0.15 * (t * 0.07).sin().abs();
                (
                    t,
                    r * a.cos(),
                    r * a.sin(),
                    -a - std::f64::consts::FRAC_PI_2,
                )
            })
            .collect();
        view.tracks.push(Track {
            name: name.to_string(),
            poses,
            body_radius: 0.0265,
        });
    }
    view.contacts = vec![ContactMark {
        robot: 0,
        t: 12.0,
        at: (0.1, -0.2),
    }];
    view.color_by_time = color_by_time;
    view
}

fn kymograph() -> Kymograph {
    let frames: Vec<(f64, Vec<f64>)> = (0..1875)
        .map(|f| {
            let t = f as f64 * 0.032;
            let row = (0..150)
                .map(|i| {
                    let a = 120.0 - (i as f64 + 0.5) * 1.6;
                    let bearing = (t * 20.0) % 360.0 - 180.0;
                    32.0 + 28.0 * (-(a - bearing).powi(2) / 50.0).exp()
                        - 20.0 * (-(a - bearing - 8.0).powi(2) / 50.0).exp()
                })
                .collect();
            (t, row)
        })
        .collect();
    let mut k = Kymograph::new(
        "khepera: odd filter, λ = 0.3 px",
        average_rows(&frames, 600, (0.0, 60.0)),
        (0.0, 60.0),
    );
    k.value_label = "odd filter, digital (LSB)".into();
    k.value_range = (0.0, 63.0);
    k.scale = ColorScale::Diverging { center: 31.5 };
    // Visits every 9 s, and two close together (0.4 s apart): every one gets its label.
    k.marks = (0..6)
        .map(|i| Mark {
            t: 5.0 + 9.0 * i as f64,
            label: (i % 3 + 1).to_string(),
        })
        .chain([(23.4, "1"), (23.8, "2")].map(|(t, label)| Mark {
            t,
            label: label.to_string(),
        }))
        .collect();
    k.marks.sort_by(|a, b| a.t.total_cmp(&b.t));
    k
}

/// Small multiples as `regatta plot --series` draws them, in a window (10 to 50 s) of a
/// minute's data: long enough to be summarised per interval.
fn time_series() -> TimeSeries {
    // A fixed, noise-like wiggle: the same numbers on every machine.
    let wiggle = |t: f64| (t * 7919.0).sin() * (t * 104.729).cos();
    let trace = |name: &str, f: &dyn Fn(f64) -> f64| {
        Trace::new(
            name,
            (0..3000)
                .map(|i| (i as f64 * 0.02, f(i as f64 * 0.02)))
                .collect(),
        )
    };
    let pair = |place: &str, phase: f64| {
        Panel::new(
            place,
            vec![
                trace(&format!("{place} left"), &move |t| {
                    (900.0 * (-(((t + phase) % 12.0) - 6.0).powi(2)).exp() + 30.0 * wiggle(t))
                        .max(0.0)
                }),
                trace(&format!("{place} right"), &move |t| {
                    (700.0 * (-(((t + phase) % 12.0) - 8.0).powi(2)).exp() + 30.0 * wiggle(t + 1.0))
                        .max(0.0)
                }),
            ],
        )
        .range(0.0, 1023.0)
        .height(130)
    };
    let command = |t: f64| if (t % 12.0) < 1.0 { -10.0 } else { 10.0 };
    TimeSeries::new("khepera: sensors and wheels", (10.0, 50.0))
        .with(pair("front", 0.0).heading("IR proximity (0–1023)"))
        .with(pair("sides", 3.0))
        .with(
            Panel::new(
                "left",
                vec![
                    trace("left, encoders", &move |t| {
                        command(t) * (1.0 + 0.1 * wiggle(t))
                    })
                    .width(4),
                    trace("left, command", &command)
                        .steps()
                        .color(regatta_figures::style::INK)
                        .width(1)
                        .without_band(),
                ],
            )
            .heading("wheel speed (pulses/10 ms)")
            .height(170),
        )
        .with(
            Panel::new(
                "cumulative count",
                vec![
                    Trace::new(
                        "visits",
                        (0..9).map(|k| (k as f64 * 7.0, k as f64)).collect(),
                    )
                    .steps(),
                    Trace::new("contacts", vec![(0.0, 0.0), (25.0, 1.0), (50.0, 2.0)]).steps(),
                ],
            )
            .height(150),
        )
}

/// Draws a figure: its PNG bytes and its SVG text.
type Draw = Box<dyn Fn() -> (Vec<u8>, String)>;

/// Every figure kind, with a name and the axis titles its SVG must hold.
fn figures() -> Vec<(&'static str, Draw, Vec<&'static str>)> {
    fn both(figure: &impl Figure) -> (Vec<u8>, String) {
        let png = render_png(figure).expect("draws as PNG");
        let mut bytes = Vec::new();
        png.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .expect("encodes");
        (bytes, render_svg(figure).expect("draws as SVG"))
    }
    vec![
        (
            "chart",
            Box::new(|| both(&chart())),
            vec!["time per update (µs)", "mean digital error (LSB)", "paper"],
        ),
        (
            "fitness",
            Box::new(|| both(&fitness())),
            vec!["generation", "fitness (visits per minute)", "best"],
        ),
        (
            "top_view",
            Box::new(|| both(&top_view(false))),
            vec![
                "x (m)",
                "z (m)",
                "khepera",
                "khepera_2",
                "start",
                "contact began",
            ],
        ),
        (
            "top_view_time",
            Box::new(|| both(&top_view(true))),
            vec!["x (m)", "z (m)", "time (s)"],
        ),
        (
            "kymograph",
            Box::new(|| both(&kymograph())),
            vec![
                "azimuth (°, left of heading > 0)",
                "simulated time (s)",
                "odd filter, digital (LSB)",
                "khepera: odd filter, λ = 0.3 px",
            ],
        ),
        (
            "time_series",
            Box::new(|| both(&time_series())),
            vec![
                "simulated time (s)",
                "IR proximity (0–1023)",
                "wheel speed (pulses/10 ms)",
                "front left",
                "left, command",
                "each trace per 0.1 s: the line is its mean, the shading its minimum to maximum",
            ],
        ),
    ]
}

/// The text of every `<text>` element of an SVG, unescaped.
fn svg_texts(svg: &str) -> Vec<String> {
    let mut texts = Vec::new();
    let mut rest = svg;
    while let Some(start) = rest.find("<text") {
        rest = &rest[start..];
        let Some(open_end) = rest.find('>') else {
            break;
        };
        let Some(close) = rest.find("</text>") else {
            break;
        };
        texts.push(
            rest[open_end + 1..close]
                .trim()
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&"),
        );
        rest = &rest[close..];
    }
    texts
}

#[test]
fn every_figure_labels_its_axes() {
    for (name, draw, titles) in figures() {
        let (_, svg) = draw();
        let texts = svg_texts(&svg);
        for title in titles {
            assert!(
                texts.iter().any(|t| t == title),
                "{name}: no text '{title}' in the SVG (texts: {texts:?})"
            );
        }
        // Ticks: at least three numbers on each axis, so at least six.
        let numbers = texts
            .iter()
            .filter(|t| {
                !t.is_empty() && t.chars().all(|c| c.is_ascii_digit() || ".−-e".contains(c))
            })
            .count();
        assert!(
            numbers >= 6,
            "{name}: only {numbers} tick labels in {texts:?}"
        );
        assert!(
            !svg.contains("regatta-raster"),
            "{name}: a raster marker was left in the SVG"
        );
    }
}

#[test]
fn figures_match_their_golden_images() {
    let golden = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let bless = std::env::var_os("REGATTA_BLESS").is_some();
    let out = std::env::var_os("REGATTA_FIGURES_OUT").map(PathBuf::from);
    let mut failures = Vec::new();
    for (name, draw, _) in figures() {
        let (png, svg) = draw();
        if let Some(out) = &out {
            std::fs::create_dir_all(out).unwrap();
            std::fs::write(out.join(format!("{name}.png")), &png).unwrap();
            std::fs::write(out.join(format!("{name}.svg")), &svg).unwrap();
        }
        let path = golden.join(format!("{name}.png"));
        if bless {
            std::fs::write(&path, &png).unwrap();
            continue;
        }
        let actual = image::load_from_memory(&png).unwrap().to_rgb8();
        let expected = match image::open(&path) {
            Ok(image) => image.to_rgb8(),
            Err(error) => {
                failures.push(format!("{name}: cannot read {}: {error}", path.display()));
                continue;
            }
        };
        if actual.dimensions() != expected.dimensions() {
            failures.push(format!(
                "{name}: {:?} pixels, the golden image {:?}",
                actual.dimensions(),
                expected.dimensions()
            ));
            continue;
        }
        // Mean difference per channel, and the share of pixels that differ visibly.
        let (mut sum, mut visible) = (0u64, 0usize);
        for (a, e) in actual.pixels().zip(expected.pixels()) {
            let d: u32 = (0..3)
                .map(|c| (a[c] as i32 - e[c] as i32).unsigned_abs())
                .sum();
            sum += d as u64;
            if d > 96 {
                visible += 1;
            }
        }
        let pixels = (actual.width() * actual.height()) as f64;
        let mean = sum as f64 / (3.0 * pixels);
        let share = visible as f64 / pixels;
        if mean > 1.5 || share > 0.005 {
            failures.push(format!(
                "{name}: mean difference {mean:.3} per channel, {:.3} % of pixels differ visibly",
                share * 100.0
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{}\n(REGATTA_BLESS=1 rewrites the golden images)",
        failures.join("\n")
    );
}

#[test]
fn a_time_series_shows_its_window_only() {
    let texts = svg_texts(&render_svg(&time_series()).unwrap());
    // The time axis runs from 10 to 50 s: its ticks say so, and nothing outside.
    for tick in ["10", "20", "30", "40", "50"] {
        assert!(
            texts.iter().any(|t| t == tick),
            "no tick {tick} in {texts:?}"
        );
    }
    assert!(!texts.iter().any(|t| t == "60"), "{texts:?}");
    // Few points: drawn point by point, and the note says so.
    let short = TimeSeries::new("short", (0.0, 10.0)).with(Panel::new(
        "value",
        vec![Trace::new(
            "a",
            (0..100).map(|i| (i as f64 * 0.1, 1.0)).collect(),
        )],
    ));
    assert_eq!(short.summary_interval(), None);
    let texts = svg_texts(&render_svg(&short).unwrap());
    assert!(texts.iter().any(|t| t == "every sample drawn"), "{texts:?}");
}

#[test]
fn every_kymograph_mark_is_labelled_outside_the_picture() {
    let figure = kymograph();
    let svg = render_svg(&figure).unwrap();
    let labels = svg_texts(&svg)
        .into_iter()
        .filter(|t| ["1", "2", "3"].contains(&t.as_str()))
        .count();
    assert_eq!(labels, figure.marks.len(), "{svg}");
}

#[test]
fn a_figure_written_to_a_missing_folder_is_an_error() {
    let error = regatta_figures::save(
        &chart(),
        std::path::Path::new("/nonexistent-folder/chart.png"),
        regatta_figures::Format::Png,
    )
    .unwrap_err();
    assert!(
        error.to_string().contains("/nonexistent-folder/chart.png"),
        "{error}"
    );
}
