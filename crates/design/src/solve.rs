//! One master solve: a starting solution from the incumbent, the solver's
//! numerical failures, and the candidate it returns.

use crate::api::DesignError;
use crate::budget::Budget;
use crate::domain::Dom;
use crate::learnt::Learnt;
use crate::lp::{self, Limits, LpError, LpSolution, Numerical, SolverKind};
use crate::master::build_within;
use crate::model::Master;
use crate::problem::{debug, Group, Problem};
use crate::sound::SoundModel;
use rtpipe_model::Nanos;

/// Work the starting solution of a master may take.
pub(crate) const HINT_NODES: u64 = 2_000;

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
        /// The model's job response times (grid units) where it has them,
        /// one per task, then its read-to-publish bounds likewise.
        responses: Vec<Option<f64>>,
    },
    Error(DesignError),
}

/// Builds and solves the master of `p` over `groups` with what the search
/// has learnt, spending from `budget`.
pub(crate) fn solve_master(
    p: &Problem,
    learnt: &Learnt,
    budget: &mut Budget,
    groups: &[Group],
    sound: Option<&SoundModel>,
) -> Solved {
    let out_of_time = || budget.out_of_time();
    let Some((m, _)) = build_within(p, learnt, groups, sound, &out_of_time) else {
        return Solved::Stopped;
    };
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
    // A large master takes long to build, and the solver's own set-up
    // (before it looks at its time limit) longer still: with the time or
    // work gone, solving it would only overrun the limit.
    if budget.out_of_time() {
        return Solved::Stopped;
    }
    let hint = hint(p, learnt, budget, &m);
    let left = budget.left();
    let lp::Solve {
        result: solved,
        work,
        numerical,
    } = lp::solve_hinted(&m.lp, p.opts.solver, left, hint.as_deref());
    budget.work = budget.work.saturating_add(work);
    note_numerical(budget, numerical.as_ref());
    if debug() {
        match &solved {
            Err(e) => eprintln!(
                "master: {e} (limit {left:?}, work {}, {:.2} s)",
                budget.work,
                budget.elapsed()
            ),
            Ok(_) => eprintln!(
                "master: solved (work {}, {:.2} s)",
                budget.work,
                budget.elapsed()
            ),
        }
    }
    read(p, &m, solved, numerical.is_some())
}

/// A complete starting solution: the master with every period fixed to
/// the best verified design's (a small MILP: the periods decide most
/// binaries), so that branch and bound can prune by bound from the start.
/// microlp only.
fn hint(p: &Problem, learnt: &Learnt, budget: &mut Budget, m: &Master) -> Option<Vec<f64>> {
    let (Some(periods), SolverKind::Microlp) = (&learnt.hint, p.opts.solver) else {
        return None;
    };
    let fixed = fix_periods(m, periods, p.g);
    let left = budget.left();
    let s = lp::solve(
        &fixed,
        p.opts.solver,
        Limits {
            time: left.time,
            nodes: Some(HINT_NODES.min(left.nodes.unwrap_or(u64::MAX))),
        },
    );
    budget.work = budget.work.saturating_add(s.work);
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
fn note_numerical(budget: &mut Budget, numerical: Option<&Numerical>) {
    budget.numerical.count(numerical);
    if let (Some(n), true) = (numerical, debug()) {
        eprintln!("master: numerical failure {n:?}");
    }
}

/// The solver's answer as a [`Solved`]: a candidate's periods read off the
/// period expressions.
fn read(p: &Problem, m: &Master, solved: Result<LpSolution, LpError>, numerical: bool) -> Solved {
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
            periods: (0..p.spec.tasks.len())
                .map(|i| (m.period[i].eval(&sol.values).round() as i64) * p.g)
                .collect(),
            objective: sol.objective,
            optimal: sol.optimal,
            responses: m
                .rvar
                .iter()
                .chain(&m.wvar)
                .map(|v| v.map(|v| sol.values[v]))
                .collect(),
        },
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
