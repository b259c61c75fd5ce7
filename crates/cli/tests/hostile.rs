//! Every command checks its outputs before the work, never drops a result
//! it computed, and handles hostile input (odd file names, huge ids, pipes,
//! terminal escapes, implausible physics, spreadsheet formulas) with a
//! located error instead of a panic or a hang.

mod common;

use common::{assert_exit, example, listing, rtpipe_in, scratch};
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

const LIMIT: Duration = Duration::from_secs(60);

fn write(p: &Path, text: &str) {
    if let Err(e) = std::fs::write(p, text) {
        panic!("cannot write {}: {e}", p.display());
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The three commands that write after a long piece of work, each writing
/// into `dir`.
fn long_writers(dir: &str) -> Vec<Vec<String>> {
    let at = |name: &str| format!("{dir}/{name}");
    vec![
        vec![
            "design".into(),
            example("table2-design.toml"),
            "--mode".into(),
            "paper".into(),
            "--write".into(),
            at("designed.toml"),
        ],
        vec![
            "fly".into(),
            example("cleanflight.toml"),
            "--sweep".into(),
            "--per-octave".into(),
            "1".into(),
            "--write-limits".into(),
            at("limits.toml"),
        ],
        vec![
            "simulate".into(),
            example("paper-table2.toml"),
            "--plot".into(),
            at("fig9.svg"),
        ],
        vec![
            "fly".into(),
            example("cleanflight.toml"),
            "--plot".into(),
            at("plots"),
        ],
    ]
}

/// Runs the binary as the unprivileged user `nobody`, when this process
/// may switch users and `nobody` can run the binary; `None` otherwise.
fn as_nobody(dir: &Path, args: &[String]) -> Option<Output> {
    let run = |args: &[String]| {
        Command::new("setpriv")
            .args(["--reuid=nobody", "--regid=nogroup", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_rtpipe"))
            .args(args)
            .current_dir(dir)
            .output()
            .ok()
    };
    let works = run(&["--version".to_string()]).is_some_and(|o| o.status.success());
    works.then(|| run(args)).flatten()
}

#[test]
fn an_unwritable_output_directory_is_refused_before_the_work() {
    let dir = scratch("h-readonly");
    // Root's scratch directory (0755) is read-only to `nobody`.
    let Some(_) = as_nobody(&dir, &["--version".to_string()]) else {
        eprintln!("cannot run rtpipe as nobody (setpriv missing or not root): skipped");
        return;
    };
    for args in long_writers(&dir.display().to_string()) {
        let started = std::time::Instant::now();
        let Some(o) = as_nobody(&dir, &args) else {
            panic!("setpriv stopped working")
        };
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(err.contains("cannot write in"), "{args:?}: {err}");
        assert!(err.contains("Permission denied"), "{args:?}: {err}");
        // Refused at once: no report, and far less than a sweep's time.
        assert!(stdout(&o).is_empty(), "{args:?}: {}", stdout(&o));
        assert!(started.elapsed() < Duration::from_secs(30));
    }
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_output_under_a_regular_file_is_refused_before_the_work() {
    let dir = scratch("h-under-file");
    write(&dir.join("file"), "x");
    let under = dir.join("file").display().to_string();
    for args in long_writers(&under) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = rtpipe_in(&dir, &args, &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(
            err.contains("is a file, not a directory"),
            "{args:?}: {err}"
        );
        assert!(stdout(&o).is_empty(), "{args:?}: {}", stdout(&o));
    }
    assert_eq!(listing(&dir), vec!["file"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_write_that_fails_after_the_work_keeps_the_result() {
    let dir = scratch("h-keep");
    let d = dir.display().to_string();
    for (args, shows) in
        long_writers(&d)
            .into_iter()
            .zip(["verdict:", "derived chain limits", "chain", "flight:"])
    {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = rtpipe_in(&dir, &args, &[("RTPIPE_TEST_WRITE_FAILS", "1")], LIMIT);
        assert_exit(&o, 2);
        assert!(stdout(&o).contains(shows), "{args:?}: {}", stdout(&o));
        let err = stderr(&o);
        assert!(err.contains("cannot write"), "{args:?}: {err}");
        assert!(!err.contains("wrote "), "{args:?}: {err}");
        assert!(!stdout(&o).contains("wrote "), "{args:?}: {}", stdout(&o));
    }
    // Nothing half-written; only the plot directory `fly --plot` created.
    assert!(
        listing(&dir).iter().all(|f| f == "plots"),
        "{:?}",
        listing(&dir)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn output_names_near_the_longest_allowed_are_written() {
    let dir = scratch("h-long-name");
    for len in [240, 250, 255] {
        let name = format!("{}.svg", "p".repeat(len - 4));
        let o = rtpipe_in(
            &dir,
            &["simulate", &example("paper-table2.toml"), "--plot", &name],
            &[],
            LIMIT,
        );
        assert_exit(&o, 0);
        assert!(dir.join(&name).is_file(), "{len}: {}", stderr(&o));
    }
    assert_eq!(listing(&dir).len(), 3, "{:?}", listing(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(unix)]
#[test]
fn a_named_pipe_as_any_input_is_refused_not_waited_on() {
    let dir = scratch("h-fifo");
    let fifo = dir.join("pipe.toml");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if !made {
        eprintln!("no mkfifo here: skipped");
        return;
    }
    let f = fifo.display().to_string();
    let spec = example("cleanflight.toml");
    for args in [
        vec!["analyze", &f],
        vec!["simulate", &f],
        vec!["design", &f],
        vec!["fly", &spec, "--mission", &f],
        vec!["fly", &spec, "--vehicle", &f],
        vec!["fly", &spec, "--sweep", "--criterion", &f],
        vec!["run", &spec, "--mission", &f],
        vec!["import", "e2eeval", &f, "out"],
        vec!["import", "px4-ulog", &f, "out"],
    ] {
        // A blocked open would hang until the supervisor's limit fails it.
        let o = rtpipe_in(&dir, &args, &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(
            err.contains("named pipe (FIFO), not a regular file"),
            "{args:?}: {err}"
        );
        assert!(err.contains("pipe.toml"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_chain_name_that_is_a_formula_reaches_the_samples_csv_neutralised() {
    let dir = scratch("h-csv");
    let text = std::fs::read_to_string(example("paper-table2.toml")).unwrap_or_default();
    let text = text.replacen(
        "[[chain]]\npath = [\"t1\", \"t4\"]",
        "[[chain]]\nname = \"=HYPERLINK(\\\"http://x\\\",\\\"y\\\")\"\npath = [\"t1\", \"t4\"]",
        1,
    );
    assert!(text.contains("HYPERLINK"), "the example changed");
    let spec = dir.join("spec.toml");
    write(&spec, &text);
    let s = spec.display().to_string();
    let args = ["simulate", &s, "--outputs", "5", "--samples", "s.csv"];
    let o = rtpipe_in(&dir, &args, &[], LIMIT);
    assert_exit(&o, 0);
    let csv = std::fs::read_to_string(dir.join("s.csv")).unwrap_or_default();
    let first = csv.lines().nth(1).unwrap_or_default();
    assert!(
        first.starts_with("\"'=HYPERLINK(\"\"http://x\"\",\"\"y\"\")\","),
        "{first}"
    );
    assert!(!csv.lines().any(|l| l.starts_with('=')), "{csv}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Cleanflight example with its `ahrs` body renamed `body`.
fn cleanflight_with_body(dir: &Path, body: &str) -> String {
    let text = std::fs::read_to_string(example("cleanflight.toml")).unwrap_or_default();
    assert!(text.contains("body = \"ahrs\""), "the example changed");
    let spec = dir.join("spec.toml");
    write(
        &spec,
        &text.replacen("body = \"ahrs\"", &format!("body = \"{body}\""), 1),
    );
    spec.display().to_string()
}

#[test]
fn a_misspelled_body_is_refused_at_its_key_by_every_command() {
    let dir = scratch("h-body");
    let spec = cleanflight_with_body(&dir, "ahsr");
    let text = std::fs::read_to_string(&spec).unwrap_or_default();
    let line = text.lines().position(|l| l.contains("ahsr")).unwrap_or(0) + 1;
    let place = format!("spec.toml:{line}:");
    for cmd in ["analyze", "simulate", "fly", "run", "design"] {
        let o = rtpipe_in(&dir, &[cmd, &spec], &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(err.contains("unknown body \"ahsr\""), "{cmd}: {err}");
        assert!(err.contains(&place), "{cmd}: {place} not in {err}");
        assert!(err.contains("gyro, accel, ahrs, radio"), "{cmd}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_terminal_escape_in_a_body_is_shown_escaped() {
    let dir = scratch("h-body-esc");
    let spec = cleanflight_with_body(&dir, "\\u001b]0;pwned\\u0007");
    for cmd in ["fly", "run", "analyze"] {
        let o = rtpipe_in(&dir, &[cmd, &spec], &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(!err.contains('\u{1b}'), "{cmd}: raw escape in {err:?}");
        assert!(!err.contains('\u{7}'), "{cmd}: raw bell in {err:?}");
        assert!(err.contains("unknown body"), "{cmd}: {err}");
        assert!(err.contains("\\u{1b}]0;pwned"), "{cmd}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn e2eeval_yaml() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/e2eeval-golden.yaml");
    std::fs::read_to_string(&p).unwrap_or_default()
}

#[test]
fn import_refuses_an_unprintable_file_name_and_cuts_a_long_one() {
    let dir = scratch("h-e2e-name");
    let yaml = e2eeval_yaml();
    for (name, shown) in [
        ("a\u{202e}lmy.yaml", "U+202E"),
        ("a\u{200b}b.yaml", "U+200B"),
    ] {
        write(&dir.join(name), &yaml);
        let o = rtpipe_in(&dir, &["import", "e2eeval", name, "out"], &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(err.contains(shown), "{name:?}: {err}");
        assert!(!err.contains(name), "{name:?} printed raw: {err}");
        assert!(!dir.join("out").exists());
    }
    let long = format!("{}.yaml", "s".repeat(250));
    write(&dir.join(&long), &yaml);
    let o = rtpipe_in(&dir, &["import", "e2eeval", &long, "out"], &[], LIMIT);
    assert_exit(&o, 0);
    let written = listing(&dir.join("out"));
    assert_eq!(written, vec![format!("{}-ecu0.toml", "s".repeat(100))]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_five_million_digit_task_id_is_refused_briefly() {
    let dir = scratch("h-e2e-id");
    let yaml = e2eeval_yaml();
    let big = "7".repeat(5_000_000);
    assert!(yaml.contains("TaskID: 10,") && yaml.contains("[20, 5, 10]"));
    let cases = [
        (
            "task.yaml",
            yaml.replace("TaskID: 10,", &format!("TaskID: {big},")),
        ),
        (
            "chain.yaml",
            yaml.replace("[20, 5, 10]", &format!("[20, 5, {big}]")),
        ),
    ];
    for (name, text) in cases {
        write(&dir.join(name), &text);
        let o = rtpipe_in(&dir, &["import", "e2eeval", name, "out"], &[], LIMIT);
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(err.len() < 1000, "{name}: {} bytes of stderr", err.len());
        assert!(err.contains("5000000"), "{name}: {err}");
        assert!(!dir.join("out").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_implausible_drag_is_refused_at_its_line_not_flown_for_half_an_hour() {
    let dir = scratch("h-drag");
    let preset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../flight/presets/racer5.toml");
    let text = std::fs::read_to_string(preset).unwrap_or_default();
    for (key, good) in [
        ("drag_linear", "drag_linear = 0.0"),
        ("drag_angular", "drag_angular = 0.0001"),
    ] {
        assert!(text.contains(good), "the preset changed");
        let line = text.lines().position(|l| l.starts_with(good)).unwrap_or(0) + 1;
        write(
            &dir.join("p.toml"),
            &text.replace(good, &format!("{key} = 1e9")),
        );
        let started = std::time::Instant::now();
        let o = rtpipe_in(
            &dir,
            &["fly", &example("cleanflight.toml"), "--vehicle", "p.toml"],
            &[],
            LIMIT,
        );
        assert_exit(&o, 2);
        let err = stderr(&o);
        assert!(err.contains(&format!("p.toml:{line}:")), "{key}: {err}");
        assert!(err.contains(&format!("body.{key}")), "{key}: {err}");
        assert!(err.contains("damping time"), "{key}: {err}");
        assert!(started.elapsed() < Duration::from_secs(30));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
