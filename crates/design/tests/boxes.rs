//! The box search (`Method::Boxes`, the default in sound mode) on the
//! bundled design problems: proven optima, verified by the analysis, the
//! same as the MILP's, and a minimal conflict set where none exists.
//! The brute-force agreement on thousands of small problems is in
//! tests/brute_force.rs, Cleanflight with transfers in tests/numerical.rs.

use rtpipe_analysis::analyze;
use rtpipe_design::{design, utilization, Method, Mode, Options, Outcome, Status};
use rtpipe_model::Spec;

fn example(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn solve(name: &str, source: &str) -> Outcome {
    let spec = Spec::parse(name, source).unwrap_or_else(|e| panic!("{name}: {e:?}"));
    let opts = Options {
        mode: Mode::Sound,
        method: Method::Boxes,
        ..Options::default()
    };
    let o = design(&spec, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(o.method, Method::Boxes);
    o
}

/// A proven optimum: verified, its objective its utilisation, no gap.
fn optimum(name: &str, o: &Outcome) -> f64 {
    assert_eq!(o.status, Status::Optimal, "{name}: {:?}", o.notes);
    let s = o.spec.as_ref().expect("an optimal outcome has a design");
    assert!(analyze(s).all_ok(), "{name}: the design fails the analysis");
    let u = utilization(s);
    assert_eq!(o.objective, Some(u));
    assert_eq!(o.lower_bound, Some(u));
    assert_eq!(o.gap, Some(0.0));
    u
}

/// Table V's budgets, periods free: the optimum HiGHS proves with the MILP
/// (docs/design.md), gyro = accl = 3889, ahrs = pid = 1937, radio = 15781,
/// pwm = 44000 µs.
#[test]
fn cleanflight_sound_optimum() {
    let o = solve("cleanflight-design", &example("cleanflight-design.toml"));
    let u = optimum("cleanflight-design", &o);
    let expected = 2.0 * 200.0 / 3889.0 + 2.0 * 100.0 / 1937.0 + 100.0 / 15781.0 + 1000.0 / 44000.0;
    assert!((u - expected).abs() < 1e-12, "{u} vs {expected}");
}

/// The limits derived from flight quality (`rtpipe fly --sweep`).
#[test]
fn cleanflight_derived_optimum() {
    let o = solve("cleanflight-derived", &example("cleanflight-derived.toml"));
    let u = optimum("cleanflight-derived", &o);
    let expected = 2.0 * 200.0 / 6352.0 + 2.0 * 100.0 / 3095.0 + 100.0 / 9718.0 + 1000.0 / 22630.0;
    assert!((u - expected).abs() < 1e-12, "{u} vs {expected}");
}

/// Table II under Liu–Layland in sound mode cannot meet its limits; the
/// deletion filter with box probes leaves exactly these three.
#[test]
fn table2_conflicts_are_minimal() {
    let o = solve("table2-design", &example("table2-design.toml"));
    assert_eq!(o.status, Status::Infeasible);
    let names: Vec<&str> = o.conflicts.iter().map(|c| c.constraint.as_str()).collect();
    assert_eq!(
        names,
        [
            "chain t1>t4: reaction ≤ 10",
            "chain t2>t5>t6: reaction ≤ 25",
            "cpu 0: liu-layland schedulability",
        ]
    );
    assert!(
        o.notes.iter().all(|n| !n.contains("may not be minimal")),
        "{:?}",
        o.notes
    );
}

/// Table II with exact RTA: the optimum docs/design.md gives (and the MILP
/// proves), periods 5, 5, 5, 10, 10, 50 ms.
#[test]
fn table2_rta_optimum() {
    let o = solve("table2-design-rta", &example("table2-design-rta.toml"));
    let u = optimum("table2-design-rta", &o);
    let periods: Vec<i64> = o
        .spec
        .as_ref()
        .map(|s| s.tasks.iter().filter_map(|t| t.fixed_period()).collect())
        .unwrap_or_default();
    assert_eq!(periods, [5, 5, 5, 10, 10, 50].map(|ms| ms * 1_000_000));
    assert!((u - 0.838).abs() < 1e-9, "{u}");
}

/// Known offsets do not change the design (its bounds hold for any
/// phasing) and stay in the answer, with a note saying so.
#[test]
fn known_offsets_are_kept_and_not_used() {
    let src = example("cleanflight-design.toml");
    let plain = solve("cleanflight-design.toml", &src);
    let sync = solve(
        "cleanflight-design (synchronous)",
        &src.replacen("[system]", "[system]\nrelease = \"synchronous\"", 1),
    );
    assert_eq!(sync.status, Status::Optimal);
    assert_eq!(sync.objective, plain.objective);
    let s = sync.spec.unwrap_or_else(|| panic!("a design"));
    assert!(s.tasks.iter().all(|t| t.offset == Some(0)));
    assert!(
        sync.notes
            .iter()
            .any(|n| n.contains("not used by the design")),
        "{:?}",
        sync.notes
    );
}
