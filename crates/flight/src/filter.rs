//! Discrete low-pass and notch filters in Betaflight's forms
//! (src/main/common/filter.c): PT1 and RBJ-cookbook biquads.
//!
//! [`GyroFilter`] chains them for a gyro read at its data-ready rate.
//!
//! Every constructor checks the invariant 0 < f < fs/2 (the cut-off must be
//! below Nyquist — at Cleanflight's rates, gyro 1 kHz and PID 500 Hz,
//! Betaflight's 8 kHz defaults such as the 500 Hz gyro LPF2 would violate
//! it) and returns a [`ConfigError`] otherwise. [`GyroFilter`] alone turns
//! a stage above Nyquist off instead, as Betaflight's gyro does.

use crate::error::ConfigError;
use crate::math::Vec3;
use std::f64::consts::PI;

/// Betaflight's gyro LPF1 default, Hz (sensors/gyro.h
/// `GYRO_LPF1_DYN_MIN_HZ_DEFAULT` = 250, PT1). Below 500 Hz Nyquist at 1 kHz.
pub const GYRO_LPF_HZ_DEFAULT: f64 = 250.0;
/// Betaflight's D-term LPF1 default, Hz (flight/pid.h
/// `DTERM_LPF1_DYN_MIN_HZ_DEFAULT` = 75, PT1).
pub const DTERM_LPF1_HZ_DEFAULT: f64 = 75.0;
/// Betaflight's D-term LPF2 default, Hz (flight/pid.h
/// `DTERM_LPF2_HZ_DEFAULT` = 150, PT1). Below 250 Hz Nyquist at 500 Hz.
pub const DTERM_LPF2_HZ_DEFAULT: f64 = 150.0;
/// Butterworth quality factor 1/√2, the biquad low-pass Q Betaflight uses.
pub const BUTTERWORTH_Q: f64 = std::f64::consts::FRAC_1_SQRT_2;

fn check_cutoff(field: &str, f_hz: f64, fs_hz: f64) -> Result<(), ConfigError> {
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(ConfigError::new(
            field,
            format!("sample rate must be > 0 Hz, got {fs_hz}"),
        ));
    }
    if !(f_hz.is_finite() && f_hz > 0.0 && f_hz < 0.5 * fs_hz) {
        return Err(ConfigError::new(
            field,
            format!(
                "cut-off {f_hz} Hz must be in (0, {} Hz) (Nyquist)",
                0.5 * fs_hz
            ),
        ));
    }
    Ok(())
}

/// First-order low-pass: y += k (x − y), k = dt / (RC + dt), RC = 1/(2π f_c).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pt1 {
    k: f64,
    state: f64,
}

impl Pt1 {
    /// A PT1 with cut-off `f_hz` sampled at `fs_hz`; errors if f ≥ fs/2.
    pub fn new(f_hz: f64, fs_hz: f64) -> Result<Self, ConfigError> {
        check_cutoff("pt1.cutoff_hz", f_hz, fs_hz)?;
        let rc = 1.0 / (2.0 * PI * f_hz);
        let dt = 1.0 / fs_hz;
        Ok(Self {
            k: dt / (rc + dt),
            state: 0.0,
        })
    }
    /// The gain k.
    pub fn gain(&self) -> f64 {
        self.k
    }
    /// Filter one sample.
    pub fn apply(&mut self, x: f64) -> f64 {
        self.state += self.k * (x - self.state);
        self.state
    }
    /// Set the state (e.g. to the first sample, to avoid a start transient).
    pub fn reset(&mut self, v: f64) {
        self.state = v;
    }
}

/// A PT1 per axis of a [`Vec3`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pt1Vec3 {
    f: [Pt1; 3],
}

impl Pt1Vec3 {
    /// Three identical PT1s.
    pub fn new(f_hz: f64, fs_hz: f64) -> Result<Self, ConfigError> {
        let p = Pt1::new(f_hz, fs_hz)?;
        Ok(Self { f: [p; 3] })
    }
    /// Filter one vector sample.
    pub fn apply(&mut self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.f[0].apply(v.x),
            self.f[1].apply(v.y),
            self.f[2].apply(v.z),
        )
    }
}

/// Biquad in transposed direct form II (RBJ audio-EQ-cookbook coefficients).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    b0: f64,
    b1: f64,
    b2: f64,
    a1: f64,
    a2: f64,
    s1: f64,
    s2: f64,
}

impl Biquad {
    fn from_rbj(b: [f64; 3], a: [f64; 3]) -> Self {
        Self {
            b0: b[0] / a[0],
            b1: b[1] / a[0],
            b2: b[2] / a[0],
            a1: a[1] / a[0],
            a2: a[2] / a[0],
            s1: 0.0,
            s2: 0.0,
        }
    }

    fn omega_alpha(f_hz: f64, fs_hz: f64, q: f64) -> (f64, f64) {
        let w0 = 2.0 * PI * f_hz / fs_hz;
        (w0.cos(), w0.sin() / (2.0 * q))
    }

    /// Low-pass at `f_hz` with quality `q` (use [`BUTTERWORTH_Q`]).
    pub fn lowpass(f_hz: f64, fs_hz: f64, q: f64) -> Result<Self, ConfigError> {
        check_cutoff("biquad.cutoff_hz", f_hz, fs_hz)?;
        crate::error::positive("biquad.q", q)?;
        let (c, alpha) = Self::omega_alpha(f_hz, fs_hz, q);
        let b0 = 0.5 * (1.0 - c);
        Ok(Self::from_rbj(
            [b0, 1.0 - c, b0],
            [1.0 + alpha, -2.0 * c, 1.0 - alpha],
        ))
    }

    /// High-pass at `f_hz` with quality `q` (use [`BUTTERWORTH_Q`]).
    pub fn highpass(f_hz: f64, fs_hz: f64, q: f64) -> Result<Self, ConfigError> {
        check_cutoff("biquad.cutoff_hz", f_hz, fs_hz)?;
        crate::error::positive("biquad.q", q)?;
        let (c, alpha) = Self::omega_alpha(f_hz, fs_hz, q);
        let b0 = 0.5 * (1.0 + c);
        Ok(Self::from_rbj(
            [b0, -(1.0 + c), b0],
            [1.0 + alpha, -2.0 * c, 1.0 - alpha],
        ))
    }

    /// The state of a filter whose input has been `x` for ever: its output
    /// is then the DC gain times `x` (a high-pass starts at rest, without
    /// the step a zero state would see).
    pub fn settle(&mut self, x: f64) {
        let y = (self.b0 + self.b1 + self.b2) / (1.0 + self.a1 + self.a2) * x;
        self.s1 = y - self.b0 * x;
        self.s2 = self.b2 * x - self.a2 * y;
    }

    /// Notch at `f_hz` with quality `q` (centre / bandwidth).
    pub fn notch(f_hz: f64, fs_hz: f64, q: f64) -> Result<Self, ConfigError> {
        check_cutoff("notch.center_hz", f_hz, fs_hz)?;
        crate::error::positive("notch.q", q)?;
        let (c, alpha) = Self::omega_alpha(f_hz, fs_hz, q);
        Ok(Self::from_rbj(
            [1.0, -2.0 * c, 1.0],
            [1.0 + alpha, -2.0 * c, 1.0 - alpha],
        ))
    }

    /// Notch Q from a centre and a lower cut-off frequency, as Betaflight's
    /// `filterGetNotchQ`: Q = f0·fc / (f0² − fc²).
    pub fn notch_q(center_hz: f64, cutoff_hz: f64) -> f64 {
        center_hz * cutoff_hz / (center_hz * center_hz - cutoff_hz * cutoff_hz)
    }

    /// Filter one sample.
    pub fn apply(&mut self, x: f64) -> f64 {
        let y = self.b0 * x + self.s1;
        self.s1 = self.b1 * x - self.a1 * y + self.s2;
        self.s2 = self.b2 * x - self.a2 * y;
        y
    }
}

/// Betaflight's gyro LPF2 default, Hz (sensors/gyro.h
/// `GYRO_LPF2_HZ_DEFAULT` = 500, PT1): the anti-alias stage of a gyro read
/// at its data-ready rate (4–8 kHz).
pub const GYRO_LPF2_HZ_DEFAULT: f64 = 500.0;

/// The gyro filters of a loop run at the gyro's data-ready rate, as
/// Betaflight chains them (sensors/gyro_filter_impl.c): the LPF2 PT1
/// (anti-alias), a static biquad notch, then the LPF1 PT1. A preset's
/// `[gyro_filter]` table. Every frequency must be positive; a stage whose
/// frequency is not below the gyro rate's Nyquist frequency is off, as
/// Betaflight turns it off (sensors/gyro_init.c: a low-pass above Nyquist
/// is its null filter, and so is a notch whose cut-off is not below it),
/// so one preset serves a loop at 8 kHz and one at PX4's 400 Hz.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GyroFilterConfig {
    /// LPF1 PT1 cut-off, Hz (Betaflight `gyro_lpf1_static_hz`).
    #[serde(default = "default_lpf1")]
    pub lpf1_hz: f64,
    /// LPF2 PT1 cut-off, Hz (Betaflight `gyro_lpf2_static_hz`).
    #[serde(default = "default_lpf2")]
    pub lpf2_hz: f64,
    /// Static notch centre, Hz (Betaflight `gyro_notch1_hz`): where the
    /// rotors shake the gyro most, their rotation frequency at hover.
    pub notch_hz: f64,
    /// The notch's lower −3 dB edge, Hz (Betaflight `gyro_notch1_cutoff`),
    /// below `notch_hz`: Q = f0·fc / (f0² − fc²).
    pub notch_cutoff_hz: f64,
}

fn default_lpf1() -> f64 {
    GYRO_LPF_HZ_DEFAULT
}

fn default_lpf2() -> f64 {
    GYRO_LPF2_HZ_DEFAULT
}

/// [`GyroFilterConfig`]'s chain on the three axes of a gyro sample; a
/// stage the rate cannot carry is `None` (off).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroFilter {
    lpf2: Option<Pt1Vec3>,
    notch: Option<[Biquad; 3]>,
    lpf1: Option<Pt1Vec3>,
}

/// Whether a stage at `f_hz` runs at `fs_hz`: a frequency that is not
/// positive is the preset's error (named by `key`); one at or above
/// Nyquist turns the stage off, as Betaflight does.
fn stage_runs(key: &str, f_hz: f64, fs_hz: f64) -> Result<bool, ConfigError> {
    if !(f_hz.is_finite() && f_hz > 0.0) {
        return Err(ConfigError::new(
            key,
            format!("must be a positive frequency in Hz, got {f_hz}"),
        ));
    }
    Ok(f_hz < 0.5 * fs_hz)
}

impl GyroFilter {
    /// The chain of `cfg` sampled at `fs_hz`; an error names the preset key
    /// at fault. Stages at or above Nyquist are off ([`GyroFilterConfig`]).
    pub fn new(cfg: &GyroFilterConfig, fs_hz: f64) -> Result<Self, ConfigError> {
        let keyed = |key: &str, e: ConfigError| ConfigError::new(key, e.reason);
        if !(cfg.notch_cutoff_hz > 0.0 && cfg.notch_cutoff_hz < cfg.notch_hz) {
            return Err(ConfigError::new(
                "gyro_filter.notch_cutoff_hz",
                format!(
                    "must be in (0, notch_hz = {} Hz), got {}",
                    cfg.notch_hz, cfg.notch_cutoff_hz
                ),
            ));
        }
        let pt1 = |key: &str, f_hz: f64| -> Result<Option<Pt1Vec3>, ConfigError> {
            if !stage_runs(key, f_hz, fs_hz)? {
                return Ok(None);
            }
            Pt1Vec3::new(f_hz, fs_hz)
                .map(Some)
                .map_err(|e| keyed(key, e))
        };
        let notch = if stage_runs("gyro_filter.notch_cutoff_hz", cfg.notch_cutoff_hz, fs_hz)?
            && stage_runs("gyro_filter.notch_hz", cfg.notch_hz, fs_hz)?
        {
            let q = Biquad::notch_q(cfg.notch_hz, cfg.notch_cutoff_hz);
            let n = Biquad::notch(cfg.notch_hz, fs_hz, q)
                .map_err(|e| keyed("gyro_filter.notch_hz", e))?;
            Some([n; 3])
        } else {
            None
        };
        Ok(Self {
            lpf2: pt1("gyro_filter.lpf2_hz", cfg.lpf2_hz)?,
            notch,
            lpf1: pt1("gyro_filter.lpf1_hz", cfg.lpf1_hz)?,
        })
    }

    /// How many of the three stages run at this rate.
    pub fn stages(&self) -> usize {
        usize::from(self.lpf2.is_some())
            + usize::from(self.notch.is_some())
            + usize::from(self.lpf1.is_some())
    }

    /// Filter one gyro sample.
    pub fn apply(&mut self, v: Vec3) -> Vec3 {
        let a = self.lpf2.as_mut().map_or(v, |f| f.apply(v));
        let n = match self.notch.as_mut() {
            Some(n) => Vec3::new(n[0].apply(a.x), n[1].apply(a.y), n[2].apply(a.z)),
            None => a,
        };
        self.lpf1.as_mut().map_or(n, |f| f.apply(n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state amplitude of `filter` driven by a unit sine at `f`:
    /// correlate the second half (whole periods) with sin and cos.
    fn gain(mut filter: impl FnMut(f64) -> f64, f: f64, fs: f64) -> f64 {
        let per = (fs / f).round() as usize;
        let n = per * 400;
        let (mut s, mut c) = (0.0, 0.0);
        for i in 0..n {
            let ph = 2.0 * PI * f * i as f64 / fs;
            let y = filter(ph.sin());
            if i >= n / 2 {
                s += y * ph.sin();
                c += y * ph.cos();
            }
        }
        2.0 * (s * s + c * c).sqrt() / (n / 2) as f64
    }

    fn db(g: f64) -> f64 {
        20.0 * g.log10()
    }

    #[test]
    fn pt1_is_minus_3db_at_cutoff_and_unity_at_dc() {
        // Well below Nyquist the discrete PT1 is close to the analog one:
        // hand-computed |H(e^jω)| at 20 Hz / 1 kHz is −3.27 dB.
        let mut p = Pt1::new(20.0, 1000.0).unwrap();
        let g = db(gain(|x| p.apply(x), 20.0, 1000.0));
        assert!((g + 3.27).abs() < 0.02, "PT1 gain at cut-off {g} dB");
        assert!((g + 3.01).abs() < 0.5);
        let mut p = Pt1::new(20.0, 1000.0).unwrap();
        let mut y = 0.0;
        for _ in 0..2000 {
            y = p.apply(1.0);
        }
        assert!((y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn biquad_lowpass_is_minus_3db_at_cutoff_and_unity_at_dc() {
        // Bilinear RBJ design: exactly −3.01 dB at f_c for Q = 1/√2, even
        // close to Nyquist (150 Hz at 500 Hz).
        for (f, fs) in [(20.0, 1000.0), (150.0, 500.0), (75.0, 500.0)] {
            let mut b = Biquad::lowpass(f, fs, BUTTERWORTH_Q).unwrap();
            let g = db(gain(|x| b.apply(x), f, fs));
            assert!((g + 3.0103).abs() < 0.02, "biquad {f}/{fs}: {g} dB");
        }
        let mut b = Biquad::lowpass(75.0, 500.0, BUTTERWORTH_Q).unwrap();
        let mut y = 0.0;
        for _ in 0..2000 {
            y = b.apply(1.0);
        }
        assert!((y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn biquad_highpass_is_minus_3db_at_cutoff_and_settles_at_rest() {
        for (f, fs) in [(5.0, 500.0), (20.0, 1000.0)] {
            let mut b = Biquad::highpass(f, fs, BUTTERWORTH_Q).unwrap();
            let g = db(gain(|x| b.apply(x), f, fs));
            assert!((g + 3.0103).abs() < 0.02, "biquad {f}/{fs}: {g} dB");
            // A decade below the corner a second-order filter takes 40 dB.
            let mut b = Biquad::highpass(f, fs, BUTTERWORTH_Q).unwrap();
            let g = db(gain(|x| b.apply(x), f / 10.0, fs));
            assert!(
                (g + 40.0).abs() < 0.5,
                "biquad {f}/{fs} a decade down: {g} dB"
            );
        }
        // Settled on a constant input, a high-pass outputs nothing from the
        // first sample on; from a zero state it would start with the step.
        let mut b = Biquad::highpass(5.0, 500.0, BUTTERWORTH_Q).unwrap();
        b.settle(7.0);
        for _ in 0..100 {
            assert!(b.apply(7.0).abs() < 1e-12);
        }
        let mut b = Biquad::lowpass(5.0, 500.0, BUTTERWORTH_Q).unwrap();
        b.settle(7.0);
        assert!((b.apply(7.0) - 7.0).abs() < 1e-12);
    }

    #[test]
    fn notch_removes_centre_and_passes_dc() {
        let q = Biquad::notch_q(100.0, 70.0);
        let mut n = Biquad::notch(100.0, 1000.0, q).unwrap();
        let g = gain(|x| n.apply(x), 100.0, 1000.0);
        assert!(g < 1e-3, "notch gain at centre {g}");
        let mut n = Biquad::notch(100.0, 1000.0, q).unwrap();
        let mut y = 0.0;
        for _ in 0..2000 {
            y = n.apply(1.0);
        }
        assert!((y - 1.0).abs() < 1e-12);
    }

    /// racer5's chain at 8 kHz: the notch takes ≥ 20 dB off its centre;
    /// the notch alone passes 10 % of its centre within 1 dB, and so does
    /// the whole chain (its low-passes sit well above that).
    #[test]
    fn gyro_filter_notches_its_centre_and_passes_a_tenth_of_it() {
        let cfg = GyroFilterConfig {
            lpf1_hz: GYRO_LPF_HZ_DEFAULT,
            lpf2_hz: GYRO_LPF2_HZ_DEFAULT,
            notch_hz: 260.0,
            notch_cutoff_hz: 200.0,
        };
        let fs = 8000.0;
        let q = Biquad::notch_q(cfg.notch_hz, cfg.notch_cutoff_hz);
        let mut n = Biquad::notch(cfg.notch_hz, fs, q).unwrap();
        let centre = db(gain(|x| n.apply(x), cfg.notch_hz, fs));
        assert!(centre <= -20.0, "notch at its centre: {centre} dB");
        let mut n = Biquad::notch(cfg.notch_hz, fs, q).unwrap();
        let pass = db(gain(|x| n.apply(x), 0.1 * cfg.notch_hz, fs));
        assert!(pass.abs() <= 1.0, "notch at 10 % of its centre: {pass} dB");
        let axis_x = |f: &mut GyroFilter, x: f64| f.apply(Vec3::new(x, 0.0, 0.0)).x;
        let mut chain = GyroFilter::new(&cfg, fs).unwrap();
        let pass = db(gain(|x| axis_x(&mut chain, x), 0.1 * cfg.notch_hz, fs));
        assert!(pass.abs() <= 1.0, "chain at 10 % of the notch: {pass} dB");
        let mut chain = GyroFilter::new(&cfg, fs).unwrap();
        let centre = db(gain(|x| axis_x(&mut chain, x), cfg.notch_hz, fs));
        assert!(centre <= -20.0, "chain at the notch: {centre} dB");
    }

    #[test]
    fn gyro_filter_turns_off_the_stages_its_rate_cannot_carry() {
        let cfg = GyroFilterConfig {
            lpf1_hz: GYRO_LPF_HZ_DEFAULT,
            lpf2_hz: GYRO_LPF2_HZ_DEFAULT,
            notch_hz: 260.0,
            notch_cutoff_hz: 200.0,
        };
        assert_eq!(GyroFilter::new(&cfg, 8000.0).unwrap().stages(), 3);
        // 500 Hz is Nyquist at 1 kHz: LPF2 is off there, the rest runs.
        assert_eq!(GyroFilter::new(&cfg, 1000.0).unwrap().stages(), 2);
        // At PX4's 400 Hz (Nyquist 200 Hz) every stage is off: the chain
        // passes the samples through unchanged.
        let mut off = GyroFilter::new(&cfg, 400.0).unwrap();
        assert_eq!(off.stages(), 0);
        let v = Vec3::new(0.3, -0.2, 0.1);
        assert_eq!(off.apply(v), v);
        // A notch whose cut-off is below Nyquist but centre is not is off
        // too; one wholly below runs.
        let low = GyroFilterConfig {
            notch_hz: 111.0,
            notch_cutoff_hz: 80.0,
            ..cfg
        };
        assert_eq!(GyroFilter::new(&low, 400.0).unwrap().stages(), 1);
        assert_eq!(GyroFilter::new(&low, 200.0).unwrap().stages(), 0);
    }

    #[test]
    fn gyro_filter_refuses_a_bad_preset_naming_the_key() {
        let cfg = GyroFilterConfig {
            lpf1_hz: GYRO_LPF_HZ_DEFAULT,
            lpf2_hz: GYRO_LPF2_HZ_DEFAULT,
            notch_hz: 260.0,
            notch_cutoff_hz: 200.0,
        };
        let e = GyroFilter::new(
            &GyroFilterConfig {
                notch_cutoff_hz: 300.0,
                ..cfg
            },
            8000.0,
        )
        .unwrap_err();
        assert_eq!(e.field, "gyro_filter.notch_cutoff_hz", "{e}");
        let e = GyroFilter::new(
            &GyroFilterConfig {
                lpf2_hz: 0.0,
                ..cfg
            },
            8000.0,
        )
        .unwrap_err();
        assert_eq!(e.field, "gyro_filter.lpf2_hz", "{e}");
        let e = GyroFilter::new(
            &GyroFilterConfig {
                lpf1_hz: f64::NAN,
                ..cfg
            },
            8000.0,
        )
        .unwrap_err();
        assert_eq!(e.field, "gyro_filter.lpf1_hz", "{e}");
    }

    #[test]
    fn cutoff_at_or_above_nyquist_is_rejected() {
        let e = Pt1::new(500.0, 1000.0).unwrap_err();
        assert!(e.to_string().contains("Nyquist"), "{e}");
        assert!(Biquad::lowpass(300.0, 500.0, BUTTERWORTH_Q).is_err());
        assert!(Biquad::notch(0.0, 500.0, 1.0).is_err());
        assert!(Pt1::new(GYRO_LPF_HZ_DEFAULT, 1000.0).is_ok());
        assert!(Pt1::new(DTERM_LPF2_HZ_DEFAULT, 500.0).is_ok());
    }
}
