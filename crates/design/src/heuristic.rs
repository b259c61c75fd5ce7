//! Verified designs found quickly, without proof: a local search on the
//! analysis alone, and the master with response times pinned to estimates.

use crate::domain::{gu, Dom};
use crate::master::Group;
use crate::runner::Runner;
use crate::solve::Solved;
use crate::sound::SoundModel;
use crate::utilization;
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};

impl<'a> Runner<'a> {
    /// A verified design by local search on the analysis alone: chain tasks
    /// start at their shortest period, the others at their longest; then
    /// every task in turn lengthens its period (largest utilisation first,
    /// in growing jumps) while the design still verifies. Cheap and often
    /// good; it proves nothing, so it only seeds the incumbent.
    pub(crate) fn descent(&mut self) -> Option<(Spec, Report, f64)> {
        let values = self.ladders();
        let (mut idx, mut best) = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1]
            .iter()
            .find_map(|&u| self.repair(&values, self.descent_start(&values, u)))?;
        self.say(|| "a first verified design by local search".into());
        loop {
            let mut moved = false;
            for i in self.lengthen_order(&values, &idx) {
                let mut jump = 1;
                while idx[i] + jump < values[i].len() && !self.out_of_time() {
                    let mut trial = idx.clone();
                    trial[i] += jump;
                    match self.check(&values, &trial) {
                        Some(found) => {
                            idx = trial;
                            best = found;
                            moved = true;
                            jump *= 2;
                        }
                        None => break,
                    }
                }
            }
            if !moved || self.out_of_time() {
                break;
            }
        }
        let u = utilization(&best.0);
        Some((best.0, best.1, u))
    }

    /// Candidate values per task (ns): every choice, or a geometric ladder
    /// over a range (about 10 % apart, both ends included).
    fn ladders(&self) -> Vec<Vec<Nanos>> {
        self.dom
            .iter()
            .map(|d| match d {
                Dom::Fixed(t) => vec![*t * self.g],
                Dom::Choice(v) => {
                    let mut v: Vec<Nanos> = v.iter().map(|&t| t * self.g).collect();
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
                    ks.iter().map(|k| k * step * self.g).collect()
                }
            })
            .collect()
    }

    /// The spec at rung `idx[i]` of every task's ladder, and its analysis.
    fn at_rungs(&self, values: &[Vec<Nanos>], idx: &[usize]) -> (Spec, Report) {
        let periods: Vec<Nanos> = (0..values.len()).map(|i| values[i][idx[i]]).collect();
        let cand = self.with_periods(&periods);
        let report = rtpipe_analysis::analyze(&cand);
        (cand, report)
    }

    /// The design at these rungs, if it verifies.
    fn check(&self, values: &[Vec<Nanos>], idx: &[usize]) -> Option<(Spec, Report)> {
        let (cand, report) = self.at_rungs(values, idx);
        (report.schedulability.schedulable && self.limits_ok(&report)).then_some((cand, report))
    }

    /// A start: chain tasks as fast as a per-CPU utilisation share u allows
    /// (each of k chain tasks on the CPU gets u/k), the others at their
    /// longest period.
    fn descent_start(&self, values: &[Vec<Nanos>], u: f64) -> Vec<usize> {
        let spec = self.spec;
        let n = spec.tasks.len();
        let on_chain = &self.on_chain;
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
        &self,
        values: &[Vec<Nanos>],
        mut idx: Vec<usize>,
    ) -> Option<(Vec<usize>, (Spec, Report))> {
        for _ in 0..4 * values.iter().map(Vec::len).max().unwrap_or(1) {
            let (cand, report) = self.at_rungs(values, &idx);
            if !report.schedulability.schedulable || self.out_of_time() {
                return None;
            }
            if self.limits_ok(&report) {
                return Some((idx, (cand, report)));
            }
            let mut changed = false;
            for c in report.chains.iter().filter(|c| !self.chain_ok(c)) {
                // Not the tail: its period does not enter its chain's
                // bounds (its response time does), and speeding it up
                // only adds load.
                let path = &self.spec.chains[c.chain].path;
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
    fn lengthen_order(&self, values: &[Vec<Nanos>], idx: &[usize]) -> Vec<usize> {
        let spec = self.spec;
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
        &mut self,
        groups: &[Group],
        sm: &SoundModel,
        start: Vec<f64>,
    ) -> Option<(Spec, Report, f64)> {
        let mut fixed = start;
        for _ in 0..60 {
            if self.out_of_time() {
                return None;
            }
            let model = SoundModel {
                rlow: sm.rlow.clone(),
                cuts: Vec::new(),
                fixed: Some(fixed.clone()),
            };
            let solved = self.solve_master(groups, Some(&model));
            if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
                if let Solved::Periods {
                    periods: p,
                    objective: obj,
                    ..
                } = &solved
                {
                    eprintln!(
                        "heuristic: objective {obj:.6} periods {p:?} ({:.2} s)",
                        self.elapsed()
                    );
                }
            }
            let Solved::Periods { periods: p, .. } = solved else {
                return None;
            };
            let cand = self.with_periods(&p);
            let report = rtpipe_analysis::analyze(&cand);
            let oa = self.oa_exact(&p);
            let sched = self.sched_ok(&cand, &report);
            if !oa || !sched {
                continue;
            }
            if self.limits_ok(&report) {
                let u = utilization(&cand);
                return Some((cand, report, u));
            }
            let mut raised = false;
            for (f, t) in fixed.iter_mut().zip(&report.timing) {
                if let Some(r) = t.job_response_time {
                    let r = gu(r, self.g);
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
}
