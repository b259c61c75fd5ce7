//! A histogram of latencies in integer ns that holds a run of any length in
//! bounded memory: exact (one count per distinct value) while the values
//! take at most [`EXACT_CAP`] distinct values, log-bucketed beyond that
//! with a relative error below 2^-[`COARSE_BITS`] (< 0.8 %) on quantiles
//! and on counts near a threshold. Count, sum (so the mean), min and max
//! stay exact either way.

use rtpipe_model::Nanos;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Hashes an integer key by one multiplication (Fibonacci hashing): the
/// keys are latencies, not attacker-chosen, and SipHash's cost showed in
/// every sample a run counts. Fixed, so iteration order is too.
#[derive(Debug, Clone, Copy, Default)]
pub struct IntHasher(u64);

impl Hasher for IntHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    fn write_i64(&mut self, v: i64) {
        // The product's high bits are the well-mixed ones: hashbrown takes
        // its control byte from the top 7 and the bucket from the low bits,
        // so the high half is folded into the low (latencies are often
        // multiples of 1000, whose low bits a product alone keeps at 0).
        let x = (v as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = x ^ (x >> 32);
    }
}

type Counts = HashMap<Nanos, u64, BuildHasherDefault<IntHasher>>;

/// Distinct values kept exactly; beyond it the histogram turns coarse.
pub const EXACT_CAP: usize = 1 << 16;

/// Mantissa bits of a coarse bucket: a bucket `[lo, hi)` has
/// `hi - lo <= lo / 2^COARSE_BITS`.
pub const COARSE_BITS: u32 = 7;

/// Counts of observed values (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Histogram {
    /// Value (exact) or bucket's lower end (coarse) → count (hashed: a
    /// push is O(1); the queries sort, and they are few).
    counts: Counts,
    coarse: bool,
    count: u64,
    sum: i128,
    min: Option<Nanos>,
    max: Option<Nanos>,
}

/// The lower end of the coarse bucket holding `v` (values below
/// 2^(COARSE_BITS+1) have a bucket each).
fn bucket(v: Nanos) -> Nanos {
    let u = v.max(0) as u64;
    if u < 1 << (COARSE_BITS + 1) {
        return u as Nanos;
    }
    let shift = 63 - u.leading_zeros() - COARSE_BITS;
    ((u >> shift) << shift) as Nanos
}

/// One past the upper end of the coarse bucket starting at `lo`.
fn bucket_end(lo: Nanos) -> Nanos {
    let u = lo.max(0) as u64;
    if u < 1 << (COARSE_BITS + 1) {
        return lo.saturating_add(1);
    }
    let shift = 63 - u.leading_zeros() - COARSE_BITS;
    lo.saturating_add(1 << shift)
}

impl Histogram {
    /// Counts one value.
    pub fn push(&mut self, v: Nanos) {
        let key = if self.coarse { bucket(v) } else { v };
        *self.counts.entry(key).or_insert(0) += 1;
        self.count += 1;
        self.sum += i128::from(v);
        self.min = Some(self.min.map_or(v, |m| m.min(v)));
        self.max = Some(self.max.map_or(v, |m| m.max(v)));
        if !self.coarse && self.counts.len() > EXACT_CAP {
            let exact = std::mem::take(&mut self.counts);
            for (v, n) in exact {
                *self.counts.entry(bucket(v)).or_insert(0) += n;
            }
            self.coarse = true;
        }
    }

    /// A histogram of `values`.
    pub fn of(values: &[Nanos]) -> Histogram {
        let mut h = Histogram::default();
        for &v in values {
            h.push(v);
        }
        h
    }

    /// How many values.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Whether every value is held exactly (no bucketing happened).
    pub fn is_exact(&self) -> bool {
        !self.coarse
    }

    /// The smallest value (exact).
    pub fn min(&self) -> Option<Nanos> {
        self.min
    }

    /// The largest value (exact).
    pub fn max(&self) -> Option<Nanos> {
        self.max
    }

    /// The mean, from the exact sum.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum as f64 / self.count as f64)
    }

    /// Each distinct value (coarse: each bucket's upper end, clamped to the
    /// observed range) with its count, in ascending order.
    pub fn entries(&self) -> Vec<(Nanos, u64)> {
        let mut v: Vec<(Nanos, u64)> = self.unordered().collect();
        v.sort_unstable();
        v
    }

    /// [`entries`](Histogram::entries) in no particular order.
    fn unordered(&self) -> impl Iterator<Item = (Nanos, u64)> + '_ {
        let (lo, hi) = (self.min.unwrap_or(0), self.max.unwrap_or(0));
        self.counts.iter().map(move |(&k, &n)| {
            let v = if self.coarse {
                (bucket_end(k) - 1).clamp(lo, hi)
            } else {
                k
            };
            (v, n)
        })
    }

    /// The value of nearest rank `rank` (1-based, clamped to the count);
    /// `None` without values.
    pub fn at_rank(&self, rank: u64) -> Option<Nanos> {
        let rank = rank.clamp(1, self.count.max(1));
        let mut seen = 0;
        for (v, n) in self.entries() {
            seen += n;
            if seen >= rank {
                return Some(v);
            }
        }
        None
    }

    /// The nearest-rank q-th percentile (q in 1..=100).
    pub fn percentile(&self, q: u64) -> Option<Nanos> {
        self.at_rank((self.count * q).div_ceil(100))
    }

    /// How many values satisfy `f` (coarse: judged on each bucket's value
    /// as [`entries`](Histogram::entries) gives it).
    pub fn count_where(&self, f: impl Fn(Nanos) -> bool) -> u64 {
        self.unordered()
            .filter(|&(v, _)| f(v))
            .map(|(_, n)| n)
            .sum()
    }

    /// Every value in ascending order (coarse: as `entries` gives them).
    pub fn sorted(&self) -> Vec<Nanos> {
        self.entries()
            .into_iter()
            .flat_map(|(v, n)| std::iter::repeat_n(v, n as usize))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_below_the_cap() {
        let h = Histogram::of(&[5, 1, 5, 9]);
        assert!(h.is_exact());
        assert_eq!((h.count(), h.min(), h.max()), (4, Some(1), Some(9)));
        assert_eq!(h.mean(), Some(5.0));
        assert_eq!(h.sorted(), vec![1, 5, 5, 9]);
        assert_eq!(h.percentile(99), Some(9));
        assert_eq!(h.percentile(50), Some(5));
        assert_eq!(h.count_where(|v| v > 5), 1);
        assert_eq!(Histogram::default().percentile(99), None);
    }

    #[test]
    fn coarse_beyond_the_cap_within_the_stated_error() {
        let mut h = Histogram::default();
        let n = 3 * EXACT_CAP as i64;
        for k in 0..n {
            h.push(1_000_000 + 7 * k);
        }
        assert!(!h.is_exact());
        assert!(h.counts.len() <= EXACT_CAP);
        assert_eq!(h.count(), n as u64);
        assert_eq!(
            (h.min(), h.max()),
            (Some(1_000_000), Some(1_000_000 + 7 * (n - 1)))
        );
        let exact_p99 = 1_000_000 + 7 * ((n as u64 * 99).div_ceil(100) as i64 - 1);
        let p99 = h.percentile(99).unwrap_or(0);
        let err = (p99 - exact_p99).abs() as f64 / exact_p99 as f64;
        assert!(
            err < 1.0 / f64::from(1u32 << COARSE_BITS),
            "{p99} vs {exact_p99}"
        );
        let mean = 1_000_000.0 + 7.0 * (n - 1) as f64 / 2.0;
        assert_eq!(h.mean(), Some(mean));
    }

    #[test]
    fn buckets_tile_the_line() {
        for v in [0, 1, 255, 256, 257, 1000, 123_456_789, i64::MAX / 2] {
            let lo = bucket(v);
            assert!(lo <= v && v < bucket_end(lo), "{v}");
            assert_eq!(bucket(bucket_end(lo) - 1), lo, "{v}");
        }
    }
}
