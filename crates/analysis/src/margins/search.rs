//! The margins' oracle (the verdict on a variant of the spec) and the
//! searches over integer values it answers.

use super::{Breach, Control, LimitSlack, MarginsError, PeriodRange, ONE};
use crate::{analyze_chain, chain_results, sched, Anchor, Mode, Report};
use rtpipe_model::bracket::{self, Gallop};
use rtpipe_model::{Nanos, PeriodSpec, Spec, MAX_TIME};

/// `base`'s task with its exec set to `v` in `t` (its best case no above
/// it), a given budget raised to the demand where the demand outgrows it
/// (the reservation resized only when the job no longer fits; below, the
/// budget stays what the other tasks see).
fn set_exec(t: &mut rtpipe_model::Task, base: &rtpipe_model::Task, v: Nanos) {
    t.exec = v;
    t.exec_min = base.exec_min.min(v);
    let demand = t.demand();
    if let (Some(c), Some(given)) = (&mut t.budget_given, base.budget_given) {
        *c = given.max(demand);
    }
}

/// Every exec of `base` on `cpu` (every CPU for `None`) scaled by
/// `millionths` / 10⁶, rounded down, into `work` (a copy of `base`), each
/// by [`set_exec`]'s rule.
pub(super) fn scale_execs(work: &mut Spec, base: &Spec, cpu: Option<u32>, millionths: Nanos) {
    for (t, b) in work.tasks.iter_mut().zip(&base.tasks) {
        if cpu.is_none_or(|c| b.cpu == c) {
            let v = i128::from(b.exec) * i128::from(millionths) / i128::from(ONE);
            set_exec(t, b, Nanos::try_from(v).unwrap_or(MAX_TIME));
        }
    }
}

/// The spec, a working copy whose execs and periods the searches set, and
/// the verdict on that copy.
pub(super) struct Oracle<'a> {
    pub(super) base: &'a Spec,
    work: Spec,
    mode: Mode,
    ctl: &'a Control<'a>,
    pub(super) evaluations: u64,
    searches: usize,
    pub(super) total: usize,
}

impl<'a> Oracle<'a> {
    pub(super) fn new(base: &'a Spec, mode: Mode, ctl: &'a Control<'a>) -> Oracle<'a> {
        Oracle {
            base,
            work: base.clone(),
            mode,
            ctl,
            evaluations: 0,
            searches: 0,
            total: 0,
        }
    }

    /// The verdict on the spec itself, from its report.
    pub(super) fn holds_base(&self, report: &Report) -> bool {
        no_conflict(self.base) && report.ok_in(self.mode)
    }

    /// One search is done: tell the caller.
    pub(super) fn done(&mut self) {
        self.searches += 1;
        (self.ctl.progress)(self.searches, self.total);
    }

    /// The working copy back to the spec.
    pub(super) fn reset(&mut self) {
        self.work.tasks.clone_from(&self.base.tasks);
    }

    /// Task `i`'s exec set to `v`: [`set_exec`]'s rule.
    pub(super) fn set_exec(&mut self, i: usize, v: Nanos) {
        set_exec(&mut self.work.tasks[i], &self.base.tasks[i], v);
    }

    /// Task `i`'s period set to `p`.
    pub(super) fn set_period(&mut self, i: usize, p: Nanos) {
        self.work.tasks[i].period = PeriodSpec::Fixed(p);
    }

    /// Every exec of `cpu` (of the system for `None`) scaled by
    /// `millionths` / 10⁶: [`scale_execs`].
    pub(super) fn scale(&mut self, cpu: Option<u32>, millionths: Nanos) {
        scale_execs(&mut self.work, self.base, cpu, millionths);
    }

    /// Task `i` at exec `v` breaks a timing rule of the model.
    pub(super) fn rule_broken_at(&mut self, i: usize, v: Nanos) -> bool {
        self.set_exec(i, v);
        !no_conflict(&self.work)
    }

    fn tick(&mut self) -> Result<(), MarginsError> {
        if (self.ctl.stop)() {
            return Err(MarginsError::Stopped);
        }
        self.evaluations += 1;
        Ok(())
    }

    /// The verdict on the working copy: every timing rule of the model and
    /// [`Report::ok_in`].
    pub(super) fn holds(&mut self) -> Result<bool, MarginsError> {
        self.tick()?;
        Ok(no_conflict(&self.work) && crate::analyze_verdict(&self.work).ok_in(self.mode))
    }

    /// The one limit `l` holds on the working copy, which keeps the
    /// model's timing rules (the analysis assumes them: a budget within
    /// the period); other limits and the schedulability test are not
    /// asked.
    pub(super) fn limit_holds(&mut self, l: &LimitSlack) -> Result<bool, MarginsError> {
        self.tick()?;
        if !no_conflict(&self.work) {
            return Ok(false);
        }
        let (timing, _) = sched::analyze(&self.work);
        let a = analyze_chain(&self.work, &timing, &self.work.chains[l.chain].path);
        let [reaction, freshness] = chain_results(&self.work, l.chain, &a);
        let c = match l.metric {
            crate::Metric::Reaction => reaction,
            crate::Metric::Freshness => freshness,
        };
        Ok(c.holds(self.mode, l.anchor))
    }

    /// The first thing that fails on the working copy: a timing rule, the
    /// schedulability test, a `max_period`, a chain.
    pub(super) fn breach(&self) -> Option<Breach> {
        let rule = (0..self.work.tasks.len()).find_map(|task| {
            let key = self.work.timing_conflict(task)?;
            Some(Breach::Rule { task, key })
        });
        if rule.is_some() {
            return rule;
        }
        let r = crate::analyze_verdict(&self.work);
        if let Some(c) = r.schedulability.cpus.iter().find(|c| !c.schedulable) {
            return Some(Breach::Schedulability { cpu: c.cpu });
        }
        if let Some(e) = r.period_excesses.first() {
            return Some(Breach::MaxPeriod { task: e.task });
        }
        self.chain_breach(&r)
    }

    fn chain_breach(&self, r: &Report) -> Option<Breach> {
        let c = r.chains.iter().find(|c| !c.ok_in(self.mode))?;
        Some(
            match Anchor::ALL.into_iter().find(|&a| !c.holds(self.mode, a)) {
                Some(anchor) => Breach::Limit {
                    chain: c.chain,
                    metric: c.metric,
                    anchor,
                },
                None => Breach::Unbounded { chain: c.chain },
            },
        )
    }
}

/// No task of `spec` breaks a timing rule of the model.
fn no_conflict(spec: &Spec) -> bool {
    (0..spec.tasks.len()).all(|i| spec.timing_conflict(i).is_none())
}

/// A search's predicate: the verdict with the searched quantity at a value.
pub(super) type Holds<'f> = &'f mut dyn FnMut(&mut Oracle, Nanos) -> Result<bool, MarginsError>;

/// Between `good` (where `f` holds) and `bad` (where it fails), either
/// side of the other: the value next to a failing one, by bisection
/// ([`bracket::bisect`] to the nanosecond). When `f` is monotone there,
/// the exact edge.
pub(super) fn boundary(
    o: &mut Oracle,
    good: Nanos,
    bad: Nanos,
    f: Holds,
) -> Result<Nanos, MarginsError> {
    let to_the_ns = |g, b| bracket::midpoint(g, b, 1);
    Ok(bracket::bisect(good, bad, to_the_ns, |x| f(o, x).map(Some))?.good)
}

/// From `from` (where `f` holds) toward `limit`, in steps of 1, 2, 4, …
/// until `f` fails ([`bracket::gallop`]), then bisected: the last value
/// before a failure, or `None` when `f` holds at `limit` too.
pub(super) fn gallop(
    o: &mut Oracle,
    from: Nanos,
    limit: Nanos,
    f: Holds,
) -> Result<Option<Nanos>, MarginsError> {
    match bracket::gallop(from, limit, 1, |x| f(o, x).map(Some))? {
        Gallop::HoldsToLimit => Ok(None),
        Gallop::Bracketed { good, bad } => Ok(Some(boundary(o, good, bad, f)?)),
        Gallop::Stopped { .. } => unreachable!("every probe of the analysis answers"),
    }
}

/// How many parts of a range, evenly spaced on a log scale, are checked.
const PROBES: Nanos = 8;

/// How often a range is narrowed around a hole before the search gives up
/// narrowing (the range then still holds at every probe of the last round
/// but one; the answer says how many it checked).
const ROUNDS: usize = 8;

/// Task `i`'s periods that keep the verdict, the others fixed.
pub(super) fn period_range(
    o: &mut Oracle,
    i: usize,
    holds: bool,
) -> Result<PeriodRange, MarginsError> {
    let period = o.base.tasks[i].fixed_period().unwrap_or(0);
    let mut f = |o: &mut Oracle, p: Nanos| {
        o.set_period(i, p);
        o.holds()
    };
    let start = if holds {
        Some(period)
    } else {
        holding_period(o, i, period, &mut f)?
    };
    let mut out = PeriodRange {
        task: i,
        period,
        range: None,
        below: None,
        above: None,
        probes: 0,
    };
    if let Some(start) = start {
        let lo = gallop(o, start, 1, &mut f)?.unwrap_or(1);
        let hi = gallop(o, start, MAX_TIME, &mut f)?;
        let (lo, hi) = narrow(o, i, start, (lo, hi), &mut out.probes, &mut f)?;
        out.range = Some((lo, hi));
        if lo > 1 {
            f(o, lo - 1)?;
            out.below = o.breach();
        }
        if let Some(h) = hi {
            f(o, h + 1)?;
            out.above = o.breach();
        }
    }
    o.reset();
    o.done();
    Ok(out)
}

/// A period where the verdict holds, nearest to `period` on a scale of
/// quarter octaves (1/16 to 16 times it) or among the other tasks'
/// periods: for a spec that fails at its own.
fn holding_period(
    o: &mut Oracle,
    i: usize,
    period: Nanos,
    f: Holds,
) -> Result<Option<Nanos>, MarginsError> {
    let mut candidates: Vec<Nanos> = (1..=16)
        .flat_map(|k| [-k, k])
        .map(|k: i32| (period as f64 * 2f64.powf(f64::from(k) / 4.0)).round() as Nanos)
        .chain(others_periods(o.base, i))
        .filter(|&p| (1..=MAX_TIME).contains(&p))
        .collect();
    candidates.sort_by(|a, b| {
        let d = |p: Nanos| (p as f64 / period.max(1) as f64).ln().abs();
        d(*a).total_cmp(&d(*b))
    });
    for p in candidates {
        if f(o, p)? {
            return Ok(Some(p));
        }
    }
    Ok(None)
}

/// The other tasks' fixed periods.
fn others_periods(spec: &Spec, i: usize) -> impl Iterator<Item = Nanos> + '_ {
    spec.tasks
        .iter()
        .enumerate()
        .filter(move |&(j, _)| j != i)
        .filter_map(|(_, t)| t.fixed_period())
}

/// The range around `start` probed for holes: next to every other task's
/// period (where rate-monotonic ranks change) and at periods spaced evenly
/// on a log scale; a failing probe narrows the range to the edge between
/// it and `start`, and the new range is probed again (points that held
/// are not asked twice).
fn narrow(
    o: &mut Oracle,
    i: usize,
    start: Nanos,
    (mut lo, mut hi): (Nanos, Option<Nanos>),
    probes: &mut usize,
    f: Holds,
) -> Result<(Nanos, Option<Nanos>), MarginsError> {
    let mut held = std::collections::BTreeSet::from([start]);
    for _ in 0..ROUNDS {
        let points = probe_points(o.base, i, lo, hi.unwrap_or(MAX_TIME));
        let mut hole = None;
        let fresh: Vec<Nanos> = points.into_iter().filter(|p| !held.contains(p)).collect();
        for p in fresh {
            *probes += 1;
            if !f(o, p)? {
                hole = Some(p);
                break;
            }
            held.insert(p);
        }
        let Some(bad) = hole else {
            break;
        };
        let edge = boundary(o, start, bad, f)?;
        if bad < start {
            lo = edge;
        } else {
            hi = Some(edge);
        }
    }
    Ok((lo, hi))
}

/// The periods strictly inside (lo, hi) a range is checked at.
fn probe_points(spec: &Spec, i: usize, lo: Nanos, hi: Nanos) -> Vec<Nanos> {
    let ratio = (hi as f64 / lo.max(1) as f64).powf(1.0 / PROBES as f64);
    let spaced = (1..PROBES).map(|k| (lo.max(1) as f64 * ratio.powi(k as i32)).round() as Nanos);
    let ranks = others_periods(spec, i).flat_map(|p| [p - 1, p + 1]);
    let mut points: Vec<Nanos> = spaced.chain(ranks).filter(|&p| lo < p && p < hi).collect();
    points.sort_unstable();
    points.dedup();
    points
}
