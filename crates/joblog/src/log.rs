//! The job log of a run: every completed job with the samples it carried,
//! the schedule's segments, per-task figures, and the result that holds
//! them with the chains' figures.

use crate::ChainStats;
use rtpipe_model::Nanos;

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
    /// A data-triggered job: the publication that released it (the first,
    /// when later ones merged into it; under join = "all" the one that
    /// completed the set). `None` for a timer's job.
    pub trigger: Option<Trigger>,
}

/// A publication that released a data-triggered job: which job of which
/// task published.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trigger {
    /// The publishing task.
    pub task: usize,
    /// Its job (release index, from 0).
    pub job: u64,
}

/// What one task's jobs did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TaskStats {
    /// Jobs released (a release merged into a queued job is not one).
    pub released: u64,
    /// Releases merged into a job of the task that was queued and not yet
    /// started (threads and data-triggered tasks: PX4's one pending
    /// activation); always 0 for a thread-less periodic task.
    pub merged: u64,
    /// Jobs completed.
    pub completed: u64,
    /// Largest finish − release over completed jobs.
    pub max_response: Option<Nanos>,
    /// Completed jobs that finished after their deadline (D, the period
    /// unless the spec gives one), counted from the nominal release.
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

/// Everything a run measured: the simulator's, or a real run's in the
/// simulator's terms.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimResult {
    /// The release offsets used (a simulator replays a random phasing with
    /// them; a real run releases from one epoch with the spec's known
    /// offsets, 0 where a task has none).
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
