//! The tasks' next releases, earliest first, in a 4-ary min-heap whose
//! every node's four children share one cache line.
//!
//! Past a few thousand tasks the release heap no longer fits the core's
//! first-level cache, and each level a sift visits below the cached top
//! is a miss: a binary heap of 10,000 tasks is 14 levels deep, this one 7,
//! and the four children a sift compares sit in one 64-byte line. Each
//! entry keeps its key inline (release, then task index), so a comparison
//! never reads a task's state. Entries are unique (one per task), so the
//! order they come out in is the total order of (release, task): the same
//! as any other heap's, and the simulation's results do not depend on
//! which heap it uses.

use rtpipe_model::Nanos;

/// One entry: when, and which task.
pub(crate) type Entry = (Nanos, u32);

/// Four entries, aligned so that they share one cache line.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Line([Entry; 4]);

const EMPTY: Entry = (Nanos::MAX, u32::MAX);

/// A 4-ary min-heap of (release, task). Logical node k lives at slot
/// k + 3 of the lines (the root alone in line 0's last slot), so the
/// children of node k, 4k + 1 to 4k + 4, are exactly line k + 1.
#[derive(Debug, Clone)]
pub(crate) struct ReleaseHeap {
    lines: Vec<Line>,
    len: usize,
}

impl ReleaseHeap {
    /// A heap of these entries (each task's next release).
    pub(crate) fn new(entries: impl IntoIterator<Item = Entry>) -> ReleaseHeap {
        let mut heap = ReleaseHeap {
            lines: Vec::new(),
            len: 0,
        };
        for e in entries {
            heap.push(e);
        }
        heap
    }

    #[cfg(any(test, debug_assertions))]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The earliest entry.
    pub(crate) fn peek(&self) -> Option<Entry> {
        (self.len > 0).then(|| self.get(0))
    }

    /// Every entry, in no particular order.
    #[cfg(any(test, debug_assertions))]
    pub(crate) fn iter(&self) -> impl Iterator<Item = Entry> + '_ {
        (0..self.len).map(|k| self.get(k))
    }

    fn get(&self, k: usize) -> Entry {
        let s = k + 3;
        self.lines[s / 4].0[s % 4]
    }

    fn set(&mut self, k: usize, e: Entry) {
        let s = k + 3;
        self.lines[s / 4].0[s % 4] = e;
    }

    fn push(&mut self, e: Entry) {
        let s = self.len + 3;
        if s / 4 == self.lines.len() {
            self.lines.push(Line([EMPTY; 4]));
        }
        self.len += 1;
        self.sift_up(self.len - 1, e);
    }

    /// Replaces the earliest entry with `e` (a task's release moved on).
    pub(crate) fn replace_top(&mut self, e: Entry) {
        assert!(self.len > 0, "replace_top on an empty release heap");
        self.sift_down(0, e);
    }

    fn sift_up(&mut self, mut k: usize, e: Entry) {
        while k > 0 {
            let parent = (k - 1) / 4;
            let p = self.get(parent);
            if p <= e {
                break;
            }
            self.set(k, p);
            k = parent;
        }
        self.set(k, e);
    }

    fn sift_down(&mut self, mut k: usize, e: Entry) {
        loop {
            let first = 4 * k + 1;
            if first >= self.len {
                break;
            }
            // The least child, from the one line the children share.
            let children = &self.lines[k + 1].0;
            let last = (self.len - first).min(4);
            let mut best = 0;
            for c in 1..last {
                if children[c] < children[best] {
                    best = c;
                }
            }
            let child = children[best];
            if e <= child {
                break;
            }
            self.set(k, child);
            k = first + best;
        }
        self.set(k, e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rng;
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    /// The hold model the simulator runs (pop the earliest, push it back
    /// later) gives the order a binary heap gives, at every size.
    #[test]
    fn pops_in_the_order_of_a_binary_heap() {
        let mut rng = Rng::new(7);
        for n in [1usize, 2, 3, 4, 5, 16, 17, 100, 1000] {
            let entries: Vec<Entry> = (0..n)
                .map(|i| (rng.range(0, 50) as Nanos, i as u32))
                .collect();
            let mut ours = ReleaseHeap::new(entries.iter().copied());
            let mut theirs: BinaryHeap<Reverse<Entry>> =
                entries.iter().map(|&e| Reverse(e)).collect();
            assert_eq!(ours.len(), n);
            for _ in 0..20 * n {
                let Some(Reverse(top)) = theirs.peek().copied() else {
                    unreachable!("n > 0")
                };
                assert_eq!(ours.peek(), Some(top), "{n} entries");
                let next = (top.0 + rng.range(0, 60) as Nanos, top.1);
                theirs.pop();
                theirs.push(Reverse(next));
                ours.replace_top(next);
            }
            let mut all: Vec<Entry> = ours.iter().collect();
            all.sort_unstable();
            let mut want: Vec<Entry> = theirs.into_iter().map(|Reverse(e)| e).collect();
            want.sort_unstable();
            assert_eq!(all, want);
        }
        assert_eq!(ReleaseHeap::new([]).peek(), None);
    }
}
