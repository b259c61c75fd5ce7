//! `rtpipe run`'s files: the output paths checked before the run, the
//! rt-app workload written before it, `--trace`, `--plot` and `--samples`
//! after it (all or none).

use super::RunArgs;
use crate::output;
use crate::plot;
use crate::report::samples::samples_csv;
use rtpipe_joblog::trace::{chrome_trace_with, TraceOptions};
use rtpipe_model::{Diagnostic, Spec};
use rtpipe_runtime::{Policy, RunConfig, RunResult};
use rtpipe_sim::observe::ChainObs;
use std::path::Path;

/// Checks the configuration and the output paths before anything runs, so
/// that a bad path is reported before a long run, not after.
pub(super) fn check_outputs(spec: &Spec, a: &RunArgs, cfg: &RunConfig) -> Result<(), Diagnostic> {
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
pub(super) fn export_rt_app(
    spec: &Spec,
    a: &RunArgs,
    cfg: &RunConfig,
    path: &Path,
) -> Result<(), Diagnostic> {
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
pub(super) fn write_outputs(
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
