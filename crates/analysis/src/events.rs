//! Response times of a spec with work-queue threads and data-triggered
//! tasks: event models per task ([`crate::arrivals`]), the FIFO analysis
//! inside a thread ([`crate::thread_rta`]) and the fixed-priority one of
//! the thread-less tasks (`sched`'s, handed in as [`FixedPriority`]),
//! iterated holistically (Tindell and Clark 1994): a data-triggered task's
//! activations are its triggers' publications, whose jitter grows with
//! their response times, which grow with the jitter of what runs above
//! them. From zero jitter the iteration only grows, and stops when no
//! figure changes or one becomes unbounded. docs/analysis.md, "Threads and
//! data-triggered tasks".

use crate::arrivals::Arrivals;
use crate::thread_rta::{fifo_response_reach, Member};
use rtpipe_model::{Join, Nanos, Server, Spec};

/// Most rounds of the holistic iteration before every figure that
/// depends on it is called unbounded.
pub const MAX_ROUNDS: usize = 1_000;

/// One stream of what runs above a task: (I, T, J), the work of each of
/// its jobs, its period and its release jitter.
pub type Load = (Nanos, Nanos, Nanos);

/// What the fixed-priority analysis provides (`sched` implements it, so
/// that thread-less tasks keep their own analysis, servers included).
pub trait FixedPriority {
    /// The tasks that can run above task `i` on its CPU (its thread's
    /// own tasks among them, which the caller leaves out).
    fn above(&self, i: usize) -> Vec<usize>;
    /// What one job of task `j` takes from the tasks below it.
    fn interference(&self, j: usize) -> Nanos;
    /// B of task `i`: once per busy period.
    fn blocking(&self, i: usize) -> Nanos;
    /// (budget, job) response times of a thread-less periodic task `i`,
    /// from its nominal release, under `hp` as (I, T, J).
    fn periodic_response(&self, i: usize, hp: &[Load]) -> (Option<Nanos>, Option<Nanos>);
    /// [`periodic_response`](Self::periodic_response) with its reach: the
    /// largest window at which its iteration read `hp`'s η⁺, so that the
    /// figures hold as long as no stream's η⁺ changes up to it. `None`
    /// (the default) when unknown: the task is then re-analysed whenever
    /// an input changes.
    fn periodic_response_reach(
        &self,
        i: usize,
        hp: &[Load],
    ) -> ((Option<Nanos>, Option<Nanos>), Option<Nanos>) {
        (self.periodic_response(i, hp), None)
    }
}

/// What the event analysis knows of a task, beside its response times.
#[derive(Debug, Clone, PartialEq)]
pub struct EventTiming {
    /// Its jobs merge: it is in a thread or data-triggered, so a release
    /// while one of its jobs is queued and not started joins that job.
    pub merging: bool,
    /// Its activations (`None`: unbounded, a trigger has no response).
    pub arrivals: Option<Arrivals>,
    /// R: from a job's first release (the nominal one of a periodic task)
    /// to its completion, for every job, with no need for R ≤ T.
    pub response: Option<Nanos>,
    /// A: the longest from any instant to the task's next activation (or
    /// nominal release): T, or from its triggers' publications.
    pub gap: Option<Nanos>,
    /// P = A + R: the longest from any instant to its next publication.
    pub publish_gap: Option<Nanos>,
    /// Per trigger (a data-triggered task's), the longest from its
    /// publication to the release it brings: 0 under `join = "any"`, the
    /// other triggers' largest `P` under `join = "all"`.
    pub waits: Vec<(usize, Option<Nanos>)>,
}

/// One task's figures: (budget, job) response times and its event facts.
#[derive(Debug, Clone, PartialEq)]
pub struct EventResult {
    /// The budget response time (C delivered), from the nominal release.
    pub budget: Option<Nanos>,
    /// The job response time (demand x), from the nominal release.
    pub job: Option<Nanos>,
    /// The rest.
    pub timing: EventTiming,
}

/// Every task's figures, by the holistic iteration. Each round recomputes
/// the activations (linear in the tasks and their streams) and then only
/// the responses whose inputs changed: a task's response reads the
/// activations of the tasks above it and of its thread's tasks alone
/// ([`Deps`]), and those only at windows up to its reach (an input whose
/// η⁺ is the same up to there leaves it as it was), so the figures are
/// those of recomputing every task every round (`analysis/tests/events_worklist.rs` holds the two together).
pub fn analyze(spec: &Spec, fp: &impl FixedPriority) -> Vec<EventResult> {
    let n = spec.tasks.len();
    let deps = Deps::of(spec, fp);
    // Each task's output jitter R − R_min, from zero.
    let mut delay: Vec<Option<Nanos>> = vec![Some(0); n];
    let mut arrivals = activations(spec, &delay);
    let mut responses: Vec<Response> = vec![Response::NONE; n];
    deps.respond_units(spec, fp, &arrivals, &mut responses, |_| true);
    for round in 0..MAX_ROUNDS {
        if round > 0 {
            let fresh = activations(spec, &delay);
            let dirty = deps.readers_of_changed(&arrivals, &fresh, &responses);
            arrivals = fresh;
            deps.respond_units(spec, fp, &arrivals, &mut responses, |u| dirty[u]);
        }
        let next: Vec<Option<Nanos>> = (0..n)
            .map(|i| {
                let grown = responses[i].actual? - spec.tasks[i].demand_min();
                // Monotone: a figure never shrinks from one round to the next.
                Some(grown.max(delay[i]?))
            })
            .collect();
        if next == delay {
            return finish(spec, arrivals, responses);
        }
        delay = next;
    }
    // No fixed point found: nothing that depends on the jitter is bounded.
    let none = vec![None; n];
    let arrivals = activations(spec, &none);
    deps.respond_units(spec, fp, &arrivals, &mut responses, |_| true);
    finish(spec, arrivals, responses)
}

/// What each task's response reads, built once per analysis. A *unit* is
/// a thread (its tasks' responses are analysed together: they share the
/// tasks above them and read each other's activations), numbered after
/// the tasks, or a thread-less task, numbered as the task.
struct Deps {
    /// Per task the tasks that can run above it, its thread's own left
    /// out (none for a background task, which has no response).
    above: Vec<Vec<usize>>,
    /// Per thread its tasks, in declaration order.
    members: Vec<Vec<usize>>,
    /// Per task j the units whose responses read j's activations,
    /// ascending and distinct.
    readers: Vec<Vec<usize>>,
}

impl Deps {
    fn of(spec: &Spec, fp: &impl FixedPriority) -> Deps {
        let n = spec.tasks.len();
        let mut members = vec![Vec::new(); spec.threads.len()];
        for (i, t) in spec.tasks.iter().enumerate() {
            if let Some(th) = t.thread {
                members[th].push(i);
            }
        }
        let above: Vec<Vec<usize>> = (0..n)
            .map(|i| {
                let t = &spec.tasks[i];
                if t.server == Server::Background {
                    return Vec::new();
                }
                let mut above = fp.above(i);
                above.retain(|&j| t.thread.is_none() || spec.tasks[j].thread != t.thread);
                above
            })
            .collect();
        let mut readers = vec![Vec::new(); n];
        for (i, t) in spec.tasks.iter().enumerate() {
            let unit = t.thread.map_or(i, |th| n + th);
            for &j in &above[i] {
                readers[j].push(unit);
            }
            if t.thread.is_none() && merging(spec, i) {
                readers[i].push(unit);
            }
        }
        for (th, on) in members.iter().enumerate() {
            for &j in on {
                readers[j].push(n + th);
            }
        }
        for r in &mut readers {
            r.sort_unstable();
            r.dedup();
        }
        Deps {
            above,
            members,
            readers,
        }
    }

    /// Per unit, whether it reads the activations of a task whose η⁺
    /// differs between `old` and `new` at a window up to the unit's reach
    /// (its `responses`, computed from `old`, read η⁺ up to there alone,
    /// so they are those `new` gives when it agrees up to there).
    fn readers_of_changed(
        &self,
        old: &[Option<Arrivals>],
        new: &[Option<Arrivals>],
        responses: &[Response],
    ) -> Vec<bool> {
        let reach = self.unit_reach(responses);
        let mut dirty = vec![false; old.len() + self.members.len()];
        for (j, readers) in self.readers.iter().enumerate() {
            if old[j] == new[j] {
                continue;
            }
            let same = match (&old[j], &new[j]) {
                (Some(a), Some(b)) => a.same_up_to(b),
                _ => 0,
            };
            for &u in readers {
                if reach[u].is_none_or(|r| r > same) {
                    dirty[u] = true;
                }
            }
        }
        dirty
    }

    /// Per unit the largest reach of its responses (`None`: a response
    /// without one, re-analysed on any change).
    fn unit_reach(&self, responses: &[Response]) -> Vec<Option<Nanos>> {
        let mut reach: Vec<Option<Nanos>> = responses.iter().map(|r| r.reach).collect();
        for on in &self.members {
            let unit = on
                .iter()
                .try_fold(0, |m: Nanos, &i| Some(m.max(responses[i].reach?)));
            reach.push(unit);
        }
        reach
    }

    /// The responses of the units `chosen` picks, into `responses`.
    fn respond_units(
        &self,
        spec: &Spec,
        fp: &impl FixedPriority,
        arrivals: &[Option<Arrivals>],
        responses: &mut [Response],
        chosen: impl Fn(usize) -> bool,
    ) {
        let n = spec.tasks.len();
        for i in (0..n).filter(|&i| spec.tasks[i].thread.is_none() && chosen(i)) {
            responses[i] = respond(spec, fp, self, arrivals, i, &mut Vec::new());
        }
        for (th, on) in self.members.iter().enumerate() {
            if chosen(n + th) {
                // The members' FIFO figures, shared between members that
                // see the same thread (ThreadCache).
                let mut cache = Vec::new();
                for &i in on {
                    responses[i] = respond(spec, fp, self, arrivals, i, &mut cache);
                }
            }
        }
    }
}

/// FIFO responses of one thread this round, by (tasks above, blocking),
/// for members whose own work is the work the others see of them (then
/// every input of [`crate::thread_rta::fifo_response`] is the same for them, and so is its
/// figure).
type ThreadCache = Vec<(Vec<usize>, Nanos, (Option<Nanos>, Nanos))>;

/// One round's response of a task.
#[derive(Debug, Clone, Copy)]
struct Response {
    budget: Option<Nanos>,
    job: Option<Nanos>,
    /// From the actual release (the first one of a merged job), for the
    /// output jitter; at most `job`.
    actual: Option<Nanos>,
    /// The largest window at which the figures read their inputs' η⁺
    /// (`None`: unbounded, or not known).
    reach: Option<Nanos>,
}

impl Response {
    /// No figure: unbounded.
    const NONE: Response = Response {
        budget: None,
        job: None,
        actual: None,
        reach: None,
    };
}

/// Each task's activations given each task's output jitter (`None`:
/// unbounded): periodic tasks their period and release jitter, a
/// data-triggered one its triggers' publications joined.
fn activations(spec: &Spec, delay: &[Option<Nanos>]) -> Vec<Option<Arrivals>> {
    let mut out: Vec<Option<Option<Arrivals>>> = vec![None; spec.tasks.len()];
    for i in 0..spec.tasks.len() {
        activation(spec, delay, &mut out, i);
    }
    out.into_iter().map(Option::flatten).collect()
}

/// Task `i`'s activations into `memo`, its triggers' first (validation
/// makes the trigger graph acyclic).
fn activation(
    spec: &Spec,
    delay: &[Option<Nanos>],
    memo: &mut [Option<Option<Arrivals>>],
    i: usize,
) -> Option<Arrivals> {
    if let Some(known) = &memo[i] {
        return known.clone();
    }
    let t = &spec.tasks[i];
    let model = match t.triggers() {
        None => t
            .fixed_period()
            .map(|period| Arrivals::periodic(period, t.jitter)),
        Some((triggers, join)) => {
            let outputs: Option<Vec<Arrivals>> = triggers
                .iter()
                .map(|&p| activation(spec, delay, memo, p)?.delayed(delay[p]?))
                .collect();
            outputs.map(|o| {
                let refs: Vec<&Arrivals> = o.iter().collect();
                match join {
                    Join::Any => Arrivals::any(&refs),
                    Join::All => Arrivals::all(&refs),
                }
            })
        }
    };
    memo[i] = Some(model.clone());
    model
}

/// Task `i`'s jobs merge: it runs in a thread or is data-triggered.
pub fn merging(spec: &Spec, i: usize) -> bool {
    let t = &spec.tasks[i];
    t.thread.is_some() || t.is_triggered()
}

/// Task `i`'s response times this round.
fn respond(
    spec: &Spec,
    fp: &impl FixedPriority,
    deps: &Deps,
    arrivals: &[Option<Arrivals>],
    i: usize,
    cache: &mut ThreadCache,
) -> Response {
    let t = &spec.tasks[i];
    if t.server == Server::Background {
        return Response::NONE;
    }
    let above = &deps.above[i];
    let mut models = Vec::with_capacity(above.len());
    for &j in above {
        let Some(a) = arrivals[j].as_ref() else {
            return Response::NONE;
        };
        models.push((fp.interference(j), a));
    }
    if !merging(spec, i) {
        let streams = models.iter().map(|(_, a)| a.streams.len()).sum();
        let mut hp: Vec<Load> = Vec::with_capacity(streams);
        for &(c, a) in &models {
            hp.extend(a.streams.iter().map(|s| (c, s.period, s.jitter)));
        }
        let ((budget, job), reach) = fp.periodic_response_reach(i, &hp);
        return Response {
            budget,
            job,
            actual: job,
            reach: reach.filter(|_| budget.is_some() && job.is_some()),
        };
    }
    let blocking = fp.blocking(i);
    let shared = t.demand() == fp.interference(i);
    let known = cache
        .iter()
        .find(|(a, b, _)| shared && a == above && *b == blocking)
        .map(|&(_, _, r)| r);
    let (actual, reach) = known.unwrap_or_else(|| {
        let r = thread_response(spec, fp, deps, arrivals, i, &models, blocking);
        if shared {
            cache.push((above.clone(), blocking, r));
        }
        r
    });
    let Some(actual) = actual else {
        return Response::NONE;
    };
    // A periodic task's figure counts from its nominal release.
    let job = actual.checked_add(t.jitter);
    Response {
        budget: job,
        job,
        actual: Some(actual),
        reach: Some(reach),
    }
}

/// The FIFO response of task `i`'s jobs in its thread (a thread of its
/// own for a thread-less data-triggered task), from their first release.
fn thread_response(
    spec: &Spec,
    fp: &impl FixedPriority,
    deps: &Deps,
    arrivals: &[Option<Arrivals>],
    i: usize,
    above: &[(Nanos, &Arrivals)],
    blocking: Nanos,
) -> (Option<Nanos>, Nanos) {
    let t = &spec.tasks[i];
    let alone = [i];
    let members = t.thread.map_or(&alone[..], |th| &deps.members[th][..]);
    let members: Option<Vec<Member>> = members
        .iter()
        .map(|&j| {
            let work = if j == i {
                t.demand()
            } else {
                fp.interference(j)
            };
            Some(Member {
                work,
                arrivals: arrivals[j].as_ref()?,
            })
        })
        .collect::<Option<_>>();
    match members {
        Some(members) => fifo_response_reach(&members, above, blocking),
        None => (None, 0),
    }
}

/// The iteration's last round as each task's figures, with the gaps.
fn finish(
    spec: &Spec,
    arrivals: Vec<Option<Arrivals>>,
    responses: Vec<Response>,
) -> Vec<EventResult> {
    let n = spec.tasks.len();
    let mut gap: Vec<Option<Option<Nanos>>> = vec![None; n];
    for i in 0..n {
        activation_gap(spec, &responses, &mut gap, i);
    }
    let gap: Vec<Option<Nanos>> = gap.into_iter().map(Option::flatten).collect();
    let publish_gap = |i: usize| gap[i]?.checked_add(responses[i].job?);
    (0..n)
        .zip(arrivals)
        .map(|(i, arrivals)| EventResult {
            budget: responses[i].budget,
            job: responses[i].job,
            timing: EventTiming {
                merging: merging(spec, i),
                arrivals,
                response: responses[i].job,
                gap: gap[i],
                publish_gap: publish_gap(i),
                waits: waits(spec, i, &publish_gap),
            },
        })
        .collect()
}

/// A of task `i` into `memo`: T for a periodic task; for a
/// data-triggered one, after any instant each trigger publishes within
/// its `P = A + R`, so `join = "any"` is released within the least of
/// them, `join = "all"` within the largest.
fn activation_gap(
    spec: &Spec,
    responses: &[Response],
    memo: &mut [Option<Option<Nanos>>],
    i: usize,
) -> Option<Nanos> {
    if let Some(known) = memo[i] {
        return known;
    }
    let t = &spec.tasks[i];
    let a = match t.triggers() {
        None => t.fixed_period(),
        Some((triggers, join)) => {
            let p: Vec<Option<Nanos>> = triggers
                .iter()
                .map(|&q| activation_gap(spec, responses, memo, q)?.checked_add(responses[q].job?))
                .collect();
            match join {
                Join::Any => p.into_iter().flatten().min(),
                Join::All => p.into_iter().collect::<Option<Vec<_>>>()?.into_iter().max(),
            }
        }
    };
    memo[i] = Some(a);
    a
}

/// Per trigger of task `i`, the longest from its publication to the
/// release of `i` it brings (see [`EventTiming::waits`]).
fn waits(
    spec: &Spec,
    i: usize,
    publish_gap: &impl Fn(usize) -> Option<Nanos>,
) -> Vec<(usize, Option<Nanos>)> {
    let Some((triggers, join)) = spec.tasks[i].triggers() else {
        return Vec::new();
    };
    triggers
        .iter()
        .map(|&p| {
            let wait = match join {
                Join::Any => Some(0),
                Join::All => triggers
                    .iter()
                    .filter(|&&q| q != p)
                    .map(|&q| publish_gap(q))
                    .try_fold(0, |m: Nanos, g| Some(m.max(g?))),
            };
            (p, wait)
        })
        .collect()
}
