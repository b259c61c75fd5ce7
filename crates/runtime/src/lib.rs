//! # rtpipe-runtime
//!
//! Runs a pipe system for real: one thread per task, released periodically
//! under `SCHED_FIFO` (rate-monotonic priorities), `SCHED_DEADLINE`, or
//! SCHED_FIFO under an EDF dispatcher (EDF with the stack resource policy), tasks
//! communicating through Simpson's four-slot registers ([`four_slot`]), one
//! per (producer, consumer) edge. docs/runtime.md describes the design.
#![deny(missing_docs)]

pub mod blame;
mod class;
mod comm;
mod config;
pub mod edf;
pub mod exec;
pub mod foreign;
pub mod four_slot;
mod let_comm;
pub mod load;
pub mod locks;
pub mod overheads;
pub mod partition;
pub mod pi;
pub mod probe;
pub mod rt_app;
pub mod seqlock;
pub mod spin;
pub mod sys;

pub use exec::{
    check, fifo_priorities, run, run_synthetic, ErrorKind, Policy, RunConfig, RunError, RunResult,
    TaskRun, OVERRUN_TOLERANCE, RESERVATION_MARGIN,
};
pub use load::Load;
pub use pi::PiMutex;
pub use rt_app::{rt_app, RtApp};
pub use spin::{synthetic, Spin};
