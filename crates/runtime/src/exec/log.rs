//! After the run: the threads' logs in the simulator's terms (the job log
//! replayed through the sample provenance, the per-task figures, the
//! trace's spans), and what the threads could not do as the model says.

use super::{Policy, RunResult, TaskRun, Thread, OVERRUN_TOLERANCE};
use rtpipe_joblog::{JobRecord, Provenance, Segment, SimResult, TaskStats, Trigger};
use rtpipe_model::{Nanos, Spec};

/// The job log in the simulator's terms, the chains `prov` measures on it,
/// and the per-task figures.
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble<V>(
    spec: &Spec,
    (threads, mut prov): (Vec<Thread<'_, V>>, Provenance),
    horizon: Nanos,
    policy: Policy,
    interrupted: bool,
    steal: Option<Nanos>,
    elapsed: Nanos,
    notes: Vec<String>,
) -> RunResult {
    let n = spec.tasks.len();
    let jobs = job_log(spec, &threads, &mut prov, horizon);
    let schedule = threads
        .iter()
        .any(|th| th.let_comm)
        .then(|| schedule(&threads));
    let chains = prov.finish();
    // The trace's spans: when the threads ran (under LET too).
    let segments = spans(spec, schedule.as_deref().unwrap_or(&jobs));
    let mut tasks = Vec::with_capacity(n);
    let mut runs = Vec::with_capacity(n);
    let mut notes = notes;
    for th in &threads {
        let (stats, run) = task_figures(th, policy);
        notes.extend(thread_notes(&spec.tasks[th.task].name, th));
        tasks.push(stats);
        runs.push(run);
    }
    RunResult {
        sim: SimResult {
            offsets: spec.tasks.iter().map(|t| t.offset.unwrap_or(0)).collect(),
            tasks,
            chains,
            jobs,
            segments,
            events: 0,
            horizon,
        },
        tasks: runs,
        policy,
        load: 0,
        epoch: 0,
        interrupted,
        steal,
        elapsed,
        notes,
        probes: Vec::new(),
        // As the run found it (the setting is the machine's).
        rt_share: crate::probe::rt_share(),
        demoted: Vec::new(),
        partitioned: false,
        dispatch: None,
        dispatch_spans: Vec::new(),
        foreign_rt: Vec::new(),
        schedule,
    }
}

/// Every job the threads logged, in publish order (ties: read order, then
/// task), replayed through `prov` for the chain samples it carried. A
/// register read need not return the latest value published before the
/// read instant (the publish instant is taken before the register write),
/// so a job takes its samples from the producer job its thread logged
/// reading; publish order guarantees that job's record exists by then.
fn job_log<V>(
    spec: &Spec,
    threads: &[Thread<'_, V>],
    prov: &mut Provenance,
    horizon: Nanos,
) -> Vec<JobRecord> {
    let mut order: Vec<(Nanos, Nanos, usize, usize)> = Vec::new();
    for (i, th) in threads.iter().enumerate() {
        for (j, r) in th.recs.iter().enumerate() {
            // Under LET a period ending at or after the horizon has not
            // published (as in the simulator, where no release ends it).
            if !th.let_comm || r.finish < horizon {
                order.push((r.finish, r.read, i, j));
            }
        }
    }
    order.sort_unstable();
    // at[task][k] = where job k of the task is in `jobs`.
    let mut at: Vec<Vec<usize>> = threads
        .iter()
        .map(|th| Vec::with_capacity(th.recs.len()))
        .collect();
    let mut jobs: Vec<JobRecord> = Vec::with_capacity(order.len());
    for &(_, _, i, j) in &order {
        let th = &threads[i];
        let r = th.recs[j];
        let nreads = th.ins.len();
        let inputs = th.inputs.get(j * nreads..(j + 1) * nreads).unwrap_or(&[]);
        let reads = &spec.tasks[i].reads;
        prov.read_with(i, r.read, |p, ps| {
            let input = reads.iter().position(|&q| q == p)?;
            let k = *at[p].get(*inputs.get(input)? as usize)?;
            jobs[k].carried.get(ps)?.sample
        });
        prov.publish(i, r.finish);
        // Jobs of one task publish in index order, so this is job j.
        at[i].push(jobs.len());
        jobs.push(JobRecord {
            task: i,
            index: r.index,
            release: r.release,
            demand: r.demand,
            read: r.read,
            finish: r.finish,
            carried: prov.record(i),
            trigger: trigger_of(spec, threads, i, r.release),
        });
    }
    jobs
}

/// The publication that released a job of data-triggered task `i` at
/// `release`: the job of one of its triggers that published at that very
/// instant (a release is made at its trigger's publish instant; the
/// first trigger in declaration order on a tie of nanoseconds). `None`
/// for a timer's job.
fn trigger_of<V>(
    spec: &Spec,
    threads: &[Thread<'_, V>],
    i: usize,
    release: Nanos,
) -> Option<Trigger> {
    let (triggers, _) = spec.tasks[i].triggers()?;
    triggers.iter().find_map(|&p| {
        // A task's jobs publish in index order.
        let k = threads[p]
            .recs
            .binary_search_by_key(&release, |r| r.finish)
            .ok()?;
        Some(Trigger {
            task: p,
            job: threads[p].recs[k].index,
        })
    })
}

/// Every job at the schedule's instants, in completion order.
fn schedule<V>(threads: &[Thread<'_, V>]) -> Vec<JobRecord> {
    let mut out: Vec<JobRecord> = threads
        .iter()
        .flat_map(|th| {
            th.recs.iter().map(|r| JobRecord {
                task: th.task,
                index: r.index,
                release: r.release,
                demand: r.demand,
                read: r.start,
                finish: r.done,
                carried: Vec::new(),
                trigger: None,
            })
        })
        .collect();
    out.sort_by_key(|j| (j.finish, j.read, j.task));
    out
}

/// Warnings about what a thread could not do as the model says.
fn thread_notes<V>(name: &str, th: &Thread<'_, V>) -> Vec<String> {
    let mut out = Vec::new();
    if th.let_misses > 0 {
        out.push(format!(
            "warning: task {name}: {} LET read(s) found another producer job than LET's (a producer overran its period, or this task read too late): their data flow is logged as it happened",
            th.let_misses
        ));
    }
    if let Some(f) = th.sections.as_ref().map(|s| s.failed).filter(|&f| f > 0) {
        out.push(format!(
            "warning: task {name}: the kernel refused {f} priority change(s) or lock(s) of its critical sections"
        ));
    }
    out
}

/// One task's figures from its thread's log: in the simulator's terms
/// (late = missed periods, exhaustions = budget overruns beyond
/// [`OVERRUN_TOLERANCE`]) and what only a real run measures.
fn task_figures<V>(th: &Thread<'_, V>, policy: Policy) -> (TaskStats, TaskRun) {
    // The schedule's response (completion, not LET's period end).
    let responses: Vec<Nanos> = th.recs.iter().map(|r| r.done - r.release).collect();
    // Against D (the period unless the spec gives a deadline).
    let missed = responses.iter().filter(|&&r| r > th.deadline).count() as u64;
    let overruns = th
        .recs
        .iter()
        .filter(|r| r.demand > th.budget + OVERRUN_TOLERANCE)
        .count() as u64;
    let stats = TaskStats {
        released: th.recs.len() as u64,
        merged: th.merges,
        completed: th.recs.len() as u64,
        max_response: responses.iter().copied().max(),
        late: missed,
        exhaustions: overruns,
        busy: th.recs.iter().map(|r| r.demand).sum(),
    };
    let run = TaskRun {
        max_demand: th.recs.iter().map(|r| r.demand).max().unwrap_or(0),
        max_start: th
            .recs
            .iter()
            .map(|r| r.start - r.release)
            .max()
            .unwrap_or(0),
        responses,
        overruns,
        missed,
        priority: th.priority,
        sections: th
            .sections
            .as_ref()
            .map_or_else(Vec::new, |s| s.held.clone()),
        let_misses: th.let_misses,
        reservation_overruns: reservation_overruns(th, policy),
    };
    (stats, run)
}

/// Under SCHED_DEADLINE, the jobs that overran the thread's reservation
/// (`TaskRun::reservation_overruns`).
fn reservation_overruns<V>(th: &Thread<'_, V>, policy: Policy) -> Vec<u64> {
    if policy != Policy::Deadline {
        return Vec::new();
    }
    let runtime = crate::config::reservation_runtime(th.budget, th.deadline);
    let recs = &th.recs;
    (0..recs.len())
        .filter(|&k| {
            let cycle = recs.get(k + 1).map(|n| n.cpu_start - recs[k].cpu_start);
            recs[k].dl_overrun || cycle.is_some_and(|c| c > runtime)
        })
        .map(|k| recs[k].index)
        .collect()
}

/// One "slice" per job from its read to its publish, for the trace writer:
/// the span the job occupied, preemptions included (the kernel does not
/// tell a thread when it was switched out), in time order.
fn spans(spec: &Spec, jobs: &[JobRecord]) -> Vec<Segment> {
    let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    cpus.sort_unstable();
    cpus.dedup();
    let mut out: Vec<Segment> = jobs
        .iter()
        .map(|j| Segment {
            cpu: cpus.binary_search(&spec.tasks[j.task].cpu).unwrap_or(0),
            task: j.task,
            job: j.index,
            start: j.read,
            end: j.finish,
            background: false,
        })
        .collect();
    out.sort_by_key(|s| (s.start, s.task));
    out
}
