//! `rtpipe run` names another process's real-time thread that ran on its
//! CPUs: this test (a process of its own) takes CPU 0 from the small
//! pipeline with a SCHED_FIFO spin for 20 ms, and the run's report, JSON
//! and the verdict's causes name the spinning thread. Needs root; without
//! it the test prints why and passes.

mod common;

use common::{json_of, scratch, small_pipeline};
use rtpipe_runtime::sys;
use std::sync::mpsc;

/// The hog's thread name (the kernel keeps 15 characters).
const HOG: &str = "rtpipe-fifo-hog";

#[test]
fn a_foreign_fifo_thread_on_the_run_s_cpu_is_named_in_the_verdict() {
    if !sys::is_root() {
        eprintln!("SKIPPED the foreign-thread test: SCHED_FIFO needs root");
        return;
    }
    let dir = scratch("foreign-rt");
    let spec = dir.join("spec.toml");
    if let Err(e) = std::fs::write(&spec, small_pipeline("rm", 0, "")) {
        panic!("cannot write {}: {e}", spec.display());
    }
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(["run", &spec.to_string_lossy(), "--duration", "1s", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn();
    let Ok(child) = child else {
        panic!("cannot start rtpipe");
    };
    // The run's epoch comes a few ms after the start; hog from 400 ms on.
    std::thread::sleep(std::time::Duration::from_millis(400));
    // The hog stays alive (asleep, still SCHED_FIFO) until the run has
    // ended: the run scans the threads on its CPUs when it ends.
    let (done, wait) = mpsc::channel::<()>();
    let (ran, got) = mpsc::channel::<i64>();
    let hog = std::thread::Builder::new().name(HOG.into()).spawn(move || {
        let ok = sys::pin_to(0).and_then(|()| sys::set_fifo(99));
        assert!(ok.is_ok(), "cannot become a FIFO hog: {ok:?}");
        let (h0, c0) = (sys::now(), sys::thread_cpu_time());
        while sys::now() < h0 + 20_000_000 {
            std::hint::spin_loop();
        }
        let _ = ran.send(sys::thread_cpu_time() - c0);
        let _ = wait.recv();
    });
    let Ok(hog) = hog else {
        panic!("cannot start the hog thread");
    };
    let cpu_time = got.recv().unwrap_or(0);
    let out = child.wait_with_output();
    let _ = done.send(());
    let _ = hog.join();
    let Ok(o) = out else {
        panic!("rtpipe did not finish");
    };
    if cpu_time < 1_000_000 {
        eprintln!("SKIPPED: the hog got {cpu_time} ns of CPU (< 1 ms): nothing to name");
        return;
    }
    let v = json_of(&o);
    let named = v["run"]["foreign_rt_threads"].to_string();
    assert!(
        named.contains(HOG),
        "not in run.foreign_rt_threads: {named}"
    );
    assert!(named.contains("SCHED_FIFO priority 99"), "{named}");
    let text = v["run"]["sound_bound_violations"].to_string();
    // The stall delays the pipeline's jobs far past their bounds; those
    // windows' foreign time names the hog.
    assert!(
        text.contains(&format!(
            "a foreign real-time thread may run on CPU 0 (within the foreign time): {HOG}"
        )),
        "the verdict does not name the hog: {text}"
    );
}
