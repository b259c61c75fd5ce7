//! Constrained deadlines, deadline-monotonic or explicit priorities and
//! the processor-demand test added to a generated system, for
//! the property tests of the analysis' relaxation and the design's
//! brute-force agreement. What validation refuses is avoided: a deadline
//! lies in [C, the task's least possible period]; deadline-monotonic and
//! explicit priorities only under a fixed-priority scheduler with the
//! exact test (RTA); QPA only under EDF. The caller writes the spec as
//! TOML and parses it back to be sure.

use super::Rng;
use crate::{Nanos, PeriodSpec, Priorities, SchedTest, Server, Spec};

/// What [`add_timing`] set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Timing {
    /// Tasks that got a deadline.
    pub deadlines: usize,
    /// The priority order set (fixed priority only).
    pub priorities: Option<Priorities>,
    /// `schedulability = "qpa"` was set (EDF only).
    pub qpa: bool,
}

/// The least period task `i` can have, when its period is bounded below.
fn least_period(spec: &Spec, i: usize) -> Option<Nanos> {
    match &spec.tasks[i].period {
        PeriodSpec::Fixed(p) => Some(*p),
        PeriodSpec::Choices(c) => c.iter().copied().min(),
        PeriodSpec::Range { min, .. } => *min,
        _ => None,
    }
}

/// Under a fixed-priority scheduler with RTA: deadline-monotonic (with a
/// deadline on about half the tasks) or explicit priorities (a random
/// order per CPU, deadlines on some tasks), each half the time. Under
/// EDF: deadlines on about half the tasks and QPA. Each deadline is drawn
/// in [max(C, P/2), P] for the task's least period P.
pub fn add_timing(spec: &mut Spec, r: &mut Rng) -> Timing {
    let mut out = Timing::default();
    let fixed = spec.policy().fixed_priority();
    if fixed && spec.schedulability != SchedTest::Rta {
        return out;
    }
    for i in 0..spec.tasks.len() {
        let t = &spec.tasks[i];
        let Some(p) = least_period(spec, i) else {
            continue;
        };
        // Validation wants D ≤ P, and a deadline below C is never met.
        if t.server == Server::Background || p < t.budget() || !r.chance(0.5) {
            continue;
        }
        let lo = t.budget().max(p / 2);
        spec.tasks[i].deadline_given = Some(lo + r.range(0, (p - lo) as u64) as Nanos);
        out.deadlines += 1;
    }
    if !fixed {
        spec.schedulability = SchedTest::Qpa;
        out.qpa = true;
        return out;
    }
    let order = if r.chance(0.5) {
        Priorities::DeadlineMonotonic
    } else {
        Priorities::Explicit
    };
    spec.priorities = order;
    out.priorities = Some(order);
    if order == Priorities::Explicit {
        explicit_priorities(spec, r);
    }
    out
}

/// A random permutation of 1..=n as the priorities of each CPU's n
/// guaranteed tasks.
fn explicit_priorities(spec: &mut Spec, r: &mut Rng) {
    let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    cpus.sort_unstable();
    cpus.dedup();
    for cpu in cpus {
        let ids: Vec<usize> = (0..spec.tasks.len())
            .filter(|&i| spec.tasks[i].cpu == cpu && spec.tasks[i].server != Server::Background)
            .collect();
        let mut prio: Vec<u32> = (1..=ids.len() as u32).collect();
        // Fisher–Yates.
        for k in (1..prio.len()).rev() {
            let j = r.range(0, k as u64) as usize;
            prio.swap(k, j);
        }
        for (&i, &p) in ids.iter().zip(&prio) {
            spec.tasks[i].priority = Some(p);
        }
    }
}
