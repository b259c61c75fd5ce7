//! Whether a long-run load `Σ C/T` reaches 1, decided the same way
//! whatever the order of its terms: the one guard of `sched`'s level-i
//! busy period and busy window and of `thread_rta`'s FIFO busy period (at
//! 1 or more no busy period ends). A floating-point sum of the terms
//! could decide `≥ 1` one way in one order and the other in another for a
//! load within rounding of 1; this one decides on the exact sum (below),
//! so callers may hand the terms in any order. docs/analysis.md, "Cost at
//! 1,000 tasks", tenth round.

use rtpipe_model::Nanos;

/// `Σ C/T ≥ 1` over `terms` as (C, T), with C ≥ 0 and T > 0 (a task's
/// work and period, as validated, or a stream's, which
/// [`crate::arrivals::Arrivals`] asserts; the exact sums assert it): exactly,
/// except where the sum is within `n·2⁻⁶⁴` of 1 (`n` terms) and the exact
/// sum of fractions passes `u128`, where the load is called full (every
/// figure that needs it below 1 then unbounded: sound).
///
/// First the sum in `f64`, in the order handed: each term `C/T` comes
/// within a relative `3u` of its value (`u = 2⁻⁵³`: the two conversions
/// and the division) and a sum of `n` non-negative terms within `(n−1)u`
/// of theirs, so the computed `s` is within a relative
/// `ε ≤ (n + 3)u/(1 − (n + 3)u)` of the exact sum `X`, whatever the
/// order. With the margin `m = (n + 4)·2⁻⁵⁰ > ε`, `s ≥ 1 + m` gives
/// `X ≥ s/(1 + ε) > 1` and `s < 1 − m` gives `X ≤ s/(1 − ε) < 1`. Only
/// between the two is the exact sum looked at ([`exactly_full`]).
#[inline]
pub fn full(terms: impl Iterator<Item = (Nanos, Nanos)> + Clone) -> bool {
    // A fold, not a loop: the callers' chained and nested iterators then
    // run as plain loops (the periodic analysis asks this of every task's
    // tasks above, twice).
    let (sum, n) = terms.clone().fold((0.0f64, 0usize), |(sum, n), (c, t)| {
        (sum + c as f64 / t as f64, n + 1)
    });
    // 2⁻⁵⁰ = 4·2⁻⁵²; (n + 4)·2⁻⁵⁰ is exact in f64 for any n of terms.
    let margin = (n as f64 + 4.0) * (4.0 * f64::EPSILON);
    if sum >= 1.0 + margin {
        return true;
    }
    if sum < 1.0 - margin {
        return false;
    }
    exactly_full(terms)
}

/// `Σ C/T ≥ 1` on integers: each term as `⌊C·2⁶⁴/T⌋`, whose sum `lo`
/// is at most `X·2⁶⁴` and, with `k` of the terms inexact, below
/// `lo + k` (equal to it when `k = 0`); where those two do not decide,
/// the sum of the fractions themselves, reduced as it goes, in `u128`
/// (full when that overflows).
fn exactly_full(terms: impl Iterator<Item = (Nanos, Nanos)> + Clone) -> bool {
    const ONE: u128 = 1 << 64;
    let (mut lo, mut inexact) = (0u128, 0u128);
    for (c, t) in terms.clone() {
        assert!(c >= 0 && t > 0, "a load term of work {c} every {t}");
        let (c, t) = (c.unsigned_abs() as u128, t.unsigned_abs() as u128);
        if c >= t {
            return true;
        }
        // c < t < 2⁶³: the shift fits, the quotient is below 2⁶⁴, and
        // `lo` stays below ONE (checked each term) plus one term.
        lo += (c << 64) / t;
        inexact += u128::from((c << 64) % t != 0);
        if lo >= ONE {
            return true;
        }
    }
    if lo.saturating_add(inexact) <= ONE && (inexact > 0 || lo < ONE) {
        return false;
    }
    fraction_sum_full(terms).unwrap_or(true)
}

/// `Σ C/T ≥ 1` as a fraction `p/q` added term by term, reduced by the
/// gcd each time (`None`: it passed `u128`).
fn fraction_sum_full(terms: impl Iterator<Item = (Nanos, Nanos)>) -> Option<bool> {
    let (mut p, mut q) = (0u128, 1u128);
    for (c, t) in terms {
        let (c, t) = (c.unsigned_abs() as u128, t.unsigned_abs() as u128);
        let g = gcd(q, t);
        let (qg, tg) = (q / g, t / g);
        p = p.checked_mul(tg)?.checked_add(c.checked_mul(qg)?)?;
        q = q.checked_mul(tg)?;
        let r = gcd(p, q);
        (p, q) = (p / r, q / r);
    }
    Some(p >= q)
}

/// Euclid's greatest common divisor (`gcd(0, q) = q`).
fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thirds_make_one() {
        assert!(full([(1, 3), (1, 3), (1, 3)].into_iter()));
        assert!(!full([(1, 3), (1, 3), (1, 4)].into_iter()));
    }

    #[test]
    fn a_load_a_hair_below_one_is_below_whatever_the_order() {
        // 1 − 1/(3·big) in all: within the f64 sum's margin of 1, so the
        // exact sums decide.
        let big: Nanos = (1 << 60) - 1;
        let terms = [(big - 1, big), (1, 3 * big), (1, 3 * big)];
        assert!(!full(terms.into_iter()));
        assert!(!full(terms.into_iter().rev()));
        let exact = [(big - 1, big), (1, 3 * big), (1, 3 * big), (1, 3 * big)];
        assert!(full(exact.into_iter()));
        assert!(full(exact.into_iter().rev()));
    }

    #[test]
    fn one_term_at_or_past_its_period_is_full() {
        assert!(full([(5, 5)].into_iter()));
        assert!(full([(0, 7), (9, 5)].into_iter()));
        assert!(!full([(0, 7), (4, 5)].into_iter()));
        assert!(!full(std::iter::empty()));
    }

    #[test]
    fn an_exact_sum_past_u128_is_full() {
        // Distinct large primes: the common denominator passes u128.
        let primes: [Nanos; 4] = [
            2_305_843_009_213_693_951,
            1_000_000_007,
            1_000_000_009,
            998_244_353,
        ];
        assert_eq!(fraction_sum_full(primes.iter().map(|&p| (1, p))), None);
    }
}
