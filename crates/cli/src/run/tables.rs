//! The run's text tables: one row per task (what its jobs measured against
//! the analysis) and one per resource (its critical sections as held).

use crate::table::Table;
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::{Policy, RunResult};
use rtpipe_sim::observe::Summary;

/// One row per task: jobs, measured response times (`!!` marks a max above
/// the analysed R(job)), start latency, CPU time against the budget,
/// overruns and missed periods; with work-queue threads or data-triggered
/// tasks, the releases merged into a queued job too.
pub(super) fn task_table(spec: &Spec, report: &Report, res: &RunResult) -> String {
    let merging = spec.event_triggered();
    let mut head = vec![
        "task",
        "cpu",
        "prio",
        "jobs",
        "mean R",
        "p99 R",
        "max R",
        "R(job)",
        "max start",
        "max demand",
        "budget",
        "overruns",
        "missed",
    ];
    if merging {
        head.push("merged");
    }
    let numeric: Vec<usize> = (1..head.len()).collect();
    let mut t = Table::new(&head).numeric(&numeric);
    for (((task, ts), tr), tm) in spec
        .tasks
        .iter()
        .zip(&res.sim.tasks)
        .zip(&res.tasks)
        .zip(&report.timing)
    {
        let s = Summary::of(&tr.responses);
        let f = |x: Option<Nanos>| x.map_or_else(|| "-".into(), |r| spec.fmt_time(r));
        let over = matches!((ts.max_response, tm.bounded_response()), (Some(s), Some(r)) if s > r);
        let mut row = vec![
            task.name.clone(),
            if res.policy == Policy::Deadline && !res.partitioned {
                "any".into()
            } else {
                task.cpu.to_string()
            },
            tr.priority.map_or_else(|| "-".into(), |p| p.to_string()),
            ts.completed.to_string(),
            s.map_or_else(|| "-".into(), |s| spec.fmt_time(s.mean as Nanos)),
            f(s.map(|s| s.p99)),
            f(ts.max_response) + if over { " !!" } else { "" },
            tm.job_response_time
                .map_or_else(|| "unbounded".into(), |r| spec.fmt_time(r)),
            spec.fmt_time(tr.max_start),
            spec.fmt_time(tr.max_demand),
            spec.fmt_time(task.budget()),
            tr.overruns.to_string(),
            tr.missed.to_string(),
        ];
        if merging {
            row.push(ts.merged.to_string());
        }
        t.row(row);
    }
    t.render()
}

/// One row per resource: the sections that held it, the longest hold, the
/// overlaps.
pub(super) fn sections_table(spec: &Spec, res: &RunResult) -> String {
    let holds: Vec<_> = res
        .tasks
        .iter()
        .flat_map(|t| t.sections.iter().copied())
        .collect();
    let mut t = Table::new(&["resource", "holds", "max held", "overlaps"]).numeric(&[1, 2, 3]);
    let rows = rtpipe_runtime::locks::summary(spec.resources.len(), &holds);
    for (r, (n, longest, overlaps)) in spec.resources.iter().zip(rows) {
        t.row(vec![
            r.name.clone(),
            n.to_string(),
            spec.fmt_time(longest),
            overlaps.to_string(),
        ]);
    }
    t.render()
}
