//! The whole design by box search: a first design by local search, the
//! search (`bnb`), and on infeasibility the conflicting constraints.

use crate::api::{DesignError, Outcome, Status, EXPLAIN_EFFORT};
use crate::budget::Budget;
use crate::explain::explain;
use crate::frontier;
use crate::heuristic::descent;
use crate::learnt::Learnt;
use crate::problem::{Group, Problem};

/// Boxes the search may examine per unit of [`Options::patience`](crate::api::Options::patience)
/// once it holds a verified design (without a time limit).
const BOX_WORK_PER_PATIENCE: u64 = 10;

/// The design of `p` by box search, spending from `budget` (`learnt` serves
/// the conflict search only).
pub(crate) fn solve_boxes(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
) -> Result<Outcome, DesignError> {
    let groups = p.all_groups();
    let seed = descent(p, budget);
    if let Some((spec, _, u)) = &seed {
        frontier::publish(p, spec, *u, 0.0);
    }
    cap_work(p, budget);
    let mut found = frontier::search(p, budget, &groups, seed);
    budget.iterations = found.nodes as usize;
    let mut notes = Vec::new();
    let checked = std::mem::take(&mut found.checked);
    let rejected = checked.iter().filter(|c| c.failure.is_some()).count();
    if rejected > 0 {
        notes.push(format!(
            "{rejected} verified design(s) failed the acceptance check and were cut, each with every design no faster than {:.0} % of it (docs/design.md, `--fly`)",
            100.0 * (1.0 - crate::gate::CUT_MARGIN)
        ));
    }
    let mut o = match (found.best, found.complete) {
        (Some((spec, report, u)), complete) => {
            let status = if complete {
                Status::Optimal
            } else {
                notes.push(stop_reason(budget, checked.len()));
                Status::Feasible
            };
            let lb = if complete {
                u
            } else {
                found.lower_bound.min(u)
            };
            let mut o =
                budget.outcome(p, status, Some((spec, report)), Some(lb), Vec::new(), notes);
            o.objective = Some(u);
            o.gap = Some(if u > 0.0 {
                ((u - lb) / u).max(0.0)
            } else {
                0.0
            });
            o
        }
        (None, true) if rejected > 0 => {
            notes.push("every verified design outside the cuts failed the acceptance check: none is both verified and accepted".into());
            budget.outcome(p, Status::Unknown, None, None, Vec::new(), notes)
        }
        (None, true) => infeasible(p, learnt, budget, &groups, notes),
        (None, false) => {
            notes.push(format!(
                "stopped ({}) before a verified design",
                stop_cause(budget, checked.len())
            ));
            let mut o = budget.outcome(p, Status::Unknown, None, None, Vec::new(), notes);
            o.lower_bound = Some(found.lower_bound);
            o
        }
    };
    o.first_design_seconds = o.spec.as_ref().and(found.first_at);
    o.peak_open = found.peak_open;
    o.peak_open_bytes = found.peak_bytes;
    o.checked = checked;
    Ok(o)
}

/// Without a time limit, the box search examines at most
/// [`BOX_WORK_PER_PATIENCE`] boxes per unit of patience from here.
fn cap_work(p: &Problem, budget: &mut Budget) {
    if let (None, Some(pat)) = (p.opts.time_limit, p.opts.patience) {
        budget.work_cap = Some(
            budget
                .work
                .saturating_add(pat.saturating_mul(BOX_WORK_PER_PATIENCE)),
        );
    }
}

/// Every box was decided and none verified: the problem is infeasible.
/// Explaining it gets a bounded effort unless a time limit says otherwise.
fn infeasible(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    mut notes: Vec<String>,
) -> Outcome {
    budget.work_cap = None;
    if let (None, Some(pat)) = (p.opts.time_limit, p.opts.patience) {
        budget.work_cap = Some(
            budget
                .work
                .saturating_add(pat.saturating_mul(BOX_WORK_PER_PATIENCE * EXPLAIN_EFFORT)),
        );
    }
    let (conflicts, minimal) = explain(p, learnt, budget, groups, None);
    if !minimal {
        notes.push(format!(
            "the conflict search stopped ({}): the set may not be minimal and fixes may be missing",
            budget.stop_cause()
        ));
    }
    budget.outcome(p, Status::Infeasible, None, None, conflicts, notes)
}

fn stop_reason(budget: &Budget, checks: usize) -> String {
    format!(
        "the exact search stopped ({}); the design is verified, the gap is to the best proven lower bound",
        stop_cause(budget, checks)
    )
}

/// Why the box search stopped early: its budgets, or the acceptance
/// check's limit.
fn stop_cause(budget: &Budget, checks: usize) -> String {
    if checks >= crate::gate::MAX_CHECKS {
        format!(
            "the acceptance check judged its limit of {} designs",
            crate::gate::MAX_CHECKS
        )
    } else {
        budget.stop_cause().to_string()
    }
}
