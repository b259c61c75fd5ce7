//! A small solver-independent MILP, handed to good_lp for each solve.
//!
//! The design loop adds cuts between solves (outer approximation, lazy
//! schedulability cuts, response-time updates), so it keeps its own model and
//! rebuilds the good_lp problem every time; the solver backend is a choice
//! made at run time.

use good_lp::{
    constraint, variable, Expression, ProblemVariables, ResolutionError, Solution, SolutionStatus,
    SolverModel, Variable, WithTimeLimit,
};
use std::fmt;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverKind {
    /// Pure-Rust microlp (default build).
    Microlp,
    /// HiGHS (cargo feature `highs`).
    Highs,
}

impl SolverKind {
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Microlp => "microlp",
            SolverKind::Highs => "highs",
        }
    }
    pub fn available(self) -> bool {
        match self {
            SolverKind::Microlp => true,
            SolverKind::Highs => cfg!(feature = "highs"),
        }
    }
}

#[derive(Debug, Clone, Copy)]
pub struct VarDef {
    pub lo: f64,
    pub hi: f64,
    pub integer: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cmp {
    Le,
    Ge,
    Eq,
}

#[derive(Debug, Clone)]
pub struct Row {
    pub terms: Vec<(usize, f64)>,
    pub cmp: Cmp,
    pub rhs: f64,
}

/// min Σ obj·x subject to rows, bounds and integrality.
#[derive(Debug, Clone, Default)]
pub struct Lp {
    pub vars: Vec<VarDef>,
    pub rows: Vec<Row>,
    pub obj: Vec<(usize, f64)>,
    pub obj_const: f64,
}

impl Lp {
    pub fn var(&mut self, lo: f64, hi: f64, integer: bool) -> usize {
        self.vars.push(VarDef { lo, hi, integer });
        self.vars.len() - 1
    }
    pub fn binary(&mut self) -> usize {
        self.var(0.0, 1.0, true)
    }
    pub fn row(&mut self, terms: Vec<(usize, f64)>, cmp: Cmp, rhs: f64) {
        self.rows.push(Row { terms, cmp, rhs });
    }
}

#[derive(Debug, Clone)]
pub struct LpSolution {
    pub values: Vec<f64>,
    pub objective: f64,
    /// The solver proved optimality (not stopped by a limit).
    pub optimal: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub enum LpError {
    Infeasible,
    Unbounded,
    /// Stopped by the time limit before a solution or a proof.
    TimeLimit,
    /// The solver is not compiled in.
    Unavailable(&'static str),
    Other(String),
}

impl fmt::Display for LpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LpError::Infeasible => write!(f, "infeasible"),
            LpError::TimeLimit => write!(f, "time limit reached"),
            LpError::Unbounded => write!(f, "unbounded"),
            LpError::Unavailable(s) => write!(
                f,
                "solver {s} is not built in; rebuild with `cargo build --release --features highs`"
            ),
            LpError::Other(s) => write!(f, "solver error: {s}"),
        }
    }
}

fn expr(vars: &[Variable], terms: &[(usize, f64)]) -> Expression {
    let mut e = Expression::from(0.0);
    // Zero coefficients (a big-M the domains made 0) upset microlp's pivoting.
    for &(i, c) in terms {
        if c != 0.0 {
            e += c * vars[i];
        }
    }
    e
}

fn build(lp: &Lp) -> (ProblemVariables, Vec<Variable>, Expression) {
    let mut pv = ProblemVariables::new();
    let vars: Vec<Variable> = lp
        .vars
        .iter()
        .map(|d| {
            let mut v = variable().min(d.lo).max(d.hi);
            if d.integer {
                v = v.integer();
            }
            pv.add(v)
        })
        .collect();
    let obj = expr(&vars, &lp.obj) + lp.obj_const;
    (pv, vars, obj)
}

fn finish<M>(lp: &Lp, vars: &[Variable], model: M) -> Result<LpSolution, LpError>
where
    M: SolverModel,
    M::Error: Into<ResolutionError>,
{
    let mut model = model;
    for r in &lp.rows {
        if r.terms.iter().all(|&(_, c)| c == 0.0) {
            // A row without variables: decide it here (microlp cannot).
            let ok = match r.cmp {
                Cmp::Le => 0.0 <= r.rhs + 1e-9,
                Cmp::Ge => 0.0 >= r.rhs - 1e-9,
                Cmp::Eq => r.rhs.abs() <= 1e-9,
            };
            if ok {
                continue;
            }
            return Err(LpError::Infeasible);
        }
        let e = expr(vars, &r.terms);
        let c = match r.cmp {
            Cmp::Le => constraint::leq(e, r.rhs),
            Cmp::Ge => constraint::geq(e, r.rhs),
            Cmp::Eq => constraint::eq(e, r.rhs),
        };
        model.add_constraint(c);
    }
    match model.solve().map_err(Into::into) {
        Ok(sol) => {
            let values: Vec<f64> = vars.iter().map(|&v| sol.value(v)).collect();
            let objective = lp.obj.iter().map(|&(i, c)| c * values[i]).sum::<f64>() + lp.obj_const;
            Ok(LpSolution {
                values,
                objective,
                optimal: matches!(sol.status(), SolutionStatus::Optimal),
            })
        }
        Err(ResolutionError::Infeasible) => Err(LpError::Infeasible),
        Err(ResolutionError::Unbounded) => Err(LpError::Unbounded),
        // microlp says so in words when its time runs out without a solution.
        Err(e) if e.to_string().contains("Time limit") => Err(LpError::TimeLimit),
        // HiGHS, stopped by its time limit before any solution.
        Err(e) if e.to_string().contains("NoSolutionFound") => Err(LpError::TimeLimit),
        Err(e) => Err(LpError::Other(e.to_string())),
    }
}

/// Solves with the chosen backend and an optional time limit in seconds.
pub fn solve(lp: &Lp, solver: SolverKind, time_limit: Option<f64>) -> Result<LpSolution, LpError> {
    let started = std::time::Instant::now();
    let r = solve_inner(lp, solver, time_limit);
    // Backends report a time-limited solve without a solution as
    // "infeasible"; that is not a proof.
    match (r, time_limit) {
        (Err(LpError::Infeasible), Some(t)) if started.elapsed().as_secs_f64() >= 0.5 * t => {
            Err(LpError::TimeLimit)
        }
        (r, _) => r,
    }
}

fn solve_inner(
    lp: &Lp,
    solver: SolverKind,
    time_limit: Option<f64>,
) -> Result<LpSolution, LpError> {
    let (pv, vars, obj) = build(lp);
    match solver {
        SolverKind::Microlp => {
            let mut m = pv.minimise(obj).using(good_lp::microlp);
            if let Some(t) = time_limit {
                m = m.with_time_limit(t.max(0.01));
            }
            finish(lp, &vars, m)
        }
        SolverKind::Highs => solve_highs(lp, pv, vars, obj, time_limit),
    }
}

#[cfg(feature = "highs")]
fn solve_highs(
    lp: &Lp,
    pv: ProblemVariables,
    vars: Vec<Variable>,
    obj: Expression,
    time_limit: Option<f64>,
) -> Result<LpSolution, LpError> {
    let mut m = pv.minimise(obj).using(good_lp::highs);
    m.set_verbose(false);
    // HiGHS stops at a 1e-4 relative and 1e-6 absolute gap by default (the
    // objective is a utilisation, so 1e-6 is not small); "optimal" must mean it.
    let mut m = m
        .set_mip_rel_gap(1e-9)
        .and_then(|m| m.set_mip_abs_gap(1e-12))
        .map_err(|e| LpError::Other(e.to_string()))?;
    if let Some(t) = time_limit {
        m = m.with_time_limit(t.max(0.01));
    }
    finish(lp, &vars, m)
}

#[cfg(not(feature = "highs"))]
fn solve_highs(
    _lp: &Lp,
    _pv: ProblemVariables,
    _vars: Vec<Variable>,
    _obj: Expression,
    _time_limit: Option<f64>,
) -> Result<LpSolution, LpError> {
    Err(LpError::Unavailable("highs"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_milp() {
        // min −x − y, x + 2y ≤ 4, 3x + y ≤ 6, integers in [0, 10]: optimum x = 1, y = 1
        // or x = 2, y = 0 (both −2)... with objective −x − 2y: (0, 2) → −4.
        let mut lp = Lp::default();
        let x = lp.var(0.0, 10.0, true);
        let y = lp.var(0.0, 10.0, true);
        lp.obj = vec![(x, -1.0), (y, -2.0)];
        lp.row(vec![(x, 1.0), (y, 2.0)], Cmp::Le, 4.0);
        lp.row(vec![(x, 3.0), (y, 1.0)], Cmp::Le, 6.0);
        match solve(&lp, SolverKind::Microlp, None) {
            Ok(s) => {
                assert!((s.objective + 4.0).abs() < 1e-9);
                assert!(s.optimal);
            }
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn infeasible_is_reported() {
        let mut lp = Lp::default();
        let x = lp.var(0.0, 1.0, true);
        lp.row(vec![(x, 1.0)], Cmp::Ge, 2.0);
        assert_eq!(
            solve(&lp, SolverKind::Microlp, None).err(),
            Some(LpError::Infeasible)
        );
    }
}
