//! `rtpipe run` of work-queue threads and data-triggered tasks end to end
//! (`examples/work-queues.toml`): the run measures every chain through the
//! triggered tasks and the verdict is the analysis' own; the policies and
//! the export that cannot run them are refused at their flag. SCHED_FIFO
//! needs root (or CAP_SYS_NICE); without it the run test says why and
//! passes.

mod common;

use common::{assert_exit, example, json_of, rtpipe, scratch};
use serde_json::Value;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Task `name`'s `observed` figures.
fn observed<'v>(v: &'v Value, name: &str) -> &'v Value {
    let tasks = v["tasks"]
        .as_array()
        .unwrap_or_else(|| panic!("no tasks in {v}"));
    let t = tasks.iter().find(|t| t["name"] == name);
    &t.unwrap_or_else(|| panic!("no task {name} in {v}"))["observed"]
}

#[test]
fn work_queues_run_on_real_threads_judged_by_the_analysis() {
    let o = rtpipe(&[
        "run",
        &example("work-queues.toml"),
        "--duration",
        "1s",
        "--json",
    ]);
    if o.status.code() == Some(2) && stderr(&o).contains("needs root or CAP_SYS_NICE") {
        eprintln!("SKIPPED the work-queues run: no privilege for SCHED_FIFO here");
        return;
    }
    let v = json_of(&o);
    assert_eq!(v["run"]["policy"], "fifo");
    // The exit status follows the verdict's unexcused observations (a
    // loaded machine may leave some), never anything else.
    let unexcused = v["run"]["sound_bound_violations"]["unexcused"]
        .as_u64()
        .unwrap_or(0);
    assert_exit(&o, if unexcused > 0 { 1 } else { 0 });
    let chains = v["chains"]
        .as_array()
        .unwrap_or_else(|| panic!("no chains"));
    assert!(!chains.is_empty());
    for c in chains {
        assert!(c["observed"]["count"].as_u64().unwrap_or(0) > 0, "{c}");
    }
    // The rate loop's data-triggered tasks: released by imu's
    // publications (each a job or a merge), all on SCHED_FIFO.
    // imu is a timer in thread spi1: each of its 1000 releases is a job,
    // or a merge when the thread was held up past its next release.
    let imu = &observed(&v, "imu");
    let imu = imu["completed"].as_u64().unwrap_or(0) + imu["merged"].as_u64().unwrap_or(0);
    assert_eq!(imu, 1000);
    for name in ["angular_velocity", "rate_control", "control_allocator"] {
        let t = observed(&v, name);
        let jobs = t["completed"].as_u64().unwrap_or(0);
        let merged = t["merged"].as_u64().unwrap_or(u64::MAX);
        assert!(jobs > 0 && jobs + merged <= imu, "{name}: {t}");
        assert!(t["priority"].as_i64().is_some(), "{name}: {t}");
    }
}

#[test]
fn edf_policies_and_the_rt_app_export_are_refused_at_their_flag() {
    let spec = example("work-queues.toml");
    for policy in ["deadline", "edf-fifo"] {
        let o = rtpipe(&["run", &spec, "--policy", policy]);
        assert_exit(&o, 2);
        let e = stderr(&o);
        assert!(
            e.contains(&format!(
                "--policy {policy} cannot run work-queue threads or data-triggered tasks"
            )) && e.contains("use --policy fifo"),
            "{e}"
        );
    }
    let out = scratch("run-queues-rt-app").within("rt-app.json");
    let o = rtpipe(&["run", &spec, "--export-rt-app", &out.to_string_lossy()]);
    assert_exit(&o, 2);
    let e = stderr(&o);
    assert!(
        e.contains("--export-rt-app cannot express work-queue threads"),
        "{e}"
    );
    assert!(!out.exists(), "a refused export wrote {}", out.display());
}

/// `--measure-overheads --write-spec` would write a spec with `[system]
/// overheads`, which an event-triggered spec may not have: refused before
/// measuring, nothing written.
#[test]
fn measured_overheads_are_not_written_into_an_event_triggered_spec() {
    let out = scratch("run-queues-overheads").within("out.toml");
    let o = rtpipe(&[
        "run",
        &example("work-queues.toml"),
        "--measure-overheads",
        "--write-spec",
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 2);
    let e = stderr(&o);
    assert!(
        e.contains("--write-spec: a spec with work-queue threads"),
        "{e}"
    );
    assert!(!e.contains("measuring"), "measured before refusing: {e}");
    assert!(!out.exists(), "wrote {}", out.display());
}
