//! # rtpipe-model
//!
//! The spec of a pipe system (Cheng, West, Einstein, EMSOFT 2018, Section III-C):
//! tasks `τ = (d_i, p, d_o)` mapped 1:1 to pipes `π = ((W_i, δ_i), (C, T), (W_o, δ_o))`,
//! the channels their ends use, and the chains whose end-to-end times matter.
//!
//! [`Spec::parse`] turns TOML into a validated [`Spec`] or a [`SpecError`] that
//! names file, line and column of every problem and how to fix it. It never
//! panics, whatever the input.

mod error;
pub mod gen;
mod raw;
pub mod time;
mod write;
pub use write::to_toml;

pub use error::{line_col, printable, suggest, Diagnostic, SpecError};
pub use time::{format_in, parse_time_str, Nanos, TimeUnit, MAX_TIME};

/// The largest spec file `Spec::load` reads: 16 MiB.
pub const MAX_SPEC_BYTES: u64 = 16 << 20;

use raw::{RawPort, RawSpec, RawTask, S};
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

/// How CPUs pick among ready pipe terminals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheduler {
    /// Fixed priority, rate monotonic; equal periods are ordered by declaration.
    Rm,
    /// Reservations scheduled EDF (constant-bandwidth servers, as SCHED_DEADLINE).
    Edf,
}

impl Scheduler {
    pub fn name(self) -> &'static str {
        match self {
            Scheduler::Rm => "rm",
            Scheduler::Edf => "edf",
        }
    }
}

/// The schedulability test applied per CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SchedTest {
    /// Σ U ≤ n(2^{1/n} − 1) (Liu and Layland 1973), the test of Table II.
    LiuLayland,
    /// Π (U_i + 1) ≤ 2 (Bini, Buttazzo, Buttazzo 2003).
    Hyperbolic,
    /// Exact response-time analysis: every R_i ≤ T_i.
    Rta,
    /// EDF: Σ U ≤ 1.
    Edf,
}

impl SchedTest {
    pub fn name(self) -> &'static str {
        match self {
            SchedTest::LiuLayland => "liu-layland",
            SchedTest::Hyperbolic => "hyperbolic",
            SchedTest::Rta => "rta",
            SchedTest::Edf => "edf",
        }
    }
}

/// The kind of VCPU a pipe terminal is (Section II-B).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Server {
    /// Main VCPU: sporadic server.
    Main,
    /// I/O VCPU: priority-inheritance bandwidth-preserving server (PIBS).
    Io,
    /// A plain periodic task, no budget enforcement.
    None,
    /// Runs only in slack at the lowest priority; no timing guarantee.
    Background,
}

impl Server {
    pub fn name(self) -> &'static str {
        match self {
            Server::Main => "main",
            Server::Io => "io",
            Server::None => "none",
            Server::Background => "background",
        }
    }
}

/// A communication channel (pipe end): shared memory, SPI, I2C, …
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub name: String,
    /// W: data units per time unit of the spec.
    pub bandwidth: f64,
    /// δ: software overhead per transfer.
    pub overhead: Nanos,
}

/// Data moved over one channel by one transfer.
#[derive(Debug, Clone, PartialEq)]
pub struct Port {
    pub channel: usize,
    pub size: f64,
}

/// Where the period of a task comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PeriodSpec {
    Fixed(Nanos),
    /// A design variable in [min, max] (either end may be open).
    Range {
        min: Option<Nanos>,
        max: Option<Nanos>,
    },
    /// A design variable taking one of these values.
    Choices(Vec<Nanos>),
    /// Not given: a design variable without bounds.
    Free,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    pub name: String,
    /// p: worst-case uninterrupted processing time.
    pub exec: Nanos,
    /// Best-case processing time (default 0): the sound analysis holds for any
    /// processing time in [exec_min, exec].
    pub exec_min: Nanos,
    /// Device input, for tasks that sample hardware.
    pub input: Option<Port>,
    /// The single output copy (Section IV-B: one copy whatever the fan-out).
    pub output: Option<Port>,
    /// Producers this task reads, in declaration order.
    pub reads: Vec<usize>,
    pub period: PeriodSpec,
    /// C. `None` = Step 1 of Section IV-B: C = Δin + p + Δout.
    pub budget_given: Option<Nanos>,
    pub server: Server,
    pub cpu: u32,
    /// I/O VCPUs only: the Main VCPU this one serves. While that task has a
    /// job pending, the I/O VCPU inherits its priority (PIBS, Section II-B).
    pub serves: Option<usize>,
    /// The task code that runs its jobs (`rtpipe fly`), by name; the timing
    /// analysis does not use it.
    pub body: Option<String>,
    /// Δin: read stage, summed over input channels (each δ once).
    pub delta_in: Nanos,
    /// Δout: write stage.
    pub delta_out: Nanos,
}

impl Task {
    /// A plain periodic task on a Main VCPU of CPU 0: one output of size 0 on
    /// channel 0, no input, no transfer cost, `exec_min = exec`, budget from
    /// Step 1. A building block for generated and hand-written systems; set
    /// other fields with struct update (`Task { cpu: 1, ..Task::periodic(..) }`).
    pub fn periodic(exec: Nanos, period: Nanos) -> Task {
        Task {
            name: String::new(),
            exec,
            exec_min: exec,
            input: None,
            output: Some(Port {
                channel: 0,
                size: 0.0,
            }),
            reads: Vec::new(),
            period: PeriodSpec::Fixed(period),
            budget_given: None,
            server: Server::Main,
            cpu: 0,
            serves: None,
            body: None,
            delta_in: 0,
            delta_out: 0,
        }
    }

    /// Worst-case demand of one job: Δin + p + Δout.
    pub fn demand(&self) -> Nanos {
        self.delta_in
            .saturating_add(self.exec)
            .saturating_add(self.delta_out)
    }
    /// Best-case demand of one job: Δin + p_min + Δout.
    pub fn demand_min(&self) -> Nanos {
        self.delta_in
            .saturating_add(self.exec_min)
            .saturating_add(self.delta_out)
    }
    /// C: the given budget or the demand (Section IV-B, Step 1).
    pub fn budget(&self) -> Nanos {
        self.budget_given.unwrap_or_else(|| self.demand())
    }
    /// T, when fixed.
    pub fn fixed_period(&self) -> Option<Nanos> {
        match self.period {
            PeriodSpec::Fixed(t) => Some(t),
            _ => None,
        }
    }
}

/// A path along edges (producer → consumer) with optional limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    pub name: Option<String>,
    pub path: Vec<usize>,
    pub reaction: Option<Nanos>,
    pub freshness: Option<Nanos>,
}

/// A validated system.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    pub name: String,
    pub time_unit: TimeUnit,
    pub scheduler: Scheduler,
    pub schedulability: SchedTest,
    /// Design: periods are integer multiples of this (default 1 time unit).
    pub resolution: Nanos,
    /// Design: every pair of periods divides one another.
    pub harmonic: bool,
    pub channels: Vec<Channel>,
    pub tasks: Vec<Task>,
    pub chains: Vec<Chain>,
}

impl Spec {
    /// Parses and validates a spec. `file` only labels diagnostics.
    pub fn parse(file: &str, source: &str) -> Result<Spec, SpecError> {
        let fail = |diagnostics| SpecError {
            file: file.to_string(),
            source: source.to_string(),
            diagnostics,
        };
        let raw: RawSpec = toml::from_str(source).map_err(|e| {
            let mut msg = e.message().trim().to_string();
            if msg.is_empty() {
                // toml says nothing for e.g. a key without a value (`exec =`).
                msg = "invalid TOML syntax here (for example a key without a value: write `exec = 0.5`)".to_string();
            }
            let help = toml_help(&msg);
            let mut d = Diagnostic::new(msg, e.span());
            if let Some(h) = help {
                d = d.help(h);
            }
            fail(vec![d])
        })?;
        let mut b = Builder::default();
        let spec = b.build(raw);
        if b.diags.is_empty() {
            if let Some(spec) = spec {
                return Ok(spec);
            }
        }
        if b.diags.is_empty() {
            b.diags
                .push(Diagnostic::new("the spec is incomplete", None));
        }
        Err(fail(b.diags))
    }

    /// Reads and parses a spec file of at most [`MAX_SPEC_BYTES`]; larger
    /// files and endless streams (`/dev/zero`) are refused after reading at
    /// most that much.
    pub fn load(path: &std::path::Path) -> Result<Spec, SpecError> {
        let file = path.display().to_string();
        let fail = |msg: String, help: &str| SpecError {
            file: file.clone(),
            source: String::new(),
            diagnostics: vec![Diagnostic::new(msg, None).help(help)],
        };
        let cap_help = "specs are small TOML files; check the path (a device, log or binary file is not a spec)";
        let too_big = || {
            fail(
                format!(
                    "the spec is larger than {} MiB, the most rtpipe reads",
                    MAX_SPEC_BYTES >> 20
                ),
                cap_help,
            )
        };
        let read_help = "check the path; specs are TOML files such as examples/paper-table2.toml";
        let f = std::fs::File::open(path)
            .map_err(|e| fail(format!("cannot read the spec: {e}"), read_help))?;
        if let Ok(m) = f.metadata() {
            if m.is_dir() {
                return Err(fail(
                    "cannot read the spec: it is a directory".into(),
                    read_help,
                ));
            }
            if m.is_file() && m.len() > MAX_SPEC_BYTES {
                return Err(too_big());
            }
        }
        let mut bytes = Vec::new();
        use std::io::Read;
        f.take(MAX_SPEC_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| fail(format!("cannot read the spec: {e}"), read_help))?;
        if bytes.len() as u64 > MAX_SPEC_BYTES {
            return Err(too_big());
        }
        match String::from_utf8(bytes) {
            Ok(text) => Spec::parse(&file, &text),
            Err(e) => Err(fail(
                format!(
                    "cannot read the spec: not UTF-8 text (invalid byte at offset {})",
                    e.utf8_error().valid_up_to()
                ),
                cap_help,
            )),
        }
    }

    pub fn task_index(&self, name: &str) -> Option<usize> {
        self.tasks.iter().position(|t| t.name == name)
    }

    /// A path of task indices as people read it: names joined by `>`
    /// (`?` for an index that names no task).
    pub fn path_label(&self, path: &[usize]) -> String {
        let names: Vec<&str> = path
            .iter()
            .map(|&i| self.tasks.get(i).map_or("?", |t| t.name.as_str()))
            .collect();
        names.join(">")
    }

    /// A declared chain's label: its name, or else its path.
    pub fn chain_label(&self, chain: usize) -> String {
        match self.chains.get(chain) {
            Some(ch) => ch.name.clone().unwrap_or_else(|| self.path_label(&ch.path)),
            None => format!("chain {chain}"),
        }
    }

    /// Edges producer → consumer, as (producer, consumer) pairs.
    pub fn edges(&self) -> Vec<(usize, usize)> {
        let mut e = Vec::new();
        for (c, t) in self.tasks.iter().enumerate() {
            for &p in &t.reads {
                e.push((p, c));
            }
        }
        e
    }

    /// Consumers of each task.
    pub fn consumers(&self) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); self.tasks.len()];
        for (p, c) in self.edges() {
            out[p].push(c);
        }
        out
    }

    /// Formats a time in the spec's unit.
    pub fn fmt_time(&self, ns: Nanos) -> String {
        format_in(ns, self.time_unit)
    }

    /// A time in the spec's unit, as a number (for JSON).
    pub fn in_unit(&self, ns: Nanos) -> f64 {
        self.time_unit.from_nanos(ns)
    }
}

/// Transfer time of `size` data units over a channel: d/W + δ (Eq. 1), in ns,
/// rounded to the nearest nanosecond.
/// Saturates just above [`MAX_TIME`], so validation can reject it instead of
/// overflowing.
pub fn transfer_time(ch: &Channel, size: f64, unit: TimeUnit) -> Nanos {
    let t = size / ch.bandwidth * unit.nanos() as f64;
    let t = if t.is_finite() {
        t.round().min(MAX_TIME as f64 + 1.0)
    } else {
        MAX_TIME as f64 + 1.0
    };
    (t as Nanos).saturating_add(ch.overhead).min(MAX_TIME + 1)
}

/// Fills Δin and Δout of every task from its ports: fan-in aggregates sizes
/// per channel and each input channel costs its δ once (Section IV-B).
pub fn compute_transfers(tasks: &mut [Task], channels: &[Channel], unit: TimeUnit) {
    for ci in 0..tasks.len() {
        let mut per_channel: BTreeMap<usize, f64> = BTreeMap::new();
        if let Some(p) = &tasks[ci].input {
            *per_channel.entry(p.channel).or_default() += p.size;
        }
        for k in 0..tasks[ci].reads.len() {
            let pi = tasks[ci].reads[k];
            if let Some(o) = &tasks[pi].output {
                *per_channel.entry(o.channel).or_default() += o.size;
            }
        }
        tasks[ci].delta_in = per_channel
            .iter()
            .map(|(&c, &size)| transfer_time(&channels[c], size, unit))
            .fold(0, |a: Nanos, b| a.saturating_add(b).min(MAX_TIME + 1));
        tasks[ci].delta_out = tasks[ci]
            .output
            .as_ref()
            .map(|o| transfer_time(&channels[o.channel], o.size, unit))
            .unwrap_or(0);
    }
}

fn toml_help(msg: &str) -> Option<String> {
    if msg.contains("unknown field") {
        Some("remove the key or correct its spelling; the expected keys are listed above".into())
    } else if msg.contains("missing field") {
        Some("add the missing key (see the spec format in the README)".into())
    } else if msg.contains("too large to fit") {
        Some("whole numbers must fit in 64 bits; times are limited to about 106 days: write a smaller value, or a time with a unit such as \"250us\"".into())
    } else if msg.contains("invalid type") {
        Some("times are numbers in the system's time_unit or strings like \"250us\"".into())
    } else {
        None
    }
}

#[derive(Default)]
struct Builder {
    diags: Vec<Diagnostic>,
    unit: Option<TimeUnit>,
}

fn span<T>(s: &S<T>) -> Option<Range<usize>> {
    Some(s.span())
}

impl Builder {
    fn err(&mut self, msg: impl Into<String>, span: Option<Range<usize>>, help: impl Into<String>) {
        self.diags.push(Diagnostic::new(msg, span).help(help));
    }

    fn unit(&self) -> TimeUnit {
        self.unit.unwrap_or(TimeUnit::Ms)
    }

    /// A name must be non-empty and printable; task names must also not
    /// contain `>`, which joins them in chain labels (`t1>t4`).
    fn check_name(&mut self, kind: &str, n: &S<String>, example: &str) -> bool {
        let s = n.get_ref();
        let problem = if s.trim().is_empty() {
            Some(format!("{kind} name is empty"))
        } else if let Some(c) = s.chars().find(|c| c.is_control()) {
            Some(format!(
                "{kind} name \"{}\" contains the control character U+{:04X}",
                s.escape_debug(),
                c as u32
            ))
        } else if kind == "task" && s.contains('>') {
            Some(format!(
                "task name \"{s}\" contains `>`, which separates the tasks of chain labels (t1>t4)"
            ))
        } else {
            None
        };
        match problem {
            Some(msg) => {
                self.err(
                    msg,
                    span(n),
                    format!("use a short printable name without `>`, e.g. {example}"),
                );
                false
            }
            None => true,
        }
    }

    /// A time: a bare number in the time unit or a string with a unit.
    fn time(&mut self, v: &S<toml::Value>, what: &str) -> Option<Nanos> {
        let r = match v.get_ref() {
            toml::Value::Integer(i) => time::number_to_nanos(*i as f64, self.unit()),
            toml::Value::Float(f) => time::number_to_nanos(*f, self.unit()),
            toml::Value::String(s) => time::parse_time_str(s),
            other => {
                self.err(
                    format!("{what} must be a time, found a {}", other.type_str()),
                    span(v),
                    format!(
                        "write a number (in {}) or a string like \"250us\"",
                        self.unit()
                    ),
                );
                return None;
            }
        };
        match r {
            Ok(ns) => Some(ns),
            Err(e) => {
                self.err(
                    format!("{what}: {e}"),
                    span(v),
                    "for example 10, 0.5 or \"250us\"",
                );
                None
            }
        }
    }

    fn positive_time(&mut self, v: &S<toml::Value>, what: &str) -> Option<Nanos> {
        let t = self.time(v, what)?;
        if t <= 0 {
            self.err(
                format!(
                    "{what} must be positive, found {}",
                    format_in(t, self.unit())
                ),
                span(v),
                format!("give {what} a value greater than zero"),
            );
            return None;
        }
        Some(t)
    }

    fn nonneg_time(&mut self, v: &S<toml::Value>, what: &str) -> Option<Nanos> {
        let t = self.time(v, what)?;
        if t < 0 {
            self.err(
                format!(
                    "{what} must not be negative, found {}",
                    format_in(t, self.unit())
                ),
                span(v),
                format!("give {what} a value of zero or more"),
            );
            return None;
        }
        Some(t)
    }

    /// A plain number (sizes, bandwidths).
    fn number(&mut self, v: &S<toml::Value>, what: &str, positive: bool) -> Option<f64> {
        let x = match v.get_ref() {
            toml::Value::Integer(i) => *i as f64,
            toml::Value::Float(f) => *f,
            other => {
                self.err(
                    format!("{what} must be a number, found a {}", other.type_str()),
                    span(v),
                    format!("write {what} as a plain number, without a unit"),
                );
                return None;
            }
        };
        let ok = x.is_finite() && x < 1e15 && if positive { x > 0.0 } else { x >= 0.0 };
        if !ok {
            self.err(
                format!(
                    "{what} must be a finite number {} zero, found {x}",
                    if positive {
                        "greater than"
                    } else {
                        "of at least"
                    }
                ),
                span(v),
                format!(
                    "give {what} a value {}",
                    if positive { "> 0" } else { ">= 0" }
                ),
            );
            return None;
        }
        Some(x)
    }

    fn choice<T: Copy>(
        &mut self,
        v: &S<String>,
        what: &str,
        options: &[(&'static str, T)],
    ) -> Option<T> {
        let s = v.get_ref().as_str();
        if let Some((_, t)) = options.iter().find(|(n, _)| *n == s) {
            return Some(*t);
        }
        let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
        let help = match suggest(s, names.iter().copied()) {
            Some(n) => format!(
                "did you mean \"{n}\"? ({what} is one of {})",
                names.join(", ")
            ),
            None => format!("{what} is one of {}", names.join(", ")),
        };
        self.err(format!("unknown {what} \"{s}\""), span(v), help);
        None
    }

    fn build(&mut self, raw: RawSpec) -> Option<Spec> {
        let sys = raw.system.get_ref();
        let name = sys.name.get_ref().trim().to_string();
        if name.is_empty() {
            self.err(
                "system name is empty",
                span(&sys.name),
                "name the system, e.g. name = \"quad\"",
            );
        } else {
            self.check_name("system", &sys.name, "name = \"quad\"");
        }
        if let Some(u) = &sys.time_unit {
            match TimeUnit::parse(u.get_ref()) {
                Some(t) => self.unit = Some(t),
                None => {
                    let names: Vec<&str> = TimeUnit::ALL.iter().map(|u| u.name()).collect();
                    let help = match suggest(u.get_ref(), names.iter().copied()) {
                        Some(n) => {
                            format!("did you mean \"{n}\"? time_unit is one of ns, us, ms, s")
                        }
                        None => "time_unit is one of ns, us, ms, s".to_string(),
                    };
                    self.err(
                        format!("unknown time_unit \"{}\"", u.get_ref()),
                        span(u),
                        help,
                    );
                }
            }
        } else {
            self.unit = Some(TimeUnit::Ms);
        }
        let scheduler = match &sys.scheduler {
            Some(s) => self.choice(
                s,
                "scheduler",
                &[("rm", Scheduler::Rm), ("edf", Scheduler::Edf)],
            ),
            None => Some(Scheduler::Rm),
        };
        let test = match &sys.schedulability {
            Some(s) => self.choice(
                s,
                "schedulability test",
                &[
                    ("liu-layland", SchedTest::LiuLayland),
                    ("hyperbolic", SchedTest::Hyperbolic),
                    ("rta", SchedTest::Rta),
                    ("edf", SchedTest::Edf),
                ],
            ),
            None => scheduler.map(|s| match s {
                Scheduler::Rm => SchedTest::Rta,
                Scheduler::Edf => SchedTest::Edf,
            }),
        };
        if let (Some(s), Some(t), Some(sp)) = (scheduler, test, &sys.schedulability) {
            let fits = match s {
                Scheduler::Rm => t != SchedTest::Edf,
                Scheduler::Edf => t == SchedTest::Edf,
            };
            if !fits {
                let help = match s {
                    Scheduler::Rm => "with scheduler = \"rm\" use \"liu-layland\", \"hyperbolic\" or \"rta\"",
                    Scheduler::Edf => "with scheduler = \"edf\" use schedulability = \"edf\" (the utilisation test)",
                };
                self.err(
                    format!(
                        "schedulability test \"{}\" does not apply to scheduler \"{}\"",
                        t.name(),
                        s.name()
                    ),
                    span(sp),
                    help,
                );
            }
        }

        // Channels.
        let mut channels = Vec::new();
        let mut ch_index: HashMap<String, usize> = HashMap::new();
        for (k, v) in &raw.channels.0 {
            let c = v.get_ref();
            self.check_name("channel", k, "[channels.mem]");
            if ch_index.contains_key(k.get_ref()) {
                self.err(
                    format!("channel `{}` is declared twice", k.get_ref()),
                    span(k),
                    "rename one of them",
                );
                continue;
            }
            let bw = self.number(&c.bandwidth, "bandwidth", true);
            let oh = match &c.overhead {
                Some(o) => self.nonneg_time(o, "overhead"),
                None => Some(0),
            };
            ch_index.insert(k.get_ref().clone(), channels.len());
            channels.push(Channel {
                name: k.get_ref().clone(),
                bandwidth: bw.unwrap_or(1.0),
                overhead: oh.unwrap_or(0),
            });
        }

        // Tasks, first pass: names.
        let mut task_index: HashMap<String, usize> = HashMap::new();
        let raw_tasks = &raw.tasks.0;
        for (i, (k, _)) in raw_tasks.iter().enumerate() {
            self.check_name("task", k, "[tasks.gyro]");
            if task_index.insert(k.get_ref().clone(), i).is_some() {
                self.err(
                    format!("task `{}` is declared twice", k.get_ref()),
                    span(k),
                    "rename one of them",
                );
            }
        }
        if raw_tasks.is_empty() {
            self.err(
                "the spec declares no tasks",
                span(&raw.system),
                "add at least one [tasks.NAME] table with exec and period",
            );
        }
        let names: Vec<String> = raw_tasks.iter().map(|(k, _)| k.get_ref().clone()).collect();

        let mut tasks = Vec::new();
        for (k, v) in raw_tasks {
            tasks.push(self.task(k, v, &ch_index, &channels, &task_index, &names));
        }
        let mut tasks: Vec<Task> = tasks.into_iter().collect::<Option<Vec<_>>>()?;

        // PIBS priority inheritance: an I/O VCPU serves a Main VCPU on its CPU.
        for (i, (_, v)) in raw_tasks.iter().enumerate() {
            let Some(sv) = &v.get_ref().serves else {
                continue;
            };
            let Some(&m) = task_index.get(sv.get_ref()) else {
                self.unknown_task(sv, &names);
                continue;
            };
            let problem = if tasks[i].server != Server::Io {
                Some(format!(
                    "`serves` is for I/O VCPUs, but `{}` has server \"{}\"",
                    names[i],
                    tasks[i].server.name()
                ))
            } else if m == i {
                Some(format!("task `{}` cannot serve itself", names[i]))
            } else if tasks[m].server != Server::Main {
                Some(format!(
                    "`{}` serves `{}`, which is not a Main VCPU (server \"{}\")",
                    names[i],
                    names[m],
                    tasks[m].server.name()
                ))
            } else if tasks[m].cpu != tasks[i].cpu {
                Some(format!(
                    "`{}` (cpu {}) serves `{}` on another cpu ({})",
                    names[i], tasks[i].cpu, names[m], tasks[m].cpu
                ))
            } else {
                None
            };
            match problem {
                Some(msg) => self.err(
                    msg,
                    span(sv),
                    "an I/O VCPU (server = \"io\") may serve a Main VCPU (server = \"main\") on the same cpu",
                ),
                None => tasks[i].serves = Some(m),
            }
        }
        // Producers must write something for consumers to read.
        for (ci, (_, v)) in raw_tasks.iter().enumerate() {
            for r in &v.get_ref().reads {
                if let Some(&pi) = task_index.get(r.get_ref()) {
                    if tasks[pi].output.is_none() {
                        self.err(
                            format!("task `{}` reads `{}`, which has no output", names[ci], names[pi]),
                            span(r),
                            format!(
                                "give [tasks.{}] an output, e.g. output = {{ channel = \"mem\", size = 1 }}",
                                names[pi]
                            ),
                        );
                    }
                    if tasks[pi].server == Server::Background
                        || tasks[ci].server == Server::Background
                    {
                        // Allowed: background tasks may exchange data; they are just not analysable.
                    }
                }
            }
        }
        if !self.diags.is_empty() {
            return None;
        }
        let unit = self.unit();
        compute_transfers(&mut tasks, &channels, unit);
        // Budgets and periods against the demand.
        for (i, (_, v)) in raw_tasks.iter().enumerate() {
            let t = &tasks[i];
            let demand = t.demand();
            if demand > MAX_TIME {
                self.err(
                    format!("task `{}` has a demand too large to represent", t.name),
                    span(v),
                    "check sizes and bandwidths: transfers take size / bandwidth time units",
                );
                continue;
            }
            let rt = v.get_ref();
            if let (Some(c), Some(b)) = (t.budget_given, &rt.budget) {
                if c < demand {
                    self.err(
                        format!(
                            "budget {} of task `{}` is smaller than its demand Δin + p + Δout = {} + {} + {} = {}",
                            format_in(c, unit),
                            t.name,
                            format_in(t.delta_in, unit),
                            format_in(t.exec, unit),
                            format_in(t.delta_out, unit),
                            format_in(demand, unit)
                        ),
                        span(b),
                        format!(
                            "raise the budget to at least {} or remove it to use the demand (Section IV-B, Step 1)",
                            format_in(demand, unit)
                        ),
                    );
                }
            }
            if let (Some(p), Some(ps)) = (t.fixed_period(), &rt.period) {
                if t.server != Server::Background && t.budget() > p {
                    self.err(
                        format!(
                            "period {} of task `{}` is shorter than its budget {}",
                            format_in(p, unit),
                            t.name,
                            format_in(t.budget(), unit)
                        ),
                        span(ps),
                        format!(
                            "a pipe terminal needs T ≥ C: make the period at least {}",
                            format_in(t.budget(), unit)
                        ),
                    );
                }
            }
        }

        // Chains.
        let mut chains = Vec::new();
        for ch in &raw.chain {
            let c = ch.get_ref();
            if let Some(n) = &c.name {
                self.check_name("chain", n, "name = \"gyro to motors\"");
            }
            let mut path = Vec::new();
            let mut ok = true;
            if c.path.get_ref().is_empty() {
                self.err(
                    "chain path is empty",
                    span(&c.path),
                    "list at least one task, e.g. path = [\"t1\", \"t4\"]",
                );
                ok = false;
            }
            for n in c.path.get_ref() {
                match task_index.get(n.get_ref()) {
                    Some(&i) => path.push(i),
                    None => {
                        self.unknown_task(n, &names);
                        ok = false;
                    }
                }
            }
            if ok {
                for w in 0..path.len().saturating_sub(1) {
                    let (p, q) = (path[w], path[w + 1]);
                    if !tasks[q].reads.contains(&p) {
                        let n = &c.path.get_ref()[w + 1];
                        self.err(
                            format!(
                                "chain step `{}` → `{}` does not follow an edge: `{}` does not read `{}`",
                                names[p], names[q], names[q], names[p]
                            ),
                            span(n),
                            format!(
                                "add \"{}\" to reads of [tasks.{}], or fix the path",
                                names[p], names[q]
                            ),
                        );
                        ok = false;
                    }
                }
                for &i in &path {
                    if tasks[i].server == Server::Background {
                        self.err(
                            format!("chain passes through background task `{}`, which has no timing guarantee", names[i]),
                            span(&c.path),
                            "give the task a server (\"main\", \"io\" or \"none\") or drop it from the chain",
                        );
                        ok = false;
                    }
                }
            }
            let reaction = c
                .reaction
                .as_ref()
                .and_then(|v| self.positive_time(v, "reaction limit"));
            let freshness = c
                .freshness
                .as_ref()
                .and_then(|v| self.positive_time(v, "freshness limit"));
            if ok {
                chains.push(Chain {
                    name: c.name.as_ref().map(|n| n.get_ref().clone()),
                    path,
                    reaction,
                    freshness,
                });
            }
        }
        if !self.diags.is_empty() {
            return None;
        }
        let harmonic = sys.harmonic.as_ref().is_some_and(|h| *h.get_ref());
        if harmonic {
            self.check_harmonic(&tasks, raw_tasks);
            if !self.diags.is_empty() {
                return None;
            }
        }
        let resolution = match &sys.resolution {
            Some(r) => self.positive_time(r, "resolution")?,
            None => unit.nanos(),
        };
        Some(Spec {
            name,
            time_unit: unit,
            scheduler: scheduler?,
            schedulability: test?,
            resolution,
            harmonic,
            channels,
            tasks,
            chains,
        })
    }

    /// `harmonic = true`: every pair of fixed periods divides one way.
    fn check_harmonic(&mut self, tasks: &[Task], raw_tasks: &[(S<String>, S<RawTask>)]) {
        let unit = self.unit();
        for b in 0..tasks.len() {
            let Some(pb) = tasks[b].fixed_period() else {
                continue;
            };
            let clash = (0..b).find(|&a| {
                tasks[a]
                    .fixed_period()
                    .is_some_and(|pa| pa % pb != 0 && pb % pa != 0)
            });
            let (Some(a), Some(ps)) = (clash, &raw_tasks[b].1.get_ref().period) else {
                continue;
            };
            let pa = tasks[a].fixed_period().unwrap_or(1).max(1);
            let up = (pb + pa - 1) / pa * pa;
            self.err(
                format!(
                    "harmonic = true, but the fixed periods of `{}` ({}) and `{}` ({}) do not divide one another",
                    tasks[a].name,
                    format_in(pa, unit),
                    tasks[b].name,
                    format_in(pb, unit)
                ),
                span(ps),
                format!(
                    "make one period a multiple of the other (e.g. period = {} here), or drop harmonic = true",
                    format_in(up, unit)
                ),
            );
        }
    }

    fn unknown_task(&mut self, n: &S<String>, names: &[String]) {
        let help = match suggest(n.get_ref(), names.iter().map(|s| s.as_str())) {
            Some(s) => format!("did you mean `{s}`?"),
            None => format!(
                "declare [tasks.{}] or use one of: {}",
                n.get_ref(),
                names.join(", ")
            ),
        };
        self.err(format!("unknown task `{}`", n.get_ref()), span(n), help);
    }

    fn port(
        &mut self,
        p: &S<RawPort>,
        ch_index: &HashMap<String, usize>,
        channels: &[Channel],
    ) -> Option<Port> {
        let rp = p.get_ref();
        let ch = match ch_index.get(rp.channel.get_ref()) {
            Some(&c) => Some(c),
            None => {
                let help = match suggest(
                    rp.channel.get_ref(),
                    channels.iter().map(|c| c.name.as_str()),
                ) {
                    Some(s) => format!("did you mean \"{s}\"?"),
                    None => format!(
                        "declare it: [channels.{}] with bandwidth and overhead",
                        rp.channel.get_ref()
                    ),
                };
                self.err(
                    format!("unknown channel \"{}\"", rp.channel.get_ref()),
                    span(&rp.channel),
                    help,
                );
                None
            }
        };
        let size = self.number(&rp.size, "size", false);
        Some(Port {
            channel: ch?,
            size: size?,
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn task(
        &mut self,
        k: &S<String>,
        v: &S<RawTask>,
        ch_index: &HashMap<String, usize>,
        channels: &[Channel],
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) -> Option<Task> {
        let t = v.get_ref();
        let exec = self.positive_time(&t.exec, "exec");
        let exec_min = match &t.exec_min {
            Some(e) => self.nonneg_time(e, "exec_min"),
            None => Some(0),
        };
        if let (Some(a), Some(b), Some(es)) = (exec_min, exec, &t.exec_min) {
            if a > b {
                self.err(
                    format!(
                        "exec_min {} is larger than exec {}",
                        format_in(a, self.unit()),
                        format_in(b, self.unit())
                    ),
                    span(es),
                    "exec_min is the best-case processing time: make it at most exec",
                );
            }
        }
        let input = match &t.input {
            Some(p) => self.port(p, ch_index, channels).map(Some),
            None => Some(None),
        };
        let output = match &t.output {
            Some(p) => self.port(p, ch_index, channels).map(Some),
            None => Some(None),
        };
        let mut reads = Vec::new();
        let mut reads_ok = true;
        for r in &t.reads {
            match task_index.get(r.get_ref()) {
                Some(&i) => {
                    if reads.contains(&i) {
                        self.err(
                            format!("`{}` appears twice in reads", r.get_ref()),
                            span(r),
                            "list each producer once",
                        );
                        reads_ok = false;
                    }
                    reads.push(i)
                }
                None => {
                    self.unknown_task(r, names);
                    reads_ok = false;
                }
            }
        }
        let period = match &t.period {
            Some(p) => self.period(p),
            None => Some(PeriodSpec::Free),
        };
        let budget = match &t.budget {
            Some(b) => self.positive_time(b, "budget").map(Some),
            None => Some(None),
        };
        let server = match &t.server {
            Some(s) => self.choice(
                s,
                "server",
                &[
                    ("main", Server::Main),
                    ("io", Server::Io),
                    ("none", Server::None),
                    ("background", Server::Background),
                ],
            ),
            None => Some(Server::Main),
        };
        let cpu = match &t.cpu {
            Some(c) => match c.get_ref() {
                toml::Value::Integer(i) if (0..=1023).contains(i) => Some(*i as u32),
                _ => {
                    self.err(
                        "cpu must be an integer from 0 to 1023",
                        span(c),
                        "write the core index, e.g. cpu = 0",
                    );
                    None
                }
            },
            None => Some(0),
        };
        if !reads_ok {
            return None;
        }
        Some(Task {
            name: k.get_ref().clone(),
            exec: exec?,
            exec_min: exec_min?,
            input: input?,
            output: output?,
            reads,
            period: period?,
            budget_given: budget?,
            server: server?,
            cpu: cpu?,
            serves: None,
            body: v.get_ref().body.as_ref().map(|b| b.get_ref().clone()),
            delta_in: 0,
            delta_out: 0,
        })
    }

    fn period(&mut self, p: &S<toml::Value>) -> Option<PeriodSpec> {
        match p.get_ref() {
            toml::Value::Table(t) => {
                let mut min = None;
                let mut max = None;
                let mut choices = None;
                for (key, val) in t {
                    // Inner values have no spans of their own; point at the table.
                    let sv = S::new(p.span(), val.clone());
                    match key.as_str() {
                        "min" => min = Some(self.positive_time(&sv, "period min")?),
                        "max" => max = Some(self.positive_time(&sv, "period max")?),
                        "choices" => {
                            let arr = match val {
                                toml::Value::Array(a) if !a.is_empty() => a,
                                _ => {
                                    self.err(
                                        "period choices must be a non-empty list of times",
                                        Some(p.span()),
                                        "write e.g. period = { choices = [\"1ms\", \"2ms\"] }",
                                    );
                                    return None;
                                }
                            };
                            let mut out = Vec::new();
                            for x in arr {
                                out.push(self.positive_time(
                                    &S::new(p.span(), x.clone()),
                                    "period choice",
                                )?);
                            }
                            out.sort_unstable();
                            out.dedup();
                            choices = Some(out);
                        }
                        other => {
                            self.err(
                                format!("unknown key `{other}` in period"),
                                Some(p.span()),
                                "a period is a time, { min = .., max = .. } or { choices = [..] }",
                            );
                            return None;
                        }
                    }
                }
                if let Some(c) = choices {
                    if min.is_some() || max.is_some() {
                        self.err(
                            "period has both choices and min/max",
                            Some(p.span()),
                            "use either choices or a min/max range",
                        );
                        return None;
                    }
                    return Some(PeriodSpec::Choices(c));
                }
                if let (Some(a), Some(b)) = (min, max) {
                    if a > b {
                        self.err(
                            "period min is larger than max",
                            Some(p.span()),
                            "swap min and max",
                        );
                        return None;
                    }
                }
                Some(PeriodSpec::Range { min, max })
            }
            _ => self.positive_time(p, "period").map(PeriodSpec::Fixed),
        }
    }
}

#[cfg(test)]
mod tests;
