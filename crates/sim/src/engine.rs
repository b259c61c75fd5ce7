//! The event loop: releases, the servers' budgets, each CPU's choice of
//! job, reads and publishes at the instants the model says.

use crate::release_heap::ReleaseHeap;
use crate::server::{Cbs, Pibs, Sporadic};
use crate::Rng;
use crate::*;
use rtpipe_joblog::{BadChain, JobRecord, Provenance, Segment, SimResult, TaskStats};
use rtpipe_model::policy::{ranks, Budget as Kind, Preemption};
use rtpipe_model::{Communication, Nanos, Server, Spec};
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap, VecDeque};

mod events;
mod setup;
use setup::{link_servers, mark_sides, offsets_of, periods_of, release_heap, task_sims, Sides};

/// What the simulator tells the code that runs task bodies: a job reads, a
/// job publishes. Called in simulated-time order, at the instants of the
/// task's semantics: its start and completion (implicit), or its release
/// and its period's end (LET, `let_comm.rs`).
pub(crate) trait Hooks {
    /// The front job of `job.task` reads at `job.read`.
    fn read(&mut self, job: &rtpipe_body::Job);
    /// The front job of `task` publishes at `t`.
    fn publish(&mut self, task: usize, t: Nanos);
}

/// Timing only.
pub(crate) struct NoHooks;

impl Hooks for NoHooks {
    fn read(&mut self, _job: &rtpipe_body::Job) {}
    fn publish(&mut self, _task: usize, _t: Nanos) {}
}

pub(crate) fn run<H: Hooks>(spec: &Spec, cfg: &SimConfig, hooks: H) -> Result<SimResult, SimError> {
    run_with_progress(spec, cfg, hooks, &mut |_| {}, None)
}

/// A run that calls `progress` every [`PROGRESS_EVENTS`] events and, with
/// `rows`, hands every chain's sample rows on as they complete.
pub(crate) fn run_with_progress<H: Hooks>(
    spec: &Spec,
    cfg: &SimConfig,
    hooks: H,
    progress: &mut dyn FnMut(Nanos),
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<SimResult, SimError> {
    let mut going_on = |t| {
        progress(t);
        true
    };
    match run_until(spec, cfg, hooks, &mut going_on, rows)? {
        Some(result) => Ok(result),
        None => unreachable!("a progress that always goes on never stops the run"),
    }
}

/// The event loop: `progress` is called every [`PROGRESS_EVENTS`] events
/// with the simulated time reached and ends the run (`None`) by returning
/// false (the caller's cancellation check).
pub(crate) fn run_until<H: Hooks>(
    spec: &Spec,
    cfg: &SimConfig,
    hooks: H,
    progress: &mut dyn FnMut(Nanos) -> bool,
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<Option<SimResult>, SimError> {
    let mut sim = Sim::new(spec, cfg, hooks)?;
    if let Some(sink) = rows {
        sim.prov.stream_rows(sink);
    }
    let Some(t) = event_loop(&mut sim, cfg.horizon, progress) else {
        return Ok(None);
    };
    sim.sync_all(t);
    if let Some(seg) = &mut sim.segments {
        // The order the every-CPU scans recorded them in.
        seg.sort_by_key(|s| (s.start, s.cpu));
    }
    Ok(Some(sim.finish()))
}

/// Every instant up to the horizon; the last instant reached, or `None`
/// when `progress` ended the run. Never inlined, so that a profiler can
/// count the event loop alone (`callgrind --toggle-collect`, in
/// docs/guide/simulate.md), without the set-up and the report.
#[inline(never)]
fn event_loop<H: Hooks>(
    sim: &mut Sim<H>,
    horizon: Nanos,
    progress: &mut dyn FnMut(Nanos) -> bool,
) -> Option<Nanos> {
    let mut t = 0;
    loop {
        sim.instant(t);
        if sim.events.is_multiple_of(PROGRESS_EVENTS) && !progress(t) {
            return None;
        }
        match sim.next_event(t) {
            Some(next) if next <= horizon => t = next,
            _ => return Some(t),
        }
    }
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Job {
    pub(crate) index: u64,
    /// Its nominal release (response times count from it).
    pub(crate) release: Nanos,
    /// When it entered the queue (its actual release, up to the jitter
    /// after the nominal one): a thread runs its jobs in this order.
    pub(crate) queued: Nanos,
    pub(crate) demand: Nanos,
    pub(crate) remaining: Nanos,
    pub(crate) read: Option<Nanos>,
    /// A data-triggered job: the publication that released it.
    pub(crate) trigger: Option<rtpipe_joblog::Trigger>,
}

/// The budget server a task runs on (Section II-B).
#[derive(Debug, Clone)]
pub(crate) enum Budget {
    /// `server = "none"` or background: no enforcement.
    Unlimited,
    /// Main VCPU under RM.
    Sporadic(Box<Sporadic>),
    /// I/O VCPU under RM.
    Pibs(Box<Pibs>),
    /// Any server under EDF (SCHED_DEADLINE).
    Cbs(Box<Cbs>),
}

impl Budget {
    pub(crate) fn capacity(&self, now: Nanos) -> Nanos {
        match self {
            Budget::Unlimited => Nanos::MAX,
            Budget::Sporadic(s) => s.capacity(now),
            Budget::Pibs(p) => p.capacity(now),
            Budget::Cbs(c) => c.capacity(now),
        }
    }
    pub(crate) fn unblock(&mut self, now: Nanos) {
        match self {
            Budget::Unlimited => {}
            Budget::Sporadic(s) => s.unblock(now),
            Budget::Pibs(p) => p.unblock(now),
            Budget::Cbs(c) => c.unblock(now),
        }
    }
    pub(crate) fn block(&mut self, now: Nanos) {
        if let Budget::Sporadic(s) = self {
            s.block(now);
        }
    }
    pub(crate) fn charge(&mut self, now: Nanos, ran: Nanos) {
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
    pub(crate) fn throttled_until(&self) -> Option<Nanos> {
        match self {
            Budget::Cbs(c) => c.throttled_until,
            _ => None,
        }
    }
    /// When a server without capacity gets some again.
    pub(crate) fn refill_at(&self) -> Option<Nanos> {
        match self {
            Budget::Unlimited => None,
            Budget::Sporadic(s) => Some(s.next_refill()),
            Budget::Pibs(p) => Some(p.next_refill()),
            Budget::Cbs(c) => c.next_refill(),
        }
    }
}

/// A released job as LET communicates it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LetJob {
    pub(crate) task: usize,
    pub(crate) index: u64,
    pub(crate) release: Nanos,
    pub(crate) demand: Nanos,
    pub(crate) period: Nanos,
}

/// A task's simulation state, laid out for the event loop: what an event
/// of a plain periodic task reads or writes fills the first four cache
/// lines (`tests::task_state_fits_four_cache_lines`), in the order a
/// release, a pick and a completion use it, and the rest (what only
/// servers, jitter or inheritance need) comes after. In a system of
/// thousands of tasks each line a task's event touches is a cache miss
/// (docs/guide/simulate.md).
#[repr(C, align(64))]
pub(crate) struct TaskSim {
    // Line 1: a release.
    pub(crate) next_release: Nanos,
    /// The nominal release of the next job (`next_release` is its actual
    /// one, up to J later).
    pub(crate) next_nominal: Nanos,
    pub(crate) period: Nanos,
    /// J: each job is released in [nominal, nominal + J].
    pub(crate) jitter: Nanos,
    pub(crate) demand_min: Nanos,
    pub(crate) demand: Nanos,
    pub(crate) rng: Rng,
    pub(crate) next_index: u64,
    // Line 2: its jobs and its standing among its CPU's contenders.
    /// Released, unfinished jobs; only the front one may have started.
    pub(crate) queue: VecDeque<Job>,
    /// (class, key) in the CPU's contenders as last refreshed; `None` when
    /// the task cannot run (no job, or waiting for budget).
    pub(crate) entry: Option<(u8, Nanos)>,
    /// PIBS: the Main VCPU this I/O VCPU serves; while it has a job pending,
    /// this one runs at its rank (priority inheritance).
    pub(crate) serves: Option<u32>,
    // Line 3: what a release and a completion count.
    pub(crate) stats: TaskStats,
    // Line 4: its priority, its server and where its events go.
    /// The budget server (its state boxed: 16 bytes here, whatever the
    /// server).
    pub(crate) budget: Budget,
    /// RM rank (1 = highest); unused under EDF.
    pub(crate) rank: i64,
    /// D: a job finishing later than this after its nominal release is late.
    pub(crate) deadline: Nanos,
    /// A job pending and no capacity: when the server gets some back.
    pub(crate) timer: Option<Nanos>,
    /// Dense CPU index (32 bits, so that line 4 holds what it must).
    pub(crate) cpu: u32,
    /// Which per-task side tables its events must visit.
    pub(crate) sides: Sides,
    /// 0 for guaranteed tasks, 1 for background ones.
    pub(crate) class: u8,
    /// A release merges into a queued, unstarted job (`events.rs`).
    pub(crate) merges: bool,
    // Then what only some tasks' events read.
    /// Sporadic servers out of budget may run in slack; others wait.
    pub(crate) slack_when_empty: bool,
    /// Where in the jitter window (drawn from `rng` when J > 0).
    pub(crate) jitter_model: Jitter,
    /// The I/O VCPUs that serve this task (their priority follows whether
    /// it has a job pending; `Sides::served`).
    pub(crate) servers: Vec<usize>,
}

/// The demand of the next job of `ts`, as `exec` says (from its stream).
pub(crate) fn draw_demand(ts: &mut TaskSim, exec: ExecModel) -> Nanos {
    match exec {
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
    }
}

/// Releases every job of `ts` due at or before t (a release merges into a
/// queued, unstarted job when the task merges: `events.rs`).
pub(crate) fn release_jobs(ts: &mut TaskSim, exec: ExecModel, t: Nanos) {
    while ts.next_release <= t {
        if ts.merges && ts.queue.back().is_some_and(|j| j.read.is_none()) {
            ts.stats.merged += 1;
            ts.next_nominal += ts.period;
            ts.next_release = ts.next_nominal + jitter_draw(ts);
            continue;
        }
        let demand = draw_demand(ts, exec);
        if ts.queue.is_empty() {
            ts.budget.unblock(ts.next_release.max(t));
        }
        // A job's release is its nominal instant: response times and
        // deadlines count from there (R = J + w); it enters the queue at
        // its actual one, `next_release`.
        ts.queue.push_back(Job {
            index: ts.next_index,
            release: ts.next_nominal,
            queued: ts.next_release,
            demand,
            remaining: demand,
            read: None,
            trigger: None,
        });
        ts.stats.released += 1;
        ts.next_index += 1;
        ts.next_nominal += ts.period;
        ts.next_release = ts.next_nominal + jitter_draw(ts);
    }
}

/// How late after its nominal release the next job of `ts` comes: 0
/// without jitter (and no draw, so jitter-free runs are as they were).
fn jitter_draw(ts: &mut TaskSim) -> Nanos {
    if ts.jitter == 0 {
        return 0;
    }
    match ts.jitter_model {
        Jitter::Uniform => ts.rng.range(0, ts.jitter as u64) as Nanos,
        Jitter::Extremes => {
            if ts.rng.chance(0.5) {
                ts.jitter
            } else {
                0
            }
        }
        Jitter::Latest => ts.jitter,
        Jitter::None => 0,
        // Even periods late, odd ones on time (the next nominal release is
        // already set when this is drawn).
        Jitter::Squeezed => match ts.next_nominal.div_euclid(ts.period) % 2 {
            0 => ts.jitter,
            _ => 0,
        },
    }
}

pub(crate) struct Sim<H> {
    pub(crate) hooks: H,
    pub(crate) edf: bool,
    pub(crate) exec: ExecModel,
    pub(crate) tasks: Vec<TaskSim>,
    /// Task indices per (dense) CPU (the reference scheduling scans them).
    #[cfg(test)]
    pub(crate) cpu_tasks: Vec<Vec<usize>>,
    /// The task whose front job holds each CPU.
    pub(crate) running: Vec<Option<usize>>,
    /// Which sample each job carries, and the chains' figures.
    pub(crate) prov: Provenance,
    pub(crate) offsets: Vec<Nanos>,
    pub(crate) log: Option<Vec<JobRecord>>,
    pub(crate) segments: Option<Vec<Segment>>,
    /// Whether each CPU's running job holds it at background priority.
    pub(crate) in_slack: Vec<bool>,
    pub(crate) last_segment: Vec<Option<usize>>,
    pub(crate) events: u64,
    pub(crate) horizon: Nanos,
    /// Every task's next release, earliest first (one entry per task).
    pub(crate) releases: ReleaseHeap,
    /// Throttled CBS servers by the end of their throttling (every
    /// throttled server has an entry; stale ones are harmless).
    pub(crate) throttled: BinaryHeap<Reverse<(Nanos, usize)>>,
    /// Refill timers: valid while equal to the task's `timer`.
    pub(crate) timers: BinaryHeap<Reverse<(Nanos, usize)>>,
    /// Per CPU: (class, key, task) of every task that may run; the pick is
    /// the least.
    pub(crate) contenders: Vec<BTreeSet<(u8, Nanos, usize)>>,
    /// Per CPU: the instant its running job has been charged up to
    /// (`cpus.rs`).
    pub(crate) since: Vec<Nanos>,
    /// Per CPU: its next event (a completion or the capacity running out).
    pub(crate) cpu_event: Vec<Option<Nanos>>,
    /// The CPUs' events, earliest first (the same as `cpu_event`).
    pub(crate) cpu_events: crate::cpu_events::CpuEvents,
    /// The CPUs to pick for again at this instant (`is_dirty` per CPU).
    pub(crate) dirty: Vec<usize>,
    pub(crate) is_dirty: Vec<bool>,
    /// Scratch lists of an instant: the CPUs due, the CPUs picked for.
    pub(crate) scratch: (Vec<usize>, Vec<usize>),
    /// Under LET, per task: the job that read at its release and publishes
    /// at the end of its period.
    pub(crate) let_open: Vec<Option<LetJob>>,
    /// Critical sections and the resources' holders (`locks.rs`).
    pub(crate) locks: Locks,
    /// Release handlers, replenishments and context switches
    /// (`overheads.rs`).
    pub(crate) ovh: crate::overheads::Overheads,
    /// Threads, triggers and merging (`events.rs`).
    pub(crate) event_model: events::Events,
}

impl<H: Hooks> Sim<H> {
    pub(crate) fn new(spec: &Spec, cfg: &SimConfig, hooks: H) -> Result<Sim<H>, SimError> {
        if cfg.horizon <= 0 {
            return Err(SimError::HorizonNotPositive(cfg.horizon));
        }
        let periods = periods_of(spec)?;
        // Offsets first, then one independent demand stream per task, so the
        // demands of a task do not depend on the schedule.
        let mut master = Rng::new(cfg.seed);
        let offsets = offsets_of(spec, &cfg.phasing, &periods, &mut master)?;
        let (mut tasks, cpu_tasks) = task_sims(spec, &periods, &offsets, cfg.jitter, &mut master);
        let prov = Provenance::new(spec).map_err(|BadChain(c)| SimError::BadChain(c))?;
        link_servers(&mut tasks);
        let locks = Locks::new(spec);
        let mut cpu_ids: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
        cpu_ids.sort_unstable();
        cpu_ids.dedup();
        let ovh = crate::overheads::Overheads::new(spec, &cpu_ids);
        let event_model = events::Events::new(spec);
        mark_sides(spec, &mut tasks, &prov, &locks, &ovh, &event_model);
        let releases = release_heap(&tasks);
        let n_cpus = cpu_tasks.len();
        if locks.any()
            && !spec
                .policy()
                .resource_protocols
                .contains(&spec.resource_protocol)
        {
            return Err(SimError::Resources(spec.scheduler.name()));
        }
        Ok(Sim {
            hooks,
            edf: spec.policy().preemption == Preemption::EarliestDeadline,
            exec: cfg.exec,
            tasks,
            running: vec![None; n_cpus],
            #[cfg(test)]
            cpu_tasks,
            prov,
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
            since: vec![0; n_cpus],
            cpu_event: vec![None; n_cpus],
            cpu_events: crate::cpu_events::CpuEvents::new(n_cpus),
            dirty: Vec::new(),
            is_dirty: vec![false; n_cpus],
            scratch: (Vec::new(), Vec::new()),
            let_open: vec![None; spec.tasks.len()],
            locks,
            ovh,
            event_model,
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
    pub(crate) fn instant(&mut self, t: Nanos) {
        self.events += 1;
        // Scratch lists kept across instants (no allocation per event).
        let (mut due, mut picked) = std::mem::take(&mut self.scratch);
        self.pop_due(t, &mut due);
        self.replenish_throttled(t);
        loop {
            self.complete_finished(t, &due);
            self.release(t);
            self.fire_timers(t);
            // Debug builds: the full check costs O(tasks) per pick, which
            // would make large systems quadratic again; skip it beyond 512.
            #[cfg(debug_assertions)]
            if self.tasks.len() <= 512 {
                self.check(t);
            }
            self.pick_marked(t, &mut picked);
            if self.locks.any() && self.lock_step(t) {
                continue;
            }
            if !self.read_started(t, &picked) {
                break;
            }
            self.pop_due(t, &mut due);
        }
        self.scratch = (due, picked);
    }

    /// CBS replenishment timers due at t (every throttled server has an
    /// entry).
    fn replenish_throttled(&mut self, t: Nanos) {
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
    }

    /// Running jobs with nothing left to do complete (and publish) at t
    /// (only those on the CPUs `due` at t can).
    fn complete_finished(&mut self, t: Nanos, due: &[usize]) {
        for &cpu in due {
            if let Some(i) = self.running[cpu] {
                if self.ovh.lead(cpu) == 0
                    && self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.remaining == 0 && j.read.is_some())
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
    }

    /// Refill timers due at t: capacity comes back to a waiting server.
    fn fire_timers(&mut self, t: Nanos) {
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
    }

    /// Picked jobs that start now read their inputs; true when one of them
    /// has zero demand (it completes at this same instant: go round again).
    fn read_started(&mut self, t: Nanos, picked: &[usize]) -> bool {
        let mut again = false;
        for &cpu in picked {
            // A job reads when its own work starts, after the CPU's
            // overheads (its event comes then).
            if self.ovh.lead(cpu) > 0 {
                continue;
            }
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
        again
    }

    /// Releases every job due at or before t; under LET, the period ends
    /// and the releases communicate (`let_comm.rs`).
    pub(crate) fn release(&mut self, t: Nanos) {
        let mut released = Vec::new();
        self.release_due(t, &mut released);
        if !released.is_empty() {
            self.let_boundary(released);
        }
    }

    /// Releases every job due at or before t; under LET, lists them.
    fn release_due(&mut self, t: Nanos, released: &mut Vec<LetJob>) {
        let exec = self.exec;
        loop {
            let i = {
                let Some((due, i)) = self.releases.peek() else {
                    return;
                };
                if due > t {
                    return;
                }
                let i = i as usize;
                let ts = &mut self.tasks[i];
                debug_assert_eq!(due, ts.next_release, "stale release entry of task {i}");
                let was_idle = ts.queue.is_empty();
                let before = ts.next_index;
                release_jobs(ts, exec, t);
                if ts.sides.let_comm {
                    let new = (ts.next_index - before) as usize;
                    let skip = ts.queue.len() - new;
                    released.extend(ts.queue.iter().skip(skip).map(|j| LetJob {
                        task: i,
                        index: j.index,
                        release: j.release,
                        demand: j.demand,
                        period: ts.period,
                    }));
                }
                self.releases.replace_top((ts.next_release, i as u32));
                (i, ts.next_index - before, was_idle, ts.sides)
            };
            let (i, new, was_idle, sides) = i;
            if sides.thread {
                let skip = self.tasks[i].queue.len() - new as usize;
                for k in skip..self.tasks[i].queue.len() {
                    let job = self.tasks[i].queue[k];
                    self.thread_queued(i, &job, t);
                }
            }
            if sides.release_work {
                self.release_overheads(i, new, t);
            }
            if !was_idle {
                // Queued behind the front job: nothing the pick sees changed.
                continue;
            }
            self.refresh(i, t);
            self.refresh_servers(i, t);
        }
    }

    /// The ready task of highest priority on a CPU, and whether it runs in
    /// slack (a sporadic server out of budget drops to background priority):
    /// the least (class, key, task) among the CPU's contenders.
    pub(crate) fn pick(&self, cpu: usize) -> Option<(usize, bool)> {
        let first = self.contenders[cpu]
            .first()
            .map(|&(class, _, i)| (i, class == 2));
        match first {
            // The stack resource policy may hold the first back (`locks.rs`).
            Some((i, _)) if self.locks.srp() => {
                self.srp_instead(cpu, i).map(|h| (h, false)).or(first)
            }
            _ => first,
        }
    }

    /// Where task i stands at t, from scratch: its (class, priority key) when
    /// it may run (a job pending, and budget or slack to run it in), and when
    /// its server gets capacity back if it waits for it with a job pending.
    pub(crate) fn standing(&self, i: usize, t: Nanos) -> (Option<(u8, Nanos)>, Option<Nanos>) {
        let ts = &self.tasks[i];
        let Some(job) = ts.queue.front() else {
            return (None, None);
        };
        // Only a thread's head contends for the CPU (`events.rs`).
        if ts.sides.thread && !self.event_model.may_contend(i) {
            return (None, None);
        }
        if ts.sides.sections && self.locks.waiting[i].is_some() {
            return (None, None);
        }
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
            (_, true) => job.release + ts.deadline,
            // Keys 2·rank leave 2·rank − 1 to a resource holder (`locks.rs`).
            (_, false) => {
                let base = 2 * match ts.serves.map(|m| &self.tasks[m as usize]) {
                    // PIBS inheritance: the better (smaller) rank of the server
                    // and the Main VCPU it serves while that one has a job.
                    Some(main) if !main.queue.is_empty() => ts.rank.min(main.rank),
                    _ => ts.rank,
                };
                match ts.sides.sections {
                    true => self.locks.key(i, base),
                    false => base,
                }
            }
        };
        (Some((class, key)), timer)
    }

    /// Task i's queue, budget or inheritance changed at t: update its place
    /// among its CPU's contenders and its refill timer.
    ///
    /// Between two refreshes a task's standing does not change: capacity
    /// only grows with time, and only at the refill instant, where the timer
    /// refreshes it.
    pub(crate) fn refresh(&mut self, i: usize, t: Nanos) {
        let (entry, timer) = self.standing(i, t);
        let ts = &mut self.tasks[i];
        if ts.entry != entry {
            let set = &mut self.contenders[ts.cpu as usize];
            if let Some((class, key)) = ts.entry {
                let was_there = set.remove(&(class, key, i));
                debug_assert!(was_there, "task {i} missing from its contenders");
            }
            if let Some((class, key)) = entry {
                set.insert((class, key, i));
            }
            ts.entry = entry;
            if !self.is_dirty[ts.cpu as usize] {
                self.is_dirty[ts.cpu as usize] = true;
                self.dirty.push(ts.cpu as usize);
            }
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
    pub(crate) fn refresh_servers(&mut self, m: usize, t: Nanos) {
        if !self.tasks[m].sides.served {
            return;
        }
        for k in 0..self.tasks[m].servers.len() {
            let s = self.tasks[m].servers[k];
            self.refresh(s, t);
        }
    }

    /// Debug builds: the incremental state is what the scans it replaces
    /// would compute at t (O(tasks), once per pick).
    #[cfg(debug_assertions)]
    pub(crate) fn check(&self, t: Nanos) {
        let mut contenders = vec![BTreeSet::new(); self.contenders.len()];
        let timers: BTreeSet<_> = self.timers.iter().map(|&Reverse(e)| e).collect();
        let throttled: BTreeSet<_> = self.throttled.iter().map(|&Reverse(e)| e).collect();
        for (i, ts) in self.tasks.iter().enumerate() {
            let (entry, timer) = self.standing(i, t);
            assert_eq!(ts.entry, entry, "task {i}: stale contender entry at {t}");
            assert_eq!(ts.timer, timer, "task {i}: stale refill timer at {t}");
            assert!(entry.is_none() || !ts.queue.is_empty());
            if let Some((class, key)) = entry {
                contenders[ts.cpu as usize].insert((class, key, i));
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
            .all(|(at, i)| at == self.tasks[i as usize].next_release));
    }

    /// The front job of task i first gets the CPU: copy the producers' values.
    pub(crate) fn read(&mut self, i: usize, t: Nanos) {
        let sides = self.tasks[i].sides;
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
        if sides.thread {
            self.thread_started(i);
        }
        if sides.let_comm {
            // Under LET the job read at its release (`let_comm.rs`).
            return;
        }
        if sides.chains {
            self.prov.read(i, t);
        }
        self.hooks.read(&job);
    }

    /// The front job of task i completes at t: publish.
    pub(crate) fn complete(&mut self, i: usize, t: Nanos) {
        let ts = &mut self.tasks[i];
        let sides = ts.sides;
        let Some(job) = ts.queue.pop_front() else {
            return;
        };
        assert!(
            job.read.is_some_and(|r| job.release <= r && r <= t),
            "task {i} publishes at {t} a job that did not read after its release"
        );
        if !sides.let_comm {
            self.hooks.publish(i, t);
        }
        let response = t - job.release;
        ts.stats.completed += 1;
        ts.stats.max_response = Some(ts.stats.max_response.map_or(response, |m| m.max(response)));
        if response > ts.deadline {
            ts.stats.late += 1;
        }
        if ts.queue.is_empty() {
            ts.budget.block(t);
        }
        if sides.thread {
            self.thread_done(i, &job, t);
        }
        if sides.let_comm {
            // LET publishes at the end of the period (`let_comm.rs`).
            return;
        }
        if sides.chains {
            self.prov.publish(i, t);
        }
        if let Some(log) = &mut self.log {
            log.push(JobRecord {
                task: i,
                index: job.index,
                release: job.release,
                demand: job.demand,
                read: job.read.unwrap_or(t),
                finish: t,
                carried: self.prov.record(i),
                trigger: job.trigger,
            });
        }
        if sides.triggers {
            self.publish_triggers(i, job.index, t);
        }
    }

    /// The next instant something happens after t: a release, a completion,
    /// a budget running out, or a budget coming back to a waiting server.
    pub(crate) fn next_event(&mut self, t: Nanos) -> Option<Nanos> {
        let release = self.releases.peek().map(|(at, _)| at);
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
        let running = self.next_cpu_event();
        // The earliest of the three kinds of event.
        release.into_iter().chain(running).chain(refill).min()
    }

    /// Records that task i ran job `index` on `cpu` over [t, t + dt) (for
    /// the Gantt chart), extending the CPU's last slice when the same job
    /// just goes on.
    pub(crate) fn record_segment(
        &mut self,
        cpu: usize,
        i: usize,
        index: u64,
        t: Nanos,
        dt: Nanos,
        slack: bool,
    ) {
        let Some(seg) = &mut self.segments else {
            return;
        };
        match self.last_segment[cpu].and_then(|k| seg.get_mut(k)) {
            Some(s) if s.task == i && s.job == index && s.end == t && s.background == slack => {
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

    pub(crate) fn finish(self) -> SimResult {
        SimResult {
            offsets: self.offsets,
            tasks: self.tasks.into_iter().map(|t| t.stats).collect(),
            chains: self.prov.finish(),
            jobs: self.log.unwrap_or_default(),
            segments: self.segments.unwrap_or_default(),
            events: self.events,
            horizon: self.horizon,
        }
    }
}
