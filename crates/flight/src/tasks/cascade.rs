//! The modern cascade's tasks, as Betaflight and PX4 fly it: the attitude
//! loop (periodic, on the AHRS estimate and the radio) hands a rate
//! set-point to the rate loop, which runs on every filtered gyro sample and
//! mixes (PX4's `mc_rate_control` over `RateControl`; Betaflight's PID
//! task). The gyro's filter chain is [`crate::filter::GyroFilter`], run by
//! the gyro body.

use super::arming::Arming;
use super::{input, mixed, PerSample, Value};
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
    /// The gyro sample the loop last stepped on.
    pub(super) last: PerSample,
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
            self.last.reset();
            return Value::Demand(MotorDemand::default());
        }
        // A job released with no new sample (a merged or a periodic one)
        // repeats its output.
        let dt = match self.last.step(gyro.last_t_ns) {
            Ok(dt) => dt,
            Err(repeat) => return Value::Demand(repeat),
        };
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
        self.last.record(gyro.last_t_ns, out);
        Value::Demand(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ahrs::GyroSnapshot;
    use crate::pid::{PidConfig, RateGains};
    use rtpipe_body::Stamp;

    fn stamped(value: Value, task: usize, at: u64) -> Option<Stamped<Value>> {
        let t = at as i64;
        Some(Stamped {
            value,
            stamp: Stamp {
                task,
                job: 0,
                read: t,
                publish: t,
            },
        })
    }

    /// A rate loop with D alone (and the D-term low-pass), at 8 kHz.
    fn d_only() -> RatePidTask {
        RatePidTask {
            rate: RateController::new(&d_only_config(), 8000.0).unwrap(),
            last: PerSample::default(),
        }
    }

    /// One job of the rate loop on gyro sample `k` (125 µs apart) at the
    /// rate `gyro` and the set-point `sp`: its motor commands.
    fn step(task: &mut RatePidTask, k: u64, gyro: Vec3, sp: Vec3) -> [f64; 4] {
        let t = 125_000 * (k + 1);
        let snap = GyroSnapshot {
            sum: gyro,
            count: k + 1,
            last_t_ns: t,
            latest: gyro,
        };
        let demand = RateDemand {
            rate: sp,
            throttle: 0.5,
            armed: true,
        };
        let inputs = [
            stamped(Value::Gyro(snap), 0, t),
            stamped(Value::RateSetpoint(demand), 1, t),
        ];
        let job = Job {
            task: 2,
            index: k,
            release: t as i64,
            read: t as i64,
        };
        match task.run(&job, &inputs, None) {
            Value::Demand(d) => d.motors,
            v => panic!("the rate loop gave {v:?}"),
        }
    }

    #[test]
    fn a_rate_setpoint_step_gives_no_d_kick_but_a_gyro_step_does() {
        let mut task = d_only();
        let level = [0.5; 4];
        assert_eq!(step(&mut task, 0, Vec3::ZERO, Vec3::ZERO), level);
        let sp = Vec3::new(3.0, -2.0, 1.0);
        for k in 1..50 {
            assert_eq!(step(&mut task, k, Vec3::ZERO, sp), level, "job {k}");
        }
        // The measured roll rate rises: D opposes it (roll down on the
        // left motors 3 and 4, up on the right).
        let m = step(&mut task, 50, Vec3::new(0.5, 0.0, 0.0), sp);
        assert!(m[0] > 0.5 && m[2] < 0.5, "{m:?}");
    }

    #[test]
    fn the_cascades_gyro_needs_the_presets_gyro_filter_table() {
        let mut p = crate::preset::Preset::builtin("racer5").unwrap();
        assert!(crate::tasks::body(crate::tasks::BodyKind::GyroFilter, 125_000, &p).is_ok());
        p.gyro_filter = None;
        let e = crate::tasks::body(crate::tasks::BodyKind::GyroFilter, 125_000, &p)
            .err()
            .unwrap();
        assert_eq!(e.field, "gyro_filter", "{e}");
        assert!(e.reason.contains("[gyro_filter]"), "{e}");
        // Cleanflight's gyro does not ask for it.
        assert!(crate::tasks::body(crate::tasks::BodyKind::Gyro, 1_000_000, &p).is_ok());
    }

    #[test]
    fn the_attitude_loop_stops_the_motors_until_armed() {
        let mut task = AttitudeTask {
            arming: Arming::new(crate::radio::FailsafeConfig {
                timeout_ms: 200,
                descent_throttle: 0.3,
                max_descent_s: 8.0,
            }),
            angle: AngleLoop::new(&d_only_config()),
        };
        let job = Job {
            task: 0,
            index: 0,
            release: 0,
            read: 0,
        };
        // No attitude or radio yet: a disarmed, zero set-point.
        assert_eq!(
            task.run(&job, &[None, None], None),
            Value::RateSetpoint(RateDemand::default())
        );
    }

    fn d_only_config() -> PidConfig {
        let g = RateGains {
            kp: 0.0,
            ki: 0.0,
            kd: 0.01,
            kff: 0.0,
            i_limit: 0.0,
        };
        PidConfig {
            roll: g,
            pitch: g,
            yaw: g,
            level_kp: 6.0,
            max_rate_dps: 300.0,
            yaw_max_rate_dps: 200.0,
            dterm_lpf_hz: 75.0,
            output_limit: 0.5,
        }
    }

    #[test]
    fn a_controller_steps_once_per_sample_and_repeats_its_output_between() {
        let mut gate = PerSample::default();
        assert_eq!(gate.step(1_000), Ok(0.0), "the first sample: dt 0");
        let out = MotorDemand {
            motors: [0.5; 4],
            armed: true,
        };
        gate.record(1_000, out);
        assert_eq!(gate.step(1_000), Err(out), "the same sample: repeat");
        assert_eq!(gate.step(126_000), Ok(125e-6));
        gate.reset();
        assert_eq!(gate.step(126_000), Ok(0.0));
    }
}
