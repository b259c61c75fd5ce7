//! Timing limits from control quality: fly the same mission (same seed, same
//! noise) while the pipeline's timing gets worse, and find where the flight
//! stops meeting its criteria.
//!
//! Three sweeps, each point a whole flight:
//! - **period scale**: every guaranteed task's period × k (budgets fixed);
//!   the analysis gives each chain's sound bounds at that k;
//! - **pure delay** on one chain's head (gyro, accelerometer or radio
//!   samples delivered `d` late, everything else nominal): that chain's
//!   bounds grow by exactly `d`;
//! - **actuation rate**: the tail's (the motor-output task's) period × k
//!   alone, everything else nominal.
//!
//! A chain's derived limits are the largest sound bounds (reaction and
//! freshness, from the read and from the event) at which the vehicle still
//! met the criteria in every point up to it: the last passing point before
//! the first failing one, a point passing by the sweep's [`Rule`] (every
//! flight meets its criterion, or a pass rate judged against the spec's
//! own timing's flights). The rate sweep gives the tail's `max_period`: a
//! sample that never reaches a slow tail is counted by no from-read bound.

mod check;
mod refine;
mod rule;
pub use check::check_below;
pub use refine::refine;
pub use rule::{deciding, AgainstReference, Rule};

use crate::{fly, Setup};
use rayon::prelude::*;
use rtpipe_analysis::Anchor;
use rtpipe_analysis::{analyze, Metric};
use rtpipe_flight::quality::{Criteria, FlightQuality};
use rtpipe_flight::tasks::BodyKind;
use rtpipe_model::Diagnostic;
use rtpipe_model::{Nanos, PeriodSpec, Server, Spec};
use rtpipe_sim::ExecModel;
use std::sync::atomic::{AtomicU64, Ordering};

/// The sensing kinds a pure delay can be put on, in the order of
/// `CosimConfig::sense_delay_ns` (`BodyKind::delay_line`: the cascade's
/// `gyro_filter` samples pass the gyro's line).
pub const DELAY_LINES: [BodyKind; 3] = [BodyKind::Gyro, BodyKind::Accel, BodyKind::Radio];

/// A chain's (reaction, freshness) bounds or limits, ns.
pub type ChainPair = (Option<Nanos>, Option<Nanos>);

/// What one sweep point changes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Variation {
    /// Every guaranteed task's period × this factor.
    Scale(f64),
    /// This delay (ns) on the samples of `DELAY_LINES[line]`.
    Delay {
        /// Index into `DELAY_LINES`.
        line: usize,
        /// The delay (ns).
        ns: u64,
    },
    /// The motor-output task's period × this factor, alone.
    Rate(f64),
}

/// One flight of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// What was varied, and by how much.
    pub variation: Variation,
    /// Per declared chain: the sound reaction and freshness bounds (from the
    /// read) of the timing flown, a pure delay included.
    pub bounds: Vec<ChainPair>,
    /// The same from the event: maximum reaction time and freshness from
    /// the event.
    pub event: Vec<ChainPair>,
    /// The timing passes the spec's schedulability test.
    pub schedulable: bool,
    /// `None` when the timing could not be flown (a period below its
    /// budget); the reason is in `failures`.
    pub quality: Option<FlightQuality>,
    /// What misses the criteria in the first flight that missed them
    /// (named by its seed and phase when several were flown); empty when
    /// every flight meets them.
    pub failures: Vec<String>,
    /// Each flight met its criterion, in the sweep's flight order
    /// (setups, seeds, phases); empty when the timing could not be flown.
    /// The one record of the flights: [`Point::flights`] and
    /// [`Point::passed`] count it.
    pub outcomes: Vec<bool>,
    /// Under the pass-rate rule, each setup's flights counted against the
    /// reference's, in the sweep's setup order.
    pub against_reference: Option<Vec<AgainstReference>>,
    /// The timing flies by the sweep's [`Rule`].
    pub flies: bool,
    /// Which pass of the sweep flew it.
    pub stage: Stage,
}

/// Which pass of a sweep flew a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The grid (2^(i/n) of the period scale and tail period, the delays).
    Grid,
    /// Bisecting an edge ([`refine`]).
    Refinement,
    /// Checking the values below a written limit ([`check_below`]).
    Check,
}

impl Stage {
    /// Its name in the reports.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Grid => "grid",
            Stage::Refinement => "refinement",
            Stage::Check => "check",
        }
    }
}

/// How many flights judge one timing: `seeds` seeds of the noise and
/// execution times (from the setup's, consecutive) × `phases` phase draws
/// ([`crate::phases::phased`]; draw 0 the nominal phase).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trials {
    /// Seeds per timing.
    pub seeds: u32,
    /// Phase draws per seed.
    pub phases: u32,
}

impl Trials {
    /// One flight: the setup's seed, the nominal phase.
    pub const ONE: Trials = Trials {
        seeds: 1,
        phases: 1,
    };

    fn count(self) -> u32 {
        assert!(self.seeds >= 1 && self.phases >= 1, "at least one flight");
        self.seeds * self.phases
    }
}

impl Point {
    /// The timing flies by the sweep's [`Rule`] (by default: every flight
    /// at it met the criteria).
    pub fn pass(&self) -> bool {
        self.flies
    }

    /// Flights flown at this timing (seeds × phases × setups; 0 when it
    /// could not be flown).
    pub fn flights(&self) -> u32 {
        self.outcomes.len() as u32
    }

    /// Of them, those that met their criterion.
    pub fn passed(&self) -> u32 {
        self.outcomes.iter().filter(|&&o| o).count() as u32
    }
}

/// `spec` with every guaranteed task's fixed period × `k` (rounded to the
/// nanosecond); budgets stay. Background tasks keep their periods.
pub fn scaled(spec: &Spec, k: f64) -> Result<Spec, String> {
    scaled_where(spec, k, |_| true)
}

/// `spec` with the fixed period of each guaranteed task that `pick` (its
/// index) selects × `k`.
fn scaled_where(spec: &Spec, k: f64, pick: impl Fn(usize) -> bool) -> Result<Spec, String> {
    assert!(
        k.is_finite() && k > 0.0,
        "a period scale is positive, found {k}"
    );
    let mut s = spec.clone();
    for (_, t) in s
        .tasks
        .iter_mut()
        .enumerate()
        .filter(|(i, t)| t.server != Server::Background && pick(*i))
    {
        let Some(p) = t.fixed_period() else { continue };
        let q = (p as f64 * k).round() as Nanos;
        if q < t.budget() {
            return Err(format!(
                "period of `{}` would be {q} ns, below its budget {} ns",
                t.name,
                t.budget()
            ));
        }
        t.period = PeriodSpec::Fixed(q);
    }
    Ok(s)
}

/// The motor-output tasks with a period of their own: the tails whose
/// rate the rate sweep varies (a data-triggered output runs at its
/// trigger's rate, which the period scale varies).
pub fn tails(spec: &Spec, s: &Setup) -> Vec<usize> {
    (0..s.kinds.len())
        .filter(|&i| s.kinds[i] == Some(BodyKind::Pwm))
        .filter(|&i| spec.tasks.get(i).is_some_and(|t| !t.is_triggered()))
        .collect()
}

/// Sound (reaction, freshness) of every declared chain, from the read and
/// from the event, and whether the spec is schedulable.
fn sound_bounds(spec: &Spec) -> (Vec<ChainPair>, Vec<ChainPair>, bool) {
    let rep = analyze(spec);
    let mut read = vec![(None, None); spec.chains.len()];
    let mut event = read.clone();
    for c in &rep.chains {
        for (out, a) in [(&mut read, Anchor::Read), (&mut event, Anchor::Event)] {
            match c.metric {
                Metric::Reaction => out[c.chain].0 = c.bound.sound(a),
                Metric::Freshness => out[c.chain].1 = c.bound.sound(a),
            }
        }
    }
    (read, event, rep.schedulability.schedulable)
}

/// The delay line a chain starts at, if any.
pub fn head_line(spec: &Spec, s: &Setup, chain: usize) -> Option<usize> {
    let head = *spec.chains.get(chain)?.path.first()?;
    s.kinds.get(head).copied().flatten()?.delay_line()
}

/// What a variation flies: the timing (or why it cannot be flown), the
/// delay on each delay line, and the delay it adds to the bounds of the
/// chains of a line (none when 0). Equal plans give equal points.
type Plan = (Result<Spec, String>, [u64; 3], Option<(usize, u64)>);

fn plan(spec: &Spec, s: &Setup, v: Variation) -> Plan {
    let mut delays = s.world.sense_delay_ns;
    let mut added = None;
    let timing = match v {
        Variation::Scale(k) => scaled(spec, k),
        Variation::Rate(k) => {
            let tails = tails(spec, s);
            scaled_where(spec, k, |i| tails.contains(&i))
        }
        Variation::Delay { line, ns } => {
            delays[line] = ns;
            added = (ns > 0).then_some((line, ns));
            Ok(spec.clone())
        }
    };
    (timing, delays, added)
}

/// `s` as a sweep flies it, judged by `criteria`, with `delays` on the
/// sensing lines.
fn prepared(s: &Setup, criteria: &Criteria, delays: [u64; 3]) -> Setup {
    let mut setup = s.clone();
    // A point keeps only the flight's quality: the bounds are the analysis's.
    setup.track_chains = false;
    setup.keep_trace = false;
    // The flight judges its envelope as it flies, by the mission's
    // criteria: the sweep's criterion replaces them.
    setup.mission.criteria = *criteria;
    setup.world.sense_delay_ns = delays;
    setup
}

fn flown(spec: &Spec, s: &Setup, v: Variation, how: &How) -> Point {
    let (timing, delays, added) = plan(spec, s, v);
    let cases: Vec<(Setup, &Criteria)> = std::iter::once((s, how.criteria))
        .chain(how.also.iter().map(|(o, c)| (o, c)))
        .map(|(o, c)| (prepared(o, c, delays), c))
        .collect();
    let timing = match timing {
        Ok(x) => x,
        Err(why) => {
            return Point {
                variation: v,
                bounds: vec![(None, None); spec.chains.len()],
                event: vec![(None, None); spec.chains.len()],
                schedulable: false,
                quality: None,
                failures: vec![why],
                against_reference: how.rule.against_reference(&[]),
                outcomes: Vec::new(),
                flies: false,
                stage: Stage::Grid,
            }
        }
    };
    let (mut bounds, mut event, schedulable) = sound_bounds(&timing);
    if let Some((line, ns)) = added {
        for k in 0..bounds.len() {
            if head_line(&timing, s, k) == Some(line) {
                let d = ns as Nanos;
                for b in [&mut bounds[k], &mut event[k]] {
                    *b = (b.0.map(|x| x + d), b.1.map(|x| x + d));
                }
            }
        }
    }
    let (quality, failures, outcomes) = trials(&timing, &cases, how);
    Point {
        variation: v,
        bounds,
        event,
        schedulable,
        quality,
        failures,
        flies: how.rule.flies(&outcomes),
        against_reference: how.rule.against_reference(&outcomes),
        outcomes,
        stage: Stage::Grid,
    }
}

/// What every flight of a sweep shares: the execution-time model, the
/// criterion, how many flights judge a timing, on what, and by what rule.
#[derive(Clone, Copy)]
pub struct How<'a> {
    /// How each job's demand is drawn.
    pub exec: ExecModel,
    /// What a flight of the sweep's own setup must meet.
    pub criteria: &'a Criteria,
    /// Flights per timing and setup.
    pub trials: Trials,
    /// Further setups (another mission or vehicle) flown at every timing
    /// with the same seeds and phases, each judged by its own criterion;
    /// their flights count with the setup's under the `rule` (all-pass:
    /// the worst of them decides each edge).
    pub also: &'a [(Setup, Criteria)],
    /// When a timing's flights make it fly.
    pub rule: Rule<'a>,
}

impl<'a> How<'a> {
    /// One flight per timing (the setup's seed, the nominal phase).
    pub fn once(exec: ExecModel, criteria: &'a Criteria) -> How<'a> {
        How {
            exec,
            criteria,
            trials: Trials::ONE,
            also: &[],
            rule: Rule::AllPass,
        }
    }

    /// Flights per timing: seeds × phases × setups.
    pub fn flights(&self) -> u32 {
        self.trials.count() * (1 + self.also.len() as u32)
    }
}

/// "vehicle/mission, " naming a setup among several.
fn case_label(s: &Setup) -> String {
    format!("{}/{}, ", s.preset.name, s.mission.name)
}

/// Every flight of one timing over `cases` (each setup prepared with its
/// criterion): the first flight's quality, the reasons of the first
/// failure the rule counts against the timing (named by setup, seed and
/// phase when several flew), and whether each flight met its criteria.
fn trials(
    timing: &Spec,
    cases: &[(Setup, &Criteria)],
    how: &How,
) -> (Option<FlightQuality>, Vec<String>, Vec<bool>) {
    let several = how.flights() > 1;
    let (mut first, mut failures, mut outcomes) = (None, Vec::new(), Vec::new());
    for (setup, criteria) in cases {
        for j in 0..u64::from(how.trials.seeds) {
            for k in 0..u64::from(how.trials.phases) {
                let mut one = crate::phases::phased(timing, setup, k);
                one.world.seed = setup.world.seed.wrapping_add(j);
                let (quality, missed) = match fly(timing, &one, how.exec) {
                    Ok(f) => {
                        let missed = f.quality.failures(criteria);
                        (Some(f.quality), missed)
                    }
                    Err(Diagnostic { message, .. }) => (None, vec![message]),
                };
                let named = how.rule.names_failure(outcomes.len());
                outcomes.push(quality.is_some() && missed.is_empty());
                if failures.is_empty() && !missed.is_empty() && named {
                    let case = if cases.len() > 1 {
                        case_label(setup)
                    } else {
                        String::new()
                    };
                    let at = format!("{case}seed {}, phase {k}: ", one.world.seed);
                    failures = missed
                        .into_iter()
                        .map(|m| if several { format!("{at}{m}") } else { m })
                        .collect();
                }
                if first.is_none() && j == 0 && k == 0 {
                    first = Some(quality);
                }
            }
        }
    }
    (first.flatten(), failures, outcomes)
}

/// Each flight's outcome at the spec's own timing (every period × 1, no
/// added delay), in the sweep's flight order: the reference the pass-rate
/// rule judges every timing against.
pub fn reference(spec: &Spec, s: &Setup, how: &How) -> Vec<bool> {
    let how = How {
        rule: Rule::AllPass,
        ..*how
    };
    flown(spec, s, Variation::Scale(1.0), &how).outcomes
}

/// Flies every variation (in parallel; each point is deterministic; the
/// points in the variations' order) and counts finished points in `done`.
/// `stopped` is asked before each flight: once it says so, no further
/// flight begins and the sweep answers `None` (a stop flag: the flights
/// flown are not the sweep).
/// Variations that fly the same timing with the same delays (the nominal
/// timing is in each of the default sweeps five times: ×1 scale, ×1 rate,
/// three 0 ms delays) are flown once.
pub fn sweep(
    spec: &Spec,
    s: &Setup,
    how: &How,
    variations: &[Variation],
    done: &AtomicU64,
    stopped: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<Point>> {
    // (timing, delays) decide a point, all but its variation (`flown`).
    let mut distinct: Vec<(Variation, Plan)> = Vec::new();
    let slot: Vec<usize> = variations
        .iter()
        .map(|&v| {
            let p = plan(spec, s, v);
            distinct.iter().position(|d| d.1 == p).unwrap_or_else(|| {
                distinct.push((v, p));
                distinct.len() - 1
            })
        })
        .collect();
    let points: Vec<Point> = distinct
        .par_iter()
        .enumerate()
        .map(|(k, (v, _))| {
            if stopped() {
                return None;
            }
            let p = flown(spec, s, *v, how);
            let copies = slot.iter().filter(|&&i| i == k).count();
            done.fetch_add(copies as u64, Ordering::Relaxed);
            Some(p)
        })
        .collect::<Option<_>>()?;
    let points = variations
        .iter()
        .zip(slot)
        .map(|(&v, k)| {
            let mut p = points[k].clone();
            p.variation = v;
            p
        })
        .collect();
    Some(points)
}

/// The default sweep: period scales 2^(i/3) from `lo` to `hi` (both
/// included when they are powers of 2^(1/3)), delays of 0, 2, 4, …,
/// 128 ms on each delay line the spec uses, and the tail's period × 2^(i/3)
/// from 1 to 32 when the spec has a motor-output task.
pub fn default_variations(spec: &Spec, s: &Setup, lo: f64, hi: f64) -> Vec<Variation> {
    variations(spec, s, lo, hi, 3)
}

/// [`default_variations`] with `per_octave` points per doubling of the
/// scales and a third as many (at least one) of the delays: 0, then
/// 2 ms × 2^(3i/per_octave) up to 128 ms.
pub fn variations(spec: &Spec, s: &Setup, lo: f64, hi: f64, per_octave: u32) -> Vec<Variation> {
    assert!(lo > 0.0 && hi >= lo, "scale range {lo}..{hi}");
    assert!(
        (1..=48).contains(&per_octave),
        "{per_octave} points per doubling"
    );
    let n = f64::from(per_octave);
    let at = |i: i32| 2f64.powf(f64::from(i) / n);
    let first = (n * lo.log2()).round() as i32;
    let last = (n * hi.log2()).round() as i32;
    let mut v: Vec<Variation> = (first..=last).map(|i| Variation::Scale(at(i))).collect();
    // Delays double from 2 ms: a third as many points per doubling.
    let per_delay = (per_octave / 3).max(1) as i32;
    for line in 0..DELAY_LINES.len() {
        if (0..spec.chains.len()).any(|k| head_line(spec, s, k) == Some(line)) {
            v.push(Variation::Delay { line, ns: 0 });
            for i in 0..=6 * per_delay {
                let ns = (2e6 * 2f64.powf(f64::from(i) / f64::from(per_delay))).round() as u64;
                v.push(Variation::Delay { line, ns });
            }
        }
    }
    if !tails(spec, s).is_empty() {
        v.extend((0..=5 * per_octave as i32).map(|i| Variation::Rate(at(i))));
    }
    v
}

/// Where a one-dimensional sweep stops: the last passing point before the
/// first failing one (in the order given) and that failing point.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge<'a> {
    /// The last passing point before the first failing one.
    pub last_pass: Option<&'a Point>,
    /// The first failing point.
    pub first_fail: Option<&'a Point>,
}

/// The edge of the schedulable points `pick` selects, in order.
pub fn edge<'a>(points: &'a [Point], pick: impl Fn(&Variation) -> bool) -> Edge<'a> {
    let mut last_pass = None;
    for p in points
        .iter()
        .filter(|p| pick(&p.variation) && p.schedulable)
    {
        if !p.pass() {
            return Edge {
                last_pass,
                first_fail: Some(p),
            };
        }
        last_pass = Some(p);
    }
    Edge {
        last_pass,
        first_fail: None,
    }
}

/// The edge of the period-scale sweep, over the schedulable scales (below
/// them nothing is guaranteed, so nothing is derived), in increasing order.
pub fn scale_edge(points: &[Point]) -> Edge<'_> {
    edge(points, |v| matches!(v, Variation::Scale(_)))
}

/// What the sweep derives: every limit the flight depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct Derived {
    /// Per declared chain, (reaction, freshness) from the read.
    pub read: Vec<ChainPair>,
    /// Per declared chain, (maximum reaction time, freshness from the event): the
    /// same from the event.
    pub event: Vec<ChainPair>,
    /// Per task, the longest period that flew in the rate sweep: the
    /// tail's `max_period` (`None` for every other task).
    pub max_period: Vec<Option<Nanos>>,
    /// Per task, its fixed period × the period-scale sweep's last passing
    /// scale: the longest period of it the scale sweep flew and passed
    /// (`None` for a task the sweep does not scale, or when no scale
    /// passed). A design that frees the task's period may not go beyond
    /// it: longer periods were never flown.
    pub scaled_period: Vec<Option<Nanos>>,
}

/// Everything the sweep derives (see [`Derived`]). A chain's limits are
/// the smaller of what the period-scale sweep and the delay sweep of the
/// chain's head allowed (the bounds at each one's last passing point). The
/// scale sweep slows every chain at once, so its limits hold as a set; the
/// delay sweep isolates one chain with the others nominal.
///
/// Every limit is then multiplied by `safety` (in (0, 1]; 1: the bound at
/// the last passing point itself), rounded down (a `max_period` down to the
/// design grid): the margin a written limit keeps from the last timing
/// that flew.
pub fn derived_limits(spec: &Spec, s: &Setup, points: &[Point], safety: f64) -> Derived {
    assert!(
        safety > 0.0 && safety <= 1.0,
        "a safety factor in (0, 1], found {safety}"
    );
    let times = |x: Nanos| (x as f64 * safety).floor() as Nanos;
    let pair = |(r, f): ChainPair| (r.map(times), f.map(times));
    let read = chain_limits(spec, s, points, |p| &p.bounds);
    let event = chain_limits(spec, s, points, |p| &p.event);
    let (read, event) = (
        read.into_iter().map(pair).collect(),
        event.into_iter().map(pair).collect(),
    );
    let rate = match edge(points, |v| matches!(v, Variation::Rate(_))).last_pass {
        Some(Point {
            variation: Variation::Rate(k),
            ..
        }) => Some(*k),
        _ => None,
    };
    let tails = tails(spec, s);
    let max_period = spec
        .tasks
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let p = t.fixed_period().filter(|_| tails.contains(&i))?;
            let k = rate?;
            // Down to the design grid, so a written range stays on it.
            let q = times((p as f64 * k).round() as Nanos);
            Some(q - q % spec.resolution.max(1))
        })
        .collect();
    Derived {
        read,
        event,
        max_period,
        scaled_period: scaled_periods(spec, points, times),
    }
}

/// Per task, its fixed period × the last passing period scale, × the
/// safety (`times`), down to the design grid; `None` for a background
/// task, a task without a fixed period, or when no scale passed.
fn scaled_periods(
    spec: &Spec,
    points: &[Point],
    times: impl Fn(Nanos) -> Nanos,
) -> Vec<Option<Nanos>> {
    let k = match scale_edge(points).last_pass {
        Some(Point {
            variation: Variation::Scale(k),
            ..
        }) => Some(*k),
        _ => None,
    };
    spec.tasks
        .iter()
        .map(|t| {
            let p = t
                .fixed_period()
                .filter(|_| t.server != Server::Background)?;
            // Rounded as `scaled` rounds the flown period, then down.
            let q = times((p as f64 * k?).round() as Nanos);
            Some(q - q % spec.resolution.max(1))
        })
        .collect()
}

/// Per chain, the limits one anchor's bounds (`of`) give.
fn chain_limits(
    spec: &Spec,
    s: &Setup,
    points: &[Point],
    of: impl Fn(&Point) -> &Vec<ChainPair>,
) -> Vec<ChainPair> {
    let scale = scale_edge(points);
    (0..spec.chains.len())
        .map(|k| {
            let mut lim = scale.last_pass.and_then(|p| of(p).get(k).copied());
            if let Some(line) = head_line(spec, s, k) {
                let d = edge(
                    points,
                    |v| matches!(v, Variation::Delay { line: l, .. } if *l == line),
                );
                let by_delay = d.last_pass.and_then(|p| of(p).get(k).copied());
                lim = match (lim, by_delay) {
                    (Some(a), Some(b)) => Some((min_opt(a.0, b.0), min_opt(a.1, b.1))),
                    (a, b) => a.or(b),
                };
            }
            lim.unwrap_or((None, None))
        })
        .collect()
}

fn min_opt(a: Option<Nanos>, b: Option<Nanos>) -> Option<Nanos> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{setup, Request};
    use std::path::Path;

    /// examples/cleanflight.toml flying `steps` on `vehicle`, seed 1.
    pub(crate) fn cleanflight(vehicle: &str) -> (Spec, Setup) {
        cleanflight_flying(vehicle, "steps", None, 1)
    }

    /// examples/cleanflight.toml flying `mission` on `vehicle` (for
    /// `horizon` ns where given) with `seed`.
    pub(crate) fn cleanflight_flying(
        vehicle: &str,
        mission: &str,
        horizon: Option<rtpipe_model::Nanos>,
        seed: u64,
    ) -> (Spec, Setup) {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
        let spec = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
        let r = Request {
            spec_path: &p,
            vehicle,
            mission,
            horizon,
            seed,
        };
        let s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        (spec, s)
    }

    #[test]
    fn the_period_sweep_finds_where_the_flight_fails() {
        let (spec, s) = cleanflight("racer5");
        let vars = default_variations(&spec, &s, 0.5, 8.0);
        let done = AtomicU64::new(0);
        let points = sweep(
            &spec,
            &s,
            &How::once(ExecModel::Uniform, &s.criteria()),
            &vars,
            &done,
            &|| false,
        )
        .unwrap_or_default();
        assert_eq!(done.load(Ordering::Relaxed), vars.len() as u64);
        let e = scale_edge(&points);
        let (Some(last), Some(fail)) = (e.last_pass, e.first_fail) else {
            panic!("no edge: {e:?}");
        };
        let (Variation::Scale(a), Variation::Scale(b)) = (last.variation, fail.variation) else {
            panic!("not scales");
        };
        assert!(1.0 <= a && a < b, "Table V's timing flies: {a} < {b}");
        let limits = derived_limits(&spec, &s, &points, 1.0).read;
        let nominal = points
            .iter()
            .find(|p| p.variation == Variation::Scale(1.0))
            .unwrap_or_else(|| panic!("no nominal point"));
        for (k, lim) in limits.iter().enumerate() {
            // Between the nominal timing's bounds and the last passing
            // scale's, and below the first failing scale's.
            for (l, lo, pass, fail) in [
                (
                    lim.0,
                    nominal.bounds[k].0,
                    last.bounds[k].0,
                    fail.bounds[k].0,
                ),
                (
                    lim.1,
                    nominal.bounds[k].1,
                    last.bounds[k].1,
                    fail.bounds[k].1,
                ),
            ] {
                assert!(
                    lo <= l && l <= pass && pass < fail,
                    "chain {k}: {l:?} {lo:?} {pass:?} {fail:?}"
                );
            }
        }
        // The gyro path's delay sweep fails too, and its limit is where.
        let g = edge(&points, |v| matches!(v, Variation::Delay { line: 0, .. }));
        let (Some(gp), Some(gf)) = (g.last_pass, g.first_fail) else {
            panic!("the gyro delay sweep never failed: {g:?}");
        };
        assert!(gp.bounds[0].0 < gf.bounds[0].0);
    }

    /// Several seeds and phases per timing: every flight counted, the first
    /// (the setup's seed, nominal phase) is the single flight's, and a
    /// safety factor scales every derived limit down.
    #[test]
    fn trials_count_every_flight_and_safety_scales_the_limits() {
        let (spec, s) = cleanflight("racer5");
        let c = s.criteria();
        let vars = [
            Variation::Scale(1.0),
            Variation::Scale(2.0),
            Variation::Scale(6.0),
        ];
        let done = AtomicU64::new(0);
        let one = How::once(ExecModel::Uniform, &c);
        let six = How {
            trials: Trials {
                seeds: 2,
                phases: 3,
            },
            ..one
        };
        let single = sweep(&spec, &s, &one, &vars, &done, &|| false).unwrap_or_default();
        let many = sweep(&spec, &s, &six, &vars, &done, &|| false).unwrap_or_default();
        for (a, b) in single.iter().zip(&many) {
            assert_eq!((a.flights(), b.flights()), (1, 6));
            assert!(b.passed() <= 6);
            assert_eq!(a.quality, b.quality, "the first flight is the nominal one");
            assert_eq!(b.pass(), b.passed() == 6 && b.quality.is_some());
            if !a.pass() {
                assert!(!b.pass());
            }
        }
        assert!(
            many[0].pass(),
            "Table V's timing flies every seed and phase"
        );
        let full = derived_limits(&spec, &s, &many, 1.0);
        let safe = derived_limits(&spec, &s, &many, 0.9);
        for (f, g) in full.read.iter().zip(&safe.read) {
            let times = |x: Option<Nanos>| x.map(|x| (x as f64 * 0.9).floor() as Nanos);
            assert_eq!((times(f.0), times(f.1)), *g);
        }
    }
}

#[cfg(test)]
mod missions {
    use super::*;

    /// A sweep over two missions judges every timing on both: each point's
    /// flights count both, and the edge it writes is the tighter of the two
    /// missions' own (here the motor-output period, which turbulence's
    /// oscillation bounds well below the calm steps' limit).
    #[test]
    fn a_sweep_over_two_missions_writes_the_tighter_limit() {
        let (spec, steps) = tests::cleanflight("racer5");
        let (_, gusty) = tests::cleanflight_flying("racer5", "gusty", None, 1);
        let vars: Vec<Variation> = [1.0, 2.0, 4.0, 8.0, 16.0].map(Variation::Rate).into();
        let done = AtomicU64::new(0);
        let max_period = |s: &Setup, also: &[(Setup, Criteria)]| {
            let c = s.criteria();
            let how = How {
                also,
                ..How::once(ExecModel::Uniform, &c)
            };
            let Some(points) = sweep(&spec, s, &how, &vars, &done, &|| false) else {
                unreachable!("nothing stops this sweep")
            };
            assert!(points.iter().all(|p| p.flights() == 1 + also.len() as u32));
            let tail = tails(&spec, s)[0];
            let limit = derived_limits(&spec, s, &points, 1.0).max_period[tail];
            (limit.unwrap_or_else(|| panic!("no rate flew")), points)
        };
        let (calm, _) = max_period(&steps, &[]);
        let (windy, _) = max_period(&gusty, &[]);
        let both_cases = [(gusty.clone(), gusty.criteria())];
        let (both, points) = max_period(&steps, &both_cases);
        assert!(
            windy < calm,
            "turbulence bounds the motor period: {windy} < {calm}"
        );
        assert_eq!(both, calm.min(windy));
        let named = points.iter().flat_map(|p| &p.failures);
        assert!(
            named
                .into_iter()
                .any(|f| f.starts_with("racer5/gusty, seed 1, phase 0: ")),
            "{points:?}"
        );
    }
}

#[cfg(test)]
mod threads {
    use super::*;
    use crate::{setup, Request};
    use std::path::Path;

    /// examples/cleanflight.toml and racer5 hovering for `horizon` ns
    /// (seed 2): the sweeps' flight.
    fn cleanflight_hover(horizon: rtpipe_model::Nanos) -> (Spec, crate::Setup) {
        tests::cleanflight_flying("racer5", "hover", Some(horizon), 2)
    }

    /// The nominal timing, in the sweep as ×1 scale, ×1 rate and 0 ms
    /// delays, is flown once and gives each of them the point its own
    /// flight would.
    #[test]
    fn variations_of_the_same_flight_are_flown_once_with_the_same_points() {
        let (spec, s) = cleanflight_hover(4_000_000_000);
        let vars = [
            Variation::Scale(1.0),
            Variation::Delay { line: 0, ns: 0 },
            Variation::Rate(1.0),
            Variation::Delay { line: 2, ns: 0 },
            Variation::Delay {
                line: 1,
                ns: 2_000_000,
            },
            Variation::Scale(0.5),
        ];
        let plans: Vec<Plan> = vars.iter().map(|&v| plan(&spec, &s, v)).collect();
        assert!(plans[..4].iter().all(|p| *p == plans[0]));
        assert!(plans[4] != plans[0] && plans[5] != plans[0]);
        let c = s.criteria();
        let done = AtomicU64::new(0);
        let got = sweep(
            &spec,
            &s,
            &How::once(ExecModel::Uniform, &c),
            &vars,
            &done,
            &|| false,
        )
        .unwrap_or_default();
        assert_eq!(done.load(Ordering::Relaxed), vars.len() as u64);
        for (v, g) in vars.iter().zip(&got) {
            let alone = flown(&spec, &s, *v, &How::once(ExecModel::Uniform, &c));
            assert_eq!(format!("{g:?}"), format!("{alone:?}"));
        }
        assert!(!got[5].schedulable, "{:?}", got[5]);
    }

    /// A stop abandons the sweep: it answers `None`, and no flight begins
    /// after the stop was seen (rayon still asks for the items not yet
    /// begun).
    #[test]
    fn a_stop_abandons_the_sweep() {
        let (spec, s) = cleanflight_hover(1_000_000_000);
        let vars = default_variations(&spec, &s, 0.5, 8.0);
        assert!(vars.len() > 20, "{}", vars.len());
        let (done, checks) = (AtomicU64::new(0), AtomicU64::new(0));
        let stopped = || checks.fetch_add(1, Ordering::Relaxed) >= 2;
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        let c = s.criteria();
        let swept = one.install(|| {
            sweep(
                &spec,
                &s,
                &How::once(ExecModel::Uniform, &c),
                &vars,
                &done,
                &stopped,
            )
        });
        assert!(swept.is_none(), "the sweep ran to its end");
        // Two flights were flown (the nominal one stands for five
        // variations); no flight began after the stop.
        assert!(done.load(Ordering::Relaxed) <= 6, "{done:?}");
    }

    /// The points are the same, in the same order, on 1, 2 or 3 threads:
    /// each flight is deterministic and the results keep the variations'
    /// order whoever flies them.
    #[test]
    fn a_sweep_is_the_same_on_any_number_of_threads() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
        let spec = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
        let r = Request {
            spec_path: &p,
            vehicle: "racer5",
            mission: "steps",
            horizon: None,
            seed: 3,
        };
        let s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        let vars: Vec<Variation> = default_variations(&spec, &s, 0.5, 8.0)
            .into_iter()
            .step_by(4)
            .collect();
        assert!(vars.len() >= 12, "{}", vars.len());
        let on = |n: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap_or_else(|e| panic!("{e}"));
            let done = AtomicU64::new(0);
            let c = s.criteria();
            pool.install(|| {
                sweep(
                    &spec,
                    &s,
                    &How::once(ExecModel::Uniform, &c),
                    &vars,
                    &done,
                    &|| false,
                )
                .unwrap_or_default()
            })
        };
        let one = on(1);
        assert_eq!(
            one.iter().map(|p| p.variation).collect::<Vec<_>>(),
            vars,
            "in the variations' order"
        );
        assert!(one.iter().any(Point::pass) && one.iter().any(|p| !p.pass()));
        for n in [2, 3] {
            assert_eq!(format!("{:?}", on(n)), format!("{one:?}"), "{n} threads");
        }
    }
}
