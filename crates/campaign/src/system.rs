//! One system of a campaign: generated from its seed, analysed, simulated
//! when asked; one row per chain and metric.

use crate::config::{Config, Simulate};
use rtpipe_analysis::{Anchor, Bound, Metric, Report};
use rtpipe_model::gen::{event_triggered_system, waters_system, EventGenConfig, Rng, WatersConfig};
use rtpipe_model::{Nanos, Spec};
use rtpipe_printer::Cell;
use rtpipe_sim::observe::{observe, ChainObs};
use rtpipe_sim::{ExecModel, Jitter, Phasing, SimConfig};

/// The seed of system `i` of a campaign seeded `base`: a function of the
/// two alone (so shards, threads and machines agree).
pub fn system_seed(base: u64, i: u64) -> u64 {
    let mut r = Rng::new(base ^ i.wrapping_mul(0xD1B5_4A32_D192_ED03));
    r.next_u64()
}

/// One chain and metric of one system.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub system: u64,
    pub seed: u64,
    pub tasks: u32,
    pub cpus: u32,
    /// The chains the system got: fewer than asked when the generator
    /// found too few (a system with none has no rows; [`run_system`]'s
    /// caller counts those).
    pub chains: u32,
    /// The utilisation drawn for each CPU.
    pub utilization_target: f64,
    /// The largest CPU's Σ C/T as generated.
    pub utilization: f64,
    pub schedulable: bool,
    pub chain: u32,
    pub chain_tasks: u32,
    pub metric: Metric,
    /// Bounds by [`Bound::ALL`] (paper, sound, Davare, Dürr) and anchor
    /// (read, event); `None`: unbounded.
    pub bounds: [[Option<Nanos>; Anchor::ALL.len()]; Bound::ALL.len()],
    /// The bounds under the known offsets (synchronous release), per anchor.
    pub offsets: [Option<Nanos>; Anchor::ALL.len()],
    /// Simulated: the largest observation per anchor, the count from the
    /// read, and the observations above the bound that holds for the run
    /// (under the known offsets when the chain has them, else the sound one).
    pub observed: Option<Observed>,
}

/// What the simulation saw of one chain and metric.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observed {
    pub max: [Option<Nanos>; Anchor::ALL.len()],
    pub count: u64,
    pub over_bound: u64,
}

/// Generates, analyses (and simulates) system `i` of `cfg`.
pub fn run_system(cfg: &Config, i: u64) -> Vec<Row> {
    match run_system_until(cfg, i, &|| false) {
        Some(rows) => rows,
        None => unreachable!("a run never stopped ends"),
    }
}

/// [`run_system`], its simulation asking `stop` as it goes (every
/// `rtpipe_sim::PROGRESS_EVENTS` events): `None` when stopped.
pub fn run_system_until(cfg: &Config, i: u64, stop: &dyn Fn() -> bool) -> Option<Vec<Row>> {
    let seed = system_seed(cfg.seed, i);
    let (spec, target) = generate(cfg, seed);
    let report = rtpipe_analysis::analyze(&spec);
    let obs = match &cfg.simulate {
        Some(s) => Some(simulate(&spec, &report, s, (seed, i), stop)?),
        None => None,
    };
    let utilization = report
        .schedulability
        .cpus
        .iter()
        .map(|c| c.utilization)
        .fold(0.0, f64::max);
    let mut rows = Vec::with_capacity(report.chains.len());
    for (k, c) in report.chains.iter().enumerate() {
        let by = |b: Bound, a: Anchor| c.bound.get(b, a);
        let offsets = report.offsets[c.chain].as_ref().map_or([None, None], |o| {
            Anchor::ALL.map(|a| o.get(c.metric, a).value)
        });
        rows.push(Row {
            system: i,
            seed,
            tasks: spec.tasks.len() as u32,
            cpus: cpus_of(cfg, &spec),
            chains: spec.chains.len() as u32,
            utilization_target: target,
            utilization,
            schedulable: report.schedulability.schedulable,
            chain: c.chain as u32,
            chain_tasks: spec.chains[c.chain].path.len() as u32,
            metric: c.metric,
            bounds: Bound::ALL.map(|b| Anchor::ALL.map(|a| by(b, a))),
            offsets,
            observed: obs.as_ref().map(|o| {
                assert!(
                    o[k].chain == c.chain && o[k].metric == c.metric,
                    "observations follow the report"
                );
                observed(&o[k])
            }),
        });
    }
    Some(rows)
}

/// The system of `seed` and the utilisation drawn for each of its CPUs.
fn generate(cfg: &Config, seed: u64) -> (Spec, f64) {
    let g = &cfg.generate;
    let mut rng = Rng::new(seed);
    if let Some(e) = &g.events {
        let target = g.utilization.0 + (g.utilization.1 - g.utilization.0) * rng.unit();
        let c = EventGenConfig {
            max_chains: g.chains as usize,
            min_links: e.links.0 as usize,
            max_links: e.links.1 as usize,
            max_threads: e.threads as usize,
            max_cpus: g.cpus,
            utilization: target,
            data_fraction: e.data_fraction,
            ..EventGenConfig::default()
        };
        return (event_triggered_system(rng.next_u64(), &c), target);
    }
    let tasks = g
        .tasks
        .map(|(lo, hi)| rng.range(u64::from(lo), u64::from(hi)) as usize);
    let target = g.utilization.0 + (g.utilization.1 - g.utilization.0) * rng.unit();
    let w = WatersConfig {
        tasks,
        cpus: g.cpus,
        utilization: target,
        chains: g.chains as usize,
        synchronous: g.synchronous,
    };
    (waters_system(seed, &w), target)
}

/// One simulation of system `i` (seeded `seed`) against its report; `None`
/// when `stop` ended it.
fn simulate(
    spec: &Spec,
    report: &Report,
    s: &Simulate,
    (seed, i): (u64, u64),
    stop: &dyn Fn() -> bool,
) -> Option<Vec<ChainObs>> {
    let sim = SimConfig {
        horizon: s.horizon,
        seed,
        phasing: if s.random_phasing {
            Phasing::Random
        } else {
            Phasing::Sync
        },
        exec: if s.uniform_exec {
            ExecModel::Uniform
        } else {
            ExecModel::Worst
        },
        jitter: Jitter::Uniform,
        log_jobs: false,
    };
    match rtpipe_sim::simulate_until(spec, &sim, stop) {
        Ok(res) => res.map(|res| observe(report, &res)),
        // A generated system has fixed positive periods: a refusal is a bug.
        Err(e) => panic!("system {i} (seed {seed}) cannot be simulated: {e}"),
    }
}

/// A system's CPUs: the campaign's (WATERS), or as many as the system
/// uses (the event-triggered generator draws them).
fn cpus_of(cfg: &Config, spec: &Spec) -> u32 {
    match cfg.generate.events {
        None => cfg.generate.cpus,
        Some(_) => spec.tasks.iter().map(|t| t.cpu + 1).max().unwrap_or(0),
    }
}

fn observed(o: &ChainObs) -> Observed {
    let max = Anchor::ALL.map(|a| o.from(a).observed.as_ref().map(|s| s.max));
    Observed {
        max,
        count: o.read.observed.as_ref().map_or(0, |s| s.count as u64),
        over_bound: o.violations() as u64,
    }
}

/// A count as a cell.
fn count(n: u64) -> Cell {
    Cell::opt_int(i64::try_from(n).ok())
}

impl Row {
    /// The row's cells, in [`crate::columns::columns`]' order.
    pub fn cells(&self) -> Vec<Cell> {
        let mut c = vec![Cell::UInt(self.system), Cell::UInt(self.seed)];
        c.extend([self.tasks, self.cpus, self.chains].map(|n| Cell::UInt(u64::from(n))));
        c.extend([
            Cell::Float(self.utilization_target),
            Cell::Float(self.utilization),
        ]);
        c.push(Cell::Bool(self.schedulable));
        c.extend([self.chain, self.chain_tasks].map(|n| Cell::UInt(u64::from(n))));
        c.push(Cell::from(self.metric.name()));
        for a in 0..Anchor::ALL.len() {
            c.extend(
                self.bounds
                    .iter()
                    .map(|by_anchor| Cell::opt_int(by_anchor[a])),
            );
        }
        c.extend(self.offsets.map(Cell::opt_int));
        let obs = self.observed.as_ref();
        c.extend((0..Anchor::ALL.len()).map(|a| Cell::opt_int(obs.and_then(|o| o.max[a]))));
        c.push(obs.map_or(Cell::Empty, |o| count(o.count)));
        c.push(obs.map_or(Cell::Empty, |o| count(o.over_bound)));
        c.push(Cell::Bool(obs.is_some()));
        c
    }
}
