//! `rtpipe analyze`.

use crate::command;
use crate::report::num;
use crate::table::Table;
use rtpipe_analysis::Bound;
use rtpipe_analysis::{AllPaths, Anchor, ChainOffsets, Metric, Mode, Report, Worst};
use rtpipe_model::{Nanos, Spec};
use serde_json::{json, Value};
use std::path::Path;
use std::process::ExitCode;

pub fn run(path: &Path, json_out: bool, all_paths: bool, mode: Mode) -> ExitCode {
    let spec = match command::load(path) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let report = rtpipe_analysis::analyze(&spec);
    let paths = all_paths.then(|| rtpipe_analysis::all_paths(&spec, &report.timing));
    if json_out {
        let mut v = report_json(&spec, &report);
        if let Some(p) = &paths {
            v["all_paths"] = paths_json(&spec, p);
        }
        if let Err(code) = command::print_json(&v) {
            return code;
        }
    } else {
        print!("{}", report_text(&spec, &report, mode));
        if let Some(p) = &paths {
            print!("{}", paths_text(&spec, p));
        }
    }
    if report.ok_in(mode) {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn path_names(spec: &Spec, path: &[usize]) -> Vec<String> {
    path.iter().map(|&i| spec.tasks[i].name.clone()).collect()
}

pub fn report_json(spec: &Spec, r: &Report) -> Value {
    let tasks: Vec<Value> = spec
        .tasks
        .iter()
        .zip(&r.timing)
        .map(|(t, tm)| {
            json!({
                "name": t.name,
                "server": t.server.name(),
                "exec": spec.in_unit(t.exec),
                "exec_min": spec.in_unit(t.exec_min),
                "delta_in": spec.in_unit(t.delta_in),
                "delta_out": spec.in_unit(t.delta_out),
                "demand": spec.in_unit(tm.demand),
                "budget": spec.in_unit(tm.budget),
                "period": spec.in_unit(tm.period),
                "utilization": tm.budget as f64 / tm.period as f64,
                "priority": tm.priority,
                "cpu": tm.cpu,
                "response_time": num(spec, tm.response_time),
                "job_response_time": num(spec, tm.job_response_time),
            })
        })
        .collect();
    let s = &r.schedulability;
    let total_u: f64 = s.cpus.iter().map(|c| c.utilization).sum();
    let single = s.cpus.len() == 1;
    let cpus: Vec<Value> = s
        .cpus
        .iter()
        .map(|c| {
            json!({"cpu": c.cpu, "tasks": c.tasks, "utilization": c.utilization,
                   "value": finite(c.value), "bound": c.bound, "schedulable": c.schedulable})
        })
        .collect();
    let chains: Vec<Value> = r.chains.iter().map(|c| chain_json(spec, r, c)).collect();
    json!({
        "system": spec.name,
        "time_unit": spec.time_unit.name(),
        "scheduler": spec.scheduler.name(),
        "tasks": tasks,
        "schedulability": {
            "test": s.test.name(),
            "utilization": total_u,
            "bound": if single { json!(s.cpus[0].bound) } else { json!(s.cpus.iter().map(|c| c.bound).collect::<Vec<_>>()) },
            "schedulable": s.schedulable,
            "cpus": cpus,
        },
        "chains": chains,
        "ok": r.all_ok(),
        "paper_ok": r.all_ok_paper(),
    })
}

/// One chain and metric of the report; `known_offsets` only for a chain
/// with known offsets.
fn chain_json(spec: &Spec, r: &Report, c: &rtpipe_analysis::ChainResult) -> Value {
    let ch = &spec.chains[c.chain];
    let mut entry = json!({
        "name": ch.name,
        "path": path_names(spec, &ch.path),
        "metric": c.metric.name(),
        "limit": num(spec, c.limit),
    });
    let bounds = |a: Anchor| -> serde_json::Map<String, Value> {
        c.bound
            .from(a)
            .map(|(b, v)| (b.name().to_string(), num(spec, v)))
            .collect()
    };
    for (k, v) in bounds(Anchor::Read) {
        entry[k] = v;
    }
    entry["ok"] = json!(c.ok);
    entry["paper_ok"] = json!(c.paper_ok());
    entry["from_event"] = Value::Object(bounds(Anchor::Event));
    entry["cases"] = r.cases[c.chain]
        .iter()
        .map(|k| match k {
            rtpipe_analysis::Case::One => 1,
            rtpipe_analysis::Case::Two => 2,
        })
        .collect();
    if let Some(o) = r.offsets.get(c.chain).and_then(Option::as_ref) {
        entry["known_offsets"] = known_offsets_json(spec, o, c.metric);
    }
    entry
}

/// A chain's bounds of `metric` under the spec's known release offsets:
/// {sound, basis, from_event {sound, basis}, hyperperiod, jobs}; the
/// hyperperiod and jobs are null when the job-level analysis did not run.
fn known_offsets_json(spec: &Spec, o: &ChainOffsets, metric: Metric) -> Value {
    let one = |a: Anchor| {
        let b = o.get(metric, a);
        json!({"sound": num(spec, b.value), "basis": b.label(spec)})
    };
    let mut v = one(Anchor::Read);
    v["from_event"] = one(Anchor::Event);
    let jl = o.job_level.as_ref();
    v["hyperperiod"] = num(spec, jl.map(|j| j.hyperperiod));
    v["jobs"] = jl.map_or(Value::Null, |j| json!(j.jobs));
    v
}

fn finite(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn opt(spec: &Spec, v: Option<Nanos>) -> String {
    match v {
        Some(n) => spec.fmt_time(n),
        None => "unbounded".to_string(),
    }
}

/// The first line of every report: the system, its size, unit and scheduler.
pub fn system_line(spec: &Spec) -> String {
    format!(
        "system {}: {} tasks, {} chains; times in {}; scheduler {}\n",
        spec.name,
        spec.tasks.len(),
        spec.chains.len(),
        spec.time_unit,
        spec.scheduler.name()
    )
}

pub fn report_text(spec: &Spec, r: &Report, mode: Mode) -> String {
    let mut out = system_line(spec);
    out.push('\n');
    out.push_str(&task_table(spec, r));
    out.push_str(&schedulability_text(r));
    out.push_str(&chain_table(spec, r));
    out.push_str(&known_offsets_text(spec, r));
    out.push_str(&verdict_text(r, mode));
    out
}

/// One row per task: its pipe, budget, period and response times.
fn task_table(spec: &Spec, r: &Report) -> String {
    let mut t = Table::new(&[
        "task", "server", "cpu", "prio", "Δin", "exec", "Δout", "budget C", "period T", "C/T",
        "R(C)", "R(job)",
    ])
    .numeric(&[2, 3, 4, 5, 6, 7, 8, 9, 10, 11]);
    for (task, tm) in spec.tasks.iter().zip(&r.timing) {
        t.row(vec![
            task.name.clone(),
            task.server.name().to_string(),
            task.cpu.to_string(),
            tm.priority
                .map(|p| p.to_string())
                .unwrap_or_else(|| "-".into()),
            spec.fmt_time(task.delta_in),
            spec.fmt_time(task.exec),
            spec.fmt_time(task.delta_out),
            spec.fmt_time(tm.budget),
            spec.fmt_time(tm.period),
            format!("{:.4}", tm.budget as f64 / tm.period as f64),
            opt(spec, tm.response_time),
            opt(spec, tm.job_response_time),
        ]);
    }
    t.render()
}

/// The schedulability test's verdict per CPU.
fn schedulability_text(r: &Report) -> String {
    let mut out = String::new();
    let s = &r.schedulability;
    out.push_str(&format!("\nschedulability ({}):\n", s.test.name()));
    for c in &s.cpus {
        let verdict = if c.schedulable {
            "schedulable"
        } else {
            "NOT schedulable"
        };
        let detail = match s.test {
            rtpipe_model::SchedTest::LiuLayland => format!(
                "U = {:.4} {} n(2^(1/n)-1) = {:.4}",
                c.utilization,
                if c.schedulable { "<=" } else { ">" },
                c.bound
            ),
            rtpipe_model::SchedTest::Hyperbolic => format!(
                "U = {:.4}, prod(U_i+1) = {:.4} {} 2",
                c.utilization,
                c.value,
                if c.schedulable { "<=" } else { ">" }
            ),
            rtpipe_model::SchedTest::Rta => format!(
                "U = {:.4}, max R/T = {}",
                c.utilization,
                if c.value.is_finite() {
                    format!("{:.4}", c.value)
                } else {
                    "unbounded".into()
                }
            ),
            rtpipe_model::SchedTest::Edf => format!(
                "U = {:.4} {} 1",
                c.utilization,
                if c.schedulable { "<=" } else { ">" }
            ),
        };
        out.push_str(&format!(
            "  cpu {} ({} tasks): {detail} -> {verdict}\n",
            c.cpu, c.tasks
        ));
    }
    out
}

/// Every chain's bounds in both modes, from the read and from the event,
/// beside the literature's, with both verdicts.
fn chain_table(spec: &Spec, r: &Report) -> String {
    let mut out = String::new();
    if !spec.chains.is_empty() {
        out.push_str(
            "\nchains (worst case from the head's read; +event: from the event in the world; davare: Davare et al. 2007, duerr: Dürr et al. 2019; see docs/analysis.md):\n",
        );
        // One column per bound and anchor, from-read first (`ChainBound::from`).
        let mut heads: Vec<String> = ["chain", "metric", "limit"].map(String::from).to_vec();
        for a in Anchor::ALL {
            let suffix = if a == Anchor::Event { "+event" } else { "" };
            heads.extend(Bound::ALL.map(|b| format!("{}{suffix}", b.name())));
        }
        heads.extend(["paper verdict", "sound verdict"].map(String::from));
        let numeric: Vec<usize> = (2..heads.len() - 2).collect();
        let heads: Vec<&str> = heads.iter().map(String::as_str).collect();
        let mut t = Table::new(&heads).numeric(&numeric);
        for c in &r.chains {
            let label = spec.chain_label(c.chain);
            let verdict = match (c.ok, c.limit) {
                (true, Some(_)) => "ok",
                (true, None) => "-",
                (false, _) => "FAIL",
            };
            let paper_verdict = match (c.paper_ok(), c.limit) {
                (true, Some(_)) => "ok",
                (true, None) => "-",
                (false, _) => "FAIL",
            };
            let mut row = vec![
                label,
                c.metric.name().to_string(),
                c.limit
                    .map(|l| spec.fmt_time(l))
                    .unwrap_or_else(|| "-".into()),
            ];
            for a in Anchor::ALL {
                row.extend(c.bound.from(a).map(|(_, v)| opt(spec, v)));
            }
            row.extend([paper_verdict.to_string(), verdict.to_string()]);
            t.row(row);
        }
        out.push_str(&t.render());
    }
    out
}

/// The last line: what fails under `mode`, or that nothing does.
fn verdict_text(r: &Report, mode: Mode) -> String {
    let mut out = String::new();
    let fails = r.chains.iter().filter(|c| !c.ok_in(mode)).count();
    let name = mode.name();
    out.push_str(&format!(
        "\n{}\n",
        match (r.schedulability.schedulable, fails) {
            (true, 0) => format!(
                "verdict: every limit holds ({name} analysis) and the system is schedulable"
            ),
            (sched, f) => format!(
                "verdict: {}{}",
                if sched { "" } else { "not schedulable; " },
                if f > 0 {
                    format!("{f} chain limit(s) fail under the {name} analysis")
                } else {
                    String::new()
                }
            ),
        }
    ));
    out
}

/// The bounds under the spec's known release offsets, for the chains with
/// any (nothing when none has).
pub fn known_offsets_text(spec: &Spec, r: &Report) -> String {
    if r.offsets.iter().all(Option::is_none) {
        return String::new();
    }
    let mut out = String::from(
        "\nknown release offsets (job by job over the hyperperiod, see docs/analysis.md; \
         basis: what each bound rests on):\n",
    );
    let mut t = Table::new(&["chain", "metric", "sound", "sound+event", "basis"]).numeric(&[2, 3]);
    for c in &r.chains {
        let Some(o) = r.offsets.get(c.chain).and_then(Option::as_ref) else {
            continue;
        };
        let (read, event) = (
            o.get(c.metric, Anchor::Read),
            o.get(c.metric, Anchor::Event),
        );
        let (lr, le) = (read.label(spec), event.label(spec));
        let basis = if lr == le {
            lr
        } else {
            format!("{lr}; +event: {le}")
        };
        // No value because no sample reaches the tail is not "unbounded".
        let value = |b: &rtpipe_analysis::OffsetBound| match b.basis {
            rtpipe_analysis::Basis::NoSampleReaches => "-".to_string(),
            _ => opt(spec, b.value),
        };
        t.row(vec![
            spec.chain_label(c.chain),
            c.metric.name().to_string(),
            value(read),
            value(event),
            basis,
        ]);
    }
    out.push_str(&t.render());
    out
}

fn worst_json(spec: &Spec, w: &Worst) -> Value {
    json!({"path": path_names(spec, &w.path), "bound": num(spec, w.value)})
}

pub fn paths_json(spec: &Spec, a: &AllPaths) -> Value {
    let pairs: Vec<Value> = a
        .pairs
        .iter()
        .map(|p| {
            json!({
                "source": spec.tasks[p.source].name,
                "sink": spec.tasks[p.sink].name,
                "reaction": {"paper": worst_json(spec, &p.reaction_paper), "sound": worst_json(spec, &p.reaction_sound)},
                "freshness": {"paper": worst_json(spec, &p.freshness_paper), "sound": worst_json(spec, &p.freshness_sound)},
            })
        })
        .collect();
    let cycles: Vec<Vec<String>> = a.cycles.iter().map(|c| path_names(spec, c)).collect();
    json!({"pairs": pairs, "skipped_cycles": cycles})
}

pub fn paths_text(spec: &Spec, a: &AllPaths) -> String {
    let mut out =
        String::from("\nall source-to-sink pairs (worst path per metric, sound analysis):\n");
    let mut t = Table::new(&[
        "source",
        "sink",
        "reaction",
        "worst path",
        "freshness",
        "worst path",
    ])
    .numeric(&[2, 4]);
    for p in &a.pairs {
        t.row(vec![
            spec.tasks[p.source].name.clone(),
            spec.tasks[p.sink].name.clone(),
            opt(spec, p.reaction_sound.value),
            spec.path_label(&p.reaction_sound.path),
            opt(spec, p.freshness_sound.value),
            spec.path_label(&p.freshness_sound.path),
        ]);
    }
    out.push_str(&t.render());
    for c in &a.cycles {
        out.push_str(&format!(
            "  skipped cycle (edges inside it are not on any listed path): {}\n",
            path_names(spec, c).join(", ")
        ));
    }
    out
}
