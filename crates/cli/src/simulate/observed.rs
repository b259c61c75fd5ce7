//! The report of a run the analysis does not bound yet (threads and
//! data-triggered tasks, `rtpipe_sim::observe::bounds_available`): what
//! the simulator observed, without bounds, verdict or exit status of its
//! own.

use super::*;
use crate::report::time;
use rtpipe_joblog::ChainStats;
use rtpipe_sim::observe::{ChainStatsExt, Summary};
use serde::Serialize;

/// Why the report has no bounds (a note on stderr, and the JSON's `bounds`).
pub(super) const NO_BOUNDS: &str = "note: no bounds: the analysis does not cover threads and data-triggered tasks yet, so the observations are the simulator's alone (no verdict)";

/// `simulate --json` without bounds.
#[derive(Serialize)]
pub(super) struct ObservedReport<'a> {
    system: &'a str,
    time_unit: String,
    bounds: Option<f64>,
    note: &'static str,
    chains: Vec<ObservedChain>,
    tasks: Vec<ObservedTask<'a>>,
    simulation: SimulationView<'a>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub search: Vec<SearchView>,
}

#[derive(Serialize)]
struct ObservedChain {
    chain: String,
    metric: &'static str,
    observed: ObservedView,
    observed_from_event: ObservedView,
}

#[derive(Serialize)]
struct ObservedTask<'a> {
    name: &'a str,
    cpu: u32,
    thread: Option<&'a str>,
    released: u64,
    merged: Option<u64>,
    completed: u64,
    max_response: Option<f64>,
    late: u64,
    utilization: f64,
}

/// The observations of chain `k`'s `metric` from `anchor`.
fn summary(res: &SimResult, k: usize, metric: Metric, anchor: Anchor) -> Option<Summary> {
    let stats: &ChainStats = res.chains.get(k)?;
    Summary::of_hist(&stats.observed(metric, anchor).hist)
}

/// Every chain and metric, in the order of the bounded report.
fn chain_metrics(spec: &Spec) -> impl Iterator<Item = (usize, Metric)> + '_ {
    (0..spec.chains.len()).flat_map(|k| [Metric::Reaction, Metric::Freshness].map(|m| (k, m)))
}

pub(super) fn to_json<'a>(
    spec: &'a Spec,
    a: &SimulateArgs,
    res: &SimResult,
    seconds: f64,
) -> ObservedReport<'a> {
    let chains = chain_metrics(spec)
        .map(|(k, metric)| ObservedChain {
            chain: spec.chain_label(k),
            metric: metric.name(),
            observed: observed_json(spec, summary(res, k, metric, Anchor::Read)),
            observed_from_event: observed_json(spec, summary(res, k, metric, Anchor::Event)),
        })
        .collect();
    let tasks = spec
        .tasks
        .iter()
        .zip(&res.tasks)
        .map(|(t, ts)| ObservedTask {
            name: &t.name,
            cpu: t.cpu,
            thread: t.thread.map(|th| spec.threads[th].name.as_str()),
            released: ts.released,
            merged: t.merges_releases().then_some(ts.merged),
            completed: ts.completed,
            max_response: time(spec, ts.max_response),
            late: ts.late,
            utilization: ts.busy as f64 / res.horizon as f64,
        })
        .collect();
    ObservedReport {
        system: &spec.name,
        time_unit: spec.time_unit.to_string(),
        bounds: None,
        note: NO_BOUNDS,
        chains,
        tasks,
        simulation: simulation_view(spec, a, res, seconds),
        search: Vec::new(),
    }
}

pub(super) fn to_text(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    res: &SimResult,
    seconds: f64,
) -> String {
    let mut out = run_lines(spec, a, p, res);
    if !spec.chains.is_empty() {
        out.push_str("\nchains (observed from the head's read; no bounds):\n");
        out.push_str(&chain_table(spec, res, Anchor::Read));
        out.push_str(
            "\nfrom the event just after each head read (reaction: to the first output that \
             reflects it; freshness: to the last output of the next sample):\n",
        );
        out.push_str(&chain_table(spec, res, Anchor::Event));
    }
    out.push_str("\ntasks (merged: releases that joined a queued job of the task):\n");
    out.push_str(&task_table(spec, res));
    out.push_str(&events_line(res, seconds));
    out
}

fn chain_table(spec: &Spec, res: &SimResult, anchor: Anchor) -> String {
    let mut t = Table::new(&["chain", "metric", "count", "min", "mean", "p99", "max"])
        .numeric(&[2, 3, 4, 5, 6]);
    for (k, metric) in chain_metrics(spec) {
        let dash = || "-".to_string();
        let row = match summary(res, k, metric, anchor) {
            Some(s) => [
                s.count.to_string(),
                spec.fmt_time(s.min),
                fmt_mean(spec, s.mean),
                format!("{}{}", if s.exact { "" } else { "~" }, spec.fmt_time(s.p99)),
                spec.fmt_time(s.max),
            ],
            None => ["0".into(), dash(), dash(), dash(), dash()],
        };
        let mut cells = vec![spec.chain_label(k), metric.name().to_string()];
        cells.extend(row);
        t.row(cells);
    }
    t.render()
}

fn task_table(spec: &Spec, res: &SimResult) -> String {
    let mut t = Table::new(&[
        "task",
        "thread",
        "cpu",
        "released",
        "merged",
        "completed",
        "max R",
        "late",
        "busy/horizon",
    ])
    .numeric(&[2, 3, 4, 5, 6, 7, 8]);
    for (task, ts) in spec.tasks.iter().zip(&res.tasks) {
        t.row(vec![
            task.name.clone(),
            task.thread
                .map_or_else(|| "-".into(), |th| spec.threads[th].name.clone()),
            task.cpu.to_string(),
            ts.released.to_string(),
            match task.merges_releases() {
                true => ts.merged.to_string(),
                false => "-".into(),
            },
            ts.completed.to_string(),
            ts.max_response
                .map_or_else(|| "-".into(), |r| spec.fmt_time(r)),
            ts.late.to_string(),
            format!("{:.4}", ts.busy as f64 / res.horizon as f64),
        ]);
    }
    t.render()
}
