//! A perturbation of the incumbent for the trades to walk from, once
//! every trade from it has failed: a group of consecutive tasks of one
//! chain moves its periods by one factor (longer or shorter), the other
//! tasks of the chains it is on are repaired (scaled down together until
//! the design verifies) and then lengthened again.
//!
//! The trades move two tasks at a time and stop at a design where every
//! such move fails; which one depends on where they start (the search's
//! path: a dive's or a guided design). A kick moves a whole group, so
//! the trades that follow from it reach other local minima. Each kick is
//! drawn from a counter (no clock, no thread), so the search stays
//! deterministic; every design it yields is verified by the analysis.

use crate::bnb::Examiner;
use crate::budget::Budget;
use rtpipe_model::gen::splitmix_at;
use rtpipe_model::Nanos;

/// The factors a kicked group's periods are multiplied by.
const FACTORS: [f64; 6] = [0.5, 0.7, 1.4, 2.0, 3.0, 4.0];

/// Each repair step scales the repaired tasks' periods by this, from the
/// incumbent's.
const REPAIR_STEP: f64 = 0.85;

/// Repair steps at most before the kick gives up.
const REPAIR_STEPS: i32 = 20;

impl Examiner<'_, '_> {
    /// Kick number `n` from the verified point `from`: a verified point
    /// (its indices), or `None` when the repair found none.
    pub(crate) fn kick(&self, from: &[u32], n: u64, budget: &Budget) -> Option<Vec<u32>> {
        let chains: Vec<&[usize]> = (self.p.spec.chains.iter())
            .map(|c| c.path.as_slice())
            .filter(|p| p.len() >= 2)
            .collect();
        if chains.is_empty() {
            return None;
        }
        let draw = |j: u64| splitmix_at(n.wrapping_mul(4).wrapping_add(j)) as usize;
        let path = chains[draw(0) % chains.len()];
        let start = draw(1) % path.len();
        let len = 1 + draw(2) % (path.len() - start);
        let group = &path[start..start + len];
        let factor = FACTORS[draw(3) % FACTORS.len()];
        let mut t = from.to_vec();
        for &i in group {
            t[i] = self.at_about(i, self.axes[i].value(from[i]) as f64 * factor);
        }
        let repaired: Vec<usize> = (self.chain_mates_of(group).into_iter())
            .filter(|i| !group.contains(i))
            .collect();
        let mut step = 0;
        while !self.verify(&t).2 {
            step += 1;
            if step > REPAIR_STEPS || repaired.is_empty() || budget.out_of_time() {
                return None;
            }
            let scale = REPAIR_STEP.powi(step);
            for &i in &repaired {
                t[i] = self.at_about(i, self.axes[i].value(from[i]) as f64 * scale);
            }
        }
        self.lengthen_chain_mates(&mut t, group, budget);
        Some(t)
    }

    /// Task i's period index nearest below `period` (ns) on its axis, its
    /// first where `period` is below them all.
    fn at_about(&self, i: usize, period: f64) -> u32 {
        self.axes[i].last_at_most(period as Nanos).unwrap_or(0)
    }
}
