//! The flight controller's gate between the pilot and the motors: arming
//! checks, the arm switch and the radio failsafe. Cleanflight's PID task
//! and the cascade's attitude task both ask it for the set-point to fly.

use crate::ahrs::Attitude;
use crate::pid::Setpoint;
use crate::radio::{ArmState, ArmingChecks, Failsafe, FailsafeAction, FailsafeConfig, RadioSample};

/// Arming and failsafe state.
pub struct Arming {
    arm: ArmState,
    checks: ArmingChecks,
    failsafe: Failsafe,
}

impl Arming {
    /// Disarmed, with the failsafe of `failsafe`.
    pub fn new(failsafe: FailsafeConfig) -> Arming {
        Arming {
            arm: ArmState::default(),
            checks: ArmingChecks::default(),
            failsafe: Failsafe::new(failsafe),
        }
    }

    /// Arming and failsafe decide at `now` (ns) on the attitude `att` and
    /// the latest radio frame `rx`; `None` means the motors stop.
    pub fn setpoint(&mut self, now: u64, att: &Attitude, rx: &RadioSample) -> Option<Setpoint> {
        // No landing detector on the controller side: a failsafe descent
        // disarms after its time-out.
        let action = self.failsafe.update(now, rx.t_ns, false);
        let check = self
            .checks
            .check(&rx.cmd, att.q.tilt(), false, self.failsafe.active());
        self.arm.update(&rx.cmd, check);
        let sp = match action {
            FailsafeAction::PassThrough => rx.cmd.setpoint(),
            FailsafeAction::Override(sp) => sp,
            FailsafeAction::Disarm => {
                self.arm.disarm();
                return None;
            }
        };
        self.arm.armed.then_some(sp)
    }
}
