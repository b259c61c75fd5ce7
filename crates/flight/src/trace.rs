//! What a flight records: the vehicle's true state and what the flight
//! controller showed the world, one point per instant, and the metrics
//! computed over such a trajectory. Every executor of the flight tasks
//! (ideal timing, the simulated schedule, real threads) records this type,
//! so the quality figures and plots do not depend on which one flew.

use crate::math::{Euler, Vec3};
use crate::pid::Setpoint;

pub mod metrics;

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
