//! The simulator as the oracle of the known-offset bounds
//! (`rtpipe_analysis::offsets`): on thousands of random systems with known
//! release offsets (synchronous, random, on a 1 ms grid, some later than a
//! period, some tasks left unknown), no reaction or freshness, from the read
//! or from the event, exceeds the bound the analysis gives for those
//! offsets, whatever the execution times in [exec_min, exec]: fixed demand
//! models and an adversarial search that keeps the known offsets and varies
//! the demands (and the unknown offsets).
//!
//! It also measures how tight the job-level bounds are (worst observed /
//! bound) and how they compare with the arbitrary-phasing bounds, the
//! figures of docs/analysis.md ("Known release offsets").
//!
//! `RTPIPE_OFFSETS_SYSTEMS` (default 4,000 in release builds, 300 in debug
//! builds), `RTPIPE_OFFSETS_FIRST` (default 0) and `RTPIPE_OFFSETS_SEARCH`
//! (default 12 steps) set the run; the `#[ignore]`d test runs 25,000 more
//! systems with 40 search steps each:
//! `cargo test -p rtpipe-sim --release --test offsets_oracle -- --ignored --nocapture`.

use rtpipe_analysis::offsets::{Basis, Fallback};
use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_joblog::SimResult;
use rtpipe_model::gen::{random_system, GenConfig, Rng};
use rtpipe_model::{Nanos, Scheduler, Spec};
use rtpipe_sim::observe::{observe, ChainStatsExt};
use rtpipe_sim::search::{search_with, Candidate, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};
use rtpipe_testkit::env_u64;

const MS: Nanos = 1_000_000;

/// Every quantity, in the order of the tallies.
const QUANTITIES: [(Metric, Anchor); 4] = [
    (Metric::Reaction, Anchor::Read),
    (Metric::Freshness, Anchor::Read),
    (Metric::Reaction, Anchor::Event),
    (Metric::Freshness, Anchor::Event),
];

/// How a system's offsets are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Offsets {
    /// `release = "synchronous"`: every task at 0.
    Sync,
    /// Uniform in [0, T) per task.
    Random,
    /// Multiples of 1 ms in [0, T): coinciding releases.
    Grid,
    /// Uniform in [0, 3 T): some tasks start late.
    Late,
    /// Random, but a third of the tasks unknown (the fallback).
    Partial,
}

/// The generator settings of a seed (as the sound oracle's) and its offsets.
fn system(seed: u64) -> (Spec, Offsets) {
    let mut r = Rng::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x00FF_5E75);
    let gen = GenConfig {
        tasks: r.range(2, 10) as usize,
        cpus: r.range(1, 2) as u32,
        utilization: 0.3 + 0.6 * r.unit(),
        scheduler: if r.chance(0.6) {
            Scheduler::Rm
        } else {
            Scheduler::Edf
        },
        mixed_servers: r.chance(0.5),
        feedback: if r.chance(0.2) { 0.3 } else { 0.0 },
        chains: 3,
        inheritance: 0.5,
        ..GenConfig::default()
    };
    let mut spec = random_system(seed, &gen);
    let kind = match r.range(0, 9) {
        0..=2 => Offsets::Sync,
        3..=5 => Offsets::Random,
        6 => Offsets::Grid,
        7 => Offsets::Late,
        _ => Offsets::Partial,
    };
    // Fixed execution times (best = worst) in a quarter of the systems.
    let fixed_exec = r.chance(0.25);
    for (i, t) in spec.tasks.iter_mut().enumerate() {
        let p = t.fixed_period().unwrap_or(MS).max(1) as u64;
        t.offset = Some(match kind {
            Offsets::Sync => 0,
            Offsets::Random | Offsets::Partial => r.range(0, p - 1) as Nanos,
            Offsets::Grid => r.range(0, (p - 1) / MS as u64) as Nanos * MS,
            Offsets::Late => r.range(0, 3 * p - 1) as Nanos,
        });
        if kind == Offsets::Partial && i % 3 == 1 {
            t.offset = None;
        }
        if fixed_exec {
            t.exec_min = t.exec;
        }
    }
    (spec, kind)
}

/// The demand models of the fixed runs, and the phasing of the unknown offsets.
fn runs() -> [(Phasing, ExecModel); 5] {
    [
        (Phasing::Sync, ExecModel::Worst),
        (Phasing::Sync, ExecModel::Best),
        (Phasing::Random, ExecModel::Uniform),
        (Phasing::Grid(MS), ExecModel::Extremes),
        (Phasing::Random, ExecModel::Extremes),
    ]
}

/// The start, plus about twenty of the longest periods, at most 5 s more.
fn horizon(spec: &Spec) -> Nanos {
    let t_max = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(MS);
    let start = spec
        .tasks
        .iter()
        .filter_map(|t| t.offset)
        .max()
        .unwrap_or(0);
    start + (20 * t_max).min(5_000 * MS)
}

#[derive(Default)]
struct Stats {
    systems: u64,
    runs: u64,
    /// (chain, quantity) pairs with a known-offset bound, per run.
    checks: u64,
    observations: u64,
    /// Per basis of the reported bound: known offsets, any phasing lower,
    /// no sample reaches, fallback for unknown offsets, too many jobs, an
    /// unbounded response time.
    basis: [u64; 6],
    /// Per scheduler (RM, EDF) and quantity: worst observed / job-level
    /// bound of every (system, chain) where the bound is the job-level one.
    tightness: [[Vec<f64>; 4]; 2],
    /// Per scheduler and quantity: job-level / arbitrary-phasing bound
    /// (every known offset below its period).
    versus_any: [[Vec<f64>; 4]; 2],
    /// Of those, how often the job-level figure was the higher one.
    above_any: [u64; 4],
    /// Chains (per run) with a task starting later than a period, and
    /// observations of theirs above the arbitrary-phasing bound (which does
    /// not cover them; every other chain must stay within it too).
    late_checks: u64,
    late_over_any: u64,
    searched: u64,
    search_sims: u64,
    failures: Vec<String>,
}

impl Stats {
    fn merge(&mut self, o: Stats) {
        self.systems += o.systems;
        self.runs += o.runs;
        self.checks += o.checks;
        self.observations += o.observations;
        for k in 0..6 {
            self.basis[k] += o.basis[k];
        }
        for k in 0..4 {
            for s in 0..2 {
                self.tightness[s][k].extend(&o.tightness[s][k]);
                self.versus_any[s][k].extend(&o.versus_any[s][k]);
            }
            self.above_any[k] += o.above_any[k];
        }
        self.late_checks += o.late_checks;
        self.late_over_any += o.late_over_any;
        self.searched += o.searched;
        self.search_sims += o.search_sims;
        self.failures.extend(o.failures);
    }
}

fn basis_index(b: &Basis) -> usize {
    match b {
        Basis::KnownOffsets => 0,
        Basis::AnyPhasingTighter => 1,
        Basis::NoSampleReaches => 2,
        Basis::AnyPhasing(Fallback::UnknownOffsets(_)) => 3,
        Basis::AnyPhasing(Fallback::TooManyJobs(_)) => 4,
        Basis::AnyPhasing(Fallback::Unbounded) => 5,
    }
}

/// One system: the fixed runs, then a search on the quantity that came
/// closest to its bound. Every run of both is checked.
fn check_system(seed: u64, steps: u32, st: &mut Stats) {
    let (spec, _) = system(seed);
    let report = analyze(&spec);
    st.systems += 1;
    let h = horizon(&spec);
    // Worst observed per (chain, quantity), over every run.
    let mut worst = vec![[None::<Nanos>; 4]; spec.chains.len()];
    let mut best: Option<(f64, usize, usize, SimConfig, Vec<Nanos>)> = None;
    for (run, (phasing, exec)) in runs().into_iter().enumerate() {
        let cfg = SimConfig {
            horizon: h,
            seed: seed.wrapping_mul(31).wrapping_add(run as u64),
            phasing,
            exec,
            log_jobs: false,
            jitter: rtpipe_sim::Jitter::Uniform,
        };
        let res = match simulate(&spec, &cfg) {
            Ok(r) => r,
            Err(e) => panic!("seed {seed}: {e}"),
        };
        if let Some((score, chain, q)) = check_run(seed, &spec, &report, &cfg, &res, &mut worst, st)
        {
            if best.as_ref().is_none_or(|b| score > b.0) {
                best = Some((score, chain, q, cfg, res.offsets.clone()));
            }
        }
    }
    if let Some((_, chain, q, cfg, offsets)) = best {
        search(
            seed,
            &spec,
            &report,
            steps,
            (chain, q, cfg, offsets),
            &mut worst,
            st,
        );
    }
    tally(&spec, &report, &worst, st);
}

/// Checks one run against every known-offset bound; returns the largest
/// observed / bound ratio (over chains of two tasks or more) and where.
fn check_run(
    seed: u64,
    spec: &Spec,
    report: &Report,
    cfg: &SimConfig,
    res: &SimResult,
    worst: &mut [[Option<Nanos>; 4]],
    st: &mut Stats,
) -> Option<(f64, usize, usize)> {
    st.runs += 1;
    let mut best: Option<(f64, usize, usize)> = None;
    for o in observe(report, res) {
        if late_start(spec, report, o.chain) {
            st.late_checks += 1;
            st.late_over_any += o.over_sound() as u64;
        } else if o.over_sound() > 0 {
            st.failures.push(format!(
                "seed {seed}: chain {} {}: {} observation(s) above the arbitrary-phasing bound \
                 with every offset below its period; sim {:?} {:?} seed {} offsets {:?}",
                o.chain,
                o.metric.name(),
                o.over_sound(),
                cfg.phasing,
                cfg.exec,
                cfg.seed,
                res.offsets
            ));
        }
        for (q, &(m, a)) in QUANTITIES.iter().enumerate() {
            if m != o.metric {
                continue;
            }
            let Some(k) = o.known_from(a) else { continue };
            let values = res.chains[o.chain].observed(m, a).hist.sorted();
            st.checks += 1;
            st.observations += values.len() as u64;
            let Some(&seen) = values.iter().max() else {
                continue;
            };
            let w = &mut worst[o.chain][q];
            *w = Some(w.map_or(seen, |x| x.max(seen)));
            if k.over > 0 {
                st.failures.push(format!(
                    "seed {seed}: chain {} {} from the {}: observed {seen} ns > {:?} ({}); \
                     sim {:?} {:?} seed {} offsets {:?}",
                    o.chain,
                    m.name(),
                    a.name(),
                    k.bound,
                    k.bound.label(spec),
                    cfg.phasing,
                    cfg.exec,
                    cfg.seed,
                    res.offsets
                ));
            }
            let ratio = k.bound.value.map_or(0.0, |b| seen as f64 / b.max(1) as f64);
            if spec.chains[o.chain].path.len() > 1 && best.is_none_or(|b| ratio > b.0) {
                best = Some((ratio, o.chain, q));
            }
        }
    }
    best
}

/// The adversarial search with the known offsets fixed, from the run that
/// came closest, maximising that quantity; every run is checked.
fn search(
    seed: u64,
    spec: &Spec,
    report: &Report,
    steps: u32,
    (chain, q, cfg, offsets): (usize, usize, SimConfig, Vec<Nanos>),
    worst: &mut [[Option<Nanos>; 4]],
    st: &mut Stats,
) {
    let (metric, anchor) = QUANTITIES[q];
    let scfg = SearchConfig {
        restarts: 1,
        steps,
        seed: seed ^ 0x0FF5,
        start: vec![Candidate {
            offsets,
            exec: cfg.exec,
            seed: cfg.seed,
            jitter: cfg.jitter,
        }],
        anchor,
        ..SearchConfig::new(chain, metric, cfg.horizon)
    };
    let mut inner = Stats::default();
    let found = search_with(spec, &scfg, |c, res| {
        let _ = check_run(seed, spec, report, c, res, worst, &mut inner);
    });
    match found {
        Ok(r) => {
            st.searched += 1;
            st.search_sims += r.simulations;
            if r.exceeds_sound() {
                st.failures.push(format!("seed {seed}: search: {r}"));
            }
        }
        Err(e) => panic!("seed {seed}: search refused the system: {e}"),
    }
    st.runs += inner.runs;
    st.checks += inner.checks;
    st.observations += inner.observations;
    st.failures.extend(inner.failures);
}

/// Tightness and the comparison with the arbitrary-phasing bound, once per
/// (system, chain, quantity), over chains of two tasks or more (a single
/// task's bound from the read is its response time either way).
fn tally(spec: &Spec, report: &Report, worst: &[[Option<Nanos>; 4]], st: &mut Stats) {
    let s = usize::from(spec.scheduler == Scheduler::Edf);
    for (k, o) in report.offsets.iter().enumerate() {
        let Some(o) = o else { continue };
        for (q, &(m, a)) in QUANTITIES.iter().enumerate() {
            let b = o.get(m, a);
            st.basis[basis_index(&b.basis)] += 1;
            if spec.chains[k].path.len() < 2 {
                continue;
            }
            if let (Basis::KnownOffsets, Some(v), Some(seen)) = (&b.basis, b.value, worst[k][q]) {
                st.tightness[s][q].push(seen as f64 / v.max(1) as f64);
            }
            let late = late_start(spec, report, k);
            let any = report
                .chains
                .iter()
                .find(|c| c.chain == k && c.metric == m)
                .and_then(|c| c.bound.sound(a));
            let job = o.job_level.as_ref().and_then(|j| *j.values.get(m, a));
            if let (false, Some(j), Some(any)) = (late, job, any) {
                st.versus_any[s][q].push(j as f64 / any.max(1) as f64);
                st.above_any[q] += u64::from(j > any);
            }
        }
    }
}

/// A task of the chain has a known offset of a period or more.
fn late_start(spec: &Spec, report: &Report, chain: usize) -> bool {
    spec.chains[chain].path.iter().any(|&i| {
        spec.tasks[i]
            .offset
            .is_some_and(|x| x >= report.timing[i].period)
    })
}

/// The p-quantile (nearest rank) of `v`, sorted in place.
fn quantile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = ((p * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

fn run_oracle(n: u64, first: u64, steps: u32) {
    let workers = std::thread::available_parallelism()
        .map(|p| p.get())
        .unwrap_or(1)
        .min(n.max(1) as usize) as u64;
    let mut total = Stats::default();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                s.spawn(move || {
                    let mut st = Stats::default();
                    let mut seed = first + w;
                    while seed < first + n {
                        check_system(seed, steps, &mut st);
                        seed += workers;
                    }
                    st
                })
            })
            .collect();
        for h in handles {
            match h.join() {
                Ok(st) => total.merge(st),
                Err(e) => std::panic::resume_unwind(e),
            }
        }
    });
    report(&mut total, first, n);
    assert!(
        n == 0 || (total.checks > 0 && total.observations > 0),
        "nothing was checked"
    );
    if !total.failures.is_empty() {
        let shown: Vec<&str> = total.failures.iter().take(5).map(String::as_str).collect();
        panic!(
            "{} violations of known-offset bounds; first ones:\n{}",
            total.failures.len(),
            shown.join("\n")
        );
    }
}

fn report(t: &mut Stats, first: u64, n: u64) {
    println!(
        "offsets oracle (seeds {first}..{}): {} systems, {} runs ({} of them in {} searches), \
         {} chain/quantity checks, {} observations, {} violations",
        first + n,
        t.systems,
        t.runs,
        t.search_sims,
        t.searched,
        t.checks,
        t.observations,
        t.failures.len()
    );
    println!(
        "  late starts: {} chain checks, {} observations above the arbitrary-phasing bound",
        t.late_checks, t.late_over_any
    );
    println!(
        "  bases (chain quantities): known offsets {}, any phasing lower {}, no sample reaches {}; \
         fallback: unknown offsets {}, too many jobs {}, unbounded {}",
        t.basis[0], t.basis[1], t.basis[2], t.basis[3], t.basis[4], t.basis[5]
    );
    for (s, sched) in ["rm", "edf", "all"].iter().enumerate() {
        println!("  {sched} (chains of 2+ tasks):");
        for (q, (m, a)) in QUANTITIES.iter().enumerate() {
            let mut tight: Vec<f64> = match s {
                2 => [&t.tightness[0][q], &t.tightness[1][q]]
                    .into_iter()
                    .flatten()
                    .copied()
                    .collect(),
                _ => t.tightness[s][q].clone(),
            };
            let mut vs: Vec<f64> = match s {
                2 => [&t.versus_any[0][q], &t.versus_any[1][q]]
                    .into_iter()
                    .flatten()
                    .copied()
                    .collect(),
                _ => t.versus_any[s][q].clone(),
            };
            println!(
                "    {} from the {}: observed/bound median {:.3} p10 {:.3} max {:.4} ({} chains); \
                 known/any-phasing median {:.3} p10 {:.3} p90 {:.3} ({} chains){}",
                m.name(),
                a.name(),
                quantile(&mut tight, 0.5),
                quantile(&mut tight, 0.1),
                quantile(&mut tight, 1.0),
                tight.len(),
                quantile(&mut vs, 0.5),
                quantile(&mut vs, 0.1),
                quantile(&mut vs, 0.9),
                vs.len(),
                if s == 2 {
                    format!(", known above any-phasing in {}", t.above_any[q])
                } else {
                    String::new()
                },
            );
        }
    }
}

#[test]
fn known_offset_bounds_are_never_exceeded() {
    let default = if cfg!(debug_assertions) { 300 } else { 4_000 };
    let n = env_u64("RTPIPE_OFFSETS_SYSTEMS", default);
    let first = env_u64("RTPIPE_OFFSETS_FIRST", 0);
    let steps = env_u64("RTPIPE_OFFSETS_SEARCH", 12).min(u64::from(u32::MAX)) as u32;
    run_oracle(n, first, steps);
}

/// The long run of docs/analysis.md: 25,000 systems after the CI ones, 40
/// search steps each.
#[test]
#[ignore]
fn known_offset_bounds_long_run() {
    run_oracle(25_000, 1_000_000, 40);
}
