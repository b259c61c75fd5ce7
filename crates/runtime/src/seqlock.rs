//! A sequence lock over `N` 64-bit words, for the benchmark against the
//! four-slot register (`benches/registers.rs`). The data words are atomics
//! accessed with `Relaxed` ordering, so a reader racing the writer reads
//! stale or mixed words (and retries), never undefined behaviour. Single
//! writer; readers retry while a write is in progress, so a read is not
//! wait-free: that is the difference with [`crate::four_slot`].

use std::sync::atomic::{fence, AtomicU64, Ordering};

/// A seqlock holding `[u64; N]`.
pub struct SeqLock<const N: usize> {
    seq: AtomicU64,
    data: [AtomicU64; N],
}

impl<const N: usize> SeqLock<N> {
    /// A seqlock holding `v`.
    pub fn new(v: [u64; N]) -> Self {
        SeqLock {
            seq: AtomicU64::new(0),
            data: v.map(AtomicU64::new),
        }
    }

    /// Writes `v`. Only one thread may write (the caller's discipline).
    pub fn write(&self, v: [u64; N]) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        for (d, x) in self.data.iter().zip(v) {
            d.store(x, Ordering::Relaxed);
        }
        self.seq.store(s.wrapping_add(2), Ordering::Release);
    }

    /// Reads a consistent value, retrying while a write overlaps.
    pub fn read(&self) -> [u64; N] {
        loop {
            let s1 = self.seq.load(Ordering::Acquire);
            if s1 & 1 == 0 {
                let mut out = [0; N];
                for (o, d) in out.iter_mut().zip(&self.data) {
                    *o = d.load(Ordering::Relaxed);
                }
                fence(Ordering::Acquire);
                if self.seq.load(Ordering::Relaxed) == s1 {
                    return out;
                }
            }
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn never_returns_a_torn_value() {
        let l = std::sync::Arc::new(SeqLock::new([0u64; 8]));
        let w = std::sync::Arc::clone(&l);
        let h = std::thread::spawn(move || {
            for k in 1..=200_000u64 {
                w.write([k; 8]);
            }
        });
        let mut last = 0;
        while last < 200_000 {
            let v = l.read();
            assert!(v.iter().all(|&x| x == v[0]), "torn: {v:?}");
            assert!(v[0] >= last);
            last = v[0];
        }
        assert!(h.join().is_ok());
    }
}
