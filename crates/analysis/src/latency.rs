//! End-to-end reaction and freshness bounds of pipe chains.
//!
//! Both modes compose link by link (Section III-F): a chain's bound is the
//! head term plus one term per appended consumer, so the same link terms serve
//! declared chains and the dynamic programme over all paths (`paths.rs`).
//! docs/analysis.md derives every term.

use crate::sched::TaskTiming;
use rtpipe_model::{Nanos, Scheduler, Spec};

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
    /// Demand x = Δin + exec + Δout.
    pub x: Nanos,
    /// Least demand x_min.
    pub x_min: Nanos,
    /// Output overhead Δout (the Δ of Eq. 6).
    pub delta_out: Nanos,
    /// Paper Eq. 1.
    pub l: Nanos,
    /// Job response time, when it is at most the period.
    pub r: Option<Nanos>,
    /// The CPU it runs on.
    pub cpu: u32,
    /// Own RM rank (the lowest priority the task runs at).
    pub prio: Option<usize>,
    /// Highest rank it can inherit (PIBS).
    pub top: Option<usize>,
}

impl LinkTask {
    /// Task `i` as its links see it.
    pub fn new(spec: &Spec, timing: &[TaskTiming], i: usize) -> LinkTask {
        let tm = &timing[i];
        LinkTask {
            c: tm.budget,
            t: tm.period,
            x: tm.demand,
            x_min: tm.demand_min,
            delta_out: spec.tasks[i].delta_out,
            l: eq1_single_pipe(tm.demand, tm.budget, tm.period),
            r: tm.bounded_response(),
            cpu: tm.cpu,
            prio: tm.priority,
            top: tm.top_priority,
        }
    }
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
/// when both tasks share a CPU scheduled by fixed priority.
pub fn fp_order(sched: Scheduler, p: &LinkTask, c: &LinkTask) -> Option<Case> {
    if sched != Scheduler::Rm || p.cpu != c.cpu {
        return None;
    }
    // "a above b" must hold at every instant: a's lowest priority above b's
    // highest (inherited) one.
    match (p.prio, p.top, c.prio, c.top) {
        (Some(_), Some(pt), Some(cp), Some(_)) if cp < pt => Some(Case::One),
        (Some(pp), Some(_), Some(_), Some(ct)) if pp < ct => Some(Case::Two),
        _ => None,
    }
}

/// Sound mode, reaction link p → c: the time from p's publish of a sample to
/// the first output of c carrying it. `p_distinct`: no two jobs of p carry the
/// same sample (true at the chain head), which licenses the reachability
/// arguments. `None` when a response time is unbounded.
pub fn sound_reaction_link(
    sched: Scheduler,
    p: &LinkTask,
    c: &LinkTask,
    p_distinct: bool,
) -> Option<Nanos> {
    sound_reaction_link_in(fp_order(sched, p, c), p, c, p_distinct)
}

/// [`sound_reaction_link`] with the priority order of the link given
/// (`fp_order`), so that a relaxation can take each order that is possible
/// over a set of periods. Every option grows with every period and response
/// time, which the relaxation relies on.
pub fn sound_reaction_link_in(
    order: Option<Case>,
    p: &LinkTask,
    c: &LinkTask,
    p_distinct: bool,
) -> Option<Nanos> {
    let (rp, rc) = (p.r?, c.r?);
    // Davare et al.: the first c release after the publish is less than T_c later.
    let mut l = c.t + rc;
    if order == Some(Case::One) {
        // c preempts p: at p's publish c has no pending job, and its last job
        // (which ran ≥ x_min(c) before the publish) was released ≥ x_min(c) earlier.
        l = l.min(c.t - c.x_min + rc);
    }
    if p_distinct {
        // Reachability: c must read before p's next publish, ≤ T_p + R_p − x_min(p) later.
        l = l.min(p.t + rp - p.x_min + rc);
        if order == Some(Case::Two) {
            // p preempts c: c must start before p's next release, ≤ T_p − x_min(p) later.
            l = l.min(p.t - p.x_min + rc);
        }
    }
    Some(l)
}

/// Sound mode, freshness link p → c, anchored on reads: from the read of the
/// last p job carrying a sample to the read of the last c job carrying it.
/// A chain's freshness is the sum of these plus the tail's response time.
pub fn sound_freshness_link(sched: Scheduler, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    sound_freshness_link_in(fp_order(sched, p, c), p, c)
}

/// [`sound_freshness_link`] with the priority order given (see
/// [`sound_reaction_link_in`]); every option grows with T_p and R_p.
pub fn sound_freshness_link_in(order: Option<Case>, p: &LinkTask, c: &LinkTask) -> Option<Nanos> {
    let (rp, _) = (p.r?, c.r?);
    // That c job reads before p's next publish, which the next p job (released
    // T_p after the one that read the sample) makes within R_p.
    Some(match order {
        // c preempts p: that c job has even finished (≥ x_min(c) after its read)
        // by the time p publishes again.
        Some(Case::One) => p.t + rp - c.x_min,
        // p preempts c: that c job started before p's next release.
        Some(Case::Two) => p.t,
        None => p.t + rp,
    })
}

/// Sound mode: does "each sample is carried by at most one job" pass from p to c?
/// It does when c's reads are further apart than p's publishes can be.
pub fn distinct_passes(p: &LinkTask, c: &LinkTask, p_distinct: bool) -> bool {
    match (p_distinct, p.r, c.r) {
        (true, Some(rp), Some(rc)) => c.t - rc + c.x > p.t + rp - p.x_min,
        _ => false,
    }
}

/// The bounds of one chain in one metric.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainBound {
    /// The paper's bound (Eqs. 1–14).
    pub paper: Nanos,
    /// `None` when some task on the chain has no bounded response time.
    pub sound: Option<Nanos>,
    /// Reaction: R_1 + Σ_{i≥2} (T_i + R_i) (Davare et al., DAC 2007);
    /// freshness: the data-age form Σ_{i<n} (T_i + R_i) + R_n.
    pub davare: Option<Nanos>,
    /// From the external event, paper mode: the paper's bound plus one head
    /// period (the event waits for the next read).
    pub from_event_paper: Nanos,
    /// From the external event, sound mode. Reaction: from an event at any
    /// instant to the first tail output carrying a sample read at or after it
    /// (the event's own sample may never reach the tail). Freshness: from the
    /// head read before a sample's read to the sample's last tail output.
    pub from_event_sound: Option<Nanos>,
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
}

impl ChainBound {
    /// The paper-mode bound measured from `a`.
    pub fn paper_from(&self, a: Anchor) -> Nanos {
        match a {
            Anchor::Read => self.paper,
            Anchor::Event => self.from_event_paper,
        }
    }

    /// The sound bound measured from `a`.
    pub fn sound_from(&self, a: Anchor) -> Option<Nanos> {
        match a {
            Anchor::Read => self.sound,
            Anchor::Event => self.from_event_sound,
        }
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

/// Sound mode, freshness from the event: the previous head read is at most
/// T_1 + R_1 − x_1 before the read of the sample (F3), so the event that the
/// sample reflects happened at most that long before it.
fn sound_sampling_delay(h: &LinkTask) -> Option<Nanos> {
    h.r.map(|r| h.t + r - h.x)
}

/// Sound mode, reaction from the event (the maximum reaction time of the
/// cause-effect-chain literature): from an event at any instant to the first
/// output of the tail carrying a sample read at or after it. Follow the
/// immediate forward job chain: the first head job reading at or after the
/// event publishes within T_1 + R_1 of it (the first release after the event
/// is less than T_1 later), and each stage's first job reading at or after
/// the producer's publish publishes within the link term. That job carries
/// the event's sample or a newer one, so nothing needs the event's own sample
/// to reach the tail: the reachability terms do not apply, and each link gets
/// the generic terms only (`p_distinct = false`). Never above Davare's
/// Σ (T_i + R_i). docs/analysis.md derives it.
fn sound_event_reaction(sched: Scheduler, lt: &[LinkTask]) -> Option<Nanos> {
    let head = &lt[0];
    let mut sum = head.t + head.r?;
    for w in lt.windows(2) {
        sum += sound_reaction_link(sched, &w[0], &w[1], false)?;
    }
    Some(sum)
}

/// The bounds of the chain along `path` (task indices, head first), given the tasks' timing.
pub fn analyze_chain(spec: &Spec, timing: &[TaskTiming], path: &[usize]) -> ChainAnalysis {
    let lt: Vec<LinkTask> = path
        .iter()
        .map(|&i| LinkTask::new(spec, timing, i))
        .collect();
    let sched = spec.scheduler;
    let head = &lt[0];
    let tail = &lt[lt.len() - 1];
    let mut pe = head.l;
    let mut pf = head.l;
    // Reaction is anchored on publishes (head: read → publish ≤ R_1), freshness
    // on reads (tail: read → publish ≤ R_n, added at the end).
    let mut se = head.r;
    let mut sf = Some(0);
    let mut dv_e = head.r;
    let mut dv_f = Some(0);
    let mut distinct = true;
    let mut cases = Vec::new();
    for w in lt.windows(2) {
        let (p, c) = (&w[0], &w[1]);
        cases.push(paper_case(p, c));
        pe += paper_reaction_link(p, c);
        pf += paper_freshness_link(p, c);
        se = se
            .zip(sound_reaction_link(sched, p, c, distinct))
            .map(|(a, b)| a + b);
        sf = sf
            .zip(sound_freshness_link(sched, p, c))
            .map(|(a, b)| a + b);
        dv_e = dv_e.zip(c.r).map(|(a, r)| a + c.t + r);
        dv_f = dv_f.zip(p.r).map(|(a, r)| a + p.t + r);
        distinct = distinct_passes(p, c, distinct);
    }
    sf = sf.zip(tail.r).map(|(a, r)| a + r);
    dv_f = dv_f.zip(tail.r).map(|(a, r)| a + r);
    // Every sample's first output comes no later than its last one.
    se = match (se, sf) {
        (Some(e), Some(f)) => Some(e.min(f)),
        (e, _) => e,
    };
    let paper_delay = paper_sampling_delay(head);
    let event_reaction = sound_event_reaction(sched, &lt);
    let event_freshness = sf.zip(sound_sampling_delay(head)).map(|(a, b)| a + b);
    let bound =
        |paper: Nanos, sound: Option<Nanos>, davare: Option<Nanos>, event: Option<Nanos>| {
            ChainBound {
                paper,
                sound,
                davare,
                from_event_paper: paper + paper_delay,
                from_event_sound: event,
            }
        };
    ChainAnalysis {
        reaction: bound(pe, se, dv_e, event_reaction),
        freshness: bound(pf, sf, dv_f, event_freshness),
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
            x: c,
            x_min: c / 2,
            delta_out,
            l: c,
            r: Some(r),
            cpu: 0,
            prio: Some(prio),
            top: Some(prio),
        }
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
        // Swap roles (Case 2: T_p = 4 ≤ T_c = 10):
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
