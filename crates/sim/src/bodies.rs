//! Task code in simulated time: the simulator decides when each job reads
//! and publishes, and at those instants runs the task's [`Body`] and talks
//! to the [`Environment`] (`rtpipe-body` defines the seam).
//!
//! A body runs at its job's read instant, on the latest value of each
//! producer (registers: the last publish before or at that instant) and, for
//! a task the environment serves, the environment's sample at that instant.
//! Its output stays private until the job's publish instant, when it
//! overwrites the task's register and reaches the environment.

use crate::{Hooks, SimConfig, SimError};
use rtpipe_body::{Body, Environment, Job, Nanos, Stamp, Stamped};
use rtpipe_joblog::SimResult;
use rtpipe_model::Spec;

/// Simulates `spec` like [`crate::simulate`] and runs `bodies[i]` for every
/// job of task i, with `env` as the world. Same spec, configuration, bodies
/// and environment: the same run, bit for bit.
///
/// # Panics
/// When `bodies` does not hold one body per task (a caller's bug, not a
/// user's input).
pub fn simulate_bodies<V: Copy>(
    spec: &Spec,
    cfg: &SimConfig,
    bodies: &mut [Box<dyn Body<V> + '_>],
    env: &mut dyn Environment<V>,
) -> Result<SimResult, SimError> {
    simulate_bodies_with_rows(spec, cfg, bodies, env, None)
}

/// [`simulate_bodies`] that, with `rows`, hands every chain's sample rows
/// on as they complete (see [`crate::simulate_with_rows`]).
pub fn simulate_bodies_with_rows<V: Copy>(
    spec: &Spec,
    cfg: &SimConfig,
    bodies: &mut [Box<dyn Body<V> + '_>],
    env: &mut dyn Environment<V>,
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<SimResult, SimError> {
    match simulate_bodies_with_progress(spec, cfg, bodies, env, &mut |_| true, rows)? {
        Some(result) => Ok(result),
        None => unreachable!("a progress that always goes on never stops the run"),
    }
}

/// [`simulate_bodies_with_rows`], calling `progress` with the simulated
/// time reached every [`crate::PROGRESS_EVENTS`] events, as
/// [`crate::simulate_with_progress`] does: the one place a caller can
/// abandon a run of task code (its answer `false` ends the run: `Ok(None)`,
/// no result), since the bodies and the environment cannot end it.
///
/// # Panics
/// As [`simulate_bodies`].
pub fn simulate_bodies_with_progress<V: Copy>(
    spec: &Spec,
    cfg: &SimConfig,
    bodies: &mut [Box<dyn Body<V> + '_>],
    env: &mut dyn Environment<V>,
    progress: &mut dyn FnMut(Nanos) -> bool,
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<Option<SimResult>, SimError> {
    assert_eq!(
        bodies.len(),
        spec.tasks.len(),
        "simulate_bodies needs one body per task"
    );
    let n = spec.tasks.len();
    let max_reads = spec.tasks.iter().map(|t| t.reads.len()).max().unwrap_or(0);
    let driver = Driver {
        bodies,
        env,
        reads: spec.tasks.iter().map(|t| t.reads.clone()).collect(),
        latest: vec![None; n],
        pending: vec![None; n],
        inputs: Vec::with_capacity(max_reads),
    };
    crate::run_until(spec, cfg, driver, progress, rows)
}

/// Runs bodies at the instants the simulator reports.
struct Driver<'a, 'b, V> {
    bodies: &'a mut [Box<dyn Body<V> + 'b>],
    env: &'a mut dyn Environment<V>,
    /// Producers of each task, in `reads` order.
    reads: Vec<Vec<usize>>,
    /// Each task's register: its last published value.
    latest: Vec<Option<Stamped<V>>>,
    /// The output of each task's running job, not yet published.
    pending: Vec<Option<(V, Job)>>,
    /// Scratch space for one job's inputs (no allocation per job).
    inputs: Vec<Option<Stamped<V>>>,
}

impl<V: Copy> Hooks for Driver<'_, '_, V> {
    fn read(&mut self, job: &Job) {
        let i = job.task;
        // Only a task's front job runs, and it publishes before the next reads.
        assert!(self.pending[i].is_none(), "task {i} reads twice");
        self.inputs.clear();
        self.inputs
            .extend(self.reads[i].iter().map(|&p| self.latest[p]));
        let device = self.env.sense(i, job.read);
        let out = self.bodies[i].run(job, &self.inputs, device);
        self.pending[i] = Some((out, *job));
    }

    fn publish(&mut self, task: usize, t: Nanos) {
        let Some((value, job)) = self.pending[task].take() else {
            unreachable!("task {task} publishes without having read");
        };
        let stamp = Stamp {
            task,
            job: job.index,
            read: job.read,
            publish: t,
        };
        self.latest[task] = Some(Stamped { value, stamp });
        self.env.actuate(task, t, &value);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::{spec, task};
    use crate::{ExecModel, Phasing};
    use rtpipe_model::Scheduler;

    /// What a body saw: (task, job, read, inputs' stamps and values, device).
    type Seen = (usize, u64, Nanos, Vec<Option<(Stamp, i64)>>, Option<i64>);

    /// A plant with one state x: sensing returns x, actuating adds the
    /// command; every call is logged to check the order.
    #[derive(Default)]
    struct Plant {
        x: i64,
        calls: Vec<(char, usize, Nanos)>,
    }

    impl Environment<i64> for Plant {
        fn sense(&mut self, task: usize, t: Nanos) -> Option<i64> {
            self.calls.push(('s', task, t));
            (task == 0).then_some(self.x)
        }
        fn actuate(&mut self, task: usize, t: Nanos, value: &i64) {
            self.calls.push(('a', task, t));
            if task == 1 {
                self.x += value;
            }
        }
    }

    /// Runs a sensor (task 0: the plant's sample) and a controller (task 1:
    /// its input + 1, commanding the plant) over 30 ns; what each body
    /// saw, and the plant's calls.
    fn run_sensor_and_controller(s: &Spec) -> (Vec<Seen>, Plant) {
        let seen = std::sync::Mutex::new(Vec::<Seen>::new());
        let log = |job: &Job, inputs: &[Option<Stamped<i64>>], device: Option<i64>| {
            let stamps = inputs.iter().map(|x| x.map(|v| (v.stamp, v.value)));
            if let Ok(mut v) = seen.lock() {
                v.push((job.task, job.index, job.read, stamps.collect(), device));
            }
        };
        let sensor = move |job: &Job, inputs: &[Option<Stamped<i64>>], device: Option<i64>| {
            log(job, inputs, device);
            device.unwrap_or(-1)
        };
        let controller = move |job: &Job, inputs: &[Option<Stamped<i64>>], device: Option<i64>| {
            log(job, inputs, device);
            inputs[0].map_or(0, |v| v.value + 1)
        };
        let mut bodies: Vec<Box<dyn Body<i64> + '_>> = vec![Box::new(sensor), Box::new(controller)];
        let mut plant = Plant::default();
        let cfg = SimConfig {
            phasing: Phasing::Sync,
            exec: ExecModel::Worst,
            ..SimConfig::new(30)
        };
        assert!(simulate_bodies(s, &cfg, &mut bodies, &mut plant).is_ok());
        drop(bodies);
        (seen.into_inner().unwrap_or_default(), plant)
    }

    fn st(task: usize, job: u64, read: Nanos, publish: Nanos) -> Stamp {
        Stamp {
            task,
            job,
            read,
            publish,
        }
    }

    #[test]
    fn bodies_run_at_reads_and_publish_at_completions() {
        // t0: T=10, C=2 (rank 1) samples the plant; t1: T=20, C=3 reads t0
        // and commands the plant with its input + 1. The schedule is the one
        // of tests::slow_consumer_rm: t0 reads at 10k, publishes at 10k + 2;
        // t1 job m reads at 20m + 2 and publishes at 20m + 5.
        let s = spec(
            Scheduler::Rm,
            vec![task(10, 2, &[], 0), task(20, 3, &[0], 0)],
            &[&[0, 1]],
        );
        let (seen, plant) = run_sensor_and_controller(&s);
        assert_eq!(
            seen,
            vec![
                (0, 0, 0, vec![], Some(0)),
                // t1's first job reads t0's sample 0, published at 2.
                (1, 0, 2, vec![Some((st(0, 0, 0, 2), 0))], None),
                (0, 1, 10, vec![], Some(1)),
                (0, 2, 20, vec![], Some(1)),
                (1, 1, 22, vec![Some((st(0, 2, 20, 22), 1))], None),
                // t1 job 1 published 2 at 25: the plant is at 3 by 30.
                (0, 3, 30, vec![], Some(3)),
            ]
        );
        // Publishes before reads at one instant; time never goes back.
        assert_eq!(
            &plant.calls[..4],
            &[('s', 0, 0), ('a', 0, 2), ('s', 1, 2), ('a', 1, 5)]
        );
        assert!(plant.calls.windows(2).all(|w| w[0].2 <= w[1].2));
    }

    #[test]
    fn under_let_bodies_read_at_releases_and_publish_at_period_ends() {
        // The same two tasks on a LET chain: t0 job k reads (and senses)
        // at 10k and publishes at 10k + 10; t1 job m reads at 20m, after
        // the publishes of that instant, and publishes at 20m + 20.
        let mut s = spec(
            Scheduler::Rm,
            vec![task(10, 2, &[], 0), task(20, 3, &[0], 0)],
            &[&[0, 1]],
        );
        s.chains[0].communication = Some(rtpipe_model::Communication::Let);
        let (seen, plant) = run_sensor_and_controller(&s);
        assert_eq!(
            seen,
            vec![
                (0, 0, 0, vec![], Some(0)),
                // Nothing published by 0, though t0 completes at 2.
                (1, 0, 0, vec![None], None),
                (0, 1, 10, vec![], Some(0)),
                (0, 2, 20, vec![], Some(0)),
                // t0 job 1 (read 10) became visible at 20, before this read.
                (1, 1, 20, vec![Some((st(0, 1, 10, 20), 0))], None),
                (0, 3, 30, vec![], Some(0)),
            ]
        );
        assert_eq!(
            &plant.calls[..6],
            &[
                ('s', 0, 0),
                ('s', 1, 0),
                ('a', 0, 10),
                ('s', 0, 10),
                ('a', 0, 20),
                ('a', 1, 20)
            ]
        );
        assert!(plant.calls.windows(2).all(|w| w[0].2 <= w[1].2));
    }
}
