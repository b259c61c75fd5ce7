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
//!   [`rtpipe_analysis::sched::rm_priorities`], EDF by absolute deadline
//!   (release + T) then task index. Jobs of one task run in FIFO order.
//!   Background tasks run only when nothing else is ready.
//! - At one instant: (1) completions publish, (2) releases, (3) each CPU picks
//!   a job, (4) jobs starting now read. So a job that starts when another job
//!   publishes sees the new value. All CPUs share one timeline.
//!
//! ## Measurement (Section III-D and the paper's instrumentation)
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
//! From the event (the cause-effect-chain literature's quantities, what the
//! analysis' `from_event` bounds bound): for each head read but the first, an
//! event just after the previous head read. Its reaction ends at the first
//! tail output carrying a sample read at or after the event, which need not
//! be the event's own sample (it may be overwritten before it is used); its
//! freshness is the previous head read to the sample's last tail output.

mod bodies;
pub mod observe;
mod rng;
pub mod search;
pub mod server;
pub mod trace;

pub use bodies::simulate_bodies;

use crate::rng::Rng;
use rtpipe_analysis::sched::rm_priorities;
use rtpipe_analysis::{Anchor, Metric};
use rtpipe_model::{Nanos, Scheduler, Server, Spec};
use server::{Cbs, Pibs, Sporadic};
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap, VecDeque};
use std::fmt;

/// Release offsets φ_i of one run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Phasing {
    /// All tasks release at 0 (the classic critical instant).
    Sync,
    /// φ_i uniform in [0, T_i), in nanoseconds.
    Random,
    /// φ_i a uniform multiple of the grid in [0, T_i): random phasings that
    /// still produce simultaneous events, where worst cases tend to hide.
    Grid(Nanos),
    /// Explicit offsets, one per task (for hand-made and replayed schedules).
    Given(Vec<Nanos>),
}

/// How each job's demand is drawn in [demand_min, demand].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecModel {
    /// Always the worst case.
    Worst,
    /// Always the best case.
    Best,
    /// Uniform integer nanoseconds.
    Uniform,
    /// Best or worst case with equal probability (extremes stress the bounds'
    /// best-case terms).
    Extremes,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimConfig {
    /// Simulated time; events after it are not processed.
    pub horizon: Nanos,
    /// Seeds offsets ([`Phasing::Random`], [`Phasing::Grid`]) and demands.
    pub seed: u64,
    pub phasing: Phasing,
    pub exec: ExecModel,
    /// Keep a [`JobRecord`] of every completed job (memory grows with the horizon).
    pub log_jobs: bool,
}

impl SimConfig {
    /// Synchronous release, worst-case demands, no job log.
    pub fn new(horizon: Nanos) -> SimConfig {
        SimConfig {
            horizon,
            seed: 0,
            phasing: Phasing::Sync,
            exec: ExecModel::Worst,
            log_jobs: false,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SimError {
    /// The task has no fixed positive period, so it cannot be released.
    NoPeriod(String),
    HorizonNotPositive(Nanos),
    /// `Phasing::Given` needs one non-negative offset per task.
    BadOffsets {
        expected: usize,
        found: usize,
    },
    NegativeOffset(String),
    GridNotPositive(Nanos),
    /// A chain names a task index that does not exist.
    BadChain(usize),
    /// A task's best-case demand is negative or above its worst case
    /// (validated specs never have one).
    BadDemand(String),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::NoPeriod(t) => write!(f, "task `{t}` has no fixed positive period"),
            SimError::HorizonNotPositive(h) => write!(f, "horizon must be positive, found {h} ns"),
            SimError::BadOffsets { expected, found } => {
                write!(
                    f,
                    "expected {expected} offsets (one per task), found {found}"
                )
            }
            SimError::NegativeOffset(t) => write!(f, "offset of task `{t}` is negative"),
            SimError::GridNotPositive(g) => {
                write!(f, "phasing grid must be positive, found {g} ns")
            }
            SimError::BadChain(c) => write!(f, "chain {c} names a task that does not exist"),
            SimError::BadDemand(t) => write!(
                f,
                "task `{t}`: its demands must satisfy 0 <= best case <= worst case"
            ),
        }
    }
}

impl std::error::Error for SimError {}

/// The sample carried for one chain position by a job.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Carried {
    pub chain: usize,
    pub pos: usize,
    /// `None` when the producer had not published yet.
    pub sample: Option<u64>,
}

/// One completed job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobRecord {
    pub task: usize,
    /// k of the k-th release, from 0.
    pub index: u64,
    pub release: Nanos,
    pub demand: Nanos,
    /// First got the CPU (read instant).
    pub read: Nanos,
    /// Publish instant.
    pub finish: Nanos,
    /// One entry per chain position the task occupies.
    pub carried: Vec<Carried>,
}

/// The life of one sample at the tail of a chain, as one observation saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Witness {
    pub sample: u64,
    /// The instant the latency is measured from: the head's read of the
    /// sample (from-read quantities), or the head read before it (from-event
    /// quantities: the event came just after that read).
    pub read: Nanos,
    /// First and last tail publishes of the observation. From-event
    /// reaction: the first tail publish carrying `sample` or a newer one.
    pub first: Nanos,
    pub last: Nanos,
}

impl Witness {
    pub fn reaction(&self) -> Nanos {
        self.first - self.read
    }
    pub fn freshness(&self) -> Nanos {
        self.last - self.read
    }
}

/// Every observation of one quantity of one chain.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Observed {
    /// The largest value.
    pub max: Option<Nanos>,
    /// The observation that gave it (the first one, on ties).
    pub witness: Option<Witness>,
    /// Every value, in sample order.
    pub values: Vec<Nanos>,
    /// When each value became known (the tail output that ended it), in
    /// the same order: a time series of the latency.
    pub at: Vec<Nanos>,
}

impl Observed {
    /// A value that ended at `at`.
    fn push(&mut self, value: Nanos, at: Nanos, w: Witness) {
        debug_assert!(value >= 0, "a latency is never negative: {w:?}");
        self.values.push(value);
        self.at.push(at);
        if self.max.is_none_or(|m| value > m) {
            self.max = Some(value);
            self.witness = Some(w);
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChainStats {
    /// Samples created by the head (head reads).
    pub samples: u64,
    /// Samples that reached the tail.
    pub reached: u64,
    /// Samples that reached the tail and whose last output is known.
    pub finalised: u64,
    /// From the head's read to the sample's first tail output: every sample
    /// that reached the tail.
    pub reaction: Observed,
    /// From the head's read to the sample's last tail output: every finalised
    /// sample.
    pub freshness: Observed,
    /// From an event just after a head read to the first tail output
    /// carrying a sample read after it: one per head sample (but the first)
    /// whose such output came before the horizon, whether or not the sample
    /// itself reached the tail.
    pub event_reaction: Observed,
    /// From the head read before a sample's read to the sample's last tail
    /// output: every finalised sample but the first.
    pub event_freshness: Observed,
}

impl ChainStats {
    /// The observations of one metric measured from one anchor.
    pub fn observed(&self, metric: Metric, anchor: Anchor) -> &Observed {
        match (metric, anchor) {
            (Metric::Reaction, Anchor::Read) => &self.reaction,
            (Metric::Freshness, Anchor::Read) => &self.freshness,
            (Metric::Reaction, Anchor::Event) => &self.event_reaction,
            (Metric::Freshness, Anchor::Event) => &self.event_freshness,
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TaskStats {
    pub released: u64,
    pub completed: u64,
    /// Largest finish − release over completed jobs.
    pub max_response: Option<Nanos>,
    /// Completed jobs that finished after their period (the model's
    /// assumptions are broken for them).
    pub late: u64,
    /// Times the server ran out of budget with a job still pending.
    pub exhaustions: u64,
    /// CPU time the task's jobs received.
    pub busy: Nanos,
}

/// A stretch of CPU time given to one job (logged with `log_jobs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// Dense CPU index (CPUs in ascending order of their ids).
    pub cpu: usize,
    pub task: usize,
    pub job: u64,
    pub start: Nanos,
    pub end: Nanos,
    /// Ran in slack at background priority (a sporadic server out of budget).
    pub background: bool,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimResult {
    /// The offsets used (replay a random phasing with [`Phasing::Given`]).
    pub offsets: Vec<Nanos>,
    pub tasks: Vec<TaskStats>,
    /// Indexed like `spec.chains`.
    pub chains: Vec<ChainStats>,
    /// Completed jobs in completion order, when `log_jobs` is set.
    pub jobs: Vec<JobRecord>,
    /// CPU time slices in time order, when `log_jobs` is set.
    pub segments: Vec<Segment>,
    /// Events processed (instants at which something happened).
    pub events: u64,
    /// The simulated span.
    pub horizon: Nanos,
}

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
    run_with_progress(spec, cfg, NoHooks, progress)
}

/// The chain statistics of a log of completed jobs (a real-time executor's,
/// say), measured exactly as the simulator measures its own runs. `jobs`
/// must hold, per task, its jobs from index 0 without gaps, in completion
/// order overall, with `carried` resolved (a head job carries its own index;
/// a job at position k the sample of the value it read from position k−1).
/// Head samples whose job is missing from the log are not counted.
pub fn chains_from_jobs(spec: &Spec, jobs: &[JobRecord]) -> Vec<ChainStats> {
    let mut trackers: Vec<Tracker> = spec.chains.iter().map(|_| Tracker::new()).collect();
    for (tr, ch) in trackers.iter_mut().zip(&spec.chains) {
        let Some(&head) = ch.path.first() else {
            continue;
        };
        let mut reads: Vec<(u64, Nanos)> = jobs
            .iter()
            .filter(|j| j.task == head)
            .map(|j| (j.index, j.read))
            .collect();
        reads.sort_unstable();
        tr.stamps = reads
            .iter()
            .enumerate()
            .take_while(|&(k, &(i, _))| k as u64 == i)
            .map(|(_, &(_, r))| r)
            .collect();
        tr.stats.samples = tr.stamps.len() as u64;
    }
    for j in jobs {
        for c in &j.carried {
            let (Some(ch), Some(sample)) = (spec.chains.get(c.chain), c.sample) else {
                continue;
            };
            let tr = &mut trackers[c.chain];
            if c.pos + 1 == ch.path.len() && (sample as usize) < tr.stamps.len() {
                tr.output(sample, j.finish);
            }
        }
    }
    trackers.into_iter().map(|t| t.stats).collect()
}

/// What the simulator tells the code that runs task bodies: a job reads, a
/// job publishes. Called in simulated-time order.
trait Hooks {
    /// The front job of `job.task` reads at `job.read`.
    fn read(&mut self, job: &rtpipe_body::Job);
    /// The front job of `task` publishes at `t`.
    fn publish(&mut self, task: usize, t: Nanos);
}

/// Timing only.
struct NoHooks;

impl Hooks for NoHooks {
    fn read(&mut self, _job: &rtpipe_body::Job) {}
    fn publish(&mut self, _task: usize, _t: Nanos) {}
}

fn run<H: Hooks>(spec: &Spec, cfg: &SimConfig, hooks: H) -> Result<SimResult, SimError> {
    run_with_progress(spec, cfg, hooks, &mut |_| {})
}

fn run_with_progress<H: Hooks>(
    spec: &Spec,
    cfg: &SimConfig,
    hooks: H,
    progress: &mut dyn FnMut(Nanos),
) -> Result<SimResult, SimError> {
    let mut sim = Sim::new(spec, cfg, hooks)?;
    let mut t = 0;
    loop {
        sim.instant(t);
        if sim.events % PROGRESS_EVENTS == 0 {
            progress(t);
        }
        match sim.next_event(t) {
            Some(next) if next <= cfg.horizon => {
                sim.advance(t, next - t);
                t = next;
            }
            _ => break,
        }
    }
    Ok(sim.finish())
}

/// A position of a chain occupied by a task.
#[derive(Debug, Clone, Copy)]
struct Slot {
    chain: usize,
    pos: usize,
    /// The producer's task and slot index, `None` at the head.
    src: Option<(usize, usize)>,
    tail: bool,
}

#[derive(Debug, Clone, Copy)]
struct Job {
    index: u64,
    release: Nanos,
    demand: Nanos,
    remaining: Nanos,
    read: Option<Nanos>,
}

/// The budget server a task runs on (Section II-B).
#[derive(Debug, Clone)]
enum Budget {
    /// `server = "none"` or background: no enforcement.
    Unlimited,
    /// Main VCPU under RM.
    Sporadic(Sporadic),
    /// I/O VCPU under RM.
    Pibs(Pibs),
    /// Any server under EDF (SCHED_DEADLINE).
    Cbs(Cbs),
}

impl Budget {
    fn capacity(&self, now: Nanos) -> Nanos {
        match self {
            Budget::Unlimited => Nanos::MAX,
            Budget::Sporadic(s) => s.capacity(now),
            Budget::Pibs(p) => p.capacity(now),
            Budget::Cbs(c) => c.capacity(now),
        }
    }
    fn unblock(&mut self, now: Nanos) {
        match self {
            Budget::Unlimited => {}
            Budget::Sporadic(s) => s.unblock(now),
            Budget::Pibs(p) => p.unblock(now),
            Budget::Cbs(c) => c.unblock(now),
        }
    }
    fn block(&mut self, now: Nanos) {
        if let Budget::Sporadic(s) = self {
            s.block(now);
        }
    }
    fn charge(&mut self, now: Nanos, ran: Nanos) {
        // The next event comes no later than the capacity runs out, so a
        // server is never charged more than it had (the servers rely on it).
        assert!(
            (0..=self.capacity(now)).contains(&ran),
            "charged {ran} ns beyond the capacity {} at {now}",
            self.capacity(now)
        );
        match self {
            Budget::Unlimited => {}
            Budget::Sporadic(s) => s.charge(now, ran),
            Budget::Pibs(p) => p.charge(now, ran),
            Budget::Cbs(c) => c.charge(now, ran),
        }
    }
    /// Until when a CBS is throttled (runtime used up).
    fn throttled_until(&self) -> Option<Nanos> {
        match self {
            Budget::Cbs(c) => c.throttled_until,
            _ => None,
        }
    }
    /// When a server without capacity gets some again.
    fn refill_at(&self) -> Option<Nanos> {
        match self {
            Budget::Unlimited => None,
            Budget::Sporadic(s) => Some(s.next_refill()),
            Budget::Pibs(p) => Some(p.next_refill()),
            Budget::Cbs(c) => c.next_refill(),
        }
    }
}

struct TaskSim {
    budget: Budget,
    /// Sporadic servers out of budget may run in slack; others wait.
    slack_when_empty: bool,
    period: Nanos,
    /// 0 for guaranteed tasks, 1 for background ones.
    class: u8,
    /// RM rank (1 = highest); unused under EDF.
    rank: i64,
    /// PIBS: the Main VCPU this I/O VCPU serves; while it has a job pending,
    /// this one runs at its rank (priority inheritance).
    serves: Option<usize>,
    demand_min: Nanos,
    demand: Nanos,
    rng: Rng,
    next_release: Nanos,
    next_index: u64,
    /// Released, unfinished jobs; only the front one may have started.
    queue: VecDeque<Job>,
    slots: Vec<Slot>,
    /// What the front job read, per slot (valid once it has started).
    carried: Vec<Option<u64>>,
    /// The latest published value's samples, per slot.
    published: Vec<Option<u64>>,
    stats: TaskStats,
    /// Dense CPU index.
    cpu: usize,
    /// The I/O VCPUs that serve this task (their priority follows whether
    /// it has a job pending).
    servers: Vec<usize>,
    /// (class, key) in the CPU's contenders as last refreshed; `None` when
    /// the task cannot run (no job, or waiting for budget).
    entry: Option<(u8, Nanos)>,
    /// A job pending and no capacity: when the server gets some back.
    timer: Option<Nanos>,
}

/// Releases every job of `ts` due at or before t.
fn release_jobs(ts: &mut TaskSim, exec: ExecModel, t: Nanos) {
    while ts.next_release <= t {
        let demand = match exec {
            ExecModel::Worst => ts.demand,
            ExecModel::Best => ts.demand_min,
            ExecModel::Uniform => ts.rng.range(ts.demand_min as u64, ts.demand as u64) as Nanos,
            ExecModel::Extremes => {
                if ts.rng.chance(0.5) {
                    ts.demand_min
                } else {
                    ts.demand
                }
            }
        };
        if ts.queue.is_empty() {
            ts.budget.unblock(ts.next_release.max(t));
        }
        ts.queue.push_back(Job {
            index: ts.next_index,
            release: ts.next_release,
            demand,
            remaining: demand,
            read: None,
        });
        ts.stats.released += 1;
        ts.next_index += 1;
        ts.next_release += ts.period;
    }
}

/// Per chain: stamps of the samples and the sample the tail currently outputs.
struct Tracker {
    stamps: Vec<Nanos>,
    /// (sample, first, last) of the newest sample seen at the tail.
    current: Option<(u64, Nanos, Nanos)>,
    /// The smallest sample whose from-event reaction is not known yet:
    /// the first tail output carrying it or a newer one has not happened.
    event_pending: u64,
    stats: ChainStats,
}

impl Tracker {
    fn new() -> Tracker {
        Tracker {
            stamps: Vec::new(),
            current: None,
            // Sample 0 has no head read before it, so no event window.
            event_pending: 1,
            stats: ChainStats::default(),
        }
    }

    fn output(&mut self, sample: u64, t: Nanos) {
        match self.current {
            Some((s, first, _)) if s == sample => self.current = Some((s, first, t)),
            prev => {
                // Samples reach the tail in order: each task's jobs read in
                // order and registers only move forward.
                debug_assert!(!matches!(prev, Some((s, _, _)) if s >= sample));
                if let Some((s, first, last)) = prev {
                    self.finalise(s, first, last);
                }
                self.stats.reached += 1;
                self.current = Some((sample, t, t));
                self.first_output(sample, t);
            }
        }
    }

    /// The first tail output of `sample`, at t: its reaction from the read,
    /// and the from-event reaction of every sample up to it that was still
    /// waiting (samples between the previous one to reach the tail and this
    /// one never reach it; this is the first output that reflects them).
    fn first_output(&mut self, sample: u64, t: Nanos) {
        let stamp = self.stamps[sample as usize];
        let w = Witness {
            sample,
            read: stamp,
            first: t,
            last: t,
        };
        self.stats.reaction.push(t - stamp, t, w);
        for s in self.event_pending..=sample {
            let event = self.stamps[s as usize - 1];
            let w = Witness {
                sample: s,
                read: event,
                first: t,
                last: t,
            };
            self.stats.event_reaction.push(t - event, t, w);
        }
        self.event_pending = self.event_pending.max(sample + 1);
    }

    fn finalise(&mut self, sample: u64, first: Nanos, last: Nanos) {
        let w = Witness {
            sample,
            read: self.stamps[sample as usize],
            first,
            last,
        };
        let st = &mut self.stats;
        st.finalised += 1;
        st.freshness.push(w.freshness(), last, w);
        if sample > 0 {
            let event = Witness {
                read: self.stamps[sample as usize - 1],
                ..w
            };
            st.event_freshness.push(event.freshness(), last, event);
        }
    }
}

struct Sim<H> {
    hooks: H,
    edf: bool,
    exec: ExecModel,
    tasks: Vec<TaskSim>,
    /// Task indices per (dense) CPU (the reference scheduling scans them).
    #[cfg(test)]
    cpu_tasks: Vec<Vec<usize>>,
    /// The task whose front job holds each CPU.
    running: Vec<Option<usize>>,
    chains: Vec<Tracker>,
    offsets: Vec<Nanos>,
    log: Option<Vec<JobRecord>>,
    segments: Option<Vec<Segment>>,
    /// Whether each CPU's running job holds it at background priority.
    in_slack: Vec<bool>,
    last_segment: Vec<Option<usize>>,
    events: u64,
    horizon: Nanos,
    /// Every task's next release, earliest first (one entry per task).
    releases: BinaryHeap<Reverse<(Nanos, usize)>>,
    /// Throttled CBS servers by the end of their throttling (every
    /// throttled server has an entry; stale ones are harmless).
    throttled: BinaryHeap<Reverse<(Nanos, usize)>>,
    /// Refill timers: valid while equal to the task's `timer`.
    timers: BinaryHeap<Reverse<(Nanos, usize)>>,
    /// Per CPU: (class, key, task) of every task that may run; the pick is
    /// the least.
    contenders: Vec<BTreeSet<(u8, Nanos, usize)>>,
}

impl<H: Hooks> Sim<H> {
    fn new(spec: &Spec, cfg: &SimConfig, hooks: H) -> Result<Sim<H>, SimError> {
        if cfg.horizon <= 0 {
            return Err(SimError::HorizonNotPositive(cfg.horizon));
        }
        let n = spec.tasks.len();
        let mut periods = Vec::with_capacity(n);
        for t in &spec.tasks {
            match t.fixed_period() {
                Some(p) if p > 0 => periods.push(p),
                _ => return Err(SimError::NoPeriod(t.name.clone())),
            }
            if !(0 <= t.demand_min() && t.demand_min() <= t.demand()) {
                return Err(SimError::BadDemand(t.name.clone()));
            }
        }
        // Offsets first, then one independent demand stream per task, so the
        // demands of a task do not depend on the schedule.
        let mut master = Rng::new(cfg.seed);
        let offsets: Vec<Nanos> = match &cfg.phasing {
            Phasing::Sync => vec![0; n],
            Phasing::Random => periods
                .iter()
                .map(|&p| master.range(0, p as u64 - 1) as Nanos)
                .collect(),
            Phasing::Grid(g) => {
                if *g <= 0 {
                    return Err(SimError::GridNotPositive(*g));
                }
                periods
                    .iter()
                    .map(|&p| master.range(0, ((p - 1) / g) as u64) as Nanos * g)
                    .collect()
            }
            Phasing::Given(v) => {
                if v.len() != n {
                    return Err(SimError::BadOffsets {
                        expected: n,
                        found: v.len(),
                    });
                }
                if let Some(i) = v.iter().position(|&o| o < 0) {
                    return Err(SimError::NegativeOffset(spec.tasks[i].name.clone()));
                }
                v.clone()
            }
        };
        let ranks = rm_priorities(spec);
        let mut cpu_ids: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
        cpu_ids.sort_unstable();
        cpu_ids.dedup();
        let mut cpu_tasks = vec![Vec::new(); cpu_ids.len()];
        let mut tasks = Vec::with_capacity(n);
        for (i, t) in spec.tasks.iter().enumerate() {
            let cpu = cpu_ids.binary_search(&t.cpu).unwrap_or(0);
            cpu_tasks[cpu].push(i);
            let (c, p) = (t.budget(), periods[i]);
            let budget = match (spec.scheduler, t.server) {
                (_, Server::None | Server::Background) => Budget::Unlimited,
                (Scheduler::Edf, _) => Budget::Cbs(Cbs::new(c, p)),
                (Scheduler::Rm, Server::Main) => Budget::Sporadic(Sporadic::new(c, p, 0)),
                (Scheduler::Rm, Server::Io) => Budget::Pibs(Pibs::new(c, p)),
            };
            tasks.push(TaskSim {
                slack_when_empty: matches!(budget, Budget::Sporadic(_)),
                budget,
                period: periods[i],
                class: u8::from(t.server == Server::Background),
                rank: ranks[i].map_or(i as i64, |r| r as i64),
                serves: if spec.scheduler == Scheduler::Rm {
                    t.serves
                } else {
                    None
                },
                demand_min: t.demand_min(),
                demand: t.demand(),
                rng: Rng::new(master.next_u64()),
                next_release: offsets[i],
                next_index: 0,
                queue: VecDeque::new(),
                slots: Vec::new(),
                carried: Vec::new(),
                published: Vec::new(),
                stats: TaskStats::default(),
                cpu,
                servers: Vec::new(),
                entry: None,
                timer: None,
            });
        }
        // Slots: the chain positions each task occupies, linked to the slot
        // of the previous position (created just before, in path order).
        for (c, ch) in spec.chains.iter().enumerate() {
            if ch.path.iter().any(|&i| i >= n) {
                return Err(SimError::BadChain(c));
            }
            let mut prev: Option<(usize, usize)> = None;
            for (pos, &i) in ch.path.iter().enumerate() {
                let ts = &mut tasks[i];
                ts.slots.push(Slot {
                    chain: c,
                    pos,
                    src: prev,
                    tail: pos + 1 == ch.path.len(),
                });
                ts.carried.push(None);
                ts.published.push(None);
                prev = Some((i, ts.slots.len() - 1));
            }
        }
        for i in 0..n {
            if let Some(m) = tasks[i].serves {
                // An index out of range is left to `standing`, which
                // panics on it as the scan did.
                if let Some(ms) = tasks.get_mut(m) {
                    ms.servers.push(i);
                }
            }
        }
        let releases = tasks
            .iter()
            .enumerate()
            .map(|(i, ts)| Reverse((ts.next_release, i)))
            .collect();
        let n_cpus = cpu_tasks.len();
        let chains = spec.chains.iter().map(|_| Tracker::new()).collect();
        Ok(Sim {
            hooks,
            edf: spec.scheduler == Scheduler::Edf,
            exec: cfg.exec,
            tasks,
            running: vec![None; n_cpus],
            #[cfg(test)]
            cpu_tasks,
            chains,
            offsets,
            log: cfg.log_jobs.then(Vec::new),
            segments: cfg.log_jobs.then(Vec::new),
            in_slack: vec![false; n_cpus],
            last_segment: vec![None; n_cpus],
            events: 0,
            horizon: cfg.horizon,
            releases,
            throttled: BinaryHeap::new(),
            timers: BinaryHeap::new(),
            contenders: vec![BTreeSet::new(); n_cpus],
        })
    }

    /// Everything that happens at instant t, in the tie order of the model.
    /// Repeats when a job of zero demand starts, so it reads before it
    /// publishes (at the same instant).
    ///
    /// Only the tasks something happens to are visited: throttled CBS
    /// servers whose throttling ends (a heap), tasks that release (a heap),
    /// refill timers that fire (a heap); each CPU's pick is the first of its
    /// contenders (an ordered set kept up to date by [`Sim::refresh`]).
    fn instant(&mut self, t: Nanos) {
        self.events += 1;
        // CBS replenishment timers (every throttled server has an entry).
        while let Some(&Reverse((until, i))) = self.throttled.peek() {
            if until > t {
                break;
            }
            self.throttled.pop();
            if let Budget::Cbs(c) = &mut self.tasks[i].budget {
                c.replenish(t);
            }
            self.refresh(i, t);
        }
        loop {
            for cpu in 0..self.running.len() {
                if let Some(i) = self.running[cpu] {
                    if self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.remaining == 0)
                    {
                        self.complete(i, t);
                        self.running[cpu] = None;
                        self.refresh(i, t);
                        if self.tasks[i].queue.is_empty() {
                            self.refresh_servers(i, t);
                        }
                    }
                }
            }
            self.release(t);
            // Refill timers: capacity comes back to a waiting server.
            while let Some(&Reverse((at, i))) = self.timers.peek() {
                if at > t {
                    break;
                }
                self.timers.pop();
                if self.tasks[i].timer == Some(at) {
                    self.tasks[i].timer = None;
                    self.refresh(i, t);
                }
            }
            // Debug builds: the full check costs O(tasks) per pick, which
            // would make large systems quadratic again; skip it beyond 512.
            #[cfg(debug_assertions)]
            if self.tasks.len() <= 512 {
                self.check(t);
            }
            for cpu in 0..self.running.len() {
                let picked = self.pick(cpu);
                self.running[cpu] = picked.map(|(i, _)| i);
                self.in_slack[cpu] = picked.is_some_and(|(_, slack)| slack);
            }
            let mut again = false;
            for cpu in 0..self.running.len() {
                if let Some(i) = self.running[cpu] {
                    if self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.read.is_none())
                    {
                        self.read(i, t);
                    }
                    again |= self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.remaining == 0);
                }
            }
            if !again {
                break;
            }
        }
    }

    /// Releases every job due at or before t.
    fn release(&mut self, t: Nanos) {
        let exec = self.exec;
        loop {
            let i = {
                let Some(mut top) = self.releases.peek_mut() else {
                    return;
                };
                let Reverse((due, i)) = *top;
                if due > t {
                    return;
                }
                let ts = &mut self.tasks[i];
                debug_assert_eq!(due, ts.next_release, "stale release entry of task {i}");
                let was_idle = ts.queue.is_empty();
                release_jobs(ts, exec, t);
                *top = Reverse((ts.next_release, i));
                if !was_idle {
                    // Queued behind the front job: nothing the pick sees changed.
                    continue;
                }
                i
            };
            self.refresh(i, t);
            self.refresh_servers(i, t);
        }
    }

    /// The ready task of highest priority on a CPU, and whether it runs in
    /// slack (a sporadic server out of budget drops to background priority):
    /// the least (class, key, task) among the CPU's contenders.
    fn pick(&self, cpu: usize) -> Option<(usize, bool)> {
        self.contenders[cpu]
            .first()
            .map(|&(class, _, i)| (i, class == 2))
    }

    /// Where task i stands at t, from scratch: its (class, priority key) when
    /// it may run (a job pending, and budget or slack to run it in), and when
    /// its server gets capacity back if it waits for it with a job pending.
    fn standing(&self, i: usize, t: Nanos) -> (Option<(u8, Nanos)>, Option<Nanos>) {
        let ts = &self.tasks[i];
        let Some(job) = ts.queue.front() else {
            return (None, None);
        };
        let has_budget = ts.budget.capacity(t) > 0;
        let timer = if has_budget {
            None
        } else {
            ts.budget.refill_at().filter(|&r| r > t)
        };
        let class = match (ts.class, has_budget) {
            (0, true) => 0,
            (0, false) if ts.slack_when_empty => 2,
            (0, false) => return (None, timer),
            _ => 1,
        };
        let key = match (&ts.budget, self.edf) {
            (Budget::Cbs(c), _) => c.deadline,
            (_, true) => job.release + ts.period,
            (_, false) => match ts.serves {
                // PIBS inheritance: the better (smaller) rank of the server
                // and the Main VCPU it serves while that one has a job.
                Some(m) if !self.tasks[m].queue.is_empty() => ts.rank.min(self.tasks[m].rank),
                _ => ts.rank,
            },
        };
        (Some((class, key)), timer)
    }

    /// Task i's queue, budget or inheritance changed at t: update its place
    /// among its CPU's contenders and its refill timer.
    ///
    /// Between two refreshes a task's standing does not change: capacity
    /// only grows with time, and only at the refill instant, where the timer
    /// refreshes it.
    fn refresh(&mut self, i: usize, t: Nanos) {
        let (entry, timer) = self.standing(i, t);
        let ts = &mut self.tasks[i];
        if ts.entry != entry {
            let set = &mut self.contenders[ts.cpu];
            if let Some((class, key)) = ts.entry {
                let was_there = set.remove(&(class, key, i));
                debug_assert!(was_there, "task {i} missing from its contenders");
            }
            if let Some((class, key)) = entry {
                set.insert((class, key, i));
            }
            ts.entry = entry;
        }
        if ts.timer != timer {
            ts.timer = timer;
            if let Some(at) = timer {
                self.timers.push(Reverse((at, i)));
            }
        }
    }

    /// Task m's queue became empty or non-empty: the I/O VCPUs serving it
    /// inherit its priority or lose it.
    fn refresh_servers(&mut self, m: usize, t: Nanos) {
        for k in 0..self.tasks[m].servers.len() {
            let s = self.tasks[m].servers[k];
            self.refresh(s, t);
        }
    }

    /// Debug builds: the incremental state is what the scans it replaces
    /// would compute at t (O(tasks), once per pick).
    #[cfg(debug_assertions)]
    fn check(&self, t: Nanos) {
        let mut contenders = vec![BTreeSet::new(); self.contenders.len()];
        let timers: BTreeSet<_> = self.timers.iter().map(|&Reverse(e)| e).collect();
        let throttled: BTreeSet<_> = self.throttled.iter().map(|&Reverse(e)| e).collect();
        for (i, ts) in self.tasks.iter().enumerate() {
            let (entry, timer) = self.standing(i, t);
            assert_eq!(ts.entry, entry, "task {i}: stale contender entry at {t}");
            assert_eq!(ts.timer, timer, "task {i}: stale refill timer at {t}");
            assert!(entry.is_none() || !ts.queue.is_empty());
            if let Some((class, key)) = entry {
                contenders[ts.cpu].insert((class, key, i));
            }
            if let Some(at) = timer {
                assert!(timers.contains(&(at, i)), "task {i}: refill timer lost");
            }
            assert!(ts.next_release > t, "task {i}: release at {t} missed");
            if let Budget::Cbs(c) = &ts.budget {
                if let Some(until) = c.throttled_until {
                    assert!(until > t, "task {i}: CBS not replenished at {t}");
                    assert!(throttled.contains(&(until, i)), "task {i}: throttling lost");
                }
            }
        }
        assert_eq!(contenders, self.contenders, "contender sets at {t}");
        assert_eq!(self.releases.len(), self.tasks.len());
        assert!(self
            .releases
            .iter()
            .all(|&Reverse((at, i))| at == self.tasks[i].next_release));
    }

    /// The front job of task i first gets the CPU: copy the producers' values.
    fn read(&mut self, i: usize, t: Nanos) {
        for s in 0..self.tasks[i].slots.len() {
            let slot = self.tasks[i].slots[s];
            let v = match slot.src {
                None => {
                    // Sample ids count head reads per chain; jobs of a task
                    // read in release order, so the id is the job index.
                    let tr = &mut self.chains[slot.chain];
                    tr.stamps.push(t);
                    tr.stats.samples += 1;
                    Some(tr.stamps.len() as u64 - 1)
                }
                Some((p, ps)) => self.tasks[p].published[ps],
            };
            self.tasks[i].carried[s] = v;
        }
        let Some(job) = self.tasks[i].queue.front_mut() else {
            unreachable!("task {i} reads without a pending job");
        };
        job.read = Some(t);
        let job = rtpipe_body::Job {
            task: i,
            index: job.index,
            release: job.release,
            read: t,
        };
        self.hooks.read(&job);
    }

    /// The front job of task i completes at t: publish.
    fn complete(&mut self, i: usize, t: Nanos) {
        let ts = &mut self.tasks[i];
        let Some(job) = ts.queue.pop_front() else {
            return;
        };
        debug_assert!(
            job.read.is_some(),
            "task {i} publishes a job that never read"
        );
        self.hooks.publish(i, t);
        let response = t - job.release;
        ts.stats.completed += 1;
        ts.stats.max_response = Some(ts.stats.max_response.map_or(response, |m| m.max(response)));
        if response > ts.period {
            ts.stats.late += 1;
        }
        ts.published.clone_from(&ts.carried);
        for (slot, v) in ts.slots.iter().zip(&ts.carried) {
            if let (true, Some(sample)) = (slot.tail, v) {
                self.chains[slot.chain].output(*sample, t);
            }
        }
        if let Some(log) = &mut self.log {
            log.push(JobRecord {
                task: i,
                index: job.index,
                release: job.release,
                demand: job.demand,
                read: job.read.unwrap_or(t),
                finish: t,
                carried: ts
                    .slots
                    .iter()
                    .zip(&ts.carried)
                    .map(|(s, &sample)| Carried {
                        chain: s.chain,
                        pos: s.pos,
                        sample,
                    })
                    .collect(),
            });
        }
        ts.carried.iter_mut().for_each(|v| *v = None);
        if ts.queue.is_empty() {
            ts.budget.block(t);
        }
    }

    /// The next instant something happens after t: a release, a completion,
    /// a budget running out, or a budget coming back to a waiting server.
    fn next_event(&mut self, t: Nanos) -> Option<Nanos> {
        let release = self.releases.peek().map(|&Reverse((at, _))| at);
        // Drop the refill timers that no longer hold.
        let refill = loop {
            match self.timers.peek() {
                Some(&Reverse((at, i))) if self.tasks[i].timer != Some(at) => {
                    self.timers.pop();
                }
                top => break top.map(|&Reverse((at, _))| at),
            }
        };
        debug_assert!(refill.is_none_or(|r| r > t));
        let running = self.running.iter().enumerate().filter_map(|(cpu, r)| {
            let ts = &self.tasks[(*r)?];
            let job = ts.queue.front()?;
            let mut next = t + job.remaining;
            if !self.in_slack[cpu] {
                let cap = ts.budget.capacity(t);
                if cap < job.remaining {
                    next = t + cap;
                }
            }
            Some(next)
        });
        // The earliest of the three kinds of event.
        release.into_iter().chain(running).chain(refill).min()
    }

    /// Runs every CPU's chosen job from t for dt and charges its server.
    fn advance(&mut self, t: Nanos, dt: Nanos) {
        for cpu in 0..self.running.len() {
            let Some(i) = self.running[cpu] else { continue };
            let slack = self.in_slack[cpu];
            let ts = &mut self.tasks[i];
            let Some(job) = ts.queue.front_mut() else {
                continue;
            };
            job.remaining -= dt;
            let (index, remaining) = (job.index, job.remaining);
            ts.stats.busy += dt;
            if !slack {
                let throttled = ts.budget.throttled_until();
                ts.budget.charge(t + dt, dt);
                if remaining > 0 && ts.budget.capacity(t + dt) == 0 {
                    ts.stats.exhaustions += 1;
                }
                if let Some(until) = ts.budget.throttled_until() {
                    if throttled != Some(until) {
                        self.throttled.push(Reverse((until, i)));
                    }
                }
                self.refresh(i, t + dt);
            }
            if let Some(seg) = &mut self.segments {
                // Extend this CPU's last slice when the same job just goes on.
                let last = self.last_segment[cpu].and_then(|k| seg.get_mut(k));
                match last {
                    Some(s)
                        if s.task == i && s.job == index && s.end == t && s.background == slack =>
                    {
                        s.end = t + dt
                    }
                    _ => {
                        self.last_segment[cpu] = Some(seg.len());
                        seg.push(Segment {
                            cpu,
                            task: i,
                            job: index,
                            start: t,
                            end: t + dt,
                            background: slack,
                        });
                    }
                }
            }
        }
    }

    fn finish(self) -> SimResult {
        SimResult {
            offsets: self.offsets,
            tasks: self.tasks.into_iter().map(|t| t.stats).collect(),
            chains: self.chains.into_iter().map(|c| c.stats).collect(),
            jobs: self.log.unwrap_or_default(),
            segments: self.segments.unwrap_or_default(),
            events: self.events,
            horizon: self.horizon,
        }
    }
}

#[cfg(test)]
mod reference;
#[cfg(test)]
mod tests;
