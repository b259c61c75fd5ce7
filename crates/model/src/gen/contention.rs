//! Critical sections and scheduling overheads added to a generated system
//!, for the property tests of the analysis' relaxation and the
//! design's brute-force agreement. What validation refuses is avoided:
//! sections only under fixed priorities, in plain tasks (`server =
//! "none"`), on resources of one CPU each; no PIP with overheads; with
//! overheads the exact tests (RTA under RM, the utilisation test under
//! EDF). The caller writes the spec as TOML and parses it back to be sure.

use super::Rng;
use crate::overheads::{Costs, CpuCosts};
use crate::{CriticalSection, Nanos, Resource, ResourceProtocol, SchedTest, Server, Spec};

/// What [`add_contention`] adds.
#[derive(Debug, Clone, Copy)]
pub struct Contention {
    /// Probability of critical sections (fixed priority only).
    pub sections: f64,
    /// Probability of overheads.
    pub overheads: f64,
    /// The largest context switch, release and replenishment cost (ns);
    /// each is drawn in [0, max] on a grid of max / 8.
    pub max_cost: Nanos,
}

/// Up to `count` critical sections for a task of `exec` ns, drawn in
/// order: each at most `share` = (num, den) of what the earlier ones left
/// (at least 1 ns), on the resource `pick` draws; none once less than 2 ns
/// is left. The one generator of sections, for this module and the
/// simulator's property tests.
pub fn random_sections(
    r: &mut Rng,
    exec: Nanos,
    count: u64,
    share: (Nanos, Nanos),
    mut pick: impl FnMut(&mut Rng) -> usize,
) -> Vec<CriticalSection> {
    let mut left = exec;
    let mut out = Vec::new();
    for _ in 0..count {
        if left < 2 {
            break;
        }
        let length = r.range(1, (left * share.0 / share.1) as u64) as Nanos;
        left -= length;
        out.push(CriticalSection {
            resource: pick(r),
            length,
        });
    }
    out
}

/// Draws the three costs, each in [0, max] on a grid of max / 8.
fn costs(r: &mut Rng, max: Nanos) -> Costs {
    let step = (max / 8).max(1);
    let mut one = || r.range(0, 8) as Nanos * step;
    Costs {
        context_switch: one(),
        release: one(),
        replenish: one(),
    }
}

/// Adds, each with its probability, critical sections (up to two per task
/// on two resources of its CPU, under PCP, SRP or PIP; no task serves
/// another, and a task with sections is plain, its server's budget
/// dropped) and overheads (the system's
/// costs, and for some systems the first task's CPU its own switch cost).
/// Returns (sections added, overheads added).
pub fn add_contention(spec: &mut Spec, r: &mut Rng, c: &Contention) -> (bool, bool) {
    let fixed = spec.policy().fixed_priority();
    let sections = fixed && r.chance(c.sections);
    let overheads = r.chance(c.overheads) && c.max_cost > 0;
    if sections {
        add_sections(spec, r, overheads);
    }
    if overheads {
        spec.overheads.system = costs(r, c.max_cost);
        if r.chance(0.3) {
            let own = costs(r, c.max_cost);
            spec.overheads.cpus.insert(
                spec.tasks[0].cpu,
                CpuCosts {
                    context_switch: Some(own.context_switch),
                    release: None,
                    replenish: None,
                },
            );
        }
        spec.schedulability = if fixed {
            SchedTest::Rta
        } else {
            SchedTest::Edf
        };
    }
    (sections, overheads)
}

/// Sections on two resources per CPU (2k and 2k + 1 on the k-th CPU in
/// ascending order), each at most half of what the task has left.
fn add_sections(spec: &mut Spec, r: &mut Rng, overheads: bool) {
    let protocols: &[ResourceProtocol] = if overheads {
        &[ResourceProtocol::Pcp, ResourceProtocol::Srp]
    } else {
        &ResourceProtocol::ALL
    };
    spec.resource_protocol = protocols[r.range(0, protocols.len() as u64 - 1) as usize];
    let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    cpus.sort_unstable();
    cpus.dedup();
    spec.resources = (0..2 * cpus.len())
        .map(|k| Resource {
            name: format!("r{k}"),
        })
        .collect();
    for t in spec.tasks.iter_mut() {
        // A served task may become plain: no inheritance with sections.
        t.serves = None;
        if t.server == Server::Background {
            continue;
        }
        let base = 2 * cpus.iter().position(|&c| c == t.cpu).unwrap_or(0);
        let count = r.range(0, 2);
        let sections = random_sections(r, t.exec, count, (1, 2), |r| base + r.range(0, 1) as usize);
        if !sections.is_empty() {
            t.sections.extend(sections);
            (t.server, t.budget_given) = (Server::None, None);
        }
    }
}
