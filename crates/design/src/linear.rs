//! Linear expressions over the master problem's variables, and binaries
//! that may be known constants.

use crate::lp::Lp;

/// A linear expression in grid units: Σ coeff·var + constant.
#[derive(Debug, Clone, Default)]
pub(crate) struct Lin {
    pub(crate) terms: Vec<(usize, f64)>,
    pub(crate) c: f64,
}

impl Lin {
    pub(crate) fn constant(c: f64) -> Lin {
        Lin {
            terms: Vec::new(),
            c,
        }
    }
    pub(crate) fn plus(&self, o: &Lin) -> Lin {
        let mut terms = self.terms.clone();
        terms.extend_from_slice(&o.terms);
        Lin {
            terms,
            c: self.c + o.c,
        }
    }
    pub(crate) fn add_c(&self, c: f64) -> Lin {
        Lin {
            terms: self.terms.clone(),
            c: self.c + c,
        }
    }
    /// The largest and smallest values over the variables' bounds.
    pub(crate) fn max_in(&self, lp: &Lp) -> f64 {
        self.c
            + self
                .terms
                .iter()
                .map(|&(v, a)| (a * lp.vars[v].lo).max(a * lp.vars[v].hi))
                .sum::<f64>()
    }
    pub(crate) fn min_in(&self, lp: &Lp) -> f64 {
        self.c
            + self
                .terms
                .iter()
                .map(|&(v, a)| (a * lp.vars[v].lo).min(a * lp.vars[v].hi))
                .sum::<f64>()
    }
    /// The value at a solution.
    pub(crate) fn eval(&self, values: &[f64]) -> f64 {
        self.terms.iter().map(|&(v, a)| a * values[v]).sum::<f64>() + self.c
    }
    pub(crate) fn scale(&self, k: f64) -> Lin {
        Lin {
            terms: self.terms.iter().map(|&(v, a)| (v, a * k)).collect(),
            c: self.c * k,
        }
    }
}

/// A binary that may be a known constant.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Bin {
    Const(bool),
    Var(usize),
}
