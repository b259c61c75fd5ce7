//! Response times inside a work-queue thread: its jobs run one at a time to
//! completion in release order (FIFO), the thread is preempted by the
//! threads and thread-less tasks of higher priority on its CPU (pyCPA's
//! `FIFOScheduler` under a fixed-priority one; Davis et al. 2007 for the
//! non-preemptive runs). docs/analysis.md, "Threads and data-triggered
//! tasks".

use crate::arrivals::Arrivals;
use crate::demand::Demand;
use rtpipe_model::{Nanos, MAX_TIME};

/// Most candidate release instants one level busy period is examined at
/// before the response is called unbounded.
pub const MAX_CANDIDATES: usize = 200_000;

/// Most steps of the fixed-point iterations of one response (the busy
/// period's and every candidate's together) before it is called
/// unbounded. Near a level load of 1 the iteration converges about as
/// slowly as 1 / (1 − load) (w ← ρ·w + c): at 1 − 10⁻⁹ it would take
/// billions of steps (a margin search, which probes execs at the edge of
/// the load, hung there). Calling such a response unbounded is sound (the
/// verdict only fails); a response that needs this many steps is
/// thousands of times its busy period's first estimate.
pub const MAX_STEPS: u64 = 100_000;

/// One task of the analysed thread: the work of each of its jobs and the
/// most jobs any window can release.
#[derive(Debug, Clone, Copy)]
pub struct Member<'a> {
    /// C: the work of one job.
    pub work: Nanos,
    /// Its activations.
    pub arrivals: &'a Arrivals,
}

/// What runs above the thread: per higher-priority task, its work per
/// job and its activations (each stream a term `⌈(w + J)/T⌉ · C`).
pub type Above<'a> = [(Nanos, &'a Arrivals)];

/// The worst time from a job's release to its completion for any job of
/// a thread whose tasks are `members` (the analysed one among them), with
/// the tasks `above` preempting it and `blocking` once per busy period.
///
/// A job released `a` after the start of a level busy period completes
/// by the least `w` with
/// `w = B + Σ_{m} η⁺_m(a + 1)·C_m + Σ_{h ∈ above} η⁺_h(w)·C_h`:
/// everything the thread released up to and at `a` runs before it or is
/// it (FIFO, ties counted ahead), and the thread runs whenever nothing
/// above it is pending. The count of the first sum changes only at the
/// instants where some member's η⁺(a + 1) steps, and between two of them
/// `f(a) − a` falls, so the candidates are 0 and those steps in the busy
/// period. `None` when the level's load reaches 1, on overflow, past
/// [`MAX_CANDIDATES`] candidates, or past [`MAX_STEPS`] iteration steps. A member whose jobs merge (a release
/// while one is queued and not started joins it) releases fewer jobs
/// than its activations: the figure bounds each job from its first
/// release.
pub fn fifo_response(members: &[Member], above: &Above, blocking: Nanos) -> Option<Nanos> {
    fifo_response_windows(members, above, blocking).0
}

/// [`fifo_response`] with the fixed points its iterations stopped at (the
/// busy period's and each candidate's), ascending and distinct (none when
/// the response is unbounded). The last is the busy period, beyond which
/// neither the members' η⁺ nor that of the tasks above is read (every
/// candidate's fixed point is within it). With the members' η⁺ the same
/// up to it, tasks above whose η⁺ only grew (the periods and works kept)
/// but is the same at every one of those fixed points leave the figure as
/// it was: each iteration's least fixed point is at or above the old one
/// (every input only grew) and the old one is still a fixed point (`f`
/// there is as it was), so it is the same, and the cold iteration reaches
/// it in at most as many steps (its iterates are at or above the old ones
/// step for step and never pass it), so [`MAX_STEPS`] cannot bind where
/// it did not (the event analysis re-analyses a thread only when an
/// input's η⁺ changes there, `crate::events`; docs/analysis.md "Cost at
/// 1,000 tasks", the eighth round).
pub fn fifo_response_windows(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
) -> (Option<Nanos>, Vec<Nanos>) {
    match fifo_response_from(members, above, blocking, None) {
        Some(stops) => (Some(stops.response()), stops.windows()),
        None => (None, Vec::new()),
    }
}

/// Where a bounded [`fifo_response`]'s iterations stopped: its busy period
/// and each candidate's release offset with its completion.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FifoStops {
    /// L: the level busy period.
    busy: Nanos,
    /// Per candidate `a`, ascending, `(a, finish(a))`: the least fixed
    /// point of `w = thread(a + 1) + Σ_{h ∈ above} η⁺_h(w)·C_h`.
    finishes: Vec<(Nanos, Nanos)>,
}

impl FifoStops {
    /// The response: the largest `finish(a) − a`.
    pub fn response(&self) -> Nanos {
        self.finishes
            .iter()
            .map(|&(a, finish)| finish - a)
            .max()
            .unwrap_or(0)
    }

    /// The fixed points, ascending and distinct; the last is the busy
    /// period ([`fifo_response_windows`]).
    pub fn windows(&self) -> Vec<Nanos> {
        let mut windows: Vec<Nanos> = self.finishes.iter().map(|&(_, f)| f).collect();
        windows.push(self.busy);
        windows.sort_unstable();
        windows.dedup();
        windows
    }
}

/// [`fifo_response`]'s stops (`None`: unbounded), its iterations started
/// from `warm`, the stops of the same thread and tasks above under
/// activations that have only grown since (the same works and streams'
/// periods, each η⁺ at least as large at every window; the event
/// analysis' jitters only grow). The figure is the one a start from the
/// bottom gives, step limit included; the load guard, which reads the
/// works and periods alone and passed where the warm stops were found, is
/// not asked again.
///
/// Why. Every input only grew, so every `f` is at least what it was and its
/// least fixed point at least the old one: the old busy period is a start
/// at or below the new one, and the old `finish(a')` of the largest old
/// candidate `a' ≤ a` one at or below the new `finish(a)` (`finish` grows
/// with `a`). From such a start a nondecreasing `f`'s iteration reaches
/// the least fixed point. The step limit counts the steps from the
/// bottom: such an iteration takes at most 2 steps to a fixed point plus
/// the counts the terms of positive work gain on the way (after its first
/// step, each step that does not stop grows `w` because some term's count
/// grew), so at most `2·(K + 1) + 2·N(L)` in all for `K` candidates,
/// `N(L)` the counts of the members and the tasks above at the busy
/// period `L` (the busy period's iterates lie in `[1, L]`, the
/// candidates' in disjoint stretches of it), and `N(L) ≤ L/c` for `c` the
/// least positive work. Where that bound is within
/// [`MAX_STEPS`] the start from the bottom could not have run out either,
/// and the warm figure is its figure; otherwise, or when the warm start
/// finds none, the response is iterated again from the bottom.
pub fn fifo_response_from(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    warm: Option<&FifoStops>,
) -> Option<FifoStops> {
    let least = least_work(members, above);
    // The bound only grows with the busy period, which only grows: past
    // the limit at the old stops, it is past it at the new ones.
    let bound = |stops: &FifoStops| cold_steps_bound(members, above, stops, least) <= MAX_STEPS;
    if let Some(warm) = warm.filter(|w| bound(w)) {
        let stops = fifo_within(members, above, blocking, Some(warm), least);
        if let Some(stops) = stops.filter(bound) {
            return Some(stops);
        }
    }
    fifo_within(members, above, blocking, None, least)
}

/// The least positive work among the members and the tasks above (`None`:
/// none), `c` of [`cold_steps_bound`].
fn least_work(members: &[Member], above: &Above) -> Option<Nanos> {
    let works = members.iter().map(|m| m.work);
    works
        .chain(above.iter().map(|&(c, _)| c))
        .filter(|&c| c > 0)
        .min()
}

/// At most how many steps the iterations of a response whose stops are
/// `stops` take from the bottom ([`fifo_response_from`]):
/// `2·(K + 1) + 2·N(L)`, or the cheap form `2·(K + 1) + 2·L/c`, tried
/// first (`N(L) ≤ L/c`: at the fixed point the work the terms bring is at
/// most `L`).
/// `least_work` is `c`, the least positive work among the members and the
/// tasks above (`None`: none).
fn cold_steps_bound(
    members: &[Member],
    above: &Above,
    stops: &FifoStops,
    least_work: Option<Nanos>,
) -> u64 {
    let fixed_points = stops.finishes.len() as u64 + 1;
    let terms = || {
        let members = members.iter().map(|m| (m.work, m.arrivals));
        members.chain(above.iter().copied()).filter(|&(c, _)| c > 0)
    };
    let climbs = least_work.map_or(0, |c| stops.busy / c);
    let cheap = (2 * fixed_points).saturating_add(2u64.saturating_mul(climbs.unsigned_abs()));
    if cheap <= MAX_STEPS {
        return cheap;
    }
    terms().fold(2 * fixed_points, |sum, (_, a)| {
        sum.saturating_add(2u64.saturating_mul(a.eta(stops.busy).unsigned_abs()))
    })
}

/// The long-run load of the thread's members and the tasks above it, one
/// (work, period) per stream, for [`crate::load::full`]: at 1 or more no
/// busy period ends.
pub fn loads<'a>(
    members: &'a [Member],
    above: &'a Above,
) -> impl Iterator<Item = (Nanos, Nanos)> + Clone + 'a {
    let members = members.iter().map(|m| (m.work, m.arrivals));
    let streams = members.chain(above.iter().copied());
    streams.flat_map(|(c, a)| a.streams.iter().map(move |s| (c, s.period)))
}

/// [`fifo_response`]'s stops, each iteration started from `warm`'s where
/// given ([`fifo_response_from`]) and from the bottom otherwise: the
/// candidates in order ([`candidates_in_order`]) where their figure is
/// provably the busy period's ([`fifo_by_busy_period`]), else the busy
/// period first. `least`: [`least_work`].
fn fifo_within(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    warm: Option<&FifoStops>,
    least: Option<Nanos>,
) -> Option<FifoStops> {
    // A warm start is a bounded analysis' stops under the same works and
    // periods (only the jitters grew): the load was below 1 then, so it is
    // now, and the guard is not asked again.
    if warm.is_none() && crate::load::full(loads(members, above)) {
        return None;
    }
    let in_order = candidates_in_order(members, above, blocking, warm);
    if let Some(stops) = in_order.filter(|s| busy_first_within_limits(members, above, s, least)) {
        return Some(stops);
    }
    busy_period_first(members, above, blocking, warm)
}

/// The busy period first, then each candidate: the stops of
/// [`fifo_response`] by its definition, from `warm`'s where given, with
/// its limits. What [`candidates_in_order`] is held against
/// (`tests/demand.rs`).
pub fn fifo_by_busy_period(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    warm: Option<&FifoStops>,
) -> Option<FifoStops> {
    if crate::load::full(loads(members, above)) {
        return None;
    }
    busy_period_first(members, above, blocking, warm)
}

/// Whether the busy period first ([`busy_period_first`]), from the
/// bottom, finds `stops` within its limits: its steps are at most
/// [`cold_steps_bound`], and its candidates (0 and every member's steps
/// below the busy period `L`, counted member by member before merging)
/// at most `1 + Σ_m η⁺_m(L)` (a stream (T, J) steps at `k·T − J` in
/// `(0, L)` at most `η⁺(L) − 1` times).
fn busy_first_within_limits(
    members: &[Member],
    above: &Above,
    stops: &FifoStops,
    least: Option<Nanos>,
) -> bool {
    let candidates = members
        .iter()
        .try_fold(1 as Nanos, |n, m| n.checked_add(m.arrivals.eta(stops.busy)));
    let fits = candidates.is_some_and(|n| n <= MAX_CANDIDATES as Nanos);
    fits && cold_steps_bound(members, above, stops, least) <= MAX_STEPS
}

/// The candidates in order, with no busy period iterated first (`None`:
/// not found, so the caller iterates the busy period; never a verdict of
/// its own). Candidate `a_0 = 0`, then each next step `a_{j+1}` of a
/// member's η⁺(a + 1), each `finish(a_j)` iterated from the last as
/// before, one demand for all (their windows only grow), until a job ends
/// by the next step: `finish(a_k) ≤ a_{k+1}`. Then `finish(a_k)` is the
/// busy period `L` and `a_0 … a_k` are its candidates, so the stops are
/// [`busy_period_first`]'s. Why: the members' η⁺(w) is η⁺(a_k + 1) for
/// `w` in `[a_k + 1, a_{k+1}]`, so `finish(a_k)`, which is past `a_k`,
/// is a fixed point of the busy period's `f(w) = thread(w) + Σ η⁺_h(w)·C_h`.
/// And no fixed point `p ≥ 1` of `f` lies below it: with `a_j` the last
/// candidate below `p` (`j ≤ k`), `thread(p) = thread(a_j + 1)`, so `p`
/// is a fixed point of candidate `a_j`'s iteration, whose least is
/// `finish(a_j) ≤ p ≤ a_{j+1}`: the search would have stopped at `j`, or
/// `j = k` and `finish(a_k) ≤ p`. The busy period from 1 (`f(1) ≥ 1`:
/// `thread(1) ≥ 1` is asked) is `f`'s least fixed point from 1, so `L`;
/// `a_k < L ≤ a_{k+1}`, so the candidates are those below `L`; and each
/// candidate's iteration is the same. Where the busy period comes out a
/// single candidate (a one-member unit whose job ends before its next
/// activation can arrive: 554 of the bench's 629, the tenth round), this
/// is one iteration, from `thread(1)`, where the busy period first took
/// one from 1 and then nothing; with several, one demand and no busy
/// period. docs/analysis.md "Cost at 1,000 tasks", the twelfth round.
fn candidates_in_order(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    warm: Option<&FifoStops>,
) -> Option<FifoStops> {
    let thread = |delta: Nanos| members_work(members, blocking, delta);
    if thread(1)? < 1 {
        return None;
    }
    let mut demand = Demand::of_arrivals(above);
    let steps = std::cell::Cell::new(MAX_STEPS);
    let old = warm.map_or(&[][..], |w| &w.finishes[..]);
    let mut finishes = Vec::new();
    let (mut a, mut finish): (Nanos, Nanos) = (0, 0);
    loop {
        let released = thread(a.checked_add(1)?)?;
        finish = candidate_finish((a, released), finish, old, &mut demand, &steps)?;
        finishes.push((a, finish));
        let next = next_step(members, a);
        if finish <= next {
            return Some(FifoStops {
                busy: finish,
                finishes,
            });
        }
        if finishes.len() >= MAX_CANDIDATES {
            return None;
        }
        a = next;
    }
}

/// The thread's own work released in a window of length `delta` from the
/// busy period's start: `blocking` plus each member's η⁺(δ)·C (`None`:
/// past `Nanos`).
fn members_work(members: &[Member], blocking: Nanos, delta: Nanos) -> Option<Nanos> {
    members.iter().try_fold(blocking, |sum, m| {
        sum.checked_add(m.arrivals.eta(delta).checked_mul(m.work)?)
    })
}

/// The least `a' > a` at which some member's η⁺(a' + 1) steps up
/// ([`Stream::step_after`](crate::arrivals::Stream::step_after)), or
/// `Nanos::MAX` where none is within range.
fn next_step(members: &[Member], a: Nanos) -> Nanos {
    let streams = members.iter().flat_map(|m| &m.arrivals.streams);
    streams
        .map(|s| s.step_after(a).unwrap_or(Nanos::MAX))
        .min()
        .unwrap_or(Nanos::MAX)
}

/// [`fifo_response`]'s stops by its definition: the busy period from 1
/// (or `warm`'s), then each candidate from the last candidate's fixed
/// point (or the old one's), with the step and candidate limits. The load
/// guard is the caller's.
fn busy_period_first(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    warm: Option<&FifoStops>,
) -> Option<FifoStops> {
    let thread = |delta: Nanos| members_work(members, blocking, delta);
    let mut demand = Demand::of_arrivals(above);
    let first = thread(1)?;
    let steps = std::cell::Cell::new(MAX_STEPS);
    let start = warm.map_or(1, |w| w.busy.max(1));
    let length = fixed_point(start, &steps, |w| {
        Some(thread(w)?.saturating_add(demand.at(w)))
    })?;
    let mut candidates = vec![0];
    for m in members {
        candidates.extend(m.arrivals.steps_below(length, MAX_CANDIDATES)?);
        if candidates.len() > MAX_CANDIDATES {
            return None;
        }
    }
    // No member releases inside the busy period but at its start: thread(w)
    // is thread(1) over [1, length], so the one candidate's fixed point,
    // from thread(1) ≥ 1, is the busy period's own (`length`, the least
    // w ≥ 1 with f(w) ≤ w), reached in at most the steps the busy period
    // took (its iterates are at or above the busy period's, step for
    // step): with as many left, the step limit cannot bind in it.
    let busy_steps = MAX_STEPS - steps.get();
    if candidates.len() == 1 && first >= 1 && busy_steps <= steps.get() {
        return Some(FifoStops {
            busy: length,
            finishes: vec![(0, length)],
        });
    }
    candidates.sort_unstable();
    candidates.dedup();
    // The candidates' windows start below the busy period's last one: a
    // demand of their own, whose windows grow from one candidate to the
    // next.
    let mut candidate_demand = Demand::of_arrivals(above);
    let old = warm.map_or(&[][..], |w| &w.finishes[..]);
    let mut finishes = Vec::with_capacity(candidates.len());
    let mut finish = 0;
    for a in candidates {
        let released = thread(a.checked_add(1)?)?;
        finish = candidate_finish((a, released), finish, old, &mut candidate_demand, &steps)?;
        finishes.push((a, finish));
    }
    Some(FifoStops {
        busy: length,
        finishes,
    })
}

/// The finish of the job released at candidate `a` (the thread's work
/// `released` up to it): the least fixed point of `released + demand(w)`.
/// Its iteration grows with `a`, so the last candidate's finish `last` is
/// a valid start, and so is the old finish (`old`, a warm start's) of the
/// largest old candidate up to `a`.
fn candidate_finish(
    (a, released): (Nanos, Nanos),
    last: Nanos,
    old: &[(Nanos, Nanos)],
    demand: &mut Demand,
    steps: &std::cell::Cell<u64>,
) -> Option<Nanos> {
    let known = old.partition_point(|&(b, _)| b <= a);
    let warm_start = known.checked_sub(1).map_or(0, |k| old[k].1);
    fixed_point(last.max(released).max(warm_start), steps, |w| {
        Some(released.saturating_add(demand.at(w)))
    })
}

/// The least fixed point of a nondecreasing `f` at or above `start`
/// (which must not exceed it), or `None` past [`MAX_TIME`] (a sum that
/// saturates is past it) or when the `steps` left run out.
fn fixed_point(
    start: Nanos,
    steps: &std::cell::Cell<u64>,
    mut f: impl FnMut(Nanos) -> Option<Nanos>,
) -> Option<Nanos> {
    let mut w = start;
    loop {
        steps.set(steps.get().checked_sub(1)?);
        let next = f(w)?;
        if next > MAX_TIME {
            return None;
        }
        if next <= w {
            return Some(w);
        }
        w = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A thread of one member.
    fn alone(work: Nanos, arrivals: &Arrivals) -> [Member<'_>; 1] {
        [Member { work, arrivals }]
    }

    #[test]
    fn one_task_alone_is_its_demand() {
        let a = Arrivals::periodic(10, 0);
        assert_eq!(fifo_response(&alone(3, &a), &[], 0), Some(3));
    }

    #[test]
    fn a_full_load_is_unbounded_cold_and_the_warm_start_keeps_the_guard() {
        // One member, C = T = 10: its iteration alone finds w = 10 = f(10),
        // but at a load of 1 no busy period need end: the guard calls it
        // unbounded. A warm start skips the guard only for stops found
        // under the same works and periods (the guard passed there): at
        // C = 9 the warm figure, after the jitter grew, is the cold one.
        let x = Arrivals::periodic(10, 0);
        assert_eq!(fifo_response(&alone(10, &x), &[], 0), None);
        let stops = fifo_response_from(&alone(9, &x), &[], 0, None);
        assert_eq!(stops.as_ref().map(FifoStops::response), Some(9));
        let jittered = Arrivals::periodic(10, 4);
        let grown = alone(9, &jittered);
        let cold = fifo_response_from(&grown, &[], 0, None);
        assert_eq!(fifo_response_from(&grown, &[], 0, stops.as_ref()), cold);
    }

    #[test]
    fn fifo_behind_a_sibling_and_under_a_higher_thread() {
        // Thread {x (T 10, C 2), y (T 10, C 3)}, above it h (T 5, C 1).
        // a = 0: w = 2 + 3 + ⌈w/5⌉ = 7 (w = 7: 5 + 2). Later candidates
        // (10, 20, … none below the busy period's 7) do not exist.
        let (x, y, h) = (
            Arrivals::periodic(10, 0),
            Arrivals::periodic(10, 0),
            Arrivals::periodic(5, 0),
        );
        let m = [
            Member {
                work: 2,
                arrivals: &x,
            },
            Member {
                work: 3,
                arrivals: &y,
            },
        ];
        assert_eq!(fifo_response(&m, &[(1, &h)], 0), Some(7));
        // Overloaded: 0.5 + 0.2·… ≥ 1.
        assert_eq!(fifo_response(&m, &[(3, &h)], 0), None);
    }

    #[test]
    fn jitter_brings_a_second_job_into_the_window() {
        // One task (T 10, J 6, C 4): η⁺(a + 1) steps at a = 4, so the job
        // released at 4 finds the one released at 0: f(4) = 8, R = 4; but
        // with h (T 100, C 5) above: f(0) = 9 (4 + 5, and the second job's
        // release at 4 makes the busy period 13): f(4) = 13, R = 9.
        let (x, h) = (Arrivals::periodic(10, 6), Arrivals::periodic(100, 0));
        let m = [Member {
            work: 4,
            arrivals: &x,
        }];
        assert_eq!(fifo_response(&m, &[], 0), Some(4));
        assert_eq!(fifo_response(&m, &[(5, &h)], 0), Some(9));
    }

    #[test]
    fn a_load_a_millionth_below_one_is_unbounded_not_iterated_forever() {
        // Above: C 999,999 every 1 ms (load 1 − 10⁻⁶); the thread's job of
        // 1 s then needs w = 10⁹ + ⌈w/10⁶⌉·999,999: about 10¹⁵ ns, reached
        // in some 10⁷ steps of ratio 1 − 10⁻⁶, past MAX_STEPS.
        let (x, h) = (
            Arrivals::periodic(4_000_000_000_000_000, 0),
            Arrivals::periodic(1_000_000, 0),
        );
        let m = [Member {
            work: 1_000_000_000,
            arrivals: &x,
        }];
        assert_eq!(fifo_response(&m, &[(999_999, &h)], 0), None);
        // Far from the edge it converges as before.
        let m = [Member {
            work: 1_000,
            arrivals: &x,
        }];
        assert_eq!(fifo_response(&m, &[(500_000, &h)], 0), Some(501_000));
    }

    #[test]
    fn one_candidate_keeps_the_step_limit() {
        // Above: C 999,999 every 1 ms; one member of work x released once:
        // the count above grows by one a step up to x, so the busy period
        // takes about x steps, and so would its one candidate (a = 0). At
        // x = 40,000 both fit in MAX_STEPS: the busy period's end, x·10⁶.
        // At x = 70,000 the candidate would run the steps out: unbounded,
        // as when it was iterated.
        let (x, h) = (
            Arrivals::periodic(4_000_000_000_000_000, 0),
            Arrivals::periodic(1_000_000, 0),
        );
        let above = [(999_999, &h)];
        let member = |work| [Member { work, arrivals: &x }];
        const { assert!(2 * 40_000 < MAX_STEPS && 2 * 70_000 > MAX_STEPS) };
        let fits = fifo_response_windows(&member(40_000), &above, 0);
        assert_eq!(fits.0, Some(40_000_000_000));
        assert_eq!(fits.1.last(), Some(&40_000_000_000));
        assert_eq!(fifo_response(&member(70_000), &above, 0), None);
    }

    #[test]
    fn a_warm_start_keeps_the_step_limit() {
        // As above: at x = 70,000 the iteration from the bottom runs out of
        // steps, while one started just below the busy period (7·10¹⁰)
        // finds it at once. The bound on the steps from the bottom
        // (2·(1 + 1) + 2·7·10¹⁰/999,999, past MAX_STEPS) sends the warm
        // start back to the bottom: unbounded, as from the bottom. At
        // x = 40,000 the bound fits and the warm start's figure stands.
        let (x, h) = (
            Arrivals::periodic(4_000_000_000_000_000, 0),
            Arrivals::periodic(1_000_000, 0),
        );
        let above = [(999_999, &h)];
        let member = |work| [Member { work, arrivals: &x }];
        let near = |busy| FifoStops {
            busy,
            finishes: vec![(0, busy)],
        };
        let far = near(70_000_000_000 - 1_000_000);
        let least = least_work(&member(70_000), &above);
        let found = fifo_within(&member(70_000), &above, 0, Some(&far), least);
        assert_eq!(found.map(|s| s.response()), Some(70_000_000_000));
        assert_eq!(
            fifo_response_from(&member(70_000), &above, 0, Some(&far)),
            None
        );
        let fits = near(40_000_000_000 - 1_000_000);
        let warm = fifo_response_from(&member(40_000), &above, 0, Some(&fits));
        assert_eq!(warm.map(|s| s.response()), Some(40_000_000_000));
    }
}
