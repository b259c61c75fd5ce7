//! `rtpipe design`: choose periods that meet every limit at least utilisation.

use crate::analyze::{report_json, report_text, Judge};
use crate::output;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_design::lp::SolverKind;
use rtpipe_design::{design, ErrorKind, Method, Mode, Options, Outcome, Status};
use rtpipe_model::Spec;
use serde_json::json;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ModeArg {
    Sound,
    Paper,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    Auto,
    Boxes,
    Milp,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum SolverArg {
    Microlp,
    Highs,
}

pub struct Args<'a> {
    pub spec: &'a Path,
    pub mode: ModeArg,
    pub json: bool,
    pub write: Option<&'a Path>,
    pub overwrite_spec: bool,
    pub method: MethodArg,
    pub solver: Option<SolverArg>,
    pub time_limit: Option<f64>,
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

pub fn run(a: Args) -> ExitCode {
    let spec = match Spec::load(a.spec) {
        Ok(s) => s,
        Err(e) => {
            eprint!("{e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    if let Some(t) = a.time_limit {
        if let Err(e) = parse_time_limit(&t.to_string()) {
            eprintln!("error: --time-limit {t}: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    }
    // The output path is checked before the (possibly long) search.
    let write = match a.write.map(|w| {
        output::prepare(
            "--write",
            w,
            a.spec,
            Some((a.overwrite_spec, "--overwrite-spec")),
        )
    }) {
        None => None,
        Some(Ok(o)) => Some(o),
        Some(Err(e)) => {
            eprint!("{e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let opts = Options {
        mode: match a.mode {
            ModeArg::Sound => Mode::Sound,
            ModeArg::Paper => Mode::Paper,
        },
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
    };
    let out = match with_progress(&spec, &opts) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{}: error: {e}", a.spec.display());
            if let Some(h) = &e.help {
                eprintln!("  = help: {h}");
            }
            return ExitCode::from(match e.kind {
                ErrorKind::Input => EXIT_BAD_INPUT,
                ErrorKind::Solver | ErrorKind::Internal => EXIT_INTERNAL,
            });
        }
    };
    match (&write, &out.spec) {
        (Some(w), Some(s)) => {
            let text = rtpipe_model::to_toml(s);
            if let Err(e) = output::write_all(&[(w, &text)]) {
                eprint!("{e}");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
        }
        (Some(w), None) => eprintln!(
            "note: nothing written to {}: no verified design",
            w.given.display()
        ),
        _ => {}
    }
    if a.json {
        let mut v = match (&out.spec, &out.report) {
            (Some(s), Some(r)) => report_json(s, r),
            _ => json!({"system": spec.name, "time_unit": spec.time_unit.name()}),
        };
        v["design"] = design_json(&spec, &out, opts.mode);
        if let Err(code) = crate::analyze::print_json(&v) {
            return code;
        }
    } else {
        print!("{}", design_text(&spec, &out, opts.mode));
    }
    match out.status {
        Status::Optimal | Status::Feasible => ExitCode::SUCCESS,
        _ => ExitCode::from(1),
    }
}

/// Runs the design with a spinner on stderr that shows what the search is
/// doing (hidden when stderr is not a terminal).
fn with_progress(spec: &Spec, opts: &Options) -> Result<Outcome, rtpipe_design::DesignError> {
    let pb = crate::spinner(format!(
        "designing {} ({} mode)",
        spec.name,
        opts.mode.name()
    ));
    let done = AtomicBool::new(false);
    let out = std::thread::scope(|s| {
        if let Some(status) = &opts.progress {
            let (pb, done) = (&pb, &done);
            s.spawn(move || {
                while !done.load(Ordering::Relaxed) {
                    if let Ok(g) = status.lock() {
                        if !g.is_empty() {
                            pb.set_message(g.clone());
                        }
                    }
                    std::thread::sleep(Duration::from_millis(200));
                }
            });
        }
        // `done` is set however the design ends, a panic included, so the
        // progress thread always stops (main's panic hook exits anyway).
        struct Done<'a>(&'a AtomicBool);
        impl Drop for Done<'_> {
            fn drop(&mut self) {
                self.0.store(true, Ordering::Relaxed);
            }
        }
        let _done = Done(&done);
        if std::env::var_os("RTPIPE_TEST_PANIC").is_some() {
            // For the tests: a panic in a long command must end the process.
            panic!("RTPIPE_TEST_PANIC is set");
        }
        design(spec, opts)
    });
    pb.finish_and_clear();
    out
}

fn design_json(spec: &Spec, o: &Outcome, mode: Mode) -> serde_json::Value {
    let periods: serde_json::Map<String, serde_json::Value> = match &o.spec {
        Some(s) => s
            .tasks
            .iter()
            .map(|t| {
                (
                    t.name.clone(),
                    json!(t.fixed_period().map(|p| spec.in_unit(p))),
                )
            })
            .collect(),
        None => serde_json::Map::new(),
    };
    json!({
        "mode": mode.name(),
        "status": o.status.name(),
        "objective": o.objective,
        "lower_bound": o.lower_bound,
        "gap": o.gap,
        "method": o.method.name(),
        "solver": (o.method == Method::Milp).then(|| o.solver.name()),
        "seconds": o.seconds,
        "iterations": o.iterations,
        "peak_open_boxes": (o.method == Method::Boxes).then_some(o.peak_open),
        "periods": periods,
        "conflicts": o.conflicts.iter().map(|c| json!({"constraint": c.constraint, "fix": c.fix})).collect::<Vec<_>>(),
        "notes": o.notes,
    })
}

fn design_text(spec: &Spec, o: &Outcome, mode: Mode) -> String {
    let search = match o.method {
        Method::Boxes => format!(
            "branch and bound over periods): {} after {} boxes ({} open at most)",
            o.status.name(),
            o.iterations,
            o.peak_open
        ),
        _ => format!(
            "solver {}): {} after {} master solves",
            o.solver.name(),
            o.status.name(),
            o.iterations
        ),
    };
    let mut out = format!(
        "design of {} ({} analysis, {search} in {:.2} s\n",
        spec.name,
        mode.name(),
        o.seconds
    );
    if let (Some(u), Some(s)) = (o.objective, &o.spec) {
        out.push_str(&format!("total utilisation {u:.4}"));
        if let Some(g) = o.gap {
            out.push_str(&format!(
                " (lower bound {:.4}, gap {:.2} %)",
                o.lower_bound.unwrap_or(u),
                100.0 * g
            ));
        }
        out.push_str("\nperiods:");
        for (orig, t) in spec.tasks.iter().zip(&s.tasks) {
            let fixed = orig.fixed_period().is_some();
            out.push_str(&format!(
                " {}={}{}",
                t.name,
                t.fixed_period()
                    .map(|p| spec.fmt_time(p))
                    .unwrap_or_default(),
                if fixed { "(fixed)" } else { "" }
            ));
        }
        out.push_str("\n\nre-check by the analysis:\n\n");
        if let Some(r) = &o.report {
            let judge = match mode {
                Mode::Sound => Judge::Sound,
                Mode::Paper => Judge::Paper,
            };
            out.push_str(&report_text(s, r, judge));
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
