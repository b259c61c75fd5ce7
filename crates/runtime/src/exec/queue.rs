//! Work-queue threads and data-triggered tasks: which OS thread runs which
//! tasks' jobs, the queued job of each task (one at most: a release while
//! one is queued and not started is merged into it, PX4's one pending
//! activation), the publications that release data-triggered tasks (join
//! any, join all), and the loop of a work-queue thread.
//!
//! The queue of a thread is one slot per task it runs, holding the release
//! instant of the task's queued job: the thread runs the queued job of
//! earliest release (ties: declaration order), which is its release order,
//! whatever order the releases reached the slots in. Nothing here
//! allocates once the run has started.

use super::{job, Thread};
use crate::config::{Policy, RunError};
use crate::locks::Resources;
use crate::pi::PiMutex;
use crate::sys;
use rtpipe_body::Environment;
use rtpipe_model::{Join, Nanos, Spec};
use std::sync::atomic::{AtomicI64, AtomicU32, AtomicU64, Ordering::SeqCst};

/// An empty slot: no job of the task queued.
const EMPTY: Nanos = Nanos::MAX;

/// Most triggers of one task with join = "all" (one bit each in
/// [`Queues`]' masks).
pub(crate) const MAX_JOIN_ALL: usize = 64;

/// How long a work-queue thread waits between looks for a publication
/// still under way, once the run's releases are over.
const SETTLE: Nanos = 1_000_000;

/// The longest a thread waits without looking at Ctrl-C: a data-triggered
/// task whose triggers have stopped would otherwise wait for a wake-up
/// until the run's end (a signal interrupts one thread's wait, not all).
const STOP_POLL: Nanos = 50_000_000;

/// What the threads of an event-triggered run share: every task's queue
/// slot and merge count, the join-all masks, and each thread's bell.
pub(crate) struct Queues {
    /// Per task: the release instant (from the epoch) of its job queued and
    /// not started, or [`EMPTY`].
    pending: Vec<AtomicI64>,
    /// Per task: releases merged into a job already queued.
    merges: Vec<AtomicU64>,
    /// Per data-triggered task with join = "all": a bit per trigger that
    /// has published since its last release.
    seen: Vec<AtomicU64>,
    /// Per task: every trigger's bit under join = "all", else 0.
    all: Vec<u64>,
    /// Per task: the data-triggered tasks it triggers, each with this
    /// task's bit among its triggers.
    consumers: Vec<Vec<(usize, u64)>>,
    /// Per task: the OS thread (index into [`workers`]) that runs it.
    worker_of: Vec<usize>,
    /// Per OS thread: a futex word bumped at every release for it.
    bells: Vec<AtomicU32>,
    /// Publications of triggering jobs under way, from before their
    /// publish instant to after their releases: no thread ends while one
    /// is (it could still release a job before the run's end).
    in_flight: AtomicU64,
    /// No job is released at or after this instant (the run's duration).
    end: Nanos,
}

/// The OS threads of a run, each the tasks it runs in declaration order:
/// a work-queue thread of the spec runs all of its tasks, every other task
/// is a thread of its own. Numbered by their first task.
pub(crate) fn workers(spec: &Spec) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut of_thread: Vec<Option<usize>> = vec![None; spec.threads.len()];
    for (i, t) in spec.tasks.iter().enumerate() {
        match t.thread.map(|th| (th, of_thread[th])) {
            Some((_, Some(w))) => out[w].push(i),
            Some((th, None)) => {
                of_thread[th] = Some(out.len());
                out.push(vec![i]);
            }
            None => out.push(vec![i]),
        }
    }
    out
}

/// Per task, the most jobs a run of `duration` releases: a timer's count
/// (+2: the release at 0 and a rounding's), a data-triggered task's
/// triggers' (their sum under join = "any", the least under "all").
pub(crate) fn job_capacity(spec: &Spec, duration: Nanos) -> Vec<u64> {
    let mut caps: Vec<Option<u64>> = vec![None; spec.tasks.len()];
    for i in 0..spec.tasks.len() {
        capacity_of(spec, duration, i, &mut caps);
    }
    caps.into_iter().map(|c| c.unwrap_or(0)).collect()
}

/// [`job_capacity`] of task `i`, its triggers' first (the trigger graph is
/// acyclic: validated).
fn capacity_of(spec: &Spec, duration: Nanos, i: usize, caps: &mut [Option<u64>]) -> u64 {
    if let Some(c) = caps[i] {
        return c;
    }
    let t = &spec.tasks[i];
    let c = match t.triggers() {
        None => (duration / t.fixed_period().unwrap_or(1).max(1)) as u64 + 2,
        Some((triggers, join)) => {
            let each = triggers
                .iter()
                .map(|&p| capacity_of(spec, duration, p, caps));
            match join {
                Join::Any => each.fold(0, u64::saturating_add),
                Join::All => each.min().unwrap_or(0),
            }
        }
    };
    caps[i] = Some(c);
    c
}

/// Why an event-triggered `spec` cannot run under `policy`, if it cannot.
pub(crate) fn refusal(spec: &Spec, policy: Policy) -> Option<RunError> {
    if !spec.event_triggered() {
        return None;
    }
    if policy.edf() {
        return Some(RunError::config(
            format!(
                "--policy {} cannot run work-queue threads or data-triggered tasks: a work-queue thread runs its tasks' jobs in release order, one at a time, which neither a SCHED_DEADLINE reservation per task nor rtpipe's EDF dispatcher (jobs by absolute deadline) does",
                policy.name()
            ),
            "use --policy fifo (threads and data-triggered tasks need scheduler = \"rm\" and explicit priorities), or --policy other --best-effort",
        ));
    }
    if spec.any_let() {
        return Some(RunError::config(
            "communication = \"let\" in a spec with work-queue threads or data-triggered tasks: the runtime releases data-triggered jobs at the publish instants of implicit communication only",
            "remove the LET communication (system or chain), or run the spec without threads and data-triggered tasks",
        ));
    }
    let wide = spec.tasks.iter().find(|t| {
        t.triggers()
            .is_some_and(|(tr, join)| join == Join::All && tr.len() > MAX_JOIN_ALL)
    })?;
    Some(RunError::config(
        format!(
            "task {} joins all of more than {MAX_JOIN_ALL} triggers, more than the runtime tracks",
            wide.name
        ),
        format!("give task {} at most {MAX_JOIN_ALL} triggers", wide.name),
    ))
}

impl Queues {
    /// For `spec`'s tasks on `workers`, releasing jobs before `end`.
    pub(crate) fn new(spec: &Spec, workers: &[Vec<usize>], end: Nanos) -> Queues {
        let n = spec.tasks.len();
        let mut worker_of = vec![0; n];
        for (w, tasks) in workers.iter().enumerate() {
            for &t in tasks {
                worker_of[t] = w;
            }
        }
        let mut consumers = vec![Vec::new(); n];
        let mut all = vec![0; n];
        for (c, t) in spec.tasks.iter().enumerate() {
            let Some((triggers, join)) = t.triggers() else {
                continue;
            };
            assert!(
                join == Join::Any || triggers.len() <= MAX_JOIN_ALL,
                "checked by `check`"
            );
            for (b, &p) in triggers.iter().enumerate() {
                let bit = if join == Join::All { 1 << b } else { 0 };
                consumers[p].push((c, bit));
                all[c] |= bit;
            }
        }
        Queues {
            pending: (0..n).map(|_| AtomicI64::new(EMPTY)).collect(),
            merges: (0..n).map(|_| AtomicU64::new(0)).collect(),
            seen: (0..n).map(|_| AtomicU64::new(0)).collect(),
            all,
            consumers,
            worker_of,
            bells: workers.iter().map(|_| AtomicU32::new(0)).collect(),
            in_flight: AtomicU64::new(0),
            end,
        }
    }

    /// Releases a job of `task` at `at`: into its empty slot (true), or
    /// merged into the job queued there (false). None at or after the end.
    fn release(&self, task: usize, at: Nanos) -> bool {
        if at >= self.end {
            return false;
        }
        let queued = self.pending[task].compare_exchange(EMPTY, at, SeqCst, SeqCst);
        if queued.is_err() {
            self.merges[task].fetch_add(1, SeqCst);
        }
        queued.is_ok()
    }

    /// Whether a job of `task` is about to publish to data-triggered
    /// tasks; if so the publication is under way until [`Queues::publish`].
    /// Called before the publish instant is taken.
    pub(crate) fn begin(&self, task: usize) -> bool {
        let triggers = !self.consumers[task].is_empty();
        if triggers {
            self.in_flight.fetch_add(1, SeqCst);
        }
        triggers
    }

    /// `task`'s job published at `at` (its registers written): releases
    /// the tasks it triggers (join = "all": once every trigger has
    /// published since the last release) and wakes their threads, then
    /// ends the publication [`Queues::begin`] started.
    pub(crate) fn publish(&self, task: usize, at: Nanos) {
        let from = self.worker_of[task];
        for &(c, bit) in &self.consumers[task] {
            if self.joined(c, bit) && self.release(c, at) && self.worker_of[c] != from {
                let w = self.worker_of[c];
                self.bells[w].fetch_add(1, SeqCst);
                sys::wake(&self.bells[w]);
            }
        }
        self.in_flight.fetch_sub(1, SeqCst);
    }

    /// A publication of the trigger of `bit` completes `c`'s join: always
    /// under join = "any" (`bit` 0); under "all", when it sets the last
    /// missing bit, which clears the mask for the next release.
    fn joined(&self, c: usize, bit: u64) -> bool {
        if bit == 0 {
            return true;
        }
        let all = self.all[c];
        let mut cur = self.seen[c].load(SeqCst);
        loop {
            let next = cur | bit;
            let (store, done) = if next == all {
                (0, true)
            } else {
                (next, false)
            };
            match self.seen[c].compare_exchange(cur, store, SeqCst, SeqCst) {
                Ok(_) => return done,
                Err(now) => cur = now,
            }
        }
    }

    /// Takes the queued job of earliest release among `tasks` (ties: the
    /// first task): (its position in `tasks`, its release).
    fn take(&self, tasks: &[usize]) -> Option<(usize, Nanos)> {
        let (m, release) = tasks
            .iter()
            .enumerate()
            .map(|(m, &t)| (m, self.pending[t].load(SeqCst)))
            .filter(|&(_, r)| r != EMPTY)
            .min_by_key(|&(m, r)| (r, m))?;
        // Only the thread empties a slot: the release stays until then.
        let taken = self.pending[tasks[m]].swap(EMPTY, SeqCst);
        debug_assert_eq!(taken, release);
        Some((m, release))
    }

    /// No job of `tasks` is queued.
    fn idle(&self, tasks: &[usize]) -> bool {
        tasks.iter().all(|&t| self.pending[t].load(SeqCst) == EMPTY)
    }

    /// Releases merged into a queued job of `task` during the run.
    pub(crate) fn merges(&self, task: usize) -> u64 {
        self.merges[task].load(SeqCst)
    }
}

/// The world and the resources a job runs with.
pub(super) type Env<'r, 'e, V> = Option<&'r PiMutex<dyn Environment<V> + Send + 'e>>;

/// The loop of OS thread `worker`, running `members`' jobs from `epoch`:
/// its tasks' timers release into their slots, its data-triggered tasks
/// are released by publications, and it runs the queued job of earliest
/// release, one at a time, to completion. It ends when the releases are
/// over (`duration`) and no job is queued or can still be released, or at
/// `stop` (the run's end plus its grace) or Ctrl-C.
pub(super) fn serve<V: Copy>(
    (members, worker): (&mut [Thread<'_, V>], usize),
    q: &Queues,
    epoch: Nanos,
    (duration, stop): (Nanos, Nanos),
    (env, res): (Env<'_, '_, V>, Option<&Resources>),
) {
    let tasks: Vec<usize> = members.iter().map(|t| t.task).collect();
    let most_inputs = members.iter().map(|t| t.ins.len()).max().unwrap_or(0);
    let mut inputs = Vec::with_capacity(most_inputs);
    let mut timers = vec![0u64; members.len()];
    loop {
        // Read before looking at the slots: a release after this look
        // changes the bell, and the wait below returns at once.
        let bell = q.bells[worker].load(SeqCst);
        let now = sys::now() - epoch;
        if sys::stop_requested() || now >= stop {
            break;
        }
        let next_timer = release_timers(members, &mut timers, now, q);
        if let Some((m, release)) = q.take(&tasks) {
            let th = &mut members[m];
            if th.recs.len() == th.recs.capacity() {
                break;
            }
            let k = th.recs.len() as u64;
            job(th, (k, release), epoch, (env, res, Some(q)), &mut inputs);
            continue;
        }
        let until = match next_timer {
            Some(t) => t,
            // Releases are over: end once no publication is under way that
            // could still release a job here, and none landed since the
            // look above (one may have ended in between).
            None if now >= duration && q.in_flight.load(SeqCst) == 0 => {
                if q.idle(&tasks) {
                    break;
                }
                continue;
            }
            None if now >= duration => now + SETTLE,
            None => duration,
        };
        let until = until.min(stop).min(now + STOP_POLL);
        sys::wait_until(&q.bells[worker], bell, epoch + until);
    }
}

/// Releases every timer of `members` due by `now` (a periodic task's
/// release at φ + k·T, before the run's end), merged into its queued job if
/// it has one; returns the next timer release, if any is before the end.
fn release_timers<V>(
    members: &[Thread<'_, V>],
    timers: &mut [u64],
    now: Nanos,
    q: &Queues,
) -> Option<Nanos> {
    let mut next: Option<Nanos> = None;
    for (th, k) in members.iter().zip(timers.iter_mut()) {
        if th.triggered {
            continue;
        }
        loop {
            let at = th.phase + *k as Nanos * th.period;
            if at >= q.end {
                break;
            }
            if at > now {
                next = Some(next.map_or(at, |n| n.min(at)));
                break;
            }
            q.release(th.task, at);
            *k += 1;
        }
    }
    next
}
