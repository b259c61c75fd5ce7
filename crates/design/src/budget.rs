//! The budget of one design search: what it may spend (work, time,
//! iterations) and what it has spent, with the solver's numerical failures
//! on the way; and the outcome stamped with it.

use crate::api::{Conflict, Options, Outcome, Status};
use crate::lp::{Limits, Numerical};
use crate::problem::Problem;
use rtpipe_analysis::Report;
use rtpipe_model::Spec;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Without a time limit, the whole MILP search (before the conflict search
/// of an infeasible problem, which has its own effort) spends at most this
/// many times [`Options::patience`] of work.
pub const SEARCH_EFFORT: u64 = 1;

/// The work, time and iterations of one search (the conflict search's
/// sub-searches get one of their own, see [`Budget::sub`]).
pub(crate) struct Budget {
    start: Instant,
    /// Wall-clock limit (s), from [`Options::time_limit`].
    time_limit: Option<f64>,
    /// Set from outside (Ctrl-C), from [`Options::cancel`].
    cancel: Option<Arc<AtomicBool>>,
    /// Master solves (MILP) or boxes examined (box search).
    pub(crate) iterations: usize,
    /// Work done so far (see [`Options::patience`]).
    pub(crate) work: u64,
    /// No solve may run past this much work (the patience after a verified
    /// design, the conflict search's effort).
    pub(crate) work_cap: Option<u64>,
    /// The whole MILP search's work without a time limit (see
    /// [`Budget::bound_search`]).
    pub(crate) search_cap: Option<u64>,
    /// Numerical failures of the solver and what became of them.
    pub(crate) numerical: NumLog,
    /// The box search stopped because its open boxes reached
    /// [`MAX_OPEN_BYTES`](crate::frontier::MAX_OPEN_BYTES).
    pub(crate) memory_full: bool,
}

impl Budget {
    /// Nothing spent yet, the clock started at `start`.
    pub(crate) fn new(opts: &Options, start: Instant) -> Self {
        Budget {
            start,
            time_limit: opts.time_limit,
            cancel: opts.cancel.clone(),
            iterations: 0,
            work: 0,
            work_cap: None,
            search_cap: None,
            memory_full: false,
            numerical: NumLog::default(),
        }
    }

    /// A sub-search's budget: what is left of this one, with its own
    /// iterations and numerical log (see [`Budget::absorb`]).
    pub(crate) fn sub(&self) -> Budget {
        Budget {
            start: self.start,
            time_limit: self.time_limit,
            cancel: self.cancel.clone(),
            iterations: 0,
            work: self.work,
            work_cap: self.work_cap,
            search_cap: self.search_cap,
            numerical: NumLog::default(),
            memory_full: false,
        }
    }

    /// A sub-search's spending counts against this budget.
    pub(crate) fn absorb(&mut self, sub: &Budget) {
        self.work = sub.work;
        self.memory_full |= sub.memory_full;
        self.numerical.absorb(&sub.numerical);
    }

    pub(crate) fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Whether the search was cancelled (Ctrl-C).
    pub(crate) fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Cancelled, or out of time or of work.
    pub(crate) fn out_of_time(&self) -> bool {
        self.out_of_clock() || self.cap().is_some_and(|c| self.work >= c)
    }

    /// Cancelled, or past the time limit (work aside).
    pub(crate) fn out_of_clock(&self) -> bool {
        self.cancelled() || self.time_limit.is_some_and(|t| self.elapsed() >= t)
    }

    /// Why a search stopped early, for the user.
    pub(crate) fn stop_cause(&self) -> &'static str {
        if self.cancelled() {
            "interrupted"
        } else if self.memory_full {
            "memory cap: the open boxes reached 1 GiB"
        } else if self.time_limit.is_some() {
            "time limit"
        } else {
            "work budget; --time-limit S searches for S seconds instead"
        }
    }

    /// Without a time limit, the MILP search spends at most
    /// [`SEARCH_EFFORT`] times the patience, verified design or not, so it
    /// ends on any machine (a harmonic design once searched for ten
    /// minutes without a design and without a bound on its work).
    pub(crate) fn bound_search(&mut self, opts: &Options) {
        self.search_cap = match (opts.time_limit, opts.patience) {
            (None, Some(p)) => Some(self.work.saturating_add(p.saturating_mul(SEARCH_EFFORT))),
            _ => None,
        };
    }

    /// The work no solve may pass: the smaller of the two caps.
    fn cap(&self) -> Option<u64> {
        match (self.work_cap, self.search_cap) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// What is left of the time and work budgets.
    pub(crate) fn left(&self) -> Limits {
        Limits {
            time: self.time_limit.map(|t| (t - self.elapsed()).max(0.01)),
            nodes: self.cap().map(|c| c.saturating_sub(self.work)),
        }
    }

    /// The answer to `p`, with what the search spent on it (time,
    /// iterations, the solver's numerical failures as a last note).
    pub(crate) fn outcome(
        &self,
        p: &Problem,
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
            method: p.method,
            solver: p.opts.solver,
            seconds: self.elapsed(),
            first_design_seconds: None,
            iterations: self.iterations,
            peak_open: 0,
            peak_open_bytes: 0,
            conflicts,
            notes,
            checked: Vec::new(),
            margin: None,
        }
    }
}

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
