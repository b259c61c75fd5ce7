//! `--objective margin`: among the designs whose utilisation is at most a
//! cap, the periods under which every exec may grow the most together —
//! the largest critical scaling factor (Lehoczky, Sha and Ding 1989) — so
//! that a user can trade CPU for robustness.
//!
//! The least-utilisation search answers it: scaling every exec by α (the
//! margins' own variant, `rtpipe_analysis::margins::scaled`) and designing
//! that system gives periods that keep every limit and the schedulability
//! test with every exec α times larger; they are accepted at α when the
//! unscaled system at those periods stays within the cap. α is galloped
//! up from 1 and then bisected to a thousandth of itself. Under the sound
//! analysis the verdict is monotone in every exec, so a design accepted
//! at α is accepted at every smaller factor, and the bisection's answer is
//! the largest factor (to its resolution) for which the least-utilisation
//! design of the scaled system fits the cap. That is the optimum when each
//! task's utilisation scales with its exec; with transfers (δ) or given
//! budgets, which do not scale, a design of higher scaled utilisation may
//! fit the cap at a larger factor, so the answer is then a verified lower
//! bound on the best factor. Under the paper's equations the verdict is not
//! monotone in exec: the answer is verified, not the largest.

use crate::api::{utilization, DesignError, MarginSearch, MarginStep, Options, Outcome, Status};
use crate::budget::Budget;
use rtpipe_analysis::margins::{self, Control, ONE};
use rtpipe_analysis::Mode;
use rtpipe_model::bracket::{self, Gallop, Probe};
use rtpipe_model::{Nanos, PeriodSpec, Spec};
use std::time::Instant;

/// The least-utilisation search, given by `lib.rs`.
pub(crate) type LeastUtilization = fn(&Spec, &Options) -> Result<Outcome, DesignError>;

/// The factor's resolution: bisection stops when the interval is below
/// this many millionths per million of the factor found.
const RESOLUTION_PER_MILLION: Nanos = 1_000;

/// The largest factor tried: 1000 × every exec.
const MAX_FACTOR: Nanos = 1_000 * ONE;

/// The design with the largest critical scaling factor whose utilisation
/// is at most `cap`.
pub(crate) fn most_robust(
    spec: &Spec,
    opts: &Options,
    cap: f64,
    least: LeastUtilization,
) -> Result<Outcome, DesignError> {
    assert!(cap.is_finite() && cap > 0.0, "a positive utilisation cap");
    let mut s = Search {
        spec,
        opts,
        cap,
        least,
        clock: Budget::new(opts, Instant::now()),
        steps: Vec::new(),
        best: None,
        stopped: false,
    };
    let best = match s.try_factor(ONE)? {
        Tried::Accepted(o) => (ONE, o),
        Tried::Rejected(o) => return Ok(s.without_design(o)),
    };
    s.best = Some(best);
    s.search()?;
    Ok(s.answer())
}

/// One factor's least-utilisation design, accepted (within the cap, on the
/// unscaled spec) or not (with the scaled search's answer).
enum Tried {
    Accepted(Outcome),
    Rejected(Outcome),
}

/// The search's state: every factor tried, the best accepted.
struct Search<'a> {
    spec: &'a Spec,
    opts: &'a Options,
    cap: f64,
    least: LeastUtilization,
    /// The time limit and Ctrl-C of the whole search (its work is the
    /// scaled searches' own).
    clock: Budget,
    steps: Vec<MarginStep>,
    /// The largest accepted factor (millionths) and its design (on the
    /// unscaled spec).
    best: Option<(Nanos, Outcome)>,
    /// The time limit or a cancel ended the search early.
    stopped: bool,
}

impl Search<'_> {
    /// Doubles the factor while designs are accepted, then halves the
    /// bracket until it is below the resolution ([`bracket`]); the best
    /// accepted design is kept as the probes go.
    fn search(&mut self) -> Result<(), DesignError> {
        let Gallop::Bracketed { good, bad } =
            bracket::gallop(ONE, MAX_FACTOR, ONE, |f| self.probe(f))?
        else {
            return Ok(());
        };
        let resolution = |lo: Nanos, hi: Nanos| {
            (hi - lo > lo / (ONE / RESOLUTION_PER_MILLION)).then(|| lo + (hi - lo) / 2)
        };
        bracket::bisect(good, bad, resolution, |f| self.probe(f))?;
        Ok(())
    }

    /// Whether `factor` gives an accepted design (kept as the best so
    /// far), or no answer once the time limit or a cancel ends the search.
    fn probe(&mut self, factor: Nanos) -> Probe<DesignError> {
        if self.out_of_time() {
            return Ok(None);
        }
        Ok(Some(match self.try_factor(factor)? {
            Tried::Accepted(o) => {
                self.best = Some((factor, o));
                true
            }
            Tried::Rejected(_) => false,
        }))
    }

    /// Whether the time limit or a cancel ends the search now.
    fn out_of_time(&mut self) -> bool {
        self.stopped |= self.clock.out_of_clock();
        self.stopped
    }

    /// The least-utilisation design of the system scaled by `factor`
    /// millionths, accepted when the unscaled spec at its periods fits the
    /// cap (a factor the search could not decide in its budget is not).
    fn try_factor(&mut self, factor: Nanos) -> Result<Tried, DesignError> {
        self.say(factor);
        let scaled = margins::scaled(self.spec, None, factor);
        let o = (self.least)(&scaled, &self.remaining())?;
        let unscaled = o.spec.as_ref().map(|d| with_periods_of(self.spec, d));
        let u = unscaled.as_ref().map(utilization);
        let accepted = u.is_some_and(|u| u <= self.cap + 1e-12);
        self.steps.push(MarginStep {
            factor: factor as f64 / ONE as f64,
            status: o.status,
            utilization: u,
            accepted,
        });
        match unscaled {
            Some(s) if accepted => Ok(Tried::Accepted(self.verified(o, s)?)),
            _ => Ok(Tried::Rejected(o)),
        }
    }

    /// The scaled search's answer turned into the unscaled design, analysed.
    fn verified(&self, o: Outcome, s: Spec) -> Result<Outcome, DesignError> {
        let report = rtpipe_analysis::analyze(&s);
        if self.opts.mode == Mode::Sound && !report.ok_in(Mode::Sound) {
            // A smaller exec never breaks the sound verdict.
            return Err(DesignError::internal(
                "internal: a design of the scaled system fails with the execs as given",
            ));
        }
        let objective = Some(utilization(&s));
        Ok(Outcome {
            spec: Some(s),
            report: Some(report),
            objective,
            lower_bound: None,
            gap: None,
            ..o
        })
    }

    /// The options of one scaled search: what is left of the time limit.
    fn remaining(&self) -> Options {
        let left = self
            .opts
            .time_limit
            .map(|t| (t - self.clock.elapsed()).max(0.001));
        Options {
            time_limit: left,
            ..self.opts.clone()
        }
    }

    fn say(&self, factor: Nanos) {
        if let Some(Ok(mut g)) = self.opts.progress.as_ref().map(|p| p.lock()) {
            let best = self.best.as_ref().map_or(0.0, |b| b.0 as f64 / ONE as f64);
            *g = format!(
                "margin: trying every exec ×{:.3} (best so far ×{best:.3})",
                factor as f64 / ONE as f64
            );
        }
    }

    /// The best design, with its own critical scaling factor and the search.
    fn answer(mut self) -> Outcome {
        let (factor, mut o) = self
            .best
            .take()
            .expect("most_robust keeps the design accepted at ×1 as the best");
        let critical = o
            .spec
            .as_ref()
            .and_then(|s| margins::critical_scaling(s, self.opts.mode, None, &Control::QUIET).ok())
            .map(|sc| sc.factor);
        if self.opts.mode == Mode::Sound {
            let at_least = |f: &margins::Factor| match f {
                margins::Factor::Millionths(m) => *m >= factor as u64,
                margins::Factor::Unlimited => true,
                margins::Factor::Unreachable => false,
            };
            assert!(
                critical.as_ref().is_none_or(at_least),
                "the answer keeps the verdict at the factor it was designed for"
            );
        }
        if self.stopped {
            o.notes.push(format!(
                "the time limit (or Ctrl-C) ended the margin search: every exec ×{:.3} is the largest factor verified, not refined further",
                factor as f64 / ONE as f64
            ));
        }
        o.seconds = self.clock.elapsed();
        o.margin = Some(MarginSearch {
            cap: self.cap,
            factor: Some(factor as f64 / ONE as f64),
            critical,
            exact: self.opts.mode == Mode::Sound && !self.stopped && scales_with_exec(self.spec),
            steps: std::mem::take(&mut self.steps),
        });
        o
    }

    /// No design fits the cap at ×1: the least-utilisation answer without
    /// its design, proven impossible only when that design was proven
    /// least.
    fn without_design(self, mut o: Outcome) -> Outcome {
        if let Some(u) = o.objective {
            o.notes.push(format!(
                "no design within --max-utilization {}: the least utilisation found that meets every limit is {u:.4}{}",
                self.cap,
                if o.status == Status::Optimal { " (proven least)" } else { " (not proven least)" }
            ));
            o.status = match o.status {
                Status::Optimal => Status::Infeasible,
                _ => Status::Unknown,
            };
            o.spec = None;
            o.report = None;
        }
        o.margin = Some(MarginSearch {
            cap: self.cap,
            factor: None,
            critical: None,
            exact: false,
            steps: self.steps,
        });
        o
    }
}

/// Every task's utilisation scales with its exec: no transfers and no
/// given budgets (the margin search's answer is then the optimum).
fn scales_with_exec(spec: &Spec) -> bool {
    spec.tasks
        .iter()
        .all(|t| t.delta_in == 0 && t.delta_out == 0 && t.budget_given.is_none())
}

/// `spec` with the periods `designed` fixed (the scaled design's).
fn with_periods_of(spec: &Spec, designed: &Spec) -> Spec {
    let mut s = spec.clone();
    for (t, d) in s.tasks.iter_mut().zip(&designed.tasks) {
        if let Some(p) = d.fixed_period() {
            if !t.is_triggered() {
                t.period = PeriodSpec::Fixed(p);
            }
        }
    }
    s
}
