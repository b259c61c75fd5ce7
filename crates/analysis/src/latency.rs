//! End-to-end reaction and freshness bounds of pipe chains.
//!
//! Both modes compose link by link (Section III-F): a chain's bound is the
//! head term plus one term per appended consumer, so the same link terms serve
//! declared chains and the dynamic programme over all paths (`paths.rs`).
//! docs/analysis.md derives every term.

use crate::event_links::{self, Activation, Side};
use crate::sched::TaskTiming;
use rtpipe_model::{Communication, Nanos, Scheduler, Spec};

/// Eq. 1 read with the paper's ε convention: a demand `x` that exactly fills
/// k budgets completes at (k−1)·T + (x − (k−1)·C), so x ≤ C gives L = x.
pub fn eq1_single_pipe(x: Nanos, c: Nanos, t: Nanos) -> Nanos {
    if x <= c {
        return x;
    }
    let k = (x + c - 1) / c; // budgets touched: ⌈x / C⌉
    (k - 1) * t + (x - (k - 1) * c)
}

/// What the link terms need to know about a task.
#[derive(Debug, Clone, Copy)]
pub struct LinkTask {
    /// Budget C.
    pub c: Nanos,
    /// Period T.
    pub t: Nanos,
    /// Relative deadline D (T unless the spec gives one); under EDF a job's
    /// priority is its release plus D.
    pub d: Nanos,
    /// Demand x = Δin + exec + Δout.
    pub x: Nanos,
    /// Least demand x_min.
    pub x_min: Nanos,
    /// Output overhead Δout (the Δ of Eq. 6).
    pub delta_out: Nanos,
    /// Paper Eq. 1.
    pub l: Nanos,
    /// Job response time from the nominal release (release jitter
    /// included), when it is at most the period.
    pub r: Option<Nanos>,
    /// A bound on the time from a job's read to its publish (`W`, at most
    /// `r`; equal to it under fixed priority), when `r` is bounded.
    pub w: Option<Nanos>,
    /// Release jitter J: a job is released in [nominal, nominal + J].
    pub j: Nanos,
    /// A server enforces its budget: a jittered job may then wait for it
    /// after its release (and a sporadic server runs it in slack meanwhile).
    pub budgeted: bool,
    /// The CPU it runs on.
    pub cpu: u32,
    /// Picked by its jobs' absolute deadlines (EDF), which stay fixed while
    /// a job is pending.
    pub edf: bool,
    /// Own RM rank (the lowest priority the task runs at).
    pub prio: Option<usize>,
    /// Highest rank it can inherit (PIBS).
    pub top: Option<usize>,
    /// Reads at its release and publishes at its period's end (LET), not
    /// at its start and completion.
    pub let_comm: bool,
    /// Its activations, in a spec with threads or data-triggered tasks
    /// (`crate::event_links`); `None` in a periodic spec.
    pub event: Option<Activation>,
}

impl LinkTask {
    /// Task `i` as its links see it.
    pub fn new(spec: &Spec, timing: &[TaskTiming], i: usize) -> LinkTask {
        let tm = &timing[i];
        let event = tm.events.as_ref().map(|e| Activation::new(i, e));
        // A task whose jobs merge needs no R ≤ T: its terms hold for every
        // job from its first release (`event_links`); W ≤ R.
        let merged = tm.events.as_ref().filter(|e| e.merging).map(|e| e.response);
        let (r, w) = match merged {
            Some(r) => (r, r),
            None => (tm.bounded_response(), tm.bounded_read_to_publish()),
        };
        LinkTask {
            c: tm.budget,
            t: tm.period,
            d: tm.deadline.min(tm.period),
            x: tm.demand,
            x_min: tm.demand_min,
            delta_out: spec.tasks[i].delta_out,
            l: eq1_single_pipe(tm.demand, tm.budget, tm.period),
            r,
            w,
            j: tm.jitter,
            budgeted: spec.policy().budget(spec.tasks[i].server).is_some(),
            cpu: tm.cpu,
            edf: !spec.policy().fixed_priority(),
            prio: tm.priority,
            top: tm.top_priority,
            let_comm: spec.task_communication(i) == Communication::Let,
            event,
        }
    }

    /// Its side of an event link (`None` in a periodic spec).
    fn side(&self) -> Option<Side> {
        Some(Side {
            r: self.r,
            w: self.w,
            x: self.x,
            t: self.t,
            act: self.event?,
            let_comm: self.let_comm,
        })
    }

    /// Its jobs merge (in a thread, or data-triggered).
    fn merging(&self) -> bool {
        self.event.is_some_and(|e| e.merging)
    }

    /// A bound on the time from a job's release to its publish: R, or
    /// under LET the period (LET's premise R ≤ T holds: `r` is bounded).
    pub fn publish(&self) -> Option<Nanos> {
        if self.let_comm {
            self.r.map(|_| self.t)
        } else {
            self.r
        }
    }

    /// A bound on the time from a job's read to its publish: W, or under
    /// LET the period (it reads at its release).
    pub fn read_to_publish(&self) -> Option<Nanos> {
        if self.let_comm {
            self.r.map(|_| self.t)
        } else {
            self.w
        }
    }
}

/// Both sides of p → c when it is an event link (`event_links`): the
/// producer's or the consumer's jobs merge.
fn event_sides(p: &LinkTask, c: &LinkTask) -> Option<(Side, Side)> {
    if !event_links::is_event_link(p.event.as_ref(), c.event.as_ref()) {
        return None;
    }
    Some((p.side()?, c.side()?))
}

/// Which of the paper's cases a link falls in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// Consumer has the shorter period / higher priority (Eqs. 2, 3, 12).
    One,
    /// Otherwise (Eqs. 4, 5).
    Two,
}

/// Paper mode, link p → c: the case by periods, as Eq. 6 splits it.
pub fn paper_case(p: &LinkTask, c: &LinkTask) -> Case {
    if c.t < p.t {
        Case::One
    } else {
        Case::Two
    }
}

/// Paper mode: what appending c to a chain ending in p adds to reaction,
/// S(p, c) + L(c), with S from Eq. 2 (Case 1) or Eq. 4 (Case 2) and
/// Δ = d/W + δ of the data p writes for c (Eq. 6: W = W_o^p = W_i^c).
pub fn paper_reaction_link(p: &LinkTask, c: &LinkTask) -> Nanos {
    paper_reaction_link_in(paper_case(p, c), p, c)
}

/// [`paper_reaction_link`] in a given case, for a relaxation that takes
/// each case possible over a set of periods.
pub fn paper_reaction_link_in(case: Case, p: &LinkTask, c: &LinkTask) -> Nanos {
    let s = match case {
        Case::One => c.t - c.c - p.delta_out,
        Case::Two => p.t - p.c - p.delta_out,
    };
    s + c.l
}

/// Paper mode: what appending c adds to freshness, F(p|c) − L(p), with
/// F(p|c) from Eq. 12 in Case 1 and Eq. 5 (= reaction) in Case 2.
pub fn paper_freshness_link(p: &LinkTask, c: &LinkTask) -> Nanos {
    paper_freshness_link_in(paper_case(p, c), p, c)
}

/// [`paper_freshness_link`] in a given case.
pub fn paper_freshness_link_in(case: Case, p: &LinkTask, c: &LinkTask) -> Nanos {
    match case {
        Case::One => 2 * p.t - p.delta_out - p.l,
        Case::Two => paper_reaction_link_in(case, p, c),
    }
}

/// Sound mode: may the priority-based arguments be used for this link? Only
/// when both tasks share a CPU scheduled by fixed priority and the task
/// above is not a server with release jitter: a jittered job may find its
/// server's budget not yet replenished and wait (a sporadic server runs it
/// in slack meanwhile, a PIBS server not at all), below tasks it otherwise
/// preempts, so "a above b" no longer holds at every instant. The task
/// below may wait so: waiting only keeps it from running, and both
/// arguments ask of it only that it not run while the task above has a job
/// pending (P1: c above p has no job pending at p's publish, since it would
/// run before p, in p's class or in slack; P2: a c job cannot start while
/// p's job is pending), docs/analysis.md "Reaction". Links without an
/// order use the windows alone, anchored on nominal releases with R = J +
/// w; plain jittered tasks keep the priority arguments, with J where an
/// anchor moves.
pub fn fp_order(sched: Scheduler, p: &LinkTask, c: &LinkTask) -> Option<Case> {
    let waits = |t: &LinkTask| t.j > 0 && t.budgeted;
    // Jobs that merge, or share a rank in a thread, break both cases.
    let merging = p.merging() || c.merging();
    if !sched.policy().fixed_priority() || p.cpu != c.cpu || merging {
        return None;
    }
    // "a above b" must hold at every instant: a's lowest priority above b's
    // highest (inherited) one, and a never waits for its budget.
    match (p.prio, p.top, c.prio, c.top) {
        (Some(_), Some(pt), Some(cp), Some(_)) if cp < pt && !waits(c) => Some(Case::One),
        (Some(pp), Some(_), Some(_), Some(ct)) if pp < ct && !waits(p) => Some(Case::Two),
        _ => None,
    }
}

/// Sound mode, reaction link p → c, anchored on releases (docs/analysis.md,
/// "Reaction"): from the release of `J_k`, the first p job carrying the
/// sample, to the release of `J_{k+1}`, the first c job reading at or after
/// `J_k`'s publish. `p_distinct`: no two jobs of p carry the same sample
/// (true at the chain head), which licenses the reachability arguments.
/// `None` when a response time is unbounded.
pub fn sound_reaction_link(
    sched: Scheduler,
    p: &LinkTask,
    c: &LinkTask,
    p_distinct: bool,
    p_read: bool,
) -> Option<Nanos> {
    sound_reaction_link_in(fp_order(sched, p, c), p, c, p_distinct, p_read)
}

/// [`sound_reaction_link`] with the priority order of the link given
/// (`fp_order`), so that a relaxation can take each order that is possible
/// over a set of periods. Every option grows with every period and response
/// time, which the relaxation relies on. `p_read`: the term starts at
/// `J_k`'s read rather than its release (the chain's head, from the read),
/// so `J_k` publishes within `W_p` of it; every other option starts at or
/// before the read and holds unchanged.
pub fn sound_reaction_link_in(
    order: Option<Case>,
    p: &LinkTask,
    c: &LinkTask,
    p_distinct: bool,
    p_read: bool,
) -> Option<Nanos> {
    if let Some((ps, cs)) = event_sides(p, c) {
        return event_links::reaction(&ps, &cs, p_read);
    }
    let (rp, _) = (p.r?, c.r?);
    if p.let_comm || c.let_comm {
        return let_reaction_link(p, c, p_distinct, p_read);
    }
    // J_k publishes within R_p of its release, W_p of its read.
    let to_publish = if p_read { p.w? } else { rp };
    // Davare et al.: the first c release after the publish is less than T_c
    // later.
    let mut l = to_publish + c.t;
    match order {
        // P1, c preempts p: at the publish c has no pending job, and its last
        // job (which ran ≥ x_min(c) before the publish) was released
        // ≥ x_min(c) earlier.
        Some(Case::One) => l = l.min(to_publish + c.t - c.x_min),
        // P2, p preempts c: a c job released at or after J_k's release starts
        // after J_k's publish, and one is released less than T_c later
        // (Dürr et al. 2019). J_k is released up to J_p after its nominal
        // release, where the term starts; from its read, after its actual
        // release, no jitter remains.
        Some(Case::Two) => l = l.min(c.t + if p_read { 0 } else { p.j }),
        // EDF on one CPU: a c job released at or after J_k's release with
        // a later deadline cannot start before J_k has published, and one
        // is released less than T_c + (D_p − D_c)⁺ after J_k's release.
        None if edf_together(p, c) => l = l.min(c.t + (p.d - c.d).max(0)),
        None => {}
    }
    if let Some(read) = reaction_to_read_in(order, p, c, p_distinct) {
        // J_{k+1} is released at or before its read.
        l = l.min(read);
    }
    if p_distinct && order.is_none() && edf_together(p, c) {
        // EDF on one CPU: J_{k+1} reads before p's next release, or while
        // p's next job is pending, so with a deadline no later than that
        // job's: released by T_p + (D_p − D_c)⁺ (a release bound only).
        l = l.min(p.t + (p.d - c.d).max(0));
    }
    Some(l)
}

/// Sound mode, reaction link p → c to `J_{k+1}`'s read rather than its
/// release (the reachability options of [`sound_reaction_link_in`], which
/// bound the read): from the release of `J_k`, or its read, to the read of
/// `J_{k+1}`, the first c job reading at or after `J_k`'s publish; `None`
/// where they do not hold (docs/analysis.md, "From a stage's read"). The
/// next link may then start at that read, and the tail add `W` for `R`.
pub fn reaction_to_read_in(
    order: Option<Case>,
    p: &LinkTask,
    c: &LinkTask,
    p_distinct: bool,
) -> Option<Nanos> {
    let merging_or_let = event_sides(p, c).is_some() || p.let_comm || c.let_comm;
    if !p_distinct || merging_or_let {
        return None;
    }
    let (rp, _) = (p.r?, c.r?);
    // Reachability: J_{k+1} reads before p's next publish, which the next
    // p job makes within T_p + R_p of J_k's release (at or before its read).
    let mut l = p.t + rp;
    if order == Some(Case::Two) {
        // p preempts c: J_{k+1} starts before p's next release, at most
        // T_p + J_p after J_k's nominal one.
        l = l.min(p.t + p.j);
    }
    Some(l)
}

/// [`sound_reaction_link_in`] when p or c communicates under LET
/// (docs/analysis.md, "Mixed links"): `J_k` publishes within R_p of its
/// release (W_p of its read), or at its period's end T_p under LET, and
/// the first c job reading at or after that is released less than T_c
/// later (a LET c reads at its release; an implicit one at or after it).
/// Reachability holds for either p (`J_{k+1}` reads, so is released,
/// before p's next publish, which the next p job makes within T_p of J_k's
/// release plus its own publish bound: R_p, or T_p under LET, whose
/// release is its read); a link of two LET tasks keeps the terms of
/// `let_bound::any_phasing`, which a chain all under LET is given (and
/// the design's relaxation bounds it by). The priority cases do not
/// apply: a LET publish or read is a timer instant, not a point of the
/// schedule.
fn let_reaction_link(p: &LinkTask, c: &LinkTask, p_distinct: bool, p_read: bool) -> Option<Nanos> {
    let to_publish = if p_read {
        p.read_to_publish()?
    } else {
        p.publish()?
    };
    let mut l = to_publish + c.t;
    if p_distinct && !(p.let_comm && c.let_comm) {
        l = l.min(p.t + p.publish()?);
    }
    Some(l)
}

/// Both tasks are picked by deadline (EDF) on one CPU: a job picked while
/// another is pending has the earlier deadline (or wins the tie), and the
/// other does not run until it completes (docs/analysis.md).
fn edf_together(p: &LinkTask, c: &LinkTask) -> bool {
    p.edf && c.edf && p.cpu == c.cpu
}

/// Sound mode, freshness link p → c, anchored on releases: from the release
/// of the last p job carrying a sample to the release of the last c job
/// carrying it. A chain's freshness is the sum of these over every link
/// but the last, plus [`sound_freshness_last_in`].
pub fn sound_freshness_link(sched: Scheduler, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    sound_freshness_link_in(fp_order(sched, p, c), p, c)
}

/// [`sound_freshness_link`] with the priority order given (see
/// [`sound_reaction_link_in`]); every option grows with T_p and R_p.
pub fn sound_freshness_link_in(order: Option<Case>, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    if let Some((ps, cs)) = event_sides(p, c) {
        return event_links::freshness(&ps, &cs);
    }
    let (rp, _) = (p.r?, c.r?);
    if p.let_comm || c.let_comm {
        // The same argument with p's publish at its period's end under
        // LET; no priority case (docs/analysis.md, "Mixed links").
        return Some(p.t + p.publish()?);
    }
    // That c job reads, so is released, before p's next publish, which the
    // next p job (released T_p after the one that carried the sample) makes
    // within R_p.
    Some(match order {
        // c preempts p: that c job has even finished (≥ x_min(c) after its
        // read) by the time p publishes again.
        Some(Case::One) => p.t + rp - c.x_min,
        // p preempts c: that c job started before p's next release (at
        // most T_p + J_p after the nominal release of the one before).
        Some(Case::Two) => p.t + p.j,
        None => p.t + rp,
    })
}

/// Sound mode, the last freshness link p → c: from the release of the last
/// p job carrying a sample to the publish of the last c job carrying it.
pub fn sound_freshness_last(sched: Scheduler, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    sound_freshness_last_in(fp_order(sched, p, c), p, c)
}

/// [`sound_freshness_last`] with the priority order given; every option
/// grows with the periods and response times.
pub fn sound_freshness_last_in(order: Option<Case>, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    if let Some((ps, cs)) = event_sides(p, c) {
        return event_links::freshness_last(&ps, &cs);
    }
    let (rp, _, wc) = (p.r?, c.r?, c.w?);
    if p.let_comm || c.let_comm {
        // L_n reads before p's next publish and publishes within W_c of
        // its read, or T_c under LET (docs/analysis.md, "Mixed links").
        return Some(p.t + p.publish()? + c.read_to_publish()?);
    }
    Some(match order {
        // c preempts p: the last c job carrying the sample has published
        // before p publishes again (nothing of c is pending while p runs).
        Some(Case::One) => p.t + rp,
        // Otherwise: it reads before that publish (started before p's next
        // release, at most T_p + J_p after the nominal one, when p preempts
        // c) and publishes within W_c of its read (W_c = R_c under fixed
        // priority).
        Some(Case::Two) => p.t + p.j + wc,
        // EDF on one CPU: if it reads before p's next release it publishes
        // within W_c of that; else it reads while p's next job is pending,
        // so it was picked over that job, whose deadline it precedes, and
        // publishes before it (docs/analysis.md).
        None if edf_together(p, c) => p.t + rp.max(wc),
        None => p.t + rp + wc,
    })
}

/// One link's sound terms, all anchored on releases.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SoundLink {
    /// [`sound_reaction_link_in`].
    pub reaction: Option<Nanos>,
    /// [`sound_reaction_link_in`] from p's read (`p_read`).
    pub reaction_from_read: Option<Nanos>,
    /// [`reaction_to_read_in`].
    pub to_read: Option<Nanos>,
    /// [`sound_freshness_link_in`].
    pub freshness: Option<Nanos>,
    /// [`sound_freshness_last_in`].
    pub freshness_last: Option<Nanos>,
}

impl SoundLink {
    /// The terms of link p → c in a given order; `p_read`: the reaction
    /// term starts at p's read ([`sound_reaction_link_in`]).
    pub fn new_in(
        order: Option<Case>,
        p: &LinkTask,
        c: &LinkTask,
        p_distinct: bool,
        p_read: bool,
    ) -> SoundLink {
        SoundLink {
            reaction: sound_reaction_link_in(order, p, c, p_distinct, p_read),
            // Through merging jobs only the head's term starts at a read.
            reaction_from_read: match event_sides(p, c) {
                Some(_) => None,
                None => sound_reaction_link_in(order, p, c, p_distinct, true),
            },
            to_read: reaction_to_read_in(order, p, c, p_distinct),
            freshness: sound_freshness_link_in(order, p, c),
            freshness_last: sound_freshness_last_in(order, p, c),
        }
    }

    /// The smallest of each term over some links (a relaxation's view of a
    /// link whose order a set of periods does not decide).
    pub fn least(links: impl IntoIterator<Item = SoundLink>) -> SoundLink {
        let min = |a: Option<Nanos>, b: Option<Nanos>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let none = SoundLink {
            reaction: None,
            reaction_from_read: None,
            to_read: None,
            freshness: None,
            freshness_last: None,
        };
        links.into_iter().fold(none, |acc, l| SoundLink {
            reaction: min(acc.reaction, l.reaction),
            reaction_from_read: min(acc.reaction_from_read, l.reaction_from_read),
            to_read: min(acc.to_read, l.to_read),
            freshness: min(acc.freshness, l.freshness),
            freshness_last: min(acc.freshness_last, l.freshness_last),
        })
    }
}

/// A chain's sound (reaction, freshness) from the head's read, composed from
/// its links' terms and the tail's publish bounds (`tail`: from its
/// release, `R_n`, and from its read, `W_n`): reaction ≤ the reaction terms
/// stage by stage ([`reaction_stages`]), freshness ≤ Σ freshness terms of
/// all links but the last + the last link's `freshness_last` (`W_1` for a
/// chain of one task, from its read to its publish: `one`), and reaction ≤
/// freshness (a sample's first output is never after its last). The sums
/// start at the head's release, at or before its read, but for the head
/// link's reaction term when it starts at the read (`SoundLink::new_in`'s
/// `p_read`). With `one = R_1` and no term from the read, the bounds start
/// at the head's release (what the bounds from the event add `T_1` to).
pub fn compose_sound(
    tail: (Option<Nanos>, Option<Nanos>),
    one: Option<Nanos>,
    links: &[SoundLink],
) -> (Option<Nanos>, Option<Nanos>) {
    if links.is_empty() {
        return (one, one);
    }
    let react = reaction_stages(tail, links);
    let fresh = match links.split_last() {
        None => one,
        Some((last, rest)) => rest
            .iter()
            .map(|l| l.freshness)
            .sum::<Option<Nanos>>()
            .zip(last.freshness_last)
            .map(|(a, b)| a + b),
    };
    let react = match (react, fresh) {
        (Some(e), Some(f)) => Some(e.min(f)),
        (e, _) => e,
    };
    // Every term is a time: both sums run forward from the head's job.
    assert!(react.is_none_or(|e| e >= 0) && fresh.is_none_or(|f| f >= 0));
    (react, fresh)
}

/// The reaction bound of a chain, stage by stage (docs/analysis.md, "From
/// a stage's read"): for each stage's job, a bound on the time to its
/// release and one to its read. A link's term runs from its producer's
/// release (`reaction`) or read (`reaction_from_read`) to its consumer's
/// release, or to its consumer's read where reachability bounds that
/// (`to_read`, which bounds the release too); the tail publishes within
/// `R_n` of its release and `W_n` of its read. `None` where no option is
/// bounded. With no `to_read` anywhere this is Σ reaction terms + R_n.
fn reaction_stages(tail: (Option<Nanos>, Option<Nanos>), links: &[SoundLink]) -> Option<Nanos> {
    let add = |a: Option<Nanos>, b: Option<Nanos>| a.zip(b).map(|(a, b)| a + b);
    let min = |a: Option<Nanos>, b: Option<Nanos>| match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    // The head: its own read is where the bound starts (the head link's
    // `reaction` already runs from it).
    let (mut release, mut read) = (Some(0), None);
    for l in links {
        let to_read = add(release, l.to_read);
        let to_release = min(add(release, l.reaction), add(read, l.reaction_from_read));
        // A job is released at or before its read.
        (release, read) = (min(to_release, to_read), to_read);
    }
    min(add(release, tail.0), add(read, tail.1))
}

/// Sound mode: does "each sample is carried by at most one job" pass from p to c?
/// It does when c's reads are further apart than p's publishes can be.
/// Under LET a task reads exactly T apart and publishes exactly T apart.
pub fn distinct_passes(p: &LinkTask, c: &LinkTask, p_distinct: bool) -> bool {
    if event_sides(p, c).is_some() {
        // Not argued for merging jobs: the reachability terms stay off.
        return false;
    }
    match (p_distinct, p.r, c.r) {
        (true, Some(rp), Some(rc)) => {
            let reads = if c.let_comm { c.t } else { c.t - rc + c.x };
            let publishes = if p.let_comm { p.t } else { p.t + rp - p.x_min };
            reads > publishes
        }
        _ => false,
    }
}

/// Who a chain bound comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Bound {
    /// The paper's equations (Eqs. 1–14); from the event, one head period
    /// more (the event waits for the next read).
    Paper,
    /// rtpipe's sound, interference-aware bound (docs/analysis.md). From the
    /// event, reaction runs from an event at any instant to the first tail
    /// output carrying a sample read at or after it (the event's own sample
    /// may never reach the tail); freshness from the head read before a
    /// sample's read to the sample's last tail output.
    Sound,
    /// Davare et al. (DAC 2007). Reaction from the read:
    /// R_1 + Σ_{i≥2} (T_i + R_i); freshness: the data-age form
    /// Σ_{i<n} (T_i + R_i) + R_n; from the event, T_1 more.
    Davare,
    /// Dürr et al. (CASES 2019), with the same response times and priority
    /// orders. Reaction from the read (Theorem 5.4 less the head's sampling
    /// T_1): R_n + Σ_links max(R_p, T_c + R_p·[p not above c]); freshness
    /// (Theorem 5.10): R_n + Σ_links (T_p + R_p·[p not above c]); from the
    /// event, T_1 more.
    Duerr,
}

impl Bound {
    /// Every method, in the order reports list them.
    pub const ALL: [Bound; 4] = [Bound::Paper, Bound::Sound, Bound::Davare, Bound::Duerr];

    /// The name used in output and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Bound::Paper => "paper",
            Bound::Sound => "sound",
            Bound::Davare => "davare",
            Bound::Duerr => "duerr",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// The bounds of one chain in one metric: one per [`Bound`] and
/// [`Anchor`]. `None` where some task on the chain has no bounded response
/// time; the paper's bound always exists.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainBound {
    by: [[Option<Nanos>; 2]; 4],
}

/// Where a latency is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Anchor {
    /// The head's read of the sample.
    Read,
    /// The event in the world: for reaction any instant, for freshness the
    /// instant just after the head read before the sample's.
    Event,
}

impl Anchor {
    /// Both anchors, from-read first.
    pub const ALL: [Anchor; 2] = [Anchor::Read, Anchor::Event];

    /// The name used in output and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Anchor::Read => "read",
            Anchor::Event => "event",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

impl ChainBound {
    /// The bounds `bound(method, anchor)` gives. Panics when the paper's
    /// bound is missing: its equations hold no response time, so it always
    /// exists.
    pub fn from_fn(bound: impl Fn(Bound, Anchor) -> Option<Nanos>) -> ChainBound {
        let mut by = [[None; 2]; 4];
        for m in Bound::ALL {
            for a in Anchor::ALL {
                by[m.index()][a.index()] = bound(m, a);
            }
        }
        assert!(
            Anchor::ALL
                .iter()
                .all(|a| by[Bound::Paper.index()][a.index()].is_some()),
            "the paper's bound always exists"
        );
        ChainBound { by }
    }

    /// `method`'s bound measured from `anchor`.
    pub fn get(&self, method: Bound, anchor: Anchor) -> Option<Nanos> {
        self.by[method.index()][anchor.index()]
    }

    /// The paper-mode bound measured from `anchor`.
    pub fn paper(&self, anchor: Anchor) -> Nanos {
        self.get(Bound::Paper, anchor)
            .expect("ChainBound::from_fn asserts the paper's bound")
    }

    /// The sound bound measured from `anchor`.
    pub fn sound(&self, anchor: Anchor) -> Option<Nanos> {
        self.get(Bound::Sound, anchor)
    }

    /// Every bound from `anchor`, in [`Bound::ALL`] order.
    pub fn from(&self, anchor: Anchor) -> impl Iterator<Item = (Bound, Option<Nanos>)> + '_ {
        Bound::ALL
            .into_iter()
            .map(move |m| (m, self.get(m, anchor)))
    }
}

/// Both metrics' bounds of one chain.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainAnalysis {
    /// Reaction time bounds.
    pub reaction: ChainBound,
    /// Freshness time bounds.
    pub freshness: ChainBound,
    /// The paper's case of each link.
    pub cases: Vec<Case>,
}

/// Sampling delay of the head task, paper mode: reads are one period apart,
/// so an event waits at most T_1 for the next read.
fn paper_sampling_delay(h: &LinkTask) -> Nanos {
    h.t
}

/// Every bound that starts at the head job's release, from the event: the
/// first head release after an event (reaction), or after the head read
/// before the sample's (freshness), is less than T_1 later.
fn from_event(head: &LinkTask, from_release: Option<Nanos>) -> Option<Nanos> {
    let sampling = match &head.event {
        Some(a) if a.merging => event_links::sampling(a)?,
        _ => head.t,
    };
    from_release?.checked_add(sampling)
}

/// Sound mode, reaction from the event (the maximum reaction time of the
/// cause-effect-chain literature): from an event at any instant to the first
/// output of the tail carrying a sample read at or after it. Follow the
/// immediate forward job chain: the first head job reading at or after the
/// event is released less than T_1 after it, and each stage's first job
/// reading at or after the producer's publish is released within the link
/// term. That job carries the event's sample or a newer one, so nothing
/// needs the event's own sample to reach the tail: the reachability terms
/// do not apply (`p_distinct = false`). docs/analysis.md derives it.
fn sound_event_reaction(sched: Scheduler, lt: &[LinkTask]) -> Option<Nanos> {
    let mut sum = Some(0);
    for w in lt.windows(2) {
        sum = sum
            .zip(sound_reaction_link(sched, &w[0], &w[1], false, false))
            .map(|(a, b)| a + b);
    }
    from_event(
        &lt[0],
        sum.zip(lt[lt.len() - 1].publish()).map(|(a, b)| a + b),
    )
}

/// The sound links of a chain from the head's read, with "distinct" passed
/// along from the head.
fn sound_links(sched: Scheduler, lt: &[LinkTask]) -> Vec<SoundLink> {
    let mut distinct = true;
    let mut links = Vec::with_capacity(lt.len().saturating_sub(1));
    for (k, w) in lt.windows(2).enumerate() {
        let (p, c) = (&w[0], &w[1]);
        links.push(SoundLink::new_in(
            fp_order(sched, p, c),
            p,
            c,
            distinct,
            k == 0,
        ));
        distinct = distinct_passes(p, c, distinct);
    }
    links
}

/// Davare's (reaction, freshness) from the read.
fn davare(lt: &[LinkTask]) -> (Option<Nanos>, Option<Nanos>) {
    // Its argument is for periodic tasks each a thread of its own.
    if lt.iter().any(LinkTask::merging) {
        return (None, None);
    }
    let tail = lt[lt.len() - 1].r;
    let mid: Option<Nanos> = lt[..lt.len() - 1]
        .iter()
        .map(|t| t.r.map(|r| t.t + r))
        .sum();
    let last_t = lt[lt.len() - 1].t;
    let reaction = mid.zip(tail).map(|(a, r)| a + last_t + r - lt[0].t);
    (reaction, mid.zip(tail).map(|(a, r)| a + r))
}

/// Dürr et al. 2019's (reaction, freshness) from the read: Theorems 5.4 and
/// 5.10 for one ECU, a link gaining R_p back when its producer preempts its
/// consumer (`fp_order`, so inheritance and other CPUs count as "not above").
fn duerr(sched: Scheduler, lt: &[LinkTask]) -> (Option<Nanos>, Option<Nanos>) {
    // The theorems assume every response time is bounded, and periodic
    // tasks each a thread of its own.
    if lt.iter().any(|t| t.r.is_none() || t.merging()) {
        return (None, None);
    }
    let mut react = lt[lt.len() - 1].r;
    let mut age = react;
    for w in lt.windows(2) {
        let (p, c) = (&w[0], &w[1]);
        // "p above c" gives R_p back but for J_p with jitter (the producer
        // job is released up to J_p after its nominal release).
        let part2 = match fp_order(sched, p, c) {
            Some(Case::Two) => Some(p.j),
            _ => p.r,
        };
        react = react
            .zip(p.r.zip(part2))
            .map(|(a, (rp, x))| a + rp.max(c.t + x));
        age = age.zip(part2).map(|(a, x)| a + p.t + x);
    }
    (react, age)
}

/// The paper's (reaction, freshness) along the chain: Eq. 1 at the head and
/// each link's term.
fn paper(lt: &[LinkTask]) -> (Nanos, Nanos, Vec<Case>) {
    let (mut reaction, mut freshness) = (lt[0].l, lt[0].l);
    let mut cases = Vec::new();
    for w in lt.windows(2) {
        let (p, c) = (&w[0], &w[1]);
        cases.push(paper_case(p, c));
        reaction += paper_reaction_link(p, c);
        freshness += paper_freshness_link(p, c);
    }
    (reaction, freshness, cases)
}

/// The bounds of the chain along `path` (task indices, head first), given the tasks' timing.
pub fn analyze_chain(spec: &Spec, timing: &[TaskTiming], path: &[usize]) -> ChainAnalysis {
    let lt: Vec<LinkTask> = path
        .iter()
        .map(|&i| LinkTask::new(spec, timing, i))
        .collect();
    let sched = spec.scheduler;
    let head = &lt[0];
    let (paper_reaction, paper_freshness, cases) = paper(&lt);
    let links = sound_links(sched, &lt);
    // The tail's publish: R_n, or T_n under LET (so are the head's terms:
    // a chain all under LET gets `let_bound::any_phasing`'s figures).
    let tail_r = lt[lt.len() - 1].publish();
    let tail = (tail_r, lt[lt.len() - 1].read_to_publish());
    let (sound_reaction, sound_freshness) = compose_sound(tail, head.read_to_publish(), &links);
    // From the event the freshness runs from the head's release: a chain of
    // one task by R_1, not W_1 (the freshness terms never start at a read).
    let sound_event = (
        sound_event_reaction(sched, &lt),
        from_event(head, compose_sound(tail, head.publish(), &links).1),
    );
    let (davare_reaction, davare_freshness) = davare(&lt);
    let (duerr_reaction, duerr_freshness) = duerr(sched, &lt);
    // `from_read` in `Bound::ALL` order; from the event, every bound but
    // sound reaction starts at the head job's release (`from_event`).
    let bound = |from_read: [Option<Nanos>; 4], sound_event: Option<Nanos>| {
        ChainBound::from_fn(|m, a| match (m, a) {
            (_, Anchor::Read) => from_read[m.index()],
            (Bound::Paper, Anchor::Event) => {
                from_read[m.index()].map(|b| b + paper_sampling_delay(head))
            }
            (Bound::Sound, Anchor::Event) => sound_event,
            (_, Anchor::Event) => from_event(head, from_read[m.index()]),
        })
    };
    ChainAnalysis {
        reaction: bound(
            [
                Some(paper_reaction),
                sound_reaction,
                davare_reaction,
                duerr_reaction,
            ],
            sound_event.0,
        ),
        freshness: bound(
            [
                Some(paper_freshness),
                sound_freshness,
                davare_freshness,
                duerr_freshness,
            ],
            sound_event.1,
        ),
        cases,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    #[test]
    fn eq1_epsilon_convention() {
        // x ≤ C: runs in one budget, L = x.
        assert_eq!(eq1_single_pipe(MS, MS, 10 * MS), MS);
        assert_eq!(eq1_single_pipe(MS / 2, MS, 10 * MS), MS / 2);
        // x = 2.5 C: two full budgets then 0.5 C → 2·T + 0.5·C.
        assert_eq!(eq1_single_pipe(5 * MS, 2 * MS, 10 * MS), 2 * 10 * MS + MS);
        // x = exactly 2 C: (2−1)·T + (2C − C) = T + C, not 2·T + 0.
        assert_eq!(eq1_single_pipe(4 * MS, 2 * MS, 10 * MS), 10 * MS + 2 * MS);
    }

    fn lt(c: Nanos, t: Nanos, delta_out: Nanos, r: Nanos, prio: usize) -> LinkTask {
        LinkTask {
            c,
            t,
            d: t,
            x: c,
            x_min: c / 2,
            delta_out,
            l: c,
            r: Some(r),
            w: Some(r),
            j: 0,
            budgeted: true,
            cpu: 0,
            edf: false,
            prio: Some(prio),
            top: Some(prio),
            let_comm: false,
            event: None,
        }
    }

    /// A server with release jitter (it may wait for its budget, in slack)
    /// breaks the priority order only as the task above: P1 and P2 ask of
    /// the task below only that it not run (docs/analysis.md, "Priorities,
    /// constrained deadlines and release jitter").
    #[test]
    fn a_jittered_server_breaks_the_order_only_above() {
        let sched = Scheduler::Rm;
        let (hi, lo) = (lt(MS, 10 * MS, 0, 2 * MS, 1), lt(MS, 20 * MS, 0, 4 * MS, 2));
        let jittered = |t: LinkTask| LinkTask { j: MS, ..t };
        assert_eq!(fp_order(sched, &hi, &lo), Some(Case::Two));
        assert_eq!(fp_order(sched, &lo, &hi), Some(Case::One));
        // Below: P2 (it is the consumer) and P1 (the producer) stand.
        assert_eq!(fp_order(sched, &hi, &jittered(lo)), Some(Case::Two));
        assert_eq!(fp_order(sched, &jittered(lo), &hi), Some(Case::One));
        // Above: neither.
        assert_eq!(fp_order(sched, &jittered(hi), &lo), None);
        assert_eq!(fp_order(sched, &lo, &jittered(hi)), None);
        // A plain task with jitter has no budget to wait for.
        let plain = LinkTask {
            budgeted: false,
            ..jittered(hi)
        };
        assert_eq!(fp_order(sched, &plain, &lo), Some(Case::Two));
        assert_eq!(fp_order(sched, &lo, &plain), Some(Case::One));
    }

    #[test]
    fn eq6_cases() {
        // Producer T = 15, C = 1; consumer T = 10, C = 1.15; Δ = 0.25 (ms, ×1e6 ns).
        let p = lt(MS, 15 * MS, MS / 4, 2 * MS, 2);
        let c = lt(1_150_000, 10 * MS, MS / 4, 2 * MS, 1);
        // Case 1 (Eq. 2): S = T_c − C_c − Δ = 10 − 1.15 − 0.25 = 8.6; + L_c 1.15 = 9.75.
        assert_eq!(paper_case(&p, &c), Case::One);
        assert_eq!(paper_reaction_link(&p, &c), 9_750_000);
        // Eq. 12: F(p|c) = 2·T_p − Δ = 29.75; minus L_p = 1 → 28.75.
        assert_eq!(paper_freshness_link(&p, &c), 28_750_000);
        // Case 2 (Eq. 4) for c → p: S = T_c − C_c − Δ_c = 10 − 1.15 − 0.25 = 8.6; + L_p = 9.6.
        assert_eq!(paper_case(&c, &p), Case::Two);
        assert_eq!(paper_reaction_link(&c, &p), 9_600_000);
        assert_eq!(paper_freshness_link(&c, &p), 9_600_000);
    }

    #[test]
    fn special_cases_eqs_7_to_14() {
        // Budgets fit the demand (Eq. 7: L = C) and Δ = 0 (Eq. 10).
        // Producer C = 2, T = 10; consumer C = 3, T = 4 (ms).
        let p = lt(2 * MS, 10 * MS, 0, 5 * MS, 2);
        let c = lt(3 * MS, 4 * MS, 0, 3 * MS, 1);
        // Eq. 10, Case 1 (T_c < T_p): E = T_c + C_p = 4 + 2 = 6.
        assert_eq!(p.l + paper_reaction_link(&p, &c), 6 * MS);
        // Eq. 11, Case 1: appending c adds T_c = 4.
        assert_eq!(paper_reaction_link(&p, &c), 4 * MS);
        // Eq. 13/14, Case 1: F = 2 T_p = 20.
        assert_eq!(p.l + paper_freshness_link(&p, &c), 20 * MS);
        // Swap kinds (Case 2: T_p = 4 ≤ T_c = 10):
        // Eq. 10: E = T_p + C_c = 4 + 2 = 6; Eq. 11 adds T_p − C_p + C_c = 4 − 3 + 2 = 3;
        // Eq. 14: F = T_p + C_c = 6.
        assert_eq!(c.l + paper_reaction_link(&c, &p), 6 * MS);
        assert_eq!(paper_reaction_link(&c, &p), 3 * MS);
        assert_eq!(c.l + paper_freshness_link(&c, &p), 6 * MS);
        // Eq. 9 with Δ = 0.5: Case 1 E = T_c + C_p − Δ = 4 + 2 − 0.5 = 5.5.
        let p2 = LinkTask {
            delta_out: MS / 2,
            ..p
        };
        assert_eq!(p2.l + paper_reaction_link(&p2, &c), 5 * MS + MS / 2);
        // Eq. 8 (Case 2, Δ = 0.5): E = T_p + C_c − Δ = 4 + 2 − 0.5 = 5.5.
        let c2 = LinkTask {
            delta_out: MS / 2,
            ..c
        };
        assert_eq!(c2.l + paper_reaction_link(&c2, &p), 5 * MS + MS / 2);
    }
}
