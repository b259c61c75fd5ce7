//! The modern cascade's tasks, as Betaflight and PX4 fly it: the attitude
//! loop (periodic, on the AHRS estimate and the radio) hands a rate
//! set-point to the rate loop, which runs on every filtered gyro sample and
//! mixes (PX4's `mc_rate_control` over `RateControl`; Betaflight's PID
//! task). The gyro's filter chain is [`crate::filter::GyroFilter`], run by
//! the gyro body.

use super::arming::Arming;
use super::{input, mixed, Value};
use crate::math::Vec3;
use crate::mixer::MotorDemand;
use crate::pid::{AngleLoop, AxisCommand, RateController};
use rtpipe_body::{Body, Job, Stamped};

/// What the attitude loop hands the rate loop.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RateDemand {
    /// Body rate set-point, rad/s.
    pub rate: Vec3,
    /// Collective throttle in [0, 1].
    pub throttle: f64,
    /// Armed: the rate loop may spin the motors.
    pub armed: bool,
}

/// Below this throttle the rate loop holds its I terms at zero, as
/// Cleanflight's PID task does (no airmode on the ground).
pub(super) const I_RESET_THROTTLE: f64 = 0.15;

/// Arming, failsafe and the angle loop: the AHRS attitude and the radio's
/// set-point become a rate set-point (Cleanflight's PID task without its
/// rate loop).
pub struct AttitudeTask {
    pub(super) arming: Arming,
    pub(super) angle: AngleLoop,
}

impl Body<Value> for AttitudeTask {
    fn run(
        &mut self,
        job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let att = input(inputs, Value::attitude);
        let rx = input(inputs, Value::radio);
        let (Some(att), Some(rx)) = (att, rx) else {
            return Value::RateSetpoint(RateDemand::default());
        };
        let now = u64::try_from(job.read).unwrap_or(0);
        let Some(sp) = self.arming.setpoint(now, &att, &rx) else {
            return Value::RateSetpoint(RateDemand::default());
        };
        Value::RateSetpoint(RateDemand {
            rate: self.angle.rate_setpoint(&sp, &att.euler),
            throttle: sp.throttle.clamp(0.0, 1.0),
            armed: true,
        })
    }
}

/// The rate loop and the mixer: one step per new filtered gyro sample, with
/// dt from the samples' stamps, on the attitude loop's latest set-point.
pub struct RatePidTask {
    pub(super) rate: RateController,
    /// The gyro sample the loop last stepped on: (its stamp, ns; the output
    /// it gave).
    pub(super) last: Option<(u64, MotorDemand)>,
}

impl Body<Value> for RatePidTask {
    fn run(
        &mut self,
        _job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let gyro = input(inputs, Value::gyro).filter(|g| g.count > 0);
        let sp = input(inputs, Value::rate_setpoint);
        let (Some(gyro), Some(sp)) = (gyro, sp) else {
            return Value::Demand(MotorDemand::default());
        };
        if !sp.armed {
            self.rate.reset();
            self.last = None;
            return Value::Demand(MotorDemand::default());
        }
        // A job released with no new sample (a merged or a periodic one)
        // repeats its output: stepping D on the same measurement spikes it.
        if let Some((t, out)) = self.last {
            if t == gyro.last_t_ns {
                return Value::Demand(out);
            }
        }
        let dt = self
            .last
            .map_or(0.0, |(t, _)| gyro.last_t_ns.saturating_sub(t) as f64 * 1e-9);
        if sp.throttle < I_RESET_THROTTLE {
            self.rate.reset();
        }
        let [roll, pitch, yaw] = self.rate.update(sp.rate, gyro.latest, dt);
        let cmd = AxisCommand {
            roll,
            pitch,
            yaw,
            throttle: sp.throttle,
        };
        let (out, saturated) = mixed(&cmd);
        self.rate.set_saturated(saturated);
        self.last = Some((gyro.last_t_ns, out));
        Value::Demand(out)
    }
}
