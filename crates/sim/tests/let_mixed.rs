//! Communication per chain: random systems whose tasks each
//! communicate under LET or implicitly, simulated task by task as specified
//! (a LET task reads at its release and publishes at its period's end, an
//! implicit one at its start and completion), against the sound bounds of
//! their mixed link terms (docs/analysis.md, "Mixed links").
//!
//! The chain observed runs through tasks of both kinds: the model refuses
//! such a declared chain (a task reads and publishes one way), so the
//! system is parsed with one chain per run of equal semantics, and the
//! whole path is added in code as the chain the simulator measures. That
//! path is also what `--all-paths` bounds for the parsed spec: its pair
//! bound must be the chain's.

mod common;

use proptest::prelude::*;
use rtpipe_analysis::{all_paths, analyze, Anchor, Metric};
use rtpipe_model::{Chain, Nanos, Spec};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};

const MS: Nanos = 1_000_000;

/// One task of the random path: period (ms), exec (ms), CPU, server, LET.
type Task = (Nanos, f64, u32, bool, bool);

fn task() -> impl Strategy<Value = Task> {
    (
        prop::sample::select(vec![2, 3, 4, 5, 6, 8, 10, 12]),
        prop::sample::select(vec![0.05, 0.2, 0.4, 0.6]),
        0u32..2,
        any::<bool>(),
        any::<bool>(),
    )
}

/// The spec: the path t0 → … → t(n−1), one chain per run of equal
/// semantics, a task off the path on CPU 0; then the whole path is added
/// as the last chain (see the module's doc).
fn spec(tasks: &[Task]) -> Spec {
    let mut src = String::from(
        "[system]\nname = \"mixed\"\ntime_unit = \"ms\"\n[channels.mem]\nbandwidth = 100\noverhead = 0.01\n",
    );
    for (i, &(t, exec, cpu, main, _)) in tasks.iter().enumerate() {
        let server = if main { "main" } else { "none" };
        src.push_str(&format!(
            "[tasks.t{i}]\nexec = {exec}\nexec_min = 0.01\nperiod = {t}\nserver = \"{server}\"\ncpu = {cpu}\noutput = {{ channel = \"mem\", size = 1 }}\n"
        ));
        if i > 0 {
            src.push_str(&format!("reads = [\"t{}\"]\n", i - 1));
        }
    }
    src.push_str("[tasks.other]\nexec = 0.5\nperiod = 7\ncpu = 0\n");
    let mut start = 0;
    for i in 1..=tasks.len() {
        if i == tasks.len() || tasks[i].4 != tasks[start].4 {
            let path: Vec<String> = (start..i).map(|k| format!("\"t{k}\"")).collect();
            let comm = if tasks[start].4 { "let" } else { "implicit" };
            src.push_str(&format!(
                "[[chain]]\npath = [{}]\ncommunication = \"{comm}\"\n",
                path.join(", ")
            ));
            start = i;
        }
    }
    let mut spec = Spec::parse("mixed.toml", &src).unwrap_or_else(|e| panic!("{e}\n{src}"));
    let mut whole = Chain::linked(&mut spec.tasks, (0..tasks.len()).collect());
    whole.name = Some("whole".into());
    spec.chains.push(whole);
    spec
}

/// Largest observed / bound over the mixed chains, per (metric, anchor),
/// how many figures were within 1% of their bound, and of how many.
#[derive(Default)]
struct Tight([f64; 4], usize, usize);

/// Simulates the system and checks every observation against its sound
/// bound (and `--all-paths`' pair against the chain's), adding a mixed
/// path's ratios to `tight`.
fn check(tasks: &[Task], offsets: &[Nanos], exec: ExecModel, seed: u64, tight: &mut Tight) {
    let spec = spec(tasks);
    let report = analyze(&spec);
    let whole = spec.chains.len() - 1;
    let bound = |m: Metric, a: Anchor| {
        report
            .chains
            .iter()
            .find(|c| c.chain == whole && c.metric == m)
            .and_then(|c| c.bound.sound(a))
    };
    let quads = [
        (Metric::Reaction, Anchor::Read),
        (Metric::Freshness, Anchor::Read),
        (Metric::Reaction, Anchor::Event),
        (Metric::Freshness, Anchor::Event),
    ];
    let bounds = quads.map(|(m, a)| bound(m, a));
    // --all-paths over the parsed spec bounds the same path the same way.
    let pair = all_paths(&spec, &report.timing)
        .pairs
        .into_iter()
        .find(|p| p.source == 0 && p.sink == tasks.len() - 1)
        .unwrap_or_else(|| panic!("no pair t0 → tail"));
    assert_eq!(pair.reaction_sound.value, bounds[0], "{tasks:?}");
    assert_eq!(pair.freshness_sound.value, bounds[1], "{tasks:?}");
    if bounds.iter().any(Option::is_none) {
        return; // a task may miss its period: no bound to check
    }
    let periods: Vec<Nanos> = tasks.iter().map(|t| t.0 * MS).collect();
    let h = periods
        .iter()
        .fold(1, |h, &t| h / rtpipe_model::gcd(h, t) * t);
    let mut given = offsets.to_vec();
    given.push(0);
    let cfg = SimConfig {
        seed,
        phasing: Phasing::Given(given),
        exec,
        log_jobs: false,
        jitter: rtpipe_sim::Jitter::None,
        ..SimConfig::new(offsets.iter().max().unwrap_or(&0) + 4 * h.max(100 * MS))
    };
    let r = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    let c = &r.chains[whole];
    let seen = [
        c.reaction.max,
        c.freshness.max,
        c.event_reaction.max,
        c.event_freshness.max,
    ];
    let mixed = tasks.iter().any(|t| t.4) && tasks.iter().any(|t| !t.4);
    for (k, (o, b)) in seen.iter().zip(&bounds).enumerate() {
        if let (Some(o), Some(b)) = (o, b) {
            assert!(
                o <= b,
                "{:?}: observed {o} above the sound bound {b}; tasks {tasks:?} offsets {offsets:?}",
                quads[k]
            );
            if mixed {
                tight.0[k] = tight.0[k].max(*o as f64 / *b as f64);
                tight.1 += usize::from(*o as f64 >= 0.99 * *b as f64);
                tight.2 += 1;
            }
        }
    }
}

fn system() -> impl Strategy<Value = (Vec<Task>, Vec<u64>, u8, u64)> {
    (
        prop::collection::vec(task(), 1..=5),
        prop::collection::vec(any::<u64>(), 5),
        0u8..4,
        any::<u64>(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3_000, ..ProptestConfig::default() })]

    #[test]
    fn no_mixed_chain_is_observed_above_its_sound_bound((tasks, raw, how, seed) in system()) {
        // Synchronous, or offsets in [0, T) (whole ms on a grid half the
        // time: simultaneous events, where the worst cases hide).
        let offsets: Vec<Nanos> = tasks
            .iter()
            .zip(&raw)
            .map(|(t, &x)| match how {
                0 => 0,
                1 => (x % t.0 as u64) as Nanos * MS,
                _ => (x % (t.0 as u64 * MS as u64)) as Nanos,
            })
            .collect();
        let exec = [ExecModel::Worst, ExecModel::Extremes, ExecModel::Uniform, ExecModel::Worst][how as usize];
        check(&tasks, &offsets, exec, seed, &mut Tight::default());
    }
}

/// A deterministic sweep with the same checks, arbitrary offsets and
/// worst-case demands, to report and assert tightness: every (metric,
/// anchor) comes within 5% of its bound on some mixed path.
#[test]
fn the_bounds_are_reached_on_some_mixed_systems() {
    let mut t = Tight::default();
    let mut rng = rtpipe_model::gen::Rng::new(1);
    let mut next = || rng.next_u64();
    let pick = |v: u64, s: &[Nanos]| s[(v % s.len() as u64) as usize];
    for case in 0..2_000u64 {
        let n = 2 + (next() % 4) as usize;
        let tasks: Vec<Task> = (0..n)
            .map(|_| {
                (
                    pick(next(), &[2, 3, 4, 5, 6, 8, 10, 12]),
                    [0.05, 0.2, 0.4, 0.6][(next() % 4) as usize],
                    (next() % 2) as u32,
                    next() % 2 == 0,
                    next() % 2 == 0,
                )
            })
            .collect();
        let offsets: Vec<Nanos> = tasks
            .iter()
            .map(|t| (next() % (t.0 as u64 * MS as u64)) as Nanos)
            .collect();
        check(&tasks, &offsets, ExecModel::Worst, case, &mut t);
    }
    eprintln!(
        "mixed chains: largest observed / sound bound (reaction, freshness, reaction from the event, freshness from the event) = {:.4} {:.4} {:.4} {:.4}; {} of {} figures within 1% of the bound",
        t.0[0], t.0[1], t.0[2], t.0[3], t.1, t.2
    );
    for (k, r) in t.0.iter().enumerate() {
        assert!(*r >= 0.95, "metric {k}: largest ratio {r}");
    }
}

/// A random mixed path of 2–5 tasks from `seed`, as [`spec`] builds it.
fn seeded(seed: u64) -> Spec {
    let mut r = rtpipe_model::gen::Rng::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x1e7);
    let n = r.range(2, 5) as usize;
    let tasks: Vec<Task> = (0..n)
        .map(|_| {
            (
                [2, 3, 4, 5, 6, 8, 10, 12][r.range(0, 7) as usize],
                [0.05, 0.2, 0.4, 0.6][r.range(0, 3) as usize],
                r.range(0, 1) as u32,
                r.chance(0.5),
                r.chance(0.5),
            )
        })
        .collect();
    spec(&tasks)
}

/// The tightness of mixed paths (`common::tight`; docs/analysis.md, "How
/// tight, per feature"): minutes of work, hence ignored; `--ignored
/// --nocapture` prints the table.
#[test]
#[ignore]
fn tightness() {
    common::tight::per_feature("let_mixed", seeded);
}
