//! A small autopilot ("companion computer") that runs at the radio task's
//! rate and turns a [`PilotIntent`] plus the vehicle state into radio
//! set-points. A stick-only time line cannot hold altitude, so:
//!
//! - altitude hold: P on altitude → vertical-speed set-point (bounded),
//!   PI on vertical speed → throttle, plus the hover throttle as a
//!   feed-forward divided by cos(roll)·cos(pitch);
//! - position hold: P on position → velocity set-point (bounded), P on
//!   velocity → acceleration → small roll/pitch set-points (bounded);
//!   a non-zero roll/pitch stick overrides it, and the hold point is
//!   re-latched where the stick is released;
//! - heading hold: P on heading error → yaw-rate set-point;
//! - landing: descend at the landing speed, disarm once on the ground.
//!
//! It reads the true position/velocity (as from motion capture); attitude
//! may be true or estimated, at the caller's choice.

use super::mission::PilotIntent;
use super::RcCommand;
use crate::error::{non_negative, positive, ConfigError};
use crate::math::{deg, wrap_pi, Euler, Vec3, GRAVITY};
use serde::Deserialize;

/// Autopilot gains (the `[autopilot]` table of a preset).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutopilotConfig {
    /// Altitude error → climb rate, 1/s.
    pub alt_kp: f64,
    /// Largest climb rate, m/s.
    pub climb_max_mps: f64,
    /// Largest descent rate, m/s.
    pub descent_max_mps: f64,
    /// Climb-rate error → throttle, per m/s.
    pub vz_kp: f64,
    /// Climb-rate error integral → throttle, per m.
    pub vz_ki: f64,
    /// Bound of the throttle integral.
    pub vz_i_limit: f64,
    /// Position error → velocity, 1/s.
    pub pos_kp: f64,
    /// Velocity error → acceleration, 1/s.
    pub vel_kp: f64,
    /// Largest horizontal speed set-point, m/s.
    pub vel_max_mps: f64,
    /// Largest tilt the position hold may ask, deg.
    pub max_tilt_deg: f64,
    /// Heading error → yaw rate, 1/s.
    pub yaw_kp: f64,
    /// Largest yaw rate the heading hold may ask, deg/s.
    pub yaw_rate_max_dps: f64,
    /// Landing descent speed, m/s.
    pub land_speed_mps: f64,
}

impl AutopilotConfig {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (n, v) in [
            ("alt_kp", self.alt_kp),
            ("climb_max_mps", self.climb_max_mps),
            ("descent_max_mps", self.descent_max_mps),
            ("vz_kp", self.vz_kp),
            ("pos_kp", self.pos_kp),
            ("vel_kp", self.vel_kp),
            ("vel_max_mps", self.vel_max_mps),
            ("max_tilt_deg", self.max_tilt_deg),
            ("yaw_kp", self.yaw_kp),
            ("yaw_rate_max_dps", self.yaw_rate_max_dps),
            ("land_speed_mps", self.land_speed_mps),
        ] {
            positive(&format!("autopilot.{n}"), v)?;
        }
        non_negative("autopilot.vz_ki", self.vz_ki)?;
        non_negative("autopilot.vz_i_limit", self.vz_i_limit)?;
        Ok(())
    }
}

/// What the autopilot observes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VehicleState {
    /// Position (world), m.
    pub pos: Vec3,
    /// Velocity (world), m/s.
    pub vel: Vec3,
    /// Attitude.
    pub euler: Euler,
    /// Resting on the ground.
    pub on_ground: bool,
}

/// Autopilot state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Autopilot {
    cfg: AutopilotConfig,
    hover_throttle: f64,
    vz_int: f64,
    hold: Option<Vec3>,
    landed: bool,
    last_t_ns: Option<u64>,
}

impl Autopilot {
    /// A fresh autopilot; `hover_throttle` is the feed-forward.
    pub fn new(cfg: AutopilotConfig, hover_throttle: f64) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            hover_throttle,
            vz_int: 0.0,
            hold: None,
            landed: false,
            last_t_ns: None,
        })
    }

    /// True once a landing finished (the autopilot keeps the vehicle disarmed).
    pub fn landed(&self) -> bool {
        self.landed
    }

    fn throttle(&mut self, intent: &PilotIntent, st: &VehicleState, dt: f64) -> f64 {
        if let Some(t) = intent.throttle {
            return t;
        }
        let c = self.cfg;
        let vz_sp = if intent.land {
            -c.land_speed_mps
        } else if let Some(h) = intent.altitude_m {
            (c.alt_kp * (h - st.pos.z)).clamp(-c.descent_max_mps, c.climb_max_mps)
        } else {
            return 0.0;
        };
        if st.on_ground && (intent.land || vz_sp <= 0.0) {
            self.vz_int = 0.0;
            return 0.0;
        }
        let err = vz_sp - st.vel.z;
        if !st.on_ground {
            self.vz_int = (self.vz_int + c.vz_ki * err * dt).clamp(-c.vz_i_limit, c.vz_i_limit);
        }
        let tilt = (st.euler.roll.cos() * st.euler.pitch.cos()).max(0.5);
        (self.hover_throttle / tilt + c.vz_kp * err + self.vz_int).clamp(0.0, 1.0)
    }

    fn attitude(&mut self, intent: &PilotIntent, st: &VehicleState) -> (f64, f64) {
        let sticks = (deg(intent.roll_deg), deg(intent.pitch_deg));
        let overridden = intent.roll_deg != 0.0 || intent.pitch_deg != 0.0;
        if !intent.hold_position || st.on_ground || overridden {
            self.hold = None;
            return sticks;
        }
        let c = self.cfg;
        let target = *self.hold.get_or_insert(Vec3::new(st.pos.x, st.pos.y, 0.0));
        let mut v_sp = Vec3::new(target.x - st.pos.x, target.y - st.pos.y, 0.0) * c.pos_kp;
        let n = v_sp.norm();
        if n > c.vel_max_mps {
            v_sp = v_sp * (c.vel_max_mps / n);
        }
        let a = (v_sp - Vec3::new(st.vel.x, st.vel.y, 0.0)) * c.vel_kp;
        let (s, co) = st.euler.yaw.sin_cos();
        let (ax, ay) = (co * a.x + s * a.y, -s * a.x + co * a.y);
        let m = deg(c.max_tilt_deg);
        // Positive pitch (nose down) accelerates +x; positive roll, −y.
        (
            (-(ay / GRAVITY).atan()).clamp(-m, m),
            (ax / GRAVITY).atan().clamp(-m, m),
        )
    }

    fn yaw_rate(&self, intent: &PilotIntent, st: &VehicleState) -> f64 {
        match intent.yaw_deg {
            Some(y) => {
                let m = deg(self.cfg.yaw_rate_max_dps);
                (self.cfg.yaw_kp * wrap_pi(deg(y) - st.euler.yaw)).clamp(-m, m)
            }
            None => deg(intent.yaw_rate_dps),
        }
    }

    /// One autopilot step at `t_ns`: the radio frame to send.
    pub fn update(&mut self, t_ns: u64, intent: &PilotIntent, st: &VehicleState) -> RcCommand {
        let dt = self
            .last_t_ns
            .map_or(0.0, |t| t_ns.saturating_sub(t) as f64 * 1e-9);
        self.last_t_ns = Some(t_ns);
        if intent.land && st.on_ground {
            self.landed = true;
        }
        if !intent.land {
            self.landed = false;
        }
        if !intent.arm || self.landed {
            self.vz_int = 0.0;
            self.hold = None;
            return RcCommand::default();
        }
        let throttle = self.throttle(intent, st, dt);
        let (roll, pitch) = self.attitude(intent, st);
        RcCommand {
            roll,
            pitch,
            yaw_rate: self.yaw_rate(intent, st),
            throttle,
            arm: true,
        }
    }
}
