//! One master solve: a starting solution from the incumbent, the solver's
//! numerical failures, and the candidate it returns.

use crate::domain::Dom;
use crate::lp::{self, Limits, LpError, LpSolution, Numerical, SolverKind};
use crate::master::Group;
use crate::master::Master;
use crate::runner::Runner;
use crate::sound::SoundModel;
use crate::DesignError;
use rtpipe_model::Nanos;

/// Work the starting solution of a master may take.
pub(crate) const HINT_NODES: u64 = 2_000;

/// Master problems on which the solver failed numerically (`lp::solve`
/// re-solves them written differently first), by what became of them.
#[derive(Debug, Clone, Default)]
pub(crate) struct NumLog {
    /// The solver's first message.
    pub(crate) message: Option<String>,
    /// Answered by a re-solve.
    pub(crate) resolved: usize,
    /// Every attempt failed; a failed attempt's best solution was used.
    pub(crate) from_failed: usize,
    /// Every attempt failed without a solution: skipped as undecided.
    pub(crate) skipped: usize,
    /// The last master solve was skipped that way.
    pub(crate) last_skipped: bool,
}

impl NumLog {
    /// Counts one master solve's numerical failure, if any, by what became
    /// of it.
    pub(crate) fn count(&mut self, numerical: Option<&Numerical>) {
        self.last_skipped = false;
        let Some(n) = numerical else { return };
        if self.message.is_none() {
            self.message = Some(n.message.clone());
        }
        if n.from_failed {
            self.from_failed += 1;
        } else if n.solved_by > 0 {
            self.resolved += 1;
        } else {
            self.skipped += 1;
            self.last_skipped = true;
        }
    }

    pub(crate) fn absorb(&mut self, o: &NumLog) {
        if self.message.is_none() {
            self.message.clone_from(&o.message);
        }
        self.resolved += o.resolved;
        self.from_failed += o.from_failed;
        self.skipped += o.skipped;
        self.last_skipped = o.last_skipped;
    }

    /// What the outcome says about them.
    pub(crate) fn note(&self) -> Option<String> {
        let total = self.resolved + self.from_failed + self.skipped;
        if total == 0 {
            return None;
        }
        let mut done = Vec::new();
        if self.resolved > 0 {
            done.push(format!(
                "{} re-solved with the rows rescaled or reordered",
                self.resolved
            ));
        }
        if self.from_failed > 0 {
            done.push(format!(
                "{} answered by the best solution found before the failure (no lower bound from it)",
                self.from_failed
            ));
        }
        if self.skipped > 0 {
            done.push(format!(
                "{} given up (treated as undecided, like a time limit)",
                self.skipped
            ));
        }
        Some(format!(
            "the solver failed numerically ({}) on {total} master problem{}: {}; any design shown is verified by the analysis",
            self.message.as_deref().unwrap_or("no message"),
            if total == 1 { "" } else { "s" },
            done.join(", ")
        ))
    }
}

pub(crate) enum Solved {
    Infeasible,
    /// Stopped by a time or work limit, or by a numerical failure of the
    /// solver that re-solving did not get round: nothing proven.
    Stopped,
    /// A candidate.
    Periods {
        /// Period per task (ns).
        periods: Vec<Nanos>,
        /// The model's objective there.
        objective: f64,
        /// Proven optimal for the master.
        optimal: bool,
        /// The model's job response times (grid units) where it has them.
        responses: Vec<Option<f64>>,
    },
    Error(DesignError),
}

/// Whether `RTPIPE_DESIGN_DEBUG` asks for the master's story on stderr.
fn debug() -> bool {
    std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some()
}

impl<'a> Runner<'a> {
    /// What is left of the time and work budgets.
    fn left(&self) -> Limits {
        Limits {
            time: self.opts.time_limit.map(|t| (t - self.elapsed()).max(0.01)),
            nodes: self.work_cap.map(|c| c.saturating_sub(self.work)),
        }
    }

    /// Builds and solves the master over `groups`.
    pub(crate) fn solve_master(&mut self, groups: &[Group], sound: Option<&SoundModel>) -> Solved {
        let (m, _) = self.build(groups, sound);
        if debug() {
            let bins =
                m.lp.vars
                    .iter()
                    .filter(|v| v.integer && v.hi <= 1.0)
                    .count();
            eprintln!(
                "master: {} variables ({bins} binary), {} rows",
                m.lp.vars.len(),
                m.lp.rows.len()
            );
        }
        let hint = self.hint(&m);
        let left = self.left();
        let lp::Solve {
            result: solved,
            work,
            numerical,
        } = lp::solve_hinted(&m.lp, self.opts.solver, left, hint.as_deref());
        self.work = self.work.saturating_add(work);
        self.note_numerical(numerical.as_ref());
        if debug() {
            match &solved {
                Err(e) => eprintln!(
                    "master: {e} (limit {left:?}, work {}, {:.2} s)",
                    self.work,
                    self.elapsed()
                ),
                Ok(_) => eprintln!(
                    "master: solved (work {}, {:.2} s)",
                    self.work,
                    self.elapsed()
                ),
            }
        }
        self.read(&m, solved, numerical.is_some())
    }

    /// A complete starting solution: the master with every period fixed to
    /// the best verified design's (a small MILP: the periods decide most
    /// binaries), so that branch and bound can prune by bound from the
    /// start. microlp only.
    fn hint(&mut self, m: &Master) -> Option<Vec<f64>> {
        let (Some(p), SolverKind::Microlp) = (&self.start_periods, self.opts.solver) else {
            return None;
        };
        let fixed = fix_periods(m, p, self.g);
        let left = self.left();
        let s = lp::solve(
            &fixed,
            self.opts.solver,
            Limits {
                time: left.time,
                nodes: Some(HINT_NODES.min(left.nodes.unwrap_or(u64::MAX))),
            },
        );
        self.work = self.work.saturating_add(s.work);
        if debug() {
            eprintln!(
                "master: starting solution {:?} (work {})",
                s.result.as_ref().map(|x| x.objective),
                s.work
            );
        }
        s.result.ok().map(|x| x.values)
    }

    /// Counts a numerical failure of the solver by what became of it.
    fn note_numerical(&mut self, numerical: Option<&Numerical>) {
        self.numerical.count(numerical);
        if let (Some(n), true) = (numerical, debug()) {
            eprintln!("master: numerical failure {n:?}");
        }
    }

    /// The solver's answer as a [`Solved`]: a candidate's periods read off
    /// the period expressions.
    fn read(&self, m: &Master, solved: Result<LpSolution, LpError>, numerical: bool) -> Solved {
        match solved {
            Err(LpError::Infeasible) => Solved::Infeasible,
            Err(LpError::TimeLimit | LpError::NodeLimit(_)) => Solved::Stopped,
            // The solver failed numerically on every attempt (`lp::solve`
            // re-solved it written differently): not the user's error, and
            // nothing proven; every caller treats it as a stopped solve.
            Err(LpError::Other(_)) if numerical => Solved::Stopped,
            Err(e @ LpError::TooLarge { .. }) => Solved::Error(
                DesignError::solver(format!(
                    "the solver cannot represent the model: {e}"
                ))
                .help(
                    "periods are integers in steps of the resolution: set a coarser `resolution` in [system] (e.g. \"1us\" or \"1ms\") or narrow the period ranges",
                ),
            ),
            Err(e) => Solved::Error(DesignError::solver(e.to_string())),
            Ok(sol) => Solved::Periods {
                periods: (0..self.spec.tasks.len())
                    .map(|i| (m.period[i].eval(&sol.values).round() as i64) * self.g)
                    .collect(),
                objective: sol.objective,
                optimal: sol.optimal,
                responses: m.rvar.iter().map(|v| v.map(|v| sol.values[v])).collect(),
            },
        }
    }
}

/// The master's LP with every period fixed to `periods` (ns).
pub(crate) fn fix_periods(m: &Master, periods: &[Nanos], g: i64) -> lp::Lp {
    let mut fixed = m.lp.clone();
    for (i, &pi) in periods.iter().enumerate() {
        let t = pi / g;
        match &m.dom[i] {
            Dom::Grid { step, .. } => {
                if let Some(k) = m.kvar[i] {
                    let k0 = (t / step) as f64;
                    fixed.vars[k].lo = k0;
                    fixed.vars[k].hi = k0;
                }
            }
            Dom::Choice(v) => {
                for (x, &y) in m.yvars[i].iter().enumerate() {
                    let on = if v[x] == t { 1.0 } else { 0.0 };
                    fixed.vars[y].lo = on;
                    fixed.vars[y].hi = on;
                }
            }
            Dom::Fixed(_) => {}
        }
    }
    fixed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn failure(solved_by: u32, from_failed: bool) -> Numerical {
        Numerical {
            message: "Singular matrix".into(),
            retries: 3,
            solved_by,
            from_failed,
        }
    }

    #[test]
    fn numerical_failures_are_counted_and_noted() {
        let mut log = NumLog::default();
        log.count(None);
        assert_eq!(log.note(), None);
        log.count(Some(&failure(2, false)));
        log.count(Some(&failure(0, true)));
        log.count(Some(&failure(0, false)));
        assert!(log.last_skipped);
        log.count(None);
        assert!(!log.last_skipped);
        assert_eq!((log.resolved, log.from_failed, log.skipped), (1, 1, 1));
        assert_eq!(
            log.note().as_deref(),
            Some(
                "the solver failed numerically (Singular matrix) on 3 master problems: \
                 1 re-solved with the rows rescaled or reordered, 1 answered by the best \
                 solution found before the failure (no lower bound from it), 1 given up \
                 (treated as undecided, like a time limit); any design shown is verified \
                 by the analysis"
            )
        );
    }
}
