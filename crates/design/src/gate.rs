//! A check beyond the analysis (a flight, for `design --fly`) that a design
//! must pass to be the answer, and the cuts its failures leave in the box
//! search.
//!
//! A rejected design P cuts the *orthant* of designs no faster than
//! (1 − [`CUT_MARGIN`])·P in every task: {T : T_i ≥ (1 − m)·P_i ∀i}. This
//! assumes that a design whose every period is at least 95 % of a failed
//! one's fails too (control gets no better when every rate drops); it is
//! the only assumption of `--fly`, it keeps the number of flights small
//! (each cut removes a neighbourhood, not a grid point), and the answer is
//! the least-utilisation verified design outside every cut that passes.
//! Measured (docs/design.md, `--fly`): the designs `--fly` rejects on
//! Cleanflight pass 58–61 of 76 randomised flights, and the same designs
//! with every period × 0.95 pass 60–67: rejected too, so the margin stays.

use crate::api::{utilization, Acceptance, Checked};
use crate::axis::{Axis, Node};
use rtpipe_model::{Nanos, Spec};
use std::sync::Arc;

/// Designs whose every period is within this share below a rejected one's
/// are cut with it.
pub const CUT_MARGIN: f64 = 0.05;

/// Checks (flights) at most per design; then the search stops as if out of
/// work, with the best accepted design so far.
pub const MAX_CHECKS: usize = 400;

/// The acceptance check, the designs it judged and the cuts they left.
pub(crate) struct Gate {
    check: Arc<dyn Acceptance>,
    /// Per cut, the least axis index of each task inside it.
    cuts: Vec<Vec<u32>>,
    /// Every design checked, in order.
    pub(crate) log: Vec<Checked>,
}

/// What the gate says of a verified point.
pub(crate) enum Verdict {
    /// It passed the check: it may be the answer.
    Accepted,
    /// It lies in this cut (just made, or earlier).
    Cut(usize),
    /// The check budget is spent: the search must stop.
    Exhausted,
}

impl Gate {
    pub(crate) fn new(check: Arc<dyn Acceptance>) -> Self {
        Gate {
            check,
            cuts: Vec::new(),
            log: Vec::new(),
        }
    }

    /// The check budget is spent.
    pub(crate) fn exhausted(&self) -> bool {
        self.log.len() >= MAX_CHECKS
    }

    /// Judges the verified point `k` (axis indices) whose spec is `spec`:
    /// inside an earlier cut it is rejected unchecked; otherwise it is
    /// checked, and a failure adds its cut.
    pub(crate) fn judge(&mut self, axes: &[Axis], k: &[u32], spec: &Spec) -> Verdict {
        if let Some(c) = self.cut_containing(k) {
            return Verdict::Cut(c);
        }
        if self.exhausted() {
            return Verdict::Exhausted;
        }
        let verdict = self.check.accept(spec);
        let accepted = verdict.failure.is_none();
        self.log.push(Checked {
            periods: periods_ns(spec),
            utilization: utilization(spec),
            failure: verdict.failure,
            trials: verdict.trials,
        });
        if accepted {
            return Verdict::Accepted;
        }
        let cut: Vec<u32> = axes
            .iter()
            .zip(k)
            .map(|(a, &ki)| {
                let floor = (1.0 - CUT_MARGIN) * a.value(ki) as f64;
                a.first_at_least(floor).min(ki)
            })
            .collect();
        self.cuts.push(cut);
        Verdict::Cut(self.cuts.len() - 1)
    }

    fn cut_containing(&self, k: &[u32]) -> Option<usize> {
        self.cuts
            .iter()
            .position(|c| c.iter().zip(k).all(|(&ci, &ki)| ki >= ci))
    }

    /// The boxes that cover `node` minus cut `c` (disjoint): for each task
    /// i with room below the cut, task i below it and every earlier task
    /// inside it. Their bounds are Σ C/hi of the caller's.
    pub(crate) fn outside(&self, node: &Node, c: usize) -> Vec<Node> {
        let cut = &self.cuts[c];
        let mut out = Vec::new();
        let mut rest = node.clone();
        for (i, &ci) in cut.iter().enumerate() {
            if rest.lo[i] < ci {
                let mut below = rest.clone();
                below.hi[i] = below.hi[i].min(ci - 1);
                out.push(below);
            }
            if rest.hi[i] < ci {
                break; // nothing of `rest` is inside the cut any more
            }
            rest.lo[i] = rest.lo[i].max(ci);
        }
        out
    }
}

/// The period of every task of a spec whose periods are fixed (ns; 0 for
/// a free one).
pub(crate) fn periods_ns(spec: &Spec) -> Vec<Nanos> {
    spec.tasks
        .iter()
        .map(|t| t.fixed_period().unwrap_or(0))
        .collect()
}
