//! The simulator's scheduling before the event heaps:
//! every event scanned every task (CBS replenishment, releases, the pick of
//! each CPU, the next release and refill). Kept verbatim, test-only, as the
//! reference the event-heap implementation must match bit for bit
//! (`tests::heaps_match_the_reference`). `read` and `complete` are shared:
//! the change did not touch them.

use super::*;

/// [`simulate`] with the reference scheduling.
pub(crate) fn simulate_reference(spec: &Spec, cfg: &SimConfig) -> Result<SimResult, SimError> {
    let mut sim = Sim::new(spec, cfg, NoHooks)?;
    let mut t = 0;
    loop {
        sim.ref_instant(t);
        match sim.ref_next_event(t) {
            Some(next) if next <= cfg.horizon => {
                sim.ref_advance(t, next - t);
                t = next;
            }
            _ => break,
        }
    }
    Ok(sim.finish())
}

impl<H: Hooks> Sim<H> {
    /// Everything that happens at instant t, in the tie order of the model.
    /// Repeats when a job of zero demand starts, so it reads before it
    /// publishes (at the same instant).
    fn ref_instant(&mut self, t: Nanos) {
        self.events += 1;
        for ts in &mut self.tasks {
            if let Budget::Cbs(c) = &mut ts.budget {
                c.replenish(t);
            }
        }
        loop {
            for cpu in 0..self.running.len() {
                if let Some(i) = self.running[cpu] {
                    if self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.remaining == 0)
                    {
                        self.complete(i, t);
                        self.running[cpu] = None;
                    }
                }
            }
            self.ref_release(t);
            for cpu in 0..self.running.len() {
                let picked = self.ref_pick(cpu, t);
                self.running[cpu] = picked.map(|(i, _)| i);
                self.in_slack[cpu] = picked.is_some_and(|(_, slack)| slack);
            }
            let mut again = false;
            for cpu in 0..self.running.len() {
                if let Some(i) = self.running[cpu] {
                    if self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.read.is_none())
                    {
                        self.read(i, t);
                    }
                    again |= self.tasks[i]
                        .queue
                        .front()
                        .is_some_and(|j| j.remaining == 0);
                }
            }
            if !again {
                break;
            }
        }
    }

    /// Every task scanned for due releases (the release itself is the
    /// engine's `release_jobs`, which the change did not touch).
    fn ref_release(&mut self, t: Nanos) {
        let exec = self.exec;
        for ts in &mut self.tasks {
            release_jobs(ts, exec, t);
        }
    }

    /// The ready task of highest priority on a CPU, and whether it runs in
    /// slack (a sporadic server out of budget drops to background priority).
    fn ref_pick(&self, cpu: usize, t: Nanos) -> Option<(usize, bool)> {
        self.cpu_tasks[cpu]
            .iter()
            .filter_map(|&i| {
                let ts = &self.tasks[i];
                let job = ts.queue.front()?;
                let has_budget = ts.budget.capacity(t) > 0;
                let class = match (ts.class, has_budget) {
                    (0, true) => 0,
                    (0, false) if ts.slack_when_empty => 2,
                    (0, false) => return None,
                    _ => 1,
                };
                let key = match (&ts.budget, self.edf) {
                    (Budget::Cbs(c), _) => c.deadline,
                    (_, true) => job.release + ts.period,
                    (_, false) => match ts.serves.map(|m| m as usize) {
                        Some(m) if !self.tasks[m].queue.is_empty() => {
                            ts.rank.min(self.tasks[m].rank)
                        }
                        _ => ts.rank,
                    },
                };
                Some(((class, key, i), (i, class == 2)))
            })
            .min()
            .map(|(_, v)| v)
    }

    /// The next instant something happens after t: a release, a completion,
    /// a budget running out, or a budget coming back to a waiting server.
    fn ref_next_event(&self, t: Nanos) -> Option<Nanos> {
        let releases = self.tasks.iter().map(|ts| ts.next_release);
        let running = self.running.iter().enumerate().filter_map(|(cpu, r)| {
            let ts = &self.tasks[(*r)?];
            let job = ts.queue.front()?;
            let mut next = t + job.remaining;
            if !self.in_slack[cpu] {
                let cap = ts.budget.capacity(t);
                if cap < job.remaining {
                    next = t + cap;
                }
            }
            Some(next)
        });
        let refills = self.tasks.iter().filter_map(|ts| {
            if ts.queue.is_empty() || ts.budget.capacity(t) > 0 {
                return None;
            }
            ts.budget.refill_at().filter(|&r| r > t)
        });
        releases.chain(running).chain(refills).min()
    }

    /// Runs every CPU's chosen job from t for dt and charges its server.
    fn ref_advance(&mut self, t: Nanos, dt: Nanos) {
        for cpu in 0..self.running.len() {
            let Some(i) = self.running[cpu] else { continue };
            let slack = self.in_slack[cpu];
            let ts = &mut self.tasks[i];
            let Some(job) = ts.queue.front_mut() else {
                continue;
            };
            job.remaining -= dt;
            let (index, remaining) = (job.index, job.remaining);
            ts.stats.busy += dt;
            if !slack {
                ts.budget.charge(t + dt, dt);
                if remaining > 0 && ts.budget.capacity(t + dt) == 0 {
                    ts.stats.exhaustions += 1;
                }
            }
            self.record_segment(cpu, i, index, t, dt, slack);
        }
    }
}
