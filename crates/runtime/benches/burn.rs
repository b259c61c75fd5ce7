//! How exactly `Spin::burn` spends the CPU time it is asked for: per
//! demand, the error (CPU time used − asked, on the thread's CPU clock)
//! over many burns: median, p99, max, and the smallest (an undershoot is
//! negative). README.md ("Runtime") and docs/runtime.md quote the figures.
//! `cargo bench -p rtpipe-runtime --bench burn`

use rtpipe_runtime::{sys, Spin};

fn main() {
    let spin = Spin::calibrate();
    println!(
        "calibrated: {:.1} iterations/us, a CPU-clock read costs {} ns",
        spin.iters_per_us, spin.clock_ns
    );
    println!(
        "{:>10} {:>6} {:>10} {:>10} {:>10} {:>10}",
        "demand", "burns", "median", "p99", "max", "min"
    );
    for (demand, n) in [
        (10_000, 5000),
        (100_000, 2000),
        (1_000_000, 500),
        (10_000_000, 100),
    ] {
        let mut err: Vec<i64> = (0..n)
            .map(|_| {
                let t0 = sys::thread_cpu_time();
                spin.burn(demand);
                sys::thread_cpu_time() - t0 - demand
            })
            .collect();
        err.sort_unstable();
        let q = |p: f64| err[((err.len() - 1) as f64 * p) as usize];
        println!(
            "{:>8}us {:>6} {:>8}ns {:>8}ns {:>8}ns {:>8}ns",
            demand / 1000,
            n,
            q(0.5),
            q(0.99),
            err[err.len() - 1],
            err[0]
        );
    }
}
