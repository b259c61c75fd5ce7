//! What a design search learns from its candidates and keeps for the next
//! master problems: RTA cuts, response-time levels, tangent points, and the
//! best verified design as a starting solution.

use crate::domain::Dom;
use crate::problem::Problem;
use crate::rta::{self, Levels, RtaCut};
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};

/// Ranges of at most this many grid steps get every tangent up front.
pub(crate) const DENSE_TANGENTS: i64 = 128;

/// The knowledge the MILP's master problems are built with; every piece is
/// valid for the whole problem, so it is kept across solves (and copied
/// into the conflict search's sub-problems).
#[derive(Debug, Clone)]
pub(crate) struct Learnt {
    pub(crate) rta_cuts: Vec<RtaCut>,
    /// Outer-approximation points (k values) per Grid task.
    pub(crate) oa_points: Vec<Vec<i64>>,
    pub(crate) levels: Levels,
    /// The best verified design's periods (ns): a starting solution for
    /// microlp's branch and bound.
    pub(crate) hint: Option<Vec<Nanos>>,
}

impl Learnt {
    /// Nothing learnt yet about `n` tasks.
    pub(crate) fn new(n: usize) -> Self {
        Learnt {
            rta_cuts: Vec::new(),
            oa_points: vec![Vec::new(); n],
            levels: Levels::new(),
            hint: None,
        }
    }

    /// What a sub-problem (a chain limit moved) starts from: every cut,
    /// level and tangent point, but no starting solution.
    pub(crate) fn for_sub(&self) -> Learnt {
        Learnt {
            rta_cuts: self.rta_cuts.clone(),
            oa_points: self.oa_points.clone(),
            levels: self.levels.clone(),
            hint: None,
        }
    }

    /// Adds outer-approximation points where the model under-estimated the
    /// utilisation (or the hyperbolic term); true when nothing was added.
    pub(crate) fn oa_exact(&mut self, p: &Problem, periods: &[Nanos]) -> bool {
        let mut exact = true;
        for ((d, pts), &t) in p.dom.iter().zip(self.oa_points.iter_mut()).zip(periods) {
            if let Dom::Grid { step, lo, hi } = *d {
                if hi - lo <= DENSE_TANGENTS {
                    continue;
                }
                let k = t / (step * p.g);
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

    /// Checks the schedulability test exactly; learns an RTA cut on
    /// failure.
    pub(crate) fn sched_ok(&mut self, p: &Problem, spec: &Spec, report: &Report) -> bool {
        rta::sched_ok(p, &mut self.rta_cuts, spec, report)
    }

    /// Counts more jobs of higher-priority tasks where the candidate's
    /// response times need them; true when any level was added.
    pub(crate) fn raise_levels(&mut self, p: &Problem, cand: &Spec, report: &Report) -> bool {
        rta::raise_levels(p, &mut self.levels, cand, report)
    }
}
