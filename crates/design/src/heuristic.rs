//! Verified designs found quickly, without proof: a local search on the
//! analysis alone, and the master with response times pinned to estimates.

use crate::api::utilization;
use crate::axis::Axis;
use crate::budget::Budget;
use crate::domain::{grid_units, Dom};
use crate::harmonic;
use crate::learnt::Learnt;
use crate::problem::{Group, Problem};
use crate::solve::{solve_master, Solved};
use crate::sound::SoundModel;
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};

/// A verified design by local search on the analysis alone: chain tasks
/// start at their shortest period, the others at their longest; then
/// every task in turn lengthens its period (largest utilisation first,
/// in growing jumps) while the design still verifies, and then pairs of
/// tasks on one chain trade latency (`exchange`). Cheap and often good;
/// it proves nothing, so it only seeds the incumbent.
pub(crate) fn descent(p: &Problem, budget: &Budget) -> Option<(Spec, Report, f64)> {
    let values = ladders(p);
    let (mut idx, mut best) = first_design(p, budget, &values)?;
    p.say(|| "a first verified design by local search".into());
    lengthen_all(p, budget, &values, &mut idx, &mut best);
    let mut allowance = EXCHANGE_TASK_TRIALS / p.spec.tasks.len().max(1);
    for _ in 0..EXCHANGE_PASSES {
        if !exchange(p, budget, &values, &mut idx, &mut best, &mut allowance) {
            break;
        }
        lengthen_all(p, budget, &values, &mut idx, &mut best);
    }
    if p.spec.harmonic {
        best = harmonize(p, &values, &idx)?;
    }
    let u = utilization(&best.0);
    Some((best.0, best.1, u))
}

/// Passes of [`exchange`] at most: each must lower U, and a pass costs
/// about (chain tasks)² × log(rungs) analyses.
const EXCHANGE_PASSES: usize = 4;

/// Pair moves tried at most, times the tasks: each costs an analysis or
/// a few, which grows with the tasks, and the descent runs before any
/// work budget (1,000 pairs at 50 tasks, 41 at 1,200).
const EXCHANGE_TASK_TRIALS: usize = 50_000;

/// Every task in turn, largest utilisation first, lengthens its period
/// in growing jumps while the design still verifies; until none moves.
fn lengthen_all(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
    idx: &mut Vec<usize>,
    best: &mut (Spec, Report),
) {
    loop {
        let mut moved = false;
        for i in lengthen_order(p, values, idx) {
            moved |= lengthen(p, budget, values, idx, best, i);
        }
        if !moved || budget.out_of_time() {
            break;
        }
    }
}

/// Task `i` lengthened by growing jumps (1, 2, 4, … rungs) while the
/// design verifies; whether it moved.
fn lengthen(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
    idx: &mut Vec<usize>,
    best: &mut (Spec, Report),
    i: usize,
) -> bool {
    let mut moved = false;
    let mut jump = 1;
    while idx[i] + jump < values[i].len() && !budget.out_of_time() {
        let mut trial = idx.clone();
        trial[i] += jump;
        match check(p, values, &trial) {
            Some(found) => {
                *idx = trial;
                *best = found;
                moved = true;
                jump *= 2;
            }
            None => break,
        }
    }
    moved
}

/// One pass of pair moves along every chain: task `a` one rung faster
/// buys latency for task `b` of the same chain to lengthen as far as it
/// verifies; kept when Σ C/T falls. A single task's moves cannot find
/// this (the descent stops where every lengthening alone breaks a
/// limit), and the optimum wants it: at a binding limit the best periods
/// grow as √C, so a chain's light tasks should run faster than its heavy
/// ones. Each pair tried spends one of `allowance`. Whether the pass
/// lowered U.
fn exchange(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
    idx: &mut Vec<usize>,
    best: &mut (Spec, Report),
    allowance: &mut usize,
) -> bool {
    let mut improved = false;
    let u_of = |idx: &[usize]| -> f64 {
        (0..idx.len())
            .map(|i| p.spec.tasks[i].budget() as f64 / values[i][idx[i]] as f64)
            .sum()
    };
    for chain in &p.spec.chains {
        for &a in &chain.path {
            for &b in &chain.path {
                if a == b || idx[a] == 0 || idx[b] + 1 >= values[b].len() {
                    continue;
                }
                if budget.out_of_time() || *allowance == 0 {
                    return improved;
                }
                *allowance -= 1;
                let mut trial = idx.clone();
                trial[a] -= 1;
                let mut found = best.clone();
                if !lengthen(p, budget, values, &mut trial, &mut found, b) {
                    continue;
                }
                if u_of(&trial) < u_of(idx) * (1.0 - 1e-9) {
                    *idx = trial;
                    *best = found;
                    improved = true;
                }
            }
        }
    }
    improved
}

/// Under `harmonic = true`: the descent's periods rounded down to a
/// harmonic point (`harmonic::round_down`), if that point verifies.
fn harmonize(p: &Problem, values: &[Vec<Nanos>], idx: &[usize]) -> Option<(Spec, Report)> {
    let axes: Vec<Axis> = p.dom.iter().map(|d| Axis::new(d, p.g)).collect();
    let periods: Vec<Nanos> = (0..values.len()).map(|i| values[i][idx[i]]).collect();
    let k = harmonic::round_down(&axes, &periods)?;
    let rounded: Vec<Nanos> = k.iter().zip(&axes).map(|(&x, a)| a.value(x)).collect();
    let cand = p.with_periods(&rounded);
    let report = rtpipe_analysis::analyze(&cand);
    passes(p, cand, report)
}

/// Candidate values per task (ns): every choice, or a geometric ladder
/// over a range (about 10 % apart, both ends included).
fn ladders(p: &Problem) -> Vec<Vec<Nanos>> {
    p.dom
        .iter()
        .map(|d| match d {
            Dom::Fixed(t) => vec![*t * p.g],
            Dom::Choice(v) => {
                let mut v: Vec<Nanos> = v.iter().map(|&t| t * p.g).collect();
                v.sort_unstable();
                v.dedup();
                v
            }
            Dom::Grid { step, lo, hi } => {
                let mut ks = vec![*lo];
                let mut k = *lo;
                while k < *hi {
                    k = (((k as f64) * 1.1).ceil() as i64).max(k + 1).min(*hi);
                    ks.push(k);
                }
                ks.iter().map(|k| k * step * p.g).collect()
            }
        })
        .collect()
}

/// The spec at rung `idx[i]` of every task's ladder, and its analysis.
fn at_rungs(p: &Problem, values: &[Vec<Nanos>], idx: &[usize]) -> (Spec, Report) {
    let periods: Vec<Nanos> = (0..values.len()).map(|i| values[i][idx[i]]).collect();
    let cand = p.with_periods(&periods);
    let report = rtpipe_analysis::analyze(&cand);
    (cand, report)
}

/// The design at these rungs, if it verifies.
fn check(p: &Problem, values: &[Vec<Nanos>], idx: &[usize]) -> Option<(Spec, Report)> {
    let (cand, report) = at_rungs(p, values, idx);
    passes(p, cand, report)
}

/// A candidate with its analysis, if it verifies.
fn passes(p: &Problem, cand: Spec, report: Report) -> Option<(Spec, Report)> {
    (report.schedulability.schedulable && p.limits_ok(&report)).then_some((cand, report))
}

/// The least-utilisation verified start of any kind: the chain tasks at
/// a per-CPU utilisation share, repaired (`descent_start`, `repair`), or
/// scaled together from one of the [`SHAPES`] (`scaled_start`). The
/// shares give good starts where the limits are loose; where they are
/// tight only a scaled shape may verify at all (a pipeline whose limit
/// is a few times its total execution time: every share either misses
/// the schedulability test or, repaired, the limit).
fn first_design(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
) -> Option<(Vec<usize>, (Spec, Report))> {
    let shared = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1]
        .iter()
        .find_map(|&u| repair(p, budget, values, descent_start(p, values, u)));
    let scaled = SHAPES
        .iter()
        .filter_map(|&shape| scaled_start(p, budget, values, shape));
    shared
        .into_iter()
        .chain(scaled)
        .min_by(|a, b| utilization(&a.1 .0).total_cmp(&utilization(&b.1 .0)))
}

/// Relative periods of a chain task from its budget C: √C (where one
/// limit binds, the least Σ C/T under Σ T ≤ L has T ∝ √C), equal periods
/// (Sinha and West's first stage: every stage of a pipeline at one
/// period) and C (equal utilisations).
const SHAPES: [fn(f64) -> f64; 3] = [f64::sqrt, |_| 1.0, |c| c];

/// Bisections of a scaled start's factor (in log₂, from 2⁻⁴⁰ of the
/// range to its whole).
const SCALE_STEPS: usize = 40;

/// The chain tasks at periods θ·shape(C) (each the shortest rung at or
/// above, the others at their longest), θ the least that passes the
/// schedulability test, found by bisection: longer periods only lengthen
/// the chains' bounds, so if the limits fail there they fail for every
/// θ of this shape.
fn scaled_start(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
    shape: fn(f64) -> f64,
) -> Option<(Vec<usize>, (Spec, Report))> {
    let weight: Vec<f64> = (0..values.len())
        .map(|i| shape(p.spec.tasks[i].budget().max(1) as f64))
        .collect();
    let chain_tasks: Vec<usize> = (0..values.len()).filter(|&i| p.on_chain[i]).collect();
    let span = |f: fn(f64, f64) -> f64, end: fn(&Vec<Nanos>) -> Nanos| {
        chain_tasks
            .iter()
            .map(|&i| end(&values[i]) as f64 / weight[i])
            .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| f(m, x))))
    };
    let lo = span(f64::min, |v| v[0])?.log2();
    let hi = span(f64::max, |v| v[v.len() - 1])?.log2();
    let at = |log_theta: f64| -> Vec<usize> {
        let theta = log_theta.exp2();
        (0..values.len())
            .map(|i| {
                let top = values[i].len() - 1;
                if !p.on_chain[i] {
                    return top;
                }
                let want = theta * weight[i];
                values[i]
                    .iter()
                    .position(|&t| t as f64 >= want)
                    .unwrap_or(top)
            })
            .collect()
    };
    let schedulable = |idx: &[usize]| at_rungs(p, values, idx).1.schedulability.schedulable;
    if !schedulable(&at(hi)) {
        return None;
    }
    // Invariant: at(b) is schedulable; at(a) is not, or a is the bottom.
    let (mut a, mut b) = (lo, hi);
    if schedulable(&at(lo)) {
        b = lo;
    }
    for _ in 0..SCALE_STEPS {
        if b - a < 1e-3 || budget.out_of_time() {
            break;
        }
        let m = 0.5 * (a + b);
        if schedulable(&at(m)) {
            b = m;
        } else {
            a = m;
        }
    }
    let idx = at(b);
    check(p, values, &idx).map(|found| (idx, found))
}

/// A start: chain tasks as fast as a per-CPU utilisation share u allows
/// (each of k chain tasks on the CPU gets u/k), the others at their
/// longest period.
fn descent_start(p: &Problem, values: &[Vec<Nanos>], u: f64) -> Vec<usize> {
    let spec = p.spec;
    let n = spec.tasks.len();
    let on_chain = &p.on_chain;
    let per_cpu = |i: usize| {
        (0..n)
            .filter(|&j| spec.tasks[j].cpu == spec.tasks[i].cpu && on_chain[j])
            .count()
            .max(1) as f64
    };
    (0..n)
        .map(|i| {
            if !on_chain[i] {
                return values[i].len() - 1;
            }
            let want = spec.tasks[i].budget() as f64 * per_cpu(i) / u;
            values[i]
                .iter()
                .position(|&t| t as f64 >= want)
                .unwrap_or(values[i].len() - 1)
        })
        .collect()
}

/// From a start that is schedulable but misses limits, speed up the
/// tasks of every failing chain one step at a time, until it verifies.
fn repair(
    p: &Problem,
    budget: &Budget,
    values: &[Vec<Nanos>],
    mut idx: Vec<usize>,
) -> Option<(Vec<usize>, (Spec, Report))> {
    for _ in 0..4 * values.iter().map(Vec::len).max().unwrap_or(1) {
        // Asked before the analysis: on 1,200 tasks one costs ~0.1 s, and
        // the descent tries up to ten starts, each repaired.
        if budget.out_of_time() {
            return None;
        }
        let (cand, report) = at_rungs(p, values, &idx);
        if !report.schedulability.schedulable {
            return None;
        }
        if p.limits_ok(&report) {
            return Some((idx, (cand, report)));
        }
        let mut changed = false;
        for c in report.chains.iter().filter(|c| !p.chain_ok(c)) {
            // Not the tail: its period does not enter its chain's
            // bounds (its response time does), and speeding it up
            // only adds load.
            let path = &p.spec.chains[c.chain].path;
            for &i in &path[..path.len() - 1] {
                if idx[i] > 0 {
                    idx[i] -= 1;
                    changed = true;
                }
            }
        }
        if !changed {
            return None;
        }
    }
    None
}

/// The tasks that can still lengthen, largest utilisation first.
fn lengthen_order(p: &Problem, values: &[Vec<Nanos>], idx: &[usize]) -> Vec<usize> {
    let spec = p.spec;
    let mut order: Vec<usize> = (0..values.len())
        .filter(|&i| idx[i] + 1 < values[i].len())
        .collect();
    order.sort_by(|&a, &b| {
        let u = |i: usize| spec.tasks[i].budget() as f64 / values[i][idx[i]] as f64;
        u(b).total_cmp(&u(a))
    });
    order
}

/// Response times pinned to estimates, raised to the analysed values of
/// each failed candidate until a candidate verifies (or the model turns
/// infeasible). Fast, not exact: the caller keeps the lower bound.
pub(crate) fn heuristic(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
    groups: &[Group],
    sm: &SoundModel,
    start: Vec<f64>,
) -> Option<(Spec, Report, f64)> {
    let mut fixed = start;
    for _ in 0..60 {
        if budget.out_of_time() {
            return None;
        }
        let model = SoundModel {
            rlow: sm.rlow.clone(),
            wlow: sm.wlow.clone(),
            cuts: Vec::new(),
            fixed: Some(fixed.clone()),
        };
        let solved = solve_master(p, learnt, budget, groups, Some(&model));
        if crate::problem::debug() {
            if let Solved::Periods {
                periods,
                objective: obj,
                ..
            } = &solved
            {
                eprintln!(
                    "heuristic: objective {obj:.6} periods {periods:?} ({:.2} s)",
                    budget.elapsed()
                );
            }
        }
        let Solved::Periods { periods, .. } = solved else {
            return None;
        };
        let cand = p.with_periods(&periods);
        let report = rtpipe_analysis::analyze(&cand);
        let oa = learnt.oa_exact(p, &periods);
        let sched = learnt.sched_ok(p, &cand, &report);
        if !oa || !sched {
            continue;
        }
        if p.limits_ok(&report) {
            let u = utilization(&cand);
            return Some((cand, report, u));
        }
        let mut raised = false;
        for (f, t) in fixed.iter_mut().zip(&report.timing) {
            if let Some(r) = t.job_response_time {
                let r = grid_units(r, p.g);
                if r > *f + 1e-9 {
                    *f = r;
                    raised = true;
                }
            }
        }
        if !raised {
            return None;
        }
    }
    None
}
