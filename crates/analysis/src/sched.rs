//! Priorities, response times and schedulability tests per CPU.

use rtpipe_model::policy::{Budget, EventAnalysis, ResponseAnalysis};
use rtpipe_model::{Nanos, ResourceProtocol, SchedTest, Server, Spec, Task, MAX_TIME};

mod edf_times;
pub(crate) use crate::blocking::tasks_on;
use edf_times::server_period;
pub(crate) use edf_times::{deadline_at, edf_overhead_load};
pub use edf_times::{
    edf_read_to_publish_at, edf_response_at, edf_response_disturbed, edf_response_times_at, EdfCpu,
};

mod busy;
pub(crate) use busy::busy_window;
mod slack;
pub use busy::{
    level_response, level_response_from, level_response_within, response_time,
    response_time_jitter, OwnJobs, MAX_BUSY_JOBS, MAX_WINDOW_STEPS,
};
pub(crate) use slack::may_run_in_slack;

/// Timing facts of one task that the latency analysis builds on.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTiming {
    /// C: budget of the pipe terminal.
    pub budget: Nanos,
    /// x = Δin + p + Δout: worst-case demand of a job.
    pub demand: Nanos,
    /// Best-case demand of a job: Δin + p_min + Δout.
    pub demand_min: Nanos,
    /// T.
    pub period: Nanos,
    /// D: the relative deadline (T unless the spec gives one).
    pub deadline: Nanos,
    /// J: release jitter (0 unless the spec gives one). Response times
    /// are measured from the nominal release and include it.
    pub jitter: Nanos,
    /// Rank on its CPU, 1 = highest; `None` under EDF and for background tasks.
    pub priority: Option<usize>,
    /// The highest rank the task can run at: its own, the rank of the Main
    /// VCPU it serves (PIBS priority inheritance), or the ceiling of a
    /// resource it locks ([`crate::blocking::locking_rank`]).
    pub top_priority: Option<usize>,
    /// B: the longest a job can wait for lower-priority critical sections
    /// ([`crate::blocking::blocking`]); included in the response times.
    pub blocking: Nanos,
    /// The CPU it runs on.
    pub cpu: u32,
    /// Worst-case time for the VCPU to deliver its whole budget C after a
    /// release, for every job, also one released while an earlier one is
    /// pending (exact RTA over the level-i busy period under RM,
    /// [`level_response`]; Spuri's EDF analysis under EDF). `None` when it
    /// does not exist (overload) or the task is background.
    pub response_time: Option<Nanos>,
    /// Worst-case response time of any job of demand x (≤ response_time),
    /// the figure the latency bounds use where it is within the period
    /// ([`TaskTiming::bounded_response`]).
    pub job_response_time: Option<Nanos>,
    /// W: a bound on the time from a job's read (its start) to its publish
    /// (its completion), at most `job_response_time`: under fixed priority
    /// the interference of releases after the start, without the job's
    /// own release jitter, switch in and ceiling blocking (all before the
    /// start, `fp_start_to_finish`; for a sporadic server that may wait
    /// for its budget after its start, the busy window of its CPU from the
    /// start, `slack`); under EDF from Spuri's `w_i(0)`
    /// ([`crate::edf::start_to_finish`]), where a job's response is mostly waiting
    /// to start. docs/analysis.md.
    pub read_to_publish: Option<Nanos>,
    /// In a spec with threads or data-triggered tasks, what the event
    /// analysis found ([`crate::events`]); `None` in a periodic spec.
    pub events: Option<crate::events::EventTiming>,
}

impl TaskTiming {
    /// A job's latest finish after release, if it finishes within its period.
    pub fn bounded_response(&self) -> Option<Nanos> {
        self.job_response_time.filter(|&r| r <= self.period)
    }

    /// [`TaskTiming::read_to_publish`] where the response is bounded
    /// ([`TaskTiming::bounded_response`]).
    pub fn bounded_read_to_publish(&self) -> Option<Nanos> {
        self.bounded_response().and(self.read_to_publish)
    }
}

/// The verdict of the chosen test on one CPU.
#[derive(Debug, Clone, PartialEq)]
pub struct CpuVerdict {
    /// The CPU.
    pub cpu: u32,
    /// How many guaranteed (not background) tasks run on it.
    pub tasks: usize,
    /// Σ C/T over the CPU's guaranteed tasks.
    pub utilization: f64,
    /// The quantity compared with the bound: Σ U (Liu–Layland, EDF), Π (U+1)
    /// (hyperbolic), the largest R/T (RTA).
    pub value: f64,
    /// The bound: n(2^{1/n} − 1), 2, 1 or 1.
    pub bound: f64,
    /// It passes the test.
    pub schedulable: bool,
}

/// The verdict of the system's test on every CPU.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedulability {
    /// The test.
    pub test: SchedTest,
    /// One verdict per CPU that has tasks.
    pub cpus: Vec<CpuVerdict>,
    /// Every CPU passes.
    pub schedulable: bool,
}

/// Interference a higher-priority task imposes per release: its budget when a
/// server enforces one (it can never take more), its demand otherwise.
pub fn interference(t: &Task) -> Nanos {
    match t.server {
        Server::Main | Server::Io => t.budget(),
        Server::None | Server::Background => t.demand(),
    }
}

/// The highest rank each task can run at: an I/O VCPU that serves a Main
/// VCPU inherits that one's rank while it has a job pending.
pub fn top_priorities(spec: &Spec, prio: &[Option<usize>]) -> Vec<Option<usize>> {
    spec.tasks
        .iter()
        .enumerate()
        .map(|(i, t)| match (prio[i], t.serves.and_then(|m| prio[m])) {
            (Some(own), Some(served)) => Some(own.min(served)),
            (own, _) => own,
        })
        .collect()
}

/// The guaranteed tasks that can run above task `i` on its CPU: rank at or
/// above i's own (an inherited rank may win the tie).
pub fn interferers(
    spec: &Spec,
    prio: &[Option<usize>],
    top: &[Option<usize>],
    i: usize,
) -> Vec<usize> {
    (0..spec.tasks.len())
        .filter(|&j| runs_above(spec, prio, top, j, i))
        .collect()
}

/// Task `j` can run above task `i`: a guaranteed task of i's CPU other
/// than i whose highest rank is at or above i's own (the rule of
/// [`interferers`]).
fn runs_above(
    spec: &Spec,
    prio: &[Option<usize>],
    top: &[Option<usize>],
    j: usize,
    i: usize,
) -> bool {
    let o = &spec.tasks[j];
    o.cpu == spec.tasks[i].cpu && o.server != Server::Background && outranks(j, top[j], i, prio[i])
}

/// Of two guaranteed tasks of one CPU, `j` (highest rank `top_j`) can run
/// above `i` (rank `prio_i`): the rank part of [`runs_above`].
fn outranks(j: usize, top_j: Option<usize>, i: usize, prio_i: Option<usize>) -> bool {
    j != i && top_j <= prio_i
}

/// A guaranteed task as the tasks below it see it, stored per CPU so that
/// a task's analysis reads its CPU's in one contiguous run (at 100,000
/// tasks, reading each `Task` instead missed the cache on most reads).
#[derive(Debug, Clone, Copy)]
struct Interferer {
    task: usize,
    /// Its highest rank.
    top: Option<usize>,
    /// I_j, T_j, J_j.
    load: (Nanos, Nanos, Nanos),
}

/// What the tasks that can run above task `i` impose, as (I_j, T_j, J_j):
/// the `hp` of [`response_time_jitter`], with the spec's overheads
/// ([`crate::overheads`]: `I_j + 2·cs` per job, and the kernel work of
/// every release on the CPU as interferers of their own). A PIBS server
/// ranked below i that runs above it only by inheritance brings its
/// carry-in ([`inherited_carry_in`]); `None` when one has no response time,
/// so nothing bounds what it brings.
pub fn hp_load(
    spec: &Spec,
    prio: &[Option<usize>],
    top: &[Option<usize>],
    i: usize,
) -> Option<Vec<(Nanos, Nanos, Nanos)>> {
    Levels::new(spec, prio, top).hp_load(i)
}

/// The fixed-priority facts every task's analysis shares, built once per
/// analysis (docs/analysis.md, "Scale"): the ranks, the tasks by CPU, the
/// resources' ceilings and each CPU's kernel load. With them a task's
/// analysis looks at its own CPU's tasks only, never at the whole system.
pub(crate) struct Levels<'a> {
    spec: &'a Spec,
    prio: &'a [Option<usize>],
    top: &'a [Option<usize>],
    by_cpu: rtpipe_model::TasksByCpu,
    /// Per CPU of `by_cpu`, its guaranteed tasks.
    guaranteed: Vec<Vec<Interferer>>,
    ceilings: Vec<Option<usize>>,
    /// Per CPU of `by_cpu`, [`crate::overheads::kernel_load`] (empty
    /// without overheads).
    kernel: Vec<Vec<(Nanos, Nanos, Nanos)>>,
    /// Under EDF, per CPU of `by_cpu`, its tasks at the spec's periods
    /// (empty under fixed priority).
    edf: Vec<EdfCpu<'a>>,
    /// Under EDF, per CPU of `by_cpu`, Baruah's b(t) at the spec's
    /// deadlines ([`crate::blocking::srp_spec_steps_among`]; empty under
    /// fixed priority and without resources).
    srp: Vec<Vec<(Nanos, Nanos)>>,
    /// Per CPU of `by_cpu`, its guaranteed tasks as (highest rank, task),
    /// ascending: the tasks above a task are a prefix
    /// ([`Levels::interferers`]). Built at the first ask (the event
    /// analysis'; the periodic path reads `guaranteed`).
    ranked: std::cell::OnceCell<Vec<RankedCpu>>,
}

/// A CPU's guaranteed tasks as (highest rank, task), ascending.
type RankedCpu = Vec<(Option<usize>, usize)>;

impl<'a> Levels<'a> {
    pub(crate) fn new(spec: &'a Spec, prio: &'a [Option<usize>], top: &'a [Option<usize>]) -> Self {
        let by_cpu = spec.tasks_by_cpu();
        let periods: Vec<Nanos> = if spec.overheads.is_zero() {
            Vec::new()
        } else {
            spec.tasks.iter().map(period_or_max).collect()
        };
        let kernel = by_cpu
            .iter()
            .map(|(_, on)| crate::overheads::kernel_load_among(spec, on.iter().copied(), &periods))
            .collect();
        let guaranteed = by_cpu
            .iter()
            .map(|(_, on)| {
                let on = on.iter().copied();
                on.filter(|&j| spec.tasks[j].server != Server::Background)
                    .map(|j| {
                        let o = &spec.tasks[j];
                        let load = (interference(o), period_or_max(o), o.jitter);
                        Interferer {
                            task: j,
                            top: top[j],
                            load,
                        }
                    })
                    .collect()
            })
            .collect();
        let edf_on = !spec.policy().fixed_priority();
        let edf = if edf_on {
            let periods: Vec<Nanos> = spec.tasks.iter().map(period_or_max).collect();
            by_cpu
                .iter()
                .map(|(_, on)| EdfCpu::new(spec, &periods, on))
                .collect()
        } else {
            Vec::new()
        };
        let srp = if edf_on && !spec.resources.is_empty() {
            by_cpu
                .iter()
                .map(|(_, on)| crate::blocking::srp_spec_steps_among(spec, on))
                .collect()
        } else {
            Vec::new()
        };
        Levels {
            spec,
            prio,
            top,
            ceilings: crate::blocking::ceilings(spec, prio),
            by_cpu,
            guaranteed,
            kernel,
            edf,
            srp,
            ranked: std::cell::OnceCell::new(),
        }
    }

    /// Under EDF, task `i`'s CPU at the spec's periods.
    fn edf_cpu(&self, i: usize) -> &EdfCpu<'a> {
        let k = self.cpu_index(self.spec.tasks[i].cpu);
        &self.edf[k]
    }

    /// The place of `cpu` in `by_cpu`: a CPU some task runs on.
    fn cpu_index(&self, cpu: u32) -> usize {
        self.by_cpu
            .position(cpu)
            .unwrap_or_else(|| panic!("CPU {cpu} has no task"))
    }

    /// Under EDF, `cpu`'s b(t) at the spec's deadlines (none without
    /// resources or under fixed priority).
    fn srp_steps(&self, cpu: u32) -> &[(Nanos, Nanos)] {
        if self.srp.is_empty() {
            return &[];
        }
        &self.srp[self.cpu_index(cpu)]
    }

    /// The guaranteed tasks that can run above task `i` ([`interferers`]).
    fn above(&self, i: usize) -> impl Iterator<Item = &Interferer> + '_ {
        let k = self.by_cpu.position(self.spec.tasks[i].cpu);
        let on = k.map_or(&[][..], |k| &self.guaranteed[k][..]);
        let prio_i = self.prio[i];
        on.iter()
            .filter(move |x| outranks(x.task, x.top, i, prio_i))
    }

    /// The tasks of task `i`'s CPU.
    fn cpu_of(&self, i: usize) -> &[usize] {
        self.by_cpu.on(self.spec.tasks[i].cpu)
    }

    /// [`interferers`] of task `i`, in the order of their highest rank
    /// (then of declaration): the prefix of the CPU's `ranked` tasks that
    /// [`outranks`] `i`, `i` itself left out, with no filter over the rest
    /// (docs/analysis.md "Cost at 1,000 tasks", tenth round). Every user of
    /// the list is indifferent to its order: the demand is a saturating
    /// sum, and the load guard is exact ([`crate::load::full`]).
    fn interferers(&self, i: usize) -> Vec<usize> {
        let (on, len) = self.ranked_prefix(i);
        let mut out = Vec::with_capacity(len);
        out.extend(on[..len].iter().map(|&(_, j)| j).filter(|&j| j != i));
        out
    }

    /// Task `i`'s CPU's `ranked` tasks and how many of them lead: those
    /// that [`outranks`] `i`, and `i` itself among them when it is
    /// guaranteed.
    fn ranked_prefix(&self, i: usize) -> (&[(Option<usize>, usize)], usize) {
        let ranked = self.ranked.get_or_init(|| self.rank_sorted());
        let k = self.by_cpu.position(self.spec.tasks[i].cpu);
        let on = k.map_or(&[][..], |k| &ranked[k][..]);
        let prio_i = self.prio[i];
        // `outranks` holds of a prefix: its rank test is `top_j ≤ prio_i`,
        // and `i` itself, whose highest rank is at or above its own, sits
        // inside it.
        let len = on.partition_point(|&(top, j)| j == i || outranks(j, top, i, prio_i));
        (on, len)
    }

    /// Per CPU of `by_cpu`, its guaranteed tasks as (highest rank, task),
    /// ascending.
    fn rank_sorted(&self) -> Vec<RankedCpu> {
        let sorted = |on: &Vec<Interferer>| {
            let mut ranked: Vec<(Option<usize>, usize)> =
                on.iter().map(|x| (x.top, x.task)).collect();
            ranked.sort_unstable();
            ranked
        };
        self.guaranteed.iter().map(sorted).collect()
    }

    /// [`crate::blocking::blocking`] of task `i`.
    fn blocking(&self, i: usize) -> Nanos {
        let on = (self.cpu_of(i), self.srp_steps(self.spec.tasks[i].cpu));
        crate::blocking::blocking_with(self.spec, self.prio, &self.ceilings, on, i)
    }

    /// [`hp_load`] of task `i`.
    fn hp_load(&self, i: usize) -> Option<Vec<(Nanos, Nanos, Nanos)>> {
        let spec = self.spec;
        // Each interfering job also pays the two switches it causes; every
        // release on the CPU its kernel work (`overheads`).
        let switches = crate::overheads::per_job(spec, i);
        let mut hp = Vec::new();
        for x in self.above(i) {
            let (work, period, jitter) = x.load;
            let (work, jitter) = if self.prio[x.task] > self.prio[i] {
                inherited_carry_in(self, x.task)?
            } else {
                (work, jitter)
            };
            hp.push((work.saturating_add(switches), period, jitter));
        }
        if let Some(k) = self.by_cpu.position(spec.tasks[i].cpu) {
            hp.extend_from_slice(&self.kernel[k]);
        }
        Some(hp)
    }
}

/// The per-job work and equivalent release jitter of a PIBS server `j` for
/// a task ranked above j's own rank, which j runs above only while it
/// inherits the rank of the Main VCPU it serves. Such a server can have
/// jobs pending when that task's busy period starts (its own rank left it
/// waiting), and at the inherited rank it runs them back to back while its
/// eligibility time lags behind the clock: more than ⌈t / T_j⌉ budgets in a
/// window of t. Every job of j runs within R_j of its nominal release, so
/// (Bertogna and Cirinei 2007) it brings at most ⌈(t + R_j − c) / T_j⌉ · c
/// in any window of t, with c the most one job runs (its budget or its
/// demand) and R_j the larger of j's two figures at its own rank: the
/// (c, R_j − c) returned. `None` when j has no response time within its
/// period (its backlog, hence its catch-up, has no bound). docs/analysis.md.
fn inherited_carry_in(levels: &Levels, j: usize) -> Option<(Nanos, Nanos)> {
    let (spec, prio, top) = (levels.spec, levels.prio, levels.top);
    let o = &spec.tasks[j];
    // Only inheritance puts a task ranked below i above it (`interferers`);
    // the recursion goes to ever lower ranks, so it ends.
    assert!(
        top[j] < prio[j] && o.serves.is_some(),
        "task `{}` runs above a higher-ranked task without inheriting a rank",
        o.name
    );
    let (budget_r, job_r, _) = response_times(levels, j);
    let r = budget_r?.max(job_r?);
    let c = interference(o).max(o.demand());
    Some((c, r.checked_sub(c)?))
}

/// Tolerance of the utilisation tests: sums of quotients may round above a
/// bound they meet exactly.
const UTIL_EPS: f64 = 1e-12;

/// A utilisation-based test on one CPU (not RTA) from the utilisations of
/// its guaranteed tasks: (value, bound, passes).
pub fn utilization_test(test: SchedTest, us: &[f64]) -> (f64, f64, bool) {
    let n = us.len();
    // An empty sum is -0.0 (shown "-0.0000"); adding 0.0 makes it 0.
    let u: f64 = us.iter().sum::<f64>() + 0.0;
    match test {
        SchedTest::LiuLayland => {
            let b = if n == 0 {
                1.0
            } else {
                n as f64 * (2f64.powf(1.0 / n as f64) - 1.0)
            };
            (u, b, u <= b + UTIL_EPS)
        }
        SchedTest::Hyperbolic => {
            let p: f64 = us.iter().map(|x| x + 1.0).product();
            (p, 2.0, p <= 2.0 + UTIL_EPS)
        }
        SchedTest::Edf => (u, 1.0, u <= 1.0 + UTIL_EPS),
        SchedTest::Rta | SchedTest::Qpa => {
            panic!(
                "utilization_test: {} is not a utilisation test",
                test.name()
            )
        }
    }
}

/// Response times, priorities and the schedulability verdict. Tasks without a
/// fixed period must not be passed here (the CLI checks first).
pub fn analyze(spec: &Spec) -> (Vec<TaskTiming>, Schedulability) {
    let prio = spec.policy().priorities(spec);
    let top = top_priorities(spec, &prio);
    let levels = Levels::new(spec, &prio, &top);
    let (responses, events) = all_responses(&levels);
    let timings: Vec<TaskTiming> = responses
        .into_iter()
        .zip(events)
        .enumerate()
        .map(|(i, ((rt, jrt, w), events))| {
            let t = &spec.tasks[i];
            TaskTiming {
                budget: t.budget(),
                demand: t.demand(),
                demand_min: t.demand_min(),
                // A data-triggered task's nominal rate, from its
                // triggers' (for the paper's terms and the utilisation).
                period: spec.activation_period(i).unwrap_or(MAX_TIME),
                deadline: t.deadline().unwrap_or(MAX_TIME),
                jitter: t.jitter,
                priority: prio[i],
                top_priority: top[i].min(crate::blocking::locking_rank_with(
                    spec,
                    &prio,
                    &levels.ceilings,
                    i,
                )),
                blocking: levels.blocking(i),
                cpu: t.cpu,
                response_time: rt,
                job_response_time: jrt,
                read_to_publish: w,
                events,
            }
        })
        .collect();
    let mut timings = timings;
    let bounded: Vec<bool> = timings
        .iter()
        .map(|t| t.bounded_response().is_some())
        .collect();
    let fixed = spec.policy().fixed_priority();
    let above = |j: usize, i: usize| {
        spec.tasks[j].cpu == spec.tasks[i].cpu && (!fixed || runs_above(spec, &prio, &top, j, i))
    };
    for i in crate::overheads::unaccounted(spec, &bounded, above) {
        (timings[i].response_time, timings[i].job_response_time) = (None, None);
    }
    let verdicts: Vec<CpuVerdict> = levels
        .by_cpu
        .iter()
        .map(|(cpu, on)| cpu_verdict(spec, &timings, (cpu, on), levels.srp_steps(cpu)))
        .collect();
    let schedulable = verdicts.iter().all(|v| v.schedulable);
    (
        timings,
        Schedulability {
            test: spec.schedulability,
            cpus: verdicts,
            schedulable,
        },
    )
}

/// Every task's response times, and in a spec with threads or
/// data-triggered tasks its event facts (the policy's analysis of them).
fn all_responses(levels: &Levels) -> (Vec<Responses>, Vec<Option<crate::events::EventTiming>>) {
    let spec = levels.spec;
    if !spec.event_triggered() {
        let mut responses: Vec<Responses> = (0..spec.tasks.len())
            .map(|i| response_times(levels, i))
            .collect();
        narrow_slack_read_to_publish(levels, &mut responses);
        return (responses, vec![None; spec.tasks.len()]);
    }
    match spec.policy().events {
        Some(EventAnalysis::HolisticFifo) => event_responses(levels),
        None => panic!(
            "validation admits threads and data-triggered tasks only under a policy that analyses them, not under {}",
            spec.policy().name
        ),
    }
}

/// A task's (budget, job, read-to-publish) response times.
type Responses = (Option<Nanos>, Option<Nanos>, Option<Nanos>);

/// Under fixed priority, the W of each sporadic server that may wait for
/// its budget after its start (`fp_start_to_finish` gave `R`), narrowed to
/// the busy window of its CPU from the start ([`slack::slack_start_to_finish`]),
/// which needs every other task's response time, hence a second pass.
fn narrow_slack_read_to_publish(levels: &Levels, responses: &mut [Responses]) {
    if levels.spec.policy().response != ResponseAnalysis::Rta {
        return;
    }
    for i in 0..responses.len() {
        if responses[i].2.is_none() || !may_run_in_slack(levels.spec, i) {
            continue;
        }
        if let Some(w) = slack::slack_start_to_finish(levels, i, responses) {
            responses[i].2 = responses[i].2.map(|r| r.min(w));
        }
    }
}

/// The figures of a spec with threads or data-triggered tasks
/// ([`crate::events`]), with this module's fixed-priority analysis for
/// its thread-less periodic tasks: per task its response times (W = R:
/// under fixed priority nothing above is pending when a job starts, and a
/// thread's job runs to completion), and its event facts.
fn event_responses(levels: &Levels) -> (Vec<Responses>, Vec<Option<crate::events::EventTiming>>) {
    crate::events::analyze(levels.spec, levels)
        .into_iter()
        .map(|r| ((r.budget, r.job, r.job), Some(r.timing)))
        .unzip()
}

/// The fixed-priority analysis as the event analysis asks for it.
impl crate::events::FixedPriority for Levels<'_> {
    fn above(&self, i: usize) -> Vec<usize> {
        self.interferers(i)
    }

    fn interference(&self, j: usize) -> Nanos {
        interference(&self.spec.tasks[j])
    }

    /// Per CPU its guaranteed tasks by their highest rank; a task's
    /// prefix those [`Levels::ranked_prefix`] says lead.
    fn ranked(&self, n: usize) -> crate::events::Ranked {
        let prefix = (0..n)
            .map(|i| {
                let k = self.cpu_index(self.spec.tasks[i].cpu);
                (k, self.ranked_prefix(i).1)
            })
            .collect();
        let ranked = self.ranked.get_or_init(|| self.rank_sorted());
        let lists = ranked
            .iter()
            .map(|on| on.iter().map(|&(_, j)| j).collect())
            .collect();
        crate::events::Ranked { lists, prefix }
    }

    fn blocking(&self, i: usize) -> Nanos {
        Levels::blocking(self, i)
    }

    fn periodic_response(
        &self,
        i: usize,
        hp: &[(Nanos, Nanos, Nanos)],
    ) -> (Option<Nanos>, Option<Nanos>) {
        rta_response(self, i, hp)
    }

    fn periodic_response_windows(
        &self,
        i: usize,
        hp: &[(Nanos, Nanos, Nanos)],
        warm: Option<&crate::events::FpStops>,
    ) -> (crate::events::Figures, Option<crate::events::FpStops>) {
        let (figures, stops) = rta_response_windows(self, i, hp, true, warm);
        (figures, Some(stops))
    }
}

/// A task's period, or [`MAX_TIME`] when none is fixed (callers are to rule
/// that out first, see [`analyze`]), so that such a task counts as almost
/// never released rather than as a panic.
fn period_or_max(t: &Task) -> Nanos {
    t.fixed_period().unwrap_or(MAX_TIME)
}

/// Task `i`'s (budget, job) response times and its read-to-publish bound:
/// under RM the exact RTA over its level-i busy period against the tasks
/// that can run above it ([`level_response`]; the read-to-publish bound
/// from the start, [`fp_start_to_finish`]); under EDF with constant-bandwidth
/// servers Spuri's analysis, when its CPU is not overloaded. A background
/// task has none: nothing guarantees it the CPU.
fn response_times(levels: &Levels, i: usize) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let spec = levels.spec;
    let t = &spec.tasks[i];
    if t.server == Server::Background {
        return (None, None, None);
    }
    match spec.policy().response {
        ResponseAnalysis::Rta => {
            let Some(hp) = levels.hp_load(i) else {
                return (None, None, None);
            };
            let (rt, jrt) = rta_response(levels, i, &hp);
            let w = jrt.map(|r| fp_start_to_finish(levels, i, &hp).map_or(r, |w| w.min(r)));
            (rt, jrt, w)
        }
        ResponseAnalysis::ServerPeriod => {
            let (rt, jrt) = server_period(levels.edf_cpu(i), i);
            (rt, jrt, jrt)
        }
        ResponseAnalysis::EdfRta => {
            let cpu = levels.edf_cpu(i);
            let (rt, jrt) = edf_response_times_at(cpu, i);
            (rt, jrt, jrt.map(|r| edf_read_to_publish_at(cpu, i).min(r)))
        }
    }
}

/// W under fixed priority: a bound on the time from a job's start (its
/// read) to its completion (its publish), against `hp` as `hp_load` gives
/// it. When the job starts nothing above it is pending (and no kernel
/// work: a job reads after the kernel work and its own switch), so only
/// releases after the start interfere: the least fixed point of
/// `w = x + B_after + Σ_{j ∈ hp} ⌈(w + J_j)/T_j⌉ · I_j` (with the kernel
/// work as interferers), `B_after` as [`fp_start_after`] says. `None`
/// (take R) where [`fp_start_after`] is. docs/analysis.md, "From the read
/// to the publish under fixed priority".
fn fp_start_to_finish(levels: &Levels, i: usize, hp: &[(Nanos, Nanos, Nanos)]) -> Option<Nanos> {
    let after = if fp_start_after(levels.spec, i)? {
        levels.blocking(i)
    } else {
        0
    };
    busy_window(levels.spec.tasks[i].demand().checked_add(after)?, hp)
}

/// Whether task `i`'s blocking B can fall after a job's start under fixed
/// priority: under PIP yes (a job is blocked when it reaches a section
/// whose resource is held); under PCP and SRP no (run as the immediate
/// ceiling, a job waits for at most one section before it starts, and
/// never finds its resource held after). The job's own release jitter and
/// its switch in fall before the start under every protocol. `None` for a
/// job that may wait for its budget after it started: a budget server,
/// unless a sporadic server whose job fits its budget and is released on
/// time (its budget is then whole at every release).
pub(crate) fn fp_start_after(spec: &Spec, i: usize) -> Option<bool> {
    let t = &spec.tasks[i];
    let whole_budget = match spec.policy().budget(t.server) {
        None => true,
        Some(Budget::Sporadic) => t.demand() <= t.budget() && t.jitter == 0,
        Some(Budget::Pibs | Budget::Cbs) => false,
    };
    whole_budget.then_some(spec.resource_protocol == ResourceProtocol::Pip)
}

/// Task `i`'s (budget, job) response times under fixed priority against
/// `hp` as (I_j, T_j, J_j): [`level_response`] over its level-i busy
/// period.
fn rta_response(
    levels: &Levels,
    i: usize,
    hp: &[(Nanos, Nanos, Nanos)],
) -> (Option<Nanos>, Option<Nanos>) {
    rta_response_windows(levels, i, hp, false, None).0
}

/// [`rta_response`] with, when `record`, the fixed points each figure's
/// jobs stopped at ([`level_response_from`], each started from `warm`'s
/// where given; none otherwise).
fn rta_response_windows(
    levels: &Levels,
    i: usize,
    hp: &[(Nanos, Nanos, Nanos)],
    record: bool,
    warm: Option<&crate::events::FpStops>,
) -> ((Option<Nanos>, Option<Nanos>), crate::events::FpStops) {
    let spec = levels.spec;
    let t = &spec.tasks[i];
    let blocking = levels.blocking(i);
    let own = |work: Nanos| OwnJobs {
        work,
        switch: crate::overheads::own(spec, i),
        blocking,
        jitter: t.jitter,
        period: period_or_max(t),
    };
    // A PIBS server with a backlog runs by its own replenishment
    // rules at instants the busy period does not model (the
    // simulator found its later jobs above the figure): none for
    // one whose busy period holds more than one own job.
    let pibs = spec.policy().budget(t.server) == Some(rtpipe_model::policy::Budget::Pibs);
    let r = |work: Nanos, warm: &[Nanos]| {
        let (r, stops) = if record {
            level_response_from(own(work), hp, Nanos::MAX, warm)
        } else {
            (level_response_within(own(work), hp, Nanos::MAX), Vec::new())
        };
        (r.filter(|&r| !pibs || r <= period_or_max(t)), stops)
    };
    let (job, job_stops) = r(t.demand(), warm.map_or(&[], |w| &w.job));
    // Without a budget of its own the budget figure is the job figure.
    if t.budget() == t.demand() {
        let stops = crate::events::FpStops {
            job: job_stops,
            budget: Vec::new(),
        };
        return ((job, job), stops);
    }
    let (budget, budget_stops) = r(t.budget(), warm.map_or(&[], |w| &w.budget));
    let stops = crate::events::FpStops {
        job: job_stops,
        budget: budget_stops,
    };
    ((budget, job), stops)
}

/// The verdict of the spec's test on one CPU, over its guaranteed tasks.
/// `on`: the tasks of `cpu`; `srp`: its b(t) under EDF
/// ([`crate::blocking::srp_spec_steps_among`]).
fn cpu_verdict(
    spec: &Spec,
    timings: &[TaskTiming],
    (cpu, on): (u32, &[usize]),
    srp: &[(Nanos, Nanos)],
) -> CpuVerdict {
    let ids = crate::blocking::guaranteed(spec, on);
    let us: Vec<f64> = ids
        .iter()
        .map(|&i| timings[i].budget as f64 / timings[i].period as f64)
        .collect();
    // An empty sum is -0.0 (shown "-0.0000"); adding 0.0 makes it 0.
    let u: f64 = us.iter().sum::<f64>() + 0.0;
    let (value, bound, ok) = match spec.schedulability {
        SchedTest::Rta => rta_test(&ids, timings),
        SchedTest::Qpa => crate::qpa::qpa_verdict(spec, &ids, srp),
        SchedTest::Edf if !spec.overheads.on(cpu).is_zero() => {
            edf_overhead_test(spec, (on, &ids), timings, u)
        }
        SchedTest::Edf if !srp.is_empty() => srp_density_test(&ids, timings, srp),
        test => utilization_test(test, &us),
    };
    CpuVerdict {
        cpu,
        tasks: ids.len(),
        utilization: u,
        value,
        bound,
        schedulable: ok,
    }
}

/// Baker's density condition for EDF with the stack resource policy
/// (Baker 1991), on the tasks `ids` of a CPU whose b(t) is `steps`: for
/// every task k in the
/// order of relative deadlines, `Σ_{D_i ≤ D_k} C_i/D_i + b(D_k)/D_k ≤ 1`
/// with b Baruah's blocking ([`crate::blocking::srp_at`]; for the last of
/// equal deadlines it is Baker's B_k, the others' sums are smaller). It
/// implies the demand test h(t) + b(t) ≤ t (docs/analysis.md). Returns
/// (the largest left-hand side, its bound 1, it holds).
fn srp_density_test(
    ids: &[usize],
    timings: &[TaskTiming],
    steps: &[(Nanos, Nanos)],
) -> (f64, f64, bool) {
    let mut worst: f64 = 0.0;
    for &k in ids {
        let dk = timings[k].deadline;
        let sum: f64 = ids
            .iter()
            .filter(|&&i| timings[i].deadline <= dk)
            .map(|&i| timings[i].budget as f64 / timings[i].deadline as f64)
            .sum();
        let b = crate::blocking::srp_at(steps, dk) as f64 / dk as f64;
        worst = worst.max(sum + b);
    }
    (worst, 1.0, worst <= 1.0 + UTIL_EPS)
}

/// EDF with overheads on one CPU: Σ U with what the overheads add must
/// stay within 1, and, since release handlers of later deadlines break the
/// processor-demand argument behind `Σ U ≤ 1`, every budget's response
/// time (Spuri's, with the overheads) must be within its deadline: (that
/// Σ U, its bound 1, both hold). `on`: the CPU's tasks, `ids` its
/// guaranteed ones.
fn edf_overhead_test(
    spec: &Spec,
    (on, ids): (&[usize], &[usize]),
    timings: &[TaskTiming],
    u: f64,
) -> (f64, f64, bool) {
    if ids.is_empty() {
        return (u, 1.0, true);
    }
    let value = u + edf_overhead_load(spec, on, |j| timings[j].period);
    let (_, _, responses) = rta_test(ids, timings);
    (value, 1.0, value <= 1.0 + UTIL_EPS && responses)
}

/// The exact RTA test on the tasks `ids` of one CPU: (the largest R/D, its
/// bound 1, every budget delivered within its deadline, R ≤ D; D = T unless
/// the spec gives a deadline). A task without a finite response time makes
/// the largest R/D infinite.
fn rta_test(ids: &[usize], timings: &[TaskTiming]) -> (f64, f64, bool) {
    let mut worst: f64 = 0.0;
    let mut ok = true;
    for &i in ids {
        match timings[i].response_time {
            Some(r) => {
                worst = worst.max(r as f64 / timings[i].deadline as f64);
                ok &= r <= timings[i].deadline;
            }
            None => {
                worst = f64::INFINITY;
                ok = false;
            }
        }
    }
    (worst, 1.0, ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rta_textbook() {
        // Liu's classic set (C, T) = (1, 4), (2, 6), (3, 13) — hand iteration for the
        // third task: 6 → 1·2 + 1·... : R0 = 3+1+2 = 6; R1 = 3 + ⌈6/4⌉·1 + ⌈6/6⌉·2 = 3+2+2 = 7;
        // R2 = 3 + ⌈7/4⌉·1 + ⌈7/6⌉·2 = 3+2+4 = 9; R3 = 3 + 3·1 + 2·2 = 10;
        // R4 = 3 + ⌈10/4⌉ + 2·⌈10/6⌉ = 3+3+4 = 10. Fixed point 10.
        assert_eq!(response_time(3, &[(1, 4), (2, 6)]), Some(10));
        assert_eq!(response_time(2, &[(1, 4)]), Some(3));
        assert_eq!(response_time(1, &[]), Some(1));
    }

    #[test]
    fn pibs_inheritance_counts_as_interference() {
        // h (T 5, C 1), m (T 10, C 1), io (T 20, C 2) serving m. io inherits m's
        // rank while m has a job, so for m: R = 1 + 1 (h) + 2 (io) = 4, not 2.
        // io itself: 2 + 1 (h) + 1 (m) = 4.
        let src = "[system]\nname = \"p\"\n[tasks.h]\nexec = 1\nperiod = 5\n[tasks.m]\nexec = 1\nperiod = 10\n[tasks.io]\nexec = 2\nperiod = 20\nserver = \"io\"\nserves = \"m\"\n";
        let spec = match Spec::parse("p.toml", src) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        let (t, _) = analyze(&spec);
        assert_eq!(t[1].job_response_time, Some(4_000_000));
        assert_eq!(t[2].job_response_time, Some(4_000_000));
        assert_eq!((t[2].priority, t[2].top_priority), (Some(3), Some(2)));
    }

    #[test]
    fn pibs_server_ranked_below_carries_in_a_pending_job() {
        // m (T 10, x 3), mid (T 12, x 4), io (T 20, C 4) serving m: ranks
        // m 1, mid 2, io 3. io at its own rank: w = 4 + 3⌈w/10⌉ + 4⌈w/12⌉
        // = 11, 14, 18 (≤ 20): R_io = 18. For m, io runs above only by
        // inheritance and may have a job pending when m's busy period
        // starts (mid held it back): J = R_io − C_io = 14, so w = 3 +
        // 4⌈(w + 14)/20⌉ = 7, 11; the second job ends by 14 − 10 = 4.
        // R_m = 11 (io released at −13.5, run at m's rank over [0, 4), its
        // next job at 6.5 before m is done at 7), not 3 + 4 = 7.
        let src = "[system]\nname = \"c\"\n[tasks.m]\nexec = 3\nperiod = 10\n\
                   [tasks.mid]\nexec = 4\nperiod = 12\nserver = \"none\"\n\
                   [tasks.io]\nexec = 4\nperiod = 20\nserver = \"io\"\nserves = \"m\"\n";
        let spec = match Spec::parse("c.toml", src) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        let (t, _) = analyze(&spec);
        let ms = |x: Nanos| Some(x * 1_000_000);
        assert_eq!(t[2].job_response_time, ms(18));
        assert_eq!(t[0].job_response_time, ms(11));
        assert_eq!(t[0].response_time, ms(11));
        // io at its own rank without a figure within its period: nothing
        // bounds its catch-up, so m has none either.
        let behind = src.replace("period = 12", "period = 7");
        let spec = match Spec::parse("c.toml", &behind) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        let (t, _) = analyze(&spec);
        assert_eq!(
            (t[2].job_response_time, t[0].job_response_time),
            (None, None)
        );
    }

    #[test]
    fn edf_response_times_through_the_descriptor() {
        // (C, T) = (2, 5), (4, 7) ms (`edf::tests::spuri_by_hand`): RM
        // gives the second 4 + 2·2 = 8 > 7; EDF's servers give (4, 6). A
        // budget of 3 for `a` overloads the CPU under EDF.
        let src = |sched: &str, c1: &str| {
            format!(
                "[system]\nname = \"e\"\nscheduler = \"{sched}\"\n\
                 [tasks.a]\nexec = 2\nperiod = 5\nbudget = {c1}\n\
                 [tasks.b]\nexec = 4\nperiod = 7\n"
            )
        };
        let r = |sched: &str, c1: &str| -> Vec<Option<Nanos>> {
            let spec = match Spec::parse("e.toml", &src(sched, c1)) {
                Ok(s) => s,
                Err(e) => panic!("{e}"),
            };
            analyze(&spec)
                .0
                .iter()
                .map(|t| t.job_response_time)
                .collect()
        };
        let ms = |x: Nanos| Some(x * 1_000_000);
        assert_eq!(r("rm", "2"), vec![ms(2), ms(8)]);
        assert_eq!(r("edf", "2"), vec![ms(4), ms(6)]);
        // U = 3/5 + 4/7 > 1: overloaded, no response time.
        assert_eq!(r("edf", "3"), vec![None, None]);
    }

    fn own(work: Nanos, blocking: Nanos, period: Nanos) -> OwnJobs {
        OwnJobs {
            work,
            switch: 0,
            blocking,
            jitter: 0,
            period,
        }
    }

    #[test]
    fn lehoczky_s_busy_period_fifth_job() {
        // Lehoczky 1990: τ1 (26, 70), τ2 (62, 100). τ2's jobs in the
        // level-2 busy period end at w_q = 114, 202, 316, 404, 518, 606,
        // 694 (≤ 700: the last), responses w_q − 100·q = 114, 102, 116,
        // 104, 118, 106, 94. The first job alone says 114.
        let hp = [(26, 70, 0)];
        assert_eq!(response_time(62, &[(26, 70)]), Some(114));
        assert_eq!(level_response(own(62, 0, 100), &hp), Some(118));
        // Within a limit: the same figure, or none above it.
        assert_eq!(level_response_within(own(62, 0, 100), &hp, 118), Some(118));
        assert_eq!(level_response_within(own(62, 0, 100), &hp, 117), None);
    }

    #[test]
    fn blocking_counts_once_per_busy_period() {
        // hi (2, 5) above lo (4, 7), B = 2: w_q = 4(q+1) + 2 + 2⌈w_q/5⌉ =
        // 10, 18, 24, 30, 38, 44, 50, 58, 64, 70 (≤ 70), the worst 18 − 7
        // = 11 (B once; twice per job would make it grow with q).
        assert_eq!(level_response(own(4, 2, 7), &[(2, 5, 0)]), Some(11));
        // Own jitter: each job's response counts from its nominal release.
        let jittered = OwnJobs {
            jitter: 1,
            ..own(3, 0, 7)
        };
        assert_eq!(level_response(jittered, &[(2, 5, 0)]), Some(6));
    }

    #[test]
    fn a_level_loaded_to_one_has_no_response() {
        // hi (2, 4) above lo (3, 5): the first job's w = 7 exists, but the
        // level's load is 1.1 and lo's backlog grows without end.
        assert_eq!(response_time(3, &[(2, 4)]), Some(7));
        assert_eq!(level_response(own(3, 0, 5), &[(2, 4, 0)]), None);
        // Exactly 1 counts as unbounded too.
        assert_eq!(level_response(own(2, 0, 4), &[(2, 4, 0)]), None);
    }

    #[test]
    fn rta_diverges_when_overloaded() {
        assert_eq!(response_time(1, &[(2, 4), (2, 4)]), None);
    }
}
