//! The paper's terms (Eqs. 1–14) over a box of periods: each link's least
//! term over the cases the box leaves possible, as lower bounds at the
//! shortest periods and as affine forms over the box.

use super::{add_link, link_task, Affine, Order};
use crate::latency::{paper_freshness_link_in, paper_reaction_link_in};
use rtpipe_model::{Nanos, Spec};

/// The paper's link terms of p → c at periods (tp, tc), least over the
/// possible cases: (reaction, freshness).
pub(super) fn paper_link(
    spec: &Spec,
    order: &Order,
    p: usize,
    c: usize,
    tp: Nanos,
    tc: Nanos,
) -> (Nanos, Nanos) {
    let (lp, lc) = (
        link_task(spec, tp, (None, None), p),
        link_task(spec, tc, (None, None), c),
    );
    let cases = order.paper_cases(p, c);
    let e = cases
        .iter()
        .map(|&k| paper_reaction_link_in(k, &lp, &lc))
        .min();
    let f = cases
        .iter()
        .map(|&k| paper_freshness_link_in(k, &lp, &lc))
        .min();
    (e.unwrap_or(Nanos::MAX), f.unwrap_or(Nanos::MAX))
}

/// Lower bounds on a chain's paper reaction and freshness: the head's L
/// plus each link's least term, at the shortest periods.
pub(super) fn paper_bounds(spec: &Spec, order: &Order, path: &[usize]) -> (Nanos, Nanos) {
    let head = link_task(spec, order.lo[path[0]], (None, None), path[0]).l;
    let (mut e, mut f) = (head, head);
    for w in path.windows(2) {
        let (a, b) = paper_link(spec, order, w[0], w[1], order.lo[w[0]], order.lo[w[1]]);
        e = e.saturating_add(a);
        f = f.saturating_add(b);
    }
    (e, f)
}

/// The paper's reaction and freshness as affine forms over the box: each
/// case's term is affine in (T_p, T_c) (Eq. 1's L is affine in T for a
/// fixed demand and budget), so the least over the cases is concave.
pub(super) fn paper_forms(spec: &Spec, order: &Order, path: &[usize]) -> (Affine, Affine) {
    let h = path[0];
    let l_at = |t: Nanos| link_task(spec, t, (None, None), h).l as f64;
    let (lo, hi) = (order.lo[h], order.hi[h]);
    let slope = if hi > lo {
        (l_at(hi) - l_at(lo)) / (hi - lo) as f64
    } else {
        0.0
    };
    let head = Affine {
        base: l_at(lo),
        slopes: if slope > 0.0 {
            vec![(h, slope)]
        } else {
            Vec::new()
        },
    };
    let (mut e, mut f) = (head.clone(), head);
    for w in path.windows(2) {
        let (p, c) = (w[0], w[1]);
        let (lp, hp, lc, hc) = (order.lo[p], order.hi[p], order.lo[c], order.hi[c]);
        let at = |tp, tc| paper_link(spec, order, p, c, tp, tc);
        let corners = [at(lp, lc), at(hp, lc), at(lp, hc), at(hp, hc)];
        add_link(&mut e, p, c, hp - lp, hc - lc, corners.map(|x| x.0));
        add_link(&mut f, p, c, hp - lp, hc - lc, corners.map(|x| x.1));
    }
    (e, f)
}
