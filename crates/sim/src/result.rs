//! What a run measured: per task, per chain (from the head's read and from
//! the event), the job log and the schedule's segments.

use crate::tracker::Tracker;
use rtpipe_analysis::{Anchor, Metric};
use rtpipe_model::{Nanos, Spec};

/// The sample carried for one chain position by a job.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Carried {
    /// Index of the chain in `Spec::chains`.
    pub chain: usize,
    /// The task's position on that chain (0 = head).
    pub pos: usize,
    /// `None` when the producer had not published yet.
    pub sample: Option<u64>,
}

/// One completed job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobRecord {
    /// The task.
    pub task: usize,
    /// k of the k-th release, from 0.
    pub index: u64,
    /// Release instant.
    pub release: Nanos,
    /// Its demand (CPU time needed).
    pub demand: Nanos,
    /// First got the CPU (read instant).
    pub read: Nanos,
    /// Publish instant.
    pub finish: Nanos,
    /// One entry per chain position the task occupies.
    pub carried: Vec<Carried>,
}

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
        debug_assert!(value >= 0, "a latency is never negative: {w:?}");
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

impl ChainStats {
    /// The observations of one metric measured from one anchor.
    pub fn observed(&self, metric: Metric, anchor: Anchor) -> &Observed {
        match (metric, anchor) {
            (Metric::Reaction, Anchor::Read) => &self.reaction,
            (Metric::Freshness, Anchor::Read) => &self.freshness,
            (Metric::Reaction, Anchor::Event) => &self.event_reaction,
            (Metric::Freshness, Anchor::Event) => &self.event_freshness,
        }
    }
}

/// What one task's jobs did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TaskStats {
    /// Jobs released.
    pub released: u64,
    /// Jobs completed.
    pub completed: u64,
    /// Largest finish − release over completed jobs.
    pub max_response: Option<Nanos>,
    /// Completed jobs that finished after their period (the model's
    /// assumptions are broken for them).
    pub late: u64,
    /// Times the server ran out of budget with a job still pending.
    pub exhaustions: u64,
    /// CPU time the task's jobs received.
    pub busy: Nanos,
}

/// A stretch of CPU time given to one job (logged with `log_jobs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// Dense CPU index (CPUs in ascending order of their ids).
    pub cpu: usize,
    /// The task.
    pub task: usize,
    /// Its job (release index, from 0).
    pub job: u64,
    /// Start of the slice.
    pub start: Nanos,
    /// End of the slice.
    pub end: Nanos,
    /// Ran in slack at background priority (a sporadic server out of budget).
    pub background: bool,
}

/// Everything a run measured.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimResult {
    /// The offsets used (replay a random phasing with [`Phasing::Given`]).
    pub offsets: Vec<Nanos>,
    /// Per task, in declaration order.
    pub tasks: Vec<TaskStats>,
    /// Indexed like `spec.chains`.
    pub chains: Vec<ChainStats>,
    /// Completed jobs in completion order, when `log_jobs` is set.
    pub jobs: Vec<JobRecord>,
    /// CPU time slices in time order, when `log_jobs` is set.
    pub segments: Vec<Segment>,
    /// Events processed (instants at which something happened).
    pub events: u64,
    /// The simulated span.
    pub horizon: Nanos,
}

/// The chain statistics of a log of completed jobs (a real-time executor's,
/// say), measured exactly as the simulator measures its own runs. `jobs`
/// must hold, per task, its jobs from index 0 without gaps, in completion
/// order overall, with `carried` resolved (a head job carries its own index;
/// a job at position k the sample of the value it read from position k−1).
/// Head samples whose job is missing from the log are not counted.
pub fn chains_from_jobs(spec: &Spec, jobs: &[JobRecord]) -> Vec<ChainStats> {
    let mut trackers: Vec<Tracker> = spec.chains.iter().map(|_| Tracker::new()).collect();
    for (tr, ch) in trackers.iter_mut().zip(&spec.chains) {
        let Some(&head) = ch.path.first() else {
            continue;
        };
        let mut reads: Vec<(u64, Nanos)> = jobs
            .iter()
            .filter(|j| j.task == head)
            .map(|j| (j.index, j.read))
            .collect();
        reads.sort_unstable();
        tr.stamps = reads
            .iter()
            .enumerate()
            .take_while(|&(k, &(i, _))| k as u64 == i)
            .map(|(_, &(_, r))| r)
            .collect();
        tr.stats.samples = tr.stamps.len() as u64;
    }
    for j in jobs {
        for c in &j.carried {
            let (Some(ch), Some(sample)) = (spec.chains.get(c.chain), c.sample) else {
                continue;
            };
            let tr = &mut trackers[c.chain];
            if c.pos + 1 == ch.path.len() && (sample as usize) < tr.stamps.len() {
                tr.output(sample, j.finish);
            }
        }
    }
    trackers.into_iter().map(|t| t.stats).collect()
}
