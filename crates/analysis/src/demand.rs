//! The work that streams above a task bring into a window of length `w`,
//! `Σ_h η⁺_h(w)·C_h` with each stream's η⁺ of [`crate::arrivals`]: the
//! right-hand side of every fixed-point iteration of the response-time
//! analyses (`sched`'s level-i busy period, `thread_rta`'s FIFO windows).
//!
//! Those iterations ask for it at windows that only grow, so it is kept
//! incrementally: each stream remembers its count and the least window at
//! which the count grows, and a window below every such step costs one
//! comparison. A stream is divided only when its count changes, instead
//! of every stream at every step of every iteration (docs/analysis.md,
//! "Cost at 1,000 tasks").

use crate::arrivals::Stream;
use rtpipe_model::Nanos;

/// One stream's part of a [`Demand`].
#[derive(Debug, Clone, Copy)]
struct Term {
    /// C: the work of each event.
    work: Nanos,
    stream: Stream,
    /// η⁺ at the last window asked.
    count: Nanos,
    /// The least window at which `count` grows.
    step: Nanos,
}

/// `Σ_h η⁺_h(w)·C_h` over a fixed list of streams, asked at windows that
/// never shrink.
#[derive(Debug, Clone)]
pub struct Demand {
    terms: Vec<Term>,
    /// Σ count·C at the last window, saturating at `Nanos::MAX` (every
    /// caller calls a figure past `MAX_TIME` unbounded, as it does an
    /// overflow).
    total: Nanos,
    /// The least `step` of all terms: below it nothing changes.
    next_step: Nanos,
    /// The last window asked (windows may not shrink).
    last: Nanos,
}

impl Demand {
    /// No streams yet, room for `n`.
    pub fn with_capacity(n: usize) -> Demand {
        Demand {
            terms: Vec::with_capacity(n),
            total: 0,
            next_step: Nanos::MAX,
            last: 0,
        }
    }

    /// Adds a stream whose events bring `work` each, before any window.
    pub fn push(&mut self, work: Nanos, stream: Stream) {
        assert!(
            self.last == 0,
            "a demand's streams are given before its first window"
        );
        // Its count is 0 at a window of 0 and at least 1 from a window of
        // 1 on (J ≥ 0): it steps at 1.
        self.terms.push(Term {
            work,
            stream,
            count: 0,
            step: 1,
        });
        self.next_step = 1;
    }

    /// The demand of (C, T, J) triples, as `sched` hands them.
    pub fn of_loads(loads: &[(Nanos, Nanos, Nanos)]) -> Demand {
        let mut demand = Demand::with_capacity(loads.len());
        for &(work, period, jitter) in loads {
            demand.push(work, Stream { period, jitter });
        }
        demand
    }

    /// The largest window asked so far: the figure of an iteration that
    /// asked no more depends on each stream's η⁺ up to it alone.
    pub fn reach(&self) -> Nanos {
        self.last
    }

    /// `Σ_h η⁺_h(w)·C_h`, saturating at `Nanos::MAX`. `w` must be at least
    /// the window asked before.
    pub fn at(&mut self, w: Nanos) -> Nanos {
        assert!(
            w >= self.last,
            "a demand is asked at growing windows: {w} after {}",
            self.last
        );
        self.last = w;
        if w < self.next_step {
            return self.total;
        }
        let mut next_step = Nanos::MAX;
        for term in &mut self.terms {
            if term.step <= w {
                let count = term.stream.eta(w);
                let grown = (count - term.count).saturating_mul(term.work);
                self.total = self.total.saturating_add(grown);
                term.count = count;
                // η⁺(w') = ⌈(w' + J)/T⌉ passes `count` once w' + J > count·T.
                term.step = count
                    .saturating_mul(term.stream.period)
                    .saturating_sub(term.stream.jitter)
                    .saturating_add(1);
            }
            next_step = next_step.min(term.step);
        }
        self.next_step = next_step;
        self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum, every stream evaluated afresh.
    fn direct(loads: &[(Nanos, Nanos, Nanos)], w: Nanos) -> Nanos {
        loads.iter().fold(0, |sum: Nanos, &(c, period, jitter)| {
            sum.saturating_add(Stream { period, jitter }.eta(w).saturating_mul(c))
        })
    }

    #[test]
    fn kept_incrementally_it_is_the_direct_sum() {
        let loads = [(3, 10, 0), (1, 7, 4), (5, 25, 30), (2, 10, 0)];
        let mut demand = Demand::of_loads(&loads);
        for w in (0..200).chain([250, 999, 1_000, 10_000]) {
            assert_eq!(demand.at(w), direct(&loads, w), "w = {w}");
        }
        // Windows may repeat, and may jump.
        let mut demand = Demand::of_loads(&loads);
        for w in [5, 5, 6, 71, 71, 500] {
            assert_eq!(demand.at(w), direct(&loads, w), "w = {w}");
        }
        assert_eq!(Demand::of_loads(&[]).at(1_000), 0);
        assert_eq!(Demand::of_loads(&loads).at(0), 0);
    }

    #[test]
    fn it_saturates_where_the_sum_would_overflow() {
        let loads = [(Nanos::MAX / 2, 1, 0), (Nanos::MAX / 2, 1, 0)];
        let mut demand = Demand::of_loads(&loads);
        assert_eq!(demand.at(1), Nanos::MAX - 1);
        assert_eq!(demand.at(3), Nanos::MAX);
        assert_eq!(demand.at(4), Nanos::MAX);
    }

    #[test]
    #[should_panic(expected = "growing windows")]
    fn a_shrinking_window_is_a_bug() {
        let mut demand = Demand::of_loads(&[(1, 10, 0)]);
        demand.at(20);
        demand.at(19);
    }
}
