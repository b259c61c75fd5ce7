//! Critical sections and LET on real threads: the protocol
//! holds (mutual exclusion, blocking where the analysis puts it, no
//! response above its bound beyond the run's own noise) and LET's data
//! flow is the simulator's. SCHED_FIFO needs root: without it the
//! SCHED_FIFO parts print why and pass; SCHED_OTHER always runs.

use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::locks::Held;
use rtpipe_runtime::{run_synthetic, Policy, RunConfig, RunResult, Spin};

const MS: Nanos = 1_000_000;

/// l (rank 3) holds r for 3 ms from its start at 0; m (rank 2, no
/// section) is released at 0.5 ms with 5 ms of work; h (rank 1), released
/// at 1 ms, needs r at its start. With the protocol h waits for l's
/// section alone: the immediate ceiling keeps m from preempting l (h runs
/// 3–4 ms, R = 3 ms), inheritance lends l h's priority once h waits (l
/// runs 1–3.5 ms, R = 3.5 ms). With a plain lock m would preempt l and h
/// would wait for m's 5 ms too (R ≈ 8 ms); without any lock h would respond
/// in 1 ms. Bounds (docs/analysis.md, "Blocking"): B_h = 3, R_h = 4 ms;
/// R_m = 5 + 3 + 1 = 9 ms; R_l = 4 + 1 + 5 = 10 ms.
fn blocking(protocol: &str) -> Spec {
    let src = format!(
        r#"[system]
name = "block"
time_unit = "ms"
resource_protocol = "{protocol}"

[resources.r]

[tasks.h]
exec = 1
period = 10
offset = 1
server = "none"
critical_sections = [{{ resource = "r", length = 0.5 }}]

[tasks.m]
exec = 5
period = 20
offset = 0.5
server = "none"

[tasks.l]
exec = 4
period = 20
offset = 0
server = "none"
critical_sections = [{{ resource = "r", length = 3 }}]
"#
    );
    Spec::parse("block.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

fn run(spec: &Spec, policy: Policy, ms: Nanos) -> RunResult {
    let cfg = RunConfig {
        duration: ms * MS,
        policy,
        load: 0,
    };
    run_synthetic(spec, &cfg, Spin::calibrate()).unwrap_or_else(|e| panic!("{e}"))
}

/// Every section of every task on one resource, in entry order: no two
/// overlap (each exits before the next enters).
fn exclusive(res: &RunResult) {
    let mut all: Vec<Held> = res.tasks.iter().flat_map(|t| t.sections.clone()).collect();
    assert!(!all.is_empty(), "no section was held");
    all.sort_by_key(|h| (h.resource, h.enter));
    for w in all.windows(2) {
        if w[0].resource == w[1].resource {
            assert!(w[0].exit <= w[1].enter, "overlapping sections: {w:?}");
        }
        assert!(w[0].enter <= w[0].exit, "{w:?}");
    }
}

/// One at a time: real-time runs disturb each other.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn the_high_task_waits_for_the_low_task_s_section_and_never_longer() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    if !rtpipe_runtime::sys::is_root() {
        eprintln!("SKIPPED the SCHED_FIFO protocols: not root");
        return;
    }
    for protocol in ["pcp", "srp", "pip"] {
        let spec = blocking(protocol);
        let res = run(&spec, Policy::Fifo, 400);
        exclusive(&res);
        let h = &res.tasks[0];
        // Every second job of h (released at 1 + 20k) meets l in its
        // section, unless l woke late (this machine's wake-up latency
        // reaches 1 ms at times; m then runs first and l's section later):
        // three in four at least.
        let blocked: Vec<Nanos> = h.responses.iter().step_by(2).copied().collect();
        let met = blocked.iter().filter(|&&r| r > 2_900_000).count();
        assert!(
            4 * met >= 3 * blocked.len(),
            "{protocol}: {met} of {} jobs of h released during l's section waited for it: h {:?}",
            blocked.len(),
            h.responses
        );
        // m never delayed it (it would by 5 ms, R ≈ 8 ms, on every job that
        // meets l): beyond R_h = 4 ms by 1 ms, at most one job in ten, a
        // spike of this VM's latency (2.6 ms seen once).
        let late = h.responses.iter().filter(|&&r| r > 5 * MS).count();
        assert!(
            10 * late <= blocked.len(),
            "{protocol}: {late} jobs of h responded beyond 5 ms: {:?}",
            h.responses
        );
        // The others run alone (≈ 1 ms).
        let free = h
            .responses
            .iter()
            .skip(1)
            .step_by(2)
            .min()
            .copied()
            .unwrap_or(0);
        assert!(free < 2 * MS, "{protocol}: h alone responded in {free} ns");
        // l's section ran at its start and was held 3 ms of CPU time.
        let l = &res.tasks[2];
        let first = l.sections[0];
        assert!(first.exit - first.enter >= 3 * MS, "{first:?}");
        // m and l reach their exact bounds every 20 ms (no slack: any
        // latency shows, 2.6 ms once here), so their medians are held to
        // them; the run's verdict judges each job (tests/run.rs in the cli).
        for (t, bound) in [(1, 9 * MS), (2, 10 * MS)] {
            let mut r = res.tasks[t].responses.clone();
            r.sort_unstable();
            let median = r[r.len() / 2];
            assert!(
                median < bound + MS / 2,
                "{protocol}: task {t}'s median response {median} ns"
            );
        }
        assert!(
            res.notes.iter().all(|n| !n.contains("refused")),
            "{:?}",
            res.notes
        );
    }
}

#[test]
fn best_effort_keeps_mutual_exclusion_and_says_the_protocol_is_off() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    for protocol in ["pcp", "pip"] {
        let spec = blocking(protocol);
        let res = run(&spec, Policy::Other, 200);
        exclusive(&res);
        assert!(
            res.notes
                .iter()
                .any(|n| n.contains("SCHED_OTHER has no priorities")),
            "{:?}",
            res.notes
        );
        // 20 jobs of h, 10 of l, each one section: all logged.
        assert_eq!(res.tasks[0].sections.len(), 20);
        assert_eq!(res.tasks[2].sections.len(), 10);
    }
}

/// sensor (5 ms) → filter (10 ms) → control (5 ms) under LET, synchronous:
/// the simulator measures reaction 20 ms and freshness 25 ms from the
/// head's read on every sample (`rtpipe simulate examples/let.toml`).
#[test]
fn let_runs_give_the_simulator_s_exact_latencies() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/let.toml");
    let spec = Spec::load(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
    let cfg = rtpipe_sim::SimConfig {
        log_jobs: true,
        ..rtpipe_sim::SimConfig::new(400 * MS)
    };
    let sim = rtpipe_sim::simulate(&spec, &cfg).unwrap_or_else(|e| panic!("{e:?}"));
    let policy = if rtpipe_runtime::sys::is_root() {
        Policy::Fifo
    } else {
        Policy::Other
    };
    let res = run(&spec, policy, 400);
    let rows = |jobs| rtpipe_joblog::sample_rows(&spec, jobs);
    let (real, model) = (rows(&res.sim.jobs), rows(&sim.jobs));
    let lat =
        |rows: &Vec<Vec<rtpipe_joblog::SampleRow>>| -> Vec<(Nanos, Option<Nanos>, Option<Nanos>)> {
            rows[0].iter().map(|r| (r.read, r.first, r.last)).collect()
        };
    let (a, b) = (lat(&real), lat(&model));
    assert!(a.len() >= 70, "{} samples", a.len());
    // The same samples, read and output at the same instants.
    let n = a.len().min(b.len());
    assert_eq!(a[..n - 2], b[..n - 2]);
    for r in &real[0] {
        if let (Some(first), Some(last)) = (r.first, r.last) {
            assert_eq!(first - r.read, 20 * MS);
            assert_eq!(last - r.read, 25 * MS);
        }
    }
    assert!(res.tasks.iter().all(|t| t.let_misses == 0));
    // The schedule's responses stay the threads' (well under the period).
    assert!(res.tasks[0].responses.iter().all(|&r| r < 5 * MS));
}

/// The caller's own bodies cannot have the runtime's sections placed in
/// them: refused before any thread starts, with the fix.
#[test]
fn sections_with_the_caller_s_bodies_are_refused() {
    let spec = blocking("pcp");
    let cfg = RunConfig {
        duration: 10 * MS,
        policy: Policy::Other,
        load: 0,
    };
    let bodies: Vec<Box<dyn rtpipe_body::Body<u64>>> = (0..3)
        .map(|_| {
            Box::new(
                |_: &rtpipe_body::Job, _: &[Option<rtpipe_body::Stamped<u64>>], _: Option<u64>| {
                    0u64
                },
            ) as Box<dyn rtpipe_body::Body<u64>>
        })
        .collect();
    let Err(e) = rtpipe_runtime::run(&spec, &cfg, bodies, None) else {
        panic!("ran a spec with sections on foreign bodies");
    };
    assert_eq!(e.kind, rtpipe_runtime::ErrorKind::Config);
    assert!(
        e.diagnostic.message.contains("synthetic bodies only"),
        "{e}"
    );
}
