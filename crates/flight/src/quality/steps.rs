//! The mission's stick steps and the responses judged on them.

use super::{secs, Axis, FlightQuality, Step};
use crate::radio::Mission;
use crate::trace::metrics::{heading_response, step_response};
use crate::trace::TracePoint;

/// A mission stick change: (time s, axis, target deg).
pub(super) fn stick_changes(mission: &Mission) -> Vec<(f64, Axis, f64)> {
    let mut out = Vec::new();
    let mut prev = mission.intent_at(0);
    for s in &mission.steps {
        let now = mission.intent_at(s.t_ns);
        let t = s.t_ns as f64 * 1e-9;
        if now.roll_deg != prev.roll_deg {
            out.push((t, Axis::Roll, now.roll_deg));
        }
        if now.pitch_deg != prev.pitch_deg {
            out.push((t, Axis::Pitch, now.pitch_deg));
        }
        if now.yaw_deg != prev.yaw_deg {
            out.push((t, Axis::Yaw, now.yaw_deg.unwrap_or(0.0)));
        }
        prev = now;
    }
    out
}

/// Where the judging window of change `k` ends: the next change after it,
/// or 2 s on.
pub(super) fn step_end(changes: &[(f64, Axis, f64)], k: usize) -> f64 {
    let t = changes[k].0;
    changes
        .iter()
        .skip(k + 1)
        .map(|c| c.0)
        .find(|&c| c > t)
        .unwrap_or(t + 2.0)
}

fn angle(axis: Axis, e: &crate::math::Euler) -> f64 {
    match axis {
        Axis::Roll => e.roll,
        Axis::Pitch => e.pitch,
        Axis::Yaw => e.yaw,
    }
    .to_degrees()
}

/// The changes judged as steps: away from level (from 0 to a non-zero
/// target), each with its index in `changes`.
fn away_from_level(
    changes: &[(f64, Axis, f64)],
) -> impl Iterator<Item = (usize, f64, Axis, f64)> + '_ {
    changes
        .iter()
        .enumerate()
        .filter(|&(k, &(_, axis, to))| {
            let from = changes[..k]
                .iter()
                .rev()
                .find(|c| c.1 == axis)
                .map_or(0.0, |c| c.2);
            from == 0.0 && to != 0.0
        })
        .map(|(k, &(t, axis, to))| (k, t, axis, to))
}

/// The holds of the roll and pitch steps, s: from `settle_s` after each
/// step (when the criteria want it settled) until the stick moves again;
/// where the attitude tracking is judged. A step released sooner has none.
pub(super) fn step_holds(changes: &[(f64, Axis, f64)], settle_s: f64) -> Vec<(f64, f64)> {
    away_from_level(changes)
        .filter(|&(_, _, axis, _)| axis != Axis::Yaw)
        .map(|(k, t, _, _)| (t + settle_s, step_end(changes, k)))
        .filter(|&(from, to)| from < to)
        .collect()
}

/// What the weather adds to a step's limits, as a fraction of the step
/// from `start` to `to`: `floor_deg`, the tracked error the same loop
/// showed holding its hover in the same world (see
/// [`super::HoverTracking`]), over the step's span. A criterion narrower
/// than what the loop holds still judges the weather, not the step; both
/// the settling band ([`settling_band`]) and the overshoot limit
/// ([`super::Step::overshoot_limit`]) are widened by it. A step of no size
/// gets none.
pub fn weather_allowance(start: f64, to: f64, floor_deg: f64) -> f64 {
    let span = (to - start).abs();
    if span > 0.0 {
        floor_deg / span
    } else {
        0.0
    }
}

/// A step's settling band as a fraction of the step: [`STEP_BAND`] of the
/// step from `start` to `to`, widened by the [`weather_allowance`] of
/// `floor_deg`.
pub fn settling_band(start: f64, to: f64, floor_deg: f64) -> f64 {
    STEP_BAND + weather_allowance(start, to, floor_deg)
}

/// The settling band of a step, as a fraction of the step: ±5 %.
pub const STEP_BAND: f64 = 0.05;

pub(super) fn steps(
    trace: &[TracePoint],
    changes: &[(f64, Axis, f64)],
    floor: super::HoverTracking,
) -> Vec<Step> {
    let mut out = Vec::new();
    for (k, t, axis, to) in away_from_level(changes) {
        let end = step_end(changes, k);
        // Each response with the weather's allowance over its own span.
        let judge = |est: bool| {
            let signal = move |p: &TracePoint| angle(axis, if est { &p.est } else { &p.euler });
            if axis == Axis::Yaw {
                return (
                    heading_response(trace, signal, t, end, to, STEP_BAND),
                    0.0,
                    0.0,
                );
            }
            // From where the response starts, not from level: a gust may
            // have tilted the vehicle when the stick moved.
            let start = trace.iter().find(|p| secs(p) >= t).map_or(0.0, &signal);
            let allowance = weather_allowance(start, to, floor.of(axis));
            let band = settling_band(start, to, floor.of(axis));
            let response = step_response(trace, signal, t, end, start, to, band);
            (response, allowance, band * (to - start).abs())
        };
        let at_end = trace
            .iter()
            .take_while(|p| secs(p) < end)
            .last()
            .map_or(f64::NAN, |p| angle(axis, &p.euler));
        let (tracked, _, band_deg) = judge(true);
        let (truth, overshoot_allowance, _) = judge(false);
        out.push(Step {
            axis,
            at_s: t,
            to_deg: to,
            tracked,
            truth,
            band_deg,
            overshoot_allowance,
            drift_deg: crate::math::angle_diff_deg(at_end, to),
        });
    }
    out
}

impl FlightQuality {
    /// A step is judged only when it began before any crash (after one,
    /// its overshoot and settling describe a wreck) and before the flight
    /// ended (else there is nothing to judge).
    pub fn judged(&self, s: &Step) -> bool {
        self.crashed_s.is_none_or(|t| s.at_s < t) && s.at_s < self.end_s
    }

    /// Why a step is not judged, in words; `None` when it is.
    pub fn unjudged_why(&self, s: &Step) -> Option<String> {
        match self.crashed_s {
            Some(t) if s.at_s >= t => Some("after the crash".to_string()),
            _ if s.at_s >= self.end_s => Some(format!(
                "not flown (the flight ended at {:.2} s)",
                self.end_s
            )),
            _ => None,
        }
    }
}
