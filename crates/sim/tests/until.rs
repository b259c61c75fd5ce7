//! `simulate_until`: the stop check ends a run early with no result, and a
//! run it never stops is exactly `simulate`'s.

use rtpipe_model::gen::{random_system, GenConfig};
use rtpipe_model::Nanos;
use rtpipe_sim::{simulate, simulate_until, ExecModel, Jitter, Phasing, SimConfig};
use std::cell::Cell;

const S: Nanos = 1_000_000_000;

fn config(horizon: Nanos) -> SimConfig {
    SimConfig {
        horizon,
        seed: 9,
        phasing: Phasing::Random,
        exec: ExecModel::Uniform,
        jitter: Jitter::Uniform,
        log_jobs: false,
    }
}

#[test]
fn a_stop_ends_a_long_run_at_its_next_check() {
    let spec = random_system(4, &GenConfig::default());
    // An hour of simulated time: far more than one stretch of events.
    let asked = Cell::new(0u32);
    let stop = || {
        asked.set(asked.get() + 1);
        asked.get() >= 2
    };
    let r = simulate_until(&spec, &config(3600 * S), &stop);
    assert!(matches!(r, Ok(None)), "stopped");
    assert_eq!(asked.get(), 2, "asked at each check, stopped at the second");
}

#[test]
fn a_run_never_stopped_is_simulates() {
    let spec = random_system(4, &GenConfig::default());
    let cfg = config(S / 2);
    let whole = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    match simulate_until(&spec, &cfg, &|| false) {
        Ok(Some(r)) => assert_eq!(format!("{r:?}"), format!("{whole:?}")),
        other => panic!("{other:?}"),
    }
}
