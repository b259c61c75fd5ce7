//! Attitude estimation: Mahony complementary filter on quaternions, as in
//! Cleanflight's src/main/flight/imu.c (`imuMahonyAHRSupdate`).
//!
//! The gyro task and the AHRS task run at different rates (1 ms and 5 ms
//! in the paper's Table V) and communicate through latest-value registers.
//! A register holds only the newest value, so the gyro side publishes
//! RUNNING SUMS and a COUNT ([`GyroSnapshot`]); the AHRS differences two
//! consecutive snapshots to get the mean rate over the interval, and takes
//! dt from the samples' timestamps rather than from a clock.

use crate::math::{Euler, Quat, Vec3, GRAVITY};

/// Cleanflight's default proportional gain: `dcm_kp` = 2500 / 10000.
pub const DCM_KP_DEFAULT: f64 = 0.25;
/// Cleanflight's default integral gain: `dcm_ki` = 0.
pub const DCM_KI_DEFAULT: f64 = 0.0;

/// What the gyro task publishes: running sums since boot, never reset.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GyroSnapshot {
    /// Σ of all rate samples so far, rad/s (f64: no loss over long flights
    /// at these magnitudes, and differences of sums stay exact enough).
    pub sum: Vec3,
    /// Number of samples in `sum`.
    pub count: u64,
    /// Timestamp of the newest sample, ns.
    pub last_t_ns: u64,
    /// The newest sample itself, rad/s (what a rate loop would read).
    pub latest: Vec3,
}

/// The gyro task's state: accumulates samples into a [`GyroSnapshot`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GyroAccumulator {
    snap: GyroSnapshot,
}

impl GyroAccumulator {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }
    /// Add one sample (rad/s) taken at `t_ns`.
    pub fn push(&mut self, rate: Vec3, t_ns: u64) {
        self.snap.sum += rate;
        self.snap.count += 1;
        self.snap.last_t_ns = t_ns;
        self.snap.latest = rate;
    }
    /// The value to publish.
    pub fn snapshot(&self) -> GyroSnapshot {
        self.snap
    }
}

/// One accelerometer sample: specific force in the body frame, m/s².
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AccelSample {
    /// Specific force (reads +g on body z when level and at rest).
    pub specific_force: Vec3,
    /// Sample time, ns.
    pub t_ns: u64,
}

/// The AHRS output.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attitude {
    /// Estimated body → world rotation.
    pub q: Quat,
    /// The same as Euler angles.
    pub euler: Euler,
    /// Mean body rate over the last interval, rad/s.
    pub rate: Vec3,
    /// Timestamp of the newest gyro sample used, ns.
    pub t_ns: u64,
    /// Whether the accelerometer correction was applied this update.
    pub accel_used: bool,
}

/// Mahony AHRS state and gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mahony {
    /// Proportional gain, rad/s per unit error (≈ rad).
    pub kp: f64,
    /// Integral gain, rad/s² per unit error.
    pub ki: f64,
    q: Quat,
    integral: Vec3,
    prev: Option<GyroSnapshot>,
}

impl Default for Mahony {
    fn default() -> Self {
        Self::new(DCM_KP_DEFAULT, DCM_KI_DEFAULT)
    }
}

/// Mean rate and dt between two gyro snapshots; `None` when no new sample.
pub fn mean_rate(prev: &GyroSnapshot, now: &GyroSnapshot) -> Option<(Vec3, f64)> {
    let n = now.count.checked_sub(prev.count)?;
    if n == 0 || now.last_t_ns <= prev.last_t_ns {
        return None;
    }
    let dt = (now.last_t_ns - prev.last_t_ns) as f64 * 1e-9;
    Some(((now.sum - prev.sum) / n as f64, dt))
}

/// Cleanflight's accelerometer health test: |a| within 0.9 g … 1.1 g.
pub fn accel_healthy(a: Vec3) -> bool {
    let g = a.norm() / GRAVITY;
    g > 0.9 && g < 1.1
}

impl Mahony {
    /// A filter starting level with the given gains.
    pub fn new(kp: f64, ki: f64) -> Self {
        Self {
            kp,
            ki,
            q: Quat::IDENTITY,
            integral: Vec3::ZERO,
            prev: None,
        }
    }

    /// Start from a given attitude (tests, or an initial alignment).
    pub fn with_attitude(mut self, q: Quat) -> Self {
        self.q = q.normalized();
        self
    }

    /// The current estimate.
    pub fn quat(&self) -> Quat {
        self.q
    }

    /// Correction rate from the accelerometer: e = â × v̂, v̂ the estimated
    /// "up" in the body (the third row of Cleanflight's rMat).
    fn accel_error(&self, accel: Vec3) -> Vec3 {
        let a = accel.normalized();
        let v = self.q.rotate_inv(Vec3::new(0.0, 0.0, 1.0));
        a.cross(v)
    }

    /// One AHRS step from the newest gyro snapshot and accelerometer sample.
    /// The first call only records the snapshot (no interval yet).
    pub fn update(&mut self, gyro: GyroSnapshot, accel: AccelSample) -> Attitude {
        let Some(prev) = self.prev.replace(gyro) else {
            return self.output(gyro.latest, gyro.last_t_ns, false);
        };
        let Some((rate, dt)) = mean_rate(&prev, &gyro) else {
            return self.output(gyro.latest, gyro.last_t_ns, false);
        };
        let use_acc = accel_healthy(accel.specific_force);
        let mut w = rate;
        if use_acc {
            let e = self.accel_error(accel.specific_force);
            if self.ki > 0.0 {
                self.integral += e * (self.ki * dt);
            }
            w += e * self.kp + self.integral;
        }
        self.q = self
            .q
            .compose(Quat::from_rotation_vector(w * dt))
            .normalized();
        self.output(rate, gyro.last_t_ns, use_acc)
    }

    fn output(&self, rate: Vec3, t_ns: u64, accel_used: bool) -> Attitude {
        Attitude {
            q: self.q,
            euler: self.q.to_euler(),
            rate,
            t_ns,
            accel_used,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::deg;

    /// Feed a stationary, tilted vehicle: gyro reads 0, accel reads the true
    /// "up" in the body. Returns the estimate's tilt error after `secs`.
    fn converge(kp: f64, tilt_deg: f64, secs: f64) -> f64 {
        let truth = Quat::from_euler(Euler {
            roll: deg(tilt_deg),
            pitch: 0.0,
            yaw: 0.0,
        });
        let up_body = truth.rotate_inv(Vec3::new(0.0, 0.0, GRAVITY));
        let mut ahrs = Mahony::new(kp, 0.0);
        let mut acc = GyroAccumulator::new();
        let mut t = 0u64;
        let mut att = Attitude::default();
        // Gyro at 1 kHz, AHRS at 200 Hz as in Table V.
        while (t as f64) * 1e-9 < secs {
            for _ in 0..5 {
                t += 1_000_000;
                acc.push(Vec3::ZERO, t);
            }
            let a = AccelSample {
                specific_force: up_body,
                t_ns: t,
            };
            att = ahrs.update(acc.snapshot(), a);
        }
        att.q.angle_to(truth).to_degrees()
    }

    #[test]
    fn converges_from_30_degrees_with_cleanflight_kp() {
        // Closed form for a static tilt: tan(θ/2) decays as exp(−kp·t), so
        // 30° → 1° takes ln(tan 15° / tan 0.5°)/kp = 3.42/0.25 = 13.7 s.
        let e = converge(DCM_KP_DEFAULT, 30.0, 13.0);
        assert!(e > 1.0, "faster than the closed form? {e}");
        let e = converge(DCM_KP_DEFAULT, 30.0, 14.5);
        assert!(e < 1.0, "after 14.5 s: {e}°");
        // 10x gain (Betaflight's disarmed boost) converges in ~1.4 s.
        assert!(converge(2.5, 30.0, 1.5) < 1.0);
    }

    #[test]
    fn accel_outside_band_is_ignored() {
        let mut ahrs = Mahony::default().with_attitude(Quat::from_euler(Euler {
            roll: deg(30.0),
            pitch: 0.0,
            yaw: 0.0,
        }));
        let q0 = ahrs.quat();
        let mut acc = GyroAccumulator::new();
        for (i, g) in [1.2, 0.85, 1.12, 0.5].iter().enumerate() {
            let t = (i as u64 + 1) * 5_000_000;
            acc.push(Vec3::ZERO, t);
            let a = AccelSample {
                specific_force: Vec3::new(0.0, 0.0, g * GRAVITY),
                t_ns: t,
            };
            let att = ahrs.update(acc.snapshot(), a);
            assert!(!att.accel_used);
        }
        assert_eq!(ahrs.quat(), q0);
        assert!(accel_healthy(Vec3::new(0.0, 0.0, 1.05 * GRAVITY)));
    }

    #[test]
    fn averaging_from_sums_and_counts_is_exact() {
        let mut acc = GyroAccumulator::new();
        acc.push(Vec3::new(1.0, 2.0, 3.0), 1_000_000);
        let a = acc.snapshot();
        for (i, r) in [0.5, 1.5, 2.5, 3.5].iter().enumerate() {
            acc.push(Vec3::new(*r, -*r, 0.25), 2_000_000 + i as u64 * 1_000_000);
        }
        let b = acc.snapshot();
        let (m, dt) = mean_rate(&a, &b).unwrap();
        assert_eq!(m, Vec3::new(2.0, -2.0, 0.25));
        assert_eq!(dt, 0.004);
        assert!(mean_rate(&b, &b).is_none());
        // Integrating the exact mean: 2 rad/s about x for 4 ms = 8 mrad.
        let mut ahrs = Mahony::new(0.0, 0.0);
        ahrs.update(a, AccelSample::default());
        let att = ahrs.update(b, AccelSample::default());
        assert!(
            (att.q.angle_to(Quat::IDENTITY) - (2.0f64 * 2.0 + 2.0 * 2.0 + 0.0625).sqrt() * 0.004)
                .abs()
                < 1e-12
        );
    }
}
