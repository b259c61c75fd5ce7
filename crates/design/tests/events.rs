//! `design` on specs with work-queue threads and data-triggered tasks
//! (docs/design.md, "Event-triggered specs"): the box search chooses the
//! periods of the periodic sources, every answer passes the event analysis,
//! and no point of the period grid with a lower utilisation passes it.

use rtpipe_analysis::{analyze, Anchor, Mode, Report};
use rtpipe_design::{design, utilization, Method, Options, Outcome, Status};
use rtpipe_model::gen::EventGenConfig;
use rtpipe_model::{Nanos, PeriodSpec, Spec};
use rtpipe_testkit::gen::event_triggered_system;

/// Designs `spec` in `mode` with the default search.
fn run(spec: &Spec, mode: Mode) -> Outcome {
    let opts = Options {
        mode,
        ..Options::default()
    };
    design(spec, &opts).unwrap_or_else(|e| panic!("{e}"))
}

/// The verdict `design` asks of a candidate: schedulable, every limit
/// held in `mode`, and in sound mode every chain bounded from the read.
fn passes(report: &Report, mode: Mode) -> bool {
    let bounded = mode == Mode::Paper
        || report
            .chains
            .iter()
            .all(|c| c.bound.sound(Anchor::Read).is_some());
    bounded && report.ok_in(mode)
}

/// Every value each task's period may take in `spec` (one value for a
/// fixed period, none for a data-triggered task).
fn grid(spec: &Spec) -> Vec<Vec<Nanos>> {
    spec.tasks
        .iter()
        .map(|t| match &t.period {
            PeriodSpec::Fixed(p) => vec![*p],
            PeriodSpec::Choices(v) => v.clone(),
            PeriodSpec::Range {
                min: Some(lo),
                max: Some(hi),
            } => (0..)
                .map(|k| lo + k * spec.resolution)
                .take_while(|p| p <= hi)
                .collect(),
            PeriodSpec::Triggered { .. } => Vec::new(),
            other => panic!("task `{}`: {other:?} has no finite grid", t.name),
        })
        .collect()
}

/// `spec` with the periodic tasks at `periods` (data-triggered ones keep
/// their triggers).
fn at(spec: &Spec, periods: &[Option<Nanos>]) -> Spec {
    let mut s = spec.clone();
    for (t, p) in s.tasks.iter_mut().zip(periods) {
        if let Some(p) = p {
            t.period = PeriodSpec::Fixed(*p);
        }
    }
    s
}

/// The least utilisation over every point of the grid that passes the
/// analysis (`None`: none does), by enumeration.
fn enumerate(spec: &Spec, mode: Mode) -> Option<f64> {
    let axes = grid(spec);
    let free: Vec<usize> = (0..axes.len()).filter(|&i| !axes[i].is_empty()).collect();
    let mut idx = vec![0usize; axes.len()];
    let mut best: Option<f64> = None;
    loop {
        let periods: Vec<Option<Nanos>> = (0..axes.len())
            .map(|i| axes[i].get(idx[i]).copied())
            .collect();
        let s = at(spec, &periods);
        if passes(&analyze(&s), mode) {
            let u = utilization(&s);
            best = Some(best.map_or(u, |b: f64| b.min(u)));
        }
        // The next point: an odometer over the free axes.
        let mut k = 0;
        loop {
            let Some(&i) = free.get(k) else {
                return best;
            };
            idx[i] += 1;
            if idx[i] < axes[i].len() {
                break;
            }
            idx[i] = 0;
            k += 1;
        }
    }
}

/// The answer is verified by the analysis, and its utilisation agrees
/// with enumeration's least (within rounding).
fn check_answer(spec: &Spec, o: &Outcome, mode: Mode, least: Option<f64>, what: &str) {
    match (o.status, least) {
        (Status::Optimal, Some(u)) => {
            let d = o.spec.as_ref().expect("an optimal design");
            assert!(passes(&analyze(d), mode), "{what}: the answer fails");
            let got = utilization(d);
            assert!(
                (got - u).abs() <= 1e-9 * u.max(1.0),
                "{what}: design {got}, enumeration {u}"
            );
        }
        (Status::Infeasible, None) => assert!(o.spec.is_none(), "{what}"),
        (s, l) => panic!(
            "{what}: design says {s:?}, enumeration {l:?} ({})",
            spec.name
        ),
    }
}

#[test]
fn work_queues_design_is_verified_and_binds() {
    let spec = rtpipe_testkit::example("work-queues-design.toml");
    let o = run(&spec, Mode::Sound);
    assert_eq!((o.status, o.method), (Status::Optimal, Method::Boxes));
    let d = o.spec.as_ref().expect("a design");
    // The data-triggered tasks keep their triggers and run at the IMU's
    // rate; the limits bind (the IMU's range ends at 1 ms, 8 kHz).
    let imu = d.task_index("imu").expect("imu");
    let av = d.task_index("angular_velocity").expect("angular_velocity");
    assert!(d.tasks[av].is_triggered());
    assert_eq!(d.activation_period(av), d.tasks[imu].fixed_period());
    assert!(d.tasks[imu].fixed_period() < Some(1_000_000));
    assert!(passes(&analyze(d), Mode::Sound));
}

/// The 5,796 points of the example's grid, each analysed: minutes on a
/// loaded machine, so run on demand (`--ignored`).
#[test]
#[ignore]
fn work_queues_design_beats_every_point_of_its_grid() {
    let spec = rtpipe_testkit::example("work-queues-design.toml");
    let o = run(&spec, Mode::Sound);
    let least = enumerate(&spec, Mode::Sound);
    check_answer(&spec, &o, Mode::Sound, least, "work-queues-design");
}

#[test]
fn the_milp_refuses_threads_at_their_key() {
    let spec = rtpipe_testkit::example("work-queues-design.toml");
    let opts = Options {
        method: Method::Milp,
        ..Options::default()
    };
    let e = design(&spec, &opts).expect_err("the MILP has no event analysis");
    let text = e.to_string();
    assert!(text.contains("threads and data-triggered tasks"), "{text}");
    assert_eq!(e.key.as_deref(), Some("tasks.imu.thread"), "{text}");
    assert!(e
        .diagnostic
        .help
        .as_deref()
        .is_some_and(|h| h.contains("--method boxes")));
}

/// Small generated systems: up to two chains of four tasks, one timer,
/// one CPU (so enumeration stays cheap).
fn small() -> EventGenConfig {
    EventGenConfig {
        max_chains: 2,
        max_links: 4,
        max_timers: 1,
        max_cpus: 1,
        ..EventGenConfig::default()
    }
}

/// The period values a periodic task of period T may take in a problem.
#[derive(Debug, Clone, Copy)]
enum Grid {
    /// {T/2, T, 2T}: halving can bring a CPU's load near 1, where one
    /// analysis iterates long (some systems then take minutes to
    /// enumerate).
    HalfToDouble,
    /// {T, 2T}: the load stays at most the generated one.
    OneOrDouble,
}

/// A generated event-triggered system with its periodic tasks' periods
/// free on `grid` (values at least their budget) and, per chain, a
/// from-event freshness limit at `scale` times its sound bound at the
/// generated periods (`None`: the system is not a design problem).
fn problem(seed: u64, grid: Grid, scale: f64) -> Option<Spec> {
    let mut spec = event_triggered_system(seed, &small());
    let report = analyze(&spec);
    for c in &report.chains {
        let bound = c.bound.sound(Anchor::Event)?;
        let limit = (bound as f64 * scale) as Nanos;
        spec.chains[c.chain].freshness_from_event = Some(limit.max(1));
    }
    for t in spec.tasks.iter_mut() {
        if let Some(p) = t.fixed_period() {
            let values = match grid {
                Grid::HalfToDouble => vec![p / 2, p, 2 * p],
                Grid::OneOrDouble => vec![p, 2 * p],
            };
            let choices: Vec<Nanos> = values.into_iter().filter(|&q| q >= t.budget()).collect();
            t.period = PeriodSpec::Choices(choices);
        }
    }
    Some(spec)
}

#[test]
fn generated_event_systems_agree_with_enumeration() {
    // Periods halved too: three systems keep the suite short on a loaded
    // machine (one of the first ten takes minutes); raise it to test more.
    let systems = rtpipe_testkit::env_u64("RTPIPE_EVENT_DESIGN_CASES", 3);
    let (optimal, infeasible) = agree_with_enumeration(systems, Grid::HalfToDouble);
    assert!(optimal > 0 && infeasible > 0);
}

#[test]
fn many_generated_event_systems_agree_with_enumeration() {
    // Periods kept or doubled: 200 systems take seconds.
    let systems = rtpipe_testkit::env_u64("RTPIPE_EVENT_DESIGN_SYSTEMS", 200);
    let (optimal, infeasible) = agree_with_enumeration(systems, Grid::OneOrDouble);
    assert!(optimal > 0 && infeasible > 0);
}

/// Designs three problems of each of `systems` generated systems on
/// `grid` and checks each against enumeration: (optimal, infeasible)
/// counts.
fn agree_with_enumeration(systems: u64, grid: Grid) -> (usize, usize) {
    let (mut optimal, mut infeasible) = (0, 0);
    for seed in 0..systems {
        for (scale, mode) in [(1.0, Mode::Sound), (0.8, Mode::Sound), (1.0, Mode::Paper)] {
            let Some(spec) = problem(seed, grid, scale) else {
                continue;
            };
            let o = run(&spec, mode);
            assert_eq!(o.method, Method::Boxes);
            let least = enumerate(&spec, mode);
            check_answer(
                &spec,
                &o,
                mode,
                least,
                &format!("seed {seed} x{scale} {mode:?}"),
            );
            match o.status {
                Status::Optimal => optimal += 1,
                _ => infeasible += 1,
            }
        }
    }
    eprintln!("{systems} systems on {grid:?}: {optimal} optimal, {infeasible} infeasible");
    (optimal, infeasible)
}

/// The search cuts a source's period by a from-event limit because the
/// analysis' bound from the event is at least the head's activation
/// period (`design/src/events.rs`): checked on generated systems.
#[test]
fn the_bound_from_the_event_is_at_least_the_heads_activation_period() {
    let mut checked = 0;
    for seed in 0..40 {
        let spec = event_triggered_system(seed, &small());
        let report = analyze(&spec);
        for c in &report.chains {
            let head = spec.chains[c.chain].path[0];
            let t = spec.activation_period(head).expect("fixed periods");
            if let Some(b) = c.bound.sound(Anchor::Event) {
                assert!(b >= t, "seed {seed}: chain {} bound {b} < {t}", c.chain);
                checked += 1;
            }
        }
    }
    assert!(checked > 20, "{checked}");
}
