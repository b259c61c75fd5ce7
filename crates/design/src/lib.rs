//! # rtpipe-design
//!
//! Section IV of Cheng, West, Einstein (EMSOFT 2018), solved exactly: choose
//! the free periods so that every chain limit holds under the chosen analysis,
//! every CPU passes the system's schedulability test, T ≥ C, and the total
//! utilisation Σ C/T is minimal. docs/design.md explains the formulation.
//!
//! Every answer is re-checked by `rtpipe_analysis::analyze` before it is
//! returned; the [`Outcome`] carries that report.

mod bnb;
pub mod lp;

use lp::{Cmp, Limits, Lp, LpError, SolverKind};
use rtpipe_analysis::sched::interference;
use rtpipe_analysis::{ChainResult, Metric, Report};
use rtpipe_model::{format_in, Nanos, PeriodSpec, SchedTest, Scheduler, Server, Spec, MAX_TIME};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Which analysis the chain limits are judged by (one enum for the whole
/// workspace).
pub use rtpipe_analysis::Mode;

/// How the exact search runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// The box search where it applies (sound mode, periods not harmonic),
    /// the MILP otherwise.
    Auto,
    /// Branch and bound over boxes of periods, pruned by the sound
    /// analysis' relaxation (`bnb.rs`; sound mode only).
    Boxes,
    /// The mixed-integer model of docs/design.md, solved by `solver`.
    Milp,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Boxes => "boxes",
            Method::Milp => "milp",
        }
    }
}

#[derive(Debug, Clone)]
pub struct Options {
    pub mode: Mode,
    pub method: Method,
    /// The MILP's solver.
    pub solver: SolverKind,
    /// Wall-clock limit for the whole search, in seconds. Without it the
    /// search is bounded by work only, so its answer is the same on every
    /// machine.
    pub time_limit: Option<f64>,
    /// Upper bound on master solves.
    pub max_iterations: usize,
    /// Without a time limit: work (branch-and-bound nodes, plus one per
    /// master solve) the exact search may spend after a verified design is
    /// found, and the conflict search spends at most [`EXPLAIN_EFFORT`]
    /// times this once infeasibility is proven (`None`: no bound, until
    /// the search is done).
    pub patience: Option<u64>,
    /// Where the search says what it is doing, for a progress display.
    pub progress: Option<Arc<Mutex<String>>>,
    /// Set from outside (Ctrl-C) to stop the search as its time limit would.
    pub cancel: Option<Arc<AtomicBool>>,
    /// Where the search publishes every better verified design as it finds
    /// it, so that a caller can still report the best one when it stops
    /// waiting (Ctrl-C).
    pub incumbent: Option<Arc<Mutex<Option<Incumbent>>>>,
}

/// A verified design found during the search.
#[derive(Debug, Clone, PartialEq)]
pub struct Incumbent {
    /// Period of every task (ns), in declaration order.
    pub periods: Vec<Nanos>,
    /// Its Σ C/T.
    pub utilization: f64,
    /// The best proven lower bound on the optimum when it was found.
    pub lower_bound: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Sound,
            method: Method::Auto,
            solver: SolverKind::Microlp,
            time_limit: None,
            max_iterations: 500,
            patience: Some(EXACT_PATIENCE),
            progress: None,
            cancel: None,
            incumbent: None,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Proven minimal.
    Optimal,
    /// Verified, but not proven minimal (see the gap).
    Feasible,
    /// Proven impossible (see the conflicts).
    Infeasible,
    /// Neither a verified design nor a proof of infeasibility.
    Unknown,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Optimal => "optimal",
            Status::Feasible => "feasible",
            Status::Infeasible => "infeasible",
            Status::Unknown => "unknown",
        }
    }
}

/// One constraint of a conflicting set, and how far it would have to move.
#[derive(Debug, Clone, PartialEq)]
pub struct Conflict {
    pub constraint: String,
    /// What would make the rest of the set feasible, when computed.
    pub fix: Option<String>,
}

#[derive(Debug, Clone)]
pub struct Outcome {
    pub status: Status,
    /// The spec with every period fixed to the design, when one was found.
    pub spec: Option<Spec>,
    /// The analysis of that spec (the re-check).
    pub report: Option<Report>,
    /// Σ C/T of the design.
    pub objective: Option<f64>,
    /// A proven lower bound on the optimum.
    pub lower_bound: Option<f64>,
    /// (objective − lower bound) / objective.
    pub gap: Option<f64>,
    /// The search that ran: [`Method::Boxes`] or [`Method::Milp`].
    pub method: Method,
    pub solver: SolverKind,
    pub seconds: f64,
    /// Master solves (MILP) or boxes examined (box search).
    pub iterations: usize,
    /// The most boxes the box search held open at once (memory).
    pub peak_open: usize,
    pub conflicts: Vec<Conflict>,
    pub notes: Vec<String>,
}

/// Whose fault a [`DesignError`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The input makes designing meaningless or impossible to model.
    Input,
    /// The solver failed.
    Solver,
    /// rtpipe's model and analysis disagree (a bug).
    Internal,
}

/// Why no design could be attempted (not an infeasible design: that is an
/// [`Outcome`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignError {
    pub kind: ErrorKind,
    pub message: String,
    /// What to change, when we can tell.
    pub help: Option<String>,
}

impl DesignError {
    pub fn input(message: impl Into<String>) -> Self {
        DesignError {
            kind: ErrorKind::Input,
            message: message.into(),
            help: None,
        }
    }
    pub fn solver(message: impl Into<String>) -> Self {
        DesignError {
            kind: ErrorKind::Solver,
            message: message.into(),
            help: None,
        }
    }
    pub fn internal(message: impl Into<String>) -> Self {
        DesignError {
            kind: ErrorKind::Internal,
            message: message.into(),
            help: None,
        }
    }
    fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

impl std::fmt::Display for DesignError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for DesignError {}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

/// The period domain of one task, in grid units (g ns).
#[derive(Debug, Clone)]
enum Dom {
    Fixed(i64),
    /// T = step · k, k ∈ [lo, hi].
    Grid {
        step: i64,
        lo: i64,
        hi: i64,
    },
    Choice(Vec<i64>),
}

impl Dom {
    fn min(&self) -> i64 {
        match self {
            Dom::Fixed(t) => *t,
            Dom::Grid { step, lo, .. } => step * lo,
            Dom::Choice(v) => v.iter().copied().min().unwrap_or(0),
        }
    }
    fn max(&self) -> i64 {
        match self {
            Dom::Fixed(t) => *t,
            Dom::Grid { step, hi, .. } => step * hi,
            Dom::Choice(v) => v.iter().copied().max().unwrap_or(0),
        }
    }
}

/// A linear expression in grid units: Σ coeff·var + constant.
#[derive(Debug, Clone, Default)]
struct Lin {
    terms: Vec<(usize, f64)>,
    c: f64,
}

impl Lin {
    fn constant(c: f64) -> Lin {
        Lin {
            terms: Vec::new(),
            c,
        }
    }
    fn plus(&self, o: &Lin) -> Lin {
        let mut terms = self.terms.clone();
        terms.extend_from_slice(&o.terms);
        Lin {
            terms,
            c: self.c + o.c,
        }
    }
    fn add_c(&self, c: f64) -> Lin {
        Lin {
            terms: self.terms.clone(),
            c: self.c + c,
        }
    }
    /// The largest and smallest values over the variables' bounds.
    fn max_in(&self, lp: &Lp) -> f64 {
        self.c
            + self
                .terms
                .iter()
                .map(|&(v, a)| (a * lp.vars[v].lo).max(a * lp.vars[v].hi))
                .sum::<f64>()
    }
    fn min_in(&self, lp: &Lp) -> f64 {
        self.c
            + self
                .terms
                .iter()
                .map(|&(v, a)| (a * lp.vars[v].lo).min(a * lp.vars[v].hi))
                .sum::<f64>()
    }
    fn scale(&self, k: f64) -> Lin {
        Lin {
            terms: self.terms.iter().map(|&(v, a)| (v, a * k)).collect(),
            c: self.c * k,
        }
    }
}

/// A binary that may be a known constant.
#[derive(Debug, Clone, Copy)]
enum Bin {
    Const(bool),
    Var(usize),
}

/// The master problem and its bookkeeping.
struct Master<'a> {
    spec: &'a Spec,
    g: i64,
    dom: Vec<Dom>,
    lp: Lp,
    /// Period expression per task (grid units).
    period: Vec<Lin>,
    /// Grid variable k per Grid task; choice binaries per Choice task.
    kvar: Vec<Option<usize>>,
    yvars: Vec<Vec<usize>>,
    /// Utilisation (and hyperbolic log term) per task.
    util: Vec<Lin>,
    uvar: Vec<Option<usize>>,
    hlog: Vec<Lin>,
    hvar: Vec<Option<usize>>,
    lt_cache: HashMap<(usize, usize, bool), Bin>,
    big_m: f64,
    /// Response-time variables (sound mode, RM).
    rvar: Vec<Option<usize>>,
    /// Valid lower ends of option variables (for their big-Ms).
    floor: HashMap<usize, f64>,
    /// Declare the option variables' bounds (see `sound_chain`).
    tight_bounds: bool,
}

/// Which constraint groups are active (for the conflict search).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Group {
    Limit(usize, Metric),
    Sched(u32),
}

impl<'a> Master<'a> {
    fn guaranteed(&self, i: usize) -> bool {
        self.spec.tasks[i].server != Server::Background
    }

    fn lt(&mut self, a: usize, b: usize, tie_true: bool) -> Bin {
        if let Some(&bin) = self.lt_cache.get(&(a, b, tie_true)) {
            return bin;
        }
        let (da, db) = (&self.dom[a], &self.dom[b]);
        // 1 ⟺ T_a < T_b, or T_a = T_b and tie_true.
        let bin = if da.max() < db.min() || (tie_true && da.max() <= db.min()) {
            Bin::Const(true)
        } else if da.min() > db.max() || (!tie_true && da.min() >= db.max()) {
            Bin::Const(false)
        } else {
            let z = self.lp.binary();
            let d1 = if tie_true { 0.0 } else { 1.0 };
            let d0 = if tie_true { 1.0 } else { 0.0 };
            // z = 1 ⇒ T_a − T_b ≤ −d1;  z = 0 ⇒ T_a − T_b ≥ d0, with the
            // smallest big-M that the period domains allow.
            let diff = self.period[a].plus(&self.period[b].scale(-1.0));
            let (hi, lo) = ((da.max() - db.min()) as f64, (da.min() - db.max()) as f64);
            let m1 = (hi + d1).max(0.0);
            let m0 = (d0 - lo).max(0.0);
            let mut t = diff.terms.clone();
            t.push((z, m1));
            self.lp.row(t, Cmp::Le, -d1 - diff.c + m1);
            let mut t = diff.terms.clone();
            t.push((z, m0));
            self.lp.row(t, Cmp::Ge, d0 - diff.c);
            Bin::Var(z)
        };
        self.lt_cache.insert((a, b, tie_true), bin);
        bin
    }

    /// A binary b with b = 1 ⇒ T_j ≥ tj + 1 ("the period of j grew past its
    /// value in a cut"); `None` when it cannot grow.
    fn grew(&mut self, j: usize, tj: i64) -> Option<usize> {
        if matches!(self.dom[j], Dom::Fixed(_)) || self.dom[j].max() <= tj {
            return None;
        }
        let b = self.lp.binary();
        let p = self.period[j].clone();
        let mut t = p.terms.clone();
        t.push((b, -self.big_m));
        self.lp.row(t, Cmp::Ge, (tj + 1) as f64 - p.c - self.big_m);
        Some(b)
    }

    /// `r ≥ own + Σ_{j ≻ i} I_j · (jobs of j released in [0, r))`: for the
    /// m-th job of j (m ≥ 2) a binary b with `b = 0 ⇒ r ≤ (m − 1)·T_j`, so
    /// b must be 1 once r passes the release. Every r the model allows has
    /// W(r) ≤ r, hence r ≥ the least fixed point (the RTA response time),
    /// and the response time itself is allowed: exact when `cap` covers
    /// every job that can fall below `rmax`, a relaxation otherwise (the
    /// levels grow lazily, see `Runner::raise_levels`).
    fn rta_levels(
        &mut self,
        i: usize,
        r: usize,
        own: f64,
        rmax: f64,
        levels: &Levels,
        budget_level: bool,
    ) {
        let spec = self.spec;
        let g = self.g;
        let mut terms = vec![(r, 1.0)];
        let mut rhs = own;
        for j in 0..spec.tasks.len() {
            if j == i || spec.tasks[j].cpu != spec.tasks[i].cpu || !self.guaranteed(j) {
                continue;
            }
            let cj = gu(interference(&spec.tasks[j]), g);
            let a = self.above(j, i);
            match a {
                Bin::Const(true) => rhs += cj,
                Bin::Const(false) => continue,
                Bin::Var(z) => terms.push((z, -cj)),
            }
            let tmin = self.dom[j].min().max(1) as f64;
            let cap = levels.get(&(budget_level, i, j)).copied().unwrap_or(1);
            let mut prev: Option<usize> = None;
            for m in 2..=cap {
                let rel = (m - 1) as f64;
                // The m-th job is released at (m − 1)·T_j ≥ (m − 1)·T_min.
                let big = rmax - rel * tmin;
                if big <= 0.0 {
                    break;
                }
                let b = self.lp.binary();
                let mut row = vec![(r, 1.0), (b, -big)];
                row.extend(self.period[j].terms.iter().map(|&(v, k)| (v, -rel * k)));
                let mut bound = rel * self.period[j].c;
                if let Bin::Var(z) = a {
                    row.push((z, big));
                    bound += big;
                }
                self.lp.row(row, Cmp::Le, bound);
                if let Some(pb) = prev {
                    self.lp.row(vec![(b, 1.0), (pb, -1.0)], Cmp::Le, 0.0);
                }
                prev = Some(b);
                terms.push((b, -cj));
            }
        }
        self.lp.row(terms, Cmp::Ge, rhs);
    }

    /// RM priority: a ≻ b.
    fn above(&mut self, a: usize, b: usize) -> Bin {
        self.lt(a, b, a < b)
    }

    /// Adds `lhs ≥ opt − M·(Σ off)` where `off` are 0/1 expressions that
    /// switch the option off when 1.
    fn ge_option(&mut self, lhs: usize, opt: &Lin, off: &[(Bin, bool)]) {
        // Switched off, the row must allow every value: M ≥ max(opt) − min(lhs).
        // (One grid unit of slack keeps microlp's pivots away from degenerate ties.)
        let lo = self
            .floor
            .get(&lhs)
            .copied()
            .unwrap_or(self.lp.vars[lhs].lo);
        let m = (opt.max_in(&self.lp) - lo + 1.0).clamp(1.0, self.big_m);
        let mut terms: Vec<(usize, f64)> = vec![(lhs, 1.0)];
        terms.extend(opt.terms.iter().map(|&(v, a)| (v, -a)));
        let mut rhs = opt.c;
        for &(b, negate) in off {
            // negate = false: off when b = 1; negate = true: off when b = 0.
            match (b, negate) {
                (Bin::Const(v), false) => {
                    if v {
                        return;
                    }
                }
                (Bin::Const(v), true) => {
                    if !v {
                        return;
                    }
                }
                (Bin::Var(z), false) => terms.push((z, m)),
                (Bin::Var(z), true) => {
                    terms.push((z, -m));
                    rhs -= m;
                }
            }
        }
        self.lp.row(terms, Cmp::Ge, rhs);
    }
}

/// The conflict search may take this many times the patience.
pub const EXPLAIN_EFFORT: u64 = 3;

/// Whether each conflict probe gets a fair share of the remaining work
/// (else each may use all that is left, as the time-bounded search did).
const FAIR_SHARES: bool = false;

/// Work the starting solution of a master may take.
const HINT_NODES: u64 = 2_000;

/// Ranges of at most this many grid steps get every tangent up front.
const DENSE_TANGENTS: i64 = 128;

/// Work (branch-and-bound nodes, plus one per master solve) the exact
/// search may spend after the first verified design, when no time limit is
/// given; about 20 s of microlp on Table II (6,000 nodes/s).
pub const EXACT_PATIENCE: u64 = 120_000;

/// Converts ns to grid units.
fn gu(ns: Nanos, g: i64) -> f64 {
    ns as f64 / g as f64
}

/// Designs the periods of `spec`.
pub fn design(spec: &Spec, opts: &Options) -> Result<Outcome, DesignError> {
    let start = Instant::now();
    if !opts.solver.available() {
        return Err(DesignError::input(
            LpError::Unavailable(opts.solver.name()).to_string(),
        ));
    }
    let n = spec.tasks.len();
    if let Some(t) = spec.tasks.iter().find(|t| t.serves.is_some()) {
        return Err(DesignError::input(format!(
            "task `{}` uses `serves` (PIBS priority inheritance), which `design` does not model yet; remove it to design, then add it back and check with `analyze`",
            t.name
        )));
    }
    // Upper end for periods without a max: the largest limit or fixed period.
    let mut horizon: i64 = 0;
    for c in &spec.chains {
        horizon = horizon
            .max(c.reaction.unwrap_or(0))
            .max(c.freshness.unwrap_or(0));
    }
    for t in &spec.tasks {
        if let Some(p) = t.fixed_period() {
            horizon = horizon.max(p);
        }
    }
    // The grid: periods are multiples of g (resolution, fixed periods, choices).
    let mut g = spec.resolution;
    for t in &spec.tasks {
        match &t.period {
            PeriodSpec::Fixed(p) => g = gcd(g, *p),
            PeriodSpec::Choices(v) => v.iter().for_each(|&p| g = gcd(g, p)),
            _ => {}
        }
    }
    let g = g.max(1);
    let res = spec.resolution;
    let mut dom = Vec::with_capacity(n);
    for t in &spec.tasks {
        let c = t.budget();
        let d = match &t.period {
            PeriodSpec::Fixed(p) => Dom::Fixed(p / g),
            PeriodSpec::Choices(v) => {
                let ok: Vec<i64> = v.iter().filter(|&&p| p >= c).map(|&p| p / g).collect();
                if ok.is_empty() {
                    return Err(DesignError::input(format!(
                        "task `{}`: no period choice is at least its budget {}{}",
                        t.name,
                        format_in(c, spec.time_unit),
                        spec.time_unit
                    )));
                }
                Dom::Choice(ok)
            }
            PeriodSpec::Range { min, max } => range_dom(spec, t, *min, *max, c, horizon, res, g)?,
            PeriodSpec::Free => range_dom(spec, t, None, None, c, horizon, res, g)?,
        };
        dom.push(d);
    }
    // microlp keeps integers in the i32 range: say which period range and
    // resolution make the steps too many.
    for (t, d) in spec.tasks.iter().zip(&dom) {
        if let Dom::Grid { hi, .. } = d {
            if *hi > i64::from(i32::MAX) {
                let mut coarser = res;
                while coarser < MAX_TIME && (hi.saturating_mul(res)) / coarser > i64::from(i32::MAX)
                {
                    coarser = coarser.saturating_mul(10);
                }
                return Err(DesignError::input(format!(
                    "task `{}`: its period range up to {}{u} is {hi} steps of the resolution {}{u}, more than the solver's integers hold ({})",
                    t.name,
                    format_in(hi.saturating_mul(res), spec.time_unit),
                    format_in(res, spec.time_unit),
                    i32::MAX,
                    u = spec.time_unit
                ))
                .help(format!(
                    "set a coarser resolution in [system], e.g. resolution = \"{}{}\", or a smaller period max for [tasks.{}]",
                    format_in(coarser, spec.time_unit),
                    spec.time_unit,
                    t.name
                )));
            }
        }
    }
    let mut notes = Vec::new();
    if spec.harmonic {
        harmonic_domains(spec, &mut dom, &mut notes)?;
    }
    let boxes = choose_method(spec, opts)?;
    let max_t = dom.iter().map(|d| d.max()).max().unwrap_or(1) as f64;
    let max_limit = gu(horizon, g);
    let big_m = 4.0 * (max_t + max_limit) + 10.0;

    let mut run = Runner {
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
    };
    let mut o = if boxes {
        run.solve_boxes()?
    } else {
        run.solve_all()?
    };
    o.notes.splice(0..0, notes);
    Ok(o)
}

/// The search `design` runs for `spec` with `opts` ([`Method::Boxes`] or
/// [`Method::Milp`]; an invalid `--method boxes` is reported by `design`).
pub fn method_for(spec: &Spec, opts: &Options) -> Method {
    match choose_method(spec, opts) {
        Ok(true) | Err(_) if opts.method != Method::Milp => Method::Boxes,
        _ => Method::Milp,
    }
}

/// Whether the box search runs (true) or the MILP.
fn choose_method(spec: &Spec, opts: &Options) -> Result<bool, DesignError> {
    let fits = opts.mode == Mode::Sound && !spec.harmonic;
    match opts.method {
        Method::Auto => Ok(fits),
        Method::Milp => Ok(false),
        Method::Boxes if fits => Ok(true),
        Method::Boxes => Err(DesignError::input(
            "the box search designs in sound mode without `harmonic = true` only",
        )
        .help("use --method milp (or leave --method out)")),
    }
}

/// Most candidate periods a free task keeps under `harmonic = true` before
/// its domain is thinned to 5-smooth multiples of the grid.
const HARMONIC_CANDIDATES: usize = 256;

/// Harmonic periods (every pair divides one way): each free domain becomes
/// a choice among the values that divide or are divided by every fixed
/// period; `build` then forbids every non-harmonic pair of choices. Large
/// ranges keep only the values g·2^a·3^b·5^c (said in a note).
fn harmonic_domains(
    spec: &Spec,
    dom: &mut [Dom],
    notes: &mut Vec<String>,
) -> Result<(), DesignError> {
    let fixed: Vec<i64> = dom
        .iter()
        .filter_map(|d| match d {
            Dom::Fixed(t) => Some(*t),
            _ => None,
        })
        .collect();
    for (a, &p) in fixed.iter().enumerate() {
        for &q in &fixed[a + 1..] {
            if !harmonic_pair(p, q) {
                return Err(DesignError::input(
                    "harmonic = true, but the fixed periods are not harmonic (one of each pair must divide the other)",
                ));
            }
        }
    }
    let smooth = |mut v: i64| {
        for f in [2, 3, 5] {
            while v % f == 0 {
                v /= f;
            }
        }
        v == 1
    };
    for (i, d) in dom.iter_mut().enumerate() {
        let values: Vec<i64> = match d {
            Dom::Fixed(_) => continue,
            Dom::Choice(v) => v.clone(),
            Dom::Grid { step, lo, hi } => (*lo..=*hi).map(|k| k * *step).collect(),
        };
        let mut ok: Vec<i64> = values
            .into_iter()
            .filter(|&v| fixed.iter().all(|&f| harmonic_pair(v, f)))
            .collect();
        if ok.len() > HARMONIC_CANDIDATES {
            ok.retain(|&v| smooth(v));
            notes.push(format!(
                "harmonic: task `{}` chooses among the {} periods of its range that are 2^a·3^b·5^c grid steps (optimal among those)",
                spec.tasks[i].name,
                ok.len()
            ));
        }
        if ok.is_empty() {
            return Err(DesignError::input(format!(
                "harmonic = true: no period in the range of task `{}` divides or is a multiple of every fixed period",
                spec.tasks[i].name
            )));
        }
        *d = Dom::Choice(ok);
    }
    Ok(())
}

fn harmonic_pair(a: i64, b: i64) -> bool {
    a > 0 && b > 0 && (a % b == 0 || b % a == 0)
}

#[allow(clippy::too_many_arguments)]
fn range_dom(
    spec: &Spec,
    t: &rtpipe_model::Task,
    min: Option<Nanos>,
    max: Option<Nanos>,
    c: Nanos,
    horizon: Nanos,
    res: Nanos,
    g: i64,
) -> Result<Dom, DesignError> {
    let lo_ns = min.unwrap_or(0).max(c);
    let hi_ns = match max {
        Some(m) => m,
        None if horizon > 0 => horizon,
        None => {
            return Err(DesignError::input(format!(
                "task `{}` has a free period without an upper end and no chain limit bounds it; give period = {{ max = ... }}",
                t.name
            )))
        }
    };
    let lo = (lo_ns + res - 1) / res;
    let hi = hi_ns / res;
    if lo > hi {
        return Err(DesignError::input(format!(
            "task `{}`: no multiple of the resolution {}{} lies in [{}, {}] {} (the period must also be at least the budget)",
            t.name,
            format_in(res, spec.time_unit),
            spec.time_unit,
            format_in(lo_ns, spec.time_unit),
            format_in(hi_ns, spec.time_unit),
            spec.time_unit
        )));
    }
    Ok(Dom::Grid {
        step: res / g,
        lo,
        hi,
    })
}

/// Response-time levels per (budget level?, task, higher-priority task): the
/// jobs of the latter the model counts (at least the first).
type Levels = HashMap<(bool, usize, usize), usize>;

/// A lazy schedulability cut: task `i` missed its deadline with hp set `hp`
/// and these periods; some period must grow or the order must change.
#[derive(Debug, Clone)]
struct RtaCut {
    i: usize,
    hp: Vec<usize>,
    periods: Vec<(usize, i64)>,
}

struct Runner<'a> {
    spec: &'a Spec,
    opts: &'a Options,
    g: i64,
    dom: Vec<Dom>,
    big_m: f64,
    start: Instant,
    rta_cuts: Vec<RtaCut>,
    /// Outer-approximation points (k values) per Grid task.
    oa_points: Vec<Vec<i64>>,
    iterations: usize,
    /// Work done so far (see [`Options::patience`]).
    work: u64,
    /// No solve may run past this much work (the patience after a verified
    /// design, the conflict search's effort).
    work_cap: Option<u64>,
    levels: Levels,
    /// Task i lies on some declared chain.
    on_chain: Vec<bool>,
    /// Numerical failures of the solver and what became of them.
    numerical: NumLog,
    /// The best verified design's periods (ns): a starting solution for
    /// microlp's branch and bound.
    start_periods: Option<Vec<Nanos>>,
    /// The box search decides (`bnb.rs`), not the MILP.
    boxes: bool,
}

/// Master problems on which the solver failed numerically (`lp::solve`
/// re-solves them written differently first), by what became of them.
#[derive(Debug, Clone, Default)]
struct NumLog {
    /// The solver's first message.
    message: Option<String>,
    /// Answered by a re-solve.
    resolved: usize,
    /// Every attempt failed; a failed attempt's best solution was used.
    from_failed: usize,
    /// Every attempt failed without a solution: skipped as undecided.
    skipped: usize,
    /// The last master solve was skipped that way.
    last_skipped: bool,
}

impl NumLog {
    fn absorb(&mut self, o: &NumLog) {
        if self.message.is_none() {
            self.message.clone_from(&o.message);
        }
        self.resolved += o.resolved;
        self.from_failed += o.from_failed;
        self.skipped += o.skipped;
        self.last_skipped = o.last_skipped;
    }

    /// What the outcome says about them.
    fn note(&self) -> Option<String> {
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

/// What the sound model knows of response times: unconditional lower
/// bounds, and conditional ones learnt from verified candidates.
#[derive(Debug, Clone)]
struct SoundModel {
    /// R_i ≥ this whatever the periods (grid units).
    rlow: Vec<f64>,
    cuts: Vec<RCut>,
    /// Heuristic phase: response times pinned to these estimates (not a
    /// relaxation; its candidates still go through the analysis).
    fixed: Option<Vec<f64>>,
}

/// R_i ≥ r unless some higher-priority task's period grew past its value
/// then, or left the higher-priority set (RTA is monotone in both).
#[derive(Debug, Clone)]
struct RCut {
    i: usize,
    r: f64,
    hp: Vec<usize>,
    periods: Vec<(usize, i64)>,
}

enum Solved {
    Infeasible,
    /// Stopped by a time or work limit, or by a numerical failure of the
    /// solver that re-solving did not get round: nothing proven.
    Stopped,
    /// Periods per task (ns), the model objective, proven optimal, and the
    /// model's response times (grid units) where it has them.
    Periods(Vec<Nanos>, f64, bool, Vec<Option<f64>>),
    Error(DesignError),
}

impl<'a> Runner<'a> {
    fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn say(&self, what: impl FnOnce() -> String) {
        if let Some(p) = &self.opts.progress {
            if let Ok(mut g) = p.lock() {
                *g = what();
            }
        }
    }

    /// Hands a better verified design to [`Options::incumbent`], so that a
    /// caller that stops waiting (Ctrl-C) can still report it.
    fn publish(&self, best: &Option<(Spec, Report, f64)>, lower_bound: Option<f64>) {
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

    fn out_of_time(&self) -> bool {
        self.opts
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
            || self.opts.time_limit.is_some_and(|t| self.elapsed() >= t)
            || self.work_cap.is_some_and(|c| self.work >= c)
    }

    fn build(
        &self,
        groups: &[Group],
        sound: Option<&SoundModel>,
    ) -> (Master<'a>, Vec<(usize, f64)>) {
        let spec = self.spec;
        let n = spec.tasks.len();
        let g = self.g;
        let mut m = Master {
            spec,
            g,
            dom: self.dom.clone(),
            lp: Lp::default(),
            period: Vec::with_capacity(n),
            kvar: vec![None; n],
            yvars: vec![Vec::new(); n],
            util: Vec::with_capacity(n),
            uvar: vec![None; n],
            hlog: Vec::with_capacity(n),
            hvar: vec![None; n],
            lt_cache: HashMap::new(),
            big_m: self.big_m,
            rvar: vec![None; n],
            floor: HashMap::new(),
            tight_bounds: self.opts.solver == SolverKind::Highs,
        };
        let mut objective: Vec<(usize, f64)> = Vec::new();
        let mut obj_const = 0.0;
        for i in 0..n {
            let c = spec.tasks[i].budget() as f64;
            let d = m.dom[i].clone();
            match d {
                Dom::Fixed(t) => {
                    m.period.push(Lin::constant(t as f64));
                    let u = c / (t * g) as f64;
                    m.util.push(Lin::constant(u));
                    m.hlog.push(Lin::constant((1.0 + u).ln()));
                }
                Dom::Choice(v) => {
                    let ys: Vec<usize> = v.iter().map(|_| m.lp.binary()).collect();
                    m.lp.row(ys.iter().map(|&y| (y, 1.0)).collect(), Cmp::Eq, 1.0);
                    m.period.push(Lin {
                        terms: ys.iter().zip(&v).map(|(&y, &t)| (y, t as f64)).collect(),
                        c: 0.0,
                    });
                    m.util.push(Lin {
                        terms: ys
                            .iter()
                            .zip(&v)
                            .map(|(&y, &t)| (y, c / (t * g) as f64))
                            .collect(),
                        c: 0.0,
                    });
                    m.hlog.push(Lin {
                        terms: ys
                            .iter()
                            .zip(&v)
                            .map(|(&y, &t)| (y, (1.0 + c / (t * g) as f64).ln()))
                            .collect(),
                        c: 0.0,
                    });
                    m.yvars[i] = ys;
                }
                Dom::Grid { step, lo, hi } => {
                    let k = m.lp.var(lo as f64, hi as f64, true);
                    m.kvar[i] = Some(k);
                    m.period.push(Lin {
                        terms: vec![(k, step as f64)],
                        c: 0.0,
                    });
                    let u = m.lp.var(0.0, 1e6, false);
                    let h = m.lp.var(0.0, 1e6, false);
                    m.uvar[i] = Some(u);
                    m.hvar[i] = Some(h);
                    m.util.push(Lin {
                        terms: vec![(u, 1.0)],
                        c: 0.0,
                    });
                    m.hlog.push(Lin {
                        terms: vec![(h, 1.0)],
                        c: 0.0,
                    });
                    // Outer approximation of U = a / k (a = C / (step·g)) and of
                    // ln(1 + a/k): tangents, valid since both are convex in k.
                    let a = c / (step * g) as f64;
                    // Small ranges get a tangent at every point: the
                    // objective is then exact from the first solve.
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
                    pts.extend(self.oa_points[i].iter().copied());
                    pts.sort_unstable();
                    pts.dedup();
                    for k0 in pts {
                        if k0 < lo.max(1) || k0 > hi {
                            continue;
                        }
                        let k0 = k0 as f64;
                        // U ≥ 2a/k0 − a·k/k0²
                        m.lp.row(vec![(u, 1.0), (k, a / (k0 * k0))], Cmp::Ge, 2.0 * a / k0);
                        // ln(1 + a/k) ≥ ln(1 + a/k0) − a/(k0 (k0 + a))·(k − k0)
                        let s = a / (k0 * (k0 + a));
                        m.lp.row(
                            vec![(h, 1.0), (k, s)],
                            Cmp::Ge,
                            (1.0 + a / k0).ln() + s * k0,
                        );
                    }
                }
            }
            if m.guaranteed(i) {
                for &(v, a) in &m.util[i].terms {
                    objective.push((v, a));
                }
                obj_const += m.util[i].c;
            }
        }
        m.lp.obj = objective.clone();
        m.lp.obj_const = obj_const;
        if spec.harmonic {
            // No two choices that are not harmonic (fixed ones are filtered).
            for a in 0..n {
                for b in a + 1..n {
                    let (Dom::Choice(va), Dom::Choice(vb)) = (&m.dom[a], &m.dom[b]) else {
                        continue;
                    };
                    for (x, &p) in va.iter().enumerate() {
                        for (y, &q) in vb.iter().enumerate() {
                            if !harmonic_pair(p, q) {
                                let (ya, yb) = (m.yvars[a][x], m.yvars[b][y]);
                                m.lp.row(vec![(ya, 1.0), (yb, 1.0)], Cmp::Le, 1.0);
                            }
                        }
                    }
                }
            }
        }

        // Schedulability per CPU.
        let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
        cpus.sort_unstable();
        cpus.dedup();
        for &cpu in &cpus {
            let ids: Vec<usize> = (0..n)
                .filter(|&i| spec.tasks[i].cpu == cpu && m.guaranteed(i))
                .collect();
            let sched_on = groups.contains(&Group::Sched(cpu));
            let sum_u = ids
                .iter()
                .fold(Lin::default(), |acc, &i| acc.plus(&m.util[i]));
            // Σ U ≤ 1 is necessary for any test; the group adds the test's bound.
            let bound = if sched_on {
                match spec.schedulability {
                    SchedTest::LiuLayland => {
                        let k = ids.len().max(1) as f64;
                        k * (2f64.powf(1.0 / k) - 1.0)
                    }
                    _ => 1.0,
                }
            } else {
                1.0
            };
            m.lp.row(sum_u.terms.clone(), Cmp::Le, bound - sum_u.c);
            if sched_on && spec.schedulability == SchedTest::Hyperbolic {
                let sum_h = ids
                    .iter()
                    .fold(Lin::default(), |acc, &i| acc.plus(&m.hlog[i]));
                m.lp.row(sum_h.terms.clone(), Cmp::Le, 2f64.ln() - sum_h.c);
            }
        }
        if spec.schedulability == SchedTest::Rta {
            // Exact RTA where the levels fit: budget-level R_i ≥ W_i(R_i), R_i ≤ T_i.
            let tested: Vec<bool> = (0..n)
                .map(|i| m.guaranteed(i) && groups.contains(&Group::Sched(spec.tasks[i].cpu)))
                .collect();
            for i in (0..n).filter(|&i| tested[i]) {
                let rmax = m.dom[i].max() as f64;
                let r = m.lp.var(0.0, rmax, false);
                let mut t = m.period[i].terms.clone();
                t.push((r, -1.0));
                m.lp.row(t, Cmp::Ge, -m.period[i].c);
                m.rta_levels(
                    i,
                    r,
                    gu(spec.tasks[i].budget(), g),
                    rmax,
                    &self.levels,
                    true,
                );
            }
            for cut in self.rta_cuts.clone() {
                if groups.contains(&Group::Sched(spec.tasks[cut.i].cpu)) {
                    add_rta_cut(&mut m, &cut);
                }
            }
        }
        // Sound mode: response-time variables with their lower bounds, and
        // every chain task finishes within its period (T ≥ R).
        if let (Some(sm), Scheduler::Rm) = (sound, spec.scheduler) {
            for i in (0..n).filter(|&i| self.on_chain[i]) {
                let r = match &sm.fixed {
                    Some(f) => m.lp.var(f[i], f[i], false),
                    None => {
                        let hi = rmax_of(&m, groups, i).max(sm.rlow[i]);
                        m.lp.var(sm.rlow[i], hi, false)
                    }
                };
                m.rvar[i] = Some(r);
                let mut t = m.period[i].terms.clone();
                t.push((r, -1.0));
                m.lp.row(t, Cmp::Ge, -m.period[i].c);
            }
            // R_i ≥ W_i(R_i), the response-time recurrence, with a binary per
            // job of each higher-priority task (docs/design.md); not when the
            // response times are pinned.
            let levels_on = sm.fixed.is_none();
            for i in (0..n).filter(|&i| levels_on && self.on_chain[i]) {
                let Some(r) = m.rvar[i] else { continue };
                let rmax = rmax_of(&m, groups, i);
                m.rta_levels(
                    i,
                    r,
                    gu(spec.tasks[i].demand(), g),
                    rmax,
                    &self.levels,
                    false,
                );
            }
            if sm.fixed.is_none() {
                for cut in &sm.cuts {
                    add_r_cut(&mut m, cut);
                }
            }
        }
        // Chain limits.
        for (k, ch) in spec.chains.iter().enumerate() {
            for metric in [Metric::Reaction, Metric::Freshness] {
                let limit = match metric {
                    Metric::Reaction => ch.reaction,
                    Metric::Freshness => ch.freshness,
                };
                let Some(limit) = limit else { continue };
                if !groups.contains(&Group::Limit(k, metric)) {
                    continue;
                }
                let l = gu(limit, g);
                match sound {
                    None => paper_chain(&mut m, &ch.path, metric, l),
                    Some(sm) => sound_chain(&mut m, &ch.path, metric, l, sm),
                }
            }
        }
        (m, objective)
    }

    fn solve_master(&mut self, groups: &[Group], sound: Option<&SoundModel>) -> Solved {
        let (m, _) = self.build(groups, sound);
        let left = Limits {
            time: self.opts.time_limit.map(|t| (t - self.elapsed()).max(0.01)),
            nodes: self.work_cap.map(|c| c.saturating_sub(self.work)),
        };
        if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
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
        // A complete starting solution: the master with every period fixed
        // to the best verified design's (a small MILP: the periods decide
        // most binaries), so that branch and bound can prune by bound from
        // the start.
        let mut hint = None;
        if let (Some(p), SolverKind::Microlp) = (&self.start_periods, self.opts.solver) {
            let mut fixed = m.lp.clone();
            for (i, &pi) in p.iter().enumerate() {
                let t = pi / self.g;
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
            let s = lp::solve(
                &fixed,
                self.opts.solver,
                Limits {
                    time: left.time,
                    nodes: Some(HINT_NODES.min(left.nodes.unwrap_or(u64::MAX))),
                },
            );
            self.work = self.work.saturating_add(s.work);
            if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
                eprintln!(
                    "master: starting solution {:?} (work {})",
                    s.result.as_ref().map(|x| x.objective),
                    s.work
                );
            }
            hint = s.result.ok().map(|x| x.values);
        }
        let left = Limits {
            time: self.opts.time_limit.map(|t| (t - self.elapsed()).max(0.01)),
            nodes: self.work_cap.map(|c| c.saturating_sub(self.work)),
        };
        let lp::Solve {
            result: solved,
            work,
            numerical,
        } = lp::solve_hinted(&m.lp, self.opts.solver, left, hint.as_deref());
        self.work = self.work.saturating_add(work);
        self.numerical.last_skipped = false;
        if let Some(n) = &numerical {
            if self.numerical.message.is_none() {
                self.numerical.message = Some(n.message.clone());
            }
            if n.from_failed {
                self.numerical.from_failed += 1;
            } else if n.solved_by > 0 {
                self.numerical.resolved += 1;
            } else {
                self.numerical.skipped += 1;
                self.numerical.last_skipped = true;
            }
            if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
                eprintln!("master: numerical failure {n:?}");
            }
        }
        if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
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
        match solved {
            Err(LpError::Infeasible) => Solved::Infeasible,
            Err(LpError::TimeLimit | LpError::NodeLimit(_)) => Solved::Stopped,
            // The solver failed numerically on every attempt (`lp::solve`
            // re-solved it written differently): not the user's error, and
            // nothing proven; every caller treats it as a stopped solve.
            Err(LpError::Other(_)) if numerical.is_some() => Solved::Stopped,
            Err(LpError::TooLarge { .. }) => Solved::Error(
                DesignError::solver(format!(
                    "the solver cannot represent the model: {}",
                    solved.err().map(|e| e.to_string()).unwrap_or_default()
                ))
                .help(
                    "periods are integers in steps of the resolution: set a coarser `resolution` in [system] (e.g. \"1us\" or \"1ms\") or narrow the period ranges",
                ),
            ),
            Err(e) => Solved::Error(DesignError::solver(e.to_string())),
            Ok(sol) => {
                let periods = (0..self.spec.tasks.len())
                    .map(|i| {
                        let t: f64 = m.period[i]
                            .terms
                            .iter()
                            .map(|&(v, a)| a * sol.values[v])
                            .sum::<f64>()
                            + m.period[i].c;
                        (t.round() as i64) * self.g
                    })
                    .collect();
                let rv = m.rvar.iter().map(|v| v.map(|v| sol.values[v])).collect();
                Solved::Periods(periods, sol.objective, sol.optimal, rv)
            }
        }
    }

    fn all_groups(&self) -> Vec<Group> {
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

    /// A verified design by local search on the analysis alone: chain tasks
    /// start at their shortest period, the others at their longest; then
    /// every task in turn lengthens its period (largest utilisation first,
    /// in growing jumps) while the design still verifies. Cheap and often
    /// good; it proves nothing, so it only seeds the incumbent.
    fn descent(&mut self) -> Option<(Spec, Report, f64)> {
        let spec = self.spec;
        let n = spec.tasks.len();
        // Candidate values per task (ns): every choice, or a geometric ladder
        // over a range (about 10 % apart, both ends included).
        let values: Vec<Vec<Nanos>> = self
            .dom
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
            .collect();
        let on_chain = &self.on_chain;
        let periods = |idx: &[usize]| -> Vec<Nanos> { (0..n).map(|i| values[i][idx[i]]).collect() };
        let check = |me: &Self, idx: &[usize]| -> Option<(Spec, Report)> {
            let cand = me.with_periods(&periods(idx));
            let report = rtpipe_analysis::analyze(&cand);
            (report.schedulability.schedulable && me.limits_ok(&report)).then_some((cand, report))
        };
        // Starts: chain tasks as fast as a per-CPU utilisation share u allows
        // (each of k tasks on the CPU gets u/k), the others at their longest
        // period; the first start that verifies wins.
        let per_cpu = |i: usize| {
            (0..n)
                .filter(|&j| spec.tasks[j].cpu == spec.tasks[i].cpu && on_chain[j])
                .count()
                .max(1) as f64
        };
        let start = |u: f64| -> Vec<usize> {
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
        };
        // From a start that is schedulable but misses limits, speed up the
        // tasks of every failing chain one step at a time.
        let repair = |me: &Self, mut idx: Vec<usize>| -> Option<(Vec<usize>, (Spec, Report))> {
            for _ in 0..4 * values.iter().map(Vec::len).max().unwrap_or(1) {
                let cand = me.with_periods(&periods(&idx));
                let report = rtpipe_analysis::analyze(&cand);
                if !report.schedulability.schedulable || me.out_of_time() {
                    return None;
                }
                if me.limits_ok(&report) {
                    return Some((idx, (cand, report)));
                }
                let mut changed = false;
                for c in &report.chains {
                    let ok = me.chain_ok(c);
                    // Not the tail: its period does not enter its chain's
                    // bounds (its response time does), and speeding it up
                    // only adds load.
                    let path = &spec.chains[c.chain].path;
                    if !ok {
                        for &i in &path[..path.len() - 1] {
                            if idx[i] > 0 {
                                idx[i] -= 1;
                                changed = true;
                            }
                        }
                    }
                }
                if !changed {
                    return None;
                }
            }
            None
        };
        let (mut idx, mut best) = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1]
            .iter()
            .find_map(|&u| repair(self, start(u)))?;
        self.say(|| "a first verified design by local search".into());
        loop {
            let mut moved = false;
            let mut order: Vec<usize> = (0..n).filter(|&i| idx[i] + 1 < values[i].len()).collect();
            order.sort_by(|&a, &b| {
                let u = |i: usize| spec.tasks[i].budget() as f64 / values[i][idx[i]] as f64;
                u(b).total_cmp(&u(a))
            });
            for i in order {
                let mut jump = 1;
                while idx[i] + jump < values[i].len() && !self.out_of_time() {
                    let mut trial = idx.clone();
                    trial[i] += jump;
                    match check(self, &trial) {
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

    /// The spec with these periods fixed.
    fn with_periods(&self, periods: &[Nanos]) -> Spec {
        let mut s = self.spec.clone();
        for (t, &p) in s.tasks.iter_mut().zip(periods) {
            t.period = PeriodSpec::Fixed(p);
        }
        s
    }

    /// Adds outer-approximation points where the model under-estimated the
    /// utilisation (or the hyperbolic term); true when nothing was added.
    fn oa_exact(&mut self, periods: &[Nanos]) -> bool {
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

    /// Checks the schedulability test exactly; adds an RTA cut on failure.
    fn sched_ok(&mut self, spec: &Spec, report: &Report) -> bool {
        if report.schedulability.schedulable {
            return true;
        }
        if self.spec.schedulability == SchedTest::Rta {
            let prio = rtpipe_analysis::sched::rm_priorities(spec);
            for (i, tm) in report.timing.iter().enumerate() {
                if spec.tasks[i].server == Server::Background {
                    continue;
                }
                let ok = tm.response_time.is_some_and(|r| r <= tm.period);
                if !ok {
                    let top = rtpipe_analysis::sched::top_priorities(spec, &prio);
                    let hp = rtpipe_analysis::sched::interferers(spec, &prio, &top, i);
                    let periods = hp
                        .iter()
                        .chain(std::iter::once(&i))
                        .map(|&j| (j, spec.tasks[j].fixed_period().unwrap_or(0) / self.g))
                        .collect();
                    self.rta_cuts.push(RtaCut { i, hp, periods });
                    return false;
                }
            }
        }
        false
    }

    /// Counts more jobs of higher-priority tasks where the candidate's
    /// response times need them: for each modelled R_i (job level for chain
    /// tasks in sound mode, budget level under the RTA test), every task j
    /// above i gets levels up to its jobs within the analysed R_i (or T_i
    /// when R_i diverged) plus one. True when any level was added.
    fn raise_levels(&mut self, cand: &Spec, report: &Report) -> bool {
        let spec = self.spec;
        if spec.scheduler != Scheduler::Rm {
            return false;
        }
        let n = spec.tasks.len();
        let prio = rtpipe_analysis::sched::rm_priorities(cand);
        let top = rtpipe_analysis::sched::top_priorities(cand, &prio);
        let sound = self.opts.mode == Mode::Sound;
        let tested = spec.schedulability == SchedTest::Rta;
        let mut raised = false;
        for i in 0..n {
            let chain_task = sound && self.on_chain[i];
            if spec.tasks[i].server == Server::Background {
                continue;
            }
            let t = &report.timing[i];
            let hp = rtpipe_analysis::sched::interferers(cand, &prio, &top, i);
            for (budget_level, on, r) in [
                (false, chain_task, t.job_response_time),
                (true, tested, t.response_time),
            ] {
                if !on {
                    continue;
                }
                let r = r.unwrap_or(t.period).min(t.period.saturating_mul(2));
                for &j in &hp {
                    let tj = report.timing[j].period.max(1);
                    let jobs = ((r + tj - 1) / tj) as usize + 1;
                    let need = (self.dom[i].max() as f64 / self.dom[j].min().max(1) as f64).ceil()
                        as usize
                        + 1;
                    let e = self.levels.entry((budget_level, i, j)).or_insert(1);
                    let want = jobs.min(need);
                    if want > *e {
                        *e = want;
                        raised = true;
                    }
                }
            }
        }
        raised
    }

    /// One chain limit holds under the mode's analysis.
    fn chain_ok(&self, c: &ChainResult) -> bool {
        c.ok_in(self.opts.mode)
    }

    fn limits_ok(&self, report: &Report) -> bool {
        report.chains.iter().all(|c| self.chain_ok(c))
    }

    fn solve_all(&mut self) -> Result<Outcome, DesignError> {
        let groups = self.all_groups();
        let mut notes = Vec::new();
        // The master is always a relaxation: utilisation and the hyperbolic
        // term are under-approximated by tangents, response times by valid
        // lower bounds. A candidate that the analysis verifies is therefore
        // optimal; one that fails yields a cut that removes it.
        let mut sound: Option<SoundModel> = match self.opts.mode {
            Mode::Paper => None,
            Mode::Sound => Some(SoundModel {
                rlow: self.rhat_lower(),
                cuts: Vec::new(),
                fixed: None,
            }),
        };
        // Every period at its longest: a lower bound before any master ends.
        let mut lower_bound: Option<f64> = Some(
            (0..self.spec.tasks.len())
                .filter(|&i| self.spec.tasks[i].server != Server::Background)
                .map(|i| self.spec.tasks[i].budget() as f64 / (self.dom[i].max() * self.g) as f64)
                .sum(),
        );
        // A verified design from the heuristic phase (sound mode), and when
        // the exact search after it started.
        // A quick verified design, if there is an easy one: reported when
        // the exact search runs out of time (it does not start the patience).
        let mut incumbent: Option<(Spec, Report, f64)> = self.descent();
        self.publish(&incumbent, lower_bound);
        let mut heuristic_tried = false;
        // Work done when the exact search found its first verified design.
        let mut exact_since: Option<u64> = None;
        loop {
            let patience_out = incumbent.is_some()
                && self.opts.time_limit.is_none()
                && self
                    .opts
                    .patience
                    .is_some_and(|p| exact_since.is_some_and(|t| self.work.saturating_sub(t) > p));
            if self.iterations >= self.opts.max_iterations || self.out_of_time() || patience_out {
                break;
            }
            self.iterations += 1;
            self.start_periods = incumbent
                .as_ref()
                .filter(|_| std::env::var_os("RTPIPE_NO_HINT").is_none())
                .map(|x| {
                    x.0.tasks
                        .iter()
                        .map(|t| t.fixed_period().unwrap_or(0))
                        .collect()
                });
            self.say(|| {
                let best = incumbent.as_ref().map_or(String::new(), |(_, _, u)| {
                    format!(", best verified U = {u:.4}")
                });
                let lb = lower_bound.map_or(String::new(), |b| format!(", lower bound {b:.4}"));
                format!("master problem {}{lb}{best}", self.iterations)
            });
            let solved = self.solve_master(&groups, sound.as_ref());
            if std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some() {
                if let Solved::Periods(p, obj, opt, _) = &solved {
                    eprintln!(
                        "iteration {}: objective {obj:.6} optimal {opt} periods {:?} ({:.2} s)",
                        self.iterations,
                        p,
                        self.elapsed()
                    );
                }
            }
            match solved {
                Solved::Error(e) => return Err(e),
                Solved::Stopped => {
                    break;
                }
                Solved::Infeasible => {
                    // Infeasibility is proven; explaining it gets a bounded
                    // effort unless a time limit says otherwise.
                    if let (None, Some(p)) = (self.opts.time_limit, self.opts.patience) {
                        self.work_cap =
                            Some(self.work.saturating_add(EXPLAIN_EFFORT.saturating_mul(p)));
                    }
                    let (conflicts, minimal) = self.explain(&groups, sound.as_ref());
                    if !minimal || self.out_of_time() {
                        notes.push(if self.opts.time_limit.is_some() {
                            "the conflict search ran out of time: the set may not be minimal and fixes may be missing".to_string()
                        } else {
                            "the conflict search used up its work budget: the set may not be minimal and fixes may be missing (--time-limit S searches for S seconds instead)".to_string()
                        });
                    }
                    return Ok(self.outcome(Status::Infeasible, None, None, conflicts, notes));
                }
                Solved::Periods(periods, obj, optimal, rmodel) => {
                    if optimal {
                        lower_bound = Some(lower_bound.map_or(obj, |b: f64| b.max(obj)));
                    }
                    let cand = self.with_periods(&periods);
                    let report = rtpipe_analysis::analyze(&cand);
                    // Any candidate the analysis accepts is a valid design,
                    // optimal or not: keep the best one.
                    if report.schedulability.schedulable && self.limits_ok(&report) {
                        let u = utilization(&cand);
                        if incumbent.as_ref().is_none_or(|(_, _, b)| u < *b) {
                            incumbent = Some((cand.clone(), report.clone(), u));
                            self.publish(&incumbent, lower_bound);
                        }
                        exact_since.get_or_insert(self.work);
                    }
                    if let (Some(t), None, None, Some(p)) = (
                        exact_since,
                        self.opts.time_limit,
                        self.work_cap,
                        self.opts.patience,
                    ) {
                        self.work_cap = Some(t.saturating_add(p));
                    }
                    if let (false, Some(sm)) = (heuristic_tried, &sound) {
                        if !self.limits_ok(&report) {
                            // Look for a verified design quickly: pin response
                            // times to estimates and raise them until one verifies.
                            heuristic_tried = true;
                            let start: Vec<f64> = (0..cand.tasks.len())
                                .map(|i| {
                                    let r = report.timing[i]
                                        .job_response_time
                                        .map_or(0.0, |r| gu(r, self.g));
                                    r.max(sm.rlow[i])
                                })
                                .collect();
                            let sm_copy = sm.clone();
                            if let Some(h) = self.heuristic(&groups, &sm_copy, start) {
                                if incumbent.as_ref().is_none_or(|(_, _, b)| h.2 < *b) {
                                    incumbent = Some(h);
                                    self.publish(&incumbent, lower_bound);
                                }
                            }
                            exact_since.get_or_insert(self.work);
                            if let (None, Some(_), Some(p)) =
                                (self.opts.time_limit, &incumbent, self.opts.patience)
                            {
                                self.work_cap.get_or_insert(self.work.saturating_add(p));
                            }
                        }
                    }
                    let oa = self.oa_exact(&periods);
                    // Response times the model under-counted: count more jobs.
                    let verified = report.schedulability.schedulable && self.limits_ok(&report);
                    if !verified && self.raise_levels(&cand, &report) {
                        continue;
                    }
                    let sched = self.sched_ok(&cand, &report);
                    if !oa || !sched {
                        // Learn response times from the same candidate now
                        // rather than after it comes back.
                        if let Some(sm) = &mut sound {
                            learn_r_cuts(self.g, &cand, &report, &periods, &rmodel, sm);
                        }
                        continue;
                    }
                    if self.limits_ok(&report) {
                        // A stopped solve's candidate may be worse than the incumbent.
                        let (cand, report) = match incumbent.take() {
                            Some((c, r, u0)) if !optimal && u0 < utilization(&cand) => (c, r),
                            _ => (cand, report),
                        };
                        let u = utilization(&cand);
                        let lb = lower_bound.map(|b| b.min(u));
                        let gap = lb.map(|b| if u > 0.0 { ((u - b) / u).max(0.0) } else { 0.0 });
                        // An optimal solve of any master is a lower bound (every
                        // master is a relaxation), earlier time-outs or not.
                        let closed = gap.is_some_and(|g| g <= 1e-9);
                        let status = if optimal || closed {
                            Status::Optimal
                        } else {
                            Status::Feasible
                        };
                        let mut o =
                            self.outcome(status, Some((cand, report)), lb, Vec::new(), notes);
                        o.objective = Some(u);
                        o.gap = if status == Status::Optimal {
                            Some(0.0)
                        } else {
                            gap
                        };
                        return Ok(o);
                    }
                    let Some(_) = &sound else {
                        return Err(DesignError::internal(
                            "internal: the paper-mode model and the analysis disagree on a candidate",
                        ));
                    };
                    let Some(sm) = &mut sound else { continue };
                    // Learn the response times the model under-estimated.
                    let learnt = learn_r_cuts(self.g, &cand, &report, &periods, &rmodel, sm);
                    if !learnt {
                        return Err(DesignError::internal(
                            "internal: the sound model and the analysis disagree on a candidate",
                        ));
                    }
                }
            }
        }
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
            return Ok(o);
        }
        notes.push(if self.numerical.last_skipped {
            "stopped by a numerical failure of the solver before a verified design".into()
        } else {
            "stopped by the time or iteration limit before a verified design".into()
        });
        let mut o = self.outcome(Status::Unknown, None, lower_bound, Vec::new(), notes);
        o.lower_bound = lower_bound;
        Ok(o)
    }

    /// Response times pinned to estimates, raised to the analysed values of
    /// each failed candidate until a candidate verifies (or the model turns
    /// infeasible). Fast, not exact: the caller keeps the lower bound.
    fn heuristic(
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
                if let Solved::Periods(p, obj, _, _) = &solved {
                    eprintln!(
                        "heuristic: objective {obj:.6} periods {p:?} ({:.2} s)",
                        self.elapsed()
                    );
                }
            }
            let Solved::Periods(p, _, _, _) = solved else {
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

    fn outcome(
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

    /// Lower bounds on job response times that hold for every choice of
    /// periods: own demand plus one job of each task that has higher
    /// priority whatever the periods.
    fn rhat_lower(&self) -> Vec<f64> {
        let spec = self.spec;
        let n = spec.tasks.len();
        (0..n)
            .map(|i| {
                let mut r = spec.tasks[i].demand();
                for j in 0..n {
                    if j == i
                        || spec.tasks[j].cpu != spec.tasks[i].cpu
                        || spec.tasks[j].server == Server::Background
                    {
                        continue;
                    }
                    let (di, dj) = (&self.dom[i], &self.dom[j]);
                    let always_above = dj.max() < di.min() || (j < i && dj.max() <= di.min());
                    if always_above && spec.scheduler == Scheduler::Rm {
                        r += interference(&spec.tasks[j]);
                    }
                }
                gu(r, self.g)
            })
            .collect()
    }

    /// Whether `groups` can hold together: the master loop (tangent, RTA and
    /// response-time cuts) restricted to them, until the master is
    /// infeasible or a candidate needs no more cuts. Cuts learnt here are
    /// valid everywhere and kept.
    /// `None` when it could not be decided (time or iteration limit).
    fn probe(&mut self, groups: &[Group], sound: Option<&SoundModel>) -> Option<bool> {
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
                Solved::Periods(p, _, _, rmodel) => {
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
    fn explain(&mut self, groups: &[Group], sound: Option<&SoundModel>) -> (Vec<Conflict>, bool) {
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
        let spec = self.spec;
        let conflicts = core
            .iter()
            .map(|gr| match *gr {
                Group::Limit(c, metric) => {
                    let ch = &spec.chains[c];
                    let name = ch.name.clone().unwrap_or_else(|| {
                        ch.path
                            .iter()
                            .map(|&i| spec.tasks[i].name.as_str())
                            .collect::<Vec<_>>()
                            .join(">")
                    });
                    let limit = match metric {
                        Metric::Reaction => ch.reaction,
                        Metric::Freshness => ch.freshness,
                    }
                    .unwrap_or(0);
                    self.say(|| format!("infeasible; how far must {name} move"));
                    let fix = self.min_limit(groups, *gr, sound).map(|need| {
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
                Group::Sched(cpu) => Conflict {
                    constraint: format!("cpu {cpu}: {} schedulability", spec.schedulability.name()),
                    fix: Some(
                        "lower the utilisation of its tasks (budgets) or move tasks to another CPU"
                            .into(),
                    ),
                },
            })
            .collect();
        (conflicts, decided)
    }

    /// The smallest limit of chain group `gr` that makes `core` feasible,
    /// by bisection on the limit (in grid units).
    fn min_limit(
        &mut self,
        core: &[Group],
        gr: Group,
        sound: Option<&SoundModel>,
    ) -> Option<Nanos> {
        let Group::Limit(c, metric) = gr else {
            return None;
        };
        let original = self.spec.clone();
        let get = |s: &Spec| match metric {
            Metric::Reaction => s.chains[c].reaction,
            Metric::Freshness => s.chains[c].freshness,
        };
        let lo0 = get(&original)?;
        let mut hi = lo0.max(1);
        // Find a feasible upper end by doubling.
        let feasible = |me: &mut Self, l: Nanos| -> Option<bool> {
            let mut s = original.clone();
            match metric {
                Metric::Reaction => s.chains[c].reaction = Some(l),
                Metric::Freshness => s.chains[c].freshness = Some(l),
            }
            let mut sub = Runner {
                spec: &s,
                opts: me.opts,
                g: me.g,
                dom: me.dom.clone(),
                big_m: me.big_m.max(4.0 * gu(l, me.g)),
                start: me.start,
                rta_cuts: me.rta_cuts.clone(),
                oa_points: me.oa_points.clone(),
                iterations: 0,
                work: me.work,
                work_cap: me.work_cap,
                levels: me.levels.clone(),
                on_chain: me.on_chain.clone(),
                numerical: NumLog::default(),
                start_periods: None,
                boxes: me.boxes,
            };
            let r = sub.probe(core, sound);
            // The sub-search's work counts against the budget.
            me.work = sub.work;
            me.numerical.absorb(&sub.numerical);
            r
        };
        // Any undecided probe makes the answer unknown: say nothing then.
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
}

/// An upper end for R_i: T_i (it finishes within its period) and every
/// active freshness limit of a chain through i (T_p and the tail's R both
/// appear in the freshness sum).
fn rmax_of(m: &Master, groups: &[Group], i: usize) -> f64 {
    let mut r = m.dom[i].max() as f64;
    for (k, ch) in m.spec.chains.iter().enumerate() {
        if let (true, Some(l)) = (
            ch.path.contains(&i) && groups.contains(&Group::Limit(k, Metric::Freshness)),
            ch.freshness,
        ) {
            r = r.min(gu(l, m.g));
        }
    }
    r
}

/// Adds a cut for every chain task whose response time the model
/// under-estimated at this candidate; false when there was none.
fn learn_r_cuts(
    g: i64,
    cand: &Spec,
    report: &Report,
    periods: &[Nanos],
    rmodel: &[Option<f64>],
    sm: &mut SoundModel,
) -> bool {
    let prio = rtpipe_analysis::sched::rm_priorities(cand);
    let top = rtpipe_analysis::sched::top_priorities(cand, &prio);
    let mut learnt = false;
    for (i, mv) in rmodel.iter().enumerate() {
        let (Some(mv), Some(tr)) = (mv, report.timing[i].job_response_time) else {
            continue;
        };
        let tr = gu(tr, g);
        if tr > mv + 1e-6 {
            let hp = rtpipe_analysis::sched::interferers(cand, &prio, &top, i);
            let periods = hp.iter().map(|&j| (j, periods[j] / g)).collect();
            sm.cuts.push(RCut {
                i,
                r: tr,
                hp,
                periods,
            });
            learnt = true;
        }
    }
    learnt
}

fn add_rta_cut(m: &mut Master, cut: &RtaCut) {
    // Σ [T_j ≥ T*_j + 1] + Σ_{j ∈ hp} [j no longer above i] ≥ 1.
    let mut sum: Vec<(usize, f64)> = Vec::new();
    let mut always = false;
    for &(j, tj) in &cut.periods {
        if let Some(b) = m.grew(j, tj) {
            sum.push((b, 1.0));
        }
    }
    for &j in &cut.hp {
        match m.above(j, cut.i) {
            Bin::Const(true) => {}
            Bin::Const(false) => always = true,
            Bin::Var(z) => {
                // flip = 1 − z
                sum.push((z, -1.0));
                // Σ … + (1 − z) ≥ 1 ⇔ Σ … − z ≥ 0; handled by the rhs below.
            }
        }
    }
    if always {
        return;
    }
    let flips = sum.iter().filter(|&&(_, a)| a < 0.0).count() as f64;
    // Σ b + Σ (1 − z) ≥ 1  ⇔  Σ b − Σ z ≥ 1 − flips
    m.lp.row(sum, Cmp::Ge, 1.0 - flips);
}

/// Paper mode (Eqs. 2–6, 12 and Section III-F), with the case of each link a
/// binary: z = 1 ⟺ T_c < T_p.
fn paper_chain(m: &mut Master, path: &[usize], metric: Metric, limit: f64) {
    let g = m.g;
    let spec = m.spec;
    // Budgets cover the demand (validated), so Eq. 1 gives L = x.
    let l = |i: usize| gu(spec.tasks[i].demand(), g);
    let mut total = Lin::constant(l(path[0]));
    let big = m.big_m;
    for w in path.windows(2) {
        let (p, c) = (w[0], w[1]);
        let z = m.lt(c, p, false);
        let delta = gu(spec.tasks[p].delta_out, g);
        let cc = gu(spec.tasks[c].budget(), g);
        let cp = gu(spec.tasks[p].budget(), g);
        let case1 = match metric {
            Metric::Reaction => m.period[c].add_c(-cc - delta + l(c)),
            Metric::Freshness => m.period[p].scale(2.0).add_c(-delta - l(p)),
        };
        let case2 = m.period[p].add_c(-cp - delta + l(c));
        let s = m.lp.var(-big, big, false);
        m.ge_option(s, &case1, &[(z, true)]);
        m.ge_option(s, &case2, &[(z, false)]);
        total = total.plus(&Lin {
            terms: vec![(s, 1.0)],
            c: 0.0,
        });
    }
    m.lp.row(total.terms.clone(), Cmp::Le, limit - total.c);
}

/// R_i ≥ r − M·(Σ [hp period grew] + Σ [left the hp set]).
fn add_r_cut(m: &mut Master, cut: &RCut) {
    let Some(rv) = m.rvar[cut.i] else { return };
    let big = m.big_m;
    let mut terms: Vec<(usize, f64)> = vec![(rv, 1.0)];
    let mut rhs = cut.r;
    for &(j, tj) in &cut.periods {
        if let Some(b) = m.grew(j, tj) {
            terms.push((b, big));
        }
    }
    for &j in &cut.hp {
        match m.above(j, cut.i) {
            Bin::Const(true) => {}
            Bin::Const(false) => return,
            Bin::Var(z) => {
                // (1 − z)·M on the right: R + … − M z ≥ r − M
                terms.push((z, -big));
                rhs -= big;
            }
        }
    }
    m.lp.row(terms, Cmp::Ge, rhs);
}

/// Sound mode (docs/analysis.md): reaction anchored on publishes, freshness
/// on reads, each link term the smallest valid option, the priority cases
/// and the "distinct" property of each stage as binaries.
fn sound_chain(m: &mut Master, path: &[usize], metric: Metric, limit: f64, _sm: &SoundModel) {
    let spec = m.spec;
    let g = m.g;
    let edf = spec.scheduler == Scheduler::Edf;
    let big = m.big_m;
    let r = |m: &Master, i: usize| -> Lin {
        match m.rvar[i] {
            Some(v) if !edf => Lin {
                terms: vec![(v, 1.0)],
                c: 0.0,
            },
            _ => m.period[i].clone(),
        }
    };
    let xmin = |i: usize| gu(spec.tasks[i].demand_min(), g);
    let x = |i: usize| gu(spec.tasks[i].demand(), g);
    let mut e = r(m, path[0]);
    let mut f = Lin::default();
    // d = 1: the stage's jobs carry distinct samples (true at the head).
    let mut d = Bin::Const(true);
    for w in path.windows(2) {
        let (p, c) = (w[0], w[1]);
        let (rp, rc) = (r(m, p), r(m, c));
        let same = !edf && spec.tasks[p].cpu == spec.tasks[c].cpu;
        let (tp, tc) = (m.period[p].clone(), m.period[c].clone());
        let o1 = tc.plus(&rc);
        let o2 = tc.plus(&rc).add_c(-xmin(c));
        let o3 = tp.plus(&rp).plus(&rc).add_c(-xmin(p));
        let o4 = tp.plus(&rc).add_c(-xmin(p));
        let q1 = tp.plus(&rp);
        let q2 = tp.plus(&rp).add_c(-xmin(c));
        let q3 = tp.clone();
        // Bounded by their options, so that the switches get tight big-Ms.
        let span = |opts: &[&Lin], lp: &Lp| -> (f64, f64) {
            let lo = opts
                .iter()
                .map(|o| o.min_in(lp))
                .fold(f64::INFINITY, f64::min);
            let hi = opts
                .iter()
                .map(|o| o.max_in(lp))
                .fold(f64::NEG_INFINITY, f64::max);
            (lo.max(-big), hi.min(big))
        };
        let (llo, lhi) = span(&[&o1, &o2, &o3, &o4], &m.lp);
        let (qlo, qhi) = span(&[&q1, &q2, &q3], &m.lp);
        // HiGHS gets the bounds declared; microlp's basis can go singular
        // when both the bounds and the big-Ms are tight, so there they are
        // only known (used for the big-Ms).
        let (l, gq) = if m.tight_bounds {
            (m.lp.var(llo, lhi, false), m.lp.var(qlo, qhi, false))
        } else {
            (m.lp.var(-big, big, false), m.lp.var(-big, big, false))
        };
        m.floor.insert(l, llo);
        m.floor.insert(gq, qlo);
        // b = 1 picks a reachability option; allowed only when d = 1.
        let b = match d {
            Bin::Const(false) => Bin::Const(false),
            _ => {
                let v = m.lp.binary();
                if let Bin::Var(dv) = d {
                    m.lp.row(vec![(v, 1.0), (dv, -1.0)], Cmp::Le, 0.0);
                }
                Bin::Var(v)
            }
        };
        if same {
            let o = m.above(c, p); // 1: c ≻ p (Case 1)
            m.ge_option(l, &o2, &[(o, true), (b, false)]);
            m.ge_option(l, &o3, &[(o, true), (b, true)]);
            m.ge_option(l, &o1, &[(o, false), (b, false)]);
            m.ge_option(l, &o4, &[(o, false), (b, true)]);
            m.ge_option(gq, &q2, &[(o, true)]);
            m.ge_option(gq, &q3, &[(o, false)]);
        } else {
            m.ge_option(l, &o1, &[(b, false)]);
            m.ge_option(l, &o3, &[(b, true)]);
            m.ge_option(gq, &q1, &[]);
        }
        e = e.plus(&Lin {
            terms: vec![(l, 1.0)],
            c: 0.0,
        });
        f = f.plus(&Lin {
            terms: vec![(gq, 1.0)],
            c: 0.0,
        });
        // Distinct passes to c when c's reads are further apart than p's
        // publishes can be: T_c − R_c + x_c > T_p + R_p − x_min(p).
        d = match d {
            Bin::Const(false) => Bin::Const(false),
            _ => {
                let dc = m.lp.binary();
                if let Bin::Var(dv) = d {
                    m.lp.row(vec![(dc, 1.0), (dv, -1.0)], Cmp::Le, 0.0);
                }
                let lhs = tc
                    .plus(&rc.scale(-1.0))
                    .plus(&tp.scale(-1.0))
                    .plus(&rp.scale(-1.0));
                // lhs + x_c + x_min(p) ≥ ε − M(1 − dc), ε = one grid unit's share of a ns
                let eps = 1.0 / g as f64;
                let mut t = lhs.terms.clone();
                t.push((dc, -big));
                m.lp.row(t, Cmp::Ge, eps - x(c) - xmin(p) - lhs.c - big);
                Bin::Var(dc)
            }
        };
    }
    let tail = *path.last().unwrap_or(&0);
    f = f.plus(&r(m, tail));
    match metric {
        Metric::Freshness => m.lp.row(f.terms.clone(), Cmp::Le, limit - f.c),
        Metric::Reaction => {
            // The reported reaction is min(E, F): one of them must fit.
            let w = m.lp.binary();
            let mut t = e.terms.clone();
            t.push((w, -big));
            m.lp.row(t, Cmp::Le, limit - e.c);
            let mut t = f.terms.clone();
            t.push((w, big));
            m.lp.row(t, Cmp::Le, limit - f.c + big);
        }
    }
}

/// Σ C/T over guaranteed tasks.
pub fn utilization(spec: &Spec) -> f64 {
    spec.tasks
        .iter()
        .filter(|t| t.server != Server::Background)
        .filter_map(|t| t.fixed_period().map(|p| t.budget() as f64 / p as f64))
        .sum()
}

#[cfg(test)]
mod tests;
