//! `rtpipe analyze --observed FILE.csv`: a `simulate --samples` file and a
//! flight log's data ages held against the bounds; every row counted, a
//! measurement above a sound bound fails the verdict (exit 1) by name and
//! line, a wrong file is refused (exit 2) at its line and column.

mod common;

use common::{assert_exit, example, json_of, rtpipe, scratch};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

/// The `--samples` columns each (metric, from) is read from.
const COLUMNS: [(&str, &str, usize); 4] = [
    ("reaction", "read", 6),
    ("freshness", "read", 7),
    ("reaction", "event", 8),
    ("freshness", "event", 9),
];

/// Per (chain, metric, from), how many cells of the `--samples` file hold
/// a value (chain names here hold no comma).
fn filled_cells(csv: &str) -> HashMap<(String, &'static str, &'static str), u64> {
    let mut n = HashMap::new();
    for line in csv.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        for (metric, from, k) in COLUMNS {
            if !cells[k].is_empty() {
                *n.entry((cells[0].to_string(), metric, from)).or_default() += 1;
            }
        }
    }
    n
}

fn analyze_observed(spec: &str, file: &Path) -> (std::process::Output, Value) {
    let f = file.to_string_lossy();
    let o = rtpipe(&["analyze", spec, "--observed", &f, "--json"]);
    let observed = if o.stdout.is_empty() {
        Value::Null
    } else {
        json_of(&o)["observed"].clone()
    };
    (o, observed)
}

/// A simulation's samples of Table III and of the work queues: within
/// every sound bound, every row and every filled cell counted.
#[test]
fn a_simulations_samples_hold_and_every_row_counts() {
    let dir = scratch("observed-samples");
    for name in ["paper-table3.toml", "work-queues.toml"] {
        let spec = example(name);
        let file = dir.join(format!("{name}.csv"));
        let f = file.to_string_lossy();
        let o = rtpipe(&["simulate", &spec, "--outputs", "300", "--samples", &f]);
        assert_exit(&o, 0);
        let csv = std::fs::read_to_string(&file).unwrap_or_default();
        let (o, observed) = analyze_observed(&spec, &file);
        assert_exit(&o, 0);
        assert_eq!(observed["format"], "samples");
        assert_eq!(observed["ok"], true);
        let rows = csv.lines().count() as u64 - 1;
        assert!(rows > 100, "{name}: {rows} rows");
        assert_eq!(observed["rows"], rows, "{name}");
        let filled = filled_cells(&csv);
        let measured = observed["measured"].as_array().cloned().unwrap_or_default();
        assert_eq!(measured.len(), filled.len(), "{name}: {observed}");
        for m in &measured {
            let key = (
                m["chain"].as_str().unwrap_or_default().to_string(),
                if m["metric"] == "reaction" {
                    "reaction"
                } else {
                    "freshness"
                },
                if m["from"] == "read" { "read" } else { "event" },
            );
            assert_eq!(
                Some(&m["count"].as_u64().unwrap_or(0)),
                filled.get(&key),
                "{m}"
            );
            assert!(m["max"].as_f64() <= m["bounds"]["sound"].as_f64(), "{m}");
            assert!(m["ratio"].as_f64().is_some_and(|r| r <= 1.0), "{m}");
        }
        assert_eq!(observed["not_measured"], serde_json::json!([]));
    }
}

const LOG_HEADER: &str = "chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns\n";

/// The sound bound of `chain`'s `metric` from the read, in ns (the spec's
/// unit is µs).
fn sound_ns(spec: &str, chain: &str, metric: &str) -> i64 {
    bound_ns(spec, chain, metric, false)
}

/// The sound bound from the event of `chain`'s `metric`, in ns.
fn event_sound_ns(spec: &str, chain: &str, metric: &str) -> i64 {
    bound_ns(spec, chain, metric, true)
}

fn bound_ns(spec: &str, chain: &str, metric: &str, event: bool) -> i64 {
    let o = rtpipe(&["analyze", spec, "--json"]);
    let chains = json_of(&o)["chains"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let c = chains
        .iter()
        .find(|c| c["name"] == chain && c["metric"] == metric)
        .cloned()
        .unwrap_or_default();
    assert_eq!(json_of(&o)["time_unit"], "us");
    let b = if event { &c["from_event"] } else { &c };
    (b["sound"].as_f64().unwrap_or(f64::NAN) * 1000.0).round() as i64
}

/// A log's rows as `chain,topic,published,sampled,age`.
fn log(rows: &[(&str, i64, i64)]) -> String {
    let mut s = String::from(LOG_HEADER);
    for (chain, published, sampled) in rows {
        s.push_str(&format!(
            "{chain},actuator_motors,{published},{sampled},{}\n",
            published - sampled
        ));
    }
    s
}

/// Hand-made data ages of the work queues: every age is a freshness from
/// the event (a sample is taken at or before the head's read), the earliest
/// publication of each sample its reaction; all within the sound bounds
/// passes, one age above the freshness bound fails by its line.
#[test]
fn a_logs_data_ages_are_held_against_the_sound_bounds() {
    let spec = example("work-queues.toml");
    let fresh = event_sound_ns(&spec, "rate loop", "freshness");
    let react = event_sound_ns(&spec, "attitude to actuators", "reaction");
    assert!(fresh > sound_ns(&spec, "rate loop", "freshness"));
    let dir = scratch("observed-log");
    let t0 = 10_000_000;
    let within = log(&[
        ("rate loop", t0 + fresh / 2, t0),
        ("rate loop", t0 + fresh, t0),
        ("rate loop", t0 + 1_000_000 + 10, t0 + 1_000_000),
        ("attitude to actuators", t0 + react, t0),
    ]);
    let file = dir.join("within.csv");
    let _ = std::fs::write(&file, within);
    let (o, observed) = analyze_observed(&spec, &file);
    assert_exit(&o, 0);
    assert_eq!(observed["format"], "data ages");
    let m = &observed["measured"];
    assert_eq!(m[0]["chain"], "rate loop");
    assert_eq!(
        (&m[0]["metric"], &m[0]["count"]),
        (&"reaction".into(), &2.into())
    );
    // The first sample's reaction is its earliest publication's age.
    assert_eq!(m[0]["max"].as_f64(), Some((fresh / 2) as f64 / 1000.0));
    assert_eq!(
        (&m[1]["metric"], &m[1]["count"]),
        (&"freshness".into(), &3.into())
    );
    assert_eq!(m[1]["max"].as_f64(), Some(fresh as f64 / 1000.0));
    assert_eq!(m[1]["ratio"].as_f64(), Some(1.0));
    assert_eq!(m[2]["max"].as_f64(), Some(react as f64 / 1000.0));

    let over = log(&[
        ("rate loop", t0 + 10, t0),
        ("rate loop", t0 + fresh + 1, t0),
    ]);
    let file = dir.join("over.csv");
    let _ = std::fs::write(&file, over);
    let (o, observed) = analyze_observed(&spec, &file);
    assert_exit(&o, 1);
    assert_eq!(observed["ok"], false);
    assert_eq!(observed["measured"][1]["over_sound"], 1);
    assert_eq!(observed["measured"][1]["worst_line"], 3);
    assert_eq!(observed["not_measured"][0], "attitude to actuators");
    let o = rtpipe(&["analyze", &spec, "--observed", &file.to_string_lossy()]);
    assert_exit(&o, 1);
    let text = String::from_utf8_lossy(&o.stdout);
    let named = format!(
        "rate loop freshness from the event: 1 above the sound bound {}; worst line 3 of {}: {} us",
        fresh / 1000,
        file.display(),
        (fresh + 1) as f64 / 1000.0
    );
    assert!(text.contains(&named), "{text}");
    assert!(
        text.contains("attitude to actuators: not measured"),
        "{text}"
    );
}

/// Wrong files exit 2 naming the file, line and column, and the fix.
#[test]
fn wrong_files_are_refused_at_their_line() {
    let spec = example("work-queues.toml");
    let dir = scratch("observed-bad");
    let cases: [(&str, String, &str); 7] = [
        (
            "unknown-chain",
            format!("{LOG_HEADER}rate loop,x,2,1,1\nyaw loop,x,2,1,1\n"),
            ":3:1: chain `yaw loop` is not in the spec",
        ),
        (
            "bad-header",
            "chain,age\nrate loop,1\n".into(),
            ":1:1: unknown header line",
        ),
        (
            "non-numeric",
            format!("{LOG_HEADER}rate loop,x,2,1,1\nrate loop,x,2,1,1.5\n"),
            ":3:17: `1.5` in column data_age_ns is not an integer",
        ),
        (
            "negative-age",
            format!("{LOG_HEADER}rate loop,x,1,2,-1\n"),
            ":2:17: data_age_ns is a latency and cannot be negative, found -1",
        ),
        (
            "inconsistent-age",
            format!("{LOG_HEADER}rate loop,x,5,2,2\n"),
            ":2:17: data_age_ns 2 is not timestamp_ns - timestamp_sample_ns = 5 - 2",
        ),
        (
            "short-row",
            format!("{LOG_HEADER}rate loop,x,5,2\n"),
            ":2:16: the row has 4 cells, the header 5",
        ),
        (
            "empty",
            String::new(),
            ":1:1: the measurements file is empty",
        ),
    ];
    for (tag, text, expected) in cases {
        let file = dir.join(format!("{tag}.csv"));
        let _ = std::fs::write(&file, text);
        let o = rtpipe(&["analyze", &spec, "--observed", &file.to_string_lossy()]);
        assert_exit(&o, 2);
        assert!(o.stdout.is_empty(), "{tag}: nothing but the error");
        let err = String::from_utf8_lossy(&o.stderr);
        let at = format!("{}{expected}", file.display());
        assert!(err.contains(&at), "{tag}: {err}");
        assert!(err.contains("help:"), "{tag}: {err}");
    }
    // The unknown chain's help lists the spec's chains.
    let file = dir.join("unknown-chain.csv");
    let o = rtpipe(&["analyze", &spec, "--observed", &file.to_string_lossy()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("`rate loop`, `attitude to actuators`"),
        "{err}"
    );
}

/// A log longer than the open samples kept (65,536 per chain): every
/// sample's reaction is still its earliest publication, and a publication
/// of a sample already closed counts toward freshness only, reported.
#[test]
fn a_long_log_closes_old_samples_and_reports_late_publications() {
    let spec = example("work-queues.toml");
    let n: i64 = 70_000;
    let mut s = String::from(LOG_HEADER);
    for k in 0..n {
        let t = 1_000_000 * k;
        // The later publication first: the earliest is the reaction.
        s.push_str(&format!("rate loop,a,{},{t},200000\n", t + 200_000));
        s.push_str(&format!("rate loop,a,{},{t},100000\n", t + 100_000));
    }
    s.push_str("rate loop,a,300000,0,300000\n");
    let file = scratch("observed-long").within("long.csv");
    let _ = std::fs::write(&file, s);
    let (o, observed) = analyze_observed(&spec, &file);
    assert_exit(&o, 0);
    let m = &observed["measured"];
    assert_eq!(m[0]["count"], n);
    assert_eq!(
        (m[0]["min"].as_f64(), m[0]["max"].as_f64()),
        (Some(100.0), Some(100.0))
    );
    assert_eq!(m[1]["count"], 2 * n + 1);
    assert_eq!(m[1]["max"].as_f64(), Some(300.0));
    assert_eq!(m[1]["worst_line"], 2 * n + 2);
    assert_eq!(observed["late"], serde_json::json!([["rate loop", 1]]));
}

/// No output replaces the measurements file.
#[test]
fn no_output_replaces_the_measurements_file() {
    let spec = example("work-queues.toml");
    let file = scratch("observed-overwrite").within("ages.csv");
    let text = log(&[("rate loop", 1_100_000, 1_000_000)]);
    let _ = std::fs::write(&file, &text);
    let f = file.to_string_lossy();
    let o = rtpipe(&["analyze", &spec, "--observed", &f, "--margins-csv", &f]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--observed"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).ok(), Some(text));
}
