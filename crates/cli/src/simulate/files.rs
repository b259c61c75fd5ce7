//! The long run's progress display and the output files (`--trace`,
//! `--plot`, `--gantt`), rendered in memory and written all or none.

use super::*;

/// Runs `f` with a progress bar over the simulated horizon (fraction done,
/// elapsed time and ETA) on stderr, hidden when stderr is not a terminal.
/// `f` reports the simulated time it has reached.
pub(super) fn with_horizon_bar<T>(
    msg: String,
    horizon: Nanos,
    f: impl FnOnce(&mut dyn FnMut(Nanos)) -> T,
) -> T {
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(horizon.max(1) as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg} [{bar:30}] {percent:>3}% [{elapsed_precise}, ETA {eta_precise}]",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg);
    pb.enable_steady_tick(std::time::Duration::from_millis(100));
    let out = f(&mut |t| pb.set_position(t.max(0) as u64));
    pb.finish_and_clear();
    out
}

/// Runs `f` with a spinner and the elapsed time on stderr (hidden when stderr
/// is not a terminal).
pub(crate) fn with_spinner<T>(msg: String, f: impl FnOnce() -> T) -> T {
    let pb = crate::spinner(msg);
    let out = f();
    pb.finish_and_clear();
    out
}

/// The files to write, rendered in memory first.
pub(super) struct Outputs {
    pub(super) files: Vec<(&'static str, PathBuf, String)>,
    pub(super) notes: Vec<String>,
}

pub(super) fn render_outputs(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    res: &SimResult,
    obs: &[ChainObs],
) -> Result<Outputs, Diagnostic> {
    let mut out = Outputs {
        files: Vec::new(),
        notes: Vec::new(),
    };
    if let Some(path) = &a.trace {
        let t = chrome_trace_with(spec, res, TraceOptions::default());
        out.notes.push(format!(
            "wrote {}: {} CPU slices, {} data-flow arrows; open it in https://ui.perfetto.dev",
            path.display(),
            t.slices,
            t.flows
        ));
        if let Some(cut) = t.truncated_at {
            out.notes.push(format!(
                "note: the trace stops at {} {u} of {} {u} to stay small; a shorter --duration traces a whole run",
                spec.fmt_time(cut),
                spec.fmt_time(res.horizon),
                u = spec.time_unit
            ));
        }
        if t.flows_dropped > 0 {
            out.notes.push(format!(
                "note: {} later data-flow arrows were left out of the trace",
                t.flows_dropped
            ));
        }
        out.files.push(("--trace", path.clone(), t.json));
    }
    if let Some(path) = &a.plot {
        let subtitle = format!(
            "{} {} simulated, seed {}, exec {}, phasing {}",
            spec.fmt_time(res.horizon),
            spec.time_unit,
            a.seed(),
            flag_name(&a.exec),
            flag_name(&a.phasing)
        );
        let svg = plot::fig9(spec, obs, &subtitle).map_err(|e| {
            Diagnostic::error(format!("cannot draw --plot {}: {e}", path.display()), "")
        })?;
        out.notes.push(format!("wrote {}", path.display()));
        out.files.push(("--plot", path.clone(), svg));
    }
    if let Some(path) = &a.gantt {
        let svg = plot::gantt(spec, res, p.window).map_err(|e| {
            Diagnostic::error(format!("cannot draw --gantt {}: {e}", path.display()), "")
        })?;
        out.notes.push(format!(
            "wrote {}: {}..{} {}",
            path.display(),
            spec.fmt_time(p.window.0),
            spec.fmt_time(p.window.1),
            spec.time_unit
        ));
        out.files.push(("--gantt", path.clone(), svg));
    }
    Ok(out)
}
