//! The EDF analysis' per-CPU path (each CPU's tasks, periods, b(t) and
//! loads gathered once from the index of tasks by CPU, `sched::EdfCpu`;
//! docs/analysis.md, "Scale") against a naive reference that gathers them
//! for every task from a scan of every task, as the analysis did before:
//! the same response times, read-to-publish bounds, blocking and verdict
//! per CPU, on random systems of several CPUs under EDF, with critical
//! sections under the stack resource policy, overheads, constrained
//! deadlines and background tasks.

use rtpipe_analysis::blocking::{srp_at, srp_max, srp_spec_steps, srp_steps};
use rtpipe_analysis::edf::{self, EdfTask};
use rtpipe_analysis::overheads;
use rtpipe_analysis::qpa;
use rtpipe_analysis::sched::{self, interference};
use rtpipe_model::gen::{add_contention, random_system, Contention, GenConfig, Rng};
use rtpipe_model::{Nanos, ResourceProtocol, SchedTest, Scheduler, Server, Spec, MAX_TIME};

const SYSTEMS: u64 = 400;

/// System `seed` under EDF: 4–40 tasks on 1–6 CPUs, critical sections
/// (drawn under RM, where `add_contention` draws them, then kept under
/// SRP) and overheads where drawn, some deadlines below the period and
/// some background tasks; `None` where validation refuses the draw.
fn system(seed: u64) -> Option<Spec> {
    let mut rng = Rng::new(seed ^ 0xedf);
    let cfg = GenConfig {
        tasks: rng.range(4, 40) as usize,
        cpus: rng.range(1, 6) as u32,
        utilization: 0.3 + 0.65 * rng.unit(),
        scheduler: Scheduler::Rm,
        chains: 2,
        mixed_servers: rng.chance(0.5),
        ..GenConfig::default()
    };
    let mut spec = random_system(seed, &cfg);
    let contention = Contention {
        sections: 0.7,
        overheads: 0.4,
        max_cost: 40_000,
    };
    add_contention(&mut spec, &mut rng, &contention);
    spec.scheduler = Scheduler::Edf;
    // Deadlines below periods take the demand test, which validation
    // refuses with overheads.
    let constrained = spec.overheads.is_zero() && rng.chance(0.5);
    spec.schedulability = if constrained || (spec.overheads.is_zero() && rng.chance(0.3)) {
        SchedTest::Qpa
    } else {
        SchedTest::Edf
    };
    if !spec.resources.is_empty() {
        spec.resource_protocol = ResourceProtocol::Srp;
    }
    for t in spec.tasks.iter_mut() {
        let Some(period) = t.fixed_period() else {
            continue;
        };
        if constrained && rng.chance(0.3) {
            t.deadline_given = Some(period / 10 * rng.range(5, 10) as Nanos);
        } else if t.sections.is_empty() && rng.chance(0.05) {
            (t.server, t.budget_given) = (Server::Background, None);
        }
    }
    Spec::parse("edf.toml", &rtpipe_model::to_toml(&spec)).ok()
}

/// The tasks of `cpu`, by a scan of every task.
fn scan(spec: &Spec, cpu: u32) -> Vec<usize> {
    (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].cpu == cpu)
        .collect()
}

fn period(spec: &Spec, j: usize) -> Nanos {
    spec.tasks[j].fixed_period().unwrap_or(MAX_TIME)
}

fn deadline(spec: &Spec, j: usize) -> Nanos {
    let t = period(spec, j);
    spec.tasks[j].deadline_given.map_or(t, |d| d.min(t))
}

/// Task `i`'s CPU as Spuri's analysis counts it, gathered by a scan, and
/// i's place in it.
fn naive_tasks(spec: &Spec, i: usize) -> (Vec<EdfTask>, usize) {
    let mut at = 0;
    let mut out = Vec::new();
    for j in scan(spec, spec.tasks[i].cpu) {
        let t = &spec.tasks[j];
        let background = t.server == Server::Background;
        if background && overheads::per_release(spec, j) == 0 {
            continue;
        }
        if j == i {
            at = out.len();
        }
        out.push(EdfTask {
            work: if background {
                0
            } else {
                interference(t).saturating_add(overheads::per_job(spec, j))
            },
            period: period(spec, j),
            deadline: if background {
                Nanos::MAX
            } else {
                deadline(spec, j)
            },
            kernel: overheads::per_release(spec, j),
        });
    }
    (out, at)
}

/// Task `i`'s (budget, job) response by Spuri's analysis, every input
/// gathered by a scan.
fn naive_spuri(spec: &Spec, i: usize) -> (Option<Nanos>, Option<Nanos>) {
    let t = &spec.tasks[i];
    let on = scan(spec, t.cpu);
    let guaranteed = || {
        on.iter()
            .copied()
            .filter(|&j| spec.tasks[j].server != Server::Background)
    };
    let u: f64 = guaranteed()
        .map(|j| spec.tasks[j].budget() as f64 / period(spec, j) as f64)
        .sum();
    let load: f64 = on
        .iter()
        .map(|&j| {
            let mut c = overheads::per_release(spec, j);
            if spec.tasks[j].server != Server::Background {
                c = c.saturating_add(overheads::per_job(spec, j));
            }
            c as f64 / period(spec, j) as f64
        })
        .sum();
    if u + load > 1.0 + 1e-12 {
        return (None, None);
    }
    let cs = overheads::blocking_switch(spec, i);
    let block: Vec<(Nanos, Nanos)> = srp_steps(spec, &on, |j| deadline(spec, j))
        .into_iter()
        .map(|(theta, b)| (theta, if b > 0 { b + cs } else { 0 }))
        .collect();
    let (tasks, at) = naive_tasks(spec, i);
    let Some(l) = edf::busy_period(&tasks, srp_max(&block), edf::MAX_BUSY_JOBS) else {
        let ok = overheads::costs(spec, i).is_zero()
            && (srp_max(&block) == 0 || qpa::edf_feasible(spec, t.cpu));
        let p = ok.then_some(period(spec, i));
        return (p, p);
    };
    let own = overheads::own(spec, i);
    let r = |x: Nanos| Some(edf::response_time(&tasks, at, x + own, l, &block));
    (r(t.budget()), r(t.demand()))
}

/// Task `i`'s (budget, job, read-to-publish) figures, as the analysis took
/// them before, from scans.
fn naive_figures(spec: &Spec, i: usize) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let t = &spec.tasks[i];
    if t.server == Server::Background {
        return (None, None, None);
    }
    let constrained = scan(spec, t.cpu).into_iter().any(|j| {
        spec.tasks[j].server != Server::Background
            && spec.tasks[j]
                .deadline_given
                .is_some_and(|d| d < period(spec, j))
    });
    let (b, j) = if !constrained {
        naive_spuri(spec, i)
    } else if qpa::edf_feasible(spec, t.cpu) {
        let d = deadline(spec, i);
        let (b, j) = naive_spuri(spec, i);
        (b.map(|b| b.min(d)), j.map(|j| j.min(d)))
    } else {
        (None, None)
    };
    let (tasks, at) = naive_tasks(spec, i);
    let own = t.demand() + overheads::own(spec, i);
    let w = j.map(|j| edf::start_to_finish(&tasks, at, own).min(j));
    (b, j, w)
}

/// A CPU whose figures the overheads' accounting may drop
/// (`overheads::unaccounted`): overheads and a server without a bounded
/// response.
fn may_drop(spec: &Spec, cpu: u32) -> bool {
    scan(spec, cpu).into_iter().any(|j| {
        !overheads::costs(spec, j).is_zero()
            && naive_figures(spec, j).1.is_none_or(|r| r > period(spec, j))
    })
}

fn check(seed: u64, spec: &Spec) {
    let (timing, verdict) = sched::analyze(spec);
    for (i, t) in spec.tasks.iter().enumerate() {
        let at = format!("system {seed}, task {}", t.name);
        let b = srp_at(
            &srp_spec_steps(spec, t.cpu),
            t.deadline().unwrap_or(MAX_TIME),
        );
        let b = if t.server == Server::Background { 0 } else { b };
        assert_eq!(timing[i].blocking, b, "{at}: B");
        if may_drop(spec, t.cpu) {
            continue;
        }
        let got = (
            timing[i].response_time,
            timing[i].job_response_time,
            timing[i].read_to_publish,
        );
        assert_eq!(got, naive_figures(spec, i), "{at}: (R budget, R job, W)");
    }
    for v in &verdict.cpus {
        let ids: Vec<usize> = scan(spec, v.cpu)
            .into_iter()
            .filter(|&i| spec.tasks[i].server != Server::Background)
            .collect();
        assert_eq!(v.tasks, ids.len(), "system {seed}, CPU {}", v.cpu);
        if spec.schedulability == SchedTest::Qpa {
            let steps = srp_spec_steps(spec, v.cpu);
            let (_, _, ok) = qpa::qpa_verdict(spec, &ids, &steps);
            assert_eq!(v.schedulable, ok, "system {seed}, CPU {}: QPA", v.cpu);
        }
    }
}

#[test]
fn the_edf_per_cpu_path_agrees_with_a_scan_of_every_task() {
    let (mut compared, mut sections, mut overheads, mut constrained) = (0, 0, 0, 0);
    for seed in 0..SYSTEMS {
        let Some(spec) = system(seed) else {
            continue;
        };
        compared += 1;
        sections += usize::from(!spec.resources.is_empty());
        overheads += usize::from(!spec.overheads.is_zero());
        constrained += usize::from(spec.tasks.iter().any(|t| t.deadline_given.is_some()));
        check(seed, &spec);
    }
    // The generator drew every kind of system, so every path was compared.
    let enough = SYSTEMS as usize / 10;
    assert!(
        compared > SYSTEMS as usize / 2,
        "{compared} systems compared"
    );
    assert!(sections > enough, "{sections} systems with sections");
    assert!(overheads > enough, "{overheads} systems with overheads");
    assert!(constrained > enough, "{constrained} with deadlines");
}
