//! What the simulator's benches share: a run that names its system when
//! it fails, and one run outside the timed loop that says what is measured.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Throughput};
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::{simulate, ExecModel, Jitter, Phasing, SimConfig};
use std::hint::black_box;
use std::time::Instant;

pub const MS: Nanos = 1_000_000;

pub fn run(spec: &Spec, cfg: &SimConfig) -> SimResult {
    match simulate(spec, cfg) {
        Ok(r) => r,
        Err(e) => panic!("{}: {e}", spec.name),
    }
}

/// One run outside the timed loop: its event count, and on stderr a line
/// with the bench's `details` of it, the span and the rate.
pub fn describe(
    label: &str,
    spec: &Spec,
    cfg: &SimConfig,
    details: impl Fn(&SimResult) -> String,
) -> u64 {
    let t0 = Instant::now();
    let r = run(spec, cfg);
    let wall = t0.elapsed();
    eprintln!(
        "{label}: {} tasks, {} in {} ms simulated; one run {wall:.2?} ({:.2} M events/s)",
        spec.tasks.len(),
        details(&r),
        cfg.horizon / MS,
        r.events as f64 / wall.as_secs_f64() / 1e6
    );
    r.events
}

/// A simulated span with about `events` events: two per job (release and
/// completion) at the system's job rate (a data-triggered task's at its
/// nominal period, `Spec::activation_period`).
pub fn span_for(spec: &Spec, events: f64) -> Nanos {
    let jobs_per_ns: f64 = (0..spec.tasks.len())
        .filter_map(|i| spec.activation_period(i))
        .map(|p| 1.0 / p as f64)
        .sum();
    ((events / 2.0 / jobs_per_ns) as Nanos).max(MS)
}

/// About 400,000 events of `spec` from `seed`: random phasing, uniform
/// demands and jitter, no job log (the runs the scaling benches time).
pub fn random_run(spec: &Spec, seed: u64) -> SimConfig {
    SimConfig {
        horizon: span_for(spec, 400_000.0),
        seed,
        phasing: Phasing::Random,
        exec: ExecModel::Uniform,
        log_jobs: false,
        jitter: Jitter::Uniform,
    }
}

/// Measures `spec` under `cfg` in `group` as `label`, at `events` events
/// per run (the throughput criterion reports).
pub fn bench_events(
    group: &mut BenchmarkGroup<'_, WallTime>,
    label: &str,
    spec: &Spec,
    cfg: &SimConfig,
    events: u64,
) {
    group.throughput(Throughput::Elements(events));
    group.bench_function(BenchmarkId::from_parameter(label), |b| {
        b.iter(|| black_box(run(black_box(spec), black_box(cfg))))
    });
}
