//! `rtpipe run`: the spec on real threads (rtpipe-runtime), measured like
//! `simulate` and held against the same bounds.

use crate::command::{self, fail, parse_time};
use crate::output;
use crate::plot;
use crate::report::analysis::{ReportView, TaskView};
use crate::report::flight::{EnvelopeView, RmsMax};
use crate::report::samples::samples_csv;
use crate::report::{self, time};
use crate::simulate::{chain_table, observations_view, Extended, ObsChain};
use crate::table::Table;
use verdict::Verdict;

mod measure;
mod tables;
mod verdict;
use clap::{Args, ValueEnum};
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_fly::{Flight, Setup};
use rtpipe_joblog::trace::{chrome_trace_with, TraceOptions};
use rtpipe_model::policy::LinuxClass;
use rtpipe_model::{Diagnostic, Nanos, Spec};
use rtpipe_runtime::{ErrorKind, Policy, RunConfig, RunResult, Spin};
use rtpipe_sim::observe::{observe, ChainObs, Summary};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tables::{sections_table, task_table};

#[derive(Args, Debug)]
pub struct RunArgs {
    /// The system spec (TOML), e.g. examples/paper-table3.toml.
    pub spec: PathBuf,
    /// How long to release jobs: "2s", "500ms", or a number in the spec's
    /// time unit [default: 2s; a flight: its mission plus 5 s].
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub duration: Option<String>,
    /// Run synthetic bodies even when the spec's tasks name flight bodies
    /// (`body = ...`); without it such a spec flies the quadrotor for real
    /// (the co-simulated world advanced to the true instants).
    #[arg(long)]
    pub synthetic: bool,
    /// A flight's vehicle: racer5, aero1kg, or a preset file (as `fly`).
    #[arg(long, default_value = "racer5")]
    pub vehicle: String,
    /// A flight's mission: steps, hover, paper, gusty, or a mission file (as
    /// `fly`).
    #[arg(long, default_value = "steps")]
    pub mission: String,
    /// Scheduling class of the task threads [default: fifo for scheduler =
    /// "rm", deadline for "edf", edf-fifo for "edf" with critical
    /// sections]. `other` needs --best-effort.
    #[arg(long, value_enum)]
    pub policy: Option<PolicyArg>,
    /// Accept --policy other (SCHED_OTHER): every figure is then marked as
    /// not real-time.
    #[arg(long)]
    pub best_effort: bool,
    /// Run a spec that `analyze` finds unschedulable under a real-time
    /// policy anyway (its threads may starve everything else on their
    /// CPUs for as long as they are behind).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub output: crate::command::FormatArgs,
    /// Run N background CPU hogs (SCHED_OTHER threads, on any CPU) for the
    /// whole run, as the paper loaded Linux during its measurements.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub load: usize,
    /// Write the run as a Chrome trace-event file for the Perfetto UI, in
    /// the format of `simulate --trace` (one span per job, read to publish).
    #[arg(long, value_name = "FILE.json")]
    pub trace: Option<PathBuf>,
    /// Draw each chain's observed reaction and freshness (mean, p99, max)
    /// against the paper's and the sound bounds as an SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Write the task set (with --policy and --load) as an rt-app workload.
    #[arg(long, value_name = "FILE.json")]
    pub export_rt_app: Option<PathBuf>,
    /// Write one CSV row per head sample of every chain (as `simulate
    /// --samples`): read, event, first and last tail output, reaction and
    /// freshness from the read and from the event, integer ns.
    #[arg(long, value_name = "FILE.csv")]
    pub samples: Option<PathBuf>,
    /// Instead of running the spec, measure this machine's scheduling
    /// overheads (context switch, timer release) on each CPU the spec uses,
    /// with threads in the class of --policy, and print them.
    #[arg(long)]
    pub measure_overheads: bool,
    /// With --measure-overheads: write a copy of the spec with the measured
    /// overheads (99th percentiles) in `[system] overheads` (never the
    /// input spec).
    #[arg(long, value_name = "OUT.toml", requires = "measure_overheads")]
    pub write_spec: Option<PathBuf>,
    /// --vehicle or --mission was given on the command line (set by main).
    #[arg(skip)]
    pub world_given: bool,
}

/// More hogs than this is a typo, not a load (each locks a 4 MB buffer).
const MAX_LOAD: usize = 64;

/// `--policy`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PolicyArg {
    /// SCHED_FIFO, rate-monotonic priorities, pinned threads (scheduler = "rm").
    Fifo,
    /// SCHED_DEADLINE reservations (scheduler = "edf").
    Deadline,
    /// SCHED_OTHER: no real-time guarantee (needs --best-effort).
    Other,
    /// SCHED_FIFO under rtpipe's EDF dispatcher (scheduler = "edf"; the
    /// default when it has critical sections: the stack resource policy).
    EdfFifo,
}

fn policy_of(spec: &Spec, a: &RunArgs) -> Result<Policy, Diagnostic> {
    let p = match (a.policy, spec.policy().linux) {
        (Some(PolicyArg::Fifo), _) => Policy::Fifo,
        (Some(PolicyArg::Deadline), _) => Policy::Deadline,
        (Some(PolicyArg::Other), _) => Policy::Other,
        (Some(PolicyArg::EdfFifo), _) => Policy::EdfFifo,
        (None, LinuxClass::Fifo) => Policy::Fifo,
        // SRP needs the dispatcher (`rtpipe_runtime::edf`).
        (None, LinuxClass::Deadline) if spec.tasks.iter().any(|t| !t.sections.is_empty()) => {
            Policy::EdfFifo
        }
        (None, LinuxClass::Deadline) => Policy::Deadline,
    };
    if p == Policy::Other && !a.best_effort {
        return Err(Diagnostic::error(
            "--policy other runs without real-time guarantees",
            "add --best-effort to accept that (every figure is then marked not real-time)",
        ));
    }
    if p != Policy::Other && a.best_effort {
        return Err(Diagnostic::error(
            "--best-effort only applies to --policy other",
            "drop --best-effort, or add --policy other",
        ));
    }
    Ok(p)
}

/// Checks the configuration and the output paths before anything runs, so
/// that a bad path is reported before a long run, not after.
fn check_outputs(spec: &Spec, a: &RunArgs, cfg: &RunConfig) -> Result<(), Diagnostic> {
    if a.load > MAX_LOAD {
        return Err(Diagnostic::error(
            format!("--load {} is more than {MAX_LOAD} hogs", a.load),
            "one or two hogs per CPU load a machine fully, e.g. --load 2",
        ));
    }
    if let Err(e) = rtpipe_runtime::check(spec, cfg) {
        return Err(e.diagnostic.within(a.spec.display()));
    }
    let mut outs = Vec::new();
    for (flag, p) in [
        ("--trace", &a.trace),
        ("--plot", &a.plot),
        ("--export-rt-app", &a.export_rt_app),
        ("--samples", &a.samples),
    ] {
        let Some(p) = p else { continue };
        outs.push(output::prepare(flag, p, &a.spec, None)?);
    }
    output::distinct(&outs)
}

/// Writes the rt-app workload (before the run: it needs no privilege, and a
/// run refused for lack of one still leaves the file).
fn export_rt_app(spec: &Spec, a: &RunArgs, cfg: &RunConfig, path: &Path) -> Result<(), Diagnostic> {
    if spec.event_triggered() {
        return Err(Diagnostic::error(
            "--export-rt-app cannot express work-queue threads or data-triggered tasks: an rt-app thread is one task released by its own timer",
            "drop --export-rt-app (`rtpipe run` runs the threads and triggers itself)",
        )
        .within(a.spec.display()));
    }
    let r = rtpipe_runtime::rt_app(spec, cfg);
    let text = serde_json::to_string_pretty(&r.json)
        .map_err(|e| Diagnostic::error(format!("cannot render --export-rt-app: {e}"), ""))?;
    output::write_files(
        &a.spec,
        &[("--export-rt-app", path.to_path_buf(), text + "\n")],
    )?;
    eprintln!(
        "wrote {}: rt-app workload of {} task(s){}; run it with `rt-app {}` (rt-app has no data flow: the tasks run independently)",
        path.display(),
        spec.tasks.len(),
        if cfg.load > 0 { format!(" and {} hog(s)", cfg.load) } else { String::new() },
        path.display()
    );
    for n in &r.notes {
        eprintln!("note: {n}");
    }
    Ok(())
}

/// Renders --trace and --plot from the run and writes them (all or none).
fn write_outputs(
    spec: &Spec,
    a: &RunArgs,
    res: &RunResult,
    obs: &[ChainObs],
) -> Result<(), Diagnostic> {
    let mut files = Vec::new();
    let mut notes = Vec::new();
    if let Some(path) = &a.trace {
        let opts = TraceOptions {
            spans: true,
            ..TraceOptions::default()
        };
        let t = chrome_trace_with(spec, &res.sim, opts);
        notes.push(format!(
            "wrote {}: {} job spans (read to publish), {} data-flow arrows; open it in https://ui.perfetto.dev beside `rtpipe simulate --trace`",
            path.display(),
            t.slices,
            t.flows
        ));
        if let Some(cut) = t.truncated_at {
            notes.push(format!(
                "note: the trace stops at {} {u} of {} {u} to stay small; a shorter --duration traces a whole run",
                spec.fmt_time(cut),
                spec.fmt_time(res.sim.horizon),
                u = spec.time_unit
            ));
        }
        files.push(("--trace", path.clone(), t.json));
    }
    if let Some(path) = &a.plot {
        let steal = res.steal.map_or_else(String::new, |s| {
            format!(", steal time {:.0} ms", s as f64 / 1e6)
        });
        let subtitle = format!(
            "{} {} on real threads, {}{}{}{steal}",
            spec.fmt_time(res.sim.horizon),
            spec.time_unit,
            res.policy.class(),
            if a.load > 0 {
                format!(", {} hog(s)", a.load)
            } else {
                String::new()
            },
            if res.policy == Policy::Other {
                " (not real-time)"
            } else {
                ""
            }
        );
        let svg = plot::fig9(spec, obs, &subtitle).map_err(|e| {
            Diagnostic::error(format!("cannot draw --plot {}: {e}", path.display()), "")
        })?;
        notes.push(format!("wrote {}", path.display()));
        files.push(("--plot", path.clone(), svg));
    }
    if let Some(path) = &a.samples {
        let rows = rtpipe_joblog::sample_rows(spec, &res.sim.jobs);
        let n: usize = rows.iter().map(Vec::len).sum();
        notes.push(format!("wrote {}: {n} samples", path.display()));
        files.push(("--samples", path.clone(), samples_csv(spec, &rows)));
    }
    output::write_files(&a.spec, &files)?;
    for n in notes {
        eprintln!("{n}");
    }
    Ok(())
}

pub fn run(a: &RunArgs) -> ExitCode {
    let spec = match command::load(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    if let Err(b) = a.output.no_csv("run") {
        return fail(b);
    }
    if let Some(code) = refuse_unrunnable(&spec, a) {
        return code;
    }
    if a.measure_overheads {
        return measure::run(&spec, a);
    }
    let (setup, cfg) = match prepare(&spec, a) {
        Ok(x) => x,
        Err(b) => return fail(b),
    };
    let report = rtpipe_analysis::analyze(&spec);
    if let Err(b) = admit(&spec, a, &cfg, &report) {
        return fail(b);
    }
    let spin = Spin::calibrate();
    if !a.output.is_json() {
        announce(&spec, a, &cfg, setup.is_some());
    }
    let (res, flown) = match execute(&spec, a, &cfg, setup.as_ref(), spin) {
        Ok(x) => x,
        Err(b) => return fail(b),
    };
    let obs = observe(&report, &res.sim);
    // A file that cannot be written (disk full) does not drop the report of
    // a run that happened: the report first, then the error (exit 2).
    let written = write_outputs(&spec, a, &res, &obs);
    let verdict = verdict::judge(&spec, &report, &res);
    let flight = flown.as_ref().zip(setup.as_ref());
    if let Err(code) = print_report(&spec, a, (&report, &res, &obs), spin, &verdict, flight) {
        return code;
    }
    for n in &res.notes {
        eprintln!("{n}");
    }
    if let Err(b) = &written {
        eprint!("{b}");
    }
    if res.interrupted {
        eprintln!(
            "error: interrupted by {} after {} of {} {u} (the report above covers that span)",
            rtpipe_runtime::sys::stop_name(),
            spec.fmt_time(res.sim.horizon),
            spec.fmt_time(cfg.duration),
            u = spec.time_unit
        );
        return ExitCode::from(crate::interrupted_status());
    }
    if written.is_err() {
        return ExitCode::from(crate::EXIT_BAD_INPUT);
    }
    exit_status(&verdict)
}

/// The report on stdout: JSON, or the text with the verdict and the flight.
fn print_report(
    spec: &Spec,
    a: &RunArgs,
    (report, res, obs): (&Report, &RunResult, &[ChainObs]),
    spin: Spin,
    verdict: &Verdict,
    flight: Option<(&Flight, &Setup)>,
) -> Result<(), ExitCode> {
    let flown = flight.is_some();
    if a.output.is_json() {
        let mut v = to_json(spec, report, res, obs, spin, verdict);
        v.flight = flight.map(|(f, s)| flight_json(f, s));
        command::print_json(&v)?;
    } else {
        print!("{}", to_text(spec, report, res, obs, spin, flown));
        print!("\n{}", verdict.text(spec, 10));
        if let Some((f, s)) = flight {
            let failures = f.quality.failures(&s.criteria());
            println!(
                "\nflight ({}, mission {}, bodies on real threads):",
                s.preset.name, s.mission.name
            );
            print!(
                "{}",
                report::flight::quality_text(&f.quality, &s.criteria(), &failures)
            );
        }
    }
    Ok(())
}

/// A spec the runtime cannot run as asked (sections under
/// SCHED_DEADLINE, `rtpipe_runtime::locks::unrunnable`): the error at its
/// `resource_protocol` (else its first `[resources]` table), exit 2.
fn refuse_unrunnable(spec: &Spec, a: &RunArgs) -> Option<ExitCode> {
    let policy = policy_of(spec, a).ok()?;
    let (msg, help) = rtpipe_runtime::locks::unrunnable(spec, policy)?;
    let source = std::fs::read_to_string(&a.spec).unwrap_or_default();
    let span = rtpipe_model::input::locate(&source, "system.resource_protocol").or_else(|| {
        let r = spec.resources.first()?;
        rtpipe_model::input::locate(&source, &format!("resources.{}.x", r.name))
    });
    let e = rtpipe_model::SpecError {
        file: a.spec.display().to_string(),
        source,
        diagnostics: vec![Diagnostic::new(msg, span).help(help)],
    };
    eprint!("{e}");
    Some(ExitCode::from(crate::EXIT_BAD_INPUT))
}

/// Everything that is checked before the run: the flight's setup when the
/// spec's tasks name flight bodies (and --synthetic does not say
/// otherwise), the duration, the policy, the output paths; writes the
/// rt-app workload if asked, since it needs no run.
fn prepare(spec: &Spec, a: &RunArgs) -> Result<(Option<Setup>, RunConfig), Diagnostic> {
    let flight = !a.synthetic && spec.tasks.iter().any(|t| t.body.is_some());
    if a.world_given && !flight {
        return Err(Diagnostic::error(
            "--vehicle and --mission choose what a flight flies, but this run has synthetic bodies (no task names a flight body, or --synthetic)",
            "drop --vehicle/--mission, or run a spec whose tasks name flight bodies without --synthetic",
        ));
    }
    let setup = if flight {
        let r = rtpipe_fly::Request {
            spec_path: &a.spec,
            vehicle: &a.vehicle,
            mission: &a.mission,
            horizon: None,
            seed: 0,
        };
        match rtpipe_fly::setup(spec, &r) {
            Ok(s) => Some(s),
            Err(e) => return Err(e.within(a.spec.display())),
        }
    } else {
        None
    };
    let duration = duration_of(spec, a, setup.as_ref())?;
    let policy = policy_of(spec, a)?;
    let cfg = RunConfig {
        duration,
        policy,
        load: a.load,
    };
    check_outputs(spec, a, &cfg)?;
    if let Some(path) = &a.export_rt_app {
        export_rt_app(spec, a, &cfg, path)?;
    }
    Ok((setup, cfg))
}

/// Refuses to run an unschedulable spec under a real-time policy without
/// --force: the analysis said its threads can fall behind for good, and a
/// SCHED_FIFO or SCHED_DEADLINE thread that is behind keeps its CPU from
/// every ordinary process (measured: up to 950 ms on CPU 0).
fn admit(spec: &Spec, a: &RunArgs, cfg: &RunConfig, report: &Report) -> Result<(), Diagnostic> {
    let s = &report.schedulability;
    if s.schedulable || a.force || cfg.policy == Policy::Other {
        return Ok(());
    }
    let failing: Vec<String> = s
        .cpus
        .iter()
        .filter(|v| !v.schedulable)
        .map(|v| {
            format!(
                "CPU {} ({} {:.3} > {:.3})",
                v.cpu,
                s.test.name(),
                v.value,
                v.bound
            )
        })
        .collect();
    Err(Diagnostic::error(
        format!(
            "{} is not schedulable ({}): under {} its threads can fall behind for good and starve everything else on their CPUs",
            spec.name,
            failing.join(", "),
            cfg.policy.class()
        ),
        "fix the budgets or periods (`rtpipe analyze` says where, `rtpipe design` picks periods), run it with --policy other --best-effort, or pass --force to run it anyway",
    ))
}

/// `--duration`, by default a flight's mission (plus its margin) or 2 s.
fn duration_of(spec: &Spec, a: &RunArgs, setup: Option<&Setup>) -> Result<Nanos, Diagnostic> {
    match (&a.duration, setup) {
        (None, Some(s)) => Ok(s.horizon),
        (None, None) => Ok(2_000_000_000),
        (Some(d), _) => match parse_time(spec, d) {
            Ok(d) if d > 0 => Ok(d),
            Ok(_) => Err(Diagnostic::error(
                format!("--duration {d} is not positive"),
                "e.g. --duration 2s",
            )),
            Err(e) => Err(Diagnostic::error(
                format!("--duration {d}: {e}"),
                "e.g. --duration 2s",
            )),
        },
    }
}

/// Says on stderr what is about to run, and how to stop it.
fn announce(spec: &Spec, a: &RunArgs, cfg: &RunConfig, flight: bool) {
    eprintln!(
        "running {} for {} {} under {}{}{} (Ctrl-C stops early)...",
        spec.name,
        spec.fmt_time(cfg.duration),
        spec.time_unit,
        cfg.policy.class(),
        if a.load > 0 {
            format!(" with {} background hog(s)", a.load)
        } else {
            String::new()
        },
        if flight { ", flying the quadrotor" } else { "" }
    );
}

/// The run itself: the flight on real threads with the world co-simulated
/// when there is a `setup`, else synthetic bodies burning each task's
/// demand. A spec the kernel refuses, like one that cannot run, is bad
/// input.
fn execute(
    spec: &Spec,
    a: &RunArgs,
    cfg: &RunConfig,
    setup: Option<&Setup>,
    spin: Spin,
) -> Result<(RunResult, Option<Flight>), Diagnostic> {
    if let Some(s) = setup {
        return match rtpipe_fly::fly_real(spec, s, cfg) {
            Ok((f, r)) => Ok((r, Some(f))),
            Err(e) => Err(e.within(a.spec.display())),
        };
    }
    // Synthetic bodies, each task's critical sections held by the runtime.
    match rtpipe_runtime::run_synthetic(spec, cfg, spin) {
        Ok(r) => Ok((r, None)),
        Err(e) => {
            let b = e.diagnostic.within(a.spec.display());
            match e.kind {
                ErrorKind::Config | ErrorKind::Refused => Err(b),
            }
        }
    }
}

/// The `flight` entry of the JSON: the vehicle, the mission and how the
/// flight went, its figures named as `fly --json` names them.
#[derive(Serialize)]
struct FlightView<'a> {
    vehicle: &'a str,
    mission: &'a str,
    crashed: bool,
    airborne_s: f64,
    landed_s: Option<f64>,
    attitude_error_deg: RmsMax,
    altitude_error_m: RmsMax,
    envelope: EnvelopeView,
    failures: Vec<String>,
}

fn flight_json<'a>(f: &Flight, s: &'a Setup) -> FlightView<'a> {
    let q = &f.quality;
    FlightView {
        vehicle: &s.preset.name,
        mission: &s.mission.name,
        crashed: q.crashed,
        airborne_s: q.airborne_s,
        landed_s: q.landed_s,
        attitude_error_deg: (&q.attitude_error_deg).into(),
        altitude_error_m: (&q.altitude_error_m).into(),
        envelope: q.into(),
        failures: q.failures(&s.criteria()),
    }
}

/// Exit 1 when an observation above a sound bound has no cause in its
/// window that adds up to its excess (a violation of the analysis, or of
/// the model by something rtpipe cannot see), or a task the analysis bounds
/// no response for ran a job (`--force`); exit 0 otherwise.
fn exit_status(v: &Verdict) -> ExitCode {
    if v.unexcused > 0 {
        eprintln!(
            "error: {} observation(s) above a sound bound with no cause in their own window that explains them{} (listed above; --json has them all)",
            v.unexcused,
            v.unbounded_note()
        );
        return ExitCode::from(1);
    }
    if v.excused > 0 {
        eprintln!(
            "warning: {} observation(s) above a sound bound, each excused by what broke the model in its window (listed above)",
            v.excused
        );
    }
    ExitCode::SUCCESS
}

/// The text report: what ran, the chains against the bounds (from the
/// head's read, from the event, and the paper's Fig. 10 columns), the
/// tasks, and the steal time.
fn to_text(
    spec: &Spec,
    report: &Report,
    res: &RunResult,
    obs: &[ChainObs],
    spin: Spin,
    flight: bool,
) -> String {
    let mut out = crate::report::analysis::system_line(spec);
    out.push_str(&ran_line(spec, res, spin, flight));
    if res.policy == Policy::Deadline {
        out.push_str(if res.partitioned {
            "SCHED_DEADLINE, partitioned EDF: one root domain per CPU (exclusive cpusets), each thread pinned to its task's CPU\n"
        } else {
            "SCHED_DEADLINE threads are not pinned (the kernel requires their affinity to span the root domain): global EDF on all CPUs\n"
        });
    }
    out.extend(res.dispatch.map(|d| d.describe()));
    if !obs.is_empty() {
        out.push_str(
            "\nchains (observed from the head's read, against the analysis' worst-case bounds):\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Read));
        out.push_str("\nfrom the event just after each head read, against the +event bounds:\n");
        out.push_str(&chain_table(spec, obs, Anchor::Event));
        out.push_str(
            "\nthe paper's Fig. 10 columns (from the head's read; AVG mean, WC max, MaxV max - min; R reaction, F freshness):\n",
        );
        out.push_str(&fig10_table(spec, obs));
    }
    let overheads = if spec.overheads.is_zero() {
        "which has no wake-up latency or switching overhead"
    } else {
        "with the spec's [system] overheads (`--measure-overheads` measures this machine's)"
    };
    out.push_str(&format!(
        "\ntasks (R = publish - release; R(job): the analysed worst case, {overheads}; \
         start = read - release; demand = CPU time of one job):\n",
    ));
    out.push_str(&task_table(spec, report, res));
    if !spec.resources.is_empty() {
        out.push_str(&format!(
            "\ncritical sections (resource_protocol = \"{}\"; held: lock taken to given back, wall time; overlaps: holds of one resource that overlapped, 0 when mutual exclusion held):\n",
            spec.resource_protocol.name()
        ));
        out.push_str(&sections_table(spec, res));
    }
    out.push_str(&format!(
        "\nsteal time during the run: {}\n",
        res.steal
            .map_or_else(|| "unknown".into(), |s| format!("{:.1} ms", s as f64 / 1e6))
    ));
    for t in &res.foreign_rt {
        out.push_str(&format!(
            "foreign real-time thread on the run's CPUs: {}\n",
            t.describe()
        ));
    }
    out
}

/// What ran, for how long, under which class and load, with which bodies;
/// best effort says loudly that no figure is a real-time measurement.
fn ran_line(spec: &Spec, res: &RunResult, spin: Spin, flight: bool) -> String {
    let u = spec.time_unit;
    let rt = if res.policy == Policy::Other {
        " -- NOT REAL-TIME (best effort): no figure below is a real-time measurement"
    } else {
        ""
    };
    format!(
        "ran {} {u} under {}{}{}{rt}; {}\n",
        spec.fmt_time(res.sim.horizon),
        res.policy.class(),
        match res.load {
            0 => String::new(),
            n => format!(" with {n} background hog(s)"),
        },
        if res.interrupted {
            format!(", interrupted by {}", rtpipe_runtime::sys::stop_name())
        } else {
            String::new()
        },
        if flight {
            "the flight bodies, the world co-simulated at the true instants".to_string()
        } else {
            format!(
                "synthetic bodies burning each task's demand (spin loop: {:.0} iterations/us)",
                spin.iters_per_us
            )
        }
    )
}

/// `run --json`: the observations report with each task's measurements,
/// the Fig. 10 figures, the run, and the flight when bodies flew.
#[derive(Serialize)]
struct RunView<'a> {
    #[serde(flatten)]
    report: ReportView<'a, Extended<TaskView<'a>, TaskMeasured>, ObsChain<'a>>,
    fig10: Vec<Fig10View>,
    run: RunInfo<'a>,
    #[serde(skip_serializing_if = "Option::is_none")]
    flight: Option<FlightView<'a>>,
}

#[derive(Serialize)]
struct TaskMeasured {
    released: u64,
    completed: u64,
    max_response: Option<f64>,
    mean_response: Option<f64>,
    p99_response: Option<f64>,
    late: u64,
    missed_periods: u64,
    overruns: u64,
    /// Releases merged into a job still queued (a task in a work-queue
    /// thread or data-triggered); 0 for any other.
    merged: u64,
    max_demand: f64,
    max_start: f64,
    priority: Option<i32>,
    utilization: f64,
}

#[derive(Serialize)]
struct RunInfo<'a> {
    duration: f64,
    policy: &'static str,
    load: usize,
    epoch_monotonic_ns: Nanos,
    real_time: bool,
    interrupted: bool,
    steal: Option<f64>,
    /// Other processes' real-time threads that may run on the run's CPUs
    /// and used CPU time during it, in words (most CPU time first).
    foreign_rt_threads: Vec<String>,
    spin_iterations_per_us: f64,
    /// EDF only: `partitioned` (SCHED_DEADLINE with a root domain per CPU,
    /// or the EDF dispatcher's pinned threads) or `global` EDF.
    edf: Option<&'static str>,
    sound_bound_violations: &'a Verdict,
    notes: &'a [String],
    /// Per resource: its sections as the threads held them.
    critical_sections: Vec<HeldView<'a>>,
    /// Under `edf-fifo`: what the EDF dispatcher did.
    dispatcher: Option<DispatchView>,
}

/// The EDF dispatcher's counts (`rtpipe_runtime::edf::Stats`).
#[derive(Serialize)]
struct DispatchView {
    dispatches: u64,
    priority_changes: u64,
    held_back_by_ceiling: u64,
    quiet_section_exits: u64,
    contended: u64,
    refused: u64,
}

impl From<rtpipe_runtime::edf::Stats> for DispatchView {
    fn from(s: rtpipe_runtime::edf::Stats) -> DispatchView {
        DispatchView {
            dispatches: s.dispatches,
            priority_changes: s.changes,
            held_back_by_ceiling: s.held_back,
            quiet_section_exits: s.quiet_exits,
            contended: s.contended,
            refused: s.failed,
        }
    }
}

/// One resource's sections in a run.
#[derive(Serialize)]
struct HeldView<'a> {
    resource: &'a str,
    holds: usize,
    max_held: f64,
    overlaps: usize,
}

fn held_json<'a>(spec: &'a Spec, res: &RunResult) -> Vec<HeldView<'a>> {
    let holds: Vec<_> = res
        .tasks
        .iter()
        .flat_map(|t| t.sections.iter().copied())
        .collect();
    let rows = rtpipe_runtime::locks::summary(spec.resources.len(), &holds);
    spec.resources
        .iter()
        .zip(rows)
        .map(|(r, (holds, longest, overlaps))| HeldView {
            resource: &r.name,
            holds,
            max_held: spec.in_unit(longest),
            overlaps,
        })
        .collect()
}

fn to_json<'a>(
    spec: &'a Spec,
    report: &Report,
    res: &'a RunResult,
    obs: &[ChainObs],
    spin: Spin,
    verdict: &'a Verdict,
) -> RunView<'a> {
    let measured = |(ts, tr): (&rtpipe_joblog::TaskStats, &rtpipe_runtime::TaskRun)| {
        let s = Summary::of(&tr.responses);
        TaskMeasured {
            released: ts.released,
            completed: ts.completed,
            max_response: time(spec, ts.max_response),
            mean_response: s.map(|s| s.mean / spec.time_unit.nanos() as f64),
            p99_response: time(spec, s.map(|s| s.p99)),
            late: ts.late,
            missed_periods: tr.missed,
            overruns: tr.overruns,
            merged: ts.merged,
            max_demand: spec.in_unit(tr.max_demand),
            max_start: spec.in_unit(tr.max_start),
            priority: tr.priority,
            utilization: ts.busy as f64 / res.sim.horizon as f64,
        }
    };
    let runs = res.sim.tasks.iter().zip(&res.tasks);
    let report = observations_view(spec, report, obs).with(
        |tasks| {
            (tasks.into_iter().zip(runs))
                .map(|(base, r)| Extended {
                    base,
                    observed: measured(r),
                })
                .collect()
        },
        |chains| chains,
    );
    let run = RunInfo {
        duration: spec.in_unit(res.sim.horizon),
        policy: res.policy.name(),
        load: res.load,
        epoch_monotonic_ns: res.epoch,
        real_time: res.policy != Policy::Other,
        edf: res
            .policy
            .edf()
            .then_some(if res.partitioned || res.policy == Policy::EdfFifo {
                "partitioned"
            } else {
                "global"
            }),
        interrupted: res.interrupted,
        steal: res.steal.map(|s| spec.in_unit(s)),
        foreign_rt_threads: res.foreign_rt.iter().map(|t| t.describe()).collect(),
        spin_iterations_per_us: spin.iters_per_us,
        sound_bound_violations: verdict,
        notes: &res.notes,
        critical_sections: held_json(spec, res),
        dispatcher: res.dispatch.map(DispatchView::from),
    };
    RunView {
        report,
        fig10: fig10_json(spec, obs),
        run,
        flight: None,
    }
}

/// One chain's Fig. 10 figures from the head's read: (mean, max, max − min)
/// of reaction and of freshness, and the sound bounds.
struct Fig10 {
    chain: usize,
    reaction: Option<Summary>,
    freshness: Option<Summary>,
    sound_r: Option<Nanos>,
    sound_f: Option<Nanos>,
}

/// The chains in order, each with its two metrics.
fn fig10_rows(obs: &[ChainObs]) -> Vec<Fig10> {
    let mut rows: Vec<Fig10> = Vec::new();
    for o in obs {
        if rows.last().is_none_or(|r| r.chain != o.chain) {
            rows.push(Fig10 {
                chain: o.chain,
                reaction: None,
                freshness: None,
                sound_r: None,
                sound_f: None,
            });
        }
        let Some(row) = rows.last_mut() else { continue };
        match o.metric {
            Metric::Reaction => (row.reaction, row.sound_r) = (o.read.observed, o.read.sound),
            Metric::Freshness => (row.freshness, row.sound_f) = (o.read.observed, o.read.sound),
        }
    }
    rows
}

fn fig10_table(spec: &Spec, obs: &[ChainObs]) -> String {
    let mut t = Table::new(&[
        "chain", "AVGR", "WCR", "MaxRV", "sound R", "AVGF", "WCF", "MaxFV", "sound F",
    ])
    .numeric(&[1, 2, 3, 4, 5, 6, 7, 8]);
    let f = |x: Option<Nanos>| x.map_or_else(|| "-".into(), |v| spec.fmt_time(v));
    let summary_cells = |s: Option<Summary>| {
        [
            f(s.map(|s| s.mean.round() as Nanos)),
            f(s.map(|s| s.max)),
            f(s.map(|s| s.max - s.min)),
        ]
    };
    for r in fig10_rows(obs) {
        let mut row = vec![spec.chain_label(r.chain)];
        row.extend(summary_cells(r.reaction));
        row.push(f(r.sound_r));
        row.extend(summary_cells(r.freshness));
        row.push(f(r.sound_f));
        t.row(row);
    }
    t.render()
}

/// `fig10`: one entry per chain, in the spec's unit.
#[derive(Serialize)]
#[allow(non_snake_case)] // the paper's names for the figures
struct Fig10View {
    chain: String,
    AVGR: Option<f64>,
    WCR: Option<f64>,
    MaxRV: Option<f64>,
    sound_reaction: Option<f64>,
    AVGF: Option<f64>,
    WCF: Option<f64>,
    MaxFV: Option<f64>,
    sound_freshness: Option<f64>,
}

fn fig10_json(spec: &Spec, obs: &[ChainObs]) -> Vec<Fig10View> {
    let unit = spec.time_unit.nanos() as f64;
    let n = |x: Option<Nanos>| time(spec, x);
    let summary_cells = |s: Option<Summary>| {
        (
            s.map(|s| s.mean / unit),
            n(s.map(|s| s.max)),
            n(s.map(|s| s.max - s.min)),
        )
    };
    fig10_rows(obs)
        .into_iter()
        .map(|r| {
            let (avgr, wcr, maxrv) = summary_cells(r.reaction);
            let (avgf, wcf, maxfv) = summary_cells(r.freshness);
            Fig10View {
                chain: spec.chain_label(r.chain),
                AVGR: avgr,
                WCR: wcr,
                MaxRV: maxrv,
                sound_reaction: n(r.sound_r),
                AVGF: avgf,
                WCF: wcf,
                MaxFV: maxfv,
                sound_freshness: n(r.sound_f),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_names_the_flight_s_figures_as_fly_does() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
        let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let r = rtpipe_fly::Request {
            spec_path: &path,
            vehicle: "racer5",
            mission: "hover",
            horizon: Some(6_000_000_000),
            seed: 0,
        };
        let s = rtpipe_fly::setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        let f = rtpipe_fly::fly(&spec, &s, rtpipe_sim::ExecModel::Uniform)
            .unwrap_or_else(|e| panic!("{e}"));
        let v = serde_json::to_value(flight_json(&f, &s)).unwrap_or_default();
        // `fly --json` has flight.attitude_error_deg.rms and .max.
        for key in ["attitude_error_deg", "altitude_error_m"] {
            assert!(
                v[key]["rms"].is_number() && v[key]["max"].is_number(),
                "{v}"
            );
        }
        assert!(v.get("attitude_error_deg_rms").is_none(), "{v}");
    }
}
