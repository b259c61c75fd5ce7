//! Worst paths between all sources and sinks on generated DAGs.
//!
//! `cargo bench -p rtpipe-analysis` (a few minutes: 10 samples per benchmark).
//! The systems come from `rtpipe_model::gen::random_system`, deterministic per
//! seed; each is described on stderr before it is measured.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rtpipe_analysis::{all_paths, analyze, sched};
use rtpipe_model::gen::{random_system, GenConfig};
use rtpipe_model::{Scheduler, Spec};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEED: u64 = 2018;

fn system(tasks: usize) -> Spec {
    random_system(
        SEED,
        &GenConfig {
            tasks,
            cpus: 8,
            utilization: 0.6,
            scheduler: Scheduler::Rm,
            source_fraction: 0.1,
            max_fan_in: 3,
            feedback: 0.0,
            chains: 0,
            // With transfers a fast consumer of a slow producer inherits its
            // large output as Δin and the systems end up unschedulable.
            transfers: false,
            mixed_servers: true,
            inheritance: 0.0,
        },
    )
}

fn describe(spec: &Spec) {
    let t0 = Instant::now();
    let (timing, verdict) = sched::analyze(spec);
    let sched_time = t0.elapsed();
    let t1 = Instant::now();
    let ap = all_paths(spec, &timing);
    let paths_time = t1.elapsed();
    let edges = spec.edges().len();
    eprintln!(
        "{} tasks, {edges} edges: schedulable {}, sched::analyze {sched_time:.2?}, \
         all_paths {paths_time:.2?}, {} (source, sink) pairs, {} cycles",
        spec.tasks.len(),
        verdict.schedulable,
        ap.pairs.len(),
        ap.cycles.len()
    );
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("all_paths");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in [1_000, 10_000] {
        let spec = system(n);
        describe(&spec);
        // Response times once, outside the timed loop.
        let (timing, _) = sched::analyze(&spec);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(all_paths(black_box(&spec), black_box(&timing))))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("analyze+all_paths");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    let spec = system(10_000);
    group.bench_function(BenchmarkId::from_parameter(10_000), |b| {
        b.iter(|| {
            let spec = black_box(&spec);
            let report = analyze(spec);
            black_box(all_paths(spec, &report.timing))
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
