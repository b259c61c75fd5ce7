//! The executor as a library: bodies see stamps consistent with the model,
//! the job log measures the chain, and no thread (task or load hog)
//! outlives `run`.

use rtpipe_body::{Body, Job, Stamped};
use rtpipe_model::Spec;
use rtpipe_runtime::{run, Policy, RunConfig, Spin};
use std::sync::atomic::{AtomicU64, Ordering};

const SPEC: &str = r#"
[system]
name = "pair"
time_unit = "ms"
scheduler = "rm"

[channels.shm]
bandwidth = 1000
overhead = 0

[tasks.src]
exec = 0.1
period = 1
output = { channel = "shm", size = 0 }

[tasks.dst]
exec = 0.2
reads = ["src"]
period = 3
output = { channel = "shm", size = 0 }

[[chain]]
path = ["src", "dst"]
"#;

fn threads_of_this_process() -> usize {
    std::fs::read_dir("/proc/self/task").map_or(0, |d| d.count())
}

fn policies() -> Vec<Policy> {
    let mut p = vec![Policy::Other];
    if rtpipe_runtime::sys::is_root() {
        p.push(Policy::Fifo);
    } else {
        eprintln!("SKIPPED the SCHED_FIFO run: not root");
    }
    p
}

/// The tests count this process's threads: one at a time.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn stamps_follow_the_model_and_every_thread_is_joined() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Ok(spec) = Spec::parse("pair.toml", SPEC) else {
        panic!("the spec parses");
    };
    let spin = Spin::calibrate();
    for policy in policies() {
        let before = threads_of_this_process();
        let bad = AtomicU64::new(0);
        // The producer job each consumer job read, as the body saw it: the
        // oracle for the measurement, whatever the machine's load did to
        // the schedule.
        let seen = std::sync::Mutex::new(Vec::new());
        let src = rtpipe_runtime::synthetic(spin, 100_000);
        let (bad_ref, seen_ref) = (&bad, &seen);
        let mut last = None;
        let dst = move |job: &Job, inputs: &[Option<Stamped<u64>>], _: Option<u64>| {
            spin.burn(200_000);
            if let Some(Some(v)) = inputs.first() {
                // Published before this job read it; never an older value
                // than the previous job saw; value = the producer's job.
                let ok = v.stamp.publish <= job.read
                    && v.stamp.read <= v.stamp.publish
                    && v.value == v.stamp.job
                    && last.is_none_or(|l| l <= v.stamp.job);
                if !ok {
                    bad_ref.fetch_add(1, Ordering::Relaxed);
                }
                last = Some(v.stamp.job);
                if let Ok(mut s) = seen_ref.lock() {
                    s.push((job.read, v.stamp.job));
                }
            }
            job.index
        };
        let bodies: Vec<Box<dyn Body<u64> + '_>> = vec![Box::new(src), Box::new(dst)];
        let cfg = RunConfig {
            duration: 300_000_000,
            policy,
            // Two hogs: they too must be gone when run returns.
            load: 2,
        };
        let r = run(&spec, &cfg, bodies, None);
        let Ok(r) = r else {
            panic!("{policy:?}: {:?}", r.err());
        };
        assert_eq!(
            threads_of_this_process(),
            before,
            "{policy:?}: a thread outlived run"
        );
        assert_eq!(bad.load(Ordering::Relaxed), 0, "{policy:?}");
        assert_eq!(r.sim.tasks[0].completed, 300);
        assert_eq!(r.sim.tasks[1].completed, 100);
        let ch = &r.sim.chains[0];
        let seen = seen.into_inner().unwrap_or_else(|e| e.into_inner());
        // The trace draws the reads up to the run's end (a loaded machine
        // may delay the last ones past it).
        let reads = seen.iter().filter(|&&(t, _)| t <= r.sim.horizon).count();
        let mut seen: Vec<u64> = seen.into_iter().map(|(_, s)| s).collect();
        seen.dedup();
        // Every sample the consumer read reached the tail (it is the tail):
        // as many reaction samples as distinct samples read.
        assert!(reads > 0, "{policy:?}: the consumer never read a sample");
        assert_eq!(ch.reaction.hist.count() as usize, seen.len(), "{policy:?}");
        // A job log in publish order, each task's jobs in index order.
        assert!(r.sim.jobs.windows(2).all(|w| w[0].finish <= w[1].finish));
        assert!(ch.reaction.hist.min().is_some_and(|x| x > 0));
        // Replayed as the run went or measured from the finished log: one
        // measurement.
        assert_eq!(
            rtpipe_joblog::chains_from_jobs(&spec, &r.sim.jobs),
            r.sim.chains,
            "{policy:?}"
        );
        // The simulator's trace writer draws the run: one span per job,
        // data-flow arrows along the chain.
        let opts = rtpipe_joblog::trace::TraceOptions {
            spans: true,
            ..Default::default()
        };
        let t = rtpipe_joblog::trace::chrome_trace_with(&spec, &r.sim, opts);
        assert_eq!(t.slices, r.sim.jobs.len(), "{policy:?}");
        // One arrow per consumer job that read a sample.
        assert_eq!(t.flows, reads, "{policy:?}");
    }
}

/// One SCHED_DEADLINE task per CPU reserving 0.944 of it (9.35 ms of
/// runtime per 9.9 ms, `config::reservation`): within rtpipe's check (0.95
/// per CPU), beyond what a kernel with fair servers admits (0.95 minus
/// their 0.05 per CPU), so the kernel refuses the reservations (after the
/// EBUSY retries) once the load has started: the hogs must be gone when
/// `run` returns the error.
#[test]
fn a_refused_run_leaves_no_hog_behind() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    if !rtpipe_runtime::sys::is_root() {
        eprintln!("SKIPPED a_refused_run_leaves_no_hog_behind: SCHED_DEADLINE needs root");
        return;
    }
    let cpus = rtpipe_runtime::sys::online_cpus();
    let mut text = String::from(
        "[system]\nname = \"full\"\ntime_unit = \"ms\"\nscheduler = \"edf\"\nschedulability = \"edf\"\n\
         [channels.shm]\nbandwidth = 1000\noverhead = 0\n",
    );
    for i in 0..cpus {
        text.push_str(&format!(
            "[tasks.t{i}]\nexec = 9.3\nperiod = 10\noutput = {{ channel = \"shm\", size = 0 }}\n"
        ));
    }
    let spec = Spec::parse("full.toml", &text).unwrap_or_else(|e| panic!("{e}"));
    let spin = Spin::calibrate();
    let bodies: Vec<Box<dyn Body<u64>>> = (0..cpus)
        .map(|_| Box::new(rtpipe_runtime::synthetic(spin, 9_300_000)) as Box<dyn Body<u64>>)
        .collect();
    let cfg = RunConfig {
        duration: 200_000_000,
        policy: Policy::Deadline,
        load: 2,
    };
    let before = threads_of_this_process();
    let r = run(&spec, &cfg, bodies, None);
    assert_eq!(threads_of_this_process(), before, "a thread outlived run");
    match r {
        Err(e) => assert!(e.diagnostic.message.contains("refused"), "{e}"),
        // A kernel without fair servers admits it: then the run completed,
        // and the check above still held.
        Ok(_) => {
            eprintln!("note: the kernel admitted {cpus} x 0.944: the error path was not taken")
        }
    }
}

/// A task's `offset` delays its releases as in the simulator and the
/// analysis: the k-th job is released at offset + k·T after the epoch.
#[test]
fn offsets_shift_the_releases() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let text = SPEC.replace("period = 3\n", "period = 3\noffset = 2.5\n");
    let Ok(spec) = Spec::parse("pair.toml", &text) else {
        panic!("the spec parses");
    };
    let spin = Spin::calibrate();
    let bodies: Vec<Box<dyn Body<u64>>> = vec![
        Box::new(rtpipe_runtime::synthetic(spin, 100_000)),
        Box::new(rtpipe_runtime::synthetic(spin, 200_000)),
    ];
    let cfg = RunConfig {
        duration: 30_000_000,
        policy: Policy::Other,
        load: 0,
    };
    let r = run(&spec, &cfg, bodies, None);
    let Ok(r) = r else {
        panic!("{:?}", r.err());
    };
    assert_eq!(r.sim.offsets, vec![0, 2_500_000]);
    let releases: Vec<i64> = r
        .sim
        .jobs
        .iter()
        .filter(|j| j.task == 1)
        .map(|j| j.release)
        .collect();
    let expected: Vec<i64> = (0..10).map(|k| 2_500_000 + k * 3_000_000).collect();
    assert_eq!(releases, expected);
    assert!(r.sim.jobs.iter().all(|j| j.release <= j.read));
}

/// Each task's OS thread is named after its task, so a kernel trace
/// (`sched_switch` names `comm`), `ps -L` and `top -H` tell them apart.
#[test]
fn each_task_thread_is_named_after_its_task() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Ok(spec) = Spec::parse("pair.toml", SPEC) else {
        panic!("the spec parses");
    };
    let names = std::sync::Mutex::new(Vec::new());
    let bodies: Vec<Box<dyn Body<u64> + '_>> = (0..2)
        .map(|_| {
            let names = &names;
            Box::new(move |_: &Job, _: &[Option<Stamped<u64>>], _: Option<u64>| {
                // What the kernel shows, not only what std recorded.
                let comm = std::fs::read_to_string("/proc/thread-self/comm").unwrap_or_default();
                if let Ok(mut v) = names.lock() {
                    v.push(comm.trim().to_string());
                }
                0u64
            }) as Box<dyn Body<u64> + '_>
        })
        .collect();
    let cfg = RunConfig {
        duration: 3_000_000,
        policy: Policy::Other,
        load: 0,
    };
    let r = run(&spec, &cfg, bodies, None);
    assert!(r.is_ok(), "{:?}", r.err());
    let mut seen = names.into_inner().unwrap_or_else(|e| e.into_inner());
    seen.sort();
    seen.dedup();
    assert_eq!(seen, vec!["rt:dst".to_string(), "rt:src".to_string()]);
}
