//! `rtpipe import px4-ulog LOG.ulg OUTDIR`: the files and what is printed.
//! Reading the log and building the spec are
//! [`rtpipe_model::import::px4_ulog`]'s; every problem is exit status 2 with
//! nothing written, and both files are written atomically, all or none.

use super::{write_files, ExecStat};
use crate::command::{Answer, Done, Rendered};
use crate::table::Table;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_model::import::px4_ulog::{self, ExecFrom, Import, Options};
use rtpipe_model::{Diagnostic, Spec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where the execution times come from (`--exec`, `--exec-from`, `--exec-us`).
pub(super) struct ExecArgs<'a> {
    pub(super) stat: ExecStat,
    pub(super) from: Option<&'a Path>,
    pub(super) us: &'a [(String, u64)],
    pub(super) px4_version: Option<(u32, u32)>,
}

/// Reads `log` (and `--exec-from`'s log) and builds the import; a problem
/// names the log it is in.
fn read(log: &Path, exec: &ExecArgs) -> Result<Import, Diagnostic> {
    let shown = log.display().to_string().escape_debug().to_string();
    let read = px4_ulog::load(log).map_err(|d| d.within(&shown))?;
    let other_shown = exec
        .from
        .map(|p| p.display().to_string().escape_debug().to_string());
    let other = match (exec.from, &other_shown) {
        (Some(p), Some(name)) => {
            Some(px4_ulog::load(p).map_err(|d| d.within(format!("--exec-from {name}")))?)
        }
        _ => None,
    };
    let opts = Options {
        stat: match exec.stat {
            ExecStat::Max => ExecFrom::Max,
            ExecStat::Mean => ExecFrom::Mean,
        },
        exec_log: other.as_ref().zip(other_shown.as_deref()),
        exec_us: exec.us,
        px4_version: exec.px4_version,
    };
    px4_ulog::import(&read, &spec_name(log), &opts).map_err(|d| d.within(&shown))
}

/// Imports `log` into `outdir/spec.toml` and `outdir/observed.csv`.
pub(super) fn import(log: &Path, outdir: &Path, exec: &ExecArgs) -> Result<(), ExitCode> {
    let shown = log.display().to_string().escape_debug().to_string();
    let imported = read(log, exec).map_err(|d| {
        eprint!("{d}");
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    let spec_path = outdir.join("spec.toml");
    if let Err(e) = Spec::parse(&spec_path.display().to_string(), &imported.spec) {
        eprint!("{e}");
        eprintln!("error: internal error: the spec imported from {shown} does not parse; please report it with the log");
        return Err(ExitCode::from(EXIT_INTERNAL));
    }
    let files: Vec<(PathBuf, &str)> = vec![
        (spec_path, imported.spec.as_str()),
        (outdir.join("observed.csv"), imported.observed.as_str()),
    ];
    write_files(&files, outdir)?;
    print_summary(&shown, outdir, &imported);
    Ok(())
}

/// A called `import px4-ulog`: the spec (`spec`), `observed.csv`'s text,
/// and what the summary prints as JSON (board, data ages, assumptions).
pub(super) fn done(log: &Path, exec: &ExecArgs) -> Result<Done, Diagnostic> {
    let f = read(log, exec)?;
    let spec = Spec::parse(&spec_name(log), &f.spec).map_err(|e| {
        Diagnostic::error(
            format!(
                "internal error: the spec imported from {} does not parse: {e}",
                log.display()
            ),
            "please report it with the log",
        )
    })?;
    let ages: Vec<serde_json::Value> = f
        .ages
        .iter()
        .map(|a| {
            serde_json::json!({
                "chain": a.chain, "topic": a.topic, "messages": a.count,
                "min_ns": a.min_ns, "max_ns": a.max_ns,
            })
        })
        .collect();
    let summary = serde_json::json!({
        "board": f.board,
        "lockstep": f.lockstep,
        "ages": ages,
        "assumptions": f.assumptions,
    });
    Ok(Done {
        answer: Answer {
            report: Rendered::Json(summary, Vec::new()),
            notes: Vec::new(),
            status: 0,
        },
        specs: vec![("spec".to_string(), spec)],
        files: vec![("observed.csv".to_string(), f.observed)],
    })
}

/// The spec's name: `px4-` and the log's file stem, in characters a name
/// may hold (any other becomes `_`).
fn spec_name(log: &Path) -> String {
    let stem = log
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let clean: String = stem
        .chars()
        .take(64)
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("px4-{clean}")
}

/// What was written, the measured data ages and the assumptions.
fn print_summary(shown: &str, outdir: &Path, f: &Import) {
    println!("imported {shown}: {}", f.board);
    println!(
        "wrote {} and {}",
        outdir.join("spec.toml").display(),
        outdir.join("observed.csv").display()
    );
    println!();
    if f.lockstep {
        println!("measured data ages (timestamp - timestamp_sample), us: lockstep ages (SITL: the simulated clock stands still while the modules run)");
    } else {
        println!("measured data ages (timestamp - timestamp_sample), us:");
    }
    let mut t = Table::new(&["chain", "topic", "messages", "min", "max"]).numeric(&[2, 3, 4]);
    for a in &f.ages {
        t.row(vec![
            a.chain.clone(),
            a.topic.clone(),
            a.count.to_string(),
            format!("{}", a.min_ns as f64 / 1000.0),
            format!("{}", a.max_ns as f64 / 1000.0),
        ]);
    }
    print!("{}", t.render());
    println!();
    println!("what the log cannot tell, and what the spec assumes:");
    for a in &f.assumptions {
        println!("  - {a}");
    }
    println!();
    println!(
        "next: rtpipe analyze {} (bounds on the same chains)",
        outdir.join("spec.toml").display()
    );
}
