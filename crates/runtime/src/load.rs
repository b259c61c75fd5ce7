//! Background load for a run: CPU hogs under SCHED_OTHER, as the paper kept
//! the machine busy decompressing the Linux sources during its Linux runs.
//! Each hog streams through a buffer of its own (like a decompressor, it
//! pollutes the caches, not only the pipeline), never sleeps, and stops
//! within about a millisecond of being asked.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// Bytes each hog streams through: larger than a typical L2, so the tasks'
/// caches are disturbed as by a real workload.
const BUFFER: usize = 4 << 20;

/// Running hogs; dropping it stops and joins them (nothing outlives it,
/// whatever path the caller leaves by: the end of a run, an error, a panic).
pub struct Load {
    stop: Arc<AtomicBool>,
    hogs: Vec<JoinHandle<()>>,
}

impl Load {
    /// Starts `n` hogs, named `rtpipe-load-<i>`, under SCHED_OTHER (each
    /// sets it, whatever class `rtpipe` was started in) and on any CPU. On an error the ones started are
    /// stopped again.
    pub fn start(n: usize) -> io::Result<Load> {
        let mut load = Load {
            stop: Arc::new(AtomicBool::new(false)),
            hogs: Vec::with_capacity(n),
        };
        for i in 0..n {
            let stop = Arc::clone(&load.stop);
            let hog = std::thread::Builder::new()
                .name(format!("rtpipe-load-{i}"))
                .spawn(move || hog(&stop))?;
            load.hogs.push(hog);
        }
        Ok(load)
    }

    /// How many hogs run.
    pub fn len(&self) -> usize {
        self.hogs.len()
    }

    /// Whether no hog runs.
    pub fn is_empty(&self) -> bool {
        self.hogs.is_empty()
    }

    /// Stops the hogs and waits for them to end.
    pub fn stop(self) {
        drop(self);
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        for h in self.hogs.drain(..) {
            // A hog cannot panic (no indexing out of bounds, no allocation
            // after start); if it did, there is nothing left to stop.
            let _ = h.join();
        }
    }
}

/// One hog: passes over its buffer (a few hundred microseconds each),
/// checking the stop flag between passes.
fn hog(stop: &AtomicBool) {
    // Threads inherit their creator's class: under `chrt -f` a hog would
    // otherwise compete with the tasks as a real-time thread.
    let _ = crate::sys::set_other(crate::sys::gettid());
    let mut buf = vec![0u64; BUFFER / 8];
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    while !stop.load(Ordering::Relaxed) {
        for w in buf.iter_mut() {
            // xorshift: data-dependent work the compiler cannot fold away.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            *w = w.wrapping_add(x);
        }
        std::hint::black_box(&buf);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Hogs alive in this process (by thread name: other tests of this
    /// binary start threads in parallel, so a plain thread count would race).
    fn hogs_running() -> usize {
        let Ok(d) = std::fs::read_dir("/proc/self/task") else {
            return 0;
        };
        d.filter_map(Result::ok)
            .filter_map(|e| std::fs::read_to_string(e.path().join("comm")).ok())
            .filter(|c| c.starts_with("rtpipe-load-"))
            .count()
    }

    /// The tests count hogs by name: one test at a time.
    static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

    /// The scheduling class of each hog.
    fn hog_policies() -> Vec<i32> {
        let Ok(d) = std::fs::read_dir("/proc/self/task") else {
            return vec![];
        };
        d.filter_map(Result::ok)
            .filter(|e| {
                std::fs::read_to_string(e.path().join("comm"))
                    .is_ok_and(|c| c.starts_with("rtpipe-load-"))
            })
            .filter_map(|e| e.file_name().to_str().and_then(|t| t.parse::<i32>().ok()))
            // SAFETY: sched_getscheduler takes a thread id and returns its
            // class (or -1 when the thread has just ended).
            .map(|tid| unsafe { libc::sched_getscheduler(tid) })
            .collect()
    }

    #[test]
    fn hogs_are_sched_other_even_when_started_from_a_realtime_thread() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        if !crate::sys::is_root() {
            eprintln!("SKIPPED hogs_are_sched_other...: SCHED_FIFO needs root");
            return;
        }
        let policies = std::thread::spawn(|| {
            crate::sys::set_fifo(10).unwrap_or_else(|e| panic!("{e}"));
            // One hog: were it SCHED_FIFO (the bug this test catches), two
            // would hold both CPUs at this thread's priority and starve it.
            let load = Load::start(1).unwrap_or_else(|e| panic!("{e}"));
            std::thread::sleep(Duration::from_millis(20));
            let p = hog_policies();
            drop(load);
            p
        })
        .join()
        .unwrap_or_else(|_| panic!("the starter panicked"));
        assert_eq!(policies, vec![libc::SCHED_OTHER]);
    }

    #[test]
    fn hogs_run_and_stop_without_a_trace() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        let load = Load::start(2).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(load.len(), 2);
        std::thread::sleep(Duration::from_millis(50));
        assert!(hogs_running() >= 2, "the hogs run as named threads");
        load.stop();
        assert_eq!(hogs_running(), 0, "both hogs ended");
        // Dropped without stop (an error path): joined as well.
        drop(Load::start(1).unwrap_or_else(|e| panic!("{e}")));
        assert_eq!(hogs_running(), 0);
    }
}
