//! `analyze` as the task count grows: WATERS 2015 task sets
//! (`rtpipe_model::gen::waters_system`, deterministic per seed) of 1k, 10k
//! and 100k tasks at 25 tasks per CPU, and 10k at 100 per CPU, five chains
//! each. The analysis is to stay close to linear in the task count
//! (docs/analysis.md, "Scale").
//!
//! `cargo bench -p rtpipe-analysis --bench scale` (10 samples per size);
//! `RTPIPE_SCALE_MAX=N` leaves out the sizes above N tasks.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rtpipe_analysis::analyze;
use rtpipe_model::gen::{waters_system, WatersConfig};
use rtpipe_model::Spec;
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEED: u64 = 2018;

/// (tasks, tasks per CPU) measured.
const SIZES: [(usize, usize); 4] = [(1_000, 25), (10_000, 25), (100_000, 25), (10_000, 100)];

fn system(tasks: usize, per_cpu: usize) -> Spec {
    waters_system(
        SEED,
        &WatersConfig {
            tasks: Some(tasks),
            cpus: u32::try_from(tasks / per_cpu).expect("a CPU count that fits u32"),
            utilization: 0.5,
            chains: 5,
            synchronous: false,
        },
    )
}

fn describe(spec: &Spec, per_cpu: usize) {
    let t0 = Instant::now();
    let report = analyze(spec);
    eprintln!(
        "{} tasks, {per_cpu} per CPU, {} chains: schedulable {}, one analyze {:.2?}",
        spec.tasks.len(),
        spec.chains.len(),
        report.schedulability.schedulable,
        t0.elapsed()
    );
}

fn bench(c: &mut Criterion) {
    let max: usize = std::env::var("RTPIPE_SCALE_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(usize::MAX);
    let mut group = c.benchmark_group("analyze");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for (tasks, per_cpu) in SIZES.into_iter().filter(|&(n, _)| n <= max) {
        let spec = system(tasks, per_cpu);
        describe(&spec, per_cpu);
        let id = BenchmarkId::new(format!("{per_cpu}-per-cpu"), tasks);
        group.bench_function(id, |b| b.iter(|| black_box(analyze(black_box(&spec)))));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
