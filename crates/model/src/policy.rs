//! Scheduling policies: what a [`Scheduler`] means to everything that
//! schedules or analyses tasks.
//!
//! Each policy is one [`SchedPolicy`] descriptor: who preempts whom, which
//! budget each kind of VCPU gets, which response-time analysis and
//! schedulability tests apply, and which Linux class runs it. The analysis,
//! the simulator, the design and the runtime ask the descriptor instead of
//! matching on the scheduler, so adding a policy is a variant of
//! [`Scheduler`] and its descriptor here, plus the mechanisms it names.

use crate::{Nanos, Server, Spec};

/// How CPUs pick among ready pipe terminals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheduler {
    /// Fixed priority, rate monotonic; equal periods are ordered by declaration.
    Rm,
    /// Reservations scheduled EDF (constant-bandwidth servers, as SCHED_DEADLINE).
    Edf,
}

impl Scheduler {
    /// Every scheduler, in the order specs list them.
    pub const ALL: [Scheduler; 2] = [Scheduler::Rm, Scheduler::Edf];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        self.policy().name
    }

    /// The policy's descriptor.
    #[inline]
    pub fn policy(self) -> &'static SchedPolicy {
        match self {
            Scheduler::Rm => &RM,
            Scheduler::Edf => &EDF,
        }
    }
}

/// The schedulability test applied per CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SchedTest {
    /// Σ U ≤ n(2^{1/n} − 1) (Liu and Layland 1973), the test of Table II.
    LiuLayland,
    /// Π (U_i + 1) ≤ 2 (Bini, Buttazzo, Buttazzo 2003).
    Hyperbolic,
    /// Exact response-time analysis: every R_i ≤ T_i.
    Rta,
    /// EDF: Σ U ≤ 1 (exact when every deadline equals its period).
    Edf,
    /// EDF with constrained deadlines: the processor-demand test by Quick
    /// Processor-demand Analysis (Zhang and Burns 2009).
    Qpa,
}

impl SchedTest {
    /// Every test, in the order specs list them.
    pub const ALL: [SchedTest; 5] = [
        SchedTest::LiuLayland,
        SchedTest::Hyperbolic,
        SchedTest::Rta,
        SchedTest::Edf,
        SchedTest::Qpa,
    ];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        match self {
            SchedTest::LiuLayland => "liu-layland",
            SchedTest::Hyperbolic => "hyperbolic",
            SchedTest::Rta => "rta",
            SchedTest::Edf => "edf",
            SchedTest::Qpa => "qpa",
        }
    }

    /// The test holds only for implicit deadlines (D = T), jitter-free
    /// releases and, for the fixed-priority ones, rate-monotonic ranks:
    /// Liu–Layland, hyperbolic and the EDF utilisation test.
    pub fn needs_implicit_deadlines(self) -> bool {
        matches!(
            self,
            SchedTest::LiuLayland | SchedTest::Hyperbolic | SchedTest::Edf
        )
    }
}

/// How fixed priorities are assigned (`[system] priorities`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Priorities {
    /// Shorter period first, ties by declaration order (the default).
    #[default]
    RateMonotonic,
    /// Shorter deadline first (D, or T when none is given), ties by
    /// declaration order.
    DeadlineMonotonic,
    /// Each task's `priority = N`, 1 the highest.
    Explicit,
}

impl Priorities {
    /// Every order, in the order specs list them.
    pub const ALL: [Priorities; 3] = [
        Priorities::RateMonotonic,
        Priorities::DeadlineMonotonic,
        Priorities::Explicit,
    ];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        match self {
            Priorities::RateMonotonic => "rate-monotonic",
            Priorities::DeadlineMonotonic => "deadline-monotonic",
            Priorities::Explicit => "explicit",
        }
    }
}

/// When a task's jobs exchange data with the registers (`[system]
/// communication`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Communication {
    /// Implicit communication (the paper's): a job reads when it first
    /// gets the CPU and publishes when it completes.
    #[default]
    Implicit,
    /// Logical Execution Time (Kirsch and Sokolova 2012): a job reads at
    /// its release and its output becomes visible at the end of its period
    /// (release + T), whenever it ran, so the data flow depends on the
    /// periods and offsets alone. A job that has not completed by then
    /// misses its deadline.
    Let,
}

impl Communication {
    /// Every semantics, in the order specs list them.
    pub const ALL: [Communication; 2] = [Communication::Implicit, Communication::Let];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        match self {
            Communication::Implicit => "implicit",
            Communication::Let => "let",
        }
    }
}

/// How tasks of one CPU share a resource (`[system] resource_protocol`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ResourceProtocol {
    /// Priority ceiling (Sha, Rajkumar, Lehoczky 1990), run as its
    /// immediate form: a job holding a resource runs at the resource's
    /// ceiling (the highest rank of the tasks that use it). A job is
    /// blocked at most once, for one critical section of a lower-priority
    /// task on a resource whose ceiling is at or above its rank.
    #[default]
    Pcp,
    /// The stack resource policy (Baker 1991). Under fixed priorities the
    /// same preemption ceilings, the same bound and the same schedule as
    /// the immediate priority ceiling; under EDF a job starts only when its
    /// deadline is the earliest of the ready jobs and its preemption level
    /// ([`preemption_levels`]) is above the ceilings of the resources held.
    Srp,
    /// Priority inheritance (Sha, Rajkumar, Lehoczky 1990): a job holding
    /// a resource runs at the highest rank of the jobs it blocks; a job
    /// can be blocked once per lower-priority task and once per resource.
    Pip,
}

impl ResourceProtocol {
    /// Every protocol, in the order specs list them.
    pub const ALL: [ResourceProtocol; 3] = [
        ResourceProtocol::Pcp,
        ResourceProtocol::Srp,
        ResourceProtocol::Pip,
    ];

    /// The name used in specs and output.
    pub fn name(self) -> &'static str {
        match self {
            ResourceProtocol::Pcp => "pcp",
            ResourceProtocol::Srp => "srp",
            ResourceProtocol::Pip => "pip",
        }
    }

    /// A job holding a resource runs at the resource's ceiling (PCP, SRP),
    /// not at the rank of the jobs it blocks (PIP).
    pub fn ceiling(self) -> bool {
        self != ResourceProtocol::Pip
    }
}

/// Who preempts whom on a CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preemption {
    /// Fixed ranks ([`SchedPolicy::priorities`]): a ready task of a higher
    /// rank preempts; an I/O VCPU inherits the rank of the Main VCPU it
    /// serves while that one has a job pending (PIBS).
    FixedPriority,
    /// The earliest absolute deadline (release + period) runs first.
    EarliestDeadline,
}

/// The budget a guaranteed VCPU enforces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Budget {
    /// Sporadic server: C per T, replenished T after it is consumed.
    Sporadic,
    /// Priority-inheritance bandwidth-preserving server (the paper's I/O VCPU).
    Pibs,
    /// Constant-bandwidth server (SCHED_DEADLINE's reservation).
    Cbs,
}

/// Which response-time analysis bounds a task's jobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResponseAnalysis {
    /// Exact response-time analysis over the tasks that can run above it
    /// (Joseph and Pandya 1986; Audsley et al. 1993).
    Rta,
    /// The server period: a reservation delivers its budget by the end of
    /// each period when its CPU is not overloaded, possibly at the very end.
    ServerPeriod,
    /// EDF response-time analysis (Spuri 1996) over the reservations of a
    /// CPU, each with deadline = period; the server period where the busy
    /// period is too long to analyse.
    EdfRta,
}

/// How a spec with work-queue threads and data-triggered tasks is analysed
/// under a policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventAnalysis {
    /// Event models per task, FIFO inside each thread, fixed priorities
    /// between threads and thread-less tasks, iterated holistically over
    /// the triggers' jitter (docs/analysis.md, "Threads and data-triggered
    /// tasks").
    HolisticFifo,
}

/// The Linux scheduling class that runs a policy on real threads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinuxClass {
    /// SCHED_FIFO with one static priority per rank.
    Fifo,
    /// SCHED_DEADLINE with one reservation per task.
    Deadline,
}

/// What a scheduling policy means to the analysis, the simulator, the
/// design and the runtime.
#[derive(Debug, PartialEq, Eq)]
pub struct SchedPolicy {
    /// The name used in specs and output.
    pub name: &'static str,
    /// Who preempts whom.
    pub preemption: Preemption,
    /// The budget of a Main VCPU.
    pub main_budget: Budget,
    /// The budget of an I/O VCPU.
    pub io_budget: Budget,
    /// How job response times are bounded.
    pub response: ResponseAnalysis,
    /// How threads and data-triggered tasks are analysed (`None`: the
    /// policy has no analysis of them, and validation refuses them).
    pub events: Option<EventAnalysis>,
    /// The schedulability tests that apply; the first is the default.
    pub tests: &'static [SchedTest],
    /// What to write instead of a test that does not apply.
    pub tests_help: &'static str,
    /// The Linux class that runs it.
    pub linux: LinuxClass,
    /// The resource protocols the analysis and the simulator implement
    /// under this policy (none: specs with resources are refused).
    pub resource_protocols: &'static [ResourceProtocol],
    /// What to do instead of a resource this policy cannot analyse.
    pub resources_help: &'static str,
}

const RM: SchedPolicy = SchedPolicy {
    name: "rm",
    preemption: Preemption::FixedPriority,
    main_budget: Budget::Sporadic,
    io_budget: Budget::Pibs,
    response: ResponseAnalysis::Rta,
    events: Some(EventAnalysis::HolisticFifo),
    tests: &[SchedTest::Rta, SchedTest::LiuLayland, SchedTest::Hyperbolic],
    tests_help: "with scheduler = \"rm\" use \"liu-layland\", \"hyperbolic\" or \"rta\"",
    linux: LinuxClass::Fifo,
    resource_protocols: &ResourceProtocol::ALL,
    resources_help: "with scheduler = \"rm\" use resource_protocol = \"pcp\", \"srp\" or \"pip\"",
};

const EDF: SchedPolicy = SchedPolicy {
    name: "edf",
    preemption: Preemption::EarliestDeadline,
    main_budget: Budget::Cbs,
    io_budget: Budget::Cbs,
    response: ResponseAnalysis::EdfRta,
    events: None,
    tests: &[SchedTest::Edf, SchedTest::Qpa],
    tests_help: "with scheduler = \"edf\" use schedulability = \"edf\" (the utilisation test) or \"qpa\" (the processor-demand test, for deadlines below periods)",
    linux: LinuxClass::Deadline,
    resource_protocols: &[ResourceProtocol::Srp],
    resources_help: "under scheduler = \"edf\" shared resources need the stack resource policy (Baker 1991): write resource_protocol = \"srp\" in [system]",
};

impl SchedPolicy {
    /// Tasks run by fixed ranks (so priority arguments apply between them).
    pub fn fixed_priority(&self) -> bool {
        self.preemption == Preemption::FixedPriority
    }

    /// The test a spec gets when it names none.
    pub fn default_test(&self) -> SchedTest {
        self.tests[0]
    }

    /// The test a spec gets when it names none, given whether some task has
    /// a deadline below its period or release jitter: the first admitted
    /// test that holds for such tasks.
    pub fn default_test_for(&self, constrained: bool) -> SchedTest {
        self.tests
            .iter()
            .copied()
            .find(|t| !(constrained && t.needs_implicit_deadlines()))
            .unwrap_or(self.tests[0])
    }

    /// `test` applies to this policy.
    pub fn admits(&self, test: SchedTest) -> bool {
        self.tests.contains(&test)
    }

    /// The budget a VCPU of this kind enforces; `None` for a plain periodic
    /// or a background task, which enforce none.
    pub fn budget(&self, server: Server) -> Option<Budget> {
        match server {
            Server::Main => Some(self.main_budget),
            Server::Io => Some(self.io_budget),
            Server::None | Server::Background => None,
        }
    }

    /// The Main VCPU whose rank an I/O VCPU inherits while it has a job
    /// pending (PIBS), where the policy has ranks to inherit.
    pub fn inherits_from(&self, serves: Option<usize>) -> Option<usize> {
        serves.filter(|_| self.fixed_priority())
    }

    /// Ranks per CPU, 1 = highest (`None` for background tasks, and for
    /// every task when the policy has no fixed ranks).
    pub fn priorities(&self, spec: &Spec) -> Vec<Option<usize>> {
        match self.preemption {
            Preemption::FixedPriority => ranks(spec),
            Preemption::EarliestDeadline => vec![None; spec.tasks.len()],
        }
    }
}

/// Fixed-priority ranks per CPU in the spec's order (`[system]
/// priorities`): [`rate_monotonic`], [`deadline_monotonic`] or the explicit
/// `priority` of each task. Background tasks get none. The tasks of one
/// work-queue thread share the thread's rank (validation makes every
/// other rank on a CPU distinct). Whatever runs tasks
/// by fixed priority (the analysis, the simulator, the design, the
/// runtime's SCHED_FIFO priorities) takes its ranks from here.
pub fn ranks(spec: &Spec) -> Vec<Option<usize>> {
    ranked_by(spec, |t| {
        rank_key(spec.priorities, t).at(t.fixed_period().unwrap_or(Nanos::MAX))
    })
}

/// What ranks a task under a priority order (smaller ranks higher, ties
/// by declaration order): its period, or a constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RankKey {
    /// The task's period (rate-monotonic; deadline-monotonic without a
    /// given deadline, D = T).
    Period,
    /// A given deadline (deadline-monotonic) or priority (explicit).
    Fixed(Nanos),
}

impl RankKey {
    /// The key's value when the task's period is `period`. It never falls
    /// as the period grows, which the design's box search uses to bound
    /// it over an interval of periods.
    pub fn at(self, period: Nanos) -> Nanos {
        match self {
            RankKey::Period => period,
            RankKey::Fixed(k) => k,
        }
    }
}

/// The key that ranks task `t` under `order`: the period (rate-monotonic),
/// the given deadline or else the period (deadline-monotonic), the
/// explicit `priority`. Validation makes explicit priorities distinct per
/// CPU; a task without one (not a validated spec) ranks last.
pub fn rank_key(order: Priorities, t: &crate::Task) -> RankKey {
    match (order, t.deadline_given) {
        (Priorities::RateMonotonic, _) | (Priorities::DeadlineMonotonic, None) => RankKey::Period,
        (Priorities::DeadlineMonotonic, Some(d)) => RankKey::Fixed(d),
        (Priorities::Explicit, _) => RankKey::Fixed(t.priority.map_or(Nanos::MAX, Nanos::from)),
    }
}

/// Deadline-monotonic ranks per CPU: shorter deadline (D, else T) first,
/// ties by declaration order.
pub fn deadline_monotonic(spec: &Spec) -> Vec<Option<usize>> {
    ranked_by(spec, |t| {
        rank_key(Priorities::DeadlineMonotonic, t).at(t.fixed_period().unwrap_or(Nanos::MAX))
    })
}

/// The stack resource policy's preemption levels under EDF, per CPU, as
/// ranks (1 = the highest level): shorter relative deadline (D, else T)
/// first, ties by declaration order, the order in which EDF breaks ties of
/// absolute deadlines; background tasks get none. A job of a higher level
/// has a shorter relative deadline or, on a tie, wins every tie of
/// absolute deadlines, which is Baker's condition (a job may preempt
/// another only when its level is higher). The analysis
/// (`analysis/src/blocking.rs`) and the simulator (`sim/src/locks.rs`)
/// take them from here.
pub fn preemption_levels(spec: &Spec) -> Vec<Option<usize>> {
    deadline_monotonic(spec)
}

/// The stack resource policy's numbers, as the simulator
/// (`sim/src/locks.rs`) and the runtime's EDF dispatcher
/// (`runtime/src/edf.rs`) apply them: per task its preemption level as a
/// rank ([`preemption_levels`]; `Nanos::MAX`, the lowest, for a task with
/// none), per resource its ceiling (the best level of its users;
/// `Nanos::MAX` for a resource nobody uses).
pub fn srp_levels(spec: &Spec) -> (Vec<Nanos>, Vec<Nanos>) {
    let level: Vec<Nanos> = preemption_levels(spec)
        .iter()
        .map(|r| r.map_or(Nanos::MAX, |r| r as Nanos))
        .collect();
    let mut ceiling = vec![Nanos::MAX; spec.resources.len()];
    for (i, t) in spec.tasks.iter().enumerate() {
        for s in &t.sections {
            if let Some(c) = ceiling.get_mut(s.resource) {
                *c = (*c).min(level[i]);
            }
        }
    }
    (level, ceiling)
}

/// SRP's start rule (Baker 1991): a job that has not started yet may start
/// only when its level (a rank, smaller is higher) is above the system
/// ceiling, the best ceiling of the resources held on its CPU (`None`:
/// none is held). A job that has started runs whatever the ceiling: it
/// passed the test when it started.
pub fn srp_may_start(started: bool, level: Nanos, system_ceiling: Option<Nanos>) -> bool {
    started || system_ceiling.is_none_or(|c| level < c)
}

/// Rate-monotonic ranks per CPU: shorter period first, ties by declaration
/// order; background tasks get none. A task without a fixed period ranks
/// last among its CPU's.
pub fn rate_monotonic(spec: &Spec) -> Vec<Option<usize>> {
    ranked_by(spec, |t| t.fixed_period().unwrap_or(Nanos::MAX))
}

/// Ranks per CPU by `key` (smaller first), ties by declaration order;
/// background tasks get none.
fn ranked_by(spec: &Spec, key: impl Fn(&crate::Task) -> Nanos) -> Vec<Option<usize>> {
    let mut out = vec![None; spec.tasks.len()];
    for (_, on) in spec.tasks_by_cpu().iter() {
        let mut ids: Vec<usize> = on
            .iter()
            .copied()
            .filter(|&i| spec.tasks[i].server != Server::Background)
            .collect();
        ids.sort_by_key(|&i| (key(&spec.tasks[i]), i));
        // The tasks of one thread share its rank: they have its priority,
        // so they sort next to each other, and none preempts another.
        let mut rank = 0;
        let mut previous: Option<usize> = None;
        for i in ids {
            let thread = spec.tasks[i].thread;
            if thread.is_none() || thread != previous {
                rank += 1;
            }
            previous = thread;
            out[i] = Some(rank);
        }
    }
    out
}

impl Spec {
    /// The descriptor of the spec's scheduler.
    #[inline]
    pub fn policy(&self) -> &'static SchedPolicy {
        self.scheduler.policy()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_policy_has_a_default_test_it_admits() {
        for s in Scheduler::ALL {
            let p = s.policy();
            assert_eq!(p.name, s.name());
            assert!(p.admits(p.default_test()));
        }
        assert_eq!(Scheduler::Rm.policy().default_test(), SchedTest::Rta);
        assert_eq!(Scheduler::Edf.policy().default_test(), SchedTest::Edf);
        assert_eq!(
            Scheduler::Edf.policy().default_test_for(true),
            SchedTest::Qpa
        );
        assert_eq!(
            Scheduler::Rm.policy().default_test_for(true),
            SchedTest::Rta
        );
    }

    #[test]
    fn every_test_applies_to_exactly_one_policy() {
        for t in SchedTest::ALL {
            let n = Scheduler::ALL
                .iter()
                .filter(|s| s.policy().admits(t))
                .count();
            assert_eq!(n, 1, "{}", t.name());
        }
    }
}
