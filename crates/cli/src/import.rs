//! `rtpipe import e2eeval FILE.yaml OUTDIR`: the arguments, the files and
//! what is printed. The mapping from E2EEvaluation's YAML to specs is
//! [`rtpipe_model::import::e2eeval`]'s.
//!
//! Every problem in the file is an error that names the file and the task
//! or chain, with exit status 2, and nothing is written: the whole file is
//! read and every spec built and parsed back before the first file is
//! written, and then all of them are written atomically.

mod px4_ulog;

use crate::command::{Answer, Call, Done, Rendered};
use crate::output;
use crate::table::Table;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_model::import::e2eeval::{self, Import, ImportedSpec};
use rtpipe_model::{Diagnostic, Spec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The formats `rtpipe import` reads.
#[derive(clap::Subcommand)]
pub enum ImportCommand {
    /// Task sets and cause-effect chains written by TU Dortmund's
    /// E2EEvaluation framework (its cause_effect_chains.yaml): one spec per
    /// ECU, ECUs joined by a chain in one spec as CPUs.
    ///
    /// Exit status: 0 when every spec was written, 2 on bad input (the file,
    /// a task or chain rtpipe cannot model, the output directory; nothing is
    /// written then), 3 on an internal error.
    #[command(name = "e2eeval")]
    E2eeval {
        /// The YAML file (`Chains:` and `Tasks:` with `!Task` entries).
        file: PathBuf,
        /// The directory the specs are written to (created if missing);
        /// existing specs of the same names are replaced.
        outdir: PathBuf,
    },
    /// A PX4 flight log (ULog, PX4 v1.5–v1.6 and v1.11–v1.15): OUTDIR/spec.toml (the
    /// threads, priorities, modules and execution times the log shows, the
    /// rate loop's chains) and OUTDIR/observed.csv (every logged data age
    /// of the rate loop: `timestamp - timestamp_sample`). See docs/px4.md.
    ///
    /// Exit status: 0 when both files were written, 2 on bad input (a log
    /// that is not ULog, or lacks what the spec needs; nothing is written
    /// then), 3 on an internal error.
    #[command(name = "px4-ulog")]
    Px4Ulog {
        /// The log (.ulg).
        log: PathBuf,
        /// The directory spec.toml and observed.csv are written to (created
        /// if missing); existing files of those names are replaced.
        outdir: PathBuf,
        /// Each module's `exec`: `max`, the longest run its perf counter
        /// saw (first runs after boot included), or `mean`, its average.
        #[arg(long, value_enum, default_value_t = ExecStat::Max)]
        exec: ExecStat,
        /// Take the execution times from this log's perf counters (and its
        /// top, for modules without one) instead of LOG's: for a log
        /// without perf counters or a SITL log (whose counters time 0 µs).
        /// A log of a board running the same modules.
        #[arg(long, value_name = "OTHER.ulg")]
        exec_from: Option<PathBuf>,
        /// A module's execution time in µs, over any counter (repeatable):
        /// e.g. `--exec-us control_allocator=20`.
        #[arg(long, value_name = "MODULE=US", value_parser = parse_exec_us)]
        exec_us: Vec<(String, u64)>,
        /// PX4's release X.Y, for a log without `ver_sw_release` (older
        /// logs have none): 1.5, 1.6 or 1.11 to 1.15. Without it the
        /// version is inferred from the log's topics where they show it.
        #[arg(long, value_name = "X.Y", value_parser = parse_px4_version)]
        px4_version: Option<(u32, u32)>,
    },
}

/// `--px4-version X.Y`: PX4's major and minor release numbers.
fn parse_px4_version(s: &str) -> Result<(u32, u32), String> {
    let parsed = s
        .trim()
        .trim_start_matches('v')
        .split_once('.')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
    parsed.ok_or_else(|| format!("`{s}`: expected X.Y, PX4's release, e.g. 1.6"))
}

/// `--exec-us MODULE=US`: a module name and a whole number of µs (≥ 1).
fn parse_exec_us(s: &str) -> Result<(String, u64), String> {
    let (module, us) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected MODULE=US, e.g. control_allocator=20"))?;
    let us: u64 =
        us.trim().parse().ok().filter(|n| *n >= 1).ok_or_else(|| {
            format!("`{s}`: US must be a whole number of microseconds, at least 1")
        })?;
    let module = module.trim();
    if module.is_empty()
        || !module
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_')
    {
        return Err(format!(
            "`{s}`: MODULE must be a PX4 module name (letters, digits, _)"
        ));
    }
    Ok((module.to_string(), us))
}

/// `import px4-ulog --exec`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExecStat {
    /// The longest run.
    Max,
    /// The average run.
    Mean,
}

/// `rtpipe import`'s arguments: the format, with its own.
#[derive(clap::Args)]
pub struct ImportArgs {
    #[command(subcommand)]
    pub format: ImportCommand,
}

impl crate::command::Registered for ImportArgs {
    fn run(&self) -> ExitCode {
        run(&self.format)
    }

    fn inputs(&self) -> Vec<(&'static str, &Path)> {
        match &self.format {
            ImportCommand::E2eeval { file, .. } => vec![("FILE", file.as_path())],
            ImportCommand::Px4Ulog { log, exec_from, .. } => {
                let other = exec_from.iter().map(|o| ("--exec-from", o.as_path()));
                std::iter::once(("LOG", log.as_path()))
                    .chain(other)
                    .collect()
            }
        }
    }

    /// The imported specs handed back, nothing written (OUTDIR unused).
    fn call(&self, call: Call<'_>) -> Result<Done, Diagnostic> {
        match &self.format {
            ImportCommand::E2eeval { file, .. } => e2eeval_done(file, call.text),
            ImportCommand::Px4Ulog {
                log,
                exec,
                exec_from,
                exec_us,
                px4_version,
                ..
            } => {
                let exec = exec_args(*exec, exec_from, exec_us, *px4_version);
                px4_ulog::done(log, &exec)
            }
        }
    }
}

/// `import px4-ulog`'s execution-time flags, as its reader takes them.
fn exec_args<'a>(
    stat: ExecStat,
    from: &'a Option<PathBuf>,
    us: &'a [(String, u64)],
    px4_version: Option<(u32, u32)>,
) -> px4_ulog::ExecArgs<'a> {
    px4_ulog::ExecArgs {
        stat,
        from: from.as_deref(),
        us,
        px4_version,
    }
}

/// Runs `rtpipe import`.
pub fn run(cmd: &ImportCommand) -> ExitCode {
    match cmd {
        ImportCommand::E2eeval { file, outdir } => match import_e2eeval(file, outdir) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
        ImportCommand::Px4Ulog {
            log,
            outdir,
            exec,
            exec_from,
            exec_us,
            px4_version,
        } => {
            let exec = exec_args(*exec, exec_from, exec_us, *px4_version);
            match px4_ulog::import(log, outdir, &exec) {
                Ok(()) => ExitCode::SUCCESS,
                Err(code) => code,
            }
        }
    }
}

/// One spec to write: where, and the spec.
struct Planned<'a> {
    path: PathBuf,
    spec: &'a ImportedSpec,
}

/// `file` (or `text`, its content given in its place) imported, its
/// problem placed at `file:line:column`.
fn read_e2eeval(file: &Path, text: Option<&str>) -> Result<Import, Diagnostic> {
    check_file_name(file)?;
    let read = match text {
        Some(t) => e2eeval::import(file, t),
        None => e2eeval::load(file),
    };
    read.map_err(|e| e.diagnostic.clone().within(place(file, &e)))
}

/// `FILE:line:column` of an import's problem (`FILE` when it has no place).
fn place(file: &Path, e: &e2eeval::ImportError) -> String {
    let at = e.at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default();
    format!("{}{at}", file.display())
}

/// A called `import e2eeval`: the specs by name, a summary and the notes.
fn e2eeval_done(file: &Path, text: Option<&str>) -> Result<Done, Diagnostic> {
    let imported = read_e2eeval(file, text)?;
    let mut specs = Vec::new();
    for s in &imported.specs {
        let spec = Spec::parse(&s.name, &s.text).map_err(|e| {
            Diagnostic::error(
                format!(
                    "internal error: the spec imported for ECU {} does not parse: {e}",
                    s.ecus[0]
                ),
                "please report it with the file",
            )
        })?;
        specs.push((s.name.clone(), spec));
    }
    let summary = serde_json::json!({
        "tasks": imported.tasks,
        "ecus": imported.ecus,
        "chains": imported.chains,
        "specs": imported.specs.iter().map(|s| serde_json::json!({
            "name": s.name, "ecus": s.ecus, "tasks": s.tasks, "chains": s.chains,
        })).collect::<Vec<_>>(),
    });
    let notes = imported.notes.iter();
    let answer = Answer {
        report: Rendered::Json(summary, Vec::new()),
        notes: notes
            .map(|n| format!("{}: {}", n.level, n.message))
            .collect(),
        status: 0,
    };
    Ok(Done {
        answer,
        specs,
        files: Vec::new(),
    })
}

fn import_e2eeval(file: &Path, outdir: &Path) -> Result<(), ExitCode> {
    if let Err(d) = check_file_name(file) {
        eprint!("{d}");
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    let shown = file.display().to_string();
    let imported = e2eeval::load(file).map_err(|e| {
        eprint!("{}: {}", place(file, &e), e.diagnostic);
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    let plans: Vec<Planned> = imported
        .specs
        .iter()
        .map(|spec| Planned {
            path: outdir.join(format!("{}.toml", spec.name)),
            spec,
        })
        .collect();
    verify(&plans)?;
    for n in &imported.notes {
        eprintln!("{shown}: {}: {}", n.level, n.message);
    }
    let files: Vec<(PathBuf, &str)> = plans
        .iter()
        .map(|p| (p.path.clone(), p.spec.text.as_str()))
        .collect();
    write_files(&files, outdir)?;
    print_summary(&shown, &imported, &plans);
    Ok(())
}

/// The specs' names, their files' names and their header comments come
/// from the file's name: it must print as what it is (no control,
/// bidirectional or invisible character: the one printable-name rule,
/// `name_problem`), or the names would not parse back or would lie.
fn check_file_name(file: &Path) -> Result<(), Diagnostic> {
    let path = file.to_string_lossy();
    let name = file.file_name().map(|n| n.to_string_lossy());
    // A file name has at most 255 bytes: only its characters can be wrong.
    let problem = name.as_deref().and_then(rtpipe_model::input::name_problem);
    // The directories are printed in messages: no control character there.
    let problem = problem.or_else(|| {
        path.chars()
            .any(char::is_control)
            .then(|| "contains a control character (newline, tab, ...)".to_string())
    });
    match problem {
        None => Ok(()),
        Some(p) => Err(Diagnostic::error(
            format!(
                "the file name \"{}\" {p}; the specs' names are made from it",
                path.escape_debug()
            ),
            "rename the file to a printable name, e.g. cause_effect_chains.yaml",
        )),
    }
}

/// Every spec text parses as it will be read (a failure is a bug: exit 3).
fn verify(plans: &[Planned]) -> Result<(), ExitCode> {
    for p in plans {
        if let Err(e) = Spec::parse(&p.path.display().to_string(), &p.spec.text) {
            eprint!("{e}");
            eprintln!("error: internal error: the spec written for ECU {} does not parse; please report it with the file", p.spec.ecus[0]);
            return Err(ExitCode::from(EXIT_INTERNAL));
        }
    }
    Ok(())
}

/// "s" unless one.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// Creates OUTDIR and writes every file atomically (all or none).
fn write_files(files: &[(PathBuf, &str)], outdir: &Path) -> Result<(), ExitCode> {
    let fail = |msg: String, help: &str| {
        eprint!("{}", Diagnostic::error(msg, help));
        ExitCode::from(EXIT_BAD_INPUT)
    };
    if outdir.exists() && !outdir.is_dir() {
        return Err(fail(
            format!("OUTDIR {} is not a directory", outdir.display()),
            "give a directory for the specs",
        ));
    }
    std::fs::create_dir_all(outdir).map_err(|e| {
        fail(
            format!("OUTDIR {}: cannot create it: {e}", outdir.display()),
            "check the path and its permissions",
        )
    })?;
    let mut outs = Vec::new();
    for (path, _) in files {
        let o = output::prepare("OUTDIR", path, Path::new(""), None).map_err(|e| {
            eprint!("{e}");
            ExitCode::from(EXIT_BAD_INPUT)
        })?;
        outs.push(o);
    }
    let files: Vec<(&output::Output, &str)> = outs
        .iter()
        .zip(files)
        .map(|(o, (_, text))| (o, *text))
        .collect();
    output::write_all(&files).map_err(|e| {
        eprint!("{e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

/// What was written: one row per spec.
fn print_summary(shown: &str, f: &Import, plans: &[Planned]) {
    println!(
        "imported {shown} (E2EEvaluation): {} task{} on {} ECU{}, {} chain{}; times in ms",
        f.tasks,
        plural(f.tasks),
        f.ecus,
        plural(f.ecus),
        f.chains,
        plural(f.chains),
    );
    println!();
    let mut t = Table::new(&["file", "ECUs", "tasks", "chains"]).numeric(&[2, 3]);
    for p in plans {
        let e: Vec<String> = p.spec.ecus.clone();
        t.row(vec![
            p.path.display().to_string(),
            e.join("+"),
            p.spec.tasks.to_string(),
            p.spec.chains.to_string(),
        ]);
    }
    print!("{}", t.render());
}
