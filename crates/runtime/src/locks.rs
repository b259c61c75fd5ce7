//! Critical sections on real threads, placed as the simulator
//! places them (`rtpipe_sim`'s locks.rs): a job runs its sections back to
//! back, in the spec's order, from the start of its processing (after Δin),
//! each cut at the job's demand. Synthetic bodies only: the runtime burns
//! Δin and the sections itself, the body the rest.
//!
//! Protocols, under SCHED_FIFO:
//! - PCP and SRP run as the immediate priority ceiling, as the simulator
//!   and the analysis (`rtpipe_analysis::blocking`) take them: on entry the
//!   thread raises its own priority to the resource's ceiling (the FIFO
//!   priority of its highest-ranked user, by `model::policy::ranks`), on
//!   exit it unlocks, then restores its priority (lowered, Linux puts it at
//!   the head of its priority's queue: sched(7)). A plain mutex keeps
//!   mutual exclusion; under the ceiling on one CPU it is never contended.
//!   Not a `PTHREAD_PRIO_PROTECT` mutex: glibc's fail to lock from a
//!   SCHED_OTHER thread, and best-effort runs must lock too;
//! - PIP: a `PTHREAD_PRIO_INHERIT` mutex ([`PiMutex`]): the kernel lends a
//!   waiter's priority to the holder.
//!
//! Under SCHED_OTHER there are no priorities to raise or lend: the sections
//! keep mutual exclusion only, and the run says so.

use crate::config::{fifo_priorities, Policy};
use crate::edf::Dispatcher;
use crate::pi::PiMutex;
use crate::spin::Spin;
use crate::sys;
use rtpipe_model::{Nanos, ResourceProtocol, Spec};
use std::sync::Mutex;

/// (what is wrong, how to fix it) when `spec` has critical sections under
/// a policy whose resource protocol the runtime cannot run: under EDF the
/// stack resource policy needs preemption levels and a system ceiling
/// that hold a job back from starting, which SCHED_DEADLINE does not
/// have (it picks by deadline alone, and a ceiling cannot be raised in
/// it as SCHED_FIFO's priority is); the EDF dispatcher (`crate::edf`,
/// [`Policy::EdfFifo`]) has them.
pub fn unrunnable(spec: &Spec, policy: Policy) -> Option<(&'static str, &'static str)> {
    let sections = spec.tasks.iter().any(|t| !t.sections.is_empty());
    (sections && !spec.policy().fixed_priority() && policy == Policy::Deadline).then_some((
        "critical sections under scheduler = \"edf\" (resource_protocol = \"srp\") with --policy deadline: SCHED_DEADLINE picks by deadline alone and has no preemption levels or system ceiling, so the stack resource policy cannot run in it",
        "drop --policy deadline: by default (--policy edf-fifo) rtpipe's EDF dispatcher runs the stack resource policy on SCHED_FIFO threads",
    ))
}

/// One critical section a job ran: which, and when it held its resource
/// (ns from the epoch: from just after the lock to just before the unlock).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Held {
    /// The job's index.
    pub job: u64,
    /// The resource (index into `Spec::resources`).
    pub resource: usize,
    /// Taken.
    pub enter: Nanos,
    /// Given back.
    pub exit: Nanos,
}

/// A resource's lock.
enum Lock {
    /// PCP/SRP: mutual exclusion; the ceiling is the thread's own doing.
    Plain(Mutex<()>),
    /// PIP: the kernel's priority inheritance.
    Inherit(PiMutex<()>),
}

/// Every resource of a run: its lock and its ceiling.
pub(crate) struct Resources {
    locks: Vec<Lock>,
    /// Per resource: the SCHED_FIFO priority of its highest-ranked user
    /// (`None`: no priority is raised, PIP or not SCHED_FIFO).
    ceiling: Vec<Option<i32>>,
    /// Under [`Policy::EdfFifo`]: the EDF dispatcher, which keeps the
    /// system ceilings of the stack resource policy.
    pub(crate) dispatch: Option<Dispatcher>,
}

impl Resources {
    /// The spec's resources for a run under `policy`.
    pub(crate) fn new(spec: &Spec, policy: Policy) -> std::io::Result<Resources> {
        let prio = fifo_priorities(spec);
        let raise = policy == Policy::Fifo && spec.resource_protocol != ResourceProtocol::Pip;
        let mut ceiling: Vec<Option<i32>> = vec![None; spec.resources.len()];
        for (i, t) in spec.tasks.iter().enumerate() {
            for s in &t.sections {
                if let (true, Some(c)) = (raise, ceiling.get_mut(s.resource)) {
                    *c = Some(c.map_or(prio[i], |c| c.max(prio[i])));
                }
            }
        }
        let locks = (0..spec.resources.len())
            .map(|_| match spec.resource_protocol {
                ResourceProtocol::Pip => PiMutex::new(()).map(Lock::Inherit),
                _ => Ok(Lock::Plain(Mutex::new(()))),
            })
            .collect::<std::io::Result<Vec<_>>>()?;
        let dispatch = (policy == Policy::EdfFifo).then(|| Dispatcher::new(spec));
        Ok(Resources {
            locks,
            ceiling,
            dispatch,
        })
    }

    /// Runs `length` of CPU time holding resource `r` for task `task`, the
    /// thread's own SCHED_FIFO priority being `own`: (taken, given back) on
    /// CLOCK_MONOTONIC, and whether every priority change succeeded. Under
    /// the EDF dispatcher the system ceiling rises before the lock and
    /// drops after it (the dispatcher then picks again).
    fn hold(
        &self,
        (task, r): (usize, usize),
        length: Nanos,
        own: Option<i32>,
        spin: &Spin,
    ) -> (Nanos, Nanos, bool) {
        let raise = self.ceiling[r].zip(own).filter(|&(c, o)| c > o);
        if let Some(d) = &self.dispatch {
            d.enter(r);
        }
        let mut ok = raise.is_none_or(|(c, _)| sys::set_priority(c).is_ok());
        let (enter, exit) = match &self.locks[r] {
            Lock::Plain(m) => {
                let _g = m.lock().unwrap_or_else(|e| e.into_inner());
                burn_between(spin, length)
            }
            Lock::Inherit(m) => {
                let g = m.lock();
                ok &= g.is_ok();
                burn_between(spin, length)
            }
        };
        if let Some((_, o)) = raise {
            ok &= sys::set_priority(o).is_ok();
        }
        if let Some(d) = &self.dispatch {
            d.exit(task, r);
        }
        (enter, exit, ok)
    }
}

/// Burns `length`: the instants it started and ended.
fn burn_between(spin: &Spin, length: Nanos) -> (Nanos, Nanos) {
    let enter = sys::now();
    spin.burn(length);
    (enter, sys::now())
}

/// Where a job of a task with critical sections spends its demand, as the
/// simulator places it: Δin first, then the sections back to back in the
/// spec's order (cut at the demand), then the rest (the body's).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Plan {
    /// Δin, before the first section.
    pub(crate) lead: Nanos,
    /// (length, resource) in order.
    pub(crate) list: Vec<(Nanos, usize)>,
    /// The demand after the sections.
    pub(crate) rest: Nanos,
}

/// Task `i`'s plan; `None` when it has no sections.
pub(crate) fn plan(spec: &Spec, i: usize) -> Option<Plan> {
    let t = &spec.tasks[i];
    if t.sections.is_empty() {
        return None;
    }
    let demand = t.demand();
    let lead = t.delta_in.min(demand);
    let mut at = lead;
    let mut list = Vec::with_capacity(t.sections.len());
    for s in &t.sections {
        let end = (at + s.length).min(demand);
        list.push((end - at, s.resource));
        at = end;
    }
    assert!(at <= demand, "sections placed past the demand");
    Some(Plan {
        lead,
        list,
        rest: demand - at,
    })
}

/// One task's sections as its jobs run them.
pub(crate) struct Sections {
    /// The task.
    task: usize,
    spin: Spin,
    /// Δin, burnt before the first section.
    lead: Nanos,
    /// (length, resource) in order, cut at the demand.
    list: Vec<(Nanos, usize)>,
    /// Priority changes that failed (the kernel refused them).
    pub(crate) failed: u64,
    /// Every section held, in order (room for every job: no allocation in
    /// the periodic path).
    pub(crate) held: Vec<Held>,
}

impl Sections {
    /// Task `i`'s sections for `jobs` jobs; `None` when it has none. The
    /// rest of its demand is the body's: [`Sections::rest`].
    pub(crate) fn of(spec: &Spec, i: usize, spin: Spin, jobs: usize) -> Option<Sections> {
        let p = plan(spec, i)?;
        Some(Sections {
            task: i,
            spin,
            lead: p.lead,
            held: Vec::with_capacity(jobs * p.list.len()),
            list: p.list,
            failed: 0,
        })
    }

    /// What a job's body burns: after its sections, or all its demand.
    pub(crate) fn rest(spec: &Spec, i: usize) -> Nanos {
        plan(spec, i).map_or(spec.tasks[i].demand(), |p| p.rest)
    }

    /// Job `job`'s Δin and sections, at the thread's own priority `own`.
    pub(crate) fn run(&mut self, res: &Resources, job: u64, own: Option<i32>, epoch: Nanos) {
        self.spin.burn(self.lead);
        for &(length, r) in &self.list {
            let (enter, exit, ok) = res.hold((self.task, r), length, own, &self.spin);
            self.failed += u64::from(!ok);
            if self.held.len() < self.held.capacity() {
                self.held.push(Held {
                    job,
                    resource: r,
                    enter: enter - epoch,
                    exit: exit - epoch,
                });
            }
        }
    }
}

/// The run's note on what the protocol could do under `policy`.
pub(crate) fn note(spec: &Spec, policy: Policy) -> Option<String> {
    if spec.tasks.iter().all(|t| t.sections.is_empty()) {
        return None;
    }
    let name = spec.resource_protocol.name();
    Some(match policy {
        Policy::EdfFifo => "note: critical sections under the stack resource policy, run by rtpipe's EDF dispatcher on SCHED_FIFO (a job starts only as its CPU's earliest deadline and above its system ceiling)".into(),
        Policy::Other => format!(
            "note: resource_protocol = \"{name}\" not applied: SCHED_OTHER has no priorities to raise or lend; the critical sections keep mutual exclusion only, and the blocking bound does not hold"
        ),
        _ => match spec.resource_protocol {
            ResourceProtocol::Pip => "note: critical sections under priority inheritance (PTHREAD_PRIO_INHERIT mutexes)".into(),
            _ => format!("note: critical sections under the immediate priority ceiling (resource_protocol = \"{name}\"): a holder runs at its resource's ceiling"),
        },
    })
}

/// Per resource (of `resources`): how many sections held it, the longest
/// hold (wall time, preemptions included), and how many holds began
/// before the previous one on it ended (0 when mutual exclusion held).
pub fn summary(resources: usize, holds: &[Held]) -> Vec<(usize, Nanos, usize)> {
    let mut by: Vec<Vec<Held>> = vec![Vec::new(); resources];
    for h in holds {
        if let Some(v) = by.get_mut(h.resource) {
            v.push(*h);
        }
    }
    by.into_iter()
        .map(|mut v| {
            v.sort_by_key(|h| h.enter);
            let longest = v.iter().map(|h| h.exit - h.enter).max().unwrap_or(0);
            let overlaps = v.windows(2).filter(|w| w[1].enter < w[0].exit).count();
            (v.len(), longest, overlaps)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_counts_overlapping_holds() {
        let h = |resource, enter, exit| Held {
            job: 0,
            resource,
            enter,
            exit,
        };
        let holds = [h(0, 0, 5), h(0, 5, 9), h(1, 2, 4), h(0, 8, 10), h(1, 4, 5)];
        assert_eq!(summary(2, &holds), vec![(3, 5, 1), (2, 2, 0)]);
    }
}
