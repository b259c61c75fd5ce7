//! Cleanflight's tasks as task bodies on rtpipe's seam (`rtpipe-body`), and
//! the world they fly in.
//!
//! Each task of Fig. 11 (gyro, accelerometer, AHRS, PID, PWM, radio) and
//! each of the four housekeeping tasks is a [`Body`]: a thin adapter that
//! takes its job's inputs (the latest value of each producer), calls the
//! pure algorithms of this crate and returns its output, as PX4 separates a
//! rate controller from its module glue. Bodies never read a clock: time
//! comes from the job (its read instant) and from the samples' stamps.
//!
//! [`Cosim`] is the [`Environment`]: the quadrotor plant with its IMU and
//! battery, and the pilot (a mission, flown through an autopilot the way an
//! on-board companion would, at the radio task's rate). Executors call it at
//! the instants they choose: a sensor job samples the world at its read
//! instant, the PWM job's output reaches the motors at its publish instant.
//! The plant advances to each such instant first, so the simulator's
//! schedule, not a fixed loop, decides what the controller sees and when.

use crate::ahrs::{AccelSample, Attitude, GyroAccumulator, Mahony, DCM_KP_DEFAULT};
use crate::battery::{Battery, BatteryAlert, Housekeeping, HousekeepingConfig};
use crate::error::ConfigError;
use crate::filter::{GyroFilter, Pt1Vec3, GYRO_LPF_HZ_DEFAULT};
use crate::imu::{Imu, ImuConfig, Reading};
use crate::math::{Euler, Vec3};
use crate::mixer::{mix, MotorDemand};
use crate::motor::through_dshot;
use crate::pid::{AngleLoop, AxisCommand, Controller, RateController, Setpoint};
use crate::plant::Plant;
use crate::preset::Preset;
use crate::radio::{Autopilot, FailsafeConfig, Mission, RadioSample, VehicleState};
use crate::trace::TracePoint;
use crate::wind::Wind;
use rtpipe_body::{Body, Environment, Job, Nanos, Stamped};

mod arming;
mod cascade;
mod per_sample;

pub(crate) use per_sample::PerSample;

use arming::Arming;
pub use cascade::{AttitudeTask, RateDemand, RatePidTask};

/// What flows between the flight tasks: one register value type for the
/// whole pipeline (`Copy`, so registers are fixed-size slots).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Value {
    /// Nothing yet (a task whose inputs have not arrived).
    #[default]
    Nothing,
    /// A raw IMU reading: the device sample of the gyro and accelerometer tasks.
    Imu(Reading),
    /// The gyro task's running sums (the AHRS averages the interval).
    Gyro(crate::ahrs::GyroSnapshot),
    /// The accelerometer task's sample.
    Accel(AccelSample),
    /// The AHRS estimate.
    Attitude(Attitude),
    /// A radio frame.
    Radio(RadioSample),
    /// The PID task's mixed motor demand.
    Demand(MotorDemand),
    /// What the PWM task sent to the ESCs.
    Motors(MotorDemand),
    /// A housekeeping figure: battery volts, amps, or load percent.
    Scalar(f64),
    /// The low-battery alert level.
    Alert(BatteryAlert),
    /// The attitude loop's rate set-point for the rate loop.
    RateSetpoint(RateDemand),
}

/// Typed views of a [`Value`], for picking a task's inputs by kind.
impl Value {
    /// The gyro task's running sums.
    pub fn gyro(self) -> Option<crate::ahrs::GyroSnapshot> {
        match self {
            Value::Gyro(g) => Some(g),
            _ => None,
        }
    }

    /// The accelerometer task's sample.
    pub fn accel(self) -> Option<AccelSample> {
        match self {
            Value::Accel(a) => Some(a),
            _ => None,
        }
    }

    /// The AHRS estimate.
    pub fn attitude(self) -> Option<Attitude> {
        match self {
            Value::Attitude(a) => Some(a),
            _ => None,
        }
    }

    /// A radio frame.
    pub fn radio(self) -> Option<RadioSample> {
        match self {
            Value::Radio(r) => Some(r),
            _ => None,
        }
    }

    /// The PID task's mixed motor demand.
    pub fn demand(self) -> Option<MotorDemand> {
        match self {
            Value::Demand(d) => Some(d),
            _ => None,
        }
    }

    /// The attitude loop's rate set-point.
    pub fn rate_setpoint(self) -> Option<RateDemand> {
        match self {
            Value::RateSetpoint(r) => Some(r),
            _ => None,
        }
    }

    /// A housekeeping figure.
    pub fn scalar(self) -> Option<f64> {
        match self {
            Value::Scalar(x) => Some(x),
            _ => None,
        }
    }
}

/// The job a task does, named by the spec's `body = "..."`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Samples the gyro, low-pass filters it, accumulates sums.
    Gyro,
    /// Samples the accelerometer.
    Accel,
    /// Mahony attitude estimate from the gyro sums and the accelerometer.
    Ahrs,
    /// Reads the radio receiver.
    Radio,
    /// Arming, failsafe, angle/rate PID and the mixer.
    Pid,
    /// Motor output (DShot600 frames to the ESCs).
    Pwm,
    /// Housekeeping: the system load figure.
    Load,
    /// Housekeeping: battery voltage.
    Vbat,
    /// Housekeeping: battery current.
    Current,
    /// Housekeeping: low-battery alert.
    Alert,
    /// Samples the gyro at its data-ready rate through the preset's
    /// `[gyro_filter]` chain (low-pass, notch, low-pass), accumulates sums.
    GyroFilter,
    /// Arming, failsafe and the angle loop: publishes rate set-points.
    Attitude,
    /// The rate PID on the filtered gyro, and the mixer.
    RatePid,
}

impl BodyKind {
    /// Reads the vehicle or its battery when it starts, so the world must be
    /// integrated to that instant (the other bodies' reads take only the
    /// schedule's registers).
    fn observes_world(self) -> bool {
        matches!(
            self,
            BodyKind::Gyro
                | BodyKind::GyroFilter
                | BodyKind::Accel
                | BodyKind::Radio
                | BodyKind::Vbat
                | BodyKind::Current
        )
    }

    /// The six tasks of Fig. 11 a flight controller cannot fly without.
    pub const CRITICAL: [BodyKind; 6] = [
        BodyKind::Gyro,
        BodyKind::Accel,
        BodyKind::Ahrs,
        BodyKind::Radio,
        BodyKind::Pid,
        BodyKind::Pwm,
    ];

    /// The tasks of the modern cascade (Betaflight's, PX4's): the gyro at
    /// its data-ready rate with its filters, the attitude loop handing rate
    /// set-points to the rate PID and mixer, and the motor output.
    pub const CASCADE: [BodyKind; 7] = [
        BodyKind::GyroFilter,
        BodyKind::Accel,
        BodyKind::Ahrs,
        BodyKind::Radio,
        BodyKind::Attitude,
        BodyKind::RatePid,
        BodyKind::Pwm,
    ];

    /// The complete flight controllers: a spec that has every task of one
    /// of them flies ([`BodyKind::CRITICAL`] first).
    pub const STRUCTURES: [&'static [BodyKind]; 2] = [&BodyKind::CRITICAL, &BodyKind::CASCADE];

    /// Every role, in the order of [`BodyKind::name`]'s list.
    pub const ALL: [BodyKind; 13] = [
        BodyKind::Gyro,
        BodyKind::Accel,
        BodyKind::Ahrs,
        BodyKind::Radio,
        BodyKind::Pid,
        BodyKind::Pwm,
        BodyKind::Load,
        BodyKind::Vbat,
        BodyKind::Current,
        BodyKind::Alert,
        BodyKind::GyroFilter,
        BodyKind::Attitude,
        BodyKind::RatePid,
    ];

    /// The name a spec uses: `rtpipe_model::BODY_NAMES`, the list the
    /// spec's validation checks, holds them in [`BodyKind::ALL`]'s order.
    pub fn name(self) -> &'static str {
        rtpipe_model::BODY_NAMES[self as usize]
    }

    /// Which of the world's delay lines ([`CosimConfig::sense_delay_ns`])
    /// this role's samples pass: the gyro (either structure's), the
    /// accelerometer, the radio; `None` for the others.
    pub fn delay_line(self) -> Option<usize> {
        match self {
            BodyKind::Gyro | BodyKind::GyroFilter => Some(0),
            BodyKind::Accel => Some(1),
            BodyKind::Radio => Some(2),
            _ => None,
        }
    }

    /// The role a spec names, if any.
    pub fn parse(name: &str) -> Option<BodyKind> {
        BodyKind::ALL.into_iter().find(|r| r.name() == name)
    }

    /// The inputs this body takes, each as the roles that can give it
    /// (any one will do): without one of them among its task's `reads`, the
    /// input is always missing (a PID without the radio never arms: zero
    /// motor demand).
    pub fn needs(self) -> &'static [&'static [BodyKind]] {
        const GYRO: &[BodyKind] = &[BodyKind::Gyro, BodyKind::GyroFilter];
        match self {
            BodyKind::Ahrs => &[GYRO, &[BodyKind::Accel]],
            BodyKind::Pid => &[&[BodyKind::Ahrs], &[BodyKind::Radio]],
            BodyKind::Attitude => &[&[BodyKind::Ahrs], &[BodyKind::Radio]],
            BodyKind::RatePid => &[GYRO, &[BodyKind::Attitude]],
            BodyKind::Pwm => &[&[BodyKind::Pid, BodyKind::RatePid]],
            BodyKind::Alert => &[&[BodyKind::Vbat]],
            _ => &[],
        }
    }

    /// The names a spec may use, for error messages.
    pub fn names() -> String {
        let v: Vec<&str> = BodyKind::ALL.iter().map(|r| r.name()).collect();
        v.join(", ")
    }
}

/// The value of the first input of a kind, if it has arrived.
fn input<T>(inputs: &[Option<Stamped<Value>>], pick: impl Fn(Value) -> Option<T>) -> Option<T> {
    inputs.iter().flatten().find_map(|s| pick(s.value))
}

/// Samples the gyro, filters it (PT1 at Betaflight's default cut-off) and
/// publishes running sums and a count: a register holds only the latest
/// value, so the AHRS differences two snapshots to average every sample of
/// its interval.
pub struct GyroTask {
    filter: GyroFilters,
    acc: GyroAccumulator,
}

/// The gyro body's filters: Cleanflight's one PT1, or the cascade's chain.
enum GyroFilters {
    Pt1(Pt1Vec3),
    Chain(Box<GyroFilter>),
}

impl Body<Value> for GyroTask {
    fn run(
        &mut self,
        _job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        device: Option<Value>,
    ) -> Value {
        if let Some(Value::Imu(r)) = device {
            let rate = match &mut self.filter {
                GyroFilters::Pt1(f) => f.apply(r.value),
                GyroFilters::Chain(f) => f.apply(r.value),
            };
            self.acc.push(rate, r.t_ns);
        }
        Value::Gyro(self.acc.snapshot())
    }
}

/// Samples the accelerometer.
pub struct AccelTask;

impl Body<Value> for AccelTask {
    fn run(
        &mut self,
        _job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        device: Option<Value>,
    ) -> Value {
        match device {
            Some(Value::Imu(r)) => Value::Accel(AccelSample {
                specific_force: r.value,
                t_ns: r.t_ns,
            }),
            _ => Value::Nothing,
        }
    }
}

/// Mahony AHRS over the gyro sums and the latest accelerometer sample.
pub struct AhrsTask {
    mahony: Mahony,
}

impl Body<Value> for AhrsTask {
    fn run(
        &mut self,
        _job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let gyro = input(inputs, Value::gyro);
        let accel = input(inputs, Value::accel);
        match (gyro, accel) {
            (Some(g), Some(a)) => Value::Attitude(self.mahony.update(g, a)),
            _ => Value::Nothing,
        }
    }
}

/// Reads the radio receiver; with no new frame it republishes the last one
/// (whose old timestamp lets the PID task's failsafe notice the loss).
#[derive(Default)]
pub struct RadioTask {
    last: Option<RadioSample>,
}

impl Body<Value> for RadioTask {
    fn run(
        &mut self,
        _job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        device: Option<Value>,
    ) -> Value {
        if let Some(Value::Radio(r)) = device {
            self.last = Some(r);
        }
        self.last.map_or(Value::Nothing, Value::Radio)
    }
}

/// Arming, failsafe, the angle/rate controller and the mixer (Cleanflight's
/// PID task). It sees only its inputs: the attitude estimate (with the mean
/// gyro rate) and the radio frame.
pub struct PidTask {
    ctrl: Controller,
    arming: Arming,
    last: PerSample,
}

/// The mixer's motor demand for `cmd`, armed, and whether it saturated
/// (for the rate loop's anti-windup).
fn mixed(cmd: &AxisCommand) -> (MotorDemand, bool) {
    let m = mix(cmd);
    let out = MotorDemand {
        motors: m.motors,
        armed: true,
    };
    (out, m.saturated)
}

impl Body<Value> for PidTask {
    /// The controller steps once per new attitude sample ([`PerSample`]),
    /// with dt from the samples' timestamps: the PID task runs faster than
    /// the AHRS.
    fn run(
        &mut self,
        job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let att = input(inputs, Value::attitude);
        let rx = input(inputs, Value::radio);
        let (Some(att), Some(rx)) = (att, rx) else {
            return Value::Demand(MotorDemand::default());
        };
        let now = u64::try_from(job.read).unwrap_or(0);
        let Some(sp) = self.arming.setpoint(now, &att, &rx) else {
            self.ctrl.reset();
            self.last.reset();
            return Value::Demand(MotorDemand::default());
        };
        let dt = match self.last.step(att.t_ns) {
            Ok(dt) => dt,
            Err(repeat) => return Value::Demand(repeat),
        };
        if sp.throttle < cascade::I_RESET_THROTTLE {
            // Betaflight resets the I term at low throttle (no airmode on the ground).
            self.ctrl.reset();
        }
        let cmd = self.ctrl.update(&sp, &att.euler, att.rate, dt);
        let (out, saturated) = mixed(&cmd);
        self.ctrl.set_saturated(saturated);
        self.last.record(att.t_ns, out);
        Value::Demand(out)
    }
}

/// Motor output: DShot600 frames to the ESCs, which decode them (the round
/// trip quantises the command to the protocol's 11 bits).
pub struct PwmTask;

impl Body<Value> for PwmTask {
    fn run(
        &mut self,
        _job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let d = input(inputs, Value::demand).unwrap_or_default();
        let out = MotorDemand {
            motors: through_dshot(d.motors, d.armed),
            armed: d.armed,
        };
        Value::Motors(out)
    }
}

/// Housekeeping: the system load figure. A background task runs only in
/// slack, so how long its job waited for the CPU (read − release) against
/// its period is the load it saw.
pub struct LoadTask {
    period: Nanos,
    hk: Housekeeping,
}

impl Body<Value> for LoadTask {
    fn run(
        &mut self,
        job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        let waited = (job.read - job.release) as f64 / self.period as f64;
        self.hk.system(100.0 * waited);
        Value::Scalar(self.hk.load_percent)
    }
}

/// Housekeeping: filters the battery voltage.
pub struct VbatTask {
    hk: Housekeeping,
}

impl Body<Value> for VbatTask {
    fn run(
        &mut self,
        _job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        device: Option<Value>,
    ) -> Value {
        if let Some(Value::Scalar(v)) = device {
            self.hk.battery_voltage(v);
        }
        Value::Scalar(self.hk.voltage)
    }
}

/// Housekeeping: battery current and the charge drawn.
pub struct CurrentTask {
    hk: Housekeeping,
    last_read: Option<Nanos>,
}

impl Body<Value> for CurrentTask {
    fn run(
        &mut self,
        job: &Job,
        _inputs: &[Option<Stamped<Value>>],
        device: Option<Value>,
    ) -> Value {
        let dt = self.last_read.map_or(0.0, |p| (job.read - p) as f64 * 1e-9);
        self.last_read = Some(job.read);
        if let Some(Value::Scalar(a)) = device {
            self.hk.battery_current(a, dt);
        }
        Value::Scalar(self.hk.current)
    }
}

/// Housekeeping: the low-battery alert, from the voltage task's output.
pub struct AlertTask {
    hk: Housekeeping,
}

impl Body<Value> for AlertTask {
    fn run(
        &mut self,
        _job: &Job,
        inputs: &[Option<Stamped<Value>>],
        _device: Option<Value>,
    ) -> Value {
        if let Some(v) = input(inputs, Value::scalar) {
            self.hk.voltage = v;
        }
        Value::Alert(self.hk.battery_alerts())
    }
}

/// Builds the body of a task of `role` with period `period` (ns) for the
/// vehicle `preset`.
pub fn body(
    role: BodyKind,
    period: Nanos,
    preset: &Preset,
) -> Result<Box<dyn Body<Value>>, ConfigError> {
    if period <= 0 {
        return Err(ConfigError::new(
            "period",
            "a flight task needs a positive period",
        ));
    }
    let hz = 1e9 / period as f64;
    let hk = || Housekeeping::new(HousekeepingConfig::cleanflight(preset.battery.cells));
    Ok(match role {
        BodyKind::Gyro => Box::new(GyroTask {
            filter: GyroFilters::Pt1(Pt1Vec3::new(GYRO_LPF_HZ_DEFAULT.min(0.45 * hz), hz)?),
            acc: GyroAccumulator::new(),
        }),
        BodyKind::GyroFilter => Box::new(GyroTask {
            filter: GyroFilters::Chain(Box::new(GyroFilter::new(gyro_filter(preset)?, hz)?)),
            acc: GyroAccumulator::new(),
        }),
        BodyKind::Attitude => Box::new(AttitudeTask {
            arming: Arming::new(failsafe_config(preset)),
            angle: AngleLoop::new(&preset.pid),
        }),
        BodyKind::RatePid => Box::new(RatePidTask {
            rate: RateController::new(&preset.pid, hz)?,
            last: PerSample::default(),
        }),
        BodyKind::Accel => Box::new(AccelTask),
        BodyKind::Ahrs => Box::new(AhrsTask {
            mahony: Mahony::new(DCM_KP_DEFAULT, 0.0),
        }),
        BodyKind::Radio => Box::new(RadioTask::default()),
        BodyKind::Pid => Box::new(PidTask {
            ctrl: Controller::new(preset.pid, hz)?,
            arming: Arming::new(failsafe_config(preset)),
            last: PerSample::default(),
        }),
        BodyKind::Pwm => Box::new(PwmTask),
        BodyKind::Load => Box::new(LoadTask { period, hk: hk()? }),
        BodyKind::Vbat => Box::new(VbatTask { hk: hk()? }),
        BodyKind::Current => Box::new(CurrentTask {
            hk: hk()?,
            last_read: None,
        }),
        BodyKind::Alert => Box::new(AlertTask { hk: hk()? }),
    })
}

/// The preset's `[gyro_filter]` table, which the cascade's gyro needs.
fn gyro_filter(preset: &Preset) -> Result<&crate::filter::GyroFilterConfig, ConfigError> {
    preset.gyro_filter.as_ref().ok_or_else(|| {
        ConfigError::new(
            "gyro_filter",
            "the preset has no [gyro_filter] table (lpf1_hz, lpf2_hz, notch_hz, notch_cutoff_hz), which the gyro_filter body needs",
        )
    })
}

/// Radio loss for 200 ms starts a descent a little below hover throttle;
/// without a landing detector it disarms after 8 s.
fn failsafe_config(preset: &Preset) -> FailsafeConfig {
    FailsafeConfig {
        timeout_ms: 200,
        descent_throttle: 0.9 * preset.plant_params().hover_cmd(),
        max_descent_s: 8.0,
    }
}

/// Scenario options of a co-simulated flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CosimConfig {
    /// IMU model (noise on by default).
    pub imu: ImuConfig,
    /// Seeds the IMU noise.
    pub seed: u64,
    /// An angular impulse (body, N·m·s) at a time (ns): a disturbance.
    pub impulse: Option<(u64, Vec3)>,
    /// The radio link is down in [from, to) ns.
    pub radio_loss: Option<(u64, u64)>,
    /// Record the state every this many ns.
    pub trace_every_ns: u64,
    /// A pure delay (ns) on what the gyro, accelerometer and radio tasks
    /// sample, in that order: the sample a job gets at t is the one the
    /// world produced at the latest sensing instant at or before t − delay
    /// (nothing before the first such one). It lengthens the chains that
    /// start there by exactly the delay.
    pub sense_delay_ns: [u64; 3],
}

impl CosimConfig {
    /// Noise on, no disturbance, a trace point every 2 ms.
    pub fn new(seed: u64) -> CosimConfig {
        CosimConfig {
            imu: ImuConfig::default(),
            seed,
            impulse: None,
            radio_loss: None,
            trace_every_ns: 2_000_000,
            sense_delay_ns: [0; 3],
        }
    }
}

/// What the world saw of the flight controller's outputs, for the trace.
#[derive(Debug, Clone, Copy, Default)]
struct Seen {
    est: Euler,
    sp: Setpoint,
    motors: MotorDemand,
}

/// The world of a co-simulated flight: plant, IMU, battery and the pilot.
pub struct Cosim {
    cfg: CosimConfig,
    plant: Plant,
    imu: Imu,
    battery: Battery,
    mission: Mission,
    autopilot: Autopilot,
    kinds: Vec<Option<BodyKind>>,
    now: u64,
    next_trace: u64,
    /// Time since the battery last stepped, s (it steps every millisecond:
    /// its dynamics are slow and its model is costly per call).
    battery_dt: f64,
    seen: Seen,
    /// The delay lines of the gyro, accelerometer and radio samples.
    delayed: [DelayLine; 3],
    /// Where the world's time is published for a progress display.
    progress: Option<std::sync::Arc<std::sync::atomic::AtomicU64>>,
    /// First time each battery alert level was raised, ns.
    pub alerts: Vec<(u64, BatteryAlert)>,
    /// The recorded trajectory, one point every `trace_every_ns` (when
    /// `keep_trace`; the flight's quality streams into `assessor` anyway).
    pub trace: Vec<TracePoint>,
    /// Keep every trace point (plots, logs); off, memory does not grow with
    /// the flight.
    pub keep_trace: bool,
    /// The flight's quality, point by point.
    pub assessor: crate::quality::Assessor,
    /// The mission's turbulence, if any, and the next instant it steps at.
    wind: Option<(Wind, u64)>,
}

/// The turbulence steps every millisecond (exactly, whatever the step:
/// [`crate::wind`]) and is held between: its spectrum ends far below 500 Hz.
const WIND_STEP_NS: u64 = 1_000_000;
/// Mixed into the seed so the wind's noise is not the IMU's.
const WIND_SALT: u64 = 0x5749_4E44; // "WIND"

impl Cosim {
    /// The world for tasks of the given kinds (indexed like the spec's tasks).
    pub fn new(
        preset: &Preset,
        mission: Mission,
        kinds: Vec<Option<BodyKind>>,
        cfg: CosimConfig,
    ) -> Result<Cosim, ConfigError> {
        let pp = preset.plant_params();
        let hover = pp.hover_cmd();
        let imu = if mission.world.sensor_errors {
            preset.imu.apply(
                cfg.imu,
                preset.hover_omega_rad_s(),
                preset.rotors.positions_m,
            )
        } else {
            cfg.imu
        };
        let wind = mission.world.dryden()?;
        let assessor = crate::quality::Assessor::new(&mission);
        Ok(Cosim {
            plant: Plant::new(pp)?,
            imu: Imu::new(imu, cfg.seed),
            wind: wind.map(|d| (Wind::new(&d, cfg.seed ^ WIND_SALT), 0)),
            battery: Battery::new(preset.battery)?,
            autopilot: Autopilot::new(preset.autopilot, hover)?,
            mission,
            kinds,
            now: 0,
            next_trace: 0,
            battery_dt: 0.0,
            seen: Seen::default(),
            progress: None,
            delayed: cfg.sense_delay_ns.map(DelayLine::new),
            alerts: Vec::new(),
            trace: Vec::new(),
            keep_trace: true,
            assessor,
            cfg,
        })
    }

    /// Publish the world's time (ns) here as it advances, for a progress
    /// display in another thread.
    pub fn report_progress(&mut self, to: std::sync::Arc<std::sync::atomic::AtomicU64>) {
        self.progress = Some(to);
    }

    /// Makes room now for everything the world records up to `until_ns`
    /// (the trace, when kept, and the points the assessor keeps), so that
    /// no sense or actuate of a run that long grows a vector: on real
    /// threads a doubling vector is copied inside a job, under the world's
    /// lock. Memory still grows with the flight, but only here.
    pub fn reserve(&mut self, until_ns: u64) {
        let every = self.cfg.trace_every_ns.max(1);
        if self.keep_trace {
            let points = until_ns / every + 2;
            self.trace.reserve(usize::try_from(points).unwrap_or(0));
        }
        self.assessor.reserve(every, until_ns);
    }

    /// The plant (for checks after a run).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The mission flown.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// Moves the world to `t`, recording trace points and applying the
    /// disturbance on the way. Executors call in time order; a call for an
    /// earlier instant is a bug.
    pub fn advance(&mut self, t: u64) {
        self.trace_to(t);
        self.step_to(t);
    }

    /// Records the trace points up to `t` without integrating the plant to
    /// `t` itself: for the instants that neither observe nor act on it
    /// (most of the schedule's reads and publishes), where a step to them
    /// would only cut the plant's sub-steps short.
    fn trace_to(&mut self, t: u64) {
        assert!(
            t >= self.now,
            "the world cannot go back from {} to {t} ns",
            self.now
        );
        while self.next_trace <= t {
            let at = self.next_trace;
            self.step_to(at);
            self.record();
            self.next_trace += self.cfg.trace_every_ns.max(1);
            if let Some(p) = &self.progress {
                p.store(at, std::sync::atomic::Ordering::Relaxed);
            }
        }
    }

    fn step_to(&mut self, t: u64) {
        if let Some((ti, j)) = self.cfg.impulse {
            if self.now < ti && ti <= t {
                self.plant.advance_to(ti);
                self.plant.apply_torque_impulse(j);
            }
        }
        self.battery_dt += (t - self.now) as f64 * 1e-9;
        if let Some((wind, next)) = &mut self.wind {
            while *next <= t {
                self.plant.advance_to(*next);
                self.plant.set_wind(wind.at(*next));
                *next += WIND_STEP_NS;
            }
        }
        self.plant.advance_to(t);
        if self.battery_dt >= 1e-3 {
            self.battery.step(self.plant.shaft_power(), self.battery_dt);
            self.battery_dt = 0.0;
        }
        self.now = t;
    }

    fn record(&mut self) {
        // The state, not the whole truth: its accelerations cost a wrench.
        let st = self.plant.state();
        let p = TracePoint {
            t_ns: self.now,
            pos: st.pos,
            vel: st.vel,
            euler: st.q.to_euler(),
            rate: st.rate,
            est: self.seen.est,
            sp: self.seen.sp,
            alt_target: self.mission.intent_at(self.now).altitude_m,
            armed: self.seen.motors.armed,
            on_ground: self.plant.on_ground(),
            crashed: self.plant.crashed(),
            motors: self.seen.motors.motors,
            voltage: self.battery.voltage(),
        };
        self.assessor.push(&p);
        if self.keep_trace {
            self.trace.push(p);
        }
    }

    /// The IMU's vibration follows the rotors (a no-op without vibration).
    fn tell_rotors(&mut self, t: u64) {
        let omega = self.plant.state().omega;
        self.imu.set_rotors(t, self.plant.rotor_angles(), omega);
    }

    /// The pilot's radio frame at `t`: the mission's intent flown by the
    /// autopilot from the true state (a companion with motion capture).
    fn radio_frame(&mut self, t: u64) -> Option<Value> {
        if self
            .cfg
            .radio_loss
            .is_some_and(|(a, b)| (a..b).contains(&t))
        {
            return None;
        }
        let now = self.plant.state();
        let st = VehicleState {
            pos: now.pos,
            vel: now.vel,
            euler: now.q.to_euler(),
            on_ground: self.plant.on_ground(),
        };
        let intent = self.mission.intent_at(t);
        let cmd = self.autopilot.update(t, &intent, &st);
        Some(Value::Radio(RadioSample { t_ns: t, cmd }))
    }
}

/// A pure delay on a stream of samples.
struct DelayLine {
    delay: u64,
    /// Samples not yet delivered, oldest first, with when they were taken.
    queue: std::collections::VecDeque<(u64, Option<Value>)>,
}

impl DelayLine {
    fn new(delay: u64) -> DelayLine {
        DelayLine {
            delay,
            queue: std::collections::VecDeque::new(),
        }
    }

    /// Takes `fresh` (the sample at `t`) in and gives out the newest one
    /// taken at or before t − delay.
    fn pass(&mut self, t: u64, fresh: Option<Value>) -> Option<Value> {
        if self.delay == 0 {
            return fresh;
        }
        self.queue.push_back((t, fresh));
        let due = t.checked_sub(self.delay)?;
        while self.queue.get(1).is_some_and(|&(at, _)| at <= due) {
            self.queue.pop_front();
        }
        match self.queue.front() {
            Some(&(at, v)) if at <= due => v,
            _ => None,
        }
    }
}

fn ns(t: Nanos) -> u64 {
    u64::try_from(t).unwrap_or(0)
}

impl Environment<Value> for Cosim {
    fn sense(&mut self, task: usize, t: Nanos) -> Option<Value> {
        let t = ns(t);
        let Some(kind) = self.kinds.get(task).copied().flatten() else {
            self.trace_to(t);
            return None;
        };
        if kind.observes_world() {
            self.advance(t);
        } else {
            self.trace_to(t);
        }
        let fresh = match kind {
            BodyKind::Gyro | BodyKind::GyroFilter => {
                self.tell_rotors(t);
                let rate = self.plant.state().rate;
                Some(Value::Imu(self.imu.read_gyro(t, rate)))
            }
            BodyKind::Accel => {
                self.tell_rotors(t);
                let sf = self.plant.specific_force();
                Some(Value::Imu(self.imu.read_accel(t, sf)))
            }
            BodyKind::Radio => self.radio_frame(t),
            BodyKind::Vbat => return Some(Value::Scalar(self.battery.voltage())),
            BodyKind::Current => return Some(Value::Scalar(self.battery.current())),
            _ => return None,
        };
        let line = kind.delay_line();
        match line.and_then(|l| self.delayed.get_mut(l)) {
            Some(d) => d.pass(t, fresh),
            None => fresh,
        }
    }

    fn actuate(&mut self, task: usize, t: Nanos, value: &Value) {
        let t = ns(t);
        match (self.kinds.get(task).copied().flatten(), *value) {
            (Some(BodyKind::Pwm), Value::Motors(m)) => {
                self.advance(t);
                self.plant.set_motor_commands(m.motors, m.armed);
                self.seen.motors = m;
            }
            (Some(BodyKind::Ahrs), Value::Attitude(a)) => {
                self.trace_to(t);
                self.seen.est = a.euler;
            }
            (Some(BodyKind::Radio), Value::Radio(r)) => {
                self.trace_to(t);
                self.seen.sp = r.cmd.setpoint();
            }
            (Some(BodyKind::Alert), Value::Alert(a))
                if a != BatteryAlert::Ok && self.alerts.last().is_none_or(|&(_, l)| l != a) =>
            {
                self.alerts.push((t, a));
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::BodyKind;

    #[test]
    fn every_body_is_named_by_its_place_in_the_models_list() {
        for (i, k) in BodyKind::ALL.into_iter().enumerate() {
            assert_eq!(k as usize, i, "{k:?}");
            assert_eq!(BodyKind::parse(k.name()), Some(k));
        }
    }
}
