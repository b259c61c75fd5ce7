//! Response times in the master: the recurrence with one binary per job of
//! a higher-priority task (levels added lazily), and the RTA test's cuts.

use crate::domain::grid_units;
use crate::linear::Bin;
use crate::lp::Cmp;
use crate::model::Master;
use crate::problem::Problem;
use rtpipe_analysis::sched::interference;
use rtpipe_analysis::{Mode, Report};
use rtpipe_model::{SchedTest, Server, Spec};
use std::collections::HashMap;

/// Response-time levels per (budget level?, task, higher-priority task): the
/// jobs of the latter the model counts (at least the first).
pub(crate) type Levels = HashMap<(bool, usize, usize), usize>;

/// A lazy schedulability cut: task `i` missed its deadline with hp set `hp`
/// and these periods; some period must grow or the order must change.
#[derive(Debug, Clone)]
pub(crate) struct RtaCut {
    pub(crate) i: usize,
    pub(crate) hp: Vec<usize>,
    pub(crate) periods: Vec<(usize, i64)>,
}

impl<'a> Master<'a> {
    /// `r ≥ own + Σ_{j ≻ i} I_j · (jobs of j released in [0, r))`: for the
    /// m-th job of j (m ≥ 2) a binary b with `b = 0 ⇒ r ≤ (m − 1)·T_j`, so
    /// b must be 1 once r passes the release. Every r the model allows has
    /// W(r) ≤ r, hence r ≥ the least fixed point (the RTA response time),
    /// and the response time itself is allowed: exact when `cap` covers
    /// every job that can fall below `rmax`, a relaxation otherwise (the
    /// levels grow lazily, see `raise_levels`). It is the first own job's
    /// recurrence, where the analysis takes every own job of the level-i
    /// busy period (`sched::level_response`): with `r ≤ T_i`
    /// (`at_most_period`, on every response variable) the busy period
    /// holds that one job, so the two agree wherever the model admits r.
    pub(crate) fn rta_levels(
        &mut self,
        i: usize,
        r: usize,
        own: f64,
        rmax: f64,
        levels: &Levels,
        budget_level: bool,
    ) {
        let spec = self.spec;
        let g = self.g;
        let mut terms = vec![(r, 1.0)];
        let mut rhs = own;
        for j in 0..spec.tasks.len() {
            if j == i || spec.tasks[j].cpu != spec.tasks[i].cpu || !self.guaranteed(j) {
                continue;
            }
            let cj = grid_units(interference(&spec.tasks[j]), g);
            let a = self.above(j, i);
            match a {
                Bin::Const(true) => rhs += cj,
                Bin::Const(false) => continue,
                Bin::Var(z) => terms.push((z, -cj)),
            }
            let tmin = self.dom[j].min().max(1) as f64;
            let cap = levels.get(&(budget_level, i, j)).copied().unwrap_or(1);
            let mut prev: Option<usize> = None;
            for m in 2..=cap {
                let rel = (m - 1) as f64;
                // The m-th job is released at (m − 1)·T_j ≥ (m − 1)·T_min.
                let big = rmax - rel * tmin;
                if big <= 0.0 {
                    break;
                }
                let b = self.lp.binary();
                let mut row = vec![(r, 1.0), (b, -big)];
                row.extend(self.period[j].terms.iter().map(|&(v, k)| (v, -rel * k)));
                let mut bound = rel * self.period[j].c;
                if let Bin::Var(z) = a {
                    row.push((z, big));
                    bound += big;
                }
                self.lp.row(row, Cmp::Le, bound);
                if let Some(pb) = prev {
                    self.lp.row(vec![(b, 1.0), (pb, -1.0)], Cmp::Le, 0.0);
                }
                prev = Some(b);
                terms.push((b, -cj));
            }
        }
        self.lp.row(terms, Cmp::Ge, rhs);
    }
}

pub(crate) fn add_rta_cut(m: &mut Master, cut: &RtaCut) {
    // Σ [T_j ≥ T*_j + 1] + Σ_{j ∈ hp} [j no longer above i] ≥ 1.
    let mut sum: Vec<(usize, f64)> = Vec::new();
    let mut always = false;
    for &(j, tj) in &cut.periods {
        if let Some(b) = m.grew(j, tj) {
            sum.push((b, 1.0));
        }
    }
    for &j in &cut.hp {
        match m.above(j, cut.i) {
            Bin::Const(true) => {}
            Bin::Const(false) => always = true,
            Bin::Var(z) => {
                // flip = 1 − z
                sum.push((z, -1.0));
                // Σ … + (1 − z) ≥ 1 ⇔ Σ … − z ≥ 0; handled by the rhs below.
            }
        }
    }
    if always {
        return;
    }
    let flips = sum.iter().filter(|&&(_, a)| a < 0.0).count() as f64;
    // Σ b + Σ (1 − z) ≥ 1  ⇔  Σ b − Σ z ≥ 1 − flips
    m.lp.row(sum, Cmp::Ge, 1.0 - flips);
}

/// Checks the schedulability test of `p` exactly; adds an RTA cut to
/// `cuts` on failure.
pub(crate) fn sched_ok(p: &Problem, cuts: &mut Vec<RtaCut>, spec: &Spec, report: &Report) -> bool {
    if report.schedulability.schedulable {
        return true;
    }
    if p.spec.schedulability == SchedTest::Rta {
        let prio = rtpipe_model::policy::rate_monotonic(spec);
        for (i, tm) in report.timing.iter().enumerate() {
            if spec.tasks[i].server == Server::Background {
                continue;
            }
            // The RTA test: R ≤ D (D = T unless the spec gives a deadline).
            let ok = tm
                .response_time
                .is_some_and(|r| r <= tm.deadline.min(tm.period));
            if !ok {
                let top = rtpipe_analysis::sched::top_priorities(spec, &prio);
                let hp = rtpipe_analysis::sched::interferers(spec, &prio, &top, i);
                let periods = hp
                    .iter()
                    .chain(std::iter::once(&i))
                    .map(|&j| (j, spec.tasks[j].fixed_period().unwrap_or(0) / p.g))
                    .collect();
                cuts.push(RtaCut { i, hp, periods });
                return false;
            }
        }
    }
    false
}

/// Counts more jobs of higher-priority tasks where the candidate's
/// response times need them: for each modelled R_i (job level for chain
/// tasks in sound mode, budget level under the RTA test), every task j
/// above i gets levels up to its jobs within the analysed R_i (or T_i
/// when R_i diverged) plus one. True when any level was added.
pub(crate) fn raise_levels(p: &Problem, levels: &mut Levels, cand: &Spec, report: &Report) -> bool {
    let spec = p.spec;
    if !spec.policy().fixed_priority() {
        return false;
    }
    let n = spec.tasks.len();
    let prio = rtpipe_model::policy::rate_monotonic(cand);
    let top = rtpipe_analysis::sched::top_priorities(cand, &prio);
    let sound = p.opts.mode == Mode::Sound;
    let tested = spec.schedulability == SchedTest::Rta;
    let mut raised = false;
    for i in 0..n {
        let chain_task = sound && p.on_chain[i];
        if spec.tasks[i].server == Server::Background {
            continue;
        }
        let t = &report.timing[i];
        let hp = rtpipe_analysis::sched::interferers(cand, &prio, &top, i);
        for (budget_level, on, r) in [
            (false, chain_task, t.job_response_time),
            (true, tested, t.response_time),
        ] {
            if !on {
                continue;
            }
            let r = r.unwrap_or(t.period).min(t.period.saturating_mul(2));
            for &j in &hp {
                let tj = report.timing[j].period.max(1);
                let jobs = ((r + tj - 1) / tj) as usize + 1;
                let need =
                    (p.dom[i].max() as f64 / p.dom[j].min().max(1) as f64).ceil() as usize + 1;
                let e = levels.entry((budget_level, i, j)).or_insert(1);
                let want = jobs.min(need);
                if want > *e {
                    *e = want;
                    raised = true;
                }
            }
        }
    }
    raised
}
