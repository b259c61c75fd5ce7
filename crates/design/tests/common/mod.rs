//! Helpers shared by the design's hand-computed tests.

use rtpipe_analysis::analyze;
use rtpipe_design::{design, utilization, Method, Mode, Options, Status};
use rtpipe_model::{Nanos, Spec};

/// A microsecond, ns.
pub const US: Nanos = 1_000;

/// Designs `s` in sound mode with `method`, which must end optimal in the
/// box search with a design `analyze` passes: its periods and job
/// response times (µs) and its utilisation.
pub fn solve(s: &Spec, method: Method) -> (Vec<Nanos>, Vec<Nanos>, f64) {
    let opts = Options {
        mode: Mode::Sound,
        method,
        ..Options::default()
    };
    let o = design(s, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((o.status, o.method), (Status::Optimal, Method::Boxes));
    let d = o.spec.expect("an optimal design");
    let rep = analyze(&d);
    assert!(rep.all_ok());
    let periods: Vec<Nanos> = d.tasks.iter().filter_map(|t| t.fixed_period()).collect();
    let r = rep
        .timing
        .iter()
        .map(|t| t.job_response_time.expect("bounded") / US)
        .collect();
    (periods.iter().map(|p| p / US).collect(), r, utilization(&d))
}
