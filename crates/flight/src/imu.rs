//! A BMI160-like IMU (Bosch BMI160 datasheet, BST-BMI160-DS000):
//! gyro ±2000 °/s (16.4 LSB/°/s) and accel ±16 g (2048 LSB/g) ranges with
//! saturation, white noise from the datasheet noise densities (gyro
//! 0.007 °/s/√Hz, accel 180 µg/√Hz) integrated over the Nyquist band of the
//! output data rate (σ = density·√(ODR/2)), a constant bias, quantisation to
//! 16-bit LSBs, and an output data rate: a read returns the latest ODR
//! sample at or before the read time. A new sample takes the plant's true
//! rate / specific force at the read time.

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

/// One axis-triple channel (gyro or accel) with its ODR cache.
#[derive(Debug, Clone)]
struct Channel {
    lsb_per_unit: f64,
    sigma: f64,
    bias: Vec3,
    odr_hz: u64,
    last: Option<(u64, Reading)>,
}

impl Channel {
    fn quantise(&self, v: f64) -> i16 {
        (v * self.lsb_per_unit)
            .round()
            .clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    }

    fn read(&mut self, t_ns: u64, truth: Vec3, rng: &mut Rng, noise: bool) -> Reading {
        let idx = (u128::from(t_ns) * u128::from(self.odr_hz) / 1_000_000_000) as u64;
        if let Some((i, r)) = self.last {
            if i == idx {
                return r;
            }
        }
        let t_sample = (u128::from(idx) * 1_000_000_000 / u128::from(self.odr_hz)) as u64;
        let mut v = truth + self.bias;
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
            odr_hz: cfg.accel_odr_hz.max(1),
            last: None,
        };
        Self {
            gyro,
            accel,
            rng: Rng::new(seed),
            noise: cfg.noise,
        }
    }

    /// Gyro read at `t_ns`; `true_rate` is the plant's body rate at `t_ns`.
    pub fn read_gyro(&mut self, t_ns: u64, true_rate: Vec3) -> Reading {
        self.gyro.read(t_ns, true_rate, &mut self.rng, self.noise)
    }

    /// Accel read at `t_ns`; `true_sf` is the plant's specific force at `t_ns`.
    pub fn read_accel(&mut self, t_ns: u64, true_sf: Vec3) -> Reading {
        self.accel.read(t_ns, true_sf, &mut self.rng, self.noise)
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
