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

/// How much shorter than the task's D and T a SCHED_DEADLINE reservation's
/// deadline and period are (at most; see [`reservation`]). At a wake-up
/// the kernel gives a fresh deadline (wake-up + D) only when the current
/// one has passed or the leftover runtime would exceed the bandwidth
/// (`update_dl_entity`), and a throttled reservation is replenished with
/// its deadline one period on, not at the next release. So a reservation
/// whose deadline once lay after a release (a late timer wake-up, an
/// overrun) kept that phase job after job: each job ran its leftover,
/// was throttled until the kept deadline and then ran behind jobs of later
/// deadlines (measured: paper-table2-edf's t6, 1.24 ms behind for the rest
/// of the run, 2.3 ms responses against R(job) = 1.15 ms). With the period
/// shorter by the lead the kept phase falls back by the lead each period
/// until the wake-up renews the deadline again, and a wake-up up to the
/// lead sooner after its release than the job before it still renews it.
/// The same lead for every task keeps the kernel's EDF order that of the
/// jobs' deadlines.
pub const RENEWAL_LEAD: Nanos = 100_000;

/// A SCHED_DEADLINE reservation, in ns: what `run` asks the kernel for
/// and the rt-app export writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reservation {
    /// [`reservation_runtime`].
    pub runtime: Nanos,
    /// The task's D less the lead.
    pub deadline: Nanos,
    /// The task's T less the lead.
    pub period: Nanos,
}

/// The reservation of a task of budget C, relative deadline D ≤ T and
/// period T: runtime C + [`RESERVATION_MARGIN`] (at most D), deadline and
/// period shorter by [`RENEWAL_LEAD`], or by less where the runtime or a
/// short period leaves no room for it (the lead is at most D − runtime and
/// T/8, so runtime ≤ deadline ≤ period still holds).
pub fn reservation(budget: Nanos, deadline: Nanos, period: Nanos) -> Reservation {
    let runtime = reservation_runtime(budget, deadline);
    let lead = RENEWAL_LEAD.min(deadline - runtime).min(period / 8).max(0);
    Reservation {
        runtime,
        deadline: deadline - lead,
        period: period - lead,
    }
}

/// How long a thread retries a reservation the kernel refuses with EBUSY
/// beyond the run's longest period: a run that ended just before holds its
/// threads' bandwidth until their reservations' 0-lag time (at most a
/// period after their last wake-up; `task_non_contending` and the inactive
/// timer in kernel/sched/deadline.c), and the process's exit adds its own.
pub const ADMISSION_MARGIN: Nanos = 500_000_000;

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reservation_leads_the_tasks_deadline_and_period_by_the_same_amount() {
        // C = 1.15 ms, D = T = 5 ms (paper-table2-edf's t6).
        let r = reservation(1_150_000, 5_000_000, 5_000_000);
        assert_eq!(r.runtime, 1_150_000 + RESERVATION_MARGIN);
        assert_eq!(r.deadline, 5_000_000 - RENEWAL_LEAD);
        assert_eq!(r.period, 5_000_000 - RENEWAL_LEAD);
        // A constrained deadline leads by the same amount: EDF order kept.
        let c = reservation(1_000_000, 8_000_000, 10_000_000);
        assert_eq!((c.deadline, c.period), (7_900_000, 9_900_000));
    }

    #[test]
    fn the_lead_never_breaks_the_kernels_order_of_runtime_deadline_period() {
        for (c, d, t) in [
            // The runtime fills D: no room for a lead.
            (1_000_000, 1_000_000, 1_000_000),
            // 30 µs of room, less than the lead.
            (970_000, 1_050_000, 1_050_000),
            // A 200 µs period: the lead is at most T/8.
            (10_000, 200_000, 200_000),
        ] {
            let r = reservation(c, d, t);
            assert!(r.runtime <= r.deadline && r.deadline <= r.period, "{r:?}");
            assert!(d - r.deadline <= (d - r.runtime).min(t / 8), "{r:?}");
        }
        assert_eq!(reservation(10_000, 200_000, 200_000).period, 175_000);
    }
}
