//! What a simulation starts from: the periods, release offsets and
//! per-task state of a spec, and which I/O VCPU serves which task.

use super::*;

/// Every task's fixed period (positive; [`NO_TIMER`] for a data-triggered
/// task, which no timer releases) and a demand range that makes sense.
pub(super) fn periods_of(spec: &Spec) -> Result<Vec<Nanos>, SimError> {
    let mut periods = Vec::with_capacity(spec.tasks.len());
    for t in &spec.tasks {
        match t.fixed_period() {
            Some(p) if p > 0 => periods.push(p),
            None if t.is_triggered() => periods.push(NO_TIMER),
            _ => return Err(SimError::NoPeriod(t.name.clone())),
        }
        if !(0 <= t.demand_min() && t.demand_min() <= t.demand()) {
            return Err(SimError::BadDemand(t.name.clone()));
        }
    }
    Ok(periods)
}

/// The period, first release and deadline of a data-triggered task: never
/// (its publications release it, `events.rs`).
const NO_TIMER: Nanos = Nanos::MAX;

/// Release offsets φ_i as `phasing` says (drawn from `master` first, before
/// any demand stream, so that a task's demands do not depend on them).
///
/// A task with a known offset (`offset` in the spec) is always released at
/// it: the phasing places only the unknown ones. `Random` and `Grid` draw
/// for the unknown tasks only, in task order, so a spec without known
/// offsets draws exactly what it always drew.
pub(super) fn offsets_of(
    spec: &Spec,
    phasing: &Phasing,
    periods: &[Nanos],
    master: &mut Rng,
) -> Result<Vec<Nanos>, SimError> {
    let n = spec.tasks.len();
    // A data-triggered task has no offset (0) and draws none.
    let known = |i: usize| match spec.tasks[i].is_triggered() {
        true => Some(0),
        false => spec.tasks[i].offset,
    };
    Ok(match phasing {
        Phasing::Sync => (0..n).map(|i| known(i).unwrap_or(0)).collect(),
        Phasing::Random => periods
            .iter()
            .enumerate()
            .map(|(i, &p)| known(i).unwrap_or_else(|| master.range(0, p as u64 - 1) as Nanos))
            .collect(),
        Phasing::Grid(g) => {
            if *g <= 0 {
                return Err(SimError::GridNotPositive(*g));
            }
            periods
                .iter()
                .enumerate()
                .map(|(i, &p)| {
                    known(i).unwrap_or_else(|| master.range(0, ((p - 1) / g) as u64) as Nanos * g)
                })
                .collect()
        }
        Phasing::Given(v) => {
            if v.len() != n {
                return Err(SimError::BadOffsets {
                    expected: n,
                    found: v.len(),
                });
            }
            if let Some(i) = v.iter().position(|&o| o < 0) {
                return Err(SimError::NegativeOffset(spec.tasks[i].name.clone()));
            }
            let clash = (0..n).find_map(|i| known(i).filter(|&k| k != v[i]).map(|k| (i, k)));
            if let Some((i, k)) = clash {
                return Err(SimError::OffsetConflict {
                    task: spec.tasks[i].name.clone(),
                    known: k,
                    given: v[i],
                });
            }
            v.clone()
        }
    })
}

/// Each task's simulation state (its server, rank, demand stream) and the
/// tasks of each CPU.
pub(super) fn task_sims(
    spec: &Spec,
    periods: &[Nanos],
    offsets: &[Nanos],
    jitter: Jitter,
    master: &mut Rng,
) -> (Vec<TaskSim>, Vec<Vec<usize>>) {
    let n = spec.tasks.len();
    let ranks = ranks(spec);
    let mut cpu_ids: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    cpu_ids.sort_unstable();
    cpu_ids.dedup();
    let mut cpu_tasks = vec![Vec::new(); cpu_ids.len()];
    let mut tasks = Vec::with_capacity(n);
    for (i, t) in spec.tasks.iter().enumerate() {
        let cpu = cpu_ids.binary_search(&t.cpu).unwrap_or(0);
        cpu_tasks[cpu].push(i);
        let (c, p) = (t.budget(), periods[i]);
        let budget = match spec.policy().budget(t.server) {
            None => Budget::Unlimited,
            Some(Kind::Cbs) => Budget::Cbs(Box::new(Cbs::with_deadline(
                c,
                p,
                t.deadline().unwrap_or(p),
            ))),
            Some(Kind::Sporadic) => Budget::Sporadic(Box::new(Sporadic::new(c, p, 0))),
            Some(Kind::Pibs) => Budget::Pibs(Box::new(Pibs::new(c, p))),
        };
        tasks.push(TaskSim {
            slack_when_empty: matches!(budget, Budget::Sporadic(_)),
            budget,
            period: periods[i],
            deadline: t.deadline().unwrap_or(p),
            jitter: t.jitter,
            jitter_model: jitter,
            next_nominal: if t.is_triggered() {
                NO_TIMER
            } else {
                offsets[i]
            },
            class: u8::from(t.server == Server::Background),
            rank: ranks[i].map_or(i as i64, |r| r as i64),
            // An index beyond 32 bits is left to `standing`, which panics
            // on any index out of range.
            serves: spec
                .policy()
                .inherits_from(t.serves)
                .map(|m| u32::try_from(m).unwrap_or(u32::MAX)),
            demand_min: t.demand_min(),
            demand: t.demand(),
            rng: Rng::new(master.next_u64()),
            next_release: NO_TIMER,
            next_index: 0,
            queue: VecDeque::new(),
            merges: t.merges_releases(),
            stats: TaskStats::default(),
            // A dense index into the spec's distinct u32 CPU ids: it fits.
            cpu: cpu as u32,
            servers: Vec::new(),
            entry: None,
            timer: None,
            sides: Sides::default(),
        });
        if let (Some(ts), false) = (tasks.last_mut(), t.is_triggered()) {
            // The first job is jittered too.
            ts.next_release = offsets[i] + jitter_draw(ts);
        }
    }
    (tasks, cpu_tasks)
}

/// The servers (PIBS) each Main VCPU has.
pub(super) fn link_servers(tasks: &mut [TaskSim]) {
    let n = tasks.len();
    for i in 0..n {
        if let Some(m) = tasks[i].serves.map(|m| m as usize) {
            // An index out of range is left to `standing`, which
            // panics on it as the scan did.
            if let Some(ms) = tasks.get_mut(m) {
                ms.servers.push(i);
            }
        }
    }
}

/// Each task's [`Sides`], from the side tables and the servers linked.
pub(super) fn mark_sides(
    spec: &Spec,
    tasks: &mut [TaskSim],
    prov: &Provenance,
    locks: &Locks,
    ovh: &crate::overheads::Overheads,
    event_model: &events::Events,
) {
    // LET tasks (per chain, `Spec::communications`): their reads at
    // releases and publishes at period ends feed the provenance, not the
    // schedule's instants (`let_comm.rs`).
    let communications = spec.communications();
    for (i, ts) in tasks.iter_mut().enumerate() {
        let served = !ts.servers.is_empty();
        ts.sides = Sides::of(i, communications[i], served, prov, locks, ovh, event_model);
    }
}

/// Every task's next release in the release heap.
pub(super) fn release_heap(tasks: &[TaskSim]) -> ReleaseHeap {
    // The heap keeps task indices in 32 bits (a spec of 2^32 tasks would
    // not fit in memory to begin with).
    assert!(
        u32::try_from(tasks.len()).is_ok(),
        "{} tasks: more than the release heap indexes",
        tasks.len()
    );
    ReleaseHeap::new(
        tasks
            .iter()
            .enumerate()
            .map(|(i, ts)| (ts.next_release, i as u32)),
    )
}

/// Which of the per-task side tables (threads, triggers, chains, release
/// overheads, critical sections, LET) an event of a task must visit: all
/// false for a plain periodic task. Kept in the task's own state, which
/// its every event reads anyway, so that the event of a plain task does
/// not touch a cache line of each table only to find nothing there; in a
/// system of thousands of tasks those lines are cache misses, and they
/// were most of an event's (docs/guide/simulate.md).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Sides {
    /// LET communication (`let_comm.rs`, `Spec::communications`).
    pub(crate) let_comm: bool,
    /// Runs on a work-queue thread (`events.rs`).
    pub(crate) thread: bool,
    /// Its publications release data-triggered tasks (`events.rs`).
    pub(crate) triggers: bool,
    /// On a chain: its reads and publishes carry samples (`Provenance`).
    pub(crate) chains: bool,
    /// A release costs kernel work (`overheads.rs`).
    pub(crate) release_work: bool,
    /// It has critical sections (`locks.rs`): only such a task holds or
    /// waits for a resource.
    pub(crate) sections: bool,
    /// I/O VCPUs serve it (`TaskSim::servers`).
    pub(crate) served: bool,
}

impl Sides {
    /// Task i's, from the side tables and its communication semantics.
    pub(super) fn of(
        i: usize,
        communication: Communication,
        served: bool,
        prov: &Provenance,
        locks: &Locks,
        ovh: &crate::overheads::Overheads,
        event_model: &events::Events,
    ) -> Sides {
        Sides {
            let_comm: communication == Communication::Let,
            thread: event_model.thread_of[i].is_some(),
            triggers: event_model.triggers_any(i),
            chains: !prov.slots(i).is_empty(),
            release_work: ovh.release_work(i, 1) != 0,
            sections: locks.has_sections(i),
            served,
        }
    }
}
