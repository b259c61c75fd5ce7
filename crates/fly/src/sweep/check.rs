//! The check below a written limit. A written `max_period` (or period
//! scale) claims every shorter period too, but the grid flies 2^(i/3) of
//! the spec's period and [`super::refine`] bisects only between the last
//! passing and the first failing point, so a response that is not monotone
//! in the period can fail in a band below the edge that no flown point
//! falls in: aero1kg's steps in light turbulence fail up to a third of
//! their flights with the motor output at 11.4–12.6 ms and pass all at
//! 11.0 and 13.0 ms, where the grid flies 10 and 12.6 ms. The check flies
//! every value from the spec's own (× 1) up to each edge's last passing
//! point on a ladder of ratio 1 + `step`, with the sweep's seeds, phases
//! and rule; a failing check point is a failing point of its sweep, so the
//! edge (the last point that flies before the first that does not) comes
//! down below the lowest one, and every point below it has been flown.
//!
//! It covers the period scale and the motor output's period: ratios of the
//! spec's own, on which a ladder from × 1 has a bottom. A delay sweep
//! starts at 0 ms, where a ratio ladder has none, and it was never the
//! tighter of a chain's limits in the sweeps measured (docs/flight.md), so
//! its written limits rest on the grid and the refinement alone.

use super::refine::{at, family, insert_in_order, value};
use super::{edge, sweep, How, Point, Stage, Variation};
use rtpipe_model::Spec;
use std::sync::atomic::AtomicU64;

/// `points` (a sweep's, refined or not) with the check points of the period
/// scale and the tail period flown and inserted in order, each marked
/// [`Stage::Check`]. Flown in parallel as [`sweep`] flies (values already
/// flown are not flown again); `done` counts the flights; `None` once
/// `stopped` says so.
pub fn check_below(
    spec: &Spec,
    s: &crate::Setup,
    how: &How,
    points: Vec<Point>,
    step: f64,
    done: &AtomicU64,
    stopped: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<Point>> {
    check_with(points, step, |vars| {
        sweep(spec, s, how, vars, done, stopped)
    })
}

/// [`check_below`] with `fly` flying the check points (in the order given;
/// `None`: stopped).
fn check_with(
    mut points: Vec<Point>,
    step: f64,
    fly: impl FnOnce(&[Variation]) -> Option<Vec<Point>>,
) -> Option<Vec<Point>> {
    let wanted = wanted(&points, step);
    for p in fly(&wanted)? {
        insert_in_order(
            &mut points,
            Point {
                stage: Stage::Check,
                ..p
            },
        );
    }
    Some(points)
}

/// The check points not yet flown: per covered sweep with a passing point,
/// [`ladder`] from the larger of × 1 and the sweep's lowest value up to its
/// last passing point.
fn wanted(points: &[Point], step: f64) -> Vec<Variation> {
    assert!(
        step > 0.0 && step < 1.0,
        "a check step in (0, 1), found {step}"
    );
    let mut out = Vec::new();
    for like in [Variation::Scale(1.0), Variation::Rate(1.0)] {
        let f = family(&like);
        let mine = || points.iter().filter(|p| family(&p.variation) == f);
        let Some(top) = edge(points, |v| family(v) == f).last_pass else {
            continue;
        };
        let lowest = mine().map(|p| value(&p.variation)).fold(f64::MAX, f64::min);
        let flown = |x: f64| mine().any(|p| (value(&p.variation) - x).abs() <= 1e-9 * x);
        out.extend(
            ladder(lowest.max(1.0), value(&top.variation), step)
                .filter(|&x| !flown(x))
                .map(|x| at(&like, x)),
        );
    }
    out
}

/// lo × (1 + step)^i for i ≥ 1, strictly below `top`.
fn ladder(lo: f64, top: f64, step: f64) -> impl Iterator<Item = f64> {
    (1..)
        .map(move |i| lo * (1.0 + step).powi(i))
        .take_while(move |&x| x < top)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{derived_limits, tails, tests::cleanflight};

    /// A point of the rate sweep at × `k` that flies or not, as a flight
    /// would give it (one flight, schedulable).
    fn synthetic(k: f64, flies: bool) -> Point {
        Point {
            variation: Variation::Rate(k),
            bounds: Vec::new(),
            event: Vec::new(),
            schedulable: true,
            quality: None,
            failures: Vec::new(),
            outcomes: vec![flies],
            against_reference: None,
            flies,
            stage: Stage::Grid,
        }
    }

    /// A quality response that fails in a band (× 2.28–× 2.5 of the motor
    /// period, 11.4–12.5 ms of 5 ms, where aero1kg's breeze steps fail) below its edge (× 3.0)
    /// and passes elsewhere up to it: the grid (2^(i/3)) and its
    /// refinement fly no point in the band and write × 2.9; the check at
    /// 2 % steps flies the band and brings the written `max_period` below
    /// its lowest value. Without the check the limit stays above the band.
    #[test]
    fn a_failing_band_below_the_edge_brings_the_limit_below_it() {
        let band = |k: f64| (2.28..=2.5).contains(&k);
        let flies = |k: f64| k < 3.0 && !band(k);
        // The grid 2^(i/3) up to × 4 and a refinement at 2 % that found the
        // edge between × 2.9 and × 3.0 (the band between two grid points).
        let mut grid: Vec<Point> = (0..=6)
            .map(|i| 2f64.powf(f64::from(i) / 3.0))
            .chain([2.7, 2.9, 3.0])
            .map(|k| synthetic(k, flies(k)))
            .collect();
        grid.sort_by(|a, b| value(&a.variation).total_cmp(&value(&b.variation)));
        assert!(grid.iter().all(|p| !band(value(&p.variation))));
        let (spec, s) = cleanflight("racer5");
        let pwm = tails(&spec, &s)[0];
        let period = spec.tasks[pwm]
            .fixed_period()
            .unwrap_or_else(|| panic!("a fixed PWM period"));
        let written =
            |points: &[Point]| derived_limits(&spec, &s, points, 1.0).max_period[pwm].unwrap_or(0);
        let before = written(&grid);
        assert_eq!(before, (period as f64 * 2.9).round() as rtpipe_model::Nanos);
        let flown = std::cell::Cell::new(0);
        let checked = check_with(grid, 0.02, |vars| {
            flown.set(vars.len());
            Some(
                vars.iter()
                    .map(|v| synthetic(value(v), flies(value(v))))
                    .collect(),
            )
        })
        .unwrap_or_default();
        // 1.02^i below × 2.9: 53 values, none on the grid.
        assert_eq!(flown.get(), 53);
        let after = written(&checked);
        let lowest_fail = checked
            .iter()
            .find(|p| !p.pass())
            .map(|p| value(&p.variation))
            .unwrap_or_default();
        assert!(band(lowest_fail), "{lowest_fail}");
        assert!(
            (after as f64) < period as f64 * 2.28,
            "{after} ns is not below the band (from {before} ns)"
        );
        // Every point up to the new limit flew, and it is one step below
        // the band.
        assert!(after as f64 >= period as f64 * 2.28 / 1.02 - 1.0, "{after}");
        let up_to = checked
            .iter()
            .filter(|p| value(&p.variation) * period as f64 <= after as f64 + 1.0);
        assert!(up_to.clone().all(Point::pass));
        assert!(checked.iter().any(|p| p.stage == Stage::Check));
    }

    /// A stop while checking answers `None`; a sweep without an edge to
    /// check (nothing passed) flies nothing.
    #[test]
    fn a_stop_ends_the_check_and_nothing_passing_checks_nothing() {
        let grid: Vec<Point> = [1.0, 1.26].map(|k| synthetic(k, true)).to_vec();
        assert!(check_with(grid, 0.02, |_| None).is_none());
        let failing: Vec<Point> = [1.0, 1.26].map(|k| synthetic(k, false)).to_vec();
        let asked = check_with(failing, 0.02, |vars| {
            assert!(vars.is_empty(), "{vars:?}");
            Some(Vec::new())
        });
        assert_eq!(asked.map(|p| p.len()), Some(2));
    }
}
