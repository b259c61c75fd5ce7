//! Response times under EDF: Spuri's analysis (*Analysis of deadline
//! scheduled real-time systems*, INRIA RR-2772, 1996, Section 4), for the
//! reservations rtpipe schedules.
//!
//! What the simulator does (`sim/src/server.rs`, `engine.rs`): a task on a
//! constant-bandwidth server is released every `T` and, since a job's
//! demand never exceeds the budget (`x ≤ C`), each job wakes the server
//! with a fresh budget and the absolute deadline `release + T` (the CBS
//! wake-up rule keeps an old deadline only when it is later than the
//! release, which a job finishing by its own deadline never leaves
//! behind), and never exhausts it before it completes. A plain task
//! (`server = "none"`) has the same deadline and no budget. So every
//! guaranteed task of a CPU is a sporadic task with relative deadline
//! `D = T` and per-job work at most `I` ([`crate::sched::interference`]:
//! its budget on a server, which never runs more, its demand otherwise),
//! scheduled by absolute deadline; background tasks run only when none of
//! those has work. Ties may go either way: jobs of equal deadline count as
//! interference.
//!
//! Spuri's bound for a job of task `i` released `a` after the start of a
//! busy period in which every other task is released at the start and then
//! as often as it may:
//!
//! ```text
//! w_i(a) = ⌊a/T_i⌋·I_i + own + Σ_{j≠i} min(⌈w/T_j⌉, 1 + ⌊(a + T_i − T_j)/T_j⌋)⁺ · I_j
//! R_i    = max_{a ∈ A, a < L} max(own, w_i(a) − a)
//! ```
//!
//! with `own` the job's demand (`x` for the job response time, `C` for the
//! budget), `L` the synchronous busy period (`L = Σ ⌈L/T_j⌉ I_j`) and `A`
//! the instants where the right-hand side steps: `k·T_i` and
//! `(k + 1)·T_j − T_i` (k ≥ 0). Between two of them `w_i(a)` is constant and
//! `w_i(a) − a` falls, so the maximum over every real `a` is at one of them.
//!
//! With critical sections under the stack resource policy, a job of the
//! window may also wait, before it starts, for the rest of one section of
//! a job released before the window with a deadline after it (Baker 1991):
//! `+ b(a + T_i)` in `w_i(a)`, Baruah's blocking of an interval of that
//! length ([`crate::blocking::srp_at`]; its steps at `T_k − T_i` are
//! candidates already), and the longest such section `B*` in `L`
//! (`L = B* + Σ ⌈L/T_j⌉ I_j`). docs/analysis.md, "Shared resources under
//! EDF", proves both.
//!
//! With scheduling overheads ([`crate::overheads`]) each task's `I_j`
//! carries its two context switches and every release brings kernel work
//! (`EdfTask::kernel`) that runs whatever its deadline: `+ Σ_k ⌈w/T_k⌉·K_k`
//! in `w_i(a)` (not capped by deadlines, independent of `a`, so the
//! candidates stay the same) and `K_j` beside `I_j` in `L`
//! (docs/analysis.md, "Scheduling overheads").

use rtpipe_model::{Nanos, MAX_TIME};

/// The analysis gives up above this many jobs in the synchronous busy
/// period (its work grows with that number); the caller then falls back to
/// the server period, which is also a bound. Monotone in every period: a
/// longer period never makes the busy period hold more jobs.
pub const MAX_BUSY_JOBS: u64 = 200_000;

/// One guaranteed task of a CPU: per-job work (at most), period and
/// relative deadline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdfTask {
    /// The most one job can run (`sched::interference`).
    pub work: Nanos,
    /// Period T (the least distance between two releases).
    pub period: Nanos,
    /// Relative deadline D ≤ T (T for implicit deadlines); `Nanos::MAX`
    /// for a task whose releases only run their handlers (no job of it
    /// is ever picked first).
    pub deadline: Nanos,
    /// Kernel work each release brings at top priority, whatever the
    /// deadlines (the release handler and a server's replenishment,
    /// [`crate::overheads`]; 0 without overheads).
    pub kernel: Nanos,
}

/// Jobs of `tasks` released in `[0, w)` under synchronous release.
fn jobs_within(tasks: &[EdfTask], w: Nanos) -> u64 {
    tasks
        .iter()
        .map(|t| ((w + t.period - 1) / t.period) as u64)
        .sum()
}

/// The busy period `L = blocking + Σ ⌈L/T_j⌉ I_j` (least fixed point;
/// the synchronous one for `blocking = 0`), or `None` when it holds more
/// than `max_jobs` jobs or passes [`MAX_TIME`]. Without blocking it exists
/// exactly when `Σ I_j/T_j ≤ 1` (with a larger load every iterate grows),
/// so a value proves the CPU is not overloaded.
pub fn busy_period(tasks: &[EdfTask], blocking: Nanos, max_jobs: u64) -> Option<Nanos> {
    assert!(
        blocking >= 0
            && tasks
                .iter()
                .all(|t| t.period > 0 && t.work >= 0 && t.kernel >= 0)
    );
    let mut l: Nanos = blocking + tasks.iter().map(|t| t.work + t.kernel).sum::<Nanos>();
    if l == 0 {
        return Some(0);
    }
    loop {
        if l > MAX_TIME || jobs_within(tasks, l) > max_jobs {
            return None;
        }
        let next: Nanos = blocking
            + tasks
                .iter()
                .map(|t| ((l + t.period - 1) / t.period) * (t.work + t.kernel))
                .sum::<Nanos>();
        if next == l {
            return Some(l);
        }
        assert!(next > l, "busy period iteration must grow");
        l = next;
    }
}

/// The instants `a < l` where `w_i(a)` steps (see the module docs),
/// ascending, without duplicates; 0 first.
fn candidates(tasks: &[EdfTask], i: usize, l: Nanos) -> Vec<Nanos> {
    let (ti, di) = (tasks[i].period, tasks[i].deadline);
    let mut out = vec![0];
    for (j, t) in tasks.iter().enumerate() {
        // Own releases at k·T_i; another task's k-th deadline reaches the
        // analysed one's at k·T_j + D_j − D_i.
        let mut a = if j == i {
            ti
        } else {
            t.deadline.saturating_sub(di)
        };
        if a < 0 {
            a += (-a + t.period - 1) / t.period * t.period;
        }
        while a < l {
            if a > 0 {
                out.push(a);
            }
            a += t.period;
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Spuri's worst-case response time of a job of task `i` with demand `own`
/// (`own ≤ I_i` for a bound within the period), against the other tasks
/// of `tasks` (one CPU's guaranteed tasks, `i` among them), given the
/// busy period `l` ([`busy_period`], with the largest blocking), and the
/// blocking steps `block` of the stack resource policy
/// ([`crate::blocking::srp_steps`] with deadlines = periods; empty without
/// critical sections). Never below `own`.
pub fn response_time(
    tasks: &[EdfTask],
    i: usize,
    own: Nanos,
    l: Nanos,
    block: &[(Nanos, Nanos)],
) -> Nanos {
    let me = tasks[i];
    let mut worst = own;
    // A job of no demand still waits for the jobs it may not overtake; it
    // finishes no later than one of a nanosecond (same schedule up to its
    // start), which the half-open release count below handles.
    let own = own.max(1);
    let mut w: Nanos = 0;
    let mut at = candidates(tasks, i, l);
    // Where b(a + T_i) steps (already there when every threshold is a
    // period; kept for any other).
    at.extend(
        block
            .iter()
            .map(|&(theta, _)| theta - me.deadline)
            .filter(|&a| a > 0 && a < l),
    );
    at.sort_unstable();
    at.dedup();
    for a in at {
        let own_a =
            (a / me.period) * me.work + own + crate::blocking::srp_at(block, a + me.deadline);
        // Jobs of j with a deadline at or before the analysed one's.
        let cap = |t: &EdfTask| {
            if a + me.deadline >= t.deadline {
                1 + (a + me.deadline - t.deadline) / t.period
            } else {
                0
            }
        };
        // w_i(a) grows with a: the previous fixed point is a valid start, and
        // so is the first job of every task that may not be overtaken.
        let first: Nanos = tasks
            .iter()
            .enumerate()
            .filter(|&(j, t)| j != i && cap(t) > 0)
            .map(|(_, t)| t.work)
            .sum();
        // Blocking may fall as a grows: then only the fresh start is below
        // the least fixed point.
        let start = if block.is_empty() {
            w.max(own_a + first)
        } else {
            own_a + first
        };
        w = fixed_point(tasks, i, own_a, |j| cap(&tasks[j]), start);
        worst = worst.max(w - a);
    }
    worst
}

/// The least `w ≥ start` with
/// `w = base + Σ_{j≠i} min(⌈w/T_j⌉, cap(j))·I_j + Σ_k ⌈w/T_k⌉·K_k`
/// (`start` at most that fixed point, so the iteration only grows). Every
/// release in the window runs its kernel work `K`, whatever its deadline,
/// i's own included (docs/analysis.md, "Scheduling overheads").
fn fixed_point(
    tasks: &[EdfTask],
    i: usize,
    base: Nanos,
    cap: impl Fn(usize) -> Nanos,
    start: Nanos,
) -> Nanos {
    let mut w = start;
    loop {
        let next = base
            + tasks
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(j, t)| ((w + t.period - 1) / t.period).min(cap(j)) * t.work)
                .sum::<Nanos>()
            + tasks
                .iter()
                .map(|t| (w + t.period - 1) / t.period * t.kernel)
                .sum::<Nanos>();
        assert!(next >= w, "the busy-window iteration must not fall");
        if next == w {
            return w;
        }
        w = next;
    }
}

/// A bound on the time from a job's start (its read) to its completion
/// (its publish) for a job of task `i` with demand `own`, given every
/// task's relative deadline `deadline[j]` (the period for implicit
/// deadlines): the least `w` with
///
/// ```text
/// w = own + Σ_{j≠i, D_j < D_i} min(⌈w/T_j⌉, ⌈(D_i − D_j)/T_j⌉) · I_j
/// ```
///
/// The simulator releases every job due at an instant before it picks at
/// that instant, and picks by (deadline, task index) among pending jobs,
/// none of which is ever throttled under EDF. So every job pending when
/// the analysed job starts at `s` (released at or before `s`) either
/// finished before or ranks after it and never runs before it completes;
/// what runs in between is released strictly after `s` with a deadline at
/// most `d = r + D_i`: for task j, releases in `(s, d − D_j]`, at most
/// `⌈(D_i − D_j − (s − r))/T_j⌉` of them (none when `D_j ≥ D_i`), and in
/// `(s, s + w)` at most `⌈w/T_j⌉`. Starting at the release is the worst
/// case. It never exceeds Spuri's `w_i(0)`, which counts a job of every
/// task released at the start itself, so it is never above the response
/// time; docs/analysis.md proves it. Never below `own` (nor 1).
pub fn start_to_finish(tasks: &[EdfTask], i: usize, own: Nanos) -> Nanos {
    let di = tasks[i].deadline;
    let cap = |j: usize| {
        let l = di.saturating_sub(tasks[j].deadline);
        if l > 0 {
            (l + tasks[j].period - 1) / tasks[j].period
        } else {
            0
        }
    };
    // As in `response_time`: a job of no demand is analysed as one of 1 ns.
    let own = own.max(1);
    let first: Nanos = (0..tasks.len())
        .filter(|&j| j != i && cap(j) > 0)
        .map(|j| tasks[j].work)
        .sum();
    fixed_point(tasks, i, own, cap, own + first)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(v: &[(Nanos, Nanos)]) -> Vec<EdfTask> {
        v.iter()
            .map(|&(work, period)| EdfTask {
                work,
                period,
                deadline: period,
                kernel: 0,
            })
            .collect()
    }

    /// [`set`] with the given relative deadlines.
    fn due(v: &[(Nanos, Nanos)], deadlines: &[Nanos]) -> Vec<EdfTask> {
        let mut s = set(v);
        for (t, &d) in s.iter_mut().zip(deadlines) {
            t.deadline = d;
        }
        s
    }

    #[test]
    fn busy_period_and_overload() {
        // (1, 4), (2, 6), (3, 13): L = 6 → 1·2 + 2 + 3 = 7 → 2 + 4 + 3 = 9
        // → 3 + 4 + 3 = 10 → 10.
        assert_eq!(
            busy_period(&set(&[(1, 4), (2, 6), (3, 13)]), 0, 1000),
            Some(10)
        );
        // U = 1 exactly: the busy period is the hyperperiod.
        assert_eq!(busy_period(&set(&[(1, 2), (2, 4)]), 0, 1000), Some(4));
        // U > 1: no fixed point, the job bound stops the iteration.
        assert_eq!(busy_period(&set(&[(3, 4), (2, 4)]), 0, 1000), None);
        assert_eq!(busy_period(&[], 0, 1000), Some(0));
    }

    #[test]
    fn a_single_task_responds_in_its_demand() {
        let s = set(&[(3, 10)]);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        assert_eq!(response_time(&s, 0, 3, l, &[]), 3);
        assert_eq!(response_time(&s, 0, 1, l, &[]), 1);
    }

    /// Spuri's iteration by hand on two task sets.
    ///
    /// (C, T) = (2, 5), (4, 7): U = 0.971, not schedulable under RM
    /// (R_2 = 4 + 2·⌈8/5⌉ = 8 > 7), schedulable under EDF. L: 6 → 8 → 12 →
    /// 14 → 14. τ1: A = {0, 2, 5, 9, 10}; at a = 10 (own jobs at 0, 5, 10,
    /// τ2's at 0 and 7, deadlines 5, 10, 15 and 7, 14) w = 3·2 + 2·4 = 14,
    /// R = 14 − 10 = 4 (a = 2 also gives 4, by a tie of deadlines at 7).
    /// τ2: A = {0, 3, 7, 8, 13}; a = 0: w = 4 + 2 = 6; a = 8: own 2·4, τ1's
    /// deadlines 5, 10, 15 ≤ 15: w = 8 + 3·2 = 14, R = 6. So R = (4, 6).
    /// A job of τ2 of demand 1 at a = 0: w = 1 + 2 = 3; at a = 8: own
    /// 4 + 1, w = 5 + 3·2 = 11 (τ1's third job is released at 10 < 11),
    /// R = 3.
    ///
    /// (1, 4), (2, 6), (3, 13), the set of `sched::rta_textbook`: L = 10;
    /// τ3 at a = 0: 3 + 1 + 2 = 6 → 3 + 2 + 2 = 7 → 3 + 2 + 4 = 9 →
    /// 3 + 3 + 4 = 10, R = 10; τ2 at a = 7 (τ3's deadline 13 ties its own):
    /// own 2 + 2, τ1 ⌈w/4⌉ ≤ 3, τ3 once: 4 + 2 + 3 = 9 → 4 + 3 + 3 = 10,
    /// R = 3; τ1: 1.
    #[test]
    fn spuri_by_hand() {
        let s = set(&[(2, 5), (4, 7)]);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        assert_eq!(l, 14);
        assert_eq!(candidates(&s, 0, l), vec![0, 2, 5, 9, 10]);
        assert_eq!(candidates(&s, 1, l), vec![0, 3, 7, 8, 13]);
        assert_eq!(response_time(&s, 0, 2, l, &[]), 4);
        assert_eq!(response_time(&s, 1, 4, l, &[]), 6);
        assert_eq!(response_time(&s, 1, 1, l, &[]), 3);
        let s = set(&[(1, 4), (2, 6), (3, 13)]);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        let r: Vec<Nanos> = (0..3)
            .map(|i| response_time(&s, i, s[i].work, l, &[]))
            .collect();
        assert_eq!(r, vec![1, 3, 10]);
    }

    /// Spuri with constrained deadlines by hand, (C, T, D): (2, 5, 3),
    /// (4, 7, 7), L = 14. τ1: A = {0, 4, 5, 10, 11} (own releases, and τ2's
    /// deadlines k·7 + 7 − 3); a = 5: own 2·2, τ2's first job (deadline 7
    /// ≤ 8): 8 − 5 = 3 = R_1 = D_1. τ2: A = {0, 1, 6, 7, 11}; a = 1: τ1's
    /// jobs of deadlines 3 and 8 ≤ 8, w = 4 + 2·2 = 8, R_2 = 7. (1, 10, 4),
    /// (2, 10, 10): L = 3; τ2 at a = 0 meets τ1's deadline 4 ≤ 10, R_2 = 3,
    /// far below D_2 = 10 (what QPA alone gives).
    #[test]
    fn spuri_with_deadlines_by_hand() {
        let s = due(&[(2, 5), (4, 7)], &[3, 7]);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        assert_eq!(l, 14);
        assert_eq!(candidates(&s, 0, l), vec![0, 4, 5, 10, 11]);
        assert_eq!(candidates(&s, 1, l), vec![0, 1, 6, 7, 11]);
        assert_eq!(response_time(&s, 0, 2, l, &[]), 3);
        assert_eq!(response_time(&s, 1, 4, l, &[]), 7);
        let s = due(&[(1, 10), (2, 10)], &[4, 10]);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        assert_eq!(l, 3);
        assert_eq!(response_time(&s, 0, 1, l, &[]), 1);
        assert_eq!(response_time(&s, 1, 2, l, &[]), 3);
    }

    /// The start-to-finish bound by hand. (2, 5), (4, 7): τ1 (D = 5)
    /// meets no deadline of τ2 (7 > 5) after it starts: W = 2, where its
    /// response time is 4 (it may wait behind τ2's job of deadline 7 ≤ 10
    /// first, `spuri_by_hand`); τ2 (D = 7): ⌈(7 − 5)/5⌉ = 1 job of τ1,
    /// w = 4 + 2 = 6, so W = R = 6. (1, 4), (2, 6), (3, 13): τ3 admits
    /// ⌈9/4⌉ = 3 jobs of τ1 and ⌈7/6⌉ = 2 of τ2: 3 + 1 + 2 = 6 → 3 + 2 + 2
    /// = 7 → 3 + 2 + 4 = 9 → 3 + 3 + 4 = 10, W = 10 = R. Ties: (2, 4),
    /// (3, 8): τ2 admits ⌈4/4⌉ = 1 job of τ1 (the one released at 4 after
    /// the start has the deadline 8 + what the start lost), W = 3 + 2 = 5
    /// where Spuri's w(0) is 7; (1, 8), (3, 8): none, W = 3. Constrained,
    /// (C, T, D) = (2, 5, 3), (4, 7, 7): τ2 admits ⌈(7 − 3)/5⌉ = 1 job of
    /// τ1, W = 6; τ1 none, W = 2.
    #[test]
    fn start_to_finish_by_hand() {
        let s = set(&[(2, 5), (4, 7)]);
        assert_eq!(start_to_finish(&s, 0, 2), 2);
        assert_eq!(start_to_finish(&s, 1, 4), 6);
        let s = due(&[(2, 5), (4, 7)], &[3, 7]);
        assert_eq!(start_to_finish(&s, 1, 4), 6);
        assert_eq!(start_to_finish(&s, 0, 2), 2);
        let s = set(&[(1, 4), (2, 6), (3, 13)]);
        let w: Vec<Nanos> = (0..3).map(|i| start_to_finish(&s, i, s[i].work)).collect();
        assert_eq!(w, vec![1, 3, 10]);
        let s = set(&[(2, 4), (3, 8)]);
        assert_eq!(start_to_finish(&s, 1, 3), 5);
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        assert_eq!(response_time(&s, 1, 3, l, &[]), 7);
        assert_eq!(start_to_finish(&set(&[(1, 8), (3, 8)]), 1, 3), 3);
        // No demand: analysed as 1 ns, like the response time.
        assert_eq!(start_to_finish(&set(&[(3, 10)]), 0, 0), 1);
    }

    /// Spuri with SRP blocking by hand (`examples/edf-srp.toml`): (1, 4),
    /// (2, 6), (3, 12), b(4) = b(6) = 2, b(12) = 0; L = 2 + 6 = 8 → 11 →
    /// 12. τ1: a = 0: 1 + b(4) = 3; a = 2: 1 + b(6) + τ2's first = 5, 3;
    /// a = 4: 2 + b(8) + 2 = 6, 2; a = 8: 3 + b(12) + 2·2 + 3 = 10, 2:
    /// R = 3. τ2: a = 0: 2 + b(6) + 1 = 5. τ3: b(12 + a) = 0: 10.
    #[test]
    fn spuri_with_blocking_by_hand() {
        let s = set(&[(1, 4), (2, 6), (3, 12)]);
        let block = [(4, 2), (6, 2), (12, 0)];
        let l = busy_period(&s, 2, 1000).unwrap_or(0);
        assert_eq!(l, 12);
        let r: Vec<Nanos> = (0..3)
            .map(|i| response_time(&s, i, s[i].work, l, &block))
            .collect();
        assert_eq!(r, vec![3, 5, 10]);
        // Without the blocking the deadline ties at 12 decide: τ1 at a = 8
        // (own 3, τ2's jobs of deadlines 6 and 12, τ3's): 10 − 8 = 2; τ2 at
        // a = 6 (own 4, three of τ1, τ3): 10 − 6 = 4.
        let l = busy_period(&s, 0, 1000).unwrap_or(0);
        let r: Vec<Nanos> = (0..3)
            .map(|i| response_time(&s, i, s[i].work, l, &[]))
            .collect();
        assert_eq!(r, vec![2, 4, 10]);
    }

    #[test]
    fn candidates_are_the_steps() {
        // T = (4, 6), i = 1, L = 12: own 6; the other's deadlines reach
        // T_1's at 4·(k + 1) − 6 = 2, 6, 10.
        let s = set(&[(2, 4), (3, 6)]);
        assert_eq!(candidates(&s, 1, 12), vec![0, 2, 6, 10]);
    }
}
