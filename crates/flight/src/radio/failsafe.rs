//! Failsafe on radio loss (after Cleanflight's failsafe.c, simplified): no
//! new radio frame for more than `timeout_ms` → level the vehicle and
//! descend with a fixed throttle below hover; disarm when landed or after
//! `max_descent_s`. A fresh frame before landing returns control.

use crate::pid::Setpoint;

/// Failsafe parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FailsafeConfig {
    /// Radio silence that triggers the failsafe, ms.
    pub timeout_ms: u64,
    /// Throttle held while descending (a little below hover).
    pub descent_throttle: f64,
    /// Longest descent before a forced disarm, s.
    pub max_descent_s: f64,
}

/// Failsafe phase.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum FailsafePhase {
    /// Radio fine.
    #[default]
    Idle,
    /// Radio lost at the given time (ns): level and descend.
    Descending(u64),
    /// Landed or timed out: disarmed until the radio returns and the
    /// pilot re-arms.
    Disarmed,
}

/// What the flight controller must do this step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FailsafeAction {
    /// Use the pilot's set-points.
    PassThrough,
    /// Use these set-points instead.
    Override(Setpoint),
    /// Disarm now / stay disarmed.
    Disarm,
}

/// The failsafe state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Failsafe {
    cfg: FailsafeConfig,
    phase: FailsafePhase,
}

impl Failsafe {
    /// Idle failsafe.
    pub fn new(cfg: FailsafeConfig) -> Self {
        Self {
            cfg,
            phase: FailsafePhase::Idle,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> FailsafePhase {
        self.phase
    }

    /// True unless idle.
    pub fn active(&self) -> bool {
        self.phase != FailsafePhase::Idle
    }

    /// Step at `now_ns`, given the newest frame's time and whether the
    /// vehicle is (detected) on the ground.
    pub fn update(&mut self, now_ns: u64, last_frame_ns: u64, on_ground: bool) -> FailsafeAction {
        let lost = now_ns.saturating_sub(last_frame_ns) > self.cfg.timeout_ms * 1_000_000;
        self.phase = match self.phase {
            FailsafePhase::Idle if lost => FailsafePhase::Descending(now_ns),
            FailsafePhase::Idle => FailsafePhase::Idle,
            FailsafePhase::Descending(_) if !lost => FailsafePhase::Idle,
            FailsafePhase::Descending(t0) => {
                let timed_out = now_ns.saturating_sub(t0) as f64 * 1e-9 > self.cfg.max_descent_s;
                if on_ground || timed_out {
                    FailsafePhase::Disarmed
                } else {
                    FailsafePhase::Descending(t0)
                }
            }
            FailsafePhase::Disarmed if !lost => FailsafePhase::Idle,
            FailsafePhase::Disarmed => FailsafePhase::Disarmed,
        };
        match self.phase {
            FailsafePhase::Idle => FailsafeAction::PassThrough,
            FailsafePhase::Descending(_) => FailsafeAction::Override(Setpoint {
                throttle: self.cfg.descent_throttle,
                ..Setpoint::default()
            }),
            FailsafePhase::Disarmed => FailsafeAction::Disarm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn sequence_idle_descend_land_disarm_recover() {
        let cfg = FailsafeConfig {
            timeout_ms: 100,
            descent_throttle: 0.4,
            max_descent_s: 10.0,
        };
        let mut f = Failsafe::new(cfg);
        assert_eq!(f.update(50 * MS, 0, false), FailsafeAction::PassThrough);
        // 100 ms of silence is still fine; 110 ms is not.
        assert_eq!(f.update(100 * MS, 0, false), FailsafeAction::PassThrough);
        let a = f.update(110 * MS, 0, false);
        assert!(matches!(a, FailsafeAction::Override(s) if s.throttle == 0.4 && s.roll == 0.0));
        assert_eq!(f.phase(), FailsafePhase::Descending(110 * MS));
        assert!(matches!(
            f.update(2000 * MS, 0, false),
            FailsafeAction::Override(_)
        ));
        assert_eq!(f.update(2500 * MS, 0, true), FailsafeAction::Disarm);
        assert_eq!(f.update(2600 * MS, 0, true), FailsafeAction::Disarm);
        // The radio returns: back to idle (re-arming is the pilot's job).
        assert_eq!(
            f.update(2700 * MS, 2690 * MS, true),
            FailsafeAction::PassThrough
        );
    }

    #[test]
    fn descent_times_out_and_a_frame_recovers_before_landing() {
        let cfg = FailsafeConfig {
            timeout_ms: 100,
            descent_throttle: 0.4,
            max_descent_s: 1.0,
        };
        let mut f = Failsafe::new(cfg);
        f.update(200 * MS, 0, false);
        assert!(f.active());
        assert!(matches!(
            f.update(500 * MS, 450 * MS, false),
            FailsafeAction::PassThrough
        ));
        f.update(1000 * MS, 450 * MS, false);
        assert_eq!(f.update(2100 * MS, 450 * MS, false), FailsafeAction::Disarm);
    }
}
