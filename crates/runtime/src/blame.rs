//! What broke the model in a window of a real run: the evidence an
//! observation above a sound bound may be excused by. A cause counts only
//! inside the observation's window and on the CPUs of the tasks involved;
//! `rtpipe run` excuses the observation only when the causes' total, taken
//! as a disturbance of the analysis (`rtpipe_analysis::disturbance`),
//! grows the bound by at least the excess. Everything else is a violation.

use crate::exec::{Policy, RunResult, RESERVATION_MARGIN};
use crate::foreign::ForeignThread;
use crate::probe::{Probe, PROBE_PERIOD};
use rtpipe_joblog::JobRecord;
use rtpipe_model::{Nanos, Spec};

/// One thing that broke the model's assumptions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Cause {
    /// The run had no real-time policy (`--policy other --best-effort`).
    BestEffort,
    /// SCHED_DEADLINE ran global EDF on all CPUs, which the analysis (EDF
    /// partitioned by the spec's `cpu`) does not cover.
    GlobalEdf,
    /// A job used more CPU time than its task's budget.
    Overrun {
        /// The task.
        task: usize,
        /// Its job (release index).
        job: u64,
        /// CPU time the job used, ns.
        demand: Nanos,
        /// The task's budget C, ns.
        budget: Nanos,
        /// What the analysis assumed of this job, ns: the budget C where it
        /// interferes with the observed tasks, but the declared demand x
        /// where it is a job of one of them (R(job) assumes x for the job
        /// itself), so that all of its CPU time above x delayed it, the
        /// part below C too.
        assumed: Nanos,
        /// How long the kernel then withheld the CPU from the task: under
        /// SCHED_DEADLINE a reservation that overruns its runtime is
        /// throttled until its next period (up to T); 0 under SCHED_FIFO.
        throttle: Nanos,
    },
    /// A job used more CPU time than its task's declared demand x (the job
    /// frame's register copies and clock reads, a burn's overshoot): the
    /// analysis' R(job) assumes x.
    Demand {
        /// The task.
        task: usize,
        /// Its job (release index).
        job: u64,
        /// CPU time the job used, ns.
        demand: Nanos,
        /// The declared demand x, ns.
        declared: Nanos,
    },
    /// Time in the window when jobs of the run on a CPU were pending but
    /// none of them used it: the kernel's timer and wake-up latency,
    /// interrupts, other processes (a foreign real-time thread), the
    /// hypervisor (steal), the kernel's real-time throttling, and under
    /// [`Policy::EdfFifo`] the EDF dispatcher's work at releases and
    /// completions. The model has none of it; it excuses nothing when the
    /// run's own threads had used the CPU's real-time share (`throttled`).
    Foreign {
        /// The CPU (`None`: all of them, under global EDF).
        cpu: Option<u32>,
        /// Pending time minus the CPU time the run's jobs used in it, ns.
        ns: Nanos,
        /// The run was under the EDF dispatcher (`crate::edf`), whose
        /// release and completion work is part of this time.
        dispatcher: bool,
        /// Around the window the run's own threads on the CPU had used
        /// its real-time share (`sched_rt_runtime_us` of every
        /// `sched_rt_period_us`): the kernel throttled them, for the run's
        /// own overload, and this time is no delay from outside.
        throttled: bool,
    },
    /// The hypervisor ran something else on a CPU (steal time): named, but
    /// already part of that CPU's [`Cause::Foreign`] time, so it adds no
    /// delay of its own.
    Steal {
        /// The CPU.
        cpu: usize,
        /// Steal time in the probe intervals covering the window, ns.
        ns: Nanos,
    },
    /// Under SCHED_DEADLINE the kernel signalled (SIGXCPU) that the task's
    /// reservation overran its runtime: it throttled the thread until the
    /// reservation's deadline and replenished it a period on, so the
    /// task's next jobs ran with a kernel deadline later than their own
    /// (release + D), out of EDF order, until one met its deadline again.
    /// No `sched_setattr` re-arms it: the kernel keeps a reservation's
    /// deadline while it lies ahead (docs/runtime.md). Each of those jobs
    /// may be late by up to the lag.
    ReservationOverrun {
        /// The task.
        task: usize,
        /// The job during which the kernel signalled it.
        job: u64,
        /// Its jobs from that one until one met its deadline again.
        affected: u64,
        /// How far its reservation can lag its releases: its period, ns.
        lag: Nanos,
    },
    /// Under SCHED_DEADLINE the task's reservation may hold, at this job's
    /// wake-up, a deadline that lies after the job's release, kept from
    /// the task's earlier jobs: a wake-up later than the lead sets one
    /// there, a throttled reservation is replenished with its deadline a
    /// period on, and a wake-up keeps a deadline that lies ahead while the
    /// leftover runtime fits the bandwidth (the CBS wake-up rule). The job
    /// then runs that leftover, is throttled until the kept deadline (up to
    /// `lag` after its release), and with the leftover it also runs ahead
    /// of other tasks' jobs of earlier deadlines (out of EDF order).
    StaleDeadline {
        /// The task.
        task: usize,
        /// The job.
        job: u64,
        /// How far after the job's release the kept deadline may lie, ns
        /// (`kept_deadlines`): how long the job itself may be throttled.
        lag: Nanos,
        /// How much runtime the reservation may have kept with it, ns: how
        /// long the job may run ahead. The kernel keeps a deadline only
        /// when the leftover is at most runtime × (deadline − now) /
        /// relative deadline, and at most what the job before left of the
        /// runtime when that job ran unthrottled.
        ahead: Nanos,
        /// A job of the observation's own task (delayed by `lag`), or
        /// another task's on its CPU (delaying it by `ahead`).
        own: bool,
    },
    /// Another process's real-time thread that may run on a CPU with
    /// foreign time in the window and used CPU time during the run
    /// (`crate::foreign`): named, but already part of that CPU's
    /// [`Cause::Foreign`] time, so it adds no delay of its own. The scans
    /// are before and after the run, so it ran during the run, not
    /// necessarily in the window.
    ForeignThread {
        /// The CPU of the foreign time (`None`: all of them, under global EDF).
        cpu: Option<u32>,
        /// The thread.
        thread: ForeignThread,
    },
    /// The task was still running long after the run's end and was moved
    /// to SCHED_OTHER.
    Demoted {
        /// The task.
        task: usize,
    },
}

impl Cause {
    /// How long it can have delayed the window's observation, ns.
    pub fn delay(&self) -> Nanos {
        match *self {
            Cause::BestEffort | Cause::GlobalEdf | Cause::Demoted { .. } => Nanos::MAX,
            Cause::Steal { .. } | Cause::ForeignThread { .. } => 0,
            Cause::Overrun {
                demand,
                assumed,
                throttle,
                ..
            } => demand - assumed + throttle,
            Cause::Demand {
                demand, declared, ..
            } => demand - declared,
            Cause::ReservationOverrun { lag, .. } => lag,
            Cause::StaleDeadline {
                lag, ahead, own, ..
            } => {
                if own {
                    lag
                } else {
                    ahead
                }
            }
            Cause::Foreign {
                throttled: true, ..
            } => 0,
            Cause::Foreign { ns, .. } => ns,
        }
    }

    /// In words, naming tasks as the spec does.
    pub fn describe(&self, spec: &Spec) -> String {
        let name = |t: usize| spec.tasks.get(t).map_or("?", |t| t.name.as_str());
        match *self {
            Cause::BestEffort => "SCHED_OTHER (--best-effort): no real-time guarantee".into(),
            Cause::GlobalEdf => {
                "SCHED_DEADLINE ran global EDF on all CPUs, which the partitioned analysis does not cover"
                    .into()
            }
            Cause::Overrun {
                task,
                job,
                demand,
                budget,
                assumed,
                throttle,
            } => format!(
                "{} job {job} ran {} us against a budget of {} us{}{}",
                name(task),
                us(demand),
                us(budget),
                if assumed < budget {
                    format!(" (its own response assumed its demand of {} us)", us(assumed))
                } else {
                    String::new()
                },
                if throttle > 0 {
                    format!(" (SCHED_DEADLINE throttles it up to {} us)", us(throttle))
                } else {
                    String::new()
                }
            ),
            Cause::Demand {
                task,
                job,
                demand,
                declared,
            } => format!(
                "{} job {job} used {} us of CPU against a demand of {} us",
                name(task),
                us(demand),
                us(declared)
            ),
            Cause::Foreign {
                cpu,
                ns,
                dispatcher,
                throttled,
            } => format!(
                "{} us on {} with jobs of the run pending but none running ({})",
                us(ns),
                cpu.map_or("the CPUs".to_string(), |c| format!("CPU {c}")),
                foreign_sources(dispatcher, throttled)
            ),
            Cause::Steal { cpu, ns } => format!(
                "{} us of steal time on CPU {cpu} (within the foreign time)",
                us(ns)
            ),
            Cause::ReservationOverrun { .. }
            | Cause::StaleDeadline { .. }
            | Cause::ForeignThread { .. } => self.describe_kernel(spec),
            Cause::Demoted { task } => format!("{} was demoted to SCHED_OTHER", name(task)),
        }
    }

    /// In words, what SCHED_DEADLINE and other processes did (the causes
    /// the kernel's side of a run adds).
    fn describe_kernel(&self, spec: &Spec) -> String {
        let name = |t: usize| spec.tasks.get(t).map_or("?", |t| t.name.as_str());
        match *self {
            Cause::ReservationOverrun {
                task,
                job,
                affected,
                lag,
            } => format!(
                "{} job {job}: the kernel signalled an overrun of its SCHED_DEADLINE reservation, \
                 which then lagged its releases by up to {} us (out of EDF order) for {affected} job(s)",
                name(task),
                us(lag)
            ),
            Cause::StaleDeadline {
                task,
                job,
                lag,
                ahead,
                own,
            } => format!(
                "{} job {job}: its SCHED_DEADLINE reservation may have kept a deadline up to {} us \
                 after its release from the task's earlier jobs (a late wake-up or a throttle put it \
                 there; a wake-up keeps a deadline that lies ahead), {}",
                name(task),
                us(lag),
                if own {
                    format!("and throttle it up to {} us", us(lag))
                } else {
                    format!("with which it may run {} us ahead of earlier deadlines", us(ahead))
                }
            ),
            Cause::ForeignThread { cpu, ref thread } => format!(
                "a foreign real-time thread may run on {} (within the foreign time): {}",
                cpu.map_or("the CPUs".to_string(), |c| format!("CPU {c}")),
                thread.describe()
            ),
            _ => unreachable!("not a kernel cause: {self:?}"),
        }
    }
}

/// What a foreign time is made of, as far as the run can tell.
fn foreign_sources(dispatcher: bool, throttled: bool) -> String {
    let mut out = String::new();
    if throttled {
        out.push_str("the kernel's real-time throttling, which the run's own demand triggered: its threads there had used the CPU's real-time share (sched_rt_runtime_us), so this excuses nothing; ");
    }
    if dispatcher {
        out.push_str("the EDF dispatcher's releases and completions, ");
    }
    // A foreign real-time thread is one of the other processes.
    out.push_str("kernel latency, interrupts, other processes, steal");
    out
}

fn us(ns: Nanos) -> String {
    format!("{:.1}", ns as f64 / 1e3)
}

/// The evidence of one run, indexed for windows.
pub struct Blame<'r> {
    spec: &'r Spec,
    res: &'r RunResult,
    /// Per task, its jobs in release order.
    jobs: Vec<Vec<&'r JobRecord>>,
    /// Per CPU, the probe instants where the run's own threads there had
    /// used the CPU's real-time share over the throttling period before.
    saturated: Vec<Vec<Nanos>>,
    /// Per task, its reservation's overruns: (from, to, cause), from the
    /// release of the job that overran to the finish of the last job
    /// before one met its deadline again.
    lags: Vec<Vec<(Nanos, Nanos, Cause)>>,
}

impl<'r> Blame<'r> {
    /// Indexes `res`'s jobs as the threads ran them.
    pub fn new(spec: &'r Spec, res: &'r RunResult) -> Blame<'r> {
        let mut jobs: Vec<Vec<&JobRecord>> = vec![Vec::new(); spec.tasks.len()];
        for j in res.scheduled() {
            if let Some(v) = jobs.get_mut(j.task) {
                v.push(j);
            }
        }
        for v in &mut jobs {
            v.sort_by_key(|j| j.index);
        }
        let saturated = saturated(spec, res);
        let lags = (0..spec.tasks.len())
            .map(|t| lags(spec, res, t, &jobs[t]))
            .collect();
        Blame {
            spec,
            res,
            jobs,
            saturated,
            lags,
        }
    }

    /// Whether the run's own threads on `cpu` had used its real-time share
    /// around `window` (a probe period either side: the probes' grain).
    fn self_throttled(&self, cpu: u32, (a, b): (Nanos, Nanos)) -> bool {
        let Some(list) = self.saturated.get(cpu as usize) else {
            return false;
        };
        let k = list.partition_point(|&x| x < a - PROBE_PERIOD);
        list.get(k).is_some_and(|&x| x <= b + PROBE_PERIOD)
    }

    /// The causes inside `window` (relative to the epoch; callers pass it
    /// through [`Blame::extend`] first) on the CPUs of `tasks`: budget
    /// overruns of jobs of the tasks that may delay them, CPU time above
    /// `exec` of their own jobs, foreign time and steal on those CPUs.
    pub fn causes(&self, window: (Nanos, Nanos), tasks: &[usize]) -> Vec<Cause> {
        match self.res.policy {
            Policy::Other => return vec![Cause::BestEffort],
            Policy::Deadline if !self.res.partitioned => return vec![Cause::GlobalEdf],
            Policy::Deadline | Policy::Fifo | Policy::EdfFifo => {}
        }
        let mut out: Vec<Cause> = tasks
            .iter()
            .filter(|t| self.res.demoted.contains(t))
            .map(|&task| Cause::Demoted { task })
            .collect();
        let cpus = self.cpus_of(tasks);
        for t in 0..self.spec.tasks.len() {
            if self.on(t, &cpus) && self.level(t, tasks) {
                out.extend(self.overruns(t, window, tasks.contains(&t)));
                if !tasks.contains(&t) {
                    out.extend(self.ahead(t, window));
                }
            }
        }
        for &t in tasks {
            out.extend(self.demands(t, window));
            // Only the task's own jobs: the kernel throttles the
            // overrunning reservation, not the others.
            let lags = self.lags.get(t).map_or(&[][..], Vec::as_slice);
            out.extend(
                lags.iter()
                    .filter(|(a, b, _)| *a <= window.1 && *b >= window.0)
                    .map(|(_, _, c)| c.clone()),
            );
        }
        match &cpus {
            Some(list) => {
                let mut list = list.clone();
                list.sort_unstable();
                list.dedup();
                for c in list {
                    out.extend(self.foreign(Some(c), window, tasks));
                }
            }
            None => out.extend(self.foreign(None, window, tasks)),
        }
        let (p0, p1) = covering(&self.res.probes, window);
        if let (Some(p0), Some(p1)) = (p0, p1) {
            out.extend(steal(p0, p1, &cpus));
        }
        let named = self.foreign_threads(&out);
        out.extend(named);
        out
    }

    /// Task `t`'s jobs in `window` that ran ahead of EDF order with a
    /// deadline kept from the job before ([`Cause::StaleDeadline`]).
    fn ahead(&self, t: usize, window: (Nanos, Nanos)) -> Vec<Cause> {
        let lags = self.lags.get(t).map_or(&[][..], Vec::as_slice);
        lags.iter()
            .filter(|(a, b, _)| *a <= window.1 && *b >= window.0)
            .filter_map(|(_, _, c)| match *c {
                Cause::StaleDeadline {
                    task,
                    job,
                    lag,
                    ahead,
                    ..
                } if ahead > 0 => Some(Cause::StaleDeadline {
                    task,
                    job,
                    lag,
                    ahead,
                    own: false,
                }),
                _ => None,
            })
            .collect()
    }

    /// The foreign real-time threads that may have taken the foreign time
    /// among `causes` (one it excuses: not the run's own throttling).
    fn foreign_threads(&self, causes: &[Cause]) -> Vec<Cause> {
        let mut out = Vec::new();
        for c in causes {
            let Cause::Foreign {
                cpu,
                throttled: false,
                ..
            } = *c
            else {
                continue;
            };
            let on = |t: &&ForeignThread| cpu.is_none_or(|c| t.cpus.contains(&(c as usize)));
            out.extend(
                self.res
                    .foreign_rt
                    .iter()
                    .filter(on)
                    .map(|t| Cause::ForeignThread {
                        cpu,
                        thread: t.clone(),
                    }),
            );
        }
        out
    }

    /// `window` reaching back to the start of the busy period (of the
    /// tasks' level, on their CPUs) it begins in: what delayed the jobs
    /// pending at its start delays what happens in it (a backlog carries a
    /// disturbance on).
    pub fn extend(&self, (a, b): (Nanos, Nanos), tasks: &[usize]) -> (Nanos, Nanos) {
        let cpus = self.cpus_of(tasks);
        let mut start = a;
        loop {
            // The earliest release of a job still pending just before
            // `start`, if any.
            let earlier = (0..self.spec.tasks.len())
                .filter(|&t| self.on(t, &cpus) && self.level(t, tasks))
                .filter_map(|t| {
                    let jobs = &self.jobs[t];
                    let k = jobs.partition_point(|j| j.release < start);
                    let j = jobs.get(k.checked_sub(1)?)?;
                    (j.finish >= start).then_some(j.release)
                })
                .min();
            match earlier {
                Some(r) if r < start => start = r,
                _ => return (start, b),
            }
        }
    }

    /// How long the causes can have delayed things, together, ns.
    pub fn total(causes: &[Cause]) -> Nanos {
        causes
            .iter()
            .map(Cause::delay)
            .fold(0, Nanos::saturating_add)
    }

    /// Whether task `t` belongs to the level of `tasks`: under SCHED_FIFO a
    /// priority at least the lowest of theirs (only those can delay them:
    /// the level-i busy period of RTA), under global EDF every task.
    fn level(&self, t: usize, tasks: &[usize]) -> bool {
        let prio = |t: usize| self.res.tasks.get(t).and_then(|r| r.priority);
        let lowest = tasks.iter().map(|&i| prio(i)).min().flatten();
        match (prio(t), lowest) {
            (Some(p), Some(low)) => p >= low,
            _ => true,
        }
    }

    /// The CPUs the tasks run on (`None`: all of them, under global EDF).
    fn cpus_of(&self, tasks: &[usize]) -> Option<Vec<u32>> {
        // Pinned to their tasks' CPUs unless SCHED_DEADLINE ran global EDF.
        let pinned = self.res.policy != Policy::Deadline || self.res.partitioned;
        pinned.then(|| {
            tasks
                .iter()
                .filter_map(|&t| self.spec.tasks.get(t))
                .map(|t| t.cpu)
                .collect()
        })
    }

    fn on(&self, task: usize, cpus: &Option<Vec<u32>>) -> bool {
        cpus.as_ref().is_none_or(|c| {
            self.spec
                .tasks
                .get(task)
                .is_some_and(|t| c.contains(&t.cpu))
        })
    }

    /// Jobs of `task` that overlap `window` ([release, finish]) and overran;
    /// `observed`: `task` is one of the observation's own (its jobs count
    /// from its declared demand, not from its budget).
    fn overruns(&self, task: usize, window: (Nanos, Nanos), observed: bool) -> Vec<Cause> {
        let t = &self.spec.tasks[task];
        let budget = t.budget();
        let assumed = if observed {
            t.demand().min(budget)
        } else {
            budget
        };
        // A SCHED_DEADLINE reservation's runtime is C + its margin; beyond
        // it the kernel throttles the task.
        let throttled = |demand: Nanos| match self.res.policy {
            Policy::Deadline if demand > budget + RESERVATION_MARGIN => {
                t.fixed_period().unwrap_or(0)
            }
            _ => 0,
        };
        self.overlapping(task, window)
            .iter()
            // Any excess: the analysis charges the budget as interference,
            // so even the job frame's few µs above it delay others.
            .filter(|j| j.demand > budget)
            .map(|j| Cause::Overrun {
                task,
                job: j.index,
                demand: j.demand,
                budget,
                assumed,
                throttle: throttled(j.demand),
            })
            .collect()
    }

    /// Jobs of `task` overlapping `window` ([release, finish]).
    fn overlapping(&self, task: usize, (a, b): (Nanos, Nanos)) -> &[&'r JobRecord] {
        let jobs = &self.jobs[task];
        let end = jobs.partition_point(|j| j.release <= b);
        let start = jobs[..end].partition_point(|j| j.finish < a);
        &jobs[start..end]
    }

    /// Jobs of `task` in `window` that used more CPU time than its declared
    /// demand (within its budget: beyond it, [`Cause::Overrun`]).
    fn demands(&self, task: usize, window: (Nanos, Nanos)) -> Vec<Cause> {
        let t = &self.spec.tasks[task];
        let (declared, budget) = (t.demand(), t.budget());
        self.overlapping(task, window)
            .iter()
            .filter(|j| j.demand > declared && j.demand <= budget)
            .map(|j| Cause::Demand {
                task,
                job: j.index,
                demand: j.demand,
                declared,
            })
            .collect()
    }

    /// How long job `j` can have run inside `window`: its read → publish
    /// span there, less, under partitioned EDF (SCHED_DEADLINE or the EDF
    /// dispatcher), the spans of started jobs of its CPU with an earlier
    /// absolute deadline, which it cannot run beside (the stack resource
    /// policy never blocks a started job), and the dispatcher's release and
    /// completion work there (`RunResult::dispatch_spans`). Without that, a job pending past
    /// the window's end would be counted as running while the jobs that
    /// preempted it ran, and hide foreign time. Public for the runtime's
    /// tests: a job's own span must leave room for its CPU time.
    pub fn could_run(&self, j: &JobRecord, (a, b): (Nanos, Nanos)) -> Nanos {
        let (lo, hi) = (j.read.max(a), j.finish.min(b));
        if hi <= lo {
            return 0;
        }
        let edf = matches!(self.res.policy, Policy::EdfFifo | Policy::Deadline);
        let Some(due) = self.due(j).filter(|_| edf) else {
            return hi - lo;
        };
        let cpu = self.spec.tasks[j.task].cpu;
        let mine = |t: usize| self.spec.tasks[t].cpu == cpu;
        let earlier = (0..self.spec.tasks.len())
            .filter(|&t| t != j.task && mine(t))
            .flat_map(|t| self.overlapping(t, (lo, hi)))
            .filter(|e| self.due(e).is_some_and(|d| d < due))
            .map(|e| (e.read, e.finish));
        // The EDF dispatcher's releases and completions: no job ran.
        let dispatching = (0..self.res.dispatch_spans.len())
            .filter(|&t| mine(t))
            .flat_map(|t| self.dispatching(t, (lo, hi)).iter().copied());
        let busy: Vec<(Nanos, Nanos)> = earlier
            .chain(dispatching)
            .map(|(x, y)| (x.max(lo), y.min(hi)))
            .filter(|(x, y)| y > x)
            .collect();
        hi - lo - union_length(busy)
    }

    /// Task `t`'s dispatch spans that overlap `window`. A thread records
    /// its own spans one after the other, so they are in order and
    /// disjoint: two binary searches, not a pass over the run.
    fn dispatching(&self, t: usize, (a, b): (Nanos, Nanos)) -> &[(Nanos, Nanos)] {
        let spans = &self.res.dispatch_spans[t];
        let end = spans.partition_point(|&(x, _)| x < b);
        let start = spans[..end].partition_point(|&(_, y)| y <= a);
        &spans[start..end]
    }

    /// Job `j`'s absolute deadline (release + D), if its task has one.
    fn due(&self, j: &JobRecord) -> Option<Nanos> {
        let t = self.spec.tasks.get(j.task)?;
        if t.server == rtpipe_model::Server::Background {
            return None;
        }
        Some(j.release + t.deadline()?)
    }

    /// The foreign time on `cpu` (all CPUs when `None`) in `window`: how
    /// long some job of the level of `tasks` there was pending (released,
    /// not yet published) less the CPU time those jobs can have used in the
    /// window (each at most its demand, at most its read → publish span
    /// inside the window: an upper estimate, so the foreign time is a
    /// lower one).
    fn foreign(&self, cpu: Option<u32>, (a, b): (Nanos, Nanos), tasks: &[usize]) -> Option<Cause> {
        let cpus = cpu.map(|c| vec![c]);
        let (p0, p1) = covering(&self.res.probes, (a, b));
        let mut pending: Vec<(Nanos, Nanos)> = Vec::new();
        let mut used: Nanos = 0;
        let level = |t: usize| self.on(t, &cpus) && self.level(t, tasks);
        for t in (0..self.spec.tasks.len()).filter(|&t| level(t)) {
            let mut by_jobs = 0;
            for j in self.overlapping(t, (a, b)) {
                pending.push((j.release.max(a), j.finish.min(b)));
                by_jobs += j.demand.min(self.could_run(j, (a, b)));
            }
            // The thread's CPU time over the probes around the window
            // bounds it too (it covers a little more than the window). A
            // counter that could not be read (a thread gone at the run's
            // end reads 0) says nothing: a falling counter is ignored.
            let by_probes = match (p0, p1) {
                (Some(p0), Some(p1)) if p0.at <= a && p1.at >= b => p1
                    .run
                    .get(t)
                    .zip(p0.run.get(t))
                    // A thread that ran in the window has a counter above
                    // 0 after it: 0 is one that could not be read.
                    .filter(|&(&x, _)| x > 0)
                    .map(|(x, y)| x - y)
                    .filter(|&d| d >= 0),
                _ => None,
            };
            used += by_probes.map_or(by_jobs, |p| p.min(by_jobs));
        }
        let union = union_length(pending);
        assert!(
            used >= 0,
            "CPU time used in a window is not negative: {used}"
        );
        let ns = union - used;
        (ns > 0).then_some(Cause::Foreign {
            cpu,
            ns,
            dispatcher: self.res.policy == Policy::EdfFifo,
            throttled: cpu.is_some_and(|c| self.self_throttled(c, (a, b))),
        })
    }
}

/// Task `t`'s reservation overruns as spans of its jobs (`jobs`, in
/// release order): from the job before the one the kernel signalled it in through the
/// jobs after it that missed their deadlines (the lag made up by the first
/// one that did not).
fn lags(spec: &Spec, res: &RunResult, t: usize, jobs: &[&JobRecord]) -> Vec<(Nanos, Nanos, Cause)> {
    let (Some(run), Some(task)) = (res.tasks.get(t), spec.tasks.get(t)) else {
        return Vec::new();
    };
    let Some(period) = task
        .fixed_period()
        .filter(|_| res.policy == Policy::Deadline)
    else {
        return Vec::new();
    };
    let due = task.deadline().unwrap_or(period);
    let mut out = Vec::new();
    for &job in &run.reservation_overruns {
        let Ok(first) = jobs.binary_search_by_key(&job, |j| j.index) else {
            continue;
        };
        let late = jobs[first + 1..]
            .iter()
            .take_while(|j| j.finish - j.release > due)
            .count();
        // At least the next job: the overrun may be charged at its
        // wake-up (the kernel charges a reservation from the wake-up that
        // preempts the CPU, so another thread's non-preemptible stretch
        // before the switch eats its runtime) and throttle it until the
        // deadline its wake-up set, which it then meets.
        let last = (first + late).max((first + 1).min(jobs.len() - 1));
        let cause = Cause::ReservationOverrun {
            task: t,
            job,
            affected: (last - first) as u64 + 1,
            lag: period,
        };
        // The signal comes at the thread's next tick on the CPU: the job
        // before may be the one that overran.
        let from = jobs[first.saturating_sub(1)].release;
        out.push((from, jobs[last].finish, cause));
    }
    if res.partitioned {
        let deadline = task.deadline().unwrap_or(period).min(period);
        let r = crate::config::reservation(task.budget(), deadline, period);
        out.extend(kept_deadlines(
            t,
            jobs,
            &run.reservation_overruns,
            (r, period),
        ));
    }
    out
}

/// Task `t`'s jobs (`jobs`, in release order) whose reservation may hold a
/// deadline kept from earlier jobs past their release
/// ([`Cause::StaleDeadline`]), each over its own span, given the jobs the
/// kernel signalled or the run saw overrunning the reservation
/// (`overruns`) and the reservation `r` of a task of period `period`.
///
/// How far after job k's release the kernel's deadline may lie at its
/// wake-up, carry(k), follows from job k−1 (s its start latency; its
/// kernel deadline kd = s + r.deadline after its release when its wake-up
/// renewed it, carry(k−1) when it kept one):
/// - renewed and unthrottled: s + r.deadline − T, the wake-up's lateness
///   less the lead (T − r.deadline);
/// - kept: the job may have run out of the leftover and been throttled
///   until kd, then replenished a period on: carry(k−1) − (T − r.period);
/// - an overrun (signalled at job k−1 or, at the next tick, at job k):
///   throttled at kd and replenished a period on: kd − (T − r.period).
///
/// The largest of these, if positive. A job's start latency alone
/// undercounts it: a job that kept a deadline starts on time with its
/// leftover and is throttled mid-job (docs/runtime.md has the trace).
fn kept_deadlines(
    t: usize,
    jobs: &[&JobRecord],
    overruns: &[u64],
    (r, period): (crate::config::Reservation, Nanos),
) -> Vec<(Nanos, Nanos, Cause)> {
    let replenished = period - r.period;
    let overran = |k: u64| overruns.contains(&k) || overruns.contains(&(k + 1));
    let mut out = Vec::new();
    let mut carry: Nanos = 0;
    let mut prev: Option<&JobRecord> = None;
    for &j in jobs {
        let Some(p) = prev.filter(|p| j.index == p.index + 1) else {
            // No job before it in the log: nothing known to carry.
            carry = 0;
            prev = Some(j);
            continue;
        };
        let start = p.read - p.release;
        let kd = (start + r.deadline).max(carry);
        let mut next = start + r.deadline - period;
        // Whether job k−1 may have been throttled: then what it left of
        // the runtime is no measure of the leftover.
        let mut paused = false;
        if carry > 0 {
            next = next.max(carry - replenished);
            paused = true;
        }
        if overran(p.index) {
            next = next.max(kd - replenished);
            paused = true;
        }
        carry = next.max(0);
        if carry > 0 {
            let cause = Cause::StaleDeadline {
                task: t,
                job: j.index,
                lag: carry,
                ahead: kept_runtime(r, carry, (!paused).then_some(p.demand)),
                own: true,
            };
            out.push((j.release, j.finish, cause));
        }
        prev = Some(j);
    }
    out
}

/// The most runtime reservation `r` can keep with a deadline `carry` ns
/// after the wake-up: the kernel renews a deadline whose leftover exceeds
/// runtime × (deadline − now) / relative deadline (`dl_entity_overflow`;
/// under a constrained deadline it cuts the leftover to that); and at most
/// what the job before left when it ran unthrottled (`used`: its CPU time).
fn kept_runtime(r: crate::config::Reservation, carry: Nanos, used: Option<Nanos>) -> Nanos {
    let fits = i128::from(r.runtime) * i128::from(carry) / i128::from(r.deadline.max(1));
    let fits = Nanos::try_from(fits + 1).unwrap_or(Nanos::MAX);
    let left = used.map_or(r.runtime, |u| (r.runtime - u).max(0));
    fits.min(left)
}

/// How far below the real-time share a CPU's use by the run still counts
/// as having reached it: two probe periods, the probes' grain at both
/// ends of the span.
const SHARE_SLACK: Nanos = 2 * PROBE_PERIOD;

/// Per CPU, the probe instants where the run's own threads there had used
/// at least the kernel's real-time share (`RunResult::rt_share`, less
/// [`SHARE_SLACK`]) over the throttling period before: where the kernel's
/// real-time throttling is the run's own doing. Only under SCHED_FIFO
/// (SCHED_DEADLINE's reservations are not throttled so).
fn saturated(spec: &Spec, res: &RunResult) -> Vec<Vec<Nanos>> {
    let fifo = matches!(res.policy, Policy::Fifo | Policy::EdfFifo);
    let Some((runtime, period)) = res.rt_share.filter(|_| fifo) else {
        return Vec::new();
    };
    let cpus = spec
        .tasks
        .iter()
        .map(|t| t.cpu as usize + 1)
        .max()
        .unwrap_or(0);
    let mut out = vec![Vec::new(); cpus];
    let probes = &res.probes;
    for p in probes {
        // The last probe a period or more before (the first, early on:
        // the kernel throttles within the run's first period too).
        let k = probes.partition_point(|q| q.at <= p.at - period);
        let Some(q) = probes.get(k.saturating_sub(1)) else {
            continue;
        };
        let mut used = vec![0; cpus];
        for (t, task) in spec.tasks.iter().enumerate() {
            // A counter that falls (a thread gone reads 0) says nothing.
            if let (Some(&x), Some(&y)) = (p.run.get(t), q.run.get(t)) {
                used[task.cpu as usize] += (x - y).max(0);
            }
        }
        // A span shorter than the period reaches the share only by using
        // the whole runtime in it.
        let span = (p.at - q.at).max(period);
        for (cpu, &u) in used.iter().enumerate() {
            // u / span ≥ (runtime − slack) / period, without division.
            if i128::from(u) * i128::from(period)
                >= i128::from(runtime - SHARE_SLACK) * i128::from(span)
            {
                out[cpu].push(p.at);
            }
        }
    }
    out
}

/// The total length of a set of intervals (overlaps counted once).
fn union_length(mut spans: Vec<(Nanos, Nanos)>) -> Nanos {
    spans.sort_unstable();
    let (mut total, mut reach) = (0, Nanos::MIN);
    for (s, e) in spans {
        let from = s.max(reach);
        if e > from {
            total += e - from;
        }
        reach = reach.max(e);
    }
    total
}

/// The last probe at or before `a` and the first at or after `b` (the
/// first and last probes where the run's probes do not reach that far).
fn covering(probes: &[Probe], (a, b): (Nanos, Nanos)) -> (Option<&Probe>, Option<&Probe>) {
    let i0 = probes.partition_point(|p| p.at <= a).saturating_sub(1);
    let i1 = probes
        .partition_point(|p| p.at < b)
        .min(probes.len().saturating_sub(1));
    (probes.get(i0), probes.get(i1))
}

/// Steal between two probes on the given CPUs (all when `None`).
fn steal(p0: &Probe, p1: &Probe, cpus: &Option<Vec<u32>>) -> Vec<Cause> {
    (0..p1.steal.len())
        .filter(|&c| cpus.as_ref().is_none_or(|v| v.contains(&(c as u32))))
        .filter_map(|cpu| {
            let ns = p1.steal[cpu] - p0.steal.get(cpu).copied().unwrap_or(0);
            (ns > 0).then_some(Cause::Steal { cpu, ns })
        })
        .collect()
}

#[cfg(test)]
mod tests;
