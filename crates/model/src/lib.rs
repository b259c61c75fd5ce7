//! # rtpipe-model
//!
//! The spec of a pipe system (Cheng, West, Einstein, EMSOFT 2018, Section III-C):
//! tasks `τ = (d_i, p, d_o)` mapped 1:1 to pipes `π = ((W_i, δ_i), (C, T), (W_o, δ_o))`,
//! the channels their ends use, and the chains whose end-to-end times matter.
//!
//! [`Spec::parse`] turns TOML into a validated [`Spec`] or a [`SpecError`] that
//! names file, line and column of every problem and how to fix it. It never
//! panics, whatever the input.
#![deny(missing_docs)]

pub mod bracket;
mod cpus;
mod error;
pub mod gen;
pub mod import;
pub mod input;
pub mod output;
pub mod overheads;
pub mod policy;
mod raw;
pub mod time;
mod validate;
mod write;
pub use write::to_toml;

pub use cpus::TasksByCpu;
pub use error::{line_col, printable, suggest, Diagnostic, SpecError};
pub use overheads::Overheads;
pub use policy::{Communication, Priorities, ResourceProtocol, SchedPolicy, SchedTest, Scheduler};
pub use time::{format_in, gcd, harmonic_pair, parse_time_str, Nanos, TimeUnit, MAX_TIME};

/// The largest spec file `Spec::load` reads: 16 MiB (every TOML input's
/// cap, [`input::MAX_INPUT_BYTES`]).
pub const MAX_SPEC_BYTES: u64 = input::MAX_INPUT_BYTES;

/// The task bodies a spec's `body` may name: the flight controller's tasks
/// (crate `flight`'s `BodyKind`, whose names these are, in its order). They
/// live here so that the spec's validation refuses a misspelling at its key.
pub const BODY_NAMES: [&str; 13] = [
    "gyro",
    "accel",
    "ahrs",
    "radio",
    "pid",
    "pwm",
    "system_load",
    "battery_voltage",
    "battery_current",
    "battery_alert",
    "gyro_filter",
    "attitude",
    "rate_pid",
];

use raw::RawSpec;
use std::collections::BTreeMap;
use validate::Builder;

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
    /// The name used in specs and output.
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
    /// Its name in the spec.
    pub name: String,
    /// W: data units per time unit of the spec.
    pub bandwidth: f64,
    /// δ: software overhead per transfer.
    pub overhead: Nanos,
}

/// Data moved over one channel by one transfer.
#[derive(Debug, Clone, PartialEq)]
pub struct Port {
    /// The channel (index into `Spec::channels`).
    pub channel: usize,
    /// Data units moved per transfer (the channel's bandwidth is per time unit).
    pub size: f64,
}

/// Where the period of a task comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PeriodSpec {
    /// A fixed period.
    Fixed(Nanos),
    /// A design variable in [min, max] (either end may be open).
    Range {
        /// Lower end.
        min: Option<Nanos>,
        /// Upper end.
        max: Option<Nanos>,
    },
    /// A design variable taking one of these values.
    Choices(Vec<Nanos>),
    /// Not given: a design variable without bounds.
    Free,
    /// No period: a data-triggered task (`activation = "data"`), released
    /// by publications of its triggers, not by a timer.
    Triggered {
        /// The producers whose publications release it (indices into
        /// `Spec::tasks`, each one of its `reads`), in declaration order.
        triggers: Vec<usize>,
        /// How the triggers combine.
        join: Join,
    },
}

/// How the publications of a data-triggered task's triggers release it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Join {
    /// A publication of any trigger releases a job (`join = "any"`, the
    /// default).
    #[default]
    Any,
    /// A job is released once every trigger has published since the last
    /// release (`join = "all"`: fusion of several inputs).
    All,
}

impl Join {
    /// Every join, in the order specs list them.
    pub const ALL: [Join; 2] = [Join::Any, Join::All];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        match self {
            Join::Any => "any",
            Join::All => "all",
        }
    }
}

/// A work-queue thread (`[threads.NAME]`, PX4's `wq:rate_ctrl`): one job
/// at a time on one CPU, its tasks' jobs run to completion in the order
/// they were released (jobs released at the same instant in declaration
/// order); threads and thread-less tasks preempt each other by priority.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Thread {
    /// Its name in the spec.
    pub name: String,
    /// Its fixed priority on its CPU, 1 the highest (shared in one order
    /// with the thread-less tasks of that CPU).
    pub priority: u32,
    /// The CPU it runs on.
    pub cpu: u32,
}

/// A task (one pipe, Section III-C), validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// Its name in the spec.
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
    /// Where its period comes from.
    pub period: PeriodSpec,
    /// C. `None` = Step 1 of Section IV-B: C = Δin + p + Δout.
    pub budget_given: Option<Nanos>,
    /// The server that provides its budget.
    pub server: Server,
    /// The CPU it runs on.
    pub cpu: u32,
    /// I/O VCPUs only: the Main VCPU this one serves. While that task has a
    /// job pending, the I/O VCPU inherits its priority (PIBS, Section II-B).
    pub serves: Option<usize>,
    /// The task code that runs its jobs (`rtpipe fly`), by name: one of
    /// [`BODY_NAMES`]; the timing analysis does not use it.
    pub body: Option<String>,
    /// Release offset: the first job is released at this instant and every
    /// later one a period after the previous. `None`: unknown (the analysis
    /// then holds for every phasing).
    pub offset: Option<Nanos>,
    /// Explicit fixed priority (`priorities = "explicit"`): 1 is the
    /// highest; `None` under the other priority orders.
    pub priority: Option<u32>,
    /// D, the relative deadline, when given (at most the period); `None`:
    /// D = T (implicit deadline). See [`Task::deadline`].
    pub deadline_given: Option<Nanos>,
    /// J, release jitter: each job is released somewhere in
    /// [nominal, nominal + J], nominal = offset + k·T (0: none).
    pub jitter: Nanos,
    /// The longest period control tolerates (`max_period`: a minimum
    /// actuation or sampling rate); a fixed period above it fails the
    /// verdict and the design keeps a free period at or under it.
    pub max_period: Option<Nanos>,
    /// Its critical sections, in the order a job runs them: back to back,
    /// not nested, the first starting when the job's processing does (after
    /// Δin). A job whose processing time is shorter than the sections
    /// runs them cut to its length.
    pub sections: Vec<CriticalSection>,
    /// The work-queue thread that runs its jobs (index into
    /// `Spec::threads`); `None`: the task is a thread of its own. A task in
    /// a thread has the thread's CPU and priority and no server.
    pub thread: Option<usize>,
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
            offset: None,
            priority: None,
            deadline_given: None,
            jitter: 0,
            max_period: None,
            sections: Vec::new(),
            thread: None,
            delta_in: 0,
            delta_out: 0,
        }
    }

    /// The producers whose publications release it and how they join, for
    /// a data-triggered task; `None` for a periodic one.
    pub fn triggers(&self) -> Option<(&[usize], Join)> {
        match &self.period {
            PeriodSpec::Triggered { triggers, join } => Some((triggers, *join)),
            _ => None,
        }
    }

    /// Released by data (`activation = "data"`), not by a timer.
    pub fn is_triggered(&self) -> bool {
        self.triggers().is_some()
    }

    /// Does a release of this task merge into its job that is queued and
    /// not yet started (PX4's one pending activation)? For a task in a
    /// thread and a data-triggered task; a thread-less periodic task queues
    /// every job.
    pub fn merges_releases(&self) -> bool {
        self.thread.is_some() || self.is_triggered()
    }

    /// Worst-case demand of one job: Δin + p + Δout.
    #[inline]
    pub fn demand(&self) -> Nanos {
        self.delta_in
            .saturating_add(self.exec)
            .saturating_add(self.delta_out)
    }
    /// Best-case demand of one job: Δin + p_min + Δout.
    #[inline]
    pub fn demand_min(&self) -> Nanos {
        self.delta_in
            .saturating_add(self.exec_min)
            .saturating_add(self.delta_out)
    }
    /// C: the given budget or the demand (Section IV-B, Step 1).
    #[inline]
    pub fn budget(&self) -> Nanos {
        self.budget_given.unwrap_or_else(|| self.demand())
    }
    /// D: the given deadline, else the fixed period (implicit deadline).
    #[inline]
    pub fn deadline(&self) -> Option<Nanos> {
        self.deadline_given.or_else(|| self.fixed_period())
    }
    /// T, when fixed.
    pub fn fixed_period(&self) -> Option<Nanos> {
        match self.period {
            PeriodSpec::Fixed(t) => Some(t),
            _ => None,
        }
    }
}

/// A shared resource (`[resources.NAME]`), locked by the critical sections
/// of the tasks of one CPU.
#[derive(Debug, Clone, PartialEq)]
pub struct Resource {
    /// Its name in the spec.
    pub name: String,
}

/// One critical section of a task: `length` of its processing time spent
/// holding `resource`.
#[derive(Debug, Clone, PartialEq)]
pub struct CriticalSection {
    /// The resource (index into `Spec::resources`).
    pub resource: usize,
    /// How long the job holds it (at most the task's `exec`).
    pub length: Nanos,
}

/// A path along edges (producer → consumer) with optional limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    /// Its name, when the spec gives one.
    pub name: Option<String>,
    /// Task indices, head first.
    pub path: Vec<usize>,
    /// Limit on the reaction time.
    pub reaction: Option<Nanos>,
    /// Limit on the freshness time.
    pub freshness: Option<Nanos>,
    /// Limit on the reaction time from the event (`max_reaction_time`: the
    /// maximum reaction time of Dürr et al. 2019 and Günzel et al., which
    /// Günzel et al. 2023 prove equal to the maximum data age).
    pub max_reaction_time: Option<Nanos>,
    /// Limit on the freshness time from the event (`freshness_from_event`:
    /// from just after the head read before a sample's to its last output;
    /// no quantity of the literature; the key was `max_data_age`).
    pub freshness_from_event: Option<Nanos>,
    /// Its own communication semantics (`communication` in `[[chain]]`);
    /// `None`: the system's. Every task on the chain reads and publishes
    /// that way ([`Spec::communications`]).
    pub communication: Option<Communication>,
}

impl Chain {
    /// An unnamed chain along `path` without limits, each task on it made to
    /// read its predecessor: how generated and imported systems get their
    /// edges from their chains.
    pub fn linked(tasks: &mut [Task], path: Vec<usize>) -> Chain {
        for w in path.windows(2) {
            if !tasks[w[1]].reads.contains(&w[0]) {
                tasks[w[1]].reads.push(w[0]);
            }
        }
        Chain {
            name: None,
            path,
            reaction: None,
            freshness: None,
            max_reaction_time: None,
            freshness_from_event: None,
            communication: None,
        }
    }
}

/// A validated system.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// The system's name.
    pub name: String,
    /// The unit of bare numbers in the spec (and of the output).
    pub time_unit: TimeUnit,
    /// The scheduler of every CPU.
    pub scheduler: Scheduler,
    /// The schedulability test applied.
    pub schedulability: SchedTest,
    /// Design: periods are integer multiples of this (default 1 time unit).
    pub resolution: Nanos,
    /// Design: every pair of periods divides one another.
    pub harmonic: bool,
    /// How fixed priorities are assigned (rate monotonic by default).
    pub priorities: Priorities,
    /// When jobs read and publish (implicit by default; LET): the tasks on
    /// no chain with its own `communication`, and the chains without one
    /// ([`Spec::communications`]).
    pub communication: Communication,
    /// How the tasks of a CPU share resources (`[system]
    /// resource_protocol`, PCP by default).
    pub resource_protocol: ResourceProtocol,
    /// The shared resources, in declaration order.
    pub resources: Vec<Resource>,
    /// Context switch, release and replenishment costs per CPU (`[system]
    /// overheads`; none by default).
    pub overheads: Overheads,
    /// The channels, in declaration order.
    pub channels: Vec<Channel>,
    /// The work-queue threads (`[threads.NAME]`), in declaration order.
    pub threads: Vec<Thread>,
    /// The tasks, in declaration order.
    pub tasks: Vec<Task>,
    /// The declared chains.
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
    /// files, and anything but a regular file (a pipe, `/dev/zero`), are
    /// refused (the rules of every input file: [`input`]).
    pub fn load(path: &std::path::Path) -> Result<Spec, SpecError> {
        let text = input::read_text(path, &input::Kind::SPEC)?;
        Spec::parse(&path.display().to_string(), &text)
    }

    /// Each task's communication semantics: that of the chains it is on
    /// (validation refuses a task on chains of different semantics), the
    /// system's for a task on no chain with its own.
    pub fn communications(&self) -> Vec<Communication> {
        task_communications(&self.chains, self.communication, self.tasks.len())
    }

    /// Task `i`'s communication semantics ([`Spec::communications`]).
    pub fn task_communication(&self, i: usize) -> Communication {
        self.chains
            .iter()
            .filter(|ch| ch.path.contains(&i))
            .find_map(|ch| ch.communication)
            .unwrap_or(self.communication)
    }

    /// Does some task communicate under LET?
    pub fn any_let(&self) -> bool {
        self.communications().contains(&Communication::Let)
    }
    /// The first rule between task `i`'s exec, budget and fixed period
    /// that its timing breaks, by the key a user would change: "budget"
    /// (a given budget below the demand Δin + p + Δout), "period" (below
    /// the budget), "offset" (not below the period), "deadline" (above
    /// the period, or below it under a test that needs D = T), "jitter"
    /// (not below the period). Validation refuses a spec that breaks one
    /// with a diagnostic at its key; this is the same test for a validated
    /// spec whose exec or period a caller changed (the analysis' margins).
    pub fn timing_conflict(&self, i: usize) -> Option<&'static str> {
        let t = &self.tasks[i];
        if t.budget_given.is_some_and(|c| c < t.demand()) {
            return Some("budget");
        }
        let p = t.fixed_period()?;
        let d = t.deadline_given;
        if t.server != Server::Background && t.budget() > p {
            Some("period")
        } else if t.offset.is_some_and(|x| x >= p) {
            Some("offset")
        } else if d
            .is_some_and(|d| d > p || (d < p && self.schedulability.needs_implicit_deadlines()))
        {
            Some("deadline")
        } else if t.jitter > 0 && t.jitter >= p {
            Some("jitter")
        } else {
            None
        }
    }

    /// Has the spec threads or data-triggered tasks (the event-triggered
    /// model of docs/analysis.md), or only periodic tasks each on a thread
    /// of its own (the paper's)?
    pub fn event_triggered(&self) -> bool {
        !self.threads.is_empty() || self.tasks.iter().any(Task::is_triggered)
    }

    /// The tasks each data-triggered task's publications release: per
    /// task, the data-triggered consumers that name it a trigger.
    pub fn triggered_by(&self) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); self.tasks.len()];
        for (c, t) in self.tasks.iter().enumerate() {
            if let Some((triggers, _)) = t.triggers() {
                for &p in triggers {
                    out[p].push(c);
                }
            }
        }
        out
    }

    /// The nominal distance between task `i`'s releases: its fixed period,
    /// or for a data-triggered task its triggers' (with `join = "any"` the
    /// fastest trigger's, which releases it at least that often; with
    /// `"all"` the slowest's, which it waits for). `None` where a period
    /// on the way is not fixed. A rate for what needs one (a controller's
    /// sample time, the paper's terms); the analysis bounds the actual
    /// releases with event models, not with this.
    pub fn activation_period(&self, i: usize) -> Option<Nanos> {
        self.activation_period_with(i, &|j| self.tasks[j].fixed_period())
    }

    /// [`Spec::activation_period`] with the periodic tasks' periods given
    /// by `period` (task index → period) instead of the spec's: the rate
    /// a data-triggered task inherits at periods under consideration (the
    /// design's boxes). Never smaller when a period grows (min and max
    /// of the triggers').
    pub fn activation_period_with(
        &self,
        i: usize,
        period: &impl Fn(usize) -> Option<Nanos>,
    ) -> Option<Nanos> {
        let t = self.tasks.get(i)?;
        let Some((triggers, join)) = t.triggers() else {
            return period(i);
        };
        // Validation makes the trigger graph acyclic, so this ends.
        let periods = triggers
            .iter()
            .map(|&p| self.activation_period_with(p, period));
        let periods: Option<Vec<Nanos>> = periods.collect();
        match join {
            Join::Any => periods?.into_iter().min(),
            Join::All => periods?.into_iter().max(),
        }
    }

    /// The index of the task called `name`.
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

/// Each of `n` tasks' communication semantics: that of the chains it is
/// on, else the system's ([`Spec::communications`]; validation asks it
/// before the spec exists).
fn task_communications(chains: &[Chain], system: Communication, n: usize) -> Vec<Communication> {
    let mut out = vec![system; n];
    // The first chain with a key wins, as in `task_communication` (a
    // spec built in code may disagree with itself; a parsed one cannot).
    for ch in chains.iter().rev() {
        if let Some(c) = ch.communication {
            for &i in &ch.path {
                out[i] = c;
            }
        }
    }
    out
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
        Some("add the missing key (see the spec format, docs/reference/spec.md)".into())
    } else if msg.contains("too large to fit") {
        Some("whole numbers must fit in 64 bits; times are limited to about 104 days: write a smaller value, or a time with a unit such as \"250us\"".into())
    } else if msg.contains("invalid type") {
        Some("times are numbers in the system's time_unit or strings like \"250us\"".into())
    } else {
        None
    }
}

#[cfg(test)]
mod tests;
