//! Scheduling overheads against the simulator: a small task set
//! computed by hand reaches its bounds exactly, and on random systems with
//! context switch, release and replenishment costs (fixed priority with
//! sporadic servers, PIBS with inheritance and plain tasks, or EDF with
//! constant-bandwidth servers; one or two CPUs, some with a CPU table of
//! their own, some with a background task, some plain tasks with release
//! jitter, some with critical sections under PCP or SRP) no simulated job response time, reaction or freshness
//! exceeds its bound, while some tasks come within 3 % of their `R(job)`.
//!
//! `RTPIPE_OVERHEAD_SYSTEMS` (default 1,500) sets the number of systems;
//! run with `--nocapture` for the tally.

mod common;

use common::worst;
use rtpipe_analysis::{analyze, Report};
use rtpipe_joblog::SimResult;
use rtpipe_model::gen::{random_sections, random_system, GenConfig, Rng};
use rtpipe_model::overheads::{Costs, CpuCosts};
use rtpipe_model::{Nanos, Resource, ResourceProtocol, Scheduler, Server, Spec};
use rtpipe_sim::SimConfig;
use rtpipe_testkit::env_u64;

const MS: Nanos = 1_000_000;
const US: Nanos = 1_000;

/// Two sporadic servers on one CPU, cs = 5 µs, rel = 2 µs, rep = 1 µs
/// (so K = 3 µs per release of either).
const HAND: &str = r#"
[system]
name = "hand"
time_unit = "us"
overheads = { context_switch = "5us", release = "2us", replenish = "1us" }
[channels.mem]
bandwidth = 100
overhead = 0
[tasks.a]
exec = 1000
period = 4000
output = { channel = "mem", size = 0 }
[tasks.b]
exec = 2000
period = 10000
reads = ["a"]
"#;

/// By hand (docs/analysis.md, "Scheduling overheads"), in µs:
/// a: w = 1000 + 5 + ⌈w/4000⌉·3 + ⌈w/10000⌉·3 = 1011.
/// b: w = 2000 + 5 + ⌈w/4000⌉·(1000 + 2·5) + ⌈w/4000⌉·3 + ⌈w/10000⌉·3
///    = 2005 + 1010 + 3 + 3 = 3021 (⌈3021/4000⌉ = 1: the fixed point).
/// The simulator reaches both: released together, a runs after the two
/// handlers (6) and its switch (5): 1011. With b released first and a
/// 10 µs later, b has taken its handler (3), its switch (5) and 2 µs of
/// work when a's handler (3), a's switch (5) and a (1000) preempt it;
/// the switch back (5) and b's 1998 µs left end at 3021.
#[test]
fn the_hand_example_reaches_its_bounds() {
    let spec = Spec::parse("hand.toml", HAND).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    let r: Vec<Option<Nanos>> = rep.timing.iter().map(|t| t.job_response_time).collect();
    assert_eq!(r, vec![Some(1011 * US), Some(3021 * US)]);
    assert_eq!(worst(&spec, vec![0, 0])[0], 1011 * US);
    assert_eq!(worst(&spec, vec![10 * US, 0])[1], 3021 * US);
    // Without overheads: 1000 and 3000.
    let plain = Spec::parse("hand.toml", &HAND.replace("overheads = {", "x = {"));
    assert!(plain.is_err(), "an unknown key is refused");
    let mut bare = spec.clone();
    bare.overheads = rtpipe_model::Overheads::default();
    let r: Vec<Option<Nanos>> = analyze(&bare)
        .timing
        .iter()
        .map(|t| t.job_response_time)
        .collect();
    assert_eq!(r, vec![Some(1000 * US), Some(3000 * US)]);
    assert_eq!(worst(&bare, vec![10 * US, 0])[1], 3000 * US);
}

/// EDF by hand (`analysis/tests/overheads.rs`: R = (1.4, 3.4) ms): both
/// released at 0, a's handlers (0.1), a's switch and a (1.1), b's switch
/// and b (2.1): b ends at 3.4, its bound, exactly.
#[test]
fn edf_reaches_its_bound_by_hand() {
    let text = "[system]\nname = \"edf\"\nscheduler = \"edf\"\n\
                overheads = { context_switch = \"100us\", release = \"50us\" }\n\
                [tasks.a]\nexec = 1\nperiod = 4\nserver = \"none\"\n\
                [tasks.b]\nexec = 2\nperiod = 6\nserver = \"none\"\n";
    let spec = Spec::parse("edf.toml", text).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    assert_eq!(rep.timing[1].job_response_time, Some(3_400 * US));
    assert_eq!(worst(&spec, vec![0, 0])[1], 3_400 * US);
}

/// One draw of the three costs, in whole µs.
fn costs(r: &mut Rng) -> Costs {
    Costs {
        context_switch: r.range(0, 60) as Nanos * US,
        release: r.range(0, 40) as Nanos * US,
        replenish: r.range(0, 30) as Nanos * US,
    }
}

/// A generated system (fixed priority with mixed servers and inheritance,
/// or EDF), with overheads, written as TOML and parsed back.
fn system(seed: u64) -> Spec {
    let mut r = Rng::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x0e0e);
    let edf = r.chance(0.35);
    let gen = GenConfig {
        tasks: r.range(2, 7) as usize,
        cpus: r.range(1, 2) as u32,
        utilization: 0.3 + 0.55 * r.unit(),
        scheduler: if edf { Scheduler::Edf } else { Scheduler::Rm },
        mixed_servers: true,
        inheritance: if edf { 0.0 } else { 0.5 },
        chains: 2,
        ..GenConfig::default()
    };
    let mut spec = random_system(seed, &gen);
    spec.overheads.system = costs(&mut r);
    if r.chance(0.3) {
        let c = costs(&mut r);
        spec.overheads.cpus.insert(
            spec.tasks[0].cpu,
            CpuCosts {
                context_switch: Some(c.context_switch),
                release: r.chance(0.5).then_some(c.release),
                replenish: None,
            },
        );
    }
    if !edf && r.chance(0.25) {
        add_sections(&mut spec, &mut r);
    }
    // Plain tasks may have release jitter under fixed priorities (a
    // server may not: validation).
    let jitter = !edf && r.chance(0.3);
    for t in spec.tasks.iter_mut() {
        let period = t.fixed_period().unwrap_or(MS);
        if jitter && t.server == Server::None && r.chance(0.5) {
            t.jitter = r.range(0, (period / 4 / US) as u64) as Nanos * US;
        }
    }
    // A background task (on no chain, served by nobody) whose releases
    // still run their handlers.
    let free = (0..spec.tasks.len()).rev().find(|&i| {
        !spec.chains.iter().any(|c| c.path.contains(&i))
            && !spec.tasks.iter().any(|t| t.serves == Some(i))
    });
    if let Some(i) = free.filter(|_| r.chance(0.5)) {
        let t = &mut spec.tasks[i];
        (t.server, t.serves, t.budget_given, t.jitter) = (Server::Background, None, None, 0);
        t.sections.clear();
    }
    if r.chance(0.3) {
        for t in spec.tasks.iter_mut() {
            t.offset = Some(0);
        }
    }
    let text = rtpipe_model::to_toml(&spec);
    Spec::parse("ovh.toml", &text).unwrap_or_else(|e| {
        panic!("seed {seed}: the generated spec does not validate:\n{e}\n{text}")
    })
}

/// Every task plain, with up to two critical sections each on one or two
/// resources of its CPU, under PCP or SRP (PIP is refused with overheads).
fn add_sections(spec: &mut Spec, r: &mut Rng) {
    spec.resource_protocol = [ResourceProtocol::Pcp, ResourceProtocol::Srp][r.range(0, 1) as usize];
    let cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    // Two resources per CPU (0 and 1 on the lowest, 2 and 3 on the next),
    // each used on one CPU only.
    let lowest = cpus.iter().copied().min().unwrap_or(0);
    spec.resources = (0..4)
        .map(|k| Resource {
            name: format!("r{k}"),
        })
        .collect();
    for t in spec.tasks.iter_mut() {
        (t.server, t.serves, t.budget_given) = (Server::None, None, None);
        let base = if t.cpu == lowest { 0 } else { 2 };
        let count = r.range(0, 2);
        t.sections = random_sections(r, t.exec, count, (1, 2), |r| base + r.range(0, 1) as usize);
    }
}

#[derive(Default)]
struct Tally {
    systems: u64,
    runs: u64,
    checks: u64,
    /// Tasks with a bounded response under overheads, and those whose
    /// worst response came within 3 % of it.
    bounded: u64,
    near: u64,
    /// Systems with EDF, a background task, release jitter, critical
    /// sections.
    edf: u64,
    sections: u64,
    background: u64,
    jittered: u64,
    /// The system's best observed / sound of a chain of two or more
    /// tasks, and the systems where it reached 0.97.
    chain_best: f64,
    chains_near: u64,
    failures: Vec<String>,
}

/// Every bound against one run (`common::check_run`), tallied.
fn check(
    spec: &Spec,
    rep: &Report,
    cfg: &SimConfig,
    res: &SimResult,
    t: &mut Tally,
    ratios: &mut [f64],
) -> (f64, usize) {
    t.runs += 1;
    let (checks, best) = common::check_run(spec, rep, cfg, res, ratios, &mut t.failures);
    t.checks += checks;
    t.chain_best = t.chain_best.max(best.0);
    best
}

fn check_system(seed: u64, t: &mut Tally) {
    let spec = system(seed);
    let rep = analyze(&spec);
    let horizon = common::horizon(&spec);
    t.systems += 1;
    t.chain_best = 0.0;
    t.edf += u64::from(spec.scheduler == Scheduler::Edf);
    t.background += u64::from(spec.tasks.iter().any(|x| x.server == Server::Background));
    t.jittered += u64::from(spec.tasks.iter().any(|x| x.jitter > 0));
    t.sections += u64::from(spec.tasks.iter().any(|x| !x.sections.is_empty()));
    let mut ratios = vec![0.0; spec.tasks.len()];
    let how = common::Probe {
        runs: common::plain_runs(),
        stride: 31,
        salt: 0x0e0e,
        horizon,
    };
    common::probe(&spec, &rep, seed, &how, &mut |cfg, res| {
        check(&spec, &rep, cfg, res, t, &mut ratios)
    });
    t.chains_near += u64::from(t.chain_best >= 0.97);
    for (i, tm) in rep.timing.iter().enumerate() {
        if tm.bounded_response().is_some() {
            t.bounded += 1;
            t.near += u64::from(ratios[i] >= 0.97);
        }
    }
}

#[test]
fn overheads_never_exceed_the_bounds() {
    let n = env_u64("RTPIPE_OVERHEAD_SYSTEMS", 1_500);
    let mut t = Tally::default();
    for seed in 0..n {
        check_system(seed, &mut t);
        assert!(
            t.failures.is_empty(),
            "seed {seed}:\n{}",
            t.failures.join("\n")
        );
    }
    println!(
        "{} systems ({} EDF, {} with a background task, {} with jitter, {} with critical sections), {} runs, {} checks; {} of {} bounded tasks within 3 % of R(job); {} systems with a chain of two or more tasks within 3 % of its sound bound",
        t.systems, t.edf, t.background, t.jittered, t.sections, t.runs, t.checks, t.near, t.bounded, t.chains_near
    );
    assert!(t.chains_near > 0, "no chain came near its bound");
    assert!(t.near > 0, "no task came near its bound");
}

/// The tightness of these systems per feature (`common::tight`;
/// docs/analysis.md, "How tight, per feature"): minutes of work, hence
/// ignored; `--ignored --nocapture` prints the table.
#[test]
#[ignore]
fn tightness() {
    common::tight::per_feature("overheads", system);
}
