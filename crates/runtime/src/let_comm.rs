//! LET communication on real threads (`[system] communication = "let"`,
//! Kirsch and Sokolova 2012), as the simulator runs it (`rtpipe_sim`'s
//! let_comm.rs): a job reads the inputs visible at its release and its
//! output becomes visible at the end of its period, release + T; at one
//! instant, every period that ends publishes before any release reads.
//!
//! What a job of a consumer released at t reads is then fixed by the
//! periods and offsets alone: job j* of the producer, the latest whose
//! period has ended, φp + (j* + 1)·Tp ≤ t. The runtime enforces that by
//! index rather than by a timer: the producer writes job j's output, when
//! it completes, into slot j mod N of the edge (each slot a four-slot
//! register), and the consumer takes slot j* mod N. No thread has to act at
//! the exact instants (a preempted thread cannot), yet the data flow is
//! exactly LET's, and the job log holds LET's instants: read = release,
//! publish = release + T. It holds when the producer finishes each job
//! within its period (R ≤ T, which LET needs and `rtpipe analyze` checks)
//! and the consumer reads within N − 2 producer periods of its release,
//! N = ⌈Tc / Tp⌉ + 3 (a consumer reads at the start of its job, before its
//! deadline Dc ≤ Tc); a read that finds another job in its slot is counted
//! ([`LetIn::read`]), its data flow logged as it happened. A consumer more
//! than N periods late finds its job written over: it takes the latest job
//! held up to it, else the oldest after it. Whatever a slot holds, one
//! consumer's reads never go back: a read that would return an older job
//! than the last one it returned (a producer late on job j leaves job
//! j − N in j's slot, or nothing) returns the last one again, counted as
//! not the job LET prescribes. The job log's replay, like every register's
//! reader, relies on that: a newer job taken first, then an older one,
//! made a later output carry an older sample, which the chain tracker
//! cannot place.
//!
//! Communication per chain makes edges mixed. A LET producer's
//! edge to an implicit consumer is the same ring: the consumer, reading at
//! the start of its job, takes the job whose period ended by then. An
//! implicit producer's edge to a LET consumer cannot go by index (which
//! job has completed by the consumer's release is the schedule's), so the
//! consumer takes, among the slots, the latest job whose publish (its
//! completion, stamped) is at or before its release: exact while the
//! consumer reads within N − 2 producer periods of its release, as above
//! (a completion stamped but not yet written when the consumer looks is
//! missed, as with the implicit registers: the log holds what was read).

use crate::four_slot::{self, Reader, Writer};
use rtpipe_body::{Nanos, Stamped};

/// The value a register holds: `None` until the producer first publishes.
pub(crate) type Cell<V> = Option<Stamped<V>>;

/// A consumer's end of one LET edge.
pub(crate) struct LetIn<V> {
    slots: Vec<Reader<Cell<V>>>,
    /// The producer's offset and period.
    phase: Nanos,
    period: Nanos,
    /// The producer communicates under LET: its jobs are visible by
    /// period; otherwise by publish instant.
    by_period: bool,
    /// The slots' values of one read by publish instant (no allocation
    /// while a job runs).
    seen: Vec<Cell<V>>,
    /// What the last read returned: no read returns an older job.
    last: Cell<V>,
}

/// A producer's end of one LET edge.
pub(crate) struct LetOut<V> {
    slots: Vec<Writer<Cell<V>>>,
}

/// One edge from a producer (offset, period) to a consumer of period
/// `consumer`; `by_period`: the producer communicates under LET.
pub(crate) fn edge<V: Copy + Send>(
    (phase, period): (Nanos, Nanos),
    consumer: Nanos,
    by_period: bool,
) -> (LetOut<V>, LetIn<V>) {
    assert!(period > 0 && consumer > 0, "positive periods");
    let n = (consumer + period - 1) / period + 3;
    let (w, r): (Vec<_>, Vec<_>) = (0..n).map(|_| four_slot::register(None)).unzip();
    (
        LetOut { slots: w },
        LetIn {
            slots: r,
            phase,
            period,
            by_period,
            seen: Vec::with_capacity(n as usize),
            last: None,
        },
    )
}

/// The producer job whose output is visible at `release` (relative to the
/// epoch) on an edge from a producer released at φ + k·T: the latest whose
/// period has ended by then.
pub(crate) fn visible(release: Nanos, (phase, period): (Nanos, Nanos)) -> Option<u64> {
    let ended = (release - phase).div_euclid(period);
    (ended >= 1).then(|| (ended - 1) as u64)
}

impl<V: Copy> LetIn<V> {
    /// The value visible at `release`, and whether it is the job LET
    /// prescribes (false: the producer had not written it yet, or had
    /// already written over it). Never an older job than the last read
    /// returned.
    pub(crate) fn read(&mut self, release: Nanos) -> (Cell<V>, bool) {
        let (v, exact) = self.prescribed(release);
        let job = |c: &Cell<V>| c.map(|s| s.stamp.job);
        // `None` (nothing written) orders before every job.
        if job(&v) < job(&self.last) {
            return (self.last, false);
        }
        self.last = v;
        (v, exact)
    }

    /// What LET prescribes at `release`, as near as the slots hold it.
    fn prescribed(&mut self, release: Nanos) -> (Cell<V>, bool) {
        if !self.by_period {
            return self.read_published(release);
        }
        let Some(j) = visible(release, (self.phase, self.period)) else {
            return (None, true);
        };
        let n = self.slots.len() as u64;
        let v = self.slots[(j % n) as usize].read();
        if v.is_none_or(|s| s.stamp.job <= j) {
            return (v, v.is_some_and(|s| s.stamp.job == j));
        }
        // Job j was written over: the consumer reads more than N periods
        // late. Of what the slots hold, take the latest job up to j, else
        // the oldest after it, so that what one consumer reads never goes
        // back (the slots only move forward), as every register's reads.
        (self.nearest(j), false)
    }

    /// The latest job up to `j` the slots hold, else the oldest after it.
    fn nearest(&mut self, j: u64) -> Cell<V> {
        self.seen.clear();
        self.seen.extend(self.slots.iter_mut().map(|r| r.read()));
        let held = self.seen.iter().flatten();
        let before = held
            .clone()
            .filter(|s| s.stamp.job <= j)
            .max_by_key(|s| s.stamp.job);
        let after = || {
            held.clone()
                .filter(|s| s.stamp.job > j)
                .min_by_key(|s| s.stamp.job)
        };
        before.or_else(after).copied()
    }
}

impl<V: Copy> LetIn<V> {
    /// From an implicit producer: the latest job published at or before
    /// `at`, and whether that is certain (the next job's slot does not
    /// hold a newer job: nothing between was written over).
    fn read_published(&mut self, at: Nanos) -> (Cell<V>, bool) {
        self.seen.clear();
        self.seen.extend(self.slots.iter_mut().map(|r| r.read()));
        let cells = &self.seen;
        let n = cells.len() as u64;
        let best = cells
            .iter()
            .flatten()
            .filter(|s| s.stamp.publish <= at)
            .max_by_key(|s| s.stamp.job)
            .copied();
        // The job after the one taken (job 0 when none): its slot must
        // hold it (published after `at`), an older job, or nothing.
        let next = best.map_or(0, |s| s.stamp.job + 1);
        let exact = cells[(next % n) as usize].is_none_or(|s| s.stamp.job <= next);
        (best, exact)
    }
}

impl<V: Copy> LetOut<V> {
    /// Job `value.stamp.job`'s output, for the consumer jobs released once
    /// its period has ended.
    pub(crate) fn write(&mut self, value: Stamped<V>) {
        let n = self.slots.len() as u64;
        self.slots[(value.stamp.job % n) as usize].write(Some(value));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtpipe_body::Stamp;

    #[test]
    fn a_read_whose_job_was_written_over_never_goes_back() {
        // Producer at 0 + 10k, consumer period 10: N = 4 slots. The
        // producer has written jobs 0..=4 (slot 0 now holds job 4) while
        // the consumer still reads at 15 (job 0 prescribed), then at 25
        // (job 1, still in its slot).
        let (mut out, mut inp) = edge::<u64>((0, 10), 10, true);
        let stamped = |job: u64| Stamped {
            value: job,
            stamp: Stamp {
                task: 0,
                job,
                read: job as Nanos * 10,
                publish: job as Nanos * 10 + 10,
            },
        };
        for job in 0..=4 {
            out.write(stamped(job));
        }
        let (a, exact_a) = inp.read(15);
        let (b, exact_b) = inp.read(25);
        assert!(!exact_a && exact_b, "job 0 was written over, job 1 not");
        // Not slot 0's job 4 and then job 1: the oldest held after the
        // prescribed job, so the reads do not go back.
        let (a, b) = (a.map(|s| s.stamp.job), b.map(|s| s.stamp.job));
        assert_eq!((a, b), (Some(1), Some(1)));
        for job in 5..=9 {
            out.write(stamped(job));
        }
        // Job 2 (visible at 35) is gone too; 6 is the oldest held.
        assert_eq!(inp.read(35).0.map(|s| s.stamp.job), Some(6));
    }

    #[test]
    fn a_producer_late_on_the_prescribed_job_never_sends_the_reader_back() {
        // Producer and consumer at 0 + 10k: N = 4 slots. Jobs 0..=4 are
        // written (slot 0 holds job 4); at 50 job 4 is prescribed, at 60
        // job 5, whose slot still holds job 1 (the producer is late).
        let (mut out, mut inp) = edge::<u64>((0, 10), 10, true);
        for job in 0..=4 {
            let stamp = Stamp {
                task: 0,
                job,
                read: job as Nanos * 10,
                publish: job as Nanos * 10 + 10,
            };
            out.write(Stamped { value: job, stamp });
        }
        let (a, exact_a) = inp.read(50);
        let (b, exact_b) = inp.read(60);
        assert!(exact_a && !exact_b, "job 4 is held, job 5 is not written");
        let (a, b) = (a.map(|s| s.value), b.map(|s| s.value));
        assert_eq!((a, b), (Some(4), Some(4)), "job 4 again, not job 1");
        // Nothing written is older than anything: job 4 again at 90.
        let (mut _out, mut fresh) = edge::<u64>((0, 10), 10, true);
        assert_eq!(fresh.read(90).0.map(|s| s.value), None);
        assert_eq!(inp.read(90).0.map(|s| s.value), Some(4));
    }

    #[test]
    fn a_release_sees_the_periods_ended_by_then() {
        // Producer at 1 + 5k: job 0's period ends at 6.
        assert_eq!(visible(5, (1, 5)), None);
        assert_eq!(
            visible(6, (1, 5)),
            Some(0),
            "publish before read at one instant"
        );
        assert_eq!(visible(10, (1, 5)), Some(0));
        assert_eq!(visible(11, (1, 5)), Some(1));
        assert_eq!(
            visible(0, (3, 5)),
            None,
            "before the producer's first release"
        );
    }

    #[test]
    fn from_an_implicit_producer_the_latest_published_by_the_release() {
        // Producer T = 2 (implicit: published at its completion, stamped),
        // consumer T = 4 under LET: N = 2 + 3 = 5 slots.
        let (mut w, mut r) = edge::<u64>((0, 2), 4, false);
        let put = |w: &mut LetOut<u64>, job: u64, publish: Nanos| {
            let stamp = Stamp {
                task: 0,
                job,
                read: 0,
                publish,
            };
            w.write(Stamped {
                value: 100 + job,
                stamp,
            });
        };
        assert_eq!(r.read(3).0.map(|s| s.value), None, "nothing published yet");
        put(&mut w, 0, 1);
        put(&mut w, 1, 3);
        put(&mut w, 2, 5);
        // Released at 4: job 1 (out at 3), though job 2 is out by the read.
        let (v, ok) = r.read(4);
        assert!(ok);
        assert_eq!(v.map(|s| s.value), Some(101));
        assert_eq!(r.read(3).0.map(|s| s.value), Some(101), "at the instant");
        // Jobs 3 … 7 overwrite every slot: job 1's successor is gone, and
        // a reader that never read before finds nothing published by 4.
        for j in 3..=7 {
            put(&mut w, j, 2 * j as Nanos + 1);
        }
        let (v, ok) = r.read_published(4);
        assert!(v.is_none() && !ok);
        // This reader took job 1 already: job 1 again, not nothing.
        let (v, ok) = r.read(4);
        assert!(v.is_some_and(|s| s.value == 101) && !ok);
        assert_eq!(r.read(13).0.map(|s| s.value), Some(106));
    }

    #[test]
    fn the_consumer_gets_the_prescribed_job_though_newer_ones_completed() {
        let (mut w, mut r) = edge::<u64>((0, 2), 10, true);
        let put = |w: &mut LetOut<u64>, job: u64| {
            let stamp = Stamp {
                task: 0,
                job,
                read: 0,
                publish: 0,
            };
            w.write(Stamped {
                value: 100 + job,
                stamp,
            });
        };
        // Jobs 0..=4 done; at 6 job 2 is visible (its period ended at 6),
        // though 3 and 4 completed before the consumer read.
        for j in 0..=4 {
            put(&mut w, j);
        }
        let (v, ok) = r.read(6);
        assert!(ok);
        assert_eq!(v.map(|s| s.value), Some(102));
        // Far too late a reader finds its slot written over: counted.
        for j in 5..=12 {
            put(&mut w, j);
        }
        assert!(!r.read(6).1);
    }
}
