//! Paper mode (Eqs. 2–6, 12): each link's case a binary, the link term a
//! variable bounded below by the active case.

use crate::domain::grid_units;
use crate::linear::Lin;
use crate::lp::Cmp;
use crate::model::Master;
use rtpipe_analysis::Metric;

/// Paper mode (Eqs. 2–6, 12 and Section III-F), with the case of each link a
/// binary: z = 1 ⟺ T_c < T_p. Returns the chain's sum.
pub(crate) fn paper_chain(
    m: &mut Master,
    path: &[usize],
    metric: Metric,
    limit: f64,
    shift: &Lin,
) -> Lin {
    let g = m.g;
    let spec = m.spec;
    // Budgets cover the demand (validated), so Eq. 1 gives L = x.
    let l = |i: usize| grid_units(spec.tasks[i].demand(), g);
    let mut total = Lin::constant(l(path[0]));
    let big = m.big_m;
    for w in path.windows(2) {
        let (p, c) = (w[0], w[1]);
        let z = m.lt(c, p, false);
        let delta = grid_units(spec.tasks[p].delta_out, g);
        let cc = grid_units(spec.tasks[c].budget(), g);
        let cp = grid_units(spec.tasks[p].budget(), g);
        let case1 = match metric {
            Metric::Reaction => m.period[c].add_c(-cc - delta + l(c)),
            Metric::Freshness => m.period[p].scale(2.0).add_c(-delta - l(p)),
        };
        let case2 = m.period[p].add_c(-cp - delta + l(c));
        let s = m.lp.var(-big, big, false);
        m.ge_option(s, &case1, &[(z, true)]);
        m.ge_option(s, &case2, &[(z, false)]);
        total = total.plus(&Lin {
            terms: vec![(s, 1.0)],
            c: 0.0,
        });
    }
    // From the event the bound is one head period more (`shift`).
    let row = total.plus(shift);
    m.lp.row(row.terms, Cmp::Le, limit - row.c);
    total
}
