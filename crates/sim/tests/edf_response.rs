//! EDF response times (Spuri 1996, `rtpipe_analysis::edf`) against the
//! simulator's reservations: no job of any phasing or demand responds later
//! than the analysis says, and Spuri's critical pattern (every other task
//! released at 0, the analysed one at some offset) reaches the bound. The
//! same for the read-to-publish bound `W` (`edf::start_to_finish`): no job
//! publishes later than `W` after its read, and the start pattern (the
//! analysed job alone at its release, every other task released just after
//! its read) reaches it.
//!
//! Systems are small and on a 1 ms grid (periods 2–24 ms, one CPU, servers
//! or plain tasks, budgets at or above the demands), so a few hyperperiods
//! are cheap to simulate and the grid of offsets holds every candidate
//! instant of the analysis.

use proptest::prelude::*;
use rtpipe_analysis::analyze;
use rtpipe_joblog::SimResult;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::{simulate, ExecModel, Phasing, SimConfig};
use rtpipe_testkit::check;

const MS: Nanos = 1_000_000;

/// One task: (demand ms, extra budget ms, period ms, on a server).
type Params = (i64, i64, i64, bool);

/// The spec of `tasks` under EDF, one CPU; `last` is declared last (it
/// loses every tie of deadlines, as the analysis assumes it may).
fn spec_of(tasks: &[Params]) -> Option<Spec> {
    let mut src = String::from("[system]\nname = \"edf\"\nscheduler = \"edf\"\n");
    let mut u = 0.0;
    for (k, &(x, extra, t, server)) in tasks.iter().enumerate() {
        let c = x + if server { extra } else { 0 };
        u += c as f64 / t as f64;
        let srv = if server { "main" } else { "none" };
        src += &format!("[tasks.t{k}]\nexec = \"{x}ms\"\nperiod = \"{t}ms\"\nserver = \"{srv}\"\n");
        if server {
            src += &format!("budget = \"{c}ms\"\n");
        }
    }
    if u > 1.0 {
        return None;
    }
    Spec::parse("edf.toml", &src).ok()
}

fn lcm(a: i64, b: i64) -> i64 {
    a / rtpipe_model::gcd(a, b) * b
}

/// A run of `offsets` (ns) over three hyperperiods past the last offset.
fn run(spec: &Spec, offsets: &[Nanos], exec: ExecModel, seed: u64, log_jobs: bool) -> SimResult {
    let h = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .fold(1, lcm);
    let last = offsets.iter().copied().max().unwrap_or(0);
    let cfg = SimConfig {
        horizon: last + 3 * h,
        seed,
        phasing: Phasing::Given(offsets.to_vec()),
        exec,
        log_jobs,
        jitter: rtpipe_sim::Jitter::default(),
    };
    simulate(spec, &cfg).unwrap_or_else(|e| panic!("{e}"))
}

/// Every job's worst response per task, from a run of `offsets` (ms).
fn worst_responses(spec: &Spec, offsets: &[i64], exec: ExecModel, seed: u64) -> Vec<Nanos> {
    let offsets: Vec<Nanos> = offsets.iter().map(|o| o * MS).collect();
    run(spec, &offsets, exec, seed, false)
        .tasks
        .iter()
        .map(|t| t.max_response.unwrap_or(0))
        .collect()
}

/// Every job's longest time from its read to its publish per task, from a
/// run of `offsets` (ns).
fn worst_read_to_publish(spec: &Spec, offsets: &[Nanos], exec: ExecModel, seed: u64) -> Vec<Nanos> {
    let mut worst = vec![0; spec.tasks.len()];
    for j in run(spec, offsets, exec, seed, true).jobs {
        worst[j.task] = worst[j.task].max(j.finish - j.read);
    }
    worst
}

fn params() -> impl Strategy<Value = Params> {
    let periods = vec![2i64, 3, 4, 5, 6, 8, 10, 12, 24];
    (
        1i64..=4,
        0i64..=2,
        prop::sample::select(periods),
        any::<bool>(),
    )
        // At most a third of the period: fewer overloaded systems to skip.
        .prop_map(|(x, e, t, s)| (x.min(t / 3).max(1), e, t, s))
}

/// No job of any phasing or demand model exceeds its task's job response
/// time, and that is within the period.
#[test]
fn no_job_exceeds_the_edf_response_time() {
    let strategy = (
        prop::collection::vec(params(), 2..=5),
        prop::collection::vec(0i64..24, 5),
        any::<bool>(),
        any::<u64>(),
    );
    check(
        "no_job_exceeds_the_edf_response_time",
        10_000,
        strategy,
        |(tasks, offsets, uniform, seed)| {
            let Some(spec) = spec_of(&tasks) else {
                return Ok("overloaded");
            };
            let report = analyze(&spec);
            let offs: Vec<i64> = (0..tasks.len()).map(|k| offsets[k] % tasks[k].2).collect();
            let exec = if uniform {
                ExecModel::Uniform
            } else {
                ExecModel::Worst
            };
            let seen = worst_responses(&spec, &offs, exec, seed);
            let mut reached = false;
            for (k, t) in report.timing.iter().enumerate() {
                let r = t.job_response_time.unwrap_or(0);
                prop_assert!(r <= t.period, "task {k}: R {r} above T");
                prop_assert!(
                    seen[k] <= r,
                    "task {k}: observed {} > bound {r}, offsets {offs:?}",
                    seen[k]
                );
                reached |= seen[k] == r;
            }
            Ok(if reached {
                "checked, some task at its bound"
            } else {
                "checked"
            })
        },
    );
}

/// Spuri's critical pattern: the analysed task declared last (it loses
/// every tie), every other task released at 0 with its worst demand, the
/// analysed one at every offset on the grid. The worst response found is
/// the bound on almost every system, and never above it.
#[test]
fn the_critical_pattern_reaches_the_bound() {
    let mut rng = rtpipe_model::gen::Rng::new(2026);
    let periods = [2i64, 3, 4, 5, 6, 8, 10, 12, 24];
    let (mut systems, mut reached) = (0, 0);
    while systems < 400 {
        let n = rng.range(2, 4) as usize;
        let tasks: Vec<Params> = (0..n)
            .map(|_| {
                let t = periods[rng.range(0, periods.len() as u64 - 1) as usize];
                let x = (rng.range(1, 4) as i64).min(t);
                (x, 0, t, rng.chance(0.5))
            })
            .collect();
        let Some(spec) = spec_of(&tasks) else {
            continue;
        };
        systems += 1;
        let report = analyze(&spec);
        let last = n - 1;
        let bound = report.timing[last].job_response_time.unwrap_or(0);
        let mut worst = 0;
        for phi in 0..tasks[last].2 {
            let mut offs = vec![0; n];
            offs[last] = phi;
            worst = worst.max(worst_responses(&spec, &offs, ExecModel::Worst, 1)[last]);
        }
        assert!(worst <= bound, "{tasks:?}: {worst} > {bound}");
        reached += usize::from(worst == bound);
    }
    println!("critical pattern: bound reached on {reached} of {systems} systems");
    assert!(
        reached * 10 >= systems * 9,
        "reached on {reached} of {systems}"
    );
}

/// No job of any phasing (on the 1 ms grid, each offset shifted by 0, 1 or
/// 2 ns so that releases fall just after reads) or demand model publishes
/// later than its task's `W` after its read; `W ≤ R ≤ T`.
#[test]
fn no_job_exceeds_the_read_to_publish_bound() {
    let strategy = (
        prop::collection::vec(params(), 2..=5),
        prop::collection::vec((0i64..24, 0i64..=2), 5),
        any::<bool>(),
        any::<u64>(),
    );
    check(
        "no_job_exceeds_the_read_to_publish_bound",
        10_000,
        strategy,
        |(tasks, offsets, uniform, seed)| {
            let Some(spec) = spec_of(&tasks) else {
                return Ok("overloaded");
            };
            let report = analyze(&spec);
            let offs: Vec<Nanos> = (0..tasks.len())
                .map(|k| (offsets[k].0 % tasks[k].2) * MS + offsets[k].1)
                .collect();
            let exec = if uniform {
                ExecModel::Uniform
            } else {
                ExecModel::Worst
            };
            let seen = worst_read_to_publish(&spec, &offs, exec, seed);
            let mut below_r = false;
            for (k, t) in report.timing.iter().enumerate() {
                let (Some(w), Some(r)) = (t.read_to_publish, t.job_response_time) else {
                    return Err(TestCaseError::fail(format!("task {k}: no W or R")));
                };
                prop_assert!(w <= r && r <= t.period, "task {k}: W {w}, R {r}");
                prop_assert!(
                    seen[k] <= w,
                    "task {k}: read to publish {} > W {w}, offsets {offs:?}",
                    seen[k]
                );
                below_r |= seen[k] == w && w < r;
            }
            Ok(if below_r {
                "checked, some task at a W below its R"
            } else {
                "checked"
            })
        },
    );
}

/// The start pattern: the analysed task released at 0 with its worst
/// demand, every other task at 1 ns (just after the read) and then as often
/// as it may, budgets equal to demands (the analysis charges a server its
/// budget). On the 1 ms grid the jobs released after the read with a
/// deadline before the analysed one's are exactly those `W` counts, so the
/// read-to-publish time is `W` on every system.
#[test]
fn the_start_pattern_reaches_the_bound() {
    let mut rng = rtpipe_model::gen::Rng::new(2027);
    let periods = [2i64, 3, 4, 5, 6, 8, 10, 12, 24];
    let (mut systems, mut below_r) = (0, 0);
    while systems < 400 {
        let n = rng.range(2, 5) as usize;
        let tasks: Vec<Params> = (0..n)
            .map(|_| {
                let t = periods[rng.range(0, periods.len() as u64 - 1) as usize];
                let x = (rng.range(1, 4) as i64).min(t);
                (x, 0, t, rng.chance(0.5))
            })
            .collect();
        let Some(spec) = spec_of(&tasks) else {
            continue;
        };
        systems += 1;
        let report = analyze(&spec);
        let i = rng.range(0, n as u64 - 1) as usize;
        let tm = &report.timing[i];
        let w = tm.read_to_publish.unwrap_or(0);
        let mut offs = vec![1; n];
        offs[i] = 0;
        let found = worst_read_to_publish(&spec, &offs, ExecModel::Worst, 1)[i];
        assert_eq!(
            found, w,
            "{tasks:?}, task {i}: the pattern gives {found}, W = {w}"
        );
        below_r += usize::from(w < tm.job_response_time.unwrap_or(0));
    }
    println!("start pattern: W reached on all {systems} systems, below R on {below_r}");
    assert!(below_r >= 40, "W below R on only {below_r} systems");
}

/// Under EDF with constrained deadlines (QPA) the response time is
/// Spuri's with the deadlines, not the deadline itself (docs/analysis.md,
/// "EDF response times"): a (1 ms every 10, D = 4) and b (2 ms every 10,
/// D = 10): R_b = 3 ms where QPA alone gives D_b = 10; no run exceeds it,
/// and the synchronous one reaches it.
#[test]
fn constrained_deadlines_get_spuri_s_response_times() {
    let src = r#"
[system]
name = "qpa"
time_unit = "ms"
scheduler = "edf"
schedulability = "qpa"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.a]
exec = 1
period = 10
deadline = 4
server = "none"
[tasks.b]
exec = 2
period = 10
server = "none"
"#;
    let spec = Spec::parse("qpa.toml", src).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    let r: Vec<Option<Nanos>> = rep.timing.iter().map(|t| t.job_response_time).collect();
    assert_eq!(r, vec![Some(MS), Some(3 * MS)]);
    let mut seen = vec![0; 2];
    // Offsets in whole ms (`worst_responses`).
    for phi in 0..10 {
        for (k, s) in worst_responses(&spec, &[0, phi], ExecModel::Worst, phi as u64)
            .into_iter()
            .enumerate()
        {
            seen[k] = seen[k].max(s);
        }
    }
    assert_eq!(seen, vec![MS, 3 * MS]);
}
