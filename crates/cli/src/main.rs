//! `rtpipe`: analyse pipe systems (Cheng, West, Einstein, EMSOFT 2018).

mod analyze;
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
    /// Exit status: 0 when every limit and the schedulability test hold, 1 when
    /// one fails, 2 on bad input.
    Analyze {
        /// The system spec (TOML), e.g. examples/paper-table2.toml.
        spec: PathBuf,
        /// Print one JSON object instead of tables.
        #[arg(long)]
        json: bool,
        /// Also list the worst path between every source and sink.
        #[arg(long)]
        all_paths: bool,
    },
    /// Simulate the system and hold observed reaction and freshness times
    /// against the analysis' bounds.
    ///
    /// Exit status: 0 when no sample exceeds a sound bound, 1 when one does
    /// (a bug in the analysis), 2 on bad input.
    Simulate(simulate::SimulateArgs),
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
        } => analyze::run(&spec, json, all_paths),
        Command::Simulate(args) => simulate::run(&args),
    }
}
