//! Refinement near the edge: the coarse grid brackets each one-dimensional
//! sweep's edge between its last passing point and its first failing one;
//! bisection then flies points between them (with the same seeds × phases)
//! until the bracket is within a stated resolution, so a written limit is
//! the largest value below which every probed point passed, not a grid
//! point whose neighbour just above was never flown.

use super::{edge, flown, How, Point, Stage, Variation, DELAY_LINES};
use rayon::prelude::*;
use rtpipe_model::bracket::{self, Probe};
use rtpipe_model::Spec;
use std::convert::Infallible;
use std::sync::atomic::{AtomicU64, Ordering};

/// The one-dimensional sweeps a variation belongs to: the period scale,
/// each delay line, the actuation rate.
pub(super) fn family(v: &Variation) -> usize {
    match v {
        Variation::Scale(_) => 0,
        Variation::Delay { line, .. } => 1 + line,
        Variation::Rate(_) => 1 + DELAY_LINES.len(),
    }
}

/// A variation's value along its sweep.
pub(super) fn value(v: &Variation) -> f64 {
    match *v {
        Variation::Scale(k) | Variation::Rate(k) => k,
        Variation::Delay { ns, .. } => ns as f64,
    }
}

/// The variation of `like`'s sweep at `x`.
pub(super) fn at(like: &Variation, x: f64) -> Variation {
    match *like {
        Variation::Scale(_) => Variation::Scale(x),
        Variation::Rate(_) => Variation::Rate(x),
        Variation::Delay { line, .. } => Variation::Delay {
            line,
            ns: x.round() as u64,
        },
    }
}

/// `points` (a sweep's, in its variations' order) with every edge refined
/// to `resolution`: between each sweep's last passing point `lo` and first
/// failing point `hi`, the midpoint is flown and replaces the end of its
/// outcome (a point that is not schedulable counts as failing) until
/// hi − lo ≤ resolution × hi. The probed points are inserted in their
/// sweep's order, so [`edge`] and the derived limits see them. Sweeps are
/// refined in parallel; each refinement is sequential and deterministic.
/// `done` counts the flights; `stopped` is asked before each (see
/// [`super::sweep`]): once it says so, no further flight begins and the
/// refinement answers `None`.
pub fn refine(
    spec: &Spec,
    s: &crate::Setup,
    how: &How,
    mut points: Vec<Point>,
    resolution: f64,
    done: &AtomicU64,
    stopped: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<Point>> {
    assert!(
        resolution > 0.0 && resolution < 1.0,
        "a resolution in (0, 1), found {resolution}"
    );
    let brackets: Vec<(Variation, f64, f64)> = (0..=1 + DELAY_LINES.len())
        .filter_map(|f| {
            let e = edge(&points, |v| family(v) == f);
            let (lo, hi) = (e.last_pass?, e.first_fail?);
            Some((lo.variation, value(&lo.variation), value(&hi.variation)))
        })
        .collect();
    let probed: Vec<Vec<Point>> = brackets
        .par_iter()
        .map(|&(like, lo, hi)| bisect(spec, s, how, like, (lo, hi), resolution, done, stopped))
        .collect();
    // A bisection that saw the stop ended early: its points are not the
    // refinement.
    if stopped() {
        return None;
    }
    for p in probed.into_iter().flatten() {
        insert_in_order(&mut points, p);
    }
    Some(points)
}

/// Puts `p` before the first point of its sweep with a greater value (at
/// the end when there is none), so each sweep's points stay in increasing
/// order for [`edge`] and the derived limits.
pub(super) fn insert_in_order(points: &mut Vec<Point>, p: Point) {
    let f = family(&p.variation);
    let x = value(&p.variation);
    let at = points
        .iter()
        .position(|q| family(&q.variation) == f && value(&q.variation) > x)
        .unwrap_or(points.len());
    points.insert(at, p);
}

/// The points flown bisecting (lo, hi) of `like`'s sweep.
#[allow(clippy::too_many_arguments)]
fn bisect(
    spec: &Spec,
    s: &crate::Setup,
    how: &How,
    like: Variation,
    (lo, hi): (f64, f64),
    resolution: f64,
    done: &AtomicU64,
    stopped: &(dyn Fn() -> bool + Sync),
) -> Vec<Point> {
    let mut out = Vec::new();
    // The next probe: the midpoint as its sweep rounds it (a delay to the
    // nanosecond), while the bracket is wider than the resolution and the
    // rounded midpoint still lies strictly inside it.
    let between = |lo: f64, hi: f64| {
        let x = value(&at(&like, (lo + hi) / 2.0));
        (hi - lo > resolution * hi && x > lo && x < hi).then_some(x)
    };
    let flies = |x: f64| -> Probe<Infallible> {
        if stopped() {
            // No answer: the bisection ends with the bracket it has.
            return Ok(None);
        }
        let p = Point {
            stage: Stage::Refinement,
            ..flown(spec, s, at(&like, x), how)
        };
        done.fetch_add(1, Ordering::Relaxed);
        let passed = p.schedulable && p.pass();
        out.push(p);
        Ok(Some(passed))
    };
    let Ok(_) = bracket::bisect(lo, hi, between, flies);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{derived_limits, scale_edge, sweep, tests::cleanflight, Trials};
    use rtpipe_sim::ExecModel;

    /// Refined, the period scale's edge is bracketed within 2 %, every
    /// probed point at or below the new last pass flew, the limit is
    /// written from it (between the coarse last pass's and first fail's
    /// bounds) and every point says flights passed / flown.
    #[test]
    fn refinement_brackets_the_edge_within_the_resolution() {
        let (spec, s) = cleanflight("racer5");
        let c = s.criteria();
        let how = How {
            trials: Trials {
                seeds: 1,
                phases: 2,
            },
            ..How::once(ExecModel::Uniform, &c)
        };
        let vars: Vec<Variation> = [1.0, 1.26, 1.587, 2.0, 2.52].map(Variation::Scale).to_vec();
        let done = AtomicU64::new(0);
        let coarse = sweep(&spec, &s, &how, &vars, &done, &|| false).unwrap_or_default();
        let ce = scale_edge(&coarse);
        let (Some(a), Some(b)) = (ce.last_pass.cloned(), ce.first_fail.cloned()) else {
            panic!("no coarse edge: {coarse:?}");
        };
        let before = done.load(Ordering::Relaxed);
        let fine =
            refine(&spec, &s, &how, coarse.clone(), 0.02, &done, &|| false).unwrap_or_default();
        let probes = (done.load(Ordering::Relaxed) - before) as usize;
        assert_eq!(fine.len(), coarse.len() + probes);
        assert!(probes >= 2, "{probes}");
        let fe = scale_edge(&fine);
        let (Some(fa), Some(fb)) = (fe.last_pass, fe.first_fail) else {
            panic!("no refined edge");
        };
        let (x, y) = (value(&fa.variation), value(&fb.variation));
        assert!(value(&a.variation) <= x && x < y && y <= value(&b.variation));
        assert!(y - x <= 0.02 * y, "{x} {y}");
        // In increasing order, every schedulable point up to the last
        // pass flew all of its flights.
        let scales: Vec<f64> = fine.iter().map(|p| value(&p.variation)).collect();
        assert!(scales.windows(2).all(|w| w[0] < w[1]), "{scales:?}");
        for p in fine
            .iter()
            .filter(|p| value(&p.variation) <= x && p.schedulable)
        {
            assert!(p.pass() && p.passed() == 2 && p.flights() == 2, "{p:?}");
        }
        let lim = derived_limits(&spec, &s, &fine, 1.0).read;
        for (k, l) in lim.iter().enumerate() {
            assert_eq!(l.0, fa.bounds[k].0);
            assert!(a.bounds[k].0 <= l.0 && l.0 < b.bounds[k].0);
        }
    }

    /// A stop seen during the refinement ends it with `None` after at most
    /// the flights begun before it: the probed points are not a refinement.
    #[test]
    fn a_stop_ends_the_refinement_without_an_answer() {
        let (spec, s) = cleanflight("racer5");
        let c = s.criteria();
        let how = How::once(ExecModel::Uniform, &c);
        let vars: Vec<Variation> = [1.0, 1.26, 1.587, 2.0, 2.52].map(Variation::Scale).to_vec();
        let done = AtomicU64::new(0);
        let coarse = sweep(&spec, &s, &how, &vars, &done, &|| false).unwrap_or_default();
        assert!(
            scale_edge(&coarse).first_fail.is_some(),
            "an edge to refine"
        );
        let asked = AtomicU64::new(0);
        let stopped = || asked.fetch_add(1, Ordering::Relaxed) >= 1;
        let before = done.load(Ordering::Relaxed);
        let fine = refine(&spec, &s, &how, coarse, 0.02, &done, &stopped);
        assert!(fine.is_none());
        assert!(done.load(Ordering::Relaxed) - before <= 1, "{done:?}");
    }
}
