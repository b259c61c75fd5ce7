//! The real-time path of work-queue threads and data-triggered tasks
//! allocates nothing: from a thread's first job to its last, through
//! timers, queue slots, merges, publications that wake other threads and
//! join waits, the thread's allocation count does not move
//! (`examples/work-queues.toml`).
//!
//! A counting global allocator, so this binary holds only this test: the
//! count is per thread, and each body reads its own thread's.

use rtpipe_body::{Body, Job, Stamped};
use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::{run, Policy, RunConfig, Spin};
use rtpipe_testkit::alloc::{allocations, Counting};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

#[global_allocator]
static GLOBAL: Counting = Counting;

const MS: Nanos = 1_000_000;

/// Per task: its thread's allocation count at its first and at its last
/// job, and its jobs.
struct Seen {
    first: AtomicU64,
    last: AtomicU64,
    jobs: AtomicU64,
}

#[test]
fn work_queue_threads_allocate_nothing_between_jobs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/work-queues.toml");
    let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let spin = Spin::calibrate();
    let mut policies = vec![Policy::Other];
    if rtpipe_runtime::sys::is_root() {
        policies.push(Policy::Fifo);
    } else {
        eprintln!("SKIPPED the SCHED_FIFO run: not root");
    }
    for policy in policies {
        let seen: Vec<Seen> = spec
            .tasks
            .iter()
            .map(|_| Seen {
                first: AtomicU64::new(u64::MAX),
                last: AtomicU64::new(0),
                jobs: AtomicU64::new(0),
            })
            .collect();
        let bodies: Vec<Box<dyn Body<u64> + '_>> = spec
            .tasks
            .iter()
            .zip(&seen)
            .map(|(t, s)| {
                let demand = t.exec_min;
                let body = move |job: &Job, _: &[Option<Stamped<u64>>], _: Option<u64>| {
                    let n = allocations();
                    let _ =
                        s.first
                            .compare_exchange(u64::MAX, n, Ordering::SeqCst, Ordering::SeqCst);
                    s.last.store(n, Ordering::SeqCst);
                    s.jobs.fetch_add(1, Ordering::SeqCst);
                    spin.burn(demand);
                    job.index
                };
                Box::new(body) as Box<dyn Body<u64> + '_>
            })
            .collect();
        let cfg = RunConfig {
            duration: 200 * MS,
            policy,
            load: 0,
        };
        let r = run(&spec, &cfg, bodies, None);
        assert!(r.is_ok(), "{policy:?}: {:?}", r.err());
        for (t, s) in spec.tasks.iter().zip(&seen) {
            let jobs = s.jobs.load(Ordering::SeqCst);
            assert!(jobs >= 2, "{policy:?}: task {} ran {jobs} job(s)", t.name);
            let (first, last) = (
                s.first.load(Ordering::SeqCst),
                s.last.load(Ordering::SeqCst),
            );
            assert_eq!(
                last - first,
                0,
                "{policy:?}: task {}'s thread allocated between its jobs",
                t.name
            );
        }
    }
}
