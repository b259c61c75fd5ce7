//! `rtpipe analyze --margins`: the analysis' margins
//! (`rtpipe_analysis::margins`) as a table, JSON and a CSV file.

use crate::table::Table as TextTable;
use rtpipe_analysis::margins::{
    Breach, ExecMargin, Factor, LimitSlack, Margin, Margins, PeriodRange, Scaling,
};
use rtpipe_analysis::margins::{Control, MarginsError};
use rtpipe_analysis::Mode;
use rtpipe_model::Diagnostic;
use rtpipe_model::{Nanos, Spec};
use rtpipe_printer::{Cell, Column, Kind, Table};
use serde::Serialize;

/// The margins of `spec` under `mode`, with a progress line on stderr
/// (hidden when it is not a terminal); `None` when `stop` ended the search.
pub fn compute(
    spec: &Spec,
    mode: Mode,
    stop: &dyn Fn() -> bool,
) -> Result<Option<Margins>, Diagnostic> {
    let pb = crate::spinner(format!("margins of {} ({} mode)", spec.name, mode.name()));
    let progress = |done: usize, total: usize| {
        pb.set_message(format!(
            "margins of {} ({} mode): {done} of {total} searches",
            spec.name,
            mode.name()
        ));
    };
    let ctl = Control {
        stop,
        progress: &progress,
    };
    let found = rtpipe_analysis::margins::margins(spec, mode, &ctl);
    pb.finish_and_clear();
    match found {
        Ok(m) => Ok(Some(m)),
        Err(MarginsError::Stopped) => Ok(None),
    }
}

/// The answer when Ctrl-C (or SIGTERM, SIGHUP) stopped the margins:
/// nothing printed or written, the signal's exit status.
pub fn stopped() -> crate::command::Answer {
    crate::command::Answer {
        report: crate::command::Rendered::Nothing,
        notes: vec![format!(
            "stopped ({}) before the margins were complete: nothing printed, no file written",
            rtpipe_runtime::sys::stop_name()
        )],
        status: crate::interrupted_status(),
    }
}

/// What fails just beyond a margin, in words.
fn breach_text(spec: &Spec, b: &Breach) -> String {
    let name = |t: usize| spec.tasks[t].name.as_str();
    match *b {
        Breach::Rule { task, key } => rule_text(name(task), key),
        Breach::Schedulability { cpu } => format!("schedulability of cpu {cpu}"),
        Breach::MaxPeriod { task } => format!("max_period of {}", name(task)),
        Breach::Limit {
            chain,
            metric,
            anchor,
        } => format!("{} {}", spec.chain_label(chain), metric.key(anchor)),
        Breach::Unbounded { chain } => format!("{} unbounded", spec.chain_label(chain)),
    }
}

/// A timing rule of the model a task breaks, by its key.
fn rule_text(task: &str, key: &str) -> String {
    match key {
        "budget" => format!("budget of {task} (below its demand)"),
        "period" => format!("period of {task} (below its budget)"),
        other => format!("{other} of {task} (against its period)"),
    }
}

/// A signed time in the spec's unit ("+1.5", "-0.25").
fn signed(spec: &Spec, v: Nanos) -> String {
    let sign = if v < 0 { "-" } else { "+" };
    format!("{sign}{}", spec.fmt_time(v.abs()))
}

fn margin_text(spec: &Spec, m: Margin) -> String {
    match m {
        Margin::By(v) => signed(spec, v),
        Margin::Unlimited => "unlimited".into(),
        Margin::Unreachable => "none".into(),
    }
}

/// The margin in % of the exec it moves.
fn percent(m: Margin, exec: Nanos) -> Option<f64> {
    match m {
        Margin::By(v) if exec > 0 => Some(100.0 * v as f64 / exec as f64),
        _ => None,
    }
}

fn status(m: Margin) -> &'static str {
    match m {
        Margin::By(v) if v >= 0 => "holds",
        Margin::By(_) => "shrink",
        Margin::Unlimited => "unlimited",
        Margin::Unreachable => "unreachable",
    }
}

/// A critical scaling factor in words (six decimals).
pub(crate) fn factor_text(f: Factor) -> String {
    match f {
        Factor::Millionths(m) => format!("{}.{:06}", m / 1_000_000, m % 1_000_000),
        Factor::Unlimited => "unlimited".into(),
        Factor::Unreachable => "none".into(),
    }
}

/// A critical scaling factor as a number (`None`: unlimited or none).
pub(crate) fn factor_value(f: Factor) -> Option<f64> {
    match f {
        Factor::Millionths(m) => Some(m as f64 / 1e6),
        _ => None,
    }
}

/// The text section of `--margins`.
pub fn text(spec: &Spec, m: &Margins) -> String {
    let mut out = format!(
        "\nmargins ({} mode; {} analyses; each verified one step beyond):\n",
        m.mode.name(),
        m.evaluations
    );
    out.push_str("\nexec: the largest growth of one task's exec, the others unchanged\n");
    out.push_str(&exec_table(spec, &m.exec));
    if !m.limits.is_empty() {
        out.push_str(
            "\nchain limits: slack = limit - bound; the task whose exec growth eats it first\n",
        );
        out.push_str(&limit_table(spec, &m.limits));
    }
    out.push_str("\ncritical scaling factor: the largest factor on every exec\n");
    out.push_str(&scaling_table(spec, &m.cpus, &m.system));
    if !m.periods.is_empty() {
        out.push_str("\nperiods: the range that keeps everything, the others fixed\n");
        out.push_str(&period_table(spec, &m.periods));
        out.push_str(
            "  (a period is not monotone: each range is verified at its ends and checked at the periods counted)\n",
        );
    }
    if !m.exact {
        out.push_str("\nthe paper's bounds can fall when an exec grows (Eqs. 2, 4, 12): each margin is the verified edge nearest the spec's value, and a larger value may hold again\n");
    }
    if !m.holds {
        out.push_str("\nthe spec fails now: a negative margin is how much it must shrink, \"none\" that no value of it alone is enough\n");
    }
    out
}

fn breach_cell(spec: &Spec, b: Option<&Breach>) -> String {
    b.map(|b| breach_text(spec, b))
        .unwrap_or_else(|| "-".into())
}

fn exec_table(spec: &Spec, rows: &[ExecMargin]) -> String {
    let mut t =
        TextTable::new(&["task", "exec", "margin", "margin %", "limited by"]).numeric(&[1, 2, 3]);
    for e in rows {
        t.row(vec![
            spec.tasks[e.task].name.clone(),
            spec.fmt_time(e.exec),
            margin_text(spec, e.margin),
            percent(e.margin, e.exec).map_or("-".into(), |p| format!("{p:+.1}")),
            breach_cell(spec, e.breach.as_ref()),
        ]);
    }
    t.render()
}

fn limit_table(spec: &Spec, rows: &[LimitSlack]) -> String {
    let heads = [
        "chain",
        "key",
        "limit",
        "bound",
        "slack",
        "first eaten by",
        "its margin",
    ];
    let mut t = TextTable::new(&heads).numeric(&[2, 3, 4, 6]);
    for l in rows {
        let (who, margin) = match l.critical() {
            Some((task, m)) => (spec.tasks[task].name.clone(), margin_text(spec, m)),
            None => ("-".into(), "-".into()),
        };
        t.row(vec![
            spec.chain_label(l.chain),
            l.metric.key(l.anchor).to_string(),
            spec.fmt_time(l.limit),
            l.bound.map_or("unbounded".into(), |b| spec.fmt_time(b)),
            l.slack().map_or("-".into(), |s| signed(spec, s)),
            who,
            margin,
        ]);
    }
    t.render()
}

fn scaling_table(spec: &Spec, cpus: &[Scaling], system: &Scaling) -> String {
    let mut t = TextTable::new(&["tasks", "factor", "limited by"]).numeric(&[1]);
    let label = |s: &Scaling| s.cpu.map_or("all".into(), |c| format!("cpu {c}"));
    let multi = cpus.len() > 1;
    for s in cpus.iter().filter(|_| multi).chain([system]) {
        t.row(vec![
            label(s),
            factor_text(s.factor),
            breach_cell(spec, s.breach.as_ref()),
        ]);
    }
    t.render()
}

fn period_table(spec: &Spec, rows: &[PeriodRange]) -> String {
    let heads = [
        "task", "period", "least", "greatest", "below", "above", "checked",
    ];
    let mut t = TextTable::new(&heads).numeric(&[1, 2, 3, 6]);
    for p in rows {
        let (lo, hi) = match p.range {
            Some((lo, hi)) => (
                spec.fmt_time(lo),
                hi.map_or("unlimited".into(), |h| spec.fmt_time(h)),
            ),
            None => ("none".into(), "none".into()),
        };
        t.row(vec![
            spec.tasks[p.task].name.clone(),
            spec.fmt_time(p.period),
            lo,
            hi,
            breach_cell(spec, p.below.as_ref()),
            breach_cell(spec, p.above.as_ref()),
            p.probes.to_string(),
        ]);
    }
    t.render()
}

/// `--json`'s `margins`.
#[derive(Serialize, schemars::JsonSchema)]
pub struct MarginsView {
    /// The mode every verdict follows (`sound` or `paper`).
    mode: &'static str,
    /// The verdict on the spec as it is.
    holds: bool,
    /// The exec margins and factors are the exact largest values (sound
    /// mode), not only verified edges (paper mode).
    exact: bool,
    /// How many variants of the spec were analysed.
    evaluations: u64,
    /// One per task, in task order: how much its exec may grow.
    exec: Vec<ExecView>,
    /// One per chain limit: its slack and how each exec eats it.
    limits: Vec<LimitView>,
    /// The critical scaling factors: one per CPU with tasks, then the whole
    /// system.
    scaling: Vec<ScalingView>,
    /// One per task with a fixed period and a guarantee: the periods that keep
    /// the verdict.
    periods: Vec<PeriodView>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct ExecView {
    /// The task's name.
    task: String,
    /// Its exec in the spec, in the spec's time unit.
    exec: f64,
    /// null when unlimited or unreachable (`status` says which).
    margin: Option<f64>,
    /// The margin as a percentage of the exec.
    margin_percent: Option<f64>,
    /// `holds` (the exec may grow by `margin`), `shrink` (it must shrink),
    /// `unlimited` or `unreachable`.
    status: &'static str,
    /// What fails one nanosecond beyond the margin (null when unlimited).
    limited_by: Option<String>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct LimitView {
    /// The chain's label.
    chain: String,
    /// `reaction` or `freshness`.
    metric: &'static str,
    /// `read` or `event`: where the limit is measured from.
    from: &'static str,
    /// The spec key of the limit.
    key: &'static str,
    /// The limit, in the spec's time unit.
    limit: f64,
    /// The mode's bound, in the spec's time unit; null when unbounded.
    bound: Option<f64>,
    /// limit − bound, in the spec's time unit (negative: exceeded); null when
    /// unbounded.
    slack: Option<f64>,
    /// The task whose exec the bound is most sensitive to.
    first_eaten_by: Option<String>,
    /// Per task: the growth of its exec this limit alone allows (null:
    /// unlimited or unreachable).
    exec_margins: crate::report::Pairs<String, Option<f64>>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct ScalingView {
    /// null: every CPU together.
    cpu: Option<u32>,
    /// The largest factor on every exec (of the CPU) that keeps the verdict;
    /// null when unlimited or unreachable.
    factor: Option<f64>,
    /// `holds` (factor ≥ 1), `shrink` (every exec must shrink), `unlimited`
    /// or `unreachable`.
    status: &'static str,
    /// What fails just beyond the factor.
    limited_by: Option<String>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct PeriodView {
    /// The task's name.
    task: String,
    /// Its period in the spec, in the spec's time unit.
    period: f64,
    /// The least period found that keeps the verdict, in the spec's time unit;
    /// null when none was found.
    least: Option<f64>,
    /// null: unlimited (or no range).
    greatest: Option<f64>,
    /// Whether a period that keeps the verdict was found.
    found: bool,
    /// What fails one nanosecond below the range.
    below: Option<String>,
    /// What fails one nanosecond above it.
    above: Option<String>,
    /// Periods inside the range checked besides its ends (the verdict is not
    /// monotone in a period).
    checked: usize,
}

fn margin_value(spec: &Spec, m: Margin) -> Option<f64> {
    match m {
        Margin::By(v) => Some(spec.in_unit(v)),
        _ => None,
    }
}

/// The JSON view of `m`.
pub fn view(spec: &Spec, m: &Margins) -> MarginsView {
    let b = |b: &Option<Breach>| b.as_ref().map(|b| breach_text(spec, b));
    MarginsView {
        mode: m.mode.name(),
        holds: m.holds,
        exact: m.exact,
        evaluations: m.evaluations,
        exec: m.exec.iter().map(|e| exec_view(spec, e)).collect(),
        limits: m.limits.iter().map(|l| limit_view(spec, l)).collect(),
        scaling: m
            .cpus
            .iter()
            .chain([&m.system])
            .map(|s| ScalingView {
                cpu: s.cpu,
                factor: factor_value(s.factor),
                status: factor_status(s.factor),
                limited_by: b(&s.breach),
            })
            .collect(),
        periods: m.periods.iter().map(|p| period_view(spec, p)).collect(),
    }
}

fn factor_status(f: Factor) -> &'static str {
    match f {
        Factor::Millionths(m) if m >= 1_000_000 => "holds",
        Factor::Millionths(_) => "shrink",
        Factor::Unlimited => "unlimited",
        Factor::Unreachable => "unreachable",
    }
}

fn exec_view(spec: &Spec, e: &ExecMargin) -> ExecView {
    ExecView {
        task: spec.tasks[e.task].name.clone(),
        exec: spec.in_unit(e.exec),
        margin: margin_value(spec, e.margin),
        margin_percent: percent(e.margin, e.exec),
        status: status(e.margin),
        limited_by: e.breach.as_ref().map(|b| breach_text(spec, b)),
    }
}

fn limit_view(spec: &Spec, l: &LimitSlack) -> LimitView {
    LimitView {
        chain: spec.chain_label(l.chain),
        metric: l.metric.name(),
        from: l.anchor.name(),
        key: l.metric.key(l.anchor),
        limit: spec.in_unit(l.limit),
        bound: l.bound.map(|b| spec.in_unit(b)),
        slack: l.slack().map(|s| spec.in_unit(s)),
        first_eaten_by: l.critical().map(|(t, _)| spec.tasks[t].name.clone()),
        exec_margins: crate::report::Pairs(
            l.per_task
                .iter()
                .enumerate()
                .map(|(t, m)| (spec.tasks[t].name.clone(), margin_value(spec, *m)))
                .collect(),
        ),
    }
}

fn period_view(spec: &Spec, p: &PeriodRange) -> PeriodView {
    let b = |b: &Option<Breach>| b.as_ref().map(|b| breach_text(spec, b));
    PeriodView {
        task: spec.tasks[p.task].name.clone(),
        period: spec.in_unit(p.period),
        least: p.range.map(|(lo, _)| spec.in_unit(lo)),
        greatest: p.range.and_then(|(_, hi)| hi).map(|h| spec.in_unit(h)),
        found: p.range.is_some(),
        below: b(&p.below),
        above: b(&p.above),
        checked: p.probes,
    }
}

/// One row of the `--margins-csv` file (empty cells where a column does
/// not apply to its kind).
#[derive(Default)]
struct CsvRow {
    kind: &'static str,
    subject: String,
    key: &'static str,
    value: Option<f64>,
    limit: Option<f64>,
    margin: Option<f64>,
    margin_percent: Option<f64>,
    least: Option<f64>,
    greatest: Option<f64>,
    factor: Option<f64>,
    status: &'static str,
    limited_by: String,
    first_eaten_by: String,
}

/// The columns of the margins' table.
const CSV_COLUMNS: [&str; 13] = [
    "kind",
    "subject",
    "key",
    "value",
    "limit",
    "margin",
    "margin_percent",
    "least",
    "greatest",
    "factor",
    "status",
    "limited_by",
    "first_eaten_by",
];

impl CsvRow {
    /// The row's cells, in [`CSV_COLUMNS`]' order.
    fn cells(self) -> Vec<Cell> {
        let mut cells = vec![
            Cell::from(self.kind),
            Cell::Text(self.subject),
            Cell::from(self.key),
        ];
        cells.extend(
            [
                self.value,
                self.limit,
                self.margin,
                self.margin_percent,
                self.least,
                self.greatest,
                self.factor,
            ]
            .map(Cell::opt_float),
        );
        cells.extend([
            Cell::from(self.status),
            Cell::Text(self.limited_by),
            Cell::Text(self.first_eaten_by),
        ]);
        cells
    }
}

/// The `--margins-csv` file: the margins' table as CSV.
pub fn csv(spec: &Spec, m: &Margins) -> String {
    rtpipe_printer::csv::table(&table(spec, m))
}

/// The margins' table: one row per margin, times in the spec's unit.
pub fn table(spec: &Spec, m: &Margins) -> Table {
    let b = |b: &Option<Breach>| b.as_ref().map(|b| breach_text(spec, b)).unwrap_or_default();
    let exec = m.exec.iter().map(|e| CsvRow {
        kind: "exec",
        subject: spec.tasks[e.task].name.clone(),
        key: "exec",
        value: Some(spec.in_unit(e.exec)),
        margin: margin_value(spec, e.margin),
        margin_percent: percent(e.margin, e.exec),
        status: status(e.margin),
        limited_by: b(&e.breach),
        ..CsvRow::default()
    });
    let limits = m.limits.iter().map(|l| CsvRow {
        kind: "limit",
        subject: spec.chain_label(l.chain),
        key: l.metric.key(l.anchor),
        value: l.bound.map(|v| spec.in_unit(v)),
        limit: Some(spec.in_unit(l.limit)),
        margin: l.slack().map(|s| spec.in_unit(s)),
        status: slack_status(l),
        first_eaten_by: l
            .critical()
            .map(|(t, _)| spec.tasks[t].name.clone())
            .unwrap_or_default(),
        ..CsvRow::default()
    });
    let scaling = m.cpus.iter().chain([&m.system]).map(|s| CsvRow {
        kind: "scaling",
        subject: s.cpu.map_or("all".into(), |c| format!("cpu {c}")),
        key: "exec",
        factor: factor_value(s.factor),
        status: factor_status(s.factor),
        limited_by: b(&s.breach),
        ..CsvRow::default()
    });
    let periods = m.periods.iter().map(|p| period_row(spec, p));
    let rows = exec.chain(limits).chain(scaling).chain(periods);
    let kind = |name: &str| match name {
        "value" | "limit" | "margin" | "margin_percent" | "least" | "greatest" | "factor" => {
            Kind::Float
        }
        _ => Kind::Text,
    };
    let columns = CSV_COLUMNS.map(|n| Column::new(n, kind(n))).into();
    let Ok(mut t) = Table::new("margins", columns) else {
        unreachable!("the margins' columns are distinct names");
    };
    for r in rows {
        t.push(r.cells());
    }
    t
}

fn slack_status(l: &LimitSlack) -> &'static str {
    match l.slack() {
        Some(s) if s >= 0 => "holds",
        Some(_) => "exceeded",
        None => "unbounded",
    }
}

fn period_row(spec: &Spec, p: &PeriodRange) -> CsvRow {
    let b = |b: &Option<Breach>| b.as_ref().map(|b| breach_text(spec, b));
    let status = match p.range {
        None => "unreachable",
        Some((lo, hi)) if lo <= p.period && hi.is_none_or(|h| p.period <= h) => "holds",
        Some(_) => "moved",
    };
    CsvRow {
        kind: "period",
        subject: spec.tasks[p.task].name.clone(),
        key: "period",
        value: Some(spec.in_unit(p.period)),
        least: p.range.map(|(lo, _)| spec.in_unit(lo)),
        greatest: p.range.and_then(|(_, hi)| hi).map(|h| spec.in_unit(h)),
        status,
        limited_by: [b(&p.below), b(&p.above)]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join("; "),
        ..CsvRow::default()
    }
}
