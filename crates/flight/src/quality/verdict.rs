//! The verdict: what fails a mission's criteria, in words.

use super::{Axis, Criteria, FlightQuality, Step, OSCILLATION_HZ};

impl FlightQuality {
    /// What fails `c`, in words; empty when the flight meets it.
    pub fn failures(&self, c: &Criteria) -> Vec<String> {
        let mut out = Vec::new();
        match self.crashed_s {
            Some(t) => out.push(format!("crashed at {t:.2} s")),
            None if self.crashed => out.push("crashed".to_string()),
            None => {}
        }
        out.extend(self.envelope_failures());
        let never = self.hovers && self.attitude_error_deg.count == 0;
        if never {
            out.push("never hovered (no sample to judge)".to_string());
        }
        let a = self.attitude_error_deg.rms;
        if !never && a >= c.attitude_rms_deg {
            out.push(format!(
                "attitude error RMS {a:.2}° ≥ {}°",
                c.attitude_rms_deg
            ));
        }
        let h = self.altitude_error_m.rms;
        if !never && h >= c.altitude_rms_m {
            out.push(format!(
                "altitude error RMS {h:.3} m ≥ {} m",
                c.altitude_rms_m
            ));
        }
        if let Some(limit) = c.position_rms_m {
            let p = self.position_error_m.rms;
            if !never && p >= limit {
                out.push(format!("position error RMS {p:.3} m ≥ {limit} m"));
            }
        }
        out.extend(self.smoothness_failures(c, never));
        let mut unjudged: Vec<(String, String)> = Vec::new();
        for s in self.steps.iter().filter(|s| s.axis != Axis::Yaw) {
            if let Some(why) = self.unjudged_why(s) {
                match unjudged.iter_mut().find(|(w, _)| *w == why) {
                    Some((_, at)) => at.push_str(&format!(", {:.1}", s.at_s)),
                    None => unjudged.push((why, format!("{:.1}", s.at_s))),
                }
            }
        }
        for (why, at) in unjudged {
            out.push(format!("steps at {at} s not judged: {why}"));
        }
        for s in self
            .steps
            .iter()
            .filter(|s| s.axis != Axis::Yaw && self.judged(s))
        {
            let (over, settle) = (s.truth.overshoot, s.tracked.settling_s);
            let over_limit = s.overshoot_limit(c);
            if over >= over_limit || settle >= c.settling_s {
                out.push(format!(
                    "{} step at {:.1} s: overshoot {:.1} %, settling {:.3} s (limits {}, {} s)",
                    s.axis.name(),
                    s.at_s,
                    100.0 * over,
                    settle,
                    overshoot_limit_words(c, s),
                    c.settling_s
                ));
            }
        }
        out
    }

    /// The hover's oscillation and control effort (when it hovered) and
    /// the steps' tracking (when a step was flown) against `c`.
    fn smoothness_failures(&self, c: &Criteria, never: bool) -> Vec<String> {
        let mut out = Vec::new();
        let (o, u) = (self.oscillation_dps, self.motor_variation_per_s);
        if self.hovers && !never && o >= c.oscillation_dps {
            out.push(format!(
                "hover oscillation {o:.2}°/s RMS above {OSCILLATION_HZ} Hz ≥ {}°/s",
                c.oscillation_dps
            ));
        }
        if self.hovers && !never && u >= c.motor_variation_per_s {
            out.push(format!(
                "hover motor command variation {u:.2}/s ≥ {}/s",
                c.motor_variation_per_s
            ));
        }
        let track = self.step_tracking_deg;
        if track.count > 0 && track.rms >= c.step_tracking_rms_deg {
            out.push(format!(
                "step tracking error RMS {:.2}° ≥ {}°",
                track.rms, c.step_tracking_rms_deg
            ));
        }
        out
    }
}

/// The overshoot limit a step was judged on, in words: the criterion's
/// plain percentage in calm air; in turbulence, that plus the hover's
/// tracked error over the step's span, and the sum.
fn overshoot_limit_words(c: &Criteria, s: &Step) -> String {
    if s.overshoot_allowance > 0.0 {
        format!(
            "{:.1} % = {:.0} % + {:.1} % hover tracking",
            100.0 * s.overshoot_limit(c),
            100.0 * c.overshoot,
            100.0 * s.overshoot_allowance
        )
    } else {
        format!("{:.0} %", 100.0 * c.overshoot)
    }
}
