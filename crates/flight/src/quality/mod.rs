//! Flight quality of a recorded trajectory against a mission: what `rtpipe
//! fly` reports and what its criteria judge.
//!
//! Windows: the **hover** samples are those with the vehicle armed and
//! airborne under an altitude target, from 3 s after the first altitude
//! target (the climb) until the first stick step or the landing, whichever
//! comes first: steady hover, before any manoeuvre. Attitude error is the
//! true roll/pitch against the set-point in use (√(e_roll² + e_pitch²));
//! altitude error the true height against the target.
//!
//! **Steps** away from level (a stick moved from 0) are judged twice, each
//! until the stick moves again: on the attitude the controller closes its
//! loop on (the AHRS estimate: how well the control loop tracks), and on the
//! true attitude (overshoot, rise time, and the drift at the end of the
//! hold). The two differ because Cleanflight's Mahony filter trusts the
//! accelerometer within 0.9–1.1 g: in a sustained 20° bank at constant
//! height the specific force is 1.064 g along the body's z axis, so the
//! filter pulls its estimate toward level and the true angle drifts away
//! (docs/flight.md). Returns to level are not judged: the autopilot's
//! position hold takes over and brakes the sideways speed with its own
//! set-points. A step's rise, overshoot and settling are measured from
//! where the response stands at the step instant (a gust may have tilted
//! the vehicle) to the target; heading steps on the unwrapped heading, and
//! every heading difference wrapped to (−180°, 180°]
//! ([`crate::math::angle_diff_deg`]). A roll or pitch step settles into
//! 5 % of the step, plus, in a mission flown in turbulence, the hover's
//! tracked error on its axis ([`HoverTracking`]): there the loop strays
//! from its set-point by that much holding still, whatever a step did.
//! The true overshoot's limit is widened by the same error over the
//! step's span ([`weather_allowance`], [`Step::overshoot_limit`]).
//!
//! **Smoothness**: over the same hover samples, the roll and pitch body
//! rate above [`OSCILLATION_HZ`] (the loop ringing) and the motor
//! commands' total variation per second (control effort); over each roll
//! or pitch step's hold (from the criteria's settling time after the step
//! until the stick moves again), the tracked attitude's error.

mod assessor;
mod envelope;
mod smoothness;
mod steps;
mod verdict;

pub use crate::radio::Criteria;
pub use assessor::Assessor;
pub use envelope::{Envelope, Excursion, Excursions, LANDING_TIME_S};
pub use smoothness::OSCILLATION_HZ;
pub use steps::{settling_band, weather_allowance, STEP_BAND};

use crate::radio::Mission;
use crate::trace::metrics::StepResponse;
use crate::trace::TracePoint;

const CLIMB_S: f64 = 3.0;

/// RMS and maximum of an error.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorStats {
    /// Root mean square.
    pub rms: f64,
    /// Largest magnitude.
    pub max: f64,
    /// Samples.
    pub count: usize,
}

/// Which angle a stick step moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Roll angle.
    Roll,
    /// Pitch angle.
    Pitch,
    /// Heading.
    Yaw,
}

impl Axis {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Axis::Roll => "roll",
            Axis::Pitch => "pitch",
            Axis::Yaw => "yaw",
        }
    }
}

/// The response to one stick step away from level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The axis.
    pub axis: Axis,
    /// When the stick moved, s.
    pub at_s: f64,
    /// The target, degrees.
    pub to_deg: f64,
    /// Overshoot, settling (into [`Step::band_deg`]) and 10–90 % rise time
    /// of the estimate the controller tracks, judged until the stick moves
    /// again.
    pub tracked: StepResponse,
    /// The same on the true attitude.
    pub truth: StepResponse,
    /// True angle minus the target when the stick moves again, degrees.
    pub drift_deg: f64,
    /// The half-width of the band the tracked response settled into,
    /// degrees: 5 % of the step, plus in turbulence the hover's tracked
    /// error on its axis ([`FlightQuality::hover_tracking_deg`]); 0 for a
    /// heading step (judged on the plain 5 %, which no criterion asks of).
    pub band_deg: f64,
    /// What the weather adds to the overshoot limit, a fraction of the
    /// step: in turbulence the hover's tracked error on the step's axis
    /// over the true response's span ([`weather_allowance`]); 0 in calm
    /// air and for a heading step.
    pub overshoot_allowance: f64,
}

impl Step {
    /// The overshoot the true response may reach before it fails `c`: the
    /// criterion's fraction plus [`Step::overshoot_allowance`] (the gust
    /// adds to the true attitude as much as the loop wanders holding its
    /// hover; docs/flight.md, "Settling in a disturbed world").
    pub fn overshoot_limit(&self, c: &Criteria) -> f64 {
        c.overshoot + self.overshoot_allowance
    }
}

/// The tracked roll and pitch error RMS over the hover samples (the AHRS
/// estimate against the set-point in use), degrees: how closely the loop
/// holds its own set-point when asked to hold still, in the world the
/// mission flies. In a mission flown in turbulence a step's settling band
/// and overshoot limit are widened by it ([`weather_allowance`]): there the loop wanders about its
/// set-point by this much whatever the step did, and a band narrower than
/// that judges the weather, not the response (docs/flight.md, "Settling in
/// a disturbed world"). In calm air the wander is the loop's own, and the
/// band stays 5 %. Zero without a hover before the steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HoverTracking {
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
}

impl HoverTracking {
    /// The figure of a step's axis; 0 for the heading.
    pub fn of(self, axis: Axis) -> f64 {
        match axis {
            Axis::Roll => self.roll_deg,
            Axis::Pitch => self.pitch_deg,
            Axis::Yaw => 0.0,
        }
    }
}

/// Everything `rtpipe fly` reports about a flight.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FlightQuality {
    /// The vehicle hit the ground too hard or tipped over.
    pub crashed: bool,
    /// When it crashed, s: figures judged after it mean nothing.
    pub crashed_s: Option<f64>,
    /// The last trace point, s: a step at or after it was not flown.
    pub end_s: f64,
    /// Over the hover samples, degrees.
    pub attitude_error_deg: ErrorStats,
    /// Over the hover samples, metres.
    pub altitude_error_m: ErrorStats,
    /// Largest horizontal distance from where the first hover window began,
    /// over that window, metres.
    pub drift_m: f64,
    /// Horizontal distance from where the first hover window began, over
    /// the hover samples, metres (a disturbance-rejection figure).
    pub position_error_m: ErrorStats,
    /// Over the hover samples: the RMS of the roll and pitch body rate
    /// above [`OSCILLATION_HZ`], °/s (an oscillation or limit cycle).
    pub oscillation_dps: f64,
    /// Over the hover samples: the motor commands' total variation per
    /// second, averaged over the motors, 1/s (control effort: a noisy or
    /// chattering output).
    pub motor_variation_per_s: f64,
    /// Over the roll and pitch steps' holds (each from the mission's
    /// `settling_s` after the step until the stick moves again), the true
    /// attitude against the set-point in use, degrees: how well a settled
    /// step holds, in the world the mission flies.
    pub step_tracking_deg: ErrorStats,
    /// Over the hover samples: the tracked roll and pitch error RMS, the
    /// floor every roll or pitch step's settling band is widened by in a
    /// mission flown in turbulence.
    pub hover_tracking_deg: HoverTracking,
    /// Every roll, pitch and heading step of the mission.
    pub steps: Vec<Step>,
    /// Time armed with some motor at 0 or 1 (saturated), s.
    pub saturation_s: f64,
    /// Time armed and off the ground, s.
    pub airborne_s: f64,
    /// When the vehicle was last disarmed on the ground after flying, s.
    pub landed_s: Option<f64>,
    /// The mission holds an altitude, so there is a hover to judge.
    pub hovers: bool,
    /// The envelope the flight was judged against.
    pub envelope: Envelope,
    /// How far the flight went in each of the envelope's quantities.
    pub excursions: Excursions,
    /// Where the vehicle was at the end, m (the landing's figure).
    pub end_pos: crate::math::Vec3,
    /// Armed at the end.
    pub end_armed: bool,
}

fn secs(p: &TracePoint) -> f64 {
    p.t_ns as f64 * 1e-9
}

/// Rates the flight in `trace` (one point per fixed interval) against the
/// `mission` it flew.
pub fn assess(trace: &[TracePoint], mission: &Mission) -> FlightQuality {
    let mut a = Assessor::new(mission);
    for p in trace {
        a.push(p);
    }
    a.finish()
}

#[cfg(test)]
mod tests;
