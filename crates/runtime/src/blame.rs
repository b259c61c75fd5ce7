//! What broke the model in a window of a real run: the evidence an
//! observation above a sound bound may be excused by. A cause counts only
//! inside the observation's window and on the CPUs of the tasks involved;
//! `rtpipe run` excuses the observation only when the causes' total, taken
//! as a disturbance of the analysis (`rtpipe_analysis::disturbance`),
//! grows the bound by at least the excess. Everything else is a violation.

use crate::exec::{Policy, RunResult, RESERVATION_MARGIN};
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
            Cause::Steal { .. } => 0,
            Cause::Overrun {
                demand,
                assumed,
                throttle,
                ..
            } => demand - assumed + throttle,
            Cause::Demand {
                demand, declared, ..
            } => demand - declared,
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
            Cause::Demoted { task } => format!("{} was demoted to SCHED_OTHER", name(task)),
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
        Blame {
            spec,
            res,
            jobs,
            saturated,
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
            }
        }
        for &t in tasks {
            out.extend(self.demands(t, window));
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
mod tests {
    use super::*;
    use rtpipe_joblog::SimResult;

    const SPEC: &str = r#"
[system]
name = "two"
time_unit = "ms"
[channels.shm]
bandwidth = 1000
overhead = 0
[tasks.a]
exec = 1
period = 10
output = { channel = "shm", size = 0 }
[tasks.b]
exec = 1
period = 10
cpu = 1
output = { channel = "shm", size = 0 }
"#;

    const MS: Nanos = 1_000_000;

    fn job(task: usize, index: u64, demand: Nanos) -> JobRecord {
        let release = index as Nanos * 10 * MS;
        JobRecord {
            task,
            index,
            release,
            demand,
            read: release,
            finish: release + demand,
            carried: Vec::new(),
            trigger: None,
        }
    }

    fn probe(at: Nanos, steal: [Nanos; 2]) -> Probe {
        Probe {
            at,
            steal: steal.to_vec(),
            run: Vec::new(),
        }
    }

    /// Task a overruns its job 2 (20–23 ms, 3 ms against 1); CPU 1 (task b)
    /// has 4 ms of steal in 10–20 ms; CPU 0 none; a's job 3 starts 0.5 ms
    /// late and takes 3 ms for 1 ms of CPU with nothing of the run beside
    /// it.
    fn run() -> (Spec, RunResult) {
        let Ok(spec) = Spec::parse("two.toml", SPEC) else {
            panic!("the spec parses");
        };
        let jobs = vec![
            job(0, 0, MS),
            job(1, 0, MS),
            job(0, 1, MS),
            job(0, 2, 3 * MS),
            JobRecord {
                read: 30 * MS + MS / 2,
                finish: 33 * MS + MS / 2,
                ..job(0, 3, MS)
            },
        ];
        let probes = vec![
            probe(0, [0, 0]),
            probe(10 * MS, [0, 0]),
            probe(20 * MS, [0, 4 * MS]),
            probe(30 * MS, [0, 4 * MS]),
            probe(40 * MS, [0, 4 * MS]),
        ];
        let sim = SimResult {
            offsets: vec![0, 0],
            tasks: Vec::new(),
            chains: Vec::new(),
            jobs,
            segments: Vec::new(),
            events: 0,
            horizon: 40 * MS,
        };
        let res = RunResult {
            sim,
            tasks: Vec::new(),
            policy: Policy::Fifo,
            load: 0,
            interrupted: false,
            steal: None,
            elapsed: 40 * MS,
            epoch: 0,
            notes: Vec::new(),
            probes,
            rt_share: None,
            demoted: Vec::new(),
            partitioned: false,
            dispatch: None,
            dispatch_spans: Vec::new(),
            schedule: None,
        };
        (spec, res)
    }

    #[test]
    fn causes_count_only_inside_the_window_and_on_the_tasks_cpus() {
        let (spec, res) = run();
        let b = Blame::new(&spec, &res);
        let at = |w: (Nanos, Nanos), t: &[usize]| b.causes(b.extend(w, t), t);
        // 0–9 ms on CPU 0: nothing happened there then.
        assert_eq!(at((0, 9 * MS), &[0]), vec![]);
        // 21–22 ms on CPU 0: a's overrun; CPU 1's steal is not a's.
        let overrun = Cause::Overrun {
            task: 0,
            job: 2,
            demand: 3 * MS,
            budget: MS,
            assumed: MS,
            throttle: 0,
        };
        assert_eq!(at((21 * MS, 22 * MS), &[0]), vec![overrun]);
        // 12–18 ms on CPU 1: the steal there.
        let steal = Cause::Steal { cpu: 1, ns: 4 * MS };
        assert_eq!(at((12 * MS, 18 * MS), &[1]), vec![steal]);
        // 31–39 ms, from the start of its busy period (job 3's release at
        // 30): job 3 was pending 3.5 ms of it and ran 1 ms.
        let foreign = Cause::Foreign {
            cpu: Some(0),
            ns: 5 * MS / 2,
            dispatcher: false,
            throttled: false,
        };
        assert_eq!(at((31 * MS, 39 * MS), &[0]), vec![foreign]);
        // Outside them, no evidence.
        assert_eq!(Blame::total(&at((0, 9 * MS), &[0])), 0);
    }

    #[test]
    fn a_thread_counter_that_falls_says_nothing() {
        // a's thread ran 1 ms by 30 ms; at 40 ms its counter reads 0 (the
        // thread is gone): the job log alone bounds its CPU time.
        let (spec, mut res) = run();
        for (k, p) in res.probes.iter_mut().enumerate() {
            p.run = vec![if k == 3 { MS } else { 0 }, 0];
        }
        let b = Blame::new(&spec, &res);
        let w = b.extend((31 * MS, 39 * MS), &[0]);
        let foreign = Cause::Foreign {
            cpu: Some(0),
            ns: 5 * MS / 2,
            dispatcher: false,
            throttled: false,
        };
        assert_eq!(b.causes(w, &[0]), vec![foreign]);
    }

    #[test]
    fn the_total_delay_adds_the_causes_up() {
        let c = [
            Cause::Foreign {
                cpu: Some(0),
                ns: 3 * MS,
                dispatcher: false,
                throttled: false,
            },
            Cause::Overrun {
                task: 0,
                job: 0,
                demand: 2 * MS,
                budget: MS,
                assumed: MS,
                throttle: 0,
            },
        ];
        assert_eq!(Blame::total(&c), 4 * MS);
        // Steal is named but already inside the foreign time.
        assert_eq!(Blame::total(&[Cause::Steal { cpu: 0, ns: 1 }]), 0);
        assert_eq!(Blame::total(&[]), 0);
        assert_eq!(
            Blame::total(&[Cause::BestEffort, Cause::Steal { cpu: 0, ns: 1 }]),
            Nanos::MAX
        );
    }

    /// A job above its budget delays its own response by all of its CPU
    /// time above its declared demand x (R(job) assumes x), and another
    /// task's by its time above the budget C (the analysis charges C): g
    /// (x 174 µs, C 200 µs) ran 284 µs in a 307 µs response, l (below it)
    /// waited. Counted from C alone, g's own lateness (133 µs above x) was
    /// left 26 µs short of what delayed it: a false alarm.
    #[test]
    fn an_overrun_counts_from_the_demand_for_its_own_job_and_from_the_budget_for_others() {
        let src = "[system]\nname = \"o\"\ntime_unit = \"us\"\n[tasks.g]\nexec = 174\nbudget = 200\nperiod = 1000\n[tasks.l]\nexec = 100\nperiod = 5000\n";
        let spec = Spec::parse("o.toml", src).unwrap_or_else(|e| panic!("{e}"));
        let us = 1_000;
        let g = JobRecord {
            finish: 307 * us,
            ..job(0, 0, 284 * us)
        };
        let l = JobRecord {
            read: 307 * us,
            finish: 407 * us,
            ..job(1, 0, 100 * us)
        };
        let (_, mut res) = run();
        res.sim.jobs = vec![g, l];
        res.probes = Vec::new();
        let b = Blame::new(&spec, &res);
        let overrun = |assumed| Cause::Overrun {
            task: 0,
            job: 0,
            demand: 284 * us,
            budget: 200 * us,
            assumed,
            throttle: 0,
        };
        let own = b.causes((0, 307 * us), &[0]);
        assert_eq!(own[0], overrun(174 * us), "{own:?}");
        // 110 µs above x, and 23 µs with g pending but not running.
        assert_eq!(Blame::total(&own), 133 * us, "{own:?}");
        let other = b.causes((0, 407 * us), &[1]);
        assert_eq!(other[0], overrun(200 * us), "{other:?}");
        assert_eq!(other[0].delay(), 84 * us);
        // A job within its budget is no overrun: its time above x is.
        res.sim.jobs[0].demand = 190 * us;
        let b = Blame::new(&spec, &res);
        let own = b.causes((0, 307 * us), &[0]);
        assert!(
            own.iter().all(|c| !matches!(c, Cause::Overrun { .. })),
            "{own:?}"
        );
        assert_eq!(own[0].delay(), 16 * us, "{own:?}");
    }

    /// Foreign time where the run's own threads had used the CPU's
    /// real-time share is the kernel's throttling of the run's own
    /// overload: named, and no excuse. Here a's thread ran all of 0–40 ms
    /// on CPU 0 under a share of 9 ms per 10 ms; CPU 1's b ran 1 ms in 10.
    #[test]
    fn throttling_by_the_run_s_own_demand_excuses_nothing() {
        let (spec, mut res) = run();
        for p in &mut res.probes {
            p.run = vec![p.at, p.at / 10];
        }
        res.rt_share = Some((9 * MS, 10 * MS));
        let b = Blame::new(&spec, &res);
        let w = b.extend((31 * MS, 39 * MS), &[0]);
        let throttled = Cause::Foreign {
            cpu: Some(0),
            ns: 5 * MS / 2,
            dispatcher: false,
            throttled: true,
        };
        let causes = b.causes(w, &[0]);
        assert_eq!(causes, vec![throttled.clone()]);
        assert_eq!(Blame::total(&causes), 0);
        assert!(throttled.describe(&spec).contains("excuses nothing"));
        // Below the share, the same time is foreign and excuses.
        for p in &mut res.probes {
            p.run = vec![p.at / 4, 0];
        }
        let b = Blame::new(&spec, &res);
        assert_eq!(Blame::total(&b.causes(w, &[0])), 5 * MS / 2);
        // Without throttling (sched_rt_runtime_us = -1), none is the run's.
        res.rt_share = None;
        for p in &mut res.probes {
            p.run = vec![p.at, 0];
        }
        let b = Blame::new(&spec, &res);
        assert_eq!(Blame::total(&b.causes(w, &[0])), 5 * MS / 2);
    }

    /// Under the EDF dispatcher a job pending past the window's end is not
    /// credited with the time a job of an earlier deadline ran, nor with
    /// the dispatcher's release: lo (D 20 ms) runs 0–1 ms, hi (D 5 ms) is
    /// released at 1, dispatched 1.00–1.02, reads at 1.05 and publishes at
    /// 2.05; lo ends at 3.05. In hi's window [0, 2.05] lo can have run 1.03
    /// ms (not its whole 2 ms): the 20 µs dispatch is foreign time; the
    /// 30 µs after it, where lo may still have run, is not.
    #[test]
    fn edf_windows_do_not_credit_a_later_deadline_with_what_preempted_it() {
        let src = "[system]\nname = \"e\"\nscheduler = \"edf\"\n[tasks.hi]\nexec = 1\nperiod = 4\nserver = \"none\"\n[tasks.lo]\nexec = 2\nperiod = 20\nserver = \"none\"\n";
        let spec = Spec::parse("e.toml", src).unwrap_or_else(|e| panic!("{e}"));
        let us = 1_000;
        let hi = JobRecord {
            release: MS,
            read: MS + 50 * us,
            finish: 2 * MS + 50 * us,
            ..job(0, 0, MS)
        };
        let lo = JobRecord {
            finish: 3 * MS + 50 * us,
            ..job(1, 0, 2 * MS)
        };
        let (_, mut res) = run();
        res.sim.jobs = vec![hi, lo];
        res.probes = Vec::new();
        res.policy = Policy::EdfFifo;
        res.dispatch_spans = vec![vec![(MS, MS + 20 * us)], Vec::new()];
        let b = Blame::new(&spec, &res);
        let w = b.extend((MS, 2 * MS + 50 * us), &[0]);
        assert_eq!(w, (0, 2 * MS + 50 * us));
        let foreign = Cause::Foreign {
            cpu: Some(0),
            ns: 20 * us,
            dispatcher: true,
            throttled: false,
        };
        assert_eq!(b.causes(w, &[0]), vec![foreign]);
        // Without the dispatcher's spans, nothing is seen.
        res.dispatch_spans = Vec::new();
        let b = Blame::new(&spec, &res);
        assert_eq!(b.causes(w, &[0]), vec![]);
    }
}
