//! `harmonic = true` in the box search: every pair of periods divides one
//! way. The domains already hold only values harmonic with every fixed
//! period (`domain::harmonic_domains`); what is left is the pairs of free
//! tasks. A point that breaks a pair is not a design, so its box is split
//! on the tasks of a broken pair; a task whose interval is one value keeps
//! the others to the values harmonic with it.

use crate::axis::{Axis, Node};
use crate::domain::harmonic_pair;
use rtpipe_model::Nanos;

/// Whether every pair of `periods` divides one way.
pub(crate) fn all_pairs(periods: &[Nanos]) -> bool {
    periods
        .iter()
        .enumerate()
        .all(|(a, &p)| periods[a + 1..].iter().all(|&q| harmonic_pair(p, q)))
}

/// The tasks of some pair of `periods` that does not divide one way.
pub(crate) fn broken(periods: &[Nanos]) -> Vec<bool> {
    let mut out = vec![false; periods.len()];
    for (a, &p) in periods.iter().enumerate() {
        for (b, &q) in periods.iter().enumerate().skip(a + 1) {
            if !harmonic_pair(p, q) {
                out[a] = true;
                out[b] = true;
            }
        }
    }
    out
}

/// Keeps every interval's ends on values harmonic with each task whose
/// interval is a single value, until nothing moves; false when an interval
/// empties. Interior values are left (an interval cannot skip them); the
/// corner check rejects them.
pub(crate) fn propagate(axes: &[Axis], node: &mut Node) -> bool {
    let n = axes.len();
    let mut done = vec![false; n];
    loop {
        let Some(i) = (0..n).find(|&i| !done[i] && node.lo[i] == node.hi[i]) else {
            return true;
        };
        done[i] = true;
        let v = axes[i].value(node.lo[i]);
        for j in (0..n).filter(|&j| j != i) {
            let fits = |k: u32| harmonic_pair(axes[j].value(k), v);
            let Some(lo) = (node.lo[j]..=node.hi[j]).find(|&k| fits(k)) else {
                return false;
            };
            let hi = (lo..=node.hi[j]).rev().find(|&k| fits(k)).unwrap_or(lo);
            node.lo[j] = lo;
            node.hi[j] = hi;
        }
    }
}

/// The indices above `k[i]` on task i's axis whose value is harmonic with
/// every other period of `k`, ascending: where a harmonic design may move
/// task i's period without breaking a pair.
pub(crate) fn moves_up(axes: &[Axis], k: &[u32], i: usize) -> Vec<u32> {
    let others: Vec<Nanos> = (0..k.len())
        .filter(|&j| j != i)
        .map(|j| axes[j].value(k[j]))
        .collect();
    (k[i] + 1..axes[i].len())
        .filter(|&x| {
            let v = axes[i].value(x);
            others.iter().all(|&q| harmonic_pair(v, q))
        })
        .collect()
}

/// A harmonic point at or below `periods` (ns) on the axes: tasks from the
/// shortest period up each take the longest value of their axis at most
/// their period and harmonic with every one taken so far (the shortest
/// such value above it when none is below). `None` when some task has no
/// value harmonic with those before it.
pub(crate) fn round_down(axes: &[Axis], periods: &[Nanos]) -> Option<Vec<u32>> {
    let mut order: Vec<usize> = (0..axes.len()).collect();
    order.sort_by_key(|&i| (periods[i], i));
    let mut k = vec![0u32; axes.len()];
    let mut taken: Vec<Nanos> = Vec::new();
    for i in order {
        let fits = |x: &u32| {
            let v = axes[i].value(*x);
            taken.iter().all(|&q| harmonic_pair(v, q))
        };
        let top = axes[i].last_at_most(periods[i]);
        let below = top.and_then(|t| (0..=t).rev().find(fits));
        let above = || (top.map_or(0, |t| t + 1)..axes[i].len()).find(fits);
        k[i] = below.or_else(above)?;
        taken.push(axes[i].value(k[i]));
    }
    debug_assert!(all_pairs(
        &k.iter()
            .zip(axes)
            .map(|(&x, a)| a.value(x))
            .collect::<Vec<_>>()
    ));
    Some(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn list(v: &[Nanos]) -> Axis {
        Axis::List(v.to_vec())
    }

    #[test]
    fn pairs_and_the_tasks_that_break_them() {
        assert!(all_pairs(&[5, 10, 20, 40]));
        assert!(!all_pairs(&[5, 10, 15]));
        assert_eq!(broken(&[5, 10, 15, 30]), vec![false, true, true, false]);
    }

    #[test]
    fn a_single_value_keeps_the_other_ends_harmonic_with_it() {
        let axes = [list(&[10]), list(&[3, 5, 7, 20, 30, 40, 45])];
        let mut node = Node {
            lo: vec![0, 0],
            hi: vec![0, 6],
            above: Vec::new(),
            shares: Default::default(),
            bound: 0.0,
        };
        assert!(propagate(&axes, &mut node));
        // 5 and 40 are the first and last that divide or are divided by 10.
        assert_eq!((node.lo[1], node.hi[1]), (1, 5));
        let axes = [list(&[10]), list(&[3, 7, 45])];
        let mut node = Node {
            lo: vec![0, 0],
            hi: vec![0, 2],
            above: Vec::new(),
            shares: Default::default(),
            bound: 0.0,
        };
        assert!(!propagate(&axes, &mut node));
    }

    #[test]
    fn round_down_and_moves_up_stay_harmonic() {
        let axes = [
            list(&[4, 5, 8, 10]),
            list(&[10, 12, 20, 30, 40]),
            list(&[25, 40, 60, 80]),
        ];
        // 5, then the longest ≤ 30 harmonic with 5: 30 (divisible), then
        // ≤ 60 harmonic with 5 and 30: 60.
        let k = round_down(&axes, &[5, 30, 60]);
        assert_eq!(k, Some(vec![1, 3, 2]));
        // Task 0 may rise from 5 to 10 (harmonic with 30 and 60); not 8.
        assert_eq!(moves_up(&axes, &[1, 3, 2], 0), vec![3]);
        // Nothing at or below 3 for task 0: its shortest harmonic value.
        assert_eq!(round_down(&axes, &[3, 40, 80]), Some(vec![0, 4, 3]));
    }
}
