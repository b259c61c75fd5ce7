//! Quad-X mixer with Betaflight's motor order (src/main/flight/mixer.c /
//! mixer_init.c `mixerQuadX`), airmode-like saturation handling.
//!
//! Motor order (seen from above, nose up): 1 rear-right, 2 front-right,
//! 3 rear-left, 4 front-left. Betaflight's default "props in": motors 1 and
//! 4 spin clockwise, 2 and 3 counter-clockwise (seen from above).
//!
//! Betaflight's table (throttle, roll, pitch, yaw) is
//! 1: (1, −1, +1, −1), 2: (1, −1, −1, +1), 3: (1, +1, +1, +1), 4: (1, +1, −1, −1).
//! Our roll and pitch columns are the same (positive roll lowers the right
//! side, positive pitch lowers the nose); our yaw column is negated
//! because our yaw axis is z-up (positive = counter-clockwise from above)
//! while Betaflight's yaw is positive nose-right. The sign of every column
//! is checked against the plant's angular acceleration in the tests.

use crate::pid::AxisCommand;

/// Roll, pitch, yaw factors per motor, in our FLU convention.
pub const QUAD_X: [[f64; 3]; 4] = [
    [-1.0, 1.0, 1.0],   // 1 rear-right, CW
    [-1.0, -1.0, -1.0], // 2 front-right, CCW
    [1.0, 1.0, -1.0],   // 3 rear-left, CCW
    [1.0, -1.0, 1.0],   // 4 front-left, CW
];

/// Mixer result.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MixOutput {
    /// Motor commands in [0, 1], Betaflight order.
    pub motors: [f64; 4],
    /// True if the attitude differential had to be scaled down or the
    /// throttle shifted to fit [0, 1].
    pub saturated: bool,
}

/// What the PID task publishes for the motor task (and the motor task for
/// the ESCs): the mixed commands and whether they spin the motors.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotorDemand {
    /// Motor commands in [0, 1], Betaflight order.
    pub motors: [f64; 4],
    /// Armed: motors spin.
    pub armed: bool,
}

/// Mix axis commands into four motor commands.
///
/// The attitude differential d_i = roll·R_i + pitch·P_i + yaw·Y_i keeps
/// priority (airmode): if its span max−min exceeds 1 it is scaled to fit;
/// then the throttle is shifted into [−min d, 1 − max d] so every motor
/// lands in [0, 1]. Saturation is reported for PID anti-windup.
pub fn mix(cmd: &AxisCommand) -> MixOutput {
    let mut d = [0.0; 4];
    for (di, f) in d.iter_mut().zip(QUAD_X.iter()) {
        *di = cmd.roll * f[0] + cmd.pitch * f[1] + cmd.yaw * f[2];
    }
    let lo = d.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = hi - lo;
    let mut saturated = false;
    let (scale, lo, hi) = if span > 1.0 {
        saturated = true;
        (1.0 / span, lo / span, hi / span)
    } else {
        (1.0, lo, hi)
    };
    let thr_in = cmd.throttle.clamp(0.0, 1.0);
    // With span = 1 after scaling the window is a single point; rounding
    // could invert it, so take it directly.
    let thr = if scale < 1.0 {
        -lo
    } else {
        thr_in.clamp(-lo, 1.0 - hi)
    };
    saturated |= (thr - thr_in).abs() > 1e-12;
    let mut motors = [0.0; 4];
    for (m, di) in motors.iter_mut().zip(d.iter()) {
        *m = (thr + di * scale).clamp(0.0, 1.0);
    }
    MixOutput { motors, saturated }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd(roll: f64, pitch: f64, yaw: f64, throttle: f64) -> AxisCommand {
        AxisCommand {
            roll,
            pitch,
            yaw,
            throttle,
        }
    }

    #[test]
    fn unsaturated_mix_is_the_table() {
        let m = mix(&cmd(0.1, 0.0, 0.0, 0.5));
        assert_eq!(m.motors, [0.4, 0.4, 0.6, 0.6]);
        assert!(!m.saturated);
        let m = mix(&cmd(0.0, 0.1, 0.05, 0.5));
        assert_eq!(m.motors, [0.65, 0.35, 0.55, 0.45]);
    }

    #[test]
    fn throttle_is_shifted_to_keep_attitude_authority() {
        // Low throttle: differential ±0.2 needs throttle ≥ 0.2.
        let m = mix(&cmd(0.2, 0.0, 0.0, 0.05));
        assert!(m.saturated);
        assert!((m.motors[0] - 0.0).abs() < 1e-12 && (m.motors[2] - 0.4).abs() < 1e-12);
        // Span 2.0 > 1: scaled by 1/2, then fitted.
        let m = mix(&cmd(1.0, 0.0, 0.0, 0.9));
        assert!(m.saturated);
        assert!((m.motors[2] - m.motors[0] - 1.0).abs() < 1e-12);
        assert!(m.motors.iter().all(|x| (0.0..=1.0).contains(x)));
    }
}
