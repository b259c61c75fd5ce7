//! Blocking by lower-priority critical sections (issue 22): the B_i of
//! fixed-priority response-time analysis, R_i = J_i + w_i with
//! w_i = C_i + B_i + Σ_{j ∈ hp(i)} ⌈(w_i + J_j) / T_j⌉ · I_j
//! (Audsley, Burns, Richardson, Tindell, Wellings 1993; Burns and Wellings,
//! "Real-Time Systems and Programming Languages", the response-time
//! equation with blocking).
//!
//! The ceiling of a resource is the highest rank (smallest number) among
//! the tasks that use it; every user is on one CPU (validation). With
//! lp(i) the tasks of i's CPU ranked below i, and a section "able to block
//! i" when its resource's ceiling is at or above i's rank:
//!
//! - PCP and SRP (and the immediate ceiling the simulator runs):
//!   B_i = max over the sections of lp(i) able to block i of their length
//!   (Sha, Rajkumar, Lehoczky 1990, the priority ceiling protocol; Baker
//!   1991);
//! - PIP: B_i = min(Σ_{j ∈ lp(i)} max_{s ∈ j able to block i} |s|,
//!   Σ_k max_{j ∈ lp(i), s ∈ j on k able to block i} |s|): at most one
//!   section per lower-priority task and one per resource (Sha, Rajkumar,
//!   Lehoczky 1990, the basic inheritance protocol; sections are not
//!   nested).
//!
//! This module is the one home of the rule: `sched::response_times` adds it
//! to a job's own demand, `disturbance` adds a disturbance on top of it.

use rtpipe_model::{Nanos, ResourceProtocol, Spec};

/// Each resource's ceiling: the highest rank (smallest number) of a task
/// that uses it; `None` for a resource no ranked task uses.
pub fn ceilings(spec: &Spec, prio: &[Option<usize>]) -> Vec<Option<usize>> {
    let mut out: Vec<Option<usize>> = vec![None; spec.resources.len()];
    for (i, t) in spec.tasks.iter().enumerate() {
        for s in &t.sections {
            if let (Some(c), Some(p)) = (out.get_mut(s.resource), prio[i]) {
                *c = Some(c.map_or(p, |c| c.min(p)));
            }
        }
    }
    out
}

/// The highest rank task `i` can run at while it holds a resource (the
/// ceiling of the resources it uses, under every protocol: PIP raises it
/// at most to the rank of a user), or its own rank when it uses none.
pub fn locking_rank(spec: &Spec, prio: &[Option<usize>], i: usize) -> Option<usize> {
    let ceil = ceilings(spec, prio);
    spec.tasks[i]
        .sections
        .iter()
        .filter_map(|s| ceil.get(s.resource).copied().flatten())
        .fold(prio[i], |a, c| Some(a.map_or(c, |a| a.min(c))))
}

/// B_i: the longest time a job of task `i` can wait for lower-priority
/// tasks' critical sections under the spec's protocol (0 without
/// resources, for a background task, and for the lowest-ranked task).
pub fn blocking(spec: &Spec, prio: &[Option<usize>], i: usize) -> Nanos {
    let Some(own) = prio[i] else {
        return 0;
    };
    let ceil = ceilings(spec, prio);
    let cpu = spec.tasks[i].cpu;
    blocking_by(
        spec,
        |j| spec.tasks[j].cpu == cpu && prio[j].is_some_and(|p| p > own),
        |r| ceil.get(r).copied().flatten().is_some_and(|c| c <= own),
    )
}

/// The rule behind [`blocking`], given which tasks are ranked below the
/// blocked task on its CPU (`below`) and which resources have a ceiling at
/// or above its rank (`able`). Both the PCP/SRP maximum and each of PIP's
/// two sums only grow when `below` or `able` admit more, so predicates
/// that admit a subset of the true sets give a lower bound (what
/// `relax` takes over a box of periods).
pub fn blocking_by(
    spec: &Spec,
    below: impl Fn(usize) -> bool,
    able: impl Fn(usize) -> bool,
) -> Nanos {
    // (task, resource, length) of every section able to block i.
    let mut sections: Vec<(usize, usize, Nanos)> = Vec::new();
    for (j, t) in spec.tasks.iter().enumerate() {
        if !below(j) {
            continue;
        }
        for s in t.sections.iter().filter(|s| able(s.resource)) {
            sections.push((j, s.resource, s.length));
        }
    }
    match spec.resource_protocol {
        ResourceProtocol::Pcp | ResourceProtocol::Srp => {
            sections.iter().map(|&(_, _, l)| l).max().unwrap_or(0)
        }
        ResourceProtocol::Pip => {
            let per_task = sum_of_max(&sections, |&(j, _, _)| j);
            let per_resource = sum_of_max(&sections, |&(_, r, _)| r);
            per_task.min(per_resource)
        }
    }
}

/// Σ over the groups of `key` of the longest section in each.
fn sum_of_max(
    able: &[(usize, usize, Nanos)],
    key: impl Fn(&(usize, usize, Nanos)) -> usize,
) -> Nanos {
    let mut longest: std::collections::BTreeMap<usize, Nanos> = Default::default();
    for a in able {
        let e = longest.entry(key(a)).or_insert(0);
        *e = (*e).max(a.2);
    }
    longest.values().sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtpipe_model::policy::ranks;

    /// h (rank 1) uses r1 and r2; m (2) holds r1 for 2 and r3 for 4; l (3)
    /// holds r1 for 3, r2 for 1 and r3 for 5. r3's ceiling is m's rank, so
    /// r3 never blocks h. By hand:
    /// - PCP/SRP: B_h = max(2, 3, 1) = 3; B_m = max(3, 1, 5) = 5 (every
    ///   resource l uses has a ceiling at or above m); B_l = 0;
    /// - PIP: B_h = min(per task 2 + 3 = 5, per resource r1 max(2, 3) + r2
    ///   1 = 4) = 4; B_m = min(per task 5, per resource 3 + 1 + 5 = 9) = 5.
    #[test]
    fn the_rules_by_hand() {
        let src = |p: &str| {
            format!(
                "[system]\nname = \"b\"\nresource_protocol = \"{p}\"\n\
                 [resources.r1]\n[resources.r2]\n[resources.r3]\n\
                 [tasks.h]\nexec = 1\nperiod = 10\nserver = \"none\"\n\
                 critical_sections = [{{ resource = \"r1\", length = 0.5 }}, {{ resource = \"r2\", length = 0.5 }}]\n\
                 [tasks.m]\nexec = 6\nperiod = 20\nserver = \"none\"\n\
                 critical_sections = [{{ resource = \"r1\", length = 2 }}, {{ resource = \"r3\", length = 4 }}]\n\
                 [tasks.l]\nexec = 9\nperiod = 40\nserver = \"none\"\n\
                 critical_sections = [{{ resource = \"r1\", length = 3 }}, {{ resource = \"r2\", length = 1 }}, {{ resource = \"r3\", length = 5 }}]\n"
            )
        };
        let b = |p: &str| -> Vec<Nanos> {
            let spec = Spec::parse("b.toml", &src(p)).unwrap_or_else(|e| panic!("{e}"));
            let prio = ranks(&spec);
            (0..3)
                .map(|i| blocking(&spec, &prio, i) / 1_000_000)
                .collect()
        };
        assert_eq!(b("pcp"), vec![3, 5, 0]);
        assert_eq!(b("srp"), vec![3, 5, 0]);
        assert_eq!(b("pip"), vec![4, 5, 0]);
    }
}
