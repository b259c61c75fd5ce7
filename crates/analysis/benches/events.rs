//! The whole analysis (`analyze`: the holistic iteration over threads and
//! data-triggered tasks, then every chain's bounds) of a generated
//! event-triggered system of 1,000 tasks, against the same generator's
//! system with no thread and no data-triggered task (every task periodic,
//! analysed by the fixed-priority path alone): like with like, per task
//! (criterion's throughput in tasks).
//!
//! `cargo bench -p rtpipe-analysis --bench events`. The systems come from
//! `rtpipe_model::gen::event_triggered_system`, deterministic per seed;
//! each is described on stderr before it is measured, and written as
//! `NAME-1000.toml` into the directory `RTPIPE_BENCH_SPECS` names, when
//! set (for `rtpipe analyze` of the same system, e.g. its peak memory).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rtpipe_analysis::analyze;
use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
use rtpipe_model::Spec;
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEED: u64 = 2018;

/// 250 chains of 4 tasks (1,000 tasks) on up to 8 CPUs, a few of them in
/// up to 64 work-queue threads (a thread's tasks queue behind each other:
/// with most of 1,000 tasks in a handful of threads no system is
/// schedulable). `periodic`: no threads and no data-triggered links.
fn system(periodic: bool) -> Spec {
    event_triggered_system(
        SEED,
        &EventGenConfig {
            min_chains: 250,
            max_chains: 250,
            min_links: 4,
            max_links: 4,
            max_threads: 64,
            max_cpus: 8,
            utilization: 0.5,
            data_fraction: if periodic { 0.0 } else { 0.6 },
            thread_fraction: if periodic { 0.0 } else { 0.05 },
            max_timers: 0,
        },
    )
}

fn describe(spec: &Spec) {
    let t0 = Instant::now();
    let report = analyze(spec);
    let data = (0..spec.tasks.len())
        .filter(|&i| spec.tasks[i].triggers().is_some())
        .count();
    eprintln!(
        "{} tasks ({data} data-triggered), {} threads, {} chains: schedulable {}, \
         {} of {} chain bounds sound-bounded, one analyze {:.2?}",
        spec.tasks.len(),
        spec.threads.len(),
        spec.chains.len(),
        report.schedulability.schedulable,
        report
            .chains
            .iter()
            .filter(|c| c.bound.sound(rtpipe_analysis::Anchor::Read).is_some())
            .count(),
        report.chains.len(),
        t0.elapsed()
    );
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("analyze 1000 tasks");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for (name, periodic) in [("periodic", true), ("event-triggered", false)] {
        let spec = system(periodic);
        describe(&spec);
        if let Some(dir) = std::env::var_os("RTPIPE_BENCH_SPECS") {
            let path = std::path::Path::new(&dir).join(format!("{name}-{}.toml", spec.tasks.len()));
            std::fs::write(&path, rtpipe_model::to_toml(&spec))
                .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        }
        group.throughput(Throughput::Elements(spec.tasks.len() as u64));
        let id = BenchmarkId::new(name, spec.tasks.len());
        group.bench_function(id, |b| b.iter(|| black_box(analyze(black_box(&spec)))));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
