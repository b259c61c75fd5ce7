//! # rtpipe-fly
//!
//! The flight controller on the simulated schedule: builds each task's body
//! from the spec (`body = "..."`, see `rtpipe_flight::tasks`), runs them with
//! `rtpipe_sim::simulate_bodies` while the co-simulated world (`Cosim`) is
//! sampled and actuated at exactly the instants the schedule gives, and
//! rates the flight (`rtpipe_flight::quality`). `rtpipe fly` and the flight
//! benchmark use it; the analysis and the simulator know nothing of it.
#![deny(missing_docs)]

pub mod confidence;
pub mod phases;
/// The timing sweep: flights over scaled periods and added delays.
pub mod sweep;

use rtpipe_body::{Body, Job, Stamped};
use rtpipe_flight::battery::BatteryAlert;
use rtpipe_flight::preset::{Preset, BUILTIN};
use rtpipe_flight::quality::FlightQuality;
use rtpipe_flight::radio::{Mission, BUILTIN_MISSIONS};
use rtpipe_flight::tasks::{body, BodyKind, Cosim, CosimConfig, Value};
use rtpipe_flight::trace::TracePoint;
use rtpipe_flight::ConfigError;
use rtpipe_joblog::SimResult;
use rtpipe_model::input::shown_name;
use rtpipe_model::{Diagnostic, Nanos, Spec};
use rtpipe_sim::{simulate_bodies_with_progress, ExecModel, Phasing, SimConfig};
use std::path::Path;
use std::sync::atomic::AtomicU64;
use std::sync::Arc;

/// Time flown after the mission's last step when no duration is given.
pub const AFTER_LAST_STEP_NS: Nanos = 5_000_000_000;

/// Everything a flight needs besides the spec.
#[derive(Clone)]
pub struct Setup {
    /// The vehicle.
    pub preset: Preset,
    /// What it flies.
    pub mission: Mission,
    /// The flight-controller role of each task's body, in declaration order
    /// (`None`: a task without a body).
    pub kinds: Vec<Option<BodyKind>>,
    /// How long to fly (simulated ns).
    pub horizon: Nanos,
    /// The world's options (noise, disturbances).
    pub world: CosimConfig,
    /// Keep the job log (`Flight::sim.jobs`), for per-sample figures.
    pub log_jobs: bool,
    /// Keep every trace point (`Flight::trace`, for plots and logs); off,
    /// the trace is empty and a flight's memory does not grow with its
    /// length (its quality is assessed as it flies).
    pub keep_trace: bool,
    /// Measure the chains' latencies (`Flight::sim.chains`); off, the
    /// flight is flown on the spec without its chains, which schedules and
    /// flies the same (chains only observe) at about a fifth less cost,
    /// for callers that want only its quality (`--sweep`).
    pub track_chains: bool,
    /// Each task's first release (`None`: every task at 0, the spec's
    /// known offsets kept); a phase of the flight ([`phases::phased`]).
    pub offsets: Option<Vec<Nanos>>,
}

impl Setup {
    /// What the flight is judged by: the mission's criteria, with the
    /// vehicle's own tolerances where its world has turbulence (a preset's
    /// `[criteria]`).
    pub fn criteria(&self) -> rtpipe_flight::quality::Criteria {
        self.preset
            .criteria
            .in_world(self.mission.criteria, &self.mission.world)
    }
}

/// The outcome of one flight.
pub struct Flight {
    /// The simulation of the schedule it flew on.
    pub sim: SimResult,
    /// The vehicle's state over time.
    pub trace: Vec<TracePoint>,
    /// How well it flew.
    pub quality: FlightQuality,
    /// When the housekeeping raised each battery alert level, ns.
    pub alerts: Vec<(u64, BatteryAlert)>,
}

fn vehicle(v: &str) -> Result<Preset, Diagnostic> {
    let help = || {
        format!(
            "name a built-in preset ({}) or a preset file",
            BUILTIN.join(", ")
        )
    };
    if BUILTIN.contains(&v) {
        return Preset::builtin(v)
            .map_err(|e| Diagnostic::error(format!("--vehicle {v}: {e}"), help()));
    }
    Preset::from_file(Path::new(v)).map_err(|e| from_file("--vehicle", &e, &help()))
}

/// A file's error as the error of the flag that named it:
/// `--mission m.toml:3:5: message`, with the file's help or else `help`.
pub fn from_file(flag: &str, e: &rtpipe_model::SpecError, help: &str) -> Diagnostic {
    let d = e.located();
    let help = d.help.unwrap_or_else(|| help.to_string());
    Diagnostic::error(format!("{flag} {}", d.message), help)
}

fn mission(m: &str) -> Result<Mission, Diagnostic> {
    let help = format!(
        "name a built-in mission ({}) or a mission file",
        BUILTIN_MISSIONS.join(", ")
    );
    if BUILTIN_MISSIONS.contains(&m) {
        return Mission::builtin(m)
            .map_err(|e| Diagnostic::error(format!("--mission {m}: {e}"), help));
    }
    Mission::from_file(Path::new(m)).map_err(|e| from_file("--mission", &e, &help))
}

/// The role of every task from its `body`; the pipeline must be complete.
pub fn body_kinds(spec: &Spec, path: &Path) -> Result<Vec<Option<BodyKind>>, Diagnostic> {
    let mut kinds = Vec::with_capacity(spec.tasks.len());
    for t in &spec.tasks {
        let r = match &t.body {
            None => None,
            Some(b) => Some(BodyKind::parse(b).ok_or_else(|| {
                Diagnostic::error(
                    format!(
                        "{}: task `{}` names an unknown body `{}`",
                        path.display(),
                        shown_name(&t.name),
                        shown_name(b)
                    ),
                    format!("use one of: {}", BodyKind::names()),
                )
            })?),
        };
        kinds.push(r);
    }
    check_complete(path, &kinds)?;
    check_wiring(spec, path, &kinds)?;
    Ok(kinds)
}

/// The tasks of one of the flight controllers of
/// [`BodyKind::STRUCTURES`] are all there; when none is complete, the
/// nearest (fewest missing; Cleanflight's on a tie) names its first gap.
fn check_complete(path: &Path, kinds: &[Option<BodyKind>]) -> Result<(), Diagnostic> {
    let missing = |s: &[BodyKind]| -> Vec<BodyKind> {
        s.iter()
            .copied()
            .filter(|k| !kinds.contains(&Some(*k)))
            .collect()
    };
    let nearest = BodyKind::STRUCTURES
        .iter()
        .map(|s| missing(s))
        .min_by_key(Vec::len)
        .unwrap_or_default();
    match nearest.first() {
        None => Ok(()),
        Some(need) => Err(Diagnostic::error(
            format!(
                "{}: no task has body = \"{}\", so the flight controller is incomplete",
                path.display(),
                need.name()
            ),
            "give the tasks of the critical path their bodies, as examples/cleanflight.toml (or examples/betaflight-8k.toml) does",
        )),
    }
}

/// Every body's inputs are wired: a task whose body needs another role's
/// output reads a task of that role (else that input is always missing and
/// the vehicle flies on defaults, e.g. zero motor demand).
fn check_wiring(spec: &Spec, path: &Path, kinds: &[Option<BodyKind>]) -> Result<(), Diagnostic> {
    for (t, kind) in spec.tasks.iter().zip(kinds) {
        let Some(kind) = kind else { continue };
        for &roles in kind.needs() {
            let gives = |k: &Option<BodyKind>| k.is_some_and(|k| roles.contains(&k));
            if t.reads.iter().any(|&j| kinds.get(j).is_some_and(gives)) {
                continue;
            }
            let found = spec.tasks.iter().zip(kinds).find(|(_, k)| gives(k));
            let source = found.map_or(String::new(), |(s, _)| s.name.clone());
            // The role the spec has, else the first that could give it.
            let need = found.and_then(|(_, k)| *k).unwrap_or(roles[0]);
            return Err(Diagnostic::error(
                format!(
                    "{}: task `{}` (body {}) reads no task with body = \"{}\", so its input from it would always be missing",
                    path.display(),
                    t.name,
                    kind.name(),
                    need.name()
                ),
                if source.is_empty() {
                    format!("add a task with body = \"{}\" and list it in `{}`'s reads", need.name(), t.name)
                } else {
                    format!("add \"{source}\" to the reads of task `{}`", t.name)
                },
            ));
        }
    }
    Ok(())
}

/// What to fly: the vehicle (a built-in preset name or a preset file), the
/// mission (`hover`, `steps`, `paper` or a mission file), how long (default: 5 s after
/// the mission's last step) and the seed of the noise and execution times.
pub struct Request<'a> {
    /// The spec's file, named in diagnostics.
    pub spec_path: &'a Path,
    /// A built-in preset name or a preset file.
    pub vehicle: &'a str,
    /// `hover`, `steps`, `paper` or a mission file.
    pub mission: &'a str,
    /// How long to fly (default: 5 s after the mission's last step).
    pub horizon: Option<Nanos>,
    /// Seed of the noise and execution times.
    pub seed: u64,
}

/// Checks the request against the spec before anything runs.
pub fn setup(spec: &Spec, r: &Request) -> Result<Setup, Diagnostic> {
    let kinds = body_kinds(spec, r.spec_path)?;
    let preset = vehicle(r.vehicle)?;
    let mission = mission(r.mission)?;
    let horizon = r
        .horizon
        .unwrap_or(mission.end_ns() as Nanos + AFTER_LAST_STEP_NS);
    if horizon <= 0 {
        return Err(Diagnostic::error(
            format!("the flight must last a positive time, found {horizon} ns"),
            "give a positive duration",
        ));
    }
    let world = gyro_at_data_ready_rate(spec, &kinds, CosimConfig::new(r.seed));
    Ok(Setup {
        preset,
        mission,
        kinds,
        horizon,
        world,
        log_jobs: false,
        keep_trace: true,
        track_chains: true,
        offsets: None,
    })
}

/// The cascade's gyro (`gyro_filter`) is read at the sensor's data-ready
/// rate, so the sensor's output data rate is that task's rate (rounded up:
/// every read on time gets a sample of its own), not the default IMU's
/// 3200 Hz, which would hand an 8 kHz loop the same sample two or three
/// times. Cleanflight's `gyro` polls the default IMU as before.
fn gyro_at_data_ready_rate(
    spec: &Spec,
    kinds: &[Option<BodyKind>],
    mut world: CosimConfig,
) -> CosimConfig {
    let gyro = kinds.iter().position(|k| *k == Some(BodyKind::GyroFilter));
    let period = gyro.and_then(|i| spec.activation_period(i));
    if let Some(p) = period
        .and_then(|p| u64::try_from(p).ok())
        .filter(|&p| p > 0)
    {
        world.imu.gyro_odr_hz = 1_000_000_000u64.div_ceil(p);
    }
    world
}

/// Why the body of task `task` could not be built, blaming what is at
/// fault: the task's period when it has none a flight task can run at,
/// else the preset's key (a filter cut-off above the Nyquist frequency of
/// the task's rate is the preset's setting, whatever the period: the
/// preset file and the key are named, and both ways out).
fn body_error(
    task: &str,
    role: BodyKind,
    period: Nanos,
    preset: &Preset,
    e: &ConfigError,
) -> Diagnostic {
    if e.field == "period" {
        return Diagnostic::error(
            format!("task `{task}` (body {}): {e}", role.name()),
            "give it a fixed period the body can run at",
        );
    }
    // Three decimals at most: 10.079 ms, not 10.079367999999999.
    let short = |x: f64| (x * 1e3).round() / 1e3;
    let (ms, hz) = (short(period as f64 * 1e-6), short(1e9 / period as f64));
    Diagnostic::error(
        format!(
            "{}: `{}` does not suit task `{task}` (body {}), which runs every {ms} ms ({hz} Hz): {}",
            preset.source,
            e.field,
            role.name(),
            e.reason
        ),
        format!(
            "change `{}` in {} to suit the task's rate, or give task `{task}` a period it suits",
            e.field, preset.source
        ),
    )
}

/// A task without a body: it runs (its timing matters) but computes nothing.
fn idle(_: &Job, _: &[Option<Stamped<Value>>], _: Option<Value>) -> Value {
    Value::Nothing
}

/// Flies `spec` as `setup` says: bodies on the simulated schedule, the
/// world co-simulated at their read and publish instants.
pub fn fly(spec: &Spec, s: &Setup, exec: ExecModel) -> Result<Flight, Diagnostic> {
    match fly_with_progress(spec, s, exec, Watch::default(), None)? {
        Some(flight) => Ok(flight),
        None => unreachable!("an unwatched flight is never abandoned"),
    }
}

/// One body per task of a spec, in task order.
pub type Bodies = Vec<Box<dyn Body<Value>>>;

/// The body of every task (an idle one for a task without `body`) and the
/// world, both for `s`: what every executor of a flight needs.
fn bodies_and_world(spec: &Spec, s: &Setup) -> Result<(Bodies, Cosim), Diagnostic> {
    let mut bodies: Vec<Box<dyn Body<Value>>> = Vec::with_capacity(spec.tasks.len());
    for (i, (t, role)) in spec.tasks.iter().zip(&s.kinds).enumerate() {
        // A data-triggered body runs at its triggers' rate.
        let period = spec.activation_period(i).unwrap_or(0);
        bodies.push(match role {
            Some(r) => body(*r, period, &s.preset)
                .map_err(|e| body_error(&t.name, *r, period, &s.preset, &e))?,
            None => Box::new(idle),
        });
    }
    let mut world = Cosim::new(&s.preset, s.mission.clone(), s.kinds.clone(), s.world)
        .map_err(|e| Diagnostic::error(format!("--vehicle: {e}"), "check the preset file"))?;
    world.keep_trace = s.keep_trace;
    Ok((bodies, world))
}

/// What a caller watching a flight adds: where to publish the simulated
/// time (ns) as it goes, and a check called with it every
/// `rtpipe_sim::PROGRESS_EVENTS` events, whose `false` abandons the flight
/// (a stop flag).
#[derive(Default)]
pub struct Watch<'a> {
    /// Receives the world's time as it advances (a progress bar).
    pub progress: Option<Arc<AtomicU64>>,
    /// Called with the simulated time every few thousand events; `false`
    /// ends the flight.
    pub check: Option<&'a mut dyn FnMut(i64) -> bool>,
}

/// [`fly`], watched as `watch` says and, with `rows`, handing every
/// chain's sample rows on as they complete
/// (`rtpipe_sim::simulate_with_rows`); `None` when the watch's check
/// abandoned it.
pub fn fly_with_progress(
    spec: &Spec,
    s: &Setup,
    exec: ExecModel,
    watch: Watch<'_>,
    rows: Option<rtpipe_joblog::RowSink>,
) -> Result<Option<Flight>, Diagnostic> {
    let seed = s.world.seed;
    let (mut bodies, mut world) = bodies_and_world(spec, s)?;
    if let Some(p) = watch.progress {
        world.report_progress(p);
    }
    let cfg = SimConfig {
        horizon: s.horizon,
        seed,
        phasing: match &s.offsets {
            Some(v) => Phasing::Given(v.clone()),
            None => Phasing::Sync,
        },
        exec,
        log_jobs: s.log_jobs,
        jitter: rtpipe_sim::Jitter::Uniform,
    };
    let chainless;
    let spec = if s.track_chains {
        spec
    } else {
        chainless = Spec {
            chains: Vec::new(),
            ..spec.clone()
        };
        &chainless
    };
    let mut unwatched = |_| true;
    let check = watch.check.unwrap_or(&mut unwatched);
    let flown = simulate_bodies_with_progress(spec, &cfg, &mut bodies, &mut world, check, rows)
        .map_err(|e| {
            Diagnostic::error(
                format!("cannot simulate: {e}"),
                "give every task a fixed positive period",
            )
        })?;
    let Some(sim) = flown else {
        return Ok(None);
    };
    world.advance(u64::try_from(s.horizon).unwrap_or(0));
    let quality = world.assessor.clone().finish();
    Ok(Some(Flight {
        sim,
        trace: std::mem::take(&mut world.trace),
        quality,
        alerts: std::mem::take(&mut world.alerts),
    }))
}

/// The bodies and the world of a flight of `duration` ns on real threads:
/// what the world records in that span is reserved now
/// ([`Cosim::reserve`]), so that no job grows a vector (copying it,
/// faulting in fresh locked pages) under the world's lock. Measured before:
/// gyro jobs of 230 to 764 µs, against a median of 1.1 µs, at 4,096, 8,192
/// and 16,384 jobs. [`fly_real`] runs them; `tests/no_alloc.rs` holds their
/// periodic path to no allocation.
pub fn real_time_parts(
    spec: &Spec,
    s: &Setup,
    duration: Nanos,
) -> Result<(Bodies, Cosim), Diagnostic> {
    let (bodies, mut world) = bodies_and_world(spec, s)?;
    world.reserve(u64::try_from(duration).unwrap_or(0));
    Ok((bodies, world))
}

/// Flies `spec` for real: the same bodies on real threads
/// (`rtpipe_runtime::run`, one per task, under `cfg.policy`), the world
/// behind a priority-inheritance lock (it is not thread-safe) sensed and actuated at the true
/// instants, relative to the run's epoch. `cfg.duration` replaces the
/// setup's horizon. Returns the flight and the run's figures.
pub fn fly_real(
    spec: &Spec,
    s: &Setup,
    cfg: &rtpipe_runtime::RunConfig,
) -> Result<(Flight, rtpipe_runtime::RunResult), Diagnostic> {
    let (bodies, world) = real_time_parts(spec, s, cfg.duration)?;
    // Priority inheritance: a background task preempted while it holds the
    // world must not delay the gyro for longer than its critical section.
    let world = rtpipe_runtime::PiMutex::new(world).map_err(|e| {
        Diagnostic::error(
            format!("cannot create a priority-inheritance mutex for the world: {e}"),
            "this C library lacks PTHREAD_PRIO_INHERIT; run `rtpipe fly` (simulated threads) instead",
        )
    })?;
    let res = rtpipe_runtime::run(spec, cfg, bodies, Some(&world)).map_err(|e| e.diagnostic)?;
    let mut world = world.into_inner();
    // The world's last call was at the last publish (or read) of the run.
    let last = res.sim.jobs.iter().map(|j| j.finish).max().unwrap_or(0);
    let end = u64::try_from(cfg.duration.max(last)).unwrap_or(0);
    world.advance(end);
    let quality = world.assessor.clone().finish();
    let flight = Flight {
        sim: res.sim.clone(),
        trace: std::mem::take(&mut world.trace),
        quality,
        alerts: std::mem::take(&mut world.alerts),
    };
    Ok((flight, res))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtpipe_analysis::Anchor;
    use rtpipe_flight::math::Vec3;
    use rtpipe_flight::quality::Axis;
    use rtpipe_flight::quality::Criteria;
    use rtpipe_sim::observe::{observe, response_violations};
    use std::path::PathBuf;

    fn cleanflight() -> (Spec, PathBuf) {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
        match Spec::load(&p) {
            Ok(s) => (s, p),
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn a_flight_streams_the_rows_its_job_log_would_give() {
        use std::sync::{Arc, Mutex};
        let (spec, p) = cleanflight();
        let mut s = setup_of(&spec, &p, &["--mission", "hover", "--duration", "6s"]);
        s.log_jobs = true;
        let got = Arc::new(Mutex::new(vec![Vec::new(); spec.chains.len()]));
        let sink = got.clone();
        let f = fly_with_progress(
            &spec,
            &s,
            ExecModel::Uniform,
            Watch::default(),
            Some(Box::new(move |c, r| {
                if let Ok(mut g) = sink.lock() {
                    g[c].push(*r);
                }
            })),
        )
        .unwrap_or_else(|e| panic!("{e}"))
        .unwrap_or_else(|| panic!("an unwatched flight ends"));
        let want = rtpipe_joblog::sample_rows(&spec, &f.sim.jobs);
        let got = got.lock().map(|g| g.clone()).unwrap_or_default();
        assert!(want.iter().all(|c| c.len() > 100), "rows per chain");
        assert_eq!(got, want);
    }

    #[test]
    fn a_watch_check_is_called_as_the_flight_goes_and_can_abandon_it() {
        let (spec, p) = cleanflight();
        let s = setup_of(&spec, &p, &["--mission", "hover", "--duration", "600s"]);
        let mut seen = Vec::new();
        let mut check = |t: i64| {
            seen.push(t);
            seen.len() < 3
        };
        let watch = Watch {
            progress: None,
            check: Some(&mut check),
        };
        let flown = fly_with_progress(&spec, &s, ExecModel::Uniform, watch, None);
        assert!(matches!(flown, Ok(None)), "the flight was not abandoned");
        // Called at rising times, and abandoned at the third call, seconds
        // into the flight, not at its end.
        assert!(seen.len() == 3 && seen[0] < seen[1] && seen[1] < seen[2]);
        assert!(seen[2] < 60_000_000_000, "{seen:?}");
    }

    fn setup_of(spec: &Spec, path: &Path, flags: &[&str]) -> Setup {
        let flag = |name: &str| {
            flags
                .iter()
                .position(|f| *f == name)
                .and_then(|k| flags.get(k + 1))
                .copied()
        };
        let r = Request {
            spec_path: path,
            vehicle: flag("--vehicle").unwrap_or("racer5"),
            mission: flag("--mission").unwrap_or("steps"),
            horizon: flag("--duration")
                .map(|d| d.trim_end_matches('s').parse::<i64>().unwrap_or(0) * 1_000_000_000),
            seed: flag("--seed").and_then(|s| s.parse().ok()).unwrap_or(0),
        };
        setup(spec, &r).unwrap_or_else(|e| panic!("{e}"))
    }

    fn flown(spec: &Spec, s: &Setup) -> Flight {
        fly(spec, s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"))
    }

    /// No observation, from the read or from the event, above a sound bound.
    fn assert_within_sound(spec: &Spec, f: &Flight) {
        let report = rtpipe_analysis::analyze(spec);
        let obs = observe(&report, &f.sim);
        for o in &obs {
            for a in Anchor::ALL {
                let j = o.from(a);
                assert!(j.observed.is_some_and(|x| x.count > 100), "{o:?}");
                assert_eq!(
                    j.over_sound,
                    Some(0),
                    "{} {:?} {a:?}",
                    spec.chain_label(o.chain),
                    o.metric
                );
            }
        }
        assert!(response_violations(&report, &f.sim).is_empty());
    }

    #[test]
    fn table_v_flies_the_steps_mission_with_both_presets() {
        let (spec, path) = cleanflight();
        for vehicle in BUILTIN {
            let s = setup_of(&spec, &path, &["--vehicle", vehicle, "--seed", "7"]);
            let f = flown(&spec, &s);
            let q = &f.quality;
            let failures = q.failures(&Criteria::default());
            assert!(failures.is_empty(), "{vehicle}: {failures:?}");
            assert!(!q.crashed && q.landed_s.is_some(), "{vehicle}: {q:?}");
            assert!(q.attitude_error_deg.rms < 2.0 && q.altitude_error_m.rms < 0.1);
            let judged: Vec<Axis> = q.steps.iter().map(|s| s.axis).collect();
            assert_eq!(
                judged,
                vec![Axis::Roll, Axis::Pitch, Axis::Yaw],
                "{vehicle}"
            );
            for st in q.steps.iter().filter(|s| s.axis != Axis::Yaw) {
                assert!(st.truth.overshoot < 0.2, "{vehicle}: {st:?}");
                assert!(st.tracked.settling_s < 0.5, "{vehicle}: {st:?}");
                assert!(st.truth.rise_s < 0.3, "{vehicle}: {st:?}");
            }
            assert_within_sound(&spec, &f);
        }
    }

    #[test]
    fn table_v_hovers_ten_seconds_with_noise() {
        let (spec, path) = cleanflight();
        for vehicle in BUILTIN {
            let s = setup_of(&spec, &path, &["--vehicle", vehicle, "--mission", "hover"]);
            assert!(s.world.imu.noise);
            let f = flown(&spec, &s);
            let q = &f.quality;
            // The hover mission holds 1 m from 2 s (climb) to 15 s (land):
            // from 5 s on, 10 s of steady hover.
            let hover_s = q.attitude_error_deg.count as f64 * 0.002;
            assert!(hover_s >= 9.9, "{vehicle}: {hover_s} s");
            assert!(q.attitude_error_deg.rms < 2.0, "{vehicle}: {q:?}");
            assert!(q.altitude_error_m.rms < 0.1, "{vehicle}: {q:?}");
            assert!(q.drift_m < 0.5, "{vehicle}: {q:?}");
            assert!(
                q.landed_s.is_some(),
                "{vehicle}: never disarmed on the ground"
            );
        }
    }

    #[test]
    fn recovers_from_a_20_degree_disturbance() {
        let (spec, path) = cleanflight();
        for (vehicle, kick) in [("racer5", 10.0), ("aero1kg", 6.0)] {
            let mut s = setup_of(&spec, &path, &["--vehicle", vehicle, "--mission", "hover"]);
            let j = Vec3::new(s.preset.body.inertia_kg_m2[0] * kick, 0.0, 0.0);
            s.world.impulse = Some((8_000_000_000, j));
            let f = flown(&spec, &s);
            let after = || {
                f.trace
                    .iter()
                    .filter(|p| (8_000_000_000..11_000_000_000).contains(&p.t_ns))
            };
            let peak = after()
                .map(|p| p.euler.roll.to_degrees().abs())
                .fold(0.0, f64::max);
            let level = after()
                .find(|p| p.t_ns > 8_020_000_000 && p.euler.roll.to_degrees().abs() < 2.0)
                .map_or(f64::INFINITY, |p| (p.t_ns - 8_000_000_000) as f64 * 1e-9);
            assert!(peak >= 20.0, "{vehicle}: peak {peak}");
            assert!(level < 0.5, "{vehicle}: back within 2° after {level} s");
            assert!(!f.quality.crashed && f.quality.landed_s.is_some());
        }
    }

    #[test]
    fn same_seed_same_flight() {
        let (spec, path) = cleanflight();
        let s = setup_of(
            &spec,
            &path,
            &["--mission", "hover", "--seed", "3", "--duration", "6s"],
        );
        let (a, b) = (flown(&spec, &s), flown(&spec, &s));
        assert_eq!(a.sim, b.sim);
        assert!(a.trace == b.trace, "same seed, different flights");
        let s4 = setup_of(
            &spec,
            &path,
            &["--mission", "hover", "--seed", "4", "--duration", "6s"],
        );
        assert!(
            flown(&spec, &s4).trace != a.trace,
            "the seed changes nothing"
        );
    }

    #[test]
    fn a_flight_without_its_trace_streams_the_same_quality() {
        // Before, `fly` kept every 2 ms trace point (~0.1 MB per flown
        // second) to assess the flight at the end.
        let (spec, path) = cleanflight();
        let mut s = setup_of(&spec, &path, &["--duration", "30s"]);
        let kept = flown(&spec, &s);
        s.keep_trace = false;
        let streamed = flown(&spec, &s);
        assert!(streamed.trace.is_empty());
        assert_eq!(kept.trace.len(), 15_001);
        assert_eq!(
            format!("{:?}", streamed.quality),
            format!("{:?}", kept.quality)
        );
        let again = rtpipe_flight::quality::assess(&kept.trace, &s.mission);
        assert_eq!(format!("{:?}", again), format!("{:?}", kept.quality));
    }

    #[test]
    fn a_flight_without_its_chains_flies_the_same() {
        let (spec, path) = cleanflight();
        let mut s = setup_of(&spec, &path, &["--duration", "12s", "--seed", "4"]);
        let tracked = flown(&spec, &s);
        s.track_chains = false;
        let untracked = flown(&spec, &s);
        assert!(tracked.sim.chains.iter().all(|c| c.reached > 100));
        assert!(untracked.sim.chains.is_empty());
        assert_eq!(tracked.sim.tasks, untracked.sim.tasks);
        assert_eq!(tracked.sim.events, untracked.sim.events);
        assert_eq!(
            format!("{:?}", tracked.trace),
            format!("{:?}", untracked.trace)
        );
        assert_eq!(
            format!("{:?}", tracked.quality),
            format!("{:?}", untracked.quality)
        );
    }

    #[test]
    fn low_battery_alert_fires_in_flight() {
        let (spec, path) = cleanflight();
        let mut s = setup_of(&spec, &path, &["--mission", "hover", "--duration", "8s"]);
        // A nearly empty pack: the voltage sags below 3.5 V per cell under
        // the hover current.
        s.preset.battery.initial_soc = 0.03;
        let f = flown(&spec, &s);
        assert!(
            f.alerts.iter().any(|&(_, a)| a != BatteryAlert::Ok),
            "no alert: {:?}",
            f.trace.last().map(|p| p.voltage)
        );
        // A full one raises none.
        let full = setup_of(&spec, &path, &["--mission", "hover", "--duration", "8s"]);
        assert!(flown(&spec, &full).alerts.is_empty());
    }

    #[test]
    fn a_missing_wire_is_refused_with_its_place_and_fix() {
        let (mut spec, path) = cleanflight();
        let pid = spec
            .tasks
            .iter()
            .position(|t| t.name == "pid")
            .unwrap_or_else(|| panic!("no pid task"));
        let radio = spec.tasks.iter().position(|t| t.name == "radio");
        spec.tasks[pid].reads.retain(|&j| Some(j) != radio);
        let e = body_kinds(&spec, &path)
            .err()
            .map(|b| b.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("task `pid` (body pid) reads no task with body = \"radio\"")
                && e.contains("add \"radio\" to the reads of task `pid`"),
            "{e}"
        );
    }

    #[test]
    fn the_cascade_is_complete_and_its_gaps_are_named() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/betaflight-8k.toml");
        let mut spec = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
        assert!(body_kinds(&spec, &p).is_ok());
        let task = |spec: &Spec, name: &str| {
            spec.tasks
                .iter()
                .position(|t| t.name == name)
                .unwrap_or_else(|| panic!("no task {name}"))
        };
        // The motor output of the cascade reads the rate PID.
        let (pwm, rate_pid) = (task(&spec, "pwm"), task(&spec, "rate_pid"));
        spec.tasks[pwm].reads.retain(|&j| j != rate_pid);
        let e = body_kinds(&spec, &p)
            .err()
            .map(|b| b.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("task `pwm` (body pwm) reads no task with body = \"rate_pid\"")
                && e.contains("add \"rate_pid\" to the reads of task `pwm`"),
            "{e}"
        );
        // Nearer the cascade than Cleanflight's structure: its gap is named.
        spec.tasks[rate_pid].body = None;
        let e = body_kinds(&spec, &p)
            .err()
            .map(|b| b.to_string())
            .unwrap_or_default();
        assert!(e.contains("no task has body = \"rate_pid\""), "{e}");
    }

    #[test]
    fn incomplete_or_unknown_bodies_are_refused() {
        let (mut spec, path) = cleanflight();
        spec.tasks[0].body = Some("gyroscope".into());
        let e = body_kinds(&spec, &path)
            .err()
            .map(|b| b.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("unknown body `gyroscope`") && e.contains("battery_alert"),
            "{e}"
        );
        spec.tasks[0].body = None;
        let e = body_kinds(&spec, &path)
            .err()
            .map(|b| b.to_string())
            .unwrap_or_default();
        assert!(e.contains("body = \"gyro\""), "{e}");
    }

    #[test]
    fn a_design_under_the_derived_limits_flies_the_steps_mission() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/cleanflight-derived-design.toml");
        let spec = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
        // It meets its own (derived) limits under the sound analysis ...
        let rep = rtpipe_analysis::analyze(&spec);
        assert!(rep.all_ok(), "the design misses its limits");
        // ... and both vehicles fly it within the criteria.
        for vehicle in BUILTIN {
            let s = setup_of(&spec, &p, &["--vehicle", vehicle, "--seed", "2"]);
            let f = flown(&spec, &s);
            let failures = f.quality.failures(&s.criteria());
            assert!(failures.is_empty(), "{vehicle}: {failures:?}");
            assert_within_sound(&spec, &f);
        }
    }
}
