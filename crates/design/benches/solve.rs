//! Solve times of `design` on generated design problems.
//!
//! `cargo bench -p rtpipe-design --bench solve` (microlp; add
//! `--features highs` for HiGHS as well). Up to about 15 minutes per backend.
//!
//! The problems come from `rtpipe_model::gen::design_problem`, deterministic
//! per seed: WATERS periods, 6, 20, 50 and 100 tasks (1, 2, 4 and 8 CPUs,
//! utilisation 0.5 each, RM with exact RTA), every period a range
//! `[min?, k·T]` around its generating value, chains of 2–15 tasks over at
//! most 3 periods with limits at the generating design's sound bounds times
//! a factor in [0.8, 1.5]. Each problem is solved in paper mode (time limit
//! 30 s) and sound mode (10 s) with every backend built in.
//!
//! Each solve is described once on stderr (tasks, chains, mode, solver,
//! status, objective, gap, seconds) before it is measured. A solve that
//! runs to its time limit (an unknown status, or an infeasibility whose
//! explanation ran out of time) measures the limit, not the solver, so it is
//! not timed again unless `RTPIPE_BENCH_ALL=1`. `RTPIPE_BENCH_SOLVERS=highs`
//! (comma-separated names) restricts the backends.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use rtpipe_analysis::Anchor;
use rtpipe_analysis::{analyze, bounds_per_chain};
use rtpipe_design::lp::SolverKind;
use rtpipe_design::{design, utilization, Mode, Options, Outcome};
use rtpipe_model::gen::{
    benchmark_config, design_origin, design_problem, ChainBounds, DesignGenConfig,
};
use rtpipe_model::{PeriodSpec, Spec};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEED: u64 = 2018;

fn sound_bounds(spec: &Spec) -> Vec<ChainBounds> {
    bounds_per_chain(spec, |b| b.sound(Anchor::Read))
}

fn config(tasks: usize) -> DesignGenConfig {
    benchmark_config(tasks)
}

/// The problem, described on stderr with its generating design (which the
/// limits were drawn around): utilisation and how many limits it meets.
fn problem(tasks: usize) -> Spec {
    let cfg = config(tasks);
    let spec = design_problem(SEED, &cfg, &sound_bounds);
    let mut origin = spec.clone();
    for (t, o) in origin.tasks.iter_mut().zip(design_origin(SEED, &cfg).tasks) {
        t.period = o.period;
    }
    let report = analyze(&origin);
    let limits = report.chains.iter().filter(|c| c.limit.is_some()).count();
    let sound = report.chains.iter().filter(|c| c.ok).count();
    let paper = report
        .chains
        .iter()
        .filter(|c| c.limit.is_some_and(|l| c.bound.paper(Anchor::Read) <= l))
        .count();
    let ranges = spec
        .tasks
        .iter()
        .filter(|t| matches!(t.period, PeriodSpec::Range { .. }))
        .count();
    eprintln!(
        "problem {}: {} tasks ({ranges} ranges), {} CPUs, {} chains ({} tasks on chains); \
         generating design U = {:.4}, schedulable {}, meets {sound} of {limits} limits (sound), \
         {paper} (paper)",
        spec.name,
        spec.tasks.len(),
        cfg.system.cpus,
        spec.chains.len(),
        spec.chains.iter().map(|c| c.path.len()).sum::<usize>(),
        utilization(&origin),
        report.schedulability.schedulable,
    );
    spec
}

/// Every backend built in, or those named in `RTPIPE_BENCH_SOLVERS`
/// (comma-separated).
fn backends() -> Vec<SolverKind> {
    #[allow(unused_mut)]
    let mut v = vec![SolverKind::Microlp];
    #[cfg(feature = "highs")]
    v.push(SolverKind::Highs);
    if let Ok(names) = std::env::var("RTPIPE_BENCH_SOLVERS") {
        v.retain(|s| names.split(',').any(|n| n.trim() == s.name()));
    }
    v
}

fn options(mode: Mode, solver: SolverKind) -> Options {
    Options {
        mode,
        solver,
        time_limit: Some(match mode {
            Mode::Paper => 30.0,
            Mode::Sound => 10.0,
        }),
        ..Options::default()
    }
}

fn solve(spec: &Spec, opts: &Options) -> Outcome {
    match design(spec, opts) {
        Ok(o) => o,
        Err(e) => panic!("{}: {e}", spec.name),
    }
}

/// One solve outside the timed loop; true when it ended before its limit.
fn describe(spec: &Spec, opts: &Options) -> (bool, f64) {
    let t0 = Instant::now();
    let o = solve(spec, opts);
    let secs = t0.elapsed().as_secs_f64();
    let fmt =
        |x: Option<f64>, scale: f64| x.map_or("-".to_string(), |v| format!("{:.4}", v * scale));
    eprintln!(
        "design {}: {} tasks, {} chains, mode {}, solver {}: {}, objective {}, \
         lower bound {}, gap {} %, {} master solves, {secs:.2} s",
        spec.name,
        spec.tasks.len(),
        spec.chains.len(),
        opts.mode.name(),
        opts.solver.name(),
        o.status.name(),
        fmt(o.objective, 1.0),
        fmt(o.lower_bound, 1.0),
        match o.gap {
            Some(g) if g > 0.0 && g < 1e-6 => format!("{:.1e}", g * 100.0),
            g => fmt(g, 100.0),
        },
        o.iterations,
    );
    let limit = opts.time_limit.unwrap_or(f64::INFINITY);
    (secs < 0.9 * limit, secs)
}

fn bench(c: &mut Criterion) {
    let all = std::env::var_os("RTPIPE_BENCH_ALL").is_some();
    let problems: Vec<Spec> = [6, 20, 50, 100].into_iter().map(problem).collect();
    for solver in backends() {
        for mode in [Mode::Paper, Mode::Sound] {
            let opts = options(mode, solver);
            let mut group = c.benchmark_group(format!("design/{}/{}", solver.name(), mode.name()));
            group
                .sample_size(10)
                .sampling_mode(SamplingMode::Flat)
                .warm_up_time(Duration::from_millis(500));
            for spec in &problems {
                let (finished, secs) = describe(spec, &opts);
                if !finished && !all {
                    eprintln!("  (ran to its time limit: not timed again)");
                    continue;
                }
                // Ten solves (and some room) when they are slow, 2 s when fast.
                group.measurement_time(Duration::from_secs_f64((11.0 * secs).max(2.0)));
                group.bench_with_input(
                    BenchmarkId::from_parameter(spec.tasks.len()),
                    spec,
                    |b, spec| b.iter(|| black_box(solve(black_box(spec), &opts))),
                );
            }
            group.finish();
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
