//! EDF with the stack resource policy on SCHED_FIFO threads: a
//! dispatcher in user space, one per CPU, for the specs SCHED_DEADLINE
//! cannot run (critical sections under `scheduler = "edf"`: it picks by
//! deadline alone and has no preemption level or ceiling to hold a job
//! back). docs/runtime.md, "EDF with shared resources", gives the design.
//!
//! Three SCHED_FIFO priorities per CPU stand for the dispatcher's state:
//! - [`DISPATCH`]: a thread asleep until its next release, and a thread
//!   changing the dispatcher's state. Released, it preempts whatever of the
//!   run is running, ranks its job and lowers itself; threads of one CPU at
//!   one priority never preempt each other (SCHED_FIFO), so on a pinned CPU
//!   the state changes one at a time, as with preemption disabled (the
//!   mutex is never contended; [`Stats::contended`] counts it if it is);
//! - [`RUN`]: the one job SRP's rule picks (the simulator's,
//!   `rtpipe_sim`'s locks.rs): the earliest deadline if it has started or
//!   its preemption level is above the CPU's system ceiling, else the
//!   earliest-deadline job that has started (the one on top of the stack);
//! - [`WAIT`]: every other released job, runnable but below the picked one.
//!
//! The kernel's pick is the dispatcher's as long as the picked thread is
//! runnable. Re-ranked at releases, completions and those section exits
//! where the dropping ceiling had held a job back (other exits are one
//! atomic store and load); entering a section only raises the ceiling,
//! which changes no pick, so it is one atomic store.

use crate::sys;
use rtpipe_model::policy::{srp_levels, srp_may_start};
use rtpipe_model::{Nanos, Server, Spec};
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, TryLockError};

/// A thread asleep until its release, or changing the dispatcher's state.
pub const DISPATCH: i32 = 90;
/// The job the dispatcher picked on its CPU.
pub const RUN: i32 = 80;
/// Every other released job.
pub const WAIT: i32 = 10;

/// The dispatcher's counters ([`Stats`]), by index.
const DISPATCHES: usize = 0;
const CHANGES: usize = 1;
const HELD_BACK: usize = 2;
const CONTENDED: usize = 3;
const REFUSED: usize = 4;
const QUIET_EXITS: usize = 5;

/// One released job not yet completed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Ready {
    /// EDF's order: (0, or 1 for a background task; absolute deadline;
    /// task), ties by declaration order as in the simulator.
    pub(crate) key: (u8, Nanos, usize),
    /// Its task's preemption level as a rank (1 the highest).
    pub(crate) level: Nanos,
    /// Picked once: it passed SRP's start test.
    pub(crate) started: bool,
}

/// SRP's pick among a CPU's released jobs under the system ceiling
/// `ceiling` (the best level rank of the resources held there): the index
/// in `ready`, and whether the ceiling held the earliest deadline back.
pub(crate) fn pick(ready: &[Ready], ceiling: Option<Nanos>) -> Option<(usize, bool)> {
    let first = (0..ready.len()).min_by_key(|&k| ready[k].key)?;
    let f = ready[first];
    if srp_may_start(f.started, f.level, ceiling) {
        return Some((first, false));
    }
    let top = (0..ready.len())
        .filter(|&k| ready[k].started)
        .min_by_key(|&k| ready[k].key);
    assert!(top.is_some(), "SRP: a resource held by no started job");
    top.map(|k| (k, true))
}

/// One CPU's released jobs and its pick.
#[derive(Default)]
struct Cpu {
    ready: Vec<Ready>,
    picked: Option<usize>,
}

/// What the dispatchers did in a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Dispatches (releases, completions, section exits).
    pub dispatches: u64,
    /// Priority changes (each a system call).
    pub changes: u64,
    /// Dispatches at which the system ceiling held the earliest deadline
    /// back (SRP's blocking).
    pub held_back: u64,
    /// Dispatches that found the state locked (0 by the argument above).
    pub contended: u64,
    /// Priority changes the kernel refused.
    pub failed: u64,
    /// Section exits that needed no dispatch (the CPU's last pick held no
    /// job back, so a lower ceiling changes nothing).
    pub quiet_exits: u64,
}

impl Stats {
    /// One line for the report.
    pub fn describe(&self) -> String {
        format!(
            "SCHED_FIFO with rtpipe's EDF dispatcher (stack resource policy): {} dispatches, {} priority changes, {} held back by a system ceiling, {} section exits with nothing to dispatch, {} contended, {} refused\n",
            self.dispatches, self.changes, self.held_back, self.quiet_exits, self.contended, self.failed
        )
    }
}

/// Every CPU's dispatcher.
pub(crate) struct Dispatcher {
    cpus: Vec<Mutex<Cpu>>,
    /// Per task: its CPU, level rank, background, thread id.
    cpu_of: Vec<usize>,
    level: Vec<Nanos>,
    background: Vec<bool>,
    tids: Vec<AtomicI32>,
    /// Per resource: its ceiling (the best level rank of its users), its
    /// CPU (validation keeps a resource's users on one), held.
    ceiling: Vec<Nanos>,
    res_cpu: Vec<usize>,
    held: Vec<AtomicBool>,
    /// Per task: its thread's release and completion dispatches
    /// (CLOCK_MONOTONIC), when no job of the CPU ran ([`Dispatcher::spans`]).
    spans: Vec<Mutex<Vec<(Nanos, Nanos)>>>,
    /// Per CPU: its last pick was held back by the system ceiling.
    back: Vec<AtomicBool>,
    counters: [AtomicU64; 6],
}

impl Dispatcher {
    /// For `spec`'s tasks and resources.
    pub(crate) fn new(spec: &Spec) -> Dispatcher {
        let (level, ceiling) = srp_levels(spec);
        let mut res_cpu = vec![0; spec.resources.len()];
        for t in &spec.tasks {
            for s in &t.sections {
                res_cpu[s.resource] = t.cpu as usize;
            }
        }
        let background = spec.tasks.iter().map(|t| t.server == Server::Background);
        Dispatcher::of(
            spec.tasks.iter().map(|t| t.cpu as usize).collect(),
            (level, background.collect()),
            (ceiling, res_cpu),
        )
    }

    /// A dispatcher of `tasks` bare tasks on `cpu` (levels by index, no
    /// resources): `crate::overheads` measures its costs with it.
    pub(crate) fn bare(cpu: usize, tasks: usize) -> Dispatcher {
        let level = (1..=tasks as Nanos).collect();
        Dispatcher::of(
            vec![cpu; tasks],
            (level, vec![false; tasks]),
            (Vec::new(), Vec::new()),
        )
    }

    /// Per task its CPU, (level, background); per resource (ceiling, CPU).
    fn of(
        cpu_of: Vec<usize>,
        (level, background): (Vec<Nanos>, Vec<bool>),
        (ceiling, res_cpu): (Vec<Nanos>, Vec<usize>),
    ) -> Dispatcher {
        let cpus = cpu_of.iter().map(|&c| c + 1).max().unwrap_or(0);
        let n = cpu_of.len();
        Dispatcher {
            cpus: (0..cpus).map(|_| Mutex::default()).collect(),
            back: (0..cpus).map(|_| AtomicBool::new(false)).collect(),
            cpu_of,
            level,
            background,
            tids: (0..n).map(|_| AtomicI32::new(0)).collect(),
            spans: (0..n).map(|_| Mutex::default()).collect(),
            held: ceiling.iter().map(|_| AtomicBool::new(false)).collect(),
            ceiling,
            res_cpu,
            counters: Default::default(),
        }
    }

    /// The calling thread is task `task`'s.
    pub(crate) fn register(&self, task: usize) {
        self.tids[task].store(sys::gettid(), Ordering::SeqCst);
    }

    /// Task `task`'s job with absolute deadline `deadline` (CLOCK_MONOTONIC)
    /// is released; its thread, at [`DISPATCH`], ranks it and takes the
    /// priority the pick gives it.
    pub(crate) fn release(&self, task: usize, deadline: Nanos) {
        let entry = Ready {
            key: (u8::from(self.background[task]), deadline, task),
            level: self.level[task],
            started: false,
        };
        let t0 = sys::now();
        let own = self.dispatch(task, |cpu| cpu.ready.push(entry));
        // The span ends before the thread lowers itself: from then on
        // others may run before it (another release of the same instant,
        // or the pick if it is not this job), and only at DISPATCH is no
        // job of the CPU running.
        self.record(task, t0);
        self.set_own(own);
    }

    /// Task `task`'s job completed: the next pick runs, and the thread
    /// stays at [`DISPATCH`] for its next release.
    pub(crate) fn complete(&self, task: usize) {
        self.set_own(DISPATCH);
        // Only from here can no other job of the CPU run (below DISPATCH
        // a release may preempt the thread and pick another job).
        let t0 = sys::now();
        let own = self.dispatch(task, |cpu| cpu.ready.retain(|r| r.key.2 != task));
        assert_eq!(own, DISPATCH, "a completed job stays ranked");
        self.record(task, t0);
    }

    /// Makes room for the dispatch spans of `jobs[i]` jobs of each task i
    /// (a release and a completion each), before the run: a span is
    /// recorded at DISPATCH on the real-time path, where a vector that
    /// doubles would copy itself.
    pub(crate) fn reserve(&self, jobs: impl Iterator<Item = usize>) {
        for (spans, n) in self.spans.iter().zip(jobs) {
            if let Ok(mut v) = spans.lock() {
                v.reserve(2 * n);
            }
        }
    }

    fn record(&self, task: usize, t0: Nanos) {
        let span = (t0, sys::now());
        if let Ok(mut v) = self.spans[task].lock() {
            v.push(span);
        }
    }

    /// Per task, its thread's release and completion dispatches relative
    /// to `epoch`: the thread ran at DISPATCH, outside every job's read →
    /// publish span, so no job of its CPU ran then (`crate::blame`). A
    /// section exit's dispatch is inside its job's span, counted in its
    /// CPU time, and not here.
    pub(crate) fn spans(&self, epoch: Nanos) -> Vec<Vec<(Nanos, Nanos)>> {
        self.spans
            .iter()
            .map(|m| {
                let v: Vec<(Nanos, Nanos)> = m
                    .lock()
                    .map(|v| v.iter().map(|&(a, b)| (a - epoch, b - epoch)).collect())
                    .unwrap_or_default();
                // One thread records them one after the other (the blame
                // searches them as such).
                assert!(
                    v.iter().all(|&(a, b)| a <= b) && v.windows(2).all(|w| w[0].1 <= w[1].0),
                    "a thread's dispatch spans are in order and disjoint"
                );
                v
            })
            .collect()
    }

    /// Task `task`'s running job takes resource `r`: the ceiling rises
    /// (the pick cannot change: the running job is the picked one).
    pub(crate) fn enter(&self, r: usize) {
        self.held[r].store(true, Ordering::SeqCst);
    }

    /// Task `task`'s running job gave `r` back: the ceiling drops and a
    /// job it held back may start. Only a pick the ceiling held back can
    /// change when it drops, so without one this is one store and one load
    /// (no system call): a release dispatched before the store set the
    /// CPU's flag, one after it picked under the lower ceiling already.
    pub(crate) fn exit(&self, task: usize, r: usize) {
        self.held[r].store(false, Ordering::SeqCst);
        if !self.back[self.cpu_of[task]].load(Ordering::SeqCst) {
            self.count(QUIET_EXITS);
            return;
        }
        self.set_own(DISPATCH);
        let own = self.dispatch(task, |_| {});
        self.set_own(own);
    }

    /// What the dispatchers did.
    pub(crate) fn stats(&self) -> Stats {
        let c = |k: usize| self.counters[k].load(Ordering::SeqCst);
        Stats {
            dispatches: c(DISPATCHES),
            changes: c(CHANGES),
            held_back: c(HELD_BACK),
            contended: c(CONTENDED),
            failed: c(REFUSED),
            quiet_exits: c(QUIET_EXITS),
        }
    }

    fn count(&self, k: usize) {
        self.counters[k].fetch_add(1, Ordering::SeqCst);
    }

    /// The caller (task `task`'s thread, at [`DISPATCH`]) applies `change`
    /// to its CPU's state and re-picks: the previous pick goes to [`WAIT`],
    /// the new one to [`RUN`]. Returns the caller's own priority (it sets
    /// it itself, after the state's lock is given back).
    fn dispatch(&self, task: usize, change: impl FnOnce(&mut Cpu)) -> i32 {
        let c = self.cpu_of[task];
        let mut cpu = self.lock(c);
        change(&mut cpu);
        self.count(DISPATCHES);
        let ceiling = (0..self.ceiling.len())
            .filter(|&r| self.res_cpu[r] == c && self.held[r].load(Ordering::SeqCst))
            .map(|r| self.ceiling[r])
            .min();
        let choice = pick(&cpu.ready, ceiling);
        let held_back = choice.is_some_and(|(_, back)| back);
        let picked = choice.map(|(k, _)| {
            cpu.ready[k].started = true;
            cpu.ready[k].key.2
        });
        if held_back {
            self.count(HELD_BACK);
        }
        self.back[c].store(held_back, Ordering::SeqCst);
        let old = std::mem::replace(&mut cpu.picked, picked);
        if old != picked {
            let ready = |t: usize| cpu.ready.iter().any(|r| r.key.2 == t);
            if let Some(o) = old.filter(|&o| o != task && ready(o)) {
                self.set(o, WAIT);
            }
            if let Some(p) = picked.filter(|&p| p != task) {
                self.set(p, RUN);
            }
        }
        match (
            picked == Some(task),
            cpu.ready.iter().any(|r| r.key.2 == task),
        ) {
            (true, _) => RUN,
            (false, true) => WAIT,
            (false, false) => DISPATCH,
        }
    }

    fn lock(&self, c: usize) -> MutexGuard<'_, Cpu> {
        match self.cpus[c].try_lock() {
            Ok(g) => g,
            Err(TryLockError::Poisoned(e)) => e.into_inner(),
            Err(TryLockError::WouldBlock) => {
                self.count(CONTENDED);
                self.cpus[c].lock().unwrap_or_else(|e| e.into_inner())
            }
        }
    }

    fn set(&self, task: usize, priority: i32) {
        self.count(CHANGES);
        let tid = self.tids[task].load(Ordering::SeqCst);
        if tid <= 0 || sys::set_priority_of(tid, priority).is_err() {
            self.count(REFUSED);
        }
    }

    fn set_own(&self, priority: i32) {
        self.count(CHANGES);
        if sys::set_priority(priority).is_err() {
            self.count(REFUSED);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(deadline: Nanos, task: usize, level: Nanos, started: bool) -> Ready {
        Ready {
            key: (0, deadline, task),
            level,
            started,
        }
    }

    /// examples/edf-srp.toml at 4 ms: c (level 3) holds bus (ceiling 1,
    /// a's level) and a (deadline 8) is released: a may not start, c runs;
    /// once bus is given back a runs. b (level 2) is held back as well:
    /// its level is not above 1.
    #[test]
    fn reserved_spans_never_grow_in_the_run() {
        let d = Dispatcher::bare(0, 2);
        d.reserve([20_000, 3].into_iter());
        let capacity = |t: usize| d.spans[t].lock().map_or(0, |v| v.capacity());
        let before = capacity(0);
        assert!(before >= 40_000);
        for _ in 0..20_000 {
            d.record(0, sys::now());
            d.record(0, sys::now());
        }
        assert_eq!(capacity(0), before, "a span vector grew in the run");
    }

    #[test]
    fn the_ceiling_holds_an_earlier_deadline_back_until_it_drops() {
        let ready = [r(12, 2, 3, true), r(8, 0, 1, false)];
        assert_eq!(pick(&ready, Some(1)), Some((0, true)));
        assert_eq!(pick(&ready, None), Some((1, false)));
        // A started job of earlier deadline runs whatever the ceiling (it
        // passed the test when it started).
        let ready = [r(12, 2, 3, true), r(8, 0, 1, true)];
        assert_eq!(pick(&ready, Some(1)), Some((1, false)));
        // A level above the ceiling starts: b (level 2) under a ceiling of 3.
        let ready = [r(12, 2, 3, true), r(10, 1, 2, false)];
        assert_eq!(pick(&ready, Some(3)), Some((1, false)));
        assert_eq!(pick(&ready, Some(2)), Some((0, true)));
        // Ties by declaration order, background last.
        let ready = [r(12, 2, 3, false), r(12, 1, 2, false)];
        assert_eq!(pick(&ready, None), Some((1, false)));
        let bg = Ready {
            key: (1, 0, 0),
            level: Nanos::MAX,
            started: false,
        };
        assert_eq!(pick(&[bg, r(99, 1, 2, false)], None), Some((1, false)));
        assert_eq!(pick(&[], None), None);
    }
}
