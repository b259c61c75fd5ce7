//! What every command does the same way: load the spec, report a bad flag
//! or value, read a time flag, print JSON; and the flags several commands
//! share.

use crate::EXIT_BAD_INPUT;
use clap::builder::TypedValueParser;
use clap::ValueEnum;
use rtpipe_analysis::Mode;
use rtpipe_model::time::number_to_nanos;
use rtpipe_model::{parse_time_str, Diagnostic, Nanos, Spec, SpecError};
use rtpipe_sim::ExecModel;
use std::path::Path;
use std::process::ExitCode;

/// Loads a spec and checks it can be analysed, printing errors to stderr.
pub fn load(path: &Path) -> Result<Spec, ExitCode> {
    let spec = match Spec::load(path) {
        Ok(s) => s,
        Err(e) => {
            eprint!("{e}");
            return Err(ExitCode::from(EXIT_BAD_INPUT));
        }
    };
    let missing = rtpipe_analysis::missing_periods(&spec);
    if !missing.is_empty() {
        let msg = format!(
            "no fixed period for task{} {}",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        );
        // A spec's problem without a place in its text, shown as the spec's
        // own diagnostics are (task names hold no control characters).
        let e = SpecError {
            file: path.display().to_string(),
            source: String::new(),
            diagnostics: vec![Diagnostic::new(msg, None)
                .help("give each a `period = ...`, or let `rtpipe design` choose them")],
        };
        eprint!("{e}");
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    Ok(spec)
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
