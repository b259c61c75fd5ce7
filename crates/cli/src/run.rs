//! `rtpipe run`: the spec on real threads (rtpipe-runtime), measured like
//! `simulate` and held against the same bounds.

use crate::command::{self, fail, parse_time, Answer};
use verdict::Verdict;

mod files;
mod measure;
mod report;
mod tables;
mod verdict;
use clap::{Args, ValueEnum};
use rtpipe_analysis::Report;
use rtpipe_fly::{Flight, Setup};
use rtpipe_model::policy::LinuxClass;
use rtpipe_model::{Diagnostic, Nanos, Spec};
use rtpipe_runtime::{ErrorKind, Policy, RunConfig, RunResult, Spin};
use rtpipe_sim::observe::observe;
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// A flight's vehicle: racer5, aero1kg, or a preset file (as `fly`)
    /// [default: racer5].
    #[arg(long)]
    pub vehicle: Option<String>,
    /// A flight's mission: steps, hover, paper, gusty, breeze, or a mission
    /// file (as `fly`) [default: steps].
    #[arg(long)]
    pub mission: Option<String>,
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
}

impl RunArgs {
    /// `--vehicle`, or its default.
    pub fn vehicle(&self) -> &str {
        self.vehicle.as_deref().unwrap_or("racer5")
    }

    /// `--mission`, or its default.
    pub fn mission(&self) -> &str {
        self.mission.as_deref().unwrap_or("steps")
    }

    /// Whether a flight's world was chosen (`--vehicle`, `--mission`).
    fn world_given(&self) -> bool {
        self.vehicle.is_some() || self.mission.is_some()
    }

    /// The checks of the flags alone, whichever way they came (the command
    /// line, Python's keywords): a flag that would do nothing, or a value
    /// out of range, is an error that names the fix. What needs the spec
    /// too (a flight's world on a spec without flight bodies, a bare
    /// number's unit) is checked where the spec is.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        let other = self.policy == Some(PolicyArg::Other);
        if other && !self.best_effort {
            return Err(Diagnostic::error(
                "--policy other runs without real-time guarantees",
                "add --best-effort to accept that (every figure is then marked not real-time)",
            ));
        }
        if !other && self.best_effort {
            return Err(Diagnostic::error(
                "--best-effort only applies to --policy other",
                "drop --best-effort, or add --policy other",
            ));
        }
        if self.load > MAX_LOAD {
            return Err(Diagnostic::error(
                format!("--load {} is more than {MAX_LOAD} hogs", self.load),
                "one or two hogs per CPU load a machine fully, e.g. --load 2",
            ));
        }
        if self.synthetic && self.world_given() {
            return Err(no_world_to_fly());
        }
        match &self.duration {
            Some(d) => duration_alone(d).map(|_| ()),
            None => Ok(()),
        }
    }
}

/// `--vehicle` or `--mission` on a run without a flight.
fn no_world_to_fly() -> Diagnostic {
    Diagnostic::error(
        "--vehicle and --mission choose what a flight flies, but this run has synthetic bodies (no task names a flight body, or --synthetic)",
        "drop --vehicle/--mission, or run a spec whose tasks name flight bodies without --synthetic",
    )
}

/// `--duration D` read without the spec: a positive number (in the spec's
/// unit, which only scales it) or a positive time with its unit; the
/// nanoseconds of the latter.
fn duration_alone(d: &str) -> Result<Option<Nanos>, Diagnostic> {
    let bad = |why: String| Diagnostic::error(why, "e.g. --duration 2s");
    let not_positive = || bad(format!("--duration {d} is not positive"));
    match d.trim().parse::<f64>() {
        Ok(x) if x.is_nan() => Err(bad(format!("--duration {d}: not a number"))),
        Ok(x) if x <= 0.0 => Err(not_positive()),
        Ok(_) => Ok(None),
        Err(_) => match rtpipe_model::parse_time_str(d.trim()) {
            Ok(n) if n > 0 => Ok(Some(n)),
            Ok(_) => Err(not_positive()),
            Err(e) => Err(bad(format!("--duration {d}: {e}"))),
        },
    }
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
    // `validate` refused --policy other without --best-effort, and the
    // reverse; the spec's default is never `other`.
    debug_assert_eq!(p == Policy::Other, a.best_effort);
    Ok(p)
}

/// `rtpipe run`: parse and check ([`prepare`], [`admit`]), run
/// ([`execute`]), write the files (`files.rs`), then print the report
/// (`report.rs`, as `--format` asks) and the notes in one place.
pub fn run(a: &RunArgs) -> ExitCode {
    let spec = match command::load(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    if let Err(d) = a.validate() {
        return fail(d);
    }
    if let Some(code) = refuse_unrunnable(&spec, a) {
        return code;
    }
    if a.measure_overheads {
        return measure::run(&spec, a);
    }
    match answer(&spec, a, !a.output.is_json()) {
        Ok(answer) => answer.emit(),
        Err(b) => fail(b),
    }
}

/// `run` on a loaded spec, as the binary and Python both call it: the
/// report, the notes (the run's, a file not written, why the status is
/// what it is) and the exit status. `announce` says on stderr what is
/// about to run (the binary's text report).
pub fn answer(spec: &Spec, a: &RunArgs, announce_it: bool) -> Result<Answer, Diagnostic> {
    a.validate()?;
    if let Some(d) = unrunnable(spec, a) {
        return Err(d);
    }
    if a.measure_overheads {
        return Err(Diagnostic::error(
            "--measure-overheads measures this machine, it runs no spec",
            "run `rtpipe run SPEC --measure-overheads` from the command line",
        ));
    }
    let (setup, cfg) = prepare(spec, a)?;
    let report = rtpipe_analysis::analyze(spec);
    admit(spec, a, &cfg, &report)?;
    let spin = Spin::calibrate();
    if announce_it {
        announce(spec, a, &cfg, setup.is_some());
    }
    let (res, flown) = execute(spec, a, &cfg, setup.as_ref(), spin)?;
    let obs = observe(&report, &res.sim);
    // A file that cannot be written (disk full) does not drop the report of
    // a run that happened: the report first, then the error (exit 2).
    let written = files::write_outputs(spec, a, &res, &obs);
    let verdict = verdict::judge(spec, &report, &res);
    let printed = report::RunReport {
        spec,
        report: &report,
        res: &res,
        obs: &obs,
        spin,
        verdict: &verdict,
        flight: flown.as_ref().zip(setup.as_ref()),
    };
    let rendered = command::render(&printed, a.output.chosen())?;
    let mut notes = res.notes.clone();
    if let Err(b) = &written {
        notes.push(b.to_string().trim_end().to_string());
    }
    let status = status_after(spec, &cfg, &res, written.is_ok(), &verdict, &mut notes);
    Ok(Answer {
        report: rendered,
        notes,
        status,
    })
}

/// The exit status once the report is out: a stop signal's (the span run
/// covered said), a file that was not written (2), else the verdict's;
/// what it says for people goes to `notes`.
fn status_after(
    spec: &Spec,
    cfg: &RunConfig,
    res: &RunResult,
    written: bool,
    verdict: &Verdict,
    notes: &mut Vec<String>,
) -> u8 {
    if res.interrupted {
        notes.push(format!(
            "error: interrupted by {} after {} of {} {u} (the report above covers that span)",
            rtpipe_runtime::sys::stop_name(),
            spec.fmt_time(res.sim.horizon),
            spec.fmt_time(cfg.duration),
            u = spec.time_unit
        ));
        return crate::interrupted_status();
    }
    if !written {
        return crate::EXIT_BAD_INPUT;
    }
    exit_status(verdict, notes)
}

/// Why the runtime cannot run `spec` as `a` asks (sections under
/// SCHED_DEADLINE, `rtpipe_runtime::locks::unrunnable`), without a place.
fn unrunnable(spec: &Spec, a: &RunArgs) -> Option<Diagnostic> {
    let policy = policy_of(spec, a).ok()?;
    let (msg, help) = rtpipe_runtime::locks::unrunnable(spec, policy)?;
    Some(Diagnostic::error(msg, help))
}

/// A spec the runtime cannot run as asked (sections under
/// SCHED_DEADLINE, `rtpipe_runtime::locks::unrunnable`): the error at its
/// `resource_protocol` (else its first `[resources]` table), exit 2.
fn refuse_unrunnable(spec: &Spec, a: &RunArgs) -> Option<ExitCode> {
    let d = unrunnable(spec, a)?;
    let source = std::fs::read_to_string(&a.spec).unwrap_or_default();
    let span = rtpipe_model::input::locate(&source, "system.resource_protocol").or_else(|| {
        let r = spec.resources.first()?;
        rtpipe_model::input::locate(&source, &format!("resources.{}.x", r.name))
    });
    let e = rtpipe_model::SpecError {
        file: a.spec.display().to_string(),
        source,
        diagnostics: vec![Diagnostic { span, ..d }],
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
    if a.world_given() && !flight {
        return Err(no_world_to_fly());
    }
    let setup = if flight {
        let r = rtpipe_fly::Request {
            spec_path: &a.spec,
            vehicle: a.vehicle(),
            mission: a.mission(),
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
    files::check_outputs(spec, a, &cfg)?;
    if let Some(path) = &a.export_rt_app {
        files::export_rt_app(spec, a, &cfg, path)?;
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
    let Some(d) = &a.duration else {
        return Ok(setup.map_or(2_000_000_000, |s| s.horizon));
    };
    if let Some(n) = duration_alone(d)? {
        return Ok(n);
    }
    // A bare number, in the spec's unit (`validate` saw it positive).
    match parse_time(spec, d) {
        Ok(n) if n > 0 => Ok(n),
        Ok(_) => Err(Diagnostic::error(
            format!("--duration {d} is not positive"),
            "e.g. --duration 2s",
        )),
        Err(e) => Err(Diagnostic::error(
            format!("--duration {d}: {e}"),
            "e.g. --duration 2s",
        )),
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

/// Exit 1 when an observation above a sound bound has no cause in its
/// window that adds up to its excess (a violation of the analysis, or of
/// the model by something rtpipe cannot see), or a task the analysis bounds
/// no response for ran a job (`--force`); exit 0 otherwise.
fn exit_status(v: &Verdict, notes: &mut Vec<String>) -> u8 {
    if v.unexcused > 0 {
        notes.push(format!(
            "error: {} observation(s) above a sound bound with no cause in their own window that explains them{} (listed above; --json has them all)",
            v.unexcused,
            v.unbounded_note()
        ));
        return 1;
    }
    if v.excused > 0 {
        notes.push(format!(
            "warning: {} observation(s) above a sound bound, each excused by what broke the model in its window (listed above)",
            v.excused
        ));
    }
    0
}

impl command::Registered for RunArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn inputs(&self) -> Vec<(&'static str, &std::path::Path)> {
        command::world_inputs(self.vehicle(), self.mission())
    }

    /// The flags' own checks and a spec without periods: the caller's
    /// input, refused before anything runs.
    fn check(&self, call: &command::Call<'_>) -> Result<(), Diagnostic> {
        self.validate()?;
        match command::missing_periods(call.spec()?) {
            Some(d) => Err(d),
            None => Ok(()),
        }
    }

    /// A refusal once the checks passed is the machine's (`RunError` in
    /// Python): the kernel refused a class or a reservation, a CPU is
    /// missing.
    fn refusal(&self) -> command::Refusal {
        command::Refusal::Run
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        answer(call.spec()?, self, false).map(command::Done::from)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(report::RunView<'static>)
}
