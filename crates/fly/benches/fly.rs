//! Co-simulation speed: simulated seconds of flight per wall second, one
//! core, for the full Cleanflight pipeline (ten tasks) flying the `steps`
//! mission (26 s) with each preset.
//!
//! `cargo bench -p rtpipe-fly`. Criterion reports the rate as elements/s,
//! where one element is one simulated millisecond.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rtpipe_fly::{fly, setup, Request};
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

fn flights(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
    let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut group = c.benchmark_group("cleanflight-steps");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for vehicle in ["racer5", "aero1kg"] {
        let r = Request {
            spec_path: &path,
            vehicle,
            mission: "steps",
            horizon: None,
            seed: 1,
        };
        let s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        let t0 = Instant::now();
        let f = fly(&spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
        let wall = t0.elapsed().as_secs_f64();
        let simulated = s.horizon as f64 * 1e-9;
        eprintln!(
            "{vehicle}: {simulated:.1} s flown, {} events, one run {wall:.3} s ({:.0}× real time)",
            f.sim.events,
            simulated / wall
        );
        group.throughput(Throughput::Elements((s.horizon / 1_000_000) as u64));
        group.bench_function(BenchmarkId::from_parameter(vehicle), |b| {
            b.iter(|| black_box(fly(black_box(&spec), black_box(&s), ExecModel::Uniform)))
        });
    }
    group.finish();
}

criterion_group!(benches, flights);
criterion_main!(benches);
