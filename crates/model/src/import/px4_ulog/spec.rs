//! A read log → the spec's text and the observed data ages.
//!
//! - Threads: every thread of the log's `top` (`perf_top_*`) whose priority
//!   is at least the output driver's, on one CPU (the boards these versions
//!   ran on are single-core). rtpipe's priorities count from 1 (highest);
//!   PX4's (NuttX's) higher number runs first, so they are ranked
//!   descending, equal priorities sharing a rank.
//! - Modules: [`super::px4`]'s table, each on its queue; `exec` is its
//!   `perf` counter's maximum, `exec_min` its minimum. A maximum at or
//!   above the module's own interval times blocking I/O, not CPU (PX4's
//!   `io update` waits for the IO coprocessor's serial link): its thread's
//!   CPU time from `top` is taken then (the average when it shares a
//!   thread), with a note. `--exec mean` takes every average instead. A module without a counter (the gyro
//!   driver, `VehicleAngularVelocity`) and a thread without a module of the
//!   table are charged their thread's CPU time from `top` per gyro period.
//! - The gyro driver runs at `1e6 / IMU_GYRO_RATEMAX` µs; the rate loop's
//!   modules are data-triggered by the one before; the others are periodic
//!   at their observed interval (`perf` events over the uptime).

use super::observed::{self, ObservedRow};
use super::perf::{self, Counter, TopThread};
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

/// What the spec is built from.
struct Facts {
    counters: Vec<Counter>,
    threads: Vec<TopThread>,
    uptime_us: u64,
    gyro_period_us: u64,
    gyro_queue: String,
    version: String,
    exec_from: ExecFrom,
}

fn missing(what: &str, help: &str) -> Diagnostic {
    Diagnostic::error(format!("the log lacks {what}"), help)
}

/// Builds the spec and the observed rows of `log`, named `name`, each
/// module's `exec` from `exec_from`.
pub fn import(log: &Ulog, name: &str, exec_from: ExecFrom) -> Result<Import, Diagnostic> {
    let mut facts = facts(log)?;
    facts.exec_from = exec_from;
    let table = px4::table(parse_release(log)?).map_err(|e| {
        Diagnostic::error(e, "import a log of PX4 v1.11 or v1.12, or add the version's table to crates/model/src/import/px4_ulog/px4.rs")
    })?;
    let modules = present(table, &facts)?;
    let lowest = chain_floor(&modules, &facts)?;
    // A thread that used no CPU has nothing to model unless the loop runs on it.
    let on_loop: Vec<String> = modules
        .iter()
        .filter(|m| m.release != Release::Periodic)
        .map(|m| queue_name(m.queue, &facts))
        .collect();
    let threads: Vec<&TopThread> = facts
        .threads
        .iter()
        .filter(|t| t.priority >= lowest && (t.cpu_ms > 0 || on_loop.contains(&t.name)))
        .collect();
    let mut assumptions = base_assumptions(&facts);
    let (ages, rows) = observe(log, &modules)?;
    let spec = spec_text(name, &facts, &modules, &threads, &mut assumptions)?;
    Ok(Import {
        spec,
        observed: observed::to_csv(&rows),
        ages,
        assumptions,
        board: format!(
            "{} (PX4 {})",
            log.info_text("ver_hw").unwrap_or_default(),
            facts.version
        ),
    })
}

fn parse_release(log: &Ulog) -> Result<u32, Diagnostic> {
    log.info
        .get("ver_sw_release")
        .filter(|v| v.ty == super::FieldType::U32)
        .map(|v| v.number() as u32)
        .ok_or_else(|| {
            missing(
                "the info message ver_sw_release (PX4's version)",
                "import a log of PX4 v1.11 or later",
            )
        })
}

/// The counters, threads, uptime and gyro of the log.
fn facts(log: &Ulog) -> Result<Facts, Diagnostic> {
    let text = |prefix: &str| -> Option<Vec<String>> {
        let (_, v) = log
            .info_multiple
            .iter()
            .find(|(k, _)| k.starts_with(prefix))?;
        Some(v.first()?.clone())
    };
    let perf_help = "the logger stores `perf` and `top` at the start of a log on PX4 v1.11 and later; import a log with both";
    let counters: Vec<Counter> = text("perf_counter_")
        .ok_or_else(|| missing("perf_counter_* (the modules' execution times)", perf_help))?
        .iter()
        .filter_map(|l| perf::counter(l))
        .collect();
    let top = text("perf_top_")
        .ok_or_else(|| missing("perf_top_* (the threads' priorities)", perf_help))?;
    let threads: Vec<TopThread> = top.iter().filter_map(|l| perf::top_thread(l)).collect();
    let uptime_us = top
        .iter()
        .find_map(|l| perf::uptime_us(l))
        .ok_or_else(|| missing("the uptime line of perf_top_*", perf_help))?;
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
    let gyro_queue = px4::spi_queue(device as u32).ok_or_else(|| {
        Diagnostic::error(
            format!("the selected gyro (device id {device}) is not on an SPI bus"),
            "rtpipe's PX4 table knows SPI gyros only",
        )
    })?;
    let release = parse_release(log)?;
    Ok(Facts {
        counters,
        threads,
        uptime_us,
        gyro_period_us: (1e6 / rate).round() as u64,
        gyro_queue,
        version: format!(
            "v{}.{}.{}",
            release >> 24,
            (release >> 16) & 0xff,
            (release >> 8) & 0xff
        ),
        exec_from: ExecFrom::Max,
    })
}

/// The table's modules the log ran (optional ones only when counted).
fn present(table: &[Module], f: &Facts) -> Result<Vec<Module>, Diagnostic> {
    let mut out = Vec::new();
    for m in table {
        let counted = m
            .counter
            .and_then(|c| counter(f, c))
            .is_some_and(|c| c.events > 0);
        if m.optional && !counted {
            continue;
        }
        if let Some(c) = m.counter.and_then(|c| counter(f, c)) {
            if c.events > 0 && c.max_us == 0 {
                return Err(Diagnostic::error(
                    format!("the perf counter `{}` measured {} runs of 0 µs: the log's execution times are not real (a SITL lockstep log, whose simulated clock stands still while code runs)", c.name, c.events),
                    "import a log from a flight controller board",
                ));
            }
        }
        out.push(*m);
    }
    Ok(out)
}

fn counter<'a>(f: &'a Facts, name: &str) -> Option<&'a Counter> {
    f.counters.iter().find(|c| c.name == name && c.elapsed)
}

fn thread<'a>(f: &'a Facts, name: &str) -> Option<&'a TopThread> {
    f.threads.iter().find(|t| t.name == name)
}

/// The queue's thread name in `top`.
fn queue_name(q: Queue, f: &Facts) -> String {
    match q {
        Queue::Wq(n) | Queue::Own(n) => n.to_string(),
        Queue::GyroBus => f.gyro_queue.clone(),
    }
}

/// The lowest priority on the rate loop: threads below it cannot delay it.
fn chain_floor(modules: &[Module], f: &Facts) -> Result<u8, Diagnostic> {
    let mut lowest = u8::MAX;
    for m in modules.iter().filter(|m| m.release != Release::Periodic) {
        let name = queue_name(m.queue, f);
        let t = thread(f, &name).ok_or_else(|| {
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

fn base_assumptions(f: &Facts) -> Vec<String> {
    vec![
        format!("the gyro driver runs every {} µs (1e6 / IMU_GYRO_RATEMAX) on {}; the sensor samples before the driver reads its FIFO, a wait the log's timestamp_sample includes and the spec does not", f.gyro_period_us, f.gyro_queue),
        "interrupt load (the NuttX kernel, DMA completion, the high-resolution timer) is not in the log: the spec has none".to_string(),
        "a module or thread without a perf counter is charged its thread's CPU time from top per gyro period (an average, not a worst case)".to_string(),
        "one CPU: these boards are single-core".to_string(),
    ]
}

/// The rows of every topic a loop module publishes, and their ages.
fn observe(
    log: &Ulog,
    modules: &[Module],
) -> Result<(Vec<TopicAges>, Vec<ObservedRow>), Diagnostic> {
    let mut topics: Vec<&str> = Vec::new();
    for t in modules.iter().filter_map(|m| m.publishes) {
        if !topics.contains(&t) {
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
        return Err(missing("timestamp_sample on vehicle_angular_velocity and actuator_controls_0 (the rate loop's measured data ages)", "log those topics (PX4's default logging profile does)"));
    }
    Ok((ages, all))
}

/// A module's exec and exec_min (µs) and how they were found.
fn timing(
    m: &Module,
    f: &Facts,
    period_us: u64,
    notes: &mut Vec<String>,
) -> Result<(u64, u64, String), Diagnostic> {
    let Some(c) = m.counter.and_then(|c| counter(f, c)) else {
        let name = queue_name(m.queue, f);
        let exec = share(f, &name).ok_or_else(|| {
            missing(
                &format!("CPU time of {name} in perf_top_*"),
                "import a log whose top lists it",
            )
        })?;
        return Ok((
            exec,
            1,
            format!("no perf counter: {name}'s CPU time per gyro period from top"),
        ));
    };
    let stats = format!(
        "perf `{}`: max {} µs, avg {:.2} µs, min {} µs, {} runs",
        c.name, c.max_us, c.avg_us, c.min_us, c.events
    );
    if c.max_us >= period_us {
        return blocking(m, c, f, period_us, notes, stats);
    }
    let exec = match f.exec_from {
        ExecFrom::Max => c.max_us,
        ExecFrom::Mean => c.avg_us.ceil() as u64,
    }
    .max(1);
    Ok((exec, c.min_us.clamp(1, exec), stats))
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
        if let Some(cpu) = share(f, name) {
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

/// A thread's CPU time from `top` per gyro period, µs, at least 1.
fn share(f: &Facts, name: &str) -> Option<u64> {
    let t = thread(f, name)?;
    let per = (t.cpu_ms as f64 * 1000.0) * f.gyro_period_us as f64 / f.uptime_us as f64;
    Some((per.ceil() as u64).max(1))
}

/// A periodic module's interval: the uptime over its runs, µs.
fn interval(m: &Module, f: &Facts) -> u64 {
    match m.counter.and_then(|c| counter(f, c)) {
        Some(c) if m.release == Release::Periodic && c.events > 0 => {
            (f.uptime_us / c.events).max(1)
        }
        _ => f.gyro_period_us,
    }
}

/// The spec as TOML text.
fn spec_text(
    name: &str,
    f: &Facts,
    modules: &[Module],
    threads: &[&TopThread],
    notes: &mut Vec<String>,
) -> Result<String, Diagnostic> {
    let mut timings = Vec::new();
    for m in modules {
        let period = interval(m, f);
        timings.push((period, timing(m, f, period, notes)?));
    }
    let mut s = header(name, f, notes);
    let ranks = ranks(threads);
    let used: Vec<String> = modules.iter().map(|m| queue_name(m.queue, f)).collect();
    for t in threads {
        // A module on a thread of its own is a task with that priority.
        if modules
            .iter()
            .any(|m| m.queue == Queue::Own(static_name(&t.name)))
        {
            continue;
        }
        let _ = writeln!(
            s,
            "[threads.{}]  # PX4 {} priority {}\npriority = {}\ncpu = 0\n",
            thread_key(&t.name),
            t.name,
            t.priority,
            ranks[&t.priority]
        );
    }
    let mut before: Option<&str> = None;
    for (m, (period, timing)) in modules.iter().zip(timings) {
        let q = queue_name(m.queue, f);
        // A periodic module on a thread below the loop cannot delay it.
        let Some(t) = threads.iter().find(|t| t.name == q) else {
            continue;
        };
        let rank = ranks[&t.priority];
        task_table(
            &mut s,
            f,
            m,
            (period, timing),
            rank,
            before.unwrap_or("gyro"),
        );
        if m.release != Release::Periodic {
            before = Some(m.name);
        }
    }
    load_tasks(&mut s, f, threads, &used);
    chains(&mut s, modules);
    Ok(s)
}

/// `name` when it is a thread of its own in the table (the table's names
/// are static), else the empty string, which no table entry has.
fn static_name(name: &str) -> &'static str {
    px4::V1_11
        .iter()
        .find_map(|m| match m.queue {
            Queue::Own(n) if n == name => Some(n),
            _ => None,
        })
        .unwrap_or("")
}

/// The comment lines and the `[system]` and channel tables.
fn header(name: &str, f: &Facts, notes: &[String]) -> String {
    let mut s = String::new();
    let stat = match f.exec_from {
        ExecFrom::Max => "longest",
        ExecFrom::Mean => "average",
    };
    let _ = writeln!(
        s,
        "# exec: each module's {stat} run in the log's perf counters"
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
        _ => writeln!(s, "thread = {:?}", thread_key(&queue_name(m.queue, f))),
    };
    let runs = m
        .counter
        .and_then(|c| counter(f, c))
        .map_or(0, |c| c.events);
    let _ = match m.release {
        Release::Gyro => writeln!(s, "period = \"{}us\"", f.gyro_period_us),
        Release::Periodic => writeln!(
            s,
            "period = \"{period}us\"  # {runs} runs in {} µs of uptime",
            f.uptime_us
        ),
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
        let exec = share(f, &t.name).unwrap_or(1);
        let _ = writeln!(s, "[tasks.{}_load]  # no module of the table: {}'s CPU time from top ({} ms in {} µs of uptime) per gyro period", thread_key(&t.name), t.name, t.cpu_ms, f.uptime_us);
        let _ = writeln!(
            s,
            "exec = \"{exec}us\"\nexec_min = \"1us\"\nperiod = \"{}us\"\nthread = {:?}\n",
            f.gyro_period_us,
            thread_key(&t.name)
        );
    }
}

/// The rate loop's chains: to each observed topic and to the outputs.
fn chains(s: &mut String, modules: &[Module]) {
    let lp: Vec<&Module> = modules
        .iter()
        .filter(|m| m.release != Release::Periodic)
        .collect();
    let mut written: Vec<&str> = Vec::new();
    for (k, m) in lp.iter().enumerate() {
        let Some(topic) = m.publishes else { continue };
        // The last publisher of a topic ends its chain.
        if lp[k + 1..].iter().any(|n| n.publishes == Some(topic)) || written.contains(&topic) {
            continue;
        }
        written.push(topic);
        let path: Vec<String> = lp[..=k].iter().map(|m| format!("{:?}", m.name)).collect();
        let _ = writeln!(
            s,
            "[[chain]]\nname = \"gyro to {topic}\"\npath = [{}]\n",
            path.join(", ")
        );
    }
    let path: Vec<String> = lp.iter().map(|m| format!("{:?}", m.name)).collect();
    let _ = writeln!(
        s,
        "[[chain]]\nname = \"gyro to outputs\"\npath = [{}]",
        path.join(", ")
    );
}
