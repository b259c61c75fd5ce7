//! `rtpipe run SPEC --measure-overheads [--write-spec OUT.toml]`: this
//! machine's scheduling overheads (`rtpipe_runtime::overheads`) on every
//! CPU the spec uses, in the class a run would use, printed, and written
//! into a copy of the spec (`[system] overheads`, the 99th percentiles)
//! that is validated before it is written. The input spec is never
//! replaced (`output::prepare`).

use super::{policy_of, RunArgs};
use crate::command::fail;
use crate::output;
use crate::table::Table;
use rtpipe_model::{Diagnostic, Nanos, Spec};
use rtpipe_runtime::overheads::{measure, CpuOverheads};
use std::process::ExitCode;

/// Measures, prints, and writes `--write-spec`.
pub(super) fn run(spec: &Spec, a: &RunArgs) -> ExitCode {
    let policy = match policy_of(spec, a) {
        Ok(p) => p,
        Err(d) => return fail(d),
    };
    if a.write_spec.is_some() && spec.event_triggered() {
        // Refused before measuring: the spec written would not validate.
        return fail(
            Diagnostic::error(
                "--write-spec: a spec with work-queue threads or data-triggered tasks cannot carry [system] overheads (the analysis does not account for them there yet)",
                "drop --write-spec to measure and print the overheads, and fold them into each task's exec",
            )
            .within(a.spec.display()),
        );
    }
    if let Some(p) = &a.write_spec {
        if let Err(d) = output::prepare("--write-spec", p, &a.spec, None) {
            return fail(d);
        }
    }
    let mut cpus: Vec<usize> = spec.tasks.iter().map(|t| t.cpu as usize).collect();
    cpus.sort_unstable();
    cpus.dedup();
    let online = rtpipe_runtime::sys::online_cpus();
    if let Some(&c) = cpus.iter().find(|&&c| c >= online) {
        return fail(Diagnostic::error(
            format!("the spec places tasks on CPU {c}, but this machine has {online}"),
            "measure on a machine with the spec's CPUs, or move the tasks (`cpu = N`)",
        ));
    }
    eprintln!(
        "measuring context switches and timer releases on CPU {} under {} (about 1.5 s per CPU)...",
        cpus.iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        policy.class()
    );
    let measured = match measure(policy, &cpus) {
        Ok(m) => m,
        Err(e) => return fail(e.diagnostic),
    };
    if rtpipe_runtime::sys::stop_requested() {
        eprintln!(
            "interrupted ({}): nothing measured or written",
            rtpipe_runtime::sys::stop_name()
        );
        return ExitCode::from(crate::interrupted_status());
    }
    print!("{}", table(&measured));
    let out = with_overheads(spec, &measured);
    let Some(path) = &a.write_spec else {
        println!("as a spec writes it: {}", overheads_note(&out));
        return ExitCode::SUCCESS;
    };
    let text = rtpipe_model::to_toml(&out);
    if let Err(e) = Spec::parse(&path.display().to_string(), &text) {
        eprint!("{e}");
        return fail(Diagnostic::error(
            "the spec with the measured overheads does not validate",
            "fix what the diagnostics above name in the input spec, then measure again",
        ));
    }
    if let Err(d) = output::write_files(&a.spec, &[("--write-spec", path.clone(), text)]) {
        return fail(d);
    }
    // Said only once it is true: the copy validated and is in place.
    println!("written as: {}", overheads_note(&out));
    eprintln!("wrote {}", path.display());
    ExitCode::SUCCESS
}

/// The `overheads = { ... }` line of `out`, and where its figures come from.
fn overheads_note(out: &Spec) -> String {
    format!(
        "overheads = {} (the 99th percentiles; replenish is kept: the runtime has no budget path of its own, SCHED_DEADLINE replenishes inside the measured release)",
        overheads_line(out)
    )
}

/// One row per CPU and figure, µs.
fn table(m: &[CpuOverheads]) -> String {
    let us = |ns: Nanos| format!("{:.3}", ns as f64 / 1e3);
    let mut t = Table::new(&[
        "cpu",
        "overhead",
        "samples",
        "median us",
        "p99 us",
        "max us",
    ])
    .numeric(&[0, 2, 3, 4, 5]);
    for c in m {
        for (what, s) in [("context_switch", c.context_switch), ("release", c.release)] {
            t.row(vec![
                c.cpu.to_string(),
                what.into(),
                s.samples.to_string(),
                us(s.median),
                us(s.p99),
                us(s.max),
            ]);
        }
    }
    t.render()
}

/// The spec with the measured figures: the first CPU's as the system's,
/// each other CPU's in its own table; replenishment as the spec had it.
fn with_overheads(spec: &Spec, m: &[CpuOverheads]) -> Spec {
    let mut out = spec.clone();
    for (k, c) in m.iter().enumerate() {
        let (cs, rel) = (c.context_switch.p99, c.release.p99);
        if k == 0 {
            out.overheads.system.context_switch = cs;
            out.overheads.system.release = rel;
            if let Some(own) = out.overheads.cpus.get_mut(&(c.cpu as u32)) {
                (own.context_switch, own.release) = (None, None);
            }
        } else {
            let own = out.overheads.cpus.entry(c.cpu as u32).or_default();
            (own.context_switch, own.release) = (Some(cs), Some(rel));
        }
    }
    out
}

/// `{ ... }` as the TOML writer puts it.
fn overheads_line(spec: &Spec) -> String {
    rtpipe_model::to_toml(spec)
        .lines()
        .find_map(|l| l.strip_prefix("overheads = ").map(str::to_string))
        .unwrap_or_default()
}
