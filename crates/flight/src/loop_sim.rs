//! Test support: fly the plant with the controller under IDEAL timing —
//! every task released exactly periodically at Cleanflight's Table V rates
//! (gyro and accel 1 ms, AHRS 5 ms, PID 2 ms, motor output 5 ms, radio
//! 10 ms) and every output visible to its consumers a fixed transport delay
//! after the release (latest-value registers). This proves the controller
//! flies at the paper's rates before it runs on the scheduler simulator.
//!
//! The task bodies here are also a worked example for an adapter:
//! [`LoopSim::gyro_task`], [`LoopSim::ahrs_task`], [`LoopSim::pid_task`],
//! [`LoopSim::pwm_task`], [`LoopSim::radio_task`].

use crate::ahrs::{AccelSample, Attitude, GyroAccumulator, GyroSnapshot, Mahony, DCM_KP_DEFAULT};
use crate::battery::Battery;
use crate::error::ConfigError;
use crate::filter::{Pt1Vec3, GYRO_LPF_HZ_DEFAULT};
use crate::imu::{Imu, ImuConfig};
use crate::math::{Euler, Vec3};
use crate::mixer::mix;
use crate::motor::through_dshot;
use crate::pid::{Controller, Setpoint};
use crate::plant::Plant;
use crate::preset::Preset;
use crate::radio::{
    ArmState, ArmingChecks, Autopilot, Failsafe, FailsafeAction, FailsafeConfig, Mission,
    RadioSample, VehicleState,
};

const MS: u64 = 1_000_000;

/// True if `t` is a release instant of a task with period `p` (p > 0).
// The workspace's rust-version (1.80) predates u64::is_multiple_of (1.87).
#[allow(clippy::manual_is_multiple_of)]
fn due(t: u64, p: u64) -> bool {
    t % p == 0
}

/// Task periods and the transport delay, ns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Gyro sampling period.
    pub gyro: u64,
    /// Accelerometer sampling period.
    pub accel: u64,
    /// AHRS period.
    pub ahrs: u64,
    /// PID (+ mixer) period.
    pub pid: u64,
    /// Motor output period.
    pub pwm: u64,
    /// Radio (+ autopilot) period.
    pub radio: u64,
    /// Delay from a release to its output being visible.
    pub delay: u64,
    /// Simulation tick; every period and the delay must be multiples.
    pub tick: u64,
}

impl Timing {
    /// Cleanflight's Table V rates with a `delay_ms` transport delay.
    pub fn table_v(delay_ms: u64) -> Self {
        Self {
            gyro: MS,
            accel: MS,
            ahrs: 5 * MS,
            pid: 2 * MS,
            pwm: 5 * MS,
            radio: 10 * MS,
            delay: delay_ms * MS,
            tick: MS,
        }
    }
}

/// Scenario options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopConfig {
    /// Task timing.
    pub timing: Timing,
    /// IMU model (noise on by default).
    pub imu: ImuConfig,
    /// Noise seed.
    pub seed: u64,
    /// Simulated duration, ns.
    pub duration_ns: u64,
    /// Mahony gain.
    pub ahrs_kp: f64,
    /// An angular impulse (body, N·m·s) applied at a time, ns.
    pub impulse: Option<(u64, Vec3)>,
    /// Radio silent in [from, to) ns.
    pub radio_loss: Option<(u64, u64)>,
    /// Record one trace point every this many ns.
    pub trace_every_ns: u64,
}

impl LoopConfig {
    /// Table V timing with a 2 ms delay, noise on, `secs` long.
    pub fn new(secs: f64, seed: u64) -> Self {
        Self {
            timing: Timing::table_v(2),
            imu: ImuConfig::default(),
            seed,
            duration_ns: (secs * 1e9) as u64,
            ahrs_kp: DCM_KP_DEFAULT,
            impulse: None,
            radio_loss: None,
            trace_every_ns: 2 * MS,
        }
    }
}

/// One recorded instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TracePoint {
    /// Time, ns.
    pub t_ns: u64,
    /// True position, m.
    pub pos: Vec3,
    /// True velocity, m/s.
    pub vel: Vec3,
    /// True attitude.
    pub euler: Euler,
    /// True body rate, rad/s.
    pub rate: Vec3,
    /// Estimated attitude (AHRS register).
    pub est: Euler,
    /// Set-point the controller is using (radio register).
    pub sp: Setpoint,
    /// Altitude-hold target of the mission, m.
    pub alt_target: Option<f64>,
    /// Armed (motor register).
    pub armed: bool,
    /// Resting on the ground.
    pub on_ground: bool,
    /// Crashed.
    pub crashed: bool,
    /// Motor commands in effect.
    pub motors: [f64; 4],
    /// Battery voltage, V.
    pub voltage: f64,
}

/// A latest-value register whose writes become visible `delay` later.
#[derive(Debug, Clone, Copy)]
struct Reg<T: Copy> {
    value: T,
    pending: [(u64, T); 8],
    len: usize,
}

impl<T: Copy> Reg<T> {
    fn new(v: T) -> Self {
        Self {
            value: v,
            pending: [(0, v); 8],
            len: 0,
        }
    }
    fn write(&mut self, visible_at: u64, v: T) {
        // Bounded: a period shorter than delay/8 would overflow, which
        // Timing::validate rules out; drop the oldest defensively.
        if self.len == self.pending.len() {
            self.pending.copy_within(1.., 0);
            self.len -= 1;
        }
        self.pending[self.len] = (visible_at, v);
        self.len += 1;
    }
    /// Publish every pending write visible at `now`; true if any.
    fn poll(&mut self, now: u64) -> bool {
        let n = self.pending[..self.len]
            .iter()
            .take_while(|(t, _)| *t <= now)
            .count();
        if n == 0 {
            return false;
        }
        self.value = self.pending[n - 1].1;
        self.pending.copy_within(n..self.len, 0);
        self.len -= n;
        true
    }
}

/// What the PID task publishes for the motor task (and the motor task for
/// the ESCs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotorDemand {
    /// Motor commands in [0, 1], Betaflight order.
    pub motors: [f64; 4],
    /// Armed: motors spin.
    pub armed: bool,
}

/// The whole closed loop.
pub struct LoopSim {
    cfg: LoopConfig,
    /// The plant (public for scenario tweaks).
    pub plant: Plant,
    imu: Imu,
    gyro_lpf: Pt1Vec3,
    gyro_acc: GyroAccumulator,
    ahrs: Mahony,
    ctrl: Controller,
    arm: ArmState,
    checks: ArmingChecks,
    failsafe: Failsafe,
    autopilot: Autopilot,
    mission: Mission,
    battery: Battery,
    last_pid_ns: Option<u64>,
    r_gyro: Reg<GyroSnapshot>,
    r_accel: Reg<AccelSample>,
    r_att: Reg<Attitude>,
    r_radio: Reg<RadioSample>,
    r_mix: Reg<MotorDemand>,
    r_motor: Reg<MotorDemand>,
    /// The recorded trajectory.
    pub trace: Vec<TracePoint>,
}

impl LoopSim {
    /// Build the loop for `preset` flying `mission`.
    pub fn new(preset: &Preset, mission: Mission, cfg: LoopConfig) -> Result<Self, ConfigError> {
        let t = cfg.timing;
        for (n, p) in [
            ("gyro", t.gyro),
            ("accel", t.accel),
            ("ahrs", t.ahrs),
            ("pid", t.pid),
            ("pwm", t.pwm),
            ("radio", t.radio),
        ] {
            if t.tick == 0 || p == 0 || !due(p, t.tick) || !due(t.delay, t.tick) || t.delay / p >= 7
            {
                return Err(ConfigError::new(
                    format!("timing.{n}"),
                    "periods and delay must be multiples of the tick, delay < 7 periods",
                ));
            }
        }
        let pid_hz = 1e9 / t.pid as f64;
        let pp = preset.plant_params();
        let hover = pp.hover_cmd();
        let zero_sample = RadioSample::default();
        let n_trace = (cfg.duration_ns / cfg.trace_every_ns.max(1)) as usize + 1;
        Ok(Self {
            cfg,
            plant: Plant::new(pp)?,
            imu: Imu::new(cfg.imu, cfg.seed),
            gyro_lpf: Pt1Vec3::new(GYRO_LPF_HZ_DEFAULT, 1e9 / t.gyro as f64)?,
            gyro_acc: GyroAccumulator::new(),
            ahrs: Mahony::new(cfg.ahrs_kp, 0.0),
            ctrl: Controller::new(preset.pid, pid_hz)?,
            arm: ArmState::default(),
            checks: ArmingChecks::default(),
            failsafe: Failsafe::new(FailsafeConfig {
                timeout_ms: 200,
                descent_throttle: 0.9 * hover,
                max_descent_s: 20.0,
            }),
            autopilot: Autopilot::new(preset.autopilot, hover)?,
            mission,
            battery: Battery::new(preset.battery)?,
            last_pid_ns: None,
            r_gyro: Reg::new(GyroSnapshot::default()),
            r_accel: Reg::new(AccelSample::default()),
            r_att: Reg::new(Attitude::default()),
            r_radio: Reg::new(zero_sample),
            r_mix: Reg::new(MotorDemand::default()),
            r_motor: Reg::new(MotorDemand::default()),
            trace: Vec::with_capacity(n_trace),
        })
    }

    /// Gyro task: sample, low-pass (PT1 at Betaflight's 250 Hz), accumulate.
    pub fn gyro_task(&mut self, t: u64) -> GyroSnapshot {
        let truth = self.plant.truth();
        let r = self.imu.read_gyro(t, truth.rate);
        let filtered = self.gyro_lpf.apply(r.value);
        self.gyro_acc.push(filtered, r.t_ns);
        self.gyro_acc.snapshot()
    }

    /// Accelerometer task.
    pub fn accel_task(&mut self, t: u64) -> AccelSample {
        let truth = self.plant.truth();
        let r = self.imu.read_accel(t, truth.specific_force);
        AccelSample {
            specific_force: r.value,
            t_ns: r.t_ns,
        }
    }

    /// AHRS task: Mahony from the latest gyro sums and accel sample.
    pub fn ahrs_task(&mut self) -> Attitude {
        self.ahrs.update(self.r_gyro.value, self.r_accel.value)
    }

    /// Radio task: the mission's intent through the autopilot (true
    /// position/velocity, as from motion capture).
    pub fn radio_task(&mut self, t: u64) -> RadioSample {
        let truth = self.plant.truth();
        let intent = self.mission.intent_at(t);
        let st = VehicleState {
            pos: truth.pos,
            vel: truth.vel,
            euler: truth.euler,
            on_ground: truth.on_ground,
        };
        RadioSample {
            t_ns: t,
            cmd: self.autopilot.update(t, &intent, &st),
        }
    }

    /// PID task: arming, failsafe, angle/rate PID, mixer.
    pub fn pid_task(&mut self, t: u64) -> MotorDemand {
        let rx = self.r_radio.value;
        let att = self.r_att.value;
        let gyro = self.r_gyro.value.latest;
        let truth = self.plant.truth();
        let action = self.failsafe.update(t, rx.t_ns, truth.on_ground);
        let check = self
            .checks
            .check(&rx.cmd, att.q.tilt(), truth.crashed, self.failsafe.active());
        self.arm.update(&rx.cmd, check);
        let sp = match action {
            FailsafeAction::PassThrough => rx.cmd.setpoint(),
            FailsafeAction::Override(sp) => sp,
            FailsafeAction::Disarm => {
                self.arm.disarm();
                Setpoint::default()
            }
        };
        let dt = self.last_pid_ns.map_or(0.0, |p| (t - p) as f64 * 1e-9);
        self.last_pid_ns = Some(t);
        if !self.arm.armed || truth.crashed {
            self.ctrl.reset();
            return MotorDemand::default();
        }
        if sp.throttle < 0.15 {
            // Betaflight resets the I term at low throttle (no airmode on the ground).
            self.ctrl.reset();
        }
        let cmd = self.ctrl.update(&sp, &att.euler, gyro, dt);
        let m = mix(&cmd);
        self.ctrl.set_saturated(m.saturated);
        MotorDemand {
            motors: m.motors,
            armed: true,
        }
    }

    /// Motor-output task: encode DShot600 frames; the ESC decodes them.
    pub fn pwm_task(&mut self) -> MotorDemand {
        let d = self.r_mix.value;
        MotorDemand {
            motors: through_dshot(d.motors, d.armed),
            armed: d.armed,
        }
    }
}

impl LoopSim {
    fn poll_registers(&mut self, t: u64) {
        self.r_gyro.poll(t);
        self.r_accel.poll(t);
        self.r_att.poll(t);
        self.r_radio.poll(t);
        self.r_mix.poll(t);
        if self.r_motor.poll(t) {
            let m = self.r_motor.value;
            self.plant.set_motor_commands(m.motors, m.armed);
        }
    }

    fn release_tasks(&mut self, t: u64) {
        let tm = self.cfg.timing;
        let vis = t + tm.delay;
        let lost = self
            .cfg
            .radio_loss
            .is_some_and(|(a, b)| (a..b).contains(&t));
        if due(t, tm.radio) && !lost {
            let v = self.radio_task(t);
            self.r_radio.write(vis, v);
            self.poll_registers(t);
        }
        if due(t, tm.gyro) {
            let v = self.gyro_task(t);
            self.r_gyro.write(vis, v);
            self.poll_registers(t);
        }
        if due(t, tm.accel) {
            let v = self.accel_task(t);
            self.r_accel.write(vis, v);
            self.poll_registers(t);
        }
        if due(t, tm.ahrs) {
            let v = self.ahrs_task();
            self.r_att.write(vis, v);
            self.poll_registers(t);
        }
        if due(t, tm.pid) {
            let v = self.pid_task(t);
            self.r_mix.write(vis, v);
            self.poll_registers(t);
        }
        if due(t, tm.pwm) {
            let v = self.pwm_task();
            self.r_motor.write(vis, v);
            self.poll_registers(t);
        }
    }

    fn record(&mut self, t: u64) {
        let truth = self.plant.truth();
        self.trace.push(TracePoint {
            t_ns: t,
            pos: truth.pos,
            vel: truth.vel,
            euler: truth.euler,
            rate: truth.rate,
            est: self.r_att.value.euler,
            sp: self.r_radio.value.cmd.setpoint(),
            alt_target: self.mission.intent_at(t).altitude_m,
            armed: self.r_motor.value.armed,
            on_ground: truth.on_ground,
            crashed: truth.crashed,
            motors: self.r_motor.value.motors,
            voltage: self.battery.voltage(),
        });
    }

    /// Run one tick starting at `t`: publish, release, integrate.
    pub fn tick(&mut self, t: u64) {
        self.poll_registers(t);
        if let Some((ti, j)) = self.cfg.impulse {
            if ti == t {
                self.plant.apply_torque_impulse(j);
            }
        }
        self.release_tasks(t);
        if due(t, self.cfg.trace_every_ns.max(1)) {
            self.record(t);
        }
        let next = t + self.cfg.timing.tick;
        self.plant.advance_to(next);
        self.battery
            .step(self.plant.shaft_power(), self.cfg.timing.tick as f64 * 1e-9);
    }

    /// Run the whole scenario.
    pub fn run(&mut self) {
        let mut t = 0;
        while t < self.cfg.duration_ns {
            self.tick(t);
            t += self.cfg.timing.tick;
        }
    }
}

/// Build and run a scenario; returns the trace.
pub fn fly(
    preset: &Preset,
    mission: Mission,
    cfg: LoopConfig,
) -> Result<Vec<TracePoint>, ConfigError> {
    let mut sim = LoopSim::new(preset, mission, cfg)?;
    sim.run();
    Ok(sim.trace)
}

/// Metrics over a trace.
pub mod metrics {
    use super::TracePoint;

    fn window(tr: &[TracePoint], t0: f64, t1: f64) -> impl Iterator<Item = &TracePoint> {
        tr.iter().filter(move |p| {
            let t = p.t_ns as f64 * 1e-9;
            t >= t0 && t < t1
        })
    }

    fn rms(it: impl Iterator<Item = f64>) -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for e in it {
            s += e * e;
            n += 1;
        }
        if n == 0 {
            f64::NAN
        } else {
            (s / n as f64).sqrt()
        }
    }

    /// RMS of true altitude minus the mission's altitude target, m.
    pub fn altitude_rms(tr: &[TracePoint], t0: f64, t1: f64) -> f64 {
        rms(window(tr, t0, t1).map(|p| p.pos.z - p.alt_target.unwrap_or(f64::NAN)))
    }

    /// RMS of the true roll/pitch error to the set-point in use, deg.
    pub fn attitude_rms_deg(tr: &[TracePoint], t0: f64, t1: f64) -> f64 {
        rms(window(tr, t0, t1).map(|p| {
            let er = p.euler.roll - p.sp.roll;
            let ep = p.euler.pitch - p.sp.pitch;
            (er * er + ep * ep).sqrt().to_degrees()
        }))
    }

    /// Largest horizontal distance from the position at `t0`, m.
    pub fn max_drift(tr: &[TracePoint], t0: f64, t1: f64) -> f64 {
        let mut w = window(tr, t0, t1);
        let Some(first) = w.next() else {
            return f64::NAN;
        };
        let p0 = first.pos;
        w.map(|p| ((p.pos.x - p0.x).powi(2) + (p.pos.y - p0.y).powi(2)).sqrt())
            .fold(0.0, f64::max)
    }

    /// Step response of a signal from `from` to `to` starting at `t_step`,
    /// judged until `t_end`.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub struct StepResponse {
        /// Peak overshoot as a fraction of the step.
        pub overshoot: f64,
        /// Time from the step until the signal last entered the band
        /// |x − to| ≤ band·|to − from| and stayed there until `t_end`, s.
        pub settling_s: f64,
        /// 10 % → 90 % rise time, s.
        pub rise_s: f64,
    }

    /// Measure a step of `signal` (e.g. true roll in degrees).
    pub fn step_response(
        tr: &[TracePoint],
        signal: impl Fn(&TracePoint) -> f64,
        t_step: f64,
        t_end: f64,
        from: f64,
        to: f64,
        band: f64,
    ) -> StepResponse {
        let span = to - from;
        let (mut peak, mut last_out, mut t10, mut t90) = (0.0f64, t_step, None, None);
        for p in window(tr, t_step, t_end) {
            let t = p.t_ns as f64 * 1e-9;
            let x = (signal(p) - from) / span;
            peak = peak.max(x);
            if t10.is_none() && x >= 0.1 {
                t10 = Some(t);
            }
            if t90.is_none() && x >= 0.9 {
                t90 = Some(t);
            }
            if (x - 1.0).abs() > band {
                last_out = t;
            }
        }
        let rise = match (t10, t90) {
            (Some(a), Some(b)) => b - a,
            _ => f64::NAN,
        };
        StepResponse {
            overshoot: (peak - 1.0).max(0.0),
            settling_s: last_out - t_step,
            rise_s: rise,
        }
    }
}
