//! A read log → the spec's text and the observed data ages.
//!
//! - Threads: every thread of the log's `top` (`perf_top_*`) whose priority
//!   is at least the output driver's, on one CPU (the boards these versions
//!   ran on are single-core). rtpipe's priorities count from 1 (highest);
//!   PX4's (NuttX's) higher number runs first, so they are ranked
//!   descending, equal priorities sharing a rank. Without `top`, the
//!   table's modules' queues at the priorities of PX4's source
//!   ([`super::facts`]).
//! - Modules: [`super::px4`]'s table, each on its queue; `exec` is its
//!   `perf` counter's maximum, `exec_min` its minimum. A maximum at or
//!   above the module's own interval times blocking I/O, not CPU (PX4's
//!   `io update` waits for the IO coprocessor's serial link): its thread's
//!   CPU time from `top` is taken then (the average when it shares a
//!   thread), with a note. `--exec mean` takes every average instead. A
//!   module without a counter (the gyro driver, `VehicleAngularVelocity`)
//!   and a thread without a module of the table are charged their thread's
//!   CPU time from `top` per gyro period. The counters and `top` are
//!   another log's with [`Options::exec_log`] (for a log without counters,
//!   or a SITL log whose counters time 0 µs); [`Options::exec_us`] gives a
//!   module's time outright. A log with neither is refused naming both.
//! - The gyro driver runs at `1e6 / IMU_GYRO_RATEMAX` µs (SITL's simulator
//!   at its measured lockstep step); the rate loop's
//!   modules are data-triggered by the one before; the others are periodic
//!   at their observed interval (`perf` events over the uptime).

use super::facts::{self, missing, Facts};
use super::observed::{self, ObservedRow};
use super::perf::{Counter, TopThread};
use super::px4::{self, Module, Queue, Release};
use super::Ulog;
use crate::Diagnostic;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// What an import built: the spec, the observed rows, and what to tell.
#[derive(Debug, Clone)]
pub struct Import {
    /// The spec as TOML.
    pub spec: String,
    /// `observed.csv`'s text.
    pub observed: String,
    /// Per topic: the chain ending there and its measured data ages.
    pub ages: Vec<TopicAges>,
    /// What the log cannot tell and what was assumed, one line each.
    pub assumptions: Vec<String>,
    /// `ver_hw`, `ver_sw_release` as `vX.Y.Z`.
    pub board: String,
    /// A SITL log: its measured ages are lockstep ages (0 µs).
    pub lockstep: bool,
}

/// One topic's measured data ages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicAges {
    /// The spec's chain that ends at the topic.
    pub chain: String,
    /// The topic.
    pub topic: String,
    /// Messages.
    pub count: usize,
    /// Least and largest data age, ns.
    pub min_ns: u64,
    /// Largest data age, ns.
    pub max_ns: u64,
}

/// Which `perf` statistic becomes a module's `exec`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExecFrom {
    /// The largest run the log saw (a worst case as far as the log knows;
    /// it includes the first runs after boot).
    #[default]
    Max,
    /// The average run, rounded up (the typical load, as `top` sees it).
    Mean,
}

/// Where each module's `exec` comes from.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options<'a> {
    /// Which `perf` statistic.
    pub stat: ExecFrom,
    /// Another log of the same modules whose counters (and `top`) give the
    /// execution times, and how to name it; `None`: the log's own.
    pub exec_log: Option<(&'a Ulog, &'a str)>,
    /// Per module, an execution time (µs) the user gives; it overrides
    /// every counter.
    pub exec_us: &'a [(String, u64)],
    /// PX4's `(major, minor)` for a log without `ver_sw_release`.
    pub px4_version: Option<(u32, u32)>,
}

/// The execution times' source while the spec is built.
struct Exec<'a> {
    facts: &'a Facts,
    /// How the source is named in comments (`the log`, `--exec-from X`).
    label: String,
    stat: ExecFrom,
    given: &'a [(String, u64)],
}

/// Builds the spec and the observed rows of `log`, named `name`, each
/// module's `exec` as `opts` says.
pub fn import(log: &Ulog, name: &str, opts: &Options) -> Result<Import, Diagnostic> {
    let facts = facts::of(log, opts.px4_version)?;
    let other = match opts.exec_log {
        Some((l, label)) => Some((
            facts::of(l, None).map_err(|d| d.within(format!("--exec-from {label}")))?,
            label,
        )),
        None => None,
    };
    let exec = match &other {
        Some((f, label)) => Exec {
            facts: f,
            label: format!("--exec-from {label} ({}, PX4 {})", f.board, f.version),
            stat: opts.stat,
            given: opts.exec_us,
        },
        None => Exec {
            facts: &facts,
            label: "the log".to_string(),
            stat: opts.stat,
            given: opts.exec_us,
        },
    };
    check_exec_source(&exec)?;
    let modules = facts.present();
    for (given, _) in opts.exec_us {
        if !modules.iter().any(|m| m.name == given) {
            let names: Vec<&str> = modules.iter().map(|m| m.name).collect();
            return Err(Diagnostic::error(
                format!("--exec-us {given}: the spec has no module `{given}`"),
                format!("name one of: {}", names.join(", ")),
            ));
        }
    }
    let lowest = chain_floor(&modules, &facts)?;
    // A thread that used no CPU has nothing to model unless the loop runs
    // on it (without `top` every thread is a queue of the table's modules).
    let on_loop: Vec<String> = modules
        .iter()
        .filter(|m| m.release != Release::Periodic)
        .map(|m| facts.queue_name(m.queue))
        .collect();
    let threads: Vec<&TopThread> = facts
        .threads
        .iter()
        .filter(|t| {
            t.priority >= lowest && (!facts.top || t.cpu_ms > 0 || on_loop.contains(&t.name))
        })
        .collect();
    let mut assumptions = base_assumptions(&facts, &exec);
    let (ages, rows) = observe(log, &modules)?;
    let observed: Vec<&str> = ages.iter().map(|a| a.topic.as_str()).collect();
    let spec = spec_text(
        name,
        &facts,
        &exec,
        &modules,
        &threads,
        &observed,
        &mut assumptions,
    )?;
    Ok(Import {
        spec,
        observed: observed::to_csv(&rows),
        ages,
        assumptions,
        board: format!("{} (PX4 {})", facts.board, facts.version),
        lockstep: facts.lockstep,
    })
}

/// Refuses an execution-time source that has no times: a log without
/// `perf_counter_*`, or one whose counters timed every run as 0 µs.
fn check_exec_source(exec: &Exec) -> Result<(), Diagnostic> {
    if exec.facts.counters.is_empty() && exec.given.is_empty() {
        let d = missing("perf_counter_* (the modules' execution times)", EXEC_HELP);
        return Err(match exec.label.as_str() {
            "the log" => d,
            other => d.within(other),
        });
    }
    match exec.facts.zero_times() {
        // Times given for some modules: each other one is refused by name.
        Some(c) if exec.given.is_empty() => Err(zero_times(c, exec)),
        _ => Ok(()),
    }
}

/// A counter that timed its runs as 0 µs, refused.
fn zero_times(c: &Counter, exec: &Exec) -> Diagnostic {
    Diagnostic::error(
        format!("the perf counter `{}` of {} measured {} runs of 0 µs: the log's execution times are not real (a SITL lockstep log, whose simulated clock stands still while code runs)", c.name, exec.label, c.events),
        EXEC_HELP,
    )
}

/// How to give execution times a log lacks.
const EXEC_HELP: &str = "give --exec-from OTHER.ulg (a log of a flight controller board running the same modules: its perf counters, and its top for modules without one) or --exec-us MODULE=US for each module";

/// The lowest priority on the rate loop: threads below it cannot delay it.
fn chain_floor(modules: &[Module], f: &Facts) -> Result<u8, Diagnostic> {
    let mut lowest = u8::MAX;
    for m in modules.iter().filter(|m| m.release != Release::Periodic) {
        let name = f.queue_name(m.queue);
        let t = f.thread(&name).ok_or_else(|| {
            missing(
                &format!("the thread {name} (of {}) in perf_top_*", m.name),
                "import a log whose top lists the rate loop's threads",
            )
        })?;
        lowest = lowest.min(t.priority);
    }
    Ok(lowest)
}

/// The spec's name for a thread (`wq:` dropped: a name is a TOML key).
fn thread_key(name: &str) -> String {
    name.trim_start_matches("wq:")
        .replace(|c: char| !c.is_ascii_alphanumeric() && c != '_', "_")
}

fn base_assumptions(f: &Facts, exec: &Exec) -> Vec<String> {
    let mut out = Vec::new();
    if f.lockstep {
        out.push(format!("SITL: the simulator publishes the gyro every {} µs (the step of vehicle_angular_velocity's timestamp_sample; IMU_GYRO_RATEMAX does not apply) on its own thread `{}`, spawned at SCHED_PRIORITY_MAX like wq:rate_ctrl", f.gyro_period_us, f.gyro_queue));
        out.push("the measured ages are lockstep ages: SITL's simulated clock stands still while the modules run, so a gyro sample and what the loop makes of it carry the same time (0 µs); they show the data flow, not the CPU's delays".to_string());
        out.push("one CPU: SITL ran on a host whose cores the log does not give; the spec puts every thread on cpu 0".to_string());
    } else if f.tasks {
        out.extend(f.version_note.clone());
        out.push(format!("the gyro driver runs every {} µs (the median step of sensor_combined's timestamps) from a high-resolution-timer callout, i.e. interrupt context: the task `{}`, above every other", f.gyro_period_us, f.gyro_queue));
        out.push("before work queues each module is its own task (px4_task_spawn_cmd) blocking in px4_poll() on the topic before it: gyro → sensors → the estimator (SYS_MC_EST_GROUP) → control_state → mc_att_control (attitude and rate control in one task); sensors, the estimator and mc_att_control are all spawned at SCHED_PRIORITY_MAX - 5, which PX4 runs FIFO: rtpipe needs distinct priorities and ranks them in data-flow order".to_string());
        out.push("the log has no perf_top_*: what else ran (drivers, the logger, mavlink, navigator) is not known and not in the spec; interrupt load neither".to_string());
        out.push(if f.table.iter().any(|m| m.name == "ekf2") {
            "ekf2 stamps control_state with the time of its own run (hrt_absolute_time()), and mc_att_control passes that stamp on as actuator_controls_0's timestamp_sample: the measured age runs from ekf2's run, not from the gyro sample, a part of the chain's age".to_string()
        } else {
            "attitude_estimator_q stamps control_state with sensor_combined's timestamp (the gyro's), and mc_att_control passes it on as actuator_controls_0's timestamp_sample: the measured age runs from the gyro driver's read".to_string()
        });
    } else {
        out.push(format!("the gyro driver runs every {} µs (1e6 / IMU_GYRO_RATEMAX) on {}; the sensor samples before the driver reads its FIFO, a wait the log's timestamp_sample includes and the spec does not", f.gyro_period_us, f.gyro_queue));
        out.push("interrupt load (the NuttX kernel, DMA completion, the high-resolution timer) is not in the log: the spec has none".to_string());
    }
    if !f.top && !f.tasks {
        out.push("the log has no perf_top_*: the threads are the queues of rtpipe's module table, their priorities PX4's source's (WorkQueueManager.hpp, relative to SCHED_PRIORITY_MAX); what else ran is not known".to_string());
    }
    if exec.label != "the log" {
        out.push(format!("execution times from {}: that board's perf counters for the modules of the same name, and its top for those without one", exec.label));
    }
    if exec.facts.top {
        out.push("a module or thread without a perf counter is charged its thread's CPU time from top per gyro period (an average, not a worst case)".to_string());
    }
    if !f.lockstep {
        out.push("one CPU: these boards are single-core".to_string());
    }
    for (m, us) in exec.given {
        out.push(format!("{m}: exec {us} µs as given (--exec-us)"));
    }
    out
}

/// The rows of every topic a loop module publishes, and their ages.
fn observe(
    log: &Ulog,
    modules: &[Module],
) -> Result<(Vec<TopicAges>, Vec<ObservedRow>), Diagnostic> {
    let mut topics: Vec<&str> = Vec::new();
    for t in modules.iter().flat_map(|m| m.publishes) {
        if !topics.contains(t) {
            topics.push(t);
        }
    }
    let (mut ages, mut all) = (Vec::new(), Vec::new());
    for topic in topics {
        let chain = format!("gyro to {topic}");
        let rows = observed::rows(log, topic, &chain).map_err(|e| e.diagnostic())?;
        let Some(rows) = rows else { continue };
        let data = rows.iter().map(ObservedRow::data_age_ns);
        ages.push(TopicAges {
            min_ns: data.clone().min().unwrap_or(0),
            max_ns: data.max().unwrap_or(0),
            count: rows.len(),
            topic: topic.to_string(),
            chain,
        });
        all.extend(rows);
    }
    if ages.is_empty() {
        return Err(missing("timestamp_sample on vehicle_angular_velocity and the rate controller's output (actuator_controls_0, vehicle_torque_setpoint: the rate loop's measured data ages)", "log those topics (PX4's default logging profile does)"));
    }
    Ok((ages, all))
}

/// A module's exec and exec_min (µs) and how they were found.
fn timing(
    m: &Module,
    exec: &Exec,
    period_us: u64,
    notes: &mut Vec<String>,
) -> Result<(u64, u64, String), Diagnostic> {
    if let Some((_, us)) = exec.given.iter().find(|(n, _)| n == m.name) {
        return Ok((*us, 1, format!("exec as given: --exec-us {}={us}", m.name)));
    }
    let ex = exec.facts;
    // The same module in the source's version (its counter's name and
    // queue may differ between versions).
    let entry = ex.table.iter().find(|e| e.name == m.name).unwrap_or(m);
    let Some(c) = ex.counter(entry.counter) else {
        let name = ex.queue_name(entry.queue);
        let exec_us = ex.share(&name).ok_or_else(|| {
            Diagnostic::error(
                format!("no execution time for {}: {} has no perf counter for it and no top CPU time of its thread {name}", m.name, exec.label),
                format!("give --exec-us {}=US (its execution time in µs), or --exec-from a log that times it", m.name),
            )
        })?;
        return Ok((
            exec_us,
            1,
            format!(
                "no perf counter: {name}'s CPU time per gyro period from top of {}",
                exec.label
            ),
        ));
    };
    if c.events > 0 && c.max_us == 0 {
        return Err(zero_times(c, exec));
    }
    let stats = format!(
        "perf `{}` of {}: max {} µs, avg {:.2} µs, min {} µs, {} runs",
        c.name, exec.label, c.max_us, c.avg_us, c.min_us, c.events
    );
    if c.max_us >= period_us {
        return blocking(entry, c, ex, period_us, notes, stats);
    }
    let exec_us = match exec.stat {
        ExecFrom::Max => c.max_us,
        ExecFrom::Mean => c.avg_us.ceil() as u64,
    }
    .max(1);
    Ok((exec_us, c.min_us.clamp(1, exec_us), stats))
}

/// A counter whose longest run is not shorter than the module's interval
/// times waiting, not computing (PX4's `io update` waits for the IO
/// coprocessor's serial link). rtpipe has no self-suspension: a module
/// with a thread of its own is charged that thread's CPU time from `top`,
/// and the wait is left out of the bounds; any other its average.
fn blocking(
    m: &Module,
    c: &Counter,
    f: &Facts,
    period_us: u64,
    notes: &mut Vec<String>,
    stats: String,
) -> Result<(u64, u64, String), Diagnostic> {
    if let Queue::Own(name) = m.queue {
        if let Some(cpu) = f.share(name) {
            notes.push(format!(
                "{}: perf `{}` (max {} µs, avg {:.2} µs) is not below its interval {period_us} µs: it times waits for I/O, which rtpipe cannot model (no self-suspension); exec is its thread's CPU time from top, {cpu} µs per gyro period, and the bounds leave the wait out",
                m.name, c.name, c.max_us, c.avg_us
            ));
            return Ok((cpu, 1, format!("{stats}; exec: {name}'s CPU time from top")));
        }
    }
    let avg = (c.avg_us.ceil() as u64).max(1);
    notes.push(format!(
        "{}: perf `{}` max {} µs is not below its interval {period_us} µs, so it times blocking I/O, not CPU: exec is the average {avg} µs",
        m.name, c.name, c.max_us
    ));
    Ok((
        avg,
        c.min_us.clamp(1, avg),
        format!("{stats}; exec: the average"),
    ))
}

/// A periodic module's interval: the uptime over its runs, µs.
fn interval(m: &Module, f: &Facts) -> u64 {
    match (f.counter(m.counter), f.uptime_us) {
        (Some(c), Some(up)) if m.release == Release::Periodic && c.events > 0 => {
            (up / c.events).max(1)
        }
        _ => f.gyro_period_us,
    }
}

/// The spec as TOML text.
fn spec_text(
    name: &str,
    f: &Facts,
    exec: &Exec,
    modules: &[Module],
    threads: &[&TopThread],
    observed: &[&str],
    notes: &mut Vec<String>,
) -> Result<String, Diagnostic> {
    let mut timings = Vec::new();
    for m in modules {
        let q = f.queue_name(m.queue);
        // A periodic module on a thread below the loop cannot delay it:
        // it is left out, and so needs no execution time.
        if !threads.iter().any(|t| t.name == q) {
            timings.push(None);
            continue;
        }
        let period = interval(m, f);
        timings.push(Some((period, timing(m, exec, period, notes)?)));
    }
    let mut s = header(name, exec, notes);
    let ranks = ranks(threads);
    let used: Vec<String> = modules.iter().map(|m| f.queue_name(m.queue)).collect();
    for t in threads {
        // A module on a thread of its own is a task with that priority.
        if modules
            .iter()
            .any(|m| m.queue == Queue::Own(static_name(&t.name)))
        {
            continue;
        }
        let rel = facts::SCHED_PRIORITY_MAX - i16::from(t.priority);
        let why = if f.top {
            format!("PX4 {} priority {}", t.name, t.priority)
        } else if rel < 0 {
            format!("PX4 {}: SCHED_PRIORITY_MAX, as wq:rate_ctrl, ranked just above it (PX4 runs the two FIFO; rtpipe needs distinct priorities)", t.name)
        } else {
            format!(
                "PX4 {}: SCHED_PRIORITY_MAX - {rel} (WorkQueueManager.hpp; the log has no top)",
                t.name
            )
        };
        let _ = writeln!(
            s,
            "[threads.{}]  # {why}\npriority = {}\ncpu = 0\n",
            thread_key(&t.name),
            ranks[&t.priority]
        );
    }
    let mut before: Option<&str> = None;
    for (m, timing) in modules.iter().zip(timings) {
        let Some(timing) = timing else { continue };
        let q = f.queue_name(m.queue);
        let rank = threads
            .iter()
            .find(|t| t.name == q)
            .map_or(1, |t| ranks[&t.priority]);
        task_table(&mut s, f, m, timing, rank, before.unwrap_or("gyro"));
        if m.release != Release::Periodic {
            before = Some(m.name);
        }
    }
    load_tasks(&mut s, f, threads, &used);
    chains(&mut s, modules, observed);
    Ok(s)
}

/// `name` when it is a thread of its own in a table (the tables' names
/// are static), else the empty string, which no table entry has.
fn static_name(name: &str) -> &'static str {
    px4::V1_11
        .iter()
        .chain(px4::V1_13)
        .chain(px4::V1_6_Q)
        .chain(px4::V1_6_EKF2)
        .find_map(|m| match m.queue {
            Queue::Own(n) if n == name => Some(n),
            _ => None,
        })
        .unwrap_or("")
}

/// The comment lines and the `[system]` and channel tables.
fn header(name: &str, exec: &Exec, notes: &[String]) -> String {
    let mut s = String::new();
    let stat = match exec.stat {
        ExecFrom::Max => "longest",
        ExecFrom::Mean => "average",
    };
    let _ = writeln!(
        s,
        "# exec: each module's {stat} run in {}'s perf counters",
        exec.label
    );
    for n in notes {
        let _ = writeln!(s, "# assumption: {n}");
    }
    let _ = writeln!(s, "[system]\nname = {name:?}\ntime_unit = \"us\"\nscheduler = \"rm\"\npriorities = \"explicit\"\n\n[channels.uorb]\nbandwidth = 1000000\noverhead = 0\n");
    s
}

/// One module's task table: its times, its thread (or priority), its
/// activation (`trigger`: the loop module before it).
fn task_table(
    s: &mut String,
    f: &Facts,
    m: &Module,
    (period, (exec, exec_min, why)): (u64, (u64, u64, String)),
    rank: usize,
    trigger: &str,
) {
    let _ = writeln!(s, "[tasks.{}]  # {why}", m.name);
    let _ = writeln!(s, "exec = \"{exec}us\"\nexec_min = \"{exec_min}us\"");
    let _ = match m.queue {
        Queue::Own(_) => writeln!(s, "priority = {rank}\ncpu = 0"),
        _ => writeln!(s, "thread = {:?}", thread_key(&f.queue_name(m.queue))),
    };
    let runs = f.counter(m.counter).map_or(0, |c| c.events);
    let uptime = match (f.uptime_us, f.top) {
        (Some(up), true) => format!("{runs} runs in {up} µs of uptime"),
        (Some(up), false) => {
            format!("{runs} runs in {up} µs (the rate loop's runs times the gyro period)")
        }
        (None, _) => "no uptime in the log: every gyro period".to_string(),
    };
    let _ = match m.release {
        Release::Gyro => writeln!(s, "period = \"{}us\"", f.gyro_period_us),
        Release::Periodic => writeln!(s, "period = \"{period}us\"  # {uptime}"),
        Release::Loop => writeln!(
            s,
            "activation = \"data\"\nreads = [{trigger:?}]\ntriggers = [{trigger:?}]"
        ),
    };
    let _ = writeln!(s, "output = {{ channel = \"uorb\", size = 0 }}\n");
}

/// Ranks 1.. for NuttX priorities, highest first.
fn ranks(threads: &[&TopThread]) -> BTreeMap<u8, usize> {
    let mut ps: Vec<u8> = threads.iter().map(|t| t.priority).collect();
    ps.sort_unstable_by(|a, b| b.cmp(a));
    ps.dedup();
    ps.into_iter()
        .enumerate()
        .map(|(i, p)| (p, i + 1))
        .collect()
}

/// One periodic task for each thread no module of the table runs on.
fn load_tasks(s: &mut String, f: &Facts, threads: &[&TopThread], used: &[String]) {
    for t in threads.iter().filter(|t| !used.contains(&t.name)) {
        let exec = f.share(&t.name).unwrap_or(1);
        let _ = writeln!(s, "[tasks.{}_load]  # no module of the table: {}'s CPU time from top ({} ms in {} µs of uptime) per gyro period", thread_key(&t.name), t.name, t.cpu_ms, f.uptime_us.unwrap_or(0));
        let _ = writeln!(
            s,
            "exec = \"{exec}us\"\nexec_min = \"1us\"\nperiod = \"{}us\"\nthread = {:?}\n",
            f.gyro_period_us,
            thread_key(&t.name)
        );
    }
}

/// The rate loop's chains: to each observed topic and to the outputs.
fn chains(s: &mut String, modules: &[Module], observed: &[&str]) {
    let lp: Vec<&Module> = modules
        .iter()
        .filter(|m| m.release != Release::Periodic)
        .collect();
    let mut written: Vec<&str> = Vec::new();
    for (k, m) in lp.iter().enumerate() {
        for &topic in m.publishes {
            // The last publisher of a topic ends its chain; a topic the
            // log did not measure gets none.
            let later = lp[k + 1..].iter().any(|n| n.publishes.contains(&topic));
            if later || written.contains(&topic) || !observed.contains(&topic) {
                continue;
            }
            written.push(topic);
            chain(s, topic, &lp[..=k]);
        }
    }
    // The whole loop to the output driver, unless a measured chain is the
    // whole loop already (no output driver on it: SITL).
    let whole = lp
        .last()
        .is_some_and(|m| m.publishes.iter().any(|t| written.contains(t)));
    if !whole {
        let path: Vec<String> = lp.iter().map(|m| format!("{:?}", m.name)).collect();
        let _ = writeln!(
            s,
            "[[chain]]\nname = \"gyro to outputs\"\npath = [{}]",
            path.join(", ")
        );
    }
}

/// One `[[chain]]` from the gyro to `topic` along `path`.
fn chain(s: &mut String, topic: &str, path: &[&Module]) {
    {
        let path: Vec<String> = path.iter().map(|m| format!("{:?}", m.name)).collect();
        let _ = writeln!(
            s,
            "[[chain]]\nname = \"gyro to {topic}\"\npath = [{}]\n",
            path.join(", ")
        );
    }
}
