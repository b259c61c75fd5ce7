//! The periodic path of a flight on real threads allocates nothing: every
//! job's sense, body and actuate, as `rtpipe_runtime`'s threads call them,
//! on the parts `fly_real` runs (`rtpipe_fly::real_time_parts`), past
//! 20,000 gyro jobs. A vector that doubles inside a job (the assessor's
//! kept points did, at 4,096, 8,192 and 16,384 gyro jobs) copies itself
//! there: a job of hundreds of µs against a median of about one.
//!
//! A counting global allocator, so this binary holds only this test: the
//! count is of the calling thread's allocations, and the jobs run on it.

use rtpipe_body::{Job, Stamp, Stamped};
use rtpipe_fly::{real_time_parts, setup, Request};
use rtpipe_model::{Nanos, Spec};
use rtpipe_testkit::alloc::{allocations, Counting};
use std::path::Path;

#[global_allocator]
static GLOBAL: Counting = Counting;

const MS: Nanos = 1_000_000;

/// 20.5 s of Cleanflight: 20,500 gyro jobs, past the 16,384th.
const DURATION: Nanos = 20_500 * MS;

#[test]
fn a_flights_jobs_allocate_nothing_past_20000_gyro_jobs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
    let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let request = Request {
        spec_path: &path,
        vehicle: "racer5",
        mission: "steps",
        horizon: Some(DURATION),
        seed: 1,
    };
    let s = setup(&spec, &request).unwrap_or_else(|e| panic!("{e}"));
    let (mut bodies, mut world) =
        real_time_parts(&spec, &s, DURATION).unwrap_or_else(|e| panic!("{e}"));
    // Every job's release in time order (ties: task order), and per task
    // its inputs' buffer and the latest value it published: what the
    // runtime's threads hold before their first job.
    let mut releases: Vec<(Nanos, usize, u64)> = Vec::new();
    for (i, t) in spec.tasks.iter().enumerate() {
        let period = t.fixed_period().unwrap_or_else(|| panic!("fixed period"));
        let mut k = 0;
        while t.offset.unwrap_or(0) + k as Nanos * period < DURATION {
            releases.push((t.offset.unwrap_or(0) + k as Nanos * period, i, k));
            k += 1;
        }
    }
    releases.sort_unstable();
    let mut latest: Vec<Option<Stamped<_>>> = vec![None; spec.tasks.len()];
    let mut inputs: Vec<_> = spec
        .tasks
        .iter()
        .map(|t| Vec::with_capacity(t.reads.len()))
        .collect();
    let gyro = spec.tasks.iter().position(|t| t.name == "gyro");
    // The counter counts (a test that cannot fail proves nothing).
    let probe = allocations();
    drop(std::hint::black_box(vec![0u8; 16]));
    assert!(allocations() > probe, "the counting allocator is installed");
    let before = allocations();
    let mut gyro_jobs = 0;
    let mut first = None;
    let mut now = 0;
    for &(release, task, index) in &releases {
        // One job as `rtpipe_runtime`'s `job` runs it: the registers read
        // into the kept buffer, the world sensed, the body, the world
        // actuated, the output published.
        let buf: &mut Vec<_> = &mut inputs[task];
        buf.clear();
        buf.extend(spec.tasks[task].reads.iter().map(|&p| latest[p]));
        // One CPU, jobs one after the other: the world's instants never
        // go back.
        let read = now.max(release) + 1_000;
        let device = rtpipe_body::Environment::sense(&mut world, task, read);
        let job = Job {
            task,
            index,
            release,
            read,
        };
        let value = bodies[task].run(&job, buf, device);
        let publish = read + 1_000;
        now = publish;
        rtpipe_body::Environment::actuate(&mut world, task, publish, &value);
        latest[task] = Some(Stamped {
            value,
            stamp: Stamp {
                task,
                job: index,
                read,
                publish,
            },
        });
        gyro_jobs += u64::from(Some(task) == gyro);
        if first.is_none() && allocations() > before {
            first = Some((spec.tasks[task].name.clone(), index));
        }
    }
    let n = allocations() - before;
    assert!(gyro_jobs > 20_000, "{gyro_jobs} gyro jobs");
    assert_eq!(
        n, 0,
        "the flight's periodic path allocated {n} time(s), first in job {first:?}"
    );
}
