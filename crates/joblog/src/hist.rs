//! A histogram of latencies in integer ns that holds a run of any length in
//! bounded memory: exact (one count per distinct value) while the values
//! take at most [`EXACT_CAP`] distinct values, log-bucketed beyond that
//! with a relative error below 2^-[`COARSE_BITS`] (< 0.8 %) on quantiles
//! and on counts near a threshold. Count, sum (so the mean), min and max
//! stay exact either way.

use rtpipe_model::Nanos;
use std::borrow::Cow;

/// Distinct values kept exactly; beyond it the histogram turns coarse.
pub const EXACT_CAP: usize = 1 << 16;

/// Mantissa bits of a coarse bucket: a bucket `[lo, hi)` has
/// `hi - lo <= lo / 2^COARSE_BITS`.
pub const COARSE_BITS: u32 = 7;

/// Values held unsorted before they are merged into the counts: a push
/// is an append, and the sort and merge run once per this many (a hash
/// table of up to [`EXACT_CAP`] entries cost a cache miss per push).
const PENDING_CAP: usize = 1 << 14;

/// Counts of observed values (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Histogram {
    /// Value (exact) or bucket's lower end (coarse) → count, ascending by
    /// key, each key once.
    counts: Vec<(Nanos, u64)>,
    /// Values pushed since the last merge, in push order.
    pending: Vec<Nanos>,
    coarse: bool,
    count: u64,
    sum: i128,
    min: Option<Nanos>,
    max: Option<Nanos>,
}

/// Two histograms are equal when they hold the same values (however much
/// of them waits unmerged).
impl PartialEq for Histogram {
    fn eq(&self, o: &Histogram) -> bool {
        (self.count, self.sum, self.min, self.max) == (o.count, o.sum, o.min, o.max)
            && self.settled() == o.settled()
    }
}

impl Eq for Histogram {}

/// `counts` (ascending, keys distinct) with `keys` (ascending) added, one
/// count each.
fn merged(counts: &[(Nanos, u64)], keys: &[Nanos]) -> Vec<(Nanos, u64)> {
    let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(counts.len() + keys.len().min(EXACT_CAP));
    let (mut i, mut j) = (0, 0);
    while j < keys.len() {
        let v = keys[j];
        while i < counts.len() && counts[i].0 < v {
            out.push(counts[i]);
            i += 1;
        }
        let mut n = 0;
        while j < keys.len() && keys[j] == v {
            n += 1;
            j += 1;
        }
        if i < counts.len() && counts[i].0 == v {
            n += counts[i].1;
            i += 1;
        }
        out.push((v, n));
    }
    out.extend_from_slice(&counts[i..]);
    out
}

/// Sorts `values` ascending: an LSD radix sort on their offsets from the
/// least (three 11-bit digits) when they span less than 2^33 ns, as a
/// run's latencies do; a comparison sort otherwise.
fn sort_values(values: &mut [Nanos]) {
    const BITS: u32 = 11;
    let (Some(&lo), Some(&hi)) = (values.iter().min(), values.iter().max()) else {
        return;
    };
    let span = hi.abs_diff(lo);
    if values.len() < 256 || span >= 1 << (3 * BITS) {
        values.sort_unstable();
        return;
    }
    let mut from: Vec<u64> = values.iter().map(|&v| v.abs_diff(lo)).collect();
    let mut to = vec![0u64; from.len()];
    for pass in 0..3 {
        let shift = pass * BITS;
        if span >> shift == 0 {
            break;
        }
        let digit = |x: u64| ((x >> shift) & ((1 << BITS) - 1)) as usize;
        let mut at = vec![0usize; 1 << BITS];
        from.iter().for_each(|&x| at[digit(x)] += 1);
        let mut sum = 0;
        for a in at.iter_mut() {
            (*a, sum) = (sum, sum + *a);
        }
        for &x in &from {
            to[at[digit(x)]] = x;
            at[digit(x)] += 1;
        }
        std::mem::swap(&mut from, &mut to);
    }
    for (v, x) in values.iter_mut().zip(from) {
        *v = lo + x as Nanos;
    }
}

/// Exact counts (ascending) as coarse buckets: `bucket` is monotone, so
/// the order holds and equal buckets are adjacent.
fn coarsened(exact: &[(Nanos, u64)]) -> Vec<(Nanos, u64)> {
    let mut out: Vec<(Nanos, u64)> = Vec::new();
    for &(v, n) in exact {
        let b = bucket(v);
        match out.last_mut() {
            Some(last) if last.0 == b => last.1 += n,
            _ => out.push((b, n)),
        }
    }
    out
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
        self.pending.push(v);
        self.count += 1;
        self.sum += i128::from(v);
        self.min = Some(self.min.map_or(v, |m| m.min(v)));
        self.max = Some(self.max.map_or(v, |m| m.max(v)));
        if self.pending.len() >= PENDING_CAP {
            let mut keys = std::mem::take(&mut self.pending);
            (self.counts, self.coarse) = self.merge(&mut keys);
            keys.clear();
            self.pending = keys;
        }
    }

    /// The counts with `values` merged in (sorting them in place), and
    /// whether they are coarse: they turn coarse when the distinct values
    /// pass the cap (distinct values only grow, so when the merge happens
    /// does not change the outcome).
    fn merge(&self, values: &mut [Nanos]) -> (Vec<(Nanos, u64)>, bool) {
        if self.coarse {
            values.iter_mut().for_each(|v| *v = bucket(*v));
        }
        sort_values(values);
        let counts = merged(&self.counts, values);
        if !self.coarse && counts.len() > EXACT_CAP {
            (coarsened(&counts), true)
        } else {
            (counts, self.coarse)
        }
    }

    /// The counts, ascending, and whether they are coarse, pending values
    /// included.
    fn settled(&self) -> (Cow<'_, [(Nanos, u64)]>, bool) {
        if self.pending.is_empty() {
            (Cow::Borrowed(&self.counts), self.coarse)
        } else {
            let (counts, coarse) = self.merge(&mut self.pending.clone());
            (Cow::Owned(counts), coarse)
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
        !self.settled().1
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
        let (lo, hi) = (self.min.unwrap_or(0), self.max.unwrap_or(0));
        let (counts, coarse) = self.settled();
        if !coarse {
            return counts.into_owned();
        }
        // A bucket's upper end is monotone in its lower end, and the
        // clamp keeps the order (equal ends only at the range's edges).
        let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(counts.len());
        for &(k, n) in counts.iter() {
            let v = (bucket_end(k) - 1).clamp(lo, hi);
            match out.last_mut() {
                Some(last) if last.0 == v => last.1 += n,
                _ => out.push((v, n)),
            }
        }
        out
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
        self.entries()
            .into_iter()
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
        assert!(h.settled().0.len() <= EXACT_CAP);
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
    fn the_radix_sort_sorts() {
        let mut rng = 0x2545_F491_4F6C_DD1Du64;
        for (n, span) in [
            (300, 1000),
            (5000, 1 << 20),
            (5000, 1 << 33),
            (5000, 1 << 40),
        ] {
            let mut v: Vec<Nanos> = (0..n)
                .map(|_| {
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    -12_345 + (rng % span) as Nanos
                })
                .collect();
            let mut want = v.clone();
            want.sort_unstable();
            sort_values(&mut v);
            assert_eq!(v, want, "n {n}, span {span}");
        }
    }

    #[test]
    fn merging_in_batches_counts_as_pushing_one_by_one() {
        // Crosses the pending cap several times, repeating values.
        let mut h = Histogram::default();
        let mut want = std::collections::BTreeMap::new();
        for k in 0..(5 * PENDING_CAP as i64) {
            let v = (k * 7919) % 40_000;
            h.push(v);
            *want.entry(v).or_insert(0u64) += 1;
        }
        let want: Vec<(Nanos, u64)> = want.into_iter().collect();
        assert!(h.is_exact());
        assert_eq!(h.entries(), want);
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
