//! Known release offsets (docs/analysis.md, "Known release offsets"): the
//! golden case of the cause-effect-chain literature by hand, the fallbacks
//! and the late start.

use rtpipe_analysis::offsets::{chain_offsets, Basis, ChainOffsets, Fallback, MAX_JOBS};
use rtpipe_analysis::{analyze, analyze_chain, schedulability, Anchor, Metric, Report};
use rtpipe_model::{Nanos, Spec};
use rtpipe_testkit::{example_text, spec};

const MS: Nanos = 1_000_000;

/// The E2EEvaluation example (Kloda et al., ETFA 2018; Becker et al., JSA
/// 2017): periods 5, 10, 20 ms, execution times 1, 2, 5 ms (best = worst),
/// RM, synchronous release, chain t20 → t5 → t10, zero-cost transfers.
fn golden_text() -> String {
    example_text("e2e-golden.toml")
}

const QUANTITIES: [(Metric, Anchor); 4] = [
    (Metric::Reaction, Anchor::Read),
    (Metric::Freshness, Anchor::Read),
    (Metric::Reaction, Anchor::Event),
    (Metric::Freshness, Anchor::Event),
];

fn known(r: &Report, chain: usize) -> &ChainOffsets {
    match r.offsets.get(chain).and_then(Option::as_ref) {
        Some(o) => o,
        None => panic!("chain {chain} has no known-offset result"),
    }
}

/// The four reported values, in [`QUANTITIES`] order.
fn values(o: &ChainOffsets) -> [Option<Nanos>; 4] {
    QUANTITIES.map(|(m, a)| o.get(m, a).value)
}

/// The arbitrary-phasing sound bounds, in [`QUANTITIES`] order.
fn any_phasing(r: &Report, chain: usize) -> [Option<Nanos>; 4] {
    QUANTITIES.map(|(m, a)| {
        r.chains
            .iter()
            .find(|c| c.chain == chain && c.metric == m)
            .and_then(|c| c.bound.sound(a))
    })
}

/// By hand. R(t5) = 1, R(t10) = 2 + 1 = 3, R(t20) = 5 + 2·1 + 1·2 = 9 (RTA).
/// Windows of job k (release r = k·T): read [r, r + R − x], publish
/// [r + x_min, r + R]:
///   t20 job j: read [20j, 20j + 4], publish [20j + 5, 20j + 9];
///   t5 job m:  read [5m, 5m],       publish [5m + 1, 5m + 1];
///   t10 job q: read [10q, 10q + 1], publish [10q + 2, 10q + 3].
/// Link t20 → t5: t5 preempts t20 (P1), so a t5 job sees a t20 job exactly
/// when released at or after its publish: it may see job j from
/// 5m ≥ 20j + 5 (m ≥ 4j + 1), surely from 5m ≥ 20j + 9 (m ≥ 4j + 2). The
/// t5 jobs that may carry sample j: 4j + 1 ..= 4j + 5 (job 4j + 6, at
/// 20j + 30, surely sees job j + 1, published by 20j + 29).
/// Link t5 → t10: t5 preempts t10 (P2), so a t10 job released at or after a
/// t5 job's release reads it or a newer one: q surely sees m when
/// 5m ≤ 10q, and may see it when 5m + 1 ≤ 10q + 1; both say m ≤ 2q. The
/// t10 jobs carrying t5 jobs 4j + 1 ..= 4j + 5: 2j + 1 ..= 2j + 2.
///
/// - Reaction from the read: the first t5 job sure to see j is 4j + 2
///   (at 20j + 10), the first t10 job sure to see that is 2j + 1 (at
///   20j + 10), which publishes by 20j + 13: 13 ms after the release of j.
/// - Freshness from the read: the last carrier, t10 job 2j + 2, publishes
///   by 20j + 23: 23 ms.
/// - Reaction from the event: an event just after the read of t20 job
///   j − 1 (at 20j − 20 at the earliest) is first reflected by the output
///   of t10 job 2j + 1, by 20j + 13: 33 ms, the 33 ms Kloda et al. and
///   Becker et al. give for this system's maximum reaction time.
/// - Freshness from the event: 20j + 23 − (20j − 20) = 43 ms.
///
/// Every job is the same up to the hyperperiod of 20 ms. (The schedule is
/// fixed here: t20 reads at 20j + 3 and publishes at 20j + 9; t10 job 2j + 1
/// reads at 20j + 11 and publishes at 20j + 13, job 2j + 2 at 20j + 23. The
/// simulator measures 10, 20, 30 and 40 ms; the bounds take the head's read
/// at its release, 3 ms earlier: crates/sim/tests/known_offsets.rs.)
#[test]
fn golden_case_by_hand() {
    let s = spec("golden.toml", &golden_text());
    let r = analyze(&s);
    let o = known(&r, 0);
    assert_eq!(values(o), [13, 23, 33, 43].map(|x| Some(x * MS)));
    for (m, a) in QUANTITIES {
        assert_eq!(o.get(m, a).basis, Basis::KnownOffsets, "{m:?} {a:?}");
        assert_eq!(o.get(m, a).label(&s), "known offsets");
    }
    let jl = o.job_level.as_ref().expect("the job-level analysis ran");
    assert_eq!(jl.hyperperiod, 20 * MS);
    // Warm-up: largest offset 0 + head period 20 + R(t5) 1 + R(t10) 3 = 24;
    // the span [0, 44) holds 3 t20 jobs, 9 t5 jobs and 5 t10 jobs.
    assert_eq!((jl.head_jobs, jl.jobs), (3, 17));
    // Far below the arbitrary-phasing bounds (26, 36, 46 and 56 ms).
    assert_eq!(any_phasing(&r, 0), [26, 36, 46, 56].map(|x| Some(x * MS)));
}

/// The same system with offsets that make the links wait longer: t5 at
/// 4 ms, t10 at 1 ms (t20 at 0). Values checked against the formulas by
/// hand for the reaction from the event: t20 job j publishes by 20j + 9;
/// the first t5 job released at or after it is at 20j + 9 (4 + 5m = 20j + 9
/// for m = 4j + 1); t5 preempts t10 (P2): the first t10 job released at or
/// after 20j + 9 is at 20j + 11; it publishes by 20j + 11 + 3 = 20j + 14,
/// 34 ms after the release of job j − 1.
#[test]
fn offsets_move_the_bound() {
    let src = golden_text()
        .replace("period = 5\n", "period = 5\noffset = 4\n")
        .replace("period = 10\n", "period = 10\noffset = 1\n");
    let s = spec("golden-offsets.toml", &src);
    let r = analyze(&s);
    let o = known(&r, 0);
    assert_eq!(o.get(Metric::Reaction, Anchor::Event).value, Some(34 * MS));
    assert_eq!(
        o.get(Metric::Reaction, Anchor::Event).basis,
        Basis::KnownOffsets
    );
}

#[test]
fn without_known_offsets_there_is_nothing_to_add() {
    let s = spec(
        "golden.toml",
        &golden_text().replace("release = \"synchronous\"\n", ""),
    );
    let r = analyze(&s);
    assert_eq!(r.offsets, vec![None]);
}

#[test]
fn unknown_offsets_fall_back_and_say_which() {
    // Only t20 has an offset: the chain uses the arbitrary-phasing bound.
    let src = golden_text()
        .replace("release = \"synchronous\"\n", "")
        .replace("period = 20\n", "period = 20\noffset = 3\n");
    let s = spec("golden-partial.toml", &src);
    let r = analyze(&s);
    let o = known(&r, 0);
    assert_eq!(values(o), any_phasing(&r, 0));
    let b = o.get(Metric::Reaction, Anchor::Read);
    assert_eq!(
        b.basis,
        Basis::AnyPhasing(Fallback::UnknownOffsets(vec![0, 1]))
    );
    assert_eq!(b.label(&s), "any phasing (offset unknown: t5, t10)");
    assert!(o.job_level.is_none());
}

#[test]
fn too_many_jobs_fall_back_and_say_how_many() {
    let s = spec("golden.toml", &golden_text());
    let (timing, _) = schedulability(&s);
    let path = &s.chains[0].path;
    let any = analyze_chain(&s, &timing, path);
    // The golden chain needs 17 jobs.
    let Some(o) = chain_offsets(&s, &timing, 0, path, &any, 16) else {
        panic!("known offsets")
    };
    let b = o.get(Metric::Freshness, Anchor::Event);
    assert_eq!(b.basis, Basis::AnyPhasing(Fallback::TooManyJobs(17)));
    assert_eq!(b.label(&s), "any phasing (hyperperiod too long: 17 jobs)");
    assert_eq!(values(&o), any_phasing(&analyze(&s), 0));
    let o = chain_offsets(&s, &timing, 0, path, &any, 17);
    assert!(o.is_some_and(|o| o.job_level.is_some()));
    // Coprime periods in the ms range: the hyperperiod explodes, and the
    // limit stops the lcm long before it could overflow.
    let big = golden_text()
        .replace("period = 5\n", "period = 4.999999\n")
        .replace("period = 10\n", "period = 9.999997\n")
        .replace("period = 20\n", "period = 19.999993\n");
    let s = spec("big.toml", &big);
    let r = analyze(&s);
    let b = known(&r, 0).get(Metric::Reaction, Anchor::Read);
    assert!(
        matches!(b.basis, Basis::AnyPhasing(Fallback::TooManyJobs(n)) if n > MAX_JOBS),
        "{b:?}"
    );
    assert_eq!(b.value, r.chains[0].bound.sound(Anchor::Read));
}

/// A task that starts later than one period: head `a` (T = 5 ms, offset 0)
/// feeds `b` (T = 10 ms, offset 100 ms). No sample reaches b before 100 ms,
/// so an event just after a's first read (at 0) is first reflected by b's
/// first output, at 100 + R_b: far above the arbitrary-phasing bound from
/// the event (which assumes b releases a job every 10 ms from the start).
/// The job-level analysis covers the start; the fallback raises the
/// arbitrary-phasing figure by the delay to the last start.
#[test]
fn late_start_is_covered() {
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
    // Specs refuse offsets of a period or more; code can still build them,
    // and the analysis covers them.
    let mut s: Spec = spec("late.toml", src);
    s.tasks[1].offset = Some(100 * MS);
    let r = analyze(&s);
    let any = any_phasing(&r, 0);
    let o = known(&r, 0);
    let ev = o.get(Metric::Reaction, Anchor::Event);
    // R_a = 1, R_b = 3. Head job 1 (the event after job 0's read at 0):
    // b's first job (released at 100) is the first sure to see it; it
    // publishes by 103.
    assert_eq!(ev.value, Some(103 * MS));
    assert_eq!(ev.basis, Basis::KnownOffsets);
    assert!(any[2].is_some_and(|b| b < 103 * MS));
    // The fallback: the same with a limit of one job.
    let (timing, _) = schedulability(&s);
    let path = &s.chains[0].path;
    let chain = analyze_chain(&s, &timing, path);
    let Some(f) = chain_offsets(&s, &timing, 0, path, &chain, 1) else {
        panic!("known offsets")
    };
    let fe = f.get(Metric::Reaction, Anchor::Event);
    assert_eq!(fe.value, any[2].map(|b| b + 100 * MS));
    assert!(fe.late_start && fe.label(&s).ends_with(", late start"));
    // Reaction from the read falls back to freshness from the read.
    assert_eq!(f.get(Metric::Reaction, Anchor::Read).value, any[1]);
    assert!(!f.get(Metric::Freshness, Anchor::Read).late_start);
}
