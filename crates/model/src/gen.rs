//! Random systems for property tests and benchmarks, deterministic per seed.
//!
//! Periods follow the WATERS 2015 automotive benchmark (Kramer, Ziegenbein,
//! Hamann): 1, 2, 5, 10, 20, 50, 100, 200, 1000 ms with shares
//! 3, 2, 2, 25, 25, 3, 20, 1, 4 % (the angle-synchronous class left out).
//! Utilisation per CPU is split with UUniFast (Bini and Buttazzo 2005).

use crate::{
    compute_transfers, Chain, Channel, PeriodSpec, Port, SchedTest, Scheduler, Server, Spec, Task,
    TimeUnit,
};

/// SplitMix64: tiny, fast, good enough for test generation, and stable across
/// platforms and crate versions (so a seed always means the same system).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi] (inclusive).
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.next_u64() % (hi - lo + 1)
    }
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
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
    pub tasks: usize,
    pub cpus: u32,
    /// Total utilisation per CPU (budgets over periods).
    pub utilization: f64,
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

/// A random valid system. Times are whole microseconds so that every demand,
/// budget and period is exact.
pub fn random_system(seed: u64, cfg: &GenConfig) -> Spec {
    let mut rng = Rng::new(seed);
    let n = cfg.tasks.max(1);
    let cpus = cfg.cpus.max(1);
    let mut tasks: Vec<Task> = Vec::with_capacity(n);
    let n_sources = ((n as f64 * cfg.source_fraction).ceil() as usize).clamp(1, n);
    for i in 0..n {
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
        tasks.push(Task {
            name: format!("t{i}"),
            exec: 1,
            exec_min: 0,
            input: if i < n_sources {
                Some(Port {
                    channel: 0,
                    size: 0.0,
                })
            } else {
                None
            },
            output: Some(Port {
                channel: 0,
                size: 0.0,
            }),
            reads,
            period: PeriodSpec::Fixed(waters_period(&mut rng)),
            budget_given: None,
            server,
            cpu: rng.range(0, cpus as u64 - 1) as u32,
            serves: None,
            delta_in: 0,
            delta_out: 0,
        });
    }
    if cfg.feedback > 0.0 {
        for (i, t) in tasks.iter_mut().enumerate().take(n.saturating_sub(1)) {
            if rng.chance(cfg.feedback) {
                let p = rng.range(i as u64 + 1, n as u64 - 1) as usize;
                if !t.reads.contains(&p) {
                    t.reads.push(p);
                }
            }
        }
    }
    if cfg.inheritance > 0.0 {
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
    // Execution times from UUniFast utilisations per CPU, in whole µs.
    for cpu in 0..cpus {
        let ids: Vec<usize> = (0..n).filter(|&i| tasks[i].cpu == cpu).collect();
        if ids.is_empty() {
            continue;
        }
        let us = uunifast(&mut rng, ids.len(), cfg.utilization);
        for (&i, &u) in ids.iter().zip(&us) {
            let t = tasks[i].fixed_period().unwrap_or(1_000_000);
            let budget_us = ((u * t as f64 / 1000.0).floor() as i64).max(3);
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
            tasks[i].exec = exec_us * 1000;
            tasks[i].exec_min = rng.range(0, exec_us as u64) as i64 * 1000;
            // Transfers as sizes on the 1-unit-per-µs channel below.
            if let Some(p) = &mut tasks[i].input {
                p.size = din as f64;
            }
            if let Some(p) = &mut tasks[i].output {
                p.size = dout as f64;
            }
            if rng.chance(0.3) {
                tasks[i].budget_given = Some(budget_us * 1000 + rng.range(0, 3) as i64 * 1000);
            }
        }
    }
    // One memory channel of 1000 units per ms (1 unit per µs): a size of k
    // units is a transfer of k µs, so every demand is a whole number of µs.
    let channels = vec![Channel {
        name: "mem".into(),
        bandwidth: 1000.0,
        overhead: 0,
    }];
    compute_transfers(&mut tasks, &channels, TimeUnit::Ms);
    // Budgets must cover the (now aggregated) demand and fit the period.
    for t in &mut tasks {
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
    // Chains: random walks forward along edges.
    let consumers = {
        let mut c = vec![Vec::new(); n];
        for (ci, t) in tasks.iter().enumerate() {
            for &p in &t.reads {
                if p < ci {
                    c[p].push(ci);
                }
            }
        }
        c
    };
    let mut chains = Vec::new();
    for _ in 0..cfg.chains {
        let mut cur = rng.range(0, n_sources as u64 - 1) as usize;
        let len = rng.range(2, 15) as usize;
        let mut path = vec![cur];
        while path.len() < len && !consumers[cur].is_empty() {
            cur = consumers[cur][rng.range(0, consumers[cur].len() as u64 - 1) as usize];
            path.push(cur);
        }
        chains.push(Chain {
            name: None,
            path,
            reaction: None,
            freshness: None,
        });
    }
    Spec {
        name: format!("random-{seed}"),
        time_unit: TimeUnit::Ms,
        scheduler: cfg.scheduler,
        schedulability: match cfg.scheduler {
            Scheduler::Rm => SchedTest::Rta,
            Scheduler::Edf => SchedTest::Edf,
        },
        resolution: 1_000_000,
        harmonic: false,
        channels,
        tasks,
        chains,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
