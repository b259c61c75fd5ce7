//! The CPUs' next events (a completion or a budget running out) in a
//! tournament tree (`cpus.rs` keeps it up to date).

use rtpipe_model::Nanos;

/// The CPUs' next events in a tournament tree: the earliest (then the
/// lowest CPU) at the root, an update O(log CPUs), no stale entries.
#[derive(Debug, Clone)]
pub(crate) struct CpuEvents {
    /// Leaves from `leaves` on; (`Nanos::MAX`, _) where a CPU has none.
    tree: Vec<(Nanos, usize)>,
    leaves: usize,
}

impl CpuEvents {
    pub(crate) fn new(cpus: usize) -> CpuEvents {
        let leaves = cpus.next_power_of_two().max(1);
        CpuEvents {
            tree: vec![(Nanos::MAX, usize::MAX); 2 * leaves],
            leaves,
        }
    }

    /// The earliest event and its CPU.
    pub(crate) fn first(&self) -> Option<(Nanos, usize)> {
        Some(self.tree[1]).filter(|&(at, _)| at != Nanos::MAX)
    }

    /// `cpu`'s event is now `at`.
    pub(crate) fn set(&mut self, cpu: usize, at: Option<Nanos>) {
        let mut k = self.leaves + cpu;
        self.tree[k] = (at.unwrap_or(Nanos::MAX), cpu);
        while k > 1 {
            k /= 2;
            self.tree[k] = self.tree[2 * k].min(self.tree[2 * k + 1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn earliest_then_lowest_cpu_first() {
        let mut e = CpuEvents::new(5);
        assert_eq!(e.first(), None);
        e.set(3, Some(20));
        e.set(4, Some(10));
        e.set(1, Some(10));
        assert_eq!(e.first(), Some((10, 1)));
        e.set(1, None);
        assert_eq!(e.first(), Some((10, 4)));
        e.set(4, Some(30));
        assert_eq!(e.first(), Some((20, 3)));
        e.set(3, None);
        e.set(4, None);
        assert_eq!(e.first(), None);
        assert_eq!(CpuEvents::new(0).first(), None);
    }
}
