//! The work that streams above a task bring into a window of length `w`,
//! `Σ_h η⁺_h(w)·C_h` with each stream's η⁺ of [`crate::arrivals`]: the
//! right-hand side of every fixed-point iteration of the response-time
//! analyses (`sched`'s level-i busy period, `thread_rta`'s FIFO windows).
//!
//! Those iterations ask for it at windows that only grow, so it is kept
//! incrementally: each stream remembers its count and the least window at
//! which the count grows, and a window below every such step costs one
//! comparison. A stream is divided only when its count grows by more than
//! one, instead of every stream at every step of every iteration
//! (docs/analysis.md, "Cost at 1,000 tasks").

use crate::arrivals::{Arrivals, Stream};
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
    /// The largest window at which η⁺ is `count + 1`,
    /// `(count + 1)·T − J` (below `step` when η⁺ jumps by more there), or
    /// −1 where that overflows: a window from `step` up to it moves the
    /// count by one, with no division.
    ceiling: Nanos,
}

/// `Σ_h η⁺_h(w)·C_h` over a fixed list of streams, asked at windows that
/// never shrink.
#[derive(Debug, Clone)]
pub struct Demand<'a> {
    /// The streams as handed over and how many they are, until the first
    /// window that counts any event (at least 1) makes `terms` of them.
    streams: Option<(Streams<'a>, usize)>,
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

/// The streams of a [`Demand`] before its first window.
#[derive(Debug, Clone, Copy)]
enum Streams<'a> {
    /// Per task above, the work of each of its jobs and its activations.
    Arrivals(&'a [(Nanos, &'a Arrivals)]),
    /// (C, T, J) triples.
    Loads(&'a [(Nanos, Nanos, Nanos)]),
}

impl<'a> Demand<'a> {
    /// The demand of the tasks above as `thread_rta` hands them: per task
    /// the work of each of its jobs and its activations, each stream a
    /// term, a stretch of terms per task.
    pub fn of_arrivals(above: &'a [(Nanos, &'a Arrivals)]) -> Demand<'a> {
        let streams = above.iter().map(|(_, a)| a.streams.len()).sum();
        Demand::of_streams(Streams::Arrivals(above), streams)
    }

    /// The demand of (C, T, J) triples, as `sched` hands them.
    pub fn of_loads(loads: &'a [(Nanos, Nanos, Nanos)]) -> Demand<'a> {
        Demand::of_streams(Streams::Loads(loads), loads.len())
    }

    /// The demand of `count` streams, before any window: every stream's
    /// count is 0 at a window of 0 and at least 1 from a window of 1 on
    /// (J ≥ 0), so it steps at 1.
    fn of_streams(streams: Streams<'a>, count: usize) -> Demand<'a> {
        Demand {
            next_step: if count == 0 { Nanos::MAX } else { 1 },
            streams: Some((streams, count)),
            terms: Vec::new(),
            total: 0,
            last: 0,
        }
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
        if let Some((streams, count)) = self.streams.take() {
            self.first(streams, count, w);
            return self.total;
        }
        let mut next_step = Nanos::MAX;
        for term in &mut self.terms {
            if term.step <= w {
                self.total = self.total.saturating_add(term.advance(w));
            }
            next_step = next_step.min(term.step);
        }
        self.next_step = next_step;
        self.total
    }

    /// The terms of `streams` at their first window `w` (at least 1, so
    /// every term steps there), each made and brought to `w` in one pass:
    /// a demand is made for every fixed-priority or FIFO analysis, from
    /// about 225 streams on the 1,000-task bench, and its first window
    /// moves every term (docs/analysis.md, "Cost at 1,000 tasks", the
    /// tenth round).
    fn first(&mut self, streams: Streams, count: usize, w: Nanos) {
        let (mut total, mut next_step) = (0 as Nanos, Nanos::MAX);
        let mut bring = |work, stream| {
            let mut term = Term::fresh(work, stream);
            total = total.saturating_add(term.advance(w));
            next_step = next_step.min(term.step);
            term
        };
        self.terms.reserve_exact(count);
        match streams {
            Streams::Arrivals(above) => {
                for &(work, arrivals) in above {
                    for &stream in &arrivals.streams {
                        self.terms.push(bring(work, stream));
                    }
                }
            }
            Streams::Loads(loads) => {
                let terms = loads
                    .iter()
                    .map(|&(work, period, jitter)| bring(work, Stream { period, jitter }));
                self.terms.extend(terms);
            }
        }
        self.total = total;
        self.next_step = next_step;
    }
}

impl Term {
    /// A stream's term before any window: its count is 0 at a window of 0
    /// and at least 1 from a window of 1 on (J ≥ 0), so it steps at 1.
    #[inline]
    fn fresh(work: Nanos, stream: Stream) -> Term {
        Term {
            work,
            stream,
            count: 0,
            step: 1,
            ceiling: ceiling(0, stream),
        }
    }

    /// Brings the term to window `w`, at or past its step; the work it
    /// grew by (saturating).
    #[inline]
    fn advance(&mut self, w: Nanos) -> Nanos {
        if w <= self.ceiling {
            // One event more (most steps of an iteration, and a first window
            // within a period of the jitter, move a count by one).
            self.count += 1;
            self.step = self.ceiling.saturating_add(1);
            self.ceiling = ceiling(self.count, self.stream);
            return self.work;
        }
        let count = self.stream.eta(w);
        let grown = (count - self.count).saturating_mul(self.work);
        self.count = count;
        // η⁺(w') = ⌈(w' + J)/T⌉ passes `count` once w' + J > count·T.
        self.step = count
            .saturating_mul(self.stream.period)
            .saturating_sub(self.stream.jitter)
            .saturating_add(1);
        self.ceiling = ceiling(count, self.stream);
        grown
    }
}

/// `(count + 1)·T − J`, the largest window at which a stream's η⁺ is at
/// most `count + 1`, or −1 (no window) where `(count + 1)·T` overflows:
/// below it `w + J` cannot saturate, so η⁺ there is exactly as counted.
fn ceiling(count: Nanos, stream: Stream) -> Nanos {
    count
        .checked_add(1)
        .and_then(|c| c.checked_mul(stream.period))
        .and_then(|top| top.checked_sub(stream.jitter))
        .unwrap_or(-1)
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
    fn a_count_moved_by_one_and_by_more_is_the_direct_sum() {
        // One event more, from the first window on (J < T) and from a step
        // (w within a period of it), or several at once (J ≥ T, a jump),
        // and streams whose figures overflow, which always divide.
        let loads = [
            (1, 10, 3),
            (2, 10, 25),
            (3, 7, 0),
            (1, Nanos::MAX / 2, Nanos::MAX / 2),
            (1, Nanos::MAX, 5),
        ];
        let mut demand = Demand::of_loads(&loads);
        for w in (0..60).chain([61, 100, 101, 1_000, Nanos::MAX / 2, Nanos::MAX - 1]) {
            assert_eq!(demand.at(w), direct(&loads, w), "w = {w}");
        }
    }

    #[test]
    #[should_panic(expected = "growing windows")]
    fn a_shrinking_window_is_a_bug() {
        let mut demand = Demand::of_loads(&[(1, 10, 0)]);
        demand.at(20);
        demand.at(19);
    }
}
