//! The Chrome trace of a simulated run (`rtpipe_joblog::trace`): stages
//! tile each job, data-flow arrows pair up, limits cut the trace.

use rtpipe_joblog::trace::{chrome_trace, chrome_trace_with, TraceOptions};
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::{simulate, SimConfig};
use serde_json::Value;

fn us(ns: Nanos) -> f64 {
    ns as f64 / 1000.0
}

const SPEC: &str = r#"
[system]
name = "two"
time_unit = "ms"
[channels.m]
bandwidth = 1
overhead = 1
[tasks.a]
exec = 2
input = { channel = "m", size = 0 }
output = { channel = "m", size = 0 }
period = 10
[tasks.b]
exec = 1
reads = ["a"]
output = { channel = "m", size = 0 }
period = 5
[[chain]]
path = ["a", "b"]
"#;

fn run() -> (Spec, SimResult) {
    let spec = match Spec::parse("two.toml", SPEC) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    let mut cfg = SimConfig::new(40_000_000);
    cfg.log_jobs = true;
    match simulate(&spec, &cfg) {
        Ok(r) => (spec, r),
        Err(e) => panic!("{e}"),
    }
}

fn events(json: &str) -> Vec<Value> {
    match serde_json::from_str::<Value>(json) {
        Ok(v) => v["traceEvents"].as_array().cloned().unwrap_or_default(),
        Err(e) => panic!("not JSON: {e}"),
    }
}

#[test]
fn stages_tile_each_job_and_flows_pair_up() {
    let (spec, res) = run();
    let ev = events(&chrome_trace(&spec, &res));
    let of = |ph: &str, name: &str| {
        ev.iter()
            .filter(|e| e["ph"] == ph && (name.is_empty() || e["name"] == name))
            .count()
    };
    assert_eq!(of("X", "a") + of("X", "b"), res.segments.len());
    // Δin = Δout = 1 ms per job: one read and one write piece per job
    // (no job is preempted inside a 1 ms stage here).
    assert_eq!(of("X", "read"), res.jobs.len());
    assert_eq!(of("X", "write"), res.jobs.len());
    let dur: f64 = ev
        .iter()
        .filter(|e| e["cat"] == "stage")
        .filter_map(|e| e["dur"].as_f64())
        .sum();
    let busy: Nanos = res.jobs.iter().map(|j| j.demand).sum();
    assert!((dur - us(busy)).abs() < 1e-6, "{dur} vs {}", us(busy));
    assert!(of("s", "data") > 0);
    assert_eq!(of("s", "data"), of("f", "data"));
    assert_eq!(of("M", "thread_name"), 2);
}

#[test]
fn spans_have_no_stages() {
    let (spec, res) = run();
    let opts = TraceOptions {
        spans: true,
        ..TraceOptions::default()
    };
    let t = chrome_trace_with(&spec, &res, opts);
    let ev = events(&t.json);
    assert_eq!(t.slices, res.segments.len());
    assert!(ev.iter().all(|e| e["cat"] != "stage" && e["cat"] != "job"));
    assert_eq!(
        ev.iter().filter(|e| e["cat"] == "span").count(),
        res.segments.len()
    );
    assert!(t.flows > 0);
}

#[test]
fn limits_cut_the_trace() {
    let (spec, res) = run();
    let t = chrome_trace_with(
        &spec,
        &res,
        TraceOptions {
            max_slices: 3,
            max_flows: 1,
            spans: false,
        },
    );
    assert_eq!(t.slices, 3);
    assert!(t.flows <= 1);
    assert_eq!(t.truncated_at, Some(res.segments[3].start));
    let ev = events(&t.json);
    let late = ev
        .iter()
        .filter(|e| e["ph"] != "M")
        .filter_map(|e| e["ts"].as_f64())
        .any(|ts| ts >= us(res.segments[3].start) && ts > 0.0);
    assert!(!late, "nothing after the cut");
}
