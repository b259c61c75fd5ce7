//! A BMI160-like IMU (Bosch BMI160 datasheet, BST-BMI160-DS000):
//! gyro ±2000 °/s (16.4 LSB/°/s) and accel ±16 g (2048 LSB/g) ranges with
//! saturation, white noise from the datasheet noise densities (gyro
//! 0.007 °/s/√Hz, accel 180 µg/√Hz) integrated over the Nyquist band of the
//! output data rate (σ = density·√(ODR/2)), a constant bias, quantisation to
//! 16-bit LSBs, and an output data rate: a read returns the latest ODR
//! sample at or before the read time. A new sample takes the plant's true
//! rate / specific force at the read time.
//!
//! The disturbed world adds, per axis, a scale error (value × (1 + e)) and
//! the rotors' vibration. Rotor i at angle φ_i and speed Ω_i shakes both
//! sensors with amplitudes growing as the forces behind them, with Ω²
//! (A_k given at the hover speed Ω_ref), and a fixed phase ψ_ik (seeded):
//! - at the rotation frequency (imbalance), a force spinning in the rotor
//!   plane: accel A_1 (cos, sin, 0)(φ_i + ψ_i1), gyro (a rocking of the
//!   frame) G_1 the same way about x and y;
//! - at its 2nd and 3rd harmonics (blade passing, thrust ripple), along the
//!   rotor axis: accel A_k (0, 0, sin(kφ_i + ψ_ik)), and the ripple's moment
//!   about the arm: gyro G_k sin(kφ_i + ψ_ik) along (y_i, −x_i, 0)/|r_i|.
//!
//! Components at different frequencies or in quadrature, so the vibration
//! has no mean and no product term a normalisation could rectify.
use crate::math::{Vec3, GRAVITY};
use crate::rng::Rng;

/// IMU configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuConfig {
    /// Gyro full scale, °/s.
    pub gyro_range_dps: f64,
    /// Accel full scale, g.
    pub accel_range_g: f64,
    /// Gyro noise density, °/s/√Hz.
    pub gyro_noise_dps_rthz: f64,
    /// Accel noise density, µg/√Hz.
    pub accel_noise_ug_rthz: f64,
    /// Gyro bias, rad/s.
    pub gyro_bias: Vec3,
    /// Accel bias, m/s².
    pub accel_bias: Vec3,
    /// Gyro output data rate, Hz.
    pub gyro_odr_hz: u64,
    /// Accel output data rate, Hz.
    pub accel_odr_hz: u64,
    /// Noise on (off gives exact, quantised truth).
    pub noise: bool,
    /// Gyro scale error per axis (a fraction: reads value × (1 + e)).
    pub gyro_scale_error: Vec3,
    /// Accel scale error per axis (a fraction).
    pub accel_scale_error: Vec3,
    /// The rotors' vibration (none by default).
    pub vibration: Vibration,
}

/// Vibration of the rotors reaching the IMU: amplitude per rotor and axis
/// at the rotation frequency and its 2nd and 3rd harmonics, at the rotor
/// speed `ref_omega_rad_s`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vibration {
    /// Gyro amplitudes, rad/s, harmonics 1, 2, 3.
    pub gyro_rad_s: [f64; 3],
    /// Accel amplitudes, m/s², harmonics 1, 2, 3.
    pub accel_mps2: [f64; 3],
    /// The rotor speed the amplitudes are given at, rad/s.
    pub ref_omega_rad_s: f64,
    /// The direction of each rotor's arm moment, (y_i, −x_i)/|r_i|.
    pub arm_dir: [[f64; 2]; 4],
    /// The flight controller's accelerometer low-pass (first order), Hz,
    /// as it acts on the vibration: each component's steady-state gain
    /// 1/√(1 + (ω/ω_c)²) and lag atan(ω/ω_c). 0: none.
    pub accel_lpf_hz: f64,
}

impl Vibration {
    fn is_none(&self) -> bool {
        self.gyro_rad_s == [0.0; 3] && self.accel_mps2 == [0.0; 3]
    }
}

impl Default for ImuConfig {
    fn default() -> Self {
        Self {
            gyro_range_dps: 2000.0,
            accel_range_g: 16.0,
            gyro_noise_dps_rthz: 0.007,
            accel_noise_ug_rthz: 180.0,
            gyro_bias: Vec3::ZERO,
            accel_bias: Vec3::ZERO,
            gyro_odr_hz: 3200,
            accel_odr_hz: 1600,
            noise: true,
            gyro_scale_error: Vec3::ZERO,
            accel_scale_error: Vec3::ZERO,
            vibration: Vibration::default(),
        }
    }
}

/// One sensor reading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reading {
    /// Value in SI units (rad/s or m/s²), after quantisation.
    pub value: Vec3,
    /// Raw 16-bit counts.
    pub raw: [i16; 3],
    /// Time of the ODR sample, ns.
    pub t_ns: u64,
}

/// ⌊a·b / c⌋, in u64 when a·b fits (an u128 division is a library call
/// that cost a fifth of a read), else in u128; the same value either way.
fn mul_div(a: u64, b: u64, c: u64) -> u64 {
    match a.checked_mul(b) {
        Some(p) => p / c,
        None => (u128::from(a) * u128::from(b) / u128::from(c)) as u64,
    }
}

/// One axis-triple channel (gyro or accel) with its ODR cache.
#[derive(Debug, Clone)]
struct Channel {
    lsb_per_unit: f64,
    sigma: f64,
    bias: Vec3,
    /// 1 + the scale error, per axis.
    gain: Vec3,
    odr_hz: u64,
    last: Option<(u64, Reading)>,
}

impl Channel {
    fn quantise(&self, v: f64) -> i16 {
        (v * self.lsb_per_unit)
            .round()
            .clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    }

    fn read(
        &mut self,
        t_ns: u64,
        truth: Vec3,
        rng: &mut Rng,
        noise: bool,
        shake: impl Fn(u64) -> Option<Vec3>,
    ) -> Reading {
        let idx = mul_div(t_ns, self.odr_hz, 1_000_000_000);
        if let Some((i, r)) = self.last {
            if i == idx {
                return r;
            }
        }
        let t_sample = mul_div(idx, 1_000_000_000, self.odr_hz);
        let mut v = truth.hadamard(self.gain) + self.bias;
        if let Some(d) = shake(t_sample) {
            v += d;
        }
        if noise {
            v += Vec3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * self.sigma;
        }
        let raw = [self.quantise(v.x), self.quantise(v.y), self.quantise(v.z)];
        let value =
            Vec3::new(f64::from(raw[0]), f64::from(raw[1]), f64::from(raw[2])) / self.lsb_per_unit;
        let r = Reading {
            value,
            raw,
            t_ns: t_sample,
        };
        self.last = Some((idx, r));
        r
    }
}

/// The IMU: a gyro and an accelerometer with their own ODRs, one noise stream.
#[derive(Debug, Clone)]
pub struct Imu {
    gyro: Channel,
    accel: Channel,
    rng: Rng,
    noise: bool,
    shaker: Option<Shaker>,
}

/// The vibration source: amplitudes, phases, and the rotors' last state.
#[derive(Debug, Clone)]
struct Shaker {
    v: Vibration,
    /// ψ per rotor and harmonic.
    phase: [[f64; 3]; 4],
    /// (time ns, angles rad, speeds rad/s) of the rotors, as last told.
    rotors: Option<(u64, [f64; 4], [f64; 4])>,
}

impl Shaker {
    fn new(v: Vibration, seed: u64) -> Shaker {
        // Its own stream: the white noise stays what it is without it.
        let mut rng = Rng::new(seed ^ 0x5648_4942); // "VHIB"
        let mut phase = [[0.0; 3]; 4];
        for x in phase.iter_mut().flatten() {
            *x = std::f64::consts::TAU * rng.uniform();
        }
        Shaker {
            v,
            phase,
            rotors: None,
        }
    }

    /// The vibration of sensor `which` (0 gyro, 1 accel) at `t_ns`, each
    /// rotor's angle carried from its last known one at its speed then.
    fn at(&self, which: usize, t_ns: u64) -> Option<Vec3> {
        let (t0, angle, omega) = self.rotors?;
        let amp = if which == 0 {
            self.v.gyro_rad_s
        } else {
            self.v.accel_mps2
        };
        let dt = (t_ns as f64 - t0 as f64) * 1e-9;
        let mut out = Vec3::ZERO;
        let wc = std::f64::consts::TAU * self.v.accel_lpf_hz;
        // (gain, lag) of the filter at ω; none for the gyro.
        let lpf = |w: f64| {
            if which == 1 && wc > 0.0 {
                let r = w.abs() / wc;
                (1.0 / (1.0 + r * r).sqrt(), r.atan())
            } else {
                (1.0, 0.0)
            }
        };
        for i in 0..4 {
            let phi = angle[i] + omega[i] * dt;
            let s = (omega[i] / self.v.ref_omega_rad_s).powi(2);
            let ps = self.phase[i];
            let (g, lag) = lpf(omega[i]);
            let (sin1, cos1) = (phi + ps[0] - lag).sin_cos();
            out += Vec3::new(cos1, sin1, 0.0) * (g * amp[0] * s);
            let along = if which == 0 {
                let [dx, dy] = self.v.arm_dir[i];
                Vec3::new(dx, dy, 0.0)
            } else {
                Vec3::new(0.0, 0.0, 1.0)
            };
            for k in 1..3 {
                let n = (k + 1) as f64;
                let (g, lag) = lpf(n * omega[i]);
                out += along * (g * amp[k] * s * (n * phi + ps[k] - lag).sin());
            }
        }
        Some(out)
    }
}

impl Imu {
    /// An IMU with `cfg`, noise seeded by `seed`.
    pub fn new(cfg: ImuConfig, seed: u64) -> Self {
        let dps = std::f64::consts::PI / 180.0;
        // Full scale maps to 2^15 counts (datasheet: 16.4 LSB/°/s at ±2000).
        let gyro = Channel {
            lsb_per_unit: 32768.0 / (cfg.gyro_range_dps * dps),
            sigma: cfg.gyro_noise_dps_rthz * dps * (cfg.gyro_odr_hz as f64 / 2.0).sqrt(),
            bias: cfg.gyro_bias,
            gain: Vec3::new(1.0, 1.0, 1.0) + cfg.gyro_scale_error,
            odr_hz: cfg.gyro_odr_hz.max(1),
            last: None,
        };
        let accel = Channel {
            lsb_per_unit: 32768.0 / (cfg.accel_range_g * GRAVITY),
            sigma: cfg.accel_noise_ug_rthz
                * 1e-6
                * GRAVITY
                * (cfg.accel_odr_hz as f64 / 2.0).sqrt(),
            bias: cfg.accel_bias,
            gain: Vec3::new(1.0, 1.0, 1.0) + cfg.accel_scale_error,
            odr_hz: cfg.accel_odr_hz.max(1),
            last: None,
        };
        Self {
            gyro,
            accel,
            rng: Rng::new(seed),
            noise: cfg.noise,
            shaker: (!cfg.vibration.is_none() && cfg.vibration.ref_omega_rad_s > 0.0)
                .then(|| Shaker::new(cfg.vibration, seed)),
        }
    }

    /// The rotors' angles and speeds at `t_ns` (from the plant), for the
    /// vibration; ignored when there is none.
    pub fn set_rotors(&mut self, t_ns: u64, angle: [f64; 4], omega: [f64; 4]) {
        if let Some(s) = &mut self.shaker {
            s.rotors = Some((t_ns, angle, omega));
        }
    }

    /// Gyro read at `t_ns`; `true_rate` is the plant's body rate at `t_ns`.
    pub fn read_gyro(&mut self, t_ns: u64, true_rate: Vec3) -> Reading {
        let shaker = &self.shaker;
        let shake = |t| shaker.as_ref().and_then(|s| s.at(0, t));
        self.gyro
            .read(t_ns, true_rate, &mut self.rng, self.noise, shake)
    }

    /// Accel read at `t_ns`; `true_sf` is the plant's specific force at `t_ns`.
    pub fn read_accel(&mut self, t_ns: u64, true_sf: Vec3) -> Reading {
        let shaker = &self.shaker;
        let shake = |t| shaker.as_ref().and_then(|s| s.at(1, t));
        self.accel
            .read(t_ns, true_sf, &mut self.rng, self.noise, shake)
    }

    /// Gyro noise σ per sample, rad/s.
    pub fn gyro_sigma(&self) -> f64 {
        self.gyro.sigma
    }

    /// Accel noise σ per sample, m/s².
    pub fn accel_sigma(&self) -> f64 {
        self.accel.sigma
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet() -> ImuConfig {
        ImuConfig {
            noise: false,
            ..ImuConfig::default()
        }
    }

    #[test]
    fn quantises_and_saturates() {
        let mut imu = Imu::new(quiet(), 1);
        let r = imu.read_gyro(0, Vec3::new(1.0, 100.0, -100.0));
        // 1 rad/s = 57.2958 °/s · 16.384 = 938.7 → 939 counts.
        assert_eq!(r.raw, [939, i16::MAX, i16::MIN]);
        let a = imu.read_accel(0, Vec3::new(0.0, 0.0, GRAVITY));
        assert_eq!(a.raw[2], 2048);
        assert!((a.value.z - GRAVITY).abs() < 1e-12);
    }

    #[test]
    fn returns_latest_odr_sample_and_adds_bias() {
        let cfg = ImuConfig {
            gyro_bias: Vec3::new(0.01, 0.0, 0.0),
            gyro_odr_hz: 1000,
            ..quiet()
        };
        let mut imu = Imu::new(cfg, 1);
        let a = imu.read_gyro(1_200_000, Vec3::ZERO);
        assert_eq!(a.t_ns, 1_000_000);
        // Same ODR slot: the cached sample, even if the truth changed.
        let b = imu.read_gyro(1_900_000, Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(a, b);
        let c = imu.read_gyro(2_000_000, Vec3::ZERO);
        assert_eq!(c.t_ns, 2_000_000);
        assert!((c.value.x - 0.01).abs() < 1.1e-3 / 2.0);
    }

    #[test]
    fn noise_matches_datasheet_density() {
        let mut imu = Imu::new(ImuConfig::default(), 9);
        let n = 20_000u64;
        let mut s2 = 0.0;
        for k in 0..n {
            let r = imu.read_gyro(k * 312_500, Vec3::ZERO);
            s2 += r.value.x * r.value.x;
        }
        let sigma = (s2 / n as f64).sqrt().to_degrees();
        // 0.007 °/s/√Hz · √1600 Hz = 0.28 °/s.
        assert!((sigma - 0.28).abs() < 0.02, "σ = {sigma} °/s");
    }
}

#[cfg(test)]
mod disturbed_tests {
    use super::*;

    #[test]
    fn scale_error_and_vibration_at_the_rotor_frequency() {
        let cfg = ImuConfig {
            noise: false,
            gyro_scale_error: Vec3::new(0.01, 0.0, 0.0),
            vibration: Vibration {
                gyro_rad_s: [0.1, 0.0, 0.0],
                accel_mps2: [0.0; 3],
                ref_omega_rad_s: 1000.0,
                arm_dir: [[0.0; 2]; 4],
                accel_lpf_hz: 0.0,
            },
            ..ImuConfig::default()
        };
        let mut imu = Imu::new(cfg, 5);
        // No rotor state told yet: no vibration; the scale error alone.
        let r = imu.read_gyro(0, Vec3::new(1.0, 0.0, 0.0));
        assert!((r.value.x - 1.01).abs() < 1.1e-3, "{r:?}");
        // One rotor at the reference speed, the others stopped: a sine at
        // 1000 rad/s of amplitude 0.1 rad/s on each axis. Its RMS over many
        // samples is 0.1/√2.
        let omega = [1000.0, 0.0, 0.0, 0.0];
        let (mut s2, n) = (0.0, 20_000u64);
        for k in 1..=n {
            let t = k * 312_500;
            let phi = (1000.0 * t as f64 * 1e-9) % std::f64::consts::TAU;
            imu.set_rotors(t, [phi, 0.0, 0.0, 0.0], omega);
            s2 += imu.read_gyro(t, Vec3::ZERO).value.y.powi(2);
        }
        let rms = (s2 / n as f64).sqrt();
        assert!((rms - 0.1 / 2f64.sqrt()).abs() < 0.003, "{rms}");
    }
}
