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

#[test]
fn a_work_queue_thread_is_one_track_and_triggered_jobs_name_their_trigger() {
    let spec = rtpipe_testkit::example("work-queues.toml");
    let mut cfg = SimConfig::new(3_000_000);
    cfg.log_jobs = true;
    let res = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    let ev = events(&chrome_trace(&spec, &res));
    // Three threads, three tracks, named by the thread.
    let names: Vec<&str> = ev
        .iter()
        .filter(|e| e["name"] == "thread_name")
        .filter_map(|e| e["args"]["name"].as_str())
        .collect();
    assert_eq!(
        names,
        vec![
            "thread spi1",
            "thread rate_ctrl",
            "thread nav_and_controllers"
        ]
    );
    // Every slice of the rate thread's tasks is on its track, named by
    // its task.
    let tid_of = |task: &str| -> Vec<u64> {
        let mut tids: Vec<u64> = ev
            .iter()
            .filter(|e| e["ph"] == "X" && e["name"] == task)
            .filter_map(|e| e["tid"].as_u64())
            .collect();
        tids.dedup();
        tids
    };
    let rate = tid_of("angular_velocity");
    assert_eq!(rate.len(), 1);
    for task in ["rate_control", "control_allocator", "land_detector"] {
        assert_eq!(tid_of(task), rate, "{task}");
    }
    // Each gyro-triggered job names the imu publication that released it,
    // with an arrow from it.
    let releases: Vec<&Value> = ev
        .iter()
        .filter(|e| e["ph"] == "i" && e["name"] == "release angular_velocity")
        .collect();
    assert_eq!(releases.len(), 3);
    for (k, r) in releases.iter().enumerate() {
        assert_eq!(r["args"]["trigger"], format!("imu#{k}"));
    }
    let arrows = |ph: &str| {
        ev.iter()
            .filter(|e| e["ph"] == ph && e["cat"] == "trigger")
            .count()
    };
    let triggered = res.jobs.iter().filter(|j| j.trigger.is_some()).count();
    assert!(triggered > 0);
    assert_eq!((arrows("s"), arrows("f")), (triggered, triggered));
}
