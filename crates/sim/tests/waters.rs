//! The sound bounds on the field's own benchmark: WATERS 2015 automotive
//! task sets with cause-effect chains (`rtpipe_model::gen::waters_system`,
//! as `rtpipe generate waters` writes them), set against Davare's and Dürr's
//! bounds and against the worst latencies the simulator and its adversarial
//! search find.
//!
//! Per system: three runs (synchronous release with worst-case demands,
//! random offsets with uniform demands, random offsets with extreme demands)
//! and, per chain, a search for its reaction from the event; every run is
//! checked against every chain's four sound bounds. The test fails on any
//! observation above a sound bound and on any sound bound above Davare's or
//! Dürr's. `RTPIPE_WATERS_SYSTEMS` (default 6) and `RTPIPE_WATERS_SEARCH`
//! (steps per search, default 12) size it; run with `--nocapture` for the
//! table that docs/analysis.md reports.

use rtpipe_analysis::Bound;
use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_joblog::SimResult;
use rtpipe_model::gen::{waters_system, WatersConfig};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::observe::ChainStatsExt;
use rtpipe_sim::search::{search_with, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};
use rtpipe_testkit::env_u64;

const MS: Nanos = 1_000_000;

/// Every quantity, in table order.
const QUANTITIES: [(Metric, Anchor); 4] = [
    (Metric::Reaction, Anchor::Read),
    (Metric::Freshness, Anchor::Read),
    (Metric::Reaction, Anchor::Event),
    (Metric::Freshness, Anchor::Event),
];

/// Ratios per quantity, one entry per system chain.
#[derive(Default)]
struct Ratios {
    davare: [Vec<f64>; 4],
    duerr: [Vec<f64>; 4],
    found: [Vec<f64>; 4],
}

/// Twenty periods of the chain's slowest task (at least 2 s) lets every
/// sample of the slowest head reach the tail a few times.
fn horizon(spec: &Spec) -> Nanos {
    let t_max = spec
        .chains
        .iter()
        .flat_map(|c| &c.path)
        .filter_map(|&i| spec.tasks[i].fixed_period())
        .max()
        .unwrap_or(MS);
    (20 * t_max).clamp(2_000 * MS, 20_000 * MS)
}

/// Worst observed value per (chain, quantity), raised by one run; panics on
/// a sound-bound violation.
fn observe(report: &Report, res: &SimResult, worst: &mut [[Nanos; 4]], seed: u64) {
    for c in &report.chains {
        for (q, &(metric, anchor)) in QUANTITIES.iter().enumerate() {
            if metric != c.metric {
                continue;
            }
            let (Some(seen), Some(bound)) = (
                res.chains[c.chain].observed(metric, anchor).max,
                c.bound.sound(anchor),
            ) else {
                continue;
            };
            assert!(
                seen <= bound,
                "seed {seed} chain {} {} from the {}: observed {seen} > sound {bound}",
                c.chain,
                metric.name(),
                anchor.name()
            );
            worst[c.chain][q] = worst[c.chain][q].max(seen);
        }
    }
}

/// Simulates and searches one system; returns the worst found per chain and quantity.
fn found(spec: &Spec, report: &Report, seed: u64, steps: u32) -> Vec<[Nanos; 4]> {
    let h = horizon(spec);
    let mut worst = vec![[0; 4]; spec.chains.len()];
    let runs = [
        (Phasing::Sync, ExecModel::Worst),
        (Phasing::Random, ExecModel::Uniform),
        (Phasing::Random, ExecModel::Extremes),
    ];
    for (k, (phasing, exec)) in runs.into_iter().enumerate() {
        let cfg = SimConfig {
            seed: seed.wrapping_mul(7).wrapping_add(k as u64),
            phasing,
            exec,
            ..SimConfig::new(h)
        };
        let res = simulate(spec, &cfg).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        observe(report, &res, &mut worst, seed);
    }
    for chain in 0..spec.chains.len() {
        let cfg = SearchConfig {
            restarts: 1,
            steps,
            seed: seed ^ chain as u64,
            anchor: Anchor::Event,
            ..SearchConfig::new(chain, Metric::Reaction, h)
        };
        let obs = |_: &SimConfig, res: &SimResult| observe(report, res, &mut worst, seed);
        search_with(spec, &cfg, obs).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
    }
    worst
}

/// Adds one system's ratios; panics when a sound bound exceeds Davare's or Dürr's.
fn tally(report: &Report, worst: &[[Nanos; 4]], seed: u64, r: &mut Ratios) {
    for c in &report.chains {
        for (q, &(metric, anchor)) in QUANTITIES.iter().enumerate() {
            if metric != c.metric {
                continue;
            }
            let b = &c.bound;
            let (Some(s), Some(d), Some(u)) = (
                b.sound(anchor),
                b.get(Bound::Davare, anchor),
                b.get(Bound::Duerr, anchor),
            ) else {
                continue;
            };
            assert!(
                s <= d.min(u),
                "seed {seed} chain {}: sound {s} > min(davare {d}, duerr {u})",
                c.chain
            );
            r.davare[q].push(s as f64 / d as f64);
            r.duerr[q].push(s as f64 / u as f64);
            if worst[c.chain][q] > 0 {
                r.found[q].push(worst[c.chain][q] as f64 / s as f64);
            }
        }
    }
}

/// (median, 10th percentile, max) of some ratios.
fn summary(v: &[f64]) -> (f64, f64, f64) {
    let mut w = v.to_vec();
    w.sort_by(f64::total_cmp);
    let at = |p: f64| {
        w.get(((w.len() as f64 - 1.0) * p).round() as usize)
            .copied()
    };
    let nan = f64::NAN;
    (
        at(0.5).unwrap_or(nan),
        at(0.1).unwrap_or(nan),
        w.last().copied().unwrap_or(nan),
    )
}

fn print_table(r: &Ratios) {
    println!("quantity | chains | sound/Davare median, max | sound/Dürr median, max | found/sound median, 10th pct, max");
    for (q, &(metric, anchor)) in QUANTITIES.iter().enumerate() {
        let (dm, _, dx) = summary(&r.davare[q]);
        let (um, _, ux) = summary(&r.duerr[q]);
        let (fm, fp, fx) = summary(&r.found[q]);
        println!(
            "{} from the {} | {} | {dm:.3}, {dx:.3} | {um:.3}, {ux:.3} | {fm:.3}, {fp:.3}, {fx:.3}",
            metric.name(),
            anchor.name(),
            r.davare[q].len()
        );
    }
}

#[test]
fn waters_sound_bounds_hold_and_stay_within_the_literature() {
    let n = env_u64("RTPIPE_WATERS_SYSTEMS", 6);
    let steps = env_u64("RTPIPE_WATERS_SEARCH", 12).min(u64::from(u32::MAX)) as u32;
    let cfg = WatersConfig {
        tasks: Some(30),
        chains: 5,
        ..WatersConfig::default()
    };
    let mut ratios = Ratios::default();
    let mut chains = 0;
    for seed in 0..n {
        let spec = waters_system(seed, &cfg);
        let report = analyze(&spec);
        assert!(report.schedulability.schedulable, "seed {seed}");
        chains += spec.chains.len();
        let worst = found(&spec, &report, seed, steps);
        tally(&report, &worst, seed, &mut ratios);
    }
    println!("WATERS: {n} systems, {chains} chains, {steps} search steps per chain");
    print_table(&ratios);
    assert!(chains > 0 && ratios.found.iter().all(|v| !v.is_empty()));
}
