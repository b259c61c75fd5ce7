//! Validation: from the raw TOML tables to a [`Spec`], every problem a
//! diagnostic with its place and a fix. [`Builder::build`] runs the steps in
//! order: the system, channels, task names, tasks, inheritance, producers,
//! transfers, budgets and periods, chains, harmonic periods.

use crate::raw::{RawChain, RawChannel, RawSpec, RawSystem, RawTask, S};
use crate::*;
use std::collections::HashMap;
use std::ops::Range;

mod body;
mod comm;
mod events;
mod overheads;
mod prio;
mod resources;
mod task;

/// What a task's keys are resolved against: the channels, the tasks and
/// the threads, by name.
struct Known<'a> {
    ch_index: &'a HashMap<String, usize>,
    channels: &'a [Channel],
    task_index: &'a HashMap<String, usize>,
    names: &'a [String],
    thread_index: &'a HashMap<String, usize>,
}

#[derive(Default)]
pub(crate) struct Builder {
    pub(crate) diags: Vec<Diagnostic>,
    unit: Option<TimeUnit>,
}

/// The bound on plain numbers (sizes, bandwidths): far beyond any real
/// one, and small enough that transfer times stay exact in f64.
pub(crate) const MAX_NUMBER: f64 = 1e15;

pub(crate) fn span<T>(s: &S<T>) -> Option<Range<usize>> {
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
        } else if let Some(p) = crate::input::name_problem(s) {
            Some(format!(
                "{kind} name \"{}\" {p}",
                crate::input::shown_name(s)
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

    /// A plain number (sizes, bandwidths), below [`MAX_NUMBER`].
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
        let ok = x.is_finite() && x < MAX_NUMBER && if positive { x > 0.0 } else { x >= 0.0 };
        if !ok {
            let low = if positive { "> 0" } else { ">= 0" };
            self.err(
                format!("{what} must be {low} and below {MAX_NUMBER:e}, found {x:e}"),
                span(v),
                format!("give {what} a value {low} and < {MAX_NUMBER:e}"),
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

    /// Validates a parsed spec; every problem becomes a diagnostic, and the
    /// spec is returned only when there is none.
    pub(crate) fn build(&mut self, raw: RawSpec) -> Option<Spec> {
        let sys = raw.system.get_ref();
        let (name, scheduler, test) = self.system(sys);
        let order = self.priority_order(sys, scheduler);
        let (channels, ch_index) = self.channels(&raw.channels.0);
        let raw_tasks = &raw.tasks.0;
        let (task_index, names) = self.task_names(raw_tasks, &raw.system);
        let (threads, thread_index) = self.threads(&raw.threads);
        let known = Known {
            ch_index: &ch_index,
            channels: &channels,
            task_index: &task_index,
            names: &names,
            thread_index: &thread_index,
        };
        let (mut tasks, threads) = self.tasks_and_threads(&raw, &known, threads)?;
        self.events(&raw, &threads, &mut tasks, order, scheduler);
        if !self.diags.is_empty() {
            return None;
        }
        let unit = self.unit();
        compute_transfers(&mut tasks, &channels, unit);
        self.budgets_and_periods(raw_tasks, &tasks);
        self.priorities_and_deadlines(raw_tasks, &tasks, order, scheduler);
        let communication = self.communication(sys);
        let (resource_protocol, resources) =
            self.resources(sys, &raw.resources.0, raw_tasks, &mut tasks, scheduler);
        let test = scheduler
            .zip(test)
            .map(|(s, t)| self.test_for_tasks(sys, s, t, order, &tasks));
        let overheads = self.overheads(sys, raw_tasks, &tasks, scheduler, resource_protocol, test);
        let chains: Vec<Chain> = raw
            .chain
            .iter()
            .filter_map(|ch| self.chain(ch.get_ref(), &tasks, &task_index, &names))
            .collect();
        if !self.diags.is_empty() {
            return None;
        }
        self.task_semantics(&raw.chain, &chains, communication, raw_tasks, &tasks);
        let communications = task_communications(&chains, communication, tasks.len());
        self.no_let_on_triggered(raw_tasks, &tasks, &communications);
        if !self.diags.is_empty() {
            return None;
        }
        let harmonic = sys.harmonic.as_ref().is_some_and(|h| *h.get_ref());
        if harmonic && !self.check_harmonic(&tasks, raw_tasks) {
            return None;
        }
        let resolution = self.resolution(sys)?;
        Some(Spec {
            name,
            time_unit: unit,
            scheduler: scheduler?,
            schedulability: test?,
            resolution,
            harmonic,
            priorities: order,
            communication,
            resource_protocol,
            resources,
            overheads,
            channels,
            threads,
            tasks,
            chains,
        })
    }

    /// Every task from its keys, then what a task needs of the others
    /// (synchronous offsets, the Main VCPU an I/O VCPU serves, producers
    /// that write); `None` when a task or thread had an error.
    fn tasks_and_threads(
        &mut self,
        raw: &RawSpec,
        known: &Known,
        threads: Vec<Option<Thread>>,
    ) -> Option<(Vec<Task>, Vec<Thread>)> {
        let raw_tasks = &raw.tasks.0;
        let tasks: Vec<Option<Task>> = raw_tasks
            .iter()
            .map(|(k, v)| self.task(k, v, known))
            .collect();
        let mut tasks: Vec<Task> = tasks.into_iter().collect::<Option<Vec<_>>>()?;
        let threads: Vec<Thread> = threads.into_iter().collect::<Option<Vec<_>>>()?;
        if self.synchronous(raw.system.get_ref()) {
            for t in tasks
                .iter_mut()
                .filter(|t| t.offset.is_none() && !t.is_triggered())
            {
                t.offset = Some(0);
            }
        }
        self.serves(raw_tasks, &mut tasks, known.task_index, known.names);
        self.producers_write(raw_tasks, &tasks, known.task_index, known.names);
        Some((tasks, threads))
    }

    /// `resolution`: positive, one time unit by default.
    fn resolution(&mut self, sys: &RawSystem) -> Option<Nanos> {
        match &sys.resolution {
            Some(r) => self.positive_time(r, "resolution"),
            None => Some(self.unit().nanos()),
        }
    }

    /// `release = "synchronous"`: every task without its own `offset` is
    /// released at 0; `"arbitrary"` (the default) leaves them unknown.
    fn synchronous(&mut self, sys: &RawSystem) -> bool {
        match &sys.release {
            Some(r) => self
                .choice(r, "release", &[("synchronous", true), ("arbitrary", false)])
                .unwrap_or(false),
            None => false,
        }
    }

    /// `[system]`: the name, the time unit (set on `self`), the scheduler
    /// and the schedulability test, which must fit the scheduler.
    fn system(&mut self, sys: &RawSystem) -> (String, Option<Scheduler>, Option<SchedTest>) {
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
        self.time_unit(sys);
        let schedulers = Scheduler::ALL.map(|s| (s.name(), s));
        let scheduler = match &sys.scheduler {
            Some(s) => self.choice(s, "scheduler", &schedulers),
            None => Some(Scheduler::Rm),
        };
        let tests = SchedTest::ALL.map(|t| (t.name(), t));
        let test = match &sys.schedulability {
            Some(s) => self.choice(s, "schedulability test", &tests),
            None => scheduler.map(|s| s.policy().default_test()),
        };
        if let (Some(s), Some(t), Some(sp)) = (scheduler, test, &sys.schedulability) {
            if !s.policy().admits(t) {
                let help = s.policy().tests_help;
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
        (name, scheduler, test)
    }

    /// `time_unit` (ms by default), set on `self` for every time after it.
    fn time_unit(&mut self, sys: &RawSystem) {
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
    }

    /// `[channels.*]`, and their index by name.
    fn channels(
        &mut self,
        raw: &[(S<String>, S<RawChannel>)],
    ) -> (Vec<Channel>, HashMap<String, usize>) {
        let mut channels = Vec::new();
        let mut ch_index: HashMap<String, usize> = HashMap::new();
        for (k, v) in raw {
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
        (channels, ch_index)
    }

    /// Tasks, first pass: their names (unique, valid) and index.
    fn task_names(
        &mut self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        system: &S<RawSystem>,
    ) -> (HashMap<String, usize>, Vec<String>) {
        let mut task_index: HashMap<String, usize> = HashMap::new();
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
                span(system),
                "add at least one [tasks.NAME] table with exec and period",
            );
        }
        let names: Vec<String> = raw_tasks.iter().map(|(k, _)| k.get_ref().clone()).collect();
        (task_index, names)
    }

    /// PIBS priority inheritance: an I/O VCPU serves a Main VCPU on its CPU.
    fn serves(
        &mut self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &mut [Task],
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) {
        for (i, (_, v)) in raw_tasks.iter().enumerate() {
            let Some(sv) = &v.get_ref().serves else {
                continue;
            };
            let Some(&m) = task_index.get(sv.get_ref()) else {
                self.unknown_task(sv, names);
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
    }

    /// Producers must write something for consumers to read.
    fn producers_write(
        &mut self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) {
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
    }

    /// Budgets and periods against the demand (Δin + p + Δout, known once
    /// the transfers are).
    fn budgets_and_periods(&mut self, raw_tasks: &[(S<String>, S<RawTask>)], tasks: &[Task]) {
        let unit = self.unit();
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
            self.check_offset(t, rt);
        }
    }

    /// An offset must be below every period the task can have: a task that
    /// starts a period or more late has no job in its first periods, and the
    /// any-phasing bounds assume one release per period from the start.
    fn check_offset(&mut self, t: &Task, rt: &RawTask) {
        let (Some(x), Some(os)) = (t.offset, &rt.offset) else {
            return;
        };
        let (least, what) = match &t.period {
            PeriodSpec::Fixed(p) => (*p, "its period"),
            PeriodSpec::Range { min: Some(m), .. } => (*m, "the least period of its range"),
            PeriodSpec::Choices(c) => (
                c.iter().copied().min().unwrap_or(0),
                "its shortest period choice",
            ),
            // The design never picks a period below the budget.
            _ => (
                t.budget(),
                "its budget, the least period the design may pick",
            ),
        };
        if x >= least {
            let unit = self.unit();
            self.err(
                format!(
                    "offset {} of task `{}` is not below {what} ({})",
                    format_in(x, unit),
                    t.name,
                    format_in(least, unit)
                ),
                span(os),
                format!(
                    "make the offset less than {} (e.g. offset = {}); a task released a period or more late has no job in its first periods, which the analysis does not model",
                    format_in(least, unit),
                    format_in(x % least.max(1), unit)
                ),
            );
        }
    }

    /// One `[[chain]]`: a path along edges, through no background task, and
    /// its limits; `None` (with diagnostics) when the path is not valid.
    fn chain(
        &mut self,
        c: &RawChain,
        tasks: &[Task],
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) -> Option<Chain> {
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
                    self.unknown_task(n, names);
                    ok = false;
                }
            }
        }
        if ok {
            ok = self.path_is_timed(c, &path, tasks, names);
        }
        let reaction = c
            .reaction
            .as_ref()
            .and_then(|v| self.positive_time(v, "reaction limit"));
        let freshness = c
            .freshness
            .as_ref()
            .and_then(|v| self.positive_time(v, "freshness limit"));
        let max_reaction_time = c
            .max_reaction_time
            .as_ref()
            .and_then(|v| self.positive_time(v, "max_reaction_time"));
        let freshness_from_event = c
            .freshness_from_event
            .as_ref()
            .and_then(|v| self.positive_time(v, "freshness_from_event"));
        if let Some(v) = &c.max_data_age {
            self.renamed_max_data_age(v);
        }
        let communication = self.chain_communication(c);
        ok.then(|| Chain {
            name: c.name.as_ref().map(|n| n.get_ref().clone()),
            path,
            reaction,
            freshness,
            max_reaction_time,
            freshness_from_event,
            communication,
        })
    }

    /// `max_data_age` limited freshness from the event, which is not the
    /// literature's maximum data age (that runs to the tail's next output
    /// and equals the maximum reaction time): refused, so that no spec
    /// keeps a limit under a name that says another quantity.
    fn renamed_max_data_age(&mut self, v: &S<toml::Value>) {
        self.err(
            "`max_data_age` is now `freshness_from_event`: it limits freshness from the event \
             (to a sample's last output), not the literature's maximum data age (to the next \
             output, equal to the maximum reaction time)",
            span(v),
            "rename the key to `freshness_from_event`; to limit the literature's maximum data \
             age, use `max_reaction_time`",
        );
    }

    /// A chain's path follows edges (each task reads the one before) and
    /// passes through no background task.
    fn path_is_timed(
        &mut self,
        c: &RawChain,
        path: &[usize],
        tasks: &[Task],
        names: &[String],
    ) -> bool {
        let mut ok = true;
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
        for &i in path {
            if tasks[i].server == Server::Background {
                self.err(
                    format!("chain passes through background task `{}`, which has no timing guarantee", names[i]),
                    span(&c.path),
                    "give the task a server (\"main\", \"io\" or \"none\") or drop it from the chain",
                );
                ok = false;
            }
        }
        ok
    }

    /// `harmonic = true`: every pair of fixed periods divides one way.
    /// Whether the fixed periods are harmonic (a diagnostic per clash).
    fn check_harmonic(&mut self, tasks: &[Task], raw_tasks: &[(S<String>, S<RawTask>)]) -> bool {
        let unit = self.unit();
        let before = self.diags.len();
        for b in 0..tasks.len() {
            let Some(pb) = tasks[b].fixed_period() else {
                continue;
            };
            let clash = (0..b).find(|&a| {
                tasks[a]
                    .fixed_period()
                    .is_some_and(|pa| !crate::time::harmonic_pair(pa, pb))
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
        self.diags.len() == before
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
}
