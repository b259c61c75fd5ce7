//! The envelope a flight must stay within from start to end, and what
//! left it.

use super::{Criteria, FlightQuality};
use crate::radio::Mission;

/// What a flight must stay within from start to end, whatever its
/// mission does (a mission's or criterion file's `max_altitude_m`,
/// `max_distance_m`, `max_tilt_deg`; the defaults follow the mission:
/// [`Envelope::of`]). The hover and step criteria judge windows; the
/// envelope catches what those windows miss, such as a vehicle that climbs
/// away after its last step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Envelope {
    /// Highest altitude, m.
    pub max_altitude_m: f64,
    /// Farthest horizontal distance from the launch point, m.
    pub max_distance_m: f64,
    /// Largest tilt from level while off the ground, degrees.
    pub max_tilt_deg: f64,
    /// When the mission's last landing command comes, s, if it ends
    /// landing: the vehicle must then be on the ground and disarmed by the
    /// end of the flight.
    pub land_s: Option<f64>,
}

/// Metres of altitude above the mission's highest target the default
/// envelope allows (an altitude loop that overshoots by this much is
/// broken, not tuned).
const ALTITUDE_MARGIN_M: f64 = 2.0;
/// The default ceiling of a mission that holds no altitude, m.
const CEILING_WITHOUT_TARGET_M: f64 = 10.0;
/// The default farthest distance from the launch point, m (Table V's
/// timing, seeds 0–23: the `steps` mission takes racer5 4.96 m away,
/// aero1kg in the `gusty` turbulence 7.44 m).
const MAX_DISTANCE_M: f64 = 20.0;
/// Degrees of tilt the default envelope allows beyond the mission's
/// largest stick angle (at least [`LEAST_STICK_DEG`]: the autopilot tilts
/// up to 15° on its own, and aero1kg's gusts tilt it up to 42.5° over
/// seeds 0–23 of `gusty`); the default, 60°, stays below the plant's 80°
/// crash tilt.
const TILT_MARGIN_DEG: f64 = 40.0;
/// The least stick angle the default tilt allowance starts from, degrees.
const LEAST_STICK_DEG: f64 = 20.0;
/// A landing is judged only on a flight that ran this long after the
/// landing command (the default flight runs 5 s past the last step).
pub const LANDING_TIME_S: f64 = 5.0;

impl Envelope {
    /// The envelope of `mission` under `criteria`: each key the criteria
    /// set, else the mission's default.
    pub fn of(mission: &Mission, criteria: &Criteria) -> Envelope {
        let highest_target = mission
            .steps
            .iter()
            .filter_map(|s| s.altitude_m)
            .reduce(f64::max);
        let largest_stick = mission
            .steps
            .iter()
            .flat_map(|s| [s.roll_deg, s.pitch_deg])
            .flatten()
            .map(f64::abs)
            .fold(LEAST_STICK_DEG, f64::max);
        let last = mission.steps.last().map(|s| s.t_ns);
        let ends_landing = last.is_some_and(|t| mission.intent_at(t).land);
        let land_s = mission
            .steps
            .iter()
            .rev()
            .find(|s| s.land == Some(true))
            .filter(|_| ends_landing)
            .map(|s| s.t_ns as f64 * 1e-9);
        Envelope {
            max_altitude_m: criteria.max_altitude_m.unwrap_or(
                highest_target.map_or(CEILING_WITHOUT_TARGET_M, |h| h + ALTITUDE_MARGIN_M),
            ),
            max_distance_m: criteria.max_distance_m.unwrap_or(MAX_DISTANCE_M),
            max_tilt_deg: criteria
                .max_tilt_deg
                .unwrap_or(largest_stick + TILT_MARGIN_DEG),
            land_s,
        }
    }

    /// The envelope in words.
    pub fn describe(&self) -> String {
        let landing = if self.land_s.is_some() {
            ", landed and disarmed at the end"
        } else {
            ""
        };
        format!(
            "envelope over the whole flight: altitude ≤ {} m, within {} m of the launch point, tilt ≤ {}°{landing}",
            self.max_altitude_m, self.max_distance_m, self.max_tilt_deg
        )
    }
}

/// How far one quantity of the envelope went: its peak and when, and when
/// it first left its bound.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Excursion {
    /// The largest value, over the flight until any crash.
    pub peak: f64,
    /// When it was reached, s.
    pub peak_s: f64,
    /// When the value first exceeded the envelope's bound, s.
    pub left_s: Option<f64>,
}

impl Excursion {
    pub(super) fn push(&mut self, t: f64, value: f64, bound: f64) {
        if value > self.peak {
            (self.peak, self.peak_s) = (value, t);
        }
        if value > bound && self.left_s.is_none() {
            self.left_s = Some(t);
        }
    }
}

/// The envelope's quantities over a flight.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Excursions {
    /// Altitude, m.
    pub altitude_m: Excursion,
    /// Horizontal distance from the launch point, m.
    pub distance_m: Excursion,
    /// Tilt from level while off the ground, degrees.
    pub tilt_deg: Excursion,
}

impl FlightQuality {
    /// What left the envelope, and when, in words; a landing that did not
    /// happen.
    pub fn envelope_failures(&self) -> Vec<String> {
        let (e, x) = (&self.envelope, &self.excursions);
        let mut out = Vec::new();
        let left = [
            (
                x.altitude_m,
                format!("altitude above {} m", e.max_altitude_m),
                "highest",
                "m",
                "max_altitude_m",
            ),
            (
                x.distance_m,
                format!("more than {} m from the launch point", e.max_distance_m),
                "farthest",
                "m",
                "max_distance_m",
            ),
            (
                x.tilt_deg,
                format!("tilt above {}°", e.max_tilt_deg),
                "most",
                "°",
                "max_tilt_deg",
            ),
        ];
        for (ex, what, peak, unit, key) in left {
            if let Some(t) = ex.left_s {
                let space = if unit == "m" { " " } else { "" };
                out.push(format!(
                    "left the envelope at {t:.2} s: {what} ({peak} {:.1}{space}{unit} at {:.2} s; criteria key {key})",
                    ex.peak, ex.peak_s
                ));
            }
        }
        if let Some(why) = self.not_landed() {
            out.push(why);
        }
        out
    }

    /// Why the flight did not end landed as its mission does; `None` when
    /// it did, when it crashed (that is the verdict), or when it ended too
    /// soon after the landing command to judge.
    fn not_landed(&self) -> Option<String> {
        let land = self.envelope.land_s?;
        if self.crashed || self.landed_s.is_some() || self.end_s < land + LANDING_TIME_S {
            return None;
        }
        let state = if self.end_armed {
            "still armed"
        } else {
            "disarmed"
        };
        Some(format!(
            "did not land: the mission lands from {land:.1} s, but at the end ({:.2} s) the vehicle is {state} at {:.1} m",
            self.end_s, self.end_pos.z
        ))
    }
}
