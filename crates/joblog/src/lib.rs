//! # rtpipe-joblog
//!
//! What a run of a pipe system measured, whoever ran it: the simulator
//! (`rtpipe-sim`) or the real-time runtime (`rtpipe-runtime`). Both feed
//! the same code, so a run is measured one way.
//!
//! - The job log: every completed job ([`JobRecord`]) with the
//!   samples it carried ([`Carried`]), CPU slices or job spans
//!   ([`Segment`]), per-task figures ([`TaskStats`]), and the result that
//!   holds them ([`SimResult`]).
//! - Sample provenance ([`Provenance`]): an executor says when each job
//!   reads and publishes; the provenance follows each chain's samples from
//!   the head's reads to the tail's outputs and yields every chain's
//!   reaction and freshness, from the read and from the event
//!   ([`ChainStats`]). [`chains_from_jobs`] measures a finished log.
//! - Chrome traces of a log ([`trace`]).
//!
//! ## Measurement
//!
//! Every job of a chain's head creates a sample stamped with its read
//! instant. A job at position k of a chain carries the sample carried by the
//! value it read from position k−1 (provenance follows the chain's edges
//! only, each chain separately). Per sample, the first and last publish of
//! the tail that carries it give reaction = first − stamp (counted at the
//! first output) and freshness = last − stamp (counted once the tail has
//! published a newer sample, so the last output is known). Only samples
//! that reach the tail count.
//!
//! From the event (the cause-effect-chain literature's quantities): for each
//! head read but the first, an event just after the previous head read. Its
//! reaction ends at the first tail output carrying a sample read at or after
//! the event, which need not be the event's own sample (it may be
//! overwritten before it is used); its freshness is the previous head read
//! to the sample's last tail output.
#![deny(missing_docs)]

mod chain;
pub mod hist;
mod log;
mod provenance;
mod rows;
pub mod samples;
pub mod trace;
mod tracker;

pub use chain::{ChainStats, Observed, SampleRow, Witness};
pub use hist::Histogram;
pub use log::{Carried, JobRecord, Segment, SimResult, TaskStats, Trigger};
pub use provenance::{chains_from_jobs, sample_rows, BadChain, Provenance, Slot};
pub use rows::RowSink;
