//! The text PX4's logger stores from `perf` and `top` (info-multiple
//! messages `perf_counter_*` and `perf_top_*`): each module's counters and
//! each thread's priority and CPU time.

/// One `perf` counter line, e.g. `mc_rate_control: cycle: 7641 events,
/// 56744us elapsed, 7.43us avg, min 6us max 257us 2.964us rms`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Counter {
    /// Everything before the event count (`mc_rate_control: cycle`).
    pub(super) name: String,
    pub(super) events: u64,
    /// An elapsed-time counter's average, µs (an interval counter's
    /// average interval).
    pub(super) avg_us: f64,
    pub(super) min_us: u64,
    pub(super) max_us: u64,
    /// An elapsed-time counter (execution times), not an interval one.
    pub(super) elapsed: bool,
}

/// Parses one counter line; `None` for an event-only counter or a line
/// that is not a counter.
pub(super) fn counter(line: &str) -> Option<Counter> {
    let (name, rest) = line.rsplit_once(" events")?;
    let (name, events) = name.rsplit_once(": ")?;
    let events = events.trim().parse().ok()?;
    let elapsed = rest.contains("elapsed");
    let avg = rest.split(',').find(|p| p.contains(" avg"))?;
    let avg_us = avg
        .trim()
        .trim_end_matches(" avg")
        .trim_end_matches("us")
        .parse()
        .ok()?;
    let number_after = |key: &str| -> Option<u64> {
        let s = rest.split(key).nth(1)?;
        s.trim_start().split("us").next()?.trim().parse().ok()
    };
    Some(Counter {
        name: name.trim().to_string(),
        events,
        avg_us,
        min_us: number_after("min ")?,
        max_us: number_after("max ")?,
        elapsed,
    })
}

/// One thread of `top`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TopThread {
    pub(super) name: String,
    /// CPU time since boot, ms.
    pub(super) cpu_ms: u64,
    /// NuttX priority (higher runs first).
    pub(super) priority: u8,
}

/// Parses one `top` row: `PID COMMAND CPU(ms) CPU(%) USED/ STACK PRIO(BASE) STATE FD`.
pub(super) fn top_thread(line: &str) -> Option<TopThread> {
    let t: Vec<&str> = line.split_whitespace().collect();
    t.first()?.parse::<u32>().ok()?;
    let slash = t.iter().position(|s| s.contains('/'))?;
    let prio_at = if t[slash].ends_with('/') {
        slash + 2
    } else {
        slash + 1
    };
    if slash < 4 {
        return None;
    }
    Some(TopThread {
        name: t[1..slash - 2].join(" "),
        cpu_ms: t[slash - 2].parse().ok()?,
        priority: t.get(prio_at)?.parse().ok()?,
    })
}

/// The `Uptime: 21.326s total` of `top`, µs.
pub(super) fn uptime_us(line: &str) -> Option<u64> {
    let s = line.split("Uptime:").nth(1)?;
    let secs: f64 = s.trim_start().split('s').next()?.parse().ok()?;
    (secs.is_finite() && secs > 0.0).then(|| (secs * 1e6).round() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_threads_and_uptime_parse() {
        let c = counter("mc_rate_control: cycle: 7641 events, 56744us elapsed, 7.43us avg, min 6us max 257us 2.964us rms").unwrap();
        assert_eq!(
            (c.name.as_str(), c.events, c.min_us, c.max_us, c.elapsed),
            ("mc_rate_control: cycle", 7641, 6, 257, true)
        );
        assert!((c.avg_us - 7.43).abs() < 1e-9);
        let i = counter("vehicle_imu: gyro update interval: 7612 events, 2443.69 avg, min 2024us max 2545us 62.673us rms").unwrap();
        assert!(!i.elapsed && i.max_us == 2545);
        assert_eq!(counter("icm20602: FIFO reset: 1 events"), None);
        let t = top_thread(
            " 201 wq:rate_ctrl                  315  1.600  1108/ 1660 255 (255)  w:sem  4",
        )
        .unwrap();
        assert_eq!(
            (t.name.as_str(), t.cpu_ms, t.priority),
            ("wq:rate_ctrl", 315, 255)
        );
        let idle = top_thread(
            "   0 Idle Task                   16387 76.700   200/  512   0 (  0)  READY  0",
        )
        .unwrap();
        assert_eq!(idle.name, "Idle Task");
        assert_eq!(
            top_thread(
                " PID COMMAND                   CPU(ms) CPU(%)  USED/STACK PRIO(BASE) STATE FD"
            ),
            None
        );
        assert_eq!(
            uptime_us("Uptime: 21.326s total, 16.387s idle"),
            Some(21_326_000)
        );
    }
}
