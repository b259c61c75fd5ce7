//! `analyze` as the task count grows: WATERS 2015 task sets
//! (`rtpipe_model::gen::waters_system`, deterministic per seed) of 1k, 10k
//! and 100k tasks at 25 tasks per CPU, and 10k at 100 per CPU, five chains
//! each, under rate-monotonic scheduling; and the same sets at 25 per CPU
//! under EDF: plain, with critical sections under the stack resource
//! policy, and with overheads (`gen::add_contention`, its sections drawn
//! under RM and then kept under EDF with SRP). The analysis is to stay
//! close to linear in the task count (docs/analysis.md, "Scale").
//!
//! `cargo bench -p rtpipe-analysis --bench scale` (10 samples per size);
//! `RTPIPE_SCALE_MAX=N` leaves out the sizes above N tasks,
//! `RTPIPE_SCALE_ONLY=NAME` keeps the groups whose name contains NAME,
//! `RTPIPE_SCALE_WRITE=DIR` writes each spec as DIR/NAME-TASKS.toml (for
//! timing `rtpipe analyze` on it).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rtpipe_analysis::analyze;
use rtpipe_model::gen::{add_contention, waters_system, Contention, Rng, WatersConfig};
use rtpipe_model::{ResourceProtocol, SchedTest, Scheduler, Spec};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEED: u64 = 2018;

/// (tasks, tasks per CPU) measured under RM.
const SIZES: [(usize, usize); 4] = [(1_000, 25), (10_000, 25), (100_000, 25), (10_000, 100)];

/// Task counts measured under EDF, at 25 per CPU.
const EDF_SIZES: [usize; 3] = [1_000, 10_000, 100_000];

/// The variants measured: group name and how the WATERS set is changed.
const VARIANTS: [(&str, Variant); 4] = [
    ("analyze", Variant::Rm),
    ("analyze-edf", Variant::Edf),
    ("analyze-edf-srp", Variant::EdfSrp),
    ("analyze-edf-overheads", Variant::EdfOverheads),
];

#[derive(Clone, Copy, PartialEq)]
enum Variant {
    Rm,
    Edf,
    EdfSrp,
    EdfOverheads,
}

fn system(tasks: usize, per_cpu: usize, variant: Variant) -> Spec {
    let mut spec = waters_system(
        SEED,
        &WatersConfig {
            tasks: Some(tasks),
            cpus: u32::try_from(tasks / per_cpu).expect("a CPU count that fits u32"),
            utilization: 0.5,
            chains: 5,
            synchronous: false,
        },
    );
    if variant == Variant::Rm {
        return spec;
    }
    let contention = Contention {
        sections: f64::from(u8::from(variant == Variant::EdfSrp)),
        overheads: f64::from(u8::from(variant == Variant::EdfOverheads)),
        max_cost: 40_000,
    };
    add_contention(&mut spec, &mut Rng::new(SEED), &contention);
    spec.scheduler = Scheduler::Edf;
    spec.schedulability = SchedTest::Edf;
    if !spec.resources.is_empty() {
        spec.resource_protocol = ResourceProtocol::Srp;
    }
    // Not parsed back: the 100k sets' 4,000 CPUs are more than a spec
    // file takes (`rtpipe generate waters --cpus` stops at 1,024); the 1k
    // and 10k files (`RTPIPE_SCALE_WRITE`) pass `rtpipe analyze`.
    spec
}

fn describe(name: &str, spec: &Spec, per_cpu: usize) {
    if let Ok(dir) = std::env::var("RTPIPE_SCALE_WRITE") {
        let path = format!("{dir}/{name}-{}.toml", spec.tasks.len());
        std::fs::write(&path, rtpipe_model::to_toml(spec))
            .unwrap_or_else(|e| panic!("cannot write {path}: {e}"));
    }
    let t0 = Instant::now();
    let report = analyze(spec);
    eprintln!(
        "{name}: {} tasks, {per_cpu} per CPU, {} chains, {} resources: schedulable {}, one analyze {:.2?}",
        spec.tasks.len(),
        spec.chains.len(),
        spec.resources.len(),
        report.schedulability.schedulable,
        t0.elapsed()
    );
}

fn bench(c: &mut Criterion) {
    let max: usize = std::env::var("RTPIPE_SCALE_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(usize::MAX);
    let only = std::env::var("RTPIPE_SCALE_ONLY").unwrap_or_default();
    for (name, variant) in VARIANTS.into_iter().filter(|(n, _)| n.contains(&only)) {
        let sizes: Vec<(usize, usize)> = if variant == Variant::Rm {
            SIZES.to_vec()
        } else {
            EDF_SIZES.iter().map(|&n| (n, 25)).collect()
        };
        let mut group = c.benchmark_group(name);
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(5));
        for (tasks, per_cpu) in sizes.into_iter().filter(|&(n, _)| n <= max) {
            let spec = system(tasks, per_cpu, variant);
            describe(name, &spec, per_cpu);
            let id = BenchmarkId::new(format!("{per_cpu}-per-cpu"), tasks);
            group.bench_function(id, |b| b.iter(|| black_box(analyze(black_box(&spec)))));
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
