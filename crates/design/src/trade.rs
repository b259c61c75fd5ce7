//! Better incumbents by trading periods between two tasks of a chain: one
//! task goes to its longest period and the other to the longest period
//! that then verifies, and the chains' tasks are lengthened again.
//!
//! The dives and the guided designs only shorten periods from a box's
//! corner and lengthen them one at a time, and the descent's pair moves
//! go one rung at a time: none of them crosses the point where two tasks
//! of a chain swap priorities (a response time jumps there), so in sound
//! mode they stop at designs where the light task of a link runs slow and
//! the heavy one fast. Each candidate is verified by the analysis and only
//! a better one replaces the incumbent, so the search stays exact.

use crate::api::utilization;
use crate::bnb::Examiner;
use crate::budget::Budget;
use rayon::prelude::*;
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};

/// Pairs tried per call, all from one point and in parallel: each costs a
/// few dozen analyses (the other task's period by steps and bisection,
/// then the chains' tasks lengthened), and the calls come at the dives'
/// cadence, so the pairs are dealt out over the calls.
const TRADES_PER_CALL: usize = 8;

/// A trial's period falls by this factor per step until it verifies.
const STEP_DOWN: f64 = 0.8;

/// Steps down at most before a trial gives up.
const MAX_STEPS: usize = 24;

/// Kicks in a row from one incumbent at most, each followed by the
/// trades from it, before the trades wait for another incumbent (a
/// dive's or a guided design): a search bounded by work must not repeat
/// analyses that find nothing forever.
const KICKS_PER_INCUMBENT: usize = 256;

/// Where the trades stand: the point they walk from (the incumbent of U
/// `at`, or a kick from it), the next pair to try, and how many pairs in
/// a row found nothing from that point. Once every pair has failed, the
/// incumbent is kicked ([`Examiner::kick`]) and the trades walk from
/// there; after [`KICKS_PER_INCUMBENT`] kicks that bring nothing better,
/// trading waits for another incumbent.
#[derive(Debug, Default)]
pub(crate) struct Trades {
    cursor: usize,
    fruitless: usize,
    at: f64,
    /// A kicked point and its U, where the trades walk instead of from
    /// the incumbent (`None`: from the incumbent).
    walker: Option<(Vec<u32>, f64)>,
    /// Kicks drawn so far (the next kick's number).
    kicks: u64,
    /// Kicks since the incumbent last changed.
    idle_kicks: usize,
}

impl Trades {
    /// Every pair has failed from the incumbent and from each of its
    /// kicks: nothing is left to try until another incumbent.
    pub(crate) fn is_spent(&self) -> bool {
        self.walker.is_none()
            && self.fruitless == usize::MAX
            && self.idle_kicks >= KICKS_PER_INCUMBENT
    }

    /// Kicks drawn so far.
    #[cfg(test)]
    pub(crate) fn kicks(&self) -> u64 {
        self.kicks
    }
}

impl Examiner<'_, '_> {
    /// Up to [`TRADES_PER_CALL`] trades from the walking point (the
    /// incumbent `best` or a kick from it), the next pair of
    /// [`Examiner::trade_pairs`] (cyclically) first; or, when every pair
    /// has failed there, a kick. A verified design better than `best`,
    /// if found.
    pub(crate) fn trade(
        &self,
        best: &(Spec, Report, f64),
        state: &mut Trades,
        budget: &Budget,
    ) -> Option<(Spec, Report, f64)> {
        if self.p.spec.harmonic || self.p.spec.event_triggered() {
            return None;
        }
        if best.2 != state.at {
            (state.at, state.fruitless, state.idle_kicks) = (best.2, 0, 0);
            state.walker = None;
        }
        if state.is_spent() {
            return None;
        }
        let from = self.indices(&best.0);
        let (mut k, mut u) = match &state.walker {
            Some((k, u)) => (k.clone(), *u),
            None if self.verify(&from).2 => (from.clone(), self.bound(&from)),
            None => return None,
        };
        let pairs = self.trade_pairs(&k);
        if state.fruitless >= pairs.len() {
            (k, u) = self.kicked(&from, state, budget)?;
        } else {
            match self.trade_batch(&k, u, &pairs, state, budget) {
                Some((t, v)) => (k, u, state.fruitless) = (t, v, 0),
                None => state.fruitless += TRADES_PER_CALL.min(pairs.len()),
            }
            if state.walker.is_some() {
                state.walker = Some((k.clone(), u));
            }
        }
        if u >= best.2 * (1.0 - 1e-9) {
            return None;
        }
        let (spec, report, ok) = self.verify(&k);
        assert!(ok, "a traded design no longer verifies");
        let u = utilization(&spec);
        (u < best.2).then_some((spec, report, u))
    }

    /// The next [`TRADES_PER_CALL`] pairs (cyclically from the cursor),
    /// each traded from `k` (of U `u`) in parallel: the best trade below
    /// `u` (the first in the pairs' order among equals, so the answer is
    /// the same on any number of threads), if any.
    fn trade_batch(
        &self,
        k: &[u32],
        u: f64,
        pairs: &[(usize, usize)],
        state: &mut Trades,
        budget: &Budget,
    ) -> Option<(Vec<u32>, f64)> {
        let batch: Vec<(usize, usize)> = (0..TRADES_PER_CALL.min(pairs.len()))
            .map(|j| pairs[(state.cursor + j) % pairs.len()])
            .collect();
        state.cursor += batch.len();
        let traded: Vec<Option<(Vec<u32>, f64)>> = batch
            .into_par_iter()
            .map(|pair| {
                let t = self.trade_one(k, pair, budget)?;
                let v = self.bound(&t);
                Some((t, v))
            })
            .collect();
        traded
            .into_iter()
            .flatten()
            .filter(|(_, v)| *v < u * (1.0 - 1e-9))
            .min_by(|x, y| x.1.total_cmp(&y.1))
    }

    /// The next kick from the incumbent `from`, made the walking point
    /// (with its U); `None` once the incumbent has had its kicks. A kick
    /// whose repair fails leaves the walker at the incumbent, so the next
    /// call kicks again.
    fn kicked(&self, from: &[u32], state: &mut Trades, budget: &Budget) -> Option<(Vec<u32>, f64)> {
        if state.idle_kicks >= KICKS_PER_INCUMBENT {
            (state.walker, state.fruitless) = (None, usize::MAX);
            return None;
        }
        state.idle_kicks += 1;
        state.kicks += 1;
        let k = self.kick(from, state.kicks, budget);
        state.walker = k.map(|k| {
            let u = self.bound(&k);
            (k, u)
        });
        // Every pair has failed from the incumbent: without a walker the
        // next call kicks again.
        state.fruitless = if state.walker.is_some() {
            0
        } else {
            usize::MAX
        };
        state.walker.clone()
    }

    /// Every ordered pair (a, b) of distinct tasks on a common chain where
    /// `a` can still lengthen its period, the largest saving `C_a/T_a −
    /// C_a/T_a,max` first (ties by index, so the order is the same on
    /// every run).
    fn trade_pairs(&self, k: &[u32]) -> Vec<(usize, usize)> {
        let mut pairs = Vec::new();
        for chain in &self.p.spec.chains {
            for &a in &chain.path {
                for &b in &chain.path {
                    if a != b && k[a] + 1 < self.axes[a].len() {
                        pairs.push((a, b));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let saving = |a: usize| {
            let c = self.p.spec.tasks[a].budget() as f64;
            let longest = self.axes[a].value(self.axes[a].len() - 1);
            c / self.axes[a].value(k[a]) as f64 - c / longest as f64
        };
        pairs.sort_by(|x, y| saving(y.0).total_cmp(&saving(x.0)).then(x.cmp(y)));
        pairs
    }

    /// `a` at its longest period and `b` at the longest period at most its
    /// own in `k` that then verifies (steps down, then bisection), then
    /// the tasks of their chains lengthened; `None` when no such period
    /// verifies. The answer verifies.
    fn trade_one(&self, k: &[u32], (a, b): (usize, usize), budget: &Budget) -> Option<Vec<u32>> {
        let mut t = k.to_vec();
        t[a] = self.axes[a].len() - 1;
        // `failed` does not verify (or is past b's own index) and every
        // index tried below it so far failed too.
        let (mut failed, mut at, mut ok) = (k[b] + 1, k[b], None);
        for _ in 0..MAX_STEPS {
            if budget.out_of_time() {
                return None;
            }
            t[b] = at;
            if self.verify(&t).2 {
                ok = Some(at);
                break;
            }
            failed = at;
            let shorter = (self.axes[b].value(at) as f64 * STEP_DOWN) as Nanos;
            match self.axes[b].last_at_most(shorter) {
                Some(next) if next < at => at = next,
                _ => return None,
            }
        }
        let mut ok = ok?;
        while failed - ok > 1 {
            let m = ok + (failed - ok) / 2;
            t[b] = m;
            if self.verify(&t).2 {
                ok = m;
            } else {
                failed = m;
            }
        }
        t[b] = ok;
        self.lengthen_chain_mates(&mut t, &[a, b], budget);
        Some(t)
    }

    /// Each task on a chain with any of `tasks`, in index order,
    /// lengthened in `t` ([`Examiner::lengthen`]; `t` verifies, and so
    /// does it after) while `budget` has time.
    pub(crate) fn lengthen_chain_mates(&self, t: &mut [u32], tasks: &[usize], budget: &Budget) {
        for i in self.chain_mates_of(tasks) {
            if budget.out_of_time() {
                break;
            }
            self.lengthen(t, i);
        }
    }

    /// The tasks on a chain with any of `tasks`, in index order.
    pub(crate) fn chain_mates_of(&self, tasks: &[usize]) -> Vec<usize> {
        let mut mates: Vec<usize> = self
            .p
            .spec
            .chains
            .iter()
            .filter(|c| c.path.iter().any(|i| tasks.contains(i)))
            .flat_map(|c| c.path.iter().copied())
            .collect();
        mates.sort_unstable();
        mates.dedup();
        mates
    }
}
