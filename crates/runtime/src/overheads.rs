//! Measures the scheduling overheads of this machine for `[system]
//! overheads` (`rtpipe run --measure-overheads`), per CPU the spec uses,
//! with the threads in the class a run would give them (SCHED_FIFO
//! pinned, SCHED_DEADLINE in the CPU's root domain, or SCHED_OTHER):
//!
//! - **context switch**: two threads of the class on one CPU hand the CPU
//!   to each other (a futex wake, then a wait: `park`/`unpark`); a round
//!   trip is two switches with their wake-ups, so half of it is one switch
//!   as the model charges it (a switch to a job that was woken);
//! - **release**: a thread of the class sleeps to an absolute instant of
//!   CLOCK_MONOTONIC and reads the clock when it runs: the timer
//!   interrupt, the wake-up and the switch to it, all of what a release
//!   costs before the job's first instruction (under SCHED_DEADLINE the
//!   kernel's CBS replenishment at the wake-up is inside it too; under the
//!   EDF dispatcher the dispatcher's release and completion work, see
//!   `dispatched_releases`);
//! - **replenishment**: the runtime has no budget path of its own (under
//!   SCHED_FIFO budgets are not enforced; SCHED_DEADLINE replenishes in the
//!   wake-up measured above), so nothing is measured for it.
//!
//! Each figure is a distribution over many samples; the spec gets its
//! 99th percentile (a maximum on a shared machine is a preemption by
//! something else, which the model does not have, and `run` blames).

use crate::class::{configure, Placement};
use crate::config::{Policy, RunError};
use crate::edf::Dispatcher;
use crate::partition::Partition;
use crate::sys;
use rtpipe_model::Nanos;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Context switch round trips per CPU.
pub const SWITCH_SAMPLES: usize = 20_000;
/// Timer releases per CPU, one every [`RELEASE_GAP`].
pub const RELEASE_SAMPLES: usize = 2_000;
/// The time between two measured releases.
pub const RELEASE_GAP: Nanos = 500_000;

/// The spinning job's cycle in [`dispatched_releases`]: it sleeps a tenth.
const SPIN_CYCLE: Nanos = 10_000_000;

/// A measured distribution, ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Spread {
    /// Samples taken.
    pub samples: usize,
    /// Median.
    pub median: Nanos,
    /// 99th percentile (what a spec gets).
    pub p99: Nanos,
    /// Largest.
    pub max: Nanos,
}

impl Spread {
    fn of(mut v: Vec<Nanos>) -> Spread {
        assert!(!v.is_empty(), "a spread of no samples");
        v.sort_unstable();
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        Spread {
            samples: v.len(),
            median: at(0.5),
            p99: at(0.99),
            max: v[v.len() - 1],
        }
    }
}

/// What one CPU measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CpuOverheads {
    /// The CPU.
    pub cpu: usize,
    /// One context switch (half a round trip).
    pub context_switch: Spread,
    /// Timer expiry to the released thread running.
    pub release: Spread,
}

/// The class of the measuring threads: as a run's, with a reservation of
/// 3 ms per 10 ms under SCHED_DEADLINE (two of them fit one CPU).
fn placement(cpu: usize, priority: i32) -> Placement<'static> {
    Placement {
        name: "overhead probe",
        cpu,
        priority: Some(priority),
        budget: 3_000_000,
        deadline: 10_000_000,
        period: 10_000_000,
        admission_wait: 10_000_000 + crate::config::ADMISSION_MARGIN,
    }
}

/// Measures every CPU of `cpus` under `policy`. A stop signal
/// (`sys::STOP_SIGNALS`) is held off until the measurement ends (about
/// 1.5 s per CPU), so that the cpusets it made go with it; the caller
/// asks [`sys::stop_requested`] then.
pub fn measure(policy: Policy, cpus: &[usize]) -> Result<Vec<CpuOverheads>, RunError> {
    sys::catch_stop_signals();
    // What a run killed by SIGKILL left on the machine goes first.
    crate::partition::repair()
        .map_err(|why| RunError::refused(why, "repair the cpuset hierarchy as the message says"))?;
    let partition = if policy == Policy::Deadline {
        Partition::create(sys::online_cpus()).ok().map(Arc::new)
    } else {
        None
    };
    cpus.iter()
        .map(|&cpu| {
            Ok(CpuOverheads {
                cpu,
                context_switch: switches(policy, cpu, partition.clone())?,
                release: releases(policy, cpu, partition.clone())?,
            })
        })
        .collect()
}

/// Half of each of [`SWITCH_SAMPLES`] round trips between two threads of
/// the class on `cpu` (neither of them the caller, whose class stays).
fn switches(
    policy: Policy,
    cpu: usize,
    partition: Option<Arc<Partition>>,
) -> Result<Spread, RunError> {
    let prober = std::thread::spawn(move || ping_pong(policy, cpu, partition));
    match prober.join() {
        Ok(r) => Ok(Spread::of(r?)),
        Err(_) => Err(RunError::config("the overhead probe's thread failed", "")),
    }
}

/// The measuring side of [`switches`], in its own thread: it starts the
/// partner, both enter the class, then they hand the CPU back and forth.
fn ping_pong(
    policy: Policy,
    cpu: usize,
    partition: Option<Arc<Partition>>,
) -> Result<Vec<Nanos>, RunError> {
    let done = Arc::new(AtomicBool::new(false));
    let (tx, rx) = std::sync::mpsc::channel();
    let me = std::thread::current();
    let part = partition.clone();
    let flag = done.clone();
    let partner = std::thread::spawn(move || -> Result<(), RunError> {
        let r = configure(&placement(cpu, 50), policy, part.as_deref());
        let _ = tx.send((std::thread::current(), r.is_ok()));
        r?;
        while !flag.load(Ordering::SeqCst) {
            std::thread::park();
            me.unpark();
        }
        Ok(())
    });
    let setup = configure(&placement(cpu, 50), policy, partition.as_deref());
    let mut v = Vec::with_capacity(SWITCH_SAMPLES);
    let other = rx.recv().ok();
    if let (Ok(()), Some((other, true))) = (&setup, &other) {
        for k in 0..SWITCH_SAMPLES + 100 {
            let t0 = sys::now();
            other.unpark();
            std::thread::park();
            if k >= 100 {
                v.push((sys::now() - t0) / 2);
            }
        }
    }
    done.store(true, Ordering::SeqCst);
    if let Some((other, _)) = &other {
        other.unpark();
    }
    let joined = partner.join();
    setup?;
    match joined {
        Ok(r) => r?,
        Err(_) => return Err(RunError::config("the overhead probe's thread failed", "")),
    }
    Ok(v)
}

/// [`RELEASE_SAMPLES`] timer releases of a thread of the class on `cpu`.
fn releases(
    policy: Policy,
    cpu: usize,
    partition: Option<Arc<Partition>>,
) -> Result<Spread, RunError> {
    if policy == Policy::EdfFifo {
        return dispatched_releases(cpu);
    }
    let probe = std::thread::spawn(move || -> Result<Vec<Nanos>, RunError> {
        configure(&placement(cpu, 60), policy, partition.as_deref())?;
        let mut v = Vec::with_capacity(RELEASE_SAMPLES);
        let mut at = sys::now() + RELEASE_GAP;
        for k in 0..RELEASE_SAMPLES + 20 {
            sys::sleep_until(at);
            let late = sys::now() - at;
            if k >= 20 {
                v.push(late);
            }
            at = sys::now().max(at) + RELEASE_GAP;
        }
        Ok(v)
    });
    match probe.join() {
        Ok(r) => Ok(Spread::of(r?)),
        Err(_) => Err(RunError::config("the overhead probe's thread failed", "")),
    }
}

/// [`RELEASE_SAMPLES`] releases under the EDF dispatcher on `cpu`, each
/// with all the dispatcher's work its job brings: a probe thread, woken by
/// its timer at DISPATCH, preempts a spinning job of a later deadline (the
/// dispatch that changes the most: the running job to WAIT, the probe to
/// RUN; one release in ten finds it asleep and the CPU idle), then
/// completes at once (raise, remove, the spinning job back to
/// RUN). A sample is the wake-up's lateness to the end of that release
/// dispatch plus the completion's dispatch: a job's release and its
/// completion come in pairs, so charging both at the release counts each
/// once (docs/runtime.md, "Resources under EDF").
fn dispatched_releases(cpu: usize) -> Result<Spread, RunError> {
    let d = Arc::new(Dispatcher::bare(cpu, 2));
    let done = Arc::new(AtomicBool::new(false));
    let (dd, flag) = (d.clone(), done.clone());
    let spinner = std::thread::spawn(move || -> Result<(), RunError> {
        configure(&placement(cpu, 0), Policy::EdfFifo, None)?;
        dd.register(1);
        dd.release(1, Nanos::MAX);
        // A tenth of the time asleep: some releases find the CPU idle (a
        // wake-up from idle, as in a run), and the class stays below the
        // kernel's real-time throttling (95 % by default).
        while !flag.load(Ordering::SeqCst) {
            let t = sys::now();
            while sys::now() - t < 9 * SPIN_CYCLE / 10 && !flag.load(Ordering::SeqCst) {
                std::hint::spin_loop();
            }
            sys::sleep_until(sys::now() + SPIN_CYCLE / 10);
        }
        dd.complete(1);
        Ok(())
    });
    let probe = std::thread::spawn(move || -> Result<Vec<Nanos>, RunError> {
        let placed = configure(&placement(cpu, 0), Policy::EdfFifo, None);
        let v = placed.map(|()| release_samples(&d));
        done.store(true, Ordering::SeqCst);
        v
    });
    let (v, spun) = (probe.join(), spinner.join());
    match (v, spun) {
        (Ok(v), Ok(s)) => {
            s?;
            Ok(Spread::of(v?))
        }
        _ => Err(RunError::config("the overhead probe's thread failed", "")),
    }
}

/// The probe's side of [`dispatched_releases`] (task 0 of `d`).
fn release_samples(d: &Dispatcher) -> Vec<Nanos> {
    d.register(0);
    let mut v = Vec::with_capacity(RELEASE_SAMPLES);
    let mut at = sys::now() + RELEASE_GAP;
    for k in 0..RELEASE_SAMPLES + 20 {
        sys::sleep_until(at);
        d.release(0, at + RELEASE_GAP);
        let late = sys::now() - at;
        let t0 = sys::now();
        d.complete(0);
        if k >= 20 {
            v.push(late + sys::now() - t0);
        }
        at = sys::now().max(at) + RELEASE_GAP;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_known_spread() {
        let s = Spread::of((1..=100).rev().collect());
        assert_eq!((s.samples, s.median, s.p99, s.max), (100, 51, 99, 100));
        assert_eq!(Spread::of(vec![7]).p99, 7);
    }

    #[test]
    fn the_best_effort_class_measures_positive_costs() {
        let m = measure(Policy::Other, &[0]).unwrap_or_else(|e| panic!("{e:?}"));
        let c = m[0];
        assert_eq!(c.context_switch.samples, SWITCH_SAMPLES);
        assert!(c.context_switch.median > 0 && c.release.median > 0, "{c:?}");
        assert!(c.release.median <= c.release.p99 && c.release.p99 <= c.release.max);
    }
}
