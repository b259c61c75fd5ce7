//! What a log says about the system that wrote it: its version and module
//! table, its `perf` counters, its threads and their priorities (`top`, or
//! PX4's source when the log has no `top`), its gyro and whether it ran in
//! SITL's lockstep.

use super::perf::{self, Counter, TopThread};
use super::px4::{self, Module, Queue};
use super::Ulog;
use crate::Diagnostic;

/// `SCHED_PRIORITY_MAX` as a source thread's `priority` holds it: a
/// queue's priority from the source is this plus its relative priority
/// (only the order matters to rtpipe). One below 255 so that the simulator,
/// at `SCHED_PRIORITY_MAX` like `wq:rate_ctrl`, can rank just above it:
/// rtpipe needs distinct priorities where PX4 has a FIFO tie.
pub(super) const SCHED_PRIORITY_MAX: i16 = 254;

/// What the spec is built from, read from one log.
pub(super) struct Facts {
    /// The `perf` counters (none when the log has no `perf_counter_*`).
    pub(super) counters: Vec<Counter>,
    /// The threads: `top`'s, or (without `top`) the table's modules' queues
    /// with the priorities of PX4's source.
    pub(super) threads: Vec<TopThread>,
    /// The threads are `top`'s.
    pub(super) top: bool,
    /// Uptime when the counters were stored, µs: `top`'s, or estimated as
    /// the rate loop's runs times the gyro period; `None` without either.
    pub(super) uptime_us: Option<u64>,
    pub(super) gyro_period_us: u64,
    pub(super) gyro_queue: String,
    /// `vX.Y.Z`.
    pub(super) version: String,
    pub(super) table: &'static [Module],
    /// SITL: the simulator publishes the gyro and the clock is simulated.
    pub(super) lockstep: bool,
    /// `ver_hw`.
    pub(super) board: String,
    /// Before work queues (v1.5–v1.6): each module its own task.
    pub(super) tasks: bool,
    /// How the version was found when the log does not say it.
    pub(super) version_note: Option<String>,
}

pub(super) fn missing(what: &str, help: &str) -> Diagnostic {
    Diagnostic::error(format!("the log lacks {what}"), help)
}

/// The info-multiple text whose key begins with `prefix` (the first key:
/// `perf_counter_postflight` before `perf_counter_preflight`).
fn text(log: &Ulog, prefix: &str) -> Option<Vec<String>> {
    let (_, v) = log
        .info_multiple
        .iter()
        .find(|(k, _)| k.starts_with(prefix))?;
    Some(v.first()?.clone())
}

/// The log's `ver_sw_release` (`major << 24 | minor << 16 | patch << 8 | type`).
fn release(log: &Ulog) -> Option<u32> {
    log.info
        .get("ver_sw_release")
        .filter(|v| v.ty == super::FieldType::U32 && v.number().is_finite())
        .map(|v| v.number() as u32)
}

/// PX4's version: the log's `ver_sw_release`, else the user's
/// `--px4-version`, else what the log's topics show; and how it was found
/// when the log does not say it. `vX.Y.Z` (or a range when inferred).
struct Version {
    major: u32,
    minor: u32,
    text: String,
    note: Option<String>,
}

const VERSION_HELP: &str =
    "give --px4-version X.Y (PX4's release the log was written by: 1.5, 1.6 or 1.11 to 1.15)";

fn version(log: &Ulog, given: Option<(u32, u32)>) -> Result<Version, Diagnostic> {
    if let Some(r) = release(log) {
        let (major, minor, patch) = (r >> 24, (r >> 16) & 0xff, (r >> 8) & 0xff);
        if let Some((a, b)) = given.filter(|g| *g != (major, minor)) {
            return Err(Diagnostic::error(
                format!("--px4-version {a}.{b}: the log's ver_sw_release says PX4 v{major}.{minor}.{patch}"),
                "leave --px4-version out: it is for logs without ver_sw_release",
            ));
        }
        let text = format!("v{major}.{minor}.{patch}");
        return Ok(Version {
            major,
            minor,
            text,
            note: None,
        });
    }
    if let Some((major, minor)) = given {
        let note =
            format!("the log has no ver_sw_release: PX4 v{major}.{minor} as given (--px4-version)");
        let text = format!("v{major}.{minor}, as given");
        return Ok(Version {
            major,
            minor,
            text,
            note: Some(note),
        });
    }
    // `control_state` was removed in v1.7; `sensor_combined` carries
    // `gyro_integral_dt` from v1.5 on.
    let has = |topic: &str, field: &str| {
        log.subscriptions
            .iter()
            .any(|s| s.name == topic && s.field(field).is_some())
    };
    if has("control_state", "timestamp") && has("sensor_combined", "gyro_integral_dt") {
        let note = "the log has no ver_sw_release: PX4 v1.5–v1.6 inferred from its topics (control_state, removed in v1.7; sensor_combined with gyro_integral_dt, from v1.5); --px4-version X.Y overrides".to_string();
        let text = "v1.5–v1.6, inferred".to_string();
        return Ok(Version {
            major: 1,
            minor: 6,
            text,
            note: Some(note),
        });
    }
    Err(missing(
        "the info message ver_sw_release (PX4's version; older logs have none), and its topics do not show the version (control_state and sensor_combined.gyro_integral_dt would show v1.5–v1.6)",
        VERSION_HELP,
    ))
}

/// Reads the facts of `log`; `given` is `--px4-version`.
pub(super) fn of(log: &Ulog, given: Option<(u32, u32)>) -> Result<Facts, Diagnostic> {
    let v = version(log, given)?;
    let est_group = log.parameters.get("SYS_MC_EST_GROUP").map(|p| p.number());
    let table = px4::table(v.major, v.minor, est_group).map_err(|e| {
        Diagnostic::error(e, "import a log of PX4 v1.5–v1.6 or v1.11 to v1.15, or add the version's table to crates/model/src/import/px4_ulog/px4.rs")
    })?;
    let tasks = table.iter().any(|m| m.queue == Queue::Own(px4::HRT));
    let counters: Vec<Counter> = text(log, "perf_counter_")
        .unwrap_or_default()
        .iter()
        .filter_map(|l| perf::counter(l))
        .collect();
    let gyro_queue = if tasks {
        px4::HRT.to_string()
    } else {
        gyro_queue(log)?
    };
    let board = log.info_text("ver_hw").unwrap_or_default();
    let lockstep = gyro_queue == px4::SIMULATOR || board == "PX4_SITL";
    let gyro_period_us = if tasks {
        sensor_combined_period(log)?
    } else if lockstep {
        lockstep_period(log)?
    } else {
        gyro_rate_period(log)?
    };
    let mut f = Facts {
        counters,
        threads: Vec::new(),
        top: false,
        uptime_us: None,
        gyro_period_us,
        gyro_queue,
        version: v.text,
        table,
        lockstep,
        board,
        tasks,
        version_note: v.note,
    };
    match text(log, "perf_top_") {
        Some(top) => {
            f.threads = top.iter().filter_map(|l| perf::top_thread(l)).collect();
            let uptime = top.iter().find_map(|l| perf::uptime_us(l));
            f.uptime_us = Some(uptime.ok_or_else(|| {
                missing(
                    "the uptime line of perf_top_*",
                    "import a log whose top is whole",
                )
            })?);
            f.top = true;
        }
        None => {
            f.threads = source_threads(&f.present(), &f)?;
            f.uptime_us = f.loop_uptime();
        }
    }
    Ok(f)
}

/// `1e6 / IMU_GYRO_RATEMAX` µs: the rate the gyro driver publishes at.
fn gyro_rate_period(log: &Ulog) -> Result<u64, Diagnostic> {
    let rate = log
        .parameters
        .get("IMU_GYRO_RATEMAX")
        .map(|v| v.number())
        .filter(|r| (1.0..=1e6).contains(r));
    let rate = rate.ok_or_else(|| {
        missing(
            "the parameter IMU_GYRO_RATEMAX (the gyro's rate)",
            "import a log of PX4 v1.11 or later",
        )
    })?;
    Ok((1e6 / rate).round() as u64)
}

/// Before work queues: the gyro period as the median step between
/// consecutive `sensor_combined` timestamps (`sensors` publishes one per
/// gyro sample; the logger drops a few, so the median, not the least).
fn sensor_combined_period(log: &Ulog) -> Result<u64, Diagnostic> {
    let stamps = log
        .topic("sensor_combined", 0)
        .and_then(|s| log.u64_values(s, "timestamp"))
        .unwrap_or_default();
    let mut steps: Vec<u64> = stamps
        .windows(2)
        .filter_map(|w| w[1].checked_sub(w[0]).filter(|d| *d > 0))
        .collect();
    steps.sort_unstable();
    steps.get(steps.len() / 2).copied().ok_or_else(|| {
        missing(
            "two sensor_combined messages apart in time (the gyro period is measured from them)",
            "log sensor_combined (PX4's default logging profile does)",
        )
    })
}

/// SITL's gyro period: the greatest common divisor of the steps between
/// consecutive `timestamp_sample`s of `vehicle_angular_velocity` (the
/// simulator's lockstep step; `IMU_GYRO_RATEMAX` does not apply to it).
fn lockstep_period(log: &Ulog) -> Result<u64, Diagnostic> {
    let samples = log
        .topic("vehicle_angular_velocity", 0)
        .and_then(|s| log.u64_values(s, "timestamp_sample"))
        .unwrap_or_default();
    // Steps beyond i64 (over 290,000 years of µs) are no lockstep step.
    let step = samples
        .windows(2)
        .filter_map(|w| w[1].checked_sub(w[0]).filter(|d| *d > 0))
        .filter_map(|d| i64::try_from(d).ok())
        .fold(0, crate::time::gcd);
    if step == 0 {
        return Err(missing(
            "two vehicle_angular_velocity samples apart in time (SITL's gyro period is measured from them)",
            "log vehicle_angular_velocity (PX4's default logging profile does)",
        ));
    }
    Ok(step.unsigned_abs())
}

/// The thread of the gyro `sensor_selection.gyro_device_id` names.
fn gyro_queue(log: &Ulog) -> Result<String, Diagnostic> {
    let selection = log
        .topic("sensor_selection", 0)
        .and_then(|s| log.values(s, "gyro_device_id"))
        .and_then(|v| v.first().copied());
    let device = selection.ok_or_else(|| {
        missing(
            "sensor_selection.gyro_device_id (which gyro the loop uses)",
            "log sensor_selection (in PX4's default logging profile)",
        )
    })?;
    px4::gyro_queue(device as u32).ok_or_else(|| {
        Diagnostic::error(
            format!(
                "the selected gyro (device id {device}) is neither on an SPI bus nor simulated"
            ),
            "rtpipe's PX4 table knows SPI gyros and SITL's simulated one only",
        )
    })
}

/// Without `top`: one thread per queue of `modules`, its priority from
/// PX4's `WorkQueueManager.hpp`.
fn source_threads(modules: &[Module], f: &Facts) -> Result<Vec<TopThread>, Diagnostic> {
    let mut out: Vec<TopThread> = Vec::new();
    for m in modules {
        let name = f.queue_name(m.queue);
        if out.iter().any(|t| t.name == name) {
            continue;
        }
        let rel = px4::wq_priority(&name).or_else(|| px4::task_priority(&name)).ok_or_else(|| {
            Diagnostic::error(
                format!("the log has no perf_top_* (the threads' priorities), and PX4's source gives none rtpipe knows for {name} (of {})", m.name),
                "import a log with perf_top_* (PX4 stores it at the start of a log on a board), or add the queue to wq_priority in crates/model/src/import/px4_ulog/px4.rs",
            )
        })?;
        let tie_break = i16::from(name == px4::SIMULATOR);
        let mut priority = u8::try_from(SCHED_PRIORITY_MAX + rel + tie_break).unwrap_or(0);
        // Tasks spawned at one priority (PX4 runs them FIFO) are ranked in
        // data-flow order: rtpipe needs distinct priorities.
        while out.iter().any(|t| t.priority == priority) {
            priority = priority.checked_sub(1).ok_or_else(|| {
                Diagnostic::error(
                    format!("no priority left for {name}"),
                    "report it with the log",
                )
            })?;
        }
        out.push(TopThread {
            name,
            cpu_ms: 0,
            priority,
        });
    }
    Ok(out)
}

impl Facts {
    /// The table's modules the log ran (optional ones only when counted).
    pub(super) fn present(&self) -> Vec<Module> {
        self.table
            .iter()
            .filter(|m| !m.optional || self.counter(m.counter).is_some_and(|c| c.events > 0))
            .copied()
            .collect()
    }

    /// The first of `names` the log has as an elapsed-time counter.
    pub(super) fn counter(&self, names: &[&str]) -> Option<&Counter> {
        names
            .iter()
            .find_map(|n| self.counters.iter().find(|c| c.name == *n && c.elapsed))
    }

    pub(super) fn thread(&self, name: &str) -> Option<&TopThread> {
        self.threads.iter().find(|t| t.name == name)
    }

    /// The queue's thread name.
    pub(super) fn queue_name(&self, q: Queue) -> String {
        match q {
            Queue::Wq(n) | Queue::Own(n) => n.to_string(),
            Queue::GyroBus => self.gyro_queue.clone(),
        }
    }

    /// A thread's CPU time from `top` per gyro period, µs, at least 1;
    /// `None` without `top` or the thread.
    pub(super) fn share(&self, name: &str) -> Option<u64> {
        let t = self.thread(name).filter(|_| self.top)?;
        let per = (t.cpu_ms as f64 * 1000.0) * self.gyro_period_us as f64 / self.uptime_us? as f64;
        Some((per.ceil() as u64).max(1))
    }

    /// Without `top`: the uptime as the first counted loop module's runs
    /// times the gyro period (it runs once per gyro sample).
    fn loop_uptime(&self) -> Option<u64> {
        let runs = self
            .table
            .iter()
            .filter(|m| m.release == px4::Release::Loop)
            .find_map(|m| self.counter(m.counter).filter(|c| c.events > 0))?
            .events;
        runs.checked_mul(self.gyro_period_us)
    }

    /// A counter of the table's modules that counted runs of 0 µs each:
    /// the log's times are not real (SITL's lockstep clock stands still
    /// while code runs).
    pub(super) fn zero_times(&self) -> Option<&Counter> {
        self.table
            .iter()
            .filter_map(|m| self.counter(m.counter))
            .find(|c| c.events > 0 && c.max_us == 0)
    }
}
