//! The margins (`rtpipe_analysis::margins`): hand-computed on small
//! systems and the bundled examples, and on hundreds of generated systems
//! the property that defines them: the verdict holds at the margin and
//! fails one nanosecond beyond it.

use rtpipe_analysis::margins::{margins, Breach, Control, Factor, Margin, Margins, MarginsError};
use rtpipe_analysis::{analyze, Anchor, Metric, Mode};
use rtpipe_model::{Nanos, Spec};
use rtpipe_testkit::{example, spec};

const MS: Nanos = 1_000_000;

fn quiet(s: &Spec, mode: Mode) -> Margins {
    match margins(s, mode, &Control::QUIET) {
        Ok(m) => m,
        Err(e) => panic!("{}: {e:?}", s.name),
    }
}

/// One task alone on its CPU: its exec may grow until it fills the period,
/// T − C exactly, under the utilisation tests and both modes; under RTA
/// one nanosecond less, as the level-i busy period must end (U < 1,
/// `sched::level_response`). Every exec scales by T / C, rounded down to a
/// millionth, and the period may fall to C (RTA: C + 1 ns).
#[test]
fn one_task_margin_is_period_minus_exec() {
    for (test, strict) in [("rta", 1), ("liu-layland", 0), ("hyperbolic", 0)] {
        let s = spec(
            "one.toml",
            &format!(
                "[system]\nname = \"one\"\nschedulability = \"{test}\"\n[tasks.a]\nexec = 3\nperiod = 10\n"
            ),
        );
        for mode in Mode::ALL {
            let m = quiet(&s, mode);
            assert!(m.holds);
            assert_eq!(m.exec[0].margin, Margin::By(7 * MS - strict), "{test}");
            let beyond = if strict == 1 {
                Breach::Schedulability { cpu: 0 }
            } else {
                // At 10 ms + 1 ns the budget exceeds the period.
                Breach::Rule {
                    task: 0,
                    key: "period",
                }
            };
            assert_eq!(m.exec[0].breach, Some(beyond), "{test}");
            assert_eq!(m.system.factor, Factor::Millionths(3_333_333));
            assert_eq!(m.periods[0].range, Some((3 * MS + strict, None)));
        }
    }
}

/// Two tasks on two CPUs, a → b, reaction limit 10 ms, no transfers. Sound
/// (docs/analysis.md, "Reaction"): the head link is min(W_a + T_b, T_a +
/// W_a) = min(1 + 5, 10 + 1) = 6 ms, plus R_b = 2: 8 ms, slack 2 ms, which
/// a 2 ms growth of either exec eats (W_a and R_b grow one for one).
/// Paper: E = L_a + (T_b − C_b) + L_b = 1 + 3 + 2 = 6 ms (Case 1), slack
/// 4 ms; b's exec cancels (C_b and L_b grow together), a's eats it 1:1.
#[test]
fn two_task_chain_slack_by_hand() {
    let s = spec(
        "pair.toml",
        "[system]\nname = \"pair\"\nschedulability = \"rta\"\n\
         [channels.mem]\nbandwidth = 1\noverhead = 0\n\
         [tasks.a]\nexec = 1\nperiod = 10\ncpu = 0\noutput = { channel = \"mem\", size = 0 }\n\
         [tasks.b]\nexec = 2\nperiod = 5\ncpu = 1\nreads = [\"a\"]\n\
         [[chain]]\npath = [\"a\", \"b\"]\nreaction = 10\n",
    );
    let m = quiet(&s, Mode::Sound);
    let l = &m.limits[0];
    assert_eq!((l.metric, l.anchor), (Metric::Reaction, Anchor::Read));
    assert_eq!(l.bound, Some(8 * MS));
    assert_eq!(l.slack(), Some(2 * MS));
    assert_eq!(l.per_task, vec![Margin::By(2 * MS), Margin::By(2 * MS)]);
    assert_eq!(l.critical(), Some((0, Margin::By(2 * MS))));
    assert_eq!(m.exec[0].margin, Margin::By(2 * MS));
    let reaction = Breach::Limit {
        chain: 0,
        metric: Metric::Reaction,
        anchor: Anchor::Read,
    };
    assert_eq!(m.exec[0].breach, Some(reaction));
    assert_eq!(m.exec[1].margin, Margin::By(2 * MS));
    // Scaling both by f: W_a + T_b + R_b = 1f + 5 + 2f ≤ 10, f ≤ 5/3.
    assert_eq!(m.system.factor, Factor::Millionths(1_666_666));

    let p = quiet(&s, Mode::Paper);
    let l = &p.limits[0];
    assert_eq!(l.bound, Some(6 * MS));
    assert_eq!(l.slack(), Some(4 * MS));
    assert_eq!(l.per_task[0], Margin::By(4 * MS));
    // b does not move the bound at any exec the model allows (budget ≤
    // period); its CPU's RTA (U < 1) ends its exec margin.
    assert_eq!(l.per_task[1], Margin::Unlimited);
    assert_eq!(p.exec[1].margin, Margin::By(3 * MS - 1));
    assert_eq!(p.exec[1].breach, Some(Breach::Schedulability { cpu: 1 }));
}

/// Table III: every budget is 0.5 ms above the demand. Within it an exec
/// grows unseen by the other tasks (they see the budget), so every margin
/// is above 0.5 ms; beyond it the budget follows the demand, and the
/// schedulability test (RTA, R ≤ D) ends each growth, one nanosecond
/// beyond the margin.
#[test]
fn table3_margins_past_the_budgets() {
    let s = example("paper-table3.toml");
    let m = quiet(&s, Mode::Sound);
    let within = analyze(&with_exec(&s, 0, s.tasks[0].exec + MS / 2));
    assert_eq!(within.timing[1..], analyze(&s).timing[1..]);
    for e in &m.exec {
        assert!(matches!(e.margin, Margin::By(v) if v > MS / 2), "{e:?}");
        assert_eq!(e.breach, Some(Breach::Schedulability { cpu: 0 }));
        let Margin::By(v) = e.margin else { continue };
        let grown = with_exec(&s, e.task, e.exec + v + 1);
        assert_eq!(grown.tasks[e.task].budget(), grown.tasks[e.task].demand());
    }
}

/// Cleanflight fails its gyro path's reaction limit by 480 µs under the
/// sound analysis (10 480 µs against 10 000): the slack is −480 µs, pwm's
/// exec (970 µs, alone on the path's last link) must shrink by exactly
/// that, and every exec together by about half.
#[test]
fn cleanflight_infeasible_reports_how_much_to_shrink() {
    let s = example("cleanflight.toml");
    let m = quiet(&s, Mode::Sound);
    assert!(!m.holds);
    let gyro = &m.limits[0];
    assert_eq!(gyro.slack(), Some(-480_000));
    let pwm = s.task_index("pwm").unwrap_or(usize::MAX);
    assert_eq!(m.exec[pwm].margin, Margin::By(-480_000));
    assert_eq!(gyro.critical(), Some((pwm, Margin::By(-480_000))));
    match m.system.factor {
        Factor::Millionths(f) => assert!(f < 1_000_000, "{f}"),
        other => panic!("{other:?}"),
    }
    // Paper mode accepts it.
    assert!(quiet(&s, Mode::Paper).holds);
}

/// Table II fails every reaction limit, whatever one exec is (the periods
/// alone exceed them): no exec margin exists, and each exceeded limit has
/// none either; the schedulability test still passes.
#[test]
fn table2_reaction_limits_are_beyond_any_exec() {
    let s = example("paper-table2.toml");
    let m = quiet(&s, Mode::Sound);
    assert!(!m.holds);
    assert!(m.exec.iter().all(|e| e.margin == Margin::Unreachable));
    assert!(m
        .exec
        .iter()
        .all(|e| matches!(e.breach, Some(Breach::Limit { .. }))));
    assert_eq!(m.system.factor, Factor::Unreachable);
    for l in &m.limits {
        let r = analyze(&s).chains[2 * l.chain + usize::from(l.metric == Metric::Freshness)]
            .bound_in(Mode::Sound, l.anchor);
        assert_eq!(l.bound, r);
    }
}

/// Work-queue threads and data-triggered tasks: the rate loop of the
/// example has slack against its limit, and each margin is an edge.
#[test]
fn event_triggered_margins_are_edges() {
    let s = example("work-queues.toml");
    let m = quiet(&s, Mode::Sound);
    assert!(m.holds);
    for e in &m.exec {
        let Margin::By(v) = e.margin else {
            panic!("task {}: {:?}", e.task, e.margin)
        };
        assert!(verdict(&with_exec(&s, e.task, e.exec + v), Mode::Sound));
        assert!(!verdict(
            &with_exec(&s, e.task, e.exec + v + 1),
            Mode::Sound
        ));
    }
}

/// The stop flag ends the search at the next evaluation.
#[test]
fn stop_ends_the_search() {
    let s = example("cleanflight.toml");
    let calls = std::cell::Cell::new(0);
    let stop = || {
        calls.set(calls.get() + 1);
        calls.get() > 10
    };
    let ctl = Control {
        stop: &stop,
        progress: &|_, _| {},
    };
    assert_eq!(margins(&s, Mode::Sound, &ctl), Err(MarginsError::Stopped));
    assert_eq!(calls.get(), 11);
}

// --- Generated systems -------------------------------------------------

use proptest::prelude::*;
use rtpipe_model::gen::{random_system, GenConfig};
use rtpipe_model::Scheduler;
use rtpipe_testkit::{check, env_u64};

prop_compose! {
    /// Acyclic systems of 2..=8 tasks on 1..=3 CPUs with 1..=4 chains
    /// (small: under EDF one analysis takes a millisecond or more).
    fn gen_config()(
        tasks in 2usize..=8,
        cpus in 1u32..=3,
        edf in any::<bool>(),
        utilization in 0.2f64..=0.9,
        chains in 1usize..=4,
        transfers in any::<bool>(),
        mixed_servers in any::<bool>(),
    ) -> GenConfig {
        GenConfig {
            tasks,
            cpus,
            utilization,
            scheduler: if edf { Scheduler::Edf } else { Scheduler::Rm },
            source_fraction: 0.3,
            max_fan_in: 2,
            feedback: 0.0,
            chains,
            transfers,
            mixed_servers,
            inheritance: if mixed_servers { 0.3 } else { 0.0 },
        }
    }
}

/// A generated system whose chains get limits at `scale` times their
/// bounds under `mode` (from the read and from the event), so that some
/// limits hold and some fail.
fn limited_system(seed: u64, cfg: &GenConfig, mode: Mode, scale: f64) -> Spec {
    limited(random_system(seed, cfg), mode, scale)
}

/// `s` with chain limits at `scale` times its bounds under `mode`.
fn limited(mut s: Spec, mode: Mode, scale: f64) -> Spec {
    let r = analyze(&s);
    for c in &r.chains {
        let limit = |a: Anchor| {
            c.bound_in(mode, a)
                .map(|b| (b as f64 * scale) as Nanos)
                .filter(|&l| l > 0)
        };
        let ch = &mut s.chains[c.chain];
        match c.metric {
            Metric::Reaction => {
                ch.reaction = limit(Anchor::Read);
                ch.max_reaction_time = limit(Anchor::Event);
            }
            Metric::Freshness => {
                ch.freshness = limit(Anchor::Read);
                ch.freshness_from_event = limit(Anchor::Event);
            }
        }
    }
    s
}

/// The verdict `margins` searches with, from the public analysis: every
/// timing rule of the model, then `Report::ok_in`.
fn verdict(s: &Spec, mode: Mode) -> bool {
    (0..s.tasks.len()).all(|i| s.timing_conflict(i).is_none())
        && rtpipe_analysis::analyze_verdict(s).ok_in(mode)
}

/// Task `i` with exec `v`, a given budget raised to the demand where the
/// demand outgrows it (as the margins resize a reservation).
fn with_exec(s: &Spec, i: usize, v: Nanos) -> Spec {
    let mut s = s.clone();
    let t = &mut s.tasks[i];
    t.exec = v;
    t.exec_min = t.exec_min.min(v);
    let demand = t.demand();
    if let Some(c) = &mut t.budget_given {
        *c = (*c).max(demand);
    }
    s
}

fn with_period(s: &Spec, i: usize, p: Nanos) -> Spec {
    let mut s = s.clone();
    s.tasks[i].period = rtpipe_model::PeriodSpec::Fixed(p);
    s
}

fn scaled(s: &Spec, millionths: u64) -> Spec {
    let mut out = s.clone();
    for (i, t) in s.tasks.iter().enumerate() {
        let v = (i128::from(t.exec) * i128::from(millionths) / 1_000_000) as Nanos;
        out = with_exec(&out, i, v);
    }
    out
}

/// Every exec margin is an edge of the public verdict: it holds at exec +
/// margin and fails 1 ns beyond; the system's scaling factor likewise at
/// one millionth; each period range at its ends. Whether the verdict also
/// holds at points before the edge (monotonicity) is checked on a sample
/// and must hold in sound mode; paper mode's exceptions are tallied.
#[test]
fn margins_are_edges_of_the_verdict() {
    let cases = env_u64("RTPIPE_MARGIN_CASES", 300) as u32;
    let strategy = (any::<u64>(), gen_config(), any::<bool>(), 0.7f64..1.6);
    check(
        "margins_are_edges",
        cases,
        strategy,
        |(seed, cfg, paper, scale)| {
            let mode = if paper { Mode::Paper } else { Mode::Sound };
            let s = limited_system(seed, &cfg, mode, scale);
            let m = quiet(&s, mode);
            prop_assert_eq!(m.holds, verdict(&s, mode));
            let mut monotone = true;
            for e in &m.exec {
                if let Margin::By(v) = e.margin {
                    let edge = e.exec + v;
                    prop_assert!(
                        verdict(&with_exec(&s, e.task, edge), mode),
                        "task {} at {edge}",
                        e.task
                    );
                    prop_assert!(
                        !verdict(&with_exec(&s, e.task, edge + 1), mode),
                        "task {} at {edge}+1",
                        e.task
                    );
                    for k in 1..4 {
                        monotone &= verdict(&with_exec(&s, e.task, edge * k / 4), mode);
                    }
                }
            }
            if let Factor::Millionths(f) = m.system.factor {
                prop_assert!(verdict(&scaled(&s, f), mode));
                prop_assert!(!verdict(&scaled(&s, f + 1), mode));
            }
            for p in &m.periods {
                if let Some((lo, hi)) = p.range {
                    prop_assert!(verdict(&with_period(&s, p.task, lo), mode));
                    prop_assert!(lo == 1 || !verdict(&with_period(&s, p.task, lo - 1), mode));
                    if let Some(hi) = hi {
                        prop_assert!(verdict(&with_period(&s, p.task, hi), mode));
                        prop_assert!(!verdict(&with_period(&s, p.task, hi + 1), mode));
                    }
                }
            }
            prop_assert!(
                monotone || mode == Mode::Paper,
                "sound verdict not monotone in an exec"
            );
            Ok(match (monotone, mode, m.holds) {
                (false, _, _) => "paper: not monotone below an edge",
                (true, Mode::Sound, true) => "sound, holds",
                (true, Mode::Sound, false) => "sound, fails",
                (true, Mode::Paper, true) => "paper, holds",
                (true, Mode::Paper, false) => "paper, fails",
            })
        },
    );
}

/// Paper mode is not monotone in an exec (docs/analysis.md, "Margins"):
/// a (1 ms, T 20) → b (1, T 10) → c (1, T 20) has the paper reaction 21 ms
/// (Eq. 2 adds T_b − C_b + L_b, Eq. 4 subtracts C_b), 20 ms with exec_b =
/// 2. Against a 20.5 ms limit no shrinking of b helps, so its margin is
/// `Unreachable`, though growing it does: the answer says it is not exact.
#[test]
fn paper_margins_are_edges_not_maxima() {
    let text = "[system]\nname = \"nm\"\nschedulability = \"rta\"\n\
                [channels.mem]\nbandwidth = 1\noverhead = 0\n\
                [tasks.a]\nexec = 1\nperiod = 20\noutput = { channel = \"mem\", size = 0 }\n\
                [tasks.b]\nexec = 1\nperiod = 10\nreads = [\"a\"]\noutput = { channel = \"mem\", size = 0 }\n\
                [tasks.c]\nexec = 1\nperiod = 20\nreads = [\"b\"]\n\
                [[chain]]\npath = [\"a\", \"b\", \"c\"]\nreaction = 20.5\n";
    let s = spec("nm.toml", text);
    let m = quiet(&s, Mode::Paper);
    assert!(!m.holds && !m.exact);
    assert_eq!(m.exec[1].margin, Margin::Unreachable);
    assert_eq!(m.exec[0].margin, Margin::By(-MS / 2));
    assert!(verdict(&with_exec(&s, 1, 2 * MS), Mode::Paper));
    assert!(quiet(&s, Mode::Sound).exact);
}

/// A task of 3 ns: the scaling factor's search ends at MAX_TIME millionths,
/// not at 10⁶ · MAX_TIME / 3, which overflows a Nanos (wrapped, it was
/// negative). 3 ns in a 10 ms period scales by (10⁷ − 1) / 3 (RTA: U < 1),
/// to the last millionth whose product rounds down to it.
#[test]
fn scaling_a_tiny_exec_does_not_overflow() {
    let s = spec(
        "tiny.toml",
        "[system]\nname = \"tiny\"\nschedulability = \"rta\"\n[tasks.a]\nexec = \"3ns\"\nperiod = 10\n",
    );
    let m = quiet(&s, Mode::Sound);
    // ⌊3 · m / 10⁶⌋ ≤ 9 999 999 ns ⇔ m ≤ 3 333 333 333 333.
    assert_eq!(m.system.factor, Factor::Millionths(3_333_333_333_333));
}

/// The same on generated event-triggered systems (threads, data-triggered
/// tasks, join any and all): the sound verdict is monotone in every exec
/// there too, and every margin is an edge of it.
#[test]
fn event_triggered_margins_are_edges_of_the_verdict() {
    use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
    // Each case searches every margin with the full analysis as oracle:
    // seconds on a large generated system, so few and small by default.
    let cases = env_u64("RTPIPE_EVENT_MARGIN_CASES", 12) as u32;
    let strategy = (any::<u64>(), 0.2f64..0.9, 0.7f64..1.6);
    check(
        "event_triggered_margins",
        cases,
        strategy,
        |(seed, utilization, scale)| {
            let cfg = EventGenConfig {
                utilization,
                max_chains: 1,
                max_links: 4,
                max_threads: 3,
                max_timers: 1,
                ..EventGenConfig::default()
            };
            let s = limited(event_triggered_system(seed, &cfg), Mode::Sound, scale);
            let m = quiet(&s, Mode::Sound);
            prop_assert_eq!(m.holds, verdict(&s, Mode::Sound));
            for e in &m.exec {
                if let Margin::By(v) = e.margin {
                    let edge = e.exec + v;
                    prop_assert!(verdict(&with_exec(&s, e.task, edge), Mode::Sound));
                    prop_assert!(!verdict(&with_exec(&s, e.task, edge + 1), Mode::Sound));
                    for k in 1..4 {
                        prop_assert!(
                            verdict(&with_exec(&s, e.task, edge * k / 4), Mode::Sound),
                            "sound verdict not monotone in task {}'s exec",
                            e.task
                        );
                    }
                }
            }
            Ok(if m.holds { "holds" } else { "fails" })
        },
    );
}
