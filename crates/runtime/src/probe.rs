//! The run's evidence beyond the job log, sampled every [`PROBE_PERIOD`]
//! by the thread that watches the run: per CPU the hypervisor's steal time
//! (/proc/stat), per task thread its time on a CPU so far
//! (/proc/self/task/TID/schedstat). [`crate::blame`] reads them, with the
//! job log, to name what broke the model in a window of the run.

use crate::sys;
use rtpipe_model::Nanos;
use std::sync::atomic::{AtomicI32, Ordering};

/// How often the watcher samples (the resolution of every cause found in
/// the probes: a window is judged by the probe intervals that cover it).
pub const PROBE_PERIOD: Nanos = 2_000_000;

/// Cumulative counters at one instant of the run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Probe {
    /// When, relative to the epoch.
    pub at: Nanos,
    /// Per CPU (index = CPU number): steal time so far, ns (`/proc/stat`
    /// counts it in clock ticks, so it moves in steps of 1/USER_HZ).
    pub steal: Vec<Nanos>,
    /// Per task: its thread's time on a CPU so far, ns (0 before the
    /// thread started).
    pub run: Vec<Nanos>,
}

/// The counters now (`tids[i]`: the thread of task i, 0 until it started).
pub(crate) fn probe(epoch: Nanos, tids: &[AtomicI32]) -> Probe {
    Probe {
        at: sys::now() - epoch,
        steal: steal_per_cpu(),
        run: tids
            .iter()
            .map(|t| on_cpu(t.load(Ordering::SeqCst)).unwrap_or(0))
            .collect(),
    }
}

/// The kernel's real-time throttling: at most `sched_rt_runtime_us` of
/// every `sched_rt_period_us` of a CPU go to its real-time threads, ns
/// (`None`: unlimited, -1, or unreadable). [`crate::blame`] tells the
/// throttling the run's own demand triggers from foreign time by it.
pub fn rt_share() -> Option<(Nanos, Nanos)> {
    let read = |name: &str| -> Option<Nanos> {
        let text = std::fs::read_to_string(format!("/proc/sys/kernel/{name}")).ok()?;
        text.trim().parse::<Nanos>().ok()
    };
    let runtime = read("sched_rt_runtime_us").filter(|&r| r >= 0)?;
    let period = read("sched_rt_period_us").filter(|&p| p > 0)?;
    Some((runtime * 1_000, period * 1_000))
}

/// Thread `tid`'s time on a CPU so far (schedstat's first field), ns.
fn on_cpu(tid: i32) -> Option<Nanos> {
    if tid <= 0 {
        return None;
    }
    let text = std::fs::read_to_string(format!("/proc/self/task/{tid}/schedstat")).ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Steal time of each CPU so far, ns (empty when /proc/stat lacks it).
fn steal_per_cpu() -> Vec<Nanos> {
    let Ok(stat) = std::fs::read_to_string("/proc/stat") else {
        return Vec::new();
    };
    let tick = sys::tick_ns();
    let mut out = Vec::new();
    for line in stat.lines() {
        let mut f = line.split_whitespace();
        let Some(cpu) = f.next().and_then(|c| c.strip_prefix("cpu")) else {
            continue;
        };
        let (Ok(n), Some(Ok(steal))) = (cpu.parse::<usize>(), f.nth(7).map(str::parse::<Nanos>))
        else {
            continue;
        };
        if out.len() <= n {
            out.resize(n + 1, 0);
        }
        out[n] = steal * tick;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cpu_has_a_steal_counter_and_threads_their_cpu_time() {
        // The kernel adds a thread's CPU time up at switches and ticks: run
        // a little, then sleep.
        let t0 = sys::thread_cpu_time();
        while sys::thread_cpu_time() < t0 + 2_000_000 {}
        std::thread::sleep(std::time::Duration::from_millis(1));
        let tids = [AtomicI32::new(sys::gettid()), AtomicI32::new(0)];
        let p = probe(0, &tids);
        assert!(p.steal.len() >= sys::online_cpus(), "{p:?}");
        assert!(p.at > 0);
        assert!(p.run[0] > 0 && p.run[1] == 0, "{p:?}");
    }
}
