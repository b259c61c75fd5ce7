//! Response times and read-to-publish bounds under EDF at given periods
//! (Spuri's analysis through [`crate::edf`], the processor-demand test for
//! constrained deadlines), for [`super`]'s analysis and the design's
//! relaxation; docs/analysis.md, "EDF response times".

use super::{interference, period_or_max, UTIL_EPS};
use crate::edf;
use rtpipe_model::{Nanos, Server, Spec, Task, MAX_TIME};

/// Task `i`'s read-to-publish bound under EDF ([`edf::start_to_finish`]),
/// with the spec's periods and relative deadlines.
pub(super) fn edf_read_to_publish(spec: &Spec, i: usize) -> Nanos {
    let periods: Vec<Nanos> = spec.tasks.iter().map(period_or_max).collect();
    edf_read_to_publish_at(spec, &periods, i)
}

/// [`edf_read_to_publish`] at the given periods (one per task); a relative
/// deadline is the spec's, else the period.
pub fn edf_read_to_publish_at(spec: &Spec, periods: &[Nanos], i: usize) -> Nanos {
    let (tasks, at) = edf_tasks(spec, periods, i);
    let own = spec.tasks[i]
        .demand()
        .saturating_add(crate::overheads::own(spec, i));
    edf::start_to_finish(&tasks, at, own)
}

/// Task `i`'s relative deadline at the period `t`: the spec's, else the
/// period.
pub(crate) fn deadline_at(spec: &Spec, i: usize, t: Nanos) -> Nanos {
    spec.tasks[i].deadline_given.map_or(t, |d| d.min(t))
}

/// The tasks [`edf_tasks`] lists for task `i`'s CPU, in its order: the
/// guaranteed ones, and background ones whose releases run handlers.
fn edf_members(spec: &Spec, i: usize) -> impl Iterator<Item = usize> + '_ {
    let cpu = spec.tasks[i].cpu;
    (0..spec.tasks.len()).filter(move |&j| {
        let t = &spec.tasks[j];
        t.cpu == cpu
            && (t.server != Server::Background || crate::overheads::per_release(spec, j) > 0)
    })
}

/// EDF with constant-bandwidth servers: every server gets its budget by
/// the end of each period when Σ U ≤ 1, but possibly at its very end; with
/// constrained deadlines, by its deadline when the processor-demand test
/// passes (docs/analysis.md).
pub(super) fn server_period(spec: &Spec, t: &Task) -> (Option<Nanos>, Option<Nanos>) {
    let periods: Vec<Nanos> = spec.tasks.iter().map(period_or_max).collect();
    let d = t.deadline().unwrap_or(MAX_TIME);
    server_period_at(spec, &periods, t.cpu, d)
}

/// [`server_period`] at `periods`: the deadline `d` of a task on `cpu`
/// when the processor-demand test passes there.
fn server_period_at(
    spec: &Spec,
    periods: &[Nanos],
    cpu: u32,
    d: Nanos,
) -> (Option<Nanos>, Option<Nanos>) {
    if crate::qpa::edf_feasible_at(spec, periods, cpu) {
        (Some(d), Some(d))
    } else {
        (None, None)
    }
}

/// The guaranteed tasks of `cpu` as the EDF analysis sees them, and the
/// place of task `i` among them (when it is one).
fn edf_tasks(spec: &Spec, periods: &[Nanos], i: usize) -> (Vec<edf::EdfTask>, usize) {
    let mut at = 0;
    let mut out = Vec::new();
    for j in edf_members(spec, i) {
        let t = &spec.tasks[j];
        if j == i {
            at = out.len();
        }
        out.push(edf::EdfTask {
            // A background task's releases still run their handlers.
            work: match t.server {
                Server::Background => 0,
                _ => interference(t).saturating_add(crate::overheads::per_job(spec, j)),
            },
            period: periods[j],
            deadline: match t.server {
                // Releases whose only work is their handlers' (overheads):
                // never a job that runs first.
                Server::Background => Nanos::MAX,
                _ => deadline_at(spec, j, periods[j]),
            },
            kernel: crate::overheads::per_release(spec, j),
        });
    }
    (out, at)
}

/// Task `i`'s (budget, job) response times under EDF at the spec's periods:
/// Spuri's analysis with the tasks' relative deadlines; where a task of
/// the CPU has one below its period, only when the processor-demand test
/// passes there, and at most the deadline.
pub(super) fn edf_response_times(spec: &Spec, i: usize) -> (Option<Nanos>, Option<Nanos>) {
    let periods: Vec<Nanos> = spec.tasks.iter().map(period_or_max).collect();
    edf_response_times_at(spec, &periods, i)
}

/// [`edf_response_times`] at `periods` (one per task; a deadline is the
/// given one, else the period), for the design's relaxation at a box of
/// one point: Spuri's bound; where some task of the CPU has a deadline
/// below its period, when the processor-demand test passes (every job
/// then completes by its deadline, so the deadlines Spuri's analysis
/// orders by are the jobs' own: docs/analysis.md, "EDF response times"),
/// and at most the deadline.
pub fn edf_response_times_at(
    spec: &Spec,
    periods: &[Nanos],
    i: usize,
) -> (Option<Nanos>, Option<Nanos>) {
    let cpu = spec.tasks[i].cpu;
    if edf_constrained_at(spec, periods, cpu) {
        let d = deadline_at(spec, i, periods[i]);
        let (Some(_), Some(_)) = server_period_at(spec, periods, cpu, d) else {
            return (None, None);
        };
        let (b, j) = edf_response_at(spec, periods, i);
        return (b.map(|b| b.min(d)), j.map(|j| j.min(d)));
    }
    edf_response_at(spec, periods, i)
}

/// Some guaranteed task of `cpu` has a deadline below its period at
/// `periods`.
pub fn edf_constrained_at(spec: &Spec, periods: &[Nanos], cpu: u32) -> bool {
    (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].cpu == cpu && spec.tasks[j].server != Server::Background)
        .any(|j| spec.tasks[j].deadline_given.is_some_and(|d| d < periods[j]))
}

/// Task `i`'s (budget, job) response times under EDF (Spuri 1996, see
/// [`edf`]) at the given periods (one per task); `None` when its CPU is
/// overloaded, and the server period where the busy period holds more than
/// [`edf::MAX_BUSY_JOBS`] jobs. The job figure is at most the period.
pub fn edf_response_at(spec: &Spec, periods: &[Nanos], i: usize) -> (Option<Nanos>, Option<Nanos>) {
    edf_response_disturbed(spec, periods, i, 0)
}

/// [`edf_response_at`] with `extra` ns of CPU time taken from the window
/// whatever the deadlines (a disturbance the model does not have,
/// `crate::disturbance`): blocking of `extra` at every offset, on top of
/// the stack resource policy's, and in the busy period.
pub fn edf_response_disturbed(
    spec: &Spec,
    periods: &[Nanos],
    i: usize,
    extra: Nanos,
) -> (Option<Nanos>, Option<Nanos>) {
    assert!(extra >= 0, "a disturbance is a duration: {extra}");
    let (tasks, at) = edf_tasks(spec, periods, i);
    // The test's utilisation (budgets), as everywhere else (`relax` too); it
    // bounds the work's (x ≤ C), so below it a busy period exists.
    let u: f64 = (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].cpu == spec.tasks[i].cpu)
        .filter(|&j| spec.tasks[j].server != Server::Background)
        .map(|j| spec.tasks[j].budget() as f64 / periods[j] as f64)
        .sum();
    let overheads = !crate::overheads::costs(spec, i).is_zero();
    if u + edf_overhead_load(spec, periods, i) > 1.0 + UTIL_EPS {
        return (None, None);
    }
    let t = &spec.tasks[i];
    // The stack resource policy's blocking, deadlines being the periods,
    // with the switch to the blocking job (`overheads::blocking_switch`).
    let cs = crate::overheads::blocking_switch(spec, i);
    let deadlines: Vec<Nanos> = (0..spec.tasks.len())
        .map(|j| deadline_at(spec, j, periods[j]))
        .collect();
    let srp = crate::blocking::srp_steps(spec, &deadlines, t.cpu)
        .into_iter()
        .map(|(theta, b)| (theta, if b > 0 { b.saturating_add(cs) } else { 0 }));
    let block: Vec<(Nanos, Nanos)> = if extra > 0 {
        std::iter::once((0, extra))
            .chain(srp.map(|(theta, b)| (theta, b.saturating_add(extra))))
            .collect()
    } else {
        srp.collect()
    };
    let b_max = crate::blocking::srp_max(&block);
    let Some(l) = edf::busy_period(&tasks, b_max, edf::MAX_BUSY_JOBS) else {
        // The server period is a bound only without overheads (a release
        // handler of a later deadline runs first) and, with blocking, when
        // the demand test with blocking passes.
        let ok = !overheads && (b_max == 0 || crate::qpa::edf_feasible(spec, t.cpu));
        return if ok {
            (Some(periods[i]), Some(periods[i]))
        } else {
            (None, None)
        };
    };
    let own = crate::overheads::own(spec, i);
    let job = edf::response_time(&tasks, at, t.demand().saturating_add(own), l, &block);
    // Spuri's demand argument: with Σ I/T ≤ 1 (the busy period exists) a
    // job of demand x ≤ I meets its deadline, so the bound is within the
    // period. Release handlers of later deadlines break the argument, and
    // so does blocking unless the demand test with it passes: then the
    // bound may pass the period (it is no guarantee, `bounded_response`,
    // and the verdict fails).
    assert!(
        overheads || b_max > 0 || job <= periods[i],
        "EDF response time {job} above the period {}",
        periods[i]
    );
    let budget = edf::response_time(&tasks, at, t.budget().saturating_add(own), l, &block);
    (Some(budget), Some(job))
}

/// What the overheads add to the utilisation of task `i`'s CPU under EDF:
/// `Σ (2·cs + K_k) / T_k` over its guaranteed tasks, `Σ K_k / T_k` over
/// its background ones (0 without overheads).
pub(crate) fn edf_overhead_load(spec: &Spec, periods: &[Nanos], i: usize) -> f64 {
    let cpu = spec.tasks[i].cpu;
    (0..spec.tasks.len())
        .filter(|&j| spec.tasks[j].cpu == cpu)
        .map(|j| {
            let mut c = crate::overheads::per_release(spec, j);
            if spec.tasks[j].server != Server::Background {
                c = c.saturating_add(crate::overheads::per_job(spec, j));
            }
            c as f64 / periods[j] as f64
        })
        .sum()
}
