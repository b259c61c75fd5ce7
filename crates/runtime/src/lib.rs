//! # rtpipe-runtime
//!
//! Runs a pipe system for real: one thread per task, released periodically
//! under `SCHED_FIFO` (rate-monotonic priorities) or `SCHED_DEADLINE`, tasks
//! communicating through Simpson's four-slot registers ([`four_slot`]), one
//! per (producer, consumer) edge. docs/runtime.md describes the design.

pub mod exec;
pub mod four_slot;
pub mod seqlock;
pub mod spin;
pub mod sys;

pub use exec::{
    check, run, ErrorKind, Policy, RunConfig, RunError, RunResult, TaskRun, OVERRUN_TOLERANCE,
};
pub use spin::{synthetic, Spin};
