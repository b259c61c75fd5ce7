//! The report of a simulation: text tables and JSON.

use super::*;
use crate::report::analysis::{ChainView, ReportView, TaskView};
use crate::report::{time, Pairs};
use rtpipe_sim::observe::Summary;
use serde::Serialize;

#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct SearchView {
    /// The chain's label.
    chain: String,
    /// `reaction` or `freshness`.
    metric: &'static str,
    /// `read` or `event`: where the latency starts.
    from: &'static str,
    /// The worst latency the search found, in the spec's time unit (a lower
    /// bound on the true worst case).
    found: Option<f64>,
    /// The paper's bound, in the spec's time unit.
    paper: Option<f64>,
    /// The sound bound, in the spec's time unit.
    sound: Option<f64>,
    /// found / sound: how close the bound is to a latency that happens.
    tightness: Option<f64>,
    /// Simulations the search ran.
    simulations: u64,
    /// The release offsets of the worst case found, in the spec's time unit,
    /// per task.
    offsets: Vec<f64>,
    /// The demands of the worst case found.
    exec: String,
    /// The seed that reproduces it.
    seed: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    known_offsets: Option<SearchKnown>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct SearchKnown {
    sound: Option<f64>,
    basis: String,
    tightness: Option<f64>,
}

pub(super) fn search_json(spec: &Spec, rs: &[SearchResult]) -> Vec<SearchView> {
    rs.iter()
        .map(|r| SearchView {
            chain: spec.chain_label(r.chain),
            metric: r.metric.name(),
            from: r.anchor.name(),
            found: time(spec, r.value),
            paper: time(spec, r.paper),
            sound: time(spec, r.sound),
            tightness: r.tightness(),
            simulations: r.simulations,
            offsets: r.best.offsets.iter().map(|&o| spec.in_unit(o)).collect(),
            exec: format!("{:?}", r.best.exec).to_lowercase(),
            seed: r.best.seed,
            known_offsets: r.known.as_ref().map(|k| SearchKnown {
                sound: time(spec, k.value),
                basis: k.label(spec),
                tightness: r.tightness_known(),
            }),
        })
        .collect()
}

pub(super) fn search_text(spec: &Spec, rs: &[SearchResult]) -> String {
    let known = rs.iter().any(|r| r.known.is_some());
    let mut header = vec![
        "chain",
        "metric",
        "from",
        "found",
        "paper",
        "sound",
        "found/sound",
        "above paper",
        "simulations",
    ];
    if known {
        header.extend(["known offsets", "found/known"]);
    }
    let mut t = Table::new(&header).numeric(&[3, 4, 5, 6, 8, 9, 10]);
    for r in rs {
        let f = |v: Option<Nanos>| v.map_or("-".to_string(), |n| spec.fmt_time(n));
        let mut row = vec![
            spec.chain_label(r.chain),
            r.metric.name().to_string(),
            r.anchor.name().to_string(),
            f(r.value),
            f(r.paper),
            f(r.sound),
            r.tightness().map_or("-".into(), |x| format!("{x:.4}")),
            match (r.value, r.paper) {
                (Some(v), Some(p)) if v > p => "yes".into(),
                // No paper bound (a spec the analysis does not bound yet).
                (_, None) => "-".into(),
                _ => "no".into(),
            },
            r.simulations.to_string(),
        ];
        if known {
            row.push(f(r.known.as_ref().and_then(|k| k.value)));
            row.push(
                r.tightness_known()
                    .map_or("-".into(), |x| format!("{x:.4}")),
            );
        }
        t.row(row);
    }
    format!(
        "\nadversarial search (a lower bound on the true worst case; found/sound brackets it):\n{}",
        t.render()
    )
}

/// `simulate --json`: the observations report, the run, and the adversarial
/// search when one ran.
#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct SimulateView<'a> {
    #[serde(flatten)]
    report: ReportView<'a, Extended<TaskView<'a>, TaskObserved>, ObsChain<'a>>,
    /// The run's settings and figures.
    simulation: SimulationView<'a>,
    /// With `phasing="search"`: the adversarial search's worst case per chain,
    /// metric and anchor.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub search: Vec<SearchView>,
}

/// A report entry with one more key at its end.
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "{B}{X}")]
pub(crate) struct Extended<B, X> {
    #[serde(flatten)]
    pub base: B,
    pub observed: X,
}

/// What the simulation observed of a task (counts of jobs; times in the
/// spec's unit).
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "Simulated")]
pub(super) struct TaskObserved {
    /// Jobs released.
    released: u64,
    /// Releases merged into a queued job (threads and data-triggered
    /// tasks only: absent, not 0, for the others).
    #[serde(skip_serializing_if = "Option::is_none")]
    merged: Option<u64>,
    /// Jobs completed.
    completed: u64,
    /// The largest response time observed, in the spec's time unit; null
    /// without a completed job.
    max_response: Option<f64>,
    /// Jobs that finished after their period (or deadline).
    late: u64,
    /// Times its server's budget ran out.
    exhaustions: u64,
    /// The share of the CPU it used over the run.
    utilization: f64,
}

#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct SimulationView<'a> {
    /// The simulated time, in the spec's time unit.
    horizon: f64,
    /// The seed of the random offsets and demands.
    seed: u64,
    /// How demands were drawn (`worst`, `uniform`, `best`, `extremes`).
    exec: String,
    /// How release offsets were chosen (`sync`, `random`, `search`).
    phasing: String,
    /// Each task's release offset, in the spec's time unit.
    offsets: Pairs<&'a str, f64>,
    /// Scheduler events simulated.
    events: u64,
    /// Wall-clock seconds the simulation took.
    seconds: f64,
}

pub(super) fn to_json<'a>(
    spec: &'a Spec,
    report: &Report,
    a: &SimulateArgs,
    res: &SimResult,
    obs: &[ChainObs],
    seconds: f64,
) -> SimulateView<'a> {
    let observed = |ts: &rtpipe_joblog::TaskStats, t: &rtpipe_model::Task| TaskObserved {
        released: ts.released,
        merged: t.merges_releases().then_some(ts.merged),
        completed: ts.completed,
        max_response: time(spec, ts.max_response),
        late: ts.late,
        exhaustions: ts.exhaustions,
        utilization: ts.busy as f64 / res.horizon as f64,
    };
    let report = observations_view(spec, report, obs).with(
        |tasks| {
            tasks
                .into_iter()
                .zip(res.tasks.iter().zip(&spec.tasks))
                .map(|(base, (ts, t))| Extended {
                    base,
                    observed: observed(ts, t),
                })
                .collect()
        },
        |chains| chains,
    );
    SimulateView {
        report,
        simulation: simulation_view(spec, a, res, seconds),
        search: Vec::new(),
    }
}

/// The run's settings and figures in `--json`.
pub(super) fn simulation_view<'a>(
    spec: &'a Spec,
    a: &SimulateArgs,
    res: &SimResult,
    seconds: f64,
) -> SimulationView<'a> {
    let offsets = spec.tasks.iter().zip(&res.offsets);
    SimulationView {
        horizon: spec.in_unit(res.horizon),
        seed: a.seed(),
        exec: flag_name(&a.exec),
        phasing: flag_name(&a.phasing),
        offsets: Pairs(
            offsets
                .map(|(t, &o)| (t.name.as_str(), spec.in_unit(o)))
                .collect(),
        ),
        events: res.events,
        seconds,
    }
}

/// A chain entry of the report with its observations from the read and
/// from the event.
#[derive(Serialize, schemars::JsonSchema)]
pub(crate) struct ObsChain<'a> {
    #[serde(flatten)]
    base: ChainView<'a>,
    /// The latencies observed from the read (the head's sample).
    observed: ObservedView,
    /// Samples above the bounds, from the read.
    violations: Violations,
    /// The latencies observed from the external event.
    observed_from_event: ObservedView,
    /// Samples above the bounds, from the event.
    violations_from_event: Violations,
}

#[derive(Serialize, schemars::JsonSchema)]
struct Violations {
    /// Samples above the paper's bound.
    paper: usize,
    /// Samples above the sound bound; null when the bound is unbounded.
    sound: Option<usize>,
}

impl Violations {
    fn of(j: &Judged) -> Self {
        Violations {
            paper: j.over_paper,
            sound: j.over_sound,
        }
    }
}

/// The `analyze --json` report with each chain entry's observations from the
/// read and from the event.
pub(crate) fn observations_view<'a>(
    spec: &'a Spec,
    report: &Report,
    obs: &[ChainObs],
) -> ReportView<'a, TaskView<'a>, ObsChain<'a>> {
    let chain = |(mut base, o): (ChainView<'a>, &ChainObs)| {
        if let (Some(k), Some([read, event])) = (base.known_offsets.as_mut(), &o.known) {
            k.violations = Some(read.over);
            k.from_event.violations = Some(event.over);
        }
        ObsChain {
            base,
            observed: observed_json(spec, o.read.observed),
            violations: Violations::of(&o.read),
            observed_from_event: observed_json(spec, o.event.observed),
            violations_from_event: Violations::of(&o.event),
        }
    };
    crate::report::analysis::report_view(spec, report).with(
        |tasks| tasks,
        |chains| chains.into_iter().zip(obs).map(chain).collect(),
    )
}

/// {count, min, mean, p99, max, variation} in the spec's unit; variation =
/// max − min, the spread the paper's Fig. 10 reports (MaxRV, MaxFV); all
/// but the count null without observations.
#[derive(Serialize, schemars::JsonSchema)]
pub(crate) struct ObservedView {
    /// The samples observed.
    count: usize,
    /// The smallest, in the spec's time unit.
    min: Option<f64>,
    /// The mean, in the spec's time unit.
    mean: Option<f64>,
    /// The 99th percentile, in the spec's time unit.
    p99: Option<f64>,
    /// The largest, in the spec's time unit.
    max: Option<f64>,
    /// max − min, in the spec's time unit (the paper's MaxRV and MaxFV).
    variation: Option<f64>,
}

pub(crate) fn observed_json(spec: &Spec, s: Option<Summary>) -> ObservedView {
    let unit = spec.time_unit.nanos() as f64;
    ObservedView {
        count: s.map_or(0, |s| s.count),
        min: s.map(|s| spec.in_unit(s.min)),
        mean: s.map(|s| s.mean / unit),
        p99: s.map(|s| spec.in_unit(s.p99)),
        max: s.map(|s| spec.in_unit(s.max)),
        variation: s.map(|s| spec.in_unit(s.max - s.min)),
    }
}

/// A mean in the spec's unit, to a thousandth of the unit.
pub(super) fn fmt_mean(spec: &Spec, mean_ns: f64) -> String {
    let step = (spec.time_unit.nanos() / 1000).max(1) as f64;
    spec.fmt_time(((mean_ns / step).round() * step) as Nanos)
}

/// A duration for people in the largest unit that keeps it at least 1
/// ("300.01 s"), when that differs from the spec's unit.
pub(super) fn human(spec: &Spec, ns: Nanos) -> String {
    let unit = TimeUnit::ALL
        .iter()
        .rev()
        .copied()
        .find(|u| ns >= u.nanos())
        .unwrap_or(TimeUnit::Ns);
    if unit == spec.time_unit {
        return String::new();
    }
    let x = unit.from_nanos(ns);
    let v = format!("{x:.2}");
    let v = v.trim_end_matches('0').trim_end_matches('.');
    format!(" ({v} {unit})")
}

/// 1234567 → "1.23M".
pub(super) fn si(x: f64) -> String {
    match x {
        x if x >= 1e9 => format!("{:.2}G", x / 1e9),
        x if x >= 1e6 => format!("{:.2}M", x / 1e6),
        x if x >= 1e3 => format!("{:.1}k", x / 1e3),
        x => format!("{x:.0}"),
    }
}

/// One row per chain and metric: the observations from `a` against the
/// bounds from `a`.
pub(crate) fn chain_table(spec: &Spec, obs: &[ChainObs], a: Anchor) -> String {
    let mut t = Table::new(&[
        "chain",
        "metric",
        "count",
        "min",
        "mean",
        "p99",
        "max",
        "paper",
        "sound",
        ">paper",
        ">sound",
        "max/sound",
    ])
    .numeric(&[2, 3, 4, 5, 6, 7, 8, 9, 10, 11]);
    for o in obs {
        let j = o.from(a);
        let dash = || "-".to_string();
        let (count, min, mean, p99, max) = match j.observed {
            Some(s) => (
                s.count.to_string(),
                spec.fmt_time(s.min),
                fmt_mean(spec, s.mean),
                format!("{}{}", if s.exact { "" } else { "~" }, spec.fmt_time(s.p99)),
                spec.fmt_time(s.max),
            ),
            None => ("0".into(), dash(), dash(), dash(), dash()),
        };
        let ratio = match (j.observed, j.sound) {
            (Some(s), Some(b)) if b > 0 => format!("{:.3}", s.max as f64 / b as f64),
            _ => dash(),
        };
        let over_sound = match j.over_sound {
            Some(0) => "0".to_string(),
            Some(n) => format!("{n} !!"),
            None => dash(),
        };
        t.row(vec![
            spec.chain_label(o.chain),
            o.metric.name().to_string(),
            count,
            min,
            mean,
            p99,
            max,
            spec.fmt_time(j.paper),
            j.sound
                .map_or_else(|| "unbounded".into(), |s| spec.fmt_time(s)),
            j.over_paper.to_string(),
            over_sound,
            ratio,
        ]);
    }
    let mut out = t.render();
    if obs
        .iter()
        .any(|o| o.from(a).observed.is_some_and(|s| !s.exact))
    {
        out.push_str(&format!(
            "  ~ p99 within {:.2} % (below the {} highest distinct values of a chain's latency, counted exactly, values are log-bucketed; count, min, mean, max and the counts above a bound stay exact but for values that close to it)\n",
            100.0 / f64::from(1u32 << rtpipe_joblog::hist::COARSE_BITS),
            rtpipe_joblog::hist::exact_cap(4 * spec.chains.len()) / 2
        ));
    }
    out
}

/// The observations against the bounds under the spec's known offsets,
/// for the chains with any (nothing when none has).
pub(crate) fn known_table(spec: &Spec, obs: &[ChainObs]) -> String {
    if obs.iter().all(|o| o.known.is_none()) {
        return String::new();
    }
    let mut t = Table::new(&[
        "chain",
        "metric",
        "from",
        "count",
        "max",
        "bound",
        ">bound",
        "max/bound",
        "basis",
    ])
    .numeric(&[3, 4, 5, 6, 7]);
    for o in obs {
        for a in Anchor::ALL {
            let (Some(k), j) = (o.known_from(a), o.from(a)) else {
                continue;
            };
            let max = j.observed.map(|s| s.max);
            let ratio = match (max, k.bound.value) {
                (Some(m), Some(b)) if b > 0 => format!("{:.3}", m as f64 / b as f64),
                _ => "-".to_string(),
            };
            t.row(vec![
                spec.chain_label(o.chain),
                o.metric.name().to_string(),
                a.name().to_string(),
                j.observed.map_or(0, |s| s.count).to_string(),
                max.map_or_else(|| "-".into(), |m| spec.fmt_time(m)),
                k.bound
                    .value
                    .map_or_else(|| "-".into(), |b| spec.fmt_time(b)),
                match k.over {
                    0 => "0".to_string(),
                    n => format!("{n} !!"),
                },
                ratio,
                k.bound.label(spec),
            ]);
        }
    }
    format!(
        "\nagainst the bounds under the spec's known release offsets (every run releases a task \
         with a known offset at it; these bounds, not the ones above, hold for such a chain):\n{}",
        t.render()
    )
}

pub(super) fn to_text(
    spec: &Spec,
    report: &Report,
    a: &SimulateArgs,
    p: &Plan,
    res: &SimResult,
    obs: &[ChainObs],
    seconds: f64,
) -> String {
    let mut out = run_lines(spec, a, p, res);
    if !obs.is_empty() {
        out.push_str(
            "\nchains (observed from the head's read, against the analysis' worst-case bounds):\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Read));
        out.push_str(
            "\nfrom the event just after each head read (reaction: to the first output that \
             reflects it; freshness: to the last output of the next sample), against the +event bounds:\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Event));
        out.push_str(&known_table(spec, obs));
    }
    out.push_str(if spec.event_triggered() {
        "\ntasks (R(job): the analysed worst-case job response time, from a job's first release; merged: releases that joined a queued job of the task):\n"
    } else {
        "\ntasks (R(job): the analysed worst-case job response time):\n"
    });
    out.push_str(&task_table(spec, report, res));
    out.push_str(&events_line(res, seconds));
    out.push_str(&verdict_text(spec, report, res, obs));
    out
}

/// The system, the simulated span and settings, and the offsets when any
/// is not 0.
pub(super) fn run_lines(spec: &Spec, a: &SimulateArgs, p: &Plan, res: &SimResult) -> String {
    let u = spec.time_unit;
    let mut out = crate::report::analysis::system_line(spec);
    let span = match p.outputs {
        Some(n) => format!(", >= {n} outputs of every chain's tail"),
        None => String::new(),
    };
    out.push_str(&format!(
        "simulated {} {u}{}{span}; seed {}, exec {}, phasing {}\n",
        spec.fmt_time(res.horizon),
        human(spec, res.horizon),
        a.seed(),
        flag_name(&a.exec),
        flag_name(&a.phasing)
    ));
    if res.offsets.iter().any(|&o| o != 0) {
        let offs: Vec<String> = spec
            .tasks
            .iter()
            .zip(&res.offsets)
            // A data-triggered task has no offset: its triggers release it.
            .filter(|(t, _)| !t.is_triggered())
            .map(|(t, &o)| format!("{}={}", t.name, spec.fmt_time(o)))
            .collect();
        out.push_str(&format!("offsets: {}\n", offs.join(" ")));
    }
    out
}

/// How many events the run took and how fast.
pub(super) fn events_line(res: &SimResult, seconds: f64) -> String {
    let eps = if seconds > 0.0 {
        res.events as f64 / seconds
    } else {
        0.0
    };
    format!(
        "\n{} events simulated in {seconds:.3} s ({} events/s)\n",
        res.events,
        si(eps)
    )
}

/// Per task: jobs released and completed, the largest response time seen
/// against the analysed one (`!!` when above), late jobs, exhaustions, load.
fn task_table(spec: &Spec, report: &Report, res: &SimResult) -> String {
    // Threads and data-triggered tasks add how many releases joined a
    // queued job (`merged`; "-" for a task whose jobs queue instead).
    let merging = spec.event_triggered();
    let mut head = vec!["task", "cpu", "released"];
    head.extend(merging.then_some("merged"));
    head.extend([
        "completed",
        "max R",
        "R(job)",
        "late",
        "exhaustions",
        "busy/horizon",
    ]);
    let numeric: Vec<usize> = (1..head.len()).collect();
    let mut t = Table::new(&head).numeric(&numeric);
    for ((task, ts), tm) in spec.tasks.iter().zip(&res.tasks).zip(&report.timing) {
        let over = matches!((ts.max_response, tm.bounded_response()), (Some(s), Some(r)) if s > r);
        let merged = match task.merges_releases() {
            true => ts.merged.to_string(),
            false => "-".into(),
        };
        t.row(
            vec![
                task.name.clone(),
                task.cpu.to_string(),
                ts.released.to_string(),
            ]
            .into_iter()
            .chain(merging.then_some(merged))
            .chain([
                ts.completed.to_string(),
                ts.max_response
                    .map_or_else(|| "-".into(), |r| spec.fmt_time(r))
                    + if over { " !!" } else { "" },
                tm.job_response_time
                    .map_or_else(|| "unbounded".into(), |r| spec.fmt_time(r)),
                ts.late.to_string(),
                ts.exhaustions.to_string(),
                format!("{:.4}", ts.busy as f64 / res.horizon as f64),
            ])
            .collect(),
        );
    }
    t.render()
}

/// The verdict line (and a note on jobs that finished after their period).
fn verdict_text(spec: &Spec, report: &Report, res: &SimResult, obs: &[ChainObs]) -> String {
    let mut out = String::new();
    let over_sound: usize = obs.iter().map(ChainObs::violations).sum();
    let over_paper: usize = obs
        .iter()
        .map(|o| o.read.over_paper + o.event.over_paper)
        .sum();
    let late_rt = response_violations(report, res).len();
    // Background tasks have no deadline: their backlog is not a miss.
    let late: u64 = res
        .tasks
        .iter()
        .zip(&spec.tasks)
        .filter(|(_, t)| t.server != rtpipe_model::Server::Background)
        .map(|(r, _)| r.late)
        .sum();
    let verdict = if over_sound > 0 || late_rt > 0 {
        format!(
            "verdict: SOUND BOUND EXCEEDED ({over_sound} sample(s), {late_rt} task response time(s)): a bug in the analysis or the simulator"
        )
    } else {
        let paper = match over_paper {
            0 => "none above the paper bounds either".to_string(),
            n => format!(
                "{n} above the paper bounds (the published equations are not upper bounds here)"
            ),
        };
        format!("verdict: no sample above a sound bound; {paper}")
    };
    out.push_str(&verdict);
    out.push('\n');
    let over_any: usize = obs.iter().map(ChainObs::over_sound).sum();
    if over_any > over_sound {
        out.push_str(&format!(
            "note: {} sample(s) above an arbitrary-phasing bound, which does not cover a task \
             that starts later than one period; the known-offset bounds hold\n",
            over_any - over_sound
        ));
    }
    if late > 0 {
        out.push_str(&format!(
            "note: {late} job(s) finished after their period: the system breaks the model's assumptions\n"
        ));
    }
    out
}

/// `rtpipe simulate`'s report: the analysis, what the run and the
/// adversarial searches observed, as text, JSON or tables.
pub(super) struct SimulateReport<'a> {
    pub spec: &'a Spec,
    pub args: &'a SimulateArgs,
    pub plan: &'a Plan,
    pub report: &'a Report,
    pub res: &'a SimResult,
    pub obs: &'a [ChainObs],
    pub searches: &'a [SearchResult],
    pub seconds: f64,
}

impl Serialize for SimulateReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (spec, r) = (self.spec, self.report);
        let mut v = to_json(spec, r, self.args, self.res, self.obs, self.seconds);
        v.search = search_json(spec, self.searches);
        v.serialize(s)
    }
}

impl rtpipe_printer::Report for SimulateReport<'_> {
    fn text(&self) -> String {
        let (spec, r) = (self.spec, self.report);
        let mut t = to_text(
            spec,
            r,
            self.args,
            self.plan,
            self.res,
            self.obs,
            self.seconds,
        );
        if !self.searches.is_empty() {
            t.push_str(&search_text(spec, self.searches));
        }
        t
    }

    /// The analysis' tasks and chains, then what was observed of each
    /// chain from each anchor.
    fn tables(&self) -> Vec<rtpipe_printer::Table> {
        let mut ts = crate::report::analysis::tables(self.spec, self.report);
        ts.push(observed_table(self.spec, self.obs));
        ts
    }
}

/// A row per chain, metric and anchor: the observations' summary beside
/// the bounds, times in the spec's unit.
pub(crate) fn observed_table(spec: &Spec, obs: &[ChainObs]) -> rtpipe_printer::Table {
    use rtpipe_printer::{Cell, Column, Kind, Table};
    let mut columns: Vec<Column> = ["chain", "metric", "from"]
        .map(|n| Column::new(n, Kind::Text))
        .into();
    columns.push(Column::new("count", Kind::UInt));
    columns.extend(
        ["min", "mean", "p99", "max", "paper", "sound"].map(|n| Column::new(n, Kind::Float)),
    );
    columns.push(Column::new("over_paper", Kind::UInt));
    columns.push(Column::new("over_sound", Kind::OptInt));
    let Ok(mut t) = Table::new("observed", columns) else {
        unreachable!("the observed table's columns are distinct names");
    };
    let at = |ns: Option<Nanos>| Cell::opt_float(ns.map(|n| spec.in_unit(n)));
    let count = |n: usize| Cell::UInt(u64::try_from(n).unwrap_or(u64::MAX));
    for o in obs {
        for anchor in Anchor::ALL {
            let j = o.from(anchor);
            let s = j.observed.as_ref();
            t.push(vec![
                Cell::from(spec.chain_label(o.chain)),
                Cell::from(o.metric.name()),
                Cell::from(anchor.name()),
                count(s.map_or(0, |s| s.count)),
                at(s.map(|s| s.min)),
                Cell::opt_float(s.map(|s| s.mean / spec.time_unit.nanos() as f64)),
                at(s.map(|s| s.p99)),
                at(s.map(|s| s.max)),
                at(Some(j.paper)),
                at(j.sound),
                count(j.over_paper),
                Cell::opt_int(j.over_sound.and_then(|n| i64::try_from(n).ok())),
            ]);
        }
    }
    t
}
