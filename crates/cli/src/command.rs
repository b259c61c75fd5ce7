//! What every command does the same way: load the spec, report a bad flag
//! or value, read a time flag, print JSON; and the flags several commands
//! share.

use crate::EXIT_BAD_INPUT;
use clap::builder::TypedValueParser;
use clap::ValueEnum;
use rtpipe_analysis::Mode;
use rtpipe_model::time::number_to_nanos;
use rtpipe_model::{parse_time_str, Diagnostic, Nanos, Spec, SpecError};
use rtpipe_printer::{Format, Printed};
use rtpipe_sim::ExecModel;
use std::path::Path;
use std::process::ExitCode;

/// Loads a spec and checks it can be analysed, printing errors to stderr.
pub fn load(path: &Path) -> Result<Spec, ExitCode> {
    load_checked(path, missing_periods)
}

/// Loads a spec and checks it can be simulated: every task but a
/// data-triggered one (its triggers' publications release it) has a fixed
/// period.
pub fn load_simulated(path: &Path) -> Result<Spec, ExitCode> {
    load_checked(path, unsimulable)
}

/// Why `spec` cannot be simulated: [`missing_periods`], but for the
/// data-triggered tasks of an event-triggered spec (their triggers release
/// them).
pub fn unsimulable(spec: &Spec) -> Option<Diagnostic> {
    missing_periods(spec).filter(|_| !spec.event_triggered() || !timers_fixed(spec))
}

/// Every task a timer releases has a fixed period.
fn timers_fixed(spec: &Spec) -> bool {
    spec.tasks
        .iter()
        .filter(|t| !t.is_triggered())
        .all(|t| t.fixed_period().is_some())
}

/// Loads a spec and refuses it with `problem`'s diagnostic, printing
/// errors to stderr.
fn load_checked(
    path: &Path,
    problem: impl Fn(&Spec) -> Option<Diagnostic>,
) -> Result<Spec, ExitCode> {
    let spec = match Spec::load(path) {
        Ok(s) => s,
        Err(e) => {
            eprint!("{e}");
            return Err(ExitCode::from(EXIT_BAD_INPUT));
        }
    };
    if let Some(d) = problem(&spec) {
        // A spec's problem without a place in its text, shown as the spec's
        // own diagnostics are (task names hold no control characters).
        let e = SpecError {
            file: path.display().to_string(),
            source: String::new(),
            diagnostics: vec![d],
        };
        eprint!("{e}");
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    Ok(spec)
}

/// Why `spec` cannot be analysed, simulated or flown: tasks without a
/// fixed period (what `design` chooses).
pub fn missing_periods(spec: &Spec) -> Option<Diagnostic> {
    let missing = rtpipe_analysis::missing_periods(spec);
    (!missing.is_empty()).then(|| {
        let msg = format!(
            "no fixed period for task{} {}",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        );
        Diagnostic::new(msg, None)
            .help("give each a `period = ...`, or let `rtpipe design` choose them")
    })
}

/// Prints a JSON value on stdout; an encoding failure is an error exit.
pub fn print_json(v: &impl serde::Serialize) -> Result<(), ExitCode> {
    match serde_json::to_string_pretty(v) {
        Ok(s) => {
            println!("{s}");
            Ok(())
        }
        Err(e) => {
            eprintln!("error: cannot encode JSON: {e}");
            Err(ExitCode::from(EXIT_BAD_INPUT))
        }
    }
}

/// Prints a bad flag or value (what is wrong and how to fix it) and gives
/// exit status 2.
pub(crate) fn fail(b: Diagnostic) -> ExitCode {
    eprint!("{b}");
    ExitCode::from(EXIT_BAD_INPUT)
}

/// A time from the command line: a bare number in the spec's unit or a
/// string with a unit.
pub(crate) fn parse_time(spec: &Spec, s: &str) -> Result<Nanos, String> {
    let t = s.trim();
    let r = match t.parse::<f64>() {
        Ok(x) => number_to_nanos(x, spec.time_unit),
        Err(_) => parse_time_str(t),
    };
    r.map_err(|e| e.to_string())
}

/// `--format` and `--json` (its older spelling): how a command prints its
/// report. Flattened into every command's flags, so the choice is made
/// once, here; the printers are `rtpipe_printer`'s.
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct FormatArgs {
    /// How to print the report: text (tables for people), json (one
    /// object) or csv (the report's tables; several are each headed by a
    /// `# NAME` line and split by an empty line).
    #[arg(long, value_parser = format_parser(), default_value = "text", conflicts_with = "json")]
    pub format: Format,
    /// Print one JSON object instead of tables (the same as --format json).
    #[arg(long)]
    pub json: bool,
}

impl FormatArgs {
    /// The format asked for.
    pub fn chosen(&self) -> Format {
        if self.json {
            Format::Json
        } else {
            self.format
        }
    }

    /// Whether the report is JSON.
    pub fn is_json(&self) -> bool {
        self.chosen() == Format::Json
    }
}

/// `--format`'s names, listed in the help and in errors.
fn format_parser() -> impl clap::builder::TypedValueParser<Value = Format> {
    clap::builder::PossibleValuesParser::new(Format::ALL.map(Format::name))
        .try_map(|s| s.parse::<Format>())
}

/// `report` printed in `format`, as a command's [`Rendered`] report.
pub fn render<R: rtpipe_printer::Report>(
    report: &R,
    format: Format,
) -> Result<Rendered, Diagnostic> {
    match rtpipe_printer::print(report, format) {
        Ok(Printed::Text(t)) => Ok(Rendered::Text(t)),
        // The tables go with the JSON: the Python package hands both back.
        Ok(Printed::Json(v)) => Ok(Rendered::Json(v, report.tables())),
        Err(e) => Err(Diagnostic::error(
            format!("internal: cannot encode JSON: {e}"),
            "please report it with the spec and the command line",
        )),
    }
}

/// `--exec`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExecArg {
    Worst,
    Uniform,
    Best,
    Extremes,
}

impl ExecArg {
    pub fn model(self) -> ExecModel {
        match self {
            ExecArg::Worst => ExecModel::Worst,
            ExecArg::Uniform => ExecModel::Uniform,
            ExecArg::Best => ExecModel::Best,
            ExecArg::Extremes => ExecModel::Extremes,
        }
    }
}

/// `--mode`: the one [`Mode`] of the analysis crate, its names listed in
/// the help and in errors.
pub fn mode_parser() -> impl clap::builder::TypedValueParser<Value = Mode> {
    clap::builder::PossibleValuesParser::new(Mode::ALL.map(Mode::name))
        .try_map(|s| s.parse::<Mode>())
}

/// `--pass-rate`, `--confidence` (of `design --fly` and `fly --sweep`): a
/// fraction strictly between 0 and 1.
pub fn parse_fraction(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x < 1.0 => Ok(x),
        _ => Err("must be a number strictly between 0 and 1 (e.g. 0.95)".into()),
    }
}

/// What a command answers: its report (text for people, JSON for
/// scripts), the lines it has for stderr (notes, warnings, why it
/// failed), and its exit status. The binary prints it ([`Answer::emit`]);
/// the Python package returns the JSON and logs the notes.
pub struct Answer {
    pub report: Rendered,
    pub notes: Vec<String>,
    pub status: u8,
}

/// A command's report, as `--json` asks.
pub enum Rendered {
    Text(String),
    /// The JSON value, and the tables `--format csv` prints of the same
    /// report.
    Json(serde_json::Value, Vec<rtpipe_printer::Table>),
    /// No report: the command failed (its notes say why).
    Nothing,
}

impl Answer {
    /// This answer after writing its files: when the write failed, the
    /// report of the work that was done is kept (a result computed is never
    /// dropped), notes that claim a file was written are taken back, and
    /// the failure ends the notes with exit status 2.
    pub fn after_write(mut self, written: Result<(), Diagnostic>) -> Answer {
        if let Err(d) = written {
            self.notes.retain(|n| !n.starts_with("wrote "));
            self.notes.push(d.to_string().trim_end().to_string());
            self.status = EXIT_BAD_INPUT;
        }
        self
    }

    /// The answer of a command that its stop flag ended: no report (the
    /// work is not whole), and the status of an interrupted command.
    pub fn stopped() -> Answer {
        Answer {
            report: Rendered::Nothing,
            notes: vec!["stopped: the stop flag was set before the work ended".into()],
            status: crate::interrupted_status(),
        }
    }

    /// Prints the report on stdout and the notes on stderr; the exit status.
    pub fn emit(self) -> ExitCode {
        match &self.report {
            Rendered::Text(t) => print!("{t}"),
            Rendered::Nothing => {}
            Rendered::Json(v, _) => {
                if let Err(code) = print_json(v) {
                    return code;
                }
            }
        }
        for n in &self.notes {
            eprintln!("{n}");
        }
        ExitCode::from(self.status)
    }
}

/// The JSON value of a report (keys in the order the views declare them).
pub fn to_value(v: &impl serde::Serialize) -> Result<serde_json::Value, Diagnostic> {
    serde_json::to_value(v).map_err(|e| {
        Diagnostic::error(
            format!("internal: cannot encode JSON: {e}"),
            "please report it with the spec and the command line",
        )
    })
}

/// What a caller of a long command adds: a second place for the sample
/// rows (the Python package's arrays), and a flag that stops the run.
#[derive(Default)]
pub struct Hooks {
    pub rows: Option<rtpipe_joblog::RowSink>,
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl Hooks {
    /// Whether the stop flag is set: a long loop asks it between its steps
    /// and, once it is, returns [`Answer::stopped`] (no unwinding: the
    /// work ends by its own return path, dropping what it holds).
    pub fn stopped(stop: Option<&std::sync::atomic::AtomicBool>) -> bool {
        stop.is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed))
    }
}

/// Both row sinks, or the one given.
pub fn tee(
    a: Option<rtpipe_joblog::RowSink>,
    b: Option<rtpipe_joblog::RowSink>,
) -> Option<rtpipe_joblog::RowSink> {
    match (a, b) {
        (Some(mut a), Some(mut b)) => Some(Box::new(move |c, r| {
            a(c, r);
            b(c, r);
        })),
        (a, b) => a.or(b),
    }
}

/// What a command is handed when it is called as a function (the Python
/// package, through `api`), rather than from the command line.
pub struct Call<'a> {
    /// The loaded spec, for a command that takes one.
    pub spec: Option<&'a Spec>,
    /// The text of the file the command reads, given in place of reading
    /// it (Python's `import_e2eeval(yaml_text)`); the flags still name it.
    pub text: Option<&'a str>,
    /// A second row sink and the stop flag.
    pub hooks: Hooks,
}

impl<'a> Call<'a> {
    /// The spec a command on a spec needs.
    pub fn spec(&self) -> Result<&'a Spec, Diagnostic> {
        self.spec.ok_or_else(|| {
            Diagnostic::error(
                "this command runs on a spec, and none was given",
                "load one first (rtpipe.load) and call the command as its method",
            )
        })
    }

    /// Whether the stop flag is set.
    pub fn stopped(&self) -> bool {
        Hooks::stopped(self.hooks.stop.as_deref())
    }

    /// A closure that asks the stop flag (what the long loops take).
    pub fn stop_fn(&self) -> impl Fn() -> bool + Send + Sync + 'static {
        let stop = self.hooks.stop.clone();
        move || Hooks::stopped(stop.as_deref())
    }
}

/// What a called command gives back: its answer, and what it made that
/// the command line writes to files (specs by name, other files' text by
/// file name), handed over instead.
pub struct Done {
    pub answer: Answer,
    pub specs: Vec<(String, Spec)>,
    pub files: Vec<(String, String)>,
}

impl From<Answer> for Done {
    fn from(answer: Answer) -> Done {
        Done {
            answer,
            specs: Vec::new(),
            files: Vec::new(),
        }
    }
}

/// How the Python package reaches a command: the function or method that
/// calls it (`System.analyze`, `rtpipe.campaign`), or why none does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reach {
    /// `rtpipe.NAME` or `System.NAME`.
    Python(&'static str),
    /// Deliberately not reachable, and why.
    Not(&'static str),
}

/// A command of the binary, as the one registration (`registry.rs`) lists
/// it: its flags (the clap struct implementing this), how the command line
/// runs it, the files it reads, and how a caller without a command line
/// runs it.
pub trait Registered {
    /// The command line's run: load, execute, print; the exit status.
    fn run(&self) -> ExitCode;

    /// The files the command reads besides its spec, with the flag that
    /// names each, so that no output replaces one.
    fn inputs(&self) -> Vec<(&'static str, &Path)> {
        Vec::new()
    }

    /// The command run on what `call` hands it, nothing printed.
    fn call(&self, call: Call<'_>) -> Result<Done, Diagnostic>;

    /// What is refused before the command starts, on its flags and its
    /// spec alone: always the caller's input ([`Refusal::Input`]), whatever
    /// [`Registered::refusal`] says of the command's later refusals.
    fn check(&self, _call: &Call<'_>) -> Result<(), Diagnostic> {
        Ok(())
    }

    /// Whose fault a refusal of [`Registered::call`] is, once
    /// [`Registered::check`] passed, for a caller that tells them apart
    /// (Python's `InputError` and `RunError`).
    fn refusal(&self) -> Refusal {
        Refusal::Input
    }
}

/// Whose fault a command's refusal is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// A flag, a value or the spec is wrong.
    Input,
    /// The machine refused a run (`run`: a scheduling class or a
    /// reservation, a missing CPU).
    Run,
}

/// The files a flight's vehicle and mission name (a built-in is a name, not
/// a file).
pub fn world_inputs<'a>(vehicle: &'a str, mission: &'a str) -> Vec<(&'static str, &'a Path)> {
    let mut out = Vec::new();
    if !rtpipe_flight::preset::BUILTIN.contains(&vehicle) {
        out.push(("--vehicle", Path::new(vehicle)));
    }
    if !rtpipe_flight::radio::BUILTIN_MISSIONS.contains(&mission) {
        out.push(("--mission", Path::new(mission)));
    }
    out
}
