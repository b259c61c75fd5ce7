//! `rtpipe generate waters OUTFILE.toml`: a random automotive task set with
//! cause-effect chains, after Kramer, Ziegenbein and Hamann, *Real World
//! Automotive Benchmarks For Free* (WATERS 2015), generated as TU Dortmund's
//! E2EEvaluation framework does (`rtpipe_model::gen::waters_system` has the
//! details). The same flags give the same file, byte for byte.

use crate::output;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_model::gen::{waters_system, WatersConfig};
use rtpipe_model::{Diagnostic, Spec};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The kinds of system `rtpipe generate` makes.
#[derive(clap::Subcommand)]
pub enum GenerateCommand {
    /// An automotive task set with cause-effect chains (WATERS 2015):
    /// periods by the paper's shares, execution times by its per-period
    /// statistics, chains of 1–3 periods with 2–5 tasks each, all plain
    /// rate-monotonic tasks with free communication (as E2EEvaluation).
    ///
    /// Exit status: 0 when the spec was written, 2 on bad input (flags, the
    /// output path), 3 on an internal error.
    Waters(WatersArgs),
}

/// `rtpipe generate waters`.
#[derive(clap::Args)]
pub struct WatersArgs {
    /// Number of tasks, spread over the CPUs in turn, their utilisation
    /// split by UUniFast (WCET = U·T). Without it, the tasks are the paper's
    /// runnables (execution times drawn from its statistics), added until
    /// each CPU's utilisation is within 1 % below --utilization.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    tasks: Option<u32>,
    /// Total utilisation of each CPU (WCET over period), in [0.001, 1].
    #[arg(long, default_value_t = 0.5, value_parser = parse_utilization)]
    utilization: f64,
    /// Cause-effect chains to generate (fewer when the task set has too few
    /// tasks of a period: a chain takes 2–5 tasks of each of its periods).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=10_000))]
    chains: u32,
    /// The seed: the same flags and seed give the same file.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Number of CPUs (partitioned; every chain is local to one CPU, as
    /// E2EEvaluation's are to one ECU).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    cpus: u32,
    /// `synchronous`: every task released at 0 (offset 0), as E2EEvaluation's
    /// task sets are, so the analysis gives known-offset bounds beside the
    /// arbitrary-phasing ones; `arbitrary`: the phasing is unknown.
    #[arg(long, value_enum, default_value = "arbitrary")]
    release: ReleaseArg,
    /// The spec to write (replaced atomically if it exists).
    #[arg(value_name = "OUTFILE.toml")]
    out: PathBuf,
}

/// `generate waters --release`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReleaseArg {
    Synchronous,
    Arbitrary,
}

/// The smallest `--utilization`: far below it the generator's tasks round
/// to nothing (1e-9 gave a spec without tasks).
const MIN_UTILIZATION: f64 = 0.001;

/// `--utilization`: a number in [0.001, 1].
fn parse_utilization(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(u) if (MIN_UTILIZATION..=1.0).contains(&u) => Ok(u),
        _ => Err(format!(
            "must be a number in [{MIN_UTILIZATION}, 1], e.g. --utilization 0.6 (per CPU)"
        )),
    }
}

/// `rtpipe generate`'s arguments: the kind of system, with its own.
#[derive(clap::Args)]
pub struct GenerateArgs {
    #[command(subcommand)]
    pub kind: GenerateCommand,
}

impl crate::command::Registered for GenerateArgs {
    fn run(&self) -> ExitCode {
        run(&self.kind)
    }

    /// The generated spec handed back (as `generated`), no file written.
    fn call(&self, _: crate::command::Call<'_>) -> Result<crate::command::Done, Diagnostic> {
        let GenerateCommand::Waters(a) = &self.kind;
        let spec = waters_spec(a);
        let answer = crate::command::Answer {
            report: crate::command::Rendered::Nothing,
            notes: Vec::new(),
            status: 0,
        };
        Ok(crate::command::Done {
            answer,
            specs: vec![("generated".to_string(), spec)],
            files: Vec::new(),
        })
    }
}

/// Runs `rtpipe generate`.
pub fn run(cmd: &GenerateCommand) -> ExitCode {
    match cmd {
        GenerateCommand::Waters(a) => match waters(a) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
    }
}

/// The WATERS task set the flags describe (its OUTFILE aside).
pub fn waters_spec(a: &WatersArgs) -> Spec {
    let cfg = WatersConfig {
        tasks: a.tasks.map(|n| n as usize),
        cpus: a.cpus,
        utilization: a.utilization,
        chains: a.chains as usize,
        synchronous: a.release == ReleaseArg::Synchronous,
    };
    waters_system(a.seed, &cfg)
}

fn waters(a: &WatersArgs) -> Result<(), ExitCode> {
    let out = check_output(&a.out)?;
    let spec = waters_spec(a);
    let text = format!("{}{}", header(a), rtpipe_model::to_toml(&spec));
    if let Err(d) = fits_the_reader(text.len(), spec.tasks.len()) {
        eprint!("{d}");
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    if let Err(e) = Spec::parse(&a.out.display().to_string(), &text) {
        eprint!("{e}");
        eprintln!("error: internal error: the generated spec does not parse; please report it with the command line");
        return Err(ExitCode::from(EXIT_INTERNAL));
    }
    output::write_all(&[(&out, &text)]).map_err(|e| {
        eprint!("{e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    summary(a, &spec);
    Ok(())
}

/// Refuses a spec of `bytes` (with `tasks` tasks) larger than every
/// command reads ([`rtpipe_model::MAX_SPEC_BYTES`]): a file nothing could
/// load is no use. The help estimates how many tasks fit.
fn fits_the_reader(bytes: usize, tasks: usize) -> Result<(), Diagnostic> {
    let cap = rtpipe_model::MAX_SPEC_BYTES;
    if bytes as u64 <= cap {
        return Ok(());
    }
    let fit = (tasks as u64).saturating_mul(cap) / (bytes as u64).max(1);
    Err(Diagnostic::error(
        format!(
            "the spec would be {:.1} MiB, more than the {} MiB rtpipe reads: no command could load it",
            bytes as f64 / f64::from(1 << 20),
            cap >> 20
        ),
        format!("generate fewer tasks or chains, e.g. --tasks {}", fit * 9 / 10),
    ))
}

/// The output path, checked before any work: a directory gets its own
/// message (the shared writer's examples name other flags' files).
fn check_output(path: &Path) -> Result<output::Output, ExitCode> {
    if path.is_dir() {
        eprint!(
            "{}",
            Diagnostic::error(
                format!("OUTFILE {} is a directory", path.display()),
                format!(
                    "give a file name, e.g. {}",
                    path.join("waters.toml").display()
                ),
            )
        );
        return Err(ExitCode::from(EXIT_BAD_INPUT));
    }
    output::prepare("OUTFILE", path, Path::new(""), None).map_err(|e| {
        eprint!("{e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

/// Comment lines with the command that makes the file again (no path, no
/// date: the same flags give the same bytes).
fn header(a: &WatersArgs) -> String {
    let tasks = a.tasks.map(|n| format!(" --tasks {n}")).unwrap_or_default();
    let release = match a.release {
        ReleaseArg::Synchronous => " --release synchronous",
        ReleaseArg::Arbitrary => "",
    };
    format!(
        "# Generated by `rtpipe generate waters{tasks} --utilization {} --chains {} --seed {} --cpus {}{release}`:\n\
         # WATERS 2015 periods and execution times (Kramer, Ziegenbein, Hamann), E2EEvaluation's chains.\n\n",
        a.utilization, a.chains, a.seed, a.cpus
    )
}

/// The most tasks whose schedulability the summary checks (the exact test
/// takes time quadratic in the tasks of a CPU).
const MAX_CHECKED: usize = 5000;

/// What was written: tasks per period, utilisation per CPU, chains, and
/// whether the task set is schedulable.
fn summary(a: &WatersArgs, spec: &Spec) {
    let mut per: BTreeMap<i64, usize> = BTreeMap::new();
    for t in &spec.tasks {
        *per.entry(t.fixed_period().unwrap_or(0)).or_default() += 1;
    }
    let shares: Vec<String> = per
        .iter()
        .map(|(p, n)| format!("{}ms:{n}", spec.fmt_time(*p)))
        .collect();
    let util: Vec<String> = (0..a.cpus)
        .map(|c| format!("{:.4}", utilisation(spec, c)))
        .collect();
    println!(
        "generated {} -> {}: {} tasks on {} CPU{}, {} chains",
        spec.name,
        a.out.display(),
        spec.tasks.len(),
        a.cpus,
        if a.cpus == 1 { "" } else { "s" },
        spec.chains.len()
    );
    println!("  tasks per period: {}", shares.join(" "));
    println!("  utilisation per CPU: {}", util.join(" "));
    if spec.tasks.len() <= MAX_CHECKED {
        let ok = rtpipe_analysis::analyze(spec).schedulability.schedulable;
        let verdict = if ok { "yes" } else { "no" };
        println!("  schedulable (rate monotonic, exact RTA): {verdict}");
    } else {
        println!("  schedulability not checked here (more than {MAX_CHECKED} tasks): run `rtpipe analyze`");
    }
    if spec.chains.len() < a.chains as usize {
        eprintln!(
            "note: {} of {} chains: a chain takes 2-5 tasks of each of its 1-3 periods on one CPU, and too few draws found them; give more --tasks",
            spec.chains.len(),
            a.chains
        );
    }
}

/// Σ WCET/T on one CPU.
fn utilisation(spec: &Spec, cpu: u32) -> f64 {
    spec.tasks
        .iter()
        .filter(|t| t.cpu == cpu)
        .map(|t| t.exec as f64 / t.fixed_period().unwrap_or(1) as f64)
        .sum::<f64>()
        + 0.0 // an empty sum is -0.0
}

#[cfg(test)]
mod tests {
    use super::fits_the_reader;

    #[test]
    fn a_spec_larger_than_the_reader_takes_is_refused() {
        let cap = rtpipe_model::MAX_SPEC_BYTES as usize;
        assert!(fits_the_reader(cap, 100_000).is_ok());
        let e = fits_the_reader(cap + cap / 8, 100_000);
        assert!(e.is_err_and(|d| d.message.contains("more than the 16 MiB")
            && d.help.is_some_and(|h| h.contains("--tasks 79999"))));
    }
}
