//! The MILP search: master solves, each candidate checked by the analysis,
//! cuts and tangents until a candidate verifies or the master is infeasible.

use crate::domain::{gu, Dom, Domains};
use crate::master::{Group, DENSE_TANGENTS};
use crate::rta::{Levels, RtaCut};
use crate::solve::{NumLog, Solved};
use crate::sound::{learn_r_cuts, SoundModel};
use crate::{
    utilization, Conflict, DesignError, Incumbent, Method, Mode, Options, Outcome, Status,
    EXPLAIN_EFFORT,
};
use rtpipe_analysis::{ChainResult, Metric, Report};
use rtpipe_model::{Nanos, PeriodSpec, Server, Spec};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// One design search: the problem, its domains, what the search has
/// learnt (cuts, tangent points, response-time levels) and the work it has
/// done. The MILP (`solve_all`) and the box search (`bnb.rs`) both run on it.
pub(crate) struct Runner<'a> {
    pub(crate) spec: &'a Spec,
    pub(crate) opts: &'a Options,
    pub(crate) g: i64,
    pub(crate) dom: Vec<Dom>,
    pub(crate) big_m: f64,
    pub(crate) start: Instant,
    pub(crate) rta_cuts: Vec<RtaCut>,
    /// Outer-approximation points (k values) per Grid task.
    pub(crate) oa_points: Vec<Vec<i64>>,
    pub(crate) iterations: usize,
    /// Work done so far (see [`Options::patience`]).
    pub(crate) work: u64,
    /// No solve may run past this much work (the patience after a verified
    /// design, the conflict search's effort).
    pub(crate) work_cap: Option<u64>,
    pub(crate) levels: Levels,
    /// Task i lies on some declared chain.
    pub(crate) on_chain: Vec<bool>,
    /// Numerical failures of the solver and what became of them.
    pub(crate) numerical: NumLog,
    /// The best verified design's periods (ns): a starting solution for
    /// microlp's branch and bound.
    pub(crate) start_periods: Option<Vec<Nanos>>,
    /// The box search decides (`bnb.rs`), not the MILP.
    pub(crate) boxes: bool,
}

impl<'a> Runner<'a> {
    /// A runner for `spec` over these domains, nothing learnt yet.
    pub(crate) fn new(
        spec: &'a Spec,
        opts: &'a Options,
        domains: Domains,
        start: Instant,
        boxes: bool,
    ) -> Self {
        let Domains { g, dom, horizon } = domains;
        let n = spec.tasks.len();
        let max_t = dom.iter().map(|d| d.max()).max().unwrap_or(1) as f64;
        let max_limit = gu(horizon, g);
        let big_m = 4.0 * (max_t + max_limit) + 10.0;
        Runner {
            spec,
            opts,
            g,
            dom,
            big_m,
            start,
            rta_cuts: Vec::new(),
            oa_points: vec![Vec::new(); n],
            iterations: 0,
            work: 0,
            work_cap: None,
            levels: Levels::new(),
            on_chain: (0..n)
                .map(|i| spec.chains.iter().any(|c| c.path.contains(&i)))
                .collect(),
            numerical: NumLog::default(),
            start_periods: None,
            boxes,
        }
    }

    pub(crate) fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    pub(crate) fn say(&self, what: impl FnOnce() -> String) {
        if let Some(p) = &self.opts.progress {
            if let Ok(mut g) = p.lock() {
                *g = what();
            }
        }
    }

    /// Hands a better verified design to [`Options::incumbent`], so that a
    /// caller that stops waiting (Ctrl-C) can still report it.
    pub(crate) fn publish(&self, best: &Option<(Spec, Report, f64)>, lower_bound: Option<f64>) {
        if let (Some(sink), Some((s, _, u))) = (&self.opts.incumbent, best) {
            if let Ok(mut g) = sink.lock() {
                *g = Some(Incumbent {
                    periods: s
                        .tasks
                        .iter()
                        .map(|t| t.fixed_period().unwrap_or(0))
                        .collect(),
                    utilization: *u,
                    lower_bound: lower_bound.map(|b| b.min(*u)),
                });
            }
        }
    }

    pub(crate) fn out_of_time(&self) -> bool {
        self.opts
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
            || self.opts.time_limit.is_some_and(|t| self.elapsed() >= t)
            || self.work_cap.is_some_and(|c| self.work >= c)
    }

    pub(crate) fn all_groups(&self) -> Vec<Group> {
        let mut v = Vec::new();
        for (k, ch) in self.spec.chains.iter().enumerate() {
            if ch.reaction.is_some() {
                v.push(Group::Limit(k, Metric::Reaction));
            }
            if ch.freshness.is_some() {
                v.push(Group::Limit(k, Metric::Freshness));
            }
        }
        let mut cpus: Vec<u32> = self.spec.tasks.iter().map(|t| t.cpu).collect();
        cpus.sort_unstable();
        cpus.dedup();
        v.extend(cpus.into_iter().map(Group::Sched));
        v
    }

    /// The spec with these periods fixed.
    pub(crate) fn with_periods(&self, periods: &[Nanos]) -> Spec {
        let mut s = self.spec.clone();
        for (t, &p) in s.tasks.iter_mut().zip(periods) {
            t.period = PeriodSpec::Fixed(p);
        }
        s
    }

    /// Adds outer-approximation points where the model under-estimated the
    /// utilisation (or the hyperbolic term); true when nothing was added.
    pub(crate) fn oa_exact(&mut self, periods: &[Nanos]) -> bool {
        let mut exact = true;
        for ((d, pts), &p) in self.dom.iter().zip(self.oa_points.iter_mut()).zip(periods) {
            if let Dom::Grid { step, lo, hi } = *d {
                if hi - lo <= DENSE_TANGENTS {
                    continue;
                }
                let k = p / (step * self.g);
                if !pts.contains(&k) {
                    // The tangent at k makes the model exact there; the
                    // neighbours keep the next solve from stepping aside.
                    for d in [0, 1, (k / 64).max(1), (k / 16).max(1), (k / 4).max(1)] {
                        for q in [k - d, k + d] {
                            if q >= lo && q <= hi && !pts.contains(&q) {
                                pts.push(q);
                            }
                        }
                    }
                    exact = false;
                }
            }
        }
        exact
    }

    /// One chain limit holds under the mode's analysis.
    pub(crate) fn chain_ok(&self, c: &ChainResult) -> bool {
        c.ok_in(self.opts.mode)
    }

    pub(crate) fn limits_ok(&self, report: &Report) -> bool {
        report.chains.iter().all(|c| self.chain_ok(c))
    }

    /// The MILP search: master solves until a candidate verifies with
    /// nothing left to learn, the master turns infeasible, or a limit stops
    /// it.
    pub(crate) fn solve_all(&mut self) -> Result<Outcome, DesignError> {
        let groups = self.all_groups();
        let mut s = self.begin();
        loop {
            if self.should_stop(&s) {
                break;
            }
            self.iterations += 1;
            self.start_periods = s
                .incumbent
                .as_ref()
                .filter(|_| std::env::var_os("RTPIPE_NO_HINT").is_none())
                .map(|x| periods_of(&x.0));
            self.say(|| {
                let best = s.incumbent.as_ref().map_or(String::new(), |(_, _, u)| {
                    format!(", best verified U = {u:.4}")
                });
                let lb = s
                    .lower_bound
                    .map_or(String::new(), |b| format!(", lower bound {b:.4}"));
                format!("master problem {}{lb}{best}", self.iterations)
            });
            let solved = self.solve_master(&groups, s.sound.as_ref());
            match solved {
                Solved::Error(e) => return Err(e),
                Solved::Stopped => break,
                Solved::Infeasible => return Ok(self.infeasible(&groups, s)),
                Solved::Periods {
                    periods,
                    objective,
                    optimal,
                    responses,
                } => {
                    if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
                        eprintln!(
                            "iteration {}: objective {objective:.6} optimal {optimal} periods {:?} ({:.2} s)",
                            self.iterations,
                            periods,
                            self.elapsed()
                        );
                    }
                    let cand = Candidate {
                        periods,
                        objective,
                        optimal,
                        responses,
                    };
                    if let Some(o) = self.candidate(&groups, &mut s, cand)? {
                        return Ok(o);
                    }
                }
            }
        }
        Ok(self.stopped(s))
    }

    /// The search's state before the first master: the lower bound with
    /// every period at its longest, and a quick verified design if there is
    /// an easy one (reported when the exact search runs out of time; it
    /// does not start the patience).
    fn begin(&mut self) -> Search {
        // The master is always a relaxation: utilisation and the hyperbolic
        // term are under-approximated by tangents, response times by valid
        // lower bounds. A candidate that the analysis verifies is therefore
        // optimal; one that fails yields a cut that removes it.
        let sound = match self.opts.mode {
            Mode::Paper => None,
            Mode::Sound => Some(SoundModel {
                rlow: self.rhat_lower(),
                cuts: Vec::new(),
                fixed: None,
            }),
        };
        let lower_bound: Option<f64> = Some(
            (0..self.spec.tasks.len())
                .filter(|&i| self.spec.tasks[i].server != Server::Background)
                .map(|i| self.spec.tasks[i].budget() as f64 / (self.dom[i].max() * self.g) as f64)
                .sum(),
        );
        let incumbent = self.descent();
        self.publish(&incumbent, lower_bound);
        Search {
            sound,
            lower_bound,
            incumbent,
            heuristic_tried: false,
            exact_since: None,
            notes: Vec::new(),
        }
    }

    /// Out of iterations, time or work, or of patience after the exact
    /// search found a verified design.
    fn should_stop(&self, s: &Search) -> bool {
        let patience_out = s.incumbent.is_some()
            && self.opts.time_limit.is_none()
            && self.opts.patience.is_some_and(|p| {
                s.exact_since
                    .is_some_and(|t| self.work.saturating_sub(t) > p)
            });
        self.iterations >= self.opts.max_iterations || self.out_of_time() || patience_out
    }

    /// The master is infeasible: the problem is. Explaining it gets a
    /// bounded effort unless a time limit says otherwise.
    fn infeasible(&mut self, groups: &[Group], mut s: Search) -> Outcome {
        if let (None, Some(p)) = (self.opts.time_limit, self.opts.patience) {
            self.work_cap = Some(self.work.saturating_add(EXPLAIN_EFFORT.saturating_mul(p)));
        }
        let (conflicts, minimal) = self.explain(groups, s.sound.as_ref());
        if !minimal || self.out_of_time() {
            s.notes.push(if self.opts.time_limit.is_some() {
                "the conflict search ran out of time: the set may not be minimal and fixes may be missing".to_string()
            } else {
                "the conflict search used up its work budget: the set may not be minimal and fixes may be missing (--time-limit S searches for S seconds instead)".to_string()
            });
        }
        self.outcome(Status::Infeasible, None, None, conflicts, s.notes)
    }

    /// One candidate of the master: checked by the analysis, kept if it
    /// verifies, and either the answer (`Some`) or the source of new cuts,
    /// tangents or response-time levels for the next master (`None`).
    fn candidate(
        &mut self,
        groups: &[Group],
        s: &mut Search,
        c: Candidate,
    ) -> Result<Option<Outcome>, DesignError> {
        if c.optimal {
            s.lower_bound = Some(
                s.lower_bound
                    .map_or(c.objective, |b: f64| b.max(c.objective)),
            );
        }
        let cand = self.with_periods(&c.periods);
        let report = rtpipe_analysis::analyze(&cand);
        self.keep_if_verified(s, &cand, &report);
        if !s.heuristic_tried && s.sound.is_some() && !self.limits_ok(&report) {
            self.run_heuristic(groups, s, &cand, &report);
        }
        let oa = self.oa_exact(&c.periods);
        // Response times the model under-counted: count more jobs.
        let verified = report.schedulability.schedulable && self.limits_ok(&report);
        if !verified && self.raise_levels(&cand, &report) {
            return Ok(None);
        }
        let sched = self.sched_ok(&cand, &report);
        if !oa || !sched {
            // Learn response times from the same candidate now rather than
            // after it comes back.
            if let Some(sm) = &mut s.sound {
                learn_r_cuts(self.g, &cand, &report, &c.periods, &c.responses, sm);
            }
            return Ok(None);
        }
        if self.limits_ok(&report) {
            return Ok(Some(self.verified(s, cand, report, c.optimal)));
        }
        let Some(sm) = &mut s.sound else {
            return Err(DesignError::internal(
                "internal: the paper-mode model and the analysis disagree on a candidate",
            ));
        };
        // Learn the response times the model under-estimated.
        if !learn_r_cuts(self.g, &cand, &report, &c.periods, &c.responses, sm) {
            return Err(DesignError::internal(
                "internal: the sound model and the analysis disagree on a candidate",
            ));
        }
        Ok(None)
    }

    /// Any candidate the analysis accepts is a valid design, optimal or
    /// not: keep the best one; the patience runs from the first.
    fn keep_if_verified(&mut self, s: &mut Search, cand: &Spec, report: &Report) {
        if report.schedulability.schedulable && self.limits_ok(report) {
            let u = utilization(cand);
            if s.incumbent.as_ref().is_none_or(|(_, _, b)| u < *b) {
                s.incumbent = Some((cand.clone(), report.clone(), u));
                self.publish(&s.incumbent, s.lower_bound);
            }
            s.exact_since.get_or_insert(self.work);
        }
        if let (Some(t), None, None, Some(p)) = (
            s.exact_since,
            self.opts.time_limit,
            self.work_cap,
            self.opts.patience,
        ) {
            self.work_cap = Some(t.saturating_add(p));
        }
    }

    /// Once, at the first candidate that misses a limit (sound mode): look
    /// for a verified design quickly, with response times pinned to
    /// estimates and raised until one verifies.
    fn run_heuristic(&mut self, groups: &[Group], s: &mut Search, cand: &Spec, report: &Report) {
        let Some(sm) = s.sound.clone() else { return };
        s.heuristic_tried = true;
        let start: Vec<f64> = (0..cand.tasks.len())
            .map(|i| {
                let r = report.timing[i]
                    .job_response_time
                    .map_or(0.0, |r| gu(r, self.g));
                r.max(sm.rlow[i])
            })
            .collect();
        if let Some(h) = self.heuristic(groups, &sm, start) {
            if s.incumbent.as_ref().is_none_or(|(_, _, b)| h.2 < *b) {
                s.incumbent = Some(h);
                self.publish(&s.incumbent, s.lower_bound);
            }
        }
        s.exact_since.get_or_insert(self.work);
        if let (None, Some(_), Some(p)) = (self.opts.time_limit, &s.incumbent, self.opts.patience) {
            self.work_cap.get_or_insert(self.work.saturating_add(p));
        }
    }

    /// A candidate that verifies with nothing left to learn: the answer,
    /// optimal when the solve was or the gap is closed.
    fn verified(&mut self, s: &mut Search, cand: Spec, report: Report, optimal: bool) -> Outcome {
        // A stopped solve's candidate may be worse than the incumbent.
        let (cand, report) = match s.incumbent.take() {
            Some((c, r, u0)) if !optimal && u0 < utilization(&cand) => (c, r),
            _ => (cand, report),
        };
        let u = utilization(&cand);
        let lb = s.lower_bound.map(|b| b.min(u));
        let gap = lb.map(|b| if u > 0.0 { ((u - b) / u).max(0.0) } else { 0.0 });
        // An optimal solve of any master is a lower bound (every master is
        // a relaxation), earlier time-outs or not.
        let closed = gap.is_some_and(|g| g <= 1e-9);
        let status = if optimal || closed {
            Status::Optimal
        } else {
            Status::Feasible
        };
        let notes = std::mem::take(&mut s.notes);
        let mut o = self.outcome(status, Some((cand, report)), lb, Vec::new(), notes);
        o.objective = Some(u);
        o.gap = if status == Status::Optimal {
            Some(0.0)
        } else {
            gap
        };
        o
    }

    /// The search stopped: the best verified design with its gap, or
    /// nothing.
    fn stopped(&mut self, s: Search) -> Outcome {
        let Search {
            incumbent,
            lower_bound,
            mut notes,
            ..
        } = s;
        if let Some((cand, report, u)) = incumbent {
            notes.push(format!(
                "the exact search stopped ({}); the design is verified, the gap is to the best proven lower bound",
                if self.numerical.last_skipped {
                    "the solver failed numerically on a master problem"
                } else if self.opts.time_limit.is_some() {
                    "time limit"
                } else {
                    "work budget; --time-limit S searches for S seconds instead"
                }
            ));
            let lb = lower_bound.map(|b| b.min(u));
            let mut o = self.outcome(
                Status::Feasible,
                Some((cand, report)),
                lb,
                Vec::new(),
                notes,
            );
            o.objective = Some(u);
            o.gap = lb.map(|b| if u > 0.0 { ((u - b) / u).max(0.0) } else { 0.0 });
            if o.gap.is_some_and(|g| g <= 1e-9) {
                o.status = Status::Optimal;
                o.notes.pop();
            }
            return o;
        }
        notes.push(if self.numerical.last_skipped {
            "stopped by a numerical failure of the solver before a verified design".into()
        } else {
            "stopped by the time or iteration limit before a verified design".into()
        });
        let mut o = self.outcome(Status::Unknown, None, lower_bound, Vec::new(), notes);
        o.lower_bound = lower_bound;
        o
    }

    pub(crate) fn outcome(
        &self,
        status: Status,
        found: Option<(Spec, Report)>,
        lower_bound: Option<f64>,
        conflicts: Vec<Conflict>,
        notes: Vec<String>,
    ) -> Outcome {
        let (spec, report) = match found {
            Some((s, r)) => (Some(s), Some(r)),
            None => (None, None),
        };
        let mut notes = notes;
        notes.extend(self.numerical.note());
        Outcome {
            status,
            spec,
            report,
            objective: None,
            lower_bound,
            gap: None,
            method: if self.boxes {
                Method::Boxes
            } else {
                Method::Milp
            },
            solver: self.opts.solver,
            seconds: self.elapsed(),
            iterations: self.iterations,
            peak_open: 0,
            conflicts,
            notes,
        }
    }
}

/// What the MILP loop carries from one master solve to the next.
struct Search {
    /// The sound model's response-time knowledge (sound mode).
    sound: Option<SoundModel>,
    /// The best proven lower bound on the optimum.
    lower_bound: Option<f64>,
    /// The best verified design so far, with its Σ C/T.
    incumbent: Option<(Spec, Report, f64)>,
    /// The heuristic phase ran.
    heuristic_tried: bool,
    /// Work done when the exact search found its first verified design.
    exact_since: Option<u64>,
    notes: Vec<String>,
}

/// A master's answer: periods per task (ns), the model objective, proven
/// optimal, and the model's response times (grid units) where it has them.
struct Candidate {
    periods: Vec<Nanos>,
    objective: f64,
    optimal: bool,
    responses: Vec<Option<f64>>,
}

/// The period of every task of a spec whose periods are fixed (ns).
fn periods_of(spec: &Spec) -> Vec<Nanos> {
    spec.tasks
        .iter()
        .map(|t| t.fixed_period().unwrap_or(0))
        .collect()
}
