//! `rtpipe fly`'s report of one flight: the analysis, what the flight
//! observed of every chain, and the flight's quality, as text, JSON or
//! tables (`rtpipe_printer` prints it as `--format` asks).

use crate::report::analysis::{ReportView, TaskView};
use crate::report::flight::{quality_text, EnvelopeView, RmsMax};
use crate::report::record_table;
use crate::simulate;
use rtpipe_analysis::{Anchor, Report};
use rtpipe_flight::quality::FlightQuality;
use rtpipe_flight::trace::metrics::StepResponse;
use rtpipe_fly::{Flight, Setup};
use rtpipe_model::{Server, Spec};
use rtpipe_printer::{Cell, Column, Kind, Table};
use rtpipe_sim::observe::ChainObs;
use serde::Serialize;

/// `rtpipe fly`'s report of one flight.
pub(super) struct FlightReport<'a> {
    pub spec: &'a Spec,
    pub report: &'a Report,
    pub setup: &'a Setup,
    pub flight: &'a Flight,
    pub obs: &'a [ChainObs],
    /// The criteria the flight did not meet (none: it met them all).
    pub failures: &'a [String],
    /// Wall-clock seconds the flight took.
    pub seconds: f64,
}

impl Serialize for FlightReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let v = to_json(
            self.spec,
            self.report,
            self.setup,
            self.flight,
            self.obs,
            self.failures,
            self.seconds,
        );
        v.serialize(s)
    }
}

impl rtpipe_printer::Report for FlightReport<'_> {
    fn text(&self) -> String {
        to_text(
            self.spec,
            self.setup,
            self.flight,
            self.obs,
            self.failures,
            self.seconds,
        )
    }

    /// The analysis' tasks and chains, what the flight observed of each
    /// chain, the flight's figures (one row) and its step responses.
    fn tables(&self) -> Vec<Table> {
        let mut ts = crate::report::analysis::tables(self.spec, self.report);
        ts.push(simulate::observed_table(self.spec, self.obs));
        ts.push(flight_table(
            self.setup,
            &self.flight.quality,
            self.failures,
        ));
        ts.push(steps_table(&self.flight.quality));
        ts
    }
}

/// The flight's figures as one row, named as `fly --json`'s `flight`
/// object names them (`attitude_error_deg.rms` → `attitude_error_deg_rms`).
fn flight_table(s: &Setup, q: &FlightQuality, failures: &[String]) -> Table {
    let mut fields = vec![
        ("vehicle", Kind::Text, Cell::from(s.preset.name.as_str())),
        ("mission", Kind::Text, Cell::from(s.mission.name.as_str())),
        ("world", Kind::Text, Cell::from(s.mission.world.describe())),
        (
            "duration_s",
            Kind::Float,
            Cell::Float(s.horizon as f64 * 1e-9),
        ),
        ("crashed", Kind::Bool, Cell::Bool(q.crashed)),
        ("crashed_s", Kind::Float, Cell::opt_float(q.crashed_s)),
    ];
    fields.extend(figures(q, s.mission.criteria.position_rms_m.is_some()));
    fields.extend([
        ("criteria_met", Kind::Bool, Cell::Bool(failures.is_empty())),
        ("failures", Kind::Text, Cell::from(failures.join("; "))),
    ]);
    record_table("flight", fields)
}

/// The quality figures of [`flight_table`]; the position error only when
/// the mission judges it (`judged`), the step tracking only when steps
/// were flown, as in the JSON.
fn figures(q: &FlightQuality, judged: bool) -> Vec<(&'static str, Kind, Cell)> {
    let f = Cell::Float;
    let steps = q.step_tracking_deg.count > 0;
    let opt = |on: bool, v: f64| Cell::opt_float(on.then_some(v));
    vec![
        (
            "attitude_error_deg_rms",
            Kind::Float,
            f(q.attitude_error_deg.rms),
        ),
        (
            "attitude_error_deg_max",
            Kind::Float,
            f(q.attitude_error_deg.max),
        ),
        (
            "altitude_error_m_rms",
            Kind::Float,
            f(q.altitude_error_m.rms),
        ),
        (
            "altitude_error_m_max",
            Kind::Float,
            f(q.altitude_error_m.max),
        ),
        ("drift_m", Kind::Float, f(q.drift_m)),
        (
            "position_error_m_rms",
            Kind::Float,
            opt(judged, q.position_error_m.rms),
        ),
        (
            "position_error_m_max",
            Kind::Float,
            opt(judged, q.position_error_m.max),
        ),
        ("oscillation_dps", Kind::Float, f(q.oscillation_dps)),
        (
            "motor_variation_per_s",
            Kind::Float,
            f(q.motor_variation_per_s),
        ),
        (
            "step_tracking_deg_rms",
            Kind::Float,
            opt(steps, q.step_tracking_deg.rms),
        ),
        (
            "step_tracking_deg_max",
            Kind::Float,
            opt(steps, q.step_tracking_deg.max),
        ),
        ("saturation_s", Kind::Float, f(q.saturation_s)),
        ("airborne_s", Kind::Float, f(q.airborne_s)),
        ("landed_s", Kind::Float, Cell::opt_float(q.landed_s)),
    ]
}

/// A row per step: its tracked (the estimate) and true (the plant)
/// responses, as `fly --json`'s `steps` give them.
fn steps_table(q: &FlightQuality) -> Table {
    let mut columns = vec![Column::new("axis", Kind::Text)];
    columns.extend(
        [
            "at_s",
            "to_deg",
            "rise_s",
            "overshoot",
            "settling_s",
            "true_rise_s",
            "true_overshoot",
            "true_settling_s",
            "drift_deg",
        ]
        .map(|n| Column::new(n, Kind::Float)),
    );
    let Ok(mut t) = Table::new("steps", columns) else {
        unreachable!("the steps table's columns are distinct names");
    };
    for st in &q.steps {
        let (e, r) = (&st.tracked, &st.truth);
        t.push(
            [st.at_s, st.to_deg, e.rise_s, e.overshoot, e.settling_s]
                .into_iter()
                .chain([r.rise_s, r.overshoot, r.settling_s, st.drift_deg])
                .map(Cell::Float)
                .fold(vec![Cell::from(st.axis.name())], |mut row, c| {
                    row.push(c);
                    row
                }),
        );
    }
    t
}

fn to_text(
    spec: &Spec,
    s: &Setup,
    f: &Flight,
    obs: &[ChainObs],
    failures: &[String],
    seconds: f64,
) -> String {
    let flown = s.horizon as f64 * 1e-9;
    let mut out = format!(
        "system {}: {} tasks; vehicle {}; mission {} ({}); {:.1} s flown in {:.2} s ({:.0}× real time)\n\n",
        spec.name,
        spec.tasks.len(),
        s.preset.name,
        s.mission.name,
        s.mission.description,
        flown,
        seconds,
        flown / seconds.max(1e-9)
    );
    let world = s.mission.world.describe();
    if !world.is_empty() {
        out.push_str(&format!("world: {world}\n"));
    }
    out.push_str(&quality_text(&f.quality, &s.criteria(), failures));
    out.push_str(
        "\nchains (observed from the head's read, against the analysis' worst-case bounds):\n",
    );
    out.push_str(&simulate::chain_table(spec, obs, Anchor::Read));
    out.push_str("\nfrom the event (see `simulate`), against the +event bounds:\n");
    out.push_str(&simulate::chain_table(spec, obs, Anchor::Event));
    let bg: Vec<&str> = spec
        .tasks
        .iter()
        .zip(&f.sim.tasks)
        .filter(|(t, _)| t.server == Server::Background)
        .map(|(t, _)| t.name.as_str())
        .collect();
    if !bg.is_empty() {
        let runs: Vec<String> = spec
            .tasks
            .iter()
            .zip(&f.sim.tasks)
            .filter(|(t, _)| t.server == Server::Background)
            .map(|(t, r)| format!("{} {}/{}", t.name, r.completed, r.released))
            .collect();
        out.push_str(&format!(
            "\nhousekeeping (background, jobs completed/released): {}\n",
            runs.join(", ")
        ));
    }
    out
}

/// `fly --json`: the observations report, then the flight's quality.
#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct FlyView<'a> {
    #[serde(flatten)]
    report: ReportView<'a, TaskView<'a>, simulate::ObsChain<'a>>,
    /// How the flight went: the vehicle, the mission and its quality figures.
    flight: FlightView<'a>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct FlightView<'a> {
    /// The vehicle flown.
    vehicle: &'a str,
    /// The mission flown.
    mission: &'a str,
    /// The disturbances flown in, in words (absent in calm air).
    #[serde(skip_serializing_if = "String::is_empty")]
    world: String,
    /// The flight's length, s.
    duration_s: f64,
    /// Whether the vehicle crashed.
    crashed: bool,
    /// When it crashed, s (absent: it did not).
    #[serde(skip_serializing_if = "Option::is_none")]
    crashed_s: Option<f64>,
    /// Attitude error against the setpoint, RMS and max, degrees.
    attitude_error_deg: RmsMax,
    /// Altitude error against the setpoint, RMS and max, m.
    altitude_error_m: RmsMax,
    /// Horizontal drift from the start while hovering, m.
    drift_m: f64,
    /// Only for a mission that judges it (a disturbance-rejection criterion).
    #[serde(skip_serializing_if = "Option::is_none")]
    position_error_m: Option<RmsMax>,
    /// Hover roll/pitch body rate RMS above `quality::OSCILLATION_HZ`, °/s.
    oscillation_dps: f64,
    /// Hover motor commands' total variation per second, 1/s.
    motor_variation_per_s: f64,
    /// Attitude error during the roll and pitch steps (absent: none flown).
    #[serde(skip_serializing_if = "Option::is_none")]
    step_tracking_deg: Option<RmsMax>,
    /// Time with a motor command saturated, s.
    saturation_s: f64,
    /// Time in the air, s.
    airborne_s: f64,
    /// When it landed, s; null when it did not.
    landed_s: Option<f64>,
    /// The envelope the flight was judged against, and its excursions.
    envelope: EnvelopeView,
    /// The attitude steps of the mission and how they were tracked.
    steps: Vec<StepView>,
    /// Whether the flight met every criterion of its mission.
    criteria_met: bool,
    /// The criteria it did not meet, in words.
    failures: &'a [String],
    /// Wall-clock seconds the flight took.
    seconds: f64,
}

#[derive(Serialize, schemars::JsonSchema)]
struct StepView {
    axis: &'static str,
    at_s: f64,
    to_deg: f64,
    tracked: ResponseView,
    #[serde(rename = "true")]
    truth: ResponseView,
    drift_deg: f64,
    /// The true overshoot the step was judged against, a fraction: the
    /// criterion's, plus in turbulence the hover's tracked error over the
    /// step's span.
    overshoot_limit: f64,
}

#[derive(Serialize, schemars::JsonSchema)]
struct ResponseView {
    rise_s: f64,
    overshoot: f64,
    settling_s: f64,
}

impl From<&StepResponse> for ResponseView {
    fn from(x: &StepResponse) -> Self {
        ResponseView {
            rise_s: x.rise_s,
            overshoot: x.overshoot,
            settling_s: x.settling_s,
        }
    }
}

fn to_json<'a>(
    spec: &'a Spec,
    report: &Report,
    s: &'a Setup,
    f: &Flight,
    obs: &[ChainObs],
    failures: &'a [String],
    seconds: f64,
) -> FlyView<'a> {
    let q = &f.quality;
    let steps = q.steps.iter().map(|st| StepView {
        axis: st.axis.name(),
        at_s: st.at_s,
        to_deg: st.to_deg,
        tracked: (&st.tracked).into(),
        truth: (&st.truth).into(),
        drift_deg: st.drift_deg,
        overshoot_limit: st.overshoot_limit(&s.mission.criteria),
    });
    let flight = FlightView {
        vehicle: &s.preset.name,
        mission: &s.mission.name,
        world: s.mission.world.describe(),
        duration_s: s.horizon as f64 * 1e-9,
        crashed: q.crashed,
        crashed_s: q.crashed_s,
        attitude_error_deg: (&q.attitude_error_deg).into(),
        altitude_error_m: (&q.altitude_error_m).into(),
        drift_m: q.drift_m,
        position_error_m: s
            .mission
            .criteria
            .position_rms_m
            .map(|_| (&q.position_error_m).into()),
        oscillation_dps: q.oscillation_dps,
        motor_variation_per_s: q.motor_variation_per_s,
        step_tracking_deg: (q.step_tracking_deg.count > 0).then(|| (&q.step_tracking_deg).into()),
        saturation_s: q.saturation_s,
        airborne_s: q.airborne_s,
        landed_s: q.landed_s,
        envelope: q.into(),
        steps: steps.collect(),
        criteria_met: failures.is_empty(),
        failures,
        seconds,
    };
    FlyView {
        report: simulate::observations_view(spec, report, obs),
        flight,
    }
}
