//! Budget servers of the execution model (Section II-B), as state machines
//! over integer nanoseconds. The simulator calls them; they never look at
//! the clock themselves.
//!
//! - [`Sporadic`]: Main VCPU, the sporadic server with the corrected POSIX
//!   rules (Stanovich, Baker, Wang, González Harbour, RTAS 2010), in the form
//!   Quest and seL4 implement: a bounded queue of replenishments `(time,
//!   amount)` whose amounts always sum to C, and the `usage` charged against
//!   the head.
//! - [`Pibs`]: I/O VCPU, the priority-inheritance bandwidth-preserving server
//!   of Quest: one replenishment, eligibility pushed back by usage / U.
//! - [`Cbs`]: a constant-bandwidth server as Linux SCHED_DEADLINE runs it.

use rtpipe_model::Nanos;
use std::collections::VecDeque;

/// One replenishment: `amount` of budget usable from `time` on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Refill {
    /// When the budget becomes usable.
    pub time: Nanos,
    /// How much.
    pub amount: Nanos,
}

/// Quest bounds the replenishment queue at 32 entries.
pub const MAX_REFILLS: usize = 32;

/// Sporadic server (Main VCPU).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sporadic {
    /// Budget C.
    pub budget: Nanos,
    /// Period T.
    pub period: Nanos,
    /// Pending replenishments.
    pub queue: VecDeque<Refill>,
    /// Budget consumed from the head since it was last charged.
    pub usage: Nanos,
    /// The most entries the queue may hold.
    pub max_refills: usize,
}

impl Sporadic {
    /// Full budget available from `now`.
    pub fn new(budget: Nanos, period: Nanos, now: Nanos) -> Sporadic {
        let mut queue = VecDeque::with_capacity(MAX_REFILLS);
        queue.push_back(Refill {
            time: now,
            amount: budget,
        });
        Sporadic {
            budget,
            period,
            queue,
            usage: 0,
            max_refills: MAX_REFILLS,
        }
    }

    fn head(&self) -> Refill {
        // Every operation keeps at least one refill (their amounts sum to C):
        // an empty queue is a bug in this file, not a state to work around.
        match self.queue.front() {
            Some(h) => *h,
            None => unreachable!("sporadic server: empty replenishment queue"),
        }
    }

    /// Budget usable right now: head.amount − usage once the head is due.
    pub fn capacity(&self, now: Nanos) -> Nanos {
        let h = self.head();
        if h.time <= now {
            // Usage beyond the head is an overrun (the corrected POSIX
            // rules allow for them, and `charge` calls this right after
            // adding the usage): nothing is left, and Budget_Check pushes the
            // next refill back by the excess. Part of the rules, not a
            // repair; the simulator itself never overruns (it asserts so).
            (h.amount - self.usage).max(0)
        } else {
            0
        }
    }

    /// When the head becomes due (the replenishment timer).
    pub fn next_refill(&self) -> Nanos {
        self.head().time
    }

    /// Σ amounts (always the budget).
    pub fn total(&self) -> Nanos {
        self.queue.iter().map(|r| r.amount).sum()
    }

    /// Charges `ran` nanoseconds of execution; runs Budget_Check when the
    /// capacity is used up.
    pub fn charge(&mut self, now: Nanos, ran: Nanos) {
        self.usage += ran;
        if self.capacity(now) == 0 && self.usage > 0 {
            let left = self.budget_check();
            if left > 0 {
                self.usage = left;
                self.split_check();
            }
            self.usage = 0;
        }
    }

    /// Budget_Check: charge whole refills, re-queue each one period later;
    /// an overrun delays the next replenishment by the overrun. Returns the
    /// usage not yet dealt with.
    fn budget_check(&mut self) -> Nanos {
        let mut usage = self.usage;
        while self.head().amount <= usage && usage > 0 {
            usage -= self.head().amount;
            if self.queue.len() == 1 {
                if let Some(h) = self.queue.front_mut() {
                    h.time += self.period;
                }
            } else if let Some(mut h) = self.queue.pop_front() {
                h.time += self.period;
                self.queue.push_back(h);
            }
        }
        if usage > 0 {
            if let Some(h) = self.queue.front_mut() {
                h.time += usage;
            }
            self.merge_front_if_overlapping();
        }
        self.usage = 0;
        usage
    }

    fn merge_front_if_overlapping(&mut self) {
        if self.queue.len() > 1 {
            let h = self.head();
            let next_time = self.queue.get(1).map(|r| r.time).unwrap_or(Nanos::MAX);
            if h.time + h.amount >= next_time {
                self.queue.pop_front();
                if let Some(n) = self.queue.front_mut() {
                    n.amount += h.amount;
                }
            }
        }
    }

    /// Split_Check when the server blocks (or is charged a partial refill):
    /// the used part of the head is re-queued one period after the head's
    /// time; the remnant stays usable (or joins the next refill when the
    /// queue is full).
    fn split_check(&mut self) {
        let usage = self.usage;
        if usage <= 0 {
            return;
        }
        let h = self.head();
        let remnant = h.amount - usage;
        // A single refill that cannot be split (nothing left, or no room for
        // a second entry) moves whole to one period later.
        if self.queue.len() == 1 && (remnant <= 0 || self.max_refills <= 1) {
            if let Some(x) = self.queue.front_mut() {
                x.time += self.period;
            }
            self.usage = 0;
            return;
        }
        if self.queue.len() >= self.max_refills || remnant <= 0 {
            self.queue.pop_front();
            if let Some(n) = self.queue.front_mut() {
                n.amount += remnant;
            }
        } else if let Some(x) = self.queue.front_mut() {
            x.amount = remnant;
        }
        let t = self.head().time + self.period;
        self.queue.push_back(Refill {
            time: t,
            amount: usage,
        });
        self.usage = 0;
    }

    /// The server blocks (no pending job) at `now`.
    pub fn block(&mut self, now: Nanos) {
        if self.usage > 0 && self.head().time <= now {
            self.split_check();
        }
    }

    /// Unblock_Check: a job arrives at `now`. With capacity, the head starts
    /// now and refills due within that capacity merge into it.
    pub fn unblock(&mut self, now: Nanos) {
        if self.head().time <= now {
            if let Some(h) = self.queue.front_mut() {
                h.time = now;
            }
            while self.queue.len() > 1 {
                let amount = self.head().amount;
                let next = self.queue.get(1).map(|r| r.time).unwrap_or(Nanos::MAX);
                if next <= now + amount {
                    self.queue.pop_front();
                    if let Some(n) = self.queue.front_mut() {
                        n.amount += amount;
                        n.time = now;
                    }
                } else {
                    break;
                }
            }
        }
    }
}

/// Priority-inheritance bandwidth-preserving server (I/O VCPU, Quest).
///
/// The eligibility time advances by usage / U = usage · T / C, a rational
/// number of nanoseconds; it is kept exactly as e · C so rounding never gives
/// bandwidth away or takes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pibs {
    /// Budget C.
    pub budget: Nanos,
    /// Period T.
    pub period: Nanos,
    /// Eligibility time × C.
    eligible_scaled: i128,
    /// Budget left in the current replenishment.
    pub left: Nanos,
}

impl Pibs {
    /// A server with budget C and period T.
    pub fn new(budget: Nanos, period: Nanos) -> Pibs {
        Pibs {
            budget,
            period,
            eligible_scaled: 0,
            left: budget,
        }
    }

    /// The eligibility time, rounded up to a whole nanosecond.
    pub fn eligible(&self) -> Nanos {
        let c = self.budget as i128;
        ((self.eligible_scaled + c - 1).div_euclid(c)) as Nanos
    }

    /// A request arrives: e = max(e, now), budget C.
    pub fn unblock(&mut self, now: Nanos) {
        self.eligible_scaled = self.eligible_scaled.max(now as i128 * self.budget as i128);
        self.left = self.budget;
    }

    /// Budget usable now. A fresh replenishment waits for the eligibility
    /// time; once started, the server may use it all (running pushes the
    /// eligibility time ahead, which only bars the next replenishment).
    pub fn capacity(&self, now: Nanos) -> Nanos {
        // now ≥ ⌈eC / C⌉ ⇔ now·C ≥ eC (now is whole, C > 0): no 128-bit
        // division on a path every scheduling decision takes.
        let due = now as i128 * self.budget as i128 >= self.eligible_scaled;
        debug_assert_eq!(due, now >= self.eligible());
        if self.left < self.budget || due {
            self.left
        } else {
            0
        }
    }

    /// After running `ran`: e += ran / U = ran · T / C.
    pub fn charge(&mut self, _now: Nanos, ran: Nanos) {
        // The simulator runs a PIBS job only within its capacity.
        assert!(ran <= self.left, "PIBS overrun: ran {ran} of {}", self.left);
        self.left -= ran;
        self.eligible_scaled += ran as i128 * self.period as i128;
        if self.left <= 0 {
            // Exhausted: the next replenishment comes at the eligibility time.
            self.left = self.budget;
        }
    }

    /// When the server can run again (after an exhaustion).
    pub fn next_refill(&self) -> Nanos {
        self.eligible()
    }
}

/// Constant-bandwidth server (SCHED_DEADLINE): runtime C per period T,
/// scheduled by absolute deadline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cbs {
    /// Budget C.
    pub budget: Nanos,
    /// Period T.
    pub period: Nanos,
    /// Relative deadline D ≤ T (SCHED_DEADLINE's dl_deadline): a fresh
    /// deadline is D after the wake-up.
    pub relative_deadline: Nanos,
    /// The current absolute deadline.
    pub deadline: Nanos,
    /// Runtime left (negative after an overrun).
    pub runtime: Nanos,
    /// Throttled until this instant (runtime exhausted).
    pub throttled_until: Option<Nanos>,
}

impl Cbs {
    /// A server with budget C and period T, not yet woken (no runtime).
    pub fn new(budget: Nanos, period: Nanos) -> Cbs {
        Cbs::with_deadline(budget, period, period)
    }

    /// A server with budget C, period T and relative deadline D ≤ T, not
    /// yet woken.
    pub fn with_deadline(budget: Nanos, period: Nanos, deadline: Nanos) -> Cbs {
        Cbs {
            budget,
            period,
            relative_deadline: deadline,
            deadline: 0,
            runtime: 0,
            throttled_until: None,
        }
    }

    /// Wake-up rule: keep (deadline, runtime) only if the remaining runtime
    /// fits the remaining time at the reserved bandwidth, else start afresh:
    /// runtime / (deadline − now) > C / T ⇒ deadline = now + T, runtime = C.
    pub fn unblock(&mut self, now: Nanos) {
        if self.throttled_until.is_some() {
            return;
        }
        let late = self.deadline <= now;
        // Time left to the deadline, none once it has passed (then `late`
        // decides anyway): part of the rule, not a repair.
        // With D < T the density C / D stands for the bandwidth C / T.
        let overflow = (self.runtime as i128) * (self.relative_deadline as i128)
            > (self.budget as i128) * ((self.deadline - now).max(0) as i128);
        if late || overflow {
            self.deadline = now + self.relative_deadline;
            self.runtime = self.budget;
        }
    }

    /// Runtime usable at `now` (0 while throttled).
    pub fn capacity(&self, now: Nanos) -> Nanos {
        match self.throttled_until {
            Some(t) if now < t => 0,
            // As in the kernel, an overrun leaves runtime negative (the
            // deficit is paid back at the next replenishment) and nothing
            // usable; the simulator itself never overruns (it asserts so).
            _ => self.runtime.max(0),
        }
    }

    /// Consumes runtime; on depletion the server is throttled until its
    /// deadline, where it gets C again and a deadline one period later.
    pub fn charge(&mut self, _now: Nanos, ran: Nanos) {
        self.runtime -= ran;
        if self.runtime <= 0 {
            self.throttled_until = Some(self.deadline);
        }
    }

    /// The replenishment timer fired at `now` (≥ the deadline).
    pub fn replenish(&mut self, now: Nanos) {
        if let Some(t) = self.throttled_until {
            if now >= t {
                self.throttled_until = None;
                self.runtime += self.budget;
                self.deadline += self.period;
            }
        }
    }

    /// When the throttled server gets its budget back, if it is throttled.
    pub fn next_refill(&self) -> Option<Nanos> {
        self.throttled_until
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(s: &Sporadic) -> Vec<(Nanos, Nanos)> {
        s.queue.iter().map(|r| (r.time, r.amount)).collect()
    }

    #[test]
    fn sporadic_one_job_replenishes_a_period_after_arrival() {
        // C = 2, T = 10. A job arrives at 3, runs 1 and blocks at 4.
        let mut s = Sporadic::new(2, 10, 0);
        s.unblock(3);
        assert_eq!(q(&s), vec![(3, 2)]);
        assert_eq!(s.capacity(3), 2);
        s.charge(4, 1);
        assert_eq!(s.capacity(4), 1);
        s.block(4);
        // Split: remnant 1 stays at 3, the used 1 returns at 3 + 10 = 13.
        assert_eq!(q(&s), vec![(3, 1), (13, 1)]);
        assert_eq!(s.total(), 2);
    }

    #[test]
    fn sporadic_exhaustion_requeues_whole_refill() {
        // C = 2, T = 10: arrive at 0, run 2 → capacity 0, refill at 10.
        let mut s = Sporadic::new(2, 10, 0);
        s.unblock(0);
        s.charge(2, 2);
        assert_eq!(s.capacity(2), 0);
        assert_eq!(q(&s), vec![(10, 2)]);
        assert_eq!(s.next_refill(), 10);
        assert_eq!(s.capacity(10), 2);
    }

    #[test]
    fn sporadic_unblock_merges_refills_due_within_capacity() {
        // Refills (0, 1) and (5, 1): arriving at 4 with capacity 1, the refill at
        // 5 ≤ 4 + 1 merges: (4, 2).
        let mut s = Sporadic::new(2, 10, 0);
        s.queue = VecDeque::from(vec![
            Refill { time: 0, amount: 1 },
            Refill { time: 5, amount: 1 },
        ]);
        s.unblock(4);
        assert_eq!(q(&s), vec![(4, 2)]);
    }

    #[test]
    fn sporadic_overrun_delays_next_refill() {
        // C = 4, T = 10, refills (0, 2) and (5, 2). A charge of 3 at time 3 overruns
        // the head by 1: the head's 2 returns at 10; the overrun delays the next
        // head 5 → 6 and, as seL4 does, is also split off it (used 1 back at 16).
        let mut s = Sporadic::new(4, 10, 0);
        s.queue = VecDeque::from(vec![
            Refill { time: 0, amount: 2 },
            Refill { time: 5, amount: 2 },
        ]);
        s.charge(3, 3);
        assert_eq!(q(&s), vec![(6, 1), (10, 2), (16, 1)]);
        assert_eq!(s.total(), 4);
    }

    #[test]
    fn sporadic_full_queue_merges_remnant_forward() {
        let mut s = Sporadic::new(4, 10, 0);
        s.max_refills = 2;
        s.queue = VecDeque::from(vec![
            Refill { time: 0, amount: 3 },
            Refill { time: 8, amount: 1 },
        ]);
        s.unblock(1);
        s.charge(2, 1);
        s.block(2);
        // Full: head popped, its remnant 2 joins (8, 1) → (8, 3); used 1 at 8 + 10.
        assert_eq!(q(&s), vec![(8, 3), (18, 1)]);
        assert_eq!(s.total(), 4);
    }

    /// Drives a server with a bursty client that runs a little, blocks, comes
    /// back (the pattern behind the POSIX defects of RTAS 2010: budget
    /// amplification by repeated short activations, and the full
    /// replenishment queue) and returns the instants of every executed unit.
    fn bursty(max_refills: usize, c: Nanos, t: Nanos, rounds: usize) -> Vec<Nanos> {
        let mut s = Sporadic::new(c, t, 0);
        s.max_refills = max_refills;
        let mut units = Vec::new();
        let mut now = 0;
        for k in 0..rounds {
            s.unblock(now);
            // Run in unit steps while capacity lasts, up to a burst of 1..=3.
            let burst = 1 + (k % 3) as Nanos;
            let mut ran = 0;
            while ran < burst && s.capacity(now) > 0 {
                units.push(now);
                s.charge(now + 1, 1);
                now += 1;
                ran += 1;
            }
            if s.capacity(now) > 0 || ran > 0 {
                s.block(now);
            }
            assert_eq!(s.total(), c, "refills must always sum to C");
            assert!(s.queue.len() <= max_refills);
            now += 1 + (k % 4) as Nanos;
        }
        units
    }

    #[test]
    fn sporadic_never_exceeds_budget_in_any_window() {
        // The corrected rules guarantee at most C of execution in every
        // sliding window of length T, with a roomy and with a full queue.
        for max_refills in [MAX_REFILLS, 2, 1] {
            let (c, t) = (3, 10);
            let units = bursty(max_refills, c, t, 400);
            assert!(units.len() > 50, "the client must get service");
            for (k, &start) in units.iter().enumerate() {
                let in_window = units[k..].iter().take_while(|&&u| u < start + t).count();
                assert!(
                    in_window as Nanos <= c,
                    "queue {max_refills}: {in_window} units in [{start}, {})",
                    start + t
                );
            }
        }
    }

    #[test]
    fn sporadic_preserves_bandwidth_over_long_runs() {
        // Not more than C per T on average, and not starved either: over
        // 400 rounds the client gets close to U = 0.3 of the elapsed time
        // whenever it is ready often enough.
        let units = bursty(MAX_REFILLS, 3, 10, 400);
        let span = units.last().copied().unwrap_or(0) + 1;
        assert!(units.len() as f64 <= 0.3 * span as f64 + 3.0);
    }

    #[test]
    fn pibs_eligibility_moves_by_usage_over_u() {
        // C = 2, T = 10 (U = 0.2). Arrive at 0, run 1: e = 0 + 1/0.2 = 5.
        let mut p = Pibs::new(2, 10);
        p.unblock(0);
        assert_eq!(p.capacity(0), 2);
        p.charge(1, 1);
        assert_eq!(p.eligible(), 5);
        // Still in the same replenishment: may go on running.
        assert_eq!(p.capacity(1), 1);
        p.charge(2, 1);
        // Exhausted: e = 10, next replenishment only then.
        assert_eq!(p.eligible(), 10);
        p.unblock(3);
        assert_eq!(p.capacity(3), 0);
        assert_eq!(p.capacity(10), 2);
    }

    #[test]
    fn pibs_keeps_fractions_exact() {
        // C = 3, T = 10: running 1 advances e by 10/3. Three runs of 1 → exactly 10.
        let mut p = Pibs::new(3, 10);
        p.unblock(0);
        p.charge(1, 1);
        assert_eq!(p.eligible(), 4); // 3.33… rounded up
        p.charge(2, 1);
        p.charge(3, 1);
        assert_eq!(p.eligible(), 10);
        // A job arriving exactly at 10 may start at once.
        p.unblock(10);
        assert_eq!(p.capacity(10), 3);
    }

    #[test]
    fn cbs_wakeup_rule_and_throttling() {
        // C = 2, T = 10. Wake at 0: d = 10, q = 2. Run 2: throttled until 10.
        let mut s = Cbs::new(2, 10);
        s.unblock(0);
        assert_eq!((s.deadline, s.runtime), (10, 2));
        s.charge(2, 2);
        assert_eq!(s.capacity(5), 0);
        s.replenish(10);
        assert_eq!((s.deadline, s.runtime), (20, 2));
        // Wake at 15 with q = 1 left: 1 · 10 > 2 · (20 − 15) = 10? No → keep d = 20.
        s.charge(11, 1);
        s.unblock(15);
        assert_eq!((s.deadline, s.runtime), (20, 1));
        // Wake at 19: 1 · 10 > 2 · 1 → new deadline 29, runtime 2.
        s.unblock(19);
        assert_eq!((s.deadline, s.runtime), (29, 2));
    }
}
