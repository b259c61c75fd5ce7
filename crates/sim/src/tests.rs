//! Hand-traced schedules. Times are plain nanoseconds (small integers) so the
//! traces in the comments read directly.

use super::*;
use rtpipe_analysis::Anchor;
use rtpipe_joblog::{chains_from_jobs, sample_rows, SampleRow, Witness};
use rtpipe_model::{Chain, PeriodSpec, SchedTest, Task, TimeUnit};
use rtpipe_model::{Scheduler, Server};

/// A task with exec = exec_min (no transfer stages), one output, on `cpu`.
pub(crate) fn task(period: Nanos, exec: Nanos, reads: &[usize], cpu: u32) -> Task {
    Task {
        reads: reads.to_vec(),
        cpu,
        ..Task::periodic(exec, period)
    }
}

pub(crate) fn spec(scheduler: Scheduler, mut tasks: Vec<Task>, chains: &[&[usize]]) -> Spec {
    for (i, t) in tasks.iter_mut().enumerate() {
        t.name = format!("t{i}");
    }
    // Start from a generated system so that fields the simulator ignores
    // keep valid defaults.
    let mut s = rtpipe_model::gen::random_system(0, &rtpipe_model::gen::GenConfig::default());
    s.name = "hand".into();
    s.time_unit = TimeUnit::Ns;
    s.scheduler = scheduler;
    s.schedulability = match scheduler {
        Scheduler::Rm => SchedTest::Rta,
        Scheduler::Edf => SchedTest::Edf,
    };
    s.tasks = tasks;
    s.chains = chains
        .iter()
        .map(|p| Chain {
            name: None,
            path: p.to_vec(),
            reaction: None,
            freshness: None,
            max_reaction_time: None,
            freshness_from_event: None,
            communication: None,
        })
        .collect();
    s
}

fn run(spec: &Spec, horizon: Nanos, phasing: Phasing, exec: ExecModel) -> SimResult {
    let cfg = SimConfig {
        horizon,
        seed: 1,
        phasing,
        exec,
        log_jobs: true,
        jitter: crate::Jitter::Uniform,
    };
    match simulate(spec, &cfg) {
        Ok(r) => r,
        Err(e) => panic!("{e}"),
    }
}

/// (read, finish, carried samples) of job `index` of `task`.
fn job(r: &SimResult, task: usize, index: u64) -> (Nanos, Nanos, Vec<Option<u64>>) {
    let j = r
        .jobs
        .iter()
        .find(|j| j.task == task && j.index == index)
        .unwrap_or_else(|| panic!("job {index} of t{task} did not complete"));
    (
        j.read,
        j.finish,
        j.carried.iter().map(|c| c.sample).collect(),
    )
}

/// The simulated maxima never exceed the analysis' sound bounds.
fn assert_within_sound(spec: &Spec, r: &SimResult) {
    let report = rtpipe_analysis::analyze(spec);
    for c in &report.chains {
        let st = &r.chains[c.chain];
        let seen = match c.metric {
            rtpipe_analysis::Metric::Reaction => st.reaction.max,
            rtpipe_analysis::Metric::Freshness => st.freshness.max,
        };
        if let (Some(s), Some(b)) = (seen, c.bound.sound(Anchor::Read)) {
            assert!(s <= b, "chain {} {:?}: {s} > {b}", c.chain, c.metric);
        }
    }
}

#[test]
fn slow_consumer_rm() {
    // t0: T=10, C=2 (rank 1); t1: T=20, C=3 (rank 2), reads t0.
    // t0 runs [10k, 10k+2], reading at 10k (sample k) and publishing at 10k+2.
    // t1 job m starts at 20m+2, right when t0 publishes, so it reads sample
    // 2m; it publishes at 20m+5: reaction = freshness = 5.
    // Chain [0] alone: 2; chain [1] alone: read 20m+2, publish 20m+5: 3.
    let s = spec(
        Scheduler::Rm,
        vec![task(10, 2, &[], 0), task(20, 3, &[0], 0)],
        &[&[0, 1], &[0], &[1]],
    );
    let r = run(&s, 100, Phasing::Sync, ExecModel::Worst);
    assert_eq!(job(&r, 0, 0), (0, 2, vec![Some(0), Some(0)]));
    assert_eq!(job(&r, 1, 0), (2, 5, vec![Some(0), Some(0)]));
    assert_eq!(job(&r, 1, 1), (22, 25, vec![Some(2), Some(1)]));
    let c = &r.chains[0];
    assert_eq!((c.reaction.max, c.freshness.max), (Some(5), Some(5)));
    // Head reads at 0, 10, …, 100; tail outputs at 5, 25, 45, 65, 85 carry
    // samples 0, 2, 4, 6, 8; the last is not final.
    assert_eq!((c.samples, c.reached, c.finalised), (11, 5, 4));
    // Reaction counts every sample that reached the tail, the last one too.
    assert_eq!(c.reaction.hist.sorted(), vec![5; 5]);
    assert_eq!(c.freshness.hist.sorted(), vec![5; 4]);
    // From the event just after head read k−1 (at 10(k−1)) to the first tail
    // output carrying sample k or newer: odd samples never reach the tail, so
    // their events wait for the next even one: 25 − 0, 25 − 10, 45 − 20, …;
    // samples 9 and 10 have no such output before the horizon.
    assert_eq!(
        c.event_reaction.hist.sorted(),
        vec![15, 15, 15, 15, 25, 25, 25, 25]
    );
    // Freshness from the event: read before the sample's to its last output.
    assert_eq!(c.event_freshness.hist.sorted(), vec![15, 15, 15]);
    assert_eq!(
        c.freshness.witness,
        Some(Witness {
            sample: 0,
            read: 0,
            first: 5,
            last: 5
        })
    );
    assert_eq!(
        (r.chains[1].reaction.max, r.chains[1].freshness.max),
        (Some(2), Some(2))
    );
    assert_eq!(
        (r.chains[2].reaction.max, r.chains[2].freshness.max),
        (Some(3), Some(3))
    );
    assert_eq!(r.tasks[0].max_response, Some(2));
    assert_eq!(r.tasks[1].max_response, Some(5));
    assert_eq!(r.tasks[1].late, 0);
    assert_within_sound(&s, &r);
}

#[test]
fn fast_consumer_reads_twice() {
    // t0: T=20, C=3 (rank 2, head); t1: T=10, C=2 (rank 1), reads t0.
    // t1 runs [10k, 10k+2]; t0 runs [20m+2, 20m+5], reading sample m at 20m+2.
    // Sample m is read by t1 at 20m+10 and 20m+20 (t0 publishes only at
    // 20m+25): outputs at 20m+12 and 20m+22, so reaction 10, freshness 20.
    // t1's job 0 reads at 0, before any publish: it carries nothing.
    let s = spec(
        Scheduler::Rm,
        vec![task(20, 3, &[], 0), task(10, 2, &[0], 0)],
        &[&[0, 1]],
    );
    let r = run(&s, 100, Phasing::Sync, ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (0, 2, vec![None]));
    assert_eq!(job(&r, 0, 0), (2, 5, vec![Some(0)]));
    assert_eq!(job(&r, 1, 1), (10, 12, vec![Some(0)]));
    assert_eq!(job(&r, 1, 2), (20, 22, vec![Some(0)]));
    assert_eq!(job(&r, 0, 1), (22, 25, vec![Some(1)]));
    let c = &r.chains[0];
    assert_eq!((c.reaction.max, c.freshness.max), (Some(10), Some(20)));
    // Samples stamped 2, 22, 42, 62, 82 (t0's job released at 100 has not
    // started); tail outputs up to 92 carry samples 0..=4; 4 is not final.
    assert_eq!((c.samples, c.reached, c.finalised), (5, 5, 4));
    assert_within_sound(&s, &r);
}

#[test]
fn read_happens_when_first_running_not_at_release() {
    // t0: T=5, C=1, φ=1 (rank 1, head); t1: T=10, C=3, φ=0, reads t0.
    // t1 job 0 starts at 0 (reads nothing), t0 preempts it over [1, 2], t1
    // resumes and publishes at 4 without a sample. t1 job 1 reads at 10
    // sample 1 (stamped 6, published 7), is preempted over [11, 12] and
    // publishes at 14: reaction = freshness = 14 − 6 = 8.
    let s = spec(
        Scheduler::Rm,
        vec![task(5, 1, &[], 0), task(10, 3, &[0], 0)],
        &[&[0, 1]],
    );
    let r = run(&s, 30, Phasing::Given(vec![1, 0]), ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (0, 4, vec![None]));
    assert_eq!(job(&r, 0, 0), (1, 2, vec![Some(0)]));
    assert_eq!(job(&r, 1, 1), (10, 14, vec![Some(1)]));
    assert_eq!(job(&r, 1, 2), (20, 24, vec![Some(3)]));
    let c = &r.chains[0];
    assert_eq!((c.reaction.max, c.freshness.max), (Some(8), Some(8)));
    assert_eq!((c.samples, c.reached, c.finalised), (6, 2, 1));
    assert_eq!(r.tasks[1].max_response, Some(4));
    assert_eq!(r.offsets, vec![1, 0]);
}

#[test]
fn publish_precedes_read_at_the_same_instant_across_cpus() {
    // t0 on CPU 0 publishes sample k at 10k+2. t1 on CPU 1 (φ=2) starts at
    // that very instant and must see sample k: reaction 10k+4 − 10k = 4.
    let tasks = vec![task(10, 2, &[], 0), task(10, 2, &[0], 1)];
    let s = spec(Scheduler::Rm, tasks, &[&[0, 1]]);
    let r = run(&s, 50, Phasing::Given(vec![0, 2]), ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (2, 4, vec![Some(0)]));
    assert_eq!(r.chains[0].reaction.max, Some(4));
    assert_eq!(r.chains[0].freshness.max, Some(4));
    // One nanosecond earlier (φ=1) it reads the previous sample: 10k+3 − 10(k−1) = 13.
    let r = run(&s, 50, Phasing::Given(vec![0, 1]), ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (1, 3, vec![None]));
    assert_eq!(job(&r, 1, 1), (11, 13, vec![Some(0)]));
    assert_eq!(r.chains[0].reaction.max, Some(13));
    assert_eq!(r.chains[0].freshness.max, Some(13));
}

#[test]
fn edf_and_rm_differ() {
    // t0: T=10, C=5, φ=0; t1: T=8, C=2, φ=3, reads t0.
    // RM (t1 rank 1): t1 preempts at 3, reads nothing, publishes at 5; t0 ends at 7.
    // EDF: t1's deadline 11 is later than t0's 10: t0 runs to 5 and publishes
    // sample 0 exactly when t1 starts, so t1 reads it and publishes at 7.
    let tasks = vec![task(10, 5, &[], 0), task(8, 2, &[0], 0)];
    let rm = spec(Scheduler::Rm, tasks.clone(), &[&[0, 1]]);
    let r = run(&rm, 9, Phasing::Given(vec![0, 3]), ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (3, 5, vec![None]));
    assert_eq!(job(&r, 0, 0), (0, 7, vec![Some(0)]));
    let edf = spec(Scheduler::Edf, tasks, &[&[0, 1]]);
    let r = run(&edf, 9, Phasing::Given(vec![0, 3]), ExecModel::Worst);
    assert_eq!(job(&r, 0, 0), (0, 5, vec![Some(0)]));
    assert_eq!(job(&r, 1, 0), (5, 7, vec![Some(0)]));
}

#[test]
fn edf_ties_go_to_the_lower_index() {
    // Equal deadlines: t0 first, then t1, whatever the declaration of reads.
    let tasks = vec![task(10, 2, &[1], 0), task(10, 2, &[], 0)];
    let s = spec(Scheduler::Edf, tasks, &[&[1, 0]]);
    let r = run(&s, 25, Phasing::Sync, ExecModel::Worst);
    assert_eq!(job(&r, 0, 0), (0, 2, vec![None]));
    assert_eq!(job(&r, 1, 0), (2, 4, vec![Some(0)]));
    assert_eq!(job(&r, 0, 1), (10, 12, vec![Some(0)]));
    // Sample 0 stamped 2, output at 12; sample 1 (12) at 22: reaction 10.
    assert_eq!(r.chains[0].reaction.max, Some(10));
    assert_eq!(r.chains[0].finalised, 1);
}

#[test]
fn zero_demand_job_reads_then_publishes_at_once() {
    // t0's best case is 0: at instant 0 it starts (reads, sample 0) and
    // completes; t1, same CPU and lower rank, then starts at 0 and sees it.
    let mut t0 = task(10, 2, &[], 0);
    t0.exec_min = 0;
    let s = spec(Scheduler::Rm, vec![t0, task(10, 3, &[0], 0)], &[&[0, 1]]);
    let r = run(&s, 25, Phasing::Sync, ExecModel::Best);
    assert_eq!(job(&r, 0, 0), (0, 0, vec![Some(0)]));
    assert_eq!(job(&r, 1, 0), (0, 3, vec![Some(0)]));
    assert_eq!(r.chains[0].reaction.max, Some(3));
    assert_eq!(r.tasks[0].max_response, Some(0));
}

#[test]
fn overrun_keeps_jobs_fifo() {
    // Two tasks of T=10, C=6 on one CPU: 120 % load. t1 gets [6, 10],
    // [16, 18] (job 0 done at 18), [18, 20], [26, 30] (job 1 done at 30).
    let s = spec(
        Scheduler::Rm,
        vec![task(10, 6, &[], 0), task(10, 6, &[], 0)],
        &[],
    );
    let r = run(&s, 40, Phasing::Sync, ExecModel::Worst);
    assert_eq!(job(&r, 1, 0), (6, 18, vec![]));
    assert_eq!(job(&r, 1, 1), (18, 30, vec![]));
    let t1 = &r.tasks[1];
    assert_eq!((t1.released, t1.completed, t1.late), (5, 2, 2));
    assert_eq!(t1.max_response, Some(20));
}

#[test]
fn transfer_stages_count_in_the_demand() {
    // Δin = 1, p = 2, Δout = 1: a job holds the CPU for 4.
    let mut t0 = task(10, 2, &[], 0);
    t0.delta_in = 1;
    t0.delta_out = 1;
    let s = spec(Scheduler::Rm, vec![t0, task(10, 1, &[0], 0)], &[&[0, 1]]);
    let r = run(&s, 30, Phasing::Sync, ExecModel::Worst);
    assert_eq!(job(&r, 0, 0), (0, 4, vec![Some(0)]));
    assert_eq!(job(&r, 1, 0), (4, 5, vec![Some(0)]));
    assert_eq!(r.chains[0].reaction.max, Some(5));
}

#[test]
fn deterministic_per_seed() {
    let cfg = rtpipe_model::gen::GenConfig {
        tasks: 8,
        cpus: 2,
        ..Default::default()
    };
    let s = rtpipe_model::gen::random_system(3, &cfg);
    let mk = |seed| SimConfig {
        horizon: 500_000_000,
        seed,
        phasing: Phasing::Random,
        exec: ExecModel::Uniform,
        log_jobs: false,
        jitter: crate::Jitter::Uniform,
    };
    let a = simulate(&s, &mk(5));
    let b = simulate(&s, &mk(5));
    let c = simulate(&s, &mk(6));
    assert!(a.is_ok());
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Grid phasing lands on the grid, within the period.
    let g = SimConfig {
        phasing: Phasing::Grid(1_000_000),
        ..mk(5)
    };
    let r = match simulate(&s, &g) {
        Ok(r) => r,
        Err(e) => panic!("{e}"),
    };
    for (o, t) in r.offsets.iter().zip(&s.tasks) {
        assert_eq!(o % 1_000_000, 0);
        assert!(t.fixed_period().is_some_and(|p| *o < p));
    }
}

#[test]
fn bad_inputs_are_errors() {
    let mut s = spec(Scheduler::Rm, vec![task(10, 2, &[], 0)], &[]);
    let mut cfg = SimConfig::new(0);
    assert_eq!(simulate(&s, &cfg), Err(SimError::HorizonNotPositive(0)));
    cfg.horizon = 10;
    cfg.phasing = Phasing::Given(vec![]);
    assert_eq!(
        simulate(&s, &cfg),
        Err(SimError::BadOffsets {
            expected: 1,
            found: 0
        })
    );
    cfg.phasing = Phasing::Grid(0);
    assert_eq!(simulate(&s, &cfg), Err(SimError::GridNotPositive(0)));
    cfg.phasing = Phasing::Sync;
    s.chains = vec![Chain {
        name: None,
        path: vec![0, 1],
        reaction: None,
        freshness: None,
        max_reaction_time: None,
        freshness_from_event: None,
        communication: None,
    }];
    assert_eq!(simulate(&s, &cfg), Err(SimError::BadChain(0)));
    s.chains.clear();
    // A best case above the worst case is refused, not clamped.
    s.tasks[0].exec_min = 3;
    assert_eq!(simulate(&s, &cfg), Err(SimError::BadDemand("t0".into())));
    s.tasks[0].exec_min = 2;
    s.tasks[0].period = PeriodSpec::Free;
    assert_eq!(simulate(&s, &cfg), Err(SimError::NoPeriod("t0".into())));
}

#[test]
fn pibs_inherits_the_served_priority() {
    // io (T 20, demand 2) serves m (T 10, demand 1); both released at 0. io
    // inherits m's rank while m waits, wins the tie (declared first) and runs
    // [0, 2); m runs [2, 3): m's response 3 = 1 + 2, as the analysis says.
    let src = "[system]\nname = \"p\"\n[tasks.io]\nexec = 2\nperiod = 20\nserver = \"io\"\nserves = \"m\"\n[tasks.m]\nexec = 1\nperiod = 10\n";
    let spec = match rtpipe_model::Spec::parse("p.toml", src) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    let res = match simulate(&spec, &SimConfig::new(20_000_000)) {
        Ok(r) => r,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(res.tasks[1].max_response, Some(3_000_000));
    let (timing, _) = rtpipe_analysis::sched::analyze(&spec);
    assert_eq!(timing[1].job_response_time, Some(3_000_000));
}

/// A generated system varied for the equivalence test: RM or EDF, one or
/// two CPUs, mixed servers with inheritance, feedback edges, overload up to
/// a utilisation of 1.3 per CPU; then some budgets cut below the demand
/// (exhaustions, slack, CBS throttling), some tasks made background and
/// some I/O VCPUs serving any task.
fn varied_system(seed: u64, tasks: std::ops::RangeInclusive<u64>) -> Spec {
    use rtpipe_model::gen::{random_system, GenConfig, Rng};
    let mut r = Rng::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x51);
    let cfg = GenConfig {
        tasks: r.range(*tasks.start(), *tasks.end()) as usize,
        cpus: r.range(1, 2) as u32,
        utilization: 0.3 + r.unit(),
        scheduler: if r.chance(0.5) {
            Scheduler::Rm
        } else {
            Scheduler::Edf
        },
        feedback: if r.chance(0.3) { 0.3 } else { 0.0 },
        chains: r.range(1, 4) as usize,
        transfers: r.chance(0.5),
        mixed_servers: r.chance(0.8),
        inheritance: r.unit(),
        ..rtpipe_model::gen::GenConfig::default()
    };
    let mut s = random_system(seed, &cfg);
    let cut = r.unit() * 0.4;
    let background = r.unit() * 0.2;
    let n = s.tasks.len() as u64;
    for t in &mut s.tasks {
        // Inheritance the spec validation would refuse (across CPUs, from
        // any kind of task): the simulator runs it all the same.
        if t.server == Server::Io && r.chance(0.2) {
            t.serves = Some(r.range(0, n - 1) as usize);
        }
        if r.chance(cut) {
            let d = t.demand();
            t.budget_given = Some((d * r.range(2, 9) as Nanos / 10).max(1_000));
        }
        if r.chance(background) {
            t.server = Server::Background;
        }
    }
    s
}

/// The configurations each system runs with: every phasing, every demand
/// model, with and without the job log.
fn varied_configs(spec: &Spec, seed: u64, horizon: Nanos) -> Vec<SimConfig> {
    use rtpipe_model::gen::Rng;
    let mut r = Rng::new(seed ^ 0x00C0_FFEE);
    let given = spec
        .tasks
        .iter()
        .map(|t| r.range(0, t.fixed_period().unwrap_or(1) as u64 - 1) as Nanos)
        .collect();
    let ms = 1_000_000;
    [
        (Phasing::Sync, ExecModel::Worst, true),
        (Phasing::Random, ExecModel::Uniform, true),
        (Phasing::Grid(ms), ExecModel::Extremes, false),
        (Phasing::Given(given), ExecModel::Best, true),
        (Phasing::Random, ExecModel::Extremes, true),
    ]
    .into_iter()
    .map(|(phasing, exec, log_jobs)| SimConfig {
        horizon,
        seed: seed.wrapping_add(7),
        phasing,
        exec,
        log_jobs,
        jitter: crate::Jitter::Uniform,
    })
    .collect()
}

fn compare_with_reference(spec: &Spec, cfg: &SimConfig) -> u64 {
    let new = simulate(spec, cfg);
    let old = reference::simulate_reference(spec, cfg);
    assert!(
        new == old,
        "{} ({} tasks, {:?}) with {cfg:?}: the event heaps differ from the reference",
        spec.name,
        spec.tasks.len(),
        spec.scheduler
    );
    new.map_or(0, |r| r.events)
}

/// The event heaps give the results of the per-event scans
/// they replaced, bit for bit: 300 systems of 1 to 14 tasks (60 in debug
/// builds, which also check the incremental state at every pick), five
/// configurations each.
#[test]
fn heaps_match_the_reference() {
    let systems = if cfg!(debug_assertions) { 60 } else { 300 };
    let mut events = 0;
    let mut exhaustions = 0;
    for seed in 0..systems {
        let spec = varied_system(seed, 1..=14);
        let horizon = 300_000_000 + (seed as Nanos % 7) * 250_000_000;
        for cfg in varied_configs(&spec, seed, horizon) {
            events += compare_with_reference(&spec, &cfg);
        }
        let r = simulate(&spec, &SimConfig::new(horizon)).expect("simulates");
        exhaustions += r.tasks.iter().map(|t| t.exhaustions).sum::<u64>();
    }
    eprintln!("{systems} systems: {events} events compared, {exhaustions} exhaustions");
    // The systems do exercise the budget servers.
    assert!(events > 5_000 * systems, "{events} events");
    assert!(exhaustions > 50 * systems, "{exhaustions} exhaustions");
}

/// The same with many tasks (long ready queues in overload): 12 systems of
/// 50 to 300 tasks (3 in debug builds).
#[test]
fn heaps_match_the_reference_with_many_tasks() {
    let systems = if cfg!(debug_assertions) { 3 } else { 12 };
    for seed in 1000..1000 + systems {
        let spec = varied_system(seed, 50..=300);
        for cfg in varied_configs(&spec, seed, 200_000_000) {
            compare_with_reference(&spec, &cfg);
        }
    }
}

/// The lazy CPUs (each CPU charged only when something happens
/// on it, the CPUs' events in a tree) give the every-CPU scans' results:
/// 200 systems (15 in debug builds) of 10 to 60 tasks spread over 3 to 16
/// CPUs, five configurations each.
#[test]
fn lazy_cpus_match_the_reference_on_many_cpus() {
    use rtpipe_model::gen::Rng;
    let systems = if cfg!(debug_assertions) { 15 } else { 200 };
    for seed in 2000..2000 + systems {
        let mut spec = varied_system(seed, 10..=60);
        let mut r = Rng::new(seed);
        let cpus = r.range(3, 16);
        for t in &mut spec.tasks {
            t.cpu = r.range(0, cpus - 1) as u32;
        }
        for cfg in varied_configs(&spec, seed, 300_000_000) {
            compare_with_reference(&spec, &cfg);
        }
    }
}

#[test]
fn progress_reports_do_not_change_the_run() {
    let spec = varied_system(3, 20..=20);
    let cfg = SimConfig {
        horizon: 20_000_000_000,
        ..SimConfig::new(1)
    };
    let mut seen = Vec::new();
    let with = simulate_with_progress(&spec, &cfg, &mut |t| seen.push(t));
    let without = simulate(&spec, &cfg);
    assert_eq!(with, without);
    let events = without.map_or(0, |r| r.events);
    assert_eq!(seen.len() as u64, events / PROGRESS_EVENTS);
    assert!(seen.windows(2).all(|w| w[0] <= w[1]));
    assert!(seen.iter().all(|&t| (0..=cfg.horizon).contains(&t)));
}

#[test]
fn chains_from_jobs_replays_the_simulators_own_measurement() {
    // The measurement from a job log (what `rtpipe run` uses) equals the
    // simulator's own, on the paper's Table 2 system with random phasing and
    // demands (jobs finishing out of their tasks' order across CPUs).
    let text = include_str!("../../../examples/paper-table2.toml");
    let Ok(s) = Spec::parse("paper-table2.toml", text) else {
        panic!("paper-table2.toml parses");
    };
    for seed in 0..4 {
        let cfg = SimConfig {
            seed,
            phasing: Phasing::Random,
            exec: ExecModel::Uniform,
            log_jobs: true,
            jitter: crate::Jitter::Uniform,
            ..SimConfig::new(2_000_000_000)
        };
        let Ok(r) = simulate(&s, &cfg) else {
            panic!("simulates");
        };
        let replayed = chains_from_jobs(&s, &r.jobs);
        for (a, b) in replayed.iter().zip(&r.chains) {
            assert_eq!(a.reaction, b.reaction);
            assert_eq!(a.freshness, b.freshness);
            assert_eq!(a.event_reaction, b.event_reaction);
            assert_eq!(a.event_freshness, b.event_freshness);
            assert_eq!(a.reached, b.reached);
        }
    }
}

#[test]
fn sample_rows_are_the_chain_figures_one_sample_at_a_time() {
    // The per-sample export (`--samples`) lists, in sample order, exactly
    // the values the chain figures hold, for every quantity and anchor.
    let text = include_str!("../../../examples/paper-table2.toml");
    let Ok(s) = Spec::parse("paper-table2.toml", text) else {
        panic!("paper-table2.toml parses");
    };
    let cfg = SimConfig {
        seed: 3,
        phasing: Phasing::Random,
        exec: ExecModel::Uniform,
        log_jobs: true,
        ..SimConfig::new(2_000_000_000)
    };
    let Ok(r) = simulate(&s, &cfg) else {
        panic!("simulates");
    };
    let rows = sample_rows(&s, &r.jobs);
    assert_eq!(rows.len(), r.chains.len());
    for (rows, c) in rows.iter().zip(&r.chains) {
        let col = |f: fn(&SampleRow) -> Option<Nanos>| -> Vec<Nanos> {
            let mut v: Vec<Nanos> = rows.iter().filter_map(f).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(rows.len() as u64, c.samples);
        assert!(rows.iter().enumerate().all(|(k, r)| r.sample == k as u64));
        assert_eq!(col(SampleRow::reaction), c.reaction.hist.sorted());
        assert_eq!(col(SampleRow::freshness), c.freshness.hist.sorted());
        assert_eq!(
            col(SampleRow::event_reaction),
            c.event_reaction.hist.sorted()
        );
        assert_eq!(
            col(SampleRow::event_freshness),
            c.event_freshness.hist.sorted()
        );
        assert!(c.reached > 10);
    }
}

#[test]
fn streamed_rows_are_the_rows_of_the_job_log() {
    // `simulate_with_rows` hands on, chain by chain and in sample order,
    // exactly the rows `sample_rows` makes from the same run's job log.
    use rtpipe_model::gen::{random_system, GenConfig};
    use std::sync::{Arc, Mutex};
    let mut compared = 0;
    for seed in 0..300 {
        let gen = GenConfig {
            tasks: 2 + (seed % 7) as usize,
            cpus: 1 + (seed % 2) as u32,
            chains: 3,
            ..GenConfig::default()
        };
        let s = random_system(seed, &gen);
        let cfg = SimConfig {
            seed,
            phasing: Phasing::Random,
            exec: ExecModel::Uniform,
            log_jobs: true,
            ..SimConfig::new(300_000_000)
        };
        let got: Arc<Mutex<Vec<Vec<SampleRow>>>> =
            Arc::new(Mutex::new(vec![Vec::new(); s.chains.len()]));
        let sink = got.clone();
        let streamed = crate::simulate_with_rows(
            &s,
            &cfg,
            &mut |_| {},
            Box::new(move |c, r| {
                if let Ok(mut g) = sink.lock() {
                    g[c].push(*r);
                }
            }),
        );
        let (Ok(streamed), Ok(logged)) = (streamed, simulate(&s, &cfg)) else {
            panic!("seed {seed}: simulates");
        };
        assert_eq!(streamed.jobs, logged.jobs, "seed {seed}: the same run");
        let want = sample_rows(&s, &logged.jobs);
        let got = got.lock().map(|g| g.clone()).unwrap_or_default();
        assert_eq!(got, want, "seed {seed}");
        compared += want.iter().map(Vec::len).sum::<usize>();
    }
    assert!(compared > 10_000, "only {compared} rows compared");
}

/// Release jitter: each job reads (alone on its CPU, at once) within
/// [k·T, k·T + J] of its nominal release, at its latest under
/// `Jitter::Latest`, at an end under `Jitter::Extremes`; its recorded
/// release and response count from the nominal instant.
#[test]
fn jittered_jobs_release_within_their_window() {
    let mut s = spec(Scheduler::Rm, vec![task(10_000, 1_000, &[], 0)], &[&[0]]);
    s.tasks[0].jitter = 3_000;
    for (jitter, check) in [
        (Jitter::Latest, (|d: Nanos| d == 3_000) as fn(Nanos) -> bool),
        (Jitter::Extremes, |d| d == 0 || d == 3_000),
        (Jitter::Uniform, |d| (0..=3_000).contains(&d)),
        (Jitter::None, |d| d == 0),
    ] {
        let cfg = SimConfig {
            horizon: 200_000,
            seed: 9,
            phasing: Phasing::Sync,
            exec: ExecModel::Worst,
            jitter,
            log_jobs: true,
        };
        let r = simulate(&s, &cfg).unwrap_or_else(|e| panic!("{e}"));
        assert!(r.jobs.len() >= 19, "{jitter:?}");
        for (k, j) in r.jobs.iter().enumerate() {
            assert_eq!(j.release, k as Nanos * 10_000);
            assert!(
                check(j.read - j.release),
                "{jitter:?}: job {k} read {}",
                j.read
            );
        }
        let late = r.jobs.iter().map(|j| j.read - j.release).max().unwrap_or(0);
        assert_eq!(r.tasks[0].max_response, Some(late + 1_000), "{jitter:?}");
    }
}

/// `Jitter::Squeezed`: jobs of even periods come J late, odd ones on time,
/// so a late job's successor comes T − J after it.
#[test]
fn squeezed_jitter_alternates_late_and_on_time() {
    let mut s = spec(Scheduler::Rm, vec![task(10_000, 1_000, &[], 0)], &[&[0]]);
    s.tasks[0].jitter = 3_000;
    let cfg = SimConfig {
        horizon: 200_000,
        seed: 9,
        phasing: Phasing::Given(vec![2_000]),
        exec: ExecModel::Worst,
        jitter: Jitter::Squeezed,
        log_jobs: true,
    };
    let r = simulate(&s, &cfg).unwrap_or_else(|e| panic!("{e}"));
    assert!(r.jobs.len() >= 19);
    for (k, j) in r.jobs.iter().enumerate() {
        assert_eq!(j.release, 2_000 + k as Nanos * 10_000);
        let late = if k % 2 == 0 { 3_000 } else { 0 };
        assert_eq!(j.read - j.release, late, "job {k}");
    }
}

/// The hot state of a task is four cache lines (`TaskSim`'s layout): an
/// event of a plain periodic task touches no more.
#[test]
fn task_state_fits_four_cache_lines() {
    use crate::engine::TaskSim;
    use std::mem::{align_of, offset_of};
    assert_eq!(align_of::<TaskSim>(), 64);
    let hot_end = offset_of!(TaskSim, merges) + 1;
    assert!(
        hot_end <= 4 * 64,
        "hot state ends at {hot_end} (stats at {}, budget at {}, sides at {})",
        offset_of!(TaskSim, stats),
        offset_of!(TaskSim, budget),
        offset_of!(TaskSim, sides),
    );
}
