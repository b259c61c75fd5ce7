//! The `rtpipe` binary end to end: exit codes, JSON shape, error messages.

mod common;

use common::{assert_exit, example, json_of, rtpipe, scratch};
use serde_json::Value;

fn analyze_json(name: &str) -> (i32, Value) {
    let o = rtpipe(&["analyze", &example(name), "--json"]);
    (o.status.code().unwrap_or(-1), json_of(&o))
}

#[test]
fn json_has_the_documented_shape() {
    let (code, v) = analyze_json("paper-table2.toml");
    // Sound reaction limits fail on the published periods: exit 1.
    assert_eq!(code, 1);
    assert_eq!(v["system"], "paper-table2");
    assert_eq!(v["time_unit"], "ms");
    let tasks = v["tasks"].as_array().map(|a| a.len());
    assert_eq!(tasks, Some(6));
    for key in [
        "name",
        "exec",
        "budget",
        "period",
        "priority",
        "cpu",
        "response_time",
    ] {
        assert!(v["tasks"][0].get(key).is_some(), "task key {key}");
    }
    let s = &v["schedulability"];
    assert_eq!(s["test"], "liu-layland");
    assert_eq!(s["schedulable"], true);
    assert!(s["utilization"].as_f64().is_some() && s["bound"].as_f64().is_some());
    let chains = v["chains"].as_array().cloned().unwrap_or_default();
    // One entry per chain and metric.
    assert_eq!(chains.len(), 8);
    let c0 = &chains[0];
    assert_eq!(c0["path"], serde_json::json!(["t1", "t4"]));
    assert_eq!(c0["metric"], "reaction");
    assert_eq!(c0["limit"], 10.0);
    assert_eq!(c0["paper"], 10.9);
    assert_eq!(c0["sound"], 14.3);
    assert_eq!(c0["ok"], false);
    assert_eq!(c0["from_event"]["paper"], 20.9);
    assert!(c0["from_event"]["sound"].as_f64().is_some());
}

#[test]
fn exit_zero_when_everything_holds() {
    let (code, v) = analyze_json("paper-table3.toml");
    assert_eq!(code, 0);
    assert_eq!(v["ok"], true);
    assert_eq!(v["chains"][0]["limit"], Value::Null);
}

#[test]
fn cleanflight_in_microseconds() {
    let (code, v) = analyze_json("cleanflight.toml");
    assert_eq!(code, 1);
    assert_eq!(v["time_unit"], "us");
    assert_eq!(v["chains"][0]["paper"], 5756.0);
    assert_eq!(v["chains"][0]["limit"], 10000.0);
}

#[test]
fn all_paths_json_and_text() {
    let p = example("paper-table2.toml");
    let o = rtpipe(&["analyze", &p, "--json", "--all-paths"]);
    let v = json_of(&o);
    let pairs = v["all_paths"]["pairs"].as_array().map(|a| a.len());
    assert_eq!(pairs, Some(4));
    let o = rtpipe(&["analyze", &p, "--all-paths"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("all source-to-sink pairs"), "{text}");
    assert!(text.contains("t2>t5>t6"), "{text}");
}

#[test]
fn table_output_for_people() {
    let p = example("paper-table2.toml");
    let o = rtpipe(&["analyze", &p]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("schedulability (liu-layland)"), "{text}");
    assert!(text.contains("t1>t4"), "{text}");
    assert!(text.contains("FAIL"), "{text}");
}

#[test]
fn bad_spec_exits_2_with_location() {
    let dir = scratch("cli");
    let f = dir.join("bad.toml");
    let text = match std::fs::read_to_string(example("paper-table2.toml")) {
        Ok(t) => t.replace("reads = [\"t1\", \"t2\"]", "reads = [\"t1\", \"tt2\"]"),
        Err(e) => panic!("{e}"),
    };
    if let Err(e) = std::fs::write(&f, text) {
        panic!("{e}");
    }
    let o = rtpipe(&["analyze", &f.to_string_lossy(), "--json"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty(), "nothing on stdout for bad input");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:41:16: error: unknown task `tt2`"),
        "{err}"
    );
    assert!(err.contains("did you mean `t2`?"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_file_and_flags_exit_2() {
    let o = rtpipe(&["analyze", "/nonexistent/spec.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot read the spec"));
    let o = rtpipe(&["analyze", "--bogus"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn missing_period_is_explained() {
    let dir = scratch("cli-np");
    let f = dir.join("np.toml");
    let src = "[system]\nname = \"np\"\n[tasks.a]\nexec = 1\n";
    if let Err(e) = std::fs::write(&f, src) {
        panic!("{e}");
    }
    let o = rtpipe(&["analyze", &f.to_string_lossy()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no fixed period for task a"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn design_writes_a_spec_that_analyze_accepts() {
    let dir = scratch("design");
    let out = dir.join("designed.toml");
    let spec = example("table2-design.toml");
    let o = rtpipe(&[
        "design",
        &spec,
        "--mode",
        "paper",
        "--json",
        "--write",
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(v["design"]["status"], "optimal");
    let u = v["design"]["objective"].as_f64().unwrap_or(f64::NAN);
    // Hand check: 1/9 + 1/14 + 1/5 + 1.15/50 + 1/12 + 1.15/50 = 0.511873…
    assert!((u - 0.511_873_015_873).abs() < 1e-9, "{u}");
    // The written spec has every period fixed and passes `analyze --mode
    // paper`; the default (sound) verdict fails three reaction limits.
    let a = rtpipe(&[
        "analyze",
        &out.to_string_lossy(),
        "--mode",
        "paper",
        "--json",
    ]);
    let r = json_of(&a);
    assert_eq!(a.status.code(), Some(0));
    assert_eq!(
        (r["paper_ok"].as_bool(), r["ok"].as_bool()),
        (Some(true), Some(false))
    );
    let a = rtpipe(&["analyze", &out.to_string_lossy()]);
    assert_eq!(a.status.code(), Some(1));
    let text = String::from_utf8_lossy(&a.stdout);
    assert!(
        text.contains("3 chain limit(s) fail under the sound analysis"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn design_rejects_bad_flags_with_exit_2() {
    let spec = example("table2-design.toml");
    let o = rtpipe(&["design", &spec, "--time-limit", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--time-limit"));
    let o = rtpipe(&["design", &spec, "--mode", "fast"]);
    assert_eq!(o.status.code(), Some(2));
}

/// A numerical failure of the solver (microlp's "Singular
/// matrix" on Cleanflight's derived limits) is not an internal error: the
/// best verified design (exit 0) or none (exit 1), never exit 3.
#[test]
fn design_survives_numerical_failures() {
    let spec = example("cleanflight-derived.toml");
    let o = rtpipe(&["design", &spec, "--json", "--time-limit", "30"]);
    let code = o.status.code();
    assert!(
        matches!(code, Some(0 | 1)),
        "exit {code:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json_of(&o);
    let status = v["design"]["status"].as_str().unwrap_or("");
    assert!(
        ["optimal", "feasible", "unknown"].contains(&status),
        "{status}"
    );
    assert_eq!(
        code == Some(0),
        status != "unknown",
        "{status} with exit {code:?}"
    );
}

/// `analyze` on an example with each (from, to) edit exits 2 with the
/// expected located message and a help line.
fn mutated_exit_2(tag: &str, name: &str, cases: &[(&str, &str, &str)]) {
    let dir = scratch(tag);
    let text = match std::fs::read_to_string(example(name)) {
        Ok(t) => t,
        Err(e) => panic!("{e}"),
    };
    for &(from, to, want) in cases {
        let f = dir.join("bad.toml");
        if let Err(e) = std::fs::write(&f, text.replacen(from, to, 1)) {
            panic!("{e}");
        }
        let o = rtpipe(&["analyze", &f.to_string_lossy()]);
        assert_eq!(o.status.code(), Some(2), "{to}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want), "{err}");
        assert!(err.contains("help:"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad combinations of timing keys exit 2 with the place and a fix; `design`
/// checks the deadline-monotonic spec with the box search (every period
/// fixed: it verifies, exit 0), the MILP refuses it at `priorities`.
#[test]
fn bad_deadlines_jitter_and_priorities_exit_2_with_location() {
    let cases = [
        ("deadline = 1.5", "deadline = 2.5", "bad.toml:24:12: error: deadline 2.5 of task `gyro` is above its period (2)"),
        ("jitter = 0.4 ", "jitter = 2 ", "bad.toml:23:10: error: jitter 2 of task `gyro` is not below its period (2)"),
        ("period = 2\n", "period = 2\npriority = 1\n", "bad.toml:23:12: error: task `gyro` gives a priority, but priorities are deadline-monotonic"),
    ];
    mutated_exit_2("cli-timing", "jitter-deadlines.toml", &cases);
    let spec = example("jitter-deadlines.toml");
    let o = rtpipe(&["design", &spec]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = rtpipe(&["design", &spec, "--method", "milp"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("jitter-deadlines.toml:12:1: error: priorities = \"deadline-monotonic\""),
        "{err}"
    );
}

/// Communication per chain: a task on chains of two semantics,
/// and what LET cannot run on a LET chain (jitter, an I/O VCPU), exit 2
/// with the place and a fix; `design` refuses a LET chain (exit 2).
#[test]
fn per_chain_let_misuse_exits_2_with_location() {
    let cases = [
        (
            "path = [\"controller\", \"mixer\"]",
            "path = [\"estimator\", \"controller\", \"mixer\"]",
            "bad.toml:66:8: error: task `estimator` is on chain `estimation` (let) and on chain `control` (implicit)",
        ),
        (
            "reads = [\"estimator\"]\nperiod = 20",
            "reads = [\"estimator\"]\nperiod = 20\njitter = 1",
            "bad.toml:52:10: error: task `logger` has release jitter, but it is on chain `logging`, whose communication is LET",
        ),
        (
            "reads = [\"imu\"]\n",
            "reads = [\"imu\"]\nserver = \"io\"\nserves = \"controller\"\n",
            "task `estimator` is an I/O VCPU, but it is on chain `estimation`, whose communication is LET",
        ),
    ];
    mutated_exit_2("cli-let-chain", "let-mixed.toml", &cases);
    // `design` takes chains of both semantics (the box search); the MILP
    // refuses a LET chain at its key.
    assert_exit(&rtpipe(&["design", &example("let-mixed.toml")]), 0);
    let o = rtpipe(&["design", &example("let-mixed.toml"), "--method", "milp"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("let-mixed.toml:56:1: error: chain `estimation` under LET"),
        "{err}"
    );
}

/// Shared resources: a critical section longer than its task's
/// exec, an undeclared resource and sections under EDF exit 2 with the
/// place and a fix; `design`'s MILP refuses specs with sections (exit 2)
/// at the first section rather than ignore them, the box search models
/// them (`run` runs them: tests/run.rs).
#[test]
fn bad_critical_sections_exit_2_with_location() {
    let cases = [
        ("length = 1.5 }", "length = 4 }", "bad.toml:45:51: error: critical section of `l` on `log` (4ms) is longer than its exec (3ms)"),
        ("\"log\", length = 1.5", "\"lgo\", length = 1.5", "bad.toml:45:35: error: unknown resource \"lgo\""),
        ("resource_protocol = \"pcp\"", "scheduler = \"edf\"", "bad.toml:18:12: error: shared resources under scheduler \"edf\""),
    ];
    mutated_exit_2("cli-resources", "resources.toml", &cases);
    let o = rtpipe(&["design", &example("resources.toml"), "--method", "milp"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("resources.toml:30:1: error: critical sections (blocking)"),
        "{err}"
    );
    assert_exit(&rtpipe(&["design", &example("resources.toml")]), 0);
}

/// Shared resources under EDF: only the stack resource policy,
/// named; sections only in plain tasks
/// and within exec, as under RM. `run --policy deadline` refuses the spec
/// at its protocol (SCHED_DEADLINE cannot run SRP), `analyze` and
/// `simulate` run it.
#[test]
fn edf_sections_need_srp_and_exit_2_otherwise() {
    let cases = [
        ("resource_protocol = \"srp\"", "resource_protocol = \"pcp\"", "bad.toml:22:21: error: resource protocol \"pcp\" does not apply to scheduler \"edf\""),
        ("resource_protocol = \"srp\"", "resource_protocol = \"pip\"", "bad.toml:22:21: error: resource protocol \"pip\" does not apply to scheduler \"edf\""),
        ("resource_protocol = \"srp\"", "", "bad.toml:24:12: error: shared resources under scheduler \"edf\" with the default resource protocol \"pcp\""),
        ("server = \"none\"\ncritical_sections = [{ resource = \"bus\", length = 2 }]", "server = \"main\"\ncritical_sections = [{ resource = \"bus\", length = 2 }]", "bad.toml:49:21: error: task `c` has critical sections but server \"main\""),
        ("length = 2 }", "length = 4 }", "bad.toml:49:51: error: critical section of `c` on `bus` (4ms) is longer than its exec (3ms)"),
    ];
    mutated_exit_2("cli-edf-srp", "edf-srp.toml", &cases);
    // SCHED_DEADLINE cannot run SRP: asked for, refused at the protocol
    // (the default, the EDF dispatcher, runs it: crates/runtime/tests/edf_srp.rs).
    let o = rtpipe(&[
        "run",
        &example("edf-srp.toml"),
        "--duration",
        "10ms",
        "--policy",
        "deadline",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("edf-srp.toml:22:1: error: critical sections under scheduler = \"edf\""),
        "{err}"
    );
    assert!(
        err.contains("SCHED_DEADLINE") && err.contains("help:") && err.contains("edf-fifo"),
        "{err}"
    );
    for cmd in ["analyze", "simulate"] {
        let o = rtpipe(&[cmd, &example("edf-srp.toml")]);
        assert_eq!(o.status.code(), Some(0), "{cmd}");
    }
}

/// sense (C 1, T 10) → act (C 2, T 20): sound reaction from the event
/// T_sense + 20 + R_act = 33 ms, freshness from the event 13 + 10 = 23 ms.
const EVENT_LIMITS: &str = "[system]\nname = \"small\"\ntime_unit = \"ms\"\n\
[channels.mem]\nbandwidth = 1\n\
[tasks.sense]\nexec = 1\nperiod = 10\noutput = { channel = \"mem\", size = 0 }\n\
[tasks.act]\nexec = 2\nperiod = 20\nreads = [\"sense\"]\noutput = { channel = \"mem\", size = 0 }\nMAXP\n\
[[chain]]\npath = [\"sense\", \"act\"]\nreaction = 40\nmax_reaction_time = MRT\nfreshness_from_event = 50\n";

#[test]
fn analyze_shows_and_judges_limits_from_the_event_and_max_period() {
    let dir = scratch("cli-event-limits");
    let f = dir.join("small.toml");
    let path = f.to_string_lossy().to_string();
    let write = |mrt: &str, maxp: &str| {
        let text = EVENT_LIMITS.replace("MRT", mrt).replace("MAXP", maxp);
        if let Err(e) = std::fs::write(&f, text) {
            panic!("{e}");
        }
    };
    write("40", "");
    let o = rtpipe(&["analyze", &path]);
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("limit+event"), "{text}");
    write("30", "");
    let o = rtpipe(&["analyze", &path, "--json"]);
    assert_exit(&o, 1);
    let v = json_of(&o);
    assert_eq!(v["chains"][0]["event_limit"], 30.0);
    assert_eq!(v["chains"][0]["from_event"]["sound"], 33.0);
    assert_eq!(v["chains"][0]["ok"], false);
    assert_eq!(v["chains"][0]["paper_ok"], true);
    assert_eq!(v["chains"][1]["event_limit"], 50.0);
    // The paper analysis (22 ms from the event) keeps the 30 ms limit.
    assert_exit(&rtpipe(&["analyze", &path, "--mode", "paper"]), 0);
    write("40", "max_period = 15");
    let o = rtpipe(&["analyze", &path]);
    assert_exit(&o, 1);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        text.contains("act: period 20 > max_period 15: FAIL"),
        "{text}"
    );
    assert!(
        text.contains("verdict: 1 period(s) above max_period"),
        "{text}"
    );
    let v = json_of(&rtpipe(&["analyze", &path, "--json"]));
    assert_eq!(v["tasks"][1]["max_period"], 15.0);
    assert_eq!(v["tasks"][1]["period_ok"], false);
    assert_eq!(v["ok"], false);
    write("0", "");
    let o = rtpipe(&["analyze", &path]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        err.contains("small.toml:") && err.contains("max_reaction_time must be positive"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `rtpipe ARGS` with stdout on /dev/full: a plain error and exit 2, as an
/// output file that cannot be written, never a panic.
fn into_full_disk(args: &[&str]) -> std::process::Output {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        panic!("no /dev/full");
    };
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(args)
        .stdout(full)
        .output();
    o.unwrap_or_else(|e| panic!("cannot run rtpipe: {e}"))
}

#[test]
fn a_full_stdout_is_a_plain_error_for_every_printing_command() {
    let t2 = example("paper-table2.toml");
    let dir = scratch("full");
    let w = dir.join("w.toml");
    let w = w.to_string_lossy();
    let out = dir.join("imported");
    let out = out.to_string_lossy();
    let cases = printing_commands(&t2, &w, &out);
    for args in cases {
        let o = into_full_disk(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("error: cannot write the output: No space left on device"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// One invocation of every subcommand that prints to stdout.
fn printing_commands<'a>(t2: &'a str, w: &'a str, out: &'a str) -> Vec<Vec<&'a str>> {
    let yaml = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/e2eeval-golden.yaml"
    );
    vec![
        vec!["analyze", t2],
        vec!["analyze", t2, "--json"],
        vec!["simulate", t2, "--outputs", "20"],
        vec!["design", t2],
        vec!["generate", "waters", "--tasks", "10", "--chains", "2", w],
        vec!["import", "e2eeval", yaml, out],
        vec![
            "fly",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../examples/cleanflight.toml"
            ),
            "--mission",
            "hover",
            "--duration",
            "3s",
        ],
        vec![
            "run",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../examples/paper-table3.toml"
            ),
            "--policy",
            "other",
            "--best-effort",
            "--duration",
            "100ms",
        ],
    ]
}

#[test]
fn a_closed_pipe_ends_every_printing_command_quietly() {
    let t2 = example("paper-table2.toml");
    let dir = scratch("pipe-all");
    let (w, out) = (dir.join("w.toml"), dir.join("imported"));
    let (w, out) = (w.to_string_lossy(), out.to_string_lossy());
    for args in printing_commands(&t2, &w, &out) {
        let _ = std::fs::remove_dir_all(dir.join("imported"));
        // The reader is gone before the command starts: its first write
        // to stdout fails, whatever its size.
        let Ok((reader, writer)) = std::io::pipe() else {
            panic!("no pipe");
        };
        drop(reader);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
            .args(&args)
            .stdout(writer)
            .output();
        let Ok(o) = o else {
            panic!("cannot run rtpipe");
        };
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(141), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn a_full_or_closed_stderr_is_no_panic() {
    // An error message that cannot be written: exit 2 (the error's own
    // status) or 141 on a closed pipe, never an abort.
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        panic!("no /dev/full");
    };
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(["analyze", "/nonexistent/spec.toml"])
        .stderr(full)
        .output();
    let o = o.unwrap_or_else(|e| panic!("cannot run rtpipe: {e}"));
    assert_eq!(o.status.code(), Some(2));
    let Ok((reader, writer)) = std::io::pipe() else {
        panic!("no pipe");
    };
    drop(reader);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(["analyze", "/nonexistent/spec.toml"])
        .stderr(writer)
        .output();
    let o = o.unwrap_or_else(|e| panic!("cannot run rtpipe: {e}"));
    assert_eq!(o.status.code(), Some(141));
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = scratch("pipe");
    let big = dir.join("big.toml");
    let big = big.to_string_lossy();
    let gen = [
        "generate", "waters", "--tasks", "200", "--chains", "40", "--seed", "1", &big,
    ];
    assert_exit(&rtpipe(&gen), 0);
    // Far more than a pipe's buffer, to a reader that is gone.
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(["analyze", &big, "--all-paths", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn();
    let Ok(mut child) = child else {
        panic!("cannot start rtpipe");
    };
    drop(child.stdout.take());
    let Ok(o) = child.wait_with_output() else {
        panic!("rtpipe did not end");
    };
    assert_eq!(
        o.status.code(),
        Some(141),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A flag that would have no effect is an error naming the fix, before
/// anything runs.
#[test]
fn flags_that_would_be_ignored_exit_2() {
    let t2 = example("table2-design.toml");
    let o = rtpipe(&["design", &t2, "--method", "boxes", "--solver", "microlp"]);
    assert_exit(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--method boxes solves no LP"));
    let t3 = example("paper-table3.toml");
    let o = rtpipe(&["run", &t3, "--vehicle", "racer5", "--duration", "100ms"]);
    assert_exit(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("this run has synthetic bodies"));
    let cf = example("cleanflight.toml");
    let o = rtpipe(&[
        "run",
        &cf,
        "--synthetic",
        "--mission",
        "hover",
        "--duration",
        "100ms",
    ]);
    assert_exit(&o, 2);
}
