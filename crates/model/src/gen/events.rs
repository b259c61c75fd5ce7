//! Random event-triggered systems (work-queue threads and data-triggered
//! tasks, PX4's model), deterministic per seed.
//!
//! Every chain starts at a periodic source; each later link is, at random,
//! data-triggered by its predecessor (`join = "any"`, or `"all"` with a
//! second trigger from earlier in the system) or periodic. Tasks land on a
//! few threads or on threads of their own; a few periodic timer items share
//! the threads. Execution times split each CPU's utilisation (UUniFast) by
//! each task's nominal activation rate (`Spec::activation_period`),
//! and priorities per CPU are rate monotonic with an occasional swap, so
//! most systems are schedulable and some are not.

use super::{uunifast, Rng};
use crate::{
    Chain, Channel, Join, PeriodSpec, Port, Priorities, Scheduler, Server, Spec, Task, Thread,
    TimeUnit,
};

/// What to generate.
#[derive(Debug, Clone)]
pub struct EventGenConfig {
    /// Chains per system: min_chains..=max_chains, drawn.
    pub min_chains: usize,
    /// See `min_chains`.
    pub max_chains: usize,
    /// Tasks per chain: min_links..=max_links, drawn (at least 2).
    pub min_links: usize,
    /// See `min_links`.
    pub max_links: usize,
    /// Threads: 1..=max_threads, drawn (unused ones are dropped).
    pub max_threads: usize,
    /// CPUs: 1..=max_cpus, drawn.
    pub max_cpus: u32,
    /// Total utilisation per CPU (worst-case execution over the nominal
    /// activation period, `Spec::activation_period`).
    pub utilization: f64,
    /// Probability that a link after a chain's head is data-triggered.
    pub data_fraction: f64,
    /// Probability that a task runs in one of the threads.
    pub thread_fraction: f64,
    /// Periodic timer items added beside the chains: 0..=max_timers.
    pub max_timers: usize,
}

impl Default for EventGenConfig {
    fn default() -> Self {
        EventGenConfig {
            min_chains: 1,
            max_chains: 3,
            min_links: 2,
            max_links: 8,
            max_threads: 6,
            max_cpus: 2,
            utilization: 0.5,
            data_fraction: 0.6,
            thread_fraction: 0.7,
            max_timers: 3,
        }
    }
}

/// The periods of periodic tasks, in µs: short, as in a flight controller,
/// so a simulation covers many releases.
const PERIODS_US: [i64; 7] = [250, 500, 1000, 2000, 4000, 5000, 10_000];

/// A random valid event-triggered system (`Spec::event_triggered` holds):
/// times in whole µs, explicit priorities, rate-monotonic scheduling.
///
/// The draws come from one stream in a fixed order (shape, chains, timers,
/// placement, demands, priorities): keep that order, or every seed would
/// mean a different system.
pub fn event_triggered_system(seed: u64, cfg: &EventGenConfig) -> Spec {
    let mut rng = Rng::new(seed);
    let cpus = rng.range(1, u64::from(cfg.max_cpus.max(1))) as u32;
    let n_threads = rng.range(1, cfg.max_threads.max(1) as u64) as usize;
    let mut threads: Vec<Thread> = (0..n_threads)
        .map(|i| Thread {
            name: format!("wq{i}"),
            priority: 0,
            cpu: rng.range(0, u64::from(cpus) - 1) as u32,
        })
        .collect();
    let mut tasks = Vec::new();
    let mut chains = Vec::new();
    let lo = cfg.min_chains.max(1);
    let n_chains = rng.range(lo as u64, cfg.max_chains.max(lo) as u64) as usize;
    for _ in 0..n_chains {
        chains.push(random_chain(&mut rng, cfg, &mut tasks));
    }
    let n_timers = rng.range(0, cfg.max_timers as u64) as usize;
    for _ in 0..n_timers {
        let i = tasks.len();
        tasks.push(periodic(&mut rng, i));
    }
    place(&mut rng, cfg, &mut tasks, &threads, cpus);
    drop_unused_threads(&mut tasks, &mut threads);
    let mut spec = Spec {
        name: format!("events-{seed}"),
        time_unit: TimeUnit::Us,
        scheduler: Scheduler::Rm,
        schedulability: Scheduler::Rm.policy().default_test(),
        resolution: 1000,
        harmonic: false,
        priorities: Priorities::Explicit,
        communication: crate::Communication::Implicit,
        resource_protocol: crate::ResourceProtocol::Pcp,
        resources: Vec::new(),
        overheads: crate::Overheads::default(),
        // Transfers cost nothing here: a job's demand is its execution.
        channels: vec![Channel {
            name: "mem".into(),
            bandwidth: 1000.0,
            overhead: 0,
        }],
        threads,
        tasks,
        chains,
    };
    let rates = release_rates(&spec);
    for cpu in 0..cpus {
        draw_execs(&mut rng, cfg, &mut spec.tasks, &rates, cpu);
    }
    assign_priorities(&mut rng, &mut spec.tasks, &mut spec.threads, &rates, cpus);
    spec
}

/// Releases per second of each task, at its nominal activation period
/// (`Spec::activation_period`: a data-triggered task's from its triggers).
fn release_rates(spec: &Spec) -> Vec<f64> {
    (0..spec.tasks.len())
        .map(|i| spec.activation_period(i).map_or(0.0, |p| 1e9 / p as f64))
        .collect()
}

/// A periodic task `t{i}` with a drawn period and, sometimes, release
/// jitter of up to a tenth of it; its execution is drawn later.
fn periodic(rng: &mut Rng, i: usize) -> Task {
    let period_us = PERIODS_US[rng.range(0, PERIODS_US.len() as u64 - 1) as usize];
    let jitter_us = if rng.chance(0.3) {
        rng.range(1, (period_us / 10) as u64) as i64
    } else {
        0
    };
    Task {
        name: format!("t{i}"),
        server: Server::None,
        jitter: jitter_us * 1000,
        ..Task::periodic(1000, period_us * 1000)
    }
}

/// One chain of new tasks: a periodic head reading a device, then links
/// that read their predecessor, each data-triggered with probability
/// `cfg.data_fraction` (join all with a second trigger from an earlier
/// task, when there is one, one time in three) or periodic.
fn random_chain(rng: &mut Rng, cfg: &EventGenConfig, tasks: &mut Vec<Task>) -> Chain {
    let lo = cfg.min_links.max(2) as u64;
    let len = rng.range(lo, cfg.max_links.max(lo as usize) as u64) as usize;
    let head = tasks.len();
    let mut path = vec![head];
    tasks.push(Task {
        input: Some(Port {
            channel: 0,
            size: 0.0,
        }),
        ..periodic(rng, head)
    });
    for _ in 1..len {
        let i = tasks.len();
        let prev = i - 1;
        let mut t = if rng.chance(cfg.data_fraction) {
            triggered(rng, i, prev)
        } else {
            periodic(rng, i)
        };
        t.reads.insert(0, prev);
        tasks.push(t);
        path.push(i);
    }
    Chain::linked(tasks, path)
}

/// A data-triggered task `t{i}` released by `prev`, and one time in three,
/// when there is an earlier task, also by it (join all or any, even odds).
fn triggered(rng: &mut Rng, i: usize, prev: usize) -> Task {
    let mut triggers = vec![prev];
    let mut reads = Vec::new();
    let mut join = Join::Any;
    if prev > 0 && rng.chance(1.0 / 3.0) {
        let other = rng.range(0, prev as u64 - 1) as usize;
        reads.push(other);
        triggers.push(other);
        if rng.chance(0.5) {
            join = Join::All;
        }
    }
    Task {
        name: format!("t{i}"),
        reads,
        period: PeriodSpec::Triggered { triggers, join },
        server: Server::None,
        ..Task::periodic(1000, 1)
    }
}

/// Each task goes, with probability `cfg.thread_fraction`, into a random
/// thread (its CPU), else runs as a thread of its own on a random CPU.
fn place(rng: &mut Rng, cfg: &EventGenConfig, tasks: &mut [Task], threads: &[Thread], cpus: u32) {
    for t in tasks {
        if rng.chance(cfg.thread_fraction) {
            let th = rng.range(0, threads.len() as u64 - 1) as usize;
            t.thread = Some(th);
            t.cpu = threads[th].cpu;
        } else {
            t.cpu = rng.range(0, u64::from(cpus) - 1) as u32;
        }
    }
}

/// Drops the threads no task runs in (validation refuses them) and
/// renumbers the tasks' threads.
fn drop_unused_threads(tasks: &mut [Task], threads: &mut Vec<Thread>) {
    let used: Vec<bool> = (0..threads.len())
        .map(|th| tasks.iter().any(|t| t.thread == Some(th)))
        .collect();
    let mut new_index = vec![None; threads.len()];
    let mut next = 0;
    for (th, &u) in used.iter().enumerate() {
        if u {
            new_index[th] = Some(next);
            next += 1;
        }
    }
    for t in tasks.iter_mut() {
        t.thread = t.thread.and_then(|th| new_index[th]);
    }
    let mut th = 0;
    threads.retain(|_| {
        th += 1;
        used[th - 1]
    });
}

/// Execution times of the tasks on `cpu`: UUniFast shares of
/// `cfg.utilization` over their release rates, in whole µs (at least 1), and
/// a best case drawn below each.
fn draw_execs(rng: &mut Rng, cfg: &EventGenConfig, tasks: &mut [Task], rates: &[f64], cpu: u32) {
    let ids: Vec<usize> = (0..tasks.len()).filter(|&i| tasks[i].cpu == cpu).collect();
    if ids.is_empty() {
        return;
    }
    let shares = uunifast(rng, ids.len(), cfg.utilization);
    for (&i, &u) in ids.iter().zip(&shares) {
        let exec_us = ((u / rates[i] * 1e6).floor() as i64).max(1);
        tasks[i].exec = exec_us * 1000;
        tasks[i].exec_min = rng.range(0, exec_us as u64) as i64 * 1000;
    }
}

/// Explicit priorities per CPU over its threads and thread-less tasks:
/// rate monotonic (a thread at its fastest task's rate), then, one time in
/// four, two neighbours swapped. A thread's tasks take its priority.
fn assign_priorities(
    rng: &mut Rng,
    tasks: &mut [Task],
    threads: &mut [Thread],
    rates: &[f64],
    cpus: u32,
) {
    // An entity is a thread (Ok) or a thread-less task (Err).
    let mut thread_rates = vec![0.0f64; threads.len()];
    for (t, &r) in tasks.iter().zip(rates) {
        if let Some(th) = t.thread {
            thread_rates[th] = thread_rates[th].max(r);
        }
    }
    let rate_of = |e: &Result<usize, usize>| -> f64 {
        match *e {
            Ok(th) => thread_rates[th],
            Err(i) => rates[i],
        }
    };
    for cpu in 0..cpus {
        let mut entities: Vec<Result<usize, usize>> = (0..threads.len())
            .filter(|&th| threads[th].cpu == cpu)
            .map(Ok)
            .chain(
                (0..tasks.len())
                    .filter(|&i| tasks[i].thread.is_none() && tasks[i].cpu == cpu)
                    .map(Err),
            )
            .collect();
        // Fastest first; the sort is stable, so ties keep the order above.
        entities.sort_by(|a, b| rate_of(b).total_cmp(&rate_of(a)));
        if entities.len() >= 2 && rng.chance(0.25) {
            let k = rng.range(0, entities.len() as u64 - 2) as usize;
            entities.swap(k, k + 1);
        }
        for (rank, e) in entities.iter().enumerate() {
            let priority = rank as u32 + 1;
            match *e {
                Ok(th) => threads[th].priority = priority,
                Err(i) => tasks[i].priority = Some(priority),
            }
        }
    }
    for t in tasks.iter_mut() {
        if let Some(th) = t.thread {
            t.priority = Some(threads[th].priority);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_systems_are_event_triggered_and_deterministic() {
        let cfg = EventGenConfig::default();
        for seed in 0..50 {
            let a = event_triggered_system(seed, &cfg);
            assert!(a.event_triggered());
            assert!(a.tasks.iter().all(|t| t.exec % 1000 == 0 && t.exec > 0));
            assert_eq!(a, event_triggered_system(seed, &cfg), "seed {seed}");
        }
    }
}
