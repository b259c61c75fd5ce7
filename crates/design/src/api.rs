//! The crate's public types: the options of a design, its outcome and its
//! errors (re-exported by `lib.rs`; every module below it may use them).

use crate::lp::SolverKind;
use rtpipe_analysis::{Mode, Report};
use rtpipe_model::{Diagnostic, Nanos, Server, Spec};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

/// How the exact search runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// The box search where it applies (sound mode; paper mode where Eq. 12
    /// does not fall as a period grows),
    /// the MILP otherwise.
    Auto,
    /// Branch and bound over boxes of periods, pruned by the sound
    /// analysis' relaxation (`bnb.rs`; sound mode only).
    Boxes,
    /// The mixed-integer model of docs/design.md, solved by `solver`.
    Milp,
}

impl Method {
    /// The name the CLI's `--method` takes.
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Boxes => "boxes",
            Method::Milp => "milp",
        }
    }
}

/// How to design: the analysis, the search, the solver and the limits.
#[derive(Debug, Clone)]
pub struct Options {
    /// The analysis the chain limits are judged by.
    pub mode: Mode,
    /// The search to run.
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
    /// A check beyond the analysis that the answer must pass (`design
    /// --fly`: its flights); box search only. See `gate.rs` for the cut a
    /// rejected design leaves.
    pub accept: Option<Arc<dyn Acceptance>>,
    /// What the answer optimises.
    pub objective: Objective,
}

/// What `design` optimises.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Objective {
    /// The least utilisation Σ C/T that meets every limit.
    #[default]
    Utilization,
    /// The largest critical scaling factor (every exec grown together)
    /// among the designs of utilisation at most `max_utilization`.
    Margin {
        /// The cap on Σ C/T.
        max_utilization: f64,
    },
}

/// What the margin objective's search did (`Objective::Margin`).
#[derive(Debug, Clone, PartialEq)]
pub struct MarginSearch {
    /// The utilisation cap.
    pub cap: f64,
    /// The largest factor on every exec at which the design was found
    /// (`None`: no design fits the cap).
    pub factor: Option<f64>,
    /// The answer's own critical scaling factor (at least `factor`).
    pub critical: Option<rtpipe_analysis::margins::Factor>,
    /// `factor` is the largest any design within the cap keeps, to a
    /// thousandth of itself: sound mode, the search not cut short, and
    /// every task's utilisation scaling with its exec (no transfers, no
    /// given budgets); otherwise a verified factor only.
    pub exact: bool,
    /// Every factor tried, in order.
    pub steps: Vec<MarginStep>,
}

/// One factor the margin search tried.
#[derive(Debug, Clone, PartialEq)]
pub struct MarginStep {
    /// The factor on every exec.
    pub factor: f64,
    /// What the least-utilisation search of the scaled system proved.
    pub status: Status,
    /// The utilisation of its design with the execs as given, if any.
    pub utilization: Option<f64>,
    /// It fits the cap.
    pub accepted: bool,
}

/// A check beyond the analysis that a design must pass to be the answer.
pub trait Acceptance: Send + Sync + std::fmt::Debug {
    /// Whether `spec` (every period fixed, verified by the analysis)
    /// passes, why not (said for the user), and the trials it was judged
    /// by.
    fn accept(&self, spec: &Spec) -> Judgement;
}

/// What an [`Acceptance`] check found of one design.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Judgement {
    /// Why it was rejected; `None` when it passed.
    pub failure: Option<String>,
    /// The trials (flights) it was judged by, when the check counts them.
    pub trials: Option<Trials>,
}

/// A design's trials: how many passed of how many run, and the lower
/// confidence bound of its pass rate against the rate required.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trials {
    /// Trials that passed.
    pub passed: u32,
    /// Trials run (a rejection may stop early: fewer than planned).
    pub run: u32,
    /// The lower confidence bound of the pass rate.
    pub lower_bound: f64,
    /// The pass rate the lower bound had to reach.
    pub required: f64,
}

/// A verified design the [`Acceptance`] check judged.
#[derive(Debug, Clone, PartialEq)]
pub struct Checked {
    /// Period of every task (ns), in declaration order.
    pub periods: Vec<Nanos>,
    /// Its Σ C/T.
    pub utilization: f64,
    /// Why it was rejected; `None` when it passed.
    pub failure: Option<String>,
    /// The trials it was judged by, when counted.
    pub trials: Option<Trials>,
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
            accept: None,
            objective: Objective::Utilization,
        }
    }
}

/// What the search proved.
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
    /// The name printed and written to JSON.
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
    /// The constraint, said for the user (e.g. `chain t1>t4: reaction ≤ 10`).
    pub constraint: String,
    /// What would make the rest of the set feasible, when computed.
    pub fix: Option<String>,
}

/// The answer of `rtpipe_design::design`.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What was proven.
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
    /// The MILP's solver (also when the box search ran).
    pub solver: SolverKind,
    /// Wall-clock time of the search.
    pub seconds: f64,
    /// Wall-clock time to the first verified design (box search; `None`
    /// without a design, or from the MILP, which does not time it).
    pub first_design_seconds: Option<f64>,
    /// Master solves (MILP) or boxes examined (box search).
    pub iterations: usize,
    /// The most boxes the box search held open at once (memory).
    pub peak_open: usize,
    /// The most bytes they took at once, counted from their sizes (the
    /// search stops at [`MAX_OPEN_BYTES`](crate::MAX_OPEN_BYTES)).
    pub peak_open_bytes: usize,
    /// A small set of constraints that cannot hold together (infeasible).
    pub conflicts: Vec<Conflict>,
    /// What the user should know about the answer.
    pub notes: Vec<String>,
    /// Every design the [`Options::accept`] check judged, in order (empty
    /// without one).
    pub checked: Vec<Checked>,
    /// The margin objective's search (`None` for least utilisation).
    pub margin: Option<MarginSearch>,
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
    /// Whose fault it is.
    pub kind: ErrorKind,
    /// What went wrong and what to change, when we can tell.
    pub diagnostic: Diagnostic,
    /// The spec key it is about, as a dotted path
    /// (`rtpipe_model::input::locate`'s form, e.g. `system.overheads`),
    /// for a caller holding the spec's text to place it.
    pub key: Option<String>,
}

impl DesignError {
    fn of(kind: ErrorKind, message: impl Into<String>) -> Self {
        DesignError {
            kind,
            diagnostic: Diagnostic::new(message, None),
            key: None,
        }
    }

    /// A problem with the input.
    pub fn input(message: impl Into<String>) -> Self {
        DesignError::of(ErrorKind::Input, message)
    }

    /// A failure of the solver.
    pub fn solver(message: impl Into<String>) -> Self {
        DesignError::of(ErrorKind::Solver, message)
    }

    /// A bug: rtpipe's model and analysis disagree.
    pub fn internal(message: impl Into<String>) -> Self {
        DesignError::of(ErrorKind::Internal, message)
    }

    /// The same error, about the spec key `key` (a dotted path).
    pub(crate) fn at(mut self, key: impl Into<String>) -> Self {
        self.key = Some(key.into());
        self
    }

    pub(crate) fn help(mut self, help: impl Into<String>) -> Self {
        self.diagnostic = self.diagnostic.help(help);
        self
    }
}

/// The message alone (the help is the caller's to show).
impl std::fmt::Display for DesignError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.diagnostic.message)
    }
}

impl std::error::Error for DesignError {}

/// The conflict search may take this many times the patience.
pub const EXPLAIN_EFFORT: u64 = 3;

/// Work (branch-and-bound nodes, plus one per master solve) the exact
/// search may spend after the first verified design, when no time limit is
/// given; about 20 s of microlp on Table II (6,000 nodes/s).
pub const EXACT_PATIENCE: u64 = 120_000;

/// Σ C/T over guaranteed tasks, a data-triggered task's T the rate it
/// inherits from its triggers (`Spec::activation_period`, as the
/// analysis' C/T column).
pub fn utilization(spec: &Spec) -> f64 {
    (0..spec.tasks.len())
        .filter(|&i| spec.tasks[i].server != Server::Background)
        .filter_map(|i| {
            let p = spec.activation_period(i)?;
            Some(spec.tasks[i].budget() as f64 / p as f64)
        })
        .sum::<f64>()
        + 0.0 // an empty sum is -0.0
}
