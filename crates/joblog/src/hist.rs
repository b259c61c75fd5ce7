//! A histogram of latencies in integer ns that holds a run of any length in
//! bounded memory. The highest values are counted exactly (one count per
//! distinct value, at most the histogram's exact cap of them, see
//! [`exact_cap`]); when there are more, the lowest are moved into
//! log-linear buckets with a relative width below 2^-[`COARSE_BITS`]
//! (< 0.8 %), keeping the top half of the cap exact. So a p99 is exact
//! while its rank falls among the exact values (at least up to 50 × the
//! cap values, however many distinct), and so is a count above a bound
//! at or above the least exact value; below, they are within the
//! buckets' width. Count, sum (so the mean), min and max stay exact
//! either way. The heap never passes [`Histogram::max_heap_bytes`],
//! however many values are counted: a run's memory is bounded by the
//! number of its chains, not by its span.

use rtpipe_model::Nanos;
use std::borrow::Cow;

/// Distinct values a run's histograms count exactly between them (2 MiB
/// of counts), shared out by [`exact_cap`]: a run keeps four histograms
/// per chain, and when each kept 65,536 they grew towards 2 MB each (the
/// counts, and a merge's copy of them) over a long span, 800 MB for 100
/// chains. A few chains keep thousands each (cleanflight's three: 10,922),
/// so their figures stay exact over long runs.
pub const EXACT_BUDGET: usize = 1 << 17;

/// The least exact cap of a histogram, however many share the budget:
/// 8 KiB of counts.
pub const EXACT_CAP_MIN: usize = 1 << 9;

/// The most, for a histogram alone (its default).
pub const EXACT_CAP_MAX: usize = 1 << 16;

/// Each of `histograms` histograms' exact cap: its share of
/// [`EXACT_BUDGET`], within [`EXACT_CAP_MIN`]..=[`EXACT_CAP_MAX`].
pub fn exact_cap(histograms: usize) -> usize {
    (EXACT_BUDGET / histograms.max(1)).clamp(EXACT_CAP_MIN, EXACT_CAP_MAX)
}

/// Mantissa bits of a coarse bucket: a bucket `[lo, hi)` has
/// `hi - lo <= lo / 2^COARSE_BITS`.
pub const COARSE_BITS: u32 = 7;

/// At most this many values are held unsorted before they are merged
/// into the counts: a push is an append, and the sort and merge run once
/// per this many, or per half the exact cap when that is less, so a merge
/// costs a few steps per value (a hash table of the counts cost a cache
/// miss per push).
const PENDING_MAX: usize = 1 << 14;

/// Coarse buckets of the whole non-negative `Nanos` range: one per value
/// below 2^(COARSE_BITS+1), then 2^COARSE_BITS per octave (a run's
/// latencies span a few octaves, so a few hundred of them are used).
const COARSE_BUCKETS: usize =
    (1 << (COARSE_BITS + 1)) + (62 - COARSE_BITS as usize) * (1 << COARSE_BITS);

/// Value or bucket → count, ascending, each key once.
type Counts = Vec<(Nanos, u64)>;

/// Counts of observed values (see the module docs).
#[derive(Debug, Clone)]
pub struct Histogram {
    /// Distinct values counted exactly before the lowest are bucketed.
    cap: usize,
    /// Value → count, ascending by value, each value once: the highest
    /// values, every value while `buckets` is empty.
    exact: Vec<(Nanos, u64)>,
    /// Bucket's lower end → count, ascending, each bucket once: every
    /// value below the least in `exact`.
    buckets: Vec<(Nanos, u64)>,
    /// Values pushed since the last merge, in push order.
    pending: Vec<Nanos>,
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

/// A histogram alone: the largest exact cap.
impl Default for Histogram {
    fn default() -> Histogram {
        Histogram::with_exact_cap(EXACT_CAP_MAX)
    }
}

/// `counts` (ascending, keys distinct) with `keys` (ascending) added, one
/// count each.
fn merged(counts: &[(Nanos, u64)], keys: &[Nanos]) -> Vec<(Nanos, u64)> {
    let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(counts.len() + keys.len());
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

/// Two count lists (each ascending, keys distinct) as one.
fn merged_counts(a: &[(Nanos, u64)], b: &[(Nanos, u64)]) -> Vec<(Nanos, u64)> {
    let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                out.push((a[i].0, a[i].1 + b[j].1));
                (i, j) = (i + 1, j + 1);
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// Exact counts (ascending) as coarse buckets: `bucket` is monotone, so
/// the order holds and equal buckets are adjacent.
fn coarsened(exact: &[(Nanos, u64)]) -> Vec<(Nanos, u64)> {
    let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(exact.len().min(COARSE_BUCKETS));
    for &(v, n) in exact {
        let b = bucket(v);
        match out.last_mut() {
            Some(last) if last.0 == b => last.1 += n,
            _ => out.push((b, n)),
        }
    }
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
        if self.pending.len() >= self.pending_cap() {
            let mut values = std::mem::take(&mut self.pending);
            (self.exact, self.buckets) = self.merge(&mut values);
            values.clear();
            self.pending = values;
        }
    }

    /// The exact counts and the buckets with `values` merged in (sorting
    /// them in place). A value below the least exact one, once there are
    /// buckets, is bucketed (the buckets hold only values below the exact
    /// ones); past the exact cap the lowest are bucketed, down to half.
    fn merge(&self, values: &mut [Nanos]) -> (Counts, Counts) {
        sort_values(values);
        let floor = match (self.buckets.is_empty(), self.exact.first()) {
            (false, Some(&(least, _))) => values.partition_point(|&v| v < least),
            _ => 0,
        };
        let (below, rest) = values.split_at(floor);
        let mut exact = merged(&self.exact, rest);
        let mut low: Vec<(Nanos, u64)> = merged(&[], below);
        if exact.len() > self.cap {
            let spill = exact.len() - self.cap / 2;
            low = merged_counts(&low, &exact[..spill]);
            exact.drain(..spill);
        }
        if low.is_empty() {
            return (exact, self.buckets.clone());
        }
        (exact, merged_counts(&self.buckets, &coarsened(&low)))
    }

    /// The exact counts and the buckets, pending values included.
    #[allow(clippy::type_complexity)]
    fn settled(&self) -> (Cow<'_, [(Nanos, u64)]>, Cow<'_, [(Nanos, u64)]>) {
        if self.pending.is_empty() {
            (Cow::Borrowed(&self.exact), Cow::Borrowed(&self.buckets))
        } else {
            let (exact, buckets) = self.merge(&mut self.pending.clone());
            (Cow::Owned(exact), Cow::Owned(buckets))
        }
    }

    /// An empty histogram that counts up to `cap` distinct values exactly
    /// (see [`exact_cap`]).
    pub fn with_exact_cap(cap: usize) -> Histogram {
        assert!(cap >= 2, "an exact cap of {cap} keeps no exact top");
        Histogram {
            cap,
            exact: Vec::new(),
            buckets: Vec::new(),
            pending: Vec::new(),
            count: 0,
            sum: 0,
            min: None,
            max: None,
        }
    }

    fn pending_cap(&self) -> usize {
        (self.cap / 2).clamp(1, PENDING_MAX)
    }

    /// The most heap it holds between pushes, however many values it
    /// counts: the exact counts with one merge's values, every bucket,
    /// and the pending values (a merge briefly holds a second copy).
    pub fn max_heap_bytes(&self) -> usize {
        let pending = self.pending_cap();
        (self.cap + pending + COARSE_BUCKETS) * std::mem::size_of::<(Nanos, u64)>()
            + pending * std::mem::size_of::<Nanos>()
    }

    /// A histogram of `values`.
    pub fn of(values: &[Nanos]) -> Histogram {
        let mut h = Histogram::default();
        for &v in values {
            h.push(v);
        }
        h
    }

    /// The bytes of heap it holds now (at most
    /// [`max_heap_bytes`](Histogram::max_heap_bytes)).
    pub fn heap_bytes(&self) -> usize {
        (self.exact.capacity() + self.buckets.capacity()) * std::mem::size_of::<(Nanos, u64)>()
            + self.pending.capacity() * std::mem::size_of::<Nanos>()
    }

    /// How many values.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Whether every value is held exactly (no bucketing happened).
    pub fn is_exact(&self) -> bool {
        self.settled().1.is_empty()
    }

    /// Whether the value of nearest rank `rank` is exact: no value is
    /// bucketed, or the rank falls among the exact values above them.
    pub fn is_exact_at_rank(&self, rank: u64) -> bool {
        let bucketed: u64 = self.settled().1.iter().map(|&(_, n)| n).sum();
        rank.clamp(1, self.count.max(1)) > bucketed
    }

    /// Whether [`percentile`](Histogram::percentile)`(q)` is exact.
    pub fn is_exact_percentile(&self, q: u64) -> bool {
        self.is_exact_at_rank((self.count * q).div_ceil(100))
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

    /// Each distinct value with its count, in ascending order: a bucket
    /// as its upper end, clamped to the observed range and below the
    /// least exact value (every value it holds is), then the exact ones.
    pub fn entries(&self) -> Vec<(Nanos, u64)> {
        let (exact, buckets) = self.settled();
        let lo = self.min.unwrap_or(0);
        let hi = exact.first().map_or(self.max.unwrap_or(0), |&(v, _)| v - 1);
        let mut out: Vec<(Nanos, u64)> = Vec::with_capacity(buckets.len() + exact.len());
        // A bucket's upper end is monotone in its lower end, and the
        // clamp keeps the order (equal ends only at the range's edges).
        for &(k, n) in buckets.iter() {
            let v = (bucket_end(k) - 1).clamp(lo, hi.max(lo));
            match out.last_mut() {
                Some(last) if last.0 == v => last.1 += n,
                _ => out.push((v, n)),
            }
        }
        out.extend_from_slice(&exact);
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

    /// How many values satisfy `f` (a bucketed value: judged on its
    /// bucket's value as [`entries`](Histogram::entries) gives it).
    pub fn count_where(&self, f: impl Fn(Nanos) -> bool) -> u64 {
        self.entries()
            .into_iter()
            .filter(|&(v, _)| f(v))
            .map(|(_, n)| n)
            .sum()
    }

    /// Every value in ascending order (bucketed ones as `entries` gives
    /// them).
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

    /// The cap of a histogram among many: bucketing starts early.
    const CAP: usize = EXACT_CAP_MIN;
    const TOP: usize = CAP / 2;

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
    fn coarse_beyond_the_exact_top_within_the_stated_error() {
        let mut h = Histogram::with_exact_cap(CAP);
        let n = 300 * TOP as i64;
        for k in 0..n {
            h.push(1_000_000 + 7 * k);
        }
        assert!(!h.is_exact() && !h.is_exact_percentile(99));
        assert!(h.settled().0.len() <= CAP);
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
    fn the_top_stays_exact_past_the_cap() {
        // 40 × the exact top, all distinct, in a scrambled order: the p99
        // and the counts above a high threshold are exact, below not.
        let n = 40 * TOP as i64;
        let values: Vec<Nanos> = (0..n).map(|k| 5_000 + (k * 7919) % n * 3).collect();
        let mut h = Histogram::with_exact_cap(CAP);
        values.iter().for_each(|&v| h.push(v));
        let mut sorted = values.clone();
        sorted.sort_unstable();
        assert!(!h.is_exact() && h.is_exact_percentile(99));
        let rank = (n as usize * 99).div_ceil(100);
        assert_eq!(h.percentile(99), Some(sorted[rank - 1]));
        let high = sorted[n as usize - TOP / 2];
        let above = sorted.iter().filter(|&&v| v > high).count() as u64;
        assert_eq!(h.count_where(|v| v > high), above);
        assert!(!h.is_exact_percentile(50));
        let entries = h.entries();
        assert!(entries.windows(2).all(|w| w[0].0 < w[1].0), "ascending");
        assert_eq!(entries.iter().map(|e| e.1).sum::<u64>(), n as u64);
    }

    #[test]
    fn the_heap_is_bounded_whatever_the_count() {
        // Distinct values over 40 octaves: the worst a run's latencies do.
        let mut h = Histogram::with_exact_cap(CAP);
        let mut rng = rtpipe_model::gen::Rng::new(1);
        let mut held = Vec::new();
        for k in 0..4_000_000u64 {
            let x = rng.next_u64();
            h.push((x >> (24 + x % 40)) as Nanos);
            assert!(
                h.heap_bytes() <= h.max_heap_bytes(),
                "{} at {k}",
                h.heap_bytes()
            );
            if (k + 1) % 1_000_000 == 0 {
                held.push(h.heap_bytes());
            }
        }
        assert!(!h.is_exact());
        // Past the first million the buckets are all in use: flat, but
        // for how full the exact counts are at the moment.
        let (lo, hi) = (held.iter().min(), held.iter().max());
        assert!(hi.zip(lo).is_some_and(|(h, l)| h - l <= l / 10), "{held:?}");
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
        for k in 0..(5 * PENDING_MAX as i64) {
            let v = (k * 7919) % 40_000;
            h.push(v);
            *want.entry(v).or_insert(0u64) += 1;
        }
        let want: Vec<(Nanos, u64)> = want.into_iter().collect();
        assert!(h.is_exact());
        assert_eq!(h.entries(), want);
    }

    #[test]
    fn the_budget_is_shared_within_bounds() {
        assert_eq!(exact_cap(1), EXACT_CAP_MAX);
        assert_eq!(exact_cap(12), EXACT_BUDGET / 12);
        assert_eq!(exact_cap(400), EXACT_CAP_MIN);
        assert_eq!(exact_cap(0), EXACT_CAP_MAX);
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
