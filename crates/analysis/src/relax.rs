//! The sound analysis over a box of periods: lower bounds that hold for
//! every choice of periods `lo ≤ T ≤ hi`, for a design search that prunes
//! whole boxes (`rtpipe_design`'s branch and bound).
//!
//! Nothing here is a second copy of the analysis. The link terms are the
//! ones of [`crate::latency`], evaluated at the box's most favourable values:
//! every option of every term grows with periods and response times, so the
//! terms at `T = lo` and `R = R_lb` bound them from below; where the priority
//! order of a link is not decided by the box, the smallest term over the
//! possible orders is taken. Response times come from the same recurrence
//! ([`response_time`]) with only the tasks that are above whatever the
//! periods, at their longest periods: fewer and rarer interferers can only
//! shorten the fixed point. At a box of one point every figure equals the
//! analysis' (a test checks it), and shrinking a box never lowers a figure.
//! docs/design.md gives the argument.

use crate::latency::{
    distinct_passes, sound_freshness_link_in, sound_reaction_link_in, Case, LinkTask,
};
use crate::sched::{interference, response_time, utilization_test};
use rtpipe_model::{Nanos, SchedTest, Scheduler, Server, Spec};

/// Lower bounds over a box of periods.
#[derive(Debug, Clone, PartialEq)]
pub struct Relaxed {
    /// Per task: a lower bound on the job response time (demand x), `None`
    /// when it exceeds the period at every point of the box (or diverges).
    pub job_response: Vec<Option<Nanos>>,
    /// Per task: the same at budget level (the RTA test's figure).
    pub budget_response: Vec<Option<Nanos>>,
    /// Per CPU, ascending: whether its schedulability test may pass
    /// somewhere in the box.
    pub cpus: Vec<(u32, bool)>,
    /// Per declared chain: lower bounds on its sound (reaction, freshness)
    /// from the read; `None` when the chain is unbounded everywhere.
    pub chains: Vec<(Option<Nanos>, Option<Nanos>)>,
}

/// The priority facts a box decides, for one CPU under RM.
struct Order<'a> {
    spec: &'a Spec,
    lo: &'a [Nanos],
    hi: &'a [Nanos],
    /// Rank orders imposed besides the box: (a, b) = a above b.
    imposed: &'a [(usize, usize)],
}

impl Order<'_> {
    fn ranked(&self, a: usize) -> bool {
        let t = &self.spec.tasks[a];
        self.spec.scheduler == Scheduler::Rm && t.server != Server::Background
    }

    /// `a` has the higher RM rank at every point: (T_a, a) < (T_b, b) always.
    fn surely_above(&self, a: usize, b: usize) -> bool {
        self.ranked(a)
            && self.ranked(b)
            && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
            && ((self.hi[a], a) < (self.lo[b], b) || self.imposed.contains(&(a, b)))
    }

    /// `a` has the higher RM rank at some point of the box.
    fn maybe_above(&self, a: usize, b: usize) -> bool {
        self.ranked(a)
            && self.ranked(b)
            && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
            && (self.lo[a], a) < (self.hi[b], b)
            && !self.imposed.contains(&(b, a))
    }

    /// `j` runs above `i` at every point (`sched::interferers`): its own rank
    /// or the rank it inherits from the task it serves is at or above i's.
    fn surely_interferes(&self, j: usize, i: usize) -> bool {
        let served = self.spec.tasks[j].serves;
        j != i
            && self.ranked(j)
            && self.ranked(i)
            && self.spec.tasks[j].cpu == self.spec.tasks[i].cpu
            && (self.surely_above(j, i)
                || served == Some(i)
                || served.is_some_and(|m| self.surely_above(m, i)))
    }

    /// `a` above `b` at every instant (`latency::fp_order`: a's own rank
    /// above b's own and inherited ones) at some point of the box.
    fn maybe_preempts(&self, a: usize, b: usize) -> bool {
        self.maybe_above(a, b)
            && self.spec.tasks[b]
                .serves
                .is_none_or(|m| m != a && self.maybe_above(a, m))
    }

    /// The link orders (`fp_order`) possible over the box; `[None]` when the
    /// priority arguments never apply.
    fn link_orders(&self, p: usize, c: usize) -> Vec<Option<Case>> {
        let same = self.spec.tasks[p].cpu == self.spec.tasks[c].cpu;
        if !(same && self.ranked(p) && self.ranked(c)) {
            return vec![None];
        }
        let mut v = Vec::new();
        if self.maybe_preempts(c, p) {
            v.push(Some(Case::One));
        }
        if self.maybe_preempts(p, c) {
            v.push(Some(Case::Two));
        }
        // Some point may have neither (an inherited rank ties them).
        if !(self.surely_preempts(c, p) || self.surely_preempts(p, c)) {
            v.push(None);
        }
        v
    }

    fn surely_preempts(&self, a: usize, b: usize) -> bool {
        self.surely_above(a, b)
            && self.spec.tasks[b]
                .serves
                .is_none_or(|m| m != a && self.surely_above(a, m))
    }
}

/// Lower bounds of the sound analysis over the periods `lo[i] ≤ T_i ≤ hi[i]`
/// (ns, one entry per task; background tasks' entries are ignored) at which
/// every pair `(a, b)` of `imposed` has a ranked above b (RM: (T_a, a) <
/// (T_b, b)), for a search that branches on priority orders too.
pub fn relax(spec: &Spec, lo: &[Nanos], hi: &[Nanos], imposed: &[(usize, usize)]) -> Relaxed {
    let n = spec.tasks.len();
    assert!(lo.len() == n && hi.len() == n, "relax: one interval per task");
    assert!(
        (0..n).all(|i| 0 < lo[i] && lo[i] <= hi[i]),
        "relax: empty or non-positive period interval"
    );
    let order = Order {
        spec,
        lo,
        hi,
        imposed,
    };
    let cpus = cpu_ids(spec);
    let util_ok = |cpu: u32| {
        let us = cpu_utilizations(spec, hi, cpu);
        us.iter().sum::<f64>() <= 1.0 + 1e-12
    };
    let mut job_response = vec![None; n];
    let mut budget_response = vec![None; n];
    for (i, t) in spec.tasks.iter().enumerate() {
        if t.server == Server::Background {
            continue;
        }
        let (rb, rj) = match spec.scheduler {
            Scheduler::Rm => {
                let hp: Vec<(Nanos, Nanos)> = (0..n)
                    .filter(|&j| order.surely_interferes(j, i))
                    .map(|j| (interference(&spec.tasks[j]), hi[j]))
                    .collect();
                (response_time(t.budget(), &hp), response_time(t.demand(), &hp))
            }
            // Servers get their budget by the end of each period (`sched`).
            Scheduler::Edf if util_ok(t.cpu) => (Some(lo[i]), Some(lo[i])),
            Scheduler::Edf => (None, None),
        };
        budget_response[i] = rb.filter(|&r| r <= hi[i]);
        job_response[i] = rj.filter(|&r| r <= hi[i]);
    }
    let cpus = cpus
        .into_iter()
        .map(|cpu| (cpu, cpu_may_pass(spec, hi, &budget_response, cpu)))
        .collect();
    let chains = spec
        .chains
        .iter()
        .map(|ch| chain_bounds(spec, &order, &job_response, &ch.path))
        .collect();
    Relaxed {
        job_response,
        budget_response,
        cpus,
        chains,
    }
}

fn cpu_ids(spec: &Spec) -> Vec<u32> {
    let mut cpus: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
    cpus.sort_unstable();
    cpus.dedup();
    cpus
}

/// C/T of the guaranteed tasks of `cpu` at periods `t`.
fn cpu_utilizations(spec: &Spec, t: &[Nanos], cpu: u32) -> Vec<f64> {
    spec.tasks
        .iter()
        .enumerate()
        .filter(|(_, x)| x.cpu == cpu && x.server != Server::Background)
        .map(|(i, x)| x.budget() as f64 / t[i] as f64)
        .collect()
}

/// The CPU's test may pass in the box: utilisation tests at the longest
/// periods (the least utilisation), RTA with the response-time bounds.
fn cpu_may_pass(spec: &Spec, hi: &[Nanos], budget_r: &[Option<Nanos>], cpu: u32) -> bool {
    match spec.schedulability {
        SchedTest::Rta => spec
            .tasks
            .iter()
            .enumerate()
            .filter(|(_, t)| t.cpu == cpu && t.server != Server::Background)
            .all(|(i, _)| budget_r[i].is_some()),
        test => utilization_test(test, &cpu_utilizations(spec, hi, cpu)).2,
    }
}

/// The link terms' view of task `i` at the box's most favourable values.
fn link_task(spec: &Spec, t: Nanos, r: Option<Nanos>, i: usize) -> LinkTask {
    let task = &spec.tasks[i];
    LinkTask {
        c: task.budget(),
        t,
        x: task.demand(),
        x_min: task.demand_min(),
        delta_out: task.delta_out,
        l: crate::latency::eq1_single_pipe(task.demand(), task.budget(), t),
        r,
        cpu: task.cpu,
        prio: None,
        top: None,
    }
}

/// Lower bounds on a chain's sound reaction and freshness from the read,
/// composed as `latency::analyze_chain` composes them.
fn chain_bounds(
    spec: &Spec,
    order: &Order,
    r: &[Option<Nanos>],
    path: &[usize],
) -> (Option<Nanos>, Option<Nanos>) {
    let low = |i: usize| link_task(spec, order.lo[i], r[i], i);
    let (head, tail) = (path[0], path[path.len() - 1]);
    let mut react = r[head];
    let mut fresh = Some(0);
    // Reachability needs the producer's samples distinct; take it where it
    // may hold (more options, smaller terms).
    let mut distinct = true;
    for w in path.windows(2) {
        let (p, c) = (low(w[0]), low(w[1]));
        let orders = order.link_orders(w[0], w[1]);
        let least = |f: &dyn Fn(Option<Case>) -> Option<Nanos>| {
            orders.iter().filter_map(|&o| f(o)).min()
        };
        let e = least(&|o| sound_reaction_link_in(o, &p, &c, distinct));
        let f = least(&|o| sound_freshness_link_in(o, &p, &c));
        react = react.zip(e).map(|(a, b)| a + b);
        fresh = fresh.zip(f).map(|(a, b)| a + b);
        // The condition grows with T_c: test it at c's longest period.
        let c_late = link_task(spec, order.hi[w[1]], r[w[1]], w[1]);
        distinct = distinct_passes(&p, &c_late, distinct);
    }
    fresh = fresh.zip(r[tail]).map(|(a, b)| a + b);
    let react = match (react, fresh) {
        (Some(e), Some(f)) => Some(e.min(f)),
        (e, _) => e,
    };
    (react, fresh)
}
