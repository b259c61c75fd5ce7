//! EDF with constrained deadlines: the processor-demand test, by Quick
//! Processor-demand Analysis (QPA; Zhang and Burns, "Schedulability
//! analysis for real-time systems with EDF scheduling", IEEE Transactions
//! on Computers 58(9), 2009).
//!
//! A synchronous periodic task set (C_i, D_i ≤ T_i, T_i) is schedulable by
//! EDF iff U ≤ 1 and h(t) ≤ t for every t below L, where the processor
//! demand is h(t) = Σ_{D_i ≤ t} (⌊(t − D_i) / T_i⌋ + 1) C_i. QPA walks the
//! absolute deadlines below L backwards, jumping from t to h(t) when
//! h(t) < t, and stops at the first t with h(t) > t (not schedulable) or
//! h(t) ≤ min D_i (schedulable). docs/analysis.md states the bounds on L.

use rtpipe_model::{Nanos, Spec, MAX_TIME};

/// One task as the demand test sees it: (C, T, D).
pub type Demand = (Nanos, Nanos, Nanos);

/// What QPA found on one task set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Qpa {
    /// Every deadline is met.
    pub schedulable: bool,
    /// The interval checked: [0, L).
    pub l: Nanos,
    /// The points t at which h(t) was evaluated, in order.
    pub visited: Vec<Nanos>,
    /// A t with h(t) > t, when not schedulable within [0, L).
    pub failure: Option<Nanos>,
}

/// h(t): the demand of the jobs with release and deadline in [0, t].
pub fn demand(tasks: &[Demand], t: Nanos) -> i128 {
    tasks
        .iter()
        .filter(|&&(_, _, d)| d <= t)
        .map(|&(c, p, d)| (i128::from((t - d) / p) + 1) * i128::from(c))
        .sum()
}

/// The largest absolute deadline k·T_i + D_i below `x`, over every task.
fn deadline_below(tasks: &[Demand], x: Nanos) -> Option<Nanos> {
    tasks
        .iter()
        .filter(|&&(_, _, d)| d < x)
        .map(|&(_, p, d)| d + ((x - d + p - 1) / p - 1) * p)
        .max()
}

/// The synchronous busy period: w = Σ ⌈w / T_i⌉ C_i from w = Σ C_i.
fn busy_period(tasks: &[Demand]) -> Option<Nanos> {
    let mut w: i128 = tasks.iter().map(|&(c, _, _)| i128::from(c)).sum();
    for _ in 0..1_000_000 {
        let next: i128 = tasks
            .iter()
            .map(|&(c, p, _)| (w + i128::from(p) - 1) / i128::from(p) * i128::from(c))
            .sum();
        if next > i128::from(MAX_TIME) {
            return None;
        }
        if next == w {
            return Nanos::try_from(w).ok();
        }
        w = next;
    }
    None
}

/// L: the least of the synchronous busy period and, when U < 1,
/// max(D_max, Σ (T_i − D_i) U_i / (1 − U)) (Zhang and Burns 2009, Theorems
/// 2 and 3, after Baruah, Rosier, Howell 1990 and Ripoll et al. 1996).
fn interval(tasks: &[Demand], u: f64) -> Option<Nanos> {
    let lb = busy_period(tasks);
    if u >= 1.0 {
        return lb;
    }
    let dmax = tasks.iter().map(|&(_, _, d)| d).max().unwrap_or(0);
    let s: f64 = tasks
        .iter()
        .map(|&(c, p, d)| (p - d) as f64 * c as f64 / p as f64)
        .sum::<f64>()
        / (1.0 - u);
    // Rounded up: a bound on an interval may only grow.
    let la = (dmax as f64).max(s.ceil()).min(MAX_TIME as f64) as Nanos;
    Some(lb.map_or(la, |b| b.min(la)))
}

/// QPA on one task set (every D_i ≤ T_i, every C_i, T_i, D_i positive).
pub fn qpa(tasks: &[Demand]) -> Qpa {
    let u: f64 = tasks.iter().map(|&(c, p, _)| c as f64 / p as f64).sum();
    let fail = |l, visited, t| Qpa {
        schedulable: false,
        l,
        visited,
        failure: t,
    };
    if u > 1.0 + 1e-12 {
        return fail(0, Vec::new(), None);
    }
    let Some(l) = interval(tasks, u) else {
        return fail(0, Vec::new(), None);
    };
    let dmin = tasks.iter().map(|&(_, _, d)| d).min().unwrap_or(0);
    let mut visited = Vec::new();
    let Some(mut t) = deadline_below(tasks, l) else {
        // No deadline below L: nothing to check.
        return Qpa {
            schedulable: true,
            l,
            visited,
            failure: None,
        };
    };
    loop {
        let h = demand(tasks, t);
        visited.push(t);
        if h > i128::from(t) {
            return fail(l, visited, Some(t));
        }
        if h <= i128::from(dmin) {
            break;
        }
        t = if h < i128::from(t) {
            // h ≤ t < L fits in Nanos.
            h as Nanos
        } else {
            match deadline_below(tasks, t) {
                Some(d) => d,
                None => break,
            }
        };
    }
    Qpa {
        schedulable: true,
        l,
        visited,
        failure: None,
    }
}

/// The processor-demand test with blocking under the stack resource
/// policy: h(t) + b(t) ≤ t at every absolute deadline t below
/// max(L, D_max), with b(t) Baruah's blocking as `steps`
/// ([`crate::blocking::srp_steps`]); the plain [`qpa`] when nothing blocks.
///
/// Above D_max, b = 0 and QPA's interval L bounds where h(t) > t can
/// first happen; below D_max, b is constant between two consecutive
/// relative deadlines, so on each such piece h + b is non-decreasing and
/// QPA's backward jump t ← h(t) + b(t) stays valid as long as it does not
/// leave the piece; past the piece's lower end the walk goes on from the
/// largest deadline below it.
pub fn qpa_srp(tasks: &[Demand], steps: &[(Nanos, Nanos)]) -> Qpa {
    if crate::blocking::srp_max(steps) == 0 {
        return qpa(tasks);
    }
    let plain = qpa(tasks);
    if plain.l == 0 && !plain.schedulable {
        // Overloaded, or no interval: blocking only adds demand.
        return plain;
    }
    let dmax = tasks.iter().map(|&(_, _, d)| d).max().unwrap_or(0);
    let mut visited = Vec::new();
    let mut next = deadline_below(tasks, plain.l.max(dmax));
    while let Some(t) = next {
        let g = demand(tasks, t) + i128::from(crate::blocking::srp_at(steps, t));
        visited.push(t);
        if g > i128::from(t) {
            return Qpa {
                schedulable: false,
                l: plain.l,
                visited,
                failure: Some(t),
            };
        }
        // The piece of t: from the largest relative deadline at or below
        // it (one exists: t is an absolute deadline).
        let lo = tasks
            .iter()
            .map(|&(_, _, d)| d)
            .filter(|&d| d <= t)
            .max()
            .unwrap_or(0);
        next = if g < i128::from(t) && g >= i128::from(lo) {
            // h + b ≤ g on [g, t], within the piece.
            Some(g as Nanos)
        } else if g < i128::from(t) {
            deadline_below(tasks, lo)
        } else {
            deadline_below(tasks, t)
        };
    }
    Qpa {
        schedulable: true,
        l: plain.l,
        visited,
        failure: None,
    }
}

/// The (C, T, D) of the guaranteed tasks `ids` at `period(j)`: D the
/// given deadline, else the period.
fn demands_at(spec: &Spec, period: impl Fn(usize) -> Nanos, ids: &[usize]) -> Vec<Demand> {
    ids.iter()
        .map(|&i| {
            let p = period(i);
            (
                spec.tasks[i].budget(),
                p,
                spec.tasks[i].deadline_given.unwrap_or(p),
            )
        })
        .collect()
}

/// The spec's periods ([`MAX_TIME`] where none is fixed).
pub(crate) fn spec_periods(spec: &Spec) -> Vec<Nanos> {
    spec.tasks.iter().map(spec_period).collect()
}

/// A task's period in the spec ([`MAX_TIME`] where none is fixed).
pub(crate) fn spec_period(t: &rtpipe_model::Task) -> Nanos {
    t.fixed_period().unwrap_or(MAX_TIME)
}

/// EDF meets every deadline on `cpu`: Σ U ≤ 1 when every deadline is the
/// period and nothing blocks (exactly as before deadlines existed), QPA
/// otherwise, with the stack resource policy's blocking ([`qpa_srp`]).
/// The CPU's tasks are found by a scan of the system; the analysis and
/// the design's relaxation pass them ([`edf_feasible_among`]).
pub fn edf_feasible(spec: &Spec, cpu: u32) -> bool {
    let on = crate::blocking::tasks_on(spec, cpu);
    edf_feasible_among(spec, &on, |j| spec_period(&spec.tasks[j]))
}

/// [`edf_feasible`] at `periods` (one per task of the system; deadlines
/// the given ones, else the periods), for the design's relaxation at a box
/// of one point, given the tasks of the CPU (`on`).
pub fn edf_feasible_at(spec: &Spec, periods: &[Nanos], on: &[usize]) -> bool {
    edf_feasible_among(spec, on, |j| periods[j])
}

/// [`edf_feasible`] on the CPU of the tasks `on` (all of them, background
/// ones included), at `period(j)` for each of them.
pub fn edf_feasible_among(spec: &Spec, on: &[usize], period: impl Fn(usize) -> Nanos) -> bool {
    let ids = crate::blocking::guaranteed(spec, on);
    let deadline = |i: usize| spec.tasks[i].deadline_given.unwrap_or(period(i));
    let steps = crate::blocking::srp_steps(spec, on, deadline);
    if ids.iter().all(|&i| deadline(i) == period(i)) {
        // Σ C/T over the same tasks in the same order as `sched` sums it,
        // so the verdict is the one the utilisation test gives.
        let u: f64 = ids
            .iter()
            .map(|&i| spec.tasks[i].budget() as f64 / period(i) as f64)
            .sum();
        if steps.is_empty() {
            return u <= 1.0 + 1e-12;
        }
    }
    qpa_srp(&demands_at(spec, &period, &ids), &steps).schedulable
}

/// The QPA test on the guaranteed tasks `ids` of one CPU, whose b(t) is
/// `steps` ([`crate::blocking::srp_spec_steps_among`]): (Σ U, its bound
/// 1, QPA's verdict).
pub fn qpa_verdict(spec: &Spec, ids: &[usize], steps: &[(Nanos, Nanos)]) -> (f64, f64, bool) {
    let ds = demands_at(spec, |j| spec_period(&spec.tasks[j]), ids);
    let u: f64 = ds.iter().map(|&(c, p, _)| c as f64 / p as f64).sum();
    (u, 1.0, qpa_srp(&ds, steps).schedulable)
}
