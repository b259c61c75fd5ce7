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
    /// Starts `n` hogs, named `rtpipe-load-<i>`, in the default class
    /// (SCHED_OTHER; they are spawned before any task thread takes a
    /// real-time class) and on any CPU. On an error the ones started are
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

    #[test]
    fn hogs_run_and_stop_without_a_trace() {
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
