//! Metrics over a recorded trajectory: error RMS, drift, step responses.

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
    let samples = window(tr, t_step, t_end).map(|p| (p.t_ns as f64 * 1e-9, signal(p)));
    response_of(samples, t_step, from, to, band)
}

/// Measure a heading step of `heading_deg` (degrees, any branch) towards
/// `to_deg`, from where the heading is at `t_step`. Headings are angles on
/// a circle: the signal is unwrapped along the window (each sample's
/// difference from the one before taken by [`crate::math::angle_diff_deg`])
/// so that crossing ±180° is no jump, and the target is the branch of
/// `to_deg` nearest to where the response ends (a 180° step may be flown
/// either way round; the controller chose the way it turned).
pub fn heading_response(
    tr: &[TracePoint],
    heading_deg: impl Fn(&TracePoint) -> f64,
    t_step: f64,
    t_end: f64,
    to_deg: f64,
    band: f64,
) -> StepResponse {
    let mut unwrapped: Option<f64> = None;
    let mut last_raw = 0.0;
    let samples: Vec<(f64, f64)> = window(tr, t_step, t_end)
        .map(|p| {
            let raw = heading_deg(p);
            let u = match unwrapped {
                None => raw,
                Some(u) => u + crate::math::angle_diff_deg(raw, last_raw),
            };
            (unwrapped, last_raw) = (Some(u), raw);
            (p.t_ns as f64 * 1e-9, u)
        })
        .collect();
    let (Some(&(_, start)), Some(&(_, end))) = (samples.first(), samples.last()) else {
        return response_of(std::iter::empty(), t_step, 0.0, to_deg, band);
    };
    let target = end + crate::math::angle_diff_deg(to_deg, end);
    response_of(samples.into_iter(), t_step, start, target, band)
}

/// The step response of `(time s, value)` samples from `t_step` on, the
/// step going from `from` to `to`.
fn response_of(
    samples: impl Iterator<Item = (f64, f64)>,
    t_step: f64,
    from: f64,
    to: f64,
    band: f64,
) -> StepResponse {
    let span = to - from;
    let (mut peak, mut last_out, mut t10, mut t90) = (0.0f64, t_step, None, None);
    for (t, value) in samples {
        let x = (value - from) / span;
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
