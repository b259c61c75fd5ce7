//! The analysis report's views, which every command that reports an
//! analysis shares (`analyze`, `design`, `simulate`, `fly`, `run`): the
//! JSON entries of tasks, schedulability and chains, and their text.

mod events;
mod tables;

pub use tables::tables;

use crate::report::{time, Pairs};
use crate::table::Table;
use rtpipe_analysis::Bound;
use rtpipe_analysis::{AllPaths, Anchor, ChainOffsets, Literature, Metric, Mode, Report, Worst};
use rtpipe_model::{Nanos, Spec};
use serde::Serialize;

pub(crate) fn path_names(spec: &Spec, path: &[usize]) -> Vec<String> {
    path.iter().map(|&i| spec.tasks[i].name.clone()).collect()
}

/// The JSON report; `T` and `C` let `simulate` extend the task and chain
/// entries with what it observed.
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "AnalysisView")]
pub struct ReportView<'a, T = TaskView<'a>, C = ChainView<'a>> {
    /// The system's name (`[system] name`).
    pub system: &'a str,
    /// The unit of every time in the report (`ns`, `us`, `ms` or `s`).
    pub time_unit: &'static str,
    /// The scheduler analysed: `rm` (fixed priorities) or `edf`.
    pub scheduler: &'static str,
    /// "let" under LET communication; absent under implicit (the default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub communication: Option<&'static str>,
    /// One entry per task, in the spec's order.
    pub tasks: Vec<T>,
    /// The schedulability test and its verdict, per CPU.
    pub schedulability: SchedView,
    /// One entry per chain and metric (reaction, then freshness).
    pub chains: Vec<C>,
    /// Whether every task is schedulable and every chain keeps its limits under
    /// the sound bounds.
    pub ok: bool,
    /// The same verdict under the paper's bounds.
    pub paper_ok: bool,
}

impl<'a, T, C> ReportView<'a, T, C> {
    /// The same report with the task and chain entries replaced.
    pub fn with<T2, C2>(
        self,
        tasks: impl FnOnce(Vec<T>) -> Vec<T2>,
        chains: impl FnOnce(Vec<C>) -> Vec<C2>,
    ) -> ReportView<'a, T2, C2> {
        ReportView {
            system: self.system,
            time_unit: self.time_unit,
            scheduler: self.scheduler,
            communication: self.communication,
            tasks: tasks(self.tasks),
            schedulability: self.schedulability,
            chains: chains(self.chains),
            ok: self.ok,
            paper_ok: self.paper_ok,
        }
    }
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct TaskView<'a> {
    /// The task's name.
    name: &'a str,
    /// The server the task runs in (`main` for none).
    server: &'static str,
    /// p, its worst-case execution time, in the spec's time unit.
    exec: f64,
    /// Its best-case execution time, in the spec's time unit.
    exec_min: f64,
    /// Δin, the time to read its input channel, in the spec's time unit.
    delta_in: f64,
    /// Δout, the time to write its output channel, in the spec's time unit.
    delta_out: f64,
    /// Δin + p + Δout, its worst-case demand per job, in the spec's time unit.
    demand: f64,
    /// Its server budget, in the spec's time unit.
    budget: f64,
    /// T, its period, in the spec's time unit.
    period: f64,
    /// D, when the spec gives a deadline (else D = T, left out).
    #[serde(skip_serializing_if = "Option::is_none")]
    deadline: Option<f64>,
    /// J, when the task has release jitter (left out when 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    jitter: Option<f64>,
    /// B, blocking by lower-priority critical sections (left out when the
    /// spec declares no resources).
    #[serde(skip_serializing_if = "Option::is_none")]
    blocking: Option<f64>,
    /// The task's `max_period` and whether its period keeps to it (both
    /// left out when the spec gives none).
    #[serde(skip_serializing_if = "Option::is_none")]
    max_period: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    period_ok: Option<bool>,
    /// Its CPU utilisation, budget / period.
    utilization: f64,
    /// Its fixed priority on its CPU, 1 the highest; null under EDF.
    priority: Option<usize>,
    /// The CPU it runs on.
    cpu: u32,
    /// R(C), the time within which its server delivers its whole budget, in
    /// the spec's time unit (the `rta` verdict uses it); null when unbounded.
    response_time: Option<f64>,
    /// R(x), the time within which a job of demand x finishes, in the spec's
    /// time unit (the latency bounds use it); null when unbounded.
    job_response_time: Option<f64>,
    /// Its activations, in a spec with threads or data-triggered tasks.
    #[serde(skip_serializing_if = "Option::is_none")]
    activation: Option<events::ActivationView<'a>>,
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct SchedView {
    /// The schedulability test applied (e.g. `rta`).
    test: &'static str,
    /// The total utilisation of all CPUs.
    utilization: f64,
    /// The test's bound: a number for one CPU, a list with one per CPU.
    bound: OneOrMany,
    /// Whether every CPU passes the test.
    schedulable: bool,
    /// The test's figures per CPU.
    cpus: Vec<CpuView>,
}

/// A single CPU's bound as a number, several as a list (the format
/// predates multiprocessor specs).
#[derive(Serialize, schemars::JsonSchema)]
#[serde(untagged)]
enum OneOrMany {
    One(f64),
    Many(Vec<f64>),
}

#[derive(Serialize, schemars::JsonSchema)]
struct CpuView {
    /// The CPU's index.
    cpu: u32,
    /// The number of tasks on it.
    tasks: usize,
    /// The CPU's utilisation.
    utilization: f64,
    /// `None` for an unbounded response time (RTA).
    value: Option<f64>,
    /// The test's bound on this CPU.
    bound: f64,
    /// Whether this CPU passes the test.
    schedulable: bool,
    /// The CPU's scheduling overheads, in the spec's unit (left out
    /// without any).
    #[serde(skip_serializing_if = "Option::is_none")]
    overheads: Option<OverheadsView>,
}

/// `[system] overheads` on one CPU.
#[derive(Serialize, schemars::JsonSchema)]
struct OverheadsView {
    /// The cost of a context switch, in the spec's time unit.
    context_switch: f64,
    /// The cost of a job release, in the spec's time unit.
    release: f64,
    /// The cost of a server budget replenishment, in the spec's time unit.
    replenish: f64,
}

/// One chain and metric of the report; `known_offsets` only for a chain
/// with known offsets.
#[derive(Serialize, schemars::JsonSchema)]
pub struct ChainView<'a> {
    /// The chain's name (null for an unnamed chain).
    name: Option<&'a str>,
    /// Its tasks, from the head (sensor) to the tail (actuator).
    path: Vec<String>,
    /// `reaction` (reaction time) or `freshness` (data age).
    metric: &'static str,
    /// The spec's limit on this metric from the read, in the spec's time unit;
    /// null when none.
    limit: Option<f64>,
    /// The limit from the event (`max_reaction_time` / `freshness_from_event`),
    /// left out when the spec gives none.
    #[serde(skip_serializing_if = "Option::is_none")]
    event_limit: Option<f64>,
    /// The bounds of the chain's metric from the head's read, in the
    /// spec's time unit.
    #[serde(flatten)]
    bounds: BoundValues,
    /// Whether the sound bound keeps the limits (true without limits when
    /// bounded).
    ok: bool,
    /// Whether the paper's bound keeps the limits.
    paper_ok: bool,
    /// The same bounds from the external event (a sample read up to one
    /// head period after it), in the spec's time unit.
    from_event: BoundValues,
    /// The literature's quantities this metric is (`Literature::of`), each
    /// with the bounds of its anchor: the same figures under their names.
    literature: Pairs<&'static str, BoundValues>,
    /// The paper's case (1 to 4) of each link of the chain, in order.
    cases: Vec<u8>,
    /// The bounds under the spec's known release offsets (only for a chain
    /// whose tasks all have offsets).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub known_offsets: Option<KnownView>,
    /// The chain's own `communication`, when the spec gives it one.
    #[serde(skip_serializing_if = "Option::is_none")]
    communication: Option<&'static str>,
}

/// One chain's bound of each method ([`rtpipe_analysis::Bound::ALL`]),
/// keyed by the method's name; null where a task on the chain has no
/// bounded response time.
pub struct BoundValues(Vec<(&'static str, Option<f64>)>);

impl Serialize for BoundValues {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl schemars::JsonSchema for BoundValues {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "BoundValues".into()
    }

    /// One property per method, named as the reports name it.
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let mut properties = serde_json::Map::new();
        for b in rtpipe_analysis::Bound::ALL {
            let about = bound_about(b);
            let field = serde_json::json!({"type": ["number", "null"], "description": about});
            properties.insert(b.name().to_string(), field);
        }
        let names: Vec<&str> = rtpipe_analysis::Bound::ALL.map(|b| b.name()).to_vec();
        schemars::json_schema!({"type": "object", "properties": properties, "required": names})
    }
}

/// What each bound is, for the reports' schema (docs/analysis.md has the
/// formulas).
fn bound_about(b: rtpipe_analysis::Bound) -> &'static str {
    use rtpipe_analysis::Bound;
    match b {
        Bound::Paper => "The paper's bound (Cheng, West, Einstein, EMSOFT 2018), in the spec's unit; null when unbounded.",
        Bound::Sound => "rtpipe's sound, interference-aware bound, in the spec's unit; null when unbounded.",
        Bound::Davare => "Davare et al.'s bound (DAC 2007), in the spec's unit; null when unbounded.",
        Bound::Duerr => "Duerr et al.'s bound (CASES 2019), in the spec's unit; null when unbounded.",
    }
}

/// A chain's bounds of its metric under the spec's known release offsets;
/// the hyperperiod and jobs are null when the job-level analysis did not
/// run. `simulate` fills in the violations.
#[derive(Serialize, schemars::JsonSchema)]
pub struct KnownView {
    #[serde(flatten)]
    read: KnownBound,
    /// The same bound from the external event.
    pub from_event: KnownBound,
    /// The hyperperiod the job-level analysis covered, in the spec's time unit;
    /// null when it did not run.
    hyperperiod: Option<f64>,
    /// The jobs the job-level analysis covered; null when it did not run.
    jobs: Option<u64>,
    /// With `simulate`: samples above the known-offset bound (from the read).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violations: Option<usize>,
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct KnownBound {
    /// The sound bound under the known offsets, in the spec's time unit; null
    /// when unbounded.
    sound: Option<f64>,
    /// How it was derived (the job-level analysis, or the offset-free bound).
    basis: String,
    /// With `simulate`: samples above this bound.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub violations: Option<usize>,
}

pub fn report_view<'a>(spec: &'a Spec, r: &Report) -> ReportView<'a> {
    let tasks = spec
        .tasks
        .iter()
        .zip(&r.timing)
        .enumerate()
        .map(|(i, (t, tm))| TaskView {
            name: &t.name,
            server: t.server.name(),
            exec: spec.in_unit(t.exec),
            exec_min: spec.in_unit(t.exec_min),
            delta_in: spec.in_unit(t.delta_in),
            delta_out: spec.in_unit(t.delta_out),
            demand: spec.in_unit(tm.demand),
            budget: spec.in_unit(tm.budget),
            period: spec.in_unit(tm.period),
            deadline: t.deadline_given.map(|d| spec.in_unit(d)),
            jitter: (t.jitter > 0).then(|| spec.in_unit(t.jitter)),
            blocking: (!spec.resources.is_empty()).then(|| spec.in_unit(tm.blocking)),
            max_period: t.max_period.map(|m| spec.in_unit(m)),
            period_ok: t.max_period.map(|m| tm.period <= m),
            utilization: tm.budget as f64 / tm.period as f64,
            priority: tm.priority,
            cpu: tm.cpu,
            response_time: time(spec, tm.response_time),
            job_response_time: time(spec, tm.job_response_time),
            activation: events::activation_view(spec, r, i),
        })
        .collect();
    ReportView {
        system: &spec.name,
        time_unit: spec.time_unit.name(),
        scheduler: spec.scheduler.name(),
        communication: (spec.communication == rtpipe_model::Communication::Let)
            .then_some(spec.communication.name()),
        tasks,
        schedulability: sched_view(spec, &r.schedulability),
        chains: r.chains.iter().map(|c| chain_view(spec, r, c)).collect(),
        ok: r.all_ok(),
        paper_ok: r.all_ok_paper(),
    }
}

fn sched_view(spec: &Spec, s: &rtpipe_analysis::Schedulability) -> SchedView {
    let bound = match s.cpus.as_slice() {
        [one] => OneOrMany::One(one.bound),
        cpus => OneOrMany::Many(cpus.iter().map(|c| c.bound).collect()),
    };
    let cpus = s
        .cpus
        .iter()
        .map(|c| CpuView {
            cpu: c.cpu,
            tasks: c.tasks,
            utilization: c.utilization,
            value: c.value.is_finite().then_some(c.value),
            bound: c.bound,
            schedulable: c.schedulable,
            overheads: Some(spec.overheads.on(c.cpu))
                .filter(|o| !o.is_zero())
                .map(|o| OverheadsView {
                    context_switch: spec.in_unit(o.context_switch),
                    release: spec.in_unit(o.release),
                    replenish: spec.in_unit(o.replenish),
                }),
        })
        .collect();
    SchedView {
        test: s.test.name(),
        utilization: s.cpus.iter().map(|c| c.utilization).sum::<f64>() + 0.0,
        bound,
        schedulable: s.schedulable,
        cpus,
    }
}

fn chain_view<'a>(spec: &'a Spec, r: &Report, c: &rtpipe_analysis::ChainResult) -> ChainView<'a> {
    let ch = &spec.chains[c.chain];
    let bounds = |a: Anchor| {
        BoundValues(
            c.bound
                .from(a)
                .map(|(b, v)| (b.name(), time(spec, v)))
                .collect(),
        )
    };
    ChainView {
        name: ch.name.as_deref(),
        path: path_names(spec, &ch.path),
        metric: c.metric.name(),
        limit: time(spec, c.limit),
        event_limit: time(spec, c.event_limit),
        bounds: bounds(Anchor::Read),
        ok: c.ok,
        paper_ok: c.paper_ok(),
        from_event: bounds(Anchor::Event),
        literature: Pairs(
            Anchor::ALL
                .into_iter()
                .flat_map(|a| Literature::of(c.metric, a).map(move |l| (l, a)))
                .map(|(l, a)| (l.name(), bounds(a)))
                .collect(),
        ),
        cases: r.cases[c.chain]
            .iter()
            .map(|k| match k {
                rtpipe_analysis::Case::One => 1,
                rtpipe_analysis::Case::Two => 2,
            })
            .collect(),
        known_offsets: r
            .offsets
            .get(c.chain)
            .and_then(Option::as_ref)
            .map(|o| known_view(spec, o, c.metric)),
        communication: ch.communication.map(|m| m.name()),
    }
}

fn known_view(spec: &Spec, o: &ChainOffsets, metric: Metric) -> KnownView {
    let one = |a: Anchor| {
        let b = o.get(metric, a);
        KnownBound {
            sound: time(spec, b.value),
            basis: b.label(spec),
            violations: None,
        }
    };
    let jl = o.job_level.as_ref();
    KnownView {
        read: one(Anchor::Read),
        from_event: one(Anchor::Event),
        hyperperiod: time(spec, jl.map(|j| j.hyperperiod)),
        jobs: jl.map(|j| j.jobs),
        violations: None,
    }
}

fn opt(spec: &Spec, v: Option<Nanos>) -> String {
    match v {
        Some(n) => spec.fmt_time(n),
        None => "unbounded".to_string(),
    }
}

/// The first line of every report: the system, its size, unit and
/// scheduler, and LET communication where it applies.
pub fn system_line(spec: &Spec) -> String {
    format!(
        "system {}: {} tasks, {} chains; times in {}; scheduler {}{}\n",
        spec.name,
        spec.tasks.len(),
        spec.chains.len(),
        spec.time_unit,
        spec.scheduler.name(),
        comm_note(spec)
    )
}

/// LET where it applies: system-wide, or on the chains that ask for it
/// (implicit communication, the default, is not named, as always).
fn comm_note(spec: &Spec) -> String {
    use rtpipe_model::Communication;
    if spec.communication == Communication::Let {
        let implicit = own_chains(spec, Communication::Implicit);
        if implicit.is_empty() {
            return "; communication let (the sound bounds are LET's)".to_string();
        }
        return format!("; communication let, implicit on chains {implicit}");
    }
    let lets = own_chains(spec, Communication::Let);
    if lets.is_empty() {
        String::new()
    } else {
        format!("; communication let on chains {lets} (their sound bounds are LET's)")
    }
}

/// The chains with their own `communication = c`, labelled and joined.
fn own_chains(spec: &Spec, c: rtpipe_model::Communication) -> String {
    let names: Vec<String> = (0..spec.chains.len())
        .filter(|&k| spec.chains[k].communication == Some(c))
        .map(|k| format!("`{}`", spec.chain_label(k)))
        .collect();
    names.join(", ")
}

pub fn report_text(spec: &Spec, r: &Report, mode: Mode) -> String {
    let mut out = system_line(spec);
    out.push('\n');
    out.push_str(&task_table(spec, r));
    out.push_str(&events::activations_text(spec, r));
    out.push_str(&schedulability_text(spec, r));
    out.push_str(&chain_table(spec, r));
    out.push_str(&known_offsets_text(spec, r));
    out.push_str(&max_period_text(spec, r));
    out.push_str(&verdict_text(r, mode));
    out
}

/// One row per task: its pipe, budget, period and response times.
fn task_table(spec: &Spec, r: &Report) -> String {
    // Deadline and jitter columns only where a task gives one, so specs
    // without them print as they always did.
    let extra = timing_keys_given(spec);
    let mut heads = vec![
        "task", "server", "cpu", "prio", "Δin", "exec", "Δout", "budget C", "period T",
    ];
    if extra {
        heads.extend(["deadline D", "jitter J"]);
    }
    let blocking = !spec.resources.is_empty();
    if blocking {
        heads.push("blocking B");
    }
    heads.extend(["C/T", "R(C)", "R(job)"]);
    let numeric: Vec<usize> = (2..heads.len()).collect();
    let mut t = Table::new(&heads).numeric(&numeric);
    for (task, tm) in spec.tasks.iter().zip(&r.timing) {
        let mut row = vec![
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
        ];
        if extra {
            // A data-triggered task has no deadline of its own.
            row.push(if tm.deadline == rtpipe_model::MAX_TIME {
                "-".to_string()
            } else {
                spec.fmt_time(tm.deadline)
            });
            row.push(spec.fmt_time(tm.jitter));
        }
        if blocking {
            row.push(spec.fmt_time(tm.blocking));
        }
        row.extend([
            format!("{:.4}", tm.budget as f64 / tm.period as f64),
            opt(spec, tm.response_time),
            opt(spec, tm.job_response_time),
        ]);
        t.row(row);
    }
    t.render()
}

/// Some task gives a deadline or release jitter.
fn timing_keys_given(spec: &Spec) -> bool {
    spec.tasks
        .iter()
        .any(|t| t.deadline_given.is_some() || t.jitter > 0)
}

/// The schedulability test's verdict per CPU.
fn schedulability_text(spec: &Spec, r: &Report) -> String {
    let constrained = timing_keys_given(spec);
    let mut out = String::new();
    let s = &r.schedulability;
    out.push_str(&format!("\nschedulability ({}):\n", s.test.name()));
    for c in &s.cpus {
        let verdict = if c.schedulable {
            "schedulable"
        } else {
            "NOT schedulable"
        };
        // Critical sections under EDF: the tests carry SRP's blocking.
        let blocked = !spec.policy().fixed_priority()
            && spec
                .tasks
                .iter()
                .any(|t| t.cpu == c.cpu && !t.sections.is_empty());
        let o_zero = spec.overheads.on(c.cpu).is_zero();
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
                "U = {:.4}, max R/{} = {}",
                c.utilization,
                if constrained { "D" } else { "T" },
                if c.value.is_finite() {
                    format!("{:.4}", c.value)
                } else {
                    "unbounded".into()
                }
            ),
            rtpipe_model::SchedTest::Edf if blocked && o_zero => format!(
                "U = {:.4}, density with blocking max_k (sum_(D_i<=D_k) C_i/D_i + B_k/D_k) = {:.4} {} 1 (Baker)",
                c.utilization,
                c.value,
                if c.schedulable { "<=" } else { ">" }
            ),
            rtpipe_model::SchedTest::Edf if !o_zero && !c.schedulable => {
                edf_overheads_failure(spec, r, c)
            }
            rtpipe_model::SchedTest::Edf => format!(
                "U = {:.4} {} 1",
                c.utilization,
                if c.schedulable { "<=" } else { ">" }
            ),
            rtpipe_model::SchedTest::Qpa => format!(
                "U = {:.4}, processor demand h(t){} {} t (QPA)",
                c.utilization,
                if blocked { " + b(t)" } else { "" },
                if c.schedulable { "<=" } else { "> some" }
            ),
        };
        out.push_str(&format!(
            "  cpu {} ({} tasks): {detail} -> {verdict}\n",
            c.cpu, c.tasks
        ));
        out.push_str(&overheads_text(spec, c));
    }
    out
}

/// Which part of EDF's test with overheads (`sched::edf_overhead_test`)
/// failed on CPU `c`: the utilisation with the overheads, or else the
/// first task whose R(C) is unbounded or above its deadline.
fn edf_overheads_failure(
    spec: &Spec,
    r: &Report,
    c: &rtpipe_analysis::sched::CpuVerdict,
) -> String {
    let with = format!("U = {:.4}, with overheads {:.4}", c.utilization, c.value);
    if c.value > c.bound {
        return format!("{with} > 1");
    }
    let late = r.timing.iter().enumerate().find(|(i, tm)| {
        let t = &spec.tasks[*i];
        t.cpu == c.cpu
            && t.server != rtpipe_model::Server::Background
            && tm.response_time.is_none_or(|rc| rc > tm.deadline)
    });
    // The verdict failed and the utilisation passed: a response did not.
    let Some((i, tm)) = late else {
        panic!(
            "cpu {}: EDF with overheads failed with every R(C) <= D",
            c.cpu
        );
    };
    format!(
        "{with} <= 1, but R(C) of {} = {} > D = {}",
        spec.tasks[i].name,
        opt(spec, tm.response_time),
        spec.fmt_time(tm.deadline)
    )
}

/// A CPU's overheads under its verdict (nothing without any): what every
/// R above charges (docs/analysis.md, "Scheduling overheads").
fn overheads_text(spec: &Spec, c: &rtpipe_analysis::sched::CpuVerdict) -> String {
    let o = spec.overheads.on(c.cpu);
    if o.is_zero() {
        return String::new();
    }
    let t = |ns| format!("{} {}", spec.fmt_time(ns), spec.time_unit);
    // The verdict line above says which part failed, with its figures.
    let edf = if spec.schedulability == rtpipe_model::SchedTest::Edf {
        "; the test: U with them <= 1 and every R(C) <= D"
    } else {
        ""
    };
    format!(
        "    overheads charged in R: context switch {}, release {}, replenish {}{edf}\n",
        t(o.context_switch),
        t(o.release),
        t(o.replenish)
    )
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
        // The from-event limit column only where a chain gives one, so
        // specs without them print as they always did.
        let event = r.chains.iter().any(|c| c.event_limit.is_some());
        let mut heads: Vec<String> = ["chain", "metric", "limit"].map(String::from).to_vec();
        if event {
            heads.push("limit+event".into());
        }
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
            let limited = c.limit.or(c.event_limit);
            let verdict = |ok: bool| match (ok, limited) {
                (true, Some(_)) => "ok",
                (true, None) => "-",
                (false, _) => "FAIL",
            };
            let shown =
                |l: Option<Nanos>| l.map(|l| spec.fmt_time(l)).unwrap_or_else(|| "-".into());
            let mut row = vec![label, c.metric.name().to_string(), shown(c.limit)];
            if event {
                row.push(shown(c.event_limit));
            }
            for a in Anchor::ALL {
                row.extend(c.bound.from(a).map(|(_, v)| opt(spec, v)));
            }
            row.extend([verdict(c.paper_ok()), verdict(c.ok)].map(String::from));
            t.row(row);
        }
        out.push_str(&t.render());
        out.push_str(&literature_line());
    }
    out
}

/// Which columns carry the literature's quantities, from the one map
/// (`Literature::quantity`): the line under the chain table.
fn literature_line() -> String {
    let named: Vec<String> = Literature::ALL
        .iter()
        .map(|l| {
            let (metric, anchor) = l.quantity();
            let suffix = if anchor == Anchor::Event {
                "+event"
            } else {
                ""
            };
            format!("{} = {}{suffix}", l.name(), metric.name())
        })
        .collect();
    format!("  the literature's quantities: {}\n", named.join(", "))
}

/// Every task with a `max_period`: its period against it (nothing when no
/// task gives one).
fn max_period_text(spec: &Spec, r: &Report) -> String {
    let mut out = String::new();
    for (i, t) in spec.tasks.iter().enumerate() {
        let Some(m) = t.max_period else { continue };
        if out.is_empty() {
            out.push_str(
                "
max_period (the slowest rate control tolerates):
",
            );
        }
        let over = r.period_excesses.iter().any(|e| e.task == i);
        out.push_str(&format!(
            "  {}: period {} {} max_period {}: {}\n",
            t.name,
            spec.fmt_time(r.timing[i].period),
            if over { ">" } else { "≤" },
            spec.fmt_time(m),
            if over { "FAIL" } else { "ok" }
        ));
    }
    out
}

/// The last line: what fails under `mode`, or that nothing does. The
/// failures are joined by "; ", so no combination leaves a dangling
/// separator.
fn verdict_text(r: &Report, mode: Mode) -> String {
    let fails = r.chains.iter().filter(|c| !c.ok_in(mode)).count();
    let name = mode.name();
    let over = r.period_excesses.len();
    let mut parts = Vec::new();
    if !r.schedulability.schedulable {
        parts.push("not schedulable".to_string());
    }
    if fails > 0 {
        parts.push(format!(
            "{fails} chain limit(s) fail under the {name} analysis"
        ));
    }
    if over > 0 {
        parts.push(format!("{over} period(s) above max_period"));
    }
    if parts.is_empty() {
        parts.push(format!(
            "every limit holds ({name} analysis) and the system is schedulable"
        ));
    }
    format!("\nverdict: {}\n", parts.join("; "))
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

#[derive(Serialize, schemars::JsonSchema)]
struct WorstView {
    path: Vec<String>,
    bound: Option<f64>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct PairMetric {
    paper: WorstView,
    sound: WorstView,
}

#[derive(Serialize, schemars::JsonSchema)]
struct PairView<'a> {
    source: &'a str,
    sink: &'a str,
    reaction: PairMetric,
    freshness: PairMetric,
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct PathsView<'a> {
    pairs: Vec<PairView<'a>>,
    skipped_cycles: Vec<Vec<String>>,
}

fn worst_view(spec: &Spec, w: &Worst) -> WorstView {
    WorstView {
        path: path_names(spec, &w.path),
        bound: time(spec, w.value),
    }
}

pub fn paths_view<'a>(spec: &'a Spec, a: &AllPaths) -> PathsView<'a> {
    let pair = |paper, sound| PairMetric {
        paper: worst_view(spec, paper),
        sound: worst_view(spec, sound),
    };
    let pairs = a
        .pairs
        .iter()
        .map(|p| PairView {
            source: &spec.tasks[p.source].name,
            sink: &spec.tasks[p.sink].name,
            reaction: pair(&p.reaction_paper, &p.reaction_sound),
            freshness: pair(&p.freshness_paper, &p.freshness_sound),
        })
        .collect();
    PathsView {
        pairs,
        skipped_cycles: a.cycles.iter().map(|c| path_names(spec, c)).collect(),
    }
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
