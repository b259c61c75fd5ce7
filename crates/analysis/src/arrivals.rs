//! Event models of activations and publications (compositional
//! performance analysis, Henia et al. 2005; pyCPA's `model.py` and
//! `junctions.py`): the most events any window of length Δ can hold,
//! η⁺(Δ), as a sum of periodic streams with jitter. A periodic task is
//! one stream; an OR junction (`join = "any"`) sums its inputs' streams;
//! an output adds the response-time jitter `R − R_min` to every stream.
//! docs/analysis.md, "Threads and data-triggered tasks".

use rtpipe_model::{Nanos, MAX_TIME};

/// One periodic stream with release jitter: at most ⌈(Δ + J) / T⌉ events
/// in any window of length Δ > 0 (none in an empty one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stream {
    /// T: the period.
    pub period: Nanos,
    /// J: the jitter, how far an event may be from its nominal instant.
    pub jitter: Nanos,
}

/// The stream that holds one event in every window however long: the
/// `1 +` of a join of all triggers.
pub const ONCE: Stream = Stream {
    period: MAX_TIME,
    jitter: 0,
};

/// The input of least rate ([`Arrivals::rate`]), the first of those
/// equally slow (`None`: no input), with what goes with it.
fn slowest<'a, T>(inputs: impl Iterator<Item = (&'a Arrivals, T)>) -> Option<(&'a Arrivals, T)> {
    inputs.min_by(|(a, _), (b, _)| a.rate().total_cmp(&b.rate()))
}

/// [`Arrivals::all`]'s join of `count` inputs whose slowest is `slowest`:
/// one input is the input itself, more are one event and the slowest's.
fn join_all(slowest: Arrivals, count: usize) -> Arrivals {
    if count == 1 {
        return slowest;
    }
    let mut streams = vec![ONCE];
    streams.extend(slowest.streams);
    Arrivals { streams }
}

impl Stream {
    /// The same events, each up to `extra` later ([`Arrivals::delayed`]'s
    /// rule for one stream; `None` when the jitter passes [`MAX_TIME`]).
    pub fn delayed(self, extra: Nanos) -> Option<Stream> {
        assert!(extra >= 0, "a delay is a duration: {extra}");
        let jitter = self.jitter.checked_add(extra).filter(|&j| j <= MAX_TIME)?;
        Some(Stream { jitter, ..self })
    }

    /// The least window length `a' > a` at which η⁺(a' + 1) steps up,
    /// `k·T − J` for the least such k (`None`: past `Nanos`). From `a = 0`
    /// and then from each answer, every step in order.
    pub fn step_after(self, a: Nanos) -> Option<Nanos> {
        let k = a.checked_add(self.jitter)? / self.period + 1;
        let step = k.checked_mul(self.period)? - self.jitter;
        assert!(step > a, "a step lies after {a}: {step}");
        Some(step)
    }

    /// η⁺(Δ) of this stream; saturates instead of overflowing.
    pub fn eta(self, delta: Nanos) -> Nanos {
        if delta <= 0 {
            return 0;
        }
        let top = delta.saturating_add(self.jitter);
        top / self.period + Nanos::from(top % self.period != 0)
    }
}

/// η⁺ of a sum of streams: Σ_k ⌈(Δ + J_k) / T_k⌉.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Arrivals {
    /// The streams whose events add up.
    pub streams: Vec<Stream>,
}

impl Arrivals {
    /// A periodic source: period `t`, release jitter `j`.
    pub fn periodic(t: Nanos, j: Nanos) -> Arrivals {
        assert!(
            t > 0 && j >= 0,
            "a stream needs T > 0 and J ≥ 0: ({t}, {j})"
        );
        Arrivals {
            streams: vec![Stream {
                period: t,
                jitter: j,
            }],
        }
    }

    /// At most how many events a window of length `delta` holds.
    pub fn eta(&self, delta: Nanos) -> Nanos {
        self.streams
            .iter()
            .fold(0, |n: Nanos, s| n.saturating_add(s.eta(delta)))
    }

    /// The long-run rate, events per nanosecond.
    pub fn rate(&self) -> f64 {
        self.streams.iter().map(|s| 1.0 / s.period as f64).sum()
    }

    /// The same events, each up to `extra` later than it could be (the
    /// output model of a task whose response varies by `extra`:
    /// η⁺_out(Δ) = η⁺_in(Δ + extra)). `None` when a jitter passes
    /// [`MAX_TIME`].
    pub fn delayed(&self, extra: Nanos) -> Option<Arrivals> {
        assert!(extra >= 0, "a delay is a duration: {extra}");
        let streams = self.streams.iter().map(|s| s.delayed(extra));
        Some(Arrivals {
            streams: streams.collect::<Option<_>>()?,
        })
    }

    /// [`Arrivals::any`] of the inputs each [`delayed`](Self::delayed) by
    /// its extra (`None` where one is, or where an input is `None`: a
    /// trigger unbounded), in one list, with no copy of each delayed input
    /// and no list of the inputs on the way.
    pub fn any_delayed<'a>(
        inputs: impl Iterator<Item = Option<(&'a Arrivals, Nanos)>> + Clone,
    ) -> Option<Arrivals> {
        let len = inputs
            .clone()
            .map(|input| input.map_or(0, |(a, _)| a.streams.len()))
            .sum();
        let mut streams = Vec::with_capacity(len);
        for input in inputs {
            let (a, extra) = input?;
            for &s in &a.streams {
                streams.push(s.delayed(extra)?);
            }
        }
        Some(Arrivals { streams })
    }

    /// An OR junction: every input's event is an event (the sum).
    pub fn any(inputs: &[&Arrivals]) -> Arrivals {
        Arrivals {
            streams: inputs.iter().flat_map(|a| a.streams.clone()).collect(),
        }
    }

    /// An AND junction (`join = "all"`): an activation needs an event of
    /// every input since the last, so `n` activations in a window need
    /// `n − 1` events of each input inside it: η⁺ ≤ 1 + η⁺_k for every
    /// input k; the slowest input (least rate) is taken. One input is
    /// the input itself.
    pub fn all(inputs: &[&Arrivals]) -> Arrivals {
        let slowest = slowest(inputs.iter().map(|&a| (a, ())));
        let (slowest, ()) = slowest.expect("a join has inputs");
        join_all(slowest.clone(), inputs.len())
    }

    /// [`Arrivals::all`] of the inputs each [`delayed`](Self::delayed) by
    /// its extra (`None` where one is, or where an input is `None`: a
    /// trigger unbounded), with only the slowest input delayed: a delay
    /// keeps the periods, and so the rates that pick the slowest, and the
    /// others are only asked whether their delay is in range.
    pub fn all_delayed<'a>(
        inputs: impl Iterator<Item = Option<(&'a Arrivals, Nanos)>> + Clone,
    ) -> Option<Arrivals> {
        let mut count = 0;
        for input in inputs.clone() {
            let (a, extra) = input?;
            for &s in &a.streams {
                s.delayed(extra)?;
            }
            count += 1;
        }
        let (slowest, extra) = slowest(inputs.flatten()).expect("a join has inputs");
        Some(join_all(slowest.delayed(extra)?, count))
    }

    /// The largest window `W` such that η⁺ of `self` and of `other` agree
    /// stream by stream at every window up to `W` (0 when they differ at
    /// once or are not the same streams with other jitters): a figure that
    /// read η⁺ at windows up to `W` alone is the same for both. A stream
    /// (T, J) and (T, J') with J ≤ J' differ first where a multiple of T
    /// falls in `[w + J, w + J')`: at `w = ⌈(1 + J)/T⌉·T − J' + 1`.
    pub fn same_up_to(&self, other: &Arrivals) -> Nanos {
        if self.streams.len() != other.streams.len() {
            return 0;
        }
        let mut reach = Nanos::MAX;
        for (s, o) in self.streams.iter().zip(&other.streams) {
            if s.period != o.period {
                return 0;
            }
            let (low, high) = (s.jitter.min(o.jitter), s.jitter.max(o.jitter));
            if low == high {
                continue;
            }
            let first = Stream { jitter: low, ..*s }.eta(1).saturating_mul(s.period);
            reach = reach.min(first.saturating_sub(high).max(0));
        }
        reach
    }

    /// Every window length `a` in `(0, limit)` at which η⁺(a + 1) steps up:
    /// `k·T − J` for a stream (T, J) and k ≥ 1, ascending and distinct.
    /// `None` when there are more than `max`.
    pub fn steps_below(&self, limit: Nanos, max: usize) -> Option<Vec<Nanos>> {
        let mut out = Vec::new();
        for s in &self.streams {
            let mut a = 0;
            while let Some(step) = s.step_after(a).filter(|&step| step < limit) {
                out.push(step);
                if out.len() > max {
                    return None;
                }
                a = step;
            }
        }
        out.sort_unstable();
        out.dedup();
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_of_a_jittered_stream() {
        // T = 10, J = 3: windows of 1..7 hold one event, 8..17 two.
        let a = Arrivals::periodic(10, 3);
        assert_eq!(a.eta(0), 0);
        assert_eq!(a.eta(1), 1);
        assert_eq!(a.eta(7), 1);
        assert_eq!(a.eta(8), 2);
        assert_eq!(a.eta(17), 2);
        assert_eq!(a.eta(18), 3);
        // η⁺(a + 1) steps at a = k·T − J: 7, 17, 27 below 30.
        assert_eq!(a.steps_below(30, 10), Some(vec![7, 17, 27]));
        assert_eq!(a.steps_below(30, 2), None);
    }

    #[test]
    fn junctions() {
        let (p, q) = (Arrivals::periodic(10, 0), Arrivals::periodic(25, 5));
        let any = Arrivals::any(&[&p, &q]);
        assert_eq!(any.eta(10), 1 + 1);
        assert_eq!(any.eta(21), 3 + 2);
        // All: one more than the slower input's events.
        let all = Arrivals::all(&[&p, &q]);
        assert_eq!(all.eta(21), 1 + 2);
        assert_eq!(Arrivals::all(&[&p]), p);
        // Output jitter.
        assert_eq!(p.delayed(4), Some(Arrivals::periodic(10, 4)));
    }

    #[test]
    fn any_delayed_is_any_of_the_delayed_inputs_and_none_where_one_is() {
        let (a, b) = (
            Arrivals::periodic(10, 3),
            Arrivals::any(&[&Arrivals::periodic(7, 0), &Arrivals::periodic(20, 5)]),
        );
        let delayed = [a.delayed(4).unwrap(), b.delayed(9).unwrap()];
        assert_eq!(
            Arrivals::any_delayed([Some((&a, 4)), Some((&b, 9))].into_iter()),
            Some(Arrivals::any(&[&delayed[0], &delayed[1]]))
        );
        // An unbounded input, first or last: no figure, as when a delay
        // passes MAX_TIME.
        assert_eq!(
            Arrivals::any_delayed([Some((&a, 4)), None].into_iter()),
            None
        );
        assert_eq!(
            Arrivals::any_delayed([None, Some((&b, 9))].into_iter()),
            None
        );
        assert_eq!(
            Arrivals::any_delayed([Some((&a, MAX_TIME))].into_iter()),
            None
        );
    }

    #[test]
    fn all_delayed_is_all_of_the_delayed_inputs_and_none_where_one_is() {
        let (p, q) = (Arrivals::periodic(10, 3), Arrivals::periodic(25, 5));
        // Two inputs as slow: the first is taken.
        let r = Arrivals::any(&[&Arrivals::periodic(50, 0), &Arrivals::periodic(50, 7)]);
        let cases: [&[(&Arrivals, Nanos)]; 4] = [
            &[(&p, 4)],
            &[(&p, 4), (&q, 9)],
            &[(&q, 9), (&p, 4), (&r, 2)],
            &[(&r, 1), (&q, 0), (&r, 6)],
        ];
        for inputs in cases {
            let delayed: Vec<Arrivals> =
                inputs.iter().map(|&(a, x)| a.delayed(x).unwrap()).collect();
            let refs: Vec<&Arrivals> = delayed.iter().collect();
            assert_eq!(
                Arrivals::all_delayed(inputs.iter().map(|&i| Some(i))),
                Some(Arrivals::all(&refs)),
                "{inputs:?}"
            );
        }
        // An unbounded input, or a delay out of range on an input that is
        // not the slowest: no figure.
        assert_eq!(
            Arrivals::all_delayed([Some((&q, 1)), None].into_iter()),
            None
        );
        assert_eq!(
            Arrivals::all_delayed([Some((&q, 1)), Some((&p, MAX_TIME))].into_iter()),
            None
        );
    }

    #[test]
    fn same_up_to_the_first_window_where_a_jitter_shows() {
        // T 10, J 3 → 5: ⌈(w + 3)/10⌉ = ⌈(w + 5)/10⌉ up to w = 5, not at 6.
        let (a, b) = (Arrivals::periodic(10, 3), Arrivals::periodic(10, 5));
        assert_eq!(a.same_up_to(&b), 5);
        assert_eq!(b.same_up_to(&a), 5);
        for w in 0..=5 {
            assert_eq!(a.eta(w), b.eta(w), "w = {w}");
        }
        assert_ne!(a.eta(6), b.eta(6));
        assert_eq!(a.same_up_to(&a), Nanos::MAX);
        // J 9 → 10 differ at once (w = 1: ⌈10/10⌉ = 1, ⌈11/10⌉ = 2).
        assert_eq!(
            Arrivals::periodic(10, 9).same_up_to(&Arrivals::periodic(10, 10)),
            0
        );
        assert_eq!(a.same_up_to(&Arrivals::periodic(20, 3)), 0);
    }
}
