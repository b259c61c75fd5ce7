//! What a refresh carries from a task whose activations changed to the
//! units that read them: the streams that moved and up to where the
//! activations are the same (`events::Deps::refresh`).

use super::readers::unit_of;
use crate::arrivals::{Arrivals, Stream};
use rtpipe_model::{Nanos, Spec};

/// A task's activations changed, the same up to `same`.
pub(super) struct Change<'a> {
    /// The task's unit.
    pub(super) unit: usize,
    /// The streams whose jitter changed, (old, new), when both are bounded
    /// (then of the same periods): where each of them keeps its η⁺, so
    /// does their sum.
    pub(super) moved: Option<&'a [(Stream, Stream)]>,
    pub(super) same: Nanos,
}

impl<'a> Change<'a> {
    /// The change of task `j` from `old` to `new`, its moved streams in
    /// `moved` (kept from one change to the next rather than allocated at
    /// each).
    pub(super) fn of(
        spec: &Spec,
        j: usize,
        old: &Option<Arrivals>,
        new: &Option<Arrivals>,
        moved: &'a mut Vec<(Stream, Stream)>,
    ) -> Self {
        let unit = unit_of(spec, j);
        match (old, new) {
            (Some(a), Some(b)) => {
                // A task's streams and their periods are the spec's (its
                // sources', through `any` and the slowest trigger of an
                // `all`); only their jitters grow. The warm analyses lean on
                // it: they skip the load guard, which reads works and
                // periods alone (`thread_rta::fifo_response_from`,
                // `sched::level_response_from`).
                assert!(
                    same_periods(a, b),
                    "task {j}'s activations changed their periods"
                );
                Change::moved(unit, a, b, moved)
            }
            _ => Change {
                unit,
                moved: None,
                same: 0,
            },
        }
    }

    /// The change of a task of `unit` from `a` to `b`, the same streams
    /// with grown jitters, those that moved into `moved`.
    pub(super) fn moved(
        unit: usize,
        a: &Arrivals,
        b: &Arrivals,
        moved: &'a mut Vec<(Stream, Stream)>,
    ) -> Self {
        moved.clear();
        let pairs = a.streams.iter().zip(&b.streams).filter(|(s, t)| s != t);
        moved.extend(pairs.map(|(&s, &t)| (s, t)));
        Change {
            unit,
            moved: Some(moved),
            same: a.same_up_to(b),
        }
    }
}

/// `a` and `b` are the same streams with other jitters at most.
fn same_periods(a: &Arrivals, b: &Arrivals) -> bool {
    a.streams.len() == b.streams.len()
        && a.streams
            .iter()
            .zip(&b.streams)
            .all(|(s, t)| s.period == t.period)
}
