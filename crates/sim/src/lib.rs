//! # rtpipe-sim
//!
//! A small deterministic discrete-event simulator of pipe systems, used as the
//! oracle of the latency analysis (Cheng, West, Einstein, EMSOFT 2018).
//!
//! Each task runs on the server its spec names ([`server`]): Main VCPUs as
//! sporadic servers and I/O VCPUs as PIBS under `rm`, constant-bandwidth
//! servers under `edf`, plain and background tasks without enforcement.
//!
//! ## Semantics
//!
//! - Task i releases jobs at φ_i + k·T_i. A job's demand is drawn in
//!   [demand_min, demand] according to [`ExecModel`].
//! - A job READS (copies the latest published value of each producer) at the
//!   instant it first gets the CPU, and PUBLISHES its output at the instant
//!   its last unit of execution completes. Register semantics: a value is
//!   overwritten by the next publish.
//! - Each CPU is preemptive: RM by the rank of
//!   [`rtpipe_model::policy::rate_monotonic`], EDF by absolute deadline
//!   (release + T) then task index. Jobs of one task run in FIFO order.
//!   Background tasks run only when nothing else is ready.
//! - Threads and data-triggered tasks (`engine/events.rs`): a work-queue thread's
//!   jobs run one at a time to completion in release order, at the thread's
//!   rank; a completion releases the data-triggered tasks its task
//!   triggers at that instant (join any, or all); a release that finds an
//!   earlier job of its task queued and not started joins it
//!   (`TaskStats::merged`).
//! - At one instant: (1) completions publish, (2) releases, (3) each CPU picks
//!   a job, (4) jobs starting now read. So a job that starts when another job
//!   publishes sees the new value. All CPUs share one timeline.
//!
//! ## Measurement (Section III-D and the paper's instrumentation)
//!
//! The simulator feeds each read and publish to [`rtpipe_joblog::Provenance`],
//! which the real-time runtime feeds too, and returns its job log as an
//! [`rtpipe_joblog::SimResult`].
//!
//! Every job of a chain's head creates a sample stamped with its read instant.
//! A job at position k of a chain carries the sample carried by the value it
//! read from position k−1 (provenance follows the chain's edges only, each
//! chain separately). Per sample, the first and last publish of the tail that
//! carries it give reaction = first − stamp (counted at the first output) and
//! freshness = last − stamp (counted once the tail has published a newer
//! sample, so the last output is known). Only samples that reach the tail
//! count.
//!
//! From the event (what the analysis' `from_event` bounds bound; reaction
//! is the literature's maximum reaction time): for each head read but the first, an
//! event just after the previous head read. Its reaction ends at the first
//! tail output carrying a sample read at or after the event, which need not
//! be the event's own sample (it may be overwritten before it is used); its
//! freshness is the previous head read to the sample's last tail output.
#![deny(missing_docs)]

mod bodies;
mod config;
mod cpu_events;
mod cpus;
mod engine;

mod let_comm;
mod locks;
pub mod observe;
mod overheads;
mod release_heap;
pub mod search;
pub mod server;

pub use config::*;
pub(crate) use engine::*;
pub(crate) use locks::Locks;
/// The simulator's random numbers (execution times, random phasing, the
/// adversarial search): the workspace's one seeded generator, whose
/// sequence is pinned (`rtpipe_model::gen::Rng`).
pub use rtpipe_model::gen::Rng;

pub use bodies::{simulate_bodies, simulate_bodies_with_progress, simulate_bodies_with_rows};
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};

/// Simulates `spec` from 0 to `cfg.horizon`: the timing alone, no task code
/// ([`simulate_bodies`] runs task bodies too).
pub fn simulate(spec: &Spec, cfg: &SimConfig) -> Result<SimResult, SimError> {
    run(spec, cfg, NoHooks)
}

/// Events between two calls of a progress callback.
pub const PROGRESS_EVENTS: u64 = 1 << 16;

/// [`simulate`], calling `progress` with the simulated time reached every
/// [`PROGRESS_EVENTS`] events (for a progress bar over `cfg.horizon`). The
/// callback only observes: the result is the one [`simulate`] gives.
pub fn simulate_with_progress(
    spec: &Spec,
    cfg: &SimConfig,
    progress: &mut dyn FnMut(Nanos),
) -> Result<SimResult, SimError> {
    run_with_progress(spec, cfg, NoHooks, progress, None)
}

/// [`simulate`] that asks `stop` every [`PROGRESS_EVENTS`] events and ends
/// the run early when it says so: `Ok(None)`, no result. A long run is
/// cancelled within one such stretch of events (a campaign's Ctrl-C).
pub fn simulate_until(
    spec: &Spec,
    cfg: &SimConfig,
    stop: &dyn Fn() -> bool,
) -> Result<Option<SimResult>, SimError> {
    run_until(spec, cfg, NoHooks, &mut |_| !stop(), None)
}

/// [`simulate_until`] with a progress of its own and, with `rows`, every
/// chain's sample rows handed on as they complete ([`simulate_with_rows`]):
/// `progress` gets the simulated time reached every [`PROGRESS_EVENTS`]
/// events and ends the run by answering `false` (`Ok(None)`, no result).
pub fn simulate_watched(
    spec: &Spec,
    cfg: &SimConfig,
    progress: &mut dyn FnMut(Nanos) -> bool,
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<Option<SimResult>, SimError> {
    run_until(spec, cfg, NoHooks, progress, rows)
}

/// [`simulate_with_progress`] that also hands every chain's sample rows
/// (`rtpipe_joblog::sample_rows`' rows, the same values) to `rows` as they
/// complete: the per-sample record of a run of any length without its job
/// log.
pub fn simulate_with_rows(
    spec: &Spec,
    cfg: &SimConfig,
    progress: &mut dyn FnMut(Nanos),
    rows: rtpipe_joblog::RowSink,
) -> Result<SimResult, SimError> {
    run_with_progress(spec, cfg, NoHooks, progress, Some(rows))
}

#[cfg(test)]
mod reference;

#[cfg(test)]
mod tests;
