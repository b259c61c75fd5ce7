//! Shared resources on the simulated schedule: each task's
//! critical sections, who holds each resource, who waits for it, and the
//! priority a holder runs at.
//!
//! Placement: a job runs its sections back to back, in the spec's order,
//! from the start of its processing (after Δin): section k covers the
//! job's progress [Δin + Σ_{l<k} |s_l|, Δin + Σ_{l≤k} |s_l|), cut at the
//! job's demand (a job shorter than its sections runs them cut). Placing
//! them first makes a lower-priority job hold its resource as soon as it
//! starts, which is where the blocking bound is reached.
//!
//! Protocols, under fixed priorities (keys are 2·rank, so 2·rank − 1 sits
//! just above a rank, ahead of its task):
//! - PCP and SRP run as the immediate priority ceiling: a holder's key is
//!   at most 2·ceiling − 1. A job then never finds its resource held on a
//!   uniprocessor (validation keeps resources on one CPU and their users
//!   unbudgeted), and waits at most one section before it starts;
//! - PIP: a job that reaches a section whose resource is held waits (it is
//!   no contender) and the holder's key is at most 2·rank − 1 of every
//!   waiter; at the release every waiter contends again and the first to
//!   run takes the resource.
//!
//! Under EDF, the stack resource policy (Baker 1991), keys unchanged (the
//! absolute deadline): a job that has not started may start only when it
//! is the first contender of its CPU and its preemption level
//! (`rtpipe_model::policy::preemption_levels`) is above the system ceiling,
//! the highest ceiling of the resources held on the CPU; when the first
//! contender may not, the first contender that has started runs (the job
//! on top of the stack, which holds the resource). A job then never finds
//! its resource held, and the ceiling drops only when a section ends,
//! where the CPU picks again.

use crate::engine::Job;
use rtpipe_model::policy::{ranks, srp_levels, srp_may_start};
use rtpipe_model::{Nanos, ResourceProtocol, Spec};

pub(crate) struct Locks {
    /// The holder's key is capped by the ceiling (PCP, SRP), or by its
    /// waiters' ranks (PIP).
    ceiling_protocol: bool,
    /// Per resource: 2·ceiling − 1 (the best key of a holder under PCP/SRP).
    ceiling: Vec<Nanos>,
    /// Per resource: the task whose front job holds it.
    pub(crate) holder: Vec<Option<usize>>,
    /// Per resource: the tasks waiting for it (PIP only).
    waiters: Vec<Vec<usize>>,
    /// Per task: its sections as (start, end, resource) in progress.
    sections: Vec<Vec<(Nanos, Nanos, usize)>>,
    /// Per task: the section its front job is in while it holds the
    /// section's resource, as (section, resource): two sections in a row
    /// on one resource are two acquisitions.
    pub(crate) holding: Vec<Option<(usize, usize)>>,
    /// Per task: the resource its front job waits for.
    pub(crate) waiting: Vec<Option<usize>>,
    /// Per task: its rank (the waiters' under PIP).
    rank: Vec<Nanos>,
    /// Some task has a section (asked at every instant: kept, not scanned).
    active: bool,
    /// The stack resource policy under EDF.
    srp: bool,
    /// Per task: its preemption level as a rank, 1 the highest (EDF).
    level: Vec<Nanos>,
    /// Per resource: the best level rank of its users (EDF).
    srp_ceiling: Vec<Nanos>,
}

impl Locks {
    pub(crate) fn new(spec: &Spec) -> Locks {
        let rk: Vec<Nanos> = ranks(spec)
            .iter()
            .enumerate()
            .map(|(i, r)| r.map_or(i as Nanos, |r| r as Nanos))
            .collect();
        let mut ceiling = vec![Nanos::MAX; spec.resources.len()];
        let mut sections = Vec::with_capacity(spec.tasks.len());
        for (i, t) in spec.tasks.iter().enumerate() {
            let mut at = t.delta_in;
            let mut own = Vec::new();
            for s in &t.sections {
                own.push((at, at + s.length, s.resource));
                at += s.length;
                if let Some(c) = ceiling.get_mut(s.resource) {
                    *c = (*c).min(2 * rk[i] - 1);
                }
            }
            sections.push(own);
        }
        let n = spec.tasks.len();
        let active = sections.iter().any(|s: &Vec<_>| !s.is_empty());
        let srp =
            !spec.policy().fixed_priority() && spec.resource_protocol == ResourceProtocol::Srp;
        let (level, srp_ceiling) = srp_levels(spec);
        Locks {
            ceiling_protocol: spec.resource_protocol != ResourceProtocol::Pip,
            holder: vec![None; ceiling.len()],
            waiters: vec![Vec::new(); ceiling.len()],
            ceiling,
            sections,
            holding: vec![None; n],
            waiting: vec![None; n],
            rank: rk,
            active,
            srp,
            level,
            srp_ceiling,
        }
    }

    /// The stack resource policy runs (EDF with sections).
    pub(crate) fn srp(&self) -> bool {
        self.srp && self.active
    }

    /// Task i has a critical section.
    pub(crate) fn has_sections(&self, i: usize) -> bool {
        !self.sections[i].is_empty()
    }

    /// Some task has a critical section.
    pub(crate) fn any(&self) -> bool {
        self.active
    }

    /// The section `job` of task i is in, if any, as (section, resource).
    pub(crate) fn section_at(&self, i: usize, job: &Job) -> Option<(usize, usize)> {
        let p = job.demand - job.remaining;
        self.sections[i]
            .iter()
            .position(|&(s, e, _)| s <= p && p < e.min(job.demand))
            .map(|k| (k, self.sections[i][k].2))
    }

    /// How much more `job` of task i runs before it enters or leaves a
    /// section (`None`: no boundary ahead).
    pub(crate) fn until_boundary(&self, i: usize, job: &Job) -> Option<Nanos> {
        let p = job.demand - job.remaining;
        self.sections[i]
            .iter()
            .flat_map(|&(s, e, _)| [s, e.min(job.demand)])
            .filter(|&b| b > p && b <= job.demand)
            .min()
            .map(|b| b - p)
    }

    /// The key of task i, whose own fixed-priority key is `base`: raised
    /// while it holds a resource.
    pub(crate) fn key(&self, i: usize, base: Nanos) -> Nanos {
        let Some((_, r)) = self.holding[i] else {
            return base;
        };
        if self.ceiling_protocol {
            return base.min(self.ceiling[r]);
        }
        self.waiters[r]
            .iter()
            .map(|&w| 2 * self.rank[w] - 1)
            .fold(base, Nanos::min)
    }

    /// Task i's front job, picked to run, is at its section `k` on `r`: it
    /// takes the resource (`None`), or waits for its holder (`Some(holder)`).
    pub(crate) fn acquire(&mut self, i: usize, (k, r): (usize, usize)) -> Option<usize> {
        // Under the stack resource policy a job starts only above the
        // ceiling of every held resource, its own included.
        assert!(
            !self.srp || self.holder[r].is_none(),
            "SRP: task {i} finds resource {r} held"
        );
        match self.holder[r] {
            None => {
                self.holder[r] = Some(i);
                self.holding[i] = Some((k, r));
                None
            }
            Some(h) => {
                self.waiting[i] = Some(r);
                self.waiters[r].push(i);
                Some(h)
            }
        }
    }

    /// Task i gives its resource back: the tasks that waited for it.
    pub(crate) fn release(&mut self, i: usize) -> Vec<usize> {
        let Some((_, r)) = self.holding[i].take() else {
            return Vec::new();
        };
        self.holder[r] = None;
        let woken = std::mem::take(&mut self.waiters[r]);
        for &w in &woken {
            self.waiting[w] = None;
        }
        woken
    }
}

impl<H: crate::engine::Hooks> crate::engine::Sim<H> {
    /// Under the stack resource policy, when `first` (the first contender
    /// of `cpu`) may not start: the first contender that has started,
    /// which then runs instead. `None` when `first` may run.
    pub(crate) fn srp_instead(&self, cpu: usize, first: usize) -> Option<usize> {
        let started = |i: usize| {
            self.tasks[i]
                .queue
                .front()
                .is_some_and(|j| j.read.is_some())
        };
        // The system ceiling: the best ceiling of a resource held on cpu.
        let ceiling = (0..self.locks.holder.len())
            .filter(|&r| self.locks.holder[r].is_some_and(|h| self.tasks[h].cpu as usize == cpu))
            .map(|r| self.locks.srp_ceiling[r])
            .min();
        if srp_may_start(started(first), self.locks.level[first], ceiling) {
            return None;
        }
        let top = self.contenders[cpu]
            .iter()
            .map(|&(_, _, i)| i)
            .find(|&i| started(i));
        assert!(
            top.is_some(),
            "SRP: a resource held on cpu {cpu} by no started job"
        );
        top
    }

    /// The running jobs at a section they do not hold take its resource or
    /// wait for it; true when one waits (its CPU must pick again).
    pub(crate) fn lock_step(&mut self, t: Nanos) -> bool {
        let mut again = false;
        for cpu in 0..self.running.len() {
            let Some(i) = self.running[cpu] else { continue };
            let Some(job) = self.tasks[i].queue.front() else {
                continue;
            };
            if self.ovh.lead(cpu) > 0 {
                // Not yet running its own work (overheads first).
                continue;
            }
            let Some(at) = self.locks.section_at(i, job) else {
                continue;
            };
            if self.locks.holding[i] == Some(at) {
                continue;
            }
            match self.locks.acquire(i, at) {
                None => self.refresh(i, t),
                Some(h) => {
                    self.refresh(i, t);
                    self.refresh(h, t);
                    again = true;
                }
            }
        }
        again
    }

    /// Task i's front job has run to t: it gives back a resource whose
    /// section it has left, and the tasks that waited for it contend again.
    pub(crate) fn unlock_passed(&mut self, i: usize, t: Nanos) {
        let Some(held) = self.locks.holding[i] else {
            return;
        };
        let inside = self.tasks[i]
            .queue
            .front()
            .and_then(|job| self.locks.section_at(i, job));
        if inside == Some(held) {
            return;
        }
        for w in self.locks.release(i) {
            self.refresh(w, t);
        }
        self.refresh(i, t);
        if self.locks.srp() {
            // The system ceiling dropped: a blocked job may start.
            self.mark(self.tasks[i].cpu as usize);
        }
    }
}
