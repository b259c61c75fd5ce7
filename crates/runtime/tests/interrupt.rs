//! Ctrl-C ends a run early, and the report covers what ran: its span ends
//! at the stop, and no job is released after it. A test binary of its own:
//! the stop flag is process-wide.

use rtpipe_body::Body;
use rtpipe_model::Spec;
use rtpipe_runtime::{run, Policy, RunConfig, Spin};

const SPEC: &str = r#"
[system]
name = "one"
time_unit = "ms"
scheduler = "rm"

[channels.shm]
bandwidth = 1000
overhead = 0

[tasks.a]
exec = 0.1
period = 2
output = { channel = "shm", size = 0 }
"#;

#[test]
fn ctrl_c_ends_the_span_at_the_stop() {
    let Ok(spec) = Spec::parse("one.toml", SPEC) else {
        panic!("the spec parses");
    };
    let spin = Spin::calibrate();
    rtpipe_runtime::sys::catch_stop_signals();
    let bodies: Vec<Box<dyn Body<u64>>> = vec![Box::new(rtpipe_runtime::synthetic(spin, 100_000))];
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
    let Ok(r) = r else {
        panic!("{:?}", r.err());
    };
    assert!(r.interrupted);
    let span = r.sim.horizon;
    // The stop came about 400 ms after the run was set up (the epoch is
    // 10 ms after that); a loaded machine may delay it, never advance it.
    assert!((300_000_000..10_000_000_000).contains(&span), "span {span}");
    assert!(r.sim.jobs.iter().all(|j| j.release < span));
    let released = r.sim.tasks[0].released as i64;
    assert!(
        (span / 2_000_000 - released).abs() <= 1,
        "{released} jobs in {span} ns"
    );
    assert!(
        r.elapsed < span + 1_000_000_000,
        "run returned {} ns after the epoch",
        r.elapsed
    );
}
