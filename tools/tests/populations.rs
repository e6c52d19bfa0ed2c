//! Populations end to end: `run --json` against its documented schema, a fitness from a log
//! equal to the live one, `batch` and `evolve` the same for any `-j`, a resumed evolution
//! equal to an uninterrupted one, and a short evolution that improves.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn regatta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regatta"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_owned()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("regatta-pop-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stdout_of(args: &[&str]) -> String {
    let output = regatta().args(args).current_dir(root()).output().unwrap();
    assert!(
        output.status.success(),
        "regatta {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

/// Checks `value` against the keywords docs/run.schema.json uses (type, required,
/// properties with no others, items, enum, minimum), and that an object's keys come in the
/// order its properties are listed.
fn validate(value: &Value, schema: &Value, at: &str) {
    if let Some(types) = schema.get("type") {
        let names: Vec<&str> = match types {
            Value::String(t) => vec![t.as_str()],
            Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
            _ => vec![],
        };
        let fits = names.iter().any(|t| match *t {
            "object" => value.is_object(),
            "array" => value.is_array(),
            "string" => value.is_string(),
            "number" => value.is_number(),
            "integer" => value.is_u64() || value.is_i64(),
            "boolean" => value.is_boolean(),
            "null" => value.is_null(),
            _ => false,
        });
        assert!(fits, "{at}: {value} is not {names:?}");
    }
    if let (Some(allowed), Some(text)) = (schema.get("enum"), value.as_str()) {
        assert!(
            allowed.as_array().unwrap().iter().any(|a| a == text),
            "{at}: {text}"
        );
    }
    if let (Some(minimum), Some(number)) = (schema.get("minimum"), value.as_f64()) {
        assert!(
            number >= minimum.as_f64().unwrap(),
            "{at}: {number} < {minimum}"
        );
    }
    if let (Some(properties), Some(object)) = (schema.get("properties"), value.as_object()) {
        let properties = properties.as_object().unwrap();
        for required in schema["required"].as_array().unwrap() {
            let key = required.as_str().unwrap();
            assert!(object.contains_key(key), "{at}: {key} is missing");
        }
        let order: Vec<usize> = object
            .keys()
            .map(|k| {
                properties
                    .keys()
                    .position(|p| p == k)
                    .unwrap_or_else(|| panic!("{at}: {k} is not in the schema"))
            })
            .collect();
        assert!(
            order.windows(2).all(|w| w[0] < w[1]),
            "{at}: keys out of order"
        );
        for (key, inner) in object {
            validate(inner, &properties[key], &format!("{at}.{key}"));
        }
    }
    if let (Some(items), Some(array)) = (schema.get("items"), value.as_array()) {
        for (i, item) in array.iter().enumerate() {
            validate(item, items, &format!("{at}[{i}]"));
        }
    }
}

#[test]
fn run_json_follows_its_schema_and_a_log_gives_the_live_fitness() {
    let schema: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("docs/run.schema.json")).unwrap(),
    )
    .unwrap();
    let dir = temp_dir("json");
    for (world, fitness) in [
        ("worlds/regatta.wbt", "regatta"),
        ("worlds/avoidance.wbt", "avoidance"),
        ("worlds/regatta_two.wbt", "phototaxis:range=0.3"),
    ] {
        let log = dir.join("run.mcap");
        let text = stdout_of(&[
            "run",
            world,
            "--duration",
            "40",
            "--json",
            "--fitness",
            fitness,
            "--log",
            log.to_str().unwrap(),
        ]);
        let value: Value = serde_json::from_str(&text).unwrap();
        validate(&value, &schema, world);
        // The same fitness from the log's channels, to the last bit.
        let live = &value["fitness"]["value"];
        let from_log = stdout_of(&[
            "log",
            "fitness",
            log.to_str().unwrap(),
            "--fitness",
            fitness,
        ]);
        let first = from_log.lines().next().unwrap();
        let logged: Value = serde_json::from_str(first.split_whitespace().nth(1).unwrap()).unwrap();
        assert_eq!(live, &logged, "{world} {fitness}: {from_log}");
        // The log answers "when did it reach buoy 2".
        let csv = dir.join("csv");
        stdout_of(&[
            "log",
            "export",
            log.to_str().unwrap(),
            "--csv",
            csv.to_str().unwrap(),
        ]);
        if world.contains("regatta") {
            let visits = std::fs::read_to_string(csv.join("visits.csv")).unwrap();
            assert!(
                visits.starts_with("step,t_ns,t,robot,buoy,name,visits\n"),
                "{visits}"
            );
            let rows = visits.lines().count() - 1;
            assert_eq!(rows, value["robots"][0]["visits"].as_array().unwrap().len());
        }
    }
    // The avoidance world's robot touches things: contacts say with what.
    let text = stdout_of(&["run", "worlds/avoidance.wbt", "--duration", "30", "--json"]);
    let value: Value = serde_json::from_str(&text).unwrap();
    let with = &value["robots"][0]["contacts"]["with"];
    assert!(
        with.as_array()
            .unwrap()
            .iter()
            .all(|w| w["obstacle"].is_string()),
        "{with}"
    );
}

#[test]
fn batch_rows_are_the_same_for_any_thread_count() {
    for format in ["--json", "--csv"] {
        let rows = |jobs: &str| {
            stdout_of(&[
                "batch",
                "worlds/regatta.wbt",
                "--seeds",
                "1..6",
                "--duration",
                "10",
                "-j",
                jobs,
                format,
                "--set",
                "Khepera.controllerArgs=irGain=2",
            ])
        };
        let one = rows("1");
        assert_eq!(one, rows("2"), "{format}");
        let lines = one.lines().count();
        assert_eq!(lines, if format == "--csv" { 7 } else { 6 }, "{one}");
    }
    // Seeds differ, so rows do.
    let rows = stdout_of(&[
        "batch",
        "worlds/regatta_two.wbt",
        "--seeds",
        "3,4",
        "--duration",
        "20",
    ]);
    let lines: Vec<&str> = rows.lines().collect();
    assert_ne!(
        lines[0].replace("\"seed\":3", ""),
        lines[1].replace("\"seed\":4", "")
    );
    // A bad --set is a clear error.
    let output = regatta()
        .args(["batch", "worlds/regatta.wbt", "--set", "Lamp.on=TRUE"])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("no node of type or DEF name 'Lamp'"));
}

fn evolve(out: &Path, extra: &[&str]) {
    let mut args = vec![
        "evolve",
        "worlds/avoidance.wbt",
        "--fitness",
        "avoidance",
        "--population",
        "8",
        "--trials",
        "2",
        "--duration",
        "8",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    stdout_of(&args);
}

/// The outputs of an evolution written to `dir` (logs name their world by path, so runs
/// compared share one output folder).
fn outputs(dir: &Path) -> Vec<Vec<u8>> {
    ["fitness.csv", "best.wbt", "best.mcap"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect()
}

#[test]
fn evolve_is_deterministic_resumes_exactly_and_improves() {
    let dir = temp_dir("evolve");
    let a = dir.join("out");
    evolve(&a, &["--generations", "6", "-j", "1"]);
    let one = outputs(&a);
    evolve(&a, &["--generations", "6", "-j", "2"]);
    assert!(one == outputs(&a), "-j 1 and -j 2 differ");
    // Three generations, then three more from the checkpoint: as if uninterrupted.
    let checkpoint = dir.join("checkpoint");
    evolve(
        &a,
        &[
            "--generations",
            "3",
            "--checkpoint",
            checkpoint.to_str().unwrap(),
        ],
    );
    evolve(
        &a,
        &[
            "--generations",
            "6",
            "--resume",
            checkpoint.to_str().unwrap(),
        ],
    );
    assert!(one == outputs(&a), "the resumed run differs");
    // Resuming under other settings is refused.
    let output = regatta()
        .args([
            "evolve",
            "worlds/avoidance.wbt",
            "--fitness",
            "regatta",
            "--population",
            "8",
            "--trials",
            "2",
            "--duration",
            "8",
            "--resume",
            checkpoint.to_str().unwrap(),
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("--fitness differs"));
    // It improved: the best so far at the end beats the first generation's best.
    let csv = std::fs::read_to_string(a.join("fitness.csv")).unwrap();
    let best_ever = |line: &str| line.split(',').nth(5).unwrap().parse::<f64>().unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 6);
    assert!(best_ever(rows[5]) > best_ever(rows[0]), "{csv}");
    // best.wbt is canonical and runs: its network is the evolved one.
    let best = a.join("best.wbt");
    stdout_of(&["fmt", "--check", best.to_str().unwrap()]);
    let text = stdout_of(&[
        "run",
        best.to_str().unwrap(),
        "--duration",
        "8",
        "--json",
        "--fitness",
        "avoidance",
    ]);
    let value: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["robots"][0]["controller"], "neural");
    assert!(std::fs::metadata(a.join("fitness.png")).unwrap().len() > 1000);
}

/// Cyclic visits of the first robot of a `run --json` or `batch --json` row.
fn cyclic_visits(row: &str) -> u64 {
    let value: Value = serde_json::from_str(row).unwrap();
    assert_eq!(value["robots"][0]["controller"], "neural", "{row}");
    value["robots"][0]["fitness"]["regatta"]["cyclic_visits"]
        .as_u64()
        .unwrap()
}

#[test]
fn a_network_moves_into_other_arenas() {
    // batch --network-from: the avoidance network (IR only) drives the two-buoy arena's robot.
    let row = stdout_of(&[
        "batch",
        "worlds/regatta_two.wbt",
        "--network-from",
        "worlds/avoidance.wbt",
        "--seeds",
        "1",
        "--duration",
        "5",
        "--json",
    ]);
    cyclic_visits(&row);
    // evolve --world with an arena that has no network: its robot takes the first world's.
    let dir = temp_dir("transplant");
    let output = regatta()
        .args([
            "evolve",
            "worlds/avoidance.wbt",
            "--world",
            "worlds/regatta_two.wbt",
            "--fitness",
            "avoidance",
            "--population",
            "4",
            "--generations",
            "1",
            "--trials",
            "1",
            "--duration",
            "2",
            "--out",
            dir.to_str().unwrap(),
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr)
        .contains("worlds/regatta_two.wbt: its robots take worlds/avoidance.wbt's network"));
    // A world with no network to take is a clear error.
    let output = regatta()
        .args([
            "batch",
            "worlds/regatta_two.wbt",
            "--network-from",
            "worlds/regatta.wbt",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("no robot with a NeuralNetwork"));
}

#[test]
fn the_evolved_regatta_beats_the_hand_tuned_one_and_sails_an_arena_it_never_saw() {
    // worlds/regatta_evolved.wbt (examples/evolve_regatta.sh) in its own arena: at least the
    // hand-tuned controller's 70 cyclic visits in ten minutes (worlds/regatta.wbt, seed 1).
    let row = stdout_of(&[
        "run",
        "worlds/regatta_evolved.wbt",
        "--duration",
        "600",
        "--json",
    ]);
    let own = cyclic_visits(&row);
    assert!(own >= 70, "{own} cyclic visits");
    // The five-buoy arena was not among its training layouts.
    let row = stdout_of(&[
        "batch",
        "worlds/regatta_five.wbt",
        "--network-from",
        "worlds/regatta_evolved.wbt",
        "--seeds",
        "1",
        "--duration",
        "600",
        "--json",
    ]);
    let unseen = cyclic_visits(&row);
    // The hand-tuned controller makes 100 to 162 there (seeds 1 to 10).
    assert!(unseen >= 100, "{unseen} cyclic visits");
}

/// `batch` and `evolve` read worlds as `run` does: a file outside the world's project (here
/// its folder, `arena/`) only with `--allow-path`, and the limits `--limit` sets.
#[test]
fn batch_and_evolve_take_the_reading_options_of_run() {
    let dir = temp_dir("reading");
    std::fs::create_dir_all(dir.join("arena")).unwrap();
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    let world = std::fs::read_to_string(root().join("worlds/regatta_neural.wbt")).unwrap();
    std::fs::write(
        dir.join("arena/w.wbt"),
        format!("{world}Inline {{\n  url \"../parts/box.wrl\"\n}}\n"),
    )
    .unwrap();
    std::fs::write(
        dir.join("parts/box.wrl"),
        "#VRML V2.0 utf8\nTransform {\n  translation 0.3 0 0.3\n  children [\n    Shape {\n      \
         geometry Box {\n        size 0.05 0.05 0.05\n      }\n    }\n  ]\n}\n",
    )
    .unwrap();
    let output = |args: &[&str]| regatta().args(args).current_dir(&dir).output().unwrap();
    let batch = ["batch", "arena/w.wbt", "--seeds", "1..2", "--duration", "1"];
    let evolve = [
        "evolve",
        "arena/w.wbt",
        "--fitness",
        "avoidance",
        "--generations",
        "1",
        "--population",
        "4",
        "--trials",
        "1",
        "--duration",
        "1",
        "--out",
        "out",
    ];
    for command in [&batch[..], &evolve[..]] {
        let refused = output(command);
        assert!(!refused.status.success(), "{command:?} read ../parts");
        let stderr = String::from_utf8_lossy(&refused.stderr);
        assert!(
            stderr.contains("leads outside the world's project"),
            "{stderr}"
        );

        let allowed = output(&[command, &["--allow-path", "parts"]].concat());
        assert!(
            allowed.status.success(),
            "{command:?} --allow-path parts: {}",
            String::from_utf8_lossy(&allowed.stderr)
        );

        let limited =
            output(&[command, &["--allow-path", "parts", "--limit", "nodes=10"]].concat());
        assert!(!limited.status.success(), "{command:?} --limit nodes=10");
        let stderr = String::from_utf8_lossy(&limited.stderr);
        assert!(stderr.contains("more than the limit of 10"), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The weights of a world's (first) NeuralNetwork.
fn written_weights(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let start = text.find("weights [").expect("a weights field") + "weights [".len();
    let end = start + text[start..].find(']').unwrap();
    text[start..end]
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect()
}

#[test]
fn evolve_from_weights_starts_at_the_written_network() {
    let dir = temp_dir("evolve-from-weights");
    let world = root().join("worlds/regatta_evolved_varied.wbt");
    let written = written_weights(&world);
    let farthest = |extra: &[&str]| {
        let out = dir.join("out");
        let mut args = vec![
            "evolve",
            "worlds/regatta_evolved_varied.wbt",
            "--fitness",
            "regatta",
            "--population",
            "4",
            "--generations",
            "1",
            "--trials",
            "1",
            "--duration",
            "1",
            "--sigma",
            "1e-9",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        stdout_of(&args);
        let best = written_weights(&out.join("best.wbt"));
        assert_eq!(best.len(), written.len());
        best.iter()
            .zip(&written)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    // From the written weights, a tiny step size keeps every candidate on them.
    assert!(farthest(&["--from-weights"]) < 1e-6);
    // Without it, the evolution starts from random weights in −1 … 1.
    assert!(farthest(&[]) > 0.1);
}
