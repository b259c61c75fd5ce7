//! Known release offsets end to end: `analyze` shows the job-level bounds
//! with what they rest on (table and JSON), `simulate` holds its runs
//! against them, and specs without offsets print what they always printed.

mod common;

use common::{assert_exit, example, json_of, rtpipe, scratch};
use serde_json::Value;

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn analyze_shows_the_known_offset_bounds() {
    let o = rtpipe(&["analyze", &example("e2e-golden.toml")]);
    assert_exit(&o, 0);
    let out = stdout(&o);
    assert!(out.contains("known release offsets"), "{out}");
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("t20>t5>t10") && l.ends_with("known offsets"))
        .collect();
    assert_eq!(rows.len(), 2, "{out}");
    let cells = |l: &str| l.split_whitespace().take(4).collect::<Vec<_>>().join(" ");
    assert_eq!(cells(rows[0]), "t20>t5>t10 reaction 13 33");
    assert_eq!(cells(rows[1]), "t20>t5>t10 freshness 23 43");

    let o = rtpipe(&["analyze", &example("e2e-golden.toml"), "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let k = &v["chains"][0]["known_offsets"];
    assert_eq!(k["sound"], 13.0);
    assert_eq!(k["basis"], "known offsets");
    assert_eq!(k["from_event"]["sound"], 33.0);
    assert_eq!(k["from_event"]["basis"], "known offsets");
    assert_eq!(k["hyperperiod"], 20.0);
    assert_eq!(k["jobs"], 17);
    assert_eq!(v["chains"][1]["known_offsets"]["sound"], 23.0);
    // The existing keys are unchanged.
    assert_eq!(v["chains"][0]["sound"], 26.0);
}

#[test]
fn specs_without_offsets_have_no_known_offset_output() {
    let o = rtpipe(&["analyze", &example("paper-table2.toml")]);
    assert!(!stdout(&o).contains("known release offsets"));
    let v = json_of(&rtpipe(&[
        "analyze",
        &example("paper-table2.toml"),
        "--json",
    ]));
    let chains = v["chains"].as_array().cloned().unwrap_or_default();
    assert!(chains.iter().all(|c| c.get("known_offsets").is_none()));
}

#[test]
fn unknown_offsets_are_named() {
    let dir = scratch("offsets-partial");
    let text = std::fs::read_to_string(example("e2e-golden.toml")).unwrap_or_default();
    let partial = text
        .replace("release = \"synchronous\"\n", "")
        .replace("period = 20\n", "period = 20\noffset = 3\n");
    let p = dir.join("partial.toml");
    if let Err(e) = std::fs::write(&p, partial) {
        panic!("{e}");
    }
    let v = json_of(&rtpipe(&["analyze", &p.to_string_lossy(), "--json"]));
    let k = &v["chains"][0]["known_offsets"];
    assert_eq!(k["basis"], "any phasing (offset unknown: t5, t10)");
    assert_eq!(k["sound"], v["chains"][0]["sound"]);
    assert_eq!(k["jobs"], Value::Null);
}

#[test]
fn simulate_holds_runs_against_the_known_offset_bounds() {
    let o = rtpipe(&[
        "simulate",
        &example("e2e-golden.toml"),
        "--outputs",
        "50",
        "--phasing",
        "search",
        "--search-steps",
        "3",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    for c in v["chains"].as_array().cloned().unwrap_or_default() {
        let k = &c["known_offsets"];
        assert_eq!(k["violations"], 0, "{c}");
        assert_eq!(k["from_event"]["violations"], 0, "{c}");
    }
    let searches = v["search"].as_array().cloned().unwrap_or_default();
    assert_eq!(searches.len(), 4);
    assert!(searches.iter().all(|s| s["known_offsets"]["tightness"]
        .as_f64()
        .is_some_and(|t| t <= 1.0)));
    // The schedule is fixed: the observed maxima of docs/analysis.md.
    assert_eq!(v["chains"][0]["observed"]["max"], 10.0);
    assert_eq!(v["chains"][0]["observed_from_event"]["max"], 30.0);
}

/// `b` starts 100 ms late: the runs exceed the arbitrary-phasing bound from
/// the event (which assumes every task has started), not the known-offset
/// one, which is the one that holds for them: exit 0, with a note.
#[test]
fn a_late_start_is_refused() {
    let dir = scratch("offsets-late");
    let p = dir.join("late.toml");
    let src = "[system]\nname = \"late\"\ntime_unit = \"ms\"\nscheduler = \"rm\"\nschedulability = \"rta\"\n\
               [channels.mem]\nbandwidth = 1\n\
               [tasks.a]\nexec = 1\nperiod = 5\noffset = 0\noutput = { channel = \"mem\", size = 0 }\n\
               [tasks.b]\nexec = 2\nperiod = 10\noffset = 100\nreads = [\"a\"]\noutput = { channel = \"mem\", size = 0 }\n\
               [[chain]]\npath = [\"a\", \"b\"]\n";
    if let Err(e) = std::fs::write(&p, src) {
        panic!("{e}");
    }
    // A task released a period or more late has no job in its first
    // periods, which the any-phasing bounds do not allow for.
    let o = rtpipe(&["simulate", &p.to_string_lossy(), "--outputs", "30"]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        err.contains("offset 100 of task `b` is not below its period (10)"),
        "{err}"
    );
    assert!(err.contains("offset = 0"), "{err}");
}
