//! The MILP search: master solves, each candidate checked by the analysis,
//! cuts and tangents until a candidate verifies or the master is infeasible.

use crate::api::{utilization, DesignError, Outcome, Status, EXPLAIN_EFFORT};
use crate::budget::Budget;
use crate::domain::grid_units;
use crate::explain::explain;
use crate::heuristic::{descent, heuristic};
use crate::learnt::Learnt;
use crate::problem::{Group, Problem};
use crate::solve::{solve_master, Solved};
use crate::sound::{learn_r_cuts, rhat_lower, w_lower, SoundModel};
use rtpipe_analysis::{Mode, Report};
use rtpipe_model::{Nanos, Server, Spec};

/// The MILP search of `p`: master solves until a candidate verifies with
/// nothing left to learn, the master turns infeasible, or a limit stops it.
/// What it learns goes to `learnt`, what it spends to `budget`.
pub(crate) fn solve_all(
    p: &Problem,
    learnt: &mut Learnt,
    budget: &mut Budget,
) -> Result<Outcome, DesignError> {
    budget.bound_search(p.opts);
    Milp { p, learnt, budget }.solve_all()
}

/// The three parts of one MILP search its steps use together.
struct Milp<'s, 'a> {
    p: &'s Problem<'a>,
    learnt: &'s mut Learnt,
    budget: &'s mut Budget,
}

impl Milp<'_, '_> {
    /// See [`solve_all`].
    fn solve_all(&mut self) -> Result<Outcome, DesignError> {
        let groups = self.p.all_groups();
        let mut s = self.begin();
        loop {
            if self.should_stop(&s) {
                break;
            }
            self.budget.iterations += 1;
            self.learnt.hint = s
                .incumbent
                .as_ref()
                .filter(|_| std::env::var_os("RTPIPE_NO_HINT").is_none())
                .map(|x| crate::gate::periods_ns(&x.0));
            self.p.say(|| {
                let best = s.incumbent.as_ref().map_or(String::new(), |(_, _, u)| {
                    format!(", best verified U = {u:.4}")
                });
                let lb = s
                    .lower_bound
                    .map_or(String::new(), |b| format!(", lower bound {b:.4}"));
                format!("master problem {}{lb}{best}", self.budget.iterations)
            });
            let solved = solve_master(self.p, self.learnt, self.budget, &groups, s.sound.as_ref());
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
                    if crate::problem::debug() {
                        eprintln!(
                            "iteration {}: objective {objective:.6} optimal {optimal} periods {:?} ({:.2} s)",
                            self.budget.iterations,
                            periods,
                            self.budget.elapsed()
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
        let sound = match self.p.opts.mode {
            Mode::Paper => None,
            Mode::Sound => Some(SoundModel {
                rlow: rhat_lower(self.p),
                wlow: w_lower(self.p),
                cuts: Vec::new(),
                fixed: None,
            }),
        };
        let lower_bound: Option<f64> = Some(
            (0..self.p.spec.tasks.len())
                .filter(|&i| self.p.spec.tasks[i].server != Server::Background)
                .map(|i| {
                    self.p.spec.tasks[i].budget() as f64 / (self.p.dom[i].max() * self.p.g) as f64
                })
                .sum(),
        );
        let incumbent = descent(self.p, self.budget);
        self.p.publish(&incumbent, lower_bound);
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
            && self.p.opts.time_limit.is_none()
            && self.p.opts.patience.is_some_and(|p| {
                s.exact_since
                    .is_some_and(|t| self.budget.work.saturating_sub(t) > p)
            });
        self.budget.iterations >= self.p.opts.max_iterations
            || self.budget.out_of_time()
            || patience_out
    }

    /// The master is infeasible: the problem is. Explaining it gets a
    /// bounded effort unless a time limit says otherwise.
    fn infeasible(&mut self, groups: &[Group], mut s: Search) -> Outcome {
        // The conflict search has an effort of its own.
        self.budget.search_cap = None;
        if let (None, Some(p)) = (self.p.opts.time_limit, self.p.opts.patience) {
            self.budget.work_cap = Some(
                self.budget
                    .work
                    .saturating_add(EXPLAIN_EFFORT.saturating_mul(p)),
            );
        }
        let (conflicts, minimal) =
            explain(self.p, self.learnt, self.budget, groups, s.sound.as_ref());
        if !minimal || self.budget.out_of_time() {
            s.notes.push(if self.p.opts.time_limit.is_some() {
                "the conflict search ran out of time: the set may not be minimal and fixes may be missing".to_string()
            } else {
                "the conflict search used up its work budget: the set may not be minimal and fixes may be missing (--time-limit S searches for S seconds instead)".to_string()
            });
        }
        self.budget
            .outcome(self.p, Status::Infeasible, None, None, conflicts, s.notes)
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
        let cand = self.p.with_periods(&c.periods);
        let report = rtpipe_analysis::analyze(&cand);
        self.keep_if_verified(s, &cand, &report);
        if !s.heuristic_tried && s.sound.is_some() && !self.p.limits_ok(&report) {
            self.run_heuristic(groups, s, &cand, &report);
        }
        let oa = self.learnt.oa_exact(self.p, &c.periods);
        // Response times the model under-counted: count more jobs.
        let verified = report.schedulability.schedulable && self.p.limits_ok(&report);
        if !verified && self.learnt.raise_levels(self.p, &cand, &report) {
            return Ok(None);
        }
        let sched = self.learnt.sched_ok(self.p, &cand, &report);
        if !oa || !sched {
            // Learn response times from the same candidate now rather than
            // after it comes back.
            if let Some(sm) = &mut s.sound {
                learn_r_cuts(self.p.g, &cand, &report, &c.periods, &c.responses, sm);
            }
            return Ok(None);
        }
        if self.p.limits_ok(&report) {
            return Ok(Some(self.verified(s, cand, report, c.optimal)));
        }
        let Some(sm) = &mut s.sound else {
            return Err(DesignError::internal(
                "internal: the paper-mode model and the analysis disagree on a candidate",
            ));
        };
        // Learn the response times the model under-estimated.
        if !learn_r_cuts(self.p.g, &cand, &report, &c.periods, &c.responses, sm) {
            return Err(DesignError::internal(
                "internal: the sound model and the analysis disagree on a candidate",
            ));
        }
        Ok(None)
    }

    /// Any candidate the analysis accepts is a valid design, optimal or
    /// not: keep the best one; the patience runs from the first.
    fn keep_if_verified(&mut self, s: &mut Search, cand: &Spec, report: &Report) {
        if report.schedulability.schedulable && self.p.limits_ok(report) {
            let u = utilization(cand);
            if s.incumbent.as_ref().is_none_or(|(_, _, b)| u < *b) {
                s.incumbent = Some((cand.clone(), report.clone(), u));
                self.p.publish(&s.incumbent, s.lower_bound);
            }
            s.exact_since.get_or_insert(self.budget.work);
        }
        if let (Some(t), None, None, Some(p)) = (
            s.exact_since,
            self.p.opts.time_limit,
            self.budget.work_cap,
            self.p.opts.patience,
        ) {
            self.budget.work_cap = Some(t.saturating_add(p));
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
                    .map_or(0.0, |r| grid_units(r, self.p.g));
                r.max(sm.rlow[i])
            })
            .collect();
        if let Some(h) = heuristic(self.p, self.learnt, self.budget, groups, &sm, start) {
            if s.incumbent.as_ref().is_none_or(|(_, _, b)| h.2 < *b) {
                s.incumbent = Some(h);
                self.p.publish(&s.incumbent, s.lower_bound);
            }
        }
        s.exact_since.get_or_insert(self.budget.work);
        if let (None, Some(_), Some(p)) =
            (self.p.opts.time_limit, &s.incumbent, self.p.opts.patience)
        {
            self.budget
                .work_cap
                .get_or_insert(self.budget.work.saturating_add(p));
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
        let mut o =
            self.budget
                .outcome(self.p, status, Some((cand, report)), lb, Vec::new(), notes);
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
                if self.budget.numerical.last_skipped {
                    "the solver failed numerically on a master problem"
                } else if self.p.opts.time_limit.is_some() {
                    "time limit"
                } else {
                    "work budget; --time-limit S searches for S seconds instead"
                }
            ));
            let lb = lower_bound.map(|b| b.min(u));
            let mut o = self.budget.outcome(
                self.p,
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
        notes.push(if self.budget.numerical.last_skipped {
            "stopped by a numerical failure of the solver before a verified design".into()
        } else {
            if self.p.opts.time_limit.is_some() {
                "stopped by the time or iteration limit before a verified design".into()
            } else {
                "stopped by the work budget before a verified design (--time-limit S searches for S seconds instead)".into()
            }
        });
        let mut o = self.budget.outcome(
            self.p,
            Status::Unknown,
            None,
            lower_bound,
            Vec::new(),
            notes,
        );
        o.lower_bound = lower_bound;
        o
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
