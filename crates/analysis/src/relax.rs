//! The sound analysis over a box of periods: lower bounds that hold for
//! every choice of periods `lo ≤ T ≤ hi`, for a design search that prunes
//! whole boxes (`rtpipe_design`'s branch and bound).
//!
//! Nothing here is a second copy of the analysis. The link terms are the
//! ones of [`crate::latency`], evaluated at the box's most favourable values:
//! every option of every term grows with periods and response times, so the
//! terms at `T = lo` and `R = R_lb` bound them from below; where the priority
//! order of a link is not decided by the box, the smallest term over the
//! possible orders is taken. Response times come from the same level-i
//! busy period ([`crate::sched::level_response`]) with only the tasks that are above
//! whatever the periods, at their longest periods, and the task's own
//! longest period: fewer and rarer interferers can only shorten each fixed
//! point, and a longer own period lets fewer own jobs into the busy period,
//! each with a smaller `w_q − q·T`. Blocking counts only the sections that can block
//! at every point of the box, overheads their per-job and per-release
//! charges at the longest periods (docs/design.md, "Critical sections and
//! overheads"). At a box of one point every figure equals the analysis' (a
//! test checks it), and shrinking a box never lowers a figure.
//! docs/design.md gives the argument.

use crate::blocking::guaranteed;
use crate::latency::{compose_sound, distinct_passes, Case, LinkTask, SoundLink};
use crate::let_bound::{any_phasing, LetLatencies};
use crate::sched::{
    deadline_at, interference, level_response_within, tasks_on, utilization_test, OwnJobs,
};
use rtpipe_model::policy::{rank_key, RankKey, ResponseAnalysis};
use rtpipe_model::{Communication, Nanos, SchedTest, Server, Spec};

mod link;
mod paper;
mod pieces;
use link::least_link;
use paper::{paper_bounds, paper_forms};
pub use pieces::{most_ranges, paper_pieces, sound_pieces, MinSum, Piece, SoundSums};

/// Lower bounds over a box of periods.
#[derive(Debug, Clone, PartialEq)]
pub struct Relaxed {
    /// Per task: a lower bound on the job response time (demand x), `None`
    /// when it exceeds the period at every point of the box (or diverges).
    pub job_response: Vec<Option<Nanos>>,
    /// Per task: a lower bound on the read-to-publish bound `W`
    /// (`TaskTiming::read_to_publish`), `None` where `job_response` is.
    pub read_to_publish: Vec<Option<Nanos>>,
    /// Per task: the same at budget level (the RTA test's figure).
    pub budget_response: Vec<Option<Nanos>>,
    /// Per CPU, ascending: whether its schedulability test may pass
    /// somewhere in the box.
    pub cpus: Vec<(u32, bool)>,
    /// Per declared chain: lower bounds on its sound (reaction, freshness)
    /// from the read; `None` when the chain is unbounded everywhere.
    pub chains: Vec<(Option<Nanos>, Option<Nanos>)>,
    /// Per declared chain: the two sums that the sound reaction is the
    /// smaller of (E: reaction links, F: freshness links), as bounds that
    /// grow linearly with the periods; the sound freshness is F. `None` when
    /// the chain is unbounded everywhere. Empty unless asked for.
    pub forms: Vec<Option<(Affine, Affine)>>,
    /// Per declared chain: a lower bound on its sound reaction from the
    /// event (the maximum reaction time: no reachability options, T_1 more;
    /// `latency::sound_event_reaction`); `None` when unbounded everywhere.
    pub event_reaction: Vec<Option<Nanos>>,
    /// Per declared chain: the same as an affine form. Empty unless asked
    /// for.
    pub event_forms: Vec<Option<Affine>>,
    /// Per declared chain: lower bounds on its paper-mode (reaction,
    /// freshness), Eqs. 1–14. Valid when [`paper_monotone`] holds.
    pub paper: Vec<(Nanos, Nanos)>,
    /// Per declared chain: the same as affine forms. Empty unless asked for.
    pub paper_forms: Vec<(Affine, Affine)>,
}

/// The paper's terms grow with every period when no task on a chain needs
/// more than three budgets per job: Eq. 12's `2 T_p − L_p` falls with T_p
/// once L_p (Eq. 1) holds three periods or more. Only then do the paper
/// figures of [`relax`] bound the analysis from below.
pub fn paper_monotone(spec: &Spec) -> bool {
    spec.chains.iter().flat_map(|c| &c.path).all(|&i| {
        let t = &spec.tasks[i];
        t.demand() <= t.budget().saturating_mul(3)
    })
}

/// A bound that grows linearly with the periods over the box:
/// `value(T) ≥ base + Σ slope_i · (T_i − lo_i)` at every point T.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Affine {
    /// The value at the box's lower corner (T = lo).
    pub base: f64,
    /// (task, slope ≥ 0); a task may appear more than once.
    pub slopes: Vec<(usize, f64)>,
}

impl Affine {
    /// The bound at periods `t` (ns), with `lo` the box's lower ends.
    pub fn at(&self, lo: &[Nanos], t: &[Nanos]) -> f64 {
        self.base
            + self
                .slopes
                .iter()
                .map(|&(i, s)| s * (t[i] - lo[i]) as f64)
                .sum::<f64>()
    }
}

/// The priority facts a box decides under fixed priorities. A task ranks
/// by its key (`policy::rank_key`: the period under RM, the deadline or
/// else the period under DM, the explicit priority), which never falls as
/// its period grows: over the box it lies in `[key(lo), key(hi)]`.
struct Order<'a> {
    spec: &'a Spec,
    lo: &'a [Nanos],
    hi: &'a [Nanos],
    /// Per task, its rank key at `lo` and at `hi`.
    key_lo: Vec<Nanos>,
    key_hi: Vec<Nanos>,
    /// Rank orders imposed besides the box: `imposed[a·n + b]` = a above b.
    imposed: Vec<bool>,
    /// Per resource, the ranked tasks that use it (its ceiling is the
    /// highest rank among them, `blocking::ceilings`).
    users: Vec<Vec<usize>>,
}

impl<'a> Order<'a> {
    /// The box `lo ≤ T ≤ hi` with the rank orders `imposed` (a above b).
    fn new(spec: &'a Spec, lo: &'a [Nanos], hi: &'a [Nanos], imposed: &[(usize, usize)]) -> Self {
        let n = lo.len();
        let mut matrix = Vec::new();
        if !imposed.is_empty() {
            matrix = vec![false; n * n];
            for &(a, b) in imposed {
                matrix[a * n + b] = true;
            }
        }
        let mut users = vec![Vec::new(); spec.resources.len()];
        for (j, t) in spec.tasks.iter().enumerate() {
            for s in &t.sections {
                let ranked = spec.policy().fixed_priority() && t.server != Server::Background;
                if ranked && !users[s.resource].contains(&j) {
                    users[s.resource].push(j);
                }
            }
        }
        let key = |t: &[Nanos]| -> Vec<Nanos> {
            (spec.tasks.iter().zip(t))
                .map(|(task, &t)| rank_key(spec.priorities, task).at(t))
                .collect()
        };
        Order {
            spec,
            lo,
            hi,
            key_lo: key(lo),
            key_hi: key(hi),
            imposed: matrix,
            users,
        }
    }

    /// The ranked users of the resources task `b` locks: while b holds one
    /// it runs at its ceiling, the highest of their ranks.
    fn lock_mates(&self, b: usize) -> impl Iterator<Item = usize> + '_ {
        self.spec.tasks[b]
            .sections
            .iter()
            .flat_map(|s| self.users[s.resource].iter().copied())
    }

    /// A lower bound on task i's blocking B_i over the box
    /// (`blocking::blocking_by`): only the sections of tasks below i at
    /// every point, on resources with a user at or above i at every point.
    /// Any order the box allows admits at least those, so B_i is at least
    /// this; at a box of one point it is B_i.
    ///
    /// Under PCP and SRP (B a maximum) a section of length ℓ, on such a
    /// resource, of a task j whose order against i the box leaves open
    /// counts too: at each point j is either below i (ℓ is in the maximum)
    /// or above it, where it interferes with at least its demand, at least
    /// ℓ, on top of B; the response-time bounds count j as an interferer
    /// only where it is above i at every point, so adding ℓ to B stays below
    /// either case.
    fn least_blocking(&self, i: usize) -> Nanos {
        if self.users.is_empty() || !self.ranked(i) {
            return 0;
        }
        let able = |r: usize| {
            self.users[r]
                .iter()
                .any(|&u| u == i || self.surely_above(u, i))
        };
        let sure = crate::blocking::blocking_by(
            self.spec,
            |j| self.ranked(j) && self.surely_above(i, j),
            able,
        );
        if self.spec.resource_protocol == rtpipe_model::ResourceProtocol::Pip {
            return sure;
        }
        let open = |j: usize| {
            j != i
                && self.ranked(j)
                && self.spec.tasks[j].cpu == self.spec.tasks[i].cpu
                && !self.surely_above(i, j)
                && !self.surely_interferes(j, i)
        };
        let either = crate::blocking::blocking_by(self.spec, open, able);
        sure.max(either)
    }

    fn is_imposed(&self, a: usize, b: usize) -> bool {
        !self.imposed.is_empty() && self.imposed[a * self.lo.len() + b]
    }

    fn ranked(&self, a: usize) -> bool {
        let t = &self.spec.tasks[a];
        self.spec.policy().fixed_priority() && t.server != Server::Background
    }

    /// `a` has the higher rank at every point: (K_a, a) < (K_b, b) always
    /// (RM: K = T).
    fn surely_above(&self, a: usize, b: usize) -> bool {
        self.ranked(a)
            && self.ranked(b)
            && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
            && ((self.key_hi[a], a) < (self.key_lo[b], b) || self.is_imposed(a, b))
    }

    /// `a` has the higher rank at some point of the box.
    fn maybe_above(&self, a: usize, b: usize) -> bool {
        self.ranked(a)
            && self.ranked(b)
            && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
            && (self.key_lo[a], a) < (self.key_hi[b], b)
            && !self.is_imposed(b, a)
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
    /// Critical sections raise b to their ceilings (`TaskTiming::top_priority`),
    /// so a must also be above every user of b's resources.
    fn maybe_preempts(&self, a: usize, b: usize) -> bool {
        self.maybe_above(a, b)
            && self.spec.tasks[b]
                .serves
                .is_none_or(|m| m != a && self.maybe_above(a, m))
            && self.lock_mates(b).all(|u| u != a && self.maybe_above(a, u))
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
        // Some point may have neither (an inherited rank ties them, or a
        // task waits for its budget).
        let decided = self.surely_preempts(c, p) || self.surely_preempts(p, c);
        if !(decided || self.always_ordered(p, c)) {
            v.push(None);
        }
        v
    }

    /// At every point one of the two preempts the other (`latency::fp_order`
    /// gives a case): ranked on one CPU, neither serves a task nor locks a
    /// resource (so each runs at its own rank, and ranks are distinct), nor
    /// waits for a budget with release jitter.
    fn always_ordered(&self, a: usize, b: usize) -> bool {
        let plain = |i: usize| {
            let t = &self.spec.tasks[i];
            let waits = t.jitter > 0 && self.spec.policy().budget(t.server).is_some();
            self.ranked(i) && t.serves.is_none() && t.sections.is_empty() && !waits
        };
        plain(a) && plain(b) && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
    }

    /// Both tasks are ranked on one CPU by their periods (`RankKey::Period`),
    /// so that an order of the two holds only where the periods allow it:
    /// `a` above `b` needs `T_a ≤ T_b`.
    fn ranked_by_period(&self, a: usize, b: usize) -> bool {
        let by_period =
            |i: usize| rank_key(self.spec.priorities, &self.spec.tasks[i]) == RankKey::Period;
        self.ranked(a)
            && self.ranked(b)
            && self.spec.tasks[a].cpu == self.spec.tasks[b].cpu
            && by_period(a)
            && by_period(b)
    }

    /// What `a` adds at least to `b`'s job response time and to its
    /// read-to-publish bound at the points of the box where `a` is above
    /// `b`, beyond `rta_lower_bounds`' figures: one job's interference
    /// (each fixed point with one more interferer is at least the old one
    /// plus its work, and so is the least of two of them, W ≤ R); to W
    /// only where W is that busy window (`sched::fp_start_after`), else 0.
    /// `None` where those figures may already hold `a`: `a` surely
    /// interferes with `b`, serves a task, or has critical sections (which
    /// `least_blocking` may count for `b` while the order is open), or the
    /// response is not RTA's.
    fn added_above(&self, a: usize, b: usize) -> Option<(Nanos, Nanos)> {
        let task = &self.spec.tasks[a];
        let rta = self.spec.policy().response == ResponseAnalysis::Rta;
        let plain = task.serves.is_none() && task.sections.is_empty();
        let work = interference(task);
        let to_w = crate::sched::fp_start_after(self.spec, b).map_or(0, |_| work);
        (rta && plain && self.ranked(a) && !self.surely_interferes(a, b)).then_some((work, to_w))
    }

    fn surely_preempts(&self, a: usize, b: usize) -> bool {
        self.surely_above(a, b)
            && self.spec.tasks[b]
                .serves
                .is_none_or(|m| m != a && self.surely_above(a, m))
            && self
                .lock_mates(b)
                .all(|u| u != a && self.surely_above(a, u))
    }
}

/// Per task, lower bounds on the job-level response times and the
/// read-to-publish bounds, and on the budget-level response times, over the
/// box (see the module documentation); `None` when above the longest
/// period.
fn response_lower_bounds(spec: &Spec, order: &Order) -> (Times, Vec<Option<Nanos>>) {
    let n = spec.tasks.len();
    let mut job_response = vec![None; n];
    let mut read_to_publish = vec![None; n];
    let mut budget_response = vec![None; n];
    for i in 0..n {
        (budget_response[i], job_response[i], read_to_publish[i]) =
            task_lower_bounds(spec, order, i);
    }
    // Responses the overheads' accounting leaves without a bound at every
    // point of the box (`overheads::unaccounted`).
    if !spec.overheads.is_zero() {
        let bounded: Vec<bool> = job_response.iter().map(Option::is_some).collect();
        let fixed = spec.policy().fixed_priority();
        let above = |j: usize, i: usize| {
            spec.tasks[j].cpu == spec.tasks[i].cpu && (!fixed || order.surely_interferes(j, i))
        };
        for i in crate::overheads::unaccounted(spec, &bounded, above) {
            (job_response[i], read_to_publish[i], budget_response[i]) = (None, None, None);
        }
    }
    let times = Times {
        r: job_response,
        w: read_to_publish,
    };
    (times, budget_response)
}

/// Task i's lower bounds over the box (budget-level response time, job
/// response time, read-to-publish bound), each `None` when above its
/// limit (D for the budget's, the longest period for the job's)
/// everywhere in the box; background tasks have none.
fn task_lower_bounds(
    spec: &Spec,
    order: &Order,
    i: usize,
) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let (lo, hi, t) = (order.lo, order.hi, &spec.tasks[i]);
    if t.server == Server::Background {
        return (None, None, None);
    }
    let util_ok = |cpu: u32| cpu_utilizations(spec, hi, cpu).iter().sum::<f64>() <= 1.0 + 1e-12;
    let (rb, rj, rw) = match spec.policy().response {
        ResponseAnalysis::Rta => rta_lower_bounds(spec, order, i),
        // Servers get their budget by the end of each period, or by
        // the deadline when one is given (`sched`).
        ResponseAnalysis::ServerPeriod if util_ok(t.cpu) => {
            let d = t.deadline_given.map_or(lo[i], |d| d.min(lo[i]));
            (Some(d), Some(d), Some(d))
        }
        ResponseAnalysis::ServerPeriod => (None, None, None),
        ResponseAnalysis::EdfRta if util_ok(t.cpu) => edf_lower_bounds(spec, lo, hi, i),
        ResponseAnalysis::EdfRta => (None, None, None),
    };
    // The RTA test asks R ≤ D (D = T unless given).
    let d = t.deadline_given.map_or(hi[i], |d| d.min(hi[i]));
    let job = rj.filter(|&r| r <= hi[i]);
    (rb.filter(|&r| r <= d), job, rw.filter(|_| job.is_some()))
}

/// Lower bounds on task i's (budget, job) response times and its
/// read-to-publish bound under RM over the box: the level-i busy
/// period of `sched::response_times` ([`level_response_within`]) with the
/// interferers above i at every point, at their longest periods, and i's
/// own longest period, each job with its switches (`2·cs`); the kernel
/// work of every release on the CPU at each task's longest period; and the
/// own switch and the least blocking over the box ([`Order::least_blocking`])
/// added to the own demand. Each term is at most the analysis' at every
/// point, and the fixed point grows with each term.
fn rta_lower_bounds(
    spec: &Spec,
    order: &Order,
    i: usize,
) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let (t, hi) = (&spec.tasks[i], order.hi);
    let switches = crate::overheads::per_job(spec, i);
    let mut hp: Vec<(Nanos, Nanos, Nanos)> = Vec::new();
    for j in (0..spec.tasks.len()).filter(|&j| order.surely_interferes(j, i)) {
        let o = &spec.tasks[j];
        // Ranked below i at every point, j runs above it only by
        // inheritance and brings its carry-in (`sched::hp_load`), with
        // R_j at its least over the box.
        let by_inheritance = o.serves.is_some() && !order.surely_above(j, i);
        let (work, jitter) = if by_inheritance && order.surely_above(i, j) {
            match carry_in_lower_bound(spec, order, j) {
                Some(carry) => carry,
                None => return (None, None, None),
            }
        } else {
            (interference(o), o.jitter)
        };
        hp.push((work.saturating_add(switches), hi[j], jitter));
    }
    hp.extend(crate::overheads::kernel_load_at(spec, t.cpu, hi));
    // Own period at its longest: later own jobs come later and fewer join
    // the busy period, so each w_q − q·T and the set of q only shrink.
    let own = |work: Nanos| OwnJobs {
        work,
        switch: crate::overheads::own(spec, i),
        blocking: order.least_blocking(i),
        jitter: t.jitter,
        period: hi[i],
    };
    // Only a figure within the longest period is kept (`response_lower_bounds`).
    let r = |work: Nanos| level_response_within(own(work), &hp, hi[i]);
    let rj = r(t.demand());
    // W from the start (`sched::fp_start_to_finish`): the same
    // interferers, without the own jitter, switch and ceiling blocking.
    let rw = rj.map(|rj| match crate::sched::fp_start_after(spec, i) {
        Some(after) => crate::sched::busy_window(
            t.demand()
                .saturating_add(if after { order.least_blocking(i) } else { 0 }),
            &hp,
        )
        .map_or(rj, |w| w.min(rj)),
        // A sporadic server that waits in slack: the analysis narrows R to
        // a busy window from the read (`sched::slack`), at least its demand.
        None if crate::sched::may_run_in_slack(spec, i) => t.demand().min(rj),
        None => rj,
    });
    (r(t.budget()), rj, rw)
}

/// The carry-in of a PIBS server `j` (`sched::inherited_carry_in`: work
/// c = max(C, x) and jitter R_j − c) with R_j's lower bound over the box,
/// so at most the analysis' at every point; `None` when j's response is
/// above its longest period at every point (the analysis then bounds no
/// task j runs above by inheritance).
fn carry_in_lower_bound(spec: &Spec, order: &Order, j: usize) -> Option<(Nanos, Nanos)> {
    let o = &spec.tasks[j];
    let (budget_r, job_r, _) = rta_lower_bounds(spec, order, j);
    let r = budget_r?.max(job_r?);
    let c = interference(o).max(o.demand());
    Some((c, r.checked_sub(c)?))
}

/// Per task, lower bounds on the job response time `R` and on the
/// read-to-publish bound `W` over the box.
struct Times {
    r: Vec<Option<Nanos>>,
    w: Vec<Option<Nanos>>,
}

/// Lower bounds on task `i`'s (budget, job) EDF response times and its
/// read-to-publish bound over the box: the analysis itself when the box
/// fixes every period of i's CPU; otherwise Spuri's bound at `a = 0`, which
/// holds the job's own demand and one job of every task whose deadline is
/// never after i's (`T_j ≤ T_i`), a figure that only grows as the box
/// shrinks; for `W` (`edf::start_to_finish`) the same with the tasks whose
/// deadline is always before i's. docs/analysis.md.
fn edf_lower_bounds(
    spec: &Spec,
    lo: &[Nanos],
    hi: &[Nanos],
    i: usize,
) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let on = tasks_on(spec, spec.tasks[i].cpu);
    let mates = guaranteed(spec, &on);
    if mates.iter().all(|&j| lo[j] == hi[j]) {
        let cpu = crate::sched::EdfCpu::new(spec, lo, &on);
        let (b, j) = crate::sched::edf_response_times_at(&cpu, i);
        // As `sched::analyze` takes it.
        let w = j.map(|j| crate::sched::edf_read_to_publish_at(&cpu, i).min(j));
        return (b, j, w);
    }
    let (b, j, w) = spuri_lower_bounds(spec, lo, hi, i, &mates);
    // Where some task of the CPU has a deadline below its period, the
    // analysis takes at most i's deadline for R
    // (`sched::edf_response_times_at`), least at i's shortest period, and
    // W is at most R.
    let below = |t: &[Nanos]| {
        let d = |j: usize| spec.tasks[j].deadline_given.is_some_and(|d| d < t[j]);
        mates.iter().any(|&j| d(j))
    };
    if !below(hi) {
        return (b, j, w);
    }
    let d = deadline_at(spec, i, lo[i]);
    let (b, j) = (b.map(|b| b.min(d)), j.map(|j| j.min(d)));
    (b, j, w.zip(j).map(|(w, j)| w.min(j)))
}

/// The part of [`edf_lower_bounds`] for a box that leaves some period of
/// i's CPU open: Spuri's analysis at a = 0, at every point of the box.
fn spuri_lower_bounds(
    spec: &Spec,
    lo: &[Nanos],
    hi: &[Nanos],
    i: usize,
    mates: &[usize],
) -> (Option<Nanos>, Option<Nanos>, Option<Nanos>) {
    let t = &spec.tasks[i];
    // With overheads each of those jobs brings its two switches, the own
    // job its one, and every release at 0 on the CPU its kernel work
    // (`edf::response_time` at a = 0 counts each at least once).
    let switches = crate::overheads::per_job(spec, i);
    let kernel: Nanos = (0..spec.tasks.len())
        .filter(|&k| spec.tasks[k].cpu == t.cpu)
        .map(|k| crate::overheads::per_release(spec, k))
        .sum();
    let own = |x: Nanos| x.saturating_add(crate::overheads::own(spec, i)).max(1) + kernel;
    // R counts a job of every task whose deadline is at or before i's at
    // every point; W only those whose deadline is before i's (a job of
    // equal deadline released after the start never runs first).
    let d = |j: usize, t: Nanos| deadline_at(spec, j, t);
    let before: Nanos = mates
        .iter()
        .filter(|&&j| j != i && d(j, hi[j]) <= d(i, lo[i]))
        .map(|&j| interference(&spec.tasks[j]).saturating_add(switches))
        .sum();
    let sooner: Nanos = mates
        .iter()
        .filter(|&&j| j != i && d(j, hi[j]) < d(i, lo[i]))
        .map(|&j| interference(&spec.tasks[j]))
        .sum();
    (
        Some(own(t.budget()) + before),
        Some(own(t.demand()) + before),
        Some(t.demand().max(1) + sooner),
    )
}

/// Lower bounds of the sound analysis over the periods `lo[i] ≤ T_i ≤ hi[i]`
/// (ns, one entry per task; background tasks' entries are ignored) at which
/// every pair `(a, b)` of `imposed` has a ranked above b (RM: (T_a, a) <
/// (T_b, b)), for a search that branches on priority orders too. The
/// affine forms are computed with `forms` only (they cost four link
/// evaluations each).
pub fn relax(
    spec: &Spec,
    lo: &[Nanos],
    hi: &[Nanos],
    imposed: &[(usize, usize)],
    forms: bool,
) -> Relaxed {
    let n = spec.tasks.len();
    assert!(
        lo.len() == n && hi.len() == n,
        "relax: one interval per task"
    );
    assert!(
        (0..n).all(|i| 0 < lo[i] && lo[i] <= hi[i]),
        "relax: empty or non-positive period interval"
    );
    let order = Order::new(spec, lo, hi, imposed);
    let cpus = cpu_ids(spec);
    let (times, budget_response) = response_lower_bounds(spec, &order);
    let cpus = cpus
        .into_iter()
        .map(|cpu| (cpu, cpu_may_pass(spec, (lo, hi), &budget_response, cpu)))
        .collect();
    let chains = spec
        .chains
        .iter()
        .map(|ch| chain_bounds(spec, &order, &times, &ch.path))
        .collect();
    let event_reaction = spec
        .chains
        .iter()
        .map(|ch| event_reaction_bound(spec, &order, &times, &ch.path))
        .collect();
    let paper = spec
        .chains
        .iter()
        .map(|ch| paper_bounds(spec, &order, &ch.path))
        .collect();
    let (forms, event_forms, paper_forms) = match forms {
        true => (
            spec.chains
                .iter()
                .map(|ch| chain_forms(spec, &order, &times, &ch.path, true))
                .collect(),
            spec.chains
                .iter()
                .map(|ch| event_form(spec, &order, &times, &ch.path))
                .collect(),
            spec.chains
                .iter()
                .map(|ch| paper_forms(spec, &order, &ch.path))
                .collect(),
        ),
        false => (Vec::new(), Vec::new(), Vec::new()),
    };
    Relaxed {
        job_response: times.r,
        read_to_publish: times.w,
        budget_response,
        cpus,
        chains,
        forms,
        event_reaction,
        event_forms,
        paper,
        paper_forms,
    }
}

/// A lower bound on the chain's sound reaction from the event: its links'
/// reaction terms without the reachability options, the tail's response
/// time and the head's shortest period (`latency::sound_event_reaction`).
fn event_reaction_bound(spec: &Spec, order: &Order, r: &Times, path: &[usize]) -> Option<Nanos> {
    if all_let(spec, path) {
        return let_low(order, r, path).map(|l| l.reaction_event);
    }
    let sum: Option<Nanos> = low_links(spec, order, r, path, false)
        .iter()
        .map(|l| l.reaction)
        .sum();
    sum.zip(r.r[path[path.len() - 1]])
        .map(|(a, b)| a + b + order.lo[path[0]])
}

/// [`event_reaction_bound`] as an affine form over the box: the reaction
/// sum E without reachability, plus T_1.
fn event_form(spec: &Spec, order: &Order, r: &Times, path: &[usize]) -> Option<Affine> {
    let (mut e, _) = chain_forms(spec, order, r, path, false)?;
    let head = path[0];
    e.base += order.lo[head] as f64;
    e.slopes.push((head, 1.0));
    Some(e)
}

/// Every task of the path reads and publishes under LET (the system's
/// communication or its chains': `Spec::task_communication`); a path that
/// mixes the two takes the per-task link terms of `latency`, as the
/// analysis does.
fn all_let(spec: &Spec, path: &[usize]) -> bool {
    path.iter()
        .all(|&i| spec.task_communication(i) == Communication::Let)
}

/// Under LET a chain's sound figures are `let_bound::any_phasing` of its
/// periods when every task completes within its period
/// (`latency::let_chain_sound`): each grows with every period, so at the
/// box's shortest periods they bound it from below. `None` when some
/// task's response exceeds its period everywhere in the box.
fn let_low(order: &Order, r: &Times, path: &[usize]) -> Option<LetLatencies> {
    if path.iter().any(|&i| r.r[i].is_none()) {
        return None;
    }
    any_phasing(&path.iter().map(|&i| order.lo[i]).collect::<Vec<_>>())
}

/// LET's two sums as affine forms: X (the reaction from the read is
/// min(X, F), from the event T_1 + X) and F. `any_phasing` is linear in
/// the periods, so the forms are exact, their slopes its steps when one
/// period grows by 1 ns.
fn let_forms(order: &Order, r: &Times, path: &[usize]) -> Option<(Affine, Affine)> {
    let l0 = let_low(order, r, path)?;
    let at = |t: &[Nanos]| any_phasing(t).map(|l| (l.reaction_event - t[0], l.freshness_read));
    let lo: Vec<Nanos> = path.iter().map(|&i| order.lo[i]).collect();
    let (x0, f0) = (l0.reaction_event - lo[0], l0.freshness_read);
    let mut e = Affine {
        base: x0 as f64,
        slopes: Vec::new(),
    };
    let mut f = Affine {
        base: f0 as f64,
        slopes: Vec::new(),
    };
    for (k, &i) in path.iter().enumerate() {
        let mut t = lo.clone();
        t[k] += 1;
        let (x1, f1) = at(&t)?;
        e.slopes.push((i, (x1 - x0) as f64));
        f.slopes.push((i, (f1 - f0) as f64));
    }
    Some((e, f))
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
fn cpu_may_pass(
    spec: &Spec,
    (lo, hi): (&[Nanos], &[Nanos]),
    budget_r: &[Option<Nanos>],
    cpu: u32,
) -> bool {
    match spec.schedulability {
        SchedTest::Rta => spec
            .tasks
            .iter()
            .enumerate()
            .filter(|(_, t)| t.cpu == cpu && t.server != Server::Background)
            .all(|(i, _)| budget_r[i].is_some()),
        // The processor demand h(t) never falls as a period (and with it
        // a deadline, D = min(D_given, T)) shortens, so a box where the
        // demand test fails at the longest periods fails everywhere; with
        // critical sections (whose blocking moves either way with the
        // deadlines) only Σ U ≤ 1 at the longest periods is kept.
        SchedTest::Qpa if fixed_or_unblocked(spec, lo, hi, cpu) => {
            crate::qpa::edf_feasible_at(spec, hi, &tasks_on(spec, cpu))
        }
        SchedTest::Qpa => utilization_test(SchedTest::Edf, &cpu_utilizations(spec, hi, cpu)).2,
        // With overheads (`sched::edf_overhead_test`): the utilisation with
        // what the overheads add, least at the longest periods, and every
        // budget within its deadline.
        SchedTest::Edf if !spec.overheads.on(cpu).is_zero() => {
            let on = tasks_on(spec, cpu);
            let mates = guaranteed(spec, &on);
            if mates.is_empty() {
                return true;
            }
            let load = crate::sched::edf_overhead_load(spec, &on, |j| hi[j]);
            let u: f64 = cpu_utilizations(spec, hi, cpu).iter().sum::<f64>() + load;
            u <= 1.0 + 1e-12 && mates.iter().all(|&i| budget_r[i].is_some())
        }
        test => utilization_test(test, &cpu_utilizations(spec, hi, cpu)).2,
    }
}

/// The box fixes every period of `cpu`, or no task there has a critical
/// section: where the demand test at the longest periods is exact or a
/// bound.
fn fixed_or_unblocked(spec: &Spec, lo: &[Nanos], hi: &[Nanos], cpu: u32) -> bool {
    let on = |j: &usize| spec.tasks[*j].cpu == cpu;
    (0..spec.tasks.len())
        .filter(on)
        .all(|j| lo[j] == hi[j] || spec.tasks[j].server == Server::Background)
        || (0..spec.tasks.len())
            .filter(on)
            .all(|j| spec.tasks[j].sections.is_empty())
}

/// The link terms' view of task `i` at the box's most favourable values:
/// period `t`, job response time and read-to-publish bound `(r, w)`.
fn link_task(spec: &Spec, t: Nanos, (r, w): (Option<Nanos>, Option<Nanos>), i: usize) -> LinkTask {
    let task = &spec.tasks[i];
    LinkTask {
        c: task.budget(),
        t,
        d: deadline_at(spec, i, t),
        x: task.demand(),
        x_min: task.demand_min(),
        delta_out: task.delta_out,
        l: crate::latency::eq1_single_pipe(task.demand(), task.budget(), t),
        r,
        w,
        j: task.jitter,
        budgeted: spec.policy().budget(task.server).is_some(),
        cpu: task.cpu,
        edf: !spec.policy().fixed_priority(),
        prio: None,
        top: None,
        let_comm: spec.task_communication(i) == rtpipe_model::Communication::Let,
        // The design refuses threads and data-triggered tasks.
        event: None,
    }
}

/// The link's two tasks with the deadlines that make `(D_p − D_c)⁺` (the
/// EDF options of `latency`) least over the box: D_p at p's shortest
/// period, D_c at c's longest. That keeps those options below the
/// analysis' at every point and affine in the periods.
fn least_deadlines(
    order: &Order,
    spec: &Spec,
    pi: usize,
    ci: usize,
    p: &mut LinkTask,
    c: &mut LinkTask,
) {
    p.d = deadline_at(spec, pi, order.lo[pi]);
    c.d = deadline_at(spec, ci, order.hi[ci]);
}

/// Lower bounds on a chain's sound reaction and freshness from the read,
/// composed by `latency::compose_sound` as the analysis composes them.
fn chain_bounds(
    spec: &Spec,
    order: &Order,
    r: &Times,
    path: &[usize],
) -> (Option<Nanos>, Option<Nanos>) {
    if all_let(spec, path) {
        let l = let_low(order, r, path);
        return (l.map(|l| l.reaction_read), l.map(|l| l.freshness_read));
    }
    compose_sound(
        r.of(path[path.len() - 1]),
        r.w[path[0]],
        &low_links(spec, order, r, path, true),
    )
}

impl Times {
    /// Task i's (R, W) lower bounds.
    fn of(&self, i: usize) -> (Option<Nanos>, Option<Nanos>) {
        (self.r[i], self.w[i])
    }
}

/// Each link's least terms at the box's shortest periods, over the orders
/// the box leaves open; `reach`: from the read, with the reachability
/// options where they may hold and the head's term from its read, or
/// without both (the reaction from the event).
fn low_links(spec: &Spec, order: &Order, r: &Times, path: &[usize], reach: bool) -> Vec<SoundLink> {
    let low = |i: usize| link_task(spec, order.lo[i], r.of(i), i);
    // Reachability needs the producer's samples distinct; take it where it
    // may hold (more options, smaller terms).
    let mut distinct = reach;
    let mut links = Vec::with_capacity(path.len() - 1);
    for (k, w) in path.windows(2).enumerate() {
        let (mut p, mut c) = (low(w[0]), low(w[1]));
        least_deadlines(order, spec, w[0], w[1], &mut p, &mut c);
        let orders = order.link_orders(w[0], w[1]);
        let head = reach && k == 0;
        links.push(SoundLink::least(
            orders
                .iter()
                .map(|&o| SoundLink::new_in(o, &p, &c, distinct, head)),
        ));
        // The condition grows with T_c: test it at c's longest period.
        let c_late = link_task(spec, order.hi[w[1]], r.of(w[1]), w[1]);
        distinct = distinct_passes(&p, &c_late, distinct);
    }
    links
}

/// The sums E and F of a chain (see [`chain_bounds`]) as affine bounds over
/// the box; `reach`: with the reachability options (from the read) or
/// without (the reaction from the event). Each link term is the least of options that grow with unit
/// slope in T_p or T_c (response times held at their lower bounds), so it is
/// concave in (T_p, T_c); an affine function below it at the four corners of
/// the (T_p, T_c) rectangle is below it on the whole rectangle.
fn chain_forms(
    spec: &Spec,
    order: &Order,
    r: &Times,
    path: &[usize],
    reach: bool,
) -> Option<(Affine, Affine)> {
    if all_let(spec, path) {
        return let_forms(order, r, path);
    }
    let tail = path[path.len() - 1];
    // The tail's response time: its lower bound, or T where a response
    // time is the server period.
    let own = |i: usize| match spec.policy().response {
        ResponseAnalysis::ServerPeriod => vec![(i, 1.0)],
        ResponseAnalysis::Rta | ResponseAnalysis::EdfRta => Vec::new(),
    };
    if path.len() == 1 {
        // From the read a task alone is its read-to-publish bound (from
        // the event, the caller's reaction sum has no such term: R).
        let one = if reach { r.w[tail] } else { r.r[tail] };
        let e = Affine {
            base: one? as f64,
            slopes: own(tail),
        };
        return Some((e.clone(), e));
    }
    // Stage reads (`reaction_stages`): below, the tail's W and reads' terms.
    let mut e = Affine {
        base: if reach { r.w[tail]? } else { r.r[tail]? } as f64,
        slopes: own(tail),
    };
    let mut f = Affine::default();
    let mut distinct = reach;
    for (k, w) in path.windows(2).enumerate() {
        let (pi, ci) = (w[0], w[1]);
        let last = k + 2 == path.len();
        let orders = order.link_orders(pi, ci);
        // Where a response time is the period itself it moves with the
        // corner; otherwise it stays at its lower bound.
        let resp = |i: usize, t: Nanos| match spec.policy().response {
            ResponseAnalysis::ServerPeriod => (r.r[i].map(|_| t), r.w[i].map(|_| t)),
            ResponseAnalysis::Rta | ResponseAnalysis::EdfRta => r.of(i),
        };
        let head = reach && k == 0;
        let at = |tp: Nanos, tc: Nanos| {
            let (p, c) = ((pi, tp, resp(pi, tp)), (ci, tc, resp(ci, tc)));
            let l = least_link(spec, order, &orders, p, c, (distinct, head));
            let fresh = if last { l.freshness_last } else { l.freshness };
            let react = [l.reaction, l.reaction_from_read][usize::from(reach)];
            Some((react?, fresh?))
        };
        let (lp, hp, lc, hc) = (order.lo[pi], order.hi[pi], order.lo[ci], order.hi[ci]);
        let corners = [at(lp, lc)?, at(hp, lc)?, at(lp, hc)?, at(hp, hc)?];
        add_link(&mut e, pi, ci, hp - lp, hc - lc, corners.map(|x| x.0));
        add_link(&mut f, pi, ci, hp - lp, hc - lc, corners.map(|x| x.1));
        let c_late = link_task(spec, hc, r.of(ci), ci);
        distinct = distinct_passes(&link_task(spec, lp, r.of(pi), pi), &c_late, distinct);
    }
    Some((e, f))
}

/// Adds to `form` an affine bound of a concave link term from its values
/// at the corners (lo,lo), (hi,lo), (lo,hi), (hi,hi) of (T_p, T_c).
fn add_link(form: &mut Affine, p: usize, c: usize, dp: Nanos, dc: Nanos, v: [Nanos; 4]) {
    let v = v.map(|x| x as f64);
    let sp = if dp > 0 {
        (v[1] - v[0]) / dp as f64
    } else {
        0.0
    };
    let sc = if dc > 0 {
        (v[2] - v[0]) / dc as f64
    } else {
        0.0
    };
    // Exact at three corners; at the fourth, lower the base as needed.
    let base = v[0].min(v[3] - sp * dp as f64 - sc * dc as f64);
    form.base += base;
    if sp > 0.0 {
        form.slopes.push((p, sp));
    }
    if sc > 0.0 {
        form.slopes.push((c, sc));
    }
}

impl Order<'_> {
    /// The paper's cases of link p → c possible over the box (Eq. 6: Case 1
    /// when T_c < T_p).
    fn paper_cases(&self, p: usize, c: usize) -> Vec<Case> {
        let mut v = Vec::new();
        if self.lo[c] < self.hi[p] {
            v.push(Case::One);
        }
        if self.hi[c] >= self.lo[p] {
            v.push(Case::Two);
        }
        v
    }
}
