//! Time: integer nanoseconds inside, human units at the edges.
//!
//! Specs accept bare numbers (in the system's `time_unit`) and strings with a
//! unit suffix (`"250us"`, `"1.5ms"`). Strings are parsed as exact decimals so
//! `"0.1ms"` is exactly 100000 ns, never 99999.99…

use std::borrow::Cow;
use std::fmt;

/// A duration or instant in integer nanoseconds.
pub type Nanos = i64;

/// The unit that bare numbers in a spec are expressed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    /// Nanoseconds.
    Ns,
    /// Microseconds.
    Us,
    /// Milliseconds.
    Ms,
    /// Seconds.
    S,
}

impl TimeUnit {
    /// Every unit, smallest first.
    pub const ALL: [TimeUnit; 4] = [TimeUnit::Ns, TimeUnit::Us, TimeUnit::Ms, TimeUnit::S];

    /// Nanoseconds in one unit.
    pub fn nanos(self) -> i64 {
        match self {
            TimeUnit::Ns => 1,
            TimeUnit::Us => 1_000,
            TimeUnit::Ms => 1_000_000,
            TimeUnit::S => 1_000_000_000,
        }
    }

    /// The unit's symbol, as written in specs (`ns`, `us`, `ms`, `s`).
    pub fn name(self) -> &'static str {
        match self {
            TimeUnit::Ns => "ns",
            TimeUnit::Us => "us",
            TimeUnit::Ms => "ms",
            TimeUnit::S => "s",
        }
    }

    /// Parses a unit name; `µs` is accepted beside `us`.
    pub fn parse(s: &str) -> Option<TimeUnit> {
        match s {
            "ns" => Some(TimeUnit::Ns),
            "us" | "µs" | "μs" => Some(TimeUnit::Us),
            "ms" => Some(TimeUnit::Ms),
            "s" => Some(TimeUnit::S),
            _ => None,
        }
    }

    /// Converts nanoseconds to this unit (for display and JSON).
    pub fn from_nanos(self, ns: Nanos) -> f64 {
        ns as f64 / self.nanos() as f64
    }
}

impl fmt::Display for TimeUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Largest time we accept: about 104 days, far beyond any period, and small
/// enough that sums of a few thousand of them cannot overflow an i64.
pub const MAX_TIME: Nanos = 1 << 53;

/// Why a time could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum TimeError {
    /// Not a number followed by a known unit.
    Syntax(String),
    /// Unknown unit suffix.
    Unit(String),
    /// Finer than one nanosecond.
    SubNanosecond,
    /// Larger than [`MAX_TIME`].
    TooLarge,
    /// NaN or an infinity.
    NotFinite,
}

impl fmt::Display for TimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TimeError::Syntax(s) => write!(
                f,
                "`{s}` is not a time; write a number with a unit, like \"250us\" or \"1.5ms\""
            ),
            TimeError::Unit(u) => write!(
                f,
                "unknown time unit `{u}`; use one of ns, us, ms, s (for example \"250us\")"
            ),
            TimeError::SubNanosecond => {
                write!(
                    f,
                    "time is below the model's 1 ns resolution (not a whole number of nanoseconds)"
                )
            }
            TimeError::TooLarge => write!(
                f,
                "time is too large (the limit is 2^53 ns = 9007199 s, about 104 days)"
            ),
            TimeError::NotFinite => write!(f, "not a finite number"),
        }
    }
}

/// Parses `"1.5ms"`, `"250 us"`, `"3s"`, `"100ns"` exactly.
pub fn parse_time_str(s: &str) -> Result<Nanos, TimeError> {
    let t = s.trim();
    let split = number_end(t);
    let (num, unit) = t.split_at(split);
    let unit = unit.trim();
    if num.is_empty() {
        return Err(TimeError::Syntax(s.to_string()));
    }
    if unit.is_empty() {
        return Err(TimeError::Syntax(s.to_string()));
    }
    let unit = TimeUnit::parse(unit).ok_or_else(|| TimeError::Unit(unit.to_string()))?;
    parse_decimal(num, unit.nanos()).ok_or_else(|| TimeError::Syntax(s.to_string()))?
}

/// Where the number of a time string ends: digits, signs, `.`, `_` and an
/// exponent (`e`/`E` followed by an optional sign and a digit; no unit starts
/// with `e`).
fn number_end(t: &str) -> usize {
    let b = t.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() || c == b'.' || c == b'-' || c == b'+' || c == b'_' {
            i += 1;
            continue;
        }
        if (c == b'e' || c == b'E') && i > 0 {
            let mut j = i + 1;
            if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                j += 1;
            }
            if j < b.len() && b[j].is_ascii_digit() {
                i = j;
                continue;
            }
        }
        break;
    }
    i
}

/// Exact decimal (with an optional exponent) × scale → integer, or an error
/// when not a whole number of ns. `None` is a syntax error. The number is
/// handled as a string of digits throughout, never as a float, so that every
/// decimal a user writes means exactly what it says.
fn parse_decimal(num: &str, scale: i64) -> Option<Result<Nanos, TimeError>> {
    let num = num.replace('_', "");
    let (neg, digits) = match num.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, num.strip_prefix('+').unwrap_or(&num)),
    };
    let (mantissa, exp) = split_exponent(digits)?;
    let (int, frac) = match mantissa.split_once('.') {
        Some((i, f)) => (i, f),
        None => (mantissa, ""),
    };
    if int.is_empty() && frac.is_empty() {
        return None;
    }
    if !int.chars().all(|c| c.is_ascii_digit()) || !frac.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    let (int, frac) = match shift_point(int, frac, exp) {
        Shifted::Digits(int, frac) => (int, frac),
        Shifted::Decided(r) => return Some(r),
    };
    Some(scale_digits(&int, &frac, scale).map(|v| if neg { -v } else { v }))
}

/// Splits an unsigned number into its mantissa and its exponent (0 when it
/// has none); `None` when the exponent is not a signed run of digits.
fn split_exponent(digits: &str) -> Option<(&str, i64)> {
    match digits.find(['e', 'E']) {
        Some(k) => {
            let e = &digits[k + 1..];
            let e_digits = e.strip_prefix(['+', '-']).unwrap_or(e);
            if e_digits.is_empty() || !e_digits.chars().all(|c| c.is_ascii_digit()) {
                return None;
            }
            // Exponents beyond a few hundred only decide zero / too large.
            let v: i64 = e_digits
                .get(..e_digits.len().min(6))
                .and_then(|d| d.parse().ok())
                .unwrap_or(999_999);
            Some((&digits[..k], if e.starts_with('-') { -v } else { v }))
        }
        None => Some((digits, 0)),
    }
}

/// The digits of a number once its exponent has moved the decimal point.
enum Shifted<'a> {
    /// The integer and fractional digits, still to be scaled.
    Digits(Cow<'a, str>, Cow<'a, str>),
    /// The exponent alone decides: zero, too large, or below a nanosecond.
    Decided(Result<Nanos, TimeError>),
}

/// Moves the decimal point of `int.frac` by `exp` places, on the digit
/// strings (so `1.5e-3` is exactly `0.0015`). A point moved more than 40
/// places from the first significant digit leaves no representable time.
fn shift_point<'a>(int: &'a str, frac: &'a str, exp: i64) -> Shifted<'a> {
    if exp == 0 {
        return Shifted::Digits(Cow::Borrowed(int), Cow::Borrowed(frac));
    }
    let all: String = format!("{int}{frac}");
    let all = all.trim_start_matches('0');
    if all.is_empty() {
        return Shifted::Decided(Ok(0));
    }
    // Position of the point in `all`, counted from its first digit.
    let lead_zeros = format!("{int}{frac}").len() - all.len();
    let point = int.len() as i64 - lead_zeros as i64 + exp;
    if point > 40 {
        return Shifted::Decided(Err(TimeError::TooLarge));
    }
    if point < -40 {
        return Shifted::Decided(Err(TimeError::SubNanosecond));
    }
    let (int, frac) = if point <= 0 {
        (
            String::new(),
            format!("{}{all}", "0".repeat((-point) as usize)),
        )
    } else if point as usize >= all.len() {
        (
            format!("{all}{}", "0".repeat(point as usize - all.len())),
            String::new(),
        )
    } else {
        (
            all[..point as usize].to_string(),
            all[point as usize..].to_string(),
        )
    };
    Shifted::Digits(Cow::Owned(int), Cow::Owned(frac))
}

/// `int.frac` × `scale` as whole nanoseconds: too large past [`MAX_TIME`]
/// (checked digit by digit, so no digit string can overflow), below a
/// nanosecond when a non-zero fractional digit falls below the scale.
fn scale_digits(int: &str, frac: &str, scale: i64) -> Result<Nanos, TimeError> {
    let mut value: i128 = 0;
    for c in int.chars() {
        value = value * 10 + (c as i128 - '0' as i128);
        if value > MAX_TIME as i128 {
            return Err(TimeError::TooLarge);
        }
    }
    value *= scale as i128;
    // Fractional digits: each must land on a whole nanosecond.
    let mut place = scale as i128;
    for c in frac.chars() {
        let d = c as i128 - '0' as i128;
        if place % 10 != 0 {
            if d != 0 {
                return Err(TimeError::SubNanosecond);
            }
            continue;
        }
        place /= 10;
        value += d * place;
    }
    if value > MAX_TIME as i128 {
        return Err(TimeError::TooLarge);
    }
    Ok(value as i64)
}

/// A bare number in `unit` to nanoseconds (rounded to the nearest ns, since
/// binary floats cannot hold most decimals exactly).
pub fn number_to_nanos(x: f64, unit: TimeUnit) -> Result<Nanos, TimeError> {
    if !x.is_finite() {
        return Err(TimeError::NotFinite);
    }
    let ns = x * unit.nanos() as f64;
    if ns.abs() > MAX_TIME as f64 {
        return Err(TimeError::TooLarge);
    }
    let r = ns.round();
    // A non-zero time that rounds to 0 ns is below the resolution, not zero.
    if (ns - r).abs() > 1e-6 * ns.abs().max(1.0) || (r == 0.0 && x != 0.0) {
        return Err(TimeError::SubNanosecond);
    }
    Ok(r as i64)
}

/// Greatest common divisor of two times (non-negative; `gcd(a, 0) = |a|`):
/// the grid of the design's periods and the simulator's search.
pub fn gcd(a: Nanos, b: Nanos) -> Nanos {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

/// Whether two periods are harmonic (`harmonic = true`): both positive and
/// one divides the other. The model checks fixed periods with it, the
/// design every candidate pair.
pub fn harmonic_pair(a: Nanos, b: Nanos) -> bool {
    a > 0 && b > 0 && (a % b == 0 || b % a == 0)
}

/// Formats nanoseconds in a unit with up to 6 significant decimals, trimming zeros.
pub fn format_in(ns: Nanos, unit: TimeUnit) -> String {
    let whole = ns / unit.nanos();
    let rem = (ns % unit.nanos()).abs();
    if rem == 0 {
        return whole.to_string();
    }
    let digits = match unit {
        TimeUnit::Ns => 0,
        TimeUnit::Us => 3,
        TimeUnit::Ms => 6,
        TimeUnit::S => 9,
    };
    let frac = format!("{rem:0digits$}");
    let frac = frac.trim_end_matches('0');
    let sign = if ns < 0 && whole == 0 { "-" } else { "" };
    format!("{sign}{whole}.{frac}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_exact_decimals() {
        assert_eq!(parse_time_str("1.5ms"), Ok(1_500_000));
        assert_eq!(parse_time_str("250us"), Ok(250_000));
        assert_eq!(parse_time_str("0.1ms"), Ok(100_000));
        assert_eq!(parse_time_str("3 s"), Ok(3_000_000_000));
        assert_eq!(parse_time_str("100ns"), Ok(100));
        assert_eq!(parse_time_str("2µs"), Ok(2_000));
        assert_eq!(parse_time_str("1.2500us"), Ok(1_250));
    }

    #[test]
    fn rejects_bad_times() {
        assert!(matches!(parse_time_str("5"), Err(TimeError::Syntax(_))));
        assert!(matches!(parse_time_str("5 msec"), Err(TimeError::Unit(_))));
        assert!(matches!(parse_time_str("ms"), Err(TimeError::Syntax(_))));
        assert_eq!(parse_time_str("1.5ns"), Err(TimeError::SubNanosecond));
        assert!(matches!(
            parse_time_str("1.2.3ms"),
            Err(TimeError::Syntax(_))
        ));
        assert_eq!(
            parse_time_str("99999999999999999999s"),
            Err(TimeError::TooLarge)
        );
    }

    #[test]
    fn numbers_round_to_nanoseconds() {
        assert_eq!(number_to_nanos(0.1, TimeUnit::Ms), Ok(100_000));
        assert_eq!(number_to_nanos(10.0, TimeUnit::Ms), Ok(10_000_000));
        assert_eq!(number_to_nanos(0.15, TimeUnit::Ms), Ok(150_000));
        assert_eq!(
            number_to_nanos(0.0001, TimeUnit::Ns),
            Err(TimeError::SubNanosecond)
        );
        assert_eq!(
            number_to_nanos(f64::NAN, TimeUnit::Ms),
            Err(TimeError::NotFinite)
        );
        assert_eq!(
            number_to_nanos(f64::INFINITY, TimeUnit::Ms),
            Err(TimeError::NotFinite)
        );
        assert_eq!(
            number_to_nanos(1e-12, TimeUnit::Ms),
            Err(TimeError::SubNanosecond)
        );
    }

    #[test]
    fn exponents_in_time_strings() {
        assert_eq!(parse_time_str("1e3us"), Ok(1_000_000));
        assert_eq!(parse_time_str("2.5E-1ms"), Ok(250_000));
        assert_eq!(parse_time_str("1e+2ns"), Ok(100));
        assert_eq!(parse_time_str("0e99s"), Ok(0));
        assert_eq!(parse_time_str("1e30ms"), Err(TimeError::TooLarge));
        assert_eq!(parse_time_str("1e999999999s"), Err(TimeError::TooLarge));
        assert_eq!(parse_time_str("1e-12ms"), Err(TimeError::SubNanosecond));
        assert_eq!(
            parse_time_str("1e-99999999s"),
            Err(TimeError::SubNanosecond)
        );
        assert!(matches!(parse_time_str("1e ms"), Err(TimeError::Unit(_))));
        assert!(matches!(parse_time_str("e3ms"), Err(TimeError::Syntax(_))));
    }

    #[test]
    fn formats_trimmed() {
        assert_eq!(format_in(10_900_000, TimeUnit::Ms), "10.9");
        assert_eq!(format_in(10_000_000, TimeUnit::Ms), "10");
        assert_eq!(format_in(250, TimeUnit::Us), "0.25");
        assert_eq!(format_in(-250, TimeUnit::Us), "-0.25");
    }
}
