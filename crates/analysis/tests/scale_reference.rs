//! The analysis' per-CPU path (tasks indexed by CPU once, ceilings and
//! kernel loads computed once, no scans without resources or overheads;
//! docs/analysis.md, "Scale") against a naive reference that scans every
//! task for every task, as the analysis did before: the same ranks,
//! blocking, highest ranks, interferers and kernel load, and the same
//! verdict per CPU, on random systems of several CPUs with and without
//! critical sections and overheads.

use rtpipe_analysis::blocking::{blocking_by, srp_at, srp_spec_steps};
use rtpipe_analysis::sched::{self, hp_load, interference, interferers, top_priorities};
use rtpipe_model::gen::{add_contention, random_system, Contention, GenConfig, Rng};
use rtpipe_model::policy::rank_key;
use rtpipe_model::{Nanos, Scheduler, Server, Spec, MAX_TIME};

const SYSTEMS: u64 = 400;

/// System `seed`: 4–40 tasks on 1–6 CPUs, RM or EDF; for three seeds in
/// four critical sections and overheads where `add_contention` draws them
/// (written and parsed back; a spec validation refuses stays without).
fn system(seed: u64) -> Spec {
    let mut rng = Rng::new(seed ^ 0x5ca1e);
    let cfg = GenConfig {
        tasks: rng.range(4, 40) as usize,
        cpus: rng.range(1, 6) as u32,
        utilization: 0.3 + 0.6 * rng.unit(),
        scheduler: if rng.chance(0.25) {
            Scheduler::Edf
        } else {
            Scheduler::Rm
        },
        chains: 2,
        mixed_servers: rng.chance(0.5),
        inheritance: if rng.chance(0.3) { 0.5 } else { 0.0 },
        ..GenConfig::default()
    };
    let spec = random_system(seed, &cfg);
    if seed.is_multiple_of(4) {
        return spec;
    }
    let mut s = spec.clone();
    let c = Contention {
        sections: 0.8,
        overheads: 0.6,
        max_cost: 40_000,
    };
    add_contention(&mut s, &mut Rng::new(seed ^ 0xc0de), &c);
    Spec::parse("c.toml", &rtpipe_model::to_toml(&s)).unwrap_or(spec)
}

/// Ranks per CPU by a scan of every task per CPU (the tasks of a thread
/// share one; the generated systems have none).
fn naive_ranks(spec: &Spec) -> Vec<Option<usize>> {
    if !spec.policy().fixed_priority() {
        return vec![None; spec.tasks.len()];
    }
    let mut out = vec![None; spec.tasks.len()];
    for cpu in 0..=spec.tasks.iter().map(|t| t.cpu).max().unwrap_or(0) {
        let mut ids: Vec<usize> = (0..spec.tasks.len())
            .filter(|&i| spec.tasks[i].cpu == cpu && spec.tasks[i].server != Server::Background)
            .collect();
        let key = |i: usize| {
            let t = &spec.tasks[i];
            rank_key(spec.priorities, t).at(t.fixed_period().unwrap_or(Nanos::MAX))
        };
        ids.sort_by_key(|&i| (key(i), i));
        for (rank, i) in ids.into_iter().enumerate() {
            out[i] = Some(rank + 1);
        }
    }
    out
}

/// Each resource's ceiling by a scan of every task.
fn naive_ceiling(spec: &Spec, prio: &[Option<usize>], r: usize) -> Option<usize> {
    (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].sections.iter().any(|s| s.resource == r))
        .filter_map(|j| prio[j])
        .min()
}

/// B_i by a scan of every task for task `i`.
fn naive_blocking(spec: &Spec, prio: &[Option<usize>], i: usize) -> Nanos {
    let t = &spec.tasks[i];
    if !spec.policy().fixed_priority() {
        if t.server == Server::Background {
            return 0;
        }
        return srp_at(
            &srp_spec_steps(spec, t.cpu),
            t.deadline().unwrap_or(MAX_TIME),
        );
    }
    let Some(own) = prio[i] else { return 0 };
    blocking_by(
        spec,
        |j| spec.tasks[j].cpu == t.cpu && prio[j].is_some_and(|p| p > own),
        |r| naive_ceiling(spec, prio, r).is_some_and(|c| c <= own),
    )
}

/// The kernel work of every task of task `i`'s CPU, by a scan.
fn naive_kernel(spec: &Spec, i: usize) -> Vec<(Nanos, Nanos, Nanos)> {
    let cpu = spec.tasks[i].cpu;
    (0..spec.tasks.len())
        .filter(|&k| spec.tasks[k].cpu == cpu)
        .map(|k| {
            let t = &spec.tasks[k];
            let c = spec.overheads.on(cpu).per_release(spec, t.server);
            (c, t.fixed_period().unwrap_or(MAX_TIME), t.jitter)
        })
        .filter(|&(c, _, _)| c > 0)
        .collect()
}

fn check(seed: u64) {
    let spec = system(seed);
    let prio = spec.policy().priorities(&spec);
    assert_eq!(prio, naive_ranks(&spec), "system {seed}: ranks");
    let top = top_priorities(&spec, &prio);
    let (timing, verdict) = sched::analyze(&spec);
    for (i, t) in spec.tasks.iter().enumerate() {
        let at = format!("system {seed}, task {}", t.name);
        assert_eq!(
            timing[i].blocking,
            naive_blocking(&spec, &prio, i),
            "{at}: B"
        );
        let locking = t
            .sections
            .iter()
            .filter_map(|s| naive_ceiling(&spec, &prio, s.resource))
            .fold(top[i], |a, c| Some(a.map_or(c, |a| a.min(c))));
        assert_eq!(timing[i].top_priority, locking, "{at}: highest rank");
        if !spec.policy().fixed_priority() || t.server == Server::Background {
            continue;
        }
        let above = interferers(&spec, &prio, &top, i);
        // Where nothing runs above by inheritance, hp is I_j + 2·cs per
        // interferer and then the CPU's kernel work.
        if above.iter().all(|&j| prio[j] <= prio[i]) {
            let cs2 = spec.overheads.on(t.cpu).context_switch * 2;
            let mut naive: Vec<(Nanos, Nanos, Nanos)> = above
                .iter()
                .map(|&j| {
                    let o = &spec.tasks[j];
                    (
                        interference(o) + cs2,
                        o.fixed_period().unwrap_or(MAX_TIME),
                        o.jitter,
                    )
                })
                .collect();
            naive.extend(naive_kernel(&spec, i));
            assert_eq!(hp_load(&spec, &prio, &top, i), Some(naive), "{at}: hp");
        }
    }
    for v in &verdict.cpus {
        let guaranteed = (0..spec.tasks.len())
            .filter(|&i| spec.tasks[i].cpu == v.cpu && spec.tasks[i].server != Server::Background)
            .count();
        assert_eq!(v.tasks, guaranteed, "system {seed}, CPU {}", v.cpu);
    }
}

#[test]
fn the_per_cpu_path_agrees_with_a_scan_of_every_task() {
    let (mut sections, mut overheads) = (0, 0);
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        sections += usize::from(!spec.resources.is_empty());
        overheads += usize::from(!spec.overheads.is_zero());
        check(seed);
    }
    // The generator drew both kinds of system, so both paths were compared.
    assert!(
        sections > SYSTEMS as usize / 10,
        "{sections} systems with sections"
    );
    assert!(
        overheads > SYSTEMS as usize / 10,
        "{overheads} systems with overheads"
    );
}
