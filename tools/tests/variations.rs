//! Variations (`--vary`, `--variations`) and `regatta transfer` end to end: values drawn the
//! same for any number of threads, recorded in results and logs, a varied log that replays,
//! refusals that name the flag or the file's line, and a transfer table equal to `batch`.

use std::path::Path;

mod common;

use common::{ok, regatta, root};

fn world(name: &str) -> String {
    root().join("worlds").join(name).display().to_string()
}

/// The log at `log` replays to the same bytes, and `log info` shows the `varied` line.
fn assert_replays_and_names(log: &str, varied: &str) {
    let replay = ok(&regatta()
        .args(["replay", "--verify", log])
        .output()
        .unwrap());
    assert!(replay.starts_with("OK: "), "{replay}");
    let info = ok(&regatta().args(["log", "info", log]).output().unwrap());
    assert!(info.contains(varied), "{info}");
}

/// Every kind of draw at once: a range, a jitter, a position in the arena, a heading.
const VARY: [&str; 10] = [
    "--vary",
    "DirectionalLight.intensity=0.02..0.8",
    "--vary",
    "Buoy.translation=±0.1",
    "--vary",
    "Buoy.irReflectance=0.5..1",
    "--vary",
    "Khepera.translation=arena",
    "--vary",
    "Khepera.rotation=any",
];

fn batch(world: &str, extra: &[&str]) -> String {
    ok(&regatta()
        .args(["batch", world, "--duration", "4"])
        .args(extra)
        .output()
        .unwrap())
}

#[test]
fn variations_are_drawn_the_same_for_any_thread_count_and_recorded() {
    let regatta_wbt = world("regatta.wbt");
    let one = batch(
        &regatta_wbt,
        &[&["--seeds", "1..6", "-j", "1"][..], &VARY].concat(),
    );
    let three = batch(
        &regatta_wbt,
        &[&["--seeds", "1..6", "-j", "3"][..], &VARY].concat(),
    );
    assert_eq!(one, three);
    let rows: Vec<serde_json::Value> = one
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // Three buoys each draw a position and a reflectance; one light, one robot twice.
    for row in &rows {
        assert_eq!(row["variations"].as_array().unwrap().len(), 9, "{row}");
    }
    assert_ne!(rows[0]["variations"], rows[1]["variations"]);
    // `run --json` under a seed draws what the batch's row of that seed drew, at any
    // thread count.
    for threads in ["1", "2"] {
        let run = ok(&regatta()
            .args([
                "run",
                &regatta_wbt,
                "--duration",
                "4",
                "--json",
                "--seed",
                "3",
            ])
            .args(["--threads", threads])
            .args(VARY)
            .output()
            .unwrap());
        let run: serde_json::Value = serde_json::from_str(&run).unwrap();
        assert_eq!(run["variations"], rows[2]["variations"]);
        assert_eq!(run["fitness"], rows[2]["fitness"]);
        assert_eq!(
            run["robots"][0]["final_pose"],
            rows[2]["robots"][0]["final_pose"]
        );
    }
    // CSV rows carry the drawn values as columns.
    let csv = batch(
        &regatta_wbt,
        &[&["--seeds", "1", "--csv"][..], &VARY].concat(),
    );
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("vary:Buoy[2].translation"),
        "{csv}"
    );
}

#[test]
fn drawing_moves_no_other_random_stream() {
    // A range of one value draws the world's own value: the run is the unvaried one, so
    // the draws took nothing from the simulation's streams.
    let regatta_wbt = world("regatta.wbt");
    let plain = batch(&regatta_wbt, &["--seeds", "1..3", "--csv"]);
    let varied = batch(
        &regatta_wbt,
        &[
            "--seeds",
            "1..3",
            "--csv",
            "--vary",
            "DirectionalLight.intensity=0.05..0.05",
        ],
    );
    // The varied rows end with the drawn value's column.
    let varied: Vec<&str> = varied
        .lines()
        .skip(1)
        .map(|l| l.rsplit_once(',').unwrap().0)
        .collect();
    assert_eq!(plain.lines().skip(1).collect::<Vec<_>>(), varied);
}

#[test]
fn a_varied_runs_log_replays_and_names_its_values() {
    let dir = common::temp_dir("variations-log");
    let log = dir.join("varied.mcap");
    let log_arg = log.display().to_string();
    let output = ok(&regatta()
        .args([
            "run",
            &world("regatta.wbt"),
            "--duration",
            "6",
            "--seed",
            "7",
        ])
        .args(["--log", &log_arg])
        .args(VARY)
        .output()
        .unwrap());
    assert!(
        output.contains("varied Khepera[1].rotation = 0 1 0 "),
        "{output}"
    );
    assert_replays_and_names(&log_arg, "varied:       Buoy[3].irReflectance = ");
    std::fs::remove_dir_all(dir).ok();
}

fn refusal(args: &[&str]) -> String {
    let output = regatta()
        .args([
            "batch",
            &world("regatta.wbt"),
            "--seeds",
            "1",
            "--duration",
            "1",
        ])
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_ne!(output.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

#[test]
fn refused_variations_name_their_flag_or_file_line() {
    for (flag, says) in [
        ("Buoy.translation=1..0", "the range 1..0 is empty"),
        ("Buoy.translation", "expected NODE.FIELD=SPEC"),
        ("Buoy.translation=wide", "is not a range LO..HI"),
        (
            "Rock.translation=±0.1",
            "no node of type or DEF name 'Rock'",
        ),
        (
            "Buoy.colour=0..1",
            "Unknown 'colour' parameter in Buoy PROTO",
        ),
        ("Buoy.translation=0..1", "the varied world does not check"),
        ("Buoy.radius=±0.01", "does not write 'radius'"),
        ("Khepera.rotation=arena", "'rotation' is not a position"),
        // Every value of a choice is checked, not only those a trial happens to draw.
        (
            "Buoy.lampLight=TRUE|maybe",
            "Expected boolean value, found 'maybe'",
        ),
        // A buoy thrown out of the arena on every draw: refused after the draws, not kept.
        (
            "Buoy.translation=±5",
            "draws for seed 1 all broke the world",
        ),
    ] {
        let stderr = refusal(&["--vary", flag]);
        assert!(
            stderr.contains(&format!("--vary '{flag}'")),
            "{flag}: {stderr}"
        );
        assert!(stderr.contains(says), "{flag}: {stderr}");
    }
    let dir = common::temp_dir("variations-file");
    let file = dir.join("conditions.toml");
    std::fs::write(
        &file,
        "# light\n[DirectionalLight]\nintensity = \"0.02..0.8\"\n\n[Buoy]\nradius = \"wide\"\n",
    )
    .unwrap();
    let path = file.display().to_string();
    let stderr = refusal(&["--variations", &path]);
    assert!(
        stderr.contains(&format!("{path}:6:1: 'wide' is not a range")),
        "{stderr}"
    );
    std::fs::write(&file, "[Buoy]\ntranslation = \"±0.05\"\nwall = \"0..1\"\n").unwrap();
    let stderr = refusal(&["--variations", &path]);
    assert!(
        stderr.contains(&format!("{path}:3:1: the varied world does not check")),
        "{stderr}"
    );
    std::fs::write(&file, "[Buoy\n").unwrap();
    let stderr = refusal(&["--variations", &path]);
    assert!(stderr.contains(&format!("{path}:1:")), "{stderr}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_robot_drawn_into_a_buoy_is_drawn_again() {
    // Anywhere in the arena often lands on or beside a buoy; every accepted start is clear
    // of them (the robot's radius plus the buoy's).
    let out = batch(
        &world("regatta.wbt"),
        &["--seeds", "1..40", "--vary", "Khepera.translation=arena"],
    );
    let buoys = [(0.0, -0.3), (-0.26, 0.15), (0.26, 0.15)];
    for line in out.lines() {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        let value = row["variations"][0]["value"].as_str().unwrap();
        let n: Vec<f64> = value.split(' ').map(|x| x.parse().unwrap()).collect();
        for (bx, bz) in buoys {
            let d = ((n[0] - bx).powi(2) + (n[2] - bz).powi(2)).sqrt();
            assert!(d > 0.02 + 0.0275, "{value} is inside a buoy");
        }
        assert!(n[0].abs() < 0.5 && n[2].abs() < 0.5, "{value}");
    }
}

fn runs_csv(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("runs.csv")).unwrap();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    reader
        .records()
        .map(|r| r.unwrap().iter().map(str::to_owned).collect())
        .collect()
}

#[test]
fn transfer_equals_the_batches_it_stands_for() {
    let dir = common::temp_dir("transfer");
    let out = dir.display().to_string();
    let (hand, evolved) = (world("regatta.wbt"), world("regatta_evolved.wbt"));
    let wide = world("regatta_wide.wbt");
    let layout = format!("wide: world={wide}");
    let table = ok(&regatta()
        .args([
            "transfer",
            &hand,
            &evolved,
            "--seeds",
            "1..3",
            "--duration",
            "15",
        ])
        .args(["--condition", "bright: DirectionalLight.intensity=0.8"])
        .args(["--condition", &layout])
        .args([
            "--condition",
            "moved: Buoy.translation=±0.05; Buoy.irReflectance=0.5",
        ])
        .args(["--out", &out, "--format", "svg"])
        .output()
        .unwrap());
    assert!(
        table.contains("bright") && table.contains("moved"),
        "{table}"
    );
    assert!(dir.join("transfer.svg").exists() && dir.join("table.csv").exists());
    let runs = runs_csv(&dir);
    assert_eq!(runs.len(), 2 * 3 * 3);
    let cell = |controller: &str, condition: &str| -> Vec<(String, String)> {
        runs.iter()
            .filter(|r| r[0] == controller && r[1] == condition)
            .map(|r| (r[3].clone(), r[4].clone()))
            .collect()
    };
    let from_batch = |world: &str, extra: &[&str]| -> Vec<(String, String)> {
        let csv = ok(&regatta()
            .args([
                "batch",
                world,
                "--seeds",
                "1..3",
                "--duration",
                "15",
                "--csv",
            ])
            .args(extra)
            .output()
            .unwrap());
        let mut reader = csv::Reader::from_reader(csv.as_bytes());
        reader
            .records()
            .map(|r| {
                let r = r.unwrap();
                (r[5].to_owned(), r[6].to_owned())
            })
            .collect()
    };
    for controller in [&hand, &evolved] {
        assert_eq!(
            cell(controller, "bright"),
            from_batch(controller, &["--set", "DirectionalLight.intensity=0.8"])
        );
        assert_eq!(
            cell(controller, "moved"),
            from_batch(
                controller,
                &[
                    "--set",
                    "Buoy.irReflectance=0.5",
                    "--vary",
                    "Buoy.translation=±0.05"
                ]
            )
        );
    }
    assert_eq!(
        cell(&evolved, "wide"),
        from_batch(&wide, &["--network-from", &evolved])
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn evolution_with_variations_is_the_same_at_any_jobs_and_logs_its_trial_as_drawn() {
    let dir = common::temp_dir("variations-evolve");
    let evolve = |jobs: &str| {
        let out = dir.join(format!("j{jobs}"));
        ok(&regatta()
            .args([
                "evolve",
                &world("regatta_neural.wbt"),
                "--fitness",
                "regatta",
            ])
            .args(["--generations", "2", "--population", "4", "--trials", "2"])
            .args(["--duration", "3", "--seed", "2", "-j", jobs])
            .args(["--out", &out.display().to_string()])
            .args(["--vary", "DirectionalLight.intensity=0.02..0.8"])
            .args(["--vary", "Khepera.rotation=any"])
            .output()
            .unwrap());
        out
    };
    let (one, two) = (evolve("1"), evolve("2"));
    // The variations reach the candidates' trials: without them the evolution differs.
    let plain = dir.join("plain");
    ok(&regatta()
        .args([
            "evolve",
            &world("regatta_neural.wbt"),
            "--fitness",
            "regatta",
        ])
        .args(["--generations", "2", "--population", "4", "--trials", "2"])
        .args(["--duration", "3", "--seed", "2", "-j", "2"])
        .args(["--out", &plain.display().to_string()])
        .output()
        .unwrap());
    let history = |dir: &Path| std::fs::read_to_string(dir.join("fitness.csv")).unwrap();
    assert_ne!(history(&one), history(&plain));
    // best.mcap names its folder, so it differs by that; its messages replay below.
    for file in ["fitness.csv", "best.wbt"] {
        let same = std::fs::read(one.join(file)).unwrap() == std::fs::read(two.join(file)).unwrap();
        assert!(same, "{file} differs between -j 1 and -j 2");
    }
    let log = one.join("best.mcap").display().to_string();
    assert_replays_and_names(&log, "varied:       Khepera[1].rotation = 0 1 0 ");
    std::fs::remove_dir_all(dir).ok();
}

/// Two or three of regatta.wbt's three buoys, each kept one with its film drawn.
const COUNT: [&str; 4] = [
    "--vary",
    "Buoy.count=2..3",
    "--vary",
    "Buoy.irReflectance=0.5|1",
];

#[test]
fn a_count_keeps_that_many_nodes_drawn_from_the_seed() {
    let out = batch(
        &world("regatta.wbt"),
        &[&["--seeds", "1..12"][..], &COUNT].concat(),
    );
    let mut kept_two = 0;
    for line in out.lines() {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        let drawn = row["variations"].as_array().unwrap();
        assert_eq!(drawn[0]["node"], "Buoy");
        assert_eq!(drawn[0]["field"], "count");
        let value = drawn[0]["value"].as_str().unwrap();
        let (count, rest) = value.split_once(" of 3: ").expect(value);
        let count: usize = count.parse().unwrap();
        assert_eq!(rest.split(' ').count(), count, "{value}");
        // The films are drawn for the buoys that stay only.
        assert_eq!(drawn.len(), 1 + count, "{line}");
        if count == 2 {
            kept_two += 1;
        }
    }
    assert!(kept_two > 0 && kept_two < 12, "{kept_two} of 12 kept two");
    // The same seeds draw the same worlds on one thread.
    assert_eq!(
        out,
        batch(
            &world("regatta.wbt"),
            &[&["--seeds", "1..12", "-j", "1"][..], &COUNT].concat(),
        )
    );
    for (flag, says) in [
        (
            "Buoy.count=2..5",
            "the world has 3 Buoy nodes, fewer than 5 to keep",
        ),
        ("Buoy.count=1.5..2", "is not a count of nodes"),
        ("Buoy.count=±1", "a count is a range of whole numbers"),
    ] {
        let stderr = refusal(&["--vary", flag]);
        assert!(stderr.contains(says), "{flag}: {stderr}");
    }
}
