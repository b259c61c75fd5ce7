//! The flight's figures point by point, in memory bounded by the mission.

use super::envelope::{Envelope, Excursions};
use super::smoothness::Smoothness;
use super::steps::{step_end, step_holds, steps, stick_changes};
use super::{secs, Axis, ErrorStats, FlightQuality, HoverTracking, CLIMB_S};
use crate::radio::Mission;
use crate::trace::TracePoint;

/// Sums of squares and the largest magnitude of an error, as it streams.
#[derive(Debug, Clone, Copy, Default)]
struct Running {
    sum_sq: f64,
    max: f64,
    count: usize,
}

impl Running {
    fn push(&mut self, e: f64) {
        self.sum_sq += e * e;
        self.max = self.max.max(e.abs());
        self.count += 1;
    }

    fn stats(self) -> ErrorStats {
        let n = self.count;
        ErrorStats {
            rms: if n == 0 {
                0.0
            } else {
                (self.sum_sq / n as f64).sqrt()
            },
            max: self.max,
            count: n,
        }
    }
}

/// The true roll and pitch against the set-point in use,
/// √(e_roll² + e_pitch²), degrees.
fn attitude_error_deg(p: &TracePoint) -> f64 {
    let (er, ep) = (p.euler.roll - p.sp.roll, p.euler.pitch - p.sp.pitch);
    (er * er + ep * ep).sqrt().to_degrees()
}

/// Hover points further apart than this, s, are two runs of the hover
/// (the control-effort figure does not count a jump across the gap).
const HOVER_GAP_S: f64 = 0.05;

/// Where the first hover window is: not begun, begun at a position, over.
#[derive(Debug, Clone, Copy)]
enum Window {
    Before,
    In(crate::math::Vec3),
    After,
}

/// [`assess`] point by point, in memory bounded by the mission (not by the
/// flight's length): the hover figures stream; only the points the steps
/// are judged on (up to the last step's window) are kept.
#[derive(Debug, Clone)]
pub struct Assessor {
    changes: Vec<(f64, Axis, f64)>,
    first_alt: Option<f64>,
    /// Hover points come before this (the landing or the first step).
    hover_end: f64,
    /// Points before this are kept for the steps.
    keep_until: f64,
    kept: Vec<TracePoint>,
    first_two: (Option<f64>, Option<f64>),
    crashed_s: Option<f64>,
    end_s: f64,
    attitude: Running,
    /// The tracked roll and pitch error in the hover.
    tracking: [Running; 2],
    /// The mission flies in turbulence: the hover's tracked error widens
    /// the steps' settling band (in calm air it is the loop's own).
    turbulent: bool,
    altitude: Running,
    position: Running,
    smoothness: Smoothness,
    /// The roll and pitch steps' holds, s, and the tracking error in them.
    step_holds: Vec<(f64, f64)>,
    step_tracking: Running,
    origin: Option<crate::math::Vec3>,
    window: Window,
    drift: f64,
    saturated: usize,
    airborne: usize,
    flew: bool,
    /// The start of the current run of disarmed points on the ground after
    /// the first flying one.
    resting_since: Option<f64>,
    envelope: Envelope,
    excursions: Excursions,
    launch: Option<crate::math::Vec3>,
    last: Option<TracePoint>,
}

impl Assessor {
    /// Nothing flown yet.
    pub fn new(mission: &Mission) -> Assessor {
        let changes = stick_changes(mission);
        let first_alt = mission
            .steps
            .iter()
            .find(|s| s.altitude_m.is_some())
            .map(|s| s.t_ns as f64 * 1e-9);
        let land = mission
            .steps
            .iter()
            .find(|s| s.land == Some(true))
            .map_or(f64::INFINITY, |s| s.t_ns as f64 * 1e-9);
        let first_step = changes.first().map_or(f64::INFINITY, |c| c.0);
        let keep_until = (0..changes.len())
            .map(|k| step_end(&changes, k))
            .fold(f64::NEG_INFINITY, f64::max);
        Assessor {
            step_holds: step_holds(&changes, mission.criteria.settling_s),
            changes,
            first_alt,
            hover_end: land.min(first_step),
            keep_until,
            kept: Vec::new(),
            first_two: (None, None),
            crashed_s: None,
            end_s: 0.0,
            attitude: Running::default(),
            tracking: [Running::default(); 2],
            turbulent: mission.world.turbulence != crate::wind::Intensity::None,
            altitude: Running::default(),
            position: Running::default(),
            smoothness: Smoothness::default(),
            step_tracking: Running::default(),
            origin: None,
            window: Window::Before,
            drift: 0.0,
            saturated: 0,
            airborne: 0,
            flew: false,
            resting_since: None,
            envelope: Envelope::of(mission, &mission.criteria),
            excursions: Excursions::default(),
            launch: None,
            last: None,
        }
    }

    /// Makes room now for every point a flight of `until_ns` with a point
    /// every `every_ns` keeps for its steps, so that no later [`push`]
    /// grows a vector: on a real-time executor a push that doubles one
    /// copies it inside a job (measured: gyro jobs of 230, 396 and 764 µs
    /// against a median of 1.1 µs, at 4,096, 8,192 and 16,384 jobs).
    ///
    /// [`push`]: Assessor::push
    pub fn reserve(&mut self, every_ns: u64, until_ns: u64) {
        let kept_ns = if self.keep_until > 0.0 {
            (self.keep_until * 1e9).min(until_ns as f64) as u64
        } else {
            0
        };
        let points = kept_ns / every_ns.max(1) + 2;
        self.kept.reserve(
            usize::try_from(points)
                .unwrap_or(0)
                .saturating_sub(self.kept.len()),
        );
    }

    fn hover(&self, p: &TracePoint) -> bool {
        let t = secs(p);
        p.armed
            && !p.on_ground
            && p.alt_target.is_some()
            && self.first_alt.is_some_and(|a| t >= a + CLIMB_S)
            && t < self.hover_end
    }

    /// The next trace point (in time order).
    pub fn push(&mut self, p: &TracePoint) {
        let t = secs(p);
        match self.first_two {
            (None, _) => self.first_two.0 = Some(t),
            (Some(_), None) => self.first_two.1 = Some(t),
            _ => {}
        }
        if p.crashed && self.crashed_s.is_none() {
            self.crashed_s = Some(t);
        }
        self.end_s = t;
        if t < self.keep_until {
            self.kept.push(*p);
        }
        self.push_hover(p);
        self.push_step_tracking(p);
        self.push_envelope(p);
        self.last = Some(*p);
        if p.armed && p.motors.iter().any(|&m| m <= 0.0 || m >= 1.0) {
            self.saturated += 1;
        }
        if p.armed && !p.on_ground {
            self.airborne += 1;
            self.flew = true;
        }
        if self.flew {
            if !p.armed && p.on_ground {
                self.resting_since.get_or_insert(t);
            } else {
                self.resting_since = None;
            }
        }
    }

    /// The envelope's figures of one point, until a crash (the crash is
    /// the verdict; a wreck's attitude is no excursion).
    fn push_envelope(&mut self, p: &TracePoint) {
        if self.crashed_s.is_some() {
            return;
        }
        let (t, e, x) = (secs(p), self.envelope, &mut self.excursions);
        x.altitude_m.push(t, p.pos.z, e.max_altitude_m);
        let o = *self.launch.get_or_insert(p.pos);
        let d = ((p.pos.x - o.x).powi(2) + (p.pos.y - o.y).powi(2)).sqrt();
        x.distance_m.push(t, d, e.max_distance_m);
        if !p.on_ground {
            // The angle between the body's z axis and the vertical.
            let cos_tilt = p.euler.roll.cos() * p.euler.pitch.cos();
            let tilt = cos_tilt.clamp(-1.0, 1.0).acos().to_degrees();
            x.tilt_deg.push(t, tilt, e.max_tilt_deg);
        }
    }

    /// The attitude tracking error of one point inside a roll or pitch
    /// step's hold, until a crash.
    fn push_step_tracking(&mut self, p: &TracePoint) {
        let t = secs(p);
        let inside = self.step_holds.iter().any(|&(a, b)| a <= t && t < b);
        if inside && self.crashed_s.is_none() && p.armed && !p.on_ground {
            // On the estimate the controller closes its loop on: the true
            // attitude drifts from it in a sustained bank (the Mahony
            // filter's accelerometer trust; docs/flight.md), about 2° on
            // every schedule, which is the estimator's figure, not the loop's.
            let (er, ep) = (p.est.roll - p.sp.roll, p.est.pitch - p.sp.pitch);
            self.step_tracking
                .push((er * er + ep * ep).sqrt().to_degrees());
        }
    }

    /// The hover figures of one point.
    fn push_hover(&mut self, p: &TracePoint) {
        let hover = self.hover(p);
        self.window = match (self.window, hover) {
            (Window::Before, true) => Window::In(p.pos),
            (Window::In(_), false) => Window::After,
            (w, _) => w,
        };
        if let Window::In(o) = self.window {
            let d = ((p.pos.x - o.x).powi(2) + (p.pos.y - o.y).powi(2)).sqrt();
            self.drift = self.drift.max(d);
        }
        if !hover {
            return;
        }
        self.attitude.push(attitude_error_deg(p));
        self.tracking[0].push((p.est.roll - p.sp.roll).to_degrees());
        self.tracking[1].push((p.est.pitch - p.sp.pitch).to_degrees());
        self.smoothness.push(secs(p), p, HOVER_GAP_S);
        self.altitude
            .push(p.pos.z - p.alt_target.unwrap_or(p.pos.z));
        let o = *self.origin.get_or_insert(p.pos);
        self.position
            .push(((p.pos.x - o.x).powi(2) + (p.pos.y - o.y).powi(2)).sqrt());
    }

    /// The figures of the flight so far.
    pub fn finish(self) -> FlightQuality {
        let dt = match self.first_two {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        };
        let crashed = self.crashed_s.is_some();
        let hover_tracking = HoverTracking {
            roll_deg: self.tracking[0].stats().rms,
            pitch_deg: self.tracking[1].stats().rms,
        };
        let floor = if self.turbulent {
            hover_tracking
        } else {
            HoverTracking::default()
        };
        FlightQuality {
            crashed,
            crashed_s: self.crashed_s,
            end_s: self.end_s,
            attitude_error_deg: self.attitude.stats(),
            altitude_error_m: self.altitude.stats(),
            drift_m: self.drift,
            position_error_m: self.position.stats(),
            oscillation_dps: self.smoothness.oscillation_dps(),
            motor_variation_per_s: self.smoothness.motor_variation_per_s(),
            step_tracking_deg: self.step_tracking.stats(),
            hover_tracking_deg: hover_tracking,
            steps: steps(&self.kept, &self.changes, floor),
            saturation_s: dt * self.saturated as f64,
            airborne_s: dt * self.airborne as f64,
            landed_s: if crashed { None } else { self.resting_since },
            hovers: self.first_alt.is_some(),
            envelope: self.envelope,
            excursions: self.excursions,
            end_pos: self.last.map_or_else(Default::default, |p| p.pos),
            end_armed: self.last.is_some_and(|p| p.armed),
        }
    }
}
