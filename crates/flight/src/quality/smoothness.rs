//! How smoothly the vehicle holds its hover: the body's oscillation above
//! the loops' bandwidth and the motors' control effort. Both stream over
//! the hover samples; docs/flight.md ("Oscillation, control effort and
//! tracking") gives their definitions and sources.

use crate::filter::{Biquad, BUTTERWORTH_Q};
use crate::trace::TracePoint;

/// The corner of the oscillation's high-pass filter, Hz: well above the
/// attitude loop's bandwidth (a level gain of 6–8 /s is 1–1.3 Hz) and the
/// turbulence's (the Dryden spectra fall off above V/(2πL), 0.1 Hz in
/// `gusty`), so that what rotates the body above it is the loop ringing,
/// a limit cycle or chatter of the actuators, not the vehicle doing its
/// job.
pub const OSCILLATION_HZ: f64 = 5.0;

/// The roll and pitch rates' high-pass filters: second-order Butterworth
/// at [`OSCILLATION_HZ`] for the trace's sample rate, built on a run's
/// second point (the first interval gives the rate) and settled on its
/// first, so a run starts at rest.
#[derive(Debug, Clone, Copy)]
struct RateHighPass {
    roll: Biquad,
    pitch: Biquad,
}

impl RateHighPass {
    /// `None` when the trace is too coarse to see [`OSCILLATION_HZ`] (a
    /// point every 100 ms or more): the figure is then not measured.
    fn new(dt: f64, first: &TracePoint) -> Option<RateHighPass> {
        let fs = 1.0 / dt;
        let mut roll = Biquad::highpass(OSCILLATION_HZ, fs, BUTTERWORTH_Q).ok()?;
        let mut pitch = roll;
        roll.settle(first.rate.x.to_degrees());
        pitch.settle(first.rate.y.to_degrees());
        // The first point's own output, at rest.
        roll.apply(first.rate.x.to_degrees());
        pitch.apply(first.rate.y.to_degrees());
        Some(RateHighPass { roll, pitch })
    }
}

/// The hover's oscillation and control effort, as they stream.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Smoothness {
    filters: Option<RateHighPass>,
    sum_sq: f64,
    count: usize,
    last: Option<(f64, TracePoint)>,
    variation: f64,
    span_s: f64,
}

impl Smoothness {
    /// One hover point at `t` s. Consecutive hover points are one run:
    /// a gap (the hover window left and entered again) starts afresh, so
    /// that a jump across it is counted neither as oscillation nor as
    /// effort.
    pub(super) fn push(&mut self, t: f64, p: &TracePoint, gap_s: f64) {
        let Some((last_t, last)) = self.last.filter(|(l, _)| t - l <= gap_s) else {
            (self.filters, self.last) = (None, Some((t, *p)));
            return;
        };
        let dt = t - last_t;
        if self.filters.is_none() {
            self.filters = RateHighPass::new(dt, &last);
        }
        if let Some(f) = self.filters.as_mut() {
            let p_hp = f.roll.apply(p.rate.x.to_degrees());
            let q_hp = f.pitch.apply(p.rate.y.to_degrees());
            self.sum_sq += p_hp * p_hp + q_hp * q_hp;
            self.count += 1;
        }
        let step: f64 = p
            .motors
            .iter()
            .zip(last.motors)
            .map(|(m, q)| (m - q).abs())
            .sum();
        self.variation += step / 4.0;
        self.span_s += dt;
        self.last = Some((t, *p));
    }

    /// RMS of the roll and pitch body rate above [`OSCILLATION_HZ`]
    /// (√(p² + q²) of the high-passed rates), °/s; 0 when not measured.
    pub(super) fn oscillation_dps(&self) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        (self.sum_sq / self.count as f64).sqrt()
    }

    /// The motor commands' total variation per second: Σ|Δu| over the
    /// hover, averaged over the four motors, divided by the hover's length
    /// (commands in [0, 1], so 1/s is one full swing a second).
    pub(super) fn motor_variation_per_s(&self) -> f64 {
        if self.span_s <= 0.0 {
            return 0.0;
        }
        self.variation / self.span_s
    }
}
