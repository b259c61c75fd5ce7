//! A chain's figures over a box as sums of link terms, each the least of
//! affine pieces in its two periods, for a bound that keeps the choice
//! between the pieces (`relax`'s affine forms replace each least by one
//! plane below it, which over a wide box is nearly flat).
//!
//! With response times held at their lower bounds over the box, a sound
//! link term is the least of options `T_p + a` and `T_c + b`
//! (`latency::sound_reaction_link_in` and the freshness terms: each option
//! is a sum of one period and response times less a fixed demand), so it
//! *is* `min(T_p + a, T_c + b)`, `a` and `b` the least constants (+∞ where
//! no option of that kind exists); where ranks follow the periods and the
//! box leaves the link's order open, the constants are tied to the side
//! of `T_p = T_c` each order needs ([`tied_pieces`], docs/design.md, "The
//! relaxation on wide boxes, term by term"). A paper term is the least over the
//! cases the box leaves open of one affine function each (Eqs. 2–5, 12;
//! Eq. 1's L is affine in T for a fixed demand and budget). Both are read
//! off the terms themselves and checked at the box's four corners of
//! `(T_p, T_c)`; a chain where that check fails (an option outside this
//! shape: LET, server periods as response times) gets no pieces.
//!
//! Response times are held at their least over the box, which counts a
//! task whose order against the chain's task the box leaves open as if
//! it were below. Where ranks follow the periods, the box is cut for the
//! chain at a chain task's period past another task's longest one
//! ([`regions`]): in the part above the cut that task is above at every
//! point and the part's response times count it; each part's sums hold in
//! that part only (`MinSum::within`), and the design's split bound takes
//! the least over the parts (docs/design.md, "Response times tied to the
//! periods").

use super::paper::paper_link;
use super::{all_let, distinct_passes, link_task, Order, Times};
use crate::latency::Case;
use rtpipe_model::policy::ResponseAnalysis;
use rtpipe_model::{Communication, Nanos, Spec};

/// A period beyond every box, at which an option in that period never is
/// the least.
const FAR: Nanos = 1 << 50;

/// `base + Σ slope·T` over absolute periods T (ns).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Piece {
    /// The value at T = 0.
    pub base: f64,
    /// (task, slope ≥ 0).
    pub slopes: Vec<(usize, f64)>,
}

impl Piece {
    /// Its value at periods `t`.
    pub fn at(&self, t: &[Nanos]) -> f64 {
        self.base
            + self
                .slopes
                .iter()
                .map(|&(i, s)| s * t[i] as f64)
                .sum::<f64>()
    }
}

/// A lower bound on a chain figure over the box, or over the part of it
/// that `within` leaves: `fixed(T) + Σ_k min over terms[k] of piece(T)`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MinSum {
    /// The part with one piece.
    pub fixed: Piece,
    /// The link terms, each at least the least of its pieces.
    pub terms: Vec<Vec<Piece>>,
    /// Where it holds: each (task, lo, hi) narrows that task's period to
    /// `lo..=hi`; empty: the whole box.
    pub within: Vec<(usize, Nanos, Nanos)>,
}

impl MinSum {
    /// Whether periods `t` lie where it holds.
    pub fn holds_at(&self, t: &[Nanos]) -> bool {
        self.within.iter().all(|&(i, l, h)| l <= t[i] && t[i] <= h)
    }

    /// The box `lo..=hi` narrowed to where it holds; `None`: nowhere.
    pub fn narrowed(&self, lo: &[Nanos], hi: &[Nanos]) -> Option<(Vec<Nanos>, Vec<Nanos>)> {
        narrow(lo, hi, &self.within)
    }

    /// Its value at periods `t`.
    pub fn at(&self, t: &[Nanos]) -> f64 {
        self.fixed.at(t)
            + self
                .terms
                .iter()
                .map(|ps| ps.iter().map(|p| p.at(t)).fold(f64::INFINITY, f64::min))
                .sum::<f64>()
    }

    /// The same sum from the event: `T_head` more.
    pub fn plus_period(mut self, head: usize) -> MinSum {
        self.fixed.slopes.push((head, 1.0));
        self
    }
}

/// A chain's sound sums over one part of a box: the reaction sum E and
/// the freshness sum F from the read (the sound reaction is the smaller,
/// the freshness F) and E without reachability from the release plus
/// `T_head` (the reaction from the event).
pub type SoundSums = (MinSum, MinSum, MinSum);

/// The sound chain figures of chain `k` as least-of-pieces sums over the
/// box (`relaxed` = `relax(spec, lo, hi, imposed, _)`), one [`SoundSums`]
/// per part of a partition of the box: where the periods decide that a
/// task interferes with one of the chain's, the part's response times
/// count it ([`regions`]). `None`: no such shape (see the module
/// documentation) or the chain is unbounded in the box.
pub fn sound_pieces(
    spec: &Spec,
    (lo, hi): (&[Nanos], &[Nanos]),
    imposed: &[(usize, usize)],
    relaxed: &super::Relaxed,
    k: usize,
) -> Option<Vec<SoundSums>> {
    let path = &spec.chains.get(k)?.path;
    let shaped = spec.policy().response != ResponseAnalysis::ServerPeriod
        && path
            .iter()
            .all(|&i| spec.task_communication(i) != Communication::Let)
        && path.len() > 1;
    if !shaped || all_let(spec, path) {
        return None;
    }
    let order = Order::new(spec, lo, hi, imposed);
    let times = Times {
        r: relaxed.job_response.clone(),
        w: relaxed.read_to_publish.clone(),
    };
    let whole = chain_sums(spec, &order, &times, path)?;
    let parts = regions(&order, path);
    if parts.len() < 2 {
        return Some(vec![whole]);
    }
    let part_sums = |within: Vec<(usize, Nanos, Nanos)>| {
        let (lo, hi) = narrow(lo, hi, &within).expect("a part of the box is not empty");
        let sub = Order::new(spec, &lo, &hi, imposed);
        let mut times = Times {
            r: times.r.clone(),
            w: times.w.clone(),
        };
        for &i in path {
            (_, times.r[i], times.w[i]) = super::task_lower_bounds(spec, &sub, i);
        }
        // A part where the sums have no shape keeps the box's (they hold
        // in every part of it).
        let sums = chain_sums(spec, &sub, &times, path).unwrap_or_else(|| whole.clone());
        let limit = |mut s: MinSum| {
            s.within = within.clone();
            s
        };
        (limit(sums.0), limit(sums.1), limit(sums.2))
    };
    Some(parts.into_iter().map(part_sums).collect())
}

/// The most ranges one task's period takes across `parts` (one
/// [`sound_pieces`] answer): 1 uncut, 2 cut once, 3 or more a staircase
/// (`regions`); what the pieces' tests count.
pub fn most_ranges(parts: &[SoundSums]) -> usize {
    let mut ranges: Vec<(usize, Nanos, Nanos)> =
        parts.iter().flat_map(|p| p.0.within.clone()).collect();
    ranges.sort_unstable();
    ranges.dedup();
    let per_task = |i: usize| ranges.iter().filter(|r| r.0 == i).count();
    ranges.iter().map(|r| per_task(r.0)).max().unwrap_or(1)
}

/// The box `lo..=hi` with each (task, l, h) of `within` narrowing that
/// task's period to `l..=h`; `None` where that leaves it empty.
fn narrow(
    lo: &[Nanos],
    hi: &[Nanos],
    within: &[(usize, Nanos, Nanos)],
) -> Option<(Vec<Nanos>, Vec<Nanos>)> {
    let (mut lo, mut hi) = (lo.to_vec(), hi.to_vec());
    for &(i, l, h) in within {
        (lo[i], hi[i]) = (lo[i].max(l), hi[i].min(h));
        if lo[i] > hi[i] {
            return None;
        }
    }
    Some((lo, hi))
}

/// [`SoundSums`] of `path` over the box of `order`.
fn chain_sums(spec: &Spec, order: &Order, times: &Times, path: &[usize]) -> Option<SoundSums> {
    let (e, f) = sound_sums(spec, order, times, path, true)?;
    let (ev, _) = sound_sums(spec, order, times, path, false)?;
    Some((e, f, ev.plus_period(path[0])))
}

/// Parts of a box for a chain at most: each costs the split bound its
/// sums (docs/design.md, "The lower bound, round seven": with 8 or 16
/// parts the staircase left waters-50-1's bound below one cut per task's,
/// with 32 above it).
const MAX_REGIONS: usize = 32;

/// A part of a box: the (task, lo, hi) ranges it narrows.
type Within = Vec<(usize, Nanos, Nanos)>;

/// A partition of the box by the periods of `path`'s tasks, each part
/// given by the ranges it narrows (`MinSum::within`): a chain task `a`'s
/// period is cut at `hi_b + 1` for a task `b` ranked by period with it
/// whose order against `a` the box leaves open, so that above the cut `b`
/// is above `a` at every point (`T_b ≤ hi_b < T_a`) and the parts' response
/// times of `a` count it. `R_a` is a staircase in `T_a` (each `hi_b + 1`
/// adds b's job), so a task may be cut several times: each chain task's
/// range becomes a row of intervals, the cut with the most interference
/// above it within its interval first ([`best_split`]), while the product
/// of the rows' lengths (the parts) is at most [`MAX_REGIONS`]; the parts
/// are that product. One part (the whole box) where there is no cut.
fn regions(order: &Order, path: &[usize]) -> Vec<Within> {
    let mut tasks: Vec<usize> = Vec::new();
    for &a in path {
        if !tasks.contains(&a) {
            tasks.push(a);
        }
    }
    let mut rows: Vec<Vec<(Nanos, Nanos)>> = tasks
        .iter()
        .map(|&a| vec![(order.lo[a], order.hi[a])])
        .collect();
    while let Some((k, j, s)) = next_cut(order, &tasks, &rows) {
        let (l, h) = rows[k][j];
        rows[k].splice(j..=j, [(l, s - 1), (s, h)]);
    }
    let mut parts: Vec<Within> = vec![Vec::new()];
    for (&a, row) in tasks.iter().zip(&rows).filter(|(_, row)| row.len() > 1) {
        parts = parts
            .into_iter()
            .flat_map(|p| {
                row.iter().map(move |&(l, h)| {
                    let mut q = p.clone();
                    q.push((a, l, h));
                    q
                })
            })
            .collect();
    }
    parts
}

/// The next cut of [`regions`]: (chain task's row, interval, point), the
/// one with the most interference above it whose row may still grow
/// within [`MAX_REGIONS`] parts (ties: the earlier task, the earlier
/// interval); `None`: none.
fn next_cut(
    order: &Order,
    tasks: &[usize],
    rows: &[Vec<(Nanos, Nanos)>],
) -> Option<(usize, usize, Nanos)> {
    let parts: usize = rows.iter().map(Vec::len).product();
    let mut best: Option<(Nanos, usize, usize, Nanos)> = None;
    for (k, (&a, row)) in tasks.iter().zip(rows).enumerate() {
        if parts / row.len() * (row.len() + 1) > MAX_REGIONS {
            continue;
        }
        for (j, &range) in row.iter().enumerate() {
            if let Some((gain, s)) = best_split(order, a, range) {
                if best.is_none_or(|b| gain > b.0) {
                    best = Some((gain, k, j, s));
                }
            }
        }
    }
    best.map(|(_, k, j, s)| (k, j, s))
}

/// Where to cut task `a`'s period within its interval `lo..=hi` of the
/// box (`regions`): the point `s` in `lo < s ≤ hi` after the longest
/// period `hi_b` of the tasks whose order against `a` it decides there,
/// with the interference those tasks add above it (`Order::added_above`,
/// summed; tasks with `hi_b < lo` are above in the whole interval
/// already); the most interference weighted by the share of the interval
/// above the point. `None`: no task to decide.
fn best_split(order: &Order, a: usize, (lo, hi): (Nanos, Nanos)) -> Option<(Nanos, Nanos)> {
    let mut points: Vec<(Nanos, Nanos)> = (0..order.lo.len())
        .filter(|&b| b != a && order.ranked_by_period(a, b) && order.maybe_above(b, a))
        .filter(|&b| lo <= order.hi[b] && order.hi[b] < hi)
        .filter_map(|b| Some((order.hi[b] + 1, order.added_above(b, a)?.0)))
        .collect();
    points.sort_unstable();
    let mut above: Nanos = 0;
    let mut best: Option<(f64, Nanos, Nanos)> = None;
    for (s, work) in points {
        above += work;
        let value = above as f64 * (hi - s + 1) as f64 / (hi - lo + 1) as f64;
        if best.is_none_or(|b| value > b.0) {
            best = Some((value, above, s));
        }
    }
    best.map(|(_, gain, s)| (gain, s))
}

/// E and F of `path` (`reach`: from the read, with reachability).
fn sound_sums(
    spec: &Spec,
    order: &Order,
    r: &Times,
    path: &[usize],
    reach: bool,
) -> Option<(MinSum, MinSum)> {
    let least = |a: Option<Nanos>, b: Option<Nanos>| a.zip(b).map(|(a, b)| a.min(b)).or(a);
    let mut e = tail_sum(r, path[path.len() - 1], reach)?;
    let mut f = MinSum::default();
    let mut distinct = reach;
    for (k, w) in path.windows(2).enumerate() {
        let (pi, ci) = (w[0], w[1]);
        let last = k + 2 == path.len();
        let orders = order.link_orders(pi, ci);
        let order_set = orders.clone();
        let head = reach && k == 0;
        let tied = order.ranked_by_period(pi, ci);
        let raise = tied.then(|| order.added_above(ci, pi)).flatten();
        // The link's (reaction, freshness) terms over some of its orders;
        // Case One alone, tied to its side of the periods (c above p),
        // with c's interference in R_p (`Order::added_above`).
        let at = |orders: &[Option<Case>], tp: Nanos, tc: Nanos| {
            let one_side = orders == [Some(Case::One)] && orders != order_set.as_slice();
            let rp = match (one_side, raise) {
                (true, Some((x, w))) => (r.r[pi].map(|v| v + x), r.w[pi].map(|v| v + w)),
                _ => r.of(pi),
            };
            let (p, c) = ((pi, tp, rp), (ci, tc, r.of(ci)));
            let l = super::least_link(spec, order, orders, p, c, (distinct, head));
            let fresh = if last { l.freshness_last } else { l.freshness };
            // The head link's reaction already runs from its read.
            let react = match reach && k > 0 {
                true => least(l.reaction, l.reaction_from_read),
                false => l.reaction,
            };
            Some((react?, fresh?))
        };
        let link = Link {
            tasks: (pi, ci),
            corners: corners(order, pi, ci),
            orders: &orders,
            tied,
        };
        // Sharing the reachability piece's slope holds with the pieces of
        // a reachability row only (`tied_pieces`).
        let stages = (k > 0 && reach).then(|| &path[..=k]);
        let reaction = link.pieces(|o, a, b| at(o, a, b).map(|x| x.0), order, stages)?;
        e.terms.push(reaction);
        f.terms
            .push(link.pieces(|o, a, b| at(o, a, b).map(|x| x.1), order, None)?);
        let c_late = link_task(spec, order.hi[ci], r.of(ci), ci);
        distinct = distinct_passes(
            &link_task(spec, order.lo[pi], r.of(pi), pi),
            &c_late,
            distinct,
        );
    }
    Some((e, f))
}

/// E's fixed part: the tail's term. From the read the analysis takes each
/// stage from its release or its read (`latency::reaction_stages`), the
/// tail's from its read with W: at least the sum of each link's smaller
/// term and the smaller of R and W at the tail (each stage's release and
/// read bounds are at least that sum up to it).
fn tail_sum(r: &Times, tail: usize, reach: bool) -> Option<MinSum> {
    let tail_term = match (reach, r.r[tail], r.w[tail]) {
        (true, Some(rt), Some(wt)) => Some(rt.min(wt)),
        (_, rt, _) => rt,
    };
    Some(MinSum {
        fixed: Piece {
            base: tail_term? as f64,
            slopes: Vec::new(),
        },
        ..MinSum::default()
    })
}

/// A reaction term's `T_p + a` piece (a reachability row) shares its
/// slope with every stage before `p` on the chain (`stages`, head first,
/// ending at `p`): the rows need `p` distinct, which needs every stage
/// before it distinct (`latency::distinct_passes` is passed along the
/// chain), and each of those stages' reads further apart than its
/// producer's publishes, `T_q − R_q + x_q > T_prev + R_prev − x_min(prev)`,
/// so `T_q > T_prev` (R ≥ x ≥ x_min): the periods grow along the chain up
/// to `p`, and where the piece applies `T_p` is at least their mean. Where
/// `p` is not distinct the analysis has no such row and the term is at
/// least its `T_c` piece. Without it a wide box lets the bound shorten a
/// chain's middle stage alone, where the analysis would need all its
/// producers shorter too. A path that visits a task twice keeps the plain
/// row (its periods cannot grow strictly along it, but the mean would
/// count that task twice).
fn share_with_producers(pieces: &mut [Piece], stages: &[usize]) {
    let Some((&p, before)) = stages.split_last() else {
        return;
    };
    if before.is_empty()
        || stages
            .iter()
            .enumerate()
            .any(|(k, s)| stages[..k].contains(s))
    {
        return;
    }
    let share = 1.0 / stages.len() as f64;
    for piece in pieces {
        if piece.slopes == [(p, 1.0)] {
            piece.slopes = stages.iter().map(|&s| (s, share)).collect();
        }
    }
}

/// One link of a chain in the box: its producer and consumer, the corners
/// of their periods' rectangle, the orders the box leaves open, and
/// whether the periods decide them (`Order::ranked_by_period`).
struct Link<'o> {
    tasks: (usize, usize),
    corners: [(Nanos, Nanos); 4],
    orders: &'o [Option<Case>],
    tied: bool,
}

impl Link<'_> {
    /// The pieces of a link term (`term(orders, T_p, T_c)`: the least over
    /// `orders`): the least over the open orders read off as two pieces
    /// (`two_pieces`), with the reachability piece's slope shared along
    /// `stages` (`share_with_producers`); where both Case One and Case Two
    /// are open and ranks follow the periods, the pieces tied to the order
    /// the periods imply ([`tied_pieces`]) when they are higher at the
    /// rectangle's corners.
    fn pieces(
        &self,
        term: impl Fn(&[Option<Case>], Nanos, Nanos) -> Option<Nanos>,
        order: &Order,
        stages: Option<&[usize]>,
    ) -> Option<Vec<Piece>> {
        let share = |mut pieces: Vec<Piece>| {
            if let Some(stages) = stages {
                share_with_producers(&mut pieces, stages);
            }
            pieces
        };
        let least = |a: Nanos, b: Nanos| term(self.orders, a, b);
        let plain = share(two_pieces(least, self.tasks, order, &self.corners)?);
        let open = |case| self.orders.contains(&Some(case));
        if !(self.tied && open(Case::One) && open(Case::Two)) {
            return Some(plain);
        }
        let mut ends = [Ends::NONE; 3];
        for (slot, case) in [None, Some(Case::One), Some(Case::Two)]
            .into_iter()
            .enumerate()
        {
            if self.orders.contains(&case) {
                let one = |a: Nanos, b: Nanos| term(&[case], a, b);
                // An order whose term has not this shape: the plain least.
                let Some(pieces) = two_pieces(one, self.tasks, order, &self.corners) else {
                    return Some(plain);
                };
                ends[slot] = Ends::of(&pieces, self.tasks);
            }
        }
        let tied = tied_pieces(ends, self.tasks, stages.is_some());
        let value = |pieces: &[Piece]| corner_sum(pieces, self.tasks, &self.corners, order.lo);
        let best = tied
            .into_iter()
            .map(|(pieces, shares)| if shares { share(pieces) } else { pieces })
            .fold(plain, |a, b| if value(&b) > value(&a) { b } else { a });
        Some(best)
    }
}

/// A link term `min(T_p + a, T_c + b)` by its constants (+∞: no piece of
/// that kind).
#[derive(Clone, Copy)]
struct Ends {
    a: f64,
    b: f64,
}

impl Ends {
    const NONE: Ends = Ends {
        a: f64::INFINITY,
        b: f64::INFINITY,
    };

    /// The constants of `two_pieces`' pieces.
    fn of(pieces: &[Piece], (p, c): (usize, usize)) -> Ends {
        let mut ends = Ends::NONE;
        for piece in pieces {
            if piece.slopes == [(p, 1.0)] {
                ends.a = piece.base;
            } else if piece.slopes == [(c, 1.0)] {
                ends.b = piece.base;
            }
        }
        ends
    }
}

/// Pieces of a link term whose order the box leaves open, tied to the
/// order the periods imply (ranks by period, RM): Case One (c preempts p)
/// only where `T_c ≤ T_p`, Case Two only where `T_p ≤ T_c`, the order
/// `None` (neither preempts) anywhere. With each order's term
/// `min(T_p + a_k, T_c + b_k)` (`ends`: None, One, Two), a pair of pieces
/// `min(T_p + A, T_c + B)` is below the term at every point when `A ≤ a_0`,
/// `B ≤ b_0` and, on One's side (`T_c ≤ T_p`), `B ≤ b_1` and (`A ≤ a_1` or
/// `B ≤ a_1`), on Two's side, `A ≤ a_2` and (`B ≤ b_2` or `A ≤ b_2`): four
/// choices, the first the plain least over the orders. Where the pieces'
/// `T_p` slope is shared along the chain (`shared`, a reachability row,
/// `share_with_producers`), a point where `p` is not distinct has only
/// each order's `T_c` options, so `B ≤ b_2` must hold too: the first and
/// the third choice. Returns each choice with whether it may share.
fn tied_pieces(ends: [Ends; 3], (p, c): (usize, usize), shared: bool) -> Vec<(Vec<Piece>, bool)> {
    let [none, one, two] = ends;
    let choices = [
        (one.a.min(two.a), one.b.min(two.b), true),
        (one.a.min(two.a).min(two.b), one.b, false),
        (two.a, one.a.min(one.b).min(two.b), true),
        (two.a.min(two.b), one.a.min(one.b), false),
    ];
    let piece = |base: f64, i: usize| {
        (base < f64::INFINITY).then(|| Piece {
            base,
            slopes: vec![(i, 1.0)],
        })
    };
    choices
        .into_iter()
        .filter(|&(_, _, may_share)| may_share || !shared)
        .map(|(a, b, may_share)| {
            let pieces = [piece(a.min(none.a), p), piece(b.min(none.b), c)];
            (pieces.into_iter().flatten().collect(), may_share && shared)
        })
        .filter(|(pieces, _): &(Vec<Piece>, bool)| !pieces.is_empty())
        .collect()
}

/// The least of `pieces` summed over a link's corners, every other period
/// at its shortest (`lo`): which of two valid piece sets to keep.
fn corner_sum(
    pieces: &[Piece],
    (p, c): (usize, usize),
    corners: &[(Nanos, Nanos); 4],
    lo: &[Nanos],
) -> f64 {
    let mut t = lo.to_vec();
    corners
        .iter()
        .map(|&(tp, tc)| {
            (t[p], t[c]) = (tp, tc);
            pieces
                .iter()
                .map(|x| x.at(&t))
                .fold(f64::INFINITY, f64::min)
        })
        .sum()
}

/// The four corners (T_p, T_c) of a link's rectangle.
fn corners(order: &Order, p: usize, c: usize) -> [(Nanos, Nanos); 4] {
    let (lp, hp, lc, hc) = (order.lo[p], order.hi[p], order.lo[c], order.hi[c]);
    [(lp, lc), (hp, lc), (lp, hc), (hp, hc)]
}

/// A term `min(T_p + a, T_c + b)` read off `term` (far periods isolate
/// each kind of option), checked at the corners.
fn two_pieces(
    term: impl Fn(Nanos, Nanos) -> Option<Nanos>,
    (p, c): (usize, usize),
    order: &Order,
    corners: &[(Nanos, Nanos); 4],
) -> Option<Vec<Piece>> {
    let mut pieces = Vec::new();
    let a = term(order.lo[p], FAR)? - order.lo[p];
    if a < FAR / 2 {
        pieces.push(Piece {
            base: a as f64,
            slopes: vec![(p, 1.0)],
        });
    }
    let b = term(FAR, order.lo[c])? - order.lo[c];
    if b < FAR / 2 {
        pieces.push(Piece {
            base: b as f64,
            slopes: vec![(c, 1.0)],
        });
    }
    checked(pieces, &term, (p, c), corners)
}

/// `pieces` when their least equals `term` at every corner.
fn checked(
    pieces: Vec<Piece>,
    term: &impl Fn(Nanos, Nanos) -> Option<Nanos>,
    (p, c): (usize, usize),
    corners: &[(Nanos, Nanos); 4],
) -> Option<Vec<Piece>> {
    if pieces.is_empty() || pieces.iter().any(|x| x.slopes.iter().any(|s| s.1 < 0.0)) {
        return None;
    }
    let n = p.max(c) + 1;
    for &(tp, tc) in corners {
        let mut t = vec![0; n];
        (t[p], t[c]) = (tp, tc);
        let least = pieces
            .iter()
            .map(|x| x.at(&t))
            .fold(f64::INFINITY, f64::min);
        if (least - term(tp, tc)? as f64).abs() > 0.5 {
            return None;
        }
    }
    Some(pieces)
}

/// The paper-mode figures of chain `k` (reaction, freshness) as
/// least-of-pieces sums over the box: the head's L and one term per link,
/// a piece per case the box leaves open. `None` where the paper's terms
/// are not monotone (`paper_monotone`) or a check fails.
pub fn paper_pieces(
    spec: &Spec,
    (lo, hi): (&[Nanos], &[Nanos]),
    imposed: &[(usize, usize)],
    k: usize,
) -> Option<(MinSum, MinSum)> {
    let path = &spec.chains.get(k)?.path;
    if !super::paper_monotone(spec) || path.len() < 2 {
        return None;
    }
    let order = Order::new(spec, lo, hi, imposed);
    let h = path[0];
    let l_at = |t: Nanos| link_task(spec, t, (None, None), h).l;
    let head = line(l_at, h, (lo[h], hi[h]))?;
    let (mut e, mut f) = (
        MinSum {
            fixed: head.clone(),
            ..MinSum::default()
        },
        MinSum {
            fixed: head,
            ..MinSum::default()
        },
    );
    for w in path.windows(2) {
        let (p, c) = (w[0], w[1]);
        let corners = corners(&order, p, c);
        let cases = order.paper_cases(p, c);
        let mut pe = Vec::new();
        let mut pf = Vec::new();
        for case in cases {
            let tasks = |tp, tc| {
                (
                    link_task(spec, tp, (None, None), p),
                    link_task(spec, tc, (None, None), c),
                )
            };
            let re = |tp, tc| {
                let (a, b) = tasks(tp, tc);
                Some(crate::latency::paper_reaction_link_in(case, &a, &b))
            };
            let fr = |tp, tc| {
                let (a, b) = tasks(tp, tc);
                Some(crate::latency::paper_freshness_link_in(case, &a, &b))
            };
            let span = ((lo[p], hi[p]), (lo[c], hi[c]));
            pe.push(plane(re, (p, c), span)?);
            pf.push(plane(fr, (p, c), span)?);
        }
        let least_e = |tp, tc| Some(paper_link(spec, &order, p, c, tp, tc).0);
        let least_f = |tp, tc| Some(paper_link(spec, &order, p, c, tp, tc).1);
        e.terms.push(checked(pe, &least_e, (p, c), &corners)?);
        f.terms.push(checked(pf, &least_f, (p, c), &corners)?);
    }
    Some((e, f))
}

/// The affine function of (T_p, T_c) through `term`'s values at three
/// corners of the rectangle `span` (affine by the paper's equations),
/// checked at the fourth; `p ≠ c`.
fn plane(
    term: impl Fn(Nanos, Nanos) -> Option<Nanos>,
    (p, c): (usize, usize),
    ((lp, hp), (lc, hc)): ((Nanos, Nanos), (Nanos, Nanos)),
) -> Option<Piece> {
    let v0 = term(lp, lc)? as f64;
    let sp = if hp > lp {
        (term(hp, lc)? as f64 - v0) / (hp - lp) as f64
    } else {
        0.0
    };
    let sc = if hc > lc {
        (term(lp, hc)? as f64 - v0) / (hc - lc) as f64
    } else {
        0.0
    };
    let piece = Piece {
        base: v0 - sp * lp as f64 - sc * lc as f64,
        slopes: vec![(p, sp), (c, sc)],
    };
    // The fourth corner: the term is affine, or no piece.
    let mut t = vec![0; p.max(c) + 1];
    (t[p], t[c]) = (hp, hc);
    ((piece.at(&t) - term(hp, hc)? as f64).abs() <= 0.5).then_some(piece)
}

/// The head's L (Eq. 1) as an affine function of its period: exact where
/// its value at the middle of `[l, h]` is on the line through the ends.
fn line(term: impl Fn(Nanos) -> Nanos, i: usize, (l, h): (Nanos, Nanos)) -> Option<Piece> {
    let v0 = term(l) as f64;
    let s = if h > l {
        (term(h) as f64 - v0) / (h - l) as f64
    } else {
        0.0
    };
    let mid = l + (h - l) / 2;
    let on_line = (term(mid) as f64 - v0 - s * (mid - l) as f64).abs() <= 0.5;
    (s >= 0.0 && on_line).then(|| Piece {
        base: v0 - s * l as f64,
        slopes: vec![(i, s)],
    })
}
