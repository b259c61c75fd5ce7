//! Pilot input: radio set-points and arming, the paper's synthetic input,
//! failsafe on radio loss, missions as TOML time lines, and a small
//! autopilot (a "companion computer") that turns a mission into radio
//! set-points at the radio task's rate.

mod autopilot;
mod failsafe;
mod mission;

pub use autopilot::{Autopilot, AutopilotConfig, VehicleState};
pub use failsafe::{Failsafe, FailsafeAction, FailsafeConfig, FailsafePhase};
pub use mission::{
    parse_time, Criteria, CriteriaOverride, Mission, MissionStep, PilotIntent, World, BREEZE_TOML,
    BUILTIN_MISSIONS, GUSTY_TOML, HOVER_TOML, MAX_AT_S, MAX_MISSION_STEPS, PAPER_TOML, STEPS_TOML,
};

use crate::math::deg;
use crate::pid::Setpoint;

/// One radio frame: sticks and the arm switch.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RcCommand {
    /// Roll angle set-point, rad.
    pub roll: f64,
    /// Pitch angle set-point, rad.
    pub pitch: f64,
    /// Yaw rate set-point, rad/s.
    pub yaw_rate: f64,
    /// Throttle in [0, 1].
    pub throttle: f64,
    /// Arm switch.
    pub arm: bool,
}

impl RcCommand {
    /// The PID set-point part.
    pub fn setpoint(&self) -> Setpoint {
        Setpoint {
            roll: self.roll,
            pitch: self.pitch,
            yaw_rate: self.yaw_rate,
            throttle: self.throttle,
        }
    }
}

/// A radio frame with its reception time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RadioSample {
    /// Reception time, ns.
    pub t_ns: u64,
    /// The frame.
    pub cmd: RcCommand,
}

/// The paper's synthetic input: armed, level, 20 % throttle.
pub fn paper_synthetic_input() -> RcCommand {
    RcCommand {
        roll: 0.0,
        pitch: 0.0,
        yaw_rate: 0.0,
        throttle: 0.2,
        arm: true,
    }
}

/// Why arming was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArmBlocker {
    /// Throttle not low.
    ThrottleHigh,
    /// Tilted more than the small-angle limit.
    NotLevel,
    /// The vehicle crashed.
    Crashed,
    /// Failsafe active.
    Failsafe,
}

/// Arming checks (Betaflight: throttle low, small_angle 25°, no crash).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmingChecks {
    /// Largest throttle accepted when arming.
    pub max_throttle: f64,
    /// Largest tilt accepted when arming, deg (Betaflight small_angle 25).
    pub max_tilt_deg: f64,
}

impl Default for ArmingChecks {
    fn default() -> Self {
        Self {
            max_throttle: 0.05,
            max_tilt_deg: 25.0,
        }
    }
}

impl ArmingChecks {
    /// Ok if arming is allowed now.
    pub fn check(
        &self,
        cmd: &RcCommand,
        tilt: f64,
        crashed: bool,
        failsafe: bool,
    ) -> Result<(), ArmBlocker> {
        if crashed {
            Err(ArmBlocker::Crashed)
        } else if failsafe {
            Err(ArmBlocker::Failsafe)
        } else if cmd.throttle > self.max_throttle {
            Err(ArmBlocker::ThrottleHigh)
        } else if tilt > deg(self.max_tilt_deg) {
            Err(ArmBlocker::NotLevel)
        } else {
            Ok(())
        }
    }
}

/// Arm state of the flight controller: arms on a rising arm switch when the
/// checks pass, disarms when the switch drops.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmState {
    /// Currently armed.
    pub armed: bool,
    prev_switch: bool,
    /// Why the last arming attempt failed.
    pub last_block: Option<ArmBlocker>,
}

impl ArmState {
    /// Update from a frame; returns the armed flag.
    pub fn update(&mut self, cmd: &RcCommand, checks: Result<(), ArmBlocker>) -> bool {
        if !cmd.arm {
            self.armed = false;
        } else if !self.armed && !self.prev_switch {
            self.last_block = checks.err();
            self.armed = checks.is_ok();
        }
        self.prev_switch = cmd.arm;
        self.armed
    }

    /// Force a disarm (failsafe, crash); re-arming needs a switch cycle.
    pub fn disarm(&mut self) {
        self.armed = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arming_needs_low_throttle_level_and_a_switch_edge() {
        let c = ArmingChecks::default();
        let mut s = ArmState::default();
        let mut cmd = RcCommand {
            throttle: 0.3,
            arm: true,
            ..RcCommand::default()
        };
        assert!(!s.update(&cmd, c.check(&cmd, 0.0, false, false)));
        assert_eq!(s.last_block, Some(ArmBlocker::ThrottleHigh));
        // Lowering the throttle with the switch still on does not arm.
        cmd.throttle = 0.0;
        assert!(!s.update(&cmd, c.check(&cmd, 0.0, false, false)));
        cmd.arm = false;
        s.update(&cmd, Ok(()));
        cmd.arm = true;
        assert_eq!(
            c.check(&cmd, deg(30.0), false, false),
            Err(ArmBlocker::NotLevel)
        );
        assert_eq!(c.check(&cmd, 0.0, true, false), Err(ArmBlocker::Crashed));
        assert!(s.update(&cmd, c.check(&cmd, deg(5.0), false, false)));
        cmd.arm = false;
        assert!(!s.update(&cmd, Ok(())));
        let p = paper_synthetic_input();
        assert_eq!((p.throttle, p.arm), (0.2, true));
    }
}
