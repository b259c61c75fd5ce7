//! Random systems for property tests and benchmarks, deterministic per seed.
//!
//! Periods follow the WATERS 2015 automotive benchmark (Kramer, Ziegenbein,
//! Hamann): 1, 2, 5, 10, 20, 50, 100, 200, 1000 ms with shares
//! 3, 2, 2, 25, 25, 3, 20, 1, 4 % (the angle-synchronous class left out).
//! Utilisation per CPU is split with UUniFast (Bini and Buttazzo 2005).
//! [`waters_system`] adds the paper's execution-time statistics and the
//! cause-effect chains of the E2EEvaluation framework (module `waters`).

use crate::{
    compute_transfers, Chain, Channel, Nanos, PeriodSpec, Port, Scheduler, Server, Spec, Task,
    TimeUnit,
};

mod contention;
mod events;
mod timing;
mod waters;
pub use contention::{add_contention, random_sections, Contention};
pub use events::{event_triggered_system, EventGenConfig};
pub use timing::{add_timing, Timing};
pub use waters::{
    sample_acet_us, waters_exec, waters_share, waters_system, WatersConfig, WatersExec, WATERS_EXEC,
};

/// SplitMix64 (Steele, Lea, Flood, OOPSLA 2014): tiny, fast, and the same
/// on every platform and version. The one generator of the workspace's
/// seeded draws: the systems drawn here, and the simulator's execution
/// times, random phasing and adversarial search (`rtpipe_sim::Rng` is
/// this type). Its sequence is part of both contracts (a seed always
/// means the same system; the same spec, configuration and seed give the
/// same simulation, bit for bit, and replay commands printed by earlier
/// versions still replay), so a test pins its first values: do not
/// change it.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ GOLDEN_GAMMA)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        splitmix_next(&mut self.0)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi] (inclusive; the modulo bias is below 2^-40 for
    /// spans below 2^24, and kept for reproducibility).
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        assert!(lo <= hi, "empty range {lo}..={hi}");
        lo + self.next_u64() % (hi - lo + 1)
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}

/// SplitMix64's increment: the state after `n` draws from state 0 is
/// `n · GOLDEN_GAMMA`.
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function of a state.
fn splitmix_output(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// One SplitMix64 step: the state advances by its increment and the
/// output is the new state's mix ([`Rng`]'s step, for a caller that keeps
/// the state itself, such as a seed expanded into another generator's).
pub fn splitmix_next(state: &mut u64) -> u64 {
    *state = state.wrapping_add(GOLDEN_GAMMA);
    splitmix_output(*state)
}

/// The `n`-th number (from 0) of the SplitMix64 stream whose state starts
/// at 0, drawn directly: a counter's draws with no generator to carry
/// (the design search's kicks).
pub fn splitmix_at(n: u64) -> u64 {
    splitmix_output(n.wrapping_add(1).wrapping_mul(GOLDEN_GAMMA))
}

/// WATERS 2015 periods in ms and their shares in percent.
pub const WATERS_PERIODS_MS: [(i64, u32); 9] = [
    (1, 3),
    (2, 2),
    (5, 2),
    (10, 25),
    (20, 25),
    (50, 3),
    (100, 20),
    (200, 1),
    (1000, 4),
];

/// Draws a WATERS period in ns.
pub fn waters_period(rng: &mut Rng) -> i64 {
    let total: u32 = WATERS_PERIODS_MS.iter().map(|&(_, w)| w).sum();
    let mut x = rng.range(0, total as u64 - 1) as u32;
    for &(p, w) in &WATERS_PERIODS_MS {
        if x < w {
            return p * 1_000_000;
        }
        x -= w;
    }
    1_000_000_000
}

/// UUniFast: n utilisations summing to `u`, uniformly distributed.
pub fn uunifast(rng: &mut Rng, n: usize, u: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    let mut sum = u;
    for i in 1..n {
        let next = sum * rng.unit().powf(1.0 / (n - i) as f64);
        out.push(sum - next);
        sum = next;
    }
    out.push(sum);
    out
}

/// What to generate.
#[derive(Debug, Clone)]
pub struct GenConfig {
    /// Number of tasks.
    pub tasks: usize,
    /// Number of CPUs.
    pub cpus: u32,
    /// Total utilisation per CPU (budgets over periods).
    pub utilization: f64,
    /// The scheduler of the generated system.
    pub scheduler: Scheduler,
    /// Fraction of tasks with no producer.
    pub source_fraction: f64,
    /// Each non-source reads 1..=max_fan_in earlier tasks.
    pub max_fan_in: usize,
    /// Probability that a task also reads a later task (a feedback edge).
    pub feedback: f64,
    /// Declared chains to generate (random walks along edges, 2–15 tasks).
    pub chains: usize,
    /// Give every transfer a cost (a memory channel with δ and bandwidth).
    pub transfers: bool,
    /// Draw server kinds among main, io and none (otherwise all main).
    pub mixed_servers: bool,
    /// Probability that an I/O VCPU serves (inherits the priority of) a Main
    /// VCPU on its CPU.
    pub inheritance: f64,
}

impl Default for GenConfig {
    fn default() -> Self {
        GenConfig {
            tasks: 10,
            cpus: 1,
            utilization: 0.6,
            scheduler: Scheduler::Rm,
            source_fraction: 0.2,
            max_fan_in: 2,
            feedback: 0.0,
            chains: 3,
            transfers: true,
            mixed_servers: false,
            inheritance: 0.0,
        }
    }
}

/// Number of source tasks (tasks `0..n_sources` read no other task) that
/// [`random_system`] makes of `n` tasks.
fn source_count(n: usize, cfg: &GenConfig) -> usize {
    ((n as f64 * cfg.source_fraction).ceil() as usize).clamp(1, n)
}

/// Consumers of every task along forward edges (producer index below the
/// consumer's), in declaration order.
fn forward_consumers(tasks: &[Task]) -> Vec<Vec<usize>> {
    let mut c = vec![Vec::new(); tasks.len()];
    for (ci, t) in tasks.iter().enumerate() {
        for &p in &t.reads {
            if p < ci {
                c[p].push(ci);
            }
        }
    }
    c
}

/// A random walk forward along edges from one of the first `n_sources`
/// tasks, aiming at 2–15 tasks; `accept(path, next)` filters the next step.
/// The walk stops early when no consumer is accepted.
fn random_walk(
    rng: &mut Rng,
    consumers: &[Vec<usize>],
    n_sources: usize,
    accept: impl Fn(&[usize], usize) -> bool,
) -> Vec<usize> {
    let mut cur = rng.range(0, n_sources as u64 - 1) as usize;
    let len = rng.range(2, 15) as usize;
    let mut path = vec![cur];
    while path.len() < len {
        let next: Vec<usize> = consumers[cur]
            .iter()
            .copied()
            .filter(|&c| accept(&path, c))
            .collect();
        if next.is_empty() {
            break;
        }
        cur = next[rng.range(0, next.len() as u64 - 1) as usize];
        path.push(cur);
    }
    path
}

/// A random valid system. Times are whole microseconds so that every demand,
/// budget and period is exact.
///
/// Every random draw comes from one stream, in a fixed order (tasks, feedback
/// edges, inheritance, demands, chains): the steps below must keep that
/// order, or every seed would mean a different system.
pub fn random_system(seed: u64, cfg: &GenConfig) -> Spec {
    let mut rng = Rng::new(seed);
    let n = cfg.tasks.max(1);
    let cpus = cfg.cpus.max(1);
    let n_sources = source_count(n, cfg);
    let mut tasks: Vec<Task> = (0..n)
        .map(|i| random_task(&mut rng, cfg, i, n_sources, cpus))
        .collect();
    if cfg.feedback > 0.0 {
        add_feedback(&mut rng, cfg, &mut tasks);
    }
    if cfg.inheritance > 0.0 {
        add_inheritance(&mut rng, cfg, &mut tasks);
    }
    for cpu in 0..cpus {
        draw_demands(&mut rng, cfg, &mut tasks, cpu);
    }
    // One memory channel of 1000 units per ms (1 unit per µs): a size of k
    // units is a transfer of k µs, so every demand is a whole number of µs.
    let channels = vec![Channel {
        name: "mem".into(),
        bandwidth: 1000.0,
        overhead: 0,
    }];
    compute_transfers(&mut tasks, &channels, TimeUnit::Ms);
    fit_budgets(&mut tasks);
    let chains = random_chains(&mut rng, cfg, &tasks, n_sources);
    Spec {
        name: format!("random-{seed}"),
        time_unit: TimeUnit::Ms,
        scheduler: cfg.scheduler,
        schedulability: cfg.scheduler.policy().default_test(),
        resolution: 1_000_000,
        harmonic: false,
        priorities: crate::Priorities::RateMonotonic,
        communication: crate::Communication::Implicit,
        resource_protocol: crate::ResourceProtocol::Pcp,
        resources: Vec::new(),
        overheads: crate::Overheads::default(),
        channels,
        threads: Vec::new(),
        tasks,
        chains,
    }
}

/// `cfg.chains` chains without limits: random walks forward along edges
/// from a source.
fn random_chains(rng: &mut Rng, cfg: &GenConfig, tasks: &[Task], n_sources: usize) -> Vec<Chain> {
    let consumers = forward_consumers(tasks);
    let mut chains = Vec::new();
    for _ in 0..cfg.chains {
        let path = random_walk(rng, &consumers, n_sources, |_, _| true);
        chains.push(Chain {
            name: None,
            path,
            reaction: None,
            freshness: None,
            max_reaction_time: None,
            freshness_from_event: None,
            communication: None,
        });
    }
    chains
}

/// Task `i` of [`random_system`] before its demand is drawn: its producers
/// (earlier tasks only, so the graph has no cycle yet), its server, its
/// WATERS period and its CPU, drawn in that order. The first `n_sources`
/// tasks read no task but an input port instead.
fn random_task(rng: &mut Rng, cfg: &GenConfig, i: usize, n_sources: usize, cpus: u32) -> Task {
    let mut reads = Vec::new();
    if i >= n_sources {
        let k = rng.range(1, cfg.max_fan_in.max(1) as u64) as usize;
        for _ in 0..k {
            let p = rng.range(0, i as u64 - 1) as usize;
            if !reads.contains(&p) {
                reads.push(p);
            }
        }
    }
    let server = if cfg.mixed_servers {
        match rng.range(0, 3) {
            0 => Server::Io,
            1 => Server::None,
            _ => Server::Main,
        }
    } else {
        Server::Main
    };
    // The period is drawn before the CPU (the streams stay as they were).
    let period = waters_period(rng);
    let cpu = rng.range(0, cpus as u64 - 1) as u32;
    Task {
        name: format!("t{i}"),
        exec_min: 0,
        input: if i < n_sources {
            Some(Port {
                channel: 0,
                size: 0.0,
            })
        } else {
            None
        },
        reads,
        server,
        cpu,
        ..Task::periodic(1, period)
    }
}

/// Feedback edges: each task but the last reads, with probability
/// `cfg.feedback`, one later task (the cycles the analysis must cope with).
fn add_feedback(rng: &mut Rng, cfg: &GenConfig, tasks: &mut [Task]) {
    let n = tasks.len();
    for (i, t) in tasks.iter_mut().enumerate().take(n.saturating_sub(1)) {
        if rng.chance(cfg.feedback) {
            let p = rng.range(i as u64 + 1, n as u64 - 1) as usize;
            if !t.reads.contains(&p) {
                t.reads.push(p);
            }
        }
    }
}

/// PIBS inheritance: each I/O VCPU, with probability `cfg.inheritance`,
/// serves one Main VCPU on its CPU (when there is one).
fn add_inheritance(rng: &mut Rng, cfg: &GenConfig, tasks: &mut [Task]) {
    let n = tasks.len();
    for i in 0..n {
        if tasks[i].server != Server::Io || !rng.chance(cfg.inheritance) {
            continue;
        }
        let mains: Vec<usize> = (0..n)
            .filter(|&j| tasks[j].server == Server::Main && tasks[j].cpu == tasks[i].cpu)
            .collect();
        if !mains.is_empty() {
            tasks[i].serves = Some(mains[rng.range(0, mains.len() as u64 - 1) as usize]);
        }
    }
}

/// Demands of the tasks on `cpu`: UUniFast utilisations summing to
/// `cfg.utilization`, each turned into a budget of whole µs and split into
/// transfers and processing.
fn draw_demands(rng: &mut Rng, cfg: &GenConfig, tasks: &mut [Task], cpu: u32) {
    let ids: Vec<usize> = (0..tasks.len()).filter(|&i| tasks[i].cpu == cpu).collect();
    if ids.is_empty() {
        return;
    }
    let us = uunifast(rng, ids.len(), cfg.utilization);
    for (&i, &u) in ids.iter().zip(&us) {
        draw_demand(rng, cfg, &mut tasks[i], u);
    }
}

/// One task's demand at utilisation `u` of its period: a budget of at least
/// 3 µs, split into an input and an output transfer of up to a quarter of it
/// each (as sizes on the 1-unit-per-µs channel) and processing, a best case
/// below the worst, and for some tasks a budget above the demand.
fn draw_demand(rng: &mut Rng, cfg: &GenConfig, t: &mut Task, u: f64) {
    let period = t.fixed_period().unwrap_or(1_000_000);
    let budget_us = ((u * period as f64 / 1000.0).floor() as i64).max(3);
    // Split the demand: transfers of up to a quarter each, the rest processing.
    let (din, dout) = if cfg.transfers {
        (
            rng.range(0, (budget_us / 4) as u64) as i64,
            rng.range(0, (budget_us / 4) as u64) as i64,
        )
    } else {
        (0, 0)
    };
    let exec_us = (budget_us - din - dout).max(1);
    t.exec = exec_us * 1000;
    t.exec_min = rng.range(0, exec_us as u64) as i64 * 1000;
    // Transfers as sizes on the 1-unit-per-µs channel below.
    if let Some(p) = &mut t.input {
        p.size = din as f64;
    }
    if let Some(p) = &mut t.output {
        p.size = dout as f64;
    }
    if rng.chance(0.3) {
        t.budget_given = Some(budget_us * 1000 + rng.range(0, 3) as i64 * 1000);
    }
}

/// Budgets must cover the (now aggregated) demand and fit the period: a
/// given budget below the demand is raised to it, and a period shorter than
/// the budget is lengthened to the next whole ms.
fn fit_budgets(tasks: &mut [Task]) {
    for t in tasks {
        let d = t.demand();
        if t.budget_given.is_some_and(|c| c < d) {
            t.budget_given = Some(d);
        }
        if let PeriodSpec::Fixed(p) = t.period {
            if t.budget() > p {
                t.period = PeriodSpec::Fixed((t.budget() + 999_999) / 1_000_000 * 1_000_000);
            }
        }
    }
}

/// What design problem to generate: a random system in the WATERS style (see
/// [`random_system`]) whose periods become design variables and whose chains
/// get limits near what the generating design achieves.
#[derive(Debug, Clone)]
pub struct DesignGenConfig {
    /// The generating system ([`random_system`]); its `chains` is how many
    /// chains to declare: walks of 2–15 tasks along edges whose tasks use at
    /// most 3 distinct generating periods (fewer when the graph offers fewer
    /// such walks). Feedback edges and inheritance are not generated.
    pub system: GenConfig,
    /// The spec's `resolution`: the grid of designed periods.
    pub resolution: Nanos,
    /// Probability that a task gets a choice domain rather than a range.
    pub choices_fraction: f64,
    /// Every task gets a choice domain of 2..=max_choices WATERS values
    /// around its generating period (for brute force).
    pub choices_only: bool,
    /// Largest choice domain (at least 2).
    pub max_choices: usize,
    /// Ranges end at k × the generating period, k drawn in 1..=max_factor.
    pub max_factor: u64,
    /// Probability that a range has a lower end (the generating period
    /// divided by 2..=4, on the resolution grid).
    pub min_fraction: f64,
    /// Every limit is the generating design's sound bound times a factor
    /// drawn uniformly in [slack.0, slack.1].
    pub slack: (f64, f64),
}

impl Default for DesignGenConfig {
    fn default() -> Self {
        DesignGenConfig {
            system: GenConfig {
                tasks: 6,
                utilization: 0.5,
                transfers: false,
                ..GenConfig::default()
            },
            resolution: 1_000_000,
            choices_fraction: 0.3,
            choices_only: false,
            max_choices: 4,
            max_factor: 4,
            min_fraction: 0.5,
            slack: (0.8, 1.5),
        }
    }
}

/// Sound (reaction, freshness) bounds of one chain, when they exist.
pub type ChainBounds = (Option<Nanos>, Option<Nanos>);

/// Salts that keep the random streams of the generator's stages apart.
const CHAIN_SALT: u64 = 0x6A09_E667_F3BC_C908;
const DOMAIN_SALT: u64 = 0xBB67_AE85_84CA_A73B;

/// The generating design of [`design_problem`]: a [`random_system`] with
/// every period fixed and chains (without limits) that use at most 3
/// distinct periods each, walked along edges.
pub fn design_origin(seed: u64, cfg: &DesignGenConfig) -> Spec {
    let gcfg = GenConfig {
        feedback: 0.0,
        chains: 0,
        inheritance: 0.0,
        ..cfg.system.clone()
    };
    let mut spec = random_system(seed, &gcfg);
    spec.name = format!("design-{seed}");
    spec.resolution = cfg.resolution.max(1);
    let n = spec.tasks.len();
    let n_sources = source_count(n, &gcfg);
    let consumers = forward_consumers(&spec.tasks);
    let periods: Vec<Nanos> = spec
        .tasks
        .iter()
        .map(|t| t.fixed_period().unwrap_or(0))
        .collect();
    let mut rng = Rng::new(seed ^ CHAIN_SALT);
    // Walks that would add a fourth distinct period are cut short; a walk of
    // one task or one already declared is drawn again.
    let at_most_3 = |path: &[usize], next: usize| {
        let mut seen: Vec<Nanos> = path.iter().map(|&i| periods[i]).collect();
        seen.push(periods[next]);
        seen.sort_unstable();
        seen.dedup();
        seen.len() <= 3
    };
    let mut attempts = 0;
    while spec.chains.len() < cfg.system.chains && attempts < 20 * cfg.system.chains.max(1) {
        attempts += 1;
        let path = random_walk(&mut rng, &consumers, n_sources, at_most_3);
        if path.len() < 2 || spec.chains.iter().any(|c| c.path == path) {
            continue;
        }
        spec.chains.push(Chain {
            name: None,
            path,
            reaction: None,
            freshness: None,
            max_reaction_time: None,
            freshness_from_event: None,
            communication: None,
        });
    }
    spec
}

/// A random design problem, deterministic per seed: [`design_origin`] with
/// every period turned into a domain that contains the generating period
/// (a range `[min?, k·T]` or a choice of nearby WATERS periods) and every
/// chain limited to its generating sound bound times a slack factor, so
/// that most instances are feasible and some are not.
///
/// `bound` gives the sound (reaction, freshness) bounds of every chain of a
/// spec whose periods are all fixed, in chain order; pass one that calls
/// `rtpipe_analysis::analyze` (this crate cannot depend on the analysis). A
/// missing bound leaves that limit out.
pub fn design_problem(
    seed: u64,
    cfg: &DesignGenConfig,
    bound: &dyn Fn(&Spec) -> Vec<ChainBounds>,
) -> Spec {
    let mut spec = design_origin(seed, cfg);
    let bounds = bound(&spec);
    let mut rng = Rng::new(seed ^ DOMAIN_SALT);
    let res = spec.resolution;
    for t in &mut spec.tasks {
        let p = t.fixed_period().unwrap_or(1_000_000);
        let c = t.budget();
        if cfg.choices_only || rng.chance(cfg.choices_fraction) {
            t.period = PeriodSpec::Choices(nearby_choices(&mut rng, p, c, cfg.max_choices));
        } else {
            let k = rng.range(1, cfg.max_factor.max(1)) as i64;
            let min = if rng.chance(cfg.min_fraction) {
                let d = rng.range(2, 4) as i64;
                Some((p / d / res * res).max(res).min(p))
            } else {
                None
            };
            t.period = PeriodSpec::Range {
                min,
                max: Some(k * p),
            };
        }
    }
    let (lo, hi) = cfg.slack;
    let mut limit = |b: Option<Nanos>| {
        b.map(|b| {
            let f = lo + (hi - lo) * rng.unit();
            // Whole µs, at least 1 µs.
            ((b as f64 * f / 1000.0).round() as i64).max(1) * 1000
        })
    };
    for (k, ch) in spec.chains.iter_mut().enumerate() {
        let (r, f) = bounds.get(k).copied().unwrap_or((None, None));
        ch.reaction = limit(r);
        ch.freshness = limit(f);
    }
    spec
}

/// 2..=max WATERS periods (and `p` itself) around `p`, all at least `c`,
/// sorted; always contains `p`.
fn nearby_choices(rng: &mut Rng, p: Nanos, c: Nanos, max: usize) -> Vec<Nanos> {
    let mut all: Vec<Nanos> = WATERS_PERIODS_MS
        .iter()
        .map(|&(ms, _)| ms * 1_000_000)
        .chain(std::iter::once(p))
        .filter(|&x| x >= c)
        .collect();
    all.sort_unstable();
    all.dedup();
    let at = all.iter().position(|&x| x == p).unwrap_or(0);
    let size = (rng.range(2, max.max(2) as u64) as usize).min(all.len());
    // A window of `size` values that contains position `at`.
    let first_lo = (at + 1).saturating_sub(size);
    let first_hi = at.min(all.len() - size);
    let first = rng.range(first_lo as u64, first_hi as u64) as usize;
    all[first..first + size].to_vec()
}

/// The design benchmarks' problems (`rtpipe-design`'s `solve` and `sizes`
/// benches): `tasks` tasks on 1, 2, 4 or 8 CPUs with 2, 4, 6 or 10 chains
/// (up to 10, 30, 60 tasks and beyond), utilisation 0.5 per CPU, ranges only.
pub fn benchmark_config(tasks: usize) -> DesignGenConfig {
    let (cpus, chains) = match tasks {
        0..=10 => (1, 2),
        11..=30 => (2, 4),
        31..=60 => (4, 6),
        _ => (8, 10),
    };
    DesignGenConfig {
        system: GenConfig {
            tasks,
            cpus,
            utilization: 0.5,
            chains,
            ..DesignGenConfig::default().system
        },
        choices_fraction: 0.0,
        ..DesignGenConfig::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_direct_draw_is_the_stream_from_state_zero() {
        // The stream of seed GOLDEN_GAMMA starts at state 0.
        let mut rng = Rng::new(GOLDEN_GAMMA);
        for n in 0..1000 {
            assert_eq!(splitmix_at(n), rng.next_u64(), "draw {n}");
        }
        // SplitMix64's published first output from state 0.
        assert_eq!(splitmix_at(0), 0xE220_A839_7B1D_CDAF);
        let mut state = 0;
        assert_eq!(splitmix_next(&mut state), 0xE220_A839_7B1D_CDAF);
        assert_eq!(state, GOLDEN_GAMMA);
    }

    /// The sequence the generated systems, the simulator's results and its
    /// printed replay commands depend on.
    #[test]
    fn the_sequence_is_pinned() {
        let mut r = Rng::new(42);
        let v: Vec<u64> = (0..3).map(|_| r.next_u64()).collect();
        assert_eq!(
            v,
            vec![
                2_949_826_092_126_892_291,
                5_139_283_748_462_763_858,
                6_349_198_060_258_255_764
            ]
        );
        assert_eq!(r.unit(), 0.03803016854024621);
        assert_eq!(r.range(3, 9), 7);
    }

    #[test]
    fn deterministic_and_valid() {
        let cfg = GenConfig {
            tasks: 50,
            cpus: 2,
            ..GenConfig::default()
        };
        let a = random_system(7, &cfg);
        let b = random_system(7, &cfg);
        assert_eq!(a, b);
        for t in &a.tasks {
            assert!(t.budget() >= t.demand());
            assert!(t.fixed_period().is_some_and(|p| p >= t.budget()));
            assert!(t.exec_min <= t.exec);
        }
        for c in &a.chains {
            for w in c.path.windows(2) {
                assert!(a.tasks[w[1]].reads.contains(&w[0]));
            }
        }
    }

    #[test]
    fn uunifast_sums() {
        let mut r = Rng::new(1);
        let u = uunifast(&mut r, 10, 0.7);
        assert!((u.iter().sum::<f64>() - 0.7).abs() < 1e-9);
        assert!(u.iter().all(|&x| x >= 0.0));
    }

    /// A stand-in for the analysis: twice the sum of periods on the chain.
    fn fake_bounds(s: &Spec) -> Vec<ChainBounds> {
        s.chains
            .iter()
            .map(|c| {
                let sum: Nanos = c
                    .path
                    .iter()
                    .filter_map(|&i| s.tasks[i].fixed_period())
                    .sum();
                (Some(2 * sum), Some(3 * sum))
            })
            .collect()
    }

    #[test]
    fn design_chains_span_at_most_three_periods() {
        let mut chains = 0;
        let mut spans = [0usize; 4];
        for seed in 0..200 {
            let cfg = DesignGenConfig {
                system: GenConfig {
                    tasks: 3 + (seed as usize % 40),
                    cpus: 1 + (seed % 2) as u32,
                    chains: 4,
                    ..DesignGenConfig::default().system
                },
                ..DesignGenConfig::default()
            };
            let o = design_origin(seed, &cfg);
            assert_eq!(o, design_origin(seed, &cfg), "deterministic");
            for c in &o.chains {
                assert!((2..=15).contains(&c.path.len()), "{:?}", c.path);
                for w in c.path.windows(2) {
                    assert!(o.tasks[w[1]].reads.contains(&w[0]));
                }
                let mut ps: Vec<Nanos> = c
                    .path
                    .iter()
                    .filter_map(|&i| o.tasks[i].fixed_period())
                    .collect();
                assert_eq!(ps.len(), c.path.len());
                ps.sort_unstable();
                ps.dedup();
                assert!((1..=3).contains(&ps.len()), "{ps:?}");
                spans[ps.len()] += 1;
                chains += 1;
            }
        }
        // Most systems have a chain; every span occurs.
        assert!(chains > 400, "{chains}");
        assert!(spans[1] > 0 && spans[2] > 0 && spans[3] > 0, "{spans:?}");
    }

    #[test]
    fn design_domains_contain_the_origin_and_round_trip() {
        let mut kinds = [0usize; 2];
        for seed in 0..200 {
            let cfg = DesignGenConfig {
                system: GenConfig {
                    tasks: 2 + (seed as usize % 30),
                    transfers: seed % 2 == 0,
                    mixed_servers: seed % 4 == 1,
                    scheduler: if seed % 5 == 0 {
                        Scheduler::Edf
                    } else {
                        Scheduler::Rm
                    },
                    ..DesignGenConfig::default().system
                },
                choices_only: seed % 3 == 0,
                max_choices: 2 + (seed as usize % 3),
                ..DesignGenConfig::default()
            };
            let o = design_origin(seed, &cfg);
            let s = design_problem(seed, &cfg, &fake_bounds);
            assert_eq!(s, design_problem(seed, &cfg, &fake_bounds), "deterministic");
            assert_eq!(o.tasks.len(), s.tasks.len());
            for (t, ot) in s.tasks.iter().zip(&o.tasks) {
                let p = ot.fixed_period().unwrap_or(0);
                assert!(p >= t.budget());
                match &t.period {
                    PeriodSpec::Choices(v) => {
                        kinds[0] += 1;
                        let n = v.len();
                        assert!(n >= 1 && n <= cfg.max_choices, "{v:?}");
                        assert!(v.windows(2).all(|w| w[0] < w[1]), "sorted: {v:?}");
                        assert!(v.contains(&p), "{v:?} lacks {p}");
                        assert!(v.iter().all(|&x| x >= t.budget()));
                    }
                    PeriodSpec::Range { min, max } => {
                        assert!(!cfg.choices_only);
                        kinds[1] += 1;
                        let max = max.unwrap_or(0);
                        assert!(max >= p && max % p == 0 && max <= 4 * p, "{max} {p}");
                        if let Some(m) = min {
                            assert!(*m > 0 && *m <= p && m % s.resolution == 0, "{m} {p}");
                        }
                    }
                    other => panic!("{other:?}"),
                }
            }
            for (c, (r, f)) in s.chains.iter().zip(fake_bounds(&o)) {
                for (l, b) in [(c.reaction, r), (c.freshness, f)] {
                    let (l, b) = (l.unwrap_or(0) as f64, b.unwrap_or(0) as f64);
                    assert!(l >= 0.8 * b - 1000.0 && l <= 1.5 * b + 1000.0, "{l} {b}");
                    assert_eq!(l % 1000.0, 0.0);
                }
            }
            let text = crate::write::to_toml(&s);
            match Spec::parse("gen.toml", &text) {
                Ok(back) => assert_eq!(back, s, "{text}"),
                Err(e) => panic!("{e}\n{text}"),
            }
        }
        assert!(kinds[0] > 100 && kinds[1] > 100, "{kinds:?}");
    }

    #[test]
    fn choice_domains_have_two_values_when_the_budget_allows() {
        let mut r = Rng::new(5);
        for _ in 0..1000 {
            let v = nearby_choices(&mut r, 10_000_000, 1_000, 4);
            assert!(
                (2..=4).contains(&v.len()) && v.contains(&10_000_000),
                "{v:?}"
            );
            let v = nearby_choices(&mut r, 1_000_000_000, 1_000, 3);
            assert!(
                (2..=3).contains(&v.len()) && v.contains(&1_000_000_000),
                "{v:?}"
            );
        }
        // Only the generating period is at least the budget.
        let v = nearby_choices(&mut r, 1_000_000_000, 900_000_000, 4);
        assert_eq!(v, vec![1_000_000_000]);
    }
}
