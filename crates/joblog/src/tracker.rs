//! Provenance of samples along one chain, and the reaction and freshness
//! of each sample that reaches the tail.

use crate::{ChainStats, SampleRow, Witness};
use rtpipe_model::Nanos;

/// Per chain: stamps of the samples and the sample the tail currently outputs.
pub(crate) struct Tracker {
    pub(crate) stamps: Vec<Nanos>,
    /// (sample, first, last) of the newest sample seen at the tail.
    pub(crate) current: Option<(u64, Nanos, Nanos)>,
    /// The smallest sample whose from-event reaction is not known yet:
    /// the first tail output carrying it or a newer one has not happened.
    pub(crate) event_pending: u64,
    pub(crate) stats: ChainStats,
    /// One row per head sample, indexed by sample id, when asked for.
    pub(crate) rows: Option<Vec<SampleRow>>,
}

impl Tracker {
    pub(crate) fn new() -> Tracker {
        Tracker {
            stamps: Vec::new(),
            current: None,
            // Sample 0 has no head read before it, so no event window.
            event_pending: 1,
            stats: ChainStats::default(),
            rows: None,
        }
    }

    /// A tracker that also keeps one [`SampleRow`] per head sample.
    pub(crate) fn with_rows() -> Tracker {
        Tracker {
            rows: Some(Vec::new()),
            ..Tracker::new()
        }
    }

    /// The head reads a new sample at t: its id (ids count head reads).
    /// Inlined: the simulator calls it on every head read, across crates.
    #[inline]
    pub(crate) fn sample(&mut self, t: Nanos) -> u64 {
        if let Some(rows) = &mut self.rows {
            rows.push(SampleRow::new(
                rows.len() as u64,
                t,
                self.stamps.last().copied(),
            ));
        }
        self.stamps.push(t);
        self.stats.samples += 1;
        self.stamps.len() as u64 - 1
    }

    /// The head's reads, known beforehand (a finished job log): sample k
    /// is the k-th read.
    pub(crate) fn set_stamps(&mut self, stamps: Vec<Nanos>) {
        if let Some(rows) = &mut self.rows {
            *rows = (0..stamps.len())
                .map(|k| SampleRow::new(k as u64, stamps[k], k.checked_sub(1).map(|e| stamps[e])))
                .collect();
        }
        self.stats.samples = stamps.len() as u64;
        self.stamps = stamps;
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
            }
        }
    }

    /// The first tail output of `sample`, at t: its reaction from the read,
    /// and the from-event reaction of every sample up to it that was still
    /// waiting (samples between the previous one to reach the tail and this
    /// one never reach it; this is the first output that reflects them).
    pub(crate) fn first_output(&mut self, sample: u64, t: Nanos) {
        let stamp = self.stamps[sample as usize];
        let w = Witness {
            sample,
            read: stamp,
            first: t,
            last: t,
        };
        self.stats.reaction.push(t - stamp, t, w);
        for s in self.event_pending..=sample {
            let event = self.stamps[s as usize - 1];
            let w = Witness {
                sample: s,
                read: event,
                first: t,
                last: t,
            };
            self.stats.event_reaction.push(t - event, t, w);
            if let Some(rows) = &mut self.rows {
                rows[s as usize].event_first = Some(t);
            }
        }
        if let Some(rows) = &mut self.rows {
            rows[sample as usize].first = Some(t);
        }
        self.event_pending = self.event_pending.max(sample + 1);
    }

    pub(crate) fn finalise(&mut self, sample: u64, first: Nanos, last: Nanos) {
        let w = Witness {
            sample,
            read: self.stamps[sample as usize],
            first,
            last,
        };
        if let Some(rows) = &mut self.rows {
            rows[sample as usize].last = Some(last);
        }
        let st = &mut self.stats;
        st.finalised += 1;
        st.freshness.push(w.freshness(), last, w);
        if sample > 0 {
            let event = Witness {
                read: self.stamps[sample as usize - 1],
                ..w
            };
            st.event_freshness.push(event.freshness(), last, event);
        }
    }
}
