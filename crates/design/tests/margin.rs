//! `Objective::Margin`: the design of largest critical scaling factor
//! within a utilisation cap, held against brute force over the design's
//! own period grid on examples/timing-design.toml (three free periods on a
//! 0.5 ms grid; no transfers and no given budgets, so each task's
//! utilisation scales with its exec and the search's factor is the
//! optimum, docs/design.md).

use rtpipe_analysis::margins::{self, Control, Factor, ONE};
use rtpipe_analysis::Mode;
use rtpipe_design::{design, utilization, Objective, Options, Outcome, Status};
use rtpipe_model::{Nanos, PeriodSpec, Spec};
use rtpipe_testkit::example;

const MS: Nanos = 1_000_000;

fn margin_design(spec: &Spec, cap: f64) -> Outcome {
    let opts = Options {
        objective: Objective::Margin {
            max_utilization: cap,
        },
        ..Options::default()
    };
    match design(spec, &opts) {
        Ok(o) => o,
        Err(e) => panic!("design: {e:?}"),
    }
}

/// The spec with the periods of the free tasks set (gyro, pid, motors).
fn at(spec: &Spec, periods: [Nanos; 3]) -> Spec {
    let mut s = spec.clone();
    let free = ["gyro", "pid", "motors"];
    for (name, p) in free.iter().zip(periods) {
        let Some(t) = s.tasks.iter_mut().find(|t| t.name == *name) else {
            panic!("timing-design.toml has no task {name}");
        };
        t.period = PeriodSpec::Fixed(p);
    }
    s
}

/// The grid of the free periods: gyro and motors 1–20 ms, pid 2.5–20 ms,
/// every 0.5 ms.
fn grid() -> impl Iterator<Item = [Nanos; 3]> {
    let steps = |lo: Nanos| (lo..=20 * MS).step_by((MS / 2) as usize);
    steps(MS)
        .flat_map(move |g| steps(5 * MS / 2).flat_map(move |p| steps(MS).map(move |m| [g, p, m])))
}

fn holds_scaled(s: &Spec, millionths: Nanos) -> bool {
    let scaled = margins::scaled(s, None, millionths);
    let model_ok = (0..scaled.tasks.len()).all(|i| scaled.timing_conflict(i).is_none());
    model_ok && rtpipe_analysis::analyze(&scaled).ok_in(Mode::Sound)
}

fn factor_of(o: &Outcome) -> Nanos {
    let Some(f) = o.margin.as_ref().and_then(|m| m.factor) else {
        panic!("no factor: {:?}", o.margin);
    };
    (f * ONE as f64).round() as Nanos
}

#[test]
fn no_design_on_the_grid_within_the_cap_keeps_a_larger_factor() {
    let spec = example("timing-design.toml");
    for cap in [0.6, 0.33, 0.30] {
        let o = margin_design(&spec, cap);
        assert_eq!(o.status, Status::Optimal, "cap {cap}: {:?}", o.notes);
        let Some(answer) = &o.spec else {
            panic!("cap {cap}: no design");
        };
        assert!(utilization(answer) <= cap + 1e-12, "cap {cap}");
        let found = factor_of(&o);
        assert!(holds_scaled(answer, found), "cap {cap}: ×{found} fails");
        // Beyond the bisection's resolution (0.1 %), nothing on the grid
        // within the cap keeps the verdict.
        let beyond = found + found / 500;
        let better = grid()
            .map(|p| at(&spec, p))
            .filter(|s| utilization(s) <= cap + 1e-12)
            .find(|s| holds_scaled(s, beyond));
        assert!(
            better.is_none(),
            "cap {cap}: a grid design keeps ×{beyond} (answer ×{found})"
        );
        // The answer's own factor, searched exactly, is at least the one
        // it was designed for.
        let own = margins::critical_scaling(answer, Mode::Sound, None, &Control::QUIET);
        match own.map(|s| s.factor) {
            Ok(Factor::Millionths(m)) => assert!(m as Nanos >= found, "cap {cap}: own ×{m}"),
            other => panic!("cap {cap}: {other:?}"),
        }
    }
}

#[test]
fn the_margin_answer_has_more_margin_than_the_least_utilisation_one() {
    let spec = example("timing-design.toml");
    let least = match design(&spec, &Options::default()) {
        Ok(o) => o,
        Err(e) => panic!("design: {e:?}"),
    };
    let Some(least_spec) = &least.spec else {
        panic!("no least-utilisation design");
    };
    let least_factor =
        match margins::critical_scaling(least_spec, Mode::Sound, None, &Control::QUIET) {
            Ok(s) => s.factor,
            Err(e) => panic!("{e:?}"),
        };
    // Hand-checked: the least-utilisation design sits on its reaction
    // limit (factor 1); within U ≤ 0.6 every exec may grow by a third.
    assert_eq!(least_factor, Factor::Millionths(ONE as u64));
    let robust = margin_design(&spec, 0.6);
    assert!(factor_of(&robust) >= 4 * ONE / 3 - ONE / 1000);
}

#[test]
fn a_cap_below_the_least_utilisation_has_no_design() {
    let spec = example("timing-design.toml");
    let o = margin_design(&spec, 0.25);
    assert_eq!(o.status, Status::Infeasible, "{:?}", o.notes);
    assert!(o.spec.is_none());
    assert!(
        o.notes.iter().any(|n| n.contains("0.2909")),
        "the least utilisation is named: {:?}",
        o.notes
    );
    let bad = Options {
        objective: Objective::Margin {
            max_utilization: f64::NAN,
        },
        ..Options::default()
    };
    assert!(design(&spec, &bad).is_err());
}
