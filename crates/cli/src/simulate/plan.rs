//! What to simulate: the horizon, the Gantt window and the output paths,
//! all checked before anything runs.

use super::*;

/// What to simulate, checked before anything runs.
#[derive(Debug)]
pub(super) struct Plan {
    pub(super) horizon: Nanos,
    /// Tail outputs asked for (`--outputs` or the default).
    pub(super) outputs: Option<u64>,
    pub(super) window: (Nanos, Nanos),
    pub(super) log_jobs: bool,
}

pub(super) fn plan(spec: &Spec, a: &SimulateArgs) -> Result<Plan, Diagnostic> {
    let t_max = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(0);
    if t_max <= 0 {
        return Err(Diagnostic::error(
            "no task has a fixed period, so nothing is ever released",
            "give the tasks a `period = ...`",
        ));
    }
    let (horizon, outputs) = horizon_of(spec, a)?;
    a.validate()?;
    let window = match &a.window {
        None => (0, (3 * t_max).min(horizon)),
        Some(w) => window_of(spec, a, w, t_max, horizon)?,
    };
    let mut outs = Vec::new();
    for (flag, p) in [
        ("--trace", &a.trace),
        ("--plot", &a.plot),
        ("--gantt", &a.gantt),
        ("--samples", &a.samples),
    ] {
        let Some(p) = p else { continue };
        outs.push(output::prepare(flag, p, &a.spec, None)?);
    }
    output::distinct(&outs)?;
    Ok(Plan {
        horizon,
        outputs,
        window,
        // `--samples` streams its rows (report::samples::SamplesFile).
        log_jobs: a.trace.is_some() || a.gantt.is_some(),
    })
}

/// The simulated span, from `--duration` or `--outputs` (and the outputs
/// asked for).
fn horizon_of(spec: &Spec, a: &SimulateArgs) -> Result<(Nanos, Option<u64>), Diagnostic> {
    Ok(match (&a.duration, a.outputs) {
        (Some(d), None) => {
            let h = parse_time(spec, d).map_err(|e| {
                Diagnostic::error(
                    format!("invalid value `{d}` for --duration: {e}"),
                    format!(
                        "write a positive time like --duration 2s or --duration 500ms, or a bare number in {}",
                        spec.time_unit
                    ),
                )
            })?;
            if h <= 0 {
                return Err(Diagnostic::error(
                    format!("--duration must be positive, found `{d}`"),
                    "write a positive time like --duration 2s",
                ));
            }
            (h, None)
        }
        (None, o) => {
            let n = o.unwrap_or(DEFAULT_OUTPUTS);
            match horizon_for_outputs(spec, n) {
                Some(h) => (h, Some(n)),
                None => {
                    return Err(Diagnostic::error(
                        format!(
                            "--outputs {n} needs more simulated time than the longest the model allows, {:.0} s (about 104 days)",
                            MAX_TIME as f64 * 1e-9
                        ),
                        "ask for fewer outputs, e.g. --outputs 10000",
                    ))
                }
            }
        }
        (Some(_), Some(_)) => {
            return Err(Diagnostic::error(
                "--outputs and --duration both set the simulated span",
                "give only one of them",
            ))
        }
    })
}

impl SimulateArgs {
    /// The checks of the flags alone, whichever way they came (the command
    /// line, Python's keywords): a flag that would do nothing is an error
    /// that names the fix.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        let a = self;
        if a.search_steps.is_some() && a.phasing != PhasingArg::Search {
            return Err(Diagnostic::error(
                "--search-steps sets the adversarial search, but --phasing is not search",
                "add --phasing search, or drop --search-steps",
            ));
        }
        if a.seed.is_some()
            && a.phasing == PhasingArg::Sync
            && matches!(a.exec, ExecArg::Worst | ExecArg::Best)
        {
            return Err(Diagnostic::error(
                format!(
                    "--seed has no effect: nothing is random with --phasing sync and --exec {}",
                    flag_name(&a.exec)
                ),
                "add --phasing random (or --exec uniform), or drop --seed",
            ));
        }
        Ok(())
    }
}

/// `--window START,END` for the Gantt chart, inside the simulated span.
fn window_of(
    spec: &Spec,
    a: &SimulateArgs,
    w: &str,
    t_max: Nanos,
    horizon: Nanos,
) -> Result<(Nanos, Nanos), Diagnostic> {
    if a.gantt.is_none() {
        return Err(Diagnostic::error(
            "--window sets the span of the Gantt chart, but no --gantt was given",
            "add --gantt FILE.svg, or drop --window",
        ));
    }
    let help = format!(
        "write --window START,END with times in {} or with units, e.g. --window 0,{}",
        spec.time_unit,
        spec.fmt_time((3 * t_max).min(horizon))
    );
    let Some((s, e)) = w.split_once(',') else {
        return Err(Diagnostic::error(
            format!("invalid value `{w}` for --window: expected START,END"),
            help,
        ));
    };
    let (s, e) = match (parse_time(spec, s), parse_time(spec, e)) {
        (Ok(s), Ok(e)) => (s, e),
        (Err(m), _) | (_, Err(m)) => {
            return Err(Diagnostic::error(
                format!("invalid value `{w}` for --window: {m}"),
                help,
            ))
        }
    };
    if s < 0 || e <= s {
        return Err(Diagnostic::error(
            format!("invalid value `{w}` for --window: need 0 <= START < END"),
            help,
        ));
    }
    if e > horizon {
        return Err(Diagnostic::error(
            format!(
                "--window ends at {} {u}, after the simulated span of {} {u}",
                spec.fmt_time(e),
                spec.fmt_time(horizon),
                u = spec.time_unit
            ),
            "lengthen --duration (or --outputs), or pick an earlier END",
        ));
    }
    Ok((s, e))
}
