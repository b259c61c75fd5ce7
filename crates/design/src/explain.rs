//! Explaining infeasibility: a small conflicting set of constraint groups
//! (deletion filter) and how far each chain limit would have to move.

use crate::domain::gu;
use crate::master::Group;
use crate::runner::Runner;
use crate::solve::{NumLog, Solved};
use crate::sound::{learn_r_cuts, SoundModel};
use crate::Conflict;
use rtpipe_analysis::Metric;
use rtpipe_model::{format_in, Nanos, Spec};

/// Whether each conflict probe gets a fair share of the remaining work
/// (else each may use all that is left, as the time-bounded search did).
pub(crate) const FAIR_SHARES: bool = false;

impl<'a> Runner<'a> {
    /// Whether `groups` can hold together: the master loop (tangent, RTA and
    /// response-time cuts) restricted to them, until the master is
    /// infeasible or a candidate needs no more cuts. Cuts learnt here are
    /// valid everywhere and kept.
    /// `None` when it could not be decided (time or iteration limit).
    pub(crate) fn probe(&mut self, groups: &[Group], sound: Option<&SoundModel>) -> Option<bool> {
        if self.boxes {
            return self.probe_boxes(groups);
        }
        let mut sm = sound.cloned();
        for _ in 0..100 {
            if self.out_of_time() {
                return None;
            }
            let periods = match self.solve_master(groups, sm.as_ref()) {
                Solved::Infeasible => return Some(false),
                Solved::Error(_) | Solved::Stopped => return None,
                Solved::Periods {
                    periods: p,
                    responses: rmodel,
                    ..
                } => {
                    let cand = self.with_periods(&p);
                    let report = rtpipe_analysis::analyze(&cand);
                    let oa = self.oa_exact(&p);
                    let verified = report.schedulability.schedulable && self.limits_ok(&report);
                    if !verified && self.raise_levels(&cand, &report) {
                        continue;
                    }
                    let sched_needed = groups.iter().any(|g| matches!(g, Group::Sched(_)));
                    let sched = !sched_needed || self.sched_ok(&cand, &report);
                    if !oa || !sched {
                        continue;
                    }
                    match &mut sm {
                        None => return Some(true),
                        Some(m) => {
                            if !learn_r_cuts(self.g, &cand, &report, &p, &rmodel, m) {
                                return Some(true);
                            }
                        }
                    }
                    p
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
        &mut self,
        groups: &[Group],
        sound: Option<&SoundModel>,
    ) -> (Vec<Conflict>, bool) {
        let (core, decided) = self.deletion_filter(groups, sound);
        let conflicts = core
            .iter()
            .map(|&gr| self.conflict(groups, gr, sound))
            .collect();
        (conflicts, decided)
    }

    /// Drops every group whose removal provably keeps the conflict; says
    /// whether every probe was decided.
    fn deletion_filter(
        &mut self,
        groups: &[Group],
        sound: Option<&SoundModel>,
    ) -> (Vec<Group>, bool) {
        let mut core: Vec<Group> = groups.to_vec();
        let mut k = 0;
        let mut decided = true;
        // Under a work budget each probe gets a fair share of what is left
        // (one share kept for the fixes), so one hard probe cannot starve
        // the others.
        let budget = self.work_cap;
        while k < core.len() {
            if self.out_of_time() {
                decided = false;
                break;
            }
            if let (Some(cap), true) = (budget, FAIR_SHARES) {
                let share = cap.saturating_sub(self.work) / (core.len() - k + 1) as u64;
                self.work_cap = Some(self.work.saturating_add(share.max(1)).min(cap));
            }
            self.say(|| {
                format!(
                    "infeasible; finding the conflicting constraints ({} of {} left to test)",
                    core.len() - k,
                    groups.len()
                )
            });
            let mut trial = core.clone();
            trial.remove(k);
            // Keep the group unless dropping it provably keeps the conflict.
            let verdict = self.probe(&trial, sound);
            self.work_cap = budget;
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
    fn conflict(&mut self, groups: &[Group], gr: Group, sound: Option<&SoundModel>) -> Conflict {
        let spec = self.spec;
        let (c, metric) =
            match gr {
                Group::Limit(c, metric) => (c, metric),
                Group::Sched(cpu) => return Conflict {
                    constraint: format!("cpu {cpu}: {} schedulability", spec.schedulability.name()),
                    fix: Some(
                        "lower the utilisation of its tasks (budgets) or move tasks to another CPU"
                            .into(),
                    ),
                },
            };
        let ch = &spec.chains[c];
        let name = ch.name.clone().unwrap_or_else(|| {
            ch.path
                .iter()
                .map(|&i| spec.tasks[i].name.as_str())
                .collect::<Vec<_>>()
                .join(">")
        });
        let limit = metric.limit(ch).unwrap_or(0);
        self.say(|| format!("infeasible; how far must {name} move"));
        let fix = self.min_limit(groups, gr, sound).map(|need| {
            format!(
                "raise the {} limit from {} to {} {} (within a thousandth of the time unit; other constraints unchanged)",
                metric.name(),
                format_in(limit, spec.time_unit),
                format_in(need, spec.time_unit),
                spec.time_unit
            )
        });
        Conflict {
            constraint: format!(
                "chain {name}: {} ≤ {}",
                metric.name(),
                format_in(limit, spec.time_unit)
            ),
            fix,
        }
    }

    /// The smallest limit of chain group `gr` that makes `core` feasible,
    /// by bisection on the limit (in grid units).
    pub(crate) fn min_limit(
        &mut self,
        core: &[Group],
        gr: Group,
        sound: Option<&SoundModel>,
    ) -> Option<Nanos> {
        let Group::Limit(c, metric) = gr else {
            return None;
        };
        let original = self.spec.clone();
        let lo0 = metric.limit(&original.chains[c])?;
        let mut hi = lo0.max(1);
        // Whether `core` holds with the limit at l, by a sub-search on a
        // copy of the spec that shares what was learnt.
        let feasible = |me: &mut Self, l: Nanos| -> Option<bool> {
            let mut s = original.clone();
            match metric {
                Metric::Reaction => s.chains[c].reaction = Some(l),
                Metric::Freshness => s.chains[c].freshness = Some(l),
            }
            let mut sub = me.sub_runner(&s, l);
            let r = sub.probe(core, sound);
            // The sub-search's work counts against the budget.
            me.work = sub.work;
            me.numerical.absorb(&sub.numerical);
            r
        };
        // Find a feasible upper end by doubling. Any undecided probe makes
        // the answer unknown: say nothing then.
        let mut tries = 0;
        while !feasible(self, hi)? {
            hi = hi.saturating_mul(2);
            tries += 1;
            if tries > 20 || self.out_of_time() {
                return None;
            }
        }
        let mut lo = lo0;
        let step = (self.spec.time_unit.nanos() / 1000).max(1);
        while hi - lo > step {
            if self.out_of_time() {
                return None;
            }
            let mid = lo + (hi - lo) / 2;
            if feasible(self, mid)? {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(hi)
    }

    /// A runner for `spec` (this one's with a chain limit moved to `l`)
    /// that starts from everything this one learnt.
    fn sub_runner<'s>(&self, spec: &'s Spec, l: Nanos) -> Runner<'s>
    where
        'a: 's,
    {
        Runner {
            spec,
            opts: self.opts,
            g: self.g,
            dom: self.dom.clone(),
            big_m: self.big_m.max(4.0 * gu(l, self.g)),
            start: self.start,
            rta_cuts: self.rta_cuts.clone(),
            oa_points: self.oa_points.clone(),
            iterations: 0,
            work: self.work,
            work_cap: self.work_cap,
            levels: self.levels.clone(),
            on_chain: self.on_chain.clone(),
            numerical: NumLog::default(),
            start_periods: None,
            boxes: self.boxes,
        }
    }
}
