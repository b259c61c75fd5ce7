//! The level-i busy period of fixed-priority response-time analysis: the
//! fixed points `w = own + Σ ⌈(w + J_j)/T_j⌉·I_j` over the jobs of a task,
//! each asking the demand of the tasks above ([`crate::demand`]) at
//! growing windows. docs/analysis.md, "Fixed priorities: every job of the
//! level-i busy period".

use crate::demand::Demand;
use rtpipe_model::{Nanos, MAX_TIME};

/// Fixed point of R = own + Σ_{j ∈ hp} ⌈R / T_j⌉ · I_j (Joseph and Pandya 1986;
/// Audsley et al. 1993). `None` when the higher-priority load (with own) is
/// 100 % or more, so the iteration would not converge, or on overflow.
pub fn response_time(own: Nanos, hp: &[(Nanos, Nanos)]) -> Option<Nanos> {
    let hp: Vec<(Nanos, Nanos, Nanos)> = hp.iter().map(|&(c, t)| (c, t, 0)).collect();
    busy_window(own, &hp)
}

/// The response time with release jitter of a task's first job
/// (Audsley, Burns, Richardson, Tindell, Wellings 1993): R = J + w, w =
/// own + Σ_{j ∈ hp} ⌈(w + J_j) / T_j⌉ · I_j, with `hp` as (I_j, T_j, J_j).
/// Measured from the nominal release; w alone is measured from the actual
/// one. It is the task's worst case only when that job completes before
/// the task's next release; [`level_response`] covers every job. `None`
/// as [`response_time`].
pub fn response_time_jitter(
    own: Nanos,
    jitter: Nanos,
    hp: &[(Nanos, Nanos, Nanos)],
) -> Option<Nanos> {
    busy_window(own, hp)?.checked_add(jitter)
}

/// The analysed task's side of its level-i busy period: what each of its
/// own jobs brings, and what the period brings once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwnJobs {
    /// The work of each own job: its demand x (the job figure) or its
    /// budget C (the budget figure).
    pub work: Nanos,
    /// The context switch cost `cs` (`crate::overheads`): each earlier own
    /// job of the busy period pays two, the analysed one one.
    pub switch: Nanos,
    /// Paid once per busy period: B (only sections begun before it can
    /// block, `crate::blocking`) and any disturbance (`crate::disturbance`).
    pub blocking: Nanos,
    /// J: the own release jitter.
    pub jitter: Nanos,
    /// T: the own period.
    pub period: Nanos,
}

/// Most own jobs one level-i busy period is followed through before the
/// response is called unbounded.
pub const MAX_BUSY_JOBS: Nanos = 100_000;

/// The worst response time of any job of a task over its level-i busy
/// period (Lehoczky 1990, arbitrary deadlines; Tindell, Burns and Wellings
/// 1994, with release jitter and blocking): the q-th own job (q = 0, 1, …)
/// completes at the least fixed point of
/// `w_q = (q+1)·x + (2q+1)·cs + B + Σ_{j ∈ hp} ⌈(w_q + J_j) / T_j⌉ · I_j`
/// after the busy period starts, was released at the earliest at
/// `q·T − J` (the first job at its latest, `J` after its nominal release),
/// so `R = max_q (w_q − q·T + J)` over the jobs until one completes by the
/// next own release, `w_q ≤ (q+1)·T − J`. `None` when the level's
/// utilisation (own share `(x + 2cs)/T` with `hp`'s) reaches 1, so the
/// busy period need not end, on overflow, and past [`MAX_BUSY_JOBS`] jobs.
pub fn level_response(own: OwnJobs, hp: &[(Nanos, Nanos, Nanos)]) -> Option<Nanos> {
    level_response_within(own, hp, Nanos::MAX)
}

/// [`level_response`] when it is at most `limit`, `None` otherwise: the
/// busy period is left as soon as a job responds later (the design's
/// relaxation only asks whether R is within a period).
pub fn level_response_within(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
) -> Option<Nanos> {
    let mut demand = Demand::of_loads(hp);
    busy_period_jobs(own, hp, limit, &mut |w| demand.at(w), &mut |_| {})
}

/// [`level_response_within`] with the fixed points `w_q` its jobs' iterations
/// stopped at, ascending and distinct. Against `hp` streams whose η⁺ only
/// grew (the periods and works kept) but is the same at every one of them,
/// the figure is as it was: each job's iteration starts where it started
/// (from the last job's fixed point and the own work), its iterates are
/// at or above the old ones step for step and never pass the old fixed
/// point (the demand there is as it was), so it stops there in at most as
/// many steps, and the same jobs are followed (the event analysis
/// re-analyses a task only when an input's η⁺ changes at one of them,
/// `crate::events`; docs/analysis.md "Cost at 1,000 tasks", the eighth
/// round).
pub fn level_response_windows(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
) -> (Option<Nanos>, Vec<Nanos>) {
    let mut demand = Demand::of_loads(hp);
    let mut stops = Vec::new();
    let r = busy_period_jobs(own, hp, limit, &mut |w| demand.at(w), &mut |w| {
        // The fixed points only grow: distinct once a repeat is left out.
        if stops.last() != Some(&w) {
            stops.push(w);
        }
    });
    (r, stops)
}

/// The jobs of [`level_response_within`]'s busy period, `demand` that of
/// `hp` before any window (a [`Demand`]'s `at`, asked at growing
/// windows), each job's fixed point handed to `stop`.
fn busy_period_jobs(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
    demand: &mut impl FnMut(Nanos) -> Nanos,
    stop: &mut impl FnMut(Nanos),
) -> Option<Nanos> {
    let share = own.work.checked_add(own.switch.checked_mul(2)?)? as f64 / own.period as f64;
    let u: f64 = hp.iter().map(|&(c, t, _)| c as f64 / t as f64).sum();
    if u + share >= 1.0 {
        return None;
    }
    // One demand for the whole busy period: its windows only grow.
    let (mut worst, mut w): (Nanos, Nanos) = (0, 0);
    for q in 0..MAX_BUSY_JOBS {
        let own_demand = (q + 1)
            .checked_mul(own.work)?
            .checked_add((2 * q + 1).checked_mul(own.switch)?)?
            .checked_add(own.blocking)?;
        // w_{q-1} plus the q-th job's own work is below w_q (the fixed
        // point grows at least by the work added): a valid start.
        w = busy_window_from(own_demand, hp, demand, w.checked_add(own.work)?)?;
        stop(w);
        worst = worst.max(w - q.saturating_mul(own.period));
        if worst.checked_add(own.jitter)? > limit {
            return None;
        }
        if w <= (q + 1).saturating_mul(own.period) - own.jitter {
            return worst.checked_add(own.jitter);
        }
    }
    None
}

/// The fixed point w of w = own + Σ ⌈(w + J_j) / T_j⌉ · I_j.
pub(crate) fn busy_window(own: Nanos, hp: &[(Nanos, Nanos, Nanos)]) -> Option<Nanos> {
    let u: f64 = hp.iter().map(|&(c, t, _)| c as f64 / t as f64).sum();
    // Divergence guard: Σ I_j/T_j ≥ 1 means no finite fixed point.
    if u >= 1.0 {
        return None;
    }
    let mut demand = Demand::of_loads(hp);
    busy_window_from(own, hp, &mut |w| demand.at(w), 0)
}

/// [`busy_window`] iterated from `start`, which must not exceed the least
/// fixed point (the iteration then reaches it from below), with `demand`
/// the demand of `hp` last asked at or below `start`. The caller has
/// checked that `hp` leaves room (Σ I_j/T_j < 1).
fn busy_window_from(
    own: Nanos,
    hp: &[(Nanos, Nanos, Nanos)],
    demand: &mut impl FnMut(Nanos) -> Nanos,
    start: Nanos,
) -> Option<Nanos> {
    let first = own.checked_add(hp.iter().map(|&(c, _, _)| c).sum::<Nanos>())?;
    let mut r = first.max(start);
    for _ in 0..1_000_000 {
        // Past MAX_TIME (the demand saturates where the sum would
        // overflow): no bounded response.
        let next = own.saturating_add(demand(r));
        if next > MAX_TIME {
            return None;
        }
        if next == r {
            // The fixed point holds the task's own demand and every
            // interferer's first release.
            assert!(r >= first);
            return Some(r);
        }
        r = next;
    }
    None
}
