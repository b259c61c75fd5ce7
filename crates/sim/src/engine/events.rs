//! Work-queue threads and data-triggered tasks (the event-triggered model
//! of docs/analysis.md, PX4's work queues) in the simulator.
//!
//! - **Threads.** The tasks of a thread share its rank
//!   (`rtpipe_model::policy::ranks`), and only one of them contends for the
//!   CPU at a time: the thread's head, whose front job is the thread's
//!   started job, or else its earliest queued one (by the instant it was
//!   queued, then declaration order). So a thread's jobs run one at a time
//!   to completion in release order and never preempt each other, while
//!   threads and thread-less tasks preempt each other by rank. Each thread
//!   keeps its queued jobs in an ordered set: a release, a start and a
//!   completion cost O(log n).
//! - **Triggers.** A job publishes at its completion (implicit
//!   communication; a LET producer at its period's end), and each
//!   publication releases the data-triggered tasks it triggers at that
//!   instant: at once under join = "any", once every trigger has published
//!   since the last release under join = "all".
//! - **Merging.** A release while an earlier job of the same task is
//!   queued and not yet started joins that job (PX4's one pending
//!   activation), for every task in a thread and every data-triggered
//!   task; `TaskStats::merged` counts them.

use super::{draw_demand, Hooks, Job, Sim};
use rtpipe_joblog::Trigger;
use rtpipe_model::{Join, Nanos, Spec};
use std::collections::BTreeSet;

/// A queued job of a thread: (instant queued, task, job index), the
/// thread's run order.
type Entry = (Nanos, usize, u64);

/// One work-queue thread's jobs.
#[derive(Debug, Clone, Default)]
pub(crate) struct ThreadQueue {
    /// Its released, unfinished jobs, in run order.
    queued: BTreeSet<Entry>,
    /// The job that has started (it runs to completion before any other).
    started: Option<Entry>,
}

impl ThreadQueue {
    /// The task whose front job the thread runs next.
    fn head(&self) -> Option<usize> {
        self.started
            .or_else(|| self.queued.first().copied())
            .map(|(_, task, _)| task)
    }
}

/// The event-triggered state of a run: threads, triggers and joins.
#[derive(Debug, Clone, Default)]
pub(crate) struct Events {
    /// Per task, its thread (index into `threads`).
    pub(crate) thread_of: Vec<Option<usize>>,
    threads: Vec<ThreadQueue>,
    /// Per task, the data-triggered tasks its publications release.
    consumers: Vec<Vec<usize>>,
    /// Per data-triggered task under join = "all": which triggers have
    /// published since its last release (in the order of its triggers).
    joins: Vec<Option<JoinAll>>,
}

/// join = "all": the triggers seen since the last release.
#[derive(Debug, Clone)]
struct JoinAll {
    triggers: Vec<usize>,
    seen: Vec<bool>,
    missing: usize,
}

impl JoinAll {
    /// `p` published; true when that completes the set (which starts over).
    fn publish(&mut self, p: usize) -> bool {
        for (k, &q) in self.triggers.iter().enumerate() {
            if q == p && !self.seen[k] {
                self.seen[k] = true;
                self.missing -= 1;
            }
        }
        if self.missing > 0 {
            return false;
        }
        self.seen.iter_mut().for_each(|s| *s = false);
        self.missing = self.triggers.len();
        true
    }
}

impl Events {
    /// The threads, triggers and joins of `spec` (all empty for a spec of
    /// periodic tasks each on a thread of its own, which then runs as
    /// before).
    pub(crate) fn new(spec: &Spec) -> Events {
        let joins = spec
            .tasks
            .iter()
            .map(|t| match t.triggers() {
                Some((triggers, Join::All)) => Some(JoinAll {
                    triggers: triggers.to_vec(),
                    seen: vec![false; triggers.len()],
                    missing: triggers.len(),
                }),
                _ => None,
            })
            .collect();
        Events {
            thread_of: spec.tasks.iter().map(|t| t.thread).collect(),
            threads: vec![ThreadQueue::default(); spec.threads.len()],
            consumers: spec.triggered_by(),
            joins,
        }
    }

    /// Task p's publications release some data-triggered task.
    pub(crate) fn triggers_any(&self, p: usize) -> bool {
        !self.consumers[p].is_empty()
    }

    /// May task `i` contend for its CPU: it is on no thread, or its
    /// thread's head?
    pub(crate) fn may_contend(&self, i: usize) -> bool {
        match self.thread_of[i] {
            None => true,
            Some(th) => self.threads[th].head() == Some(i),
        }
    }
}

impl<H: Hooks> Sim<H> {
    /// Task i queued `job` (its newest) at t: it joins its thread's order,
    /// and the thread's head may change.
    pub(crate) fn thread_queued(&mut self, i: usize, job: &Job, t: Nanos) {
        let Some(th) = self.event_model.thread_of[i] else {
            return;
        };
        let q = &mut self.event_model.threads[th];
        let before = q.head();
        q.queued.insert((job.queued, i, job.index));
        self.thread_head_moved(th, before, t);
    }

    /// The front job of task i started: its thread runs it to completion.
    pub(crate) fn thread_started(&mut self, i: usize) {
        let Some(th) = self.event_model.thread_of[i] else {
            return;
        };
        let Some(job) = self.tasks[i].queue.front() else {
            return;
        };
        let entry = (job.queued, i, job.index);
        let q = &mut self.event_model.threads[th];
        assert!(
            q.started.is_none_or(|s| s == entry),
            "thread {th} starts a second job while one runs"
        );
        q.started = Some(entry);
    }

    /// Task i's `job` completed at t: its thread moves on.
    pub(crate) fn thread_done(&mut self, i: usize, job: &Job, t: Nanos) {
        let Some(th) = self.event_model.thread_of[i] else {
            return;
        };
        let q = &mut self.event_model.threads[th];
        let before = q.head();
        let entry = (job.queued, i, job.index);
        let was_queued = q.queued.remove(&entry);
        assert!(was_queued, "thread {th} completes a job it did not queue");
        q.started = None;
        self.thread_head_moved(th, before, t);
    }

    /// The head of thread `th` was `before`: when it changed, the old and
    /// the new head change their standing among the contenders.
    fn thread_head_moved(&mut self, th: usize, before: Option<usize>, t: Nanos) {
        let after = self.event_model.threads[th].head();
        if after == before {
            return;
        }
        for i in [before, after].into_iter().flatten() {
            self.refresh(i, t);
        }
    }

    /// Job `job` of task p published at t: the data-triggered tasks it
    /// triggers are released (at once under join = "any", when it
    /// completes the set under join = "all").
    pub(crate) fn publish_triggers(&mut self, p: usize, job: u64, t: Nanos) {
        for k in 0..self.event_model.consumers[p].len() {
            let c = self.event_model.consumers[p][k];
            let due = match &mut self.event_model.joins[c] {
                None => true,
                Some(all) => all.publish(p),
            };
            if due {
                self.release_triggered(c, Trigger { task: p, job }, t);
            }
        }
    }

    /// Releases a job of data-triggered task c at t, or merges the release
    /// into its queued, unstarted job.
    fn release_triggered(&mut self, c: usize, trigger: Trigger, t: Nanos) {
        let exec = self.exec;
        let ts = &mut self.tasks[c];
        if ts.queue.back().is_some_and(|j| j.read.is_none()) {
            ts.stats.merged += 1;
            return;
        }
        let demand = draw_demand(ts, exec);
        let was_idle = ts.queue.is_empty();
        if was_idle {
            ts.budget.unblock(t);
        }
        let job = Job {
            index: ts.next_index,
            release: t,
            queued: t,
            demand,
            remaining: demand,
            read: None,
            trigger: Some(trigger),
        };
        ts.queue.push_back(job);
        ts.stats.released += 1;
        ts.next_index += 1;
        if ts.sides.thread {
            // Its thread refreshes it when it becomes the head; while it is
            // not, it stands where an idle task stands (nowhere).
            self.thread_queued(c, &job, t);
        } else if was_idle {
            self.refresh(c, t);
        }
        if was_idle {
            self.refresh_servers(c, t);
        }
    }
}
