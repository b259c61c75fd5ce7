//! Published worked examples, analysed and simulated.
//!
//! Burns and Wellings, *Real-Time Systems and Programming Languages*
//! (Addison-Wesley), the response-time analysis example of the fixed-
//! priority scheduling chapter: tasks a (T = 7, C = 3), b (T = 12, C = 3)
//! and c (T = 20, C = 5), priorities a > b > c, whose worst-case response
//! times the book computes as R_a = 3, R_b = 6 and R_c = 20 (c's iteration
//! 5, 11, 14, 17, 20, 20: the set is schedulable with c finishing exactly
//! at its deadline, although its utilisation 0.929 is above the Liu and
//! Layland bound 0.780). The simulator reaches each at the synchronous
//! release (the critical instant).

use rtpipe_analysis::analyze;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::{simulate, SimConfig};

const MS: Nanos = 1_000_000;
const US: Nanos = 1_000;

fn burns_wellings(priorities: [u32; 3]) -> Spec {
    let [a, b, c] = priorities;
    let text = format!(
        "[system]\nname = \"burns-wellings\"\ntime_unit = \"ms\"\npriorities = \"explicit\"\n\
         [tasks.a]\nexec = 3\nperiod = 7\npriority = {a}\n\
         [tasks.b]\nexec = 3\nperiod = 12\npriority = {b}\n\
         [tasks.c]\nexec = 5\nperiod = 20\npriority = {c}\n"
    );
    rtpipe_testkit::spec("burns-wellings.toml", &text)
}

fn responses(spec: &Spec) -> (Vec<Option<Nanos>>, Vec<Nanos>) {
    let r = analyze(spec);
    let analysed = r.timing.iter().map(|t| t.job_response_time).collect();
    let res = simulate(spec, &SimConfig::new(140 * MS)).unwrap_or_else(|e| panic!("{e}"));
    let seen = res
        .tasks
        .iter()
        .map(|t| t.max_response.unwrap_or(0))
        .collect();
    (analysed, seen)
}

#[test]
fn burns_and_wellings_response_times() {
    let spec = burns_wellings([1, 2, 3]);
    let (analysed, seen) = responses(&spec);
    assert_eq!(analysed, vec![Some(3 * MS), Some(6 * MS), Some(20 * MS)]);
    assert_eq!(
        seen,
        vec![3 * MS, 6 * MS, 20 * MS],
        "reached at the critical instant"
    );
    assert!(analyze(&spec).schedulability.schedulable);
}

/// The same tasks with the priorities reversed (explicit, not rate
/// monotonic): a, now lowest, waits for c (5) and b (3) released with it,
/// w = 3 + ⌈w/12⌉·3 + ⌈w/20⌉·5 = 11 > 7: unschedulable; b: 3 + 5 = 8;
/// c: 5.
#[test]
fn explicit_priorities_are_the_spec_s_not_rate_monotonic() {
    let spec = burns_wellings([3, 2, 1]);
    let r = analyze(&spec);
    assert_eq!(r.timing[1].job_response_time, Some(8 * MS));
    assert_eq!(r.timing[2].job_response_time, Some(5 * MS));
    assert!(!r.schedulability.schedulable, "a misses its period");
}

/// Audsley, Burns, Richardson, Tindell and Wellings 1993, Table 3
/// (examples/published-audsley1993.toml; the analysis reproduces the
/// published response times in crates/analysis/tests/published.rs): over
/// the whole hyperperiod (118 s), synchronous and random phasings, jitter
/// at 0, J, uniform or extreme, no simulated job responds later than its
/// bound. The three lowest (t16–t18) have B = 0: the synchronous release
/// is their critical instant and they reach their bounds exactly.
#[test]
fn audsley_1993_table_3_simulated() {
    use rtpipe_sim::{ExecModel, Jitter, Phasing};
    let spec = rtpipe_testkit::spec(
        "published-audsley1993.toml",
        include_str!("../../../examples/published-audsley1993.toml"),
    );
    let bound: Vec<Nanos> = analyze(&spec)
        .timing
        .iter()
        .map(|t| t.job_response_time.unwrap_or(0))
        .collect();
    let hyperperiod = 118_000 * MS;
    let mut runs = vec![
        (Phasing::Sync, ExecModel::Worst, Jitter::None, 0),
        (Phasing::Sync, ExecModel::Worst, Jitter::Latest, 0),
        (Phasing::Sync, ExecModel::Worst, Jitter::Uniform, 0),
    ];
    for seed in 0..8 {
        runs.push((Phasing::Random, ExecModel::Worst, Jitter::Extremes, seed));
        runs.push((
            Phasing::Grid(MS),
            ExecModel::Extremes,
            Jitter::Uniform,
            seed,
        ));
    }
    for (k, (phasing, exec, jitter, seed)) in runs.into_iter().enumerate() {
        let cfg = SimConfig {
            phasing,
            exec,
            jitter,
            seed,
            ..SimConfig::new(hyperperiod)
        };
        let res = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
        for (i, t) in res.tasks.iter().enumerate() {
            let seen = t.max_response.unwrap_or(0);
            assert!(seen <= bound[i], "run {k}: task {i} {seen} > {}", bound[i]);
            assert_eq!(t.late, 0, "run {k}: task {i}");
            if k == 0 && i >= 15 {
                assert_eq!(seen, bound[i], "task {i} at the critical instant");
            }
        }
    }
}

/// LETItGo's ROSACE graph under LET (examples/published-let-rosace.toml):
/// the simulator measures exactly the data ages the analysis gives, 240,
/// 150 and 60 ms from the head's read.
#[test]
fn letitgo_rosace_simulated() {
    let spec = rtpipe_testkit::spec(
        "published-let-rosace.toml",
        include_str!("../../../examples/published-let-rosace.toml"),
    );
    let res = simulate(&spec, &SimConfig::new(2_400 * MS)).unwrap_or_else(|e| panic!("{e}"));
    let fresh: Vec<Option<Nanos>> = res.chains.iter().map(|c| c.freshness.max).collect();
    assert_eq!(fresh, vec![Some(240 * MS), Some(150 * MS), Some(60 * MS)]);
}

/// t12's worst case (R = J + w = 100,550 µs) by construction: t12's job
/// released nominally at 0 and actually at J = 1 ms, every task above it
/// released then too, and t13 released 10 µs + 1 ns earlier, so that it
/// has run its r13 section and just taken y11 when they arrive. t11, after
/// its r10 and x11 sections, asks for y11; t13 inherits t11's rank and
/// runs the rest of its 450 µs section ahead of t12 (push-through
/// blocking, B = 450). t12 finishes 1 ns before its bound.
#[test]
fn audsley_1993_t12_reaches_its_bound() {
    use rtpipe_sim::{Jitter, Phasing};
    let spec = rtpipe_testkit::spec(
        "published-audsley1993.toml",
        include_str!("../../../examples/published-audsley1993.toml"),
    );
    let bound = analyze(&spec).timing[11].job_response_time;
    assert_eq!(bound, Some(100_550 * US));
    let mut offsets = vec![MS; 18];
    offsets[11] = 0;
    offsets[12] = MS - 10 * US - 1;
    let cfg = SimConfig {
        phasing: Phasing::Given(offsets),
        jitter: Jitter::Latest,
        ..SimConfig::new(200 * MS)
    };
    let res = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(res.tasks[11].max_response, Some(100_550 * US - 1));
}
