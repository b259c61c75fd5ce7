//! `rtpipe design`: choose periods that meet every limit at least utilisation.

mod flights;
mod margin;

use crate::command::mode_parser;
use crate::command::{self, Answer, FormatArgs, Rendered};
use crate::output;
use crate::report::analysis::{report_text, report_view, ReportView};
use crate::report::Pairs;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_design::lp::SolverKind;
use rtpipe_design::{
    design, DesignError, ErrorKind, Incumbent, Method, Mode, Options, Outcome, Status,
};
use rtpipe_model::{Diagnostic, PeriodSpec, Spec};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    Auto,
    Boxes,
    Milp,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ObjectiveArg {
    /// The least utilisation Σ C/T that meets every limit.
    Utilization,
    /// The largest critical scaling factor (every exec grown together)
    /// within --max-utilization.
    Margin,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum SolverArg {
    Microlp,
    Highs,
}

/// `rtpipe design`'s flags.
#[derive(clap::Args, Debug)]
pub struct DesignArgs {
    /// The system spec (TOML); tasks without a fixed period are designed.
    pub spec: PathBuf,
    /// The analysis the chain limits are judged by.
    #[arg(long, value_parser = mode_parser(), default_value = "sound")]
    pub mode: Mode,
    #[command(flatten)]
    pub output: FormatArgs,
    /// Write the complete designed spec here (accepted by `analyze`).
    /// Symlinks are followed; only regular files are replaced, atomically;
    /// never the input spec unless --overwrite-spec is given.
    #[arg(long, value_name = "OUT.toml")]
    pub write: Option<PathBuf>,
    /// Allow --write to replace the input spec (its comments and period
    /// ranges are lost).
    #[arg(long, requires = "write")]
    pub overwrite_spec: bool,
    /// The exact search: `boxes` (branch and bound over period boxes,
    /// pruned by the sound analysis; sound mode, and paper mode where
    /// Eq. 12 does not fall as a period grows), `milp` (the mixed-integer model; every case but critical sections and scheduling overheads), or `auto`
    /// (boxes where they apply, else milp).
    #[arg(long, value_enum, default_value = "auto")]
    pub method: MethodArg,
    /// MILP backend [default: highs when built with `--features highs`,
    /// else microlp].
    #[arg(long, value_enum)]
    pub solver: Option<SolverArg>,
    /// Stop after this many seconds (at most 1000000) and report the best
    /// verified design and its gap. Without it the search is bounded by
    /// work, not time, so the answer is the same on every machine.
    #[arg(long, value_name = "S", value_parser = parse_time_limit, allow_hyphen_values = true)]
    pub time_limit: Option<f64>,
    /// Fly every design the search would return on this mission (built-in
    /// steps, hover, paper, gusty, breeze, or a mission file; repeat or
    /// separate with commas for several; --fly alone: steps, gusty and
    /// breeze, the calm steps, the turbulent hover and steps in light
    /// turbulence) over randomised seeds and phases: one whose pass rate's
    /// lower confidence bound misses --pass-rate is cut, with every design
    /// no faster than 95 % of it, and the search goes on. The answer is the
    /// least-utilisation design that both verifies and flies. Box search
    /// only (sound mode, no harmonic periods).
    #[arg(
        long = "fly",
        value_name = "MISSION",
        value_delimiter = ',',
        num_args = 0..=1,
        default_missing_values = flights::DEFAULT_MISSIONS
    )]
    pub missions: Vec<String>,
    /// With --fly: the vehicles (built-in racer5, aero1kg, or preset files;
    /// repeat or separate with commas) [default: every built-in vehicle,
    /// racer5 and aero1kg].
    #[arg(long = "vehicle", value_name = "PRESET|FILE", value_delimiter = ',')]
    pub vehicles: Vec<String>,
    /// With --fly: the first seed of the sensor noise and execution times;
    /// flight j of each vehicle and mission flies seed S + j at phase draw
    /// j [default: 0].
    #[arg(long = "seed", value_name = "S")]
    pub seed: Option<u64>,
    /// With --fly: the pass rate whose lower confidence bound (Wilson) a
    /// design's flights must reach, in (0, 1) [default: 0.95].
    #[arg(long, value_name = "R", value_parser = crate::command::parse_fraction, allow_hyphen_values = true)]
    pub pass_rate: Option<f64>,
    /// With --fly: the confidence of that bound, in (0, 1) [default: 0.95;
    /// with the default rate, 73 flights all passing].
    #[arg(long, value_name = "C", value_parser = crate::command::parse_fraction, allow_hyphen_values = true)]
    pub confidence: Option<f64>,
    /// With --fly: flights per design [default: the fewest that can reach
    /// the bound, spread over the vehicles and missions]; more flights let
    /// a design fail a few and still pass.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub flights: Option<u32>,
    /// What the answer optimises: `utilization` (least Σ C/T) or `margin`
    /// (the largest factor every exec may grow by together, among the
    /// designs within --max-utilization).
    #[arg(long, value_enum, default_value = "utilization")]
    pub objective: ObjectiveArg,
    /// With --objective margin: the most utilisation Σ C/T the design may
    /// use (e.g. 0.8).
    #[arg(long, value_name = "U", value_parser = margin::parse_cap, allow_hyphen_values = true)]
    pub max_utilization: Option<f64>,
    /// Also compute the timing margins of the answer (as `analyze
    /// --margins` does): how much each exec may grow, each chain's slack,
    /// the critical scaling factors and each period's range.
    #[arg(long)]
    pub margins: bool,
}

/// The most `--time-limit` accepts, in seconds (about 11.6 days).
pub const MAX_TIME_LIMIT: f64 = 1e6;

/// `--time-limit`: positive seconds up to [`MAX_TIME_LIMIT`].
pub fn parse_time_limit(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 && t <= MAX_TIME_LIMIT => Ok(t),
        Ok(t) if t.is_finite() && t > MAX_TIME_LIMIT => Err(format!(
            "at most {MAX_TIME_LIMIT} seconds (about 11.6 days); without --time-limit the search is bounded by work instead"
        )),
        _ => Err(format!(
            "must be a positive number of seconds up to {MAX_TIME_LIMIT}, e.g. --time-limit 60"
        )),
    }
}

pub fn run(a: &DesignArgs) -> ExitCode {
    let spec = match Spec::load(&a.spec) {
        Ok(s) => s,
        Err(e) => {
            eprint!("{e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    rtpipe_runtime::sys::catch_stop_signals();
    match execute(&spec, a, &rtpipe_runtime::sys::stop_requested) {
        Ok((answer, _)) => answer.emit(),
        Err(b) => command::fail(b),
    }
}

/// `design` on a loaded spec; `stop` says when to stop the search and
/// answer with the best verified design so far. The answer, and the
/// designed spec when there is one.
pub fn execute(
    spec: &Spec,
    a: &DesignArgs,
    stop: &dyn Fn() -> bool,
) -> Result<(Answer, Option<Spec>), Diagnostic> {
    a.validate()?;
    // The output path is checked before the (possibly long) search.
    let write = a
        .write
        .as_deref()
        .map(|w| {
            output::prepare(
                "--write",
                w,
                &a.spec,
                Some((a.overwrite_spec, "--overwrite-spec")),
            )
        })
        .transpose()?;
    let mut opts = options(a);
    opts.objective = margin::objective(a)?;
    let flying = flight_check(a, spec)?;
    if let Some((check, _)) = &flying {
        opts.accept = Some(check.clone());
    }
    let (out, stopped) = match with_progress(spec, &opts, stop) {
        Ended::Finished(Ok(o)) => (o, false),
        Ended::Interrupted(o) => (o, true),
        Ended::Finished(Err(e)) => return Ok((design_error(&a.spec, &e), None)),
    };
    let mut notes = Vec::new();
    let written = write_design(write.as_ref(), &out, &mut notes);
    let what = flying.map(|(_, w)| w);
    let margins = match (a.margins, &out.spec) {
        (true, Some(s)) if !stopped => crate::report::margins::compute(s, opts.mode, stop)?,
        _ => None,
    };
    let printed = DesignReport {
        spec,
        out: &out,
        mode: opts.mode,
        stopped,
        flown: what.as_deref(),
        margins: margins.as_ref(),
    };
    let report = command::render(&printed, a.output.chosen())?;
    let status = match (stopped, out.status) {
        (true, _) => crate::interrupted_status(),
        (false, Status::Optimal | Status::Feasible) => 0,
        (false, _) => 1,
    };
    let answer = Answer {
        report,
        notes,
        status,
    };
    Ok((answer.after_write(written), out.spec))
}

impl DesignArgs {
    /// The checks of the flags alone, whichever way they came (the command
    /// line, Python's keywords): a flag that would do nothing, or a value
    /// out of range, is an error that names the fix.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        if let (MethodArg::Boxes, Some(_)) = (self.method, self.solver) {
            return Err(Diagnostic::error(
                "--solver picks the MILP's LP solver, but --method boxes solves no LP",
                "drop --solver, or use --method milp (or auto)",
            ));
        }
        if let Some(t) = self.time_limit {
            parse_time_limit(&t.to_string()).map_err(|e| {
                Diagnostic::error(format!("--time-limit {t}: {e}"), "give it in seconds")
            })?;
        }
        let judged = !self.vehicles.is_empty()
            || self.seed.is_some()
            || self.flights.is_some()
            || self.pass_rate.is_some()
            || self.confidence.is_some();
        if self.missions.is_empty() && judged {
            return Err(Diagnostic::error(
                "--vehicle, --seed, --flights, --pass-rate and --confidence choose and judge the flights of --fly, which is not given",
                "add --fly MISSION (e.g. --fly steps), or drop them",
            ));
        }
        flights::enough(self.flights, self.requirement())?;
        margin::objective(self).map(|_| ())
    }

    /// The pass rate and confidence `--fly`'s flights must show.
    fn requirement(&self) -> rtpipe_fly::confidence::Requirement {
        let d = rtpipe_fly::confidence::Requirement::DEFAULT;
        rtpipe_fly::confidence::Requirement {
            rate: self.pass_rate.unwrap_or(d.rate),
            confidence: self.confidence.unwrap_or(d.confidence),
        }
    }
}

/// The acceptance check of `--fly` and what it flies, in words.
type FlightCheck = (Arc<dyn rtpipe_design::Acceptance>, String);

/// `--fly`'s flights (and what they are, for the report); `--vehicle` or
/// `--seed` without `--fly` is an error, not a silently ignored flag.
fn flight_check(a: &DesignArgs, spec: &Spec) -> Result<Option<FlightCheck>, Diagnostic> {
    if a.missions.is_empty() {
        return Ok(None);
    }
    let vehicles = if a.vehicles.is_empty() {
        // Every built-in vehicle: a design is judged on each it may fly.
        rtpipe_flight::preset::BUILTIN.map(String::from).to_vec()
    } else {
        a.vehicles.clone()
    };
    let r = flights::FlyRequest {
        missions: &a.missions,
        vehicles: &vehicles,
        seed: a.seed.unwrap_or(0),
        flights: a.flights,
        need: a.requirement(),
    };
    let f = flights::flights(&a.spec, spec, &r)?;
    let what = r.describe(&f);
    Ok(Some((Arc::new(f), what)))
}

/// The search's options from the flags: the solver named, else HiGHS when
/// it is built in, else microlp; and a progress line for the spinner.
fn options(a: &DesignArgs) -> Options {
    Options {
        mode: a.mode,
        solver: match a.solver {
            Some(SolverArg::Microlp) => SolverKind::Microlp,
            Some(SolverArg::Highs) => SolverKind::Highs,
            // The faster backend when it is built in.
            None if SolverKind::Highs.available() => SolverKind::Highs,
            None => SolverKind::Microlp,
        },
        method: match a.method {
            MethodArg::Auto => Method::Auto,
            MethodArg::Boxes => Method::Boxes,
            MethodArg::Milp => Method::Milp,
        },
        time_limit: a.time_limit,
        progress: Some(Arc::new(Mutex::new(String::new()))),
        ..Options::default()
    }
}

/// Reports why no design could be attempted; the exit status says whose
/// fault it is (bad input, or the solver and rtpipe itself).
fn design_error(spec: &Path, e: &DesignError) -> Answer {
    let text = match located(spec, e) {
        Some(located) => located.to_string(),
        None => format!("{}: {}", spec.display(), e.diagnostic),
    };
    Answer {
        report: Rendered::Nothing,
        notes: vec![text.trim_end().to_string()],
        status: match e.kind {
            ErrorKind::Input => EXIT_BAD_INPUT,
            ErrorKind::Solver | ErrorKind::Internal => EXIT_INTERNAL,
        },
    }
}

/// The error at its key in the spec's text (file:line:column), when it
/// names one and the text still writes it there.
fn located(spec: &Path, e: &DesignError) -> Option<rtpipe_model::SpecError> {
    let key = e.key.as_deref()?;
    let source = rtpipe_model::input::read_text(spec, &rtpipe_model::input::Kind::SPEC).ok()?;
    // A key written as a table of its own (`[system.overheads]`) is placed
    // at its header; `locate` would give its parent's.
    let header = format!("[{key}]");
    let mut at = 0;
    let table = source.split_inclusive('\n').find_map(|line| {
        let start = at;
        at += line.len();
        (line.trim() == header).then(|| {
            let col = line.len() - line.trim_start().len();
            start + col..start + col + header.len()
        })
    });
    let span = table.or_else(|| rtpipe_model::input::locate(&source, key))?;
    let mut d = e.diagnostic.clone();
    d.span = Some(span);
    Some(rtpipe_model::SpecError {
        file: spec.display().to_string(),
        source,
        diagnostics: vec![d],
    })
}

/// `--write`: the designed spec, whole or not at all.
fn write_design(
    write: Option<&output::Output>,
    out: &Outcome,
    notes: &mut Vec<String>,
) -> Result<(), Diagnostic> {
    match (write, &out.spec) {
        (Some(w), Some(s)) => {
            let text = rtpipe_model::to_toml(s);
            output::write_all(&[(w, &text)])?;
        }
        (Some(w), None) => notes.push(format!(
            "note: nothing written to {}: no verified design",
            w.given.display()
        )),
        _ => {}
    }
    Ok(())
}

/// `rtpipe design`'s report: the search's answer, the verified design's
/// analysis, its flights and margins when asked.
struct DesignReport<'a> {
    spec: &'a Spec,
    out: &'a Outcome,
    mode: Mode,
    stopped: bool,
    flown: Option<&'a str>,
    margins: Option<&'a rtpipe_analysis::margins::Margins>,
}

impl DesignReport<'_> {
    /// The JSON value (the margins are added to the search's answer).
    fn value(&self) -> Result<serde_json::Value, Diagnostic> {
        let (spec, out) = (self.spec, self.out);
        let head = match (&out.spec, &out.report) {
            (Some(s), Some(r)) => Head::Report(report_view(s, r)),
            _ => Head::Bare {
                system: &spec.name,
                time_unit: spec.time_unit.name(),
            },
        };
        let margins = match (out.spec.as_ref(), self.margins) {
            (Some(s), Some(m)) => Some(crate::report::margins::view(s, m)),
            _ => None,
        };
        let v = DesignOut {
            head,
            design: design_json(spec, out, self.mode, self.stopped),
            margins,
        };
        command::to_value(&v)
    }
}

impl Serialize for DesignReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let v = self.value().map_err(serde::ser::Error::custom)?;
        v.serialize(s)
    }
}

impl rtpipe_printer::Report for DesignReport<'_> {
    fn text(&self) -> String {
        let (spec, out) = (self.spec, self.out);
        let mut t = design_text(spec, out, self.mode, self.stopped);
        if let Some(what) = self.flown {
            t.push_str(&flights::flown_text(spec, what, &out.checked));
        }
        margin::append_text(&mut t, out, self.margins);
        t
    }

    /// The designed spec's tasks and chains; without a design, the
    /// search's status alone.
    fn tables(&self) -> Vec<rtpipe_printer::Table> {
        use rtpipe_printer::{Cell, Column, Kind, Table};
        if let (Some(s), Some(r)) = (&self.out.spec, &self.out.report) {
            return crate::report::analysis::tables(s, r);
        }
        let Ok(mut t) = Table::new("design", vec![Column::new("status", Kind::Text)]) else {
            unreachable!("one column");
        };
        t.push(vec![Cell::from(self.out.status.name())]);
        vec![t]
    }
}

/// How long `design` waits for the search to notice Ctrl-C before it
/// answers from the best verified design published so far (a microlp
/// solve in progress cannot be interrupted).
const CTRL_C_GRACE: Duration = Duration::from_secs(1);

/// How the search ended.
enum Ended {
    /// The search returned by itself (or stopped at Ctrl-C with a complete
    /// answer: proven optimal or infeasible).
    Finished(Result<Outcome, DesignError>),
    /// Ctrl-C: the best verified design found so far, if any.
    Interrupted(Outcome),
}

/// Runs the design on a worker thread with a spinner on stderr that shows
/// what the search is doing (hidden when stderr is not a terminal). Ctrl-C
/// cancels the search; if the worker has not returned [`CTRL_C_GRACE`]
/// later, the answer is built from the designs it published, and the worker
/// is left to die with the process.
fn with_progress(spec: &Spec, opts: &Options, stop: &dyn Fn() -> bool) -> Ended {
    let pb = crate::spinner(format!(
        "designing {} ({} mode)",
        spec.name,
        opts.mode.name()
    ));
    let start = Instant::now();
    let cancel = Arc::new(AtomicBool::new(false));
    let sink: Arc<Mutex<Option<Incumbent>>> = Arc::new(Mutex::new(None));
    let opts = Options {
        cancel: Some(cancel.clone()),
        incumbent: Some(sink.clone()),
        ..opts.clone()
    };
    let (tx, rx) = mpsc::channel();
    let (spec2, opts2) = (spec.clone(), opts.clone());
    std::thread::spawn(move || {
        if std::env::var_os("RTPIPE_TEST_PANIC").is_some() {
            // For the tests: a panic in a long command must end the process
            // (main's panic hook exits with status 3).
            panic!("RTPIPE_TEST_PANIC is set");
        }
        // The receiver is gone only when main already answered.
        let _ = tx.send(design(&spec2, &opts2));
    });
    let mut stopped: Option<Instant> = None;
    let mut shown = String::new();
    let ended = loop {
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(r) => break settle(spec, &opts, r, stopped.is_some(), &sink, start),
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                break Ended::Finished(Err(DesignError::internal(
                    "internal: the design thread ended without an answer",
                )))
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Some(Ok(g)) = opts.progress.as_ref().map(|p| p.lock()) {
            if !g.is_empty() && *g != shown {
                shown.clone_from(&g);
                pb.set_message(shown.clone());
            }
        }
        if stopped.is_none() && stop() {
            cancel.store(true, Ordering::Relaxed);
            stopped = Some(Instant::now());
            pb.set_message("interrupted (Ctrl-C): stopping the search");
        }
        if stopped.is_some_and(|t| t.elapsed() >= CTRL_C_GRACE) {
            let best = sink.lock().ok().and_then(|g| g.clone());
            break Ended::Interrupted(interrupted(spec, &opts, best, start));
        }
    };
    pb.finish_and_clear();
    ended
}

/// The worker's answer; after Ctrl-C, one that is not complete (a design
/// not proven optimal, or none) is reported as interrupted, from the best
/// design published (or the worker's, should it hold one the sink lacks).
fn settle(
    spec: &Spec,
    opts: &Options,
    r: Result<Outcome, DesignError>,
    ctrl_c: bool,
    sink: &Mutex<Option<Incumbent>>,
    start: Instant,
) -> Ended {
    match r {
        Ok(o) if ctrl_c && matches!(o.status, Status::Feasible | Status::Unknown) => {
            let published = sink.lock().ok().and_then(|g| g.clone());
            let own = o.spec.as_ref().zip(o.objective).map(|(s, u)| Incumbent {
                periods: s
                    .tasks
                    .iter()
                    .map(|t| t.fixed_period().unwrap_or(0))
                    .collect(),
                utilization: u,
                lower_bound: o.lower_bound,
            });
            Ended::Interrupted(interrupted(spec, opts, published.or(own), start))
        }
        r => Ended::Finished(r),
    }
}

/// The answer after Ctrl-C: the published design, its periods fixed into
/// the spec and re-checked by the analysis (a design that does not verify
/// is not reported).
fn interrupted(spec: &Spec, opts: &Options, best: Option<Incumbent>, start: Instant) -> Outcome {
    let mut o = Outcome {
        status: Status::Unknown,
        spec: None,
        report: None,
        objective: None,
        lower_bound: None,
        gap: None,
        method: rtpipe_design::method_for(spec, opts),
        solver: opts.solver,
        seconds: start.elapsed().as_secs_f64(),
        first_design_seconds: None,
        iterations: 0,
        peak_open: 0,
        peak_open_bytes: 0,
        conflicts: Vec::new(),
        notes: Vec::new(),
        checked: Vec::new(),
        margin: None,
    };
    // Under the margin objective the designs published are of scaled
    // systems: one is an answer only within the cap, and its lower bound
    // is another problem's.
    let cap = match opts.objective {
        rtpipe_design::Objective::Margin { max_utilization } => Some(max_utilization),
        rtpipe_design::Objective::Utilization => None,
    };
    let best = best.map(|b| Incumbent {
        lower_bound: b.lower_bound.filter(|_| cap.is_none()),
        ..b
    });
    let verified = best
        .filter(|b| b.periods.len() == spec.tasks.len())
        .and_then(|b| {
            let mut s = spec.clone();
            for (t, &p) in s.tasks.iter_mut().zip(&b.periods) {
                t.period = PeriodSpec::Fixed(p);
            }
            let r = rtpipe_analysis::analyze(&s);
            let within = cap.is_none_or(|c| rtpipe_design::utilization(&s) <= c + 1e-12);
            (within && r.ok_in(opts.mode)).then_some((s, r, b))
        });
    let Some((s, r, b)) = verified else {
        o.notes
            .push("interrupted (Ctrl-C) before a verified design was found".into());
        return o;
    };
    let u = rtpipe_design::utilization(&s);
    o.gap = b.lower_bound.map(|lb| {
        if u > 0.0 {
            ((u - lb) / u).max(0.0)
        } else {
            0.0
        }
    });
    o.status = if o.gap.is_some_and(|g| g <= 1e-9) {
        Status::Optimal
    } else {
        Status::Feasible
    };
    (o.spec, o.report, o.objective, o.lower_bound) = (Some(s), Some(r), Some(u), b.lower_bound);
    o.notes.push(
        "interrupted (Ctrl-C): the best verified design found so far, re-checked by the analysis; the gap is to the lower bound proven when it was found".into(),
    );
    o
}

/// `design --json`: the verified design's analysis report (or just the
/// system when there is none), then the search's answer.
#[derive(Serialize, schemars::JsonSchema)]
struct DesignOut<'a> {
    #[serde(flatten)]
    head: Head<'a>,
    /// The search's answer: its status, the periods chosen and what the search
    /// did.
    design: DesignView<'a>,
    /// `--margins`: the designed spec's timing margins (as `analyze
    /// --margins` reports them).
    #[serde(skip_serializing_if = "Option::is_none")]
    margins: Option<crate::report::margins::MarginsView>,
}

#[derive(Serialize, schemars::JsonSchema)]
#[serde(untagged)]
enum Head<'a> {
    Report(ReportView<'a>),
    Bare {
        system: &'a str,
        time_unit: &'static str,
    },
}

#[derive(Serialize, schemars::JsonSchema)]
struct DesignView<'a> {
    /// The analysis mode the design keeps the limits under (`sound` or
    /// `paper`).
    mode: &'static str,
    /// `optimal`, `feasible` (verified, not proven least), `infeasible` or
    /// `unknown`.
    status: &'static str,
    /// The designed system's total utilisation (or the margin objective's
    /// value); null without a design.
    objective: Option<f64>,
    /// A proven lower bound on the objective; null when none.
    lower_bound: Option<f64>,
    /// (objective − lower_bound) / objective; null when either is.
    gap: Option<f64>,
    /// The search method (`boxes` or `milp`).
    method: &'static str,
    /// The MILP solver, with `method="milp"`.
    solver: Option<&'static str>,
    /// Wall-clock seconds the search took.
    seconds: f64,
    /// When the box search held its first verified design.
    first_design_seconds: Option<f64>,
    /// `None` when interrupted: the worker may still be inside a solve.
    iterations: Option<usize>,
    peak_open_boxes: Option<usize>,
    /// Their bytes, counted from their sizes (the search stops at 1 GiB).
    peak_open_box_bytes: Option<usize>,
    /// Each task's period in the design, in the spec's time unit; null for a
    /// task without one.
    periods: Pairs<&'a str, Option<f64>>,
    /// Without a design: the constraints that conflict, and how to fix each.
    conflicts: Vec<ConflictView<'a>>,
    /// Notes of the search, in words.
    notes: &'a [String],
    /// Whether Ctrl-C (or the stop flag) ended the search early.
    interrupted: bool,
    /// `--fly`: every design flown, in order.
    #[serde(skip_serializing_if = "Option::is_none")]
    flights: Option<Vec<flights::FlownView>>,
    /// `--objective margin`: the factor found and every factor tried.
    #[serde(skip_serializing_if = "Option::is_none")]
    margin_search: Option<margin::SearchView>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct ConflictView<'a> {
    /// The constraint, in words.
    constraint: &'a str,
    /// How to relax it, when known.
    fix: Option<&'a str>,
}

fn design_json<'a>(spec: &Spec, o: &'a Outcome, mode: Mode, stopped: bool) -> DesignView<'a> {
    let periods = o.spec.as_ref().map_or_else(Vec::new, |s| {
        s.tasks
            .iter()
            .map(|t| (t.name.as_str(), t.fixed_period().map(|p| spec.in_unit(p))))
            .collect()
    });
    let conflicts = o.conflicts.iter().map(|c| ConflictView {
        constraint: &c.constraint,
        fix: c.fix.as_deref(),
    });
    DesignView {
        mode: mode.name(),
        status: o.status.name(),
        objective: o.objective,
        lower_bound: o.lower_bound,
        gap: o.gap,
        method: o.method.name(),
        solver: (o.method == Method::Milp).then(|| o.solver.name()),
        seconds: o.seconds,
        first_design_seconds: o.first_design_seconds,
        iterations: (!stopped).then_some(o.iterations),
        peak_open_boxes: (o.method == Method::Boxes).then_some(o.peak_open),
        peak_open_box_bytes: (o.method == Method::Boxes).then_some(o.peak_open_bytes),
        periods: Pairs(periods),
        conflicts: conflicts.collect(),
        notes: &o.notes,
        interrupted: stopped,
        flights: (!o.checked.is_empty()).then(|| flights::flown_json(spec, &o.checked)),
        margin_search: margin::search_json(o),
    }
}

fn design_text(spec: &Spec, o: &Outcome, mode: Mode, stopped: bool) -> String {
    let search = match o.method {
        Method::Boxes => "branch and bound over periods".to_string(),
        _ => format!("solver {}", o.solver.name()),
    };
    let how = match (stopped, o.method) {
        // The worker may still be inside a solve: its count is not known.
        (true, _) => format!(", interrupted (Ctrl-C) after {:.2} s", o.seconds),
        (false, Method::Boxes) => format!(
            " after {} boxes ({} open at most) in {:.2} s",
            o.iterations, o.peak_open, o.seconds
        ),
        (false, _) => format!(
            " after {} master solves in {:.2} s",
            o.iterations, o.seconds
        ),
    };
    let mut out = format!(
        "design of {} ({} analysis, {search}): {}{how}\n",
        spec.name,
        mode.name(),
        o.status.name(),
    );
    if let (Some(u), Some(s)) = (o.objective, &o.spec) {
        out.push_str(&format!("total utilisation {:.4}", u + 0.0));
        if let Some(g) = o.gap {
            out.push_str(&format!(
                " (lower bound {:.4}, gap {:.2} %)",
                o.lower_bound.unwrap_or(u),
                100.0 * g
            ));
        }
        out.push_str("\nperiods:");
        for (i, (orig, t)) in spec.tasks.iter().zip(&s.tasks).enumerate() {
            // A data-triggered task runs at the rate of its triggers.
            let how = match (orig.fixed_period(), orig.is_triggered()) {
                (Some(_), _) => "(fixed)",
                (None, true) => "(data)",
                (None, false) => "",
            };
            out.push_str(&format!(
                " {}={}{how}",
                t.name,
                s.activation_period(i)
                    .map(|p| spec.fmt_time(p))
                    .unwrap_or_default(),
            ));
        }
        out.push_str("\n\nre-check by the analysis:\n\n");
        if let Some(r) = &o.report {
            out.push_str(&report_text(s, r, mode));
        }
    }
    if o.status == Status::Infeasible {
        out.push_str("no periods can meet these constraints together:\n");
        for c in &o.conflicts {
            out.push_str(&format!("  - {}", c.constraint));
            if let Some(f) = &c.fix {
                out.push_str(&format!(": {f}"));
            }
            out.push('\n');
        }
    }
    for n in &o.notes {
        out.push_str(&format!("note: {n}\n"));
    }
    out
}

impl command::Registered for DesignArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn inputs(&self) -> Vec<(&'static str, &Path)> {
        let vehicles = self
            .vehicles
            .iter()
            .map(|v| command::world_inputs(v, "steps"));
        let missions = self
            .missions
            .iter()
            .map(|m| command::world_inputs("racer5", m));
        vehicles.chain(missions).flatten().collect()
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        let (answer, designed) = execute(call.spec()?, self, &call.stop_fn())?;
        let mut done = command::Done::from(answer);
        done.specs
            .extend(designed.map(|s| ("designed".to_string(), s)));
        Ok(done)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(DesignOut<'static>)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table2() -> Spec {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/table2-design.toml"
        );
        match Spec::load(Path::new(path)) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn interrupted_without_a_design_says_so() {
        let o = interrupted(&table2(), &Options::default(), None, Instant::now());
        assert_eq!(o.status, Status::Unknown);
        assert!(o.spec.is_none() && o.objective.is_none());
        assert_eq!(
            o.notes,
            vec!["interrupted (Ctrl-C) before a verified design was found".to_string()]
        );
    }

    #[test]
    fn interrupted_reports_a_published_design_only_if_it_verifies() {
        let spec = table2();
        let paper = Options {
            mode: Mode::Paper,
            ..Options::default()
        };
        // The paper-mode optimum of Section IV-B (README): U = 0.5119.
        let ms = 1_000_000;
        let best = Incumbent {
            periods: [9, 14, 5, 50, 12, 50].map(|p| p * ms).to_vec(),
            utilization: 0.5119,
            lower_bound: Some(0.5),
        };
        let o = interrupted(&spec, &paper, Some(best.clone()), Instant::now());
        assert_eq!(o.status, Status::Feasible);
        let u = o.objective.unwrap_or(f64::NAN);
        assert!((u - 0.5119).abs() < 5e-5, "{u}");
        assert_eq!(o.lower_bound, Some(0.5));
        assert!((o.gap.unwrap_or(f64::NAN) - (u - 0.5) / u).abs() < 1e-12);
        assert!(o.report.as_ref().is_some_and(|r| r.ok_in(Mode::Paper)));
        // All periods at 5 ms overload the CPU: not verified, not reported.
        let bad = Incumbent {
            periods: vec![5 * ms; 6],
            ..best
        };
        let o = interrupted(&spec, &paper, Some(bad), Instant::now());
        assert_eq!(o.status, Status::Unknown);
        assert!(o.spec.is_none());
    }

    #[derive(clap::Parser)]
    struct Design {
        #[command(flatten)]
        args: DesignArgs,
    }

    fn parsed(flags: &[&str]) -> DesignArgs {
        use clap::Parser;
        let spec = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/cleanflight-design-flown.toml"
        );
        let argv = ["design", spec].into_iter().chain(flags.iter().copied());
        match Design::try_parse_from(argv) {
            Ok(d) => d.args,
            Err(e) => panic!("{flags:?}: {e}"),
        }
    }

    /// `--fly` alone judges a design on steps in turbulence (the breeze),
    /// beside the calm steps and the turbulent hover, on every built-in
    /// vehicle: the answer it gave without them missed held-out turbulent
    /// steps (docs/flight.md, "Held-out missions"). Named missions replace
    /// the default set.
    #[test]
    fn fly_alone_flies_steps_in_turbulence_on_every_built_in_vehicle() {
        use rtpipe_flight::radio::Mission;
        for flags in [&["--fly"][..], &["--fly", "--seed", "3"]] {
            assert_eq!(parsed(flags).missions, ["steps", "gusty", "breeze"]);
        }
        let turbulent_steps = |name: &str| {
            Mission::builtin(name).is_ok_and(|m| {
                m.world.dryden().is_ok_and(|d| d.is_some())
                    && m.steps
                        .iter()
                        .any(|s| s.pitch_deg.is_some_and(|p| p != 0.0))
            })
        };
        assert!(flights::DEFAULT_MISSIONS.iter().any(|m| turbulent_steps(m)));
        assert!(!turbulent_steps("steps") && !turbulent_steps("gusty"));
        assert_eq!(
            parsed(&["--fly", "steps,hover"]).missions,
            ["steps", "hover"]
        );
        assert!(parsed(&[]).missions.is_empty());
        // No --vehicle: both built-in vehicles, each on every mission.
        let a = parsed(&["--fly"]);
        let spec = match Spec::load(&a.spec) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        let what = match flight_check(&a, &spec) {
            Ok(Some((_, what))) => what,
            Ok(None) => panic!("--fly set no check"),
            Err(e) => panic!("{}", e.message),
        };
        assert!(
            what.starts_with("racer5, aero1kg × steps, gusty, breeze; 78 flights a design"),
            "{what}"
        );
    }
}
