//! Known release offsets in the simulator: every phasing keeps them, a
//! given phasing must agree with them, the search leaves them alone, and the
//! golden case of docs/analysis.md ("Known release offsets") runs as
//! computed by hand.

use rtpipe_analysis::{analyze, Anchor, Metric};
use rtpipe_joblog::SimResult;
use rtpipe_model::gen::{random_system, GenConfig};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::observe::{observe, ChainStatsExt};
use rtpipe_sim::search::{search_with, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig, SimError};

const MS: Nanos = 1_000_000;

fn parse(name: &str, src: &str) -> Spec {
    Spec::parse(name, src).unwrap_or_else(|e| panic!("{e}"))
}

fn run(spec: &Spec, phasing: Phasing, horizon: Nanos) -> SimResult {
    let cfg = SimConfig {
        horizon,
        seed: 5,
        phasing,
        exec: ExecModel::Uniform,
        log_jobs: false,
        jitter: rtpipe_sim::Jitter::Uniform,
    };
    simulate(spec, &cfg).unwrap_or_else(|e| panic!("{e}"))
}

/// A generated system with known offsets on some tasks.
fn with_some_known() -> Spec {
    let mut known = random_system(3, &GenConfig::default());
    for (i, t) in known.tasks.iter_mut().enumerate() {
        if i % 3 == 0 {
            t.offset = Some(i as Nanos * 1_000 + 7);
        }
    }
    known
}

#[test]
fn every_phasing_keeps_known_offsets() {
    let known = with_some_known();
    let h = 100 * MS;
    for phasing in [Phasing::Sync, Phasing::Random, Phasing::Grid(MS)] {
        let res = run(&known, phasing.clone(), h);
        for (i, t) in known.tasks.iter().enumerate() {
            if let Some(o) = t.offset {
                assert_eq!(res.offsets[i], o, "{phasing:?}: task {i}");
            }
        }
    }
    assert!(run(&known, Phasing::Sync, h)
        .offsets
        .iter()
        .zip(&known.tasks)
        .all(|(&o, t)| o == t.offset.unwrap_or(0)));
}

/// Four tasks of one period: `Random` draws one offset per unknown task, in
/// task order, so the unknown tasks get the first draws that the same spec
/// without known offsets gives its first tasks.
#[test]
fn random_draws_only_the_unknown_offsets_in_order() {
    let mut src = String::from("[system]\nname = \"four\"\ntime_unit = \"ms\"\n");
    for k in 0..4 {
        src.push_str(&format!("[tasks.t{k}]\nexec = 1\nperiod = 10\n"));
    }
    let plain = parse("four.toml", &src);
    let known = parse(
        "four-known.toml",
        &src.replacen("period = 10\n", "period = 10\noffset = 2\n", 1)
            .replace(
                "[tasks.t2]\nexec = 1\nperiod = 10\n",
                "[tasks.t2]\nexec = 1\nperiod = 10\noffset = 7\n",
            ),
    );
    let all = run(&plain, Phasing::Random, 50 * MS).offsets;
    let some = run(&known, Phasing::Random, 50 * MS).offsets;
    assert_eq!(some, vec![2 * MS, all[0], 7 * MS, all[1]]);
}

#[test]
fn a_given_phasing_must_agree() {
    let known = with_some_known();
    let mut v = vec![0; known.tasks.len()];
    let cfg = |v: Vec<Nanos>| SimConfig {
        phasing: Phasing::Given(v),
        ..SimConfig::new(10 * MS)
    };
    let err = simulate(&known, &cfg(v.clone())).err();
    assert_eq!(
        err,
        Some(SimError::OffsetConflict {
            task: "t0".into(),
            known: 7,
            given: 0
        })
    );
    let msg = err.map(|e| e.to_string()).unwrap_or_default();
    assert!(
        msg.contains("`t0`") && msg.contains("known offset"),
        "{msg}"
    );
    for (o, t) in v.iter_mut().zip(&known.tasks) {
        *o = t.offset.unwrap_or(12_345);
    }
    assert!(simulate(&known, &cfg(v)).is_ok());
}

#[test]
fn the_search_keeps_known_offsets_fixed() {
    let known = with_some_known();
    let mut runs = 0;
    let cfg = SearchConfig {
        restarts: 4,
        steps: 40,
        seed: 9,
        ..SearchConfig::new(0, Metric::Reaction, 200 * MS)
    };
    let r = search_with(&known, &cfg, |c, res| {
        runs += 1;
        let Phasing::Given(v) = &c.phasing else {
            panic!("the search gives offsets")
        };
        for (i, t) in known.tasks.iter().enumerate() {
            if let Some(o) = t.offset {
                assert_eq!((v[i], res.offsets[i]), (o, o), "task {i}");
            }
        }
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(runs, 4 * 41);
    assert!(!r.exceeds_sound(), "{r}");
    assert!(r.known.is_some());
    // With every offset known, the search varies the demands alone.
    let mut all = known.clone();
    for t in &mut all.tasks {
        t.offset = Some(t.offset.unwrap_or(0));
    }
    let mut execs = std::collections::BTreeSet::new();
    let r = search_with(&all, &cfg, |c, _| {
        execs.insert(format!("{:?}", c.exec));
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        r.best.offsets,
        all.tasks
            .iter()
            .map(|t| t.offset.unwrap_or(0))
            .collect::<Vec<_>>()
    );
    assert!(execs.len() > 1, "{execs:?}");
}

/// The golden case (crates/analysis/tests/offsets.rs derives the bounds
/// 13, 23, 33, 43 ms). The schedule is fixed (best = worst case): t20 reads
/// at 20j + 3 (after t5 and t10), publishes at 20j + 9; t10 job 2j + 1 reads
/// at 20j + 11, publishes at 20j + 13; job 2j + 2 at 20j + 23. So 10 and 20
/// ms from the read, 30 and 40 ms from the event just after t20's previous
/// read (20j − 17).
#[test]
fn golden_case_runs_as_computed() {
    let s = rtpipe_testkit::example("e2e-golden.toml");
    let res = run(&s, Phasing::Random, 400 * MS);
    let c = &res.chains[0];
    let max = |m, a| c.observed(m, a).max;
    assert_eq!(max(Metric::Reaction, Anchor::Read), Some(10 * MS));
    assert_eq!(max(Metric::Freshness, Anchor::Read), Some(20 * MS));
    assert_eq!(max(Metric::Reaction, Anchor::Event), Some(30 * MS));
    assert_eq!(max(Metric::Freshness, Anchor::Event), Some(40 * MS));
    let obs = observe(&analyze(&s), &res);
    assert!(obs.iter().all(|o| o.violations() == 0 && o.known.is_some()));
}

/// A task that starts later than one period (see the analysis test
/// `late_start_is_covered`): the simulator sees an event reaction of 103 ms
/// at the start, far above the arbitrary-phasing bound and exactly the
/// known-offset one, and only the latter counts for these runs.
#[test]
fn a_late_start_breaks_only_the_arbitrary_phasing_bound() {
    let src = r#"
[system]
name = "late"
time_unit = "ms"
scheduler = "rm"
schedulability = "rta"
[channels.mem]
bandwidth = 1
[tasks.a]
exec = 1
period = 5
offset = 0
output = { channel = "mem", size = 0 }
[tasks.b]
exec = 2
period = 10
offset = 0
reads = ["a"]
output = { channel = "mem", size = 0 }
[[chain]]
path = ["a", "b"]
"#;
    // Specs refuse offsets of a period or more; code can still build them.
    let mut s = parse("late.toml", src);
    s.tasks[1].offset = Some(100 * MS);
    let res = simulate(&s, &SimConfig::new(300 * MS)).unwrap_or_else(|e| panic!("{e}"));
    let seen = res.chains[0].observed(Metric::Reaction, Anchor::Event).max;
    // a's job 0 reads at 0. b's first job, released at 100 with a's job 20,
    // waits for it (a has the higher priority), reads its value at 101 and
    // publishes at 103.
    assert_eq!(seen, Some(103 * MS));
    let obs = observe(&analyze(&s), &res);
    let reaction = &obs[0];
    assert!(reaction.event.over_sound.is_some_and(|n| n > 0));
    assert_eq!(reaction.violations(), 0);
}
