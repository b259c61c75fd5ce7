//! A small solver-independent MILP, handed to good_lp for each solve.
//!
//! The design loop adds cuts between solves (outer approximation, lazy
//! schedulability cuts, response-time updates), so it keeps its own model and
//! rebuilds the good_lp problem every time; the solver backend is a choice
//! made at run time.

#[cfg(feature = "highs")]
use good_lp::{constraint, ResolutionError, Solution, SolutionStatus, SolverModel, WithTimeLimit};
use good_lp::{variable, Expression, ProblemVariables, Variable};
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
    /// Work done: branch-and-bound nodes plus one for the solve.
    pub work: u64,
}

/// What may stop a solve early. A node limit is deterministic: the same
/// model and limit give the same answer on any machine.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Limits {
    /// Wall-clock seconds.
    pub time: Option<f64>,
    /// Branch-and-bound nodes (a HiGHS solve stopped by it is charged the
    /// whole limit; one that finishes counts 1).
    pub nodes: Option<u64>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum LpError {
    Infeasible,
    Unbounded,
    /// Stopped by the time limit before a solution or a proof.
    TimeLimit,
    /// Stopped by the node limit before a solution or a proof, after this
    /// much work.
    NodeLimit(u64),
    /// An integer variable's bounds exceed what the backend represents
    /// (microlp: the i32 range).
    TooLarge {
        var: usize,
        lo: f64,
        hi: f64,
    },
    /// The solver is not compiled in.
    Unavailable(&'static str),
    Other(String),
}

impl fmt::Display for LpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LpError::Infeasible => write!(f, "infeasible"),
            LpError::TimeLimit => write!(f, "time limit reached"),
            LpError::NodeLimit(_) => write!(f, "work limit reached"),
            LpError::TooLarge { lo, hi, .. } => write!(
                f,
                "an integer variable ranges over [{lo}, {hi}], beyond the solver's integer range [{}, {}]",
                i32::MIN,
                i32::MAX
            ),
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

#[cfg(feature = "highs")]
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
                work: 1,
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

/// Solves with the chosen backend within `limits`.
pub fn solve(lp: &Lp, solver: SolverKind, limits: Limits) -> Result<LpSolution, LpError> {
    match solver {
        SolverKind::Microlp => solve_microlp(lp, limits),
        SolverKind::Highs => {
            let started = std::time::Instant::now();
            let (pv, vars, obj) = build(lp);
            let r = solve_highs(lp, pv, vars, obj, limits);
            // HiGHS reports a time-limited solve without a solution as
            // "infeasible"; that is not a proof.
            match (r, limits.time) {
                (Err(LpError::Infeasible), Some(t))
                    if started.elapsed().as_secs_f64() >= 0.5 * t =>
                {
                    Err(LpError::TimeLimit)
                }
                (r, _) => r,
            }
        }
    }
}

/// Nodes per microlp call when a node limit applies: the work of a solve
/// that ends in a proof of infeasibility (microlp reports no statistics
/// then) is counted to within this many nodes.
const NODE_CHUNK: u64 = 64;

/// microlp directly (not through good_lp), for its deterministic node limit
/// and node count.
fn solve_microlp(lp: &Lp, limits: Limits) -> Result<LpSolution, LpError> {
    use microlp::{ComparisonOp, LinearExpr, OptimizationDirection, Problem, SolveOutcome};
    let mut p = Problem::new(OptimizationDirection::Minimize);
    let mut obj = vec![0.0; lp.vars.len()];
    // Repeated objective terms add up.
    for &(i, c) in &lp.obj {
        obj[i] += c;
    }
    let mut vars = Vec::with_capacity(lp.vars.len());
    for (k, d) in lp.vars.iter().enumerate() {
        if d.integer {
            let (lo, hi) = (d.lo.ceil(), d.hi.floor());
            let range = i32::MIN as f64..=i32::MAX as f64;
            if !range.contains(&lo) || !range.contains(&hi) {
                return Err(LpError::TooLarge {
                    var: k,
                    lo: d.lo,
                    hi: d.hi,
                });
            }
            if lo > hi {
                return Err(LpError::Infeasible);
            }
            vars.push(p.add_integer_var(obj[k], (lo as i32, hi as i32)));
        } else {
            vars.push(p.add_var(obj[k], (d.lo, d.hi)));
        }
    }
    for r in &lp.rows {
        // microlp wants each variable once per row: merge repeated terms.
        let mut merged: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
        for &(i, c) in &r.terms {
            *merged.entry(i).or_insert(0.0) += c;
        }
        if merged.values().all(|&c| c == 0.0) {
            // A row without variables: decide it here.
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
        let mut e = LinearExpr::empty();
        // Zero coefficients (a big-M the domains made 0) upset microlp's pivoting.
        for (&i, &c) in &merged {
            if c != 0.0 {
                e.add(vars[i], c);
            }
        }
        let op = match r.cmp {
            Cmp::Le => ComparisonOp::Le,
            Cmp::Ge => ComparisonOp::Ge,
            Cmp::Eq => ComparisonOp::Eq,
        };
        p.add_constraint(e, op, r.rhs);
    }
    let mut opts = microlp::SolveOptions::default();
    opts.time_limit = limits.time.map(|t| {
        std::time::Duration::try_from_secs_f64(t.max(0.01)).unwrap_or(std::time::Duration::MAX)
    });
    let mut left = limits.nodes;
    let chunk = |left: Option<u64>| left.map(|l| l.min(NODE_CHUNK));
    opts.node_limit = chunk(left);
    let map_err = |e: microlp::Error| match e {
        microlp::Error::Infeasible => LpError::Infeasible,
        microlp::Error::Unbounded => LpError::Unbounded,
        other => LpError::Other(other.to_string()),
    };
    let mut done: u64 = 0;
    let mut out = p.solve_with(opts).map_err(map_err)?;
    loop {
        let nodes = out.stats().nodes_solved;
        let by_nodes = out.termination_reason() == microlp::TerminationReason::NodeLimit;
        if let (true, Some(l)) = (by_nodes, left) {
            let used = nodes - done;
            done = nodes;
            let l = l.saturating_sub(used);
            left = Some(l);
            if l > 0 {
                // Go on with a fresh chunk (counted exactly: a chunk that
                // ends in a proof of infeasibility is charged in full).
                let mut r = out.last_resume_options();
                r.node_limit = chunk(left);
                out = match out.resume_with(r) {
                    Ok(o) => o,
                    Err(microlp::Error::Infeasible) => return Err(LpError::Infeasible),
                    Err(e) => return Err(map_err(e)),
                };
                continue;
            }
        }
        let work = 1 + nodes;
        return match out {
            SolveOutcome::Solution(sol) => {
                let values: Vec<f64> = vars.iter().map(|&v| sol.var_value(v)).collect();
                let objective =
                    lp.obj.iter().map(|&(i, c)| c * values[i]).sum::<f64>() + lp.obj_const;
                Ok(LpSolution {
                    values,
                    objective,
                    optimal: sol.status() == microlp::SolutionStatus::Optimal,
                    work,
                })
            }
            SolveOutcome::Interrupted(_) if by_nodes => Err(LpError::NodeLimit(work)),
            SolveOutcome::Interrupted(_) => Err(LpError::TimeLimit),
        };
    }
}

#[cfg(feature = "highs")]
fn solve_highs(
    lp: &Lp,
    pv: ProblemVariables,
    vars: Vec<Variable>,
    obj: Expression,
    limits: Limits,
) -> Result<LpSolution, LpError> {
    let mut m = pv.minimise(obj).using(good_lp::highs);
    m.set_verbose(false);
    // HiGHS stops at a 1e-4 relative and 1e-6 absolute gap by default (the
    // objective is a utilisation, so 1e-6 is not small); "optimal" must mean it.
    let mut m = m
        .set_mip_rel_gap(1e-9)
        .and_then(|m| m.set_mip_abs_gap(1e-12))
        .map_err(|e| LpError::Other(e.to_string()))?;
    if let Some(t) = limits.time {
        m = m.with_time_limit(t.max(0.01));
    }
    if let Some(n) = limits.nodes {
        m = m.set_option("mip_max_nodes", n.min(i32::MAX as u64) as i32);
    }
    // Work: 1 for a finished solve; a solve the node limit stopped is
    // charged the whole limit (HiGHS reports no node count through good_lp).
    let charged = 1 + limits.nodes.unwrap_or(0);
    match finish(lp, &vars, m) {
        Ok(mut s) => {
            if !s.optimal && limits.nodes.is_some() {
                s.work = charged;
            }
            Ok(s)
        }
        Err(LpError::TimeLimit) if limits.nodes.is_some() && limits.time.is_none() => {
            Err(LpError::NodeLimit(charged))
        }
        Err(e) => Err(e),
    }
}

#[cfg(not(feature = "highs"))]
fn solve_highs(
    _lp: &Lp,
    _pv: ProblemVariables,
    _vars: Vec<Variable>,
    _obj: Expression,
    _limits: Limits,
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
        match solve(&lp, SolverKind::Microlp, Limits::default()) {
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
            solve(&lp, SolverKind::Microlp, Limits::default()).err(),
            Some(LpError::Infeasible)
        );
    }
}
