//! `rtpipe`: analyse pipe systems (Cheng, West, Einstein, EMSOFT 2018).

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use rtpipe::{
    analyze, campaign, design, fly, generate, import, output, run, simulate, EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE, EXIT_INTERNAL,
};
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
    /// input, 3 on an internal error (a bug).
    Analyze(analyze::AnalyzeArgs),
    /// Simulate the system and hold observed reaction and freshness times
    /// against the analysis' bounds.
    ///
    /// Exit status: 0 when no sample exceeds a sound bound, 1 when one does
    /// (a bug in the analysis), 2 on bad input (flags, spec, output paths), 3
    /// on an internal error (a bug).
    Simulate(simulate::SimulateArgs),
    /// Fly a simulated quadrotor with the spec's task code on the simulated
    /// schedule (software in the loop) and report the flight's quality and
    /// each chain's observed latencies against the bounds.
    ///
    /// Exit status: 0 when the flight meets its criteria and no sample
    /// exceeds a sound bound, 1 otherwise, 2 on bad input, 3 on an internal
    /// error.
    Fly(fly::FlyArgs),
    /// Run the spec for real: one thread per task under SCHED_FIFO (rm) or
    /// SCHED_DEADLINE (edf), synthetic bodies burning each task's demand,
    /// four-slot registers between tasks; observed reaction and freshness
    /// against the bounds, response times, overruns, missed periods.
    ///
    /// Exit status: 0 when the run completed and no observation exceeds a
    /// sound bound or the excess is explained by the measurement (overruns,
    /// missed periods, steal time, best effort), 1 otherwise, 2 on bad input
    /// or when the kernel refuses the scheduling class, 3 on an internal
    /// error.
    Run(run::RunArgs),
    /// Choose the free periods so that every limit holds at least utilisation
    /// (Section IV), and re-check the answer with the analysis.
    ///
    /// Exit status: 0 with a verified design, 1 when none exists (or none was
    /// found in time), 2 on bad input (flags, spec, output path), 3 when the
    /// solver fails or on an internal error (a bug), 130 when Ctrl-C stopped
    /// the search (the best verified design so far is printed, and written
    /// with --write).
    Design(design::DesignArgs),
    /// Turn the task sets of other tools into rtpipe specs: `import e2eeval
    /// FILE.yaml OUTDIR` reads TU Dortmund's E2EEvaluation framework,
    /// `import px4-ulog LOG.ulg OUTDIR` a PX4 flight log.
    ///
    /// Exit status: 0 when every spec was written, 2 on bad input (nothing is
    /// written then), 3 on an internal error.
    Import {
        #[command(subcommand)]
        format: import::ImportCommand,
    },
    /// Generate random systems: `generate waters` writes an automotive task
    /// set with cause-effect chains (WATERS 2015, as E2EEvaluation does).
    ///
    /// Exit status: 0 when the spec was written, 2 on bad input, 3 on an
    /// internal error.
    Generate {
        #[command(subcommand)]
        kind: generate::GenerateCommand,
    },
    /// Generate, analyse (and simulate) many task sets on every core, into
    /// sharded Parquet: deterministic per seed, resumable, `--shard i/n` to
    /// fan out over machines.
    ///
    /// Exit status: 0 when every shard of the part is written, 2 on bad
    /// input (config, flags, output directory), 3 on an internal error, 130
    /// when Ctrl-C stopped it (the shards written stay; run again to resume).
    Campaign(campaign::CampaignArgs),
}

/// A panic anywhere (any thread) prints its message and ends the process
/// with [`EXIT_INTERNAL`]: it never leaves a waiting thread behind. A
/// failed write to stdout or stderr (`print!` panics on one) is not a bug:
/// a closed pipe ends the process quietly, any other failure (a full disk)
/// with a plain error and [`EXIT_BAD_INPUT`], as an output file that cannot
/// be written does.
fn exit_on_panic() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(why) = payload.strip_prefix("failed printing to std") {
            if why.contains("Broken pipe") {
                std::process::exit(i32::from(EXIT_BROKEN_PIPE));
            }
            if why.starts_with("err") {
                // Nowhere left to say it (printing would panic again).
                std::process::exit(i32::from(EXIT_BAD_INPUT));
            }
            let why = why.trim_start_matches("out: ").trim_start_matches("err: ");
            eprintln!("error: cannot write the output: {why}");
            std::process::exit(i32::from(EXIT_BAD_INPUT));
        }
        default(info);
        eprintln!(
            "error: internal error (a bug in rtpipe); please report it with the spec and the command line"
        );
        std::process::exit(i32::from(EXIT_INTERNAL));
    }));
}

/// Every file the command reads besides its spec, so that no output flag
/// replaces one ([`output::register_input`]); built-in vehicles and
/// missions are names, not files.
fn register_inputs(command: &Command) {
    let world = |vehicle: &str, mission: &str| {
        if !rtpipe_flight::preset::BUILTIN.contains(&vehicle) {
            output::register_input("--vehicle", std::path::Path::new(vehicle));
        }
        if !rtpipe_flight::radio::BUILTIN_MISSIONS.contains(&mission) {
            output::register_input("--mission", std::path::Path::new(mission));
        }
    };
    match command {
        Command::Fly(a) => {
            world(&a.vehicle, &a.mission);
            if let Some(c) = &a.criterion {
                output::register_input("--criterion", c);
            }
        }
        Command::Run(a) => world(a.vehicle(), a.mission()),
        Command::Design(a) => {
            a.vehicles.iter().for_each(|v| world(v, "steps"));
            a.missions.iter().for_each(|m| world("racer5", m));
        }
        Command::Import { format } => import::register_inputs(format),
        Command::Analyze(a) => {
            if let Some(o) = &a.observed {
                output::register_input("--observed", o);
            }
        }
        _ => {}
    }
}

fn main() -> ExitCode {
    exit_on_panic();
    let cli = match Cli::from_arg_matches(&Cli::command().get_matches()) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    register_inputs(&cli.command);
    match cli.command {
        Command::Analyze(args) => analyze::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Fly(args) => fly::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Design(args) => design::run(&args),
        Command::Import { format } => import::run(&format),
        Command::Generate { kind } => generate::run(&kind),
        Command::Campaign(args) => campaign::run(&args),
    }
}
