//! `regatta view FILE.mcap`: a recorded run in the viewer. The log's world is compiled as
//! `replay` compiles it; its poses, wheel commands, IR readings, contacts and visits become
//! the viewer's samples, all sent at once, and the page plays them with a timeline.

use std::net::IpAddr;
use std::path::Path;

use anyhow::Context;
use regatta_view::{Event, RobotSample, Sample, Viewer};

use crate::outcome::Outcome;

/// Samples kept of a long log (every step of a shorter one): enough for a smooth timeline.
const MAX_SAMPLES: usize = 20_000;

pub fn replay(
    path: &Path,
    options: &crate::world::WorldOptions,
    bind: IpAddr,
    port: u16,
) -> anyhow::Result<Outcome> {
    let contents = crate::logs::load(path)?;
    let compiled = crate::logs::compile_embedded(&contents.run, options)?;
    let (_, robots) = regatta_evolve::record::records_from_log(&contents)
        .with_context(|| format!("cannot read the run in {}", path.display()))?;
    let robot_count = compiled.rig.robots.len();
    // Per rig robot: its records, as samples of one robot.
    let mut tracks: Vec<Vec<(f64, RobotSample)>> = vec![Vec::new(); robot_count];
    let mut events = Vec::new();
    for steps in &robots {
        // Topics carry sanitised names; the log's channel list has each robot's own.
        let topic = format!("/{}/pose", steps.name);
        let own = contents
            .topics
            .iter()
            .find(|t| t.topic == topic)
            .and_then(|t| t.robot.clone())
            .unwrap_or_else(|| steps.name.clone());
        let Some(index) = compiled.rig.robot(&own) else {
            eprintln!("warning: the log's robot '{own}' is not in its world; left out");
            continue;
        };
        let track = &mut tracks[index];
        let (mut proximity, mut touching) = ([0u16; 8], false);
        steps.for_each(contents.time_step.unwrap_or(0.0), |record| {
            proximity = record.proximity.unwrap_or(proximity);
            if record.touching && !touching {
                events.push(Event {
                    t: record.t,
                    robot: index,
                    kind: "contact",
                    buoy: None,
                });
            }
            touching = record.touching;
            for &buoy in record.entered {
                events.push(Event {
                    t: record.t,
                    robot: index,
                    kind: "visit",
                    buoy: Some(buoy),
                });
            }
            track.push((
                record.t,
                RobotSample {
                    x: record.pose.x,
                    z: record.pose.z,
                    heading: record.pose.heading,
                    wheels: record.command,
                    proximity,
                    touching,
                    retina: Vec::new(),
                },
            ));
        });
    }
    let length = tracks.iter().map(Vec::len).max().unwrap_or(0);
    anyhow::ensure!(length > 0, "{} holds no robot poses", path.display());
    let stride = length.div_ceil(MAX_SAMPLES).max(1);
    let samples: Vec<Sample> = (0..length)
        .step_by(stride)
        .chain(std::iter::once(length - 1).filter(|&l| l % stride != 0))
        .map(|k| {
            let robots: Vec<RobotSample> = (0..robot_count)
                .map(|r| {
                    let track = &tracks[r];
                    track
                        .get(k)
                        .or(track.last())
                        .map(|(_, s)| s.clone())
                        .unwrap_or_else(|| {
                            let start = compiled.rig.robots[r].start;
                            RobotSample {
                                x: start.x,
                                z: start.z,
                                heading: start.heading,
                                ..RobotSample::default()
                            }
                        })
                })
                .collect();
            let t = tracks
                .iter()
                .find_map(|track| track.get(k).map(|(t, _)| *t))
                .unwrap_or(0.0);
            Sample {
                t,
                steps: k as u64 + 1,
                robots,
            }
        })
        .collect();
    events.sort_by(|a, b| a.t.total_cmp(&b.t));
    let count = samples.len();
    let viewer = Viewer::replay(&compiled, bind, port, samples, events)
        .with_context(|| format!("cannot serve the viewer on {bind}:{port}"))?;
    println!("{}", viewer.url());
    let _ = std::io::Write::flush(&mut std::io::stdout());
    eprintln!(
        "replaying {} ({count} samples; Ctrl-C ends it)",
        path.display()
    );
    let stop = crate::signals::Stop::install();
    while !stop.requested() {
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    drop(viewer);
    Ok(stop.outcome().unwrap_or(Outcome::Clean))
}
