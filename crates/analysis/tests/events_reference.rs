//! The analysis of threads and data-triggered tasks against a brute-force
//! reference: a small discrete-event simulator of the model's semantics
//! written here, independent of the analysis (threads run their jobs one
//! at a time in release order, threads and thread-less tasks preempt each
//! other by rank, a release while a job of the task is queued and not
//! started joins it, a data-triggered task is released at its triggers'
//! publications, jobs read at their start and publish at completion). No
//! simulated job may respond later than its task's R, and no chain's
//! observed reaction or freshness, from the read or from the event, may
//! exceed its sound bound. The simulator of the `sim` crate checks the
//! same against its own engine (`sim/tests`).

use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
use rtpipe_model::{Join, Nanos, Spec};
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap, VecDeque};

/// The reference's own stream of draws (the workspace's seeded generator,
/// which no analysis code reads).
struct Rng(rtpipe_model::gen::Rng);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// Uniform in [lo, hi].
    fn range(&mut self, lo: Nanos, hi: Nanos) -> Nanos {
        if hi <= lo {
            return lo;
        }
        lo + (self.next() % (hi - lo + 1) as u64) as Nanos
    }
}

struct Job {
    task: usize,
    /// The first release (nominal for a periodic task).
    release: Nanos,
    left: Nanos,
    started: bool,
    /// Per (chain, stage) of the task: the head read time it carries.
    stamps: Vec<Option<Nanos>>,
}

/// What one chain observed: head reads and, per sample (its head read
/// time), the first and last tail output carrying it.
#[derive(Default)]
struct ChainLog {
    reads: Vec<Nanos>,
    outputs: BTreeMap<Nanos, (Nanos, Nanos)>,
}

struct Sim<'a> {
    spec: &'a Spec,
    now: Nanos,
    rng: Rng,
    /// Per task its entity (thread or itself); per entity its rank, CPU
    /// and FIFO queue of job indices.
    entity: Vec<usize>,
    rank: Vec<usize>,
    cpu: Vec<u32>,
    queue: Vec<VecDeque<usize>>,
    jobs: Vec<Job>,
    timers: BinaryHeap<Reverse<(Nanos, usize, Nanos)>>,
    seen: Vec<Vec<bool>>,
    triggered_by: Vec<Vec<usize>>,
    /// Per task its (chain, stage) places.
    places: Vec<Vec<(usize, usize)>>,
    registers: Vec<Vec<Option<Nanos>>>,
    logs: Vec<ChainLog>,
    worst: Vec<Nanos>,
    worst_case: bool,
}

impl<'a> Sim<'a> {
    fn new(spec: &'a Spec, report: &Report, seed: u64) -> Sim<'a> {
        let n = spec.tasks.len();
        let mut entity = vec![0; n];
        let (mut rank, mut cpu) = (Vec::new(), Vec::new());
        let mut of_thread = BTreeMap::new();
        for (i, t) in spec.tasks.iter().enumerate() {
            let id = match t.thread {
                Some(th) => *of_thread.entry(th).or_insert_with(|| {
                    rank.push(report.timing[i].priority.unwrap_or(usize::MAX));
                    cpu.push(t.cpu);
                    rank.len() - 1
                }),
                None => {
                    rank.push(report.timing[i].priority.unwrap_or(usize::MAX));
                    cpu.push(t.cpu);
                    rank.len() - 1
                }
            };
            entity[i] = id;
        }
        let mut places = vec![Vec::new(); n];
        for (k, ch) in spec.chains.iter().enumerate() {
            for (s, &i) in ch.path.iter().enumerate() {
                places[i].push((k, s));
            }
        }
        let mut rng = Rng(rtpipe_model::gen::Rng::new(seed));
        let worst_case = rng.next().is_multiple_of(3);
        let mut sim = Sim {
            spec,
            now: 0,
            rng,
            queue: vec![VecDeque::new(); rank.len()],
            entity,
            rank,
            cpu,
            jobs: Vec::new(),
            timers: BinaryHeap::new(),
            seen: spec
                .tasks
                .iter()
                .map(|t| vec![false; t.triggers().map_or(0, |(tr, _)| tr.len())])
                .collect(),
            triggered_by: spec.triggered_by(),
            places,
            registers: spec
                .chains
                .iter()
                .map(|c| vec![None; c.path.len()])
                .collect(),
            logs: spec.chains.iter().map(|_| ChainLog::default()).collect(),
            worst: vec![0; n],
            worst_case,
        };
        sim.start_timers();
        sim
    }

    fn start_timers(&mut self) {
        for (i, t) in self.spec.tasks.iter().enumerate() {
            if let Some(period) = t.fixed_period() {
                let phase = self.rng.range(0, period - 1);
                self.push_timer(i, phase);
            }
        }
    }

    fn push_timer(&mut self, i: usize, nominal: Nanos) {
        let j = self.rng.range(0, self.spec.tasks[i].jitter);
        self.timers.push(Reverse((nominal + j, i, nominal)));
    }

    fn merging(&self, i: usize) -> bool {
        self.spec.tasks[i].thread.is_some() || self.spec.tasks[i].is_triggered()
    }

    fn release(&mut self, i: usize, at: Nanos) {
        let e = self.entity[i];
        let waiting = self.queue[e]
            .iter()
            .any(|&j| self.jobs[j].task == i && !self.jobs[j].started);
        if self.merging(i) && waiting {
            return;
        }
        let t = &self.spec.tasks[i];
        let left = if self.worst_case || self.rng.next().is_multiple_of(2) {
            t.demand()
        } else {
            self.rng.range(t.demand_min(), t.demand())
        };
        self.jobs.push(Job {
            task: i,
            release: at,
            left: left.max(1),
            started: false,
            stamps: vec![None; self.places[i].len()],
        });
        self.queue[e].push_back(self.jobs.len() - 1);
    }

    /// The job each CPU runs now (the head of its best queue), started.
    fn dispatch(&mut self) -> Vec<usize> {
        let mut best: BTreeMap<u32, usize> = BTreeMap::new();
        for e in 0..self.queue.len() {
            if self.queue[e].is_empty() {
                continue;
            }
            let b = best.entry(self.cpu[e]).or_insert(e);
            if self.rank[e] < self.rank[*b] {
                *b = e;
            }
        }
        let running: Vec<usize> = best.values().map(|&e| self.queue[e][0]).collect();
        for &j in &running {
            if !self.jobs[j].started {
                self.start(j);
            }
        }
        running
    }

    fn start(&mut self, j: usize) {
        self.jobs[j].started = true;
        let i = self.jobs[j].task;
        for (p, &(k, s)) in self.places[i].clone().iter().enumerate() {
            let stamp = if s == 0 {
                self.logs[k].reads.push(self.now);
                Some(self.now)
            } else {
                self.registers[k][s - 1]
            };
            self.jobs[j].stamps[p] = stamp;
        }
    }

    fn complete(&mut self, j: usize) {
        let i = self.jobs[j].task;
        let e = self.entity[i];
        assert_eq!(self.queue[e].pop_front(), Some(j));
        self.worst[i] = self.worst[i].max(self.now - self.jobs[j].release);
        for (p, &(k, s)) in self.places[i].clone().iter().enumerate() {
            let stamp = self.jobs[j].stamps[p];
            self.registers[k][s] = stamp;
            if let (Some(a), true) = (stamp, s + 1 == self.spec.chains[k].path.len()) {
                let now = self.now;
                let o = self.logs[k].outputs.entry(a).or_insert((now, now));
                o.1 = now;
            }
        }
        for c in self.triggered_by[i].clone() {
            let Some((triggers, join)) = self.spec.tasks[c].triggers() else {
                continue;
            };
            let at = triggers.iter().position(|&p| p == i).unwrap_or(0);
            self.seen[c][at] = true;
            if join == Join::Any || self.seen[c].iter().all(|&s| s) {
                self.seen[c].iter_mut().for_each(|s| *s = false);
                self.release(c, self.now);
            }
        }
    }

    fn run(&mut self, horizon: Nanos) {
        while self.now < horizon {
            let running = self.dispatch();
            let next_timer = self.timers.peek().map_or(Nanos::MAX, |r| r.0 .0);
            let next_done = running
                .iter()
                .map(|&j| self.now + self.jobs[j].left)
                .min()
                .unwrap_or(Nanos::MAX);
            let next = next_timer.min(next_done);
            for &j in &running {
                self.jobs[j].left -= next - self.now;
            }
            self.now = next;
            for &j in &running {
                if self.jobs[j].left == 0 {
                    self.complete(j);
                }
            }
            while self.timers.peek().is_some_and(|r| r.0 .0 == self.now) {
                let Some(Reverse((_, i, nominal))) = self.timers.pop() else {
                    break;
                };
                let Some(period) = self.spec.tasks[i].fixed_period() else {
                    continue;
                };
                self.push_timer(i, nominal + period);
                // A periodic job's response counts from its nominal release.
                self.release(i, nominal);
            }
        }
    }
}

/// Observed (reaction, freshness) of chain `k` from the read and from the
/// event, over samples read before `until`.
fn observed(log: &ChainLog, until: Nanos) -> [[Option<Nanos>; 2]; 2] {
    let mut out = [[None; 2]; 2];
    let max =
        |slot: &mut Option<Nanos>, v: Nanos| *slot = Some(slot.map_or(v, |o: Nanos| o.max(v)));
    for (&a, &(first, last)) in log.outputs.range(..until) {
        max(&mut out[0][0], first - a);
        max(&mut out[1][0], last - a);
    }
    // From the event: just after each read, to the first output of a
    // sample read at or after the next one, or the next sample's last.
    let mut earliest_after: Vec<Option<Nanos>> = vec![None; log.reads.len() + 1];
    for (x, &a) in log.reads.iter().enumerate().rev() {
        let own = log.outputs.get(&a).map(|o| o.0);
        earliest_after[x] = match (own, earliest_after[x + 1]) {
            (Some(o), Some(e)) => Some(o.min(e)),
            (o, e) => o.or(e),
        };
    }
    for (x, w) in log.reads.windows(2).enumerate() {
        if w[1] >= until {
            break;
        }
        if let Some(e) = earliest_after[x + 1] {
            max(&mut out[0][1], e - (w[0] + 1));
        }
        if let Some(&(_, last)) = log.outputs.get(&w[1]) {
            max(&mut out[1][1], last - (w[0] + 1));
        }
    }
    out
}

/// Observed / bound per (metric, anchor) and per task, collected.
#[derive(Default)]
struct Tally {
    ratios: BTreeMap<String, Vec<f64>>,
    systems: usize,
}

impl Tally {
    fn add(&mut self, what: &str, seen: Nanos, bound: Nanos) {
        if bound > 0 {
            let r = seen as f64 / bound as f64;
            self.ratios.entry(what.to_string()).or_default().push(r);
        }
    }

    fn print(&self) {
        println!("{} systems", self.systems);
        for (k, v) in &self.ratios {
            let mut v = v.clone();
            v.sort_by(f64::total_cmp);
            println!(
                "{k}: n {}, largest observed/bound: max {:.3}, median {:.3}, min {:.3}",
                v.len(),
                v[v.len() - 1],
                v[v.len() / 2],
                v[0]
            );
        }
    }
}

/// Simulates `spec` and checks every observation against the report.
fn check(spec: &Spec, seed: u64, tally: &mut Tally) {
    let report = analyze(spec);
    let longest = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(1);
    let bound_max = report
        .chains
        .iter()
        .flat_map(|c| Anchor::ALL.map(|a| c.bound.sound(a)))
        .flatten()
        .max()
        .unwrap_or(0);
    // Samples read in the last `margin` may still be carried: left out
    // (a cut margin can only hide an output, never invent one).
    let margin = (bound_max.max(longest) * 2).min(10 * longest);
    let horizon = margin + 30 * longest;
    let mut sim = Sim::new(spec, &report, seed);
    sim.run(horizon);
    tally.systems += 1;
    for (i, t) in spec.tasks.iter().enumerate() {
        if let Some(r) = report.timing[i].job_response_time {
            assert!(
                sim.worst[i] <= r,
                "seed {seed}: task {} responded in {} > R {r}\n{}",
                t.name,
                sim.worst[i],
                rtpipe_model::to_toml(spec)
            );
            tally.add("task R", sim.worst[i], r);
        }
    }
    for c in &report.chains {
        let seen = observed(&sim.logs[c.chain], horizon - margin);
        let m = usize::from(c.metric == Metric::Freshness);
        for (x, anchor) in Anchor::ALL.into_iter().enumerate() {
            let (Some(o), Some(b)) = (seen[m][x], c.bound.sound(anchor)) else {
                continue;
            };
            assert!(
                o <= b,
                "seed {seed}: chain {} {} from the {}: observed {o} > sound {b}\n{}",
                c.chain,
                c.metric.name(),
                anchor.name(),
                rtpipe_model::to_toml(spec)
            );
            tally.add(
                &format!("{} from the {}", c.metric.name(), anchor.name()),
                o,
                b,
            );
        }
    }
}

/// 500 generated systems by default; `RTPIPE_EVENT_SEEDS=1000` for more
/// (docs/analysis.md reports that run's tightness).
#[test]
fn no_simulated_job_or_chain_exceeds_its_bound() {
    let cfg = EventGenConfig::default();
    let seeds: u64 = std::env::var("RTPIPE_EVENT_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(500);
    let mut tally = Tally::default();
    for seed in 0..seeds {
        let spec = event_triggered_system(seed, &cfg);
        check(&spec, seed, &mut tally);
    }
    tally.print();
}
