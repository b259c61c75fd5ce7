//! Response times and read-to-publish bounds under EDF at given periods
//! (Spuri's analysis through [`crate::edf`], the processor-demand test for
//! constrained deadlines), for [`super`]'s analysis and the design's
//! relaxation; docs/analysis.md, "EDF response times".
//!
//! Every figure of a task reads its CPU's tasks only, through an
//! [`EdfCpu`]: the CPU's tasks as the analysis sees them at given periods,
//! built once per CPU (the analysis, from its index of tasks by CPU) or per
//! box (the relaxation) and shared by every task of the CPU, so nothing
//! scans the system per task (docs/analysis.md, "Scale").

use super::{interference, period_or_max, UTIL_EPS};
use crate::edf;
use rtpipe_model::{Nanos, Server, Spec, MAX_TIME};
use std::cell::OnceCell;

/// One CPU under EDF at given periods: what every EDF figure of its tasks
/// shares.
#[derive(Debug)]
pub struct EdfCpu<'a> {
    spec: &'a Spec,
    /// The CPU's tasks (background ones included), in declaration order.
    on: Vec<usize>,
    /// The period of each task of `on`, at the same place.
    periods: Vec<Nanos>,
    /// The tasks Spuri's analysis counts ([`EdfCpu::members`]).
    tasks: Vec<edf::EdfTask>,
    /// The task of each entry of `tasks`.
    members: Vec<usize>,
    /// Baruah's b(t) with deadlines [`deadline_at`] the periods, without
    /// the switch to the blocking job.
    srp: Vec<(Nanos, Nanos)>,
    /// Σ C/T over the guaranteed tasks (budgets).
    utilization: f64,
    /// [`edf_overhead_load`] of the CPU.
    overhead_load: f64,
    /// Some guaranteed task has a deadline below its period.
    constrained: bool,
    /// The processor-demand test at these periods, asked only where a
    /// deadline is below its period.
    feasible: OnceCell<bool>,
    /// The processor-demand test at the spec's periods (Spuri's fallback
    /// where the busy period is too long).
    feasible_in_spec: OnceCell<bool>,
}

impl<'a> EdfCpu<'a> {
    /// The CPU of the tasks `on` (all of its tasks, in declaration order,
    /// as `rtpipe_model::TasksByCpu` lists them) at `periods` (one per task
    /// of the system).
    pub fn new(spec: &'a Spec, periods: &[Nanos], on: &[usize]) -> EdfCpu<'a> {
        let period = |j: usize| periods[j];
        let guaranteed = || {
            on.iter()
                .copied()
                .filter(|&j| spec.tasks[j].server != Server::Background)
        };
        let members: Vec<usize> = on
            .iter()
            .copied()
            .filter(|&j| {
                // A background task's releases still run their handlers.
                spec.tasks[j].server != Server::Background
                    || crate::overheads::per_release(spec, j) > 0
            })
            .collect();
        EdfCpu {
            spec,
            tasks: members
                .iter()
                .map(|&j| edf_task(spec, j, period(j)))
                .collect(),
            members,
            srp: crate::blocking::srp_steps(spec, on, |j| deadline_at(spec, j, period(j))),
            utilization: guaranteed()
                .map(|j| spec.tasks[j].budget() as f64 / period(j) as f64)
                .sum(),
            overhead_load: edf_overhead_load(spec, on, period),
            constrained: guaranteed()
                .any(|j| spec.tasks[j].deadline_given.is_some_and(|d| d < period(j))),
            on: on.to_vec(),
            periods: on.iter().map(|&j| period(j)).collect(),
            feasible: OnceCell::new(),
            feasible_in_spec: OnceCell::new(),
        }
    }

    /// Task `i`'s period here; `i` must be a task of the CPU.
    fn period(&self, i: usize) -> Nanos {
        let k = self.on.binary_search(&i).unwrap_or_else(|_| {
            panic!(
                "task `{}` is not on the CPU asked about",
                self.spec.tasks[i].name
            )
        });
        self.periods[k]
    }

    /// Some guaranteed task has a deadline below its period.
    pub fn constrained(&self) -> bool {
        self.constrained
    }

    /// What the overheads add to the CPU's utilisation
    /// ([`edf_overhead_load`]).
    pub fn overhead_load(&self) -> f64 {
        self.overhead_load
    }

    /// The processor-demand test passes at these periods
    /// ([`crate::qpa::edf_feasible_among`]), computed once.
    pub fn feasible(&self) -> bool {
        *self
            .feasible
            .get_or_init(|| crate::qpa::edf_feasible_among(self.spec, &self.on, |j| self.period(j)))
    }

    /// The processor-demand test passes at the spec's periods.
    fn feasible_in_spec(&self) -> bool {
        *self.feasible_in_spec.get_or_init(|| {
            let spec = self.spec;
            crate::qpa::edf_feasible_among(spec, &self.on, |j| period_or_max(&spec.tasks[j]))
        })
    }

    /// The place of task `i` among [`EdfCpu::tasks`] (0 when it is not
    /// one, as a task whose figures nothing reads).
    fn place(&self, i: usize) -> usize {
        self.members.binary_search(&i).unwrap_or(0)
    }
}

/// Task `j` at period `t` as Spuri's analysis counts it.
fn edf_task(spec: &Spec, j: usize, t: Nanos) -> edf::EdfTask {
    let task = &spec.tasks[j];
    edf::EdfTask {
        // A background task's releases still run their handlers.
        work: match task.server {
            Server::Background => 0,
            _ => interference(task).saturating_add(crate::overheads::per_job(spec, j)),
        },
        period: t,
        deadline: match task.server {
            // Releases whose only work is their handlers' (overheads):
            // never a job that runs first.
            Server::Background => Nanos::MAX,
            _ => deadline_at(spec, j, t),
        },
        kernel: crate::overheads::per_release(spec, j),
    }
}

/// Task `i`'s read-to-publish bound under EDF ([`edf::start_to_finish`])
/// at the periods of `cpu`, i's CPU; a relative deadline is the spec's,
/// else the period.
pub fn edf_read_to_publish_at(cpu: &EdfCpu, i: usize) -> Nanos {
    let spec = cpu.spec;
    let own = spec.tasks[i]
        .demand()
        .saturating_add(crate::overheads::own(spec, i));
    edf::start_to_finish(&cpu.tasks, cpu.place(i), own)
}

/// Task `i`'s relative deadline at the period `t`: the spec's, else the
/// period.
pub(crate) fn deadline_at(spec: &Spec, i: usize, t: Nanos) -> Nanos {
    spec.tasks[i].deadline_given.map_or(t, |d| d.min(t))
}

/// EDF with constant-bandwidth servers: every server gets its budget by
/// the end of each period when Σ U ≤ 1, but possibly at its very end; with
/// constrained deadlines, by its deadline when the processor-demand test
/// passes (docs/analysis.md): task `i`'s deadline `d` then, on `cpu`.
pub(super) fn server_period(cpu: &EdfCpu, i: usize) -> (Option<Nanos>, Option<Nanos>) {
    let d = cpu.spec.tasks[i].deadline().unwrap_or(MAX_TIME);
    if cpu.feasible() {
        (Some(d), Some(d))
    } else {
        (None, None)
    }
}

/// Task `i`'s (budget, job) response times under EDF at the periods of
/// `cpu`, i's CPU (for the design's relaxation, a box of one point): Spuri's
/// bound; where some task of the CPU has a deadline below its period, when
/// the processor-demand test passes (every job then completes by its
/// deadline, so the deadlines Spuri's analysis orders by are the jobs' own:
/// docs/analysis.md, "EDF response times"), and at most the deadline.
pub fn edf_response_times_at(cpu: &EdfCpu, i: usize) -> (Option<Nanos>, Option<Nanos>) {
    if cpu.constrained() {
        if !cpu.feasible() {
            return (None, None);
        }
        let d = deadline_at(cpu.spec, i, cpu.period(i));
        let (b, j) = edf_response_at(cpu, i);
        return (b.map(|b| b.min(d)), j.map(|j| j.min(d)));
    }
    edf_response_at(cpu, i)
}

/// Task `i`'s (budget, job) response times under EDF (Spuri 1996, see
/// [`edf`]) at the periods of `cpu`, i's CPU; `None` when the CPU is
/// overloaded, and the server period where the busy period holds more than
/// [`edf::MAX_BUSY_JOBS`] jobs. The job figure is at most the period.
pub fn edf_response_at(cpu: &EdfCpu, i: usize) -> (Option<Nanos>, Option<Nanos>) {
    edf_response_disturbed(cpu, i, 0)
}

/// [`edf_response_at`] with `extra` ns of CPU time taken from the window
/// whatever the deadlines (a disturbance the model does not have,
/// `crate::disturbance`): blocking of `extra` at every offset, on top of
/// the stack resource policy's, and in the busy period.
pub fn edf_response_disturbed(
    cpu: &EdfCpu,
    i: usize,
    extra: Nanos,
) -> (Option<Nanos>, Option<Nanos>) {
    assert!(extra >= 0, "a disturbance is a duration: {extra}");
    let spec = cpu.spec;
    // The test's utilisation (budgets), as everywhere else (`relax` too); it
    // bounds the work's (x ≤ C), so below it a busy period exists.
    let overheads = !crate::overheads::costs(spec, i).is_zero();
    if cpu.utilization + cpu.overhead_load > 1.0 + UTIL_EPS {
        return (None, None);
    }
    let t = &spec.tasks[i];
    let period = cpu.period(i);
    let block = blocking_steps(cpu, i, extra);
    let b_max = crate::blocking::srp_max(&block);
    let Some(l) = edf::busy_period(&cpu.tasks, b_max, edf::MAX_BUSY_JOBS) else {
        // The server period is a bound only without overheads (a release
        // handler of a later deadline runs first) and, with blocking, when
        // the demand test with blocking passes.
        let ok = !overheads && (b_max == 0 || cpu.feasible_in_spec());
        return if ok {
            (Some(period), Some(period))
        } else {
            (None, None)
        };
    };
    let own = crate::overheads::own(spec, i);
    let at = cpu.place(i);
    let job = edf::response_time(&cpu.tasks, at, t.demand().saturating_add(own), l, &block);
    // Spuri's demand argument: with Σ I/T ≤ 1 (the busy period exists) a
    // job of demand x ≤ I meets its deadline, so the bound is within the
    // period. Release handlers of later deadlines break the argument, and
    // so does blocking unless the demand test with it passes: then the
    // bound may pass the period (it is no guarantee, `bounded_response`,
    // and the verdict fails).
    assert!(
        overheads || b_max > 0 || job <= period,
        "EDF response time {job} above the period {period}"
    );
    let budget = edf::response_time(&cpu.tasks, at, t.budget().saturating_add(own), l, &block);
    (Some(budget), Some(job))
}

/// The blocking steps of task `i`'s window: the stack resource policy's,
/// deadlines being the periods, with the switch to the blocking job
/// (`overheads::blocking_switch`), and `extra` at every offset.
fn blocking_steps(cpu: &EdfCpu, i: usize, extra: Nanos) -> Vec<(Nanos, Nanos)> {
    let cs = crate::overheads::blocking_switch(cpu.spec, i);
    let srp = cpu
        .srp
        .iter()
        .map(|&(theta, b)| (theta, if b > 0 { b.saturating_add(cs) } else { 0 }));
    if extra > 0 {
        std::iter::once((0, extra))
            .chain(srp.map(|(theta, b)| (theta, b.saturating_add(extra))))
            .collect()
    } else {
        srp.collect()
    }
}

/// What the overheads add to the utilisation of a CPU under EDF, its tasks
/// `on` at `period(j)`: `Σ (2·cs + K_k) / T_k` over its guaranteed tasks,
/// `Σ K_k / T_k` over its background ones (0 without overheads).
pub(crate) fn edf_overhead_load(spec: &Spec, on: &[usize], period: impl Fn(usize) -> Nanos) -> f64 {
    on.iter()
        .map(|&j| {
            let mut c = crate::overheads::per_release(spec, j);
            if spec.tasks[j].server != Server::Background {
                c = c.saturating_add(crate::overheads::per_job(spec, j));
            }
            c as f64 / period(j) as f64
        })
        .sum()
}
