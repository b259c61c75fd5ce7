//! # rtpipe-flight
//!
//! Pure algorithms and models to fly a simulated quadrotor with a
//! Cleanflight-like controller: vector/quaternion maths, filters, a Mahony
//! AHRS, angle/rate PID, the quad-X mixer, motor protocols, radio/missions,
//! battery, a 6-DOF plant with RK4 and a BMI160-like IMU.
//!
//! Nothing here knows about scheduling: every periodic computation is a pure
//! `update`/`step` on caller-owned state. [`tasks`] wraps them as task bodies
//! and holds the co-simulated world they fly in; the scheduler simulator
//! runs those bodies (`rtpipe fly`), and [`loop_sim`] runs the same bodies
//! with ideal timing. Both record a [`trace`].
//!
//! ## Conventions
//!
//! - World frame: x forward (initial heading), y left, z up (ENU-like; the
//!   ground is z = 0). Body frame: FLU (x forward, y left, z up), as in
//!   ROS REP-103.
//! - Attitude: Hamilton quaternion rotating body vectors into the world.
//!   Euler angles are ZYX (yaw, then pitch, then roll) about the body axes,
//!   right-handed: positive roll lowers the right side, positive pitch
//!   lowers the nose, positive yaw turns left (counter-clockwise from above).
//! - Time: `u64` nanoseconds for timestamps, `f64` seconds for durations.
//! - SI units everywhere unless a name says otherwise (`_deg`, `_dps`, `_us`).
//! - f64 throughout, including the controller. The firmware uses f32 for
//!   speed on an FPU-less or single-precision MCU; here the arithmetic cost
//!   is irrelevant and one float type keeps the code free of conversions and
//!   the results independent of mixed-precision rounding.
#![deny(missing_docs)]

pub mod ahrs;
pub mod battery;
pub mod error;
pub mod filter;
pub mod imu;
pub mod loop_sim;
pub mod math;
pub mod mixer;
pub mod motor;
pub mod pid;
pub mod plant;
pub mod preset;
pub mod quality;
pub mod radio;
pub mod rng;
pub mod tasks;
pub mod trace;
pub mod wind;

pub use error::ConfigError;
