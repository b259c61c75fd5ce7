//! What the simulator's property tests share: the worst responses of a
//! run at given offsets, and the probe of a random system (a few runs,
//! then a search from the closest of them).
#![allow(dead_code)] // each test file uses its own subset

pub mod tight;

use rtpipe_analysis::{Anchor, Report};
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::observe::ChainStatsExt;
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

/// Asserts that no task's worst response in the run at `offsets` ([`worst`])
/// is above its job response time bound in `rep`; `at` names the run in the
/// message.
pub fn assert_within_responses(spec: &Spec, rep: &Report, offsets: Vec<Nanos>, at: &str) {
    let seen = worst(spec, offsets);
    for (i, t) in rep.timing.iter().enumerate() {
        let r = t.job_response_time.unwrap_or(0);
        assert!(seen[i] <= r, "{at}: task {i} {} > {r}", seen[i]);
    }
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

/// Every bound of `rep` against one run: each chain's sound bound and its
/// known-offset bound from both anchors, each task's R(job); a bound
/// exceeded goes into `failures` with the run and the spec. Raises
/// `ratios[i]` to task i's worst observed/R. Returns the bounds checked
/// and the best observed/sound of a chain of two or more tasks, with its
/// entry in `rep.chains` (for the search).
pub fn check_run(
    spec: &Spec,
    rep: &Report,
    cfg: &SimConfig,
    res: &SimResult,
    ratios: &mut [f64],
    failures: &mut Vec<String>,
) -> (u64, (f64, usize)) {
    let (mut checks, mut best) = (0, (0.0, 0));
    let tag = |what: String| format!("{what}; {cfg:?}\n{}", rtpipe_model::to_toml(spec));
    for (k, c) in rep.chains.iter().enumerate() {
        for a in Anchor::ALL {
            let obs = res.chains[c.chain].observed(c.metric, a);
            let (Some(seen), Some(b)) = (obs.max, c.bound.sound(a)) else {
                continue;
            };
            let m = c.metric.name();
            checks += 1;
            if seen > b {
                failures.push(tag(format!(
                    "chain {k} {m} from {}: {seen} > sound {b}",
                    a.name()
                )));
            }
            let ratio = seen as f64 / b as f64;
            if spec.chains[c.chain].path.len() > 1 && ratio > best.0 {
                best = (ratio, k);
            }
            if let Some(o) = rep.offset_bound(c.chain, c.metric, a).and_then(|o| o.value) {
                checks += 1;
                if seen > o {
                    failures.push(tag(format!(
                        "chain {k} {m} from {}: {seen} > known-offset {o}",
                        a.name()
                    )));
                }
            }
        }
    }
    for (i, ts) in res.tasks.iter().enumerate() {
        let Some(r) = rep.timing[i].bounded_response() else {
            continue;
        };
        if let Some(seen) = ts.max_response {
            checks += 1;
            if seen > r {
                failures.push(tag(format!("task {i}: response {seen} > R(job) {r}")));
            }
            ratios[i] = ratios[i].max(seen as f64 / r as f64);
        }
    }
    (checks, best)
}
