//! `rtpipe analyze`.

mod observed;

use crate::command::mode_parser;
use crate::command::{self, Answer, FormatArgs};
use crate::report::analysis::{self, PathsView, ReportView};
use crate::report::margins;
use rtpipe_analysis::margins::Margins;
use rtpipe_analysis::{AllPaths, Mode, Report};
use rtpipe_model::{Diagnostic, Spec};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// `rtpipe analyze`'s flags.
#[derive(clap::Args, Debug)]
pub struct AnalyzeArgs {
    /// The system spec (TOML), e.g. examples/paper-table2.toml.
    pub spec: PathBuf,
    #[command(flatten)]
    pub output: FormatArgs,
    /// Also list the worst path between every source and sink.
    #[arg(long)]
    pub all_paths: bool,
    /// The analysis the verdict and the exit status follow (both are
    /// always shown).
    #[arg(long, value_parser = mode_parser(), default_value = "sound")]
    pub mode: Mode,
    /// Also compute the timing margins under --mode: how much each exec may
    /// grow, each chain limit's slack and the task that eats it first, the
    /// critical scaling factor per CPU and of the system, and the range of
    /// each period (docs/analysis.md, "Margins"). Ctrl-C stops it.
    #[arg(long)]
    pub margins: bool,
    /// Write the margins as CSV to this file (one row per margin, times in
    /// the spec's unit); implies --margins.
    #[arg(long, value_name = "FILE.csv")]
    pub margins_csv: Option<PathBuf>,
    /// Measured chain latencies to hold against the bounds: the --samples
    /// CSV of simulate, fly or run, or a flight log's data ages (import
    /// px4-ulog). Exit 1 when a measurement exceeds its sound bound
    /// (docs/analysis.md, "Measurements beside the bounds").
    #[arg(long, value_name = "FILE.csv")]
    pub observed: Option<PathBuf>,
}

pub fn run(a: &AnalyzeArgs) -> ExitCode {
    let spec = match command::load(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    if a.margins || a.margins_csv.is_some() {
        rtpipe_runtime::sys::catch_stop_signals();
    }
    match execute(&spec, a, &rtpipe_runtime::sys::stop_requested) {
        Ok(answer) => answer.emit(),
        Err(b) => command::fail(b),
    }
}

/// `analyze` on a loaded spec (with every period fixed), printed as
/// `--format` asks; `stop` says when to give up the margins' search
/// (Ctrl-C).
pub fn execute(
    spec: &Spec,
    a: &AnalyzeArgs,
    stop: &dyn Fn() -> bool,
) -> Result<Answer, Diagnostic> {
    let csv = a
        .margins_csv
        .as_deref()
        .map(|p| crate::output::prepare("--margins-csv", p, &a.spec, None))
        .transpose()?;
    let Some(found) = analyze(spec, a, stop)? else {
        return Ok(margins::stopped());
    };
    let mut answer = Answer {
        report: command::render(&found, a.output.chosen())?,
        notes: Vec::new(),
        status: found.status(),
    };
    if let (Some(out), Some(m)) = (&csv, &found.margins) {
        let written = crate::output::write_all(&[(out, &margins::csv(spec, m))]);
        if written.is_ok() {
            answer.notes.push(format!("wrote {}", out.given.display()));
        }
        answer = answer.after_write(written);
    }
    Ok(answer)
}

/// The analysis and what the flags add to it; `None` when `stop` ended
/// the margins' search.
pub fn analyze<'a>(
    spec: &'a Spec,
    a: &AnalyzeArgs,
    stop: &dyn Fn() -> bool,
) -> Result<Option<AnalyzeReport<'a>>, Diagnostic> {
    let report = rtpipe_analysis::analyze(spec);
    let observed = a
        .observed
        .as_deref()
        .map(|p| observed::read(p, spec, &report))
        .transpose()?;
    let paths = a
        .all_paths
        .then(|| rtpipe_analysis::all_paths(spec, &report.timing));
    let margins = if a.margins || a.margins_csv.is_some() {
        match margins::compute(spec, a.mode, stop)? {
            Some(m) => Some(m),
            None => return Ok(None),
        }
    } else {
        None
    };
    Ok(Some(AnalyzeReport {
        spec,
        report,
        mode: a.mode,
        paths,
        margins,
        observed,
    }))
}

/// `rtpipe analyze`'s report: the analysis, and every source-to-sink
/// pair, the margins and the measurements when asked.
pub struct AnalyzeReport<'a> {
    spec: &'a Spec,
    report: Report,
    mode: Mode,
    paths: Option<AllPaths>,
    margins: Option<Margins>,
    observed: Option<observed::Observed>,
}

impl AnalyzeReport<'_> {
    /// 0 when every limit and the schedulability test hold under the mode
    /// and no measurement exceeds its sound bound, else 1.
    pub fn status(&self) -> u8 {
        let measured_ok = self.observed.as_ref().is_none_or(|o| o.ok());
        u8::from(!(self.report.ok_in(self.mode) && measured_ok))
    }
}

/// `analyze --json`: the report, then every source-to-sink pair, the
/// margins and the measurements when asked.
#[derive(Serialize, schemars::JsonSchema)]
struct AnalyzeView<'a> {
    #[serde(flatten)]
    report: ReportView<'a>,
    /// With `all_paths=True`: every source-to-sink pair's worst bounds.
    #[serde(skip_serializing_if = "Option::is_none")]
    all_paths: Option<PathsView<'a>>,
    /// With `margins=True`: how much each exec may grow, each limit's slack,
    /// the critical scaling factors and each period's range.
    #[serde(skip_serializing_if = "Option::is_none")]
    margins: Option<margins::MarginsView>,
    /// With `observed=FILE`: the measured latencies of that file against the
    /// bounds.
    #[serde(skip_serializing_if = "Option::is_none")]
    observed: Option<observed::ObservedView<'a>>,
}

impl Serialize for AnalyzeReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (spec, r) = (self.spec, &self.report);
        AnalyzeView {
            report: analysis::report_view(spec, r),
            all_paths: self.paths.as_ref().map(|p| analysis::paths_view(spec, p)),
            margins: self.margins.as_ref().map(|m| margins::view(spec, m)),
            observed: self.observed.as_ref().map(|o| observed::view(spec, r, o)),
        }
        .serialize(s)
    }
}

impl rtpipe_printer::Report for AnalyzeReport<'_> {
    fn text(&self) -> String {
        let (spec, r) = (self.spec, &self.report);
        let mut t = analysis::report_text(spec, r, self.mode);
        if let Some(p) = &self.paths {
            t.push_str(&analysis::paths_text(spec, p));
        }
        if let Some(m) = &self.margins {
            t.push_str(&margins::text(spec, m));
        }
        if let Some(o) = &self.observed {
            t.push_str(&observed::text(spec, r, o));
        }
        t
    }

    /// The tasks and the chains, then the margins when asked (the table
    /// `--margins-csv` writes).
    fn tables(&self) -> Vec<rtpipe_printer::Table> {
        let mut ts = analysis::tables(self.spec, &self.report);
        ts.extend(self.margins.as_ref().map(|m| margins::table(self.spec, m)));
        ts
    }
}

impl command::Registered for AnalyzeArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn inputs(&self) -> Vec<(&'static str, &std::path::Path)> {
        self.observed
            .iter()
            .map(|o| ("--observed", o.as_path()))
            .collect()
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        let spec = call.spec()?;
        if let Some(d) = command::missing_periods(spec) {
            return Err(d);
        }
        execute(spec, self, &call.stop_fn()).map(command::Done::from)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(AnalyzeView<'static>)
}
