//! Flags and paths that are input: a number flag's own check speaks for a negative value, and
//! a log path that cannot be a file is named as the problem before anything is written.

mod common;

use common::{regatta, root, temp_dir};

fn stderr_of(args: &[&str], dir: &std::path::Path) -> (Option<i32>, String) {
    let output = regatta().args(args).current_dir(dir).output().unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn a_negative_duration_gets_the_duration_check() {
    let world = root().join("worlds/regatta.wbt");
    let world = world.to_str().unwrap();
    let (code, stderr) = stderr_of(&["run", world, "--duration", "-5"], &root());
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("--duration must be a non-negative number of seconds, found -5"),
        "{stderr}"
    );
}

#[test]
fn a_negative_whole_number_gets_the_flag_s_own_message() {
    let world = root().join("worlds/regatta.wbt");
    let world = world.to_str().unwrap();
    for (flag, value_name) in [("--steps", "STEPS"), ("--seed", "SEED")] {
        let (code, stderr) = stderr_of(&["run", world, flag, "-5"], &root());
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!("invalid value '-5' for '{flag} <{value_name}>'")),
            "{stderr}"
        );
        assert!(!stderr.contains("unexpected argument"), "{stderr}");
    }
}

#[test]
fn a_world_with_one_error_says_one_error() {
    let dir = temp_dir("flags-one-error");
    std::fs::write(
        dir.join("typo.wbt"),
        "#VRML_SIM R2023b utf8\nWorldInfo { basicTimeStep 32 }\nKhepera {\n  translaton 0 0 0\n}\n",
    )
    .unwrap();
    let (code, stderr) = stderr_of(&["run", "typo.wbt", "--steps", "3"], &dir);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("error: typo.wbt has 1 error; `regatta check` lists them"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn plot_help_tells_the_trajectory_colour_from_the_terminal_colour() {
    let output = regatta().args(["plot", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&output.stdout);
    assert!(help.contains("--trajectory-color <BY>"), "{help}");
    assert!(
        help.contains("--color <WHEN>") && help.contains("(not figures)"),
        "{help}"
    );
    assert!(
        !help.contains("COLOR_BY") && !help.contains("--color-by"),
        "{help}"
    );
}

#[test]
fn a_log_path_through_a_file_or_to_a_folder_is_named() {
    let dir = temp_dir("flags-log");
    std::fs::write(dir.join("notes.txt"), "a file").unwrap();
    std::fs::create_dir_all(dir.join("logs")).unwrap();
    let world = root().join("worlds/regatta.wbt");
    let world = world.to_str().unwrap();
    let run = |log: &str| stderr_of(&["run", world, "--steps", "5", "--log", log], &dir);

    let (code, stderr) = run("notes.txt/x.mcap");
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains(
            "cannot write the log to notes.txt/x.mcap: notes.txt is a file, not a folder"
        ),
        "{stderr}"
    );
    let (code, stderr) = run("logs");
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write the log to logs: it is a folder"),
        "{stderr}"
    );

    // A missing folder is created, and said; the run says where its log went.
    let output = regatta()
        .args(["run", world, "--steps", "5", "--log", "new/run.mcap"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("note: created the folder new for the log"),
        "{stderr}"
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("log: new/run.mcap (") && l.ends_with(" messages)")),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
