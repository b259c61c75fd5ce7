//! `rtpipe`: analyse pipe systems (Cheng, West, Einstein, EMSOFT 2018).

mod analyze;
mod design;
mod plot;
mod simulate;
mod table;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "rtpipe",
    version,
    about = "End-to-end timing analysis of pipelines of periodic tasks (the pipe model of Cheng, West, Einstein, EMSOFT 2018)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Schedulability and worst-case reaction/freshness bounds of every chain.
    ///
    /// Exit status: 0 when every limit and the schedulability test hold (under
    /// the analysis --mode names, sound by default), 1 when one fails, 2 on bad
    /// input.
    Analyze {
        /// The system spec (TOML), e.g. examples/paper-table2.toml.
        spec: PathBuf,
        /// Print one JSON object instead of tables.
        #[arg(long)]
        json: bool,
        /// Also list the worst path between every source and sink.
        #[arg(long)]
        all_paths: bool,
        /// The analysis the verdict and the exit status follow (both are
        /// always shown).
        #[arg(long, value_enum, default_value = "sound")]
        mode: analyze::Judge,
    },
    /// Simulate the system and hold observed reaction and freshness times
    /// against the analysis' bounds.
    ///
    /// Exit status: 0 when no sample exceeds a sound bound, 1 when one does
    /// (a bug in the analysis), 2 on bad input.
    Simulate(simulate::SimulateArgs),
    /// Choose the free periods so that every limit holds at least utilisation
    /// (Section IV), and re-check the answer with the analysis.
    ///
    /// Exit status: 0 with a verified design, 1 when none exists (or none was
    /// found in time), 2 on bad input.
    Design {
        /// The system spec (TOML); tasks without a fixed period are designed.
        spec: PathBuf,
        /// The analysis the chain limits are judged by.
        #[arg(long, value_enum, default_value = "sound")]
        mode: design::ModeArg,
        /// Print one JSON object: the analysis of the design plus "design".
        #[arg(long)]
        json: bool,
        /// Write the complete designed spec here (accepted by `analyze`).
        #[arg(long, value_name = "OUT.toml")]
        write: Option<PathBuf>,
        /// MILP backend [default: highs when built with `--features highs`,
        /// else microlp].
        #[arg(long, value_enum)]
        solver: Option<design::SolverArg>,
        /// Stop after this many seconds and report the best verified design and its gap.
        #[arg(long, value_name = "S")]
        time_limit: Option<f64>,
    },
}

/// A spinner with a message and the elapsed time on stderr (hidden when
/// stderr is not a terminal).
pub fn spinner(msg: String) -> indicatif::ProgressBar {
    let pb =
        indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}]")
    {
        pb.set_style(style);
    }
    pb.set_message(msg);
    pb.enable_steady_tick(std::time::Duration::from_millis(100));
    pb
}

/// Exit status for bad input (clap uses 2 for bad flags too).
pub const EXIT_BAD_INPUT: u8 = 2;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Analyze {
            spec,
            json,
            all_paths,
            mode,
        } => analyze::run(&spec, json, all_paths, mode),
        Command::Simulate(args) => simulate::run(&args),
        Command::Design {
            spec,
            mode,
            json,
            write,
            solver,
            time_limit,
        } => design::run(design::Args {
            spec: &spec,
            mode,
            json,
            write: write.as_deref(),
            solver,
            time_limit,
        }),
    }
}
