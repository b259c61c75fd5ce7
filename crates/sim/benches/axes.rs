//! Simulator throughput along every axis of a system's size:
//! tasks, CPUs, chains and fan-in (reads per task), each varied alone
//! around a base of 1,000 tasks on 40 CPUs with 50 chains, plus WATERS
//! systems (`rtpipe generate waters`) of 1,000 tasks on 40 CPUs and of
//! 10,000 tasks on 40 and on 400 CPUs.
//!
//! `cargo bench -p rtpipe-sim --bench axes` (about three minutes). Every
//! run is about 400,000 events long (random phasing, uniform demands);
//! criterion reports events per second as elements/s. The cost per event
//! must grow at most logarithmically along each axis.
//!
//! Each system is described on stderr (events per run, reads, chains)
//! before it is measured.

mod common;
use common::{bench_events, random_run};
use criterion::{criterion_group, criterion_main, Criterion};
use rtpipe_model::gen::{random_system, waters_system, GenConfig, WatersConfig};
use rtpipe_model::{Scheduler, Spec};
use rtpipe_sim::SimConfig;
use std::time::Duration;

const SEED: u64 = 2018;

/// The base of the axes: 1,000 tasks on 40 CPUs, 50 chains, fan-in ≤ 2.
fn base() -> GenConfig {
    GenConfig {
        tasks: 1_000,
        cpus: 40,
        utilization: 0.6,
        scheduler: Scheduler::Rm,
        mixed_servers: true,
        chains: 50,
        max_fan_in: 2,
        ..GenConfig::default()
    }
}

fn waters(tasks: usize, cpus: u32, chains: usize) -> Spec {
    waters_system(
        SEED,
        &WatersConfig {
            tasks: Some(tasks),
            cpus,
            utilization: 0.5,
            chains,
            ..WatersConfig::default()
        },
    )
}

/// One run outside the timed loop (see `common::describe`).
fn describe(label: &str, spec: &Spec, cfg: &SimConfig) -> u64 {
    common::describe(label, spec, cfg, |r| {
        let reads: usize = spec.tasks.iter().map(|t| t.reads.len()).sum();
        format!(
            "{reads} reads, {} chains, {} events",
            spec.chains.len(),
            r.events
        )
    })
}

/// The systems measured: (axis, label, spec).
fn systems() -> Vec<(&'static str, String, Spec)> {
    let mut v = Vec::new();
    for (tasks, cpus, chains) in [(1_000, 40, 50), (10_000, 40, 50), (10_000, 400, 500)] {
        let label = format!("{tasks}t-{cpus}cpu-{chains}ch");
        v.push(("waters", label, waters(tasks, cpus, chains)));
    }
    let gen = |cfg: GenConfig| random_system(SEED, &cfg);
    for tasks in [100, 1_000, 10_000] {
        v.push((
            "tasks",
            format!("{tasks}t"),
            gen(GenConfig { tasks, ..base() }),
        ));
    }
    for cpus in [1, 4, 40, 400] {
        v.push((
            "cpus",
            format!("{cpus}cpu"),
            gen(GenConfig { cpus, ..base() }),
        ));
    }
    for chains in [0, 5, 50, 500] {
        v.push((
            "chains",
            format!("{chains}ch"),
            gen(GenConfig { chains, ..base() }),
        ));
    }
    for max_fan_in in [1, 4, 16, 64] {
        let cfg = GenConfig {
            max_fan_in,
            ..base()
        };
        v.push(("fan-in", format!("fan-in-{max_fan_in}"), gen(cfg)));
    }
    v
}

fn axes(c: &mut Criterion) {
    let mut group = c.benchmark_group("axes");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (axis, label, spec) in systems() {
        let cfg = random_run(&spec, SEED);
        let id = format!("{axis}/{label}");
        let n = describe(&id, &spec, &cfg);
        bench_events(&mut group, &id, &spec, &cfg, n);
    }
    group.finish();
}

criterion_group!(benches, axes);
criterion_main!(benches);
