//! `rtpipe analyze --margins` and `--margins-csv`: the table, the JSON, the
//! CSV file (written whole through `model::output`, never over the spec),
//! the refusal of event-triggered specs, and Ctrl-C.

mod common;

use common::{assert_exit, example, json_of, rtpipe, rtpipe_in, rtpipe_interrupted, scratch};
use std::time::Duration;

/// Table III: the exact RTA ends every exec's growth (p1's at 34.5 ms),
/// and every exec together at 1.885057.
#[test]
fn table3_margins_in_text_and_json() {
    let spec = example("paper-table3.toml");
    let o = rtpipe(&["analyze", &spec, "--margins"]);
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("margins (sound mode;"), "{text}");
    assert!(
        text.contains("p1     9.5   +34.5    +363.2  schedulability of cpu 0"),
        "{text}"
    );
    assert!(text.contains("all    1.885057"), "{text}");

    let o = rtpipe(&["analyze", &spec, "--margins", "--json", "--mode", "paper"]);
    assert_exit(&o, 0);
    let m = &json_of(&o)["margins"];
    assert_eq!(m["mode"], "paper");
    assert_eq!(m["exec"][0]["margin"], 34.5);
    assert_eq!(m["exec"][0]["status"], "holds");
    assert_eq!(m["scaling"][0]["factor"], 1.885057);
    // Without the flag the JSON is what it was.
    let o = rtpipe(&["analyze", &spec, "--json"]);
    assert!(json_of(&o).get("margins").is_none());
}

/// Cleanflight fails its gyro path's reaction by 480 µs (sound): the
/// slack is negative and pwm's exec must shrink by exactly that.
#[test]
fn an_infeasible_spec_says_how_much_to_shrink() {
    let o = rtpipe(&[
        "analyze",
        &example("cleanflight.toml"),
        "--margins",
        "--json",
    ]);
    assert_exit(&o, 1);
    let m = &json_of(&o)["margins"];
    assert_eq!(m["holds"], false);
    let pwm = m["exec"]
        .as_array()
        .and_then(|a| a.iter().find(|e| e["task"] == "pwm"))
        .cloned()
        .unwrap_or_default();
    assert_eq!(pwm["margin"], -480.0);
    assert_eq!(pwm["status"], "shrink");
    assert_eq!(m["limits"][0]["slack"], -480.0);
    assert_eq!(m["limits"][0]["first_eaten_by"], "pwm");
}

#[test]
fn margins_csv_is_written_whole_and_never_over_the_spec() {
    let dir = scratch("margins-csv");
    let spec = example("paper-table3.toml");
    let out = dir.join("m.csv");
    let o = rtpipe(&["analyze", &spec, "--margins-csv", &out.to_string_lossy()]);
    assert_exit(&o, 0);
    let csv = std::fs::read_to_string(&out).unwrap_or_default();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("kind,subject,key,value,limit,margin,margin_percent,least,greatest,factor,status,limited_by,first_eaten_by")
    );
    assert!(csv.contains("\nexec,p1,exec,9.5,,34.5,"), "{csv}");
    assert!(
        csv.contains("\nscaling,all,exec,,,,,,,1.885057,holds,"),
        "{csv}"
    );
    // --margins-csv implies --margins in the report.
    assert!(String::from_utf8_lossy(&o.stdout).contains("critical scaling factor"));
    let o = rtpipe(&["analyze", &spec, "--margins-csv", &spec]);
    assert_exit(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--margins-csv"));
}

/// Work-queue threads and data-triggered tasks have margins too.
#[test]
fn threads_have_margins() {
    let o = rtpipe(&[
        "analyze",
        &example("work-queues.toml"),
        "--margins",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let exec = v["margins"]["exec"].as_array().cloned().unwrap_or_default();
    assert_eq!(exec.len(), 7, "{v}");
}

/// Ctrl-C during a long search: status 130, a note, no CSV file.
#[test]
fn ctrl_c_stops_the_search_and_writes_nothing() {
    let dir = scratch("margins-ctrl-c");
    let long = dir.join("w.toml");
    let g = rtpipe_in(
        &dir,
        &[
            "generate",
            "waters",
            "--tasks",
            "150",
            "--chains",
            "10",
            "--seed",
            "1",
            &long.to_string_lossy(),
        ],
        &[],
        Duration::from_secs(60),
    );
    assert_exit(&g, 0);
    let out = dir.join("m.csv");
    let args = [
        "analyze",
        &*long.to_string_lossy(),
        "--margins-csv",
        &*out.to_string_lossy(),
    ]
    .map(str::to_string);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (o, after) = rtpipe_interrupted(
        &dir,
        &args,
        Duration::from_millis(500),
        Duration::from_secs(120),
    );
    assert_exit(&o, 130);
    assert!(String::from_utf8_lossy(&o.stderr).contains("stopped (Ctrl-C)"));
    assert!(o.stdout.is_empty());
    assert!(!out.exists());
    assert!(after < Duration::from_secs(30), "{after:?}");
}

/// `design --objective margin --max-utilization U`: the factor found, the
/// answer within the cap, `--margins` of the answer; the flags' refusals.
#[test]
fn design_for_margin_within_a_cap() {
    let spec = example("timing-design.toml");
    let o = rtpipe(&[
        "design",
        &spec,
        "--objective",
        "margin",
        "--max-utilization",
        "0.6",
        "--margins",
    ]);
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("margin objective: every exec ×1.333"),
        "{text}"
    );
    assert!(text.contains("all    1.333333"), "{text}");
    let o = rtpipe(&[
        "design",
        &spec,
        "--objective",
        "margin",
        "--max-utilization",
        "0.33",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let search = &v["design"]["margin_search"];
    assert_eq!(search["largest"], true);
    assert!(v["design"]["objective"].as_f64().is_some_and(|u| u <= 0.33));
    let steps = search["steps"].as_array().map_or(0, Vec::len);
    assert!(steps > 3, "{search}");
    // A cap below the least utilisation (0.2909): no design, exit 1.
    let o = rtpipe(&[
        "design",
        &spec,
        "--objective",
        "margin",
        "--max-utilization",
        "0.25",
    ]);
    assert_exit(&o, 1);
    assert!(String::from_utf8_lossy(&o.stdout).contains("0.2909"));
    for (args, says) in [
        (vec!["--objective", "margin"], "needs a utilisation cap"),
        (vec!["--max-utilization", "0.5"], "add --objective margin"),
        (
            vec!["--objective", "margin", "--max-utilization", "-1"],
            "positive number",
        ),
        (
            vec!["--objective", "margin", "--max-utilization", "nan"],
            "positive number",
        ),
    ] {
        let mut all = vec!["design", spec.as_str()];
        all.extend(args.iter().copied());
        let o = rtpipe(&all);
        assert_exit(&o, 2);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(says), "{args:?}: {e}");
    }
}
