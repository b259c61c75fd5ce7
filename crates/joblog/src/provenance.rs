//! Sample provenance: which sample of each chain every job carries, from
//! the head's reads along the chain's edges to the tail's publishes, and
//! the chains' figures that follow from it.

use crate::rows::{RowSink, Rows};
use crate::tracker::Tracker;
use crate::{Carried, ChainStats, JobRecord, SampleRow};
use rtpipe_model::{Nanos, Spec};
use std::fmt;

/// One chain position a task occupies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slot {
    /// Index of the chain in `Spec::chains`.
    pub chain: usize,
    /// The position on the chain (0 = head).
    pub pos: usize,
    /// The producer at the previous position: its task and the index of
    /// its slot there; `None` at the head.
    pub src: Option<(usize, usize)>,
    /// The last position: the task's publishes are the chain's outputs.
    pub tail: bool,
}

/// A chain's path names a task the spec does not have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BadChain(pub usize);

impl fmt::Display for BadChain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "chain {} names a task the spec does not have", self.0)
    }
}

impl std::error::Error for BadChain {}

/// Sample provenance of one run, fed by an executor job by job.
///
/// Every job of a chain's head creates a sample stamped with its read
/// instant (ids count head reads). A job at position k carries the sample
/// carried at position k−1 by the value it read (provenance follows each
/// chain's edges separately). A tail publish is an output of the sample it
/// carries, from which the chain's reaction and freshness follow
/// ([`ChainStats`]).
///
/// Each task's jobs read and publish in order, one job between its
/// [`read`](Provenance::read) and its [`publish`](Provenance::publish);
/// calls across tasks come in the order of the instants they give (a
/// producer's publish before the reads that see it).
pub struct Provenance {
    /// Per task (one struct each: one lookup per read or publish).
    tasks: Vec<TaskSlots>,
    /// Per chain: its samples' stamps and figures so far.
    chains: Vec<Tracker>,
    /// Where complete sample rows go, when the run streams them.
    sink: Option<RowSink>,
}

/// One task's chain positions and the samples at each.
struct TaskSlots {
    /// The chain positions it occupies, in chain then path order.
    slots: Vec<Slot>,
    /// Per slot: the sample its reading job carries.
    carried: Vec<Option<u64>>,
    /// Per slot: the sample its latest published value carries.
    published: Vec<Option<u64>>,
}

impl Provenance {
    /// No job has run yet.
    pub fn new(spec: &Spec) -> Result<Provenance, BadChain> {
        let n = spec.tasks.len();
        let mut slots: Vec<Vec<Slot>> = vec![Vec::new(); n];
        for (c, ch) in spec.chains.iter().enumerate() {
            if ch.path.iter().any(|&i| i >= n) {
                return Err(BadChain(c));
            }
            // Each slot links to the previous position's, created just
            // before it (path order).
            let mut prev: Option<(usize, usize)> = None;
            for (pos, &i) in ch.path.iter().enumerate() {
                slots[i].push(Slot {
                    chain: c,
                    pos,
                    src: prev,
                    tail: pos + 1 == ch.path.len(),
                });
                prev = Some((i, slots[i].len() - 1));
            }
        }
        let tasks = slots
            .into_iter()
            .map(|slots| TaskSlots {
                carried: vec![None; slots.len()],
                published: vec![None; slots.len()],
                slots,
            })
            .collect();
        Ok(Provenance {
            tasks,
            chains: trackers(spec, Tracker::new),
            sink: None,
        })
    }

    /// Hands every chain's [`SampleRow`]s to `sink` as they complete
    /// (before any job runs), the rest at [`finish`](Provenance::finish):
    /// the per-sample record of a run in memory bounded by the samples in
    /// flight.
    pub fn stream_rows(&mut self, sink: RowSink) {
        for tr in &mut self.chains {
            tr.rows = Some(Rows::default());
        }
        self.sink = Some(sink);
    }

    /// The chain positions `task` occupies, in chain order.
    pub fn slots(&self, task: usize) -> &[Slot] {
        &self.tasks[task].slots
    }

    /// A job of `task` reads at t the value each producer published last
    /// (register semantics, as the simulator runs).
    #[inline]
    pub fn read(&mut self, task: usize, t: Nanos) {
        self.read_by(task, t, |tasks, p, ps| tasks[p].published[ps]);
    }

    /// A job of `task` reads at t values that need not be the latest
    /// published (a real run's registers, replayed in publish order):
    /// `upstream(p, ps)` is the sample carried at slot `ps` of producer `p`
    /// by the value the job read from `p`.
    #[inline]
    pub fn read_with(
        &mut self,
        task: usize,
        t: Nanos,
        upstream: impl Fn(usize, usize) -> Option<u64>,
    ) {
        self.read_by(task, t, |_, p, ps| upstream(p, ps));
    }

    /// The samples a job of `task` carries when it reads at t: a new sample
    /// at a head, else the one `upstream` says the value read carries.
    /// Indexed, not iterated: `upstream` may look at any task's samples.
    #[inline]
    fn read_by(
        &mut self,
        task: usize,
        t: Nanos,
        upstream: impl Fn(&[TaskSlots], usize, usize) -> Option<u64>,
    ) {
        for s in 0..self.tasks[task].slots.len() {
            let slot = self.tasks[task].slots[s];
            let v = match slot.src {
                None => Some(self.chains[slot.chain].sample(t)),
                Some((p, ps)) => upstream(&self.tasks, p, ps),
            };
            self.tasks[task].carried[s] = v;
        }
    }

    /// The job of `task` that read last publishes at t: what it carried is
    /// now what the task's value carries, and at a tail it is an output.
    #[inline]
    pub fn publish(&mut self, task: usize, t: Nanos) {
        let ts = &mut self.tasks[task];
        ts.published.clone_from(&ts.carried);
        for (slot, v) in ts.slots.iter().zip(&ts.carried) {
            // Only a streaming run needs to know which head reads published.
            if let (0, Some(sample), true) = (slot.pos, v, self.sink.is_some()) {
                let tr = &mut self.chains[slot.chain];
                tr.head_done = tr.head_done.max(sample + 1);
            }
            if let (true, Some(sample)) = (slot.tail, v) {
                let tr = &mut self.chains[slot.chain];
                tr.output(*sample, t);
                if let (Some(sink), Some(rows)) = (&mut self.sink, &mut tr.rows) {
                    rows.drain(slot.chain, sink, false);
                }
            }
        }
    }

    /// What the value `task` published last carries, one entry per slot:
    /// the [`JobRecord::carried`] of the job that published it.
    pub fn record(&self, task: usize) -> Vec<Carried> {
        let ts = &self.tasks[task];
        ts.slots
            .iter()
            .zip(&ts.published)
            .map(|(s, &sample)| Carried {
                chain: s.chain,
                pos: s.pos,
                sample,
            })
            .collect()
    }

    /// Every chain's figures, indexed like `Spec::chains`; a streaming run
    /// hands on its last rows, chain by chain.
    pub fn finish(mut self) -> Vec<ChainStats> {
        if let Some(sink) = &mut self.sink {
            for (c, tr) in self.chains.iter_mut().enumerate() {
                if let Some(rows) = &mut tr.rows {
                    rows.truncate(tr.head_done);
                    rows.drain(c, sink, true);
                }
            }
        }
        self.chains.into_iter().map(|c| c.stats).collect()
    }
}

/// The chain statistics of a log of completed jobs, measured exactly as
/// [`Provenance`] measures a run as it goes. `jobs` must hold, per task,
/// its jobs from index 0 without gaps, in completion order overall, with
/// `carried` resolved (a head job carries its own index; a job at position
/// k the sample of the value it read from position k−1). Head samples
/// whose job is missing from the log are not counted.
pub fn chains_from_jobs(spec: &Spec, jobs: &[JobRecord]) -> Vec<ChainStats> {
    replay(spec, jobs, Tracker::new)
        .into_iter()
        .map(|t| t.stats)
        .collect()
}

/// Every head sample of every chain of a finished job log, one
/// [`SampleRow`] each (indexed like `Spec::chains`, then by sample id),
/// measured by the same trackers as [`chains_from_jobs`].
pub fn sample_rows(spec: &Spec, jobs: &[JobRecord]) -> Vec<Vec<SampleRow>> {
    replay(spec, jobs, Tracker::with_rows)
        .into_iter()
        .map(|t| t.rows.map(Rows::into_vec).unwrap_or_default())
        .collect()
}

/// One tracker per chain of `spec`, their histograms sharing the exact
/// budget (`hist::exact_cap`: four per chain), live or replayed alike.
fn trackers(spec: &Spec, tracker: fn(usize) -> Tracker) -> Vec<Tracker> {
    let cap = crate::hist::exact_cap(4 * spec.chains.len());
    spec.chains.iter().map(|_| tracker(cap)).collect()
}

/// Feeds a finished job log through one tracker per chain.
fn replay(spec: &Spec, jobs: &[JobRecord], tracker: fn(usize) -> Tracker) -> Vec<Tracker> {
    let mut trackers: Vec<Tracker> = trackers(spec, tracker);
    for (tr, ch) in trackers.iter_mut().zip(&spec.chains) {
        let Some(&head) = ch.path.first() else {
            continue;
        };
        let mut reads: Vec<(u64, Nanos)> = jobs
            .iter()
            .filter(|j| j.task == head)
            .map(|j| (j.index, j.read))
            .collect();
        reads.sort_unstable();
        tr.set_stamps(
            reads
                .iter()
                .enumerate()
                .take_while(|&(k, &(i, _))| k as u64 == i)
                .map(|(_, &(_, r))| r)
                .collect(),
        );
    }
    for j in jobs {
        // Causality within a job: every latency below starts from a read.
        assert!(
            j.release <= j.read && j.read <= j.finish,
            "task {} job {}: release {} read {} finish {} out of order",
            j.task,
            j.index,
            j.release,
            j.read,
            j.finish
        );
        for c in &j.carried {
            let (Some(ch), Some(sample)) = (spec.chains.get(c.chain), c.sample) else {
                continue;
            };
            let tr = &mut trackers[c.chain];
            if c.pos + 1 == ch.path.len() && tr.has(sample) {
                tr.output(sample, j.finish);
            }
        }
    }
    trackers
}

#[cfg(test)]
mod tests {
    use super::*;

    /// a → b, one chain.
    fn spec() -> Spec {
        let text = r#"
[system]
name = "two"
time_unit = "ns"
[channels.m]
bandwidth = 1
overhead = 0
[tasks.a]
exec = 1
output = { channel = "m", size = 0 }
period = 10
[tasks.b]
exec = 1
reads = ["a"]
output = { channel = "m", size = 0 }
period = 10
[[chain]]
path = ["a", "b"]
"#;
        Spec::parse("two.toml", text).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn samples_follow_the_chain_to_the_tail() {
        let s = spec();
        let mut p = Provenance::new(&s).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.slots(1)[0].src, Some((0, 0)));
        for (a, b) in [(0, 2), (10, 12)] {
            p.read(0, a);
            p.publish(0, a + 1);
            p.read(1, b);
            p.publish(1, b + 1);
        }
        // b reads again before a publishes a new sample: sample 1 again.
        p.read(1, 22);
        p.publish(1, 23);
        assert_eq!(p.record(1)[0].sample, Some(1));
        let c = &p.finish()[0];
        assert_eq!((c.samples, c.reached, c.finalised), (2, 2, 1));
        assert_eq!(c.reaction.hist.sorted(), vec![3, 3]);
        assert_eq!(c.freshness.hist.sorted(), vec![3]);
        assert_eq!(c.event_reaction.hist.sorted(), vec![13]);
    }

    #[test]
    fn a_long_run_holds_bounded_memory() {
        // Before, every stamp and every latency was kept, so memory grew
        // with the simulated span.
        let s = spec();
        let mut p = Provenance::new(&s).unwrap_or_else(|e| panic!("{e}"));
        let n = 200_000;
        for k in 0..n {
            let t = 10 * k;
            p.read(0, t);
            p.publish(0, t + 1);
            p.read(1, t + 2 + k % 3);
            p.publish(1, t + 5);
        }
        assert!(p.chains[0].held() <= 2, "{}", p.chains[0].held());
        let c = &p.finish()[0];
        assert_eq!(c.reaction.hist.count(), n as u64);
        assert_eq!(c.reaction.hist.min(), Some(5));
        assert!(c.reaction.hist.is_exact());
    }

    #[test]
    fn a_read_may_name_an_older_value() {
        let s = spec();
        let mut p = Provenance::new(&s).unwrap_or_else(|e| panic!("{e}"));
        p.read(0, 0);
        p.publish(0, 1);
        let first = p.record(0);
        p.read(0, 10);
        p.publish(0, 11);
        // b's register still held job 0's value when b read at 12.
        p.read_with(1, 12, |task, slot| {
            assert_eq!((task, slot), (0, 0));
            first[slot].sample
        });
        p.publish(1, 13);
        assert_eq!(p.record(1)[0].sample, Some(0));
        assert_eq!(p.finish()[0].reaction.hist.sorted(), vec![13]);
    }

    #[test]
    fn a_chain_through_a_missing_task_is_refused() {
        let mut s = spec();
        s.chains[0].path.push(7);
        assert_eq!(Provenance::new(&s).err(), Some(BadChain(0)));
    }
}
