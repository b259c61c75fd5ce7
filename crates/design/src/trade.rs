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
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};

/// Pairs tried per call: each costs a few dozen analyses (the other
/// task's period by steps and bisection, then the chains' tasks
/// lengthened), and the calls come at the dives' cadence, so the pairs
/// are dealt out over the calls.
const TRADES_PER_CALL: usize = 8;

/// A trial's period falls by this factor per step until it verifies.
const STEP_DOWN: f64 = 0.8;

/// Steps down at most before a trial gives up.
const MAX_STEPS: usize = 24;

/// Where the trades stand: the next pair to try, and how many pairs in a
/// row found nothing from the incumbent of U `at`. Once every pair has
/// failed from one incumbent, trading waits for another (a dive's or a
/// guided design), instead of repeating analyses that cannot succeed.
#[derive(Debug, Default)]
pub(crate) struct Trades {
    cursor: usize,
    fruitless: usize,
    at: f64,
}

impl Examiner<'_, '_> {
    /// Up to [`TRADES_PER_CALL`] trades from the incumbent `best`, the
    /// next pair of [`Examiner::trade_pairs`] (cyclically) first. A
    /// verified design better than `best`, if found.
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
            (state.at, state.fruitless) = (best.2, 0);
        }
        let mut k = self.indices(&best.0);
        let pairs = self.trade_pairs(&k);
        if state.fruitless >= pairs.len() || !self.verify(&k).2 {
            return None;
        }
        let mut u = self.bound(&k);
        let mut better = false;
        for _ in 0..TRADES_PER_CALL.min(pairs.len()) {
            if budget.out_of_time() {
                break;
            }
            let (a, b) = pairs[state.cursor % pairs.len()];
            state.cursor += 1;
            state.fruitless += 1;
            if let Some(t) = self.trade_one(&k, (a, b), budget) {
                let v = self.bound(&t);
                if v < u * (1.0 - 1e-9) {
                    (k, u, better, state.fruitless) = (t, v, true, 0);
                }
            }
        }
        if !better {
            return None;
        }
        let (spec, report, ok) = self.verify(&k);
        assert!(ok, "a traded design no longer verifies");
        let u = utilization(&spec);
        (u < best.2).then_some((spec, report, u))
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
        for i in self.chain_mates(a, b) {
            if budget.out_of_time() {
                break;
            }
            t[i] = self.lengthen(&mut t.clone(), i);
        }
        Some(t)
    }

    /// The tasks on a chain with `a` or with `b`, in index order.
    fn chain_mates(&self, a: usize, b: usize) -> Vec<usize> {
        let mut mates: Vec<usize> = self
            .p
            .spec
            .chains
            .iter()
            .filter(|c| c.path.contains(&a) || c.path.contains(&b))
            .flat_map(|c| c.path.iter().copied())
            .collect();
        mates.sort_unstable();
        mates.dedup();
        mates
    }
}
