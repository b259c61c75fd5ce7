//! How a flight went, for people.

use crate::table::Table;
use rtpipe_flight::quality::{Criteria, ErrorStats, FlightQuality, OSCILLATION_HZ};
use serde::Serialize;

/// An error's RMS and maximum, as `fly --json` and `run --json` both name
/// them (`attitude_error_deg.rms`): one name for one figure.
#[derive(Serialize, schemars::JsonSchema)]
pub struct RmsMax {
    /// The root mean square.
    pub rms: f64,
    /// The largest.
    pub max: f64,
}

impl From<&ErrorStats> for RmsMax {
    fn from(e: &ErrorStats) -> Self {
        RmsMax {
            rms: e.rms,
            max: e.max,
        }
    }
}

/// The envelope a flight was judged against over its whole length and how
/// far it went, as `fly --json` and `run --json` both give it.
#[derive(Serialize, schemars::JsonSchema)]
pub struct EnvelopeView {
    pub max_altitude_m: f64,
    pub max_distance_m: f64,
    pub max_tilt_deg: f64,
    /// When the mission's landing begins, s (absent: it does not end landed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub land_s: Option<f64>,
    pub highest_m: f64,
    pub farthest_m: f64,
    pub most_tilt_deg: f64,
}

impl From<&FlightQuality> for EnvelopeView {
    fn from(q: &FlightQuality) -> Self {
        let (e, x) = (&q.envelope, &q.excursions);
        EnvelopeView {
            max_altitude_m: e.max_altitude_m,
            max_distance_m: e.max_distance_m,
            max_tilt_deg: e.max_tilt_deg,
            land_s: e.land_s,
            highest_m: x.altitude_m.peak,
            farthest_m: x.distance_m.peak,
            most_tilt_deg: x.tilt_deg.peak,
        }
    }
}

fn three_decimals(x: f64) -> String {
    format!("{x:.3}")
}

/// The flight's quality against the mission's criteria, as `fly` and `run`
/// print it: crash and landing, hover errors, step responses, verdict.
pub fn quality_text(q: &FlightQuality, c: &Criteria, failures: &[String]) -> String {
    let mut out = match q.crashed_s {
        Some(t) => format!(
            "flight: CRASHED at {t:.2} s; airborne {:.1} s; what follows the crash is not judged\n",
            q.airborne_s
        ),
        None => format!(
            "flight: {}; airborne {:.1} s; landed and disarmed at {}\n",
            if q.crashed { "CRASHED" } else { "no crash" },
            q.airborne_s,
            q.landed_s.map_or("never".into(), |t| format!("{t:.2} s"))
        ),
    };
    if q.hovers && q.attitude_error_deg.count == 0 {
        out.push_str("  hover: never hovered (no sample to judge)\n");
    } else if q.hovers {
        out.push_str(&format!(
            "  hover: attitude error RMS {:.3}° max {:.3}°; altitude error RMS {:.4} m max {:.4} m; drift {:.3} m; motors saturated {:.2} s\n",
            q.attitude_error_deg.rms,
            q.attitude_error_deg.max,
            q.altitude_error_m.rms,
            q.altitude_error_m.max,
            q.drift_m,
            q.saturation_s
        ));
        if c.position_rms_m.is_some() {
            out.push_str(&format!(
                "  disturbance rejection: position error RMS {:.3} m max {:.3} m\n",
                q.position_error_m.rms, q.position_error_m.max
            ));
        }
        out.push_str(&format!(
            "  smoothness: oscillation {:.2}°/s RMS above {} Hz; motor command variation {:.2}/s\n",
            q.oscillation_dps, OSCILLATION_HZ, q.motor_variation_per_s
        ));
    } else {
        out.push_str("  hover: none to judge (the mission holds no altitude)\n");
    }
    if q.step_tracking_deg.count > 0 {
        out.push_str(&format!(
            "  step tracking: attitude error RMS {:.3}° max {:.3}° over the roll and pitch steps' holds\n",
            q.step_tracking_deg.rms, q.step_tracking_deg.max
        ));
    }
    let x = &q.excursions;
    out.push_str(&format!(
        "  whole flight: highest {:.2} m, farthest {:.2} m from the launch point, most tilt {:.1}°\n",
        x.altitude_m.peak, x.distance_m.peak, x.tilt_deg.peak
    ));
    if !q.steps.is_empty() {
        out.push_str("  steps (tracked: the AHRS estimate the controller closes its loop on; true: the plant):\n");
        out.push_str(&steps_table(q));
    }
    out.push_str(&match failures {
        [] => format!(
            "  criteria ({}; {}): met\n",
            c.describe(),
            q.envelope.describe()
        ),
        f => format!("  criteria NOT met: {}\n", f.join("; ")),
    });
    out
}

/// The step responses; a step after a crash shows no figure.
fn steps_table(q: &FlightQuality) -> String {
    let mut t = Table::new(&[
        "step",
        "at s",
        "to°",
        "rise s",
        "overshoot %",
        "settling s",
        "true rise s",
        "true overshoot %",
        "true drift° at release",
    ])
    .numeric(&[1, 2, 3, 4, 5, 6, 7, 8]);
    for st in &q.steps {
        let mut row = vec![
            st.axis.name().to_string(),
            format!("{:.1}", st.at_s),
            format!("{:.0}", st.to_deg),
        ];
        if let Some(why) = q.unjudged_why(st) {
            row.extend(std::iter::repeat_n("-".to_string(), 5));
            row.push(why);
            t.row(row);
            continue;
        }
        let (e, r) = (&st.tracked, &st.truth);
        row.extend([
            three_decimals(e.rise_s),
            format!("{:.1}", 100.0 * e.overshoot),
            three_decimals(e.settling_s),
            three_decimals(r.rise_s),
            format!("{:.1}", 100.0 * r.overshoot),
            format!("{:+.2}", st.drift_deg),
        ]);
        t.row(row);
    }
    t.render()
}
