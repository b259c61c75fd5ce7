//! Explaining infeasibility: a small conflicting set of constraint groups
//! (deletion filter) and how far each chain limit would have to move.

use crate::api::{Conflict, Method};
use crate::budget::Budget;
use crate::frontier;
use crate::learnt::Learnt;
use crate::problem::{Group, Problem};
use crate::solve::{solve_master, Solved};
use crate::sound::{learn_r_cuts, SoundModel};
use rtpipe_analysis::{Anchor, Metric};
use rtpipe_model::{format_in, Nanos};

/// Whether each conflict probe gets a fair share of the remaining work
/// (else each may use all that is left, as the time-bounded search did).
pub(crate) const FAIR_SHARES: bool = false;

/// Whether `groups` can hold together: the master loop (tangent, RTA and
/// response-time cuts) restricted to them, until the master is
/// infeasible or a candidate needs no more cuts. Cuts learnt here are
/// valid everywhere and kept.
/// `None` when it could not be decided (time or iteration limit).
pub(crate) fn probe(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    sound: Option<&SoundModel>,
) -> Option<bool> {
    if p.method == Method::Boxes {
        return frontier::probe(p, budget, groups);
    }
    let mut sm = sound.cloned();
    for _ in 0..100 {
        if budget.out_of_time() {
            return None;
        }
        let periods = match solve_master(p, learnt, budget, groups, sm.as_ref()) {
            Solved::Infeasible => return Some(false),
            Solved::Error(_) | Solved::Stopped => return None,
            Solved::Periods {
                periods,
                responses: rmodel,
                ..
            } => {
                let cand = p.with_periods(&periods);
                let report = rtpipe_analysis::analyze(&cand);
                let oa = learnt.oa_exact(p, &periods);
                let verified = report.schedulability.schedulable && p.limits_ok(&report);
                if !verified && learnt.raise_levels(p, &cand, &report) {
                    continue;
                }
                let sched_needed = groups.iter().any(|g| matches!(g, Group::Sched(_)));
                let sched = !sched_needed || learnt.sched_ok(p, &cand, &report);
                if !oa || !sched {
                    continue;
                }
                match &mut sm {
                    None => return Some(true),
                    Some(m) => {
                        if !learn_r_cuts(p.g, &cand, &report, &periods, &rmodel, m) {
                            return Some(true);
                        }
                    }
                }
                periods
            }
        };
        let _ = periods;
    }
    None
}

/// A small set of constraint groups that cannot hold together (deletion
/// filter) and, for each, how far it would have to move.
/// Also says whether every probe was decided (the set is minimal).
pub(crate) fn explain(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    sound: Option<&SoundModel>,
) -> (Vec<Conflict>, bool) {
    let (core, decided) = deletion_filter(p, learnt, budget, groups, sound);
    let conflicts = core
        .iter()
        .map(|&gr| conflict(p, learnt, budget, groups, gr, sound))
        .collect();
    (conflicts, decided)
}

/// Drops every group whose removal provably keeps the conflict; says
/// whether every probe was decided.
fn deletion_filter(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    sound: Option<&SoundModel>,
) -> (Vec<Group>, bool) {
    let mut core: Vec<Group> = groups.to_vec();
    let mut k = 0;
    let mut decided = true;
    // Under a work budget each probe gets a fair share of what is left
    // (one share kept for the fixes), so one hard probe cannot starve
    // the others.
    let cap0 = budget.work_cap;
    while k < core.len() {
        if budget.out_of_time() {
            decided = false;
            break;
        }
        if let (Some(cap), true) = (cap0, FAIR_SHARES) {
            let share = cap.saturating_sub(budget.work) / (core.len() - k + 1) as u64;
            budget.work_cap = Some(budget.work.saturating_add(share.max(1)).min(cap));
        }
        p.say(|| {
            format!(
                "infeasible; finding the conflicting constraints ({} of {} left to test)",
                core.len() - k,
                groups.len()
            )
        });
        let mut trial = core.clone();
        trial.remove(k);
        // Keep the group unless dropping it provably keeps the conflict.
        let verdict = probe(p, learnt, budget, &trial, sound);
        budget.work_cap = cap0;
        decided &= verdict.is_some();
        if verdict == Some(false) {
            core = trial;
        } else {
            k += 1;
        }
    }
    (core, decided)
}

/// One group of the conflicting set, said for the user, with its fix.
fn conflict(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    gr: Group,
    sound: Option<&SoundModel>,
) -> Conflict {
    let spec = p.spec;
    let (c, metric) = match gr {
        Group::Limit(c, metric) => (c, metric),
        Group::Sched(cpu) => {
            return Conflict {
                constraint: format!("cpu {cpu}: {} schedulability", spec.schedulability.name()),
                fix: Some(
                    "lower the utilisation of its tasks (budgets) or move tasks to another CPU"
                        .into(),
                ),
            }
        }
    };
    let ch = &spec.chains[c];
    let name = ch.name.clone().unwrap_or_else(|| {
        ch.path
            .iter()
            .map(|&i| spec.tasks[i].name.as_str())
            .collect::<Vec<_>>()
            .join(">")
    });
    p.say(|| format!("infeasible; how far must {name} move"));
    // The group holds the metric's limits from both anchors: name each, and
    // raise the first whose raise makes the core feasible.
    let limits: Vec<(Anchor, Nanos)> = Anchor::ALL
        .into_iter()
        .filter_map(|a| Some((a, metric.limit(ch, a)?)))
        .collect();
    let fix = limits.iter().find_map(|&(a, limit)| {
        let need = min_limit(p, learnt, budget, groups, gr, a, sound)?;
        Some(format!(
            "raise the {} limit from {} to {} {} (within a thousandth of the time unit; other constraints unchanged)",
            limit_name(metric, a),
            format_in(limit, spec.time_unit),
            format_in(need, spec.time_unit),
            spec.time_unit
        ))
    });
    let said: Vec<String> = limits
        .iter()
        .map(|&(a, l)| {
            format!(
                "{} ≤ {}",
                limit_name(metric, a),
                format_in(l, spec.time_unit)
            )
        })
        .collect();
    Conflict {
        constraint: format!("chain {name}: {}", said.join(", ")),
        fix,
    }
}

/// How a conflict names a limit: the metric from the read (as before the
/// from-event limits), the spec key from the event.
fn limit_name(metric: Metric, anchor: Anchor) -> &'static str {
    match anchor {
        Anchor::Read => metric.name(),
        Anchor::Event => metric.key(anchor),
    }
}

/// The smallest limit of chain group `gr` that makes `core` feasible,
/// by bisection on its limit from `anchor` (in grid units).
#[allow(clippy::too_many_arguments)]
pub(crate) fn min_limit(
    p: &Problem,
    learnt: &Learnt,
    budget: &mut Budget,
    core: &[Group],
    gr: Group,
    anchor: Anchor,
    sound: Option<&SoundModel>,
) -> Option<Nanos> {
    let Group::Limit(c, metric) = gr else {
        return None;
    };
    let original = p.spec.clone();
    let lo0 = metric.limit(&original.chains[c], anchor)?;
    let mut hi = lo0.max(1);
    // Whether `core` holds with the limit at l, by a sub-search on a
    // copy of the spec that shares what was learnt.
    let feasible = |budget: &mut Budget, l: Nanos| -> Option<bool> {
        let mut s = original.clone();
        let ch = &mut s.chains[c];
        *match (metric, anchor) {
            (Metric::Reaction, Anchor::Read) => &mut ch.reaction,
            (Metric::Freshness, Anchor::Read) => &mut ch.freshness,
            (Metric::Reaction, Anchor::Event) => &mut ch.max_reaction_time,
            (Metric::Freshness, Anchor::Event) => &mut ch.freshness_from_event,
        } = Some(l);
        let sub = p.with_limit(&s, l);
        let mut sub_learnt = learnt.for_sub();
        let mut sub_budget = budget.sub();
        let r = probe(&sub, &mut sub_learnt, &mut sub_budget, core, sound);
        // The sub-search's work counts against the budget.
        budget.absorb(&sub_budget);
        r
    };
    // Find a feasible upper end by doubling. Any undecided probe makes
    // the answer unknown: say nothing then.
    let mut tries = 0;
    while !feasible(budget, hi)? {
        hi = hi.saturating_mul(2);
        tries += 1;
        if tries > 20 || budget.out_of_time() {
            return None;
        }
    }
    let mut lo = lo0;
    let step = (p.spec.time_unit.nanos() / 1000).max(1);
    while hi - lo > step {
        if budget.out_of_time() {
            return None;
        }
        let mid = lo + (hi - lo) / 2;
        if feasible(budget, mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}
