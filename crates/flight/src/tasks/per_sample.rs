//! One controller step per new sample.

use crate::mixer::MotorDemand;

/// A controller that steps once per new sample: the sample it last stepped
/// on (its stamp, ns) and the output it gave. A job with no new sample (a
/// merged, a periodic or a faster job) repeats that output: stepping again
/// on the same measurement turns the D term into spikes (zero, then the
/// whole change over one period).
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct PerSample(Option<(u64, MotorDemand)>);

impl PerSample {
    /// For the sample stamped `t_ns`: `Err(out)` to repeat the output of
    /// the same sample, `Ok(dt)` the seconds since the last sample stepped
    /// on (0 for the first).
    pub(crate) fn step(&self, t_ns: u64) -> Result<f64, MotorDemand> {
        match self.0 {
            Some((t, out)) if t == t_ns => Err(out),
            Some((t, _)) => Ok(t_ns.saturating_sub(t) as f64 * 1e-9),
            None => Ok(0.0),
        }
    }

    /// The output stepped on the sample stamped `t_ns`.
    pub(crate) fn record(&mut self, t_ns: u64, out: MotorDemand) {
        self.0 = Some((t_ns, out));
    }

    /// Forgets the last sample (the controller was reset).
    pub(crate) fn reset(&mut self) {
        self.0 = None;
    }
}
