//! Lower bounds on Σ C/T over a box from the chain limits' affine forms
//! (`rtpipe_analysis::relax`): the Lagrangian dual of the separable convex
//! problem, one multiplier per limit. `budget` is C_i per task (0 for
//! background tasks), `lo` / `hi` the box's shortest and longest periods.

use rtpipe_analysis::relax::{Affine, MinSum, Piece};
use rtpipe_model::Nanos;
use std::sync::Arc;

/// Coordinate-ascent sweeps over the multipliers of the joint bound.
const JOINT_SWEEPS: usize = 3;

/// One limit in the joint bound: Σ s_i T_i ≤ room.
pub(crate) struct Row {
    pub(crate) slopes: Vec<(usize, f64)>,
    pub(crate) room: f64,
}

impl Row {
    /// The form below all of `forms` (least base, least slope per task),
    /// written as Σ s_i T_i ≤ room.
    pub(crate) fn new(forms: &[&Affine], limit: f64, lo: &[Nanos], n: usize) -> Row {
        let mut least: Option<Vec<f64>> = None;
        let mut base = f64::INFINITY;
        for a in forms {
            let mut s = vec![0.0; n];
            a.slopes.iter().for_each(|&(i, x)| s[i] += x);
            least = Some(match least {
                None => s,
                Some(m) => m.iter().zip(&s).map(|(x, y)| x.min(*y)).collect(),
            });
            base = base.min(a.base);
        }
        let slopes: Vec<(usize, f64)> = least
            .unwrap_or_default()
            .into_iter()
            .enumerate()
            .filter(|&(_, x)| x > 0.0)
            .collect();
        let at_lo: f64 = slopes.iter().map(|&(i, x)| x * lo[i] as f64).sum();
        Row {
            room: limit - base + at_lo,
            slopes,
        }
    }
}

/// A lower bound from every limit at once (limits share tasks): the
/// Lagrangian dual of the separable convex problem, with one multiplier
/// per limit, raised by coordinate ascent. For multipliers λ ≥ 0,
/// Σ_i min_T (C_i/T_i + w_i T_i) − Σ λ_c room_c with w = Σ λ_c s_c is a
/// valid bound whatever λ, the minimising T_i = √(C_i / w_i) clamped to
/// the box. A reaction limit (E or F below it) enters as the form below
/// both, the least base and slopes.
pub(crate) fn joint_bound(budget: &[f64], rows: &[Row], lo: &[Nanos], hi: &[Nanos]) -> f64 {
    joint_solution(budget, rows, lo, hi).0
}

/// [`joint_bound`] with the periods that minimise its Lagrangian.
fn joint_solution(budget: &[f64], rows: &[Row], lo: &[Nanos], hi: &[Nanos]) -> (f64, Vec<f64>) {
    let n = lo.len();
    let mut lambda = vec![0.0f64; rows.len()];
    // The minimising T_i at weight w_i.
    let t_at = |i: usize, w: f64| {
        let (l, h) = (lo[i] as f64, hi[i] as f64);
        match (budget[i] == 0.0, w > 0.0) {
            (true, _) => l,
            (false, false) => h,
            (false, true) => (budget[i] / w).sqrt().clamp(l, h),
        }
    };
    let weights = |lambda: &[f64], w: &mut Vec<f64>| {
        w.clear();
        w.resize(n, 0.0);
        for (row, &l) in rows.iter().zip(lambda) {
            row.slopes.iter().for_each(|&(i, s)| w[i] += l * s);
        }
    };
    let mut w = Vec::with_capacity(n);
    // One multiplier is maximised in one pass.
    let sweeps = if rows.len() > 1 { JOINT_SWEEPS } else { 1 };
    for _ in 0..sweeps {
        for (c, row) in rows.iter().enumerate() {
            // The weights of the other limits; λ_c adds λ_c s_c to them.
            lambda[c] = 0.0;
            weights(&lambda, &mut w);
            // d dual / d λ_c = Σ s_ci T_i − S_c falls as λ_c grows.
            let slack = |x: f64| {
                row.slopes
                    .iter()
                    .map(|&(i, s)| s * t_at(i, w[i] + x * s))
                    .sum::<f64>()
                    - row.room
            };
            if slack(0.0) <= 0.0 {
                continue;
            }
            let (mut a, mut b) = (-60.0f64, 20.0f64);
            for _ in 0..40 {
                let m = 0.5 * (a + b);
                if slack(m.exp2()) > 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            lambda[c] = b.exp2();
        }
    }
    // Valid for any λ ≥ 0: the weights afresh from the multipliers found.
    weights(&lambda, &mut w);
    let t: Vec<f64> = (0..n).map(|i| t_at(i, w[i])).collect();
    let primal: f64 = (0..n).map(|i| budget[i] / t[i] + w[i] * t[i]).sum();
    let bound = primal
        - rows
            .iter()
            .zip(&lambda)
            .map(|(r, l)| l * r.room)
            .sum::<f64>();
    (bound, t)
}

/// A lower bound on Σ C/T over the box where `form ≤ limit` (`None`:
/// nowhere): the joint bound of that one limit.
pub(crate) fn least_under(
    budget: &[f64],
    form: &Affine,
    limit: f64,
    lo: &[Nanos],
    hi: &[Nanos],
) -> Option<f64> {
    least_at(budget, form, limit, lo, hi).map(|x| x.0)
}

/// [`least_under`] with the periods that minimise its Lagrangian.
fn least_at(
    budget: &[f64],
    form: &Affine,
    limit: f64,
    lo: &[Nanos],
    hi: &[Nanos],
) -> Option<(f64, Vec<f64>)> {
    let row = Row::new(&[form], limit, lo, lo.len());
    (form.base <= limit).then(|| joint_solution(budget, &[row], lo, hi))
}

/// Piece choices enumerated per limit at most; beyond, the limit is left
/// out of [`split_bound`] (a weaker, still valid bound).
const MAX_CHOICES: usize = 1 << 12;

/// One limit of [`split_bound`]: `key` names it across boxes (the same
/// limit of the same chain has the same key in every box), so that a box's
/// budget shares can start from its parent's; one of `sums` must meet
/// `limit`.
pub(crate) struct SplitLimit {
    pub(crate) key: u32,
    pub(crate) limit: f64,
    pub(crate) sums: Vec<MinSum>,
}

/// The budget shares a box's split bound ended with, carried to its
/// sub-boxes (each a subset of it, so any shares are valid there too):
/// per limit key and shared task, the fraction of the task's budget dealt
/// to that limit (f32: any fractions are normalised to the budgets where
/// they are used). Shared by both halves of a split (`Arc`).
#[derive(Debug, Clone, Default)]
pub(crate) struct Shares(Arc<[(u32, u32, f32)]>);

impl Shares {
    /// Its heap memory, for the open boxes' count.
    pub(crate) fn bytes(&self) -> usize {
        self.0.len() * std::mem::size_of::<(u32, u32, f32)>()
    }
}

/// What [`split_bound`] finds: the bound, the best round's guide (per task
/// in some limit, the shortest period a limit's least asks of it) and its
/// shares.
pub(crate) struct Split {
    pub(crate) bound: f64,
    pub(crate) guide: Vec<Option<f64>>,
    pub(crate) shares: Shares,
}

/// A lower bound on Σ C/T over the box from limits written as sums of
/// least-of-pieces terms (`relax::MinSum`, each limit met by one of its
/// sums): every task's budget is shared among the limits it is in, and
/// each limit's share is minimised exactly (for every choice of one piece
/// per term, the sum is an affine form and [`least_under`] is the least of
/// the separable convex problem). For every T meeting the limits and any
/// shares summing to the budgets, Σ C/T = Σ_limits Σ shares/T + the rest
/// ≥ Σ_limits least + Σ C/hi over the tasks in no limit. The shares start
/// from `start` (a parent box's; equal where it has none) and move,
/// [`SHARE_ROUNDS`] times (`root_rounds` without a parent's), towards
/// the limits whose least wants the task's period shortest (the bound is
/// concave in the shares, 1/T_i its slope); the best round is the bound,
/// and its shares are what a sub-box starts from (a warm start: the ascent
/// goes on down the search tree). `None`: some limit holds nowhere in the
/// box.
pub(crate) fn split_bound(
    budget: &[f64],
    limits: &[SplitLimit],
    lo: &[Nanos],
    hi: &[Nanos],
    (start, root_rounds): (&Shares, usize),
) -> Option<Split> {
    let n = lo.len();
    let members: Vec<Vec<bool>> = limits.iter().map(|l| tasks_of(&l.sums, n)).collect();
    let mut count = vec![0u32; n];
    for m in &members {
        count
            .iter_mut()
            .zip(m)
            .for_each(|(c, &x)| *c += u32::from(x));
    }
    let rest: f64 = (0..n)
        .filter(|&i| count[i] == 0)
        .map(|i| budget[i] / hi[i] as f64)
        .sum();
    let mut shares = initial_shares(budget, limits, &members, &count, start);
    let shared = count.iter().any(|&c| c > 1);
    let mut best: Option<Split> = None;
    // The root's shares (no parent's to start from) are where every box
    // below starts: the ascent may run longer there.
    let rounds = match (shared, start.0.is_empty()) {
        (false, _) => 1,
        (true, true) => root_rounds,
        (true, false) => SHARE_ROUNDS,
    };
    for round in 0..rounds {
        let mut total = rest;
        let mut minimisers = Vec::with_capacity(limits.len());
        for (l, share) in limits.iter().zip(&shares) {
            let (least, t) = l
                .sums
                .iter()
                .filter_map(|s| least_of_sum(share, s, l.limit, lo, hi))
                .min_by(|a, b| a.0.total_cmp(&b.0))?;
            total += least;
            minimisers.push(t);
        }
        if best.as_ref().is_none_or(|b| total > b.bound) {
            best = Some(Split {
                bound: total,
                guide: guide(&members, &minimisers, n),
                shares: kept_shares(limits, &shares, &count, budget),
            });
        }
        if round + 1 < rounds {
            reshare(&mut shares, &minimisers, &count, budget);
        }
    }
    best
}

/// The shares each limit starts with: a parent's fractions where it has
/// them for that limit and task, else an equal part, normalised so that
/// every task's shares sum to its budget.
fn initial_shares(
    budget: &[f64],
    limits: &[SplitLimit],
    members: &[Vec<bool>],
    count: &[u32],
    start: &Shares,
) -> Vec<Vec<f64>> {
    let n = budget.len();
    let mut weights: Vec<Vec<f64>> = members
        .iter()
        .map(|m| {
            (0..n)
                .map(|i| if m[i] { 1.0 / f64::from(count[i]) } else { 0.0 })
                .collect()
        })
        .collect();
    for &(key, task, fraction) in start.0.iter() {
        let i = task as usize;
        let Some(c) = limits.iter().position(|l| l.key == key) else {
            continue;
        };
        if i < n && members[c][i] && fraction.is_finite() && fraction > 0.0 {
            weights[c][i] = f64::from(fraction);
        }
    }
    for i in 0..n {
        let sum: f64 = weights.iter().map(|w| w[i]).sum();
        for w in weights.iter_mut() {
            w[i] = if sum > 0.0 {
                budget[i] * w[i] / sum
            } else {
                0.0
            };
        }
    }
    weights
}

/// The shares of the shared tasks as fractions of their budgets, keyed by
/// limit, for a sub-box's start.
fn kept_shares(
    limits: &[SplitLimit],
    shares: &[Vec<f64>],
    count: &[u32],
    budget: &[f64],
) -> Shares {
    let mut fractions = Vec::new();
    for (l, share) in limits.iter().zip(shares) {
        for i in (0..count.len()).filter(|&i| count[i] > 1 && budget[i] > 0.0) {
            if share[i] > 0.0 {
                fractions.push((l.key, i as u32, (share[i] / budget[i]) as f32));
            }
        }
    }
    Shares(fractions.into())
}

/// Per task, the shortest of its limits' minimising periods (`None` for
/// a task in no limit).
fn guide(members: &[Vec<bool>], minimisers: &[Vec<f64>], n: usize) -> Vec<Option<f64>> {
    (0..n)
        .map(|i| {
            members
                .iter()
                .zip(minimisers)
                .filter(|(m, _)| m[i])
                .map(|(_, t)| t[i])
                .reduce(f64::min)
        })
        .collect()
}

/// Rounds of moving the shares in [`split_bound`], per box (from its
/// parent's shares, so a box at depth d has had 64 + 8d in sound mode,
/// which runs [`ROOT_SHARE_ROUNDS`] at the root, and 8(d + 1) in paper
/// mode).
pub(crate) const SHARE_ROUNDS: usize = 8;

/// Rounds of moving the shares at a box with no parent's shares (the
/// root): docs/design.md, "The lower bound, round seven" (the bounds
/// stopped rising past 32 rounds; 32 at every box cost the search four
/// fifths of its boxes).
pub(crate) const ROOT_SHARE_ROUNDS: usize = 64;

/// Each shared task's budget anew among its limits, each share scaled by
/// 1/T_i at that limit's minimiser (a multiplicative ascent step; 1/T_i is
/// the bound's slope in the share).
fn reshare(shares: &mut [Vec<f64>], minimisers: &[Vec<f64>], count: &[u32], budget: &[f64]) {
    for i in (0..count.len()).filter(|&i| count[i] > 1) {
        let scaled: Vec<f64> = shares
            .iter()
            .zip(minimisers)
            .map(|(s, t)| s[i] / t[i])
            .collect();
        let sum: f64 = scaled.iter().sum();
        if sum > 0.0 {
            for (s, x) in shares.iter_mut().zip(&scaled) {
                s[i] = budget[i] * x / sum;
            }
        }
    }
}

/// The tasks whose periods appear in any of `sums`.
fn tasks_of(sums: &[MinSum], n: usize) -> Vec<bool> {
    let mut m = vec![false; n];
    for s in sums {
        let pieces = std::iter::once(&s.fixed).chain(s.terms.iter().flatten());
        pieces
            .flat_map(|p| &p.slopes)
            .for_each(|&(i, _)| m[i] = true);
    }
    m
}

/// The least of Σ share/T over the part of the box where `sum` holds
/// (`MinSum::within`) and `sum ≤ limit`, over the choices of one piece
/// per term, with its minimising periods (`None` where no choice holds;
/// with too many choices, Σ share/hi, the limit left out).
fn least_of_sum(
    share: &[f64],
    sum: &MinSum,
    limit: f64,
    lo: &[Nanos],
    hi: &[Nanos],
) -> Option<(f64, Vec<f64>)> {
    // Most sums hold in the whole box: no copy of it for those.
    let narrowed;
    let (lo, hi) = if sum.within.is_empty() {
        (lo, hi)
    } else {
        narrowed = sum.narrowed(lo, hi)?;
        (narrowed.0.as_slice(), narrowed.1.as_slice())
    };
    let choices = sum
        .terms
        .iter()
        .try_fold(1usize, |acc, t| acc.checked_mul(t.len()))
        .filter(|&c| c <= MAX_CHOICES);
    let Some(choices) = choices else {
        let t: Vec<f64> = hi.iter().map(|&h| h as f64).collect();
        return Some(((0..lo.len()).map(|i| share[i] / t[i]).sum(), t));
    };
    let at_lo = |p: &Piece| p.at(lo);
    let mut best: Option<(f64, Vec<f64>)> = None;
    for mut code in 0..choices {
        let mut form = Affine {
            base: at_lo(&sum.fixed),
            slopes: sum.fixed.slopes.clone(),
        };
        for term in &sum.terms {
            let piece = &term[code % term.len()];
            code /= term.len();
            form.base += at_lo(piece);
            form.slopes
                .extend(piece.slopes.iter().filter(|s| s.1 > 0.0));
        }
        if let Some(b) = least_at(share, &form, limit, lo, hi) {
            if best.as_ref().is_none_or(|x| b.0 < x.0) {
                best = Some(b);
            }
        }
    }
    best
}
