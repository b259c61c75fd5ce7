//! The simulator as an oracle: on thousands of random systems, no simulated
//! reaction, freshness or job response time exceeds the analysis' sound bound.
//!
//! Each system is simulated with a few fixed phasings and demand models, then
//! the adversarial search of [`rtpipe_sim::search`] (local search over offsets
//! and demand models, from the fixed run that came closest to a bound) tries
//! to get closer to the bound of the tightest chain and metric. Every run of
//! the search is checked against every bound, like the fixed runs.
//!
//! `RTPIPE_ORACLE_SYSTEMS` (default 10,000 in release builds, 2,000 in debug
//! builds) sets the number of systems,
//! `RTPIPE_ORACLE_FIRST` (default 0) the first seed and
//! `RTPIPE_ORACLE_SEARCH` (default 4) the search steps per system. Run with `--nocapture`
//! to see the tightness summary; in release mode for large runs:
//! `RTPIPE_ORACLE_SYSTEMS=10000 cargo test -p rtpipe-sim --release -- --nocapture`.

mod common;

use rtpipe_analysis::Bound;
use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_joblog::{SimResult, Witness};
use rtpipe_model::gen::{random_system, GenConfig, Rng};
use rtpipe_model::policy::rate_monotonic;
use rtpipe_model::{Nanos, Scheduler, Spec};
use rtpipe_sim::observe::ChainStatsExt;
use rtpipe_sim::search::{search_with, Candidate, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};
use rtpipe_testkit::env_u64;
use std::fmt::Write;

const MS: Nanos = 1_000_000;
const MAX_HORIZON: Nanos = 5_000 * MS;

/// The generator settings of a seed: tasks 2..=12, 1 or 2 CPUs, RM or EDF,
/// utilisation 0.3..0.9 per CPU, mixed servers or not (half of the I/O
/// VCPUs serving a Main VCPU), 3 chains.
fn gen_config(seed: u64) -> GenConfig {
    let mut r = Rng::new(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0xA5A5);
    GenConfig {
        tasks: r.range(2, 12) as usize,
        cpus: r.range(1, 2) as u32,
        utilization: 0.3 + 0.6 * r.unit(),
        scheduler: if r.chance(0.5) {
            Scheduler::Rm
        } else {
            Scheduler::Edf
        },
        mixed_servers: r.chance(0.5),
        feedback: if r.chance(0.25) { 0.3 } else { 0.0 },
        chains: 3,
        // I/O VCPUs that inherit the priority of the Main VCPU they serve.
        inheritance: 0.5,
        ..GenConfig::default()
    }
}

/// Phasings and demand models simulated for every system.
fn runs() -> [(Phasing, ExecModel); 4] {
    [
        (Phasing::Sync, ExecModel::Worst),
        (Phasing::Random, ExecModel::Uniform),
        (Phasing::Grid(MS), ExecModel::Extremes),
        (Phasing::Random, ExecModel::Extremes),
    ]
}

/// About twenty of the longest periods, at most 5 s.
fn horizon(spec: &Spec) -> Nanos {
    let t_max = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(MS);
    (20 * t_max).min(MAX_HORIZON)
}

#[derive(Default, Clone, Copy)]
struct Tight {
    ratio: f64,
    seed: u64,
    chain: usize,
    run: usize,
    seen: Nanos,
    bound: Nanos,
}

#[derive(Default)]
struct Stats {
    systems: u64,
    runs: u64,
    /// (chain, metric) pairs with a sound bound, per run.
    checks: u64,
    /// Observations (samples, or events) checked against a sound bound.
    samples: u64,
    jobs_checked: u64,
    /// Per quantity ([`quantity_index`]: reaction and freshness from the
    /// read, then from the event) and chain length (1, 2, ≥ 3).
    tight: [[Tight; 3]; 4],
    /// Sum of observed/sound, for the mean.
    ratio_sum: [[f64; 3]; 4],
    ratio_n: [[u64; 3]; 4],
    /// (system, chain, quantity) triples with a sound bound, and those where
    /// some run exceeded the paper bound.
    paper_pairs: [[u64; 3]; 4],
    paper_violations: [[u64; 3]; 4],
    /// From the read only (Davare's bounds are from-read forms).
    davare_violations: [u64; 2],
    rt_tight: f64,
    /// The current system's worst observed/sound per (chain entry, anchor).
    cur_worst: Vec<[f64; 2]>,
    /// Per quantity and chain length: each system chain's worst observed/sound
    /// over every run and the search (the tightness distribution).
    worst: [[Vec<f64>; 3]; 4],
    /// Systems searched, simulations of the search (with its job-log
    /// replays), and searches that beat their starting run.
    searched: u64,
    search_sims: u64,
    search_improved: u64,
    failures: Vec<String>,
}

impl Stats {
    fn merge(&mut self, o: Stats) {
        self.systems += o.systems;
        self.runs += o.runs;
        self.checks += o.checks;
        self.samples += o.samples;
        self.jobs_checked += o.jobs_checked;
        for m in 0..4 {
            for l in 0..3 {
                if o.tight[m][l].ratio > self.tight[m][l].ratio {
                    self.tight[m][l] = o.tight[m][l];
                }
                self.ratio_sum[m][l] += o.ratio_sum[m][l];
                self.ratio_n[m][l] += o.ratio_n[m][l];
                self.paper_violations[m][l] += o.paper_violations[m][l];
                self.paper_pairs[m][l] += o.paper_pairs[m][l];
                self.worst[m][l].extend(&o.worst[m][l]);
            }
        }
        for m in 0..2 {
            self.davare_violations[m] += o.davare_violations[m];
        }
        self.rt_tight = self.rt_tight.max(o.rt_tight);
        self.searched += o.searched;
        self.search_sims += o.search_sims;
        self.search_improved += o.search_improved;
        self.failures.extend(o.failures);
    }
}

/// Every quantity a bound is checked for.
const QUANTITIES: [(Metric, Anchor); 4] = [
    (Metric::Reaction, Anchor::Read),
    (Metric::Freshness, Anchor::Read),
    (Metric::Reaction, Anchor::Event),
    (Metric::Freshness, Anchor::Event),
];

fn quantity_index(m: Metric, a: Anchor) -> usize {
    let base = match a {
        Anchor::Read => 0,
        Anchor::Event => 2,
    };
    base + match m {
        Metric::Reaction => 0,
        Metric::Freshness => 1,
    }
}

#[test]
fn sound_bounds_are_never_exceeded() {
    // 10,000 systems in release builds (the README's test command, about 40 s
    // on two cores); 2,000 in debug builds, which are about ten times slower.
    let default = if cfg!(debug_assertions) { 2000 } else { 10_000 };
    let n = env_u64("RTPIPE_ORACLE_SYSTEMS", default);
    let first = env_u64("RTPIPE_ORACLE_FIRST", 0);
    let steps = env_u64("RTPIPE_ORACLE_SEARCH", 4);
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
    // "run" below: 0..=3 index the fixed runs of `runs()`, 100 + k is the
    // k-th run of the search (100: its starting point again).
    println!(
        "oracle: {} systems, {} runs, {} chain/quantity checks, {} observations, {} task response checks",
        total.systems, total.runs, total.checks, total.samples, total.jobs_checked
    );
    for (m, (metric, anchor)) in QUANTITIES.iter().enumerate() {
        let name = format!("{} from the {}", metric.name(), anchor.name());
        if m < 2 {
            println!(
                "  {name}: Davare bound exceeded {} times",
                total.davare_violations[m]
            );
        } else {
            println!("  {name}:");
        }
        for (l, len) in ["1", "2", ">=3"].iter().enumerate() {
            let t = &total.tight[m][l];
            let k = total.ratio_n[m][l];
            println!(
                "    chains of {len} tasks: {k} checks, observed/sound max {:.4} mean {:.4} \
                 (max at seed {}, chain {}, run {}: {} of {} ns); observed > paper bound for {} of {} system chains",
                t.ratio,
                total.ratio_sum[m][l] / k.max(1) as f64,
                t.seed,
                t.chain,
                t.run,
                t.seen,
                t.bound,
                total.paper_violations[m][l],
                total.paper_pairs[m][l],
            );
        }
    }
    for (m, (metric, anchor)) in QUANTITIES.iter().enumerate() {
        for (l, len) in ["1", "2", ">=3"].iter().enumerate() {
            let mut w = total.worst[m][l].clone();
            w.sort_by(f64::total_cmp);
            let q = |p: f64| {
                w.get(((w.len() as f64 - 1.0) * p).round() as usize)
                    .copied()
            };
            println!(
                "  tightness, {} from the {}, chains of {len} tasks: {} system chains, \
                 worst found/sound median {:.4}, 10th percentile {:.4}",
                metric.name(),
                anchor.name(),
                w.len(),
                q(0.5).unwrap_or(f64::NAN),
                q(0.1).unwrap_or(f64::NAN),
            );
        }
    }
    println!(
        "  job response: max observed/analysed = {:.4}",
        total.rt_tight
    );
    println!(
        "  search: {} systems, {} simulations, target beyond its starting run in {}",
        total.searched, total.search_sims, total.search_improved
    );
    // Guard against a vacuous pass (say, if the analysis stopped giving bounds).
    assert!(
        n == 0 || (total.checks > 0 && total.samples > 0 && total.jobs_checked > 0),
        "nothing was checked"
    );
    if !total.failures.is_empty() {
        let shown: Vec<&String> = total.failures.iter().take(5).collect();
        panic!(
            "{} violations of sound bounds; first ones:\n{}",
            total.failures.len(),
            shown
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("\n")
        );
    }
}

fn check_system(seed: u64, search_steps: u64, st: &mut Stats) {
    let gen = gen_config(seed);
    let spec = random_system(seed, &gen);
    let report = analyze(&spec);
    let h = horizon(&spec);
    st.systems += 1;
    let sys = System {
        seed,
        gen: &gen,
        spec: &spec,
        report: &report,
    };
    let mut paper_exceeded = vec![[false; 2]; report.chains.len()];
    st.cur_worst = vec![[f64::NAN; 2]; report.chains.len()];
    let mut best: Option<(f64, Target, SimConfig, Vec<Nanos>)> = None;
    for (run, (phasing, exec)) in runs().into_iter().enumerate() {
        let cfg = SimConfig {
            horizon: h,
            seed: seed.wrapping_mul(31).wrapping_add(run as u64),
            phasing,
            exec,
            log_jobs: false,
            jitter: rtpipe_sim::Jitter::Uniform,
        };
        let (score, target, offsets) = check_run(&sys, &cfg, run, true, &mut paper_exceeded, st);
        let better = match &best {
            Some(b) => score > b.0,
            None => true,
        };
        if better {
            best = Some((score, target, cfg, offsets));
        }
    }
    search(&sys, best, search_steps, &mut paper_exceeded, st);
    for (k, c) in report.chains.iter().enumerate() {
        for (ai, a) in Anchor::ALL.into_iter().enumerate() {
            if c.bound.sound(a).is_some() {
                let m = quantity_index(c.metric, a);
                let l = spec.chains[c.chain].path.len().clamp(1, 3) - 1;
                st.paper_pairs[m][l] += 1;
                st.paper_violations[m][l] += u64::from(paper_exceeded[k][ai]);
                let w = st.cur_worst[k][ai];
                if !w.is_nan() {
                    st.worst[m][l].push(w);
                }
            }
        }
    }
}

/// The chain, metric and anchor a search maximises.
type Target = Option<(usize, Metric, Anchor)>;

/// Adversarial search ([`rtpipe_sim::search`]) on the chain and metric that
/// came closest to its sound bound, starting from the run that did it (chain
/// 0's reaction from the first run when no multi-task chain has a bound).
/// Every run it makes is checked against every bound.
fn search(
    sys: &System,
    best: Option<(f64, Target, SimConfig, Vec<Nanos>)>,
    search_steps: u64,
    paper_exceeded: &mut [[bool; 2]],
    st: &mut Stats,
) {
    let (seed, spec) = (sys.seed, sys.spec);
    let Some((_, target, cfg, offsets)) = best else {
        return;
    };
    if spec.chains.is_empty() {
        return;
    }
    let (chain, metric, anchor) = target.unwrap_or((0, Metric::Reaction, Anchor::Read));
    let scfg = SearchConfig {
        restarts: 1,
        steps: search_steps.min(u64::from(u32::MAX)) as u32,
        seed: seed ^ 0x005E_A2C4,
        start: vec![Candidate {
            offsets,
            exec: cfg.exec,
            seed: cfg.seed,
            jitter: cfg.jitter,
        }],
        anchor,
        ..SearchConfig::new(chain, metric, cfg.horizon)
    };
    let mut k = 0;
    let observe = |c: &SimConfig, res: &SimResult| {
        check_result(sys, c, res, 100 + k, false, paper_exceeded, st);
        k += 1;
    };
    let found = match search_with(spec, &scfg, observe) {
        Ok(r) => r,
        Err(e) => panic!("seed {seed}: search refused the system: {e}"),
    };
    st.searched += 1;
    st.search_sims += found.simulations;
    // The first improvement is the starting run itself.
    st.search_improved += u64::from(found.trajectory.len() > 1);
}

/// One generated system and its analysis.
struct System<'a> {
    seed: u64,
    gen: &'a GenConfig,
    spec: &'a Spec,
    report: &'a Report,
}

/// Simulates one run and checks every bound. Returns the largest
/// observed/bound ratio over chains of two tasks or more, the chain and
/// metric that gave it (the search's target) and the offsets used.
fn check_run(
    sys: &System,
    cfg: &SimConfig,
    run: usize,
    count_mean: bool,
    paper_exceeded: &mut [[bool; 2]],
    st: &mut Stats,
) -> (f64, Target, Vec<Nanos>) {
    let res = match simulate(sys.spec, cfg) {
        Ok(r) => r,
        Err(e) => panic!("seed {}: simulation refused the system: {e}", sys.seed),
    };
    let (score, target) = check_result(sys, cfg, &res, run, count_mean, paper_exceeded, st);
    (score, target, res.offsets)
}

/// Checks every bound against one run; see [`check_run`].
fn check_result(
    sys: &System,
    cfg: &SimConfig,
    res: &SimResult,
    run: usize,
    count_mean: bool,
    paper_exceeded: &mut [[bool; 2]],
    st: &mut Stats,
) -> (f64, Target) {
    let (spec, report) = (sys.spec, sys.report);
    st.runs += 1;
    let mut score: f64 = 0.0;
    let mut target: Target = None;
    for (k, c) in report.chains.iter().enumerate() {
        for (ai, anchor) in Anchor::ALL.into_iter().enumerate() {
            let q = Quantity {
                chain: c.chain,
                metric: c.metric,
                anchor,
            };
            let Some(ratio) = check_quantity(sys, cfg, res, run, q, count_mean, st) else {
                continue;
            };
            let w = &mut st.cur_worst[k][ai];
            if w.is_nan() || ratio > *w {
                *w = ratio;
            }
            let seen = res.chains[c.chain].observed(c.metric, anchor).max;
            if seen.is_some_and(|v| v > c.bound.paper(anchor)) {
                paper_exceeded[k][ai] = true;
            }
            // Single-task chains are exactly tight under RM; they would steer
            // the search away from the links.
            let l = spec.chains[c.chain].path.len();
            if l > 1 && (target.is_none() || ratio > score) {
                score = ratio;
                target = Some((c.chain, c.metric, anchor));
            }
        }
    }
    for (i, ts) in res.tasks.iter().enumerate() {
        let tm = &report.timing[i];
        let (Some(r), Some(seen)) = (tm.bounded_response(), ts.max_response) else {
            continue;
        };
        st.jobs_checked += 1;
        if r > 0 {
            st.rt_tight = st.rt_tight.max(seen as f64 / r as f64);
        }
        if seen > r {
            let what = format!(
                "task t{i}: observed response {seen} ns > analysed job response time {r} ns"
            );
            st.failures
                .push(reproduction(sys, cfg, res, usize::MAX, None, &what));
        }
    }
    (score, target)
}

/// One chain's metric measured from one anchor.
#[derive(Clone, Copy)]
struct Quantity {
    chain: usize,
    metric: Metric,
    anchor: Anchor,
}

/// Checks one quantity of one run against its sound bound (and Davare's,
/// from the read); records the tightness and any violation. Returns
/// observed/sound when both exist.
fn check_quantity(
    sys: &System,
    cfg: &SimConfig,
    res: &SimResult,
    run: usize,
    q: Quantity,
    count_mean: bool,
    st: &mut Stats,
) -> Option<f64> {
    let (seed, spec, report) = (sys.seed, sys.spec, sys.report);
    let c = report
        .chains
        .iter()
        .find(|c| c.chain == q.chain && c.metric == q.metric)?;
    let cs = &res.chains[q.chain];
    let obs = cs.observed(q.metric, q.anchor);
    let seen = obs.max?;
    let m = quantity_index(q.metric, q.anchor);
    if let (Anchor::Read, Some(d)) = (q.anchor, c.bound.get(Bound::Davare, Anchor::Read)) {
        st.davare_violations[m] += u64::from(seen > d);
    }
    let bound = c.bound.sound(q.anchor)?;
    st.checks += 1;
    st.samples += obs.hist.count();
    let l = spec.chains[q.chain].path.len().clamp(1, 3) - 1;
    let ratio = seen as f64 / bound as f64;
    if count_mean {
        st.ratio_sum[m][l] += ratio;
        st.ratio_n[m][l] += 1;
    }
    if ratio > st.tight[m][l].ratio {
        st.tight[m][l] = Tight {
            ratio,
            seed,
            chain: q.chain,
            run,
            seen,
            bound,
        };
    }
    if seen > bound {
        let what = format!(
            "chain {} {} from the {}: observed {seen} ns > sound bound {bound} ns (paper {} ns)",
            q.chain,
            q.metric.name(),
            q.anchor.name(),
            c.bound.paper(q.anchor)
        );
        st.failures
            .push(reproduction(sys, cfg, res, q.chain, obs.witness, &what));
    }
    Some(ratio)
}

/// A self-contained description of a failure: the generator settings, the
/// tasks, the chain, the run (with its offsets) and the sample's timeline.
fn reproduction(
    sys: &System,
    cfg: &SimConfig,
    res: &SimResult,
    chain: usize,
    witness: Option<Witness>,
    what: &str,
) -> String {
    let (seed, gen, spec, report) = (sys.seed, sys.gen, sys.spec, sys.report);
    let mut s = String::new();
    let _ = writeln!(s, "=== seed {seed}: {what}");
    let _ = writeln!(s, "gen: {gen:?}");
    let _ = writeln!(
        s,
        "sim: horizon {} ns, seed {}, {:?}, {:?}, offsets {:?}",
        cfg.horizon, cfg.seed, cfg.phasing, cfg.exec, res.offsets
    );
    let ranks = rate_monotonic(spec);
    for (i, t) in spec.tasks.iter().enumerate() {
        let tm = &report.timing[i];
        let _ = writeln!(
            s,
            "  t{i}: T={} demand={} demand_min={} budget={} cpu={} rank={:?} server={} reads={:?} R={:?} observed R={:?}",
            tm.period,
            t.demand(),
            t.demand_min(),
            t.budget(),
            t.cpu,
            ranks[i],
            t.server.name(),
            t.reads,
            tm.job_response_time,
            res.tasks[i].max_response
        );
    }
    if let Some(ch) = spec.chains.get(chain) {
        let _ = writeln!(s, "chain {chain}: path {:?}", ch.path);
        for c in report.chains.iter().filter(|c| c.chain == chain) {
            let _ = writeln!(s, "  {}: {:?}", c.metric.name(), c.bound);
        }
    }
    let Some(w) = witness else { return s };
    let _ = writeln!(
        s,
        "sample {}: measured from {} (head read or event), first output {}, last output {}",
        w.sample, w.read, w.first, w.last
    );
    // Replay with the job log; the offsets make it independent of the phasing draw.
    let replay = SimConfig {
        phasing: Phasing::Given(res.offsets.clone()),
        log_jobs: true,
        jitter: rtpipe_sim::Jitter::Uniform,
        ..cfg.clone()
    };
    let Ok(log) = simulate(spec, &replay) else {
        return s;
    };
    let path = spec
        .chains
        .get(chain)
        .map(|c| c.path.clone())
        .unwrap_or_default();
    let cpus: Vec<u32> = path.iter().map(|&i| spec.tasks[i].cpu).collect();
    let t_max = path
        .iter()
        .filter_map(|&i| spec.tasks[i].fixed_period())
        .max()
        .unwrap_or(0);
    let _ = writeln!(
        s,
        "jobs on the chain's CPUs in [{}, {}] (* = carries the sample):",
        w.read - t_max,
        w.last
    );
    let mut lines = 0;
    for j in &log.jobs {
        if j.finish < w.read - t_max
            || j.release > w.last
            || !cpus.contains(&spec.tasks[j.task].cpu)
        {
            continue;
        }
        let carries = j
            .carried
            .iter()
            .find(|c| c.chain == chain)
            .map(|c| (c.pos, c.sample));
        let mark = match carries {
            Some((_, Some(x))) if x == w.sample => "*",
            _ => " ",
        };
        let _ = writeln!(
            s,
            "  {mark} t{}#{} cpu{} release {} read {} finish {} demand {} chain pos/sample {:?}",
            j.task, j.index, spec.tasks[j.task].cpu, j.release, j.read, j.finish, j.demand, carries
        );
        lines += 1;
        if lines >= 300 {
            let _ = writeln!(s, "  …");
            break;
        }
    }
    s
}

/// Ratios per scheduler (RM, EDF), quantity and chain length.
type Spread = [[[Vec<f64>; 3]; 4]; 2];

/// The tightness distribution of docs/analysis.md: for every chain and
/// quantity of `RTPIPE_TIGHT_SYSTEMS` random systems (default 300), a search
/// of its own (`RTPIPE_TIGHT_RESTARTS` × `RTPIPE_TIGHT_STEPS`, default 3 ×
/// 40) for the worst latency, divided by the sound bound. Minutes of work,
/// hence ignored; `--ignored --nocapture` prints the distribution per
/// scheduler, quantity and chain length. Fails if a search exceeds a bound.
/// `RTPIPE_TIGHT_ONLY=rm` or `edf` skips the systems of the other scheduler
/// (the same seeds, so the figures of one scheduler do not change).
#[test]
#[ignore]
fn tightness_distribution() {
    let n = env_u64("RTPIPE_TIGHT_SYSTEMS", 300);
    let restarts = env_u64("RTPIPE_TIGHT_RESTARTS", 3) as u32;
    let steps = env_u64("RTPIPE_TIGHT_STEPS", 40) as u32;
    let workers = std::thread::available_parallelism().map_or(1, |p| p.get()) as u64;
    let mut all: Spread = Default::default();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                s.spawn(move || {
                    let mut mine: Spread = Default::default();
                    let mut seed = w;
                    while seed < n {
                        tightness_of(seed, restarts, steps, &mut mine);
                        seed += workers;
                    }
                    mine
                })
            })
            .collect();
        for h in handles {
            let mine = h.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
            for (a, m) in all.iter_mut().flatten().zip(mine.into_iter().flatten()) {
                for (x, y) in a.iter_mut().zip(m) {
                    x.extend(y);
                }
            }
        }
    });
    println!("tightness: {n} systems, {restarts} x {steps} search steps per chain and quantity");
    for (k, sched) in ["rm", "edf"].iter().enumerate() {
        for (m, (metric, anchor)) in QUANTITIES.iter().enumerate() {
            for (l, len) in ["1", "2", ">=3"].iter().enumerate() {
                let mut w = all[k][m][l].clone();
                w.sort_by(f64::total_cmp);
                let q = |p: f64| {
                    w.get(((w.len() as f64 - 1.0) * p).round() as usize)
                        .copied()
                };
                println!(
                    "  {sched}, {} from the {}, chains of {len} tasks: {} chains, found/sound median {:.3}, 10th percentile {:.3}",
                    metric.name(),
                    anchor.name(),
                    w.len(),
                    q(0.5).unwrap_or(f64::NAN),
                    q(0.1).unwrap_or(f64::NAN)
                );
            }
        }
    }
}

/// One system's searched found/sound ratios, per quantity and chain length.
fn tightness_of(seed: u64, restarts: u32, steps: u32, out: &mut Spread) {
    let spec = random_system(seed, &gen_config(seed));
    if std::env::var("RTPIPE_TIGHT_ONLY").is_ok_and(|s| s != spec.scheduler.name()) {
        return;
    }
    let report = analyze(&spec);
    let k = usize::from(spec.scheduler == Scheduler::Edf);
    for c in &report.chains {
        for anchor in Anchor::ALL {
            let Some(bound) = c.bound.sound(anchor) else {
                continue;
            };
            let cfg = SearchConfig {
                restarts,
                steps,
                seed: seed ^ 0x7167,
                anchor,
                ..SearchConfig::new(c.chain, c.metric, horizon(&spec))
            };
            if let Some(v) = common::tight::worst_found(&spec, seed, &cfg).0 {
                let l = spec.chains[c.chain].path.len().clamp(1, 3) - 1;
                out[k][quantity_index(c.metric, anchor)][l].push(v as f64 / bound as f64);
            }
        }
    }
}
