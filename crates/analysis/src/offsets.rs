//! Known release offsets: reaction and freshness bounds from job windows.
//!
//! When every task of a chain has a known offset φ (task `offset`, or
//! `[system] release = "synchronous"`), its jobs are released at φ + k·T,
//! and the worst case can be found job by job instead of over every phasing
//! (Becker et al., JSA 2017, the job-level data propagation graph; Kloda et
//! al., ETFA 2018). Each job of a task with response time `R`, demand `x`
//! and least demand `x_min`, released at `r`, reads in `[r, r + R − x]` (F1)
//! and publishes in `[r + x_min, r + R]` (F2). A consumer job may see a
//! producer job when that job may have published before the consumer may
//! read, and surely sees it (or a newer one) when it surely has; between the
//! two the analysis takes both possibilities. The priority facts P1 and P2
//! of docs/analysis.md narrow the windows of a link where they hold.
//!
//! Per head job, the jobs that may carry its sample are an interval at every
//! stage, found by arithmetic, so a head job costs O(chain length). The
//! windows repeat with the hyperperiod H of the chain's tasks once every
//! task has started, so the head jobs released before a warm-up point plus
//! one H cover every head job of the infinite run (docs/analysis.md,
//! "Known release offsets", derives it). Past [`MAX_JOBS`] jobs the analysis
//! falls back to the arbitrary-phasing bound and says so ([`Basis`]).

use crate::latency::{fp_order, ChainAnalysis, LinkTask};
use crate::sched::TaskTiming;
use crate::{Anchor, Metric};
use rtpipe_model::{Nanos, Spec};

/// The most jobs (of the chain's tasks, over the analysed span) the
/// job-level analysis of one chain may take before it falls back to the
/// arbitrary-phasing bound.
pub const MAX_JOBS: u64 = 1_000_000;

/// One value per quantity: each metric measured from the head's read and
/// from the event (docs/analysis.md).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PerQuantity<T> {
    /// Reaction from the head's read.
    pub reaction_read: T,
    /// Freshness from the head's read.
    pub freshness_read: T,
    /// Reaction from the event.
    pub reaction_event: T,
    /// Freshness from the event.
    pub freshness_event: T,
}

impl<T> PerQuantity<T> {
    /// The value of `metric` measured from `anchor`.
    pub fn get(&self, metric: Metric, anchor: Anchor) -> &T {
        match (metric, anchor) {
            (Metric::Reaction, Anchor::Read) => &self.reaction_read,
            (Metric::Freshness, Anchor::Read) => &self.freshness_read,
            (Metric::Reaction, Anchor::Event) => &self.reaction_event,
            (Metric::Freshness, Anchor::Event) => &self.freshness_event,
        }
    }

    fn from_fn(mut f: impl FnMut(Metric, Anchor) -> T) -> PerQuantity<T> {
        PerQuantity {
            reaction_read: f(Metric::Reaction, Anchor::Read),
            freshness_read: f(Metric::Freshness, Anchor::Read),
            reaction_event: f(Metric::Reaction, Anchor::Event),
            freshness_event: f(Metric::Freshness, Anchor::Event),
        }
    }
}

/// Why a chain with known offsets is bounded without them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fallback {
    /// These tasks of the chain (indices into `spec.tasks`) have no known offset.
    UnknownOffsets(Vec<usize>),
    /// The analysed span would hold this many jobs, more than the limit.
    TooManyJobs(u64),
    /// A task of the chain has no response time within its period: no bound.
    Unbounded,
}

/// What a figure rests on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Basis {
    /// The job-level analysis with the spec's offsets.
    KnownOffsets,
    /// The job-level analysis ran, but the arbitrary-phasing bound (which
    /// holds for these offsets too) is lower, and is reported.
    AnyPhasingTighter,
    /// With these offsets no sample reaches the tail: nothing to bound.
    NoSampleReaches,
    /// The arbitrary-phasing bound, because the job-level analysis could
    /// not run.
    AnyPhasing(Fallback),
}

/// One figure under known offsets.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OffsetBound {
    /// The bound; `None` when there is none (see `basis`).
    pub value: Option<Nanos>,
    /// What it rests on.
    pub basis: Basis,
    /// The arbitrary-phasing figure was raised (or replaced) because a task
    /// of the chain starts later than one period: that bound assumes every
    /// task has started (docs/analysis.md, "Known release offsets").
    pub late_start: bool,
}

/// The job-level analysis of one chain, before any comparison.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobLevel {
    /// Least common multiple of the chain's periods.
    pub hyperperiod: Nanos,
    /// Jobs of the chain's tasks released in the analysed span.
    pub jobs: u64,
    /// Head jobs analysed.
    pub head_jobs: u64,
    /// The worst case of each quantity over those head jobs; `None` when
    /// no sample reaches the tail (reaction from the event always has one).
    pub values: PerQuantity<Option<Nanos>>,
}

/// A chain's bounds under the spec's known release offsets.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChainOffsets {
    /// Index of the chain in `Spec::chains`.
    pub chain: usize,
    /// The reported bounds: the job-level figure or the arbitrary-phasing
    /// one, whichever is lower (both hold), or the arbitrary-phasing one
    /// alone when the job-level analysis could not run.
    pub bound: PerQuantity<OffsetBound>,
    /// The job-level analysis, when it ran.
    pub job_level: Option<JobLevel>,
}

impl ChainOffsets {
    /// The reported bound of `metric` from `anchor`.
    pub fn get(&self, metric: Metric, anchor: Anchor) -> &OffsetBound {
        self.bound.get(metric, anchor)
    }
}

impl OffsetBound {
    /// Whether an observed latency `v` breaks this bound: it is above it, or
    /// it exists although no sample reaches the tail.
    pub fn exceeded_by(&self, v: Nanos) -> bool {
        match (&self.basis, self.value) {
            (Basis::NoSampleReaches, _) => true,
            (_, Some(b)) => v > b,
            (_, None) => false,
        }
    }

    /// What the figure rests on, for people: "known offsets", "any phasing
    /// (hyperperiod too long: 2000000 jobs)", ….
    pub fn label(&self, spec: &Spec) -> String {
        let base = match &self.basis {
            Basis::KnownOffsets => "known offsets".to_string(),
            Basis::AnyPhasingTighter => "any phasing (lower than known offsets)".to_string(),
            Basis::NoSampleReaches => "known offsets: no sample reaches the tail".to_string(),
            Basis::AnyPhasing(Fallback::UnknownOffsets(ts)) => {
                let names: Vec<&str> = ts
                    .iter()
                    .map(|&i| spec.tasks.get(i).map_or("?", |t| t.name.as_str()))
                    .collect();
                format!("any phasing (offset unknown: {})", names.join(", "))
            }
            Basis::AnyPhasing(Fallback::TooManyJobs(n)) => {
                format!("any phasing (hyperperiod too long: {n} jobs)")
            }
            Basis::AnyPhasing(Fallback::Unbounded) => "unbounded response time".to_string(),
        };
        if self.late_start {
            format!("{base}, late start")
        } else {
            base
        }
    }
}

/// The chain along `path` under the spec's known offsets; `None` when no
/// task of the chain has one, or the path mixes LET and implicit tasks (the
/// arbitrary-phasing bound is all there is).
/// `any` is the chain's arbitrary-phasing analysis ([`crate::analyze_chain`]);
/// `limit` caps the jobs analysed ([`MAX_JOBS`]).
pub fn chain_offsets(
    spec: &Spec,
    timing: &[TaskTiming],
    chain: usize,
    path: &[usize],
    any: &ChainAnalysis,
    limit: u64,
) -> Option<ChainOffsets> {
    let offsets: Vec<Option<Nanos>> = path.iter().map(|&i| spec.tasks[i].offset).collect();
    if path.is_empty() || offsets.iter().all(Option::is_none) {
        return None;
    }
    // A parsed spec's chain is all LET or all implicit (the model refuses
    // a task on chains of different semantics); a mixed path, which only a
    // spec built in code can declare, has the arbitrary-phasing bound
    // alone (its mixed link terms, docs/analysis.md).
    let lets = path
        .iter()
        .filter(|&&i| spec.task_communication(i) == rtpipe_model::Communication::Let)
        .count();
    if lets != 0 && lets != path.len() {
        return None;
    }
    let valid = any_phasing_valid(spec, timing, path, any);
    let late = late_start_delay(spec, timing, path).is_some();
    let fallback = |f: Fallback| {
        PerQuantity::from_fn(|m, a| OffsetBound {
            value: *valid.get(m, a),
            basis: Basis::AnyPhasing(f.clone()),
            late_start: late && adjusted_for_late_start(m, a),
        })
    };
    let unknown: Vec<usize> = path
        .iter()
        .zip(&offsets)
        .filter(|(_, o)| o.is_none())
        .map(|(&i, _)| i)
        .collect();
    let (bound, job_level) = if !unknown.is_empty() {
        (fallback(Fallback::UnknownOffsets(dedup(unknown))), None)
    } else if lets == path.len() {
        match let_job_level(spec, timing, path, limit) {
            Err(f) => (fallback(f), None),
            Ok(jl) => (let_reported(&jl), Some(jl)),
        }
    } else {
        match job_level(spec, timing, path, limit) {
            Err(f) => (fallback(f), None),
            Ok(jl) => (combine(&jl.values, &valid, late), Some(jl)),
        }
    };
    Some(ChainOffsets {
        chain,
        bound,
        job_level,
    })
}

/// The known-offsets analysis of the chain along `path` under LET
/// ([`chain_offsets`] asks for it): [`exact`](crate::let_bound::exact) on the spec's
/// offsets, when every task completes within its period.
fn let_job_level(
    spec: &Spec,
    timing: &[TaskTiming],
    path: &[usize],
    limit: u64,
) -> Result<JobLevel, Fallback> {
    let lt: Vec<LinkTask> = path
        .iter()
        .map(|&i| LinkTask::new(spec, timing, i))
        .collect();
    // LET's premise: every job completes within its period.
    if lt.iter().any(|x| x.publish().is_none()) {
        return Err(Fallback::Unbounded);
    }
    let chain: Vec<crate::let_bound::LetTask> = path
        .iter()
        .zip(&lt)
        .map(|(&i, x)| crate::let_bound::LetTask {
            t: x.t,
            phi: spec.tasks[i].offset.unwrap_or(0),
        })
        .collect();
    let mut h: Nanos = 1;
    for x in &chain {
        h = (h / rtpipe_model::gcd(h, x.t)).saturating_mul(x.t);
    }
    let (values, head_jobs) = match crate::let_bound::exact(&chain, limit) {
        Ok((l, n)) => (Some(l), n),
        Err(crate::let_bound::NoExact::TooManyJobs(n)) => return Err(Fallback::TooManyJobs(n)),
        Err(crate::let_bound::NoExact::BadChain) => return Err(Fallback::Unbounded),
        Err(crate::let_bound::NoExact::NoSampleReaches) => (None, 0),
    };
    Ok(JobLevel {
        hyperperiod: h,
        jobs: head_jobs,
        head_jobs,
        values: PerQuantity {
            reaction_read: values.map(|l| l.reaction_read),
            freshness_read: values.map(|l| l.freshness_read),
            reaction_event: values.map(|l| l.reaction_event),
            freshness_event: values.map(|l| l.freshness_event),
        },
    })
}

/// The reported figures of a LET job-level analysis: exact, so never
/// replaced by the arbitrary-phasing bound (which is at least as large),
/// and no late start (under LET a consumer that starts late loses the old
/// samples, it does not delay them).
fn let_reported(jl: &JobLevel) -> PerQuantity<OffsetBound> {
    let one = |v: Option<Nanos>| OffsetBound {
        value: v,
        basis: if v.is_some() {
            Basis::KnownOffsets
        } else {
            Basis::NoSampleReaches
        },
        late_start: false,
    };
    PerQuantity {
        reaction_read: one(jl.values.reaction_read),
        freshness_read: one(jl.values.freshness_read),
        reaction_event: one(jl.values.reaction_event),
        freshness_event: one(jl.values.freshness_event),
    }
}

fn dedup(mut v: Vec<usize>) -> Vec<usize> {
    let mut seen = Vec::with_capacity(v.len());
    v.retain(|i| {
        let new = !seen.contains(i);
        seen.push(*i);
        new
    });
    v
}

/// The job-level figure, or the arbitrary-phasing one when it is lower:
/// both are upper bounds for these offsets, so their minimum is one too.
fn combine(
    job: &PerQuantity<Option<Nanos>>,
    valid: &PerQuantity<Option<Nanos>>,
    late: bool,
) -> PerQuantity<OffsetBound> {
    PerQuantity::from_fn(|m, a| {
        let (j, v) = (*job.get(m, a), *valid.get(m, a));
        let (value, basis) = match (j, v) {
            (None, _) => (None, Basis::NoSampleReaches),
            (Some(j), Some(v)) if v < j => (Some(v), Basis::AnyPhasingTighter),
            (Some(j), _) => (Some(j), Basis::KnownOffsets),
        };
        let late_start = late && basis == Basis::AnyPhasingTighter && adjusted_for_late_start(m, a);
        OffsetBound {
            value,
            basis,
            late_start,
        }
    })
}

/// The quantities whose arbitrary-phasing figure changes for a late start.
fn adjusted_for_late_start(m: Metric, _a: Anchor) -> bool {
    m == Metric::Reaction
}

/// How long after the first head read the last task of the chain with a
/// known offset beyond its period starts: `None` when every known offset
/// is below its period. Such a task has no job in its first periods, which
/// the arbitrary-phasing arguments ("the next release of c is less than
/// T_c later") assume it has.
fn late_start_delay(spec: &Spec, timing: &[TaskTiming], path: &[usize]) -> Option<Nanos> {
    let late = path
        .iter()
        .any(|&i| spec.tasks[i].offset.is_some_and(|o| o >= timing[i].period));
    if !late {
        return None;
    }
    let last_start = path
        .iter()
        .filter_map(|&i| spec.tasks[i].offset)
        .max()
        .unwrap_or(0);
    let head_start = spec.tasks[path[0]].offset.unwrap_or(0);
    Some((last_start - head_start).max(0))
}

/// The arbitrary-phasing sound bounds, as far as they hold for the spec's
/// offsets. With every known offset below its period they hold as they
/// are. A task that starts later than one period breaks the reaction
/// arguments before it starts (its first job may come much later than one
/// period after a publish), not the freshness ones (they only use jobs
/// released after the sample's). Then reaction from the read is bounded by
/// freshness from the read (a sample's first output is no later than its
/// last), and reaction from an event before the last start Φ by the delay
/// to Φ plus the bound from an event at Φ, when every task has started.
fn any_phasing_valid(
    spec: &Spec,
    timing: &[TaskTiming],
    path: &[usize],
    any: &ChainAnalysis,
) -> PerQuantity<Option<Nanos>> {
    let mut v = PerQuantity {
        reaction_read: any.reaction.sound(Anchor::Read),
        freshness_read: any.freshness.sound(Anchor::Read),
        reaction_event: any.reaction.sound(Anchor::Event),
        freshness_event: any.freshness.sound(Anchor::Event),
    };
    if let Some(delay) = late_start_delay(spec, timing, path) {
        v.reaction_read = any.freshness.sound(Anchor::Read);
        v.reaction_event = v.reaction_event.map(|b| b + delay);
    }
    v
}

/// One stage of the chain as its job windows see it (i128: release
/// instants over a long span may pass i64 before the job limit stops it).
#[derive(Debug, Clone, Copy)]
struct Stage {
    phi: i128,
    t: i128,
    r: i128,
}

impl Stage {
    fn release(&self, k: i128) -> i128 {
        self.phi + k * self.t
    }

    /// The first job released at or after `at` (never before job 0).
    fn first_at_or_after(&self, at: i128) -> i128 {
        ceil_div(at - self.phi, self.t).max(0)
    }
}

/// The windows of a link p → c, relative to the releases.
#[derive(Debug, Clone, Copy)]
struct Link {
    /// A c job released at least this long after a p job's release surely
    /// reads that job's value or a newer one.
    sure: i128,
    /// A c job may read a p job's value (or a newer one) only if released
    /// no earlier than this after the p job's release.
    may: i128,
    /// c preempts p (P1): a c job that carries a p job's value (so was
    /// released before the next p job published) has also published before
    /// that.
    c_preempts: bool,
}

impl Link {
    /// The link's windows; `order` as [`fp_order`] gives it.
    fn new(order: Option<crate::Case>, p: &LinkTask, c: &LinkTask) -> Link {
        let rp = i128::from(p.r.unwrap_or(0));
        let read_slack = i128::from(c.r.unwrap_or(0)) - i128::from(c.x);
        let (xp, xc) = (i128::from(p.x_min), i128::from(c.x_min));
        let (jp, jc) = (i128::from(p.j), i128::from(c.j));
        let (sure, may) = match order {
            // P1, c preempts p: at p's publish f, c has no pending job, so a c
            // job released before f has finished before it (it does not see
            // the value) and was released at least x_min(c) before f. So a c
            // job sees the value exactly when released at or after f, which
            // is in [r + x_min(p), r + R_p]; and one released after
            // r + R_p − x_min(c) was not released before f.
            //
            // With release jitter (of p, or of a plain c: `fp_order`) r is
            // the nominal release and R counts from it: a c job is actually
            // released up to J_c after its nominal release, so it may see
            // the value from J_c earlier.
            Some(crate::Case::One) => (rp - (xc - 1).max(0), xp - jc),
            // P2, p preempts c: a c job starting at or after p's release
            // starts after that p job finished, and one starting before it
            // cannot see it: it sees the value exactly when it starts at or
            // after the release, which it may do up to R_c − x_c after its
            // own (F1) and surely does if released after it.
            // With jitter, the p job is released up to J_p after its
            // nominal release: a c job released J_p after that surely sees it.
            Some(crate::Case::Two) => (jp, -read_slack),
            // Otherwise the windows alone: the p job publishes in
            // [r + x_min(p), r + R_p] (F2), the c job reads in
            // [r', r' + R_c − x_c] (F1). With release jitter (which
            // `fp_order` sends here) r and r' are nominal releases and R
            // counts from them (R = J + w); a job reads no earlier than its
            // actual release, so no earlier than its nominal one.
            None => (rp, xp - read_slack),
        };
        Link {
            sure,
            may,
            c_preempts: order == Some(crate::Case::One),
        }
    }
}

fn ceil_div(a: i128, b: i128) -> i128 {
    a.div_euclid(b) + i128::from(a.rem_euclid(b) != 0)
}

fn gcd(a: i128, b: i128) -> i128 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The stages and links of the chain, or why there is no job-level bound.
fn stages_and_links(
    spec: &Spec,
    timing: &[TaskTiming],
    path: &[usize],
) -> Result<(Vec<Stage>, Vec<Link>), Fallback> {
    let lt: Vec<LinkTask> = path
        .iter()
        .map(|&i| LinkTask::new(spec, timing, i))
        .collect();
    let mut stages = Vec::with_capacity(path.len());
    for (&i, t) in path.iter().zip(&lt) {
        let (Some(r), Some(phi)) = (t.r, spec.tasks[i].offset) else {
            return Err(Fallback::Unbounded);
        };
        stages.push(Stage {
            phi: i128::from(phi),
            t: i128::from(t.t),
            r: i128::from(r),
        });
    }
    let links = lt
        .windows(2)
        .map(|w| Link::new(fp_order(spec.scheduler, &w[0], &w[1]), &w[0], &w[1]))
        .collect();
    Ok((stages, links))
}

/// The analysed span: head jobs released before the warm-up point plus one
/// hyperperiod, and the jobs of the chain's tasks released in it. `Err`
/// when they are more than `limit`.
fn span(stages: &[Stage], limit: u64) -> Result<(i128, i128, u64), Fallback> {
    let too_many = |n: i128| Fallback::TooManyJobs(u64::try_from(n).unwrap_or(u64::MAX));
    let t_min = stages.iter().map(|s| s.t).min().unwrap_or(1).max(1);
    // Past this span the limit is exceeded whatever the offsets: stop the
    // lcm there so that it cannot overflow.
    let cap = (i128::from(limit) + 1) * t_min;
    let mut h: i128 = 1;
    for s in stages {
        h = h / gcd(h, s.t) * s.t;
        if h > cap {
            return Err(too_many(h / t_min));
        }
    }
    // Warm-up: every task has started (the largest offset) and the jobs a
    // head job's sample can reach no longer see the start (one head period
    // and the response times of the later stages; docs/analysis.md).
    let warm = stages.iter().map(|s| s.phi).max().unwrap_or(0)
        + stages[0].t
        + stages[1..].iter().map(|s| s.r).sum::<i128>();
    let end = warm + h;
    let jobs: i128 = stages
        .iter()
        .map(|s| ceil_div(end - s.phi, s.t).max(0))
        .sum();
    if jobs > i128::from(limit) {
        return Err(too_many(jobs));
    }
    let head_jobs = ceil_div(end - stages[0].phi, stages[0].t).max(0);
    Ok((h, head_jobs, u64::try_from(jobs).unwrap_or(u64::MAX)))
}

/// The job-level analysis of the chain along `path` (every task with a
/// known offset).
fn job_level(
    spec: &Spec,
    timing: &[TaskTiming],
    path: &[usize],
    limit: u64,
) -> Result<JobLevel, Fallback> {
    let (stages, links) = stages_and_links(spec, timing, path)?;
    let (h, head_jobs, jobs) = span(&stages, limit)?;
    let mut worst = PerQuantity::from_fn(|_, _| None::<i128>);
    for k in 0..head_jobs {
        let one = head_job(&stages, &links, k);
        for (w, v) in [
            (&mut worst.reaction_read, one.reaction_read),
            (&mut worst.freshness_read, one.freshness_read),
            (&mut worst.reaction_event, one.reaction_event),
            (&mut worst.freshness_event, one.freshness_event),
        ] {
            if let Some(v) = v {
                *w = Some(w.map_or(v, |x: i128| x.max(v)));
            }
        }
    }
    let to_ns = |v: Option<i128>| v.and_then(|x| Nanos::try_from(x).ok());
    Ok(JobLevel {
        hyperperiod: Nanos::try_from(h).unwrap_or(Nanos::MAX),
        jobs,
        head_jobs: u64::try_from(head_jobs).unwrap_or(u64::MAX),
        values: PerQuantity {
            reaction_read: to_ns(worst.reaction_read),
            freshness_read: to_ns(worst.freshness_read),
            reaction_event: to_ns(worst.reaction_event),
            freshness_event: to_ns(worst.freshness_event),
        },
    })
}

/// The four quantities for the sample of head job `k` (from the event:
/// for an event just after head job k − 1's read, so none for k = 0, as
/// the simulator measures them).
///
/// At each stage: `lo..=hi`, the jobs that may carry the sample (an
/// interval: the producer job a consumer job reads grows with the consumer
/// job); `first`, a job no earlier than the first carrier (the first job
/// sure to read at or after the previous stage's `first` published, capped
/// by `hi`: the first carrier reads the first carrier's value or none of
/// the sample's); `next`, the same without the cap, for an event: the job
/// that job reads is at least as new.
fn head_job(stages: &[Stage], links: &[Link], k: i128) -> PerQuantity<Option<i128>> {
    let (mut lo, mut hi, mut first, mut next) = (k, k, k, k);
    let mut reaches = true;
    // The latest instant a carrier of the sample at the current stage can
    // publish, when P1 says more than its window (the last link only).
    let mut cap = None;
    for (w, l) in stages.windows(2).zip(links) {
        let (p, c) = (&w[0], &w[1]);
        cap = l.c_preempts.then(|| p.release(hi + 1) + p.r);
        // The first c job that may read lo's value (or a newer one), and the
        // last that may still read hi's (it is not sure to read hi + 1's).
        lo = c.first_at_or_after(p.release(lo) + l.may);
        hi = ceil_div(p.release(hi + 1) + l.sure - c.phi, c.t) - 1;
        reaches &= lo <= hi;
        first = c.first_at_or_after(p.release(first) + l.sure).min(hi);
        next = c.first_at_or_after(p.release(next) + l.sure);
    }
    let tail = &stages[stages.len() - 1];
    let head = &stages[0];
    let publish = |j: i128| tail.release(j) + tail.r;
    // Only a carrier of the sample publishes before the cap: `next` need not
    // carry it.
    let carrier_publish = |j: i128| cap.map_or(publish(j), |c: i128| publish(j).min(c));
    let (read, event) = (head.release(k), head.release(k - 1));
    PerQuantity {
        reaction_read: reaches.then(|| carrier_publish(first) - read),
        freshness_read: reaches.then(|| carrier_publish(hi) - read),
        reaction_event: (k >= 1).then(|| publish(next) - event),
        freshness_event: (reaches && k >= 1).then(|| carrier_publish(hi) - event),
    }
}
