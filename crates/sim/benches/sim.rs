//! Simulator throughput and the Table III run.
//!
//! `cargo bench -p rtpipe-sim` (a few minutes: 10 samples per benchmark).
//!
//! - `events`: simulated events per second on generated systems
//!   (`rtpipe_model::gen::random_system`, deterministic per seed) of 10 and 50
//!   tasks on 1 and 2 CPUs under RM and EDF, random phasing, uniform demands,
//!   2 s of simulated time. Criterion reports the rate as elements/s.
//! - `table3`: examples/paper-table3.toml simulated until p5 (τ5) and p7 (τ7)
//!   have each produced 100 000 outputs: 100 000 × 150 ms (p5's period) +
//!   150 ms, worst-case demands, synchronous release.
//! - `search`: a short adversarial search (1 restart, 20 steps) on a
//!   generated system, in simulations per second.
//! - `scaling`: events per second against the task count (10, 100, 1,000,
//!   10,000 tasks on one CPU, and on two CPUs as `…t-2cpu-…`, RM and EDF),
//!   each run about 400,000 events long: the cost per event must not grow
//!   with the number of tasks (only logarithmically). Beside them,
//!   `1000t-events`: a generated event-triggered system
//!   (`rtpipe_model::gen::event_triggered_system`) of 1,000 tasks in 125
//!   chains of 8, most of them data-triggered, on 1–2 CPUs and up to 40
//!   work-queue threads, as long a run: threads, triggers and merging must
//!   cost per event what periodic releases do.
//! - `heap`: the reference for `scaling`'s growth: a plain
//!   `std::collections::BinaryHeap` of the same system's n tasks, each
//!   keyed by its next release, popped and pushed back a period later as
//!   many times as the RM run on one CPU has events (`heap/1000t` beside
//!   `scaling/1000t-rm`). Criterion's elements/s are then events/s and
//!   pop-push pairs/s from one run, so their growth from 1,000 to 10,000
//!   tasks can be set side by side: log10(t(10k)/t(1k)) per event.
//!
//! Each system is described on stderr (events per run, late jobs) before it
//! is measured.

mod common;
use common::{bench_events, random_run, run, MS};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rtpipe_analysis::Metric;
use rtpipe_model::gen::{event_triggered_system, random_system, EventGenConfig, GenConfig};
use rtpipe_model::{Nanos, Scheduler, Spec};
use rtpipe_sim::search::{search, SearchConfig};
use rtpipe_sim::{ExecModel, Phasing, SimConfig};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

const SEED: u64 = 2018;

fn system(tasks: usize, cpus: u32, scheduler: Scheduler) -> Spec {
    random_system(
        SEED,
        &GenConfig {
            tasks,
            cpus,
            utilization: 0.6,
            scheduler,
            mixed_servers: true,
            inheritance: 0.0,
            chains: 3,
            ..GenConfig::default()
        },
    )
}

/// One run outside the timed loop (see `common::describe`).
fn describe(label: &str, spec: &Spec, cfg: &SimConfig) -> u64 {
    common::describe(label, spec, cfg, |r| {
        let late: u64 = r.tasks.iter().map(|t| t.late).sum();
        let completed: u64 = r.tasks.iter().map(|t| t.completed).sum();
        format!("{} events, {completed} jobs ({late} late)", r.events)
    })
}

fn events(c: &mut Criterion) {
    let mut group = c.benchmark_group("events");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for tasks in [10, 50] {
        for cpus in [1, 2] {
            for scheduler in [Scheduler::Rm, Scheduler::Edf] {
                let spec = system(tasks, cpus, scheduler);
                let cfg = SimConfig {
                    horizon: 2_000 * MS,
                    seed: SEED,
                    phasing: Phasing::Random,
                    exec: ExecModel::Uniform,
                    log_jobs: false,
                    jitter: rtpipe_sim::Jitter::Uniform,
                };
                let sched = match scheduler {
                    Scheduler::Rm => "rm",
                    Scheduler::Edf => "edf",
                };
                let label = format!("{tasks}t-{cpus}cpu-{sched}");
                let n = describe(&label, &spec, &cfg);
                bench_events(&mut group, &label, &spec, &cfg, n);
            }
        }
    }
    group.finish();
}

fn table3(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-table3.toml");
    let spec = match rtpipe_model::Spec::load(&path) {
        Ok(s) => s,
        Err(e) => panic!("{}: {e:?}", path.display()),
    };
    let index = |name: &str| {
        spec.tasks
            .iter()
            .position(|t| t.name == name)
            .unwrap_or_else(|| panic!("no task {name}"))
    };
    let (p5, p7) = (index("p5"), index("p7"));
    let t5 = spec.tasks[p5].fixed_period().unwrap_or(150 * MS);
    let cfg = SimConfig::new(100_000 * t5 + t5);
    let n = describe("table3", &spec, &cfg);
    let r = run(&spec, &cfg);
    let (o5, o7) = (r.tasks[p5].completed, r.tasks[p7].completed);
    assert!(o5 >= 100_000 && o7 >= 100_000, "p5 {o5}, p7 {o7} outputs");
    for (k, ch) in r.chains.iter().enumerate() {
        eprintln!(
            "table3 chain {k}: {} finalised samples, reaction max {:?} ns, freshness max {:?} ns",
            ch.finalised, ch.reaction.max, ch.freshness.max
        );
    }
    eprintln!("table3: p5 {o5} outputs, p7 {o7} outputs");
    let mut group = c.benchmark_group("table3");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10))
        .throughput(Throughput::Elements(n));
    group.bench_function("100k-outputs", |b| {
        b.iter(|| black_box(run(black_box(&spec), black_box(&cfg))))
    });
    group.finish();
}

fn search_bench(c: &mut Criterion) {
    let spec = system(10, 1, Scheduler::Rm);
    let cfg = SearchConfig {
        restarts: 1,
        steps: 20,
        seed: SEED,
        ..SearchConfig::new(0, Metric::Reaction, 2_000 * MS)
    };
    let r = match search(&spec, &cfg) {
        Ok(r) => r,
        Err(e) => panic!("{e}"),
    };
    eprintln!("search: {r}");
    let mut group = c.benchmark_group("search");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements(r.simulations));
    group.bench_function("10t-1cpu-rm-20-steps", |b| {
        b.iter(|| black_box(search(black_box(&spec), black_box(&cfg))))
    });
    group.finish();
}

fn scaling(c: &mut Criterion) {
    let mut group = c.benchmark_group("scaling");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for (tasks, cpus) in [10, 100, 1_000, 10_000]
        .into_iter()
        .flat_map(|n| [(n, 1), (n, 2)])
    {
        for scheduler in [Scheduler::Rm, Scheduler::Edf] {
            let spec = system(tasks, cpus, scheduler);
            let cfg = random_run(&spec, SEED);
            let sched = match scheduler {
                Scheduler::Rm => "rm",
                Scheduler::Edf => "edf",
            };
            let label = match cpus {
                1 => format!("{tasks}t-{sched}"),
                _ => format!("{tasks}t-{cpus}cpu-{sched}"),
            };
            let n = describe(&label, &spec, &cfg);
            bench_events(&mut group, &label, &spec, &cfg, n);
        }
    }
    let spec = event_system(125);
    let cfg = random_run(&spec, SEED);
    let label = format!("{}t-events", spec.tasks.len());
    let n = describe(&label, &spec, &cfg);
    bench_events(&mut group, &label, &spec, &cfg, n);
    group.finish();
}

/// `ops` pops of the earliest release from a heap of `periods.len()`
/// tasks, each pushed back one period later (a release heap's hold
/// model: the heap stays n long); the last instant popped.
fn hold(periods: &[Nanos], ops: u64) -> Nanos {
    let mut heap: BinaryHeap<Reverse<(Nanos, usize)>> = periods
        .iter()
        .enumerate()
        .map(|(i, &p)| Reverse(((i as Nanos * 7_919) % p, i)))
        .collect();
    let mut last = 0;
    for _ in 0..ops {
        let Some(Reverse((t, i))) = heap.pop() else {
            break;
        };
        last = t;
        heap.push(Reverse((t + periods[i], i)));
    }
    last
}

fn heap(c: &mut Criterion) {
    let mut group = c.benchmark_group("heap");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for tasks in [10, 100, 1_000, 10_000] {
        let spec = system(tasks, 1, Scheduler::Rm);
        let periods: Vec<Nanos> = (0..spec.tasks.len())
            .filter_map(|i| spec.activation_period(i))
            .collect();
        let cfg = random_run(&spec, SEED);
        // The simulator's event count on the same system and span.
        let ops = run(&spec, &cfg).events;
        group.throughput(Throughput::Elements(ops));
        group.bench_function(format!("{tasks}t"), |b| {
            b.iter(|| black_box(hold(black_box(&periods), ops)))
        });
    }
    group.finish();
}

/// An event-triggered system of `chains` chains of 8 tasks and no timer
/// items (125 chains: 1,000 tasks).
fn event_system(chains: usize) -> Spec {
    event_triggered_system(
        SEED,
        &EventGenConfig {
            min_chains: chains,
            max_chains: chains,
            min_links: 8,
            max_links: 8,
            max_threads: 40,
            max_timers: 0,
            ..EventGenConfig::default()
        },
    )
}

criterion_group!(benches, events, table3, search_bench, scaling, heap);
criterion_main!(benches);
