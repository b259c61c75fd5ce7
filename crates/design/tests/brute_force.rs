//! `design` against brute force on small random design problems.
//!
//! Each instance comes from `rtpipe_model::gen::design_problem` with choice
//! domains only (3–5 tasks, 2–4 choices each, at most a few hundred period
//! assignments), deterministic per seed. Every assignment is analysed; the
//! verdict of `design` must agree:
//!
//! - a returned design (optimal or feasible) passes the analysis under the
//!   mode's judgement and takes every period from its domain;
//! - `infeasible`: no assignment passes;
//! - `optimal`: its utilisation is the least of all passing assignments
//!   (1e-9 relative); any reported lower bound is at most that least value;
//! - `unknown` (time limit) is allowed, up to 10 % of the instances.
//!
//! `RTPIPE_DESIGN_CASES=N` sets the number of instances per mode (default
//! 300 in each mode); `RTPIPE_DESIGN_VERBOSE=1` prints
//! every instance. Run with `--nocapture` to see the tallies.
//!
//! `contention_agrees_with_brute_force` adds critical sections and
//! scheduling overheads and simulates some of the designs
//! (`sim/tests/common`'s probe and check).

#[path = "../../sim/tests/common/mod.rs"]
mod common;

use rtpipe_analysis::Anchor;
use rtpipe_analysis::{analyze, bounds_per_chain, Report};
use rtpipe_design::lp::SolverKind;
use rtpipe_design::{design, utilization, Method, Mode, Options, Outcome, Status};
use rtpipe_model::gen::{
    add_contention, add_timing, design_problem, ChainBounds, Contention, DesignGenConfig,
    GenConfig, Rng,
};
use rtpipe_model::{Communication, Nanos, PeriodSpec, Priorities, SchedTest, Scheduler, Spec};
use std::collections::BTreeMap;
use std::time::Instant;

/// Sound bounds of every chain, for the generator's limits.
fn sound_bounds(spec: &Spec) -> Vec<ChainBounds> {
    bounds_per_chain(spec, |b| b.sound(Anchor::Read))
}

/// Paper bounds of every chain: limits for paper-mode instances (the sound
/// bound's limits leave many of them infeasible under the paper's equations,
/// whose freshness can exceed the sound bound).
fn paper_bounds(spec: &Spec) -> Vec<ChainBounds> {
    bounds_per_chain(spec, |b| Some(b.paper(Anchor::Read)))
}

/// Instance `seed`: 3–5 tasks on one CPU (two for some), 1–3 chains, choice
/// domains; most systems use RM with exact RTA, some Liu–Layland,
/// hyperbolic or EDF. Limits come from the sound bounds of the generating
/// design, or in paper mode for every other seed from its paper bounds.
fn instance(seed: u64, mode: Mode) -> Spec {
    let mut r = Rng::new(seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
    let tasks = r.range(3, 5) as usize;
    let scheduler = if r.chance(0.15) {
        Scheduler::Edf
    } else {
        Scheduler::Rm
    };
    let cfg = DesignGenConfig {
        system: GenConfig {
            tasks,
            cpus: if r.chance(0.15) { 2 } else { 1 },
            utilization: 0.3 + 0.4 * r.unit(),
            scheduler,
            source_fraction: 0.2,
            max_fan_in: 2,
            chains: r.range(1, 3) as usize,
            transfers: r.chance(0.3),
            mixed_servers: r.chance(0.3),
            ..GenConfig::default()
        },
        choices_only: true,
        // At most 4^4 = 256 or 3^5 = 243 assignments.
        max_choices: if tasks <= 4 { 4 } else { 3 },
        ..DesignGenConfig::default()
    };
    let mut spec = if mode == Mode::Paper && seed & 1 == 0 {
        design_problem(seed, &cfg, &paper_bounds)
    } else {
        design_problem(seed, &cfg, &sound_bounds)
    };
    if scheduler == Scheduler::Rm {
        spec.schedulability = match r.range(0, 9) {
            0 => SchedTest::LiuLayland,
            1 => SchedTest::Hyperbolic,
            _ => SchedTest::Rta,
        };
    }
    spec
}

/// Instance `seed` with some choice domains replaced by small ranges
/// (`[T − a, T + b]` around a generating period T of at most 20 ms, on the
/// 1 ms grid) while the brute-force grid stays within 600 assignments:
/// integer periods go through the outer approximation of C/T.
fn instance_with_ranges(seed: u64, mode: Mode) -> Spec {
    let mut spec = instance(seed, mode);
    let mut r = Rng::new(seed ^ 0x5851_F42D_4C95_7F2D);
    let ms: Nanos = 1_000_000;
    spec.resolution = ms;
    for i in 0..spec.tasks.len() {
        let PeriodSpec::Choices(v) = &spec.tasks[i].period else {
            continue;
        };
        // The generating period is in the domain; take the one nearest 10 ms.
        let Some(&t) = v.iter().filter(|&&p| p <= 20 * ms).max() else {
            continue;
        };
        let lo = (t - r.range(0, 5) as Nanos * ms).max(ms);
        let hi = t + r.range(0, 5) as Nanos * ms;
        let old = spec.tasks[i].period.clone();
        spec.tasks[i].period = PeriodSpec::Range {
            min: if r.chance(0.7) { Some(lo) } else { None },
            max: Some(hi),
        };
        if grid(&spec) > 600 || domain(&spec, i).is_empty() {
            spec.tasks[i].period = old;
        }
    }
    spec
}

/// A task's domain as `design` reads it: choices at least the budget, or
/// the multiples of the resolution in [max(min, C), max].
fn domain(spec: &Spec, i: usize) -> Vec<Nanos> {
    let t = &spec.tasks[i];
    let res = spec.resolution;
    match &t.period {
        PeriodSpec::Fixed(p) => vec![*p],
        PeriodSpec::Choices(v) => v.iter().copied().filter(|&p| p >= t.budget()).collect(),
        PeriodSpec::Range {
            min,
            max: Some(max),
        } => {
            let lo = (min.unwrap_or(0).max(t.budget()) + res - 1) / res;
            (lo..=max / res).map(|k| k * res).collect()
        }
        other => panic!("task {}: not a finite domain: {other:?}", t.name),
    }
}

/// The number of period assignments.
fn grid(spec: &Spec) -> usize {
    (0..spec.tasks.len())
        .map(|i| domain(spec, i).len())
        .product()
}

/// The judgement of `design` in each mode: the schedulability test, and
/// every limit against the sound bound (sound) or the paper's (paper).
fn passes(report: &Report, mode: Mode) -> bool {
    report.schedulability.schedulable
        && report.period_excesses.is_empty()
        && report.chains.iter().all(|c| match mode {
            Mode::Sound => c.ok,
            // Every limit, from the read and from the event, by hand.
            Mode::Paper => Anchor::ALL
                .into_iter()
                .all(|a| c.limit_from(a).is_none_or(|l| c.bound.paper(a) <= l)),
        })
}

/// The least utilisation over all passing assignments (None: none passes),
/// with one assignment that reaches it, and the number of assignments.
fn brute_force(spec: &Spec, mode: Mode) -> (Option<(f64, Vec<Nanos>)>, usize) {
    let doms: Vec<Vec<Nanos>> = (0..spec.tasks.len()).map(|i| domain(spec, i)).collect();
    let mut s = spec.clone();
    let mut idx = vec![0usize; doms.len()];
    let mut best: Option<(f64, Vec<Nanos>)> = None;
    let mut count = 0;
    if doms.iter().any(|d| d.is_empty()) {
        return (None, 0);
    }
    loop {
        for (i, t) in s.tasks.iter_mut().enumerate() {
            t.period = PeriodSpec::Fixed(doms[i][idx[i]]);
        }
        count += 1;
        if harmonic_ok(&s) && passes(&analyze(&s), mode) {
            let u = utilization(&s);
            if best.as_ref().is_none_or(|(b, _)| u < *b) {
                best = Some((u, s.tasks.iter().filter_map(|t| t.fixed_period()).collect()));
            }
        }
        // Next assignment (odometer).
        let mut k = 0;
        loop {
            if k == idx.len() {
                return (best, count);
            }
            idx[k] += 1;
            if idx[k] < doms[k].len() {
                break;
            }
            idx[k] = 0;
            k += 1;
        }
    }
}

/// Under `harmonic = true`, whether every pair of periods divides one way.
fn harmonic_ok(s: &Spec) -> bool {
    let p = periods(s);
    !s.harmonic
        || p.iter()
            .enumerate()
            .all(|(a, &x)| p[a + 1..].iter().all(|&y| x % y == 0 || y % x == 0))
}

/// Instance `seed` with ranges under `harmonic = true`; `None` when its
/// fixed periods are not harmonic (the spec would be refused).
fn harmonic_instance(seed: u64, mode: Mode) -> Option<Spec> {
    let mut spec = instance_with_ranges(seed, mode);
    spec.harmonic = true;
    let mut only_fixed = spec.clone();
    only_fixed.tasks.retain(|t| t.fixed_period().is_some());
    harmonic_ok(&only_fixed).then_some(spec)
}

/// Writes a reproducer into the temporary directory and returns its path
/// (only a failing run writes one, and it is kept for the bug report).
fn save_bug(spec: &Spec, seed: u64, mode: Mode) -> String {
    let name = format!("design-bug-{}-{seed}.toml", mode.name());
    let path = std::env::temp_dir().join(name).display().to_string();
    let text = format!(
        "# design brute-force mismatch: seed {seed}, mode {}\n{}",
        mode.name(),
        rtpipe_model::to_toml(spec)
    );
    if let Err(e) = std::fs::write(&path, text) {
        eprintln!("cannot write {path}: {e}");
    }
    path
}

/// Checks one instance; `Err` describes a disagreement.
fn check(spec: &Spec, o: &Outcome, mode: Mode) -> Result<(), String> {
    let (best, _) = brute_force(spec, mode);
    match o.status {
        Status::Optimal | Status::Feasible => {
            let d = o.spec.as_ref().ok_or("a design without a spec")?;
            let report = analyze(d);
            if !passes(&report, mode) {
                return Err(format!(
                    "{:?} design fails the analysis: periods {:?}",
                    o.status,
                    periods(d)
                ));
            }
            if !harmonic_ok(d) {
                return Err(format!("periods {:?} are not harmonic", periods(d)));
            }
            if mode == Mode::Sound && !report.all_ok() {
                return Err("sound design: all_ok() is false".into());
            }
            for (i, t) in d.tasks.iter().enumerate() {
                let p = t.fixed_period().ok_or("a designed period is not fixed")?;
                if !domain(spec, i).contains(&p) {
                    return Err(format!("task {}: period {p} not in its domain", t.name));
                }
            }
            let u = utilization(d);
            let obj = o.objective.ok_or("a design without an objective")?;
            if (u - obj).abs() > 1e-9 * u.max(1e-12) {
                return Err(format!(
                    "objective {obj} but the design's utilisation is {u}"
                ));
            }
            let Some((bu, bp)) = best else {
                return Err("a design where brute force finds none".into());
            };
            if u < bu * (1.0 - 1e-9) {
                return Err(format!("design {u} below the brute-force minimum {bu}"));
            }
            if let Some(lb) = o.lower_bound {
                if lb > bu * (1.0 + 1e-9) {
                    return Err(format!(
                        "lower bound {lb} above the brute-force minimum {bu} at {bp:?}"
                    ));
                }
            }
            if o.status == Status::Optimal && (u - bu).abs() > 1e-9 * bu {
                return Err(format!(
                    "optimal {u} at {:?}, brute force {bu} at {bp:?}",
                    periods(d)
                ));
            }
        }
        Status::Infeasible => {
            if let Some((bu, bp)) = best {
                return Err(format!(
                    "infeasible, but {bp:?} passes with utilisation {bu}"
                ));
            }
        }
        Status::Unknown => {}
    }
    Ok(())
}

fn periods(s: &Spec) -> Vec<Nanos> {
    s.tasks.iter().filter_map(|t| t.fixed_period()).collect()
}

fn cases(default: usize) -> usize {
    std::env::var("RTPIPE_DESIGN_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Instance `seed` with its limits moved to the event for some chains and
/// metrics (`max_reaction_time`, `freshness_from_event`): the from-read limit plus
/// the head's shortest period, times 1–1.5; the from-read limit is kept for
/// about half of them; for half the seeds one task gets a `max_period`.
fn with_event_limits(mut spec: Spec, seed: u64) -> Spec {
    let mut r = Rng::new(seed ^ 0x9E37_79B9_7F4A_7C15);
    for k in 0..spec.chains.len() {
        let head = spec.chains[k].path[0];
        let t1 = domain(&spec, head).into_iter().min().unwrap_or(0);
        let ch = &mut spec.chains[k];
        for (read, event) in [
            (&mut ch.reaction, &mut ch.max_reaction_time),
            (&mut ch.freshness, &mut ch.freshness_from_event),
        ] {
            let Some(l) = *read else { continue };
            if r.chance(0.3) {
                continue;
            }
            *event = Some(((l + t1) as f64 * (1.0 + 0.5 * r.unit())) as Nanos);
            if r.chance(0.5) {
                *read = None;
            }
        }
    }
    // Some task needs a minimum rate: its median period at most.
    if r.chance(0.5) {
        let i = r.range(0, spec.tasks.len() as u64 - 1) as usize;
        let mut d = domain(&spec, i);
        d.sort_unstable();
        spec.tasks[i].max_period = d.get(d.len() / 2).copied();
    }
    spec
}

/// Instance `seed` (choices, or ranges for every other seed) with critical
/// sections and overheads (`gen::add_contention`, costs up to 200 µs: a
/// tenth of the shortest generated executions) and, on about half, release
/// jitter, written and parsed back (without the jitter when validation
/// refuses it); `None` when nothing was added or validation refuses it.
fn contended_instance(seed: u64, mode: Mode) -> Option<Spec> {
    let mut spec = if seed.is_multiple_of(2) {
        instance(seed, mode)
    } else {
        instance_with_ranges(seed, mode)
    };
    let c = Contention {
        sections: 0.75,
        overheads: 0.6,
        max_cost: 200_000,
    };
    let mut r = Rng::new(seed ^ 0xb10c);
    let (sections, overheads) = add_contention(&mut spec, &mut r, &c);
    let parsed = |s: &Spec| Spec::parse("contended.toml", &rtpipe_model::to_toml(s)).ok();
    let mut jittered = spec.clone();
    // Jitter where validation takes it (RTA, not beside some overheads).
    if r.chance(0.5) && add_jitter(&mut jittered, &mut r) {
        if let Some(s) = parsed(&jittered) {
            return Some(s);
        }
    }
    if !(sections || overheads) {
        return None;
    }
    parsed(&spec)
}

/// Release jitter on about half the tasks, each below a quarter of the
/// task's shortest possible period; whether any was added.
fn add_jitter(spec: &mut Spec, r: &mut Rng) -> bool {
    let mut added = false;
    for i in 0..spec.tasks.len() {
        let least = domain(spec, i).into_iter().min().unwrap_or(0);
        if least >= 8 && r.chance(0.5) {
            spec.tasks[i].jitter = r.range(1, (least / 4) as u64) as Nanos;
            added = true;
        }
    }
    added
}

/// Instance `seed` (choices, or ranges for every other seed) with
/// constrained deadlines and deadline-monotonic or explicit priorities
/// (RM, under RTA) or the processor-demand test (EDF), `gen::add_timing`,
/// and LET communication on about a third, written and parsed back;
/// `None` when validation refuses it.
fn timed_instance(seed: u64, mode: Mode) -> Option<Spec> {
    let mut spec = if seed.is_multiple_of(2) {
        instance(seed, mode)
    } else {
        instance_with_ranges(seed, mode)
    };
    if spec.policy().fixed_priority() {
        spec.schedulability = SchedTest::Rta;
    }
    add_timing(&mut spec, &mut Rng::new(seed ^ 0xd1ce));
    let parsed = |s: &Spec| Spec::parse("timed.toml", &rtpipe_model::to_toml(s)).ok();
    // LET communication on about a third, where validation takes it, with
    // the limits doubled (LET's bounds run about twice the implicit ones
    // the limits come from).
    let mut coin = Rng::new(seed ^ 0x1e7);
    if coin.chance(0.35) {
        // Half of these per chain (each chain LET with probability one
        // half, where validation takes the mix), the rest system-wide.
        if coin.chance(0.5) {
            if let Some(s) = parsed(&let_chains(&spec, &mut coin)) {
                return Some(s);
            }
        }
        let mut l = spec.clone();
        l.communication = Communication::Let;
        l.chains.iter_mut().for_each(doubled);
        if let Some(s) = parsed(&l) {
            return Some(s);
        }
    }
    parsed(&spec)
}

/// A chain's limits doubled.
fn doubled(ch: &mut rtpipe_model::Chain) {
    for x in [
        &mut ch.reaction,
        &mut ch.freshness,
        &mut ch.max_reaction_time,
        &mut ch.freshness_from_event,
    ] {
        *x = x.map(|v| 2 * v);
    }
}

/// `spec` with chains of both semantics: under an implicit system some
/// chains LET, or under a LET system some chains implicit (at least one
/// either way); the LET chains' limits doubled.
fn let_chains(spec: &Spec, coin: &mut Rng) -> Spec {
    let mut l = spec.clone();
    let (system, other) = if coin.chance(0.5) {
        (Communication::Implicit, Communication::Let)
    } else {
        (Communication::Let, Communication::Implicit)
    };
    l.communication = system;
    let first = coin.range(0, l.chains.len() as u64 - 1) as usize;
    for (k, ch) in l.chains.iter_mut().enumerate() {
        if k == first || coin.chance(0.5) {
            ch.communication = Some(other);
        }
        if ch.communication.unwrap_or(system) == Communication::Let {
            doubled(ch);
        }
    }
    l
}

/// `design` refuses critical sections, overheads, jitter, DM or explicit
/// priorities and QPA with the MILP, and in paper mode where the box
/// search does not apply.
fn refused(spec: &Spec, mode: Mode, method: Method) -> bool {
    let boxes_apply = mode == Mode::Sound || rtpipe_analysis::relax::paper_monotone(spec);
    (contended(spec) || timed(spec)) && (method == Method::Milp || !boxes_apply)
}

/// The spec ranks by deadlines or explicit priorities, uses QPA or LET.
fn timed(spec: &Spec) -> bool {
    spec.priorities != Priorities::RateMonotonic
        || spec.schedulability == SchedTest::Qpa
        || spec.any_let()
}

/// The spec has critical sections, overheads or release jitter.
fn contended(spec: &Spec) -> bool {
    spec.tasks
        .iter()
        .any(|t| !t.sections.is_empty() || t.jitter > 0)
        || !spec.overheads.is_zero()
}

/// Tallies the priority orders, deadlines and QPA of an instance.
fn count_timing(spec: &Spec, tally: &mut BTreeMap<&'static str, usize>) {
    let mut add = |k| *tally.entry(k).or_default() += 1;
    match spec.priorities {
        Priorities::DeadlineMonotonic => add("deadline-monotonic"),
        Priorities::Explicit => add("explicit"),
        Priorities::RateMonotonic => {}
    }
    if spec.schedulability == SchedTest::Qpa {
        add("qpa");
    }
    if spec.chains.iter().any(|c| c.communication.is_some()) {
        add("chains of both semantics");
    } else if spec.communication == Communication::Let {
        add("let");
    }
    if spec.tasks.iter().any(|t| t.deadline_given.is_some()) {
        add("with deadlines");
    }
}

/// How many optimal designs with sections and overheads each run simulates.
const SIMULATED: usize = 30;

/// Simulates a designed spec (a few phasings and demand models, then a
/// short search from the closest run; `common::probe`) and checks every
/// job response time and chain latency against its bound
/// (`common::check_run`). Returns the violations, the bounds checked and
/// the largest observed / bound of a job response time.
fn simulate_design(d: &Spec, seed: u64) -> (Vec<String>, u64, f64) {
    let rep = analyze(d);
    let how = common::Probe {
        runs: common::plain_runs(),
        stride: 7,
        salt: 0xd5,
        horizon: common::horizon(d),
    };
    let mut ratios = vec![0.0; d.tasks.len()];
    let mut failures = Vec::new();
    let mut checks = 0;
    common::probe(d, &rep, seed, &how, &mut |cfg, res| {
        let (n, best) = common::check_run(d, &rep, cfg, res, &mut ratios, &mut failures);
        checks += n;
        best
    });
    let failures = failures
        .into_iter()
        .map(|f| format!("seed {seed}: the simulated design exceeds a bound: {f}"))
        .collect();
    (failures, checks, ratios.iter().copied().fold(0.0, f64::max))
}

/// The period domains of the instances.
#[derive(Clone, Copy)]
enum Shape {
    Choices,
    Ranges,
    /// Ranges under `harmonic = true`.
    Harmonic,
    /// Choices or ranges with critical sections and overheads.
    Contended,
    /// Choices or ranges with deadlines, DM or explicit priorities, QPA,
    /// LET.
    Timed,
}

impl Shape {
    fn name(self) -> &'static str {
        match self {
            Shape::Choices => "",
            Shape::Ranges => ", with ranges",
            Shape::Harmonic => ", harmonic ranges",
            Shape::Contended => ", sections and overheads",
            Shape::Timed => ", deadlines, DM, explicit priorities, QPA, LET",
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn run(
    mode: Mode,
    method: Method,
    first_seed: u64,
    n: usize,
    time_limit: f64,
    shape: Shape,
    event: bool,
) {
    let verbose = std::env::var_os("RTPIPE_DESIGN_VERBOSE").is_some();
    let mut tally: BTreeMap<&'static str, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut slowest = (0.0f64, 0u64);
    let (mut simulated, mut checks, mut closest) = (0, 0, 0.0f64);
    let start = Instant::now();
    for seed in first_seed..first_seed + n as u64 {
        let spec = match shape {
            Shape::Choices => instance(seed, mode),
            Shape::Ranges => instance_with_ranges(seed, mode),
            Shape::Harmonic => match harmonic_instance(seed, mode) {
                Some(s) => s,
                None => {
                    *tally
                        .entry("skipped (fixed periods not harmonic)")
                        .or_default() += 1;
                    continue;
                }
            },
            Shape::Contended => match contended_instance(seed, mode) {
                Some(s) => s,
                None => {
                    *tally.entry("skipped (nothing added)").or_default() += 1;
                    continue;
                }
            },
            Shape::Timed => match timed_instance(seed, mode) {
                Some(s) => s,
                None => {
                    *tally.entry("skipped (refused)").or_default() += 1;
                    continue;
                }
            },
        };
        count_timing(&spec, &mut tally);
        let spec = if event {
            with_event_limits(spec, seed)
        } else {
            spec
        };
        if spec.tasks.iter().any(|t| !t.sections.is_empty()) {
            *tally.entry("with sections").or_default() += 1;
        }
        if !spec.overheads.is_zero() {
            *tally.entry("with overheads").or_default() += 1;
        }
        if spec.tasks.iter().any(|t| t.jitter > 0) {
            *tally.entry("with jitter").or_default() += 1;
        }
        let opts = Options {
            mode,
            method,
            solver: SolverKind::Microlp,
            time_limit: Some(time_limit),
            ..Options::default()
        };
        let t0 = Instant::now();
        let outcome = design(&spec, &opts);
        let secs = t0.elapsed().as_secs_f64();
        if secs > slowest.0 {
            slowest = (secs, seed);
        }
        let o = match outcome {
            Ok(o) => o,
            Err(_) if refused(&spec, mode, method) => {
                *tally.entry("refused (MILP or paper)").or_default() += 1;
                continue;
            }
            Err(e) => {
                *tally.entry("error").or_default() += 1;
                let path = save_bug(&spec, seed, mode);
                failures.push(format!("seed {seed}: design error: {e} ({path})"));
                continue;
            }
        };
        *tally.entry(o.status.name()).or_default() += 1;
        let both = spec.chains.iter().any(|c| c.communication.is_some());
        if both && o.status == Status::Optimal {
            *tally.entry("both semantics optimal").or_default() += 1;
        } else if spec.communication == Communication::Let && o.status == Status::Optimal {
            *tally.entry("let optimal").or_default() += 1;
        }
        if let Shape::Contended | Shape::Timed = shape {
            *tally.entry("boxes or masters").or_default() += o.iterations;
        }
        if verbose {
            eprintln!(
                "{} seed {seed}: {} tasks {} chains, grid {}, {} obj {:?} in {secs:.2} s",
                mode.name(),
                spec.tasks.len(),
                spec.chains.len(),
                grid(&spec),
                o.status.name(),
                o.objective
            );
        }
        if let Err(e) = check(&spec, &o, mode) {
            let path = save_bug(&spec, seed, mode);
            failures.push(format!("seed {seed}: {e} ({path})"));
        }
        if let (Shape::Contended | Shape::Timed, Some(d)) = (shape, o.spec.as_ref()) {
            let sound = o.status == Status::Optimal && mode == Mode::Sound;
            if simulated < SIMULATED && sound && (contended(d) || timed(d)) {
                simulated += 1;
                let (f, n, ratio) = simulate_design(d, seed);
                failures.extend(f);
                checks += n;
                closest = closest.max(ratio);
            }
        }
    }
    if simulated > 0 {
        eprintln!(
            "simulated {simulated} designs: {checks} bounds checked, worst response {:.1} % of its bound",
            100.0 * closest
        );
        assert!(checks > 100 * simulated as u64, "{checks} checks");
    }
    let unknown = tally.get("unknown").copied().unwrap_or(0);
    eprintln!(
        "{} mode ({}){}: {n} instances {tally:?} in {:.1} s (slowest: seed {} {:.2} s)",
        mode.name(),
        method.name(),
        shape.name(),
        start.elapsed().as_secs_f64(),
        slowest.1,
        slowest.0
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        unknown * 10 <= n,
        "{unknown} of {n} instances unknown (more than 10 %)"
    );
}

#[test]
fn sound_mode_agrees_with_brute_force() {
    run(
        Mode::Sound,
        Method::Boxes,
        0,
        cases(300),
        3.0,
        Shape::Choices,
        false,
    );
}

#[test]
fn sound_mode_milp_agrees_with_brute_force() {
    run(
        Mode::Sound,
        Method::Milp,
        0,
        cases(300),
        3.0,
        Shape::Choices,
        false,
    );
}

#[test]
fn paper_mode_agrees_with_brute_force() {
    run(
        Mode::Paper,
        Method::Auto,
        100_000,
        cases(300),
        3.0,
        Shape::Choices,
        false,
    );
}

#[test]
fn paper_mode_milp_agrees_with_brute_force() {
    run(
        Mode::Paper,
        Method::Milp,
        100_000,
        cases(300) / 3,
        3.0,
        Shape::Choices,
        false,
    );
}

#[test]
fn ranges_agree_with_brute_force() {
    let n = cases(300) / 3;
    run(
        Mode::Sound,
        Method::Boxes,
        200_000,
        n,
        3.0,
        Shape::Ranges,
        false,
    );
    run(
        Mode::Paper,
        Method::Auto,
        300_000,
        n,
        3.0,
        Shape::Ranges,
        false,
    );
}

#[test]
fn ranges_agree_with_brute_force_milp() {
    run(
        Mode::Sound,
        Method::Milp,
        200_000,
        cases(300) / 3,
        3.0,
        Shape::Ranges,
        false,
    );
}

#[test]
fn event_limits_agree_with_brute_force() {
    let n = cases(300) / 3;
    run(
        Mode::Sound,
        Method::Boxes,
        400_000,
        n,
        3.0,
        Shape::Choices,
        true,
    );
    run(
        Mode::Sound,
        Method::Milp,
        400_000,
        n,
        3.0,
        Shape::Choices,
        true,
    );
    run(
        Mode::Paper,
        Method::Milp,
        500_000,
        n,
        3.0,
        Shape::Choices,
        true,
    );
}

#[test]
fn harmonic_ranges_agree_with_brute_force() {
    let n = cases(300) / 3;
    run(
        Mode::Sound,
        Method::Boxes,
        600_000,
        n,
        3.0,
        Shape::Harmonic,
        false,
    );
    run(
        Mode::Sound,
        Method::Milp,
        600_000,
        n / 3,
        3.0,
        Shape::Harmonic,
        false,
    );
    run(
        Mode::Sound,
        Method::Boxes,
        700_000,
        n,
        3.0,
        Shape::Harmonic,
        true,
    );
}

/// Critical sections and scheduling overheads: the box search against
/// brute force in sound mode (and in paper mode where it applies; the
/// MILP is refused), some designs simulated.
#[test]
fn contention_agrees_with_brute_force() {
    let n = cases(300);
    run(
        Mode::Sound,
        Method::Auto,
        800_000,
        n,
        3.0,
        Shape::Contended,
        false,
    );
    run(
        Mode::Paper,
        Method::Auto,
        900_000,
        n / 3,
        3.0,
        Shape::Contended,
        false,
    );
    run(
        Mode::Sound,
        Method::Milp,
        800_000,
        n / 10,
        3.0,
        Shape::Contended,
        false,
    );
}

/// Deadlines, deadline-monotonic and explicit priorities, QPA and LET: the
/// box search against brute force in sound mode (and in paper mode where it
/// applies; the MILP is refused), some designs simulated.
#[test]
fn timing_agrees_with_brute_force() {
    let n = cases(300);
    run(
        Mode::Sound,
        Method::Auto,
        1_000_000,
        n,
        3.0,
        Shape::Timed,
        false,
    );
    run(
        Mode::Paper,
        Method::Auto,
        1_100_000,
        n / 3,
        3.0,
        Shape::Timed,
        false,
    );
    run(
        Mode::Sound,
        Method::Milp,
        1_000_000,
        n / 10,
        3.0,
        Shape::Timed,
        false,
    );
}

#[test]
fn instances_are_small_and_varied() {
    let mut feasible = 0;
    let mut ranged = 0;
    for seed in 0..100 {
        let spec = instance(seed, Mode::Sound);
        let g = grid(&spec);
        assert!(g <= 256, "seed {seed}: {g} assignments");
        let with_ranges = instance_with_ranges(seed, Mode::Sound);
        assert!(grid(&with_ranges) <= 600);
        ranged += with_ranges
            .tasks
            .iter()
            .filter(|t| matches!(t.period, PeriodSpec::Range { .. }))
            .count();
        assert!(!spec.chains.is_empty(), "seed {seed}: no chain");
        if brute_force(&spec, Mode::Sound).0.is_some() {
            feasible += 1;
        }
    }
    // Most instances are feasible, some are not.
    assert!((50..100).contains(&feasible), "{feasible} of 100 feasible");
    assert!(ranged > 50, "{ranged} range domains in 100 instances");
}
