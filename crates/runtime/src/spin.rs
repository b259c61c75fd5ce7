//! Synthetic task bodies that burn a calibrated amount of CPU time, like
//! rt-app: any spec runs without task code.

use crate::sys;
use rtpipe_body::{Body, Job, Nanos, Stamped};
use std::hint::black_box;

/// A spin loop calibrated at start-up: how many iterations take 1 µs of CPU.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spin {
    /// Loop iterations per microsecond of CPU.
    pub iters_per_us: f64,
    /// CPU time one read of the thread's CPU clock costs (ns; a system
    /// call where the vDSO does not serve that clock).
    pub clock_ns: Nanos,
}

fn spin(iters: u64) {
    let mut x = 0u64;
    for i in 0..iters {
        x = black_box(x.wrapping_mul(6364136223846793005).wrapping_add(i));
    }
    black_box(x);
}

impl Spin {
    /// Times the loop on the calling thread's CPU clock (preemption does not
    /// count) and keeps the fastest of several trials (the least disturbed).
    pub fn calibrate() -> Spin {
        let iters = 200_000u64;
        spin(iters); // warm up
        let best = (0..7)
            .map(|_| {
                let t0 = sys::thread_cpu_time();
                spin(iters);
                (sys::thread_cpu_time() - t0).max(1)
            })
            .min()
            .unwrap_or(1);
        Spin {
            iters_per_us: iters as f64 * 1000.0 / best as f64,
            clock_ns: clock_cost(),
        }
    }

    /// Burns `ns` nanoseconds of the calling thread's CPU time, checked
    /// against the thread's CPU clock (preemption does not count). Chunks
    /// are calibrated: 20 µs while far from the end, then half of what is
    /// left, so a loop running slower than calibrated (frequency changes, a
    /// busy hyperthread sibling, steal charged to the thread) cannot carry
    /// the burn past `ns` by more than it slows half a chunk; it stops when
    /// one more clock read would end further from `ns` than stopping now.
    /// `cargo bench -p rtpipe-runtime --bench burn` measures the error.
    pub fn burn(&self, ns: Nanos) {
        if ns <= 0 {
            return;
        }
        let start = sys::thread_cpu_time();
        loop {
            let left = ns - (sys::thread_cpu_time() - start);
            if left <= self.clock_ns / 2 {
                return;
            }
            let chunk = if left > 40_000 { 20_000 } else { left / 2 };
            spin((chunk as f64 * self.iters_per_us / 1000.0) as u64);
        }
    }
}

/// The CPU time of one read of the thread's CPU clock: the least of many
/// back-to-back pairs.
fn clock_cost() -> Nanos {
    (0..1000)
        .map(|_| {
            let t0 = sys::thread_cpu_time();
            sys::thread_cpu_time() - t0
        })
        .min()
        .unwrap_or(0)
        .max(1)
}

/// A body that burns `demand` ns of CPU per job and publishes its job index.
pub fn synthetic(spin: Spin, demand: Nanos) -> impl Body<u64> {
    move |job: &Job, _: &[Option<Stamped<u64>>], _: Option<u64>| {
        spin.burn(demand);
        job.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn burns_roughly_what_it_is_asked() {
        let s = Spin::calibrate();
        assert!(s.iters_per_us > 1.0, "{s:?}");
        let t0 = sys::thread_cpu_time();
        s.burn(2_000_000);
        let used = sys::thread_cpu_time() - t0;
        // Generous: the machine is shared.
        // At least what was asked; a little more (the last chunk, clock reads).
        assert!(
            (2_000_000..2_500_000).contains(&used),
            "burned {used} ns for 2 ms"
        );
    }

    #[test]
    fn ends_within_a_few_clock_reads_of_the_demand() {
        let s = Spin::calibrate();
        let mut err: Vec<Nanos> = (0..200)
            .map(|_| {
                let t0 = sys::thread_cpu_time();
                s.burn(100_000);
                sys::thread_cpu_time() - t0 - 100_000
            })
            .collect();
        err.sort_unstable();
        // Never short by more than half a clock read; the typical burn
        // ends within the reads that measure it (interrupts and steal
        // charged to the thread make the rare outliers).
        assert!(err[0] >= -s.clock_ns / 2, "{err:?}");
        assert!(
            err[100] <= 5 * s.clock_ns + 1_000,
            "median {} ns: {err:?}",
            err[100]
        );
    }
}
