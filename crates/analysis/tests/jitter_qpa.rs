//! Hand-computed: response-time analysis with release jitter and
//! constrained deadlines (Audsley, Burns, Richardson, Tindell, Wellings
//! 1993, "Applying new scheduling theory to static priority pre-emptive
//! scheduling": w = C + Σ ⌈(w + J_j)/T_j⌉ C_j, R = J + w), deadline-
//! monotonic and explicit priorities, and QPA (Zhang and Burns 2009,
//! "Schedulability analysis for real-time systems with EDF scheduling").
//! The task sets are small ones worked by hand below (the jitter set is the
//! classic (1, 4), (2, 6), (3, 13) of the RTA textbooks with jitter added);
//! every iteration is written out in the comments.

use rtpipe_analysis::qpa::{demand, qpa};
use rtpipe_analysis::sched::{response_time, response_time_jitter};
use rtpipe_analysis::{analyze, Anchor};
use rtpipe_model::{Nanos, SchedTest, Spec};

const MS: Nanos = 1_000_000;

fn spec(text: &str) -> Spec {
    Spec::parse("t.toml", text).unwrap_or_else(|e| panic!("{e}"))
}

/// τ1 (C 1, T 4, J 3), τ2 (C 2, T 6, J 1), τ3 (C 3, T 13, J 0), rate
/// monotonic:
/// - τ1: w = 1, R1 = J1 + w = 3 + 1 = 4.
/// - τ2: w = 2 + ⌈(w + 3)/4⌉·1: w0 = 3 → 2 + ⌈6/4⌉ = 4 → 2 + ⌈7/4⌉ = 4.
///   R2 = 1 + 4 = 5.
/// - τ3: w = 3 + ⌈(w + 3)/4⌉·1 + ⌈(w + 1)/6⌉·2: w0 = 3 + 1 + 2 = 6 →
///   3 + ⌈9/4⌉ + 2⌈7/6⌉ = 3 + 3 + 4 = 10 → 3 + ⌈13/4⌉ + 2⌈11/6⌉ = 3 + 4 + 4
///   = 11 → 3 + ⌈14/4⌉ + 2⌈12/6⌉ = 3 + 4 + 4 = 11. R3 = 0 + 11 = 11
///   (10 without jitter: `sched::tests::rta_textbook`).
#[test]
fn rta_with_release_jitter_by_hand() {
    assert_eq!(response_time_jitter(1, 3, &[]), Some(4));
    assert_eq!(response_time_jitter(2, 1, &[(1, 4, 3)]), Some(5));
    assert_eq!(
        response_time_jitter(3, 0, &[(1, 4, 3), (2, 6, 1)]),
        Some(11)
    );
    // Without jitter, the textbook's 10.
    assert_eq!(response_time(3, &[(1, 4), (2, 6)]), Some(10));
}

const JITTER_SET: &str = r#"
[system]
name = "jitter"
[tasks.t1]
exec = 1
period = 4
jitter = 3
server = "none"
[tasks.t2]
exec = 2
period = 6
jitter = 1
server = "none"
reads = ["t1"]
output = { channel = "m", size = 0 }
[tasks.t3]
exec = 3
period = 13
deadline = DEADLINE
server = "none"
reads = ["t2"]
[channels.m]
bandwidth = 1
[[chain]]
path = ["t1", "t2", "t3"]
"#;

fn jitter_set(deadline: &str) -> Spec {
    let text = JITTER_SET.replace("DEADLINE", deadline).replace(
        "jitter = 3\n",
        "jitter = 3\noutput = { channel = \"m\", size = 0 }\n",
    );
    spec(&text)
}

/// The same set as a spec: R(job) = 4, 5, 11 ms; with D3 = 11 it passes
/// the RTA test (R ≤ D), with D3 = 10 it does not.
#[test]
fn jitter_spec_response_times_and_deadlines() {
    let s = jitter_set("11");
    assert_eq!(
        s.schedulability,
        SchedTest::Rta,
        "the default test for jitter"
    );
    let r = analyze(&s);
    let rt: Vec<_> = r.timing.iter().map(|t| t.job_response_time).collect();
    assert_eq!(rt, vec![Some(4 * MS), Some(5 * MS), Some(11 * MS)]);
    assert!(r.schedulability.schedulable);
    let r = analyze(&jitter_set("10"));
    assert!(!r.schedulability.schedulable, "R3 = 11 > D3 = 10");
    assert_eq!(r.schedulability.cpus[0].value, 1.1);
}

/// The chain t1 > t2 > t3 with jitter. The tasks are plain (`server =
/// "none"`: no budget to wait for), so the priority arguments hold with J
/// where an anchor moves (`latency::fp_order`); both links have the
/// producer above the consumer (P2). Reaction, link t1 > t2 (the head's
/// samples are distinct): min(R1 + T2, T2 + J1, T1 + R1, T1 + J1) =
/// min(10, 9, 8, 7) = 7; t1 does not pass distinctness on (T2 − R2 + x2 =
/// 3 ≤ T1 + R1 − x_min1 = 8), so link t2 > t3: min(R2 + T3, T3 + J2) =
/// min(18, 14) = 14; with R3: 7 + 14 + 11 = 32. Freshness: (T1 + J1) +
/// (T2 + J2 + R3) = 7 + 18 = 25, and reaction ≤ freshness gives 25. From
/// the event (no reachability): T1 + 9 + 14 + R3 = 4 + 9 + 14 + 11 = 38;
/// freshness from the event 25 + T1 = 29. Davare's reaction from the read,
/// Σ_{i<n} (T_i + R_i) + T_n + R_n − T_1 = 8 + 11 + 24 − 4 = 39.
#[test]
fn jitter_chain_bounds_by_hand() {
    let r = analyze(&jitter_set("13"));
    let reaction = &r.chains[0].bound;
    let freshness = &r.chains[1].bound;
    assert_eq!(reaction.sound(Anchor::Read), Some(25 * MS));
    assert_eq!(freshness.sound(Anchor::Read), Some(25 * MS));
    assert_eq!(
        reaction.get(rtpipe_analysis::Bound::Davare, Anchor::Read),
        Some(39 * MS)
    );
    assert_eq!(reaction.sound(Anchor::Event), Some(38 * MS));
    assert_eq!(freshness.sound(Anchor::Event), Some(29 * MS));
}

/// Deadline monotonic: t2 (T 6, D 3) ranks above t1 (T 4, D 4); rate
/// monotonic keeps t1 first; explicit follows `priority`, 1 the highest.
#[test]
fn deadline_monotonic_and_explicit_ranks() {
    let base = "[system]\nname = \"dm\"\nPRIOS\n[tasks.t1]\nexec = 1\nperiod = 4\nP1\n[tasks.t2]\nexec = 1\nperiod = 6\ndeadline = 3\nP2\n";
    let mk = |prios: &str, p1: &str, p2: &str| {
        spec(
            &base
                .replace("PRIOS", prios)
                .replace("P1", p1)
                .replace("P2", p2),
        )
    };
    let ranks = |s: &Spec| rtpipe_model::policy::ranks(s);
    assert_eq!(ranks(&mk("", "", "")), vec![Some(1), Some(2)]);
    let dm = mk("priorities = \"deadline-monotonic\"", "", "");
    assert_eq!(ranks(&dm), vec![Some(2), Some(1)]);
    // t2 first: R2 = 1, R1 = 1 + 1 = 2.
    let rt: Vec<_> = analyze(&dm)
        .timing
        .iter()
        .map(|t| t.job_response_time)
        .collect();
    assert_eq!(rt, vec![Some(2 * MS), Some(MS)]);
    let ex = mk("priorities = \"explicit\"", "priority = 7", "priority = 3");
    assert_eq!(ranks(&ex), vec![Some(2), Some(1)]);
    let ex = mk("priorities = \"explicit\"", "priority = 1", "priority = 3");
    assert_eq!(ranks(&ex), vec![Some(1), Some(2)]);
}

/// QPA on τ1 (C 1, D 2, T 4), τ2 (C 2, D 4, T 6), τ3 (C 3, D 10, T 13).
/// U = 1/4 + 2/6 + 3/13 = 127/156; Σ (T − D)·U / (1 − U) = (2/4 + 4/6 +
/// 9/13) / (29/156) = (145/78)·(156/29) = 10, so L_a = max(D_max, 10) =
/// 10; the busy period: 6 → 2+2+3 = 7 → 2+4+3 = 9 → 3+4+3 = 10 → 10, so
/// L = 10. Deadlines below 10: 2, 6 (τ1), 4 (τ2); QPA starts at t = 6:
/// h(6) = 2·1 + 1·2 = 4 < 6 → t = 4: h(4) = 1 + 2 = 3 < 4 → t = 3: h(3)
/// = 1 ≤ d_min = 2: schedulable, after visiting 6, 4, 3.
#[test]
fn qpa_schedulable_by_hand() {
    let set = [
        (MS, 4 * MS, 2 * MS),
        (2 * MS, 6 * MS, 4 * MS),
        (3 * MS, 13 * MS, 10 * MS),
    ];
    assert_eq!(demand(&set, 6 * MS), 4 * i128::from(MS));
    let q = qpa(&set);
    assert!(q.schedulable);
    assert_eq!(q.l, 10 * MS);
    assert_eq!(q.visited, vec![6 * MS, 4 * MS, 3 * MS]);
}

/// τ2's deadline down to 2: Σ (T − D)·U / (1 − U) = (1/2 + 4/3 + 9/13)
/// ·156/29 = 13.59, L_a = 14, the busy period is still 10: L = 10.
/// Deadlines below 10: 2, 6 (τ1), 2, 8 (τ2). t = 8: h = 2 + 4 = 6 < 8 →
/// t = 6: h = 2 + 2 = 4 → t = 4: h = 1 + 2 = 3 → t = 3: h = 3 = t → the
/// deadline below 3, t = 2: h(2) = 1 + 2 = 3 > 2: not schedulable (both
/// jobs due at 2 need 3).
#[test]
fn qpa_unschedulable_by_hand() {
    let set = [
        (MS, 4 * MS, 2 * MS),
        (2 * MS, 6 * MS, 2 * MS),
        (3 * MS, 13 * MS, 10 * MS),
    ];
    let q = qpa(&set);
    assert!(!q.schedulable);
    assert_eq!(q.l, 10 * MS);
    assert_eq!(q.visited, vec![8 * MS, 6 * MS, 4 * MS, 3 * MS, 2 * MS]);
    assert_eq!(q.failure, Some(2 * MS));
}

/// Under EDF a deadline below the period selects QPA by default, and the
/// response time of a server is its deadline when QPA passes.
#[test]
fn edf_constrained_deadlines_use_qpa() {
    let text = "[system]\nname = \"e\"\nscheduler = \"edf\"\n[tasks.a]\nexec = 1\nperiod = 4\ndeadline = 2\n[tasks.b]\nexec = 2\nperiod = 6\ndeadline = DB\n[tasks.c]\nexec = 3\nperiod = 13\ndeadline = 10\n";
    let s = spec(&text.replace("DB", "4"));
    assert_eq!(s.schedulability, SchedTest::Qpa);
    let r = analyze(&s);
    assert!(r.schedulability.schedulable);
    let rt: Vec<_> = r.timing.iter().map(|t| t.job_response_time).collect();
    assert_eq!(rt, vec![Some(2 * MS), Some(4 * MS), Some(10 * MS)]);
    let r = analyze(&spec(&text.replace("DB", "2")));
    assert!(!r.schedulability.schedulable);
    assert!(r.timing.iter().all(|t| t.job_response_time.is_none()));
}
