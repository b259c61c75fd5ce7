//! The task set of a run as an rt-app workload (github.com/scheduler-tools/
//! rt-app, doc/tutorial.txt), for users who measure with rt-app: one thread
//! per task with its scheduling class and parameters, a `run` event of the
//! task's demand and a `timer` event of its period (both in µs), plus the
//! `--load` hogs as SCHED_OTHER threads that always run. Critical sections
//! lock and unlock one mutex per resource around their share of the run
//! (priority inheritance on under PIP; rt-app has no ceiling protocol).
//! rt-app has no registers: the data flow between tasks is not part of the
//! file.

use crate::config::reservation;
use crate::exec::{fifo_priorities, Policy, RunConfig};
use rtpipe_model::{Nanos, ResourceProtocol, Spec};
use serde_json::{json, Map, Value};

/// The rt-app file and notes on what it rounds.
#[derive(Debug, Clone, PartialEq)]
pub struct RtApp {
    /// The rt-app JSON document.
    pub json: Value,
    /// What the translation rounds or leaves out.
    pub notes: Vec<String>,
}

/// Microseconds, rounded up (a demand or budget never shrinks); a note when
/// that changes the value.
fn us_up(ns: Nanos, what: &str, notes: &mut Vec<String>) -> u64 {
    let us = (ns.max(0) as u64).div_ceil(1000).max(1);
    if us as i64 * 1000 != ns {
        notes.push(format!(
            "{what}: {ns} ns rounded up to {us} us (rt-app counts whole microseconds)"
        ));
    }
    us
}

/// What a deadline export cannot carry: `run`'s partition of the CPUs.
const NO_CPUSETS: &str = "rt-app makes no cpusets: its SCHED_DEADLINE threads run global EDF over all CPUs, where `rtpipe run` makes one exclusive cpuset per CPU (partitioned EDF, as the analysis assumes; docs/runtime.md); for the same schedule, make one exclusive cpuset per CPU, turn the root's cpuset.sched_load_balance off and start each thread in its CPU's set";

/// One task's thread object.
fn task(spec: &Spec, i: usize, cfg: &RunConfig, prio: i32, notes: &mut Vec<String>) -> Value {
    let t = &spec.tasks[i];
    let period = t.fixed_period().unwrap_or(0);
    let period_us = us_up(period, &format!("task {} period", t.name), notes);
    let mut o = Map::new();
    o.insert("instance".into(), json!(1));
    o.insert("loop".into(), json!(-1));
    match cfg.policy {
        Policy::Fifo => {
            o.insert("policy".into(), json!("SCHED_FIFO"));
            o.insert("priority".into(), json!(prio));
            o.insert("cpus".into(), json!([t.cpu]));
        }
        // rt-app has no EDF dispatcher: the nearest is its SCHED_DEADLINE
        // (the sections then run without the stack resource policy).
        Policy::Deadline | Policy::EdfFifo => {
            if cfg.policy == Policy::EdfFifo && i == 0 {
                notes.push("rt-app has no EDF dispatcher: the edf-fifo run is exported as SCHED_DEADLINE reservations, under which the critical sections do not follow the stack resource policy".into());
            }
            if i == 0 {
                notes.push(NO_CPUSETS.into());
            }
            // The reservation `run` makes (`config::reservation`), not
            // the bare budget: rt-app's job frame needs the margin too,
            // and its deadline and period the same lead.
            let deadline = t.deadline_given.unwrap_or(period).min(period);
            let r = reservation(t.budget(), deadline, period);
            let runtime = us_up(r.runtime, &format!("task {} reservation", t.name), notes);
            o.insert("policy".into(), json!("SCHED_DEADLINE"));
            o.insert("dl-runtime".into(), json!(runtime));
            let dl_period = us_up(
                r.period,
                &format!("task {} reservation period", t.name),
                notes,
            );
            o.insert("dl-period".into(), json!(dl_period));
            let deadline = us_up(
                r.deadline,
                &format!("task {} reservation deadline", t.name),
                notes,
            );
            o.insert("dl-deadline".into(), json!(deadline));
        }
        Policy::Other => {
            o.insert("policy".into(), json!("SCHED_OTHER"));
            o.insert("cpus".into(), json!([t.cpu]));
        }
    }
    // Events run in the order listed: the job's demand (its critical
    // sections held as the runtime holds them), then the wait for the next
    // release (a timer keeps the period whatever the preemptions).
    events(spec, i, &mut o, notes);
    o.insert(
        "timer".into(),
        json!({"ref": format!("unique_{}", t.name), "period": period_us}),
    );
    Value::Object(o)
}

/// The name of resource `r`'s mutex in the workload.
fn mutex(spec: &Spec, r: usize) -> String {
    format!("rtpipe_{}", spec.resources[r].name)
}

/// The key of the `n`-th event of `kind` (from 0): rt-app tells events
/// apart by their names' prefixes, so `run`, `run1`, `run2`, ...
fn numbered(kind: &str, n: usize) -> String {
    if n == 0 {
        kind.to_string()
    } else {
        format!("{kind}{n}")
    }
}

/// Task `i`'s demand as `run` events, its critical sections between
/// `lock` and `unlock` of their mutexes (placed as [`crate::locks::plan`]
/// places them), each kind numbered by [`numbered`].
fn events(spec: &Spec, i: usize, o: &mut Map<String, Value>, notes: &mut Vec<String>) {
    let t = &spec.tasks[i];
    let Some(plan) = crate::locks::plan(spec, i) else {
        let demand = us_up(t.demand(), &format!("task {} demand", t.name), notes);
        o.insert("run".into(), json!(demand));
        return;
    };
    let mut runs = 0;
    let mut run = |o: &mut Map<String, Value>, ns: Nanos, what: &str, notes: &mut Vec<String>| {
        if ns > 0 {
            let us = us_up(ns, &format!("task {} {what}", t.name), notes);
            o.insert(numbered("run", runs), json!(us));
            runs += 1;
        }
    };
    run(o, plan.lead, "input time", notes);
    for (k, &(length, r)) in plan.list.iter().enumerate() {
        let m = mutex(spec, r);
        o.insert(numbered("lock", k), json!(m));
        run(o, length, &format!("section {k}"), notes);
        o.insert(numbered("unlock", k), json!(m));
    }
    run(o, plan.rest, "rest of the demand", notes);
}

/// What rt-app cannot do of the spec's resource protocol.
fn protocol_note(spec: &Spec) -> Option<String> {
    if spec.tasks.iter().all(|t| t.sections.is_empty()) {
        return None;
    }
    (spec.resource_protocol != ResourceProtocol::Pip).then(|| {
        format!(
            "rt-app has no priority-ceiling mutex: under {} the sections lock plain mutexes (pi_enabled = false), so a job may wait longer than the analysis' blocking; with resource_protocol = \"pip\" the export turns on the kernel's priority inheritance",
            spec.resource_protocol.name()
        )
    })
}

/// The rt-app workload equivalent to running `spec` under `cfg`.
pub fn rt_app(spec: &Spec, cfg: &RunConfig) -> RtApp {
    let mut notes = Vec::new();
    let prios = fifo_priorities(spec);
    let mut tasks = Map::new();
    for (i, t) in spec.tasks.iter().enumerate() {
        let v = task(spec, i, cfg, prios[i], &mut notes);
        tasks.insert(t.name.clone(), v);
    }
    for i in 0..cfg.load {
        // A hog: one second of work after another, never sleeping.
        tasks.insert(
            format!("rtpipe-load-{i}"),
            json!({"instance": 1, "loop": -1, "policy": "SCHED_OTHER", "run": 1_000_000}),
        );
    }
    notes.extend(protocol_note(spec));
    let seconds = (cfg.duration.max(1) as u64).div_ceil(1_000_000_000);
    if seconds as i64 * 1_000_000_000 != cfg.duration {
        notes.push(format!(
            "duration rounded up to {seconds} s (rt-app counts whole seconds)"
        ));
    }
    let json = json!({
        "tasks": tasks,
        "global": {
            "duration": seconds,
            "calibration": "CPU0",
            "default_policy": "SCHED_OTHER",
            "pi_enabled": spec.resource_protocol == ResourceProtocol::Pip,
            "lock_pages": true,
            "logdir": "./",
            "log_basename": format!("rtpipe-{}", spec.name),
            "gnuplot": false,
        },
    });
    RtApp { json, notes }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: &str = r#"
[system]
name = "pair"
time_unit = "us"
scheduler = "rm"
[channels.m]
bandwidth = 1
overhead = 0
[tasks.src]
exec = 100.5
budget = 200
period = 1000
cpu = 1
output = { channel = "m", size = 0 }
[tasks.dst]
exec = 300
budget = 400
period = 5000
cpu = 1
reads = ["src"]
output = { channel = "m", size = 0 }
"#;

    fn spec(scheduler: &str) -> Spec {
        let text = SPEC.replace("\"rm\"", &format!("\"{scheduler}\""));
        Spec::parse("pair.toml", &text).unwrap_or_else(|e| panic!("{e}"))
    }

    fn cfg(policy: Policy, load: usize) -> RunConfig {
        RunConfig {
            duration: 2_500_000_000,
            policy,
            load,
        }
    }

    #[test]
    fn fifo_tasks_have_priorities_cpus_and_run_then_timer() {
        let r = rt_app(&spec("rm"), &cfg(Policy::Fifo, 2));
        let v = &r.json;
        assert_eq!(v["global"]["duration"], 3);
        assert_eq!(v["global"]["default_policy"], "SCHED_OTHER");
        let src = &v["tasks"]["src"];
        assert_eq!(src["policy"], "SCHED_FIFO");
        assert_eq!(src["priority"], 90, "rate-monotonic rank 1");
        assert_eq!(v["tasks"]["dst"]["priority"], 89);
        assert_eq!(src["cpus"], json!([1]));
        assert_eq!(src["run"], 101, "100.5 us rounded up");
        assert_eq!(src["timer"]["period"], 1000);
        assert_eq!(v["tasks"]["dst"]["timer"]["period"], 5000);
        // Events in order: the run before the timer.
        let keys: Vec<&String> = src.as_object().map_or(vec![], |o| o.keys().collect());
        let pos = |k: &str| keys.iter().position(|x| *x == k);
        assert!(pos("run") < pos("timer"), "{keys:?}");
        assert_ne!(src["timer"]["ref"], v["tasks"]["dst"]["timer"]["ref"]);
        for i in 0..2 {
            let hog = &v["tasks"][format!("rtpipe-load-{i}")];
            assert_eq!(hog["policy"], "SCHED_OTHER");
            assert!(hog.get("timer").is_none());
        }
        assert_eq!(r.notes.len(), 2, "{:?}", r.notes);
    }

    #[test]
    fn deadline_tasks_carry_their_reservation_in_us() {
        let r = rt_app(&spec("edf"), &cfg(Policy::Deadline, 0));
        let dst = &r.json["tasks"]["dst"];
        assert_eq!(dst["policy"], "SCHED_DEADLINE");
        // The budget (400 us) and the margin `run` reserves with it; the
        // period (5 ms) and deadline less the renewal lead.
        assert_eq!(dst["dl-runtime"], 450);
        assert_eq!(dst["dl-period"], 4900);
        assert_eq!(dst["dl-deadline"], 4900);
        assert!(
            dst.get("cpus").is_none(),
            "deadline affinity spans the root domain"
        );
        assert!(dst.get("priority").is_none());
        assert_eq!(r.json["tasks"].as_object().map(|o| o.len()), Some(2));
        assert!(r.notes.iter().any(|n| n == NO_CPUSETS), "{:?}", r.notes);
    }

    #[test]
    fn sections_lock_their_resources_mutex_around_their_share_of_the_run() {
        let text = include_str!("../../../examples/resources.toml");
        let pcp = Spec::parse("resources.toml", text).unwrap_or_else(|e| panic!("{e}"));
        let r = rt_app(&pcp, &cfg(Policy::Fifo, 0));
        let h = &r.json["tasks"]["h"];
        let events: Vec<(String, Value)> = h
            .as_object()
            .map_or(vec![], |o| {
                o.iter().map(|(k, v)| (k.clone(), v.clone())).collect()
            })
            .into_iter()
            .filter(|(k, _)| {
                ["run", "lock", "unlock", "timer"]
                    .iter()
                    .any(|e| k.starts_with(e))
            })
            .collect();
        let want = [
            ("lock", json!("rtpipe_bus")),
            ("run", json!(250)),
            ("unlock", json!("rtpipe_bus")),
            ("lock1", json!("rtpipe_log")),
            ("run1", json!(250)),
            ("unlock1", json!("rtpipe_log")),
            ("run2", json!(500)),
        ];
        let got: Vec<(&str, &Value)> = events
            .iter()
            .map(|(k, v)| (k.as_str(), v))
            .take(7)
            .collect();
        let want: Vec<(&str, &Value)> = want.iter().map(|(k, v)| (*k, v)).collect();
        assert_eq!(got, want);
        assert_eq!(events[7].0, "timer");
        // l: its one section of 1.5 ms, then the rest of its 3 ms.
        assert_eq!(r.json["tasks"]["l"]["run"], 1500);
        assert_eq!(r.json["tasks"]["l"]["run1"], 1500);
        assert_eq!(r.json["global"]["pi_enabled"], false);
        assert!(
            r.notes
                .iter()
                .any(|n| n.contains("no priority-ceiling mutex")),
            "{:?}",
            r.notes
        );
        let pip = Spec::parse("r.toml", &text.replace("\"pcp\"", "\"pip\""))
            .unwrap_or_else(|e| panic!("{e}"));
        let r = rt_app(&pip, &cfg(Policy::Fifo, 0));
        assert_eq!(r.json["global"]["pi_enabled"], true);
        assert!(
            r.notes.iter().all(|n| n.starts_with("duration")),
            "{:?}",
            r.notes
        );
    }
}
