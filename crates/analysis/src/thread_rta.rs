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
/// it was: each iteration starts where it started (the start reads the
/// members and the last fixed point alone), its iterates are at or above
/// the old ones step for step and never pass the old fixed point `p`
/// (`w ≤ p` gives `f(w) ≤ f(p)`, and `f(p)` is as it was), so it stops at
/// `p` in at most as many steps, and [`MAX_STEPS`] cannot bind where it
/// did not (the event analysis re-analyses a thread only when an input's
/// η⁺ changes there, `crate::events`; docs/analysis.md "Cost at 1,000
/// tasks", the eighth round).
pub fn fifo_response_windows(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
) -> (Option<Nanos>, Vec<Nanos>) {
    let mut stops = Vec::new();
    match fifo_within(members, above, blocking, &mut stops) {
        Some(r) => {
            stops.sort_unstable();
            stops.dedup();
            (Some(r), stops)
        }
        None => (None, Vec::new()),
    }
}

/// [`fifo_response`], each fixed point its iterations stop at pushed to
/// `stops`.
fn fifo_within(
    members: &[Member],
    above: &Above,
    blocking: Nanos,
    stops: &mut Vec<Nanos>,
) -> Option<Nanos> {
    let load: f64 = members
        .iter()
        .map(|m| m.work as f64 * m.arrivals.rate())
        .chain(above.iter().map(|&(c, a)| c as f64 * a.rate()))
        .sum();
    if load >= 1.0 {
        return None;
    }
    let thread = |delta: Nanos| -> Option<Nanos> {
        members.iter().try_fold(blocking, |sum, m| {
            sum.checked_add(m.arrivals.eta(delta).checked_mul(m.work)?)
        })
    };
    let mut demand = Demand::of_arrivals(above);
    let first = thread(1)?;
    let steps = std::cell::Cell::new(MAX_STEPS);
    let length = fixed_point(1, &steps, |w| Some(thread(w)?.saturating_add(demand.at(w))))?;
    stops.push(length);
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
        return Some(length);
    }
    candidates.sort_unstable();
    candidates.dedup();
    // The candidates' windows start below the busy period's last one: a
    // demand of their own, whose windows grow from one candidate to the
    // next.
    let mut candidate_demand = Demand::of_arrivals(above);
    let (mut worst, mut finish) = (0, 0);
    for a in candidates {
        let released = thread(a.checked_add(1)?)?;
        // f grows with a: the last fixed point is a valid start.
        finish = fixed_point(finish.max(released), &steps, |w| {
            Some(released.saturating_add(candidate_demand.at(w)))
        })?;
        stops.push(finish);
        worst = worst.max(finish - a);
    }
    Some(worst)
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

    #[test]
    fn one_task_alone_is_its_demand() {
        let a = Arrivals::periodic(10, 0);
        let m = [Member {
            work: 3,
            arrivals: &a,
        }];
        assert_eq!(fifo_response(&m, &[], 0), Some(3));
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
}
