//! `rtpipe fly`: the flight controller's task code on the simulated
//! schedule, flying a simulated quadrotor (software in the loop).
//!
//! Each task of the spec runs the body its `body = "..."` names
//! (`rtpipe_flight::tasks`); the simulator decides when every job reads and
//! publishes, and the co-simulated world (`Cosim`) is sampled and actuated
//! at exactly those instants. The report holds the flight's quality against
//! the mission and, as in the paper's Fig. 12, the observed reaction and
//! freshness of every chain against the bounds.

mod args;
mod report;
mod sweep;

pub use args::FlyArgs;

use crate::command::{self, Answer, Hooks};
use crate::output;
use crate::plot;
use crate::report::samples::{self, SamplesFile};
use rtpipe_fly::{fly_with_progress, setup, Flight, Request, Setup, Watch};
use rtpipe_model::{Diagnostic, Spec};
use rtpipe_printer::{Cell, Column, Kind, Table};
use rtpipe_sim::observe::{observe, response_violations, ChainObs};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Runs `f` in a thread of its own while a progress bar over the simulated
/// time (`horizon` ns, read from the atomic `f` publishes to) shows the
/// fraction done and the time left on stderr (hidden when stderr is not a
/// terminal). A panic of `f` goes on in the caller's thread with its
/// payload.
fn with_progress_bar<T: Send>(
    msg: String,
    horizon: i64,
    f: impl FnOnce(Arc<AtomicU64>) -> T + Send,
) -> T {
    let done = Arc::new(AtomicU64::new(0));
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(u64::try_from(horizon).unwrap_or(0) / 1_000_000),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg} [{bar:30}] {pos}/{len} ms simulated, {elapsed_precise} elapsed, ETA {eta}",
    ) {
        pb.set_style(style);
    }
    pb.set_message(msg);
    let (tx, rx) = std::sync::mpsc::channel();
    let out = std::thread::scope(|scope| {
        let for_worker = Arc::clone(&done);
        scope.spawn(move || {
            let flown = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(for_worker)));
            let _ = tx.send(flown);
        });
        loop {
            match rx.recv_timeout(std::time::Duration::from_millis(50)) {
                Ok(v) => break Some(v),
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    // `--samples` is written as the flight goes.
                    samples::stop_if_interrupted(|| pb.finish_and_clear());
                    pb.set_position(done.load(Ordering::Relaxed) / 1_000_000);
                }
                // The worker panicked (main's hook ends the process first).
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break None,
            }
        }
    });
    pb.finish_and_clear();
    match out {
        Some(Ok(v)) => v,
        Some(Err(payload)) => std::panic::resume_unwind(payload),
        None => unreachable!("the flight thread ended without a result"),
    }
}

/// Every (vehicle, mission) `a` asks for, checked: the first is the
/// flight's (one flight takes one of each; a sweep flies every timing on
/// each of them).
fn setups_of(spec: &Spec, a: &FlyArgs) -> Result<Vec<Setup>, Diagnostic> {
    let (vehicles, missions) = (a.vehicles(), a.missions());
    let mut out = Vec::new();
    for v in &vehicles {
        for m in &missions {
            out.push(setup_of(spec, a, v, m)?);
        }
    }
    Ok(out)
}

/// The flight of `vehicle` on `mission` that `a` asks for, checked.
fn setup_of(spec: &Spec, a: &FlyArgs, vehicle: &str, mission: &str) -> Result<Setup, Diagnostic> {
    let horizon = match &a.duration {
        Some(d) => Some(
            command::parse_time(spec, d)
                .and_then(|h| {
                    (h > 0)
                        .then_some(h)
                        .ok_or_else(|| "the flight must last a positive time".to_string())
                })
                .map_err(|why| {
                    Diagnostic::error(
                        format!("invalid value `{d}` for --duration: {why}"),
                        format!(
                            "write a positive time up to {:.0} s (about 104 days), like --duration 30s",
                            rtpipe_model::MAX_TIME as f64 * 1e-9
                        ),
                    )
                })?,
        ),
        None => None,
    };
    let r = Request {
        spec_path: &a.spec,
        vehicle,
        mission,
        horizon,
        seed: a.seed,
    };
    let mut s = setup(spec, &r)?;
    // `--samples` streams its rows; `--log` reads the job log.
    s.log_jobs = a.log.is_some();
    s.keep_trace = a.log.is_some() || a.plot.is_some();
    if let Some(t) = a.turbulence {
        s.mission.world.turbulence = t;
    }
    Ok(s)
}

pub fn run(a: &FlyArgs) -> ExitCode {
    let spec = match command::load(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match execute(&spec, a, Hooks::default()) {
        Ok(answer) => answer.emit(),
        Err(b) => command::fail(b),
    }
}

/// `fly` (one flight, or `--sweep`) on a loaded spec, with `hooks`' extra
/// row sink and stop flag (a flight checks it as it goes, a sweep before
/// each flight; once it is set, the answer is [`Answer::stopped`]).
pub fn execute(spec: &Spec, a: &FlyArgs, hooks: Hooks) -> Result<Answer, Diagnostic> {
    a.validate()?;
    let mut setups = setups_of(spec, a)?.into_iter();
    let Some(s) = setups.next() else {
        unreachable!("a list of vehicles and one of missions have one name each at least")
    };
    check_outputs(a)?;
    if a.sweep {
        let also: Vec<Setup> = setups.collect();
        return sweep::execute(spec, (&s, &also), a, hooks.stop.as_deref());
    }
    // The phase draw of the sweep's and `design --fly`'s flights, one home.
    let s = rtpipe_fly::phases::phased(spec, &s, a.phase);
    let msg = format!(
        "flying {} ({}, mission {}) for {:.1} s",
        spec.name,
        s.preset.name,
        s.mission.name,
        s.horizon as f64 * 1e-9
    );
    let started = std::time::Instant::now();
    let samples = SamplesFile::open(a.samples.as_ref(), &a.spec, spec, &hooks)?;
    let sink = command::tee(samples.as_ref().map(SamplesFile::sink), hooks.rows);
    let stop = hooks.stop.as_deref();
    let flown = with_progress_bar(msg, s.horizon, |p| {
        let mut check = |_| !Hooks::stopped(stop);
        let watch = Watch {
            progress: Some(p),
            check: Some(&mut check),
        };
        fly_with_progress(spec, &s, a.exec.model(), watch, sink)
    })?;
    let Some(flight) = flown else {
        return Ok(Answer::stopped());
    };
    let seconds = started.elapsed().as_secs_f64();
    let report = rtpipe_analysis::analyze(spec);
    let obs = observe(&report, &flight.sim);
    let written = write_outputs(spec, a, &flight, &obs, samples);
    let failures = flight.quality.failures(&s.criteria());
    let over_sound: usize = obs.iter().map(ChainObs::over_sound).sum();
    let late_rt = response_violations(&report, &flight.sim);
    let view = report::FlightReport {
        spec,
        report: &report,
        setup: &s,
        flight: &flight,
        obs: &obs,
        failures: &failures,
        seconds,
    };
    let out = command::render(&view, a.output.chosen())?;
    let mut notes = Vec::new();
    if over_sound > 0 || !late_rt.is_empty() {
        notes.push(format!("error: SOUND BOUND EXCEEDED: {over_sound} sample(s) above a sound chain bound (a bug in the analysis or the simulator)"));
    }
    let status = u8::from(!notes.is_empty() || !failures.is_empty());
    let answer = Answer {
        report: out,
        notes,
        status,
    };
    Ok(answer.after_write(written))
}

/// The flight's columns, each with its unit (the chains' latency columns
/// follow: [`latency_columns`]).
const LOG_COLUMNS: [&str; 29] = [
    "time_s",
    "sp_roll_deg",
    "sp_pitch_deg",
    "sp_yaw_rate_dps",
    "sp_throttle",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
    "est_roll_deg",
    "est_pitch_deg",
    "est_yaw_deg",
    "rate_x_dps",
    "rate_y_dps",
    "rate_z_dps",
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "alt_target_m",
    "motor1",
    "motor2",
    "motor3",
    "motor4",
    "armed",
    "on_ground",
    "crashed",
    "battery_v",
];

/// A chain's latency as a step function of time: the value of the latest
/// observation that ended at or before each trace instant. `series` holds
/// (instant the value became known, value) in time order, from the job log
/// (`--log` keeps it: the per-sample record only where it is asked for).
struct LatencyColumn {
    series: Vec<(i64, i64)>,
    next: usize,
}

impl LatencyColumn {
    fn at(&mut self, t: i64) -> Option<i64> {
        while self.next < self.series.len() && self.series[self.next].0 <= t {
            self.next += 1;
        }
        self.next.checked_sub(1).map(|k| self.series[k].1)
    }
}

/// Two columns per chain, `LABEL_reaction_ms` and `LABEL_freshness_ms`,
/// the chain's label as it is (the CSV printer quotes it where it must).
/// Chains that share a label are told apart by their place in the spec:
/// `LABEL#K_reaction_ms`, K counted from 1.
fn latency_columns(labels: &[String]) -> Vec<Column> {
    let mut out = Vec::new();
    for (k, label) in labels.iter().enumerate() {
        let shared = labels.iter().filter(|l| *l == label).count() > 1;
        let name = if shared {
            format!("{label}#{}", k + 1)
        } else {
            label.clone()
        };
        for what in ["reaction", "freshness"] {
            out.push(Column::new(format!("{name}_{what}_ms"), Kind::Float));
        }
    }
    out
}

/// The `--log` table: a row per trace point, the chains' latencies as
/// they were last observed.
fn log_table(spec: &Spec, f: &Flight) -> Result<Table, Diagnostic> {
    let labels: Vec<String> = (0..spec.chains.len())
        .map(|k| spec.chain_label(k))
        .collect();
    let flags = ["armed", "on_ground", "crashed"];
    let columns = LOG_COLUMNS.map(|n| {
        let kind = if flags.contains(&n) {
            Kind::UInt
        } else {
            Kind::Float
        };
        Column::new(n, kind)
    });
    let columns = columns
        .into_iter()
        .chain(latency_columns(&labels))
        .collect();
    let mut table = Table::new("log", columns).map_err(|e| {
        Diagnostic::error(
            format!("--log: {e}"),
            "rename one of the chains (`name = ...`) so that their labels differ",
        )
    })?;
    let mut cols = Vec::new();
    for rows in rtpipe_joblog::sample_rows(spec, &f.sim.jobs) {
        let reaction = rows.iter().filter_map(|r| Some((r.first?, r.reaction()?)));
        let freshness = rows.iter().filter_map(|r| Some((r.last?, r.freshness()?)));
        cols.push(LatencyColumn {
            series: reaction.collect(),
            next: 0,
        });
        cols.push(LatencyColumn {
            series: freshness.collect(),
            next: 0,
        });
    }
    for p in &f.trace {
        let mut row = trace_cells(p);
        let t = i64::try_from(p.t_ns).unwrap_or(i64::MAX);
        row.extend(cols.iter_mut().map(|c| match c.at(t) {
            Some(v) => Cell::Fixed(v as f64 * 1e-6, 6),
            None => Cell::Empty,
        }));
        table.push(row);
    }
    Ok(table)
}

/// One trace point's cells, in [`LOG_COLUMNS`]' order.
fn trace_cells(p: &rtpipe_flight::trace::TracePoint) -> Vec<Cell> {
    let d = f64::to_degrees;
    let vals = [
        p.t_ns as f64 * 1e-9,
        d(p.sp.roll),
        d(p.sp.pitch),
        d(p.sp.yaw_rate),
        p.sp.throttle,
        d(p.euler.roll),
        d(p.euler.pitch),
        d(p.euler.yaw),
        d(p.est.roll),
        d(p.est.pitch),
        d(p.est.yaw),
        d(p.rate.x),
        d(p.rate.y),
        d(p.rate.z),
        p.pos.x,
        p.pos.y,
        p.pos.z,
        p.vel.x,
        p.vel.y,
        p.vel.z,
    ];
    let mut row: Vec<Cell> = vals.iter().map(|&v| Cell::Fixed(v, 6)).collect();
    row.push(p.alt_target.map_or(Cell::Empty, |a| Cell::Fixed(a, 3)));
    row.extend(p.motors.iter().map(|&m| Cell::Fixed(m, 5)));
    row.extend([p.armed, p.on_ground, p.crashed].map(|b| Cell::UInt(u64::from(b))));
    row.push(Cell::Fixed(p.voltage, 4));
    row
}

/// The output paths, checked before flying (they are checked again when
/// written): a bad one is reported at once, not after the flight.
fn check_outputs(a: &FlyArgs) -> Result<(), Diagnostic> {
    if let Some(dir) = &a.plot {
        output::check_dir(dir)?;
    }
    let mut outs = Vec::new();
    for (flag, p) in [
        ("--log", &a.log),
        ("--samples", &a.samples),
        ("--write-limits", &a.write_limits),
    ] {
        if let Some(p) = p {
            outs.push(output::prepare(flag, p, &a.spec, None)?);
        }
    }
    output::distinct(&outs)
}

/// Renders `--plot` and `--log` and writes them all or none, then puts
/// `--samples` (written as the flight went) in place.
fn write_outputs(
    spec: &Spec,
    a: &FlyArgs,
    f: &Flight,
    obs: &[ChainObs],
    samples: Option<SamplesFile>,
) -> Result<(), Diagnostic> {
    let mut files: Vec<(&'static str, PathBuf, String)> = Vec::new();
    if let Some(dir) = &a.plot {
        output::ensure_dir(dir)?;
        let svgs = [
            ("attitude.svg", plot::flight_attitude(&f.trace)),
            ("altitude.svg", plot::flight_altitude(&f.trace)),
            ("motors.svg", plot::flight_motors(&f.trace)),
            ("latency.svg", plot::fig9(spec, obs, "observed in flight")),
        ];
        for (name, svg) in svgs {
            let svg = svg.map_err(|e| Diagnostic::error(format!("cannot draw {name}: {e}"), ""))?;
            files.push(("--plot", dir.join(name), svg));
        }
    }
    if let Some(path) = &a.log {
        let log = log_table(spec, f)?;
        files.push(("--log", path.clone(), rtpipe_printer::csv::table(&log)));
    }
    samples::write_with(&a.spec, &files, samples).map(|_| ())
}

impl command::Registered for FlyArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn inputs(&self) -> Vec<(&'static str, &std::path::Path)> {
        let mut out = command::world_inputs(&self.vehicle, &self.mission);
        out.extend(self.criterion.iter().map(|c| ("--criterion", c.as_path())));
        out
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        let spec = call.spec()?;
        if let Some(d) = command::missing_periods(spec) {
            return Err(d);
        }
        execute(spec, self, call.hooks).map(command::Done::from)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(report::FlyView<'static>)
}

/// The JSON Schema of `fly --sweep --json`'s report.
pub fn sweep_json_schema() -> schemars::Schema {
    sweep::json_schema()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(labels: &[&str]) -> Vec<String> {
        let labels: Vec<String> = labels.iter().map(|l| l.to_string()).collect();
        latency_columns(&labels)
            .into_iter()
            .map(|c| c.name)
            .collect()
    }

    #[test]
    fn chain_labels_name_their_columns_as_they_are() {
        // Once both were `gyro_path_...`: the log had one column twice.
        assert_eq!(
            names(&["gyro path", "gyro-path"]),
            [
                "gyro path_reaction_ms",
                "gyro path_freshness_ms",
                "gyro-path_reaction_ms",
                "gyro-path_freshness_ms",
            ]
        );
    }

    #[test]
    fn chains_of_one_label_are_told_apart_by_their_place() {
        let n = names(&["a>b", "c", "a>b"]);
        assert_eq!(n[0], "a>b#1_reaction_ms");
        assert_eq!(n[2], "c_reaction_ms");
        assert_eq!(n[5], "a>b#3_freshness_ms");
        let columns = latency_columns(&["x".into(), "x".into()]);
        assert!(Table::new("log", columns).is_ok());
    }
}
