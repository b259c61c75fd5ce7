//! The EDF dispatcher on random EDF + SRP systems: two CPUs,
//! three or four tasks each, a resource per CPU shared by most of its
//! tasks. Each run's own log is the oracle: SRP's start rule
//! (`model::policy::srp_may_start`) at every job's start against every hold
//! of another task then in progress on its CPU, mutual exclusion, and the
//! responses against the analysis' R(job). Root only (SCHED_FIFO).

use rtpipe_model::gen::Rng;
use rtpipe_model::policy::{srp_levels, srp_may_start};
use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::blame::Blame;
use rtpipe_runtime::locks::Held;
use rtpipe_runtime::{run_synthetic, Policy, RunConfig, RunResult, Spin};

const MS: Nanos = 1_000_000;
/// Systems per run; `RTPIPE_SRP_SEEDS` asks for more.
fn seeds() -> u64 {
    std::env::var("RTPIPE_SRP_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(8)
}

/// One task's TOML: period from a harmonic-ish menu (hyperperiod 120 ms),
/// a random offset in 0.1 ms steps, utilisation 0.08–0.22, a section on its CPU's resource two times in
/// three, of up to half its exec (in 0.1 ms steps).
fn task(rng: &mut Rng, name: &str, cpu: u64) -> String {
    let period = [4, 5, 6, 8, 10, 12][rng.range(0, 5) as usize];
    let exec10 = (period * (8 + rng.range(0, 14)) / 10).max(2);
    let offset10 = rng.range(0, period * 10 - 1);
    let mut t = format!(
        "[tasks.{name}]\nexec = {}\nperiod = {period}\ncpu = {cpu}\nserver = \"none\"\noffset = {}\n",
        exec10 as f64 / 10.0,
        offset10 as f64 / 10.0
    );
    if !rng.chance(1.0 / 3.0) {
        let len = rng.range(1, (exec10 / 2).max(1));
        t += &format!(
            "critical_sections = [{{ resource = \"r{cpu}\", length = {} }}]\n",
            len as f64 / 10.0
        );
    }
    t
}

/// `RTPIPE_SRP_SPECS=DIR` also writes each system there (`seed-N.toml`)
/// for `rtpipe run` to judge.
fn system(seed: u64) -> Spec {
    let mut rng = Rng::new(seed);
    let mut src = "[system]\nname = \"srp-random\"\ntime_unit = \"ms\"\nscheduler = \"edf\"\nresource_protocol = \"srp\"\n[resources.r0]\n[resources.r1]\n".to_string();
    for cpu in 0..2 {
        for k in 0..rng.range(3, 4) {
            src += &task(&mut rng, &format!("t{cpu}{k}"), cpu);
        }
    }
    if let Ok(dir) = std::env::var("RTPIPE_SRP_SPECS") {
        let path = std::path::Path::new(&dir).join(format!("seed-{seed}.toml"));
        std::fs::write(&path, &src).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
    Spec::parse("srp-random.toml", &src).unwrap_or_else(|e| panic!("seed {seed}: {e}\n{src}"))
}

/// Every job's start against every other task's hold on its CPU: a job
/// that starts inside a hold must pass SRP's start test under that
/// resource's ceiling. Returns the starts that were inside a hold.
fn check_start_rule(spec: &Spec, res: &RunResult) -> usize {
    let (level, ceiling) = srp_levels(spec);
    let mut inside = 0;
    for j in &res.sim.jobs {
        let cpu = spec.tasks[j.task].cpu;
        for (t, run) in res.tasks.iter().enumerate() {
            if t == j.task || spec.tasks[t].cpu != cpu {
                continue;
            }
            for h in run
                .sections
                .iter()
                .filter(|h| h.enter < j.read && j.read < h.exit)
            {
                inside += 1;
                assert!(
                    srp_may_start(false, level[j.task], Some(ceiling[h.resource])),
                    "{} job {} started at {} inside {}'s hold {h:?}",
                    spec.tasks[j.task].name,
                    j.index,
                    j.read,
                    spec.tasks[t].name
                );
            }
        }
    }
    inside
}

fn check_exclusion(res: &RunResult) {
    let mut holds: Vec<&Held> = res.tasks.iter().flat_map(|t| &t.sections).collect();
    holds.sort_by_key(|h| (h.resource, h.enter));
    for w in holds.windows(2).filter(|w| w[0].resource == w[1].resource) {
        assert!(w[0].exit <= w[1].enter, "overlapping holds: {w:?}");
    }
}

/// What the blame takes as time no job could run (the dispatcher's spans,
/// the spans of started jobs of earlier deadlines) must leave each job its
/// own CPU time inside its read → publish span: a span recorded after the
/// thread lowered itself would cover other jobs' work and hide it.
/// CPU time a job may show beyond its read → publish span: the register
/// reads before the read stamp and the writes after the publish stamp run
/// on the job's CPU clock. Up to ~30 µs on this 2-core VM after a wait,
/// and 22.5 µs was seen with four busy loops competing for the CPUs
/// (the 20 µs this test allowed before failed there); a span that hid
/// another job's work would hide that job's whole execution.
const OUTSIDE_SPAN_NS: Nanos = 50_000;

fn check_room(spec: &Spec, res: &RunResult) {
    let blame = Blame::new(spec, res);
    for j in &res.sim.jobs {
        let room = blame.could_run(j, (j.read, j.finish));
        // The CPU time is read a few µs outside [read, finish] (the
        // register reads before, the writes after): held to the span where
        // it exceeds it, with OUTSIDE_SPAN_NS for the code between the
        // clock reads and the stamps.
        let ran = j.demand.min(j.finish - j.read);
        assert!(
            room + OUTSIDE_SPAN_NS >= ran,
            "{} job {}: {room} ns of room for {ran} ns of CPU time",
            spec.tasks[j.task].name,
            j.index
        );
    }
}

#[test]
fn random_srp_systems_keep_the_start_rule_exclusion_and_their_bounds() {
    if !rtpipe_runtime::sys::is_root() {
        eprintln!("SKIPPED the EDF dispatcher on random systems: SCHED_FIFO needs root");
        return;
    }
    let spin = Spin::calibrate();
    let (mut ran, mut held_back, mut inside) = (0, 0, 0);
    let seeds = seeds();
    for seed in 1..=seeds {
        let spec = system(seed);
        let report = rtpipe_analysis::analyze(&spec);
        if !report.schedulability.schedulable {
            continue;
        }
        let cfg = RunConfig {
            duration: 600 * MS,
            policy: Policy::EdfFifo,
            load: 0,
        };
        let res = run_synthetic(&spec, &cfg, spin).unwrap_or_else(|e| panic!("{e}"));
        let stats = res.dispatch.unwrap_or_else(|| panic!("no dispatcher ran"));
        assert_eq!(
            (stats.contended, stats.failed),
            (0, 0),
            "seed {seed}: {stats:?}"
        );
        held_back += stats.held_back;
        check_exclusion(&res);
        check_room(&spec, &res);
        inside += check_start_rule(&spec, &res);
        // Each response within 0.5 ms of its bound in the median (a task
        // that reaches its bound in every hyperperiod is above it by the
        // overheads): a dispatcher that
        // ranked wrongly would push some far above it. The tail is the
        // run's verdict's business (`rtpipe run` blames overheads there:
        // an EDF job that reaches its bound exactly can be pushed past a
        // release of an earlier deadline by a few µs and lose a whole job
        // of it, docs/runtime.md).
        for (t, timing) in report.timing.iter().enumerate() {
            let bound = timing.job_response_time.unwrap_or_else(|| panic!("no R"));
            let mut r = res.tasks[t].responses.clone();
            r.sort_unstable();
            assert!(
                !r.is_empty() && r[r.len() / 2] <= bound + MS / 2,
                "seed {seed} {}: bound {bound}, responses {r:?}",
                spec.tasks[t].name
            );
        }
        ran += 1;
    }
    assert!(
        ran >= seeds / 2,
        "only {ran} of {seeds} systems schedulable"
    );
    // The ceiling must have held jobs back: a run where it never binds
    // tests nothing. Starts inside a hold are legal only for a level above
    // the ceiling; the draw decides how many there are (0 is fine).
    assert!(held_back > 0, "no job was held back by a ceiling");
    eprintln!(
        "{ran} systems: {held_back} jobs held back, {inside} starts inside a hold, all by the rule"
    );
}
