//! Random event-triggered systems (`rtpipe_model::gen::event_triggered_system`)
//! on real threads, judged on the job log alone (whatever the load did to
//! the schedule): every release is a job or a merge, a data-triggered job
//! is released at a trigger's publish instant, the jobs of one OS thread
//! never overlap, and the chains are measured as from any log. SCHED_OTHER:
//! no privilege needed.

use rtpipe_joblog::JobRecord;
use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
use rtpipe_model::{Join, Nanos, Spec};
use rtpipe_runtime::{run_synthetic, Policy, RunConfig, RunResult, Spin};

const DURATION: Nanos = 100_000_000;
const SEEDS: u64 = 20;

/// The publish instants of task `p`'s jobs before the run's end, sorted.
fn publications(r: &RunResult, p: usize) -> Vec<Nanos> {
    let mut v: Vec<Nanos> = (r.sim.jobs.iter())
        .filter(|j| j.task == p && j.finish < DURATION)
        .map(|j| j.finish)
        .collect();
    v.sort_unstable();
    v
}

/// Task `i`'s releases are its jobs and merges, as its activation says.
fn releases_add_up(spec: &Spec, r: &RunResult, i: usize, seed: u64) {
    let t = &spec.tasks[i];
    let (jobs, merges) = (r.sim.tasks[i].completed, r.sim.tasks[i].merged);
    let what = format!("seed {seed}, task {}: {jobs} jobs, {merges} merges", t.name);
    match t.triggers() {
        None => {
            let (phase, period) = (t.offset.unwrap_or(0), t.fixed_period().unwrap_or(1));
            let timer = ((DURATION - phase + period - 1) / period).max(0) as u64;
            if t.thread.is_some() {
                assert_eq!(jobs + merges, timer, "{what}");
            } else {
                assert_eq!((jobs, merges), (timer, 0), "{what}");
            }
        }
        Some((triggers, join)) => {
            let pubs: Vec<Vec<Nanos>> = triggers.iter().map(|&p| publications(r, p)).collect();
            match join {
                Join::Any => {
                    let all: usize = pubs.iter().map(Vec::len).sum();
                    assert_eq!(jobs + merges, all as u64, "{what}");
                }
                Join::All => {
                    let least = pubs.iter().map(Vec::len).min().unwrap_or(0);
                    assert!(jobs + merges <= least as u64, "{what}: {least}");
                }
            }
            for j in r.sim.jobs.iter().filter(|j| j.task == i) {
                assert!(
                    pubs.iter().any(|p| p.binary_search(&j.release).is_ok()),
                    "{what}: job {} released at {} by no publication",
                    j.index,
                    j.release
                );
            }
        }
    }
}

/// The jobs of each OS thread (a work-queue thread's tasks, or one task)
/// never overlap.
fn one_job_at_a_time(spec: &Spec, r: &RunResult, seed: u64) {
    let key = |t: usize| spec.tasks[t].thread.map_or(t, |th| spec.tasks.len() + th);
    let mut jobs: Vec<&JobRecord> = r.sim.jobs.iter().collect();
    jobs.sort_by_key(|j| (key(j.task), j.read));
    for w in jobs.windows(2) {
        if key(w[0].task) == key(w[1].task) {
            assert!(
                w[0].finish <= w[1].read,
                "seed {seed}: {:?} and {:?} overlap",
                w[0],
                w[1]
            );
        }
    }
    assert!(
        r.sim.jobs.iter().all(|j| j.release <= j.read),
        "seed {seed}"
    );
}

#[test]
fn random_event_triggered_systems_keep_the_queue_rules() {
    let cpus = rtpipe_runtime::sys::online_cpus().min(2) as u32;
    let gen = EventGenConfig {
        max_cpus: cpus,
        ..EventGenConfig::default()
    };
    let spin = Spin::calibrate();
    let cfg = RunConfig {
        duration: DURATION,
        policy: Policy::Other,
        load: 0,
    };
    let (mut triggered, mut merges, mut all) = (0, 0, 0);
    for seed in 0..SEEDS {
        let spec = event_triggered_system(seed, &gen);
        let r = run_synthetic(&spec, &cfg, spin).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        for (i, t) in spec.tasks.iter().enumerate() {
            let jobs = r.sim.tasks[i].completed;
            triggered += if t.is_triggered() { jobs } else { 0 };
            all += u64::from(t.triggers().is_some_and(|(_, j)| j == Join::All)) * jobs;
            merges += r.sim.tasks[i].merged;
        }
        for i in 0..spec.tasks.len() {
            releases_add_up(&spec, &r, i, seed);
        }
        one_job_at_a_time(&spec, &r, seed);
        assert_eq!(
            rtpipe_joblog::chains_from_jobs(&spec, &r.sim.jobs),
            r.sim.chains,
            "seed {seed}"
        );
    }
    println!("{triggered} data-triggered jobs ({all} joining all), {merges} merges");
    assert!(triggered > 0 && all > 0, "the seeds exercise no trigger");
}
