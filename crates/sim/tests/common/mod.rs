//! What the simulator's property tests share: the worst responses of a
//! run at given offsets, and the probe of a random system (a few runs,
//! then a search from the closest of them).
#![allow(dead_code)] // each test file uses its own subset

use rtpipe_analysis::Report;
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::search::{search_with, Candidate, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Jitter, Phasing, SimConfig};

pub const MS: Nanos = 1_000_000;

/// The worst response of each task from a 100 ms run with the given
/// offsets (ns).
pub fn worst(spec: &Spec, offsets: Vec<Nanos>) -> Vec<Nanos> {
    let cfg = SimConfig {
        phasing: Phasing::Given(offsets),
        ..SimConfig::new(100 * MS)
    };
    let res = simulate(spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    res.tasks
        .iter()
        .map(|t| t.max_response.unwrap_or(0))
        .collect()
}

/// A random system's run: twelve of its longest periods, at most 2 s.
pub fn horizon(spec: &Spec) -> Nanos {
    let t_max = spec
        .tasks
        .iter()
        .filter_map(|x| x.fixed_period())
        .max()
        .unwrap_or(MS);
    (12 * t_max).min(2_000 * MS)
}

/// The runs of [`probe`] without jitter: synchronous, random offsets
/// (worst and extreme demands), and a 1 ms grid (uniform demands).
pub fn plain_runs() -> Vec<(Phasing, ExecModel, Jitter)> {
    vec![
        (Phasing::Sync, ExecModel::Worst, Jitter::None),
        (Phasing::Random, ExecModel::Worst, Jitter::None),
        (Phasing::Random, ExecModel::Extremes, Jitter::None),
        (Phasing::Grid(MS), ExecModel::Uniform, Jitter::None),
    ]
}

/// How a system is probed: its runs, and the seeds they and the search
/// take (run `k` of system `seed` is seeded `seed·stride + k`; the search
/// `seed ^ salt`).
pub struct Probe {
    pub runs: Vec<(Phasing, ExecModel, Jitter)>,
    pub stride: u64,
    pub salt: u64,
    pub horizon: Nanos,
}

/// Runs `spec` as `how` says, handing every run to `check`, which returns
/// how close the run came to a bound and on which of `rep`'s chains; then
/// searches from the closest run for a worse one on that chain (a short
/// local search), handing `check` every run of it too.
pub fn probe(
    spec: &Spec,
    rep: &Report,
    seed: u64,
    how: &Probe,
    check: &mut dyn FnMut(&SimConfig, &SimResult) -> (f64, usize),
) {
    let mut best: Option<(f64, usize, SimConfig, Vec<Nanos>)> = None;
    for (run, (phasing, exec, jitter)) in how.runs.iter().cloned().enumerate() {
        let cfg = SimConfig {
            horizon: how.horizon,
            seed: seed.wrapping_mul(how.stride).wrapping_add(run as u64),
            phasing,
            exec,
            jitter,
            log_jobs: false,
        };
        let res = simulate(spec, &cfg).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let (ratio, k) = check(&cfg, &res);
        if best.as_ref().is_none_or(|b| ratio > b.0) {
            best = Some((ratio, k, cfg, res.offsets));
        }
    }
    let Some((_, k, cfg, offsets)) = best.filter(|_| !rep.chains.is_empty()) else {
        return;
    };
    let c = &rep.chains[k];
    let scfg = SearchConfig {
        restarts: 1,
        steps: 6,
        seed: seed ^ how.salt,
        start: vec![Candidate {
            offsets,
            exec: cfg.exec,
            seed: cfg.seed,
            jitter: cfg.jitter,
        }],
        ..SearchConfig::new(c.chain, c.metric, how.horizon)
    };
    let observe = |sc: &SimConfig, res: &SimResult| {
        check(sc, res);
    };
    search_with(spec, &scfg, observe).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
}
