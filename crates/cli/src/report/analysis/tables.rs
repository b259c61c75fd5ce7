//! The analysis report as tables (`--format csv`): a row per task and a
//! row per chain and metric, times in the spec's unit, an empty cell for
//! no value (unbounded, not given).

use rtpipe_analysis::{Anchor, Bound, Literature, Report};
use rtpipe_model::{Nanos, Spec};
use rtpipe_printer::{Cell, Column, Kind, Table};

/// The tasks' and the chains' tables.
pub fn tables(spec: &Spec, r: &Report) -> Vec<Table> {
    vec![task_table(spec, r), chain_table(spec, r)]
}

/// A time in the spec's unit, empty for none.
fn time(spec: &Spec, ns: Option<Nanos>) -> Cell {
    Cell::opt_float(ns.map(|n| spec.in_unit(n)))
}

fn task_table(spec: &Spec, r: &Report) -> Table {
    let text = ["task", "server"].map(|n| Column::new(n, Kind::Text));
    let ints = [
        Column::new("cpu", Kind::UInt),
        Column::new("priority", Kind::OptInt),
    ];
    let times = [
        "delta_in",
        "exec",
        "delta_out",
        "budget",
        "period",
        "deadline",
        "jitter",
        "blocking",
        "utilization",
        "response_time",
        "job_response_time",
    ]
    .map(|n| Column::new(n, Kind::Float));
    let columns = text.into_iter().chain(ints).chain(times).collect();
    let Ok(mut t) = Table::new("tasks", columns) else {
        unreachable!("the task table's columns are distinct names");
    };
    for (task, tm) in spec.tasks.iter().zip(&r.timing) {
        let priority = tm.priority.and_then(|p| i64::try_from(p).ok());
        t.push(vec![
            Cell::from(task.name.as_str()),
            Cell::from(task.server.name()),
            Cell::UInt(u64::from(tm.cpu)),
            Cell::opt_int(priority),
            time(spec, Some(task.delta_in)),
            time(spec, Some(task.exec)),
            time(spec, Some(task.delta_out)),
            time(spec, Some(tm.budget)),
            time(spec, Some(tm.period)),
            time(spec, task.deadline_given),
            time(spec, Some(task.jitter)),
            time(spec, (!spec.resources.is_empty()).then_some(tm.blocking)),
            Cell::Float(tm.budget as f64 / tm.period as f64),
            time(spec, tm.response_time),
            time(spec, tm.job_response_time),
        ]);
    }
    t
}

/// The chain table's columns: one per bound and anchor (`paper`, ...,
/// `paper_from_event`, ...), from [`Bound::ALL`] × [`Anchor::ALL`], and
/// the literature's names of the row's figures from each anchor.
fn chain_columns() -> Vec<Column> {
    let mut columns: Vec<Column> = ["chain", "metric"]
        .map(|n| Column::new(n, Kind::Text))
        .into();
    columns.extend(["limit", "event_limit"].map(|n| Column::new(n, Kind::Float)));
    for a in Anchor::ALL {
        let suffix = if a == Anchor::Event {
            "_from_event"
        } else {
            ""
        };
        columns
            .extend(Bound::ALL.map(|b| Column::new(format!("{}{suffix}", b.name()), Kind::Float)));
    }
    columns.extend(["paper_ok", "ok"].map(|n| Column::new(n, Kind::Bool)));
    // Last, so the earlier columns keep their places.
    columns.extend(["literature", "literature_from_event"].map(|n| Column::new(n, Kind::Text)));
    columns
}

/// The literature's quantities that `metric` from `anchor` is
/// (`Literature::of`), `;`-separated; empty for none.
fn literature(metric: rtpipe_analysis::Metric, anchor: Anchor) -> Cell {
    let names: Vec<&str> = Literature::of(metric, anchor)
        .map(Literature::name)
        .collect();
    Cell::from(names.join(";").as_str())
}

fn chain_table(spec: &Spec, r: &Report) -> Table {
    let Ok(mut t) = Table::new("chains", chain_columns()) else {
        unreachable!("the chain table's columns are distinct names");
    };
    for c in &r.chains {
        let mut row = vec![
            Cell::from(spec.chain_label(c.chain)),
            Cell::from(c.metric.name()),
            time(spec, c.limit),
            time(spec, c.event_limit),
        ];
        for a in Anchor::ALL {
            row.extend(c.bound.from(a).map(|(_, v)| time(spec, v)));
        }
        row.extend([Cell::Bool(c.paper_ok()), Cell::Bool(c.ok)]);
        row.extend(Anchor::ALL.map(|a| literature(c.metric, a)));
        t.push(row);
    }
    t
}
