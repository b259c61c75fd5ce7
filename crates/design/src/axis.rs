//! The box search's geometry: the period values one task may take (an
//! axis) and a box of them (a node of the search).

use crate::domain::Dom;
use crate::joint::Shares;
use rtpipe_model::Nanos;
use std::cmp::Ordering as CmpOrdering;

/// The period values (ns) one task may take, ascending.
#[derive(Debug, Clone)]
pub(crate) enum Axis {
    /// `first + k·step` for k in 0..len.
    Grid {
        first: Nanos,
        step: Nanos,
        len: u32,
    },
    List(Vec<Nanos>),
}

impl Axis {
    pub(crate) fn new(d: &Dom, g: i64) -> Axis {
        match d {
            Dom::Fixed(t) => Axis::List(vec![t * g]),
            Dom::Grid { step, lo, hi } => Axis::Grid {
                first: lo * step * g,
                step: step * g,
                len: u32::try_from(hi - lo + 1).unwrap_or(u32::MAX),
            },
            Dom::Choice(v) => {
                let mut v: Vec<Nanos> = v.iter().map(|t| t * g).collect();
                v.sort_unstable();
                v.dedup();
                Axis::List(v)
            }
        }
    }

    pub(crate) fn len(&self) -> u32 {
        match self {
            Axis::Grid { len, .. } => *len,
            Axis::List(v) => v.len() as u32,
        }
    }

    pub(crate) fn value(&self, k: u32) -> Nanos {
        debug_assert!(k < self.len());
        match self {
            Axis::Grid { first, step, .. } => first + step * Nanos::from(k),
            Axis::List(v) => v[k as usize],
        }
    }

    /// The last index whose value is at most `t` (`None` when none).
    pub(crate) fn last_at_most(&self, t: Nanos) -> Option<u32> {
        let k = match self {
            Axis::Grid { first, step, len } => {
                if t < *first {
                    return None;
                }
                ((t - first) / step).min(Nanos::from(*len) - 1) as u32
            }
            Axis::List(v) => (v.partition_point(|&x| x <= t) as u32).checked_sub(1)?,
        };
        Some(k)
    }

    /// The first index whose value is at least `t` (`len` when none).
    pub(crate) fn first_at_least(&self, t: f64) -> u32 {
        match self {
            Axis::Grid { first, step, len } => {
                let k = ((t - *first as f64) / *step as f64).ceil().max(0.0);
                if k >= f64::from(*len) {
                    *len
                } else {
                    k as u32
                }
            }
            Axis::List(v) => v.partition_point(|&x| (x as f64) < t) as u32,
        }
    }
}

/// A box: index intervals per task, with its bound Σ C/hi.
#[derive(Debug, Clone)]
pub(crate) struct Node {
    pub(crate) lo: Vec<u32>,
    pub(crate) hi: Vec<u32>,
    /// RM rank orders imposed by branching: (a, b) = a above b.
    pub(crate) above: Vec<(usize, usize)>,
    pub(crate) bound: f64,
    /// The budget shares its split bound ended with, where its sub-boxes'
    /// ascent starts.
    pub(crate) shares: Shares,
}

impl Node {
    /// The heap memory of the box: the node, its index vectors and imposed
    /// orders, and an allocator's header per vector.
    pub(crate) fn bytes(&self) -> usize {
        const HEADER: usize = 16;
        std::mem::size_of::<Node>()
            + self.lo.capacity() * 4
            + self.hi.capacity() * 4
            + self.above.capacity() * std::mem::size_of::<(usize, usize)>()
            + self.shares.bytes()
            + 4 * HEADER
    }
}

impl PartialEq for Node {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == CmpOrdering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<CmpOrdering> {
        Some(self.cmp(o))
    }
}
impl Ord for Node {
    /// The heap pops the smallest bound first.
    fn cmp(&self, o: &Self) -> CmpOrdering {
        o.bound.total_cmp(&self.bound)
    }
}
