//! How sure a count of flights makes us of a pass rate: the Wilson score
//! interval (Wilson 1927). A design or a timing judged by flights passes
//! when the lower end of the interval around its observed pass rate
//! reaches a required rate, so "it flew every time" is worth as much as the
//! number of times it flew: all of 59 flights passing gives a lower end of
//! 0.939 at 95 % confidence, all of 73 gives 0.950.
//!
//! The interval is the two-sided one at confidence `c`, so its lower end
//! is exceeded with probability (1 + c)/2: z = Φ⁻¹((1 + c)/2), 1.960 at
//! c = 0.95.

/// The required pass rate and the confidence it must hold at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Requirement {
    /// The pass rate the lower bound must reach, in (0, 1).
    pub rate: f64,
    /// The confidence of the two-sided interval, in (0, 1).
    pub confidence: f64,
}

impl Requirement {
    /// Lower bound ≥ 0.95 at 95 % confidence: 73 flights, all passing.
    pub const DEFAULT: Requirement = Requirement {
        rate: 0.95,
        confidence: 0.95,
    };

    /// The interval's z: Φ⁻¹((1 + confidence)/2).
    pub fn z(self) -> f64 {
        assert!(
            self.confidence > 0.0 && self.confidence < 1.0,
            "a confidence is in (0, 1), found {}",
            self.confidence
        );
        normal_quantile((1.0 + self.confidence) / 2.0)
    }

    /// `passed` of `flown` flights meet it.
    pub fn met(self, passed: u32, flown: u32) -> bool {
        wilson_lower(passed, flown, self.z()) >= self.rate
    }

    /// The fewest flights that can meet it (all of them passing).
    pub fn least_flights(self) -> u32 {
        assert!(
            self.rate > 0.0 && self.rate < 1.0,
            "a required pass rate is in (0, 1), found {}",
            self.rate
        );
        // All n passing: the lower end is n / (n + z²).
        let z2 = self.z() * self.z();
        let mut n = (self.rate * z2 / (1.0 - self.rate)).floor().max(1.0) as u32;
        while !self.met(n, n) {
            n += 1;
        }
        n
    }

    /// The most of `flown` flights that may fail with the requirement still
    /// met (`None`: not even all passing meets it): the fewest passes that
    /// meet it, taken from `flown`.
    pub fn failures_allowed(self, flown: u32) -> Option<u32> {
        (0..=flown).find(|&p| self.met(p, flown)).map(|p| flown - p)
    }
}

/// The lower end of the Wilson score interval of `passed` successes in
/// `flown` trials at normal quantile `z` (0 when nothing was flown).
pub fn wilson_lower(passed: u32, flown: u32, z: f64) -> f64 {
    assert!(passed <= flown, "{passed} passed of {flown}");
    if flown == 0 {
        return 0.0;
    }
    let n = f64::from(flown);
    let p = f64::from(passed) / n;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * n);
    let spread = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    ((centre - spread) / (1.0 + z2 / n)).max(0.0)
}

/// Φ⁻¹(p) for p in (0, 1): Acklam's rational approximation (relative
/// error below 1.2e-9), enough for a confidence level.
fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    assert!(p > 0.0 && p < 1.0, "a quantile of {p}");
    let poly = |c: &[f64], x: f64| c.iter().fold(0.0, |acc, &k| acc * x + k);
    let tail = |q: f64| poly(&C, q) / (poly(&D, q) * q + 1.0);
    const LOW: f64 = 0.024_25;
    if p < LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        poly(&A, r) * q / (poly(&B, r) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quantile_of_the_usual_confidences() {
        for (c, z) in [(0.90, 1.644_854), (0.95, 1.959_964), (0.99, 2.575_829)] {
            let r = Requirement {
                rate: 0.5,
                confidence: c,
            };
            assert!((r.z() - z).abs() < 1e-5, "{c}: {}", r.z());
        }
        assert!((normal_quantile(0.01) + 2.326_348).abs() < 1e-5);
    }

    /// The numbers the docs state: 59 of 59 gives 0.939, 73 of 73 is the
    /// least that reaches 0.95 at 95 %, and one failure needs more flights.
    #[test]
    fn all_of_73_flights_reach_095_at_95_percent() {
        let r = Requirement::DEFAULT;
        let z = r.z();
        assert!((wilson_lower(59, 59, z) - 0.9389).abs() < 1e-4);
        assert!(!r.met(72, 72) && r.met(73, 73));
        assert_eq!(r.least_flights(), 73);
        assert_eq!(r.failures_allowed(73), Some(0));
        assert_eq!(r.failures_allowed(10), None);
        let one = (73..400).find(|&n| r.failures_allowed(n) == Some(1));
        assert_eq!(one, Some(110));
        // The interval's lower end of a mixed count: 90 of 100.
        assert!((wilson_lower(90, 100, z) - 0.8256).abs() < 1e-4);
        assert_eq!(wilson_lower(0, 0, z), 0.0);
    }
}
