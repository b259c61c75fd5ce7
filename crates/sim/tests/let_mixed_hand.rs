//! Communication per chain, by hand (docs/analysis.md, "Mixed links"):
//! a (LET, T = 5, x = 1) → b (implicit, T = 10, x = 2) → c (LET, T = 4,
//! x = 1), one CPU, rate monotonic, no transfer costs. R_c = 1, R_a = 2,
//! R_b = 2 + ⌈4/4⌉ + ⌈4/5⌉ = 4.
//!
//! The sound bound of the path, link by link from releases:
//! - reaction: a → b (LET p) min(T_a + T_b, 2·T_a) = 10 (the head is
//!   distinct: b's job carrying a sample reads before a's next publish,
//!   2·T_a after the head's release); b → c (implicit p, LET c)
//!   min(R_b + T_c, T_b + R_b) = min(8, 14) = 8 (b is distinct: its reads
//!   are ≥ T_b − R_b + x_b = 8 apart, a publishes every 5); the tail
//!   publishes T_c = 4 after its release: 22;
//! - freshness: 2·T_a = 10, then T_b + R_b + T_c = 18: 28;
//! - from the event (no reachability): T_a + 15 + 8 + 4 = 32 and
//!   T_a + 28 = 33.
//!
//! Synchronous release, worst-case demands (hyperperiod 20): c runs
//! [4m, 4m + 1]; a [0, 1+1], [5, 6], [10, 11], [15, 16]; b reads at 2 and
//! publishes at 4, reads at 11 and publishes at 14. b's read at 2 finds
//! nothing, at 11 a's job 1 (read 5, out at 10); at 22 job 3 (read 15). a's
//! jobs 0 and 2 (mod 4) are lost. Job 1: b out at 14, first c read at 16
//! (out 20), last c read at 20 (b publishes again at 24, before c's read
//! there): reaction 15, freshness 19. Job 3: b out at 24, c reads 24 … 32:
//! out 28 and 36: 13 and 21. From the event: just after a's read at 15
//! the next sample to get through is job 5 (read 25), out at 40: 25; job 3's
//! freshness from the read before (10): 36 − 10 = 26.

use rtpipe_analysis::{all_paths, analyze, Anchor, Metric};
use rtpipe_model::{Chain, Nanos, Spec};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};

const MS: Nanos = 1_000_000;

const SRC: &str = r#"
[system]
name = "hand"
time_unit = "ms"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.a]
exec = 1
period = 5
server = "none"
output = { channel = "mem", size = 0 }
[tasks.b]
exec = 2
period = 10
server = "none"
reads = ["a"]
output = { channel = "mem", size = 0 }
[tasks.c]
exec = 1
period = 4
server = "none"
reads = ["b"]
[[chain]]
path = ["a"]
communication = "let"
[[chain]]
path = ["c"]
communication = "let"
"#;

#[test]
fn a_let_implicit_let_path_by_hand() {
    let mut spec = Spec::parse("hand.toml", SRC).unwrap_or_else(|e| panic!("{e}"));
    let report = analyze(&spec);
    let r: Vec<_> = report.timing.iter().map(|t| t.job_response_time).collect();
    assert_eq!(r, vec![Some(2 * MS), Some(4 * MS), Some(MS)]);
    // --all-paths on the spec as written: the one mixed path a > b > c.
    let pair = all_paths(&spec, &report.timing)
        .pairs
        .into_iter()
        .find(|p| p.source == 0 && p.sink == 2)
        .unwrap_or_else(|| panic!("no pair a → c"));
    assert_eq!(pair.reaction_sound.value, Some(22 * MS));
    assert_eq!(pair.freshness_sound.value, Some(28 * MS));
    assert_eq!(pair.freshness_sound.path, vec![0, 1, 2]);
    // The same path as a chain the simulator measures (built in code: the
    // model refuses a declared chain of two semantics).
    let whole = Chain::linked(&mut spec.tasks, vec![0, 1, 2]);
    spec.chains.push(whole);
    let report = analyze(&spec);
    let bound = |m: Metric, a: Anchor| {
        report
            .chains
            .iter()
            .find(|c| c.chain == 2 && c.metric == m)
            .and_then(|c| c.bound.sound(a))
    };
    assert_eq!(bound(Metric::Reaction, Anchor::Read), Some(22 * MS));
    assert_eq!(bound(Metric::Freshness, Anchor::Read), Some(28 * MS));
    assert_eq!(bound(Metric::Reaction, Anchor::Event), Some(32 * MS));
    assert_eq!(bound(Metric::Freshness, Anchor::Event), Some(33 * MS));
    let cfg = SimConfig {
        phasing: Phasing::Sync,
        exec: ExecModel::Worst,
        jitter: rtpipe_sim::Jitter::None,
        ..SimConfig::new(400 * MS)
    };
    let sim = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    let c = &sim.chains[2];
    assert_eq!(c.reaction.max, Some(15 * MS));
    assert_eq!(c.freshness.max, Some(21 * MS));
    assert_eq!(c.event_reaction.max, Some(25 * MS));
    assert_eq!(c.event_freshness.max, Some(26 * MS));
}

/// A fast LET producer feeding a slow implicit consumer: a (LET, T = 1,
/// x = 0.2) → b (implicit, T = 100, x = 1), rate monotonic: R_b = 1.4.
/// A sample of a that reaches b is read by a b job released before a's
/// next publish, 2·T_a after the head's read: reaction from the read
/// 2 + 1.4 = 3.4 ms, not T_a + T_b + R_b = 102.4.
#[test]
fn a_let_producer_has_its_reachability_term() {
    const FAST: &str = r#"
[system]
name = "fast"
time_unit = "ms"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.a]
exec = 0.2
period = 1
server = "none"
output = { channel = "mem", size = 0 }
[tasks.b]
exec = 1
period = 100
server = "none"
reads = ["a"]
[[chain]]
path = ["a"]
communication = "let"
"#;
    let mut spec = Spec::parse("fast.toml", FAST).unwrap_or_else(|e| panic!("{e}"));
    let whole = Chain::linked(&mut spec.tasks, vec![0, 1]);
    spec.chains.push(whole);
    let report = analyze(&spec);
    assert_eq!(report.timing[1].job_response_time, Some(1_400_000));
    let bound = |m: Metric, a: Anchor| {
        report
            .chains
            .iter()
            .find(|c| c.chain == 1 && c.metric == m)
            .and_then(|c| c.bound.sound(a))
    };
    let b = bound(Metric::Reaction, Anchor::Read);
    assert_eq!(b, Some(3_400_000));
    let mut worst = 0;
    for phi in (0..MS).step_by(50_000) {
        let cfg = SimConfig {
            phasing: Phasing::Given(vec![0, phi]),
            exec: ExecModel::Worst,
            jitter: rtpipe_sim::Jitter::None,
            ..SimConfig::new(1_000 * MS)
        };
        let sim = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
        worst = worst.max(sim.chains[1].reaction.max.unwrap_or(0));
    }
    assert!(Some(worst) <= b, "{worst} > {b:?}");
    assert!(worst * 10 >= 3_400_000 * 8, "{worst} far below the bound");
}
