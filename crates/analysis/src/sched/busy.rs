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

/// Most steps of one job's fixed-point iteration before the response is
/// called unbounded.
pub const MAX_WINDOW_STEPS: u64 = 1_000_000;

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
    busy_period_jobs(own, hp, limit, &[], &mut |w| demand.at(w), &mut |_| {})
}

/// [`level_response_within`] with the fixed point `w_q` each job's
/// iteration stopped at, in order (one per job), each iteration started
/// from `warm`'s `w_q` where it has one, the stops of a bounded figure of
/// the same task and own jobs against `hp` streams of the same works and
/// periods whose η⁺ has only grown since (the event analysis' jitters only
/// grow; empty: from the bottom). The figure is the one the iteration from
/// the bottom gives, step limit included; the load guard, which reads the
/// works and periods alone and passed where the warm stops were found, is
/// not asked again.
///
/// Why the stops tell when a figure holds. Against `hp` streams whose η⁺
/// only grew (the periods and works kept) but is the same at every stop,
/// the figure is as it was: each job's least fixed point is at or above
/// the old one (its `f` only grew) and the old one is still a fixed point
/// (`f` there is as it was), so each job stops where it did, the same jobs
/// are followed, and the iteration from the bottom reaches each stop in at
/// most as many steps as before (its iterates are at or above the old
/// ones step for step and never pass it). The event analysis re-analyses
/// a task only when an input's η⁺ changes at a stop (`crate::events`;
/// docs/analysis.md "Cost at 1,000 tasks", the eighth round).
///
/// Why a warm start gives the same figure. `w_q` is the least fixed point
/// of its `f` (below `w_{q−1} + x` its `f` is above the window), which only
/// grew, so the old `w_q` is at or below the new one and the iteration
/// from it reaches the new one. From the bottom, a job's iteration takes
/// at most 2 steps plus the counts `hp`'s terms of positive work gain on
/// the way (after its first step, each step that does not stop grows the
/// window because some stream's count grew): `2 + N(w)`, `N(w)` their
/// counts at the largest stop `w`, at most `w/c` for `c` the least
/// positive work in `hp`. Where that is within [`MAX_WINDOW_STEPS`], no job's iteration
/// from the bottom could have run out, and the warm figure is its figure;
/// otherwise, or when the warm start finds none, the jobs are iterated
/// again from the bottom.
pub fn level_response_from(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
    warm: &[Nanos],
) -> (Option<Nanos>, Vec<Nanos>) {
    if warm.is_empty() {
        return level_response_stops(own, hp, limit, &[]);
    }
    let least = hp.iter().map(|&(c, _, _)| c).filter(|&c| c > 0).min();
    // The bound only grows with the stops, which only grow: past the limit
    // at the old stops, it is past it at the new ones.
    if cold_steps_bound(hp, warm, least) <= MAX_WINDOW_STEPS {
        let (r, stops) = level_response_stops(own, hp, limit, warm);
        if r.is_some() && cold_steps_bound(hp, &stops, least) <= MAX_WINDOW_STEPS {
            return (r, stops);
        }
    }
    level_response_stops(own, hp, limit, &[])
}

/// At most how many steps one job's iteration from the bottom takes when
/// the largest of the jobs' fixed points is the last of `stops`
/// ([`level_response_from`]): `2 + N(w)`, or the cheap form `2 + w/c`,
/// tried first (`N(w) ≤ w/c`: at the fixed point the work `hp` brings is
/// at most `w`).
/// `least_work` is `c`, the least positive work in `hp` (`None`: none).
fn cold_steps_bound(
    hp: &[(Nanos, Nanos, Nanos)],
    stops: &[Nanos],
    least_work: Option<Nanos>,
) -> u64 {
    let top = stops.last().copied().unwrap_or(0);
    let cheap = 2u64.saturating_add(least_work.map_or(0, |c| (top / c).unsigned_abs()));
    if cheap <= MAX_WINDOW_STEPS {
        return cheap;
    }
    let positive = hp.iter().filter(|&&(c, _, _)| c > 0);
    positive.fold(2, |sum: u64, &(_, period, jitter)| {
        let count = crate::arrivals::Stream { period, jitter }.eta(top);
        sum.saturating_add(count.unsigned_abs())
    })
}

/// [`level_response_within`] with each job's fixed point, each job's
/// iteration started from `warm`'s where it has one.
fn level_response_stops(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
    warm: &[Nanos],
) -> (Option<Nanos>, Vec<Nanos>) {
    let mut demand = Demand::of_loads(hp);
    let mut stops = Vec::with_capacity(warm.len().max(1));
    let r = busy_period_jobs(own, hp, limit, warm, &mut |w| demand.at(w), &mut |w| {
        stops.push(w)
    });
    (r, stops)
}

/// The jobs of [`level_response_within`]'s busy period, `demand` that of
/// `hp` before any window (a [`Demand`]'s `at`, asked at growing
/// windows), each job's fixed point handed to `stop`, the q-th job's
/// iteration started from `warm[q]` where there is one (at most its
/// fixed point, [`level_response_from`]).
fn busy_period_jobs(
    own: OwnJobs,
    hp: &[(Nanos, Nanos, Nanos)],
    limit: Nanos,
    warm: &[Nanos],
    demand: &mut impl FnMut(Nanos) -> Nanos,
    stop: &mut impl FnMut(Nanos),
) -> Option<Nanos> {
    let own_load = (
        own.work.checked_add(own.switch.checked_mul(2)?)?,
        own.period,
    );
    let loads = hp.iter().map(|&(c, t, _)| (c, t));
    // Warm stops are a bounded analysis' under the same works and periods
    // (only the jitters grew): the load was below 1 then, so it is now.
    if warm.is_empty() && crate::load::full(loads.chain(std::iter::once(own_load))) {
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
        let start = w.checked_add(own.work)?;
        let start = warm.get(q as usize).map_or(start, |&old| start.max(old));
        w = busy_window_from(own_demand, hp, demand, start)?;
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
    // Divergence guard: Σ I_j/T_j ≥ 1 means no finite fixed point.
    if crate::load::full(hp.iter().map(|&(c, t, _)| (c, t))) {
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
    for _ in 0..MAX_WINDOW_STEPS {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_load_is_unbounded_cold_and_the_warm_start_keeps_the_guard() {
        // C = T = 10 alone: w = 10 is a fixed point, but at a load of 1 the
        // busy period need not end: unbounded. Warm stops come from a
        // bounded figure under the same works and periods, where the guard
        // passed: at C = 8 (a stream above, C 1 every 100) the warm figure
        // after its jitter grew is the cold one.
        let own = |work| OwnJobs {
            work,
            switch: 0,
            blocking: 0,
            jitter: 0,
            period: 10,
        };
        assert_eq!(level_response(own(10), &[]), None);
        let (hp, grown) = ([(1, 100, 0)], [(1, 100, 95)]);
        let (r, stops) = level_response_from(own(8), &hp, Nanos::MAX, &[]);
        assert_eq!(r, Some(9));
        let cold = level_response_from(own(8), &grown, Nanos::MAX, &[]);
        assert_eq!(
            level_response_from(own(8), &grown, Nanos::MAX, &stops),
            cold
        );
    }

    #[test]
    fn a_warm_start_keeps_the_step_limit() {
        // Above: C 999,999 every 1 ms (load 1 − 10⁻⁶); one own job of x:
        // w = x + ⌈w/10⁶⌉·999,999 climbs by about one count a step, to
        // about x·10⁶ in about x steps. At x = 1,100,000 the iteration from
        // the bottom runs out of MAX_WINDOW_STEPS; one from 10¹² finds the
        // fixed point at once, but the bound on the steps from the bottom
        // (2 + w/999,999, past MAX_WINDOW_STEPS) sends it back to the
        // bottom: unbounded, as from the bottom. At x = 900,000 it fits.
        let hp = [(999_999, 1_000_000, 0)];
        let own = |work| OwnJobs {
            work,
            switch: 0,
            blocking: 0,
            jitter: 0,
            period: 4_000_000_000_000_000,
        };
        const { assert!(900_000 < MAX_WINDOW_STEPS && 1_100_000 > MAX_WINDOW_STEPS) };
        let warm = [1_000_000_000_000];
        let found = level_response_stops(own(1_100_000), &hp, Nanos::MAX, &warm);
        assert!(found.0.is_some());
        assert_eq!(level_response(own(1_100_000), &hp), None);
        let far = level_response_from(own(1_100_000), &hp, Nanos::MAX, &warm);
        assert_eq!(far.0, None);
        let fits = level_response(own(900_000), &hp);
        assert!(fits.is_some());
        let warm = [800_000_000_000];
        assert_eq!(
            level_response_from(own(900_000), &hp, Nanos::MAX, &warm).0,
            fits
        );
    }
}
