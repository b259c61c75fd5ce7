//! Observations of a run held against the analysis: per chain, metric and
//! anchor, the distribution of what was measured and how much of it exceeds
//! each bound; per task, response times above the analysed ones. The CLI's
//! `simulate` and `fly` report these; the oracle tests check them.

pub mod file;

use rtpipe_analysis::{Anchor, Metric, OffsetBound, Report};
use rtpipe_joblog::{ChainStats, Histogram, Observed, SimResult};
use rtpipe_model::{Nanos, Spec, MAX_TIME};

/// A chain's observations by the analysis' names for them (the job log
/// that measures them knows no analysis).
pub trait ChainStatsExt {
    /// The observations of one metric measured from one anchor.
    fn observed(&self, metric: Metric, anchor: Anchor) -> &Observed;
}

impl ChainStatsExt for ChainStats {
    fn observed(&self, metric: Metric, anchor: Anchor) -> &Observed {
        match (metric, anchor) {
            (Metric::Reaction, Anchor::Read) => &self.reaction,
            (Metric::Freshness, Anchor::Read) => &self.freshness,
            (Metric::Reaction, Anchor::Event) => &self.event_reaction,
            (Metric::Freshness, Anchor::Event) => &self.event_freshness,
        }
    }
}

/// Distribution of the observations of one quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// How many observations.
    pub count: usize,
    /// The smallest.
    pub min: Nanos,
    /// In nanoseconds, not rounded.
    pub mean: f64,
    /// Nearest-rank 99th percentile: exact while its rank falls among the
    /// highest values the histogram counts exactly (at least half its
    /// exact cap, [`rtpipe_joblog::hist::exact_cap`], of distinct values:
    /// always up to 50 times the cap observations), within a relative
    /// error of 2^-[`rtpipe_joblog::hist::COARSE_BITS`] beyond (`exact`
    /// says which); count, min, mean and max are always exact.
    pub p99: Nanos,
    /// The largest.
    pub max: Nanos,
    /// Whether `p99` is exact.
    pub exact: bool,
}

impl Summary {
    /// `None` without observations.
    pub fn of(values: &[Nanos]) -> Option<Summary> {
        Summary::of_hist(&Histogram::of(values))
    }

    /// The summary of a histogram; `None` when it is empty.
    pub fn of_hist(h: &Histogram) -> Option<Summary> {
        Some(Summary {
            count: usize::try_from(h.count()).unwrap_or(usize::MAX),
            min: h.min()?,
            mean: h.mean()?,
            p99: h.percentile(99)?,
            max: h.max()?,
            exact: h.is_exact_percentile(99),
        })
    }
}

/// Observations of one quantity against its bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Judged {
    /// The observations, `None` when there were none.
    pub observed: Option<Summary>,
    /// The paper bound.
    pub paper: Nanos,
    /// The sound bound, `None` when it does not exist.
    pub sound: Option<Nanos>,
    /// Observations above the paper bound.
    pub over_paper: usize,
    /// Observations above the sound bound (`None` without a sound bound).
    pub over_sound: Option<usize>,
}

impl Judged {
    /// `values` against the two bounds.
    pub fn of(values: &[Nanos], paper: Nanos, sound: Option<Nanos>) -> Judged {
        Judged::of_hist(&Histogram::of(values), paper, sound)
    }

    /// The values counted in `h` against the two bounds (counts above a
    /// bound are exact while `h` is; beyond, values within its relative
    /// error of a bound may count as above it, never a value above as not).
    pub fn of_hist(h: &Histogram, paper: Nanos, sound: Option<Nanos>) -> Judged {
        let above = |b: Nanos| usize::try_from(h.count_where(|x| x > b)).unwrap_or(usize::MAX);
        Judged {
            observed: Summary::of_hist(h),
            paper,
            sound,
            over_paper: above(paper),
            over_sound: sound.map(above),
        }
    }
}

/// Observations of one quantity against its bound under the spec's known
/// release offsets.
#[derive(Debug, Clone, PartialEq)]
pub struct KnownJudged {
    /// The bound, and what it rests on.
    pub bound: OffsetBound,
    /// Observations that break it ([`OffsetBound::exceeded_by`]).
    pub over: usize,
}

/// One chain and metric: observations against the analysis, measured from
/// the head's read and from the event.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainObs {
    /// Index of the chain in `Spec::chains`.
    pub chain: usize,
    /// Which metric.
    pub metric: Metric,
    /// Measured from the head's read.
    pub read: Judged,
    /// Measured from the event.
    pub event: Judged,
    /// The same observations against the bounds under the spec's known
    /// offsets (from the read, from the event), when the chain has any.
    pub known: Option<[KnownJudged; 2]>,
}

impl ChainObs {
    /// The observations measured from `a`.
    pub fn from(&self, a: Anchor) -> &Judged {
        match a {
            Anchor::Read => &self.read,
            Anchor::Event => &self.event,
        }
    }

    /// Observations above a sound bound, from either anchor.
    pub fn over_sound(&self) -> usize {
        self.read.over_sound.unwrap_or(0) + self.event.over_sound.unwrap_or(0)
    }

    /// The observations against the known-offset bound from `a`, if any.
    pub fn known_from(&self, a: Anchor) -> Option<&KnownJudged> {
        let k = self.known.as_ref()?;
        Some(match a {
            Anchor::Read => &k[0],
            Anchor::Event => &k[1],
        })
    }

    /// Observations that break the bound that holds for the simulated runs:
    /// the known-offset bound when the chain has one (the simulator always
    /// releases a task with a known offset at it; that bound is never above
    /// the arbitrary-phasing one where the latter holds), the sound
    /// arbitrary-phasing bound otherwise.
    pub fn violations(&self) -> usize {
        match &self.known {
            Some([r, e]) => r.over + e.over,
            None => self.over_sound(),
        }
    }
}

/// Every chain and metric of `report`, in its order, judged on `res`.
pub fn observe(report: &Report, res: &SimResult) -> Vec<ChainObs> {
    report
        .chains
        .iter()
        .map(|c| {
            let empty = Histogram::default();
            let hist = |a: Anchor| {
                res.chains
                    .get(c.chain)
                    .map_or(&empty, |cs| &cs.observed(c.metric, a).hist)
            };
            let judge = |a: Anchor| Judged::of_hist(hist(a), c.bound.paper(a), c.bound.sound(a));
            let known = |a: Anchor| {
                let bound = report.offset_bound(c.chain, c.metric, a)?.clone();
                let over = hist(a).count_where(|v| bound.exceeded_by(v));
                let over = usize::try_from(over).unwrap_or(usize::MAX);
                Some(KnownJudged { bound, over })
            };
            ChainObs {
                chain: c.chain,
                metric: c.metric,
                read: judge(Anchor::Read),
                event: judge(Anchor::Event),
                known: known(Anchor::Read)
                    .zip(known(Anchor::Event))
                    .map(|(r, e)| [r, e]),
            }
        })
        .collect()
}

/// Tasks whose observed response exceeded the analysed job response time.
pub fn response_violations(report: &Report, res: &SimResult) -> Vec<usize> {
    res.tasks
        .iter()
        .zip(&report.timing)
        .enumerate()
        .filter_map(
            |(i, (ts, tm))| match (ts.max_response, tm.bounded_response()) {
                (Some(seen), Some(r)) if seen > r => Some(i),
                _ => None,
            },
        )
        .collect()
}

/// The longest of the tasks' periods (a data-triggered task's nominal one,
/// `Spec::activation_period`, from its triggers).
fn max_period(spec: &Spec, tasks: impl Iterator<Item = usize>) -> Option<Nanos> {
    tasks.filter_map(|i| spec.activation_period(i)).max()
}

/// The horizon that gives every chain's tail at least `outputs` outputs:
/// tails release one job per period and (when schedulable) finish it within
/// the period, so N periods of the slowest tail plus one longest period
/// cover N outputs of every tail, once every task has started (after the
/// largest known offset, 0 without any). `None` when no task has a fixed
/// period or the span exceeds the longest time the model allows.
pub fn horizon_for_outputs(spec: &Spec, outputs: u64) -> Option<Nanos> {
    let t_max = max_period(spec, 0..spec.tasks.len()).filter(|&t| t > 0)?;
    let tails = spec.chains.iter().filter_map(|c| c.path.last().copied());
    let t_tail = max_period(spec, tails).unwrap_or(t_max);
    let start = spec
        .tasks
        .iter()
        .filter_map(|t| t.offset)
        .max()
        .unwrap_or(0);
    i64::try_from(outputs)
        .ok()
        .and_then(|n| n.checked_mul(t_tail))
        .and_then(|h| h.checked_add(t_max))
        .and_then(|h| h.checked_add(start))
        .filter(|&h| h <= MAX_TIME)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let xs: Vec<Nanos> = (1..=200).rev().collect();
        let o = Summary::of(&xs);
        assert_eq!(
            o.map(|o| (o.count, o.min, o.p99, o.max)),
            Some((200, 1, 198, 200))
        );
        assert_eq!(Summary::of(&[7]).map(|o| (o.p99, o.mean)), Some((7, 7.0)));
        assert_eq!(Summary::of(&[]), None);
    }

    #[test]
    fn judged_counts_strictly_above() {
        let j = Judged::of(&[1, 5, 6, 9], 5, Some(6));
        assert_eq!((j.over_paper, j.over_sound), (2, Some(1)));
        assert_eq!(Judged::of(&[9], 5, None).over_sound, None);
    }
}
