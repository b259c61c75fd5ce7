//! # rtpipe-analysis
//!
//! Schedulability tests and end-to-end latency bounds for pipe systems
//! (Cheng, West, Einstein, EMSOFT 2018, Sections III and IV-B).
//!
//! - [`sched`]: rate-monotonic priorities, exact response-time analysis,
//!   Liu–Layland, hyperbolic and EDF utilisation tests, per CPU.
//! - [`edf`]: response times under EDF (Spuri 1996) for the reservations
//!   of a CPU.
//! - [`latency`]: reaction and freshness bounds of a chain, in `paper` mode
//!   (Eqs. 1–14 as published) and `sound` mode (interference-aware, never
//!   exceeded by any execution of the model; see docs/analysis.md).
//! - [`paths`]: the worst path between every source and sink, by dynamic
//!   programming over the task graph.
//! - [`offsets`]: the bounds of chains whose tasks all have known release
//!   offsets, job by job over the hyperperiod.
#![deny(missing_docs)]

pub mod arrivals;
pub mod blocking;
pub mod demand;
pub mod disturbance;
pub mod edf;
pub mod event_links;
pub mod events;
pub mod graph;
pub mod latency;
pub mod let_bound;
pub mod load;
pub mod margins;
pub mod offsets;
pub mod overheads;
pub mod paths;
pub mod qpa;
pub mod relax;
pub mod sched;
pub mod thread_rta;

pub use latency::{analyze_chain, eq1_single_pipe, Anchor, Bound, Case, ChainAnalysis, ChainBound};
pub use offsets::{Basis, ChainOffsets, Fallback, OffsetBound};
pub use paths::{all_paths, AllPaths, PairBounds, Worst};
pub use sched::{analyze as schedulability, CpuVerdict, Schedulability, TaskTiming};

use rtpipe_model::{Nanos, Spec};

/// Which metric a bound is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Input to the first corresponding output.
    Reaction,
    /// Input to the last corresponding output (from the read: the
    /// literature's reduced data age, [`Literature::MaxReducedDataAge`]).
    Freshness,
}

impl Metric {
    /// The name used in output and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Reaction => "reaction",
            Metric::Freshness => "freshness",
        }
    }

    /// The chain's limit on this metric measured from `anchor`, if it has
    /// one: from the read `reaction` / `freshness`, from the event
    /// `max_reaction_time` / `freshness_from_event`.
    pub fn limit(self, chain: &rtpipe_model::Chain, anchor: Anchor) -> Option<Nanos> {
        match (self, anchor) {
            (Metric::Reaction, Anchor::Read) => chain.reaction,
            (Metric::Freshness, Anchor::Read) => chain.freshness,
            (Metric::Reaction, Anchor::Event) => chain.max_reaction_time,
            (Metric::Freshness, Anchor::Event) => chain.freshness_from_event,
        }
    }

    /// The spec key of this metric's limit from `anchor`.
    pub fn key(self, anchor: Anchor) -> &'static str {
        match (self, anchor) {
            (Metric::Reaction, Anchor::Read) => "reaction",
            (Metric::Freshness, Anchor::Read) => "freshness",
            (Metric::Reaction, Anchor::Event) => "max_reaction_time",
            (Metric::Freshness, Anchor::Event) => "freshness_from_event",
        }
    }
}

/// A quantity of the cause-effect-chain literature that one of rtpipe's
/// (metric, anchor) pairs is exactly, so that reports can give it under the
/// literature's name (docs/analysis.md, "What each reported number is").
/// rtpipe's other figures (reaction from the read, freshness from the
/// event) carry no literature name: none of the literature's is the same
/// quantity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Literature {
    /// Maximum reaction time (Dürr et al. 2019, Günzel et al. 2023): from
    /// an event to the first tail output that reflects it.
    MaxReactionTime,
    /// Maximum data age (Günzel et al. 2023): from a sample's head read to
    /// the tail's next output after the last one that carries it.
    MaxDataAge,
    /// Maximum reduced data age (Dürr et al. 2019's "data age", Günzel et
    /// al. 2023's MRDA, Becker et al. 2017's): from a sample's head read
    /// to the last tail output that carries it.
    MaxReducedDataAge,
}

impl Literature {
    /// Every quantity, in the order reports list them.
    pub const ALL: [Literature; 3] = [
        Literature::MaxReactionTime,
        Literature::MaxDataAge,
        Literature::MaxReducedDataAge,
    ];

    /// The name used in output and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Literature::MaxReactionTime => "max_reaction_time",
            Literature::MaxDataAge => "max_data_age",
            Literature::MaxReducedDataAge => "max_reduced_data_age",
        }
    }

    /// The (metric, anchor) whose figures are this quantity's: the one
    /// place the literature's names are mapped onto rtpipe's.
    pub fn quantity(self) -> (Metric, Anchor) {
        match self {
            Literature::MaxReactionTime => (Metric::Reaction, Anchor::Event),
            // Günzel et al. (ECRTS 2023) prove that the maximum data age
            // equals the maximum reaction time on every schedule whose
            // tasks read and publish in job order, as every rtpipe task
            // does; so every bound on one bounds the other, and no formula
            // of its own is needed.
            Literature::MaxDataAge => (Metric::Reaction, Anchor::Event),
            Literature::MaxReducedDataAge => (Metric::Freshness, Anchor::Read),
        }
    }

    /// The quantities that `metric` from `anchor` is, in [`Literature::ALL`]
    /// order (none for the pairs without a literature name).
    pub fn of(metric: Metric, anchor: Anchor) -> impl Iterator<Item = Literature> {
        Literature::ALL
            .into_iter()
            .filter(move |l| l.quantity() == (metric, anchor))
    }
}

/// Which analysis a verdict follows: every command and the design judge a
/// chain limit by [`ChainResult::ok_in`] under one of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// The paper's equations (Eqs. 1–14) as published.
    Paper,
    /// The sound, interference-aware bounds (the default: no execution of
    /// the model exceeds them).
    #[default]
    Sound,
}

impl Mode {
    /// Every mode, in the order the command line lists them.
    pub const ALL: [Mode; 2] = [Mode::Sound, Mode::Paper];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Paper => "paper",
            Mode::Sound => "sound",
        }
    }
}

impl std::str::FromStr for Mode {
    type Err = String;

    fn from_str(s: &str) -> Result<Mode, String> {
        Mode::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown mode `{s}` (expected `sound` or `paper`)"))
    }
}

/// One chain and metric, judged against its limits: one per [`Anchor`].
#[derive(Debug, Clone, PartialEq)]
pub struct ChainResult {
    /// Index of the chain in `Spec::chains`.
    pub chain: usize,
    /// Which metric.
    pub metric: Metric,
    /// The chain's limit on it from the head's read, if any.
    pub limit: Option<Nanos>,
    /// The chain's limit on it from the event, if any.
    pub event_limit: Option<Nanos>,
    /// The bounds.
    pub bound: ChainBound,
    /// Every limit holds under the sound bound from its anchor (or there is
    /// no limit and the bound from the read exists): `ok_in(Mode::Sound)`.
    pub ok: bool,
}

impl ChainResult {
    /// The limit measured from `anchor`, if any.
    pub fn limit_from(&self, anchor: Anchor) -> Option<Nanos> {
        match anchor {
            Anchor::Read => self.limit,
            Anchor::Event => self.event_limit,
        }
    }

    /// The bound `mode` judges from `anchor` (`None`: unbounded).
    pub fn bound_in(&self, mode: Mode, anchor: Anchor) -> Option<Nanos> {
        match mode {
            Mode::Sound => self.bound.sound(anchor),
            Mode::Paper => Some(self.bound.paper(anchor)),
        }
    }

    /// The limit from `anchor` holds under `mode`'s bound from the same
    /// anchor (true when there is none).
    pub fn holds(&self, mode: Mode, anchor: Anchor) -> bool {
        match self.limit_from(anchor) {
            None => true,
            Some(l) => self.bound_in(mode, anchor).is_some_and(|b| b <= l),
        }
    }

    /// The paper's bounds are within the limits (or there are none).
    pub fn paper_ok(&self) -> bool {
        self.ok_in(Mode::Paper)
    }

    /// The verdict rule: every limit, from the read and from the event,
    /// holds under `mode`'s bound from its anchor; in sound mode a chain
    /// with an unbounded response time fails even without limits.
    pub fn ok_in(&self, mode: Mode) -> bool {
        let bounded = mode == Mode::Paper || self.bound.sound(Anchor::Read).is_some();
        bounded && Anchor::ALL.into_iter().all(|a| self.holds(mode, a))
    }
}

/// A task whose fixed period exceeds its `max_period`.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodExcess {
    /// Index of the task in `Spec::tasks`.
    pub task: usize,
    /// Its period.
    pub period: Nanos,
    /// Its `max_period`.
    pub max_period: Nanos,
}

/// Every task whose fixed period is above its `max_period`, in task order.
pub fn period_excesses(spec: &Spec) -> Vec<PeriodExcess> {
    spec.tasks
        .iter()
        .enumerate()
        .filter_map(|(task, t)| {
            let (period, max_period) = (t.fixed_period()?, t.max_period?);
            (period > max_period).then_some(PeriodExcess {
                task,
                period,
                max_period,
            })
        })
        .collect()
}

/// Everything `rtpipe analyze` reports.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Timing of every task, in declaration order.
    pub timing: Vec<TaskTiming>,
    /// The schedulability verdict.
    pub schedulability: Schedulability,
    /// Two entries per declared chain: reaction, then freshness.
    pub chains: Vec<ChainResult>,
    /// Per declared chain, the paper's case of each link.
    pub cases: Vec<Vec<Case>>,
    /// Per declared chain, its bounds under the spec's known release
    /// offsets (`None` when no task of the chain has one).
    pub offsets: Vec<Option<ChainOffsets>>,
    /// Tasks whose period exceeds their `max_period` (each fails the
    /// verdict in every mode).
    pub period_excesses: Vec<PeriodExcess>,
}

impl Report {
    /// Every limit and the schedulability test hold.
    pub fn all_ok(&self) -> bool {
        self.ok_in(Mode::Sound)
    }

    /// Every limit holds under the paper's equations, and the
    /// schedulability test.
    pub fn all_ok_paper(&self) -> bool {
        self.ok_in(Mode::Paper)
    }

    /// Every limit holds under `mode` ([`ChainResult::ok_in`]), every
    /// period is within its `max_period`, and the schedulability test.
    pub fn ok_in(&self, mode: Mode) -> bool {
        self.schedulability.schedulable
            && self.period_excesses.is_empty()
            && self.chains.iter().all(|c| c.ok_in(mode))
    }

    /// The bound of `chain`'s `metric` from `anchor` under the spec's known
    /// offsets, when the chain has any.
    pub fn offset_bound(
        &self,
        chain: usize,
        metric: Metric,
        anchor: Anchor,
    ) -> Option<&OffsetBound> {
        self.offsets
            .get(chain)?
            .as_ref()
            .map(|o| o.get(metric, anchor))
    }
}

/// Names of tasks that need a fixed period before analysis.
pub fn missing_periods(spec: &Spec) -> Vec<&str> {
    spec.tasks
        .iter()
        .filter(|t| t.server != rtpipe_model::Server::Background && t.fixed_period().is_none())
        // A data-triggered task's releases come from its triggers.
        .filter(|t| !t.is_triggered())
        .map(|t| t.name.as_str())
        .collect()
}

/// (reaction, freshness) of every declared chain, in chain order, as
/// `pick` reads them off the bounds (e.g. `|b| b.sound(Anchor::Read)`). For generators
/// that set limits from a design's own bounds.
pub fn bounds_per_chain(
    spec: &Spec,
    pick: impl Fn(&ChainBound) -> Option<Nanos>,
) -> Vec<(Option<Nanos>, Option<Nanos>)> {
    let mut out = vec![(None, None); spec.chains.len()];
    for c in analyze(spec).chains {
        match c.metric {
            Metric::Reaction => out[c.chain].0 = pick(&c.bound),
            Metric::Freshness => out[c.chain].1 = pick(&c.bound),
        }
    }
    out
}

/// Runs the schedulability test and bounds every declared chain.
pub fn analyze(spec: &Spec) -> Report {
    analyze_with(spec, true)
}

/// [`analyze`] without the bounds under known offsets (`offsets` is empty):
/// everything the verdict ([`Report::ok_in`]) reads, for callers that
/// judge many variants of one spec ([`margins`]).
pub fn analyze_verdict(spec: &Spec) -> Report {
    analyze_with(spec, false)
}

fn analyze_with(spec: &Spec, with_offsets: bool) -> Report {
    let (timing, schedulability) = sched::analyze(spec);
    let mut chains = Vec::new();
    let mut cases = Vec::new();
    let mut offsets = Vec::new();
    for (k, ch) in spec.chains.iter().enumerate() {
        let a = analyze_chain(spec, &timing, &ch.path);
        if with_offsets {
            let max_jobs = offsets::MAX_JOBS;
            offsets.push(offsets::chain_offsets(
                spec, &timing, k, &ch.path, &a, max_jobs,
            ));
        }
        chains.extend(chain_results(spec, k, &a));
        cases.push(a.cases);
    }
    Report {
        timing,
        schedulability,
        chains,
        cases,
        offsets,
        period_excesses: period_excesses(spec),
    }
}

/// Chain `k`'s reaction and freshness, judged against its limits.
pub fn chain_results(spec: &Spec, k: usize, a: &ChainAnalysis) -> [ChainResult; 2] {
    let ch = &spec.chains[k];
    [
        (Metric::Reaction, a.reaction.clone()),
        (Metric::Freshness, a.freshness.clone()),
    ]
    .map(|(metric, bound)| {
        let mut c = ChainResult {
            chain: k,
            metric,
            limit: metric.limit(ch, Anchor::Read),
            event_limit: metric.limit(ch, Anchor::Event),
            bound,
            ok: false,
        };
        c.ok = c.ok_in(Mode::Sound);
        c
    })
}

#[cfg(test)]
mod tests;
