//! Timing margins (sensitivity analysis): how far each task's processing
//! time, every processing time together and each period can move before
//! the verdict changes, and how much slack each chain limit has.
//!
//! Every margin is searched over integer nanoseconds with the full verdict
//! ([`crate::analyze_verdict`], [`Report::ok_in`], and the timing rules of
//! the model, [`Spec::timing_conflict`]) as the oracle, and every answer is
//! verified at its edge: the verdict holds at the margin and fails one
//! nanosecond (or one millionth of the factor) beyond it. Where the
//! verdict is monotone in the quantity searched, that edge is the exact
//! margin; docs/analysis.md ("Margins") says where it is (processing times
//! under the sound analysis) and where not (periods; the paper's bounds),
//! and the periods' ranges are probed for holes. Bini, Di Natale and
//! Buttazzo (2008) define these margins for fixed priorities; Lehoczky,
//! Sha and Ding (1989) the critical scaling factor; MAST reports the same
//! figures as slack.

mod search;

use crate::{Anchor, Metric, Mode, Report};
use rtpipe_model::{Nanos, Spec, MAX_TIME};
use search::{boundary, gallop, Oracle};

/// What a long margin search asks of its caller.
pub struct Control<'a> {
    /// Polled before every evaluation: `true` ends the search with
    /// [`MarginsError::Stopped`].
    pub stop: &'a dyn Fn() -> bool,
    /// Told after every search: (searches done, searches in all).
    pub progress: &'a dyn Fn(usize, usize),
}

impl Control<'_> {
    /// No stop, no progress.
    pub const QUIET: Control<'static> = Control {
        stop: &|| false,
        progress: &|_, _| {},
    };
}

/// Why there are no margins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarginsError {
    /// [`Control::stop`] asked to stop before every margin was known.
    Stopped,
}

/// How far a time may move (a processing time, or a period's end).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Margin {
    /// No value of it (down to 0) makes the verdict hold: something else
    /// fails.
    Unreachable,
    /// It may grow by this much (≥ 0), or must shrink by minus this much
    /// (< 0) for the verdict to hold.
    By(Nanos),
    /// It may grow up to [`MAX_TIME`] and the verdict holds.
    Unlimited,
}

/// A factor on processing times, in millionths.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factor {
    /// No factor down to 0 makes the verdict hold.
    Unreachable,
    /// The largest factor, in millionths (1 000 000: the spec as it is).
    Millionths(u64),
    /// Every factor up to the largest representable one keeps the verdict.
    Unlimited,
}

/// What fails just beyond a margin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Breach {
    /// A rule between a task's exec, budget and period
    /// ([`Spec::timing_conflict`]), by its key.
    Rule {
        /// The task.
        task: usize,
        /// The key: "budget", "period", "offset", "deadline", "jitter".
        key: &'static str,
    },
    /// The schedulability test fails on this CPU.
    Schedulability {
        /// The CPU.
        cpu: u32,
    },
    /// A task's period is above its `max_period`.
    MaxPeriod {
        /// The task.
        task: usize,
    },
    /// A chain limit.
    Limit {
        /// Index in `Spec::chains`.
        chain: usize,
        /// Its metric.
        metric: Metric,
        /// Where the limit is measured from.
        anchor: Anchor,
    },
    /// A chain's sound bound is unbounded (no limit needed to fail).
    Unbounded {
        /// Index in `Spec::chains`.
        chain: usize,
    },
}

/// How much one task's exec may grow, the others unchanged.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecMargin {
    /// Index in `Spec::tasks`.
    pub task: usize,
    /// Its exec in the spec.
    pub exec: Nanos,
    /// How much it may grow (or must shrink).
    pub margin: Margin,
    /// What fails one nanosecond beyond the margin; when unreachable, what
    /// fails even with an exec of 0 (`None` when unlimited).
    pub breach: Option<Breach>,
}

/// One chain limit: its slack and how each task's exec eats it.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitSlack {
    /// Index in `Spec::chains`.
    pub chain: usize,
    /// Its metric.
    pub metric: Metric,
    /// Where the limit is measured from.
    pub anchor: Anchor,
    /// The limit.
    pub limit: Nanos,
    /// The mode's bound (`None`: unbounded).
    pub bound: Option<Nanos>,
    /// Per task, the largest growth of its exec that keeps this limit
    /// alone (other limits and the schedulability test aside): the bound's
    /// sensitivity to it;
    /// [`Margin::Unlimited`] when the limit holds at every exec the
    /// model's timing rules allow (a budget within the period).
    pub per_task: Vec<Margin>,
}

impl LimitSlack {
    /// limit − bound (negative: exceeded); `None` when the bound is
    /// unbounded.
    pub fn slack(&self) -> Option<Nanos> {
        self.bound.map(|b| self.limit - b)
    }

    /// The task whose exec the bound is most sensitive to: the least
    /// growth that exceeds the limit, or, when it is exceeded, the least
    /// shrinking that meets it (the first task on ties); and that margin.
    /// `None` when no single exec moves the verdict.
    pub fn critical(&self) -> Option<(usize, Margin)> {
        self.per_task
            .iter()
            .enumerate()
            .filter_map(|(task, &m)| match m {
                Margin::By(v) => Some((task, m, v.unsigned_abs())),
                _ => None,
            })
            .min_by_key(|&(task, _, size)| (size, task))
            .map(|(task, m, _)| (task, m))
    }
}

/// The critical scaling factor of a CPU's tasks, or of every task.
#[derive(Debug, Clone, PartialEq)]
pub struct Scaling {
    /// The CPU; `None` for the whole system.
    pub cpu: Option<u32>,
    /// The largest factor on every exec (of the CPU) that keeps the verdict.
    pub factor: Factor,
    /// What fails one millionth beyond it; when unreachable, what fails
    /// even with every exec 0.
    pub breach: Option<Breach>,
}

/// The periods of one task that keep the verdict, the others fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodRange {
    /// Index in `Spec::tasks`.
    pub task: usize,
    /// Its period in the spec.
    pub period: Nanos,
    /// The least and the greatest period found (`None` greatest:
    /// unlimited), around the spec's period when it holds, else around the
    /// holding period nearest to it; `None` when no period was found.
    pub range: Option<(Nanos, Option<Nanos>)>,
    /// What fails one nanosecond below the range, and above it.
    pub below: Option<Breach>,
    /// What fails one nanosecond above it.
    pub above: Option<Breach>,
    /// How many periods inside the range were checked besides its ends
    /// (every period of another task where rate-monotonic ranks change,
    /// and evenly spaced ones): the verdict is not monotone in a period.
    pub probes: usize,
}

/// Every margin of a spec under one mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Margins {
    /// The mode every verdict follows.
    pub mode: Mode,
    /// The verdict on the spec as it is.
    pub holds: bool,
    /// The verdict is monotone in every exec under this mode (sound), so
    /// the exec margins, the limits' and the scaling factors are the exact
    /// largest values; under the paper's equations a bound can fall when
    /// an exec grows (docs/analysis.md, "Margins"), so each is the verified
    /// edge nearest the spec's value, and a larger value may hold again.
    pub exact: bool,
    /// One per task, in task order.
    pub exec: Vec<ExecMargin>,
    /// One per chain limit, in chain, metric (reaction first) and anchor
    /// order.
    pub limits: Vec<LimitSlack>,
    /// One per CPU with tasks, in CPU order.
    pub cpus: Vec<Scaling>,
    /// Every exec of the system scaled together.
    pub system: Scaling,
    /// One per task with a fixed period and a guarantee, in task order.
    pub periods: Vec<PeriodRange>,
    /// How many variants of the spec were analysed.
    pub evaluations: u64,
}

/// Every margin of `spec` under `mode`.
pub fn margins(spec: &Spec, mode: Mode, ctl: &Control) -> Result<Margins, MarginsError> {
    let mut o = Oracle::new(spec, mode, ctl);
    let base = crate::analyze_verdict(spec);
    let holds = o.holds_base(&base);
    let limits = limit_keys(&base, mode);
    let cpus = cpus(spec);
    let periodic: Vec<usize> = (0..spec.tasks.len())
        .filter(|&i| has_guaranteed_period(spec, i))
        .collect();
    let n = spec.tasks.len();
    o.total = n + limits.len() * n + cpus.len() + 1 + periodic.len();
    let exec = (0..n)
        .map(|i| exec_margin(&mut o, i, holds))
        .collect::<Result<_, _>>()?;
    let limits = limits
        .into_iter()
        .map(|l| limit_slack(&mut o, l))
        .collect::<Result<_, _>>()?;
    let per_cpu = cpus
        .iter()
        .map(|&c| scaling(&mut o, Some(c), holds))
        .collect::<Result<_, _>>()?;
    let system = scaling(&mut o, None, holds)?;
    let periods = periodic
        .into_iter()
        .map(|i| search::period_range(&mut o, i, holds))
        .collect::<Result<_, _>>()?;
    Ok(Margins {
        mode,
        holds,
        exact: mode == Mode::Sound,
        exec,
        limits,
        cpus: per_cpu,
        system,
        periods,
        evaluations: o.evaluations,
    })
}

/// `spec` with every exec (of `cpu`; of every CPU for `None`) scaled by
/// `millionths` / 10⁶, rounded down, each given budget kept unless the
/// demand outgrows it: the variant a critical scaling factor judges.
pub fn scaled(spec: &Spec, cpu: Option<u32>, millionths: Nanos) -> Spec {
    let mut work = spec.clone();
    search::scale_execs(&mut work, spec, cpu, millionths);
    work
}

/// The critical scaling factor of `cpu`'s tasks (every task for `None`)
/// alone, under `mode`: [`Margins::system`] without the other searches.
pub fn critical_scaling(
    spec: &Spec,
    mode: Mode,
    cpu: Option<u32>,
    ctl: &Control,
) -> Result<Scaling, MarginsError> {
    let mut o = Oracle::new(spec, mode, ctl);
    let holds = o.holds_base(&crate::analyze_verdict(spec));
    o.total = 1;
    scaling(&mut o, cpu, holds)
}

/// A task with a fixed period the verdict depends on (not background).
fn has_guaranteed_period(spec: &Spec, i: usize) -> bool {
    let t = &spec.tasks[i];
    t.server != rtpipe_model::Server::Background && t.fixed_period().is_some()
}

/// The CPUs that run tasks, in order.
fn cpus(spec: &Spec) -> Vec<u32> {
    let mut c: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// Every limit of the base report, with its bound and no margins yet.
fn limit_keys(base: &Report, mode: Mode) -> Vec<LimitSlack> {
    let mut out = Vec::new();
    for c in &base.chains {
        for anchor in Anchor::ALL {
            if let Some(limit) = c.limit_from(anchor) {
                out.push(LimitSlack {
                    chain: c.chain,
                    metric: c.metric,
                    anchor,
                    limit,
                    bound: c.bound_in(mode, anchor),
                    per_task: Vec::new(),
                });
            }
        }
    }
    out
}

/// Task `i`'s exec margin: grown from its exec while the verdict holds,
/// else shrunk until it does.
fn exec_margin(o: &mut Oracle, i: usize, holds: bool) -> Result<ExecMargin, MarginsError> {
    let t = &o.base.tasks[i];
    let exec = t.exec;
    let cap = MAX_TIME - t.delta_in - t.delta_out;
    let mut f = |o: &mut Oracle, v: Nanos| {
        o.set_exec(i, v);
        o.holds()
    };
    let edge = edge_from(o, exec, cap, holds, &mut f)?;
    let (margin, breach) = match edge {
        Edge::At(v) => {
            f(o, v + 1)?;
            (Margin::By(v - exec), o.breach())
        }
        Edge::Unlimited => (Margin::Unlimited, None),
        Edge::Unreachable => {
            f(o, 0)?;
            (Margin::Unreachable, o.breach())
        }
    };
    o.reset();
    o.done();
    Ok(ExecMargin {
        task: i,
        exec,
        margin,
        breach,
    })
}

/// Where a quantity's verdict changes, searched from its value `at`.
enum Edge {
    /// The verdict holds here and fails one step above.
    At(Nanos),
    /// It holds up to the cap.
    Unlimited,
    /// It holds nowhere in [0, at].
    Unreachable,
}

/// The largest value in [0, cap] where `f` holds, from `at` (where it
/// `holds` or not): up by doubling steps when it holds, else down.
fn edge_from(
    o: &mut Oracle,
    at: Nanos,
    cap: Nanos,
    holds: bool,
    f: &mut dyn FnMut(&mut Oracle, Nanos) -> Result<bool, MarginsError>,
) -> Result<Edge, MarginsError> {
    if holds {
        return Ok(match gallop(o, at, cap, f)? {
            Some(v) => Edge::At(v),
            None => Edge::Unlimited,
        });
    }
    if !f(o, 0)? {
        return Ok(Edge::Unreachable);
    }
    Ok(Edge::At(boundary(o, 0, at, f)?))
}

/// One limit's margins per task: the largest growth of each exec that
/// keeps this limit (from the spec's exec: the limit may fail there, then
/// the margin is the shrinking that makes it hold).
fn limit_slack(o: &mut Oracle, mut l: LimitSlack) -> Result<LimitSlack, MarginsError> {
    let holds = l.bound.is_some_and(|b| b <= l.limit);
    for i in 0..o.base.tasks.len() {
        let t = &o.base.tasks[i];
        let (exec, cap) = (t.exec, MAX_TIME - t.delta_in - t.delta_out);
        let mut f = |o: &mut Oracle, v: Nanos| {
            o.set_exec(i, v);
            o.limit_holds(&l)
        };
        let m = match edge_from(o, exec, cap, holds, &mut f)? {
            // The model's rules, not the limit, end the growth: the limit
            // holds at every exec they allow.
            Edge::At(v) if o.rule_broken_at(i, v + 1) => Margin::Unlimited,
            Edge::At(v) => Margin::By(v - exec),
            Edge::Unlimited => Margin::Unlimited,
            Edge::Unreachable => Margin::Unreachable,
        };
        o.reset();
        o.done();
        l.per_task.push(m);
    }
    Ok(l)
}

/// A factor of 1 in millionths, the unit of every scaling factor.
pub const ONE: Nanos = 1_000_000;

/// The critical scaling factor of `cpu`'s tasks (every task for `None`).
fn scaling(o: &mut Oracle, cpu: Option<u32>, holds: bool) -> Result<Scaling, MarginsError> {
    let on = |t: &rtpipe_model::Task| cpu.is_none_or(|c| t.cpu == c);
    let longest = o.base.tasks.iter().filter(|t| on(t)).map(|t| t.exec);
    let longest = longest.max().unwrap_or(0).max(1);
    // Past this factor some exec exceeds MAX_TIME (for execs of a few
    // nanoseconds, a factor beyond what a Nanos holds: MAX_TIME millionths
    // is then the search's end).
    let cap = i128::from(ONE) * i128::from(MAX_TIME) / i128::from(longest);
    let cap = Nanos::try_from(cap).unwrap_or(MAX_TIME);
    let mut f = |o: &mut Oracle, m: Nanos| {
        o.scale(cpu, m);
        o.holds()
    };
    let edge = edge_from(o, ONE, cap, holds, &mut f)?;
    let (factor, breach) = match edge {
        Edge::At(m) => {
            f(o, m + 1)?;
            (Factor::Millionths(m as u64), o.breach())
        }
        Edge::Unlimited => (Factor::Unlimited, None),
        Edge::Unreachable => {
            f(o, 0)?;
            (Factor::Unreachable, o.breach())
        }
    };
    o.reset();
    o.done();
    Ok(Scaling {
        cpu,
        factor,
        breach,
    })
}
