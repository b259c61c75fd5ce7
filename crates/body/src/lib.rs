//! # rtpipe-body
//!
//! The seam between task code and the executors that run it. A **body** is
//! what one job of a task computes: it receives the job (which task, which
//! job, when it was released and when it read), the latest value of each
//! producer it reads (with the stamp of the job that published it) and, for
//! a task that samples the world, the environment's sample; it returns its
//! output. It never reads a clock: every instant it sees is passed in.
//!
//! Executors decide only *when* a body runs. The simulator (`rtpipe-sim`,
//! `simulate_bodies`) runs a body at its job's read instant and makes its
//! output visible at the job's publish instant, in simulated time; a
//! real-time executor calls the same bodies from real threads. The
//! communication is register-based and implicit (Section II of Cheng, West,
//! Einstein, EMSOFT 2018): inputs are copied when a job starts, the output is
//! published atomically when it ends, and a value stays until the next
//! publish overwrites it. Values are `Copy`, so a register can be a
//! fixed-size slot (Simpson's four-slot buffer) and the periodic path never
//! allocates.
//!
//! An [`Environment`] is the world around the task set (a co-simulated plant,
//! or real devices): executors ask it for a sample at each job's read instant
//! and hand it each job's output at the publish instant, always in
//! non-decreasing time order.
//!
//! ```
//! use rtpipe_body::{Body, Job, Stamped};
//!
//! /// A running average of whatever the first producer publishes.
//! struct Average {
//!     sum: f64,
//!     n: u64,
//! }
//!
//! impl Body<f64> for Average {
//!     fn run(&mut self, _job: &Job, inputs: &[Option<Stamped<f64>>], _device: Option<f64>) -> f64 {
//!         if let Some(Some(x)) = inputs.first() {
//!             self.sum += x.value;
//!             self.n += 1;
//!         }
//!         if self.n == 0 { 0.0 } else { self.sum / self.n as f64 }
//!     }
//! }
//!
//! // A closure is a body too: a sensor task that publishes what it sampled.
//! let mut sensor = |job: &Job, _: &[Option<Stamped<f64>>], device: Option<f64>| {
//!     device.unwrap_or(job.read as f64)
//! };
//! let job = Job { task: 0, index: 0, release: 0, read: 5 };
//! assert_eq!(sensor.run(&job, &[], Some(2.0)), 2.0);
//! ```

#![deny(missing_docs)]

/// Time in integer nanoseconds (the same unit as the rest of rtpipe).
pub type Nanos = i64;

/// Where a value came from: the job that published it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamp {
    /// The producing task (its index in the spec).
    pub task: usize,
    /// k of the producer's k-th job, from 0.
    pub job: u64,
    /// When that job read its inputs; for a sensor task, when it sampled
    /// the world (the timestamp of the data).
    pub read: Nanos,
    /// When that job published the value.
    pub publish: Nanos,
}

/// A value as it travels between tasks: the data and its stamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamped<V> {
    /// The data.
    pub value: V,
    /// The job that published it.
    pub stamp: Stamp,
}

/// One job of a task, as its body sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Job {
    /// The task (its index in the spec).
    pub task: usize,
    /// k of the task's k-th job, from 0.
    pub index: u64,
    /// When the job was released.
    pub release: Nanos,
    /// When it read its inputs (first got the CPU): the instant the body's
    /// inputs and device sample are from.
    pub read: Nanos,
}

/// The code of one task: what each of its jobs computes.
///
/// `inputs` holds the latest value of each producer, in the order of the
/// task's `reads` (`None` until that producer first publishes); `device` is
/// the environment's sample at the job's read instant, for tasks the
/// environment serves. The returned value is published when the job ends.
/// Implementations must not allocate or block: they run in the periodic path
/// of a real-time executor.
pub trait Body<V>: Send {
    /// Runs one job.
    fn run(&mut self, job: &Job, inputs: &[Option<Stamped<V>>], device: Option<V>) -> V;
}

impl<V, F> Body<V> for F
where
    F: FnMut(&Job, &[Option<Stamped<V>>], Option<V>) -> V + Send,
{
    fn run(&mut self, job: &Job, inputs: &[Option<Stamped<V>>], device: Option<V>) -> V {
        self(job, inputs, device)
    }
}

/// The world around the task set. Executors call it in non-decreasing time
/// order, so a co-simulated plant can advance to `t` on every call.
pub trait Environment<V> {
    /// A job of `task` reads at `t`: the world's sample for it, or `None`
    /// when the task does not sample the world.
    fn sense(&mut self, task: usize, t: Nanos) -> Option<V>;
    /// A job of `task` publishes `value` at `t`: it reaches the world (a
    /// motor command, say); tasks without an effect on the world are ignored.
    fn actuate(&mut self, task: usize, t: Nanos, value: &V);
}

/// An environment that senses nothing and ignores every output.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoEnvironment;

impl<V> Environment<V> for NoEnvironment {
    fn sense(&mut self, _task: usize, _t: Nanos) -> Option<V> {
        None
    }
    fn actuate(&mut self, _task: usize, _t: Nanos, _value: &V) {}
}
