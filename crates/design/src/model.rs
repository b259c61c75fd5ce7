//! The master problem's model: its variables (periods, utilisations,
//! response times) and the switches the encodings are written with (period
//! orders, "grew past", options under big-Ms).

use crate::domain::Dom;
use crate::linear::{Bin, Lin};
use crate::lp::{Cmp, Lp, SolverKind};
use crate::problem::Problem;
use rtpipe_analysis::Metric;
use rtpipe_model::{Server, Spec};
use std::collections::HashMap;

/// The master problem and its bookkeeping.
pub(crate) struct Master<'a> {
    pub(crate) spec: &'a Spec,
    pub(crate) g: i64,
    pub(crate) dom: Vec<Dom>,
    pub(crate) lp: Lp,
    /// Period expression per task (grid units).
    pub(crate) period: Vec<Lin>,
    /// Grid variable k per Grid task; choice binaries per Choice task.
    pub(crate) kvar: Vec<Option<usize>>,
    pub(crate) yvars: Vec<Vec<usize>>,
    /// Utilisation (and hyperbolic log term) per task.
    pub(crate) util: Vec<Lin>,
    pub(crate) uvar: Vec<Option<usize>>,
    pub(crate) hlog: Vec<Lin>,
    pub(crate) hvar: Vec<Option<usize>>,
    pub(crate) lt_cache: HashMap<(usize, usize, bool), Bin>,
    pub(crate) big_m: f64,
    /// Response-time variables (sound mode, RM).
    pub(crate) rvar: Vec<Option<usize>>,
    /// Read-to-publish variables (W ≤ R) where they can be below R: under
    /// EDF (`sound::read_response`).
    pub(crate) wvar: Vec<Option<usize>>,
    /// Valid lower ends of option variables (for their big-Ms).
    pub(crate) floor: HashMap<usize, f64>,
    /// Declare the option variables' bounds (see `sound_chain`).
    pub(crate) tight_bounds: bool,
    /// Every chain bound added, as the model writes it.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) chains: Vec<ChainExpr>,
}

impl<'a> Master<'a> {
    pub(crate) fn guaranteed(&self, i: usize) -> bool {
        self.spec.tasks[i].server != Server::Background
    }

    pub(crate) fn lt(&mut self, a: usize, b: usize, tie_true: bool) -> Bin {
        if let Some(&bin) = self.lt_cache.get(&(a, b, tie_true)) {
            return bin;
        }
        let (da, db) = (&self.dom[a], &self.dom[b]);
        // 1 ⟺ T_a < T_b, or T_a = T_b and tie_true.
        let bin = if da.max() < db.min() || (tie_true && da.max() <= db.min()) {
            Bin::Const(true)
        } else if da.min() > db.max() || (!tie_true && da.min() >= db.max()) {
            Bin::Const(false)
        } else {
            let z = self.lp.binary();
            let d1 = if tie_true { 0.0 } else { 1.0 };
            let d0 = if tie_true { 1.0 } else { 0.0 };
            // z = 1 ⇒ T_a − T_b ≤ −d1;  z = 0 ⇒ T_a − T_b ≥ d0, with the
            // smallest big-M that the period domains allow.
            let diff = self.period[a].plus(&self.period[b].scale(-1.0));
            let (hi, lo) = ((da.max() - db.min()) as f64, (da.min() - db.max()) as f64);
            let m1 = (hi + d1).max(0.0);
            let m0 = (d0 - lo).max(0.0);
            let mut t = diff.terms.clone();
            t.push((z, m1));
            self.lp.row(t, Cmp::Le, -d1 - diff.c + m1);
            let mut t = diff.terms.clone();
            t.push((z, m0));
            self.lp.row(t, Cmp::Ge, d0 - diff.c);
            Bin::Var(z)
        };
        self.lt_cache.insert((a, b, tie_true), bin);
        bin
    }

    /// A binary b with b = 1 ⇒ T_j ≥ tj + 1 ("the period of j grew past its
    /// value in a cut"); `None` when it cannot grow.
    pub(crate) fn grew(&mut self, j: usize, tj: i64) -> Option<usize> {
        if matches!(self.dom[j], Dom::Fixed(_)) || self.dom[j].max() <= tj {
            return None;
        }
        let b = self.lp.binary();
        let p = self.period[j].clone();
        let mut t = p.terms.clone();
        t.push((b, -self.big_m));
        self.lp.row(t, Cmp::Ge, (tj + 1) as f64 - p.c - self.big_m);
        Some(b)
    }

    /// A binary b with b = 1 ⇒ T_j ≤ tj − 1 ("the period of j shrank below
    /// its value in a cut"); `None` when it cannot shrink.
    pub(crate) fn shrank(&mut self, j: usize, tj: i64) -> Option<usize> {
        if matches!(self.dom[j], Dom::Fixed(_)) || self.dom[j].min() >= tj {
            return None;
        }
        let b = self.lp.binary();
        let p = self.period[j].clone();
        let mut t = p.terms.clone();
        t.push((b, self.big_m));
        self.lp.row(t, Cmp::Le, (tj - 1) as f64 - p.c + self.big_m);
        Some(b)
    }

    /// RM priority: a ≻ b.
    pub(crate) fn above(&mut self, a: usize, b: usize) -> Bin {
        self.lt(a, b, a < b)
    }

    /// Adds `lhs ≥ opt − M·(Σ off)` where `off` are 0/1 expressions that
    /// switch the option off when 1.
    pub(crate) fn ge_option(&mut self, lhs: usize, opt: &Lin, off: &[(Bin, bool)]) {
        // Switched off, the row must allow every value: M ≥ max(opt) − min(lhs).
        // (One grid unit of slack keeps microlp's pivots away from degenerate ties.)
        let lo = self
            .floor
            .get(&lhs)
            .copied()
            .unwrap_or(self.lp.vars[lhs].lo);
        let m = (opt.max_in(&self.lp) - lo + 1.0).clamp(1.0, self.big_m);
        let mut terms: Vec<(usize, f64)> = vec![(lhs, 1.0)];
        terms.extend(opt.terms.iter().map(|&(v, a)| (v, -a)));
        let mut rhs = opt.c;
        for &(b, negate) in off {
            // negate = false: off when b = 1; negate = true: off when b = 0.
            match (b, negate) {
                (Bin::Const(v), false) => {
                    if v {
                        return;
                    }
                }
                (Bin::Const(v), true) => {
                    if !v {
                        return;
                    }
                }
                (Bin::Var(z), false) => terms.push((z, m)),
                (Bin::Var(z), true) => {
                    terms.push((z, -m));
                    rhs -= m;
                }
            }
        }
        self.lp.row(terms, Cmp::Ge, rhs);
    }
}

/// A chain's bound as the model writes it, for the test that the encoding
/// agrees with the analysis: paper mode one sum; sound mode the sums E
/// (reaction) and F (freshness), both from the head's release, reaction
/// being min(E, F).
#[cfg_attr(not(test), allow(dead_code))]
#[derive(Debug, Clone)]
pub(crate) struct ChainExpr {
    pub(crate) chain: usize,
    pub(crate) metric: Metric,
    pub(crate) sums: Vec<Lin>,
}

impl<'a> Master<'a> {
    /// An empty master over the problem's domains.
    pub(crate) fn new(p: &Problem<'a>) -> Self {
        let n = p.spec.tasks.len();
        Master {
            spec: p.spec,
            g: p.g,
            dom: p.dom.clone(),
            lp: Lp::default(),
            period: Vec::with_capacity(n),
            kvar: vec![None; n],
            yvars: vec![Vec::new(); n],
            util: Vec::with_capacity(n),
            uvar: vec![None; n],
            hlog: Vec::with_capacity(n),
            hvar: vec![None; n],
            lt_cache: HashMap::new(),
            big_m: p.big_m,
            rvar: vec![None; n],
            wvar: vec![None; n],
            floor: HashMap::new(),
            tight_bounds: p.opts.solver == SolverKind::Highs,
            chains: Vec::new(),
        }
    }

    /// T_i ≥ r.
    pub(crate) fn at_most_period(&mut self, i: usize, r: usize) {
        let mut t = self.period[i].terms.clone();
        t.push((r, -1.0));
        self.lp.row(t, Cmp::Ge, -self.period[i].c);
    }
}
