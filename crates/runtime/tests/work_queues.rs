//! Work-queue threads and data-triggered tasks on real threads, judged on
//! the job log alone (whatever the machine's load did to the schedule):
//! a thread runs its jobs one at a time in release order; a publication
//! releases (or is merged into a queued job of) every task it triggers, on
//! the thread it wakes; join = "all" waits for every trigger; a release
//! while a job is queued and not started is merged into it, and every
//! release is either a job or a merge.

use rtpipe_joblog::JobRecord;
use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::{run_synthetic, Policy, RunConfig, RunResult, Spin};

const MS: Nanos = 1_000_000;
const DURATION: Nanos = 100 * MS;

/// imu (thread-less, periodic) wakes g on thread wq and f on a thread of
/// its own; g's publications release h on wq itself; slow and fast are
/// timers on wq (slow's 3 ms jobs hold fast's releases back: merges); fuse
/// joins all of g and slow, f any of imu and slow.
const SPEC: &str = r#"
[system]
name = "queues"
time_unit = "ms"
priorities = "explicit"

[channels.shm]
bandwidth = 1000
overhead = 0

[threads.wq]
priority = 2
cpu = 0

[tasks.imu]
exec = 0.05
period = 1
priority = 1
cpu = 0
output = { channel = "shm", size = 0 }

[tasks.g]
activation = "data"
reads = ["imu"]
exec = 0.05
thread = "wq"
output = { channel = "shm", size = 0 }

[tasks.h]
activation = "data"
reads = ["g"]
exec = 0.05
thread = "wq"
output = { channel = "shm", size = 0 }

[tasks.slow]
exec = 3
period = 10
thread = "wq"
output = { channel = "shm", size = 0 }

[tasks.fast]
exec = 0.05
period = 1
thread = "wq"

[tasks.f]
activation = "data"
reads = ["imu", "slow"]
exec = 0.05
priority = 3
cpu = 0

[tasks.fuse]
activation = "data"
reads = ["g", "slow"]
join = "all"
exec = 0.05
priority = 4
cpu = 0

[[chain]]
path = ["imu", "g", "h"]
"#;

fn policies() -> Vec<Policy> {
    let mut p = vec![Policy::Other];
    if rtpipe_runtime::sys::is_root() {
        p.push(Policy::Fifo);
    } else {
        eprintln!("SKIPPED the SCHED_FIFO run: not root");
    }
    p
}

/// The runs of the spec, one per policy this process may use; made once
/// for all the tests here (each judges another property of the same log).
fn runs() -> &'static [(Policy, Spec, RunResult)] {
    static RUNS: std::sync::OnceLock<Vec<(Policy, Spec, RunResult)>> = std::sync::OnceLock::new();
    RUNS.get_or_init(make_runs)
}

fn make_runs() -> Vec<(Policy, Spec, RunResult)> {
    let spec = Spec::parse("queues.toml", SPEC).unwrap_or_else(|e| panic!("{e}"));
    let spin = Spin::calibrate();
    policies()
        .into_iter()
        .map(|policy| {
            let cfg = RunConfig {
                duration: DURATION,
                policy,
                load: 0,
            };
            let r = run_synthetic(&spec, &cfg, spin).unwrap_or_else(|e| panic!("{policy:?}: {e}"));
            print_summary(&spec, policy, &r);
            (policy, spec.clone(), r)
        })
        .collect()
}

/// Per task, what the run did (`--nocapture` shows it; docs/runtime.md
/// quotes it).
fn print_summary(spec: &Spec, policy: Policy, r: &RunResult) {
    println!("{} for {} ms:", policy.class(), DURATION / MS);
    for (i, t) in spec.tasks.iter().enumerate() {
        let max = r.sim.tasks[i].max_response.unwrap_or(0);
        println!(
            "  {:<5} {:>3} jobs {:>3} merged  max R {:>7.3} ms",
            t.name,
            r.sim.tasks[i].completed,
            r.sim.tasks[i].merged,
            max as f64 / MS as f64
        );
    }
}

fn task(spec: &Spec, name: &str) -> usize {
    spec.task_index(name)
        .unwrap_or_else(|| panic!("no task {name}"))
}

/// The jobs of task `name`, in index order.
fn jobs_of<'r>(spec: &Spec, r: &'r RunResult, name: &str) -> Vec<&'r JobRecord> {
    let i = task(spec, name);
    let mut v: Vec<&JobRecord> = r.sim.jobs.iter().filter(|j| j.task == i).collect();
    v.sort_by_key(|j| j.index);
    v
}

/// The publish instants of `name`'s jobs before the run's end: the
/// instants its publications release the tasks it triggers.
fn publications(spec: &Spec, r: &RunResult, name: &str) -> Vec<Nanos> {
    jobs_of(spec, r, name)
        .iter()
        .map(|j| j.finish)
        .filter(|&f| f < DURATION)
        .collect()
}

/// Jobs plus merges of `name`: its releases.
fn releases(spec: &Spec, r: &RunResult, name: &str) -> u64 {
    let i = task(spec, name);
    r.sim.tasks[i].completed + r.sim.tasks[i].merged
}

#[test]
fn a_work_queue_runs_one_job_at_a_time_in_release_order() {
    for (policy, spec, r) in runs() {
        let (policy, spec, r) = (*policy, spec, r);
        let on_wq: Vec<usize> = ["g", "h", "slow", "fast"]
            .iter()
            .map(|n| task(spec, n))
            .collect();
        let mut jobs: Vec<&JobRecord> = r
            .sim
            .jobs
            .iter()
            .filter(|j| on_wq.contains(&j.task))
            .collect();
        jobs.sort_by_key(|j| j.read);
        // At least a job of each (a loaded machine merges many releases).
        assert!(jobs.len() >= 4, "{policy:?}: {} jobs on wq", jobs.len());
        for w in jobs.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                a.finish <= b.read,
                "{policy:?}: overlapping jobs {a:?} {b:?}"
            );
        }
        // Release order; same-instant releases in declaration order. Of the
        // releases wq makes itself (its timers, g's publications): imu's
        // reach g's slot a few µs after their publish instant, which wq may
        // pass a later timer release in (docs/runtime.md).
        let g = task(spec, "g");
        let own: Vec<&&JobRecord> = jobs.iter().filter(|j| j.task != g).collect();
        for w in own.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                (a.release, a.task) < (b.release, b.task),
                "{policy:?}: out of release order: {a:?} then {b:?}"
            );
        }
        assert!(r.sim.jobs.iter().all(|j| j.release <= j.read));
    }
}

#[test]
fn every_timer_release_is_a_job_or_a_merge() {
    for (policy, spec, r) in runs() {
        let (policy, spec, r) = (*policy, spec, r);
        assert_eq!(releases(spec, r, "fast"), 100, "{policy:?}");
        assert_eq!(releases(spec, r, "slow"), 10, "{policy:?}");
        // A thread-less periodic task runs as ever: no merging.
        assert_eq!(r.sim.tasks[task(spec, "imu")].completed, 100, "{policy:?}");
        assert_eq!(r.sim.tasks[task(spec, "imu")].merged, 0, "{policy:?}");
        // Each of slow's 3 ms jobs spans at least two of fast's releases:
        // the second is merged into the first, still queued behind it.
        let slow = r.sim.tasks[task(spec, "slow")].completed;
        assert!(
            r.sim.tasks[task(spec, "fast")].merged >= slow,
            "{policy:?}: {} merges of fast for {slow} jobs of slow",
            r.sim.tasks[task(spec, "fast")].merged
        );
    }
}

#[test]
fn a_publication_releases_its_consumers_on_the_threads_it_wakes() {
    for (policy, spec, r) in runs() {
        let (policy, spec, r) = (*policy, spec, r);
        for (consumer, triggers) in [
            ("g", vec!["imu"]),
            ("h", vec!["g"]),
            ("f", vec!["imu", "slow"]),
        ] {
            let mut at: Vec<Nanos> = triggers
                .iter()
                .flat_map(|t| publications(spec, r, t))
                .collect();
            at.sort_unstable();
            // join = "any": every publication is a release.
            assert_eq!(
                releases(spec, r, consumer),
                at.len() as u64,
                "{policy:?}: {consumer}"
            );
            // Released at a trigger's publish instant, which the job log
            // names (as the simulator's does).
            for j in jobs_of(spec, r, consumer) {
                assert!(
                    at.binary_search(&j.release).is_ok(),
                    "{policy:?}: {consumer} released at {} by no publication",
                    j.release
                );
                let tr = j
                    .trigger
                    .unwrap_or_else(|| panic!("{policy:?}: {j:?} has no trigger"));
                let by = r
                    .sim
                    .jobs
                    .iter()
                    .find(|p| p.task == tr.task && p.index == tr.job);
                assert_eq!(by.map(|p| p.finish), Some(j.release), "{policy:?}: {j:?}");
                assert!(triggers.contains(&spec.tasks[tr.task].name.as_str()));
            }
        }
        // The chain's samples flow through the triggered tasks, measured
        // as the simulator's provenance measures any log.
        assert!(r.sim.chains[0].reaction.hist.count() > 0, "{policy:?}");
        assert_eq!(
            rtpipe_joblog::chains_from_jobs(spec, &r.sim.jobs),
            r.sim.chains,
            "{policy:?}"
        );
    }
}

#[test]
fn join_all_releases_once_every_trigger_has_published() {
    for (policy, spec, r) in runs() {
        let (policy, spec, r) = (*policy, spec, r);
        // g and slow publish from one thread (wq): their publications are
        // in one order, which the join follows.
        let mut published: Vec<(Nanos, usize)> = ["g", "slow"]
            .iter()
            .enumerate()
            .flat_map(|(b, n)| publications(spec, r, n).into_iter().map(move |f| (f, b)))
            .collect();
        published.sort_unstable();
        let mut seen = [false; 2];
        let mut expected = Vec::new();
        for (at, b) in published {
            seen[b] = true;
            if seen == [true; 2] {
                expected.push(at);
                seen = [false; 2];
            }
        }
        assert!(!expected.is_empty(), "{policy:?}");
        assert_eq!(
            releases(spec, r, "fuse"),
            expected.len() as u64,
            "{policy:?}"
        );
        for j in jobs_of(spec, r, "fuse") {
            assert!(
                expected.binary_search(&j.release).is_ok(),
                "{policy:?}: fuse released at {} before both triggers published",
                j.release
            );
        }
    }
}

/// The policies that cannot run a work queue are refused before any thread
/// starts, saying why and what to use; so is LET, whose publications are
/// not at the completions that release data-triggered tasks.
#[test]
fn edf_policies_and_let_are_refused_with_the_fix() {
    let spec = Spec::parse("queues.toml", SPEC).unwrap_or_else(|e| panic!("{e}"));
    for policy in [Policy::Deadline, Policy::EdfFifo] {
        let cfg = RunConfig {
            duration: DURATION,
            policy,
            load: 0,
        };
        let e = rtpipe_runtime::check(&spec, &cfg).err();
        let d = e
            .map(|e| e.diagnostic)
            .unwrap_or_else(|| panic!("{policy:?} admitted"));
        assert!(
            d.message.contains(&format!(
                "--policy {} cannot run work-queue threads",
                policy.name()
            )),
            "{}",
            d.message
        );
        assert!(
            d.help
                .as_deref()
                .is_some_and(|h| h.contains("--policy fifo")),
            "{d:?}"
        );
    }
    let text = SPEC.replace(
        "priorities = \"explicit\"",
        "priorities = \"explicit\"\ncommunication = \"let\"",
    );
    let text = text
        .replace("activation = \"data\"", "period = 1")
        .replace("join = \"all\"\n", "");
    let spec = Spec::parse("let.toml", &text).unwrap_or_else(|e| panic!("{e}"));
    let cfg = RunConfig {
        duration: DURATION,
        policy: Policy::Other,
        load: 0,
    };
    let e = rtpipe_runtime::check(&spec, &cfg).err();
    let d = e
        .map(|e| e.diagnostic)
        .unwrap_or_else(|| panic!("LET admitted"));
    assert!(
        d.message.contains("communication = \"let\""),
        "{}",
        d.message
    );
}
