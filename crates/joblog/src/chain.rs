//! What a run measured per chain: every observation of each latency,
//! from the head's read and from the event.

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
    /// Every value, in sample order.
    pub values: Vec<Nanos>,
    /// When each value became known (the tail output that ended it), in
    /// the same order: a time series of the latency.
    pub at: Vec<Nanos>,
}

impl Observed {
    /// A value that ended at `at`.
    pub(crate) fn push(&mut self, value: Nanos, at: Nanos, w: Witness) {
        assert!(value >= 0, "a latency is never negative: {w:?}");
        self.values.push(value);
        self.at.push(at);
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
