//! Adversarial search for long latencies.
//!
//! [`search`] looks for the release offsets and execution times that make one
//! chain's observed reaction or freshness as long as it can: random restarts
//! (synchronous, random and grid-aligned offsets) each followed by a local
//! search that perturbs one or a few offsets at several scales, aligns a
//! task's releases with another task's release, read or finish instants near
//! the current worst sample (± small deltas, since ties are where data just
//! misses a job), and switches the demand model. A candidate is accepted when
//! it is at least as bad as the current one (plateaus are crossed). When
//! moving a single offset helps, a line search follows that direction
//! (doubling, then halving the step) to the edge of the ramp: latencies grow
//! linearly as a job is shifted until it catches the data, then drop. The
//! worst candidate seen over all restarts is returned, with the trajectory of
//! improvements.
//!
//! Demands are searched through the simulator's own knobs, without touching
//! it: the [`ExecModel`] (worst, best, extremes, uniform) and the seed that
//! drives the extremes and uniform draws. With [`Phasing::Given`] the seed
//! only feeds the demand streams, and each task has its own stream, so a
//! candidate's demands do not change when only its offsets do.
//!
//! A task with a known offset (`offset` in the spec) keeps it in every
//! candidate: the search moves only the unknown offsets, and the demands.
//!
//! Everything is deterministic per [`SearchConfig::seed`], and the result is
//! replayable: `simulate(spec, &result.config)` reproduces `result.value`.
//!
//! What the search finds is a **lower bound** on the true worst case (an
//! execution that exists), while the analysis' sound bound is an upper bound.
//! [`SearchResult::tightness`] = found / sound bound therefore brackets the
//! truth: a tightness of 1 proves the bound exact for this system, a tightness
//! above 1 is a soundness bug of the analysis (or of the simulator).

use crate::observe::ChainStatsExt;
use crate::Rng;
use crate::{simulate, ExecModel, Jitter, Phasing, SimConfig, SimError};
use rtpipe_analysis::{analyze, Anchor, Metric, OffsetBound};
use rtpipe_joblog::{SimResult, Witness};
use rtpipe_model::{gcd, Nanos, Spec};
use std::fmt;

/// The demand models a candidate may use.
pub const EXEC_MODELS: [ExecModel; 4] = [
    ExecModel::Worst,
    ExecModel::Best,
    ExecModel::Extremes,
    ExecModel::Uniform,
];

/// The release-jitter models a candidate may use (only drawn from when a
/// task has jitter).
pub const JITTER_MODELS: [Jitter; 5] = [
    Jitter::None,
    Jitter::Latest,
    Jitter::Extremes,
    Jitter::Uniform,
    Jitter::Squeezed,
];

/// One point of the search space: everything a run depends on besides the
/// spec and the horizon.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Candidate {
    /// φ_i in [0, T_i) for a task whose offset is unknown, its known offset
    /// otherwise; one per task.
    pub offsets: Vec<Nanos>,
    /// The demand model of the run.
    pub exec: ExecModel,
    /// Seeds the demand draws of [`ExecModel::Extremes`] and [`ExecModel::Uniform`].
    pub seed: u64,
    /// Where jittered jobs are released (the seed draws them too).
    pub jitter: Jitter,
}

impl Candidate {
    /// The simulator configuration that runs this candidate.
    pub fn config(&self, horizon: Nanos) -> SimConfig {
        SimConfig {
            horizon,
            seed: self.seed,
            phasing: Phasing::Given(self.offsets.clone()),
            exec: self.exec,
            jitter: self.jitter,
            log_jobs: false,
        }
    }
}

/// What to search for, and how long.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SearchConfig {
    /// Index into `spec.chains` of the chain whose latency is maximised.
    pub chain: usize,
    /// Which metric is maximised.
    pub metric: Metric,
    /// Measured from the head's read or from the event.
    pub anchor: Anchor,
    /// Local searches, each from its own starting point.
    pub restarts: u32,
    /// Candidates tried per local search (after its starting point).
    pub steps: u32,
    /// Simulated span of every run.
    pub horizon: Nanos,
    /// Seeds the search's random choices.
    pub seed: u64,
    /// Starting points of the first restarts (say, the worst runs of an
    /// earlier experiment); further restarts start from generated points.
    pub start: Vec<Candidate>,
}

impl SearchConfig {
    /// 4 restarts of 50 steps, seed 0, no given starting point, from the read.
    pub fn new(chain: usize, metric: Metric, horizon: Nanos) -> SearchConfig {
        SearchConfig {
            chain,
            metric,
            anchor: Anchor::Read,
            restarts: 4,
            steps: 50,
            horizon,
            seed: 0,
            start: Vec::new(),
        }
    }
}

/// The best value after some number of simulations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Simulations run so far (1 = the first one).
    pub simulation: u64,
    /// The restart in which it was found.
    pub restart: u32,
    /// The best value then.
    pub value: Nanos,
}

/// The worst latency the search found, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchResult {
    /// Index into `spec.chains`.
    pub chain: usize,
    /// The metric.
    pub metric: Metric,
    /// The anchor it is measured from.
    pub anchor: Anchor,
    /// The longest latency found; `None` when no run finalised a sample of
    /// the chain (the horizon is too short).
    pub value: Option<Nanos>,
    /// The candidate that produced it (the first one, on ties).
    pub best: Candidate,
    /// `best` as a simulator configuration: replays `value` exactly.
    pub config: SimConfig,
    /// The sample that produced `value`.
    pub witness: Option<Witness>,
    /// Simulations run, counting the replays with a job log that the
    /// alignment moves need.
    pub simulations: u64,
    /// Events processed over all simulations.
    pub events: u64,
    /// Every improvement of the best value, in order.
    pub trajectory: Vec<Progress>,
    /// The analysis' bounds for this chain, metric and anchor.
    pub sound: Option<Nanos>,
    /// The paper bound.
    pub paper: Option<Nanos>,
    /// The bound under the spec's known release offsets, when the chain has
    /// any: the one every run of the search must respect.
    pub known: Option<OffsetBound>,
}

impl SearchResult {
    /// Found / sound bound: ≤ 1 unless the analysis is unsound; the closer to
    /// 1, the tighter the bound is shown to be. `None` without a value or a
    /// sound bound.
    pub fn tightness(&self) -> Option<f64> {
        match (self.value, self.sound) {
            (Some(v), Some(b)) if b > 0 => Some(v as f64 / b as f64),
            _ => None,
        }
    }

    /// Whether the found latency exceeds the sound bound that holds for the
    /// search's runs (an analysis bug): the known-offset bound when the
    /// chain has one, the arbitrary-phasing one otherwise.
    pub fn exceeds_sound(&self) -> bool {
        match (&self.known, self.value) {
            (Some(k), Some(v)) => k.exceeded_by(v),
            (None, Some(v)) => self.sound.is_some_and(|b| v > b),
            (_, None) => false,
        }
    }

    /// Found / known-offset bound, when the chain has one.
    pub fn tightness_known(&self) -> Option<f64> {
        match (self.value, self.known.as_ref().and_then(|k| k.value)) {
            (Some(v), Some(b)) if b > 0 => Some(v as f64 / b as f64),
            _ => None,
        }
    }
}

impl fmt::Display for SearchResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chain {} {} from the {}: ",
            self.chain,
            self.metric.name(),
            self.anchor.name()
        )?;
        match self.value {
            Some(v) => write!(f, "found {v} ns")?,
            None => write!(f, "no finalised sample")?,
        }
        match self.sound {
            Some(b) => write!(f, ", sound bound {b} ns")?,
            None => write!(f, ", no sound bound")?,
        }
        if let Some(t) = self.tightness() {
            write!(f, ", tightness {t:.4}")?;
        }
        write!(
            f,
            " ({} simulations, {} improvements; replay: {:?}, seed {}, offsets {:?})",
            self.simulations,
            self.trajectory.len(),
            self.best.exec,
            self.best.seed,
            self.best.offsets
        )
    }
}

/// Maximises the observed latency of `cfg.chain` in `cfg.metric`.
pub fn search(spec: &Spec, cfg: &SearchConfig) -> Result<SearchResult, SimError> {
    search_with(spec, cfg, |_, _| {})
}

/// [`search`], calling `observe` with every run it evaluates (not with the
/// replays that only fetch a job log), e.g. to check other bounds on the way.
pub fn search_with(
    spec: &Spec,
    cfg: &SearchConfig,
    observe: impl FnMut(&SimConfig, &SimResult),
) -> Result<SearchResult, SimError> {
    let periods = checked_periods(spec, cfg)?;
    let mut s = Searcher::new(spec, cfg, periods, observe);
    for r in 0..cfg.restarts {
        let start = match cfg.start.get(r as usize) {
            Some(c) => c.clone(),
            None => s.generated_start(r as usize - cfg.start.len().min(r as usize)),
        };
        s.local_search(r, start)?;
    }
    Ok(s.result())
}

/// The tasks' periods, once the configuration is known to fit the spec.
fn checked_periods(spec: &Spec, cfg: &SearchConfig) -> Result<Vec<Nanos>, SimError> {
    if cfg.chain >= spec.chains.len() {
        return Err(SimError::BadChain(cfg.chain));
    }
    if cfg.horizon <= 0 {
        return Err(SimError::HorizonNotPositive(cfg.horizon));
    }
    let mut periods = Vec::with_capacity(spec.tasks.len());
    for (i, t) in spec.tasks.iter().enumerate() {
        // A data-triggered task has no offset to move: its nominal period
        // only scales the search's steps.
        let period = match t.is_triggered() {
            true => spec.activation_period(i),
            false => t.fixed_period(),
        };
        match period {
            Some(p) if p > 0 => periods.push(p),
            _ => return Err(SimError::NoPeriod(t.name.clone())),
        }
    }
    if let Some(c) = cfg.start.iter().find(|c| c.offsets.len() != periods.len()) {
        return Err(SimError::BadOffsets {
            expected: periods.len(),
            found: c.offsets.len(),
        });
    }
    Ok(periods)
}

/// Instants of the jobs near a run's worst sample (see `instants`).
#[derive(Default)]
struct Log {
    /// Release, read and finish instants, by task.
    all: Vec<(usize, Nanos)>,
    /// Read instants only, by task.
    reads: Vec<(usize, Nanos)>,
}

/// A candidate and what it produced.
#[derive(Clone)]
struct Scored {
    cand: Candidate,
    value: Option<Nanos>,
    witness: Option<Witness>,
}

struct Searcher<'a, F> {
    spec: &'a Spec,
    cfg: &'a SearchConfig,
    periods: Vec<Nanos>,
    demands: Vec<Nanos>,
    /// Grids for aligned starts: gcd of the periods, and of periods and demands.
    grids: [Nanos; 2],
    chain_tasks: Vec<usize>,
    /// Rate-monotonic ranks (1 highest; `None` in the background).
    prio: Vec<Option<usize>>,
    /// Some task has release jitter: the search also moves the jitter model.
    jittered: bool,
    /// Known offsets (`offset` in the spec), which no candidate changes.
    fixed: Vec<Option<Nanos>>,
    /// The tasks whose offset the search may move.
    movable: Vec<usize>,
    /// Longest period on the chain: how far before a sample's read to look
    /// for instants to align with.
    t_max: Nanos,
    rng: Rng,
    observe: F,
    simulations: u64,
    events: u64,
    best: Option<Scored>,
    trajectory: Vec<Progress>,
}

impl<'a, F: FnMut(&SimConfig, &SimResult)> Searcher<'a, F> {
    fn new(spec: &'a Spec, cfg: &'a SearchConfig, periods: Vec<Nanos>, observe: F) -> Self {
        let demands: Vec<Nanos> = spec.tasks.iter().map(|t| t.demand().max(0)).collect();
        let gcd_periods = periods.iter().fold(0, |g, &p| gcd(g, p));
        let gcd_all = spec
            .tasks
            .iter()
            .flat_map(|t| [t.demand(), t.demand_min()])
            .filter(|&x| x > 0)
            .fold(gcd_periods, gcd);
        let chain_tasks = spec.chains[cfg.chain].path.clone();
        // Known offsets, and data-triggered tasks' (none: 0, which the
        // simulator requires).
        let fixed: Vec<Option<Nanos>> = spec
            .tasks
            .iter()
            .map(|t| if t.is_triggered() { Some(0) } else { t.offset })
            .collect();
        let movable: Vec<usize> = (0..fixed.len()).filter(|&i| fixed[i].is_none()).collect();
        let t_max = chain_tasks
            .iter()
            .filter_map(|&i| periods.get(i).copied())
            .max()
            .unwrap_or(1);
        Searcher {
            spec,
            cfg,
            periods,
            demands,
            grids: [gcd_periods, gcd_all],
            chain_tasks,
            prio: rtpipe_model::policy::ranks(spec),
            jittered: spec.tasks.iter().any(|t| t.jitter > 0),
            fixed,
            movable,
            t_max,
            rng: Rng::new(cfg.seed ^ 0x5EA2_C4ED_0F7A_11E5),
            observe,
            simulations: 0,
            events: 0,
            best: None,
            trajectory: Vec::new(),
        }
    }

    /// The best run found, with the analysis' bounds for its quantity.
    fn result(self) -> SearchResult {
        let (spec, cfg) = (self.spec, self.cfg);
        let report = analyze(spec);
        let (sound, paper) = report
            .chains
            .iter()
            .find(|c| c.chain == cfg.chain && c.metric == cfg.metric)
            .map_or((None, None), |c| {
                let a = cfg.anchor;
                (c.bound.sound(a), Some(c.bound.paper(a)))
            });
        let known = report
            .offset_bound(cfg.chain, cfg.metric, cfg.anchor)
            .cloned();
        let (best, value, witness) = match &self.best {
            Some(b) => (b.cand.clone(), b.value, b.witness),
            // No restart at all: report the synchronous worst case, unevaluated.
            None => (
                self.pinned(Candidate {
                    offsets: vec![0; self.periods.len()],
                    exec: ExecModel::Worst,
                    seed: cfg.seed,
                    jitter: Jitter::Uniform,
                }),
                None,
                None,
            ),
        };
        SearchResult {
            chain: cfg.chain,
            metric: cfg.metric,
            anchor: cfg.anchor,
            value,
            config: best.config(cfg.horizon),
            best,
            witness,
            simulations: self.simulations,
            events: self.events,
            trajectory: self.trajectory,
            sound,
            paper,
            known,
        }
    }

    fn n(&self) -> usize {
        self.periods.len()
    }

    fn below(&mut self, bound: Nanos) -> Nanos {
        self.rng.range(0, bound.max(1) as u64 - 1) as Nanos
    }

    fn pick_task(&mut self) -> usize {
        // Half the time a task of the chain, otherwise any (interference).
        let i = if !self.chain_tasks.is_empty() && self.rng.chance(0.5) {
            let k = self.rng.range(0, self.chain_tasks.len() as u64 - 1) as usize;
            self.chain_tasks[k]
        } else {
            self.rng.range(0, self.n() as u64 - 1) as usize
        };
        // A known offset cannot move: any task whose offset can instead
        // (only specs with known offsets draw here).
        if self.fixed[i].is_some() && !self.movable.is_empty() {
            let k = self.rng.range(0, self.movable.len() as u64 - 1) as usize;
            return self.movable[k];
        }
        i
    }

    /// `cand` with every known offset in place.
    fn pinned(&self, mut cand: Candidate) -> Candidate {
        for (o, f) in cand.offsets.iter_mut().zip(&self.fixed) {
            if let Some(f) = f {
                *o = *f;
            }
        }
        cand
    }

    fn random_jitter(&mut self) -> Jitter {
        JITTER_MODELS[self.rng.range(0, JITTER_MODELS.len() as u64 - 1) as usize]
    }

    fn random_exec(&mut self) -> ExecModel {
        EXEC_MODELS[self.rng.range(0, EXEC_MODELS.len() as u64 - 1) as usize]
    }

    /// Starting point of the k-th generated restart: synchronous (the first
    /// one with worst-case demands), random, grid-aligned, random, ….
    fn generated_start(&mut self, k: usize) -> Candidate {
        let n = self.n();
        let offsets = match k % 4 {
            0 => vec![0; n],
            2 => {
                let g = self.grids[self.rng.range(0, 1) as usize].max(1);
                (0..n)
                    .map(|i| {
                        let slots = (self.periods[i] - 1) / g;
                        self.rng.range(0, slots as u64) as Nanos * g
                    })
                    .collect()
            }
            _ => (0..n).map(|i| self.below(self.periods[i])).collect(),
        };
        let exec = if k == 0 {
            ExecModel::Worst
        } else {
            self.random_exec()
        };
        let seed = self.rng.next_u64();
        // Jitter draws only where a task has some, so that jitter-free
        // specs search exactly as before: the nominal releases first, the
        // latest ones next, then late and on time in turn, then any model.
        let jitter = match k {
            _ if !self.jittered => Jitter::Uniform,
            0 => Jitter::None,
            1 => Jitter::Latest,
            2 => Jitter::Squeezed,
            _ => self.random_jitter(),
        };
        let cand = Candidate {
            offsets,
            exec,
            seed,
            jitter,
        };
        self.pinned(cand)
    }

    fn evaluate(&mut self, restart: u32, cand: Candidate) -> Result<Scored, SimError> {
        let sim_cfg = cand.config(self.cfg.horizon);
        let res = simulate(self.spec, &sim_cfg)?;
        self.simulations += 1;
        self.events += res.events;
        (self.observe)(&sim_cfg, &res);
        let cs = &res.chains[self.cfg.chain];
        let seen = cs.observed(self.cfg.metric, self.cfg.anchor);
        let (value, witness) = (seen.max, seen.witness);
        let scored = Scored {
            cand,
            value,
            witness,
        };
        let improves = match &self.best {
            Some(b) => value > b.value,
            None => true,
        };
        if improves {
            if let Some(v) = value {
                self.trajectory.push(Progress {
                    simulation: self.simulations,
                    restart,
                    value: v,
                });
            }
            self.best = Some(scored.clone());
        }
        Ok(scored)
    }

    /// Release, read and finish instants of every job near the witness of
    /// `cur` (the whole run when there is none), from a replay with a job log.
    /// The replay stops at the witness' last output: runs are causal, so the
    /// schedule up to there is the same, for a fraction of the cost.
    fn instants(&mut self, cur: &Scored) -> Result<Log, SimError> {
        let horizon = match cur.witness {
            Some(w) => w.last.clamp(1, self.cfg.horizon),
            None => self.cfg.horizon,
        };
        let sim_cfg = SimConfig {
            log_jobs: true,
            ..cur.cand.config(horizon)
        };
        let res = simulate(self.spec, &sim_cfg)?;
        self.simulations += 1;
        self.events += res.events;
        let (lo, hi) = match cur.witness {
            Some(w) => (w.read - 2 * self.t_max, w.last),
            None => (Nanos::MIN, Nanos::MAX),
        };
        let mut out = Log::default();
        for j in &res.jobs {
            for x in [j.release, j.read, j.finish] {
                if (lo..=hi).contains(&x) {
                    out.all.push((j.task, x));
                }
            }
            if (lo..=hi).contains(&j.read) {
                out.reads.push((j.task, j.read));
            }
        }
        Ok(out)
    }

    /// Every task that preempts a chain task is released just after one of
    /// that task's reads near the worst sample, so the job meets the whole
    /// interference of its response time after its read: the worst case of
    /// a from-read latency, which perturbing one offset at a time rarely
    /// reaches on a busy CPU.
    fn burst(&mut self, cand: &mut Candidate, log: &Log) {
        let c = self.chain_tasks[self.rng.range(0, self.chain_tasks.len() as u64 - 1) as usize];
        let reads: Vec<Nanos> = log
            .reads
            .iter()
            .filter(|&&(k, _)| k == c)
            .map(|&(_, x)| x)
            .collect();
        if reads.is_empty() {
            return;
        }
        let x = reads[self.rng.range(0, reads.len() as u64 - 1) as usize];
        let Some(pc) = self.prio[c] else { return };
        for j in 0..self.n() {
            let above = self.prio[j].is_some_and(|pj| pj < pc);
            let free = self.fixed[j].is_none();
            if above && free && self.spec.tasks[j].cpu == self.spec.tasks[c].cpu {
                // Half the time J_j earlier, for a late job (all under
                // `Latest`, one in two under `Squeezed`) to come just then.
                let late = matches!(cand.jitter, Jitter::Latest | Jitter::Squeezed);
                let early = late && self.rng.chance(0.5);
                let d =
                    1 + self.small_delta(j).max(0) - self.spec.tasks[j].jitter * i64::from(early);
                cand.offsets[j] = (x + d).rem_euclid(self.periods[j]);
            }
        }
    }

    /// 0 most of the time, else ±1 ns or ± up to a quarter of a demand: the
    /// instants around a tie decide whether a job sees a value.
    fn small_delta(&mut self, task: usize) -> Nanos {
        match self.rng.range(0, 5) {
            0 | 1 => 0,
            2 => -1,
            3 => 1,
            _ => {
                let d = self.rng.range(1, (self.demands[task] / 4).max(1) as u64) as Nanos;
                if self.rng.chance(0.5) {
                    d
                } else {
                    -d
                }
            }
        }
    }

    /// A perturbation of one offset by ±d, d log-uniform-ish between 1 ns
    /// and `scale` (a period, a demand): every scale gets its share of tries.
    fn nudge(&mut self, offsets: &mut [Nanos], i: usize, scale: Nanos) {
        let t = self.periods[i];
        let bits = 64 - (scale.max(1) as u64).leading_zeros();
        let top = 1u64 << self.rng.range(0, u64::from(bits));
        let d = self.rng.range(1, top.min(scale.max(1) as u64).max(1)) as Nanos;
        let x = if self.rng.chance(0.5) {
            offsets[i] + d
        } else {
            offsets[i] - d
        };
        offsets[i] = x.rem_euclid(t);
    }

    /// A task to align task i with: half the time a neighbour of i on the
    /// chain (where data is handed over), otherwise any other task.
    fn partner(&mut self, i: usize) -> usize {
        let n = self.n();
        if self.rng.chance(0.5) {
            let near: Vec<usize> = self
                .chain_tasks
                .windows(2)
                .filter_map(|w| match (w[0] == i, w[1] == i) {
                    (true, false) => Some(w[1]),
                    (false, true) => Some(w[0]),
                    _ => None,
                })
                .collect();
            if !near.is_empty() {
                return near[self.rng.range(0, near.len() as u64 - 1) as usize];
            }
        }
        if n > 1 {
            let j = self.rng.range(0, n as u64 - 2) as usize;
            j + usize::from(j >= i)
        } else {
            i
        }
    }

    /// Demands: 12 % of the moves change them alone, 8 % together with an
    /// offset move; with every offset known, every move changes them alone
    /// (they are all there is to search). True when the move is complete.
    fn demand_move(&mut self, cand: &mut Candidate) -> bool {
        let r = self.rng.unit();
        let all_known = self.movable.is_empty() && self.n() > 0;
        if r < 0.2 || all_known {
            cand.exec = self.random_exec();
            cand.seed = self.rng.next_u64();
            if self.jittered {
                cand.jitter = self.random_jitter();
            }
            return r < 0.12 || all_known;
        }
        false
    }

    /// A neighbour of `cur`. `log` caches the instants of `cur`'s run.
    fn neighbour(&mut self, cur: &Scored, log: &mut Option<Log>) -> Result<Candidate, SimError> {
        let mut cand = cur.cand.clone();
        let n = self.n();
        if self.demand_move(&mut cand) || n == 0 {
            return Ok(cand);
        }
        // Interference bursts after a chain task's read: 10 % of the offset moves.
        if self.rng.chance(0.1) {
            if log.is_none() {
                *log = Some(self.instants(cur)?);
            }
            if let Some(l) = log.as_ref() {
                self.burst(&mut cand, l);
            }
            return Ok(cand);
        }
        let i = self.pick_task();
        let t = self.periods[i];
        match self.rng.range(0, 9) {
            // Anywhere in the period.
            0 => cand.offsets[i] = self.below(t),
            // One offset, at the scale of a period or of a demand.
            1..=3 => {
                let scale = if self.rng.chance(0.5) {
                    t
                } else {
                    let j = self.partner(i);
                    self.demands[j].max(self.demands[i])
                };
                self.nudge(&mut cand.offsets, i, scale);
            }
            // A few offsets.
            4 => {
                let k = self.rng.range(2, 3.min(n as u64).max(2));
                for _ in 0..k {
                    let j = self.rng.range(0, n as u64 - 1) as usize;
                    let scale = if self.rng.chance(0.5) {
                        self.periods[j]
                    } else {
                        self.demands[j]
                    };
                    self.nudge(&mut cand.offsets, j, scale);
                }
            }
            // Release with a release of another task near the worst sample.
            5 | 6 => cand.offsets[i] = self.near_release(cur, &cand.offsets, i),
            // Release at a read or finish (or release) instant of another
            // task's job near the worst sample, from the run's job log.
            _ => {
                if log.is_none() {
                    *log = Some(self.instants(cur)?);
                }
                let inst = log.as_ref().map_or(&[][..], |l| &l.all[..]);
                cand.offsets[i] = self.at_instant(inst, i);
            }
        }
        Ok(self.pinned(cand))
    }

    /// An offset for task i that releases it with a release of a partner
    /// near `cur`'s worst sample (± a small delta).
    fn near_release(&mut self, cur: &Scored, offsets: &[Nanos], i: usize) -> Nanos {
        let j = self.partner(i);
        let (tj, phj) = (self.periods[j], offsets[j]);
        let k = match cur.witness {
            Some(w) => {
                let lo = (w.read - 2 * self.t_max - phj).div_euclid(tj) + 1;
                let hi = (w.last - phj).div_euclid(tj).max(lo);
                lo + self.rng.range(0, (hi - lo) as u64) as Nanos
            }
            None => self.rng.range(0, 3) as Nanos,
        };
        let d = self.small_delta(j);
        (phj + k * tj + d).rem_euclid(self.periods[i])
    }

    /// An offset for task i that releases it at one of a partner's logged
    /// instants (any other task's when the partner has none; anywhere when
    /// the log is empty), ± a small delta.
    fn at_instant(&mut self, inst: &[(usize, Nanos)], i: usize) -> Nanos {
        let t = self.periods[i];
        let j = self.partner(i);
        let mut pool: Vec<Nanos> = inst
            .iter()
            .filter(|&&(k, _)| k == j)
            .map(|&(_, x)| x)
            .collect();
        if pool.is_empty() {
            pool = inst
                .iter()
                .filter(|&&(k, _)| k != i)
                .map(|&(_, x)| x)
                .collect();
        }
        if pool.is_empty() {
            return self.below(t);
        }
        let x = pool[self.rng.range(0, pool.len() as u64 - 1) as usize];
        let d = self.small_delta(j);
        (x + d).rem_euclid(t)
    }

    /// Hill climbing from `start`. When a move of a single offset makes
    /// things strictly worse for the system (better for us), a line search
    /// follows it: the same step again, doubled while it keeps helping and
    /// halved when it overshoots. Latencies are often ramps that end in a
    /// cliff (a job shifted later until it catches the data), and this finds
    /// the edge to the nanosecond in a logarithmic number of runs.
    fn local_search(&mut self, restart: u32, start: Candidate) -> Result<(), SimError> {
        let start = self.pinned(start);
        let mut cur = self.evaluate(restart, start)?;
        let mut log = None;
        let mut line: Option<(usize, Nanos)> = None;
        for _ in 0..self.cfg.steps {
            let cand = match line {
                Some((i, step)) => {
                    let mut c = cur.cand.clone();
                    c.offsets[i] = (c.offsets[i] + step).rem_euclid(self.periods[i]);
                    self.pinned(c)
                }
                None => self.neighbour(&cur, &mut log)?,
            };
            let next = self.evaluate(restart, cand)?;
            let moved: Vec<usize> = (0..self.n())
                .filter(|&k| next.cand.offsets[k] != cur.cand.offsets[k])
                .collect();
            let better = next.value > cur.value;
            line = match (line, better || next.value == cur.value) {
                (Some((i, step)), true) => Some((i, 2 * step)),
                (Some((i, step)), false) => Some((i, step / 2)).filter(|&(_, s)| s != 0),
                (None, true) if better && moved.len() == 1 && next.cand.exec == cur.cand.exec => {
                    let i = moved[0];
                    let t = self.periods[i];
                    // The shorter way around the period.
                    let d = (next.cand.offsets[i] - cur.cand.offsets[i]).rem_euclid(t);
                    Some((i, if 2 * d > t { d - t } else { d }))
                }
                (None, _) => None,
            };
            if next.value >= cur.value {
                if next.cand != cur.cand {
                    log = None;
                }
                cur = next;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtpipe_model::{Scheduler, Task};

    /// The hand-traced tests' task, with a best-case demand.
    fn task(period: Nanos, exec: Nanos, exec_min: Nanos, reads: &[usize], cpu: u32) -> Task {
        Task {
            exec_min,
            ..crate::tests::task(period, exec, reads, cpu)
        }
    }

    fn spec(tasks: Vec<Task>, chains: &[&[usize]]) -> Spec {
        crate::tests::spec(Scheduler::Rm, tasks, chains)
    }

    /// Producer t0 (T = 10 000, demand 500..=2000, CPU 0) → consumer t1
    /// (T = 10 000, demand 1000..=3000, CPU 1). Each runs alone on its CPU,
    /// so jobs read at release and publish `demand` later.
    ///
    /// Let d = (φ1 − φ0) mod T. Sample k is read at r = φ0 + kT and published
    /// at r + x0 (x0 its demand); t1 releases (and reads) at r + d + mT. If
    /// x0 ≤ d the sample is read at r + d, so reaction = d + x1 ≤ T − 1 + C1;
    /// otherwise at r + d + T, so reaction = d + T + x1 with d < x0 ≤ C0.
    /// Worst case: d = C0 − 1, x0 = C0, x1 = C1:
    /// reaction = T + C0 + C1 − 1 = 14 999 ns (synchronous: T + C1 = 13 000).
    /// A sample is read by at most two t1 jobs, the second one at r + d + T
    /// when the next sample is not yet out (x0' > d), so freshness has the
    /// same maximum. The sound bound is R0 + T1 + R1 = 15 000.
    fn two_cpus() -> Spec {
        spec(
            vec![
                task(10_000, 2_000, 500, &[], 0),
                task(10_000, 3_000, 1_000, &[0], 1),
            ],
            &[&[0, 1]],
        )
    }

    fn cfg(metric: Metric, seed: u64) -> SearchConfig {
        SearchConfig {
            restarts: 3,
            steps: 60,
            seed,
            ..SearchConfig::new(0, metric, 100_000)
        }
    }

    #[test]
    fn reaches_the_analytical_worst_case() {
        let s = two_cpus();
        for metric in [Metric::Reaction, Metric::Freshness] {
            let r = match search(&s, &cfg(metric, 7)) {
                Ok(r) => r,
                Err(e) => panic!("{e}"),
            };
            assert_eq!(r.value, Some(14_999), "{metric:?}: {r}");
            assert_eq!(r.sound, Some(15_000));
            assert!(!r.exceeds_sound());
            assert!(r.tightness().is_some_and(|t| t > 0.9999));
            // The first restart is synchronous with worst-case demands.
            assert_eq!(r.trajectory[0].simulation, 1);
            assert_eq!(r.trajectory[0].value, 13_000);
            assert!(r.trajectory.windows(2).all(|w| w[0].value < w[1].value));
            assert_eq!(r.trajectory.last().map(|p| p.value), r.value);
            // The offsets differ by C0 − 1 and the run replays.
            let (o, t) = (&r.best.offsets, 10_000);
            assert_eq!((o[1] - o[0]).rem_euclid(t), 1_999);
            let replay = simulate(&s, &r.config).unwrap_or_else(|e| panic!("{e}"));
            let c = &replay.chains[0];
            let seen = c.observed(metric, Anchor::Read);
            assert_eq!((seen.max, seen.witness), (r.value, r.witness));
        }
    }

    /// One CPU under RM: producer t0 (T = 20 000, demand 4 000, rank 2) →
    /// consumer t1 (T = 10 000, demand 1 000, rank 1, preempts t0). Let
    /// d = (φ1 − φ0) mod 10 000, the same for every t0 job r (20 000 is two
    /// consumer periods).
    ///
    /// - 0 < d < 4 000: t0 reads at r, t1 preempts it at r + d (reading the
    ///   old value), t0 publishes at r + 5 000, the next t1 job reads at
    ///   r + d + 10 000 and outputs 1 000 later: reaction = d + 11 000.
    /// - d = 0: t1 runs first, t0 reads at r + 1 000 and publishes at
    ///   r + 5 000; output at r + 11 000: reaction 10 000 (synchronous).
    /// - 4 000 ≤ d ≤ 9 000: t0 publishes at r + 4 000 ≤ r + d (a tie publishes
    ///   first), so reaction = d + 1 000 ≤ 10 000.
    /// - d > 9 000: t0 reads when t1's job ends at s = r + d − 9 000 and
    ///   publishes at s + 4 000 < r + d; reaction = r + d + 1 000 − s = 10 000.
    ///
    /// Worst case d = 3 999: 14 999 ns, a 1 ns-wide edge before the cliff.
    /// The sound bound is R0 + (T1 − x_min(t1) + R1) = 5 000 + 10 000.
    #[test]
    fn finds_the_preemption_edge_on_one_cpu() {
        let s = spec(
            vec![
                task(20_000, 4_000, 4_000, &[], 0),
                task(10_000, 1_000, 1_000, &[0], 0),
            ],
            &[&[0, 1]],
        );
        let r = search(&s, &cfg(Metric::Reaction, 11)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.value, Some(14_999), "{r}");
        assert_eq!(r.trajectory[0].value, 10_000);
        assert_eq!(r.sound, Some(15_000));
        let o = &r.best.offsets;
        assert_eq!((o[1] - o[0]).rem_euclid(10_000), 3_999);
    }

    #[test]
    fn deterministic_per_seed() {
        let s = two_cpus();
        let mut seen = 0;
        let a = search_with(&s, &cfg(Metric::Reaction, 3), |_, _| seen += 1);
        let b = search(&s, &cfg(Metric::Reaction, 3));
        assert_eq!(a, b);
        let a = a.unwrap_or_else(|e| panic!("{e}"));
        // Every evaluated run is observed; the job-log replays come on top.
        assert_eq!(seen, 3 * 61);
        assert!(a.simulations >= seen);
        let c = search(&s, &cfg(Metric::Reaction, 4)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.value, a.value);
        assert_ne!(c.trajectory, a.trajectory);
    }

    #[test]
    fn starts_and_errors() {
        let s = two_cpus();
        let given = Candidate {
            offsets: vec![0, 1_999],
            exec: ExecModel::Worst,
            seed: 0,
            jitter: Jitter::Uniform,
        };
        let c = SearchConfig {
            restarts: 1,
            steps: 0,
            start: vec![given.clone()],
            ..SearchConfig::new(0, Metric::Reaction, 100_000)
        };
        let r = search(&s, &c).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((r.value, r.simulations), (Some(14_999), 1));
        assert_eq!(r.best, given);
        let bad = SearchConfig {
            chain: 1,
            ..c.clone()
        };
        assert_eq!(search(&s, &bad), Err(SimError::BadChain(1)));
        let bad = SearchConfig {
            start: vec![Candidate {
                offsets: vec![0],
                ..given
            }],
            ..c
        };
        assert_eq!(
            search(&s, &bad),
            Err(SimError::BadOffsets {
                expected: 2,
                found: 1
            })
        );
    }
}
