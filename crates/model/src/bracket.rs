//! The edge of a predicate that holds on one side of a value and fails on
//! the other: galloping out from a point where it holds, then bisecting
//! the bracket. One home for every such search: the analysis' margins
//! (integer nanoseconds, to the nanosecond), `design --objective margin`
//! (a scale factor, to a relative resolution) and the flight sweep's edge
//! refinement (a period scale or delay, flying each probe).
//!
//! A probe answers `Ok(Some(true))` (holds), `Ok(Some(false))` (fails),
//! `Ok(None)` (no answer: a time limit or a cancel; the search stops with
//! the bracket it has) or an error, which ends the search at once.

/// What a probe of the predicate found.
pub type Probe<E> = Result<Option<bool>, E>;

/// Where a bisection stopped: the predicate held at `good` and failed at
/// `bad`; `stopped` says a probe gave no answer before the bracket was as
/// narrow as `between` allows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bracket<T> {
    /// The last point where the predicate held.
    pub good: T,
    /// The last point where it failed.
    pub bad: T,
    /// A probe gave no answer before the resolution was reached.
    pub stopped: bool,
}

/// Narrows (`good`, `bad`) — the predicate holds at `good`, fails at `bad`,
/// either side of the other — probing `between(good, bad)` until it gives
/// no point (the resolution is reached). When the predicate is monotone on
/// the bracket, `good` ends next to its edge.
pub fn bisect<T: Copy, E>(
    mut good: T,
    mut bad: T,
    mut between: impl FnMut(T, T) -> Option<T>,
    mut holds: impl FnMut(T) -> Probe<E>,
) -> Result<Bracket<T>, E> {
    while let Some(mid) = between(good, bad) {
        match holds(mid)? {
            Some(true) => good = mid,
            Some(false) => bad = mid,
            None => {
                return Ok(Bracket {
                    good,
                    bad,
                    stopped: true,
                })
            }
        }
    }
    Ok(Bracket {
        good,
        bad,
        stopped: false,
    })
}

/// The integer midpoint of a bracket wider than `resolution`, on either
/// side: the resolution rule of searches to the unit (`resolution` 1).
pub fn midpoint(good: i64, bad: i64, resolution: i64) -> Option<i64> {
    assert!(
        resolution >= 1,
        "a resolution of at least 1, found {resolution}"
    );
    ((bad - good).abs() > resolution).then(|| good + (bad - good) / 2)
}

/// Where a gallop from a holding point toward a limit ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gallop {
    /// The predicate held at every probe up to and at the limit.
    HoldsToLimit,
    /// It held at `good` and failed at `bad`, the next probe.
    Bracketed {
        /// The last probe where it held (or the start).
        good: i64,
        /// The first probe where it failed.
        bad: i64,
    },
    /// A probe gave no answer.
    Stopped {
        /// The last probe where it held (or the start).
        good: i64,
    },
}

/// From `from` (where the predicate holds) toward `limit`, in steps of
/// `first_step`, then twice, four times, … as long (each probe one step
/// further, the last one at `limit`) until a probe fails. Doubling steps
/// find an edge at distance d in about log2(d / first_step) probes.
pub fn gallop<E>(
    from: i64,
    limit: i64,
    first_step: i64,
    mut holds: impl FnMut(i64) -> Probe<E>,
) -> Result<Gallop, E> {
    assert!(
        first_step >= 1,
        "a first step of at least 1, found {first_step}"
    );
    let dir = if limit >= from { 1 } else { -1 };
    let (mut good, mut step) = (from, first_step);
    while good != limit {
        let next = if (limit - good).abs() <= step {
            limit
        } else {
            good + dir * step
        };
        match holds(next)? {
            Some(true) => good = next,
            Some(false) => return Ok(Gallop::Bracketed { good, bad: next }),
            None => return Ok(Gallop::Stopped { good }),
        }
        step = step.saturating_mul(2);
    }
    Ok(Gallop::HoldsToLimit)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn below(edge: i64) -> impl FnMut(i64) -> Probe<()> {
        move |x| Ok(Some(x <= edge))
    }

    /// Galloping then bisecting to the unit finds the exact edge of a
    /// monotone predicate, upward and downward, wherever the edge lies.
    #[test]
    fn gallop_then_bisect_finds_the_edge() {
        for edge in [0, 1, 2, 3, 7, 8, 9, 1_000, 123_456_789] {
            let Gallop::Bracketed { good, bad } = gallop(0, i64::MAX / 4, 1, below(edge)).unwrap()
            else {
                panic!("no bracket for edge {edge}")
            };
            let b = bisect(good, bad, |g, b| midpoint(g, b, 1), below(edge)).unwrap();
            assert_eq!((b.good, b.bad, b.stopped), (edge, edge + 1, false));
        }
        let above = |x: i64| -> Probe<()> { Ok(Some(x >= 40)) };
        let Gallop::Bracketed { good, bad } = gallop(100, 1, 1, above).unwrap() else {
            panic!("no bracket downward")
        };
        assert_eq!(
            bisect(good, bad, |g, b| midpoint(g, b, 1), above)
                .unwrap()
                .good,
            40
        );
    }

    /// Holding up to the limit is said, and a limit is probed exactly.
    #[test]
    fn gallop_reaches_the_limit() {
        assert_eq!(gallop(5, 100, 1, below(100)).unwrap(), Gallop::HoldsToLimit);
        assert_eq!(gallop(5, 5, 1, below(0)).unwrap(), Gallop::HoldsToLimit);
        assert_eq!(
            gallop(5, 100, 1, below(99)).unwrap(),
            Gallop::Bracketed { good: 68, bad: 100 }
        );
    }

    /// A probe without an answer stops either search with what it had;
    /// an error ends it.
    #[test]
    fn no_answer_stops_and_an_error_ends() {
        let mut n = 0;
        let stop_third = |x: i64| -> Probe<()> {
            n += 1;
            Ok((n < 3).then_some(x < 1_000))
        };
        assert_eq!(
            gallop(0, 1 << 40, 1, stop_third).unwrap(),
            Gallop::Stopped { good: 3 }
        );
        let b = bisect(0, 1 << 20, |g, b| midpoint(g, b, 1), |_| Ok::<_, ()>(None)).unwrap();
        assert_eq!((b.good, b.bad, b.stopped), (0, 1 << 20, true));
        assert_eq!(gallop(0, 10, 1, |_| Err("boom")), Err("boom"));
    }

    /// A coarser resolution stops earlier, never with a wrong bracket.
    #[test]
    fn resolution_bounds_the_bracket() {
        let b = bisect(0, 1 << 30, |g, b| midpoint(g, b, 1 << 10), below(777_777)).unwrap();
        assert!(b.good <= 777_777 && b.bad > 777_777 && b.bad - b.good <= 1 << 10);
    }
}
