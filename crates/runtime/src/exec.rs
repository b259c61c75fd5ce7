//! The executor: one thread per task, periodic releases from one common
//! epoch, implicit communication through four-slot registers, and a log of
//! every job, replayed after the run through the simulator's own sample
//! provenance ([`rtpipe_joblog::Provenance`]) to measure the chains.

mod check;
mod log;
mod queue;

pub use check::{check, MAX_TASKS};

use crate::class::{configure, lock_memory, Placement, TASK_STACK};
pub use crate::config::{
    fifo_priorities, reservation_runtime, ErrorKind, Policy, RunConfig, RunError,
    OVERRUN_TOLERANCE, RESERVATION_MARGIN,
};
use crate::four_slot::{self, Reader, Writer};
use crate::let_comm::{self, Cell, LetIn, LetOut};
use crate::load::Load;
use crate::locks::{Held, Resources, Sections};
use crate::partition::Partition;
use crate::pi::PiMutex;
use crate::probe::{probe, Probe, PROBE_PERIOD};
use crate::spin::{synthetic, Spin};
use crate::sys;
use log::assemble;
use queue::{Env, Queues};
use rtpipe_body::{Body, Environment, Job, Nanos, Stamp, Stamped};
use rtpipe_joblog::{JobRecord, Provenance, SimResult};
use rtpipe_model::{Communication, Spec};
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicI64, Ordering};
use std::sync::{Barrier, Mutex};

/// Per task, what the run measured beyond [`TaskStats`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TaskRun {
    /// Completion − release of every job, in index order: the schedule's
    /// response (under LET too, where the job log holds the period's end).
    pub responses: Vec<Nanos>,
    /// Jobs whose CPU time (read to publish) exceeded the task's budget C
    /// by more than [`OVERRUN_TOLERANCE`].
    pub overruns: u64,
    /// Jobs that published after their deadline (release + D; D = T unless
    /// the spec gives a deadline).
    pub missed: u64,
    /// The largest CPU time of one job.
    pub max_demand: Nanos,
    /// The largest read − release: for the highest-priority task of a CPU,
    /// the kernel's wake-up latency (the model has none).
    pub max_start: Nanos,
    /// The SCHED_FIFO priority (fifo only).
    pub priority: Option<i32>,
    /// The critical sections its jobs held, in order ([`run_synthetic`]).
    pub sections: Vec<Held>,
    /// LET: reads that found another producer job than LET's in their slot
    /// (`let_comm`): the producer overran its period, or the reader came
    /// later than the edge keeps jobs for.
    pub let_misses: u64,
    /// Under `deadline`: the jobs (release indices) that overran the task's
    /// reservation: the thread used more CPU time from the job's start to
    /// the next job's than the reservation's runtime (it holds at most
    /// that much at any instant), or the kernel signalled an overrun during
    /// the job (SIGXCPU, `SCHED_FLAG_DL_OVERRUN`; it comes at the thread's
    /// next tick on the CPU, so in the job that overran or a later one).
    pub reservation_overruns: Vec<u64>,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// In the simulator's terms: per task stats (late = missed periods,
    /// exhaustions = budget overruns), the chains, the job log. Times are
    /// relative to the common epoch.
    pub sim: SimResult,
    /// Per task: what its thread measured, in declaration order.
    pub tasks: Vec<TaskRun>,
    /// The policy it ran under.
    pub policy: Policy,
    /// Background hogs that ran ([`RunConfig::load`]).
    pub load: usize,
    /// Stopped early by Ctrl-C.
    pub interrupted: bool,
    /// Steal time of all CPUs during the run (a hypervisor ran someone
    /// else), when /proc/stat has it.
    pub steal: Option<Nanos>,
    /// Wall time from the epoch to the last thread's end.
    pub elapsed: Nanos,
    /// The epoch on CLOCK_MONOTONIC: every time of the run is relative to
    /// it; add it to line the run up with other traces of the machine
    /// (ftrace, perf, a /proc/stat sampler).
    pub epoch: Nanos,
    /// Warnings (memory not locked, ...).
    pub notes: Vec<String>,
    /// The counters sampled during the run, in time order.
    pub probes: Vec<Probe>,
    /// The kernel's real-time share of a CPU, (runtime, period) in ns, as
    /// the run found it (`crate::probe::rt_share`); `None`: no throttling.
    pub rt_share: Option<(Nanos, Nanos)>,
    /// Tasks moved to SCHED_OTHER to finish (still running long after the
    /// run's end).
    pub demoted: Vec<usize>,
    /// SCHED_DEADLINE ran partitioned EDF (a root domain per CPU, each
    /// thread pinned to its task's CPU) rather than global EDF.
    pub partitioned: bool,
    /// Under [`Policy::EdfFifo`], what the EDF dispatcher did.
    pub dispatch: Option<crate::edf::Stats>,
    /// Under [`Policy::EdfFifo`], per task: its thread's release and
    /// completion dispatches (relative to the epoch), when no job of its
    /// CPU ran; empty otherwise.
    pub dispatch_spans: Vec<Vec<(Nanos, Nanos)>>,
    /// Other processes' real-time threads that may run on the run's CPUs
    /// and used CPU time during it (`crate::foreign`), most first.
    pub foreign_rt: Vec<crate::foreign::ForeignThread>,
    /// Under LET, every job at the schedule's instants (read: when its
    /// thread read, finish: when it completed), where `sim.jobs` holds
    /// LET's (release, period end); `None` otherwise ([`RunResult::scheduled`]).
    pub schedule: Option<Vec<JobRecord>>,
}

impl RunResult {
    /// Every job as the threads ran it (read, completion): what the
    /// response times and the causes of a delay are measured on.
    pub fn scheduled(&self) -> &[JobRecord] {
        self.schedule.as_deref().unwrap_or(&self.sim.jobs)
    }
}

/// One job as a thread logs it (no allocation in the periodic path).
#[derive(Debug, Clone, Copy, Default)]
struct Rec {
    index: u64,
    release: Nanos,
    /// When the thread read its inputs, and when it published.
    start: Nanos,
    done: Nanos,
    /// The communication instants: `start` and `done`, or under LET the
    /// release and the period's end.
    read: Nanos,
    finish: Nanos,
    demand: Nanos,
    /// The kernel signalled an overrun of the reservation during the job.
    dl_overrun: bool,
    /// The thread's CPU time when the job started, ns.
    cpu_start: Nanos,
}

/// What one task's thread owns.
struct Thread<'a, V> {
    task: usize,
    /// The spec's release offset (0 without one): releases at phase + k·T.
    phase: Nanos,
    period: Nanos,
    /// D ≤ T: SCHED_DEADLINE's dl_deadline.
    deadline: Nanos,
    budget: Nanos,
    cpu: usize,
    priority: Option<i32>,
    body: Box<dyn Body<V> + 'a>,
    /// Its inputs in the order of the spec's `reads`: a register, or a
    /// LET edge (`let_comm`: an edge with a LET end).
    ins: Vec<In<V>>,
    writers: Vec<Writer<Cell<V>>>,
    recs: Vec<Rec>,
    /// Per job, the producer job read on each input (u64::MAX: none yet).
    inputs: Vec<u64>,
    /// Its outputs on the edges with a LET end, instead of `writers`.
    let_out: Vec<LetOut<V>>,
    /// It communicates under LET (its chain's or the system's semantics).
    let_comm: bool,
    let_misses: u64,
    /// Its critical sections, run before the body (synthetic bodies).
    sections: Option<Sections>,
    /// Released by its triggers' publications, not by a timer.
    triggered: bool,
    /// Releases merged into a job of it still queued (`queue`):
    /// `TaskStats::merged`.
    merges: u64,
}

/// One input of a task thread.
enum In<V> {
    /// Implicit to implicit: the register's latest value.
    Reg(Reader<Cell<V>>),
    /// An edge with a LET end (`let_comm`).
    Let(LetIn<V>),
}

/// How long after the last release a thread may still be running before it
/// is deemed stuck (at least twice the longest period).
const GRACE: Nanos = 1_000_000_000;

/// Waits until every task thread is done, or until `end` (or 200 ms after
/// Ctrl-C); then moves the threads still running to SCHED_OTHER, so that a
/// throttled SCHED_DEADLINE thread (its runtime overdrawn, it may not run
/// for minutes) or a starved one still ends, and `run` returns on time.
/// Samples the run's counters every [`PROBE_PERIOD`] into `probes` (one
/// more once every thread is done). Returns the tasks moved.
fn watch(
    (epoch, end): (Nanos, Nanos),
    tids: &[AtomicI32],
    done: &[AtomicBool],
    probes: &mut Vec<Probe>,
) -> Vec<usize> {
    let mut end = end;
    loop {
        let all_done = done.iter().all(|d| d.load(Ordering::SeqCst));
        probes.push(probe(epoch, tids));
        if all_done {
            return Vec::new();
        }
        let now = sys::now();
        if sys::stop_requested() {
            end = end.min(now + 200_000_000);
        }
        if now >= end {
            break;
        }
        std::thread::sleep(std::time::Duration::from_nanos(PROBE_PERIOD as u64));
    }
    let mut moved = Vec::new();
    for (i, (tid, d)) in tids.iter().zip(done).enumerate() {
        // tid 0 would be the calling thread itself: never touch it.
        let tid = tid.load(Ordering::SeqCst);
        if !d.load(Ordering::SeqCst) && tid > 0 && sys::set_other(tid).is_ok() {
            moved.push(i);
        }
    }
    moved
}

/// Runs `spec` for real: `bodies[i]` for every job of task i, `env` as the
/// world (sensed at each read, actuated at each publish, under its
/// priority-inheritance lock, at the true instants relative to the epoch;
/// `None`: no world, no lock), with `cfg.load` hogs in the background.
///
/// # Panics
/// When `bodies` does not hold one body per task (a caller's bug).
pub fn run<'a, V: Copy + Send>(
    spec: &Spec,
    cfg: &RunConfig,
    bodies: Vec<Box<dyn Body<V> + 'a>>,
    env: Option<&PiMutex<dyn Environment<V> + Send + 'a>>,
) -> Result<RunResult, RunError> {
    if let Some((msg, help)) = crate::comm::bodies_refusal(spec, env.is_some()) {
        return Err(RunError::config(msg, help));
    }
    execute(spec, cfg, bodies, env, None)
}

/// Runs `spec` with synthetic bodies burning each task's demand
/// ([`crate::synthetic`]), its critical sections (`[resources]`) held under
/// the spec's protocol where the simulator places them (`crate::locks`),
/// each section's instants logged in [`TaskRun::sections`].
pub fn run_synthetic(spec: &Spec, cfg: &RunConfig, spin: Spin) -> Result<RunResult, RunError> {
    let bodies: Vec<Box<dyn Body<u64>>> = (0..spec.tasks.len())
        .map(|i| Box::new(synthetic(spin, Sections::rest(spec, i))) as Box<dyn Body<u64>>)
        .collect();
    execute(spec, cfg, bodies, None, Some(spin))
}

/// [`run`], the sections run with `spin` when given.
fn execute<'a, V: Copy + Send>(
    spec: &Spec,
    cfg: &RunConfig,
    bodies: Vec<Box<dyn Body<V> + 'a>>,
    env: Option<&PiMutex<dyn Environment<V> + Send + 'a>>,
    spin: Option<Spin>,
) -> Result<RunResult, RunError> {
    assert_eq!(bodies.len(), spec.tasks.len(), "one body per task");
    check(spec, cfg)?;
    let prov = Provenance::new(spec)
        .map_err(|e| RunError::config(e.to_string(), "name only the spec's tasks on a chain"))?;
    let n = spec.tasks.len();
    let mut notes: Vec<String> = lock_memory(cfg.policy, n).into_iter().collect();
    notes.extend(crate::locks::note(spec, cfg.policy));
    let threads = threads(spec, cfg, bodies, spin);
    // Stopped and joined when `_load` drops: on every way out of `run`.
    let _load = Load::start(cfg.load).map_err(|e| {
        RunError::config(
            format!("cannot start {} background load thread(s): {e}", cfg.load),
            "lower --load",
        )
    })?;
    sys::catch_stop_signals();
    let shared = shared(spec, (cfg.policy, cfg.duration), &mut notes)?;
    shared.reserve_spans(&threads);
    let (steal0, rt0) = (sys::steal_time(), crate::foreign::Scan::now());
    let longest = spec.tasks.iter().filter_map(|t| t.fixed_period()).max();
    let grace = GRACE.max(2 * longest.unwrap_or(0));
    let (finished, demoted, probes) = start(spec, cfg, threads, env, &shared, grace);
    for &i in &demoted {
        notes.push(demoted_note(&spec.tasks[i].name, cfg.policy, grace));
    }
    let e0 = shared.epoch.load(Ordering::SeqCst);
    let elapsed = sys::now() - e0;
    let steal = match (steal0, sys::steal_time()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let dispatch = shared.dispatcher().map(|d| d.stats());
    let dispatch_spans = shared.dispatcher().map(|d| d.spans(e0)).unwrap_or_default();
    if let Some(e) = shared
        .errors
        .into_inner()
        .ok()
        .and_then(|v| v.into_iter().next())
    {
        return Err(e);
    }
    let threads = unwrap_joined(finished, shared.queues.as_ref());
    let interrupted = sys::stop_requested();
    let mut res = assemble(
        spec,
        (threads, prov),
        released_span(cfg.duration, e0),
        cfg.policy,
        interrupted,
        steal,
        elapsed,
        notes,
    );
    res.load = cfg.load;
    res.epoch = e0;
    res.probes = probes;
    res.demoted = demoted;
    res.partitioned = shared.partition.is_some();
    res.dispatch = dispatch;
    res.dispatch_spans = dispatch_spans;
    res.foreign_rt = rt0.ran_until(&crate::foreign::Scan::now(), &crate::foreign::cpus_of(spec));
    Ok(res)
}

/// What the task threads of a run under `policy` share: the resources'
/// locks, and under SCHED_DEADLINE a root domain per CPU where the machine
/// allows it (else a note says EDF is global). What a run killed by
/// SIGKILL left on the machine is repaired first, whatever the policy.
fn shared(
    spec: &Spec,
    (policy, duration): (Policy, Nanos),
    notes: &mut Vec<String>,
) -> Result<Shared, RunError> {
    match crate::partition::repair() {
        Ok(done) => notes.extend(done),
        Err(why) => notes.push(format!("warning: {why}")),
    }
    let workers = queue::workers(spec);
    let mut shared = Shared::new(spec.tasks.len(), workers);
    if spec.event_triggered() {
        shared.queues = Some(Queues::new(spec, &shared.workers, duration));
    }
    shared.resources = Some(Resources::new(spec, policy).map_err(|e| {
        RunError::config(
            format!("cannot create the resources' locks: {e}"),
            "resource_protocol = \"pip\" needs PTHREAD_PRIO_INHERIT mutexes (glibc on Linux)",
        )
    })?);
    if policy == Policy::Deadline {
        let longest = spec.tasks.iter().filter_map(|t| t.fixed_period()).max();
        shared.admission_wait += longest.unwrap_or(0);
        match Partition::create(sys::online_cpus()) {
            Ok(p) => shared.partition = Some(p),
            Err(why) => notes.push(format!(
                "note: global EDF on all CPUs (partitioned EDF needs one cpuset per CPU: {why})"
            )),
        }
    }
    Ok(shared)
}

/// The span in which jobs were released: the whole duration, or up to
/// Ctrl-C (no job is released after it).
fn released_span(duration: Nanos, epoch: Nanos) -> Nanos {
    match sys::stop_instant() {
        // A stop after the last release leaves the whole run; one before
        // the epoch, an empty one.
        Some(at) => (at - epoch).clamp(0, duration),
        None => duration,
    }
}

/// The warning for a task [`watch`] demoted to SCHED_OTHER `grace` after
/// the run's end.
fn demoted_note(name: &str, policy: Policy, grace: Nanos) -> String {
    let why = match policy {
        Policy::Deadline => {
            "a SCHED_DEADLINE reservation overdrawn by far is throttled until its runtime is paid back"
        }
        Policy::Fifo | Policy::EdfFifo => {
            "higher-priority SCHED_FIFO threads kept it from running"
        }
        Policy::Other => "the fair scheduler gave it too little CPU time",
    };
    format!(
        "warning: task {name} was still waiting for the CPU {} ms after the run ended ({why}): \
         it was moved to SCHED_OTHER to finish, and its jobs released but not started by then were dropped",
        grace / 1_000_000
    )
}

/// The joined task threads, in task order, with their merges from `q`; a
/// body's panic goes on unwinding here, in the caller's thread (the panic
/// hook has reported it).
fn unwrap_joined<'a, V>(finished: Joined<'a, V>, q: Option<&Queues>) -> Vec<Thread<'a, V>> {
    let mut threads = Vec::with_capacity(finished.len());
    for r in finished {
        match r {
            Ok(t) => threads.extend(t),
            // A body panicked: the panic hook has reported it.
            Err(p) => std::panic::resume_unwind(p),
        }
    }
    threads.sort_by_key(|t| t.task);
    for th in threads.iter_mut() {
        th.merges = q.map_or(0, |q| q.merges(th.task));
    }
    threads
}

/// One [`Thread`] per task, with its body, room for every job it can log,
/// and one four-slot register per (producer, consumer) edge.
fn threads<'a, V: Copy + Send>(
    spec: &Spec,
    cfg: &RunConfig,
    bodies: Vec<Box<dyn Body<V> + 'a>>,
    spin: Option<Spin>,
) -> Vec<Thread<'a, V>> {
    let prios = fifo_priorities(spec);
    let lets: Vec<bool> = spec
        .communications()
        .into_iter()
        .map(|c| c == Communication::Let)
        .collect();
    let caps = queue::job_capacity(spec, cfg.duration);
    let mut threads: Vec<Thread<'a, V>> = bodies
        .into_iter()
        .enumerate()
        .map(|(i, body)| {
            let t = &spec.tasks[i];
            // 0 for a data-triggered task: it has no timer (`check`).
            let period = t.fixed_period().unwrap_or(0);
            let cap = caps[i] as usize;
            Thread {
                task: i,
                phase: t.offset.unwrap_or(0),
                period,
                deadline: deadline_of(t),
                budget: t.budget(),
                cpu: t.cpu as usize,
                priority: match cfg.policy {
                    Policy::Fifo => Some(prios[i]),
                    _ => None,
                },
                body,
                ins: Vec::with_capacity(t.reads.len()),
                writers: Vec::new(),
                recs: Vec::with_capacity(cap),
                inputs: Vec::with_capacity(cap * t.reads.len()),
                let_out: Vec::new(),
                let_comm: lets[i],
                let_misses: 0,
                sections: spin.and_then(|s| Sections::of(spec, i, s, cap)),
                triggered: t.is_triggered(),
                merges: 0,
            }
        })
        .collect();
    // One register per (producer, consumer) edge; with a LET end, a ring
    // of them (`let_comm`: by the producer's period under a LET producer,
    // by publish instant under an implicit one).
    for c in 0..spec.tasks.len() {
        for &p in &spec.tasks[c].reads {
            if lets[p] || lets[c] {
                let from = (threads[p].phase, threads[p].period);
                let (w, r) = let_comm::edge::<V>(from, threads[c].period, lets[p]);
                threads[p].let_out.push(w);
                threads[c].ins.push(In::Let(r));
            } else {
                let (w, r) = four_slot::register::<Cell<V>>(None);
                threads[p].writers.push(w);
                threads[c].ins.push(In::Reg(r));
            }
        }
    }
    threads
}

/// D ≤ T for a periodic task; a data-triggered one's given deadline, else
/// none (it has no period to miss).
fn deadline_of(t: &rtpipe_model::Task) -> Nanos {
    match t.fixed_period() {
        Some(p) => t.deadline_given.unwrap_or(p).min(p),
        None => t.deadline_given.unwrap_or(Nanos::MAX),
    }
}

/// What the task threads and the thread that starts them share.
struct Shared {
    /// Every task thread has configured its scheduling class.
    setup: Barrier,
    /// The epoch is set (or the run aborted): go.
    go: Barrier,
    /// A thread could not be configured: run no job.
    abort: AtomicBool,
    /// The common epoch on CLOCK_MONOTONIC.
    epoch: AtomicI64,
    /// Why threads could not be configured.
    errors: Mutex<Vec<RunError>>,
    /// Per task, its thread's id (0 until the thread has started).
    tids: Vec<AtomicI32>,
    /// Per task, its thread is done.
    done: Vec<AtomicBool>,
    /// SCHED_DEADLINE: one root domain per CPU (partitioned EDF), when the
    /// machine allows it; `None`: global EDF.
    partition: Option<Partition>,
    /// The resources' locks and ceilings (`crate::locks`).
    resources: Option<Resources>,
    /// The OS threads, each the tasks it runs (`queue::workers`: one per
    /// task unless the spec has work-queue threads).
    workers: Vec<Vec<usize>>,
    /// The queues of an event-triggered spec (`queue`); `None`: every
    /// task is a periodic thread of its own.
    queues: Option<Queues>,
    /// How long a thread retries a reservation refused as busy
    /// (`class::retry_busy`): the longest period plus
    /// [`crate::config::ADMISSION_MARGIN`].
    admission_wait: Nanos,
}

impl Shared {
    /// The EDF dispatcher, under [`Policy::EdfFifo`].
    fn dispatcher(&self) -> Option<&crate::edf::Dispatcher> {
        self.resources.as_ref().and_then(|r| r.dispatch.as_ref())
    }

    /// Room in the EDF dispatcher's span log for every job the threads
    /// can log (none grows a vector on the real-time path).
    fn reserve_spans<V>(&self, threads: &[Thread<'_, V>]) {
        if let Some(d) = self.dispatcher() {
            d.reserve(threads.iter().map(|t| t.recs.capacity()));
        }
    }

    /// For `n` tasks on `workers` (and the thread that starts them).
    fn new(n: usize, workers: Vec<Vec<usize>>) -> Shared {
        Shared {
            setup: Barrier::new(workers.len() + 1),
            go: Barrier::new(workers.len() + 1),
            abort: AtomicBool::new(false),
            epoch: AtomicI64::new(0),
            errors: Mutex::new(Vec::new()),
            tids: (0..n).map(|_| AtomicI32::new(0)).collect(),
            done: (0..n).map(|_| AtomicBool::new(false)).collect(),
            partition: None,
            resources: None,
            workers,
            queues: None,
            admission_wait: crate::config::ADMISSION_MARGIN,
        }
    }
}

/// What each OS thread returned when joined: the [`Thread`]s of its tasks
/// with their logs, or the panic of a body.
type Joined<'a, V> = Vec<std::thread::Result<Vec<Thread<'a, V>>>>;

/// Starts one OS thread per worker (`queue::workers`: per task, or per
/// work-queue thread), lets them run from a common epoch once all are
/// configured (none runs a job if one could not be), watches them until
/// the run's end plus `grace`, and joins them. Returns every OS thread's
/// outcome, in worker order, and the tasks [`watch`] had to demote.
fn start<'a, V: Copy + Send>(
    spec: &Spec,
    cfg: &RunConfig,
    threads: Vec<Thread<'a, V>>,
    env: Option<&PiMutex<dyn Environment<V> + Send + 'a>>,
    shared: &Shared,
    grace: Nanos,
) -> (Joined<'a, V>, Vec<usize>, Vec<Probe>) {
    let (policy, duration) = (cfg.policy, cfg.duration);
    let mut demoted = Vec::new();
    let mut probes = Vec::new();
    let groups = group(threads, &shared.workers);
    let finished = std::thread::scope(|s| {
        let handles: Vec<_> = groups
            .into_iter()
            .enumerate()
            .map(|(w, members)| {
                let first = &spec.tasks[members[0].task];
                let name = first.name.as_str();
                // A work-queue thread, or a data-triggered task: releases
                // into slots, merged while a job waits (the model's rule).
                let queued = first.merges_releases();
                std::thread::Builder::new()
                    .name(os_thread_name(spec, first))
                    .stack_size(TASK_STACK)
                    .spawn_scoped(s, move || {
                        let run = (policy, duration, grace);
                        os_thread((members, w, queued), name, run, env, shared)
                    })
                    .unwrap_or_else(|e| panic!("cannot start the thread of task {name}: {e}"))
            })
            .collect();
        shared.setup.wait();
        let failed = shared.errors.lock().map_or(true, |v| !v.is_empty());
        shared.abort.store(failed, Ordering::SeqCst);
        // Start 10 ms from now: every thread is past `go` by then.
        shared
            .epoch
            .store(sys::now() + 10_000_000, Ordering::SeqCst);
        shared.go.wait();
        if !failed {
            let epoch = shared.epoch.load(Ordering::SeqCst);
            let span = (epoch, epoch + duration + grace);
            demoted = watch(span, &shared.tids, &shared.done, &mut probes);
        }
        handles.into_iter().map(|h| h.join()).collect::<Vec<_>>()
    });
    (finished, demoted, probes)
}

/// The name the kernel shows for the OS thread of `task` (its work-queue
/// thread's, if it has one): `ps -L`, `top -H` and a kernel trace then
/// tell the run's threads apart (Linux keeps the first 15 bytes).
fn os_thread_name(spec: &Spec, task: &rtpipe_model::Task) -> String {
    let name = task
        .thread
        .and_then(|t| spec.threads.get(t))
        .map_or(task.name.as_str(), |t| t.name.as_str());
    format!("rt:{name}")
}

/// The task threads (in task order) grouped by the OS thread that runs
/// them, in `workers`' order.
fn group<'a, V>(threads: Vec<Thread<'a, V>>, workers: &[Vec<usize>]) -> Vec<Vec<Thread<'a, V>>> {
    let mut slots: Vec<Option<Thread<'a, V>>> = threads.into_iter().map(Some).collect();
    workers
        .iter()
        .map(|tasks| tasks.iter().filter_map(|&t| slots[t].take()).collect())
        .collect()
}

/// The life of one OS thread: enter its scheduling class (its tasks share
/// CPU and priority), wait for the others, run its loop from the epoch
/// (unless the run was aborted): a work queue's (`queue::serve`) when
/// `queued`, else its one task's periodic loop; and hand its tasks' logs
/// back.
fn os_thread<'a, V: Copy>(
    (mut members, worker, queued): (Vec<Thread<'a, V>>, usize, bool),
    name: &str,
    (policy, duration, grace): (Policy, Nanos, Nanos),
    env: Option<&PiMutex<dyn Environment<V> + Send + 'a>>,
    shared: &Shared,
) -> Vec<Thread<'a, V>> {
    let tid = sys::gettid();
    for th in &members {
        shared.tids[th.task].store(tid, Ordering::SeqCst);
        if let Some(d) = shared.dispatcher() {
            d.register(th.task);
        }
    }
    let th = &members[0];
    let place = Placement {
        name,
        cpu: th.cpu,
        priority: th.priority,
        budget: th.budget,
        deadline: th.deadline,
        period: th.period,
        admission_wait: shared.admission_wait,
    };
    if let Err(e) = configure(&place, policy, shared.partition.as_ref()) {
        if let Ok(mut v) = shared.errors.lock() {
            v.push(e);
        }
    }
    shared.setup.wait();
    shared.go.wait();
    if !shared.abort.load(Ordering::SeqCst) {
        let e = shared.epoch.load(Ordering::SeqCst);
        let (res, q) = (shared.resources.as_ref(), shared.queues.as_ref());
        let span = (duration, duration + grace);
        match q.filter(|_| queued) {
            Some(q) => queue::serve((&mut members, worker), q, e, span, (env, res)),
            None => periodic(&mut members[0], e, span, (env, res, q)),
        }
    }
    for th in &members {
        shared.done[th.task].store(true, Ordering::SeqCst);
    }
    members
}

/// The periodic loop of one task: releases at epoch + φ + k·T for
/// φ + k·T < duration, none started after `stop` (the run's end plus its grace: a
/// thread that far behind was stopped by [`watch`]).
fn periodic<V: Copy>(
    th: &mut Thread<'_, V>,
    epoch: Nanos,
    (duration, stop): (Nanos, Nanos),
    (env, res, q): (Env<'_, '_, V>, Option<&Resources>, Option<&Queues>),
) {
    let mut inputs: Vec<Cell<V>> = Vec::with_capacity(th.ins.len());
    let mut k: u64 = 0;
    loop {
        let offset = th.phase + k as i64 * th.period;
        if offset >= duration
            || sys::stop_requested()
            || th.recs.len() == th.recs.capacity()
            || sys::now() - epoch >= stop
        {
            break;
        }
        // No sched_yield() under SCHED_DEADLINE: a yield throttles the
        // thread until its reservation's current deadline, so once a
        // disturbance has put the reservation's periods behind the
        // releases, every later job starts late too, for good (measured:
        // Cleanflight's gyro missed 17,411 of 20,000 periods with it, 57
        // without). Sleeping to the release instead lets the kernel's CBS
        // wake-up rule re-anchor the deadline at the release.
        let release = epoch + offset;
        sys::sleep_until(release);
        if sys::stop_requested() {
            // Ctrl-C came while sleeping, before this release: the report's
            // span ends at the stop, so this job is not part of it.
            break;
        }
        // Under the EDF dispatcher the thread wakes at its DISPATCH
        // priority, ranks its job and runs once it is picked.
        let dispatch = res.and_then(|r| r.dispatch.as_ref());
        if let Some(d) = dispatch {
            d.release(th.task, release + th.deadline);
        }
        job(th, (k, offset), epoch, (env, res, q), &mut inputs);
        if let Some(d) = dispatch {
            d.complete(th.task);
        }
        k += 1;
    }
}

/// Job `k` of the task, released at epoch + `offset` (φ + k·T for a timer,
/// a trigger's publish instant, or the first of the releases merged into
/// it): read the registers, run its critical sections and the body,
/// publish to the registers (and release the data-triggered tasks it
/// triggers, `q`), and log it. `inputs` is the job's buffer for the values read (kept across jobs:
/// no allocation here). Under LET (`let_comm`) it reads what was visible at
/// its release and its output is visible from its period's end: those are
/// the instants it logs and stamps.
fn job<V: Copy>(
    th: &mut Thread<'_, V>,
    (k, offset): (u64, Nanos),
    epoch: Nanos,
    (env, res, q): (Env<'_, '_, V>, Option<&Resources>, Option<&Queues>),
    inputs: &mut Vec<Cell<V>>,
) {
    let cpu0 = sys::thread_cpu_time();
    read_inputs(th, offset, epoch, inputs);
    let (start, device) = sense(th.task, epoch, env);
    let start = start - epoch;
    let read = if th.let_comm { offset } else { start };
    let job = Job {
        task: th.task,
        index: k,
        release: offset,
        read,
    };
    if let (Some(s), Some(res)) = (&mut th.sections, res) {
        s.run(res, k, th.priority, epoch);
    }
    let value = th.body.run(&job, inputs, device);
    // Under way before the publish instant is taken: no thread ends before
    // the releases this publication makes (`queue`).
    let publishing = q.is_some_and(|q| q.begin(th.task));
    let done = actuate(th.task, epoch, env, &value) - epoch;
    let finish = if th.let_comm {
        offset + th.period
    } else {
        done
    };
    let stamp = Stamp {
        task: th.task,
        job: k,
        read,
        publish: finish,
    };
    for w in &mut th.writers {
        w.write(Some(Stamped { value, stamp }));
    }
    for w in &mut th.let_out {
        w.write(Stamped { value, stamp });
    }
    // The job's CPU time ends before it releases its consumers: the
    // wake-ups are the executor's work (as the kernel's timer releases
    // are), and a wake-up of a higher thread on this CPU switches to it
    // inside the call.
    let demand = sys::thread_cpu_time() - cpu0;
    let dl_overrun = sys::take_dl_overruns() > 0;
    if let Some(q) = q.filter(|_| publishing) {
        q.publish(th.task, done);
    }
    th.recs.push(Rec {
        index: k,
        release: offset,
        start,
        done,
        read,
        finish,
        demand,
        dl_overrun,
        cpu_start: cpu0,
    });
}

/// Reads every input of the job released at `offset`, in the spec's
/// `reads` order, into `inputs`, and logs the producer job read on each.
fn read_inputs<V: Copy>(
    th: &mut Thread<'_, V>,
    offset: Nanos,
    epoch: Nanos,
    inputs: &mut Vec<Cell<V>>,
) {
    inputs.clear();
    for r in &mut th.ins {
        let v = match r {
            In::Reg(r) => r.read(),
            In::Let(r) => {
                // A LET job reads at its release; an implicit one now.
                let at = if th.let_comm {
                    offset
                } else {
                    sys::now() - epoch
                };
                let (v, exact) = r.read(at);
                th.let_misses += u64::from(!exact);
                v
            }
        };
        th.inputs.push(v.map_or(u64::MAX, |s| s.stamp.job));
        inputs.push(v);
    }
}

/// The read instant of a job of `task`, and what the world gives it there.
/// The instant is taken after the register copies: every value read was
/// published (its publish instant taken) before it, as in the model. With
/// a world, it is taken under the world's lock, so the world sees
/// non-decreasing instants from all threads.
fn sense<V>(
    task: usize,
    epoch: Nanos,
    env: Option<&PiMutex<dyn Environment<V> + Send + '_>>,
) -> (Nanos, Option<V>) {
    match env.map(PiMutex::lock) {
        Some(Ok(mut e)) => {
            let read = sys::now();
            (read, e.sense(task, read - epoch))
        }
        _ => (sys::now(), None),
    }
}

/// The publish instant of a job of `task` that computed `value`, taken
/// before the registers are written (a reader's read instant then follows
/// it); with a world, under its lock, where the output reaches the world at
/// that instant.
fn actuate<V>(
    task: usize,
    epoch: Nanos,
    env: Option<&PiMutex<dyn Environment<V> + Send + '_>>,
    value: &V,
) -> Nanos {
    match env.map(PiMutex::lock) {
        Some(Ok(mut e)) => {
            let publish = sys::now();
            e.actuate(task, publish - epoch, value);
            publish
        }
        _ => sys::now(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn watch_gives_up_on_a_stuck_thread_at_the_end() {
        let tids = [AtomicI32::new(0), AtomicI32::new(0)];
        let done = [AtomicBool::new(true), AtomicBool::new(false)];
        let release = AtomicBool::new(false);
        std::thread::scope(|s| {
            s.spawn(|| {
                tids[1].store(sys::gettid(), Ordering::SeqCst);
                // Stuck until the watcher has given up on it.
                while !release.load(Ordering::SeqCst) {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                }
            });
            while tids[1].load(Ordering::SeqCst) == 0 {
                std::thread::yield_now();
            }
            let t0 = sys::now();
            let mut probes = Vec::new();
            let moved = watch((t0, t0 + 50_000_000), &tids, &done, &mut probes);
            let waited = sys::now() - t0;
            release.store(true, Ordering::SeqCst);
            assert_eq!(moved, vec![1], "only the thread not done");
            assert!((50_000_000..1_000_000_000).contains(&waited), "{waited} ns");
            // Sampled every PROBE_PERIOD while it waited, in time order.
            assert!(probes.len() >= 5, "{} probes", probes.len());
            assert!(probes.windows(2).all(|w| w[0].at < w[1].at));
        });
        // All done: returns at once, moving nobody.
        done[1].store(true, Ordering::SeqCst);
        let t0 = sys::now();
        let mut probes = Vec::new();
        assert!(watch((t0, t0 + 10_000_000_000), &tids, &done, &mut probes).is_empty());
        assert_eq!(probes.len(), 1, "one last probe");
    }
}
