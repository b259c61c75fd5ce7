//! The sound link terms of a link that touches a work-queue thread or a
//! data-triggered task (an *event link*: the producer's or the consumer's
//! jobs merge). Like every sound term they run from the producer job's
//! release to the consumer job's release (`latency`'s anchors); a merged
//! job's release is its first one. The fixed-priority cases and the
//! reachability terms are not used here: they assume periodic releases
//! and distinct ranks. docs/analysis.md, "Threads and data-triggered
//! tasks", derives each term.

use crate::events::EventTiming;
use rtpipe_model::Nanos;

/// Most triggers of one task whose release waits a link term knows;
/// a link from a trigger past them takes the generic term (still sound).
pub const MAX_WAITS: usize = 8;

/// What an event link needs of a task's activations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Activation {
    /// The task's index in `Spec::tasks`.
    pub id: usize,
    /// Its jobs merge (in a thread or data-triggered).
    pub merging: bool,
    /// A: the longest from any instant to its next activation.
    pub gap: Option<Nanos>,
    waits: [(usize, Option<Nanos>); MAX_WAITS],
    listed: usize,
}

impl Activation {
    /// Task `id`'s activations as the event analysis found them.
    pub fn new(id: usize, e: &EventTiming) -> Activation {
        let mut waits = [(usize::MAX, None); MAX_WAITS];
        let listed = e.waits.len().min(MAX_WAITS);
        waits[..listed].copy_from_slice(&e.waits[..listed]);
        Activation {
            id,
            merging: e.merging,
            gap: e.gap,
            waits,
            listed,
        }
    }

    /// When task `p` is a (listed) trigger: the longest from its
    /// publication to the release it brings.
    fn wait_after(&self, p: usize) -> Option<Option<Nanos>> {
        self.waits[..self.listed]
            .iter()
            .find(|&&(q, _)| q == p)
            .map(|&(_, w)| w)
    }
}

/// One task of an event link.
#[derive(Debug, Clone, Copy)]
pub struct Side {
    /// R: from a job's (first) release to its publish.
    pub r: Option<Nanos>,
    /// W: from a job's read to its publish (at most R).
    pub w: Option<Nanos>,
    /// x: the worst-case demand of a job.
    pub x: Nanos,
    /// T: the period (the nominal rate of a data-triggered task).
    pub t: Nanos,
    /// Its activations.
    pub act: Activation,
    /// It communicates under LET.
    pub let_comm: bool,
}

/// Is p → c an event link (the terms of this module apply)?
pub fn is_event_link(p: Option<&Activation>, c: Option<&Activation>) -> bool {
    p.is_some_and(|a| a.merging) || c.is_some_and(|a| a.merging)
}

/// Reaction, release of `J_k` (its read when `p_read`) to the release of
/// the first c job that reads at or after `J_k`'s publish: `J_k` publishes
/// within `R_p` (`W_p`); when p triggers c, c is released at that publish
/// (`join = "any"`) or once the other triggers have published again
/// (`join = "all"`, the wait); otherwise c's next activation comes within
/// `A_c`. That activation releases a job, or joins a queued job that has
/// not started, which then reads after it; either job's (first) release
/// is no later. `None` when a figure is unbounded or LET is involved
/// (not analysed).
pub fn reaction(p: &Side, c: &Side, p_read: bool) -> Option<Nanos> {
    if p.let_comm || c.let_comm {
        return None;
    }
    c.r?;
    let publish = if p_read { p.w? } else { p.r? };
    publish.checked_add(wait_or_gap(p, c)?)
}

/// Freshness in a spec with threads or data-triggered tasks, on every
/// link: the terms run between `Y_k`, the (first) release of the p job
/// after `L_k` (the last p job carrying the sample), and `Y_{k+1}`; that
/// job publishes within `R_p`, at `X_k`, and `L_{k+1}` read before `X_k`.
/// When p triggers c, the publish at `X_k` releases c (after the wait of
/// `join = "all"`), and that job (or the queued one it joins) reads after
/// it, so it follows `L_{k+1}`: `Y_{k+1} ≤ X_k + wait`. Otherwise c's next
/// job after `L_{k+1}` is released at the first activation after `L_{k+1}`
/// read (nominal release `T_c` after it for a thread-less periodic c),
/// within `A_c`. So `Y_{k+1} − Y_k ≤ R_p + (wait or A_c)`; the head link
/// adds [`head_offset`].
pub fn freshness(p: &Side, c: &Side) -> Option<Nanos> {
    if p.let_comm || c.let_comm {
        return None;
    }
    c.r?;
    p.r?.checked_add(wait_or_gap(p, c)?)
}

/// The last freshness link: `L_n` reads before `X_{n−1} ≤ Y_{n−1} + R_p`
/// and publishes within `W_c` of its read.
pub fn freshness_last(p: &Side, c: &Side) -> Option<Nanos> {
    if p.let_comm || c.let_comm {
        return None;
    }
    c.r?;
    p.r?.checked_add(c.w?)
}

/// `Y_1 − r(L_1)` of a chain's head p: its next job is released `T_p`
/// after `L_1` (thread-less periodic), or, when its jobs merge, at the
/// first activation after `L_1` starts (at most `R_p − x_p` after its
/// release), within `A_p`.
pub fn head_offset(p: &Side) -> Option<Nanos> {
    if !p.act.merging {
        return Some(p.t);
    }
    (p.r? - p.x).checked_add(p.act.gap?)
}

/// The wait for c's release after p's publish when p triggers c, else
/// `A_c`.
fn wait_or_gap(p: &Side, c: &Side) -> Option<Nanos> {
    match c.act.wait_after(p.act.id) {
        Some(wait) => wait,
        None => c.act.gap,
    }
}

/// From an event at any instant to the release of the first head job
/// reading at or after it: a head activation comes within `A` (T for a
/// periodic head, the nominal release), and its job (or the queued one
/// it joins) reads after it.
pub fn sampling(head: &Activation) -> Option<Nanos> {
    head.gap
}
