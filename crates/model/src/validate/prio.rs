//! Validation of the fixed-priority and timing keys of the timing model:
//! `[system] priorities`, and per task `priority`, `deadline` and `jitter`.
//! Each rule is one function; [`Builder::priorities_and_deadlines`] runs
//! them once the periods are known.

use super::{span, Builder};
use crate::policy::Priorities;
use crate::raw::{RawSystem, RawTask, S};
use crate::*;

/// The timing keys of one task, parsed: (priority, deadline, jitter); an
/// inner `None` where the key is not given, an outer one where it is bad.
pub(crate) type TimingKeys = (Option<Option<u32>>, Option<Option<Nanos>>, Option<Nanos>);

impl Builder {
    /// `[system] priorities`: rate-monotonic by default; only for a
    /// fixed-priority scheduler.
    pub(super) fn priority_order(
        &mut self,
        sys: &RawSystem,
        scheduler: Option<Scheduler>,
    ) -> Priorities {
        let Some(p) = &sys.priorities else {
            return Priorities::RateMonotonic;
        };
        let options = Priorities::ALL.map(|p| (p.name(), p));
        let order = self
            .choice(p, "priorities", &options)
            .unwrap_or(Priorities::RateMonotonic);
        if let Some(s) = scheduler.filter(|s| !s.policy().fixed_priority()) {
            self.err(
                format!(
                    "priorities = \"{}\" is set, but scheduler \"{}\" has no fixed priorities",
                    order.name(),
                    s.name()
                ),
                span(p),
                "remove `priorities` (EDF orders jobs by their deadlines), or use scheduler = \"rm\"",
            );
        }
        order
    }

    /// `priority`, `deadline` and `jitter` of one task, each on its own.
    pub(super) fn timing_keys(&mut self, t: &RawTask) -> TimingKeys {
        let priority = match &t.priority {
            Some(p) => match p.get_ref() {
                toml::Value::Integer(i) if (1..=i64::from(u32::MAX)).contains(i) => {
                    Some(Some(*i as u32))
                }
                _ => {
                    self.err(
                        "priority must be a whole number of at least 1",
                        span(p),
                        "write e.g. priority = 1 (1 is the highest priority, larger numbers are lower)",
                    );
                    None
                }
            },
            None => Some(None),
        };
        let deadline = match &t.deadline {
            Some(d) => self.positive_time(d, "deadline").map(Some),
            None => Some(None),
        };
        let jitter = match &t.jitter {
            Some(j) => self.nonneg_time(j, "jitter"),
            None => Some(0),
        };
        (priority, deadline, jitter)
    }

    /// Every rule between the timing keys, the periods, the priority order
    /// and the scheduler, once the tasks are built.
    pub(super) fn priorities_and_deadlines(
        &mut self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        order: Priorities,
        scheduler: Option<Scheduler>,
    ) {
        for (i, (k, v)) in raw_tasks.iter().enumerate() {
            let (t, rt) = (&tasks[i], v.get_ref());
            self.deadline_within_period(t, rt);
            self.jitter_within_period(t, rt, scheduler);
            self.priority_fits_order(t, k, rt, order);
        }
        if order == Priorities::Explicit {
            self.distinct_priorities(raw_tasks, tasks);
        }
    }

    /// The least period a task can have, and how to name it.
    fn least_period(t: &Task) -> (Nanos, &'static str) {
        match &t.period {
            PeriodSpec::Fixed(p) => (*p, "its period"),
            PeriodSpec::Range { min: Some(m), .. } => (*m, "the least period of its range"),
            PeriodSpec::Choices(c) => (
                c.iter().copied().min().unwrap_or(0),
                "its shortest period choice",
            ),
            _ => (Nanos::MAX, "its period"),
        }
    }

    /// D ≤ T (constrained deadlines), for every period the task can have.
    fn deadline_within_period(&mut self, t: &Task, rt: &RawTask) {
        let (Some(d), Some(ds)) = (t.deadline_given, &rt.deadline) else {
            return;
        };
        let unit = self.unit();
        if t.server == Server::Background {
            self.err(
                format!("background task `{}` has a deadline", t.name),
                span(ds),
                "background tasks run only in slack and have no guarantee: remove the deadline or give the task a server",
            );
            return;
        }
        let (least, what) = Self::least_period(t);
        if d > least {
            self.err(
                format!(
                    "deadline {} of task `{}` is above {what} ({})",
                    format_in(d, unit),
                    t.name,
                    format_in(least, unit)
                ),
                span(ds),
                format!(
                    "deadlines are constrained (D ≤ T): make it at most {}, or remove it for D = T",
                    format_in(least, unit)
                ),
            );
        }
    }

    /// 0 ≤ J < T (so that jobs stay in release order), and only where
    /// the analysis bounds it: under fixed priorities.
    fn jitter_within_period(&mut self, t: &Task, rt: &RawTask, scheduler: Option<Scheduler>) {
        let Some(js) = &rt.jitter else {
            return;
        };
        let unit = self.unit();
        if t.jitter > 0 && scheduler.is_some_and(|s| !s.policy().fixed_priority()) {
            self.err(
                format!("task `{}` has release jitter under an EDF scheduler", t.name),
                span(js),
                "release jitter is analysed under fixed priorities: use scheduler = \"rm\", or remove the jitter",
            );
            return;
        }
        let (least, what) = Self::least_period(t);
        if t.jitter >= least {
            self.err(
                format!(
                    "jitter {} of task `{}` is not below {what} ({})",
                    format_in(t.jitter, unit),
                    t.name,
                    format_in(least, unit)
                ),
                span(js),
                format!(
                    "a job is released within [k·T, k·T + J], and the next one must come after it: make the jitter less than {}",
                    format_in(least, unit)
                ),
            );
        }
    }

    /// `priority = N` exactly where `priorities = "explicit"` asks for it:
    /// on every guaranteed task, on no background task.
    fn priority_fits_order(&mut self, t: &Task, k: &S<String>, rt: &RawTask, order: Priorities) {
        if t.thread.is_some() {
            // Its thread's priority applies (`events.rs` refuses its own).
            return;
        }
        match (&rt.priority, order, t.server) {
            (Some(p), Priorities::Explicit, Server::Background) => self.err(
                format!("background task `{}` has a priority", t.name),
                span(p),
                "background tasks run below every priority: remove `priority`",
            ),
            (Some(p), Priorities::RateMonotonic | Priorities::DeadlineMonotonic, _) => self.err(
                format!(
                    "task `{}` gives a priority, but priorities are {}",
                    t.name,
                    order.name()
                ),
                span(p),
                format!(
                    "set priorities = \"explicit\" in [system] to use it, or remove `priority` ({} assigns them)",
                    order.name()
                ),
            ),
            (None, Priorities::Explicit, s) if s != Server::Background => self.err(
                format!(
                    "task `{}` has no priority, but priorities are explicit",
                    t.name
                ),
                span(k),
                "give it `priority = N` (1 is the highest), or use priorities = \"rate-monotonic\"",
            ),
            _ => {}
        }
    }

    /// Explicit priorities are distinct per CPU: ties would leave the
    /// order to the implementation, which neither the analysis nor the
    /// simulator can know.
    fn distinct_priorities(&mut self, raw_tasks: &[(S<String>, S<RawTask>)], tasks: &[Task]) {
        for b in 0..tasks.len() {
            let (Some(pb), Some(ps)) = (tasks[b].priority, &raw_tasks[b].1.get_ref().priority)
            else {
                continue;
            };
            // A thread's tasks share its priority; `events.rs` checks
            // threads against the rest.
            let Some(a) = (0..b).find(|&a| {
                tasks[a].thread.is_none()
                    && tasks[a].cpu == tasks[b].cpu
                    && tasks[a].priority == Some(pb)
            }) else {
                continue;
            };
            let free = (1..=u32::MAX)
                .find(|n| {
                    !tasks
                        .iter()
                        .any(|t| t.cpu == tasks[b].cpu && t.priority == Some(*n))
                })
                .unwrap_or(pb);
            self.err(
                format!(
                    "tasks `{}` and `{}` on cpu {} both have priority {pb}",
                    tasks[a].name, tasks[b].name, tasks[b].cpu
                ),
                span(ps),
                format!(
                    "give each task on a cpu its own priority (e.g. priority = {free} here, not taken on cpu {})",
                    tasks[b].cpu
                ),
            );
        }
    }

    /// The schedulability test: when the spec names none, the policy's
    /// first that holds for its deadlines and jitter; when it names one
    /// that needs implicit deadlines (or rate-monotonic ranks), an error
    /// where it is named.
    pub(super) fn test_for_tasks(
        &mut self,
        sys: &RawSystem,
        scheduler: Scheduler,
        test: SchedTest,
        order: Priorities,
        tasks: &[Task],
    ) -> SchedTest {
        let constrained = tasks
            .iter()
            .any(|t| t.jitter > 0 || t.deadline_given.is_some_and(|d| Some(d) < t.fixed_period()));
        let reordered = scheduler.policy().fixed_priority() && order != Priorities::RateMonotonic;
        let Some(named) = &sys.schedulability else {
            return scheduler
                .policy()
                .default_test_for(constrained || reordered);
        };
        if test.needs_implicit_deadlines() && (constrained || reordered) {
            let why = if reordered && !constrained {
                format!("priorities = \"{}\"", order.name())
            } else {
                "a deadline below its period or release jitter".to_string()
            };
            self.err(
                format!(
                    "schedulability test \"{}\" assumes rate-monotonic priorities, deadlines equal to periods and no jitter, but a task has {why}",
                    test.name()
                ),
                span(named),
                if scheduler.policy().fixed_priority() {
                    "use schedulability = \"rta\" (exact response-time analysis with deadlines and jitter)"
                } else {
                    "use schedulability = \"qpa\" (the processor-demand test for constrained deadlines)"
                },
            );
        }
        test
    }
}
