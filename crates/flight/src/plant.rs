//! 6-DOF quadrotor plant: rigid body with quaternion attitude, four rotors
//! with a first-order lag on their speed, thrust k_f·ω², reaction torque
//! k_m·ω² (sign by spin direction), gravity, linear drag, a small angular
//! drag, and ground contact. Integrated with RK4 at a fixed sub-step;
//! [`Plant::advance_to`] reaches any timestamp (partial last step).
//!
//! Frames: world z up, body FLU (see the crate docs). Motor commands in
//! [0, 1] map linearly to a rotor speed target between idle and max while
//! armed; disarmed rotors spin down to 0.

use crate::error::{in_range, non_negative, positive, ConfigError};
use crate::math::{Euler, Quat, Vec3, GRAVITY};
pub use aero::AeroParams;
use serde::Deserialize;

/// Rotor spin direction seen from above.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Spin {
    /// Clockwise: the reaction torque on the body is +z (counter-clockwise).
    Cw,
    /// Counter-clockwise: the reaction torque is −z.
    Ccw,
}

impl Spin {
    /// Sign of the reaction torque about body z.
    pub fn reaction_sign(self) -> f64 {
        match self {
            Spin::Cw => 1.0,
            Spin::Ccw => -1.0,
        }
    }
}

/// Rigid-body parameters (the `[body]` table of a preset).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyParams {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Principal moments of inertia (x, y, z), kg·m².
    pub inertia_kg_m2: [f64; 3],
    /// Linear drag coefficient, N per m/s (world frame, all axes).
    pub drag_linear: f64,
    /// Angular drag coefficient, N·m per rad/s.
    pub drag_angular: f64,
    /// Touch-down vertical speed above which the landing is a crash, m/s.
    #[serde(default = "default_crash_speed")]
    pub crash_speed_mps: f64,
    /// Tilt on the ground above which the vehicle counts as crashed, deg.
    #[serde(default = "default_crash_tilt")]
    pub crash_tilt_deg: f64,
}

fn default_crash_speed() -> f64 {
    3.0
}
fn default_crash_tilt() -> f64 {
    80.0
}

/// One entry per rotor: exactly four (serde would cut five to four
/// silently).
fn four<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
    field: &str,
) -> Result<[T; 4], D::Error> {
    let v: Vec<T> = Vec::deserialize(d)?;
    let n = v.len();
    v.try_into().map_err(|_| {
        serde::de::Error::custom(format!(
            "{field} needs exactly 4 entries, one per rotor (the vehicle is a quadrotor), found {n}"
        ))
    })
}

fn four_positions<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[[f64; 2]; 4], D::Error> {
    four(d, "rotors.positions_m")
}

fn four_spins<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[Spin; 4], D::Error> {
    four(d, "rotors.spin")
}

/// Rotor parameters (the `[rotors]` table of a preset).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorParams {
    /// Rotor hub positions (x, y) in the body, m, Betaflight motor order
    /// (exactly four: the mixer is a quadrotor's).
    #[serde(deserialize_with = "four_positions")]
    pub positions_m: [[f64; 2]; 4],
    /// Spin directions, Betaflight motor order.
    #[serde(deserialize_with = "four_spins")]
    pub spin: [Spin; 4],
    /// Thrust coefficient: F = k_f·ω², N/(rad/s)².
    pub k_f: f64,
    /// Torque coefficient: Q = k_m·ω², N·m/(rad/s)².
    pub k_m: f64,
    /// Rotor speed at command 1.0, rad/s.
    pub omega_max_rad_s: f64,
    /// Rotor speed at command 0.0 while armed, as a fraction of max.
    pub idle_fraction: f64,
    /// First-order time constant of the rotor speed, s.
    pub time_constant_s: f64,
}

/// All plant parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantParams {
    /// Rigid body.
    pub body: BodyParams,
    /// Rotors.
    pub rotors: RotorParams,
    /// Rotor aerodynamics (all off: the linear-drag plant).
    pub aero: AeroParams,
    /// RK4 sub-step, ns.
    pub substep_ns: u64,
}

/// A stopped rotor slower than this (rad/s) is at rest: its thrust,
/// k_f·ω² < 1e-12 N on both presets, is far below anything the flight
/// notices.
pub const OMEGA_AT_REST: f64 = 1e-3;

/// The longest RK4 sub-step: 2 ms. (Inputs may change inside one: the
/// motor commands, the turbulence every 1 ms; each change cuts the step
/// there, so no step straddles one.)
pub const SUBSTEP_NS_MAX: u64 = 2_000_000;

/// Sub-steps per time constant of the plant's fastest mode, at least.
const STEPS_PER_TIME_CONSTANT: f64 = 10.0;

/// The shortest time constant a plant may have, s: the floor of the rotors'
/// lag (`rotors.time_constant_s`), and of the body's damping times, so the
/// RK4 sub-step stays at 62.5 µs or longer.
pub const MIN_TIME_CONSTANT_S: f64 = 1e-3;

impl PlantParams {
    /// The plant of `body` and `rotors` with its RK4 sub-step: the longest
    /// of 2 ms, 1 ms, 500 µs, … (each divides the ones above, so the
    /// grids nest) that puts [`STEPS_PER_TIME_CONSTANT`] steps in the
    /// fastest of the plant's time constants: the rotors' lag τ_m, the
    /// body's rate damping I/c_ω and its velocity damping m/c_v. At h ≤
    /// τ/10 the RK4 local error is below (h/τ)⁵/120 ≈ 8e-8 relative; the
    /// rest of the plant (rates, attitude, position) integrates the rotors
    /// without a faster mode of its own (docs/flight.md).
    pub fn with_substep(body: BodyParams, rotors: RotorParams, aero: AeroParams) -> PlantParams {
        let mut params = PlantParams {
            body,
            rotors,
            aero,
            substep_ns: SUBSTEP_NS_MAX,
        };
        let fastest = params
            .damping_times()
            .iter()
            .map(|d| d.2)
            .fold(rotors.time_constant_s, f64::min);
        while params.substep_ns > 1
            && params.substep_ns as f64 * 1e-9 * STEPS_PER_TIME_CONSTANT > fastest
        {
            params.substep_ns /= 2;
        }
        params
    }

    /// The body's damping times, s, each with the key that sets it and how:
    /// its velocity damping m/c_v and rate damping I_min/c_ω, c_v and c_ω
    /// the linear drags plus what the rotor aerodynamics add at full rotor
    /// speed ([`AeroParams::damping`]); infinite without damping.
    fn damping_times(&self) -> [(&'static str, &'static str, f64); 2] {
        let b = &self.body;
        let i_min = b
            .inertia_kg_m2
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let (aero_v, aero_w) = self
            .aero
            .damping(&self.rotors.positions_m, self.rotors.omega_max_rad_s);
        let time = |inertia: f64, drag: f64| {
            if drag > 0.0 {
                inertia / drag
            } else {
                f64::INFINITY
            }
        };
        [
            (
                "body.drag_linear",
                "body.mass_kg / (body.drag_linear + the [aero] rotor drag at full speed)",
                time(b.mass_kg, b.drag_linear + aero_v),
            ),
            (
                "body.drag_angular",
                "the least body.inertia_kg_m2 / (body.drag_angular + the [aero] rate damping at full speed)",
                time(i_min, b.drag_angular + aero_w),
            ),
        ]
    }

    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let b = &self.body;
        // Physically plausible ranges: a 10 g micro quad to a 100 kg lifter
        // (far outside, the integration diverges: 1e-30 kg flew NaNs).
        in_range("body.mass_kg", b.mass_kg, 0.01, 100.0)?;
        for (i, v) in b.inertia_kg_m2.iter().enumerate() {
            in_range(&format!("body.inertia_kg_m2[{i}]"), *v, 1e-6, 100.0)?;
        }
        non_negative("body.drag_linear", b.drag_linear)?;
        non_negative("body.drag_angular", b.drag_angular)?;
        self.aero.validate()?;
        self.damping_is_plausible()?;
        positive("body.crash_speed_mps", b.crash_speed_mps)?;
        in_range("body.crash_tilt_deg", b.crash_tilt_deg, 0.0, 180.0)?;
        let r = &self.rotors;
        for (i, p) in r.positions_m.iter().enumerate() {
            for (j, v) in p.iter().enumerate() {
                in_range(&format!("rotors.positions_m[{i}][{j}]"), *v, -10.0, 10.0)?;
            }
        }
        positive("rotors.k_f", r.k_f)?;
        non_negative("rotors.k_m", r.k_m)?;
        positive("rotors.omega_max_rad_s", r.omega_max_rad_s)?;
        in_range("rotors.idle_fraction", r.idle_fraction, 0.0, 0.5)?;
        in_range(
            "rotors.time_constant_s",
            r.time_constant_s,
            MIN_TIME_CONSTANT_S,
            2.0,
        )?;
        let lift = 4.0 * r.k_f * r.omega_max_rad_s.powi(2) / (b.mass_kg * GRAVITY);
        if !(lift.is_finite() && (1.0..=100.0).contains(&lift)) {
            return Err(ConfigError::new(
                "rotors.omega_max_rad_s",
                format!(
                    "full thrust over weight (4·k_f·omega_max_rad_s² / (mass_kg·g)) must be in [1, 100], got {lift:.3e}: set k_f, omega_max_rad_s and body.mass_kg so the rotors can lift the vehicle"
                ),
            ));
        }
        if self.substep_ns == 0 {
            return Err(ConfigError::new("substep_ns", "must be > 0"));
        }
        Ok(())
    }

    /// The body's damping times (m/c_v, I/c_ω) are at least
    /// [`MIN_TIME_CONSTANT_S`], the floor of the rotors' lag: the RK4
    /// sub-step follows the fastest time constant ([`Self::with_substep`]),
    /// so an implausible drag (1e9) would take it to 1 ns and a flight to
    /// half an hour of CPU. A real quadrotor's are seconds.
    fn damping_is_plausible(&self) -> Result<(), ConfigError> {
        for (field, what, time) in self.damping_times() {
            if time < MIN_TIME_CONSTANT_S {
                return Err(ConfigError::new(
                    field,
                    format!(
                        "the damping time {what} is {time:.3e} s, under the {MIN_TIME_CONSTANT_S} s the plant integrates (a real quadrotor's is seconds): give less drag"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Rotor speed target for a command while armed, rad/s.
    pub fn omega_for_cmd(&self, cmd: f64) -> f64 {
        let r = &self.rotors;
        r.omega_max_rad_s * (r.idle_fraction + (1.0 - r.idle_fraction) * cmd.clamp(0.0, 1.0))
    }

    /// The motor command at which the four rotors together carry the weight.
    pub fn hover_cmd(&self) -> f64 {
        let w = (self.body.mass_kg * GRAVITY / (4.0 * self.rotors.k_f)).sqrt();
        let r = &self.rotors;
        (w / r.omega_max_rad_s - r.idle_fraction) / (1.0 - r.idle_fraction)
    }

    /// Total thrust over weight at full command.
    pub fn thrust_to_weight(&self) -> f64 {
        4.0 * self.rotors.k_f * self.rotors.omega_max_rad_s.powi(2) / (self.body.mass_kg * GRAVITY)
    }
}

pub mod aero;
mod dense;

/// The integrated state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Position (world), m.
    pub pos: Vec3,
    /// Velocity (world), m/s.
    pub vel: Vec3,
    /// Attitude, body → world.
    pub q: Quat,
    /// Body rate, rad/s.
    pub rate: Vec3,
    /// Rotor speeds, rad/s.
    pub omega: [f64; 4],
}

impl State {
    /// Every component finite.
    fn is_finite(&self) -> bool {
        let v = |a: Vec3| a.x.is_finite() && a.y.is_finite() && a.z.is_finite();
        let q = self.q;
        v(self.pos)
            && v(self.vel)
            && v(self.rate)
            && [q.w, q.x, q.y, q.z].iter().all(|c| c.is_finite())
            && self.omega.iter().all(|o| o.is_finite())
    }

    /// `self + Σ w_i·k_i` in one pass (RK4's end and its dense output).
    fn plus_combination(&self, k: &[State; 4], w: [f64; 4]) -> State {
        let v = |f: fn(&State) -> Vec3| {
            f(self) + f(&k[0]) * w[0] + f(&k[1]) * w[1] + f(&k[2]) * w[2] + f(&k[3]) * w[3]
        };
        let q = self
            .q
            .add_scaled(k[0].q, w[0])
            .add_scaled(k[1].q, w[1])
            .add_scaled(k[2].q, w[2])
            .add_scaled(k[3].q, w[3]);
        State {
            pos: v(|s| s.pos),
            vel: v(|s| s.vel),
            q,
            rate: v(|s| s.rate),
            omega: std::array::from_fn(|i| {
                self.omega[i]
                    + k[0].omega[i] * w[0]
                    + k[1].omega[i] * w[1]
                    + k[2].omega[i] * w[2]
                    + k[3].omega[i] * w[3]
            }),
        }
    }

    fn add_scaled(&self, d: &State, s: f64) -> State {
        let mut omega = self.omega;
        for (o, od) in omega.iter_mut().zip(d.omega.iter()) {
            *o += od * s;
        }
        State {
            pos: self.pos + d.pos * s,
            vel: self.vel + d.vel * s,
            q: self.q.add_scaled(d.q, s),
            rate: self.rate + d.rate * s,
            omega,
        }
    }
}

/// What the sensors and the tests may observe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Plant time, ns.
    pub t_ns: u64,
    /// Position (world), m.
    pub pos: Vec3,
    /// Velocity (world), m/s.
    pub vel: Vec3,
    /// Attitude.
    pub q: Quat,
    /// Attitude as Euler angles.
    pub euler: Euler,
    /// Body rate, rad/s (what an ideal gyro reads).
    pub rate: Vec3,
    /// Specific force in the body, m/s² (what an ideal accelerometer reads).
    pub specific_force: Vec3,
    /// Angular acceleration in the body, rad/s².
    pub ang_accel: Vec3,
    /// Rotor speeds, rad/s.
    pub omega: [f64; 4],
    /// Resting on the ground.
    pub on_ground: bool,
    /// Hit the ground too fast or tipped over.
    pub crashed: bool,
}

/// The quadrotor plant.
#[derive(Debug, Clone)]
pub struct Plant {
    p: PlantParams,
    k: Coefficients,
    s: State,
    t_ns: u64,
    target: [f64; 4],
    ext_torque: Vec3,
    /// The air's velocity (world), m/s: drag acts on the velocity relative
    /// to it.
    wind: Vec3,
    /// Rotor angles, rad in [0, 2π): where the vibration they shake the IMU
    /// with is in its cycle.
    rotor_angle: [f64; 4],
    on_ground: bool,
    crashed: bool,
    /// The instant observed: `t_ns`, or an instant inside the sub-step
    /// from `t_ns` to the next grid point whose state `view` interpolates
    /// (`dense`); `view` and `view_angle` are the state and rotor angles
    /// then (equal to `s` and `rotor_angle` at `t_ns`).
    view_t: u64,
    view: State,
    view_angle: [f64; 4],
    /// The sub-step from `t_ns` computed ahead for the views inside it;
    /// dropped when an input changes.
    ahead: Option<dense::Ahead>,
}

/// `a` wrapped into [0, 2π), bit for bit as `a.rem_euclid(TAU)`: for a
/// in [2π, 4π) (a step turns a rotor by less than 2π) the subtraction
/// a − 2π is exact (Sterbenz), as fmod's remainder is, without its cost
/// (fmod was 3 % of a flight).
fn wrap_tau(a: f64) -> f64 {
    use std::f64::consts::TAU;
    if (0.0..TAU).contains(&a) {
        a
    } else if (TAU..2.0 * TAU).contains(&a) {
        a - TAU
    } else {
        a.rem_euclid(TAU)
    }
}

/// The parameters as the derivative uses them, worked out once: the
/// reciprocals (a division costs several multiplications, and the
/// derivative is most of a flight's plant) and each rotor's torque per
/// ω², r × (0, 0, k_f) + (0, 0, s·k_m) = (y·k_f, −x·k_f, s·k_m).
#[derive(Debug, Clone, Copy)]
struct Coefficients {
    torque_per_w2: [Vec3; 4],
    inv_inertia: Vec3,
    inv_mass: f64,
    inv_tau_m: f64,
}

impl Coefficients {
    fn of(p: &PlantParams) -> Coefficients {
        let r = &p.rotors;
        let inertia = p.body.inertia_kg_m2;
        Coefficients {
            torque_per_w2: std::array::from_fn(|i| {
                let [x, y] = r.positions_m[i];
                Vec3::new(y * r.k_f, -x * r.k_f, r.spin[i].reaction_sign() * r.k_m)
            }),
            inv_inertia: Vec3::new(1.0 / inertia[0], 1.0 / inertia[1], 1.0 / inertia[2]),
            inv_mass: 1.0 / p.body.mass_kg,
            inv_tau_m: 1.0 / r.time_constant_s,
        }
    }
}

/// Forces and torques at a state (shared by the derivative and the truth).
struct Wrench {
    accel_world: Vec3,
    ang_accel: Vec3,
}

impl Plant {
    /// A plant at rest on the ground at the origin, level, rotors stopped.
    pub fn new(params: PlantParams) -> Result<Self, ConfigError> {
        params.validate()?;
        let rest = State {
            pos: Vec3::ZERO,
            vel: Vec3::ZERO,
            q: Quat::IDENTITY,
            rate: Vec3::ZERO,
            omega: [0.0; 4],
        };
        Ok(Self {
            p: params,
            k: Coefficients::of(&params),
            s: rest,
            t_ns: 0,
            target: [0.0; 4],
            ext_torque: Vec3::ZERO,
            wind: Vec3::ZERO,
            rotor_angle: [0.0; 4],
            on_ground: true,
            crashed: false,
            view_t: 0,
            view: rest,
            view_angle: [0.0; 4],
            ahead: None,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PlantParams {
        &self.p
    }

    /// Current time, ns.
    pub fn time_ns(&self) -> u64 {
        self.view_t
    }

    /// The raw state.
    pub fn state(&self) -> &State {
        &self.view
    }

    /// Resting on the ground ([`Truth::on_ground`]).
    pub fn on_ground(&self) -> bool {
        self.on_ground
    }

    /// Crashed ([`Truth::crashed`]).
    pub fn crashed(&self) -> bool {
        self.crashed
    }

    /// Overwrite the state (tests and scenarios); `on_ground` is re-derived.
    pub fn set_state(&mut self, s: State) {
        self.settle();
        self.s = s;
        self.on_ground = s.pos.z <= 0.0 && s.vel.z <= 0.0;
        self.sync_view();
    }

    /// Apply motor commands in [0, 1] (Betaflight order); held until the
    /// next call (zero-order hold, as an ESC holds the last pulse).
    pub fn set_motor_commands(&mut self, cmd: [f64; 4], armed: bool) {
        self.settle();
        for (t, c) in self.target.iter_mut().zip(cmd.iter()) {
            *t = if armed { self.p.omega_for_cmd(*c) } else { 0.0 };
        }
    }

    /// A constant external torque in the body (a disturbance), N·m.
    pub fn set_external_torque(&mut self, tau: Vec3) {
        self.settle();
        self.ext_torque = tau;
    }

    /// The wind (world, m/s) from now on, held until the next call: the
    /// linear drag acts on the airspeed v − wind. With no wind the
    /// arithmetic is the calm plant's, bit for bit (v − 0 = v).
    pub fn set_wind(&mut self, wind: Vec3) {
        self.settle();
        self.wind = wind;
    }

    /// The rotor angles, rad in [0, 2π), Betaflight order.
    pub fn rotor_angles(&self) -> [f64; 4] {
        self.view_angle
    }

    /// An instantaneous angular impulse in the body, N·m·s.
    pub fn apply_torque_impulse(&mut self, j: Vec3) {
        self.settle();
        let i = Vec3::from_array(self.p.body.inertia_kg_m2);
        self.s.rate += Vec3::new(j.x / i.x, j.y / i.y, j.z / i.z);
        self.on_ground = false;
        self.sync_view();
    }

    /// Mechanical shaft power of the four rotors, W (Σ k_m·ω³).
    pub fn shaft_power(&self) -> f64 {
        self.view
            .omega
            .iter()
            .map(|w| self.p.rotors.k_m * w.abs().powi(3))
            .sum()
    }

    /// Total rotor thrust at rotor speeds `omega`, N (k_f·Σω², as
    /// [`Plant::wrench`] takes it).
    fn thrust(&self, omega: &[f64; 4]) -> f64 {
        self.p.rotors.k_f * omega.iter().fold(0.0, |t, w| t + w * w)
    }

    fn wrench(&self, s: &State) -> Wrench {
        let (b, k) = (&self.p.body, &self.k);
        let mut w2_sum = 0.0;
        let mut tau = Vec3::ZERO;
        for (w, c) in s.omega.iter().zip(&k.torque_per_w2) {
            let w2 = w * w;
            tau += *c * w2;
            w2_sum += w2;
        }
        let mut f_body = Vec3::new(0.0, 0.0, self.p.rotors.k_f * w2_sum);
        tau += self.ext_torque - s.rate * b.drag_angular;
        let airspeed = s.vel - self.wind;
        // Off, the plant's arithmetic is the linear-drag one, bit for bit.
        if !self.p.aero.is_off() {
            let positions = &self.p.rotors.positions_m;
            let a = (self.p.aero).wrench(positions, &s.omega, s.rate, s.q.rotate_inv(airspeed));
            f_body += a.force;
            tau += a.moment;
        }
        let inertia = Vec3::from_array(b.inertia_kg_m2);
        let gyro = s.rate.cross(s.rate.hadamard(inertia));
        let ang_accel = (tau - gyro).hadamard(k.inv_inertia);
        let f_world = s.q.rotate(f_body) - airspeed * b.drag_linear;
        let accel_world = f_world * k.inv_mass - Vec3::new(0.0, 0.0, GRAVITY);
        Wrench {
            accel_world,
            ang_accel,
        }
    }

    /// The rotors' speed derivative: first-order lag toward the target.
    fn omega_rate(&self, omega: &[f64; 4]) -> [f64; 4] {
        std::array::from_fn(|i| (self.target[i] - omega[i]) * self.k.inv_tau_m)
    }

    /// The derivative in free flight (the ground holds nothing).
    fn derivative(&self, s: &State) -> State {
        let domega = self.omega_rate(&s.omega);
        let w = self.wrench(s);
        State {
            pos: s.vel,
            vel: w.accel_world,
            q: s.q.derivative(s.rate),
            rate: w.ang_accel,
            omega: domega,
        }
    }

    /// One RK4 step of `h` s in free flight.
    fn rk4_free(&self, h: f64) -> State {
        self.rk4_stages(h).1
    }

    /// RK4's four stages over `h` s in free flight, and the step's end.
    fn rk4_stages(&self, h: f64) -> ([State; 4], State) {
        let s = self.s;
        let k1 = self.derivative(&s);
        let k2 = self.derivative(&s.add_scaled(&k1, 0.5 * h));
        let k3 = self.derivative(&s.add_scaled(&k2, 0.5 * h));
        let k4 = self.derivative(&s.add_scaled(&k3, h));
        let k = [k1, k2, k3, k4];
        let end = s.plus_combination(&k, [h / 6.0, h / 3.0, h / 3.0, h / 6.0]);
        (k, end)
    }

    /// One RK4 step of `h` s held by the ground (or wrecked): only the
    /// rotors move. The same arithmetic as [`Plant::rk4_free`] with the
    /// body's derivatives zero, without evaluating them: the rotors' RK4 as
    /// there, and every other component plus the zero increments (x + 0.0,
    /// which turns a -0.0 into 0.0 as the full step did).
    fn rk4_held(&self, h: f64) -> State {
        let s = self.s;
        let at = |k: &[f64; 4], c: f64| {
            let mut o = s.omega;
            for (o, d) in o.iter_mut().zip(k) {
                *o += d * c;
            }
            o
        };
        let k1 = self.omega_rate(&s.omega);
        let k2 = self.omega_rate(&at(&k1, 0.5 * h));
        let k3 = self.omega_rate(&at(&k2, 0.5 * h));
        let k4 = self.omega_rate(&at(&k3, h));
        let mut omega = s.omega;
        for (k, c) in [(k1, h / 6.0), (k2, h / 3.0), (k3, h / 3.0), (k4, h / 6.0)] {
            for (o, d) in omega.iter_mut().zip(k) {
                *o += d * c;
            }
        }
        let still = State {
            pos: Vec3::ZERO,
            vel: Vec3::ZERO,
            q: Quat::new(0.0, 0.0, 0.0, 0.0),
            rate: Vec3::ZERO,
            omega: [0.0; 4],
        };
        State {
            omega,
            ..s.add_scaled(&still, 1.0)
        }
    }

    fn rk4(&mut self, h_ns: u64) {
        let h = h_ns as f64 * 1e-9;
        let ahead = self.ahead.take();
        let mut n = match &ahead {
            Some(a) if a.start_ns == self.t_ns && a.h_ns == h_ns => a.end,
            _ if self.on_ground || self.crashed => self.rk4_held(h),
            _ => self.rk4_free(h),
        };
        n.q = n.q.normalized();
        if n.is_finite() {
            self.s = n;
        } else {
            // The integration diverged (a preset the plant cannot fly
            // stably): the vehicle is lost, not flying NaNs "landed".
            self.crashed = true;
            self.s.vel = Vec3::ZERO;
            self.s.rate = Vec3::ZERO;
        }
    }

    /// Ground contact after a step: no penetration; a touch-down faster
    /// than `crash_speed_mps` or a tilt beyond `crash_tilt_deg` is a crash;
    /// otherwise the vehicle rests level (legs) while thrust < weight.
    fn ground_contact(&mut self) {
        let b = self.p.body;
        if self.crashed {
            return;
        }
        if self.on_ground {
            if self.thrust(&self.s.omega) * self.s.q.body_z_world().z > b.mass_kg * GRAVITY {
                self.on_ground = false; // lift-off
            }
            return;
        }
        if self.s.pos.z > 0.0 {
            return;
        }
        let tilt = self.s.q.tilt().to_degrees();
        if -self.s.vel.z > b.crash_speed_mps || tilt > b.crash_tilt_deg {
            self.crashed = true;
        }
        let yaw = self.s.q.to_euler().yaw;
        self.s.pos.z = 0.0;
        self.s.vel = Vec3::ZERO;
        self.s.rate = Vec3::ZERO;
        if !self.crashed {
            self.s.q = Quat::from_euler(Euler {
                roll: 0.0,
                pitch: 0.0,
                yaw,
            });
        }
        self.on_ground = true;
    }

    /// Rotor bookkeeping after a step of `h` s from speeds `before`: the
    /// angles advance by the trapezoid of the speeds, and a stopped rotor's
    /// speed is snapped to 0 once below [`OMEGA_AT_REST`]. Without the snap
    /// the exponential spin-down sinks into subnormal numbers (and sticks at
    /// the smallest one: 0.99 × 5e-324 rounds back to it), and every
    /// derivative after a disarm runs on the slow subnormal path.
    fn rotors_after_step(&mut self, before: &[f64; 4], h: f64) {
        let rotors = self.s.omega.iter_mut().zip(&self.target);
        for ((w, target), (angle, w0)) in rotors.zip(self.rotor_angle.iter_mut().zip(before)) {
            if *target == 0.0 && w.abs() < OMEGA_AT_REST {
                *w = 0.0;
            }
            *angle = wrap_tau(*angle + 0.5 * h * (w0 + *w));
        }
    }

    /// Integrate to `t_ns` on the sub-step grid (multiples of the
    /// sub-step, so instants on it cut no step short). An instant between
    /// two grid points is viewed by dense output from the whole sub-step
    /// computed ahead, in free flight; on the ground, at a touch-down, or
    /// when an input changes there (`settle`), the step is cut at it.
    /// Times before the observed time are ignored (the plant never rewinds).
    pub fn advance_to(&mut self, t_ns: u64) {
        if t_ns <= self.view_t {
            return;
        }
        let grid = self.p.substep_ns;
        loop {
            let end = (self.t_ns / grid + 1) * grid;
            if t_ns < end {
                break;
            }
            self.step(end - self.t_ns);
        }
        if t_ns > self.t_ns && !self.view_inside(t_ns) {
            self.step(t_ns - self.t_ns);
        }
        if self.view_t < self.t_ns {
            self.sync_view();
        }
    }

    /// One RK4 step of `h_ns` from `t_ns`, with the ground and the rotors'
    /// bookkeeping after it.
    fn step(&mut self, h_ns: u64) {
        let before = self.s.omega;
        self.rk4(h_ns);
        self.t_ns += h_ns;
        self.rotors_after_step(&before, h_ns as f64 * 1e-9);
        self.ground_contact();
    }

    /// Views `t_ns` (inside the sub-step from `t_ns` to the next grid
    /// point) by dense output; false when it cannot (on the ground,
    /// crashed, or the step would touch down or diverge).
    fn view_inside(&mut self, t_ns: u64) -> bool {
        if self.on_ground || self.crashed {
            return false;
        }
        let grid = self.p.substep_ns;
        let h_ns = (self.t_ns / grid + 1) * grid - self.t_ns;
        if !self
            .ahead
            .as_ref()
            .is_some_and(|a| a.start_ns == self.t_ns && a.h_ns == h_ns)
        {
            let (k, end) = self.rk4_stages(h_ns as f64 * 1e-9);
            self.ahead = Some(dense::Ahead {
                start_ns: self.t_ns,
                h_ns,
                k,
                end,
            });
        }
        let Some(a) = self.ahead.as_ref() else {
            unreachable!("the step ahead was just made")
        };
        if !(a.end.is_finite() && a.end.pos.z > 0.0) {
            return false;
        }
        self.view = a.state_at(&self.s, t_ns);
        let dt = (t_ns - self.t_ns) as f64 * 1e-9;
        self.view_angle = dense::angles_at(&self.rotor_angle, &self.s.omega, &self.view.omega, dt);
        self.view_t = t_ns;
        true
    }

    /// The view is the integrated state (after a step or a change).
    fn sync_view(&mut self) {
        self.view = self.s;
        self.view_angle = self.rotor_angle;
        self.view_t = self.t_ns;
    }

    /// Before an input changes at the observed instant: integrate to it
    /// (a step cut there, as the inputs hold only until then) and drop
    /// the step computed ahead with the old inputs.
    fn settle(&mut self) {
        if self.view_t > self.t_ns {
            self.step(self.view_t - self.t_ns);
            self.sync_view();
        }
        self.ahead = None;
    }

    /// Linear (world) and angular (body) acceleration now: zero while the
    /// ground holds the vehicle.
    fn accelerations(&self) -> (Vec3, Vec3) {
        if self.on_ground || self.crashed {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            let w = self.wrench(&self.view);
            (w.accel_world, w.ang_accel)
        }
    }

    /// The specific force in the body now, m/s²: what an ideal
    /// accelerometer reads ([`Truth::specific_force`], without the rest of
    /// the truth's cost: its Euler angles are three inverse trigonometric
    /// calls).
    pub fn specific_force(&self) -> Vec3 {
        self.felt(self.accelerations().0)
    }

    /// The specific force in the body at world acceleration `accel`.
    fn felt(&self, accel: Vec3) -> Vec3 {
        self.view.q.rotate_inv(accel + Vec3::new(0.0, 0.0, GRAVITY))
    }

    /// The observable truth at the current time.
    pub fn truth(&self) -> Truth {
        let s = &self.view;
        let (accel, ang_accel) = self.accelerations();
        Truth {
            t_ns: self.view_t,
            pos: s.pos,
            vel: s.vel,
            q: s.q,
            euler: s.q.to_euler(),
            rate: s.rate,
            specific_force: self.felt(accel),
            ang_accel,
            omega: s.omega,
            on_ground: self.on_ground,
            crashed: self.crashed,
        }
    }
}

#[cfg(test)]
mod tests;
