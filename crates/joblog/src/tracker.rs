//! Provenance of samples along one chain, and the reaction and freshness
//! of each sample that reaches the tail.

use crate::rows::Rows;
use crate::{ChainStats, SampleRow, Witness};
use rtpipe_model::Nanos;
use std::collections::VecDeque;

/// Per chain: stamps of the samples and the sample the tail currently outputs.
pub(crate) struct Tracker {
    /// Stamps of samples `base..`: older samples never reach the tail
    /// again (samples reach it in order), so they are dropped and a run's
    /// memory does not grow with its length.
    stamps: VecDeque<Nanos>,
    /// The id of `stamps[0]`.
    base: u64,
    /// (sample, first, last) of the newest sample seen at the tail.
    pub(crate) current: Option<(u64, Nanos, Nanos)>,
    /// The smallest sample whose from-event reaction is not known yet:
    /// the first tail output carrying it or a newer one has not happened.
    pub(crate) event_pending: u64,
    pub(crate) stats: ChainStats,
    /// One row per head sample, by sample id, when asked for.
    pub(crate) rows: Option<Rows>,
    /// Samples below this one were published by the head (its jobs that
    /// read later had not finished: a job log holds no such job).
    pub(crate) head_done: u64,
}

impl Tracker {
    /// Its histograms count up to `cap` distinct values exactly.
    pub(crate) fn new(cap: usize) -> Tracker {
        Tracker {
            stamps: VecDeque::new(),
            base: 0,
            current: None,
            // Sample 0 has no head read before it, so no event window.
            event_pending: 1,
            stats: ChainStats::with_exact_cap(cap),
            rows: None,
            head_done: 0,
        }
    }

    /// A tracker that also keeps one [`SampleRow`] per head sample.
    pub(crate) fn with_rows(cap: usize) -> Tracker {
        Tracker {
            rows: Some(Rows::default()),
            ..Tracker::new(cap)
        }
    }

    /// The head reads a new sample at t: its id (ids count head reads).
    /// Inlined: the simulator calls it on every head read, across crates.
    #[inline]
    pub(crate) fn sample(&mut self, t: Nanos) -> u64 {
        if let Some(rows) = &mut self.rows {
            let id = rows.next_id();
            rows.push(SampleRow::new(id, t, self.stamps.back().copied()));
        }
        self.stamps.push_back(t);
        self.stats.samples += 1;
        self.base + self.stamps.len() as u64 - 1
    }

    /// The read instant of `sample` (held: from the one before the tail's).
    fn stamp(&self, sample: u64) -> Nanos {
        self.stamps[(sample - self.base) as usize]
    }

    /// Whether the head has read `sample`.
    pub(crate) fn has(&self, sample: u64) -> bool {
        (self.base..self.base + self.stamps.len() as u64).contains(&sample)
    }

    /// How many stamps are held (bounded by the samples in flight).
    #[cfg(test)]
    pub(crate) fn held(&self) -> usize {
        self.stamps.len()
    }

    /// Forgets the stamps of samples before `sample`.
    fn drop_before(&mut self, sample: u64) {
        while self.base < sample && !self.stamps.is_empty() {
            self.stamps.pop_front();
            self.base += 1;
        }
    }

    /// The head's reads, known beforehand (a finished job log): sample k
    /// is the k-th read.
    pub(crate) fn set_stamps(&mut self, stamps: Vec<Nanos>) {
        if let Some(rows) = &mut self.rows {
            *rows = Rows::from_vec(
                (0..stamps.len())
                    .map(|k| {
                        SampleRow::new(k as u64, stamps[k], k.checked_sub(1).map(|e| stamps[e]))
                    })
                    .collect(),
            );
        }
        self.stats.samples = stamps.len() as u64;
        self.stamps = stamps.into();
        self.base = 0;
    }

    /// The tail publishes a value carrying `sample` at t.
    pub(crate) fn output(&mut self, sample: u64, t: Nanos) {
        match self.current {
            Some((s, first, _)) if s == sample => self.current = Some((s, first, t)),
            prev => {
                // Samples reach the tail in order: each task's jobs read in
                // order and registers only move forward.
                debug_assert!(!matches!(prev, Some((s, _, _)) if s >= sample));
                if let Some((s, first, last)) = prev {
                    self.finalise(s, first, last);
                }
                self.stats.reached += 1;
                self.current = Some((sample, t, t));
                self.first_output(sample, t);
                // Every older sample is final now: it reached the tail for
                // the last time, or never will.
                if let Some(rows) = &mut self.rows {
                    rows.complete_below(sample);
                }
                // Its finalising needs the stamp before it.
                self.drop_before(sample.saturating_sub(1));
            }
        }
    }

    /// The first tail output of `sample`, at t: its reaction from the read,
    /// and the from-event reaction of every sample up to it that was still
    /// waiting (samples between the previous one to reach the tail and this
    /// one never reach it; this is the first output that reflects them).
    pub(crate) fn first_output(&mut self, sample: u64, t: Nanos) {
        let stamp = self.stamp(sample);
        let w = Witness {
            sample,
            read: stamp,
            first: t,
            last: t,
        };
        self.stats.reaction.push(t - stamp, w);
        for s in self.event_pending..=sample {
            let event = self.stamp(s - 1);
            let w = Witness {
                sample: s,
                read: event,
                first: t,
                last: t,
            };
            self.stats.event_reaction.push(t - event, w);
            if let Some(rows) = &mut self.rows {
                rows.get_mut(s).event_first = Some(t);
            }
        }
        if let Some(rows) = &mut self.rows {
            rows.get_mut(sample).first = Some(t);
        }
        self.event_pending = self.event_pending.max(sample + 1);
    }

    pub(crate) fn finalise(&mut self, sample: u64, first: Nanos, last: Nanos) {
        let w = Witness {
            sample,
            read: self.stamp(sample),
            first,
            last,
        };
        if let Some(rows) = &mut self.rows {
            rows.get_mut(sample).last = Some(last);
        }
        let before = (sample > 0).then(|| self.stamp(sample - 1));
        let st = &mut self.stats;
        st.finalised += 1;
        st.freshness.push(w.freshness(), w);
        if let Some(read) = before {
            let event = Witness { read, ..w };
            st.event_freshness.push(event.freshness(), event);
        }
    }
}
