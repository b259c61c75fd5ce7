//! The CPUs without a scan per event: each CPU's running job is
//! charged lazily, only when something happens on that CPU, and the CPUs'
//! next events (a completion or a budget running out) wait in a tournament
//! tree. An instant visits only the CPUs whose event it is and those whose
//! contenders changed, so an event costs O(log n) in the number of CPUs as
//! in the number of tasks.
//!
//! Charging a running job in one piece from `since` to t gives what
//! charging it at every instant in between gave: between two of its CPU's
//! events a running job's demand and its server's capacity both fall by
//! the time it ran (every server's capacity is linear while it runs: the
//! sporadic server's head only shrinks, PIBS' replenishment is spent, the
//! CBS runtime drops), its standing among the contenders does not change,
//! and the charges add up (`tests::heaps_match_the_reference` replays the
//! former every-CPU scans).

use crate::engine::{Budget, Hooks, Sim};
use rtpipe_model::Nanos;
use std::cmp::Reverse;

impl<H: Hooks> Sim<H> {
    /// Charges the job running on `cpu` for the time since the CPU was last
    /// brought up to date, up to t.
    pub(crate) fn sync(&mut self, cpu: usize, t: Nanos) {
        let since = std::mem::replace(&mut self.since[cpu], t);
        let dt = t - since;
        debug_assert!(dt >= 0, "cpu {cpu} synced back in time to {t}");
        // Kernel work and a switch in progress run first (`overheads.rs`).
        let left = if dt > 0 { self.ovh.run(cpu, dt) } else { 0 };
        if left > 0 && self.running[cpu].is_some() {
            self.advance_cpu(cpu, t - left, left);
        }
    }

    /// `released` jobs of task i were released at t: their kernel work
    /// (`overheads.rs`) joins its CPU's, which is charged up to t first.
    pub(crate) fn release_overheads(&mut self, i: usize, released: u64, t: Nanos) {
        let work = self.ovh.release_work(i, released);
        if work == 0 {
            return;
        }
        let cpu = self.tasks[i].cpu as usize;
        self.sync(cpu, t);
        self.ovh.add_kernel(cpu, work);
        self.mark(cpu);
    }

    /// Brings every CPU up to t (at the end of a run).
    pub(crate) fn sync_all(&mut self, t: Nanos) {
        for cpu in 0..self.running.len() {
            self.sync(cpu, t);
        }
    }

    /// `cpu` must be picked for again at this instant.
    pub(crate) fn mark(&mut self, cpu: usize) {
        if !self.is_dirty[cpu] {
            self.is_dirty[cpu] = true;
            self.dirty.push(cpu);
        }
    }

    /// The CPUs whose event is at t, in CPU order, brought up to t and
    /// marked for a pick.
    pub(crate) fn pop_due(&mut self, t: Nanos, due: &mut Vec<usize>) {
        due.clear();
        while let Some((at, cpu)) = self.cpu_events.first() {
            if at > t {
                break;
            }
            debug_assert_eq!(at, t, "cpu {cpu}: event at {at} missed");
            debug_assert_eq!(self.cpu_event[cpu], Some(at));
            self.cpu_events.set(cpu, None);
            self.cpu_event[cpu] = None;
            self.sync(cpu, t);
            self.mark(cpu);
            due.push(cpu);
        }
    }

    /// Each marked CPU picks (in CPU order) and schedules its next event;
    /// returns the CPUs picked for, in that order.
    pub(crate) fn pick_marked(&mut self, t: Nanos, picked: &mut Vec<usize>) {
        std::mem::swap(picked, &mut self.dirty);
        self.dirty.clear();
        picked.sort_unstable();
        for &cpu in picked.iter() {
            self.is_dirty[cpu] = false;
            self.sync(cpu, t);
            let pick = self.pick(cpu);
            self.running[cpu] = pick.map(|(i, _)| i);
            let job = pick.and_then(|(i, _)| Some((i, self.tasks[i].queue.front()?.index)));
            self.ovh.choose(cpu, job);
            self.in_slack[cpu] = pick.is_some_and(|(_, slack)| slack);
            self.schedule(cpu, t);
        }
    }

    /// The next event of `cpu` (brought up to t): its job completes, its
    /// server's capacity runs out, or it enters or leaves a critical
    /// section.
    fn schedule(&mut self, cpu: usize, t: Nanos) {
        let lead = self.ovh.lead(cpu);
        let next = self.running[cpu].and_then(|i| {
            let ts = &self.tasks[i];
            let job = ts.queue.front()?;
            if lead > 0 {
                // The job's own work starts after the overheads: it reads,
                // locks or completes only then.
                return Some(t + lead);
            }
            let mut next = t + job.remaining;
            if !self.in_slack[cpu] {
                let cap = ts.budget.capacity(t);
                if cap < job.remaining {
                    next = t + cap;
                }
            }
            let boundary = ts.sides.sections.then(|| self.locks.until_boundary(i, job));
            if let Some(b) = boundary.flatten() {
                next = next.min(t + b);
            }
            Some(next)
        });
        if next != self.cpu_event[cpu] {
            self.cpu_event[cpu] = next;
            self.cpu_events.set(cpu, next);
        }
    }

    /// The earliest CPU event.
    pub(crate) fn next_cpu_event(&self) -> Option<Nanos> {
        self.cpu_events.first().map(|(at, _)| at)
    }

    /// Runs the job on `cpu` from t for dt and charges its server.
    pub(crate) fn advance_cpu(&mut self, cpu: usize, t: Nanos, dt: Nanos) {
        let Some(i) = self.running[cpu] else { return };
        let slack = self.in_slack[cpu];
        let ts = &mut self.tasks[i];
        let Some(job) = ts.queue.front_mut() else {
            return;
        };
        job.remaining -= dt;
        let (index, remaining) = (job.index, job.remaining);
        ts.stats.busy += dt;
        // An unlimited budget is never charged, so the job's standing
        // (`Sim::standing`: its queue front, budget and key) is as it was
        // and a refresh would find nothing to change: skipping it saves
        // one per charge (callgrind, docs/analysis.md "The simulator's
        // side").
        if !slack && !matches!(ts.budget, Budget::Unlimited) {
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
        if self.tasks[i].sides.sections {
            self.unlock_passed(i, t + dt);
        }
        self.record_segment(cpu, i, index, t, dt, slack);
    }
}
