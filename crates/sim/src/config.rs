//! What one run simulates: phasing, execution-time model, horizon, seed;
//! and why a run cannot start.

use rtpipe_model::Nanos;
use std::fmt;

/// Release offsets φ_i of one run. Every variant keeps a task's known
/// offset (`offset` in the spec) and places only the tasks whose offset is
/// unknown; `Given` must agree with the known ones.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Phasing {
    /// Tasks release at 0 (the classic critical instant).
    Sync,
    /// φ_i uniform in [0, T_i), in nanoseconds.
    Random,
    /// φ_i a uniform multiple of the grid in [0, T_i): random phasings that
    /// still produce simultaneous events, where worst cases tend to hide.
    Grid(Nanos),
    /// Explicit offsets, one per task (for hand-made and replayed schedules).
    Given(Vec<Nanos>),
}

/// How each job's demand is drawn in [demand_min, demand].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecModel {
    /// Always the worst case.
    Worst,
    /// Always the best case.
    Best,
    /// Uniform integer nanoseconds.
    Uniform,
    /// Best or worst case with equal probability (extremes stress the bounds'
    /// best-case terms).
    Extremes,
}

/// Where in [nominal, nominal + J] each job of a task with release jitter J
/// is released (tasks without jitter release at the nominal instant, and
/// draw nothing, whatever the model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Jitter {
    /// Uniform integer nanoseconds in [0, J], from the task's seeded stream.
    #[default]
    Uniform,
    /// 0 or J with equal probability.
    Extremes,
    /// Always J (every job as late as it may be).
    Latest,
    /// Always 0 (the nominal releases).
    None,
    /// J and 0 in turn, by the parity of the job's period (`⌊nominal /
    /// T⌋`): a late job is followed T − J later by an on-time one, the
    /// closest two releases may come, as the response-time analysis with
    /// jitter counts them (Audsley et al. 1993). With offsets the search
    /// moves, every window can start at such a pair, which per-job draws
    /// ([`Jitter::Extremes`]) give a job in four, and for several tasks at
    /// once rarely.
    Squeezed,
}

/// How to run a simulation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimConfig {
    /// Simulated time; events after it are not processed.
    pub horizon: Nanos,
    /// Seeds offsets ([`Phasing::Random`], [`Phasing::Grid`]) and demands.
    pub seed: u64,
    /// When each task is first released.
    pub phasing: Phasing,
    /// Which demand each job gets.
    pub exec: ExecModel,
    /// Where each job of a jittered task is released.
    pub jitter: Jitter,
    /// Keep a [`JobRecord`](rtpipe_joblog::JobRecord) of every completed job (memory grows with the horizon).
    pub log_jobs: bool,
}

impl SimConfig {
    /// Synchronous release, worst-case demands, no job log.
    pub fn new(horizon: Nanos) -> SimConfig {
        SimConfig {
            horizon,
            seed: 0,
            phasing: Phasing::Sync,
            exec: ExecModel::Worst,
            jitter: Jitter::Uniform,
            log_jobs: false,
        }
    }
}

/// Why a simulation cannot run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SimError {
    /// The task has no fixed positive period, so it cannot be released.
    NoPeriod(String),
    /// The horizon is not positive.
    HorizonNotPositive(Nanos),
    /// `Phasing::Given` needs one non-negative offset per task.
    BadOffsets {
        /// Offsets needed: one per task.
        expected: usize,
        /// Offsets given.
        found: usize,
    },
    /// A task's offset is negative.
    NegativeOffset(String),
    /// `Phasing::Given` places a task whose offset the spec fixes elsewhere.
    OffsetConflict {
        /// The task.
        task: String,
        /// Its offset in the spec.
        known: Nanos,
        /// The offset given for the run.
        given: Nanos,
    },
    /// The `Phasing::Grid` step is not positive.
    GridNotPositive(Nanos),
    /// A chain names a task index that does not exist.
    BadChain(usize),
    /// A task's best-case demand is negative or above its worst case
    /// (validated specs never have one).
    BadDemand(String),
    /// Critical sections under a resource protocol the scheduler does not
    /// implement (validated specs never have them).
    Resources(&'static str),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::NoPeriod(t) => write!(f, "task `{t}` has no fixed positive period"),
            SimError::HorizonNotPositive(h) => write!(f, "horizon must be positive, found {h} ns"),
            SimError::BadOffsets { expected, found } => {
                write!(
                    f,
                    "expected {expected} offsets (one per task), found {found}"
                )
            }
            SimError::NegativeOffset(t) => write!(f, "offset of task `{t}` is negative"),
            SimError::OffsetConflict { task, known, given } => write!(
                f,
                "task `{task}` has the known offset {known} ns in the spec, but the run gives it {given} ns \
                 (a known offset is fixed in every run)"
            ),
            SimError::GridNotPositive(g) => {
                write!(f, "phasing grid must be positive, found {g} ns")
            }
            SimError::BadChain(c) => write!(f, "chain {c} names a task that does not exist"),
            SimError::BadDemand(t) => write!(
                f,
                "task `{t}`: its demands must satisfy 0 <= best case <= worst case"
            ),
            SimError::Resources(s) => write!(
                f,
                "critical sections under scheduler \"{s}\" with a resource protocol it does not implement: under \"edf\" use resource_protocol = \"srp\""
            ),
        }
    }
}

impl std::error::Error for SimError {}
