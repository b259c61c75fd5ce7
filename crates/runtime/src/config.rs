//! What a run is asked to do and how it may fail: the policy, the
//! configuration, the error, and the constants and priorities the executor
//! and the scheduling classes share.

use rtpipe_model::{Diagnostic, Nanos, Spec};
use std::fmt;

/// How task threads are scheduled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Policy {
    /// `SCHED_FIFO`, rate-monotonic priorities, each thread pinned to its
    /// task's CPU (partitioned fixed priority, the `rm` model).
    Fifo,
    /// `SCHED_DEADLINE` reservations (runtime = budget, deadline = period =
    /// T): the `edf` model's constant-bandwidth servers.
    Deadline,
    /// `SCHED_OTHER`, pinned: no real-time guarantee (best effort).
    Other,
    /// `SCHED_FIFO` threads, pinned, under rtpipe's EDF dispatcher
    /// (`crate::edf`): the `edf` model with the stack resource policy,
    /// which SCHED_DEADLINE cannot run (budgets not enforced, as under
    /// `Fifo`).
    EdfFifo,
}

impl Policy {
    /// The name the CLI's `--policy` takes.
    pub fn name(self) -> &'static str {
        match self {
            Policy::Fifo => "fifo",
            Policy::Deadline => "deadline",
            Policy::Other => "other",
            Policy::EdfFifo => "edf-fifo",
        }
    }

    /// The kernel's class, as reports name it.
    pub fn class(self) -> &'static str {
        match self {
            Policy::Fifo => "SCHED_FIFO",
            Policy::Deadline => "SCHED_DEADLINE",
            Policy::Other => "SCHED_OTHER",
            Policy::EdfFifo => "SCHED_FIFO (rtpipe's EDF dispatcher)",
        }
    }

    /// Jobs are picked by absolute deadline (SCHED_DEADLINE or the EDF
    /// dispatcher): the `edf` model.
    pub fn edf(self) -> bool {
        matches!(self, Policy::Deadline | Policy::EdfFifo)
    }
}

/// What to run.
#[derive(Debug, Clone, Copy)]
pub struct RunConfig {
    /// Releases happen in [0, duration) after the epoch.
    pub duration: Nanos,
    /// The scheduling policy of the task threads.
    pub policy: Policy,
    /// Background CPU hogs (SCHED_OTHER) running for the whole run.
    pub load: usize,
}

/// The kind of a [`RunError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The spec or the flags cannot run as asked (exit status 2).
    Config,
    /// The kernel refused a scheduling class or a reservation (exit 2:
    /// fixable by the user).
    Refused,
}

/// Why a run could not start: the task, what is wrong, how to fix it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunError {
    /// Whose fault it is.
    pub kind: ErrorKind,
    /// What is wrong and how to fix it.
    pub diagnostic: Diagnostic,
}

impl RunError {
    pub(crate) fn config(msg: impl Into<String>, help: impl Into<String>) -> RunError {
        RunError {
            kind: ErrorKind::Config,
            diagnostic: Diagnostic::error(msg, help),
        }
    }

    pub(crate) fn refused(msg: impl Into<String>, help: impl Into<String>) -> RunError {
        RunError {
            kind: ErrorKind::Refused,
            diagnostic: Diagnostic::error(msg, help),
        }
    }
}

/// The message alone (the help is the caller's to show).
impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.diagnostic.message)
    }
}

/// CPU time a job may exceed its budget by before it counts as an overrun:
/// the job frame's own cost (three reads of the thread CPU clock, each a
/// system call, the register copies), which a synthetic body burning
/// exactly its budget adds on top.
pub const OVERRUN_TOLERANCE: Nanos = 5_000;

/// What a SCHED_DEADLINE reservation's runtime adds to the budget C: the
/// job frame, and the rare burn that ends late (up to 15 µs measured). A
/// reservation with runtime C exactly is overrun by a few µs by nearly
/// every job that burns its budget, and the kernel then throttles it until
/// its next period; once behind, a task whose reservation is its whole
/// demand never catches up (measured: every period missed).
pub const RESERVATION_MARGIN: Nanos = 50_000;

/// The runtime of the SCHED_DEADLINE reservation of a task of budget C and
/// relative deadline D: C + [`RESERVATION_MARGIN`], at most D (the kernel
/// refuses a runtime above the deadline). The one rule `run` reserves by
/// and the rt-app export writes.
pub fn reservation_runtime(budget: Nanos, deadline: Nanos) -> Nanos {
    (budget + RESERVATION_MARGIN).min(deadline)
}

/// The SCHED_FIFO priority of each task: rank 1 (the highest, in the
/// spec's priority order: rate monotonic, deadline monotonic or explicit,
/// `rtpipe_model::policy::ranks`) → 90, rank 2 → 89, ...; background tasks
/// (no rank) → 1.
pub fn fifo_priorities(spec: &Spec) -> Vec<i32> {
    rtpipe_model::policy::ranks(spec)
        .iter()
        .map(|r| r.map_or(1, |r| (91 - r as i32).max(2)))
        .collect()
}
