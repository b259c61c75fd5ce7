//! Validation of the event-triggered model: `[threads.NAME]`
//! and per task `thread`, `activation`, `triggers` and `join`. A task's
//! activation is parsed with its other keys ([`Builder::activation`]); the
//! rules between tasks, threads, the priority order and the scheduler run
//! once the tasks are built ([`Builder::events`]).

use super::{span, Builder};
use crate::policy::Priorities;
use crate::raw::{Ordered, RawSpec, RawSystem, RawTask, RawThread, S};
use crate::*;
use std::collections::HashMap;

/// How to write a data-triggered task, for the helps below.
const TRIGGER_HELP: &str = "a data-triggered task is released by publications of the tasks in its `triggers` (default: all of its `reads`)";

impl Builder {
    /// `[threads.NAME]`: name, `priority` (required: checked with the
    /// priority order in [`Builder::events`]) and `cpu` (0 by default).
    pub(super) fn threads(
        &mut self,
        raw: &Ordered<RawThread>,
    ) -> (Vec<Option<Thread>>, HashMap<String, usize>) {
        let mut index = HashMap::new();
        let mut threads = Vec::new();
        for (i, (k, v)) in raw.0.iter().enumerate() {
            self.check_name("thread", k, "[threads.rate_ctrl]");
            if index.insert(k.get_ref().clone(), i).is_some() {
                self.err(
                    format!("thread `{}` is declared twice", k.get_ref()),
                    span(k),
                    "rename one of them",
                );
            }
            threads.push(self.thread(k, v.get_ref()));
        }
        (threads, index)
    }

    /// One thread's keys.
    fn thread(&mut self, k: &S<String>, t: &RawThread) -> Option<Thread> {
        let priority = match &t.priority {
            Some(p) => match p.get_ref() {
                toml::Value::Integer(i) if (1..=i64::from(u32::MAX)).contains(i) => Some(*i as u32),
                _ => {
                    self.err(
                        "priority must be a whole number of at least 1",
                        span(p),
                        "write e.g. priority = 1 (1 is the highest priority on its cpu)",
                    );
                    None
                }
            },
            None => {
                self.err(
                    format!("thread `{}` has no priority", k.get_ref()),
                    span(k),
                    "give it `priority = N` (1 is the highest on its cpu; thread-less tasks share the order)",
                );
                None
            }
        };
        let cpu = match &t.cpu {
            Some(c) => self.cpu_index(c),
            None => Some(0),
        };
        Some(Thread {
            name: k.get_ref().clone(),
            priority: priority?,
            cpu: cpu?,
        })
    }

    /// A task's `thread`: a declared one.
    pub(super) fn task_thread(
        &mut self,
        t: &RawTask,
        thread_index: &HashMap<String, usize>,
    ) -> Option<Option<usize>> {
        let Some(th) = &t.thread else {
            return Some(None);
        };
        if let Some(&i) = thread_index.get(th.get_ref()) {
            return Some(Some(i));
        }
        let mut names: Vec<&str> = thread_index.keys().map(String::as_str).collect();
        names.sort_unstable();
        let help = match suggest(th.get_ref(), names.iter().copied()) {
            Some(s) => format!("did you mean `{s}`?"),
            None if names.is_empty() => format!(
                "declare it: [threads.{}] with priority = N and cpu = N",
                th.get_ref()
            ),
            None => format!(
                "declare [threads.{}] or use one of: {}",
                th.get_ref(),
                names.join(", ")
            ),
        };
        self.err(format!("unknown thread `{}`", th.get_ref()), span(th), help);
        None
    }

    /// A task's `activation`, `triggers` and `join`: `Some(None)` for a
    /// periodic task (its `period` applies), `Some(Some(Triggered))` for a
    /// data-triggered one, `None` on an error. `reads` are the task's
    /// resolved producers (`None` when they had an error).
    pub(super) fn activation(
        &mut self,
        t: &RawTask,
        reads: Option<&[usize]>,
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) -> Option<Option<PeriodSpec>> {
        let data = match &t.activation {
            Some(a) => self.choice(a, "activation", &[("periodic", false), ("data", true)])?,
            None => false,
        };
        if !data {
            self.periodic_has_no_trigger_keys(t);
            return Some(None);
        }
        let reads = reads?;
        let triggers = self.triggers(t, reads, task_index, names)?;
        let join = match &t.join {
            Some(j) => self.choice(j, "join", &[("any", Join::Any), ("all", Join::All)])?,
            None => Join::Any,
        };
        self.data_has_no_timer_keys(t)
            .then_some(Some(PeriodSpec::Triggered { triggers, join }))
    }

    /// `triggers` and `join` belong to data-triggered tasks.
    fn periodic_has_no_trigger_keys(&mut self, t: &RawTask) {
        if let Some(tr) = &t.triggers {
            self.err(
                "`triggers` is set, but the task is periodic",
                span(tr),
                "add activation = \"data\" to release it by its triggers' publications, or remove `triggers`",
            );
        }
        if let Some(j) = &t.join {
            self.err(
                "`join` is set, but the task is periodic",
                span(j),
                "add activation = \"data\" to release it by its triggers' publications, or remove `join`",
            );
        }
    }

    /// The triggers of a data-triggered task: each one of its `reads`,
    /// once; all of its `reads` when none are named.
    fn triggers(
        &mut self,
        t: &RawTask,
        reads: &[usize],
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) -> Option<Vec<usize>> {
        let Some(tr) = &t.triggers else {
            if reads.is_empty() {
                let at = t.activation.as_ref().map(span).unwrap_or(None);
                self.err(
                    "a data-triggered task reads nothing, so nothing can release it",
                    at,
                    format!("{TRIGGER_HELP}: add the producer to `reads`, or make the task periodic with a `period`"),
                );
                return None;
            }
            return Some(reads.to_vec());
        };
        if tr.get_ref().is_empty() {
            self.err(
                "`triggers` is empty, so nothing can release the task",
                span(tr),
                format!("{TRIGGER_HELP}: name at least one, or remove the key"),
            );
            return None;
        }
        let mut out = Vec::new();
        let mut ok = true;
        for n in tr.get_ref() {
            let Some(&i) = task_index.get(n.get_ref()) else {
                self.unknown_task(n, names);
                ok = false;
                continue;
            };
            if out.contains(&i) {
                self.err(
                    format!("`{}` appears twice in triggers", n.get_ref()),
                    span(n),
                    "list each trigger once",
                );
                ok = false;
            } else if !reads.contains(&i) {
                self.err(
                    format!("trigger `{}` is not in the task's reads", n.get_ref()),
                    span(n),
                    format!(
                        "a job reads the data that released it: add \"{}\" to `reads`, or remove it from `triggers`",
                        n.get_ref()
                    ),
                );
                ok = false;
            }
            out.push(i);
        }
        ok.then_some(out)
    }

    /// A data-triggered task has no timer: no `period`, `offset`, `jitter`
    /// (its release jitter is its triggers', which the analysis propagates)
    /// or `max_period`.
    fn data_has_no_timer_keys(&mut self, t: &RawTask) -> bool {
        let keys = [
            ("period", &t.period, "its releases follow its triggers' publications"),
            ("offset", &t.offset, "it is released when a trigger publishes"),
            ("jitter", &t.jitter, "its release jitter is its triggers' response jitter, which the analysis propagates"),
            ("max_period", &t.max_period, "set `max_period` on the periodic source that triggers it"),
        ];
        let mut ok = true;
        for (key, v, why) in keys {
            if let Some(v) = v {
                self.err(
                    format!("a data-triggered task has no `{key}`"),
                    span(v),
                    format!("remove `{key}`: {why} (or make the task periodic: remove activation = \"data\")"),
                );
                ok = false;
            }
        }
        ok
    }

    /// The default server of a task: `none` in a thread or when released
    /// by data (neither has a budget of its own), `main` otherwise.
    pub(super) fn default_server(t: &RawTask) -> Server {
        let data = t.activation.as_ref().is_some_and(|a| a.get_ref() == "data");
        if t.thread.is_some() || data {
            Server::None
        } else {
            Server::Main
        }
    }

    /// The rules between tasks, threads, the priority order and the
    /// scheduler; a task in a thread takes its thread's CPU and priority.
    pub(super) fn events(
        &mut self,
        raw: &RawSpec,
        threads: &[Thread],
        tasks: &mut [Task],
        order: Priorities,
        scheduler: Option<Scheduler>,
    ) {
        let (sys, raw_threads, raw_tasks) = (&raw.system, &raw.threads, &raw.tasks.0[..]);
        let event_triggered = !threads.is_empty() || tasks.iter().any(Task::is_triggered);
        if !event_triggered {
            return;
        }
        self.events_need_fixed_priorities(sys, raw_threads, raw_tasks, tasks, order, scheduler);
        for (i, (_, v)) in raw_tasks.iter().enumerate() {
            self.task_fits_event_model(&mut tasks[i], v.get_ref(), threads);
        }
        self.threads_are_used(raw_threads, tasks);
        self.thread_priorities_distinct(raw_threads, threads, tasks);
        self.no_trigger_cycle(raw_tasks, tasks);
        if sys.get_ref().overheads.is_some() {
            self.err(
                "scheduling overheads are not analysed for threads and data-triggered tasks yet",
                span(sys),
                "remove `overheads` from [system], or fold them into each task's exec",
            );
        }
    }

    /// Threads and data-triggered tasks are analysed under fixed,
    /// explicit priorities: a thread has no period to rank it by.
    fn events_need_fixed_priorities(
        &mut self,
        sys: &S<RawSystem>,
        raw_threads: &Ordered<RawThread>,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        order: Priorities,
        scheduler: Option<Scheduler>,
    ) {
        let first = raw_threads
            .0
            .first()
            .map(|(k, _)| span(k))
            .or_else(|| {
                let i = tasks.iter().position(Task::is_triggered)?;
                Some(
                    raw_tasks[i]
                        .1
                        .get_ref()
                        .activation
                        .as_ref()
                        .map_or_else(|| span(&raw_tasks[i].0), span),
                )
            })
            .unwrap_or(None);
        let what = if raw_threads.0.is_empty() {
            "data-triggered tasks"
        } else {
            "threads"
        };
        if let Some(s) = scheduler.filter(|s| s.policy().events.is_none()) {
            self.err(
                format!(
                    "{what} are scheduled by fixed priority, but the scheduler is \"{}\"",
                    s.name()
                ),
                sys.get_ref().scheduler.as_ref().map_or(first.clone(), span),
                "use scheduler = \"rm\" with priorities = \"explicit\" in [system]",
            );
        } else if order != Priorities::Explicit {
            self.err(
                format!("{what} need explicit priorities, but priorities are {}", order.name()),
                sys.get_ref().priorities.as_ref().map_or(first, span),
                "set priorities = \"explicit\" in [system] and give each thread and thread-less task `priority = N` (1 is the highest per cpu)",
            );
        }
    }

    /// One task against the event model: a task in a thread has the
    /// thread's CPU and priority and no server or budget of its own; a
    /// data-triggered task has no server budget; neither holds resources
    /// (their blocking is not analysed yet).
    fn task_fits_event_model(&mut self, t: &mut Task, rt: &RawTask, threads: &[Thread]) {
        if let Some(th) = t.thread.and_then(|i| threads.get(i)) {
            self.task_in_thread(t, rt, th);
        } else if t.is_triggered() && t.server != Server::None {
            if let Some(s) = &rt.server {
                self.err(
                    format!("data-triggered task `{}` has server \"{}\"", t.name, t.server.name()),
                    span(s),
                    "a server needs a period to replenish its budget: use server = \"none\" (the default for data-triggered tasks)",
                );
            }
        }
        if let Some(sv) = &rt.serves {
            self.err(
                format!("task `{}` serves another (PIBS inheritance) in a spec with threads or data-triggered tasks", t.name),
                span(sv),
                "the inheritance of an I/O VCPU is not analysed beside threads yet: remove `serves` (the server keeps its own priority)",
            );
        }
        if let (Some(cs), true) = (
            &rt.critical_sections,
            t.thread.is_some() || t.is_triggered(),
        ) {
            self.err(
                format!("task `{}` holds resources, but it is in a thread or data-triggered", t.name),
                span(cs),
                "blocking is not analysed for threads and data-triggered tasks yet: remove `critical_sections` here",
            );
        }
    }

    /// A task in a thread: the thread's CPU and priority, server `none`.
    fn task_in_thread(&mut self, t: &mut Task, rt: &RawTask, th: &Thread) {
        if let Some(c) = &rt.cpu {
            if t.cpu != th.cpu {
                self.err(
                    format!(
                        "task `{}` is on cpu {}, but its thread `{}` runs on cpu {}",
                        t.name, t.cpu, th.name, th.cpu
                    ),
                    span(c),
                    format!("a thread runs on one cpu: remove `cpu` here (it is the thread's), or set cpu = {} on [threads.{}]", t.cpu, th.name),
                );
            }
        }
        if let Some(p) = &rt.priority {
            self.err(
                format!("task `{}` gives a priority, but it runs in thread `{}`", t.name, th.name),
                span(p),
                format!("remove `priority`: the thread's ({}) applies, and its jobs run in release order", th.priority),
            );
        }
        if let (Some(s), true) = (&rt.server, t.server != Server::None) {
            self.err(
                format!("task `{}` in thread `{}` has server \"{}\"", t.name, th.name, t.server.name()),
                span(s),
                "a thread's tasks run without a server of their own: remove `server` (or write server = \"none\")",
            );
        }
        if let Some(b) = &rt.budget {
            self.err(
                format!("task `{}` in thread `{}` has a budget", t.name, th.name),
                span(b),
                "a thread's tasks run without a server, so without a budget: remove `budget`",
            );
        }
        t.cpu = th.cpu;
        t.priority = Some(th.priority);
    }

    /// Every declared thread runs some task (an unused one is a typo).
    fn threads_are_used(&mut self, raw_threads: &Ordered<RawThread>, tasks: &[Task]) {
        for (i, (k, _)) in raw_threads.0.iter().enumerate() {
            if !tasks.iter().any(|t| t.thread == Some(i)) {
                self.err(
                    format!("thread `{}` runs no task", k.get_ref()),
                    span(k),
                    format!(
                        "put a task on it (thread = \"{}\" in its table), or remove the thread",
                        k.get_ref()
                    ),
                );
            }
        }
    }

    /// A thread's priority is its own on its CPU: no other thread and no
    /// thread-less task there has it.
    fn thread_priorities_distinct(
        &mut self,
        raw_threads: &Ordered<RawThread>,
        threads: &[Thread],
        tasks: &[Task],
    ) {
        for (b, th) in threads.iter().enumerate() {
            let other_thread = (0..b)
                .find(|&a| threads[a].cpu == th.cpu && threads[a].priority == th.priority)
                .map(|a| format!("thread `{}`", threads[a].name));
            let task = tasks
                .iter()
                .find(|t| t.thread.is_none() && t.cpu == th.cpu && t.priority == Some(th.priority))
                .map(|t| format!("task `{}`", t.name));
            let Some(clash) = other_thread.or(task) else {
                continue;
            };
            let at = raw_threads.0[b]
                .1
                .get_ref()
                .priority
                .as_ref()
                .map_or_else(|| span(&raw_threads.0[b].0), span);
            self.err(
                format!(
                    "thread `{}` and {clash} on cpu {} both have priority {}",
                    th.name, th.cpu, th.priority
                ),
                at,
                "give each thread and thread-less task on a cpu its own priority",
            );
        }
    }

    /// Data-triggered tasks release each other along their triggers; a
    /// cycle of them would release jobs without end (or never, with
    /// `join = "all"`), so the trigger graph is acyclic: every release
    /// traces back to a periodic source.
    fn no_trigger_cycle(&mut self, raw_tasks: &[(S<String>, S<RawTask>)], tasks: &[Task]) {
        // Kahn's algorithm over trigger → triggered edges.
        let n = tasks.len();
        let mut indegree = vec![0usize; n];
        let mut out: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (c, t) in tasks.iter().enumerate() {
            for &p in t.triggers().map_or(&[][..], |(tr, _)| tr) {
                out[p].push(c);
                indegree[c] += 1;
            }
        }
        let mut ready: Vec<usize> = (0..n).filter(|&i| indegree[i] == 0).collect();
        while let Some(i) = ready.pop() {
            for &c in &out[i] {
                indegree[c] -= 1;
                if indegree[c] == 0 {
                    ready.push(c);
                }
            }
        }
        let Some(c) = (0..n).find(|&i| indegree[i] > 0) else {
            return;
        };
        let rt = raw_tasks[c].1.get_ref();
        let at = rt
            .triggers
            .as_ref()
            .map(span)
            .or_else(|| rt.activation.as_ref().map(span))
            .unwrap_or_else(|| span(&raw_tasks[c].0));
        self.err(
            format!("data-triggered task `{}` is on a cycle of triggers, which no periodic source starts", tasks[c].name),
            at,
            "break the cycle: make one task on it periodic (activation = \"periodic\" with a period), or drop a trigger (a task may still read a producer it is not triggered by)",
        );
    }

    /// LET reads at a timer's release and publishes at its period's end:
    /// a data-triggered task has neither.
    pub(super) fn no_let_on_triggered(
        &mut self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        communications: &[Communication],
    ) {
        for (i, t) in tasks.iter().enumerate() {
            if t.is_triggered() && communications[i] == Communication::Let {
                let rt = raw_tasks[i].1.get_ref();
                self.err(
                    format!("data-triggered task `{}` would communicate under LET", t.name),
                    rt.activation.as_ref().map_or_else(|| span(&raw_tasks[i].0), span),
                    "LET reads at a periodic release and publishes at the period's end: make the task periodic, or give its chains communication = \"implicit\"",
                );
            }
        }
    }
}
