//! What a run measured per chain: every observation of each latency,
//! from the head's read and from the event.

use crate::Histogram;
use rtpipe_model::Nanos;

/// The life of one sample at the tail of a chain, as one observation saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Witness {
    /// The sample's id.
    pub sample: u64,
    /// The instant the latency is measured from: the head's read of the
    /// sample (from-read quantities), or the head read before it (from-event
    /// quantities: the event came just after that read).
    pub read: Nanos,
    /// First and last tail publishes of the observation. From-event
    /// reaction: the first tail publish carrying `sample` or a newer one.
    pub first: Nanos,
    /// The last tail publish of the observation.
    pub last: Nanos,
}

impl Witness {
    /// First tail publish minus the anchor: the reaction time.
    pub fn reaction(&self) -> Nanos {
        self.first - self.read
    }
    /// Last tail publish minus the anchor: the freshness time.
    pub fn freshness(&self) -> Nanos {
        self.last - self.read
    }
}

/// Every observation of one quantity of one chain.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Observed {
    /// The largest value.
    pub max: Option<Nanos>,
    /// The observation that gave it (the first one, on ties).
    pub witness: Option<Witness>,
    /// Every value, counted (bounded memory whatever the run's length; the
    /// per-sample record is [`SampleRow`]'s, on request).
    pub hist: Histogram,
}

impl Observed {
    /// A value.
    pub(crate) fn push(&mut self, value: Nanos, w: Witness) {
        assert!(value >= 0, "a latency is never negative: {w:?}");
        self.hist.push(value);
        if self.max.is_none_or(|m| value > m) {
            self.max = Some(value);
            self.witness = Some(w);
        }
    }
}

/// What one chain's samples did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChainStats {
    /// Samples created by the head (head reads).
    pub samples: u64,
    /// Samples that reached the tail.
    pub reached: u64,
    /// Samples that reached the tail and whose last output is known.
    pub finalised: u64,
    /// From the head's read to the sample's first tail output: every sample
    /// that reached the tail.
    pub reaction: Observed,
    /// From the head's read to the sample's last tail output: every finalised
    /// sample.
    pub freshness: Observed,
    /// From an event just after a head read to the first tail output
    /// carrying a sample read after it: one per head sample (but the first)
    /// whose such output came before the horizon, whether or not the sample
    /// itself reached the tail.
    pub event_reaction: Observed,
    /// From the head read before a sample's read to the sample's last tail
    /// output: every finalised sample but the first.
    pub event_freshness: Observed,
}

impl ChainStats {
    /// Nothing measured yet; each latency's histogram counts up to `cap`
    /// distinct values exactly (`hist::exact_cap`: a run's chains share
    /// one budget).
    pub fn with_exact_cap(cap: usize) -> ChainStats {
        let observed = || Observed {
            hist: crate::Histogram::with_exact_cap(cap),
            ..Observed::default()
        };
        ChainStats {
            reaction: observed(),
            freshness: observed(),
            event_reaction: observed(),
            event_freshness: observed(),
            ..ChainStats::default()
        }
    }
}

/// One head sample of one chain: its read and the tail outputs that end
/// its latencies (`None` where the run ended first). The per-sample view
/// of [`ChainStats`], from the same trackers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleRow {
    /// The sample's id (the k-th head read).
    pub sample: u64,
    /// The head's read of the sample.
    pub read: Nanos,
    /// The head read before it: the latest instant of an event the sample
    /// reflects first (`None` for sample 0).
    pub event: Option<Nanos>,
    /// The first tail output carrying the sample.
    pub first: Option<Nanos>,
    /// The last tail output carrying the sample, once a newer one reached
    /// the tail.
    pub last: Option<Nanos>,
    /// The first tail output carrying the sample or a newer one.
    pub event_first: Option<Nanos>,
}

impl SampleRow {
    pub(crate) fn new(sample: u64, read: Nanos, event: Option<Nanos>) -> SampleRow {
        SampleRow {
            sample,
            read,
            event,
            first: None,
            last: None,
            event_first: None,
        }
    }

    /// Reaction from the read: first output − read.
    pub fn reaction(&self) -> Option<Nanos> {
        self.first.map(|f| f - self.read)
    }

    /// Freshness from the read: last output − read.
    pub fn freshness(&self) -> Option<Nanos> {
        self.last.map(|l| l - self.read)
    }

    /// Reaction from the event: first output carrying this sample or a
    /// newer one − the previous head read.
    pub fn event_reaction(&self) -> Option<Nanos> {
        Some(self.event_first? - self.event?)
    }

    /// Freshness from the event (rtpipe's own; not the literature's maximum
    /// data age, which runs to the next output): last output − the
    /// previous head read.
    pub fn event_freshness(&self) -> Option<Nanos> {
        Some(self.last? - self.event?)
    }
}
