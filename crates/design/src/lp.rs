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

/// Which MILP backend solves the master problems.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverKind {
    /// Pure-Rust microlp (default build).
    Microlp,
    /// HiGHS (cargo feature `highs`).
    Highs,
}

impl SolverKind {
    /// The name the CLI's `--solver` takes.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Microlp => "microlp",
            SolverKind::Highs => "highs",
        }
    }

    /// Compiled into this build.
    pub fn available(self) -> bool {
        match self {
            SolverKind::Microlp => true,
            SolverKind::Highs => cfg!(feature = "highs"),
        }
    }
}

/// A variable: its bounds and whether it is integer.
#[derive(Debug, Clone, Copy)]
pub struct VarDef {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
    /// Integer (a binary when its bounds are 0 and 1).
    pub integer: bool,
}

/// The sense of a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cmp {
    /// Σ a·x ≤ rhs.
    Le,
    /// Σ a·x ≥ rhs.
    Ge,
    /// Σ a·x = rhs.
    Eq,
}

/// One linear constraint `Σ a·x cmp rhs`.
#[derive(Debug, Clone)]
pub struct Row {
    /// (variable, coefficient) pairs.
    pub terms: Vec<(usize, f64)>,
    /// Its sense.
    pub cmp: Cmp,
    /// Right-hand side.
    pub rhs: f64,
}

/// min Σ obj·x subject to rows, bounds and integrality.
#[derive(Debug, Clone, Default)]
pub struct Lp {
    /// The variables, by index.
    pub vars: Vec<VarDef>,
    /// The constraints.
    pub rows: Vec<Row>,
    /// The objective's (variable, coefficient) pairs (minimised).
    pub obj: Vec<(usize, f64)>,
    /// The objective's constant.
    pub obj_const: f64,
}

impl Lp {
    /// Adds a variable; returns its index.
    pub fn var(&mut self, lo: f64, hi: f64, integer: bool) -> usize {
        self.vars.push(VarDef { lo, hi, integer });
        self.vars.len() - 1
    }

    /// Adds a binary variable; returns its index.
    pub fn binary(&mut self) -> usize {
        self.var(0.0, 1.0, true)
    }

    /// Adds the row `Σ terms cmp rhs`.
    pub fn row(&mut self, terms: Vec<(usize, f64)>, cmp: Cmp, rhs: f64) {
        self.rows.push(Row { terms, cmp, rhs });
    }
}

/// A solution of an [`Lp`].
#[derive(Debug, Clone)]
pub struct LpSolution {
    /// The value of every variable, by index.
    pub values: Vec<f64>,
    /// The objective there (with its constant).
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

/// Why a solve gave no solution.
#[derive(Debug, Clone, PartialEq)]
pub enum LpError {
    /// Proven infeasible.
    Infeasible,
    /// Proven unbounded.
    Unbounded,
    /// Stopped by the time limit before a solution or a proof.
    TimeLimit,
    /// Stopped by the node limit before a solution or a proof, after this
    /// much work.
    NodeLimit(u64),
    /// An integer variable's bounds exceed what the backend represents
    /// (microlp: the i32 range).
    TooLarge {
        /// The variable's index.
        var: usize,
        /// Its lower bound.
        lo: f64,
        /// Its upper bound.
        hi: f64,
    },
    /// The solver is not compiled in.
    Unavailable(&'static str),
    /// Any other failure of the solver, with its message.
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

/// A numerical failure of the solver (microlp: a singular basis, an
/// internal error) and how the solve got round it.
#[derive(Debug, Clone, PartialEq)]
pub struct Numerical {
    /// The solver's message for the first failure.
    pub message: String,
    /// Re-solves of the same problem written differently ([`variant`]).
    pub retries: u32,
    /// Which attempt gave the answer: 0 none, else the variant (1–3).
    pub solved_by: u32,
    /// Every attempt failed, and the answer is the best solution one of them
    /// had found before failing (not proven optimal).
    pub from_failed: bool,
}

/// The answer of [`solve`] and what it cost.
#[derive(Debug, Clone)]
pub struct Solve {
    /// The solution, or why there is none.
    pub result: Result<LpSolution, LpError>,
    /// Work of every attempt (branch-and-bound nodes plus one per attempt).
    pub work: u64,
    /// Set when the solver failed numerically on the way.
    pub numerical: Option<Numerical>,
}

/// The same problem written differently: the feasible set and the optimum
/// are unchanged, the solver's pivots are not. 1 scales every row to a
/// largest coefficient of 1, 2 reverses the row order, 3 does both.
pub fn variant(lp: &Lp, k: u32) -> Lp {
    let mut out = lp.clone();
    if k & 1 != 0 {
        for r in &mut out.rows {
            let m = r.terms.iter().map(|&(_, c)| c.abs()).fold(0.0, f64::max);
            if m > 0.0 && m.is_finite() {
                r.terms.iter_mut().for_each(|t| t.1 /= m);
                r.rhs /= m;
            }
        }
    }
    if k & 2 != 0 {
        out.rows.reverse();
    }
    out
}

/// Variants tried after a numerical failure, in order.
const VARIANTS: u32 = 3;

/// Solves with the chosen backend within `limits`. A numerical failure of
/// the solver is not the end: the problem is solved again written
/// differently ([`variant`] 1, 2, 3) with what is left of the limits; when
/// every attempt fails, the best solution any of them had found (not proven
/// optimal) is the answer, or else the error.
pub fn solve(lp: &Lp, solver: SolverKind, limits: Limits) -> Solve {
    solve_hinted(lp, solver, limits, None)
}

/// [`solve`] with a starting solution for microlp (a complete assignment;
/// ignored when it does not satisfy the rows, and by HiGHS).
pub fn solve_hinted(lp: &Lp, solver: SolverKind, limits: Limits, hint: Option<&[f64]>) -> Solve {
    let started = std::time::Instant::now();
    let mut so_far = Attempts::default();
    for k in 0..=VARIANTS {
        let left = Limits {
            time: limits.time.map(|t| t - started.elapsed().as_secs_f64()),
            nodes: limits.nodes.map(|n| n.saturating_sub(so_far.work)),
        };
        if k > 0 {
            if left.time.is_some_and(|t| t <= 0.0) {
                break;
            }
            if left.nodes == Some(0) {
                break;
            }
            if let Some(n) = &mut so_far.numerical {
                n.retries = k;
            }
        }
        let v;
        let problem = if k == 0 {
            lp
        } else {
            v = variant(lp, k);
            &v
        };
        let attempt = solve_once(problem, solver, left, hint);
        so_far.work = so_far.work.saturating_add(attempt.work);
        match attempt.result {
            Err(Failed::Solver(msg, found)) => so_far.failed_numerically(msg, found),
            Err(Failed::Lp(e)) => return so_far.ended(k, e),
            Ok(s) => return so_far.solved(k, s),
        }
    }
    so_far.exhausted(limits)
}

/// What the attempts of [`solve_hinted`] have gathered so far: a numerical
/// failure does not end the solve, so its message and the best solution the
/// failed attempt had found are kept for the answer.
#[derive(Default)]
struct Attempts {
    /// Work of every attempt so far.
    work: u64,
    /// Set at the first numerical failure.
    numerical: Option<Numerical>,
    /// The best solution a failed attempt had found.
    best: Option<LpSolution>,
    /// The message of the latest numerical failure.
    last_err: String,
}

impl Attempts {
    /// An attempt failed numerically: keep the better of its solution and
    /// the best so far, and the message.
    fn failed_numerically(&mut self, msg: String, found: Option<LpSolution>) {
        if let Some(f) = found {
            if self.best.as_ref().is_none_or(|b| f.objective < b.objective) {
                self.best = Some(f);
            }
        }
        self.numerical.get_or_insert(Numerical {
            message: msg.clone(),
            retries: 0,
            solved_by: 0,
            from_failed: false,
        });
        self.last_err = msg;
    }

    /// Attempt `k` ended in a limit or a verdict: that is the answer, unless
    /// a limit stopped it and a failed attempt had found a solution.
    fn ended(mut self, k: u32, e: LpError) -> Solve {
        let work = self.work;
        let result = match (e, self.best) {
            (LpError::TimeLimit | LpError::NodeLimit(_), Some(mut b)) => {
                if let Some(n) = &mut self.numerical {
                    n.from_failed = true;
                }
                b.work = work;
                Ok(b)
            }
            (LpError::NodeLimit(_), None) => Err(LpError::NodeLimit(work)),
            (e, _) => Err(e),
        };
        if let (Some(n), true) = (&mut self.numerical, k > 0) {
            n.solved_by = k;
        }
        Solve {
            result,
            work,
            numerical: self.numerical,
        }
    }

    /// Attempt `k` solved the problem.
    fn solved(mut self, k: u32, mut s: LpSolution) -> Solve {
        if let Some(n) = &mut self.numerical {
            n.solved_by = k;
        }
        s.work = self.work;
        Solve {
            result: Ok(s),
            work: self.work,
            numerical: self.numerical,
        }
    }

    /// Every attempt failed numerically (or the limits ran out between
    /// them): the best solution found on the way, not proven optimal, else
    /// the node limit or the last failure.
    fn exhausted(mut self, limits: Limits) -> Solve {
        let work = self.work;
        let result = match self.best {
            Some(mut b) => {
                if let Some(n) = &mut self.numerical {
                    n.from_failed = true;
                }
                b.optimal = false;
                b.work = work;
                Ok(b)
            }
            None if limits.nodes.is_some_and(|n| work >= n) => Err(LpError::NodeLimit(work)),
            None => Err(LpError::Other(self.last_err)),
        };
        Solve {
            result,
            work,
            numerical: self.numerical,
        }
    }
}

/// Why one attempt failed: a result of the problem (a verdict, a limit,
/// bad input), or the solver (with the best solution it had found).
enum Failed {
    Lp(LpError),
    Solver(String, Option<LpSolution>),
}

struct Attempt {
    result: Result<LpSolution, Failed>,
    work: u64,
}

fn solve_once(lp: &Lp, solver: SolverKind, limits: Limits, hint: Option<&[f64]>) -> Attempt {
    match solver {
        SolverKind::Microlp => solve_microlp(lp, limits, hint),
        SolverKind::Highs => {
            let started = std::time::Instant::now();
            let (pv, vars, obj) = build(lp);
            let r = solve_highs(lp, pv, vars, obj, limits);
            // HiGHS reports a time-limited solve without a solution as
            // "infeasible"; that is not a proof.
            let r = match (r, limits.time) {
                (Err(LpError::Infeasible), Some(t))
                    if started.elapsed().as_secs_f64() >= 0.5 * t =>
                {
                    Err(LpError::TimeLimit)
                }
                (r, _) => r,
            };
            let work = match &r {
                Ok(s) => s.work,
                Err(LpError::NodeLimit(w)) => *w,
                Err(_) => 1,
            };
            Attempt {
                result: r.map_err(|e| match e {
                    LpError::Other(m) => Failed::Solver(m, None),
                    e => Failed::Lp(e),
                }),
                work,
            }
        }
    }
}

/// Nodes per microlp call when a node limit applies: the work of a solve
/// that ends in a proof of infeasibility (microlp reports no statistics
/// then) is counted to within this many nodes.
const NODE_CHUNK: u64 = 64;

/// Nodes per microlp call without a node limit: between calls the best
/// solution so far is kept, for when a later call fails numerically.
const FREE_CHUNK: u64 = 1024;

/// microlp directly (not through good_lp), for its deterministic node limit
/// and node count.
fn solve_microlp(lp: &Lp, limits: Limits, hint: Option<&[f64]>) -> Attempt {
    let (p, vars) = match microlp_problem(lp) {
        Ok(x) => x,
        Err(e) => {
            return Attempt {
                result: Err(Failed::Lp(e)),
                work: 1,
            }
        }
    };
    let mut opts = microlp::SolveOptions::default();
    opts.time_limit = limits.time.map(|t| {
        std::time::Duration::try_from_secs_f64(t.max(0.01)).unwrap_or(std::time::Duration::MAX)
    });
    if let Some(h) = hint.filter(|h| h.len() == vars.len()) {
        opts.warm_start = Some(vars.iter().copied().zip(h.iter().copied()).collect());
    }
    opts.node_limit = node_chunk(limits.nodes);
    let started = std::time::Instant::now();
    let out = match p.solve_with(opts) {
        Ok(o) => o,
        Err(e) => return failed_call(e, 0, None, node_chunk(limits.nodes).unwrap_or(0)),
    };
    Chunked {
        lp,
        vars: &vars,
        limits,
        started,
        left: limits.nodes,
        done: 0,
        best: None,
    }
    .run(out)
}

/// The node limit of the next microlp call, given the nodes the solve's
/// limit still allows (`None`: no limit).
fn node_chunk(left: Option<u64>) -> Option<u64> {
    Some(left.map_or(FREE_CHUNK, |l| l.min(NODE_CHUNK)))
}

/// The [`Lp`] as a microlp problem and its variables, by index; an error
/// when microlp cannot hold an integer variable's bounds, or when the
/// problem is infeasible on its face (empty integer bounds, a row without
/// variables that fails).
fn microlp_problem(lp: &Lp) -> Result<(microlp::Problem, Vec<microlp::Variable>), LpError> {
    use microlp::{ComparisonOp, LinearExpr, OptimizationDirection, Problem};
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
            if constant_row_holds(r) {
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
    Ok((p, vars))
}

/// Whether a row whose coefficients are all zero holds: `0 cmp rhs`, within
/// 1e-9 (microlp cannot take a row without variables).
fn constant_row_holds(r: &Row) -> bool {
    match r.cmp {
        Cmp::Le => 0.0 <= r.rhs + 1e-9,
        Cmp::Ge => 0.0 >= r.rhs - 1e-9,
        Cmp::Eq => r.rhs.abs() <= 1e-9,
    }
}

/// A microlp call that failed, after `done` nodes of earlier calls that
/// found `best`. A verdict (infeasible, unbounded) is charged one unit, as
/// a solve; any other failure is numerical, charged the call's whole node
/// limit `charge` (microlp reports no count then) and carries `best`.
fn failed_call(e: microlp::Error, done: u64, best: Option<LpSolution>, charge: u64) -> Attempt {
    let work = 1 + done + charge;
    let result = match e {
        // A verdict is charged one unit, as a solve.
        microlp::Error::Infeasible => Err(Failed::Lp(LpError::Infeasible)),
        microlp::Error::Unbounded => Err(Failed::Lp(LpError::Unbounded)),
        other => Err(Failed::Solver(
            other.to_string(),
            best.map(|mut b| {
                b.optimal = false;
                b.work = work;
                b
            }),
        )),
    };
    let work = if matches!(result, Err(Failed::Lp(_))) {
        1
    } else {
        work
    };
    Attempt { result, work }
}

/// One microlp solve carried on call after call, each limited to a chunk of
/// nodes: under a node limit, so that the work is counted to within a
/// chunk; without one, so that the best solution so far survives a later
/// call's numerical failure.
struct Chunked<'a> {
    lp: &'a Lp,
    vars: &'a [microlp::Variable],
    limits: Limits,
    /// When the first call started: the time limit is for the whole solve.
    started: std::time::Instant,
    /// Nodes the node limit still allows (`None`: no node limit).
    left: Option<u64>,
    /// Nodes done by the calls so far.
    done: u64,
    /// The best solution the calls so far found.
    best: Option<LpSolution>,
}

impl Chunked<'_> {
    /// Resumes `out` until it ends in a solution, a proof, a limit, or a
    /// failure.
    fn run(mut self, mut out: microlp::SolveOutcome) -> Attempt {
        loop {
            let nodes = out.stats().nodes_solved;
            let by_nodes = out.termination_reason() == microlp::TerminationReason::NodeLimit;
            let used = nodes - self.done;
            self.done = nodes;
            if let microlp::SolveOutcome::Solution(sol) = &out {
                self.best = Some(self.solution(sol, 1 + nodes));
            }
            if nodes / 16384 != (nodes - used) / 16384
                && std::env::var_os("RTPIPE_LP_DEBUG").is_some()
            {
                self.debug(&out, nodes);
            }
            if by_nodes && self.more(used) {
                // Go on with a fresh chunk (counted exactly: a chunk that
                // ends in a proof of infeasibility is charged in full).
                let r = self.resume_options(&out);
                let charge = r.node_limit.unwrap_or(0);
                out = match out.resume_with(r) {
                    Ok(o) => o,
                    Err(e) => return failed_call(e, self.done, self.best, charge),
                };
                continue;
            }
            return self.finish(out, nodes, by_nodes);
        }
    }

    /// After a call the node limit stopped that used `used` nodes: whether
    /// the solve's own node limit (if any) allows another call.
    fn more(&mut self, used: u64) -> bool {
        match self.left {
            Some(l) => {
                let l = l.saturating_sub(used);
                self.left = Some(l);
                l > 0
            }
            None => true,
        }
    }

    /// The options of the next call: a fresh chunk of nodes, and what is
    /// left of the time limit (it is for the whole solve, not per call).
    fn resume_options(&self, out: &microlp::SolveOutcome) -> microlp::ResumeOptions {
        let mut r = out.last_resume_options();
        r.node_limit = node_chunk(self.left);
        r.time_limit = self.limits.time.map(|t| {
            std::time::Duration::try_from_secs_f64(
                (t - self.started.elapsed().as_secs_f64()).max(0.01),
            )
            .unwrap_or(std::time::Duration::MAX)
        });
        r
    }

    /// The answer once no call follows: the last solution, or the limit
    /// that stopped the solve before it found one.
    fn finish(mut self, out: microlp::SolveOutcome, nodes: u64, by_nodes: bool) -> Attempt {
        let work = 1 + nodes;
        let result = match out {
            microlp::SolveOutcome::Solution(_) => {
                let mut b = self.best.take().expect("a solution outcome was recorded");
                b.work = work;
                Ok(b)
            }
            microlp::SolveOutcome::Interrupted(_) if by_nodes => {
                Err(Failed::Lp(LpError::NodeLimit(work)))
            }
            microlp::SolveOutcome::Interrupted(_) => Err(Failed::Lp(LpError::TimeLimit)),
        };
        Attempt { result, work }
    }

    /// microlp's solution as an [`LpSolution`], its objective recomputed
    /// from the model's terms (with the constant microlp does not know).
    fn solution(&self, sol: &microlp::Solution, work: u64) -> LpSolution {
        let values: Vec<f64> = self.vars.iter().map(|&v| sol.var_value(v)).collect();
        let objective =
            self.lp.obj.iter().map(|&(i, c)| c * values[i]).sum::<f64>() + self.lp.obj_const;
        LpSolution {
            values,
            objective,
            optimal: sol.status() == microlp::SolutionStatus::Optimal,
            work,
        }
    }

    /// Progress on stderr (`RTPIPE_LP_DEBUG`), every 16,384 nodes.
    fn debug(&self, out: &microlp::SolveOutcome, nodes: u64) {
        let st = out.stats();
        eprintln!(
            "  microlp: {nodes} nodes, {} pivots, incumbent {:?}, bound {:?}, {:.1} s",
            st.lp_iterations,
            self.best.as_ref().map(|b| b.objective),
            st.best_bound,
            self.started.elapsed().as_secs_f64()
        );
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
        match solve(&lp, SolverKind::Microlp, Limits::default()).result {
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
            solve(&lp, SolverKind::Microlp, Limits::default())
                .result
                .err(),
            Some(LpError::Infeasible)
        );
    }
}
