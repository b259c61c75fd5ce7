//! Angle-mode attitude controller over a rate PID, after Betaflight's
//! src/main/flight/pid.c: an outer P loop turns the roll/pitch angle error
//! into a rate set-point (bounded by a maximum rate); the inner loop is a
//! PID per axis with the D term on the measurement (filtered), an I term
//! clamped and frozen while the mixer saturates (anti-windup), and a
//! feed-forward on set-point change. Yaw is rate mode.
//!
//! Outputs are in mixer units: 1.0 on an axis drives the full ±1 motor
//! differential of [`crate::mixer`].

use crate::error::{non_negative, positive, ConfigError};
use crate::filter::Pt1;
use crate::math::{Euler, Vec3};
use serde::Deserialize;

/// Gains of one rate axis (output in mixer units per rad/s of error).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RateGains {
    /// Proportional gain, 1/(rad/s).
    pub kp: f64,
    /// Integral gain, 1/rad.
    pub ki: f64,
    /// Derivative gain on the measurement, s/rad.
    pub kd: f64,
    /// Feed-forward gain on the set-point derivative, s/rad.
    #[serde(default)]
    pub kff: f64,
    /// Bound of the integral term, mixer units.
    pub i_limit: f64,
}

/// The whole controller configuration (the `[pid]` table of a preset).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PidConfig {
    /// Roll rate gains.
    pub roll: RateGains,
    /// Pitch rate gains.
    pub pitch: RateGains,
    /// Yaw rate gains.
    pub yaw: RateGains,
    /// Angle loop gain: rate set-point per angle error, 1/s.
    pub level_kp: f64,
    /// Largest roll/pitch rate set-point the angle loop may ask, deg/s.
    pub max_rate_dps: f64,
    /// Largest yaw rate set-point, deg/s.
    pub yaw_max_rate_dps: f64,
    /// D-term PT1 cut-off, Hz (must be below the PID rate's Nyquist).
    pub dterm_lpf_hz: f64,
    /// Bound of each axis output, mixer units (Betaflight pidsum_limit 500/1000).
    pub output_limit: f64,
}

impl PidConfig {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (name, g) in [
            ("roll", &self.roll),
            ("pitch", &self.pitch),
            ("yaw", &self.yaw),
        ] {
            for (f, v) in [
                ("kp", g.kp),
                ("ki", g.ki),
                ("kd", g.kd),
                ("kff", g.kff),
                ("i_limit", g.i_limit),
            ] {
                non_negative(&format!("pid.{name}.{f}"), v)?;
            }
        }
        positive("pid.level_kp", self.level_kp)?;
        positive("pid.max_rate_dps", self.max_rate_dps)?;
        positive("pid.yaw_max_rate_dps", self.yaw_max_rate_dps)?;
        positive("pid.dterm_lpf_hz", self.dterm_lpf_hz)?;
        positive("pid.output_limit", self.output_limit)?;
        Ok(())
    }
}

/// State of one rate axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisPid {
    gains: RateGains,
    limit: f64,
    integ: f64,
    prev_meas: Option<f64>,
    prev_sp: Option<f64>,
    dterm: Pt1,
}

impl AxisPid {
    /// A fresh axis; `pid_rate_hz` sizes the D-term filter.
    pub fn new(
        gains: RateGains,
        limit: f64,
        dterm_hz: f64,
        pid_rate_hz: f64,
    ) -> Result<Self, ConfigError> {
        let dterm = Pt1::new(dterm_hz, pid_rate_hz)
            .map_err(|e| ConfigError::new("pid.dterm_lpf_hz", e.reason))?;
        Ok(Self {
            gains,
            limit,
            integ: 0.0,
            prev_meas: None,
            prev_sp: None,
            dterm,
        })
    }

    /// The integral term (mixer units).
    pub fn integral(&self) -> f64 {
        self.integ
    }

    /// Zero the integrator and derivative history (on disarm).
    pub fn reset(&mut self) {
        self.integ = 0.0;
        self.prev_meas = None;
        self.prev_sp = None;
        self.dterm.reset(0.0);
    }

    /// One PID step. `hold_i`: the mixer saturated last step, so the
    /// integral may only shrink (anti-windup).
    pub fn update(&mut self, setpoint: f64, measurement: f64, dt: f64, hold_i: bool) -> f64 {
        let g = self.gains;
        let err = setpoint - measurement;
        let grows = err * self.integ >= 0.0;
        if dt > 0.0 && !(hold_i && grows) {
            self.integ = (self.integ + g.ki * err * dt).clamp(-g.i_limit, g.i_limit);
        }
        // D on measurement: no derivative kick when the set-point steps.
        let d_raw = match self.prev_meas {
            Some(p) if dt > 0.0 => -(measurement - p) / dt,
            _ => 0.0,
        };
        let d = self.dterm.apply(d_raw);
        let ff = match self.prev_sp {
            Some(p) if dt > 0.0 => (setpoint - p) / dt,
            _ => 0.0,
        };
        self.prev_meas = Some(measurement);
        self.prev_sp = Some(setpoint);
        let out = g.kp * err + self.integ + g.kd * d + g.kff * ff;
        out.clamp(-self.limit, self.limit)
    }
}

/// What the pilot (or the autopilot) asks for.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Setpoint {
    /// Roll angle, rad.
    pub roll: f64,
    /// Pitch angle, rad.
    pub pitch: f64,
    /// Yaw rate, rad/s.
    pub yaw_rate: f64,
    /// Collective throttle in [0, 1].
    pub throttle: f64,
}

/// Controller output: per-axis commands in mixer units plus throttle.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisCommand {
    /// Roll torque command.
    pub roll: f64,
    /// Pitch torque command.
    pub pitch: f64,
    /// Yaw torque command.
    pub yaw: f64,
    /// Collective throttle in [0, 1].
    pub throttle: f64,
}

/// The angle loop (Betaflight's angle mode): the roll/pitch angle error
/// times `level_kp`, and the pilot's yaw rate, each bounded, become the
/// rate set-point of the rate loop. Stateless: the same in Cleanflight's
/// PID task and in the cascade's attitude task.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleLoop {
    level_kp: f64,
    max_rate: f64,
    yaw_max_rate: f64,
}

impl AngleLoop {
    /// The angle loop of `cfg` (validated by the caller).
    pub fn new(cfg: &PidConfig) -> Self {
        Self {
            level_kp: cfg.level_kp,
            max_rate: cfg.max_rate_dps.to_radians(),
            yaw_max_rate: cfg.yaw_max_rate_dps.to_radians(),
        }
    }

    /// The body rate set-point, rad/s, for `sp` at the attitude `att`.
    pub fn rate_setpoint(&self, sp: &Setpoint, att: &Euler) -> Vec3 {
        let (k, max, ymax) = (self.level_kp, self.max_rate, self.yaw_max_rate);
        Vec3::new(
            (k * (sp.roll - att.roll)).clamp(-max, max),
            (k * (sp.pitch - att.pitch)).clamp(-max, max),
            sp.yaw_rate.clamp(-ymax, ymax),
        )
    }
}

/// The rate loop: a PID per axis on the measured body rate (D on the
/// measurement, through the D-term low-pass), anti-windup from the mixer.
/// A pure controller, as PX4's `RateControl`: rates and dt in, torque
/// commands out; arming, set-points and timing belong to its caller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateController {
    axes: [AxisPid; 3],
    saturated: bool,
}

impl RateController {
    /// The rate loop of `cfg` stepped at `rate_hz` (validates `cfg`).
    pub fn new(cfg: &PidConfig, rate_hz: f64) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let mk = |g| AxisPid::new(g, cfg.output_limit, cfg.dterm_lpf_hz, rate_hz);
        Ok(Self {
            axes: [mk(cfg.roll)?, mk(cfg.pitch)?, mk(cfg.yaw)?],
            saturated: false,
        })
    }

    /// Tell the loop whether the mixer saturated (anti-windup).
    pub fn set_saturated(&mut self, saturated: bool) {
        self.saturated = saturated;
    }

    /// Zero all integrators and derivative histories.
    pub fn reset(&mut self) {
        self.axes.iter_mut().for_each(AxisPid::reset);
    }

    /// The per-axis integral terms.
    pub fn integrals(&self) -> [f64; 3] {
        [
            self.axes[0].integral(),
            self.axes[1].integral(),
            self.axes[2].integral(),
        ]
    }

    /// One step: torque commands (mixer units) for the set-point `rate_sp`
    /// and the measured `gyro` rate, rad/s, `dt` s after the previous step.
    pub fn update(&mut self, rate_sp: Vec3, gyro: Vec3, dt: f64) -> [f64; 3] {
        let s = self.saturated;
        [
            self.axes[0].update(rate_sp.x, gyro.x, dt, s),
            self.axes[1].update(rate_sp.y, gyro.y, dt, s),
            self.axes[2].update(rate_sp.z, gyro.z, dt, s),
        ]
    }
}

/// Angle loop + rate loop in one step (Cleanflight's PID task's state).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controller {
    angle: AngleLoop,
    rate: RateController,
    rate_sp: Vec3,
}

impl Controller {
    /// A controller running at `pid_rate_hz`; validates `cfg`.
    pub fn new(cfg: PidConfig, pid_rate_hz: f64) -> Result<Self, ConfigError> {
        Ok(Self {
            rate: RateController::new(&cfg, pid_rate_hz)?,
            angle: AngleLoop::new(&cfg),
            rate_sp: Vec3::ZERO,
        })
    }

    /// Tell the controller whether the mixer saturated (anti-windup).
    pub fn set_saturated(&mut self, saturated: bool) {
        self.rate.set_saturated(saturated);
    }

    /// Zero all integrators (on disarm or while on the ground).
    pub fn reset(&mut self) {
        self.rate.reset();
    }

    /// The rate set-point of the last update, rad/s (body).
    pub fn rate_setpoint(&self) -> Vec3 {
        self.rate_sp
    }

    /// The per-axis integral terms.
    pub fn integrals(&self) -> [f64; 3] {
        self.rate.integrals()
    }

    /// One PID step: `att` from the AHRS, `gyro` the latest filtered body
    /// rate, `dt` the time since the previous step, s.
    pub fn update(&mut self, sp: &Setpoint, att: &Euler, gyro: Vec3, dt: f64) -> AxisCommand {
        self.rate_sp = self.angle.rate_setpoint(sp, att);
        let [roll, pitch, yaw] = self.rate.update(self.rate_sp, gyro, dt);
        AxisCommand {
            roll,
            pitch,
            yaw,
            throttle: sp.throttle.clamp(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> RateGains {
        RateGains {
            kp: 0.1,
            ki: 1.0,
            kd: 0.001,
            kff: 0.0,
            i_limit: 0.2,
        }
    }

    #[test]
    fn p_and_i_terms_are_hand_computable() {
        let mut a = AxisPid::new(gains(), 0.5, 100.0, 500.0).unwrap();
        // err = 1 rad/s: P = 0.1, I = 1·1·0.002 = 0.002, D = 0 (first step).
        let u = a.update(1.0, 0.0, 0.002, false);
        assert!((u - 0.102).abs() < 1e-12, "{u}");
        // The integral is clamped at i_limit.
        for _ in 0..1000 {
            a.update(1.0, 0.0, 0.002, false);
        }
        assert!((a.integral() - 0.2).abs() < 1e-12);
    }

    #[test]
    fn integral_does_not_grow_while_saturated_but_may_shrink() {
        let mut a = AxisPid::new(gains(), 0.5, 100.0, 500.0).unwrap();
        a.update(1.0, 0.0, 0.01, false);
        let i0 = a.integral();
        a.update(1.0, 0.0, 0.01, true);
        assert_eq!(a.integral(), i0);
        a.update(-1.0, 0.0, 0.01, true);
        assert!(a.integral() < i0);
    }

    #[test]
    fn d_is_on_measurement_and_ff_on_setpoint_change() {
        let g = RateGains {
            kp: 0.0,
            ki: 0.0,
            kd: 1.0,
            kff: 0.0,
            i_limit: 0.0,
        };
        let mut a = AxisPid::new(g, 10.0, 100.0, 500.0).unwrap();
        a.update(0.0, 0.0, 0.002, false);
        // A set-point step gives no D kick.
        assert_eq!(a.update(5.0, 0.0, 0.002, false), 0.0);
        // A measurement rise gives a negative D.
        assert!(a.update(5.0, 0.01, 0.002, false) < 0.0);
        let g = RateGains {
            kp: 0.0,
            ki: 0.0,
            kd: 0.0,
            kff: 0.01,
            i_limit: 0.0,
        };
        let mut a = AxisPid::new(g, 10.0, 100.0, 500.0).unwrap();
        a.update(0.0, 0.0, 0.002, false);
        // FF = 0.01 · (1 − 0)/0.002 = 5, clamped at the output limit 10.
        assert!((a.update(1.0, 0.0, 0.002, false) - 5.0).abs() < 1e-12);
    }

    /// The rate loop of the cascade: a step of the rate set-point moves
    /// only P (and FF) — no D kick — while a step of the measured rate
    /// does give a D term, through the D-term low-pass.
    #[test]
    fn rate_controller_has_no_d_kick_on_a_setpoint_step() {
        let d_only = RateGains {
            kp: 0.0,
            ki: 0.0,
            kd: 0.01,
            kff: 0.0,
            i_limit: 0.0,
        };
        let cfg = PidConfig {
            roll: d_only,
            pitch: d_only,
            yaw: d_only,
            level_kp: 6.0,
            max_rate_dps: 200.0,
            yaw_max_rate_dps: 200.0,
            dterm_lpf_hz: 75.0,
            output_limit: 1.0,
        };
        let dt = 1.0 / 8000.0;
        let mut rc = RateController::new(&cfg, 8000.0).unwrap();
        rc.update(Vec3::ZERO, Vec3::ZERO, dt);
        for _ in 0..100 {
            let out = rc.update(Vec3::new(5.0, -5.0, 2.0), Vec3::ZERO, dt);
            assert_eq!(out, [0.0; 3], "a set-point step kicked D");
        }
        let out = rc.update(Vec3::new(5.0, -5.0, 2.0), Vec3::new(0.1, 0.0, 0.0), dt);
        assert!(out[0] < 0.0, "a measurement step gives D: {out:?}");
    }
}
