//! The master problem: variables, objective, schedulability rows and the
//! chain limits (the `model`, written with the encodings in `paper`,
//! `sound` and `rta`, and with what the search has learnt).

use crate::domain::{grid_units, harmonic_pair, Dom};
use crate::learnt::{Learnt, DENSE_TANGENTS};
use crate::linear::Lin;
use crate::lp::Cmp;
use crate::model::{ChainExpr, Master};
use crate::paper::paper_chain;
use crate::problem::{Group, Problem};
use crate::rta::{add_rta_cut, Levels, RtaCut};
use crate::sound::{add_r_cut, rmax_of, sound_chain, sound_event_reaction, SoundModel};
use rtpipe_analysis::{Anchor, Metric};
use rtpipe_model::policy::ResponseAnalysis;
use rtpipe_model::SchedTest;

impl<'a> Master<'a> {
    /// The period, utilisation and hyperbolic term of every task; the
    /// objective Σ u over guaranteed tasks (also returned).
    fn add_periods(&mut self, oa_points: &[Vec<i64>]) -> Vec<(usize, f64)> {
        for (i, pts) in oa_points.iter().enumerate() {
            let c = self.spec.tasks[i].budget() as f64;
            match self.dom[i].clone() {
                Dom::Fixed(t) => {
                    self.period.push(Lin::constant(t as f64));
                    let u = c / (t * self.g) as f64;
                    self.util.push(Lin::constant(u));
                    self.hlog.push(Lin::constant((1.0 + u).ln()));
                }
                Dom::Choice(v) => self.add_choice(i, c, &v),
                Dom::Grid { step, lo, hi } => self.add_grid(i, c, (step, lo, hi), pts),
            }
        }
        let mut objective: Vec<(usize, f64)> = Vec::new();
        let mut obj_const = 0.0;
        for i in (0..self.spec.tasks.len()).filter(|&i| self.guaranteed(i)) {
            objective.extend_from_slice(&self.util[i].terms);
            obj_const += self.util[i].c;
        }
        self.lp.obj = objective.clone();
        self.lp.obj_const = obj_const;
        objective
    }

    /// A choice domain: one binary per choice, exactly one set.
    fn add_choice(&mut self, i: usize, c: f64, v: &[i64]) {
        let g = self.g;
        let ys: Vec<usize> = v.iter().map(|_| self.lp.binary()).collect();
        self.lp
            .row(ys.iter().map(|&y| (y, 1.0)).collect(), Cmp::Eq, 1.0);
        let per = |f: &dyn Fn(i64) -> f64| Lin {
            terms: ys.iter().zip(v).map(|(&y, &t)| (y, f(t))).collect(),
            c: 0.0,
        };
        self.period.push(per(&|t| t as f64));
        self.util.push(per(&|t| c / (t * g) as f64));
        self.hlog.push(per(&|t| (1.0 + c / (t * g) as f64).ln()));
        self.yvars[i] = ys;
    }

    /// A range of grid steps: an integer k, and the utilisation and
    /// hyperbolic term under-approximated by tangents.
    fn add_grid(&mut self, i: usize, c: f64, (step, lo, hi): (i64, i64, i64), oa: &[i64]) {
        let k = self.lp.var(lo as f64, hi as f64, true);
        self.kvar[i] = Some(k);
        self.period.push(Lin {
            terms: vec![(k, step as f64)],
            c: 0.0,
        });
        let u = self.lp.var(0.0, 1e6, false);
        let h = self.lp.var(0.0, 1e6, false);
        self.uvar[i] = Some(u);
        self.hvar[i] = Some(h);
        self.util.push(Lin {
            terms: vec![(u, 1.0)],
            c: 0.0,
        });
        self.hlog.push(Lin {
            terms: vec![(h, 1.0)],
            c: 0.0,
        });
        // Outer approximation of U = a / k (a = C / (step·g)) and of
        // ln(1 + a/k): tangents, valid since both are convex in k.
        let a = c / (step * self.g) as f64;
        for k0 in tangent_points(lo, hi, oa) {
            if k0 < lo.max(1) || k0 > hi {
                continue;
            }
            let k0 = k0 as f64;
            // U ≥ 2a/k0 − a·k/k0²
            self.lp
                .row(vec![(u, 1.0), (k, a / (k0 * k0))], Cmp::Ge, 2.0 * a / k0);
            // ln(1 + a/k) ≥ ln(1 + a/k0) − a/(k0 (k0 + a))·(k − k0)
            let s = a / (k0 * (k0 + a));
            self.lp.row(
                vec![(h, 1.0), (k, s)],
                Cmp::Ge,
                (1.0 + a / k0).ln() + s * k0,
            );
        }
    }

    /// No two choices that are not harmonic (fixed ones are filtered): per
    /// choice of one task, it plus every choice of the other that is not
    /// harmonic with it is at most 1 (each task picks one choice), both
    /// ways. The same integer points as one row per forbidden pair, a
    /// tighter relaxation, and |A| + |B| rows instead of up to |A|·|B|
    /// (two free periods up to 10^6 gave 210,892 rows and a root LP that
    /// did not end).
    fn forbid_non_harmonic(&mut self) {
        let n = self.spec.tasks.len();
        for a in 0..n {
            for b in a + 1..n {
                let (Dom::Choice(va), Dom::Choice(vb)) = (&self.dom[a], &self.dom[b]) else {
                    continue;
                };
                let (va, vb) = (va.clone(), vb.clone());
                self.forbid_one_way((a, &va), (b, &vb));
                self.forbid_one_way((b, &vb), (a, &va));
            }
        }
    }

    /// For each choice x of task a: y_a[x] + Σ y_b[y] over the choices of
    /// b not harmonic with x ≤ 1.
    fn forbid_one_way(&mut self, (a, va): (usize, &[i64]), (b, vb): (usize, &[i64])) {
        for (x, &p) in va.iter().enumerate() {
            let mut row = vec![(self.yvars[a][x], 1.0)];
            row.extend(
                vb.iter()
                    .enumerate()
                    .filter(|&(_, &q)| !harmonic_pair(p, q))
                    .map(|(y, _)| (self.yvars[b][y], 1.0)),
            );
            if row.len() > 1 {
                self.lp.row(row, Cmp::Le, 1.0);
            }
        }
    }

    /// Schedulability per CPU: Σ U ≤ 1 is necessary for any test; an
    /// active group adds the test's bound (Liu–Layland, hyperbolic).
    fn add_sched(&mut self, groups: &[Group]) {
        let spec = self.spec;
        let n = spec.tasks.len();
        let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
        cpus.sort_unstable();
        cpus.dedup();
        for &cpu in &cpus {
            let ids: Vec<usize> = (0..n)
                .filter(|&i| spec.tasks[i].cpu == cpu && self.guaranteed(i))
                .collect();
            let sched_on = groups.contains(&Group::Sched(cpu));
            let sum_u = ids
                .iter()
                .fold(Lin::default(), |acc, &i| acc.plus(&self.util[i]));
            let bound = match (sched_on, spec.schedulability) {
                (true, SchedTest::LiuLayland) => {
                    let k = ids.len().max(1) as f64;
                    k * (2f64.powf(1.0 / k) - 1.0)
                }
                _ => 1.0,
            };
            self.lp.row(sum_u.terms.clone(), Cmp::Le, bound - sum_u.c);
            if sched_on && spec.schedulability == SchedTest::Hyperbolic {
                let sum_h = ids
                    .iter()
                    .fold(Lin::default(), |acc, &i| acc.plus(&self.hlog[i]));
                self.lp
                    .row(sum_h.terms.clone(), Cmp::Le, 2f64.ln() - sum_h.c);
            }
        }
    }

    /// Exact RTA where the levels fit: budget-level R_i ≥ W_i(R_i),
    /// R_i ≤ T_i; and the older cuts of failed candidates.
    /// `false` when `stop` said so before every task was added (see
    /// [`build_within`]).
    fn add_rta(
        &mut self,
        groups: &[Group],
        levels: &Levels,
        cuts: &[RtaCut],
        stop: &dyn Fn() -> bool,
    ) -> bool {
        let spec = self.spec;
        let tested: Vec<bool> = (0..spec.tasks.len())
            .map(|i| self.guaranteed(i) && groups.contains(&Group::Sched(spec.tasks[i].cpu)))
            .collect();
        for i in (0..spec.tasks.len()).filter(|&i| tested[i]) {
            if stop() {
                return false;
            }
            let rmax = self.dom[i].max() as f64;
            let r = self.lp.var(0.0, rmax, false);
            self.at_most_period(i, r);
            let own = grid_units(spec.tasks[i].budget(), self.g);
            self.rta_levels(i, r, own, rmax, levels, true);
        }
        for cut in cuts {
            if groups.contains(&Group::Sched(spec.tasks[cut.i].cpu)) {
                add_rta_cut(self, cut);
            }
        }
        true
    }

    /// Sound mode: job response-time variables of the chain tasks with
    /// their lower bounds, every chain task finishing within its period
    /// (T ≥ R), and under fixed priority the recurrence R_i ≥ W_i(R_i) with
    /// a binary per job of each higher-priority task (docs/design.md); not
    /// when the response times are pinned. Under EDF the lower bounds and
    /// the cuts learnt from candidates are all there is (a relaxation).
    /// `false` when `stop` said so before every recurrence was added.
    fn add_responses(
        &mut self,
        groups: &[Group],
        sm: &SoundModel,
        p: &Problem,
        levels: &Levels,
        stop: &dyn Fn() -> bool,
    ) -> bool {
        let n = self.spec.tasks.len();
        for i in (0..n).filter(|&i| p.on_chain[i]) {
            let r = match &sm.fixed {
                Some(f) => self.lp.var(f[i], f[i], false),
                None => {
                    let hi = rmax_of(self, groups, i).max(sm.rlow[i]);
                    self.lp.var(sm.rlow[i], hi, false)
                }
            };
            self.rvar[i] = Some(r);
            self.at_most_period(i, r);
        }
        if self.spec.policy().response == ResponseAnalysis::EdfRta {
            self.add_read_responses(groups, sm, p);
        }
        if sm.fixed.is_some() {
            return true;
        }
        let recurrence = self.spec.policy().response == ResponseAnalysis::Rta;
        for i in (0..n).filter(|&i| p.on_chain[i] && recurrence) {
            if stop() {
                return false;
            }
            let Some(r) = self.rvar[i] else { continue };
            let rmax = rmax_of(self, groups, i);
            let own = grid_units(self.spec.tasks[i].demand(), self.g);
            self.rta_levels(i, r, own, rmax, levels, false);
        }
        for cut in &sm.cuts {
            add_r_cut(self, cut);
        }
        true
    }

    /// Under EDF, read-to-publish variables W_i ≤ R_i of the chain tasks
    /// with their lower bounds (pinned with the response times: to the
    /// given W, else to R); the cuts learnt from candidates come with the
    /// response times' (`RCut::read`).
    fn add_read_responses(&mut self, groups: &[Group], sm: &SoundModel, p: &Problem) {
        let n = self.spec.tasks.len();
        for i in (0..n).filter(|&i| p.on_chain[i]) {
            let Some(r) = self.rvar[i] else { continue };
            let w = match &sm.fixed {
                Some(f) => {
                    let v = f.get(n + i).copied().unwrap_or(f[i]);
                    self.lp.var(v, v, false)
                }
                None => {
                    let hi = rmax_of(self, groups, i).max(sm.wlow[i]);
                    self.lp.var(sm.wlow[i].min(hi), hi, false)
                }
            };
            self.lp.row(vec![(w, 1.0), (r, -1.0)], Cmp::Le, 0.0);
            self.wvar[i] = Some(w);
        }
    }

    /// Every active chain limit, in the mode's encoding.
    fn add_limits(&mut self, groups: &[Group], sound: Option<&SoundModel>) {
        let spec = self.spec;
        for (k, ch) in spec.chains.iter().enumerate() {
            for metric in [Metric::Reaction, Metric::Freshness] {
                if !groups.contains(&Group::Limit(k, metric)) {
                    continue;
                }
                if let Some(limit) = metric.limit(ch, Anchor::Read) {
                    let l = grid_units(limit, self.g);
                    let none = Lin::default();
                    let sums = match sound {
                        None => vec![paper_chain(self, &ch.path, metric, l, &none)],
                        Some(_) => sound_chain(self, &ch.path, metric, l, &none),
                    };
                    self.chains.push(ChainExpr {
                        chain: k,
                        metric,
                        sums,
                    });
                }
                // From the event: the same sums plus the head's period.
                if let Some(limit) = metric.limit(ch, Anchor::Event) {
                    let l = grid_units(limit, self.g);
                    let head = self.period[ch.path[0]].clone();
                    match (sound, metric) {
                        (None, _) => drop(paper_chain(self, &ch.path, metric, l, &head)),
                        (Some(_), Metric::Reaction) => {
                            drop(sound_event_reaction(self, &ch.path, l))
                        }
                        (Some(_), Metric::Freshness) => {
                            drop(sound_chain(self, &ch.path, metric, l, &head))
                        }
                    }
                }
            }
        }
    }
}

/// The tangent points of a range [lo, hi] of grid steps: every point of a
/// small range; else the ends, the middle and doublings from lo; plus the
/// points learnt from candidates (`oa`).
fn tangent_points(lo: i64, hi: i64, oa: &[i64]) -> Vec<i64> {
    // Small ranges get a tangent at every point: the objective is then
    // exact from the first solve.
    let mut pts = if hi - lo <= DENSE_TANGENTS {
        (lo..=hi).collect()
    } else {
        vec![lo, hi, (lo + hi) / 2]
    };
    let mut x = lo as f64;
    while x < hi as f64 {
        pts.push(x as i64);
        x *= 2.0;
    }
    pts.extend(oa.iter().copied());
    pts.sort_unstable();
    pts.dedup();
    pts
}

/// The master problem of `p` over `groups` (every constraint group for the
/// search, a subset for the conflict search) with what the search has
/// learnt, and its objective (the encoding tests'; the search builds
/// through [`build_within`]).
#[cfg(test)]
pub(crate) fn build<'a>(
    p: &Problem<'a>,
    learnt: &Learnt,
    groups: &[Group],
    sound: Option<&SoundModel>,
) -> (Master<'a>, Vec<(usize, f64)>) {
    build_within(p, learnt, groups, sound, &|| false)
        .expect("a build that is never stopped completes")
}

/// [`build`], abandoned (`None`) as soon as `stop` says so: it is asked
/// before each task's response-time recurrence, the part that grows with
/// the square of the tasks (a binary per pair whose order the periods
/// decide; 300,000 of them, 2 s, for 1,200 free WATERS tasks).
pub(crate) fn build_within<'a>(
    p: &Problem<'a>,
    learnt: &Learnt,
    groups: &[Group],
    sound: Option<&SoundModel>,
    stop: &dyn Fn() -> bool,
) -> Option<(Master<'a>, Vec<(usize, f64)>)> {
    let mut m = Master::new(p);
    let objective = m.add_periods(&learnt.oa_points);
    if p.spec.harmonic {
        m.forbid_non_harmonic();
    }
    m.add_sched(groups);
    if p.spec.schedulability == SchedTest::Rta
        && !m.add_rta(groups, &learnt.levels, &learnt.rta_cuts, stop)
    {
        return None;
    }
    // Response-time variables wherever the analysis computes response
    // times (not where a response time is the server period).
    let rvars = p.spec.policy().response != ResponseAnalysis::ServerPeriod;
    if let Some(sm) = sound.filter(|_| rvars) {
        if !m.add_responses(groups, sm, p, &learnt.levels, stop) {
            return None;
        }
    }
    m.add_limits(groups, sound);
    Some((m, objective))
}
