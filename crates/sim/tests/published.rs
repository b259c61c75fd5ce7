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
