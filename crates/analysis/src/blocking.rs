//! Blocking by lower-priority critical sections: the B_i of
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
//! Under EDF with the stack resource policy (Baker 1991), the blocking a
//! deadline interval of length t can hold is Baruah's
//! b(t) = max { |s| : s a section of a task j with D_j > t, on a resource
//! used by some task k with D_k ≤ t } ([`srp_steps`], [`srp_at`]; Baruah,
//! "Resource sharing in EDF-scheduled systems: a closer look", RTSS 2006):
//! at most one job, released before the interval with its deadline after
//! it, runs in it, and only for the rest of one section on a resource whose
//! ceiling is at or above the level of a job the interval holds
//! (docs/analysis.md, "Shared resources under EDF").
//!
//! This module is the one home of the rules: `sched::response_times` adds
//! B_i to a job's own demand, `disturbance` adds a disturbance on top of
//! it; `qpa` (h(t) + b(t) ≤ t), `sched` (Baker's density test) and `edf`
//! (Spuri's busy window) take b(t) from here.

use rtpipe_model::{Nanos, ResourceProtocol, Server, Spec};

/// The tasks of `cpu` (background ones included), in declaration order,
/// by a scan of the system: for callers that ask about one CPU without the
/// index of tasks by CPU (the design's relaxation, one box at a time).
pub(crate) fn tasks_on(spec: &Spec, cpu: u32) -> Vec<usize> {
    (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].cpu == cpu)
        .collect()
}

/// The guaranteed tasks among `on` (every one but a background task, which
/// has no timing guarantee), in its order: the tasks a CPU's verdict and
/// its bounds are about.
pub(crate) fn guaranteed(spec: &Spec, on: &[usize]) -> Vec<usize> {
    on.iter()
        .copied()
        .filter(|&j| spec.tasks[j].server != Server::Background)
        .collect()
}

/// Each resource's ceiling: the highest rank (smallest number) of a task
/// that uses it; `None` for a resource no ranked task uses.
pub fn ceilings(spec: &Spec, prio: &[Option<usize>]) -> Vec<Option<usize>> {
    let mut out: Vec<Option<usize>> = vec![None; spec.resources.len()];
    // Without resources no task has a section (validation): no scan.
    if spec.resources.is_empty() {
        return out;
    }
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
    locking_rank_with(spec, prio, &ceilings(spec, prio), i)
}

/// [`locking_rank`] given the [`ceilings`], computed once for every task.
pub fn locking_rank_with(
    spec: &Spec,
    prio: &[Option<usize>],
    ceil: &[Option<usize>],
    i: usize,
) -> Option<usize> {
    spec.tasks[i]
        .sections
        .iter()
        .filter_map(|s| ceil.get(s.resource).copied().flatten())
        .fold(prio[i], |a, c| Some(a.map_or(c, |a| a.min(c))))
}

/// B_i: the longest time a job of task `i` can wait for lower-priority
/// tasks' critical sections under the spec's protocol (0 without
/// resources, for a background task, and for the lowest-ranked task).
///
/// Under EDF (the stack resource policy) B_i = b(D_i) ([`srp_at`]): what
/// a job of i can wait before it starts when its deadline interval starts
/// at its release (Baker's B_i of the density test); the busy-window
/// analysis (`edf.rs`) takes b at every interval length instead.
pub fn blocking(spec: &Spec, prio: &[Option<usize>], i: usize) -> Nanos {
    if spec.resources.is_empty() {
        return 0;
    }
    let on = tasks_on(spec, spec.tasks[i].cpu);
    let srp = if spec.policy().fixed_priority() {
        Vec::new()
    } else {
        srp_spec_steps_among(spec, &on)
    };
    blocking_with(spec, prio, &ceilings(spec, prio), (&on, &srp), i)
}

/// [`blocking`] given the [`ceilings`], the tasks of i's CPU (`on`) and,
/// under EDF, the CPU's b(t) ([`srp_spec_steps_among`]; ignored under
/// fixed priority), all computed once for every task: the analysis' path,
/// linear in the tasks of one CPU rather than of the system.
pub fn blocking_with(
    spec: &Spec,
    prio: &[Option<usize>],
    ceil: &[Option<usize>],
    (on, srp): (&[usize], &[(Nanos, Nanos)]),
    i: usize,
) -> Nanos {
    // Without resources no task has a section (validation): no blocking.
    if spec.resources.is_empty() {
        return 0;
    }
    let t = &spec.tasks[i];
    if !spec.policy().fixed_priority() {
        if t.server == Server::Background {
            return 0;
        }
        let d = t.deadline().unwrap_or(rtpipe_model::MAX_TIME);
        return srp_at(srp, d);
    }
    let Some(own) = prio[i] else {
        return 0;
    };
    let cpu = t.cpu;
    blocking_among(
        spec,
        on.iter().copied(),
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
    blocking_among(spec, 0..spec.tasks.len(), below, able)
}

/// [`blocking_by`] over the tasks `candidates` only (a superset of those
/// `below` admits).
fn blocking_among(
    spec: &Spec,
    candidates: impl Iterator<Item = usize>,
    below: impl Fn(usize) -> bool,
    able: impl Fn(usize) -> bool,
) -> Nanos {
    // (task, resource, length) of every section able to block i.
    let mut sections: Vec<(usize, usize, Nanos)> = Vec::new();
    for j in candidates {
        if !below(j) {
            continue;
        }
        for s in spec.tasks[j].sections.iter().filter(|s| able(s.resource)) {
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

/// Baruah's b(t) on one CPU under EDF with the stack resource policy, as
/// steps `(θ, b(θ))` at every distinct relative deadline θ of the CPU's
/// guaranteed tasks, ascending ([`srp_at`] reads it), from `deadline(j)`,
/// each task's relative deadline. `on`: the tasks of the CPU (from the
/// index of tasks by CPU, `rtpipe_model::TasksByCpu`, so that nothing
/// scans the system). Empty when no task of the CPU has a section.
pub fn srp_steps(
    spec: &Spec,
    on: &[usize],
    deadline: impl Fn(usize) -> Nanos,
) -> Vec<(Nanos, Nanos)> {
    // Asked for every CPU and every box of the design: nothing to build
    // (or allocate) on a CPU without sections, nor scan without resources.
    if spec.resources.is_empty() || on.iter().all(|&j| spec.tasks[j].sections.is_empty()) {
        return Vec::new();
    }
    let on: Vec<(usize, Nanos)> = on
        .iter()
        .filter(|&&j| spec.tasks[j].server != Server::Background)
        .map(|&j| (j, deadline(j)))
        .collect();
    let mut thetas: Vec<Nanos> = on.iter().map(|&(_, d)| d).collect();
    thetas.sort_unstable();
    thetas.dedup();
    let used_by_some = |r: usize, t: Nanos| {
        on.iter()
            .any(|&(k, d)| d <= t && spec.tasks[k].sections.iter().any(|s| s.resource == r))
    };
    thetas
        .into_iter()
        .map(|t| {
            let b = on
                .iter()
                .filter(|&&(_, d)| d > t)
                .flat_map(|&(j, _)| spec.tasks[j].sections.iter())
                .filter(|s| used_by_some(s.resource, t))
                .map(|s| s.length)
                .max()
                .unwrap_or(0);
            (t, b)
        })
        .collect()
}

/// [`srp_steps`] on `cpu` with the spec's relative deadlines (D, else T;
/// a task without a fixed period counts as never released), its tasks
/// found by a scan of the system (the analysis takes them from its index,
/// [`srp_spec_steps_among`]).
pub fn srp_spec_steps(spec: &Spec, cpu: u32) -> Vec<(Nanos, Nanos)> {
    srp_spec_steps_among(spec, &tasks_on(spec, cpu))
}

/// [`srp_spec_steps`] given the tasks of the CPU (`on`).
pub fn srp_spec_steps_among(spec: &Spec, on: &[usize]) -> Vec<(Nanos, Nanos)> {
    srp_steps(spec, on, |j| {
        spec.tasks[j].deadline().unwrap_or(rtpipe_model::MAX_TIME)
    })
}

/// b(t) from [`srp_steps`]: the value of the last step at or below t (0
/// below the first, and for no steps).
pub fn srp_at(steps: &[(Nanos, Nanos)], t: Nanos) -> Nanos {
    let k = steps.partition_point(|&(theta, _)| theta <= t);
    if k == 0 {
        0
    } else {
        steps[k - 1].1
    }
}

/// The largest b(t) of [`srp_steps`] (0 for none).
pub fn srp_max(steps: &[(Nanos, Nanos)]) -> Nanos {
    steps.iter().map(|&(_, b)| b).max().unwrap_or(0)
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
        // Under EDF (D = T = 10, 20, 40), Baruah's b(t): b(10) = the
        // longest section of m or l on a resource h uses (r1, r2):
        // max(2, 3, 1) = 3; b(20) = every section of l, its resources all
        // used by h or m: max(3, 1, 5) = 5; b(40) = 0.
        let edf = src("srp").replace("name = \"b\"", "name = \"b\"\nscheduler = \"edf\"");
        let spec = Spec::parse("b.toml", &edf).unwrap_or_else(|e| panic!("{e}"));
        let ms = 1_000_000;
        assert_eq!(
            srp_spec_steps(&spec, 0),
            vec![(10 * ms, 3 * ms), (20 * ms, 5 * ms), (40 * ms, 0)]
        );
        assert_eq!(srp_at(&srp_spec_steps(&spec, 0), 9 * ms), 0);
        let prio = vec![None; 3];
        let got: Vec<Nanos> = (0..3).map(|i| blocking(&spec, &prio, i) / ms).collect();
        assert_eq!(got, vec![3, 5, 0]);
        assert_eq!(b("srp"), vec![3, 5, 0]);
        assert_eq!(b("pip"), vec![4, 5, 0]);
    }
}
