//! Scheduling overheads in the response times (docs/analysis.md,
//! "Scheduling overheads"): fixed priority and EDF worked by hand, and a
//! system the overheads overload still analyses, as unschedulable.

use rtpipe_analysis::analyze;
use rtpipe_model::{Nanos, Spec};

const US: Nanos = 1_000;

fn spec(text: &str) -> Spec {
    Spec::parse("o.toml", text).unwrap_or_else(|e| panic!("{e}"))
}

fn job_responses(s: &Spec) -> Vec<Option<Nanos>> {
    analyze(s)
        .timing
        .iter()
        .map(|t| t.job_response_time)
        .collect()
}

const EDF: &str = r#"
[system]
name = "edf"
scheduler = "edf"
overheads = { context_switch = "100us", release = "50us", replenish = "1ms" }
[tasks.a]
exec = 1
period = 4
server = "none"
[tasks.b]
exec = 2
period = 6
server = "none"
"#;

/// Spuri's analysis with the overheads, by hand (ms). Plain tasks, so no
/// replenishment (it is a budget server's): per job work x + 2·cs, per
/// release K = 0.05. a (1.2, 4), b (2.2, 6): L = 1.25 + 2.25 = 3.5.
/// b: A = {0, 2}; at a = 0, w = 2.1 (own 2 + cs) + 1.2 + 0.05 + 0.05 =
/// 3.4; at a = 2 the same w, 1.4: R_b = 3.4 (3 without overheads).
/// a: A = {0, 2}; at a = 0, w = 1.1 + 0.1 = 1.2; at a = 2 (b's deadline
/// 6 ties a's), w = 1.1 + 2.2 + 0.1 = 3.4, 3.4 − 2 = 1.4: R_a = 1.4.
#[test]
fn edf_by_hand() {
    let s = spec(EDF);
    assert_eq!(job_responses(&s), vec![Some(1_400 * US), Some(3_400 * US)]);
    let rep = analyze(&s);
    assert!(rep.schedulability.schedulable);
    // Σ U = 1/4 + 2/6, plus (0.2 + 0.05)/4 + (0.2 + 0.05)/6.
    let v = rep.schedulability.cpus[0].value;
    assert!(
        (v - (0.25 + 2.0 / 6.0 + 0.25 / 4.0 + 0.25 / 6.0)).abs() < 1e-12,
        "{v}"
    );
    // As servers, each release also replenishes a budget (1 ms): a
    // (1.2, 4) + 1.05 per release, b (2.2, 6) + 1.05: Σ = 2.25/4 + 3.25/6
    // > 1, overloaded: no response, and the verdict says so.
    let s = spec(&EDF.replace("server = \"none\"", "server = \"main\""));
    assert_eq!(job_responses(&s), vec![None, None]);
    assert!(!analyze(&s).schedulability.schedulable);
}

/// Fixed priority by hand (µs): two sporadic servers a (1000, 4000) above
/// b (2000, 10000), cs 5, rel 2, rep 1 (K = 3). R_a = 1000 + 5 + 3 + 3 =
/// 1011; R_b = 2000 + 5 + (1000 + 10) + 3 + 3 = 3021. The disturbance
/// `run` excuses is measured on top of the same figure.
#[test]
fn fixed_priority_by_hand() {
    let text = r#"
[system]
name = "rm"
time_unit = "us"
overheads = { context_switch = "5us", release = "2us", replenish = "1us" }
[tasks.a]
exec = 1000
period = 4000
[tasks.b]
exec = 2000
period = 10000
"#;
    let s = spec(text);
    assert_eq!(job_responses(&s), vec![Some(1011 * US), Some(3021 * US)]);
    // 979 µs more in b's window: 4000 − 3021, one more of a's jobs
    // (1010 + 3) joins at 4000.
    let grow = rtpipe_analysis::disturbance::inflation(&s, 1, 979 * US);
    assert_eq!(grow, 979 * US);
    let grow = rtpipe_analysis::disturbance::inflation(&s, 1, 980 * US);
    assert_eq!(grow, 980 * US + 1013 * US);
}

/// Overheads that overload the CPU are not refused: the analysis reports
/// what they do.
#[test]
fn overloading_overheads_still_analyse() {
    let text = r#"
[system]
name = "slow"
time_unit = "us"
overheads = { context_switch = "1ms", release = "500us" }
[tasks.a]
exec = 1000
period = 4000
[tasks.b]
exec = 2000
period = 5000
"#;
    let s = spec(text);
    let rep = analyze(&s);
    assert!(!rep.schedulability.schedulable);
    // a: 1000 + 1000 + 500 + 500 = 3000 ≤ 4000. b: its first job's w =
    // 2000 + 1000 + ⌈w/4000⌉·(3000 + 500) + ⌈w/5000⌉·500, a load of 0.975,
    // is 120000, far above b's period, and its level's load with its own
    // jobs (2000 + 2000 per 5000) is 1.775: the busy period never ends, no
    // response time at all.
    assert_eq!(job_responses(&s), vec![Some(3000 * US), None]);
    assert_eq!(rep.timing[1].bounded_response(), None);
}

/// A budget server that falls behind (R > T) may run out of budget behind
/// its backlog and switch the CPU at instants no release or completion
/// pays for: with overheads, the tasks it can run above lose their
/// response times (the simulator found one 9 ms past its bound, a PIBS
/// server with a backlog inheriting a high rank). Here the server j (2500
/// µs per 3000, below `top`'s 1000 per 10000) responds in 2500 + 1 +
/// (1000 + 2) = 3503 > 3000, and i below it (100 per 100000, 8600 µs without
/// overheads) loses its R; `top` and j keep theirs.
#[test]
fn a_server_behind_its_period_voids_the_tasks_it_runs_above() {
    let text = r#"
[system]
name = "behind"
time_unit = "us"
priorities = "explicit"
overheads = { context_switch = "1us" }
[tasks.top]
exec = 1000
period = 10000
server = "none"
priority = 1
[tasks.j]
exec = 2500
period = 3000
priority = 2
[tasks.i]
exec = 100
period = 100000
priority = 3
"#;
    let s = spec(text);
    // top: 1000 + its switch; j: 2500 + 1 + (1000 + 2).
    assert_eq!(
        job_responses(&s),
        vec![Some(1001 * US), Some(3503 * US), None]
    );
    assert!(!analyze(&s).schedulability.schedulable);
    let mut bare = s.clone();
    bare.overheads = rtpipe_model::Overheads::default();
    assert_eq!(
        job_responses(&bare),
        vec![Some(1000 * US), Some(3500 * US), Some(8600 * US)]
    );
}
