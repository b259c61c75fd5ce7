//! Ctrl-C ends a run of work-queue threads and data-triggered tasks early
//! too: a data-triggered task whose trigger has stopped does not wait for
//! a wake-up until the run's end. A test binary of its own: the stop flag
//! is process-wide.

use rtpipe_body::Body;
use rtpipe_model::Spec;
use rtpipe_runtime::{run, Policy, RunConfig, Spin};

const SPEC: &str = r#"
[system]
name = "pair"
time_unit = "ms"
priorities = "explicit"

[channels.shm]
bandwidth = 1000
overhead = 0

[threads.wq]
priority = 2
cpu = 0

[tasks.src]
exec = 0.1
period = 2
priority = 1
cpu = 0
output = { channel = "shm", size = 0 }

[tasks.dst]
activation = "data"
reads = ["src"]
exec = 0.1
thread = "wq"
"#;

#[test]
fn ctrl_c_ends_a_run_whose_consumers_wait_for_data() {
    let spec = Spec::parse("pair.toml", SPEC).unwrap_or_else(|e| panic!("{e}"));
    let spin = Spin::calibrate();
    rtpipe_runtime::sys::catch_stop_signals();
    let bodies: Vec<Box<dyn Body<u64>>> = (0..2)
        .map(|_| Box::new(rtpipe_runtime::synthetic(spin, 100_000)) as Box<dyn Body<u64>>)
        .collect();
    let cfg = RunConfig {
        duration: 20_000_000_000,
        policy: Policy::Other,
        load: 0,
    };
    let raiser = std::thread::spawn(|| {
        std::thread::sleep(std::time::Duration::from_millis(400));
        // SAFETY: raise only delivers a signal to this thread; the handler
        // catch_stop_signals installed stores to atomics.
        unsafe { libc::raise(libc::SIGINT) };
    });
    let r = run(&spec, &cfg, bodies, None);
    let _ = raiser.join();
    let r = r.unwrap_or_else(|e| panic!("{e}"));
    assert!(r.interrupted);
    let span = r.sim.horizon;
    assert!(span < 10_000_000_000, "span {span}");
    // Every thread noticed the stop: the run did not wait for its end.
    assert!(
        r.elapsed < span + 1_000_000_000,
        "run returned {} ns after the epoch, the stop at {span}",
        r.elapsed
    );
    assert!(r.sim.tasks[1].completed > 0, "dst never ran");
}
